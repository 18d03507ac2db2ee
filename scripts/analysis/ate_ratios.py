#!/usr/bin/env python3
"""A change's accuracy gate: two `idyvins bench` outputs of the same renders, old and new.

Prints, as Markdown, per mode: the geometric mean of the ATE ratios new / old, the largest ratio and
its sequence, and for idy the largest change of the moving and static observations flagged
(percentage points). Standard library only.

Usage: scripts/analysis/ate_ratios.py OLD_OUT NEW_OUT
"""
import json
import math
import sys


def runs(out):
    with open(out + "/results.json") as f:
        return {(r["sequence"], r["mode"]): r["summary"] for r in json.load(f)}


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    old, new = runs(sys.argv[1]), runs(sys.argv[2])
    keys = sorted(set(old) & set(new))
    if not keys:
        sys.exit("no run in both outputs")
    print("| mode | runs | geometric mean new / old | largest ratio | moving flagged, largest change | static flagged, largest change |")
    print("| --- | --- | --- | --- | --- | --- |")
    for mode in sorted({m for _, m in keys}):
        ratios = [(new[k]["ate_rmse_m"] / old[k]["ate_rmse_m"], k[0]) for k in keys if k[1] == mode]
        gm = math.exp(sum(math.log(r) for r, _ in ratios) / len(ratios))
        worst = max(ratios)
        d_moving = d_static = 0.0
        for k in keys:
            if k[1] != mode:
                continue
            co, cn = old[k]["classification"], new[k]["classification"]
            if co["observations_on_moving"] > 0:
                d = 100 * (cn["moving_detected_fraction"] - co["moving_detected_fraction"])
                d_moving = d if abs(d) > abs(d_moving) else d_moving
            d = 100 * (cn["static_flagged_fraction"] - co["static_flagged_fraction"])
            d_static = d if abs(d) > abs(d_static) else d_static
        print(f"| {mode} | {len(ratios)} | {gm:.4f} | {worst[0]:.3f} ({worst[1]}) | {d_moving:+.2f} | {d_static:+.2f} |")


if __name__ == "__main__":
    main()
