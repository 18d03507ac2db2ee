#!/usr/bin/env python3
"""Tables of a finished `idyvins bench` run (OUT/results.json) for the README and docs/results.md.

Prints, as Markdown: ATE per seed, the classification means over seeds per scene,
level and mode, idy's static flagged per seed, the lost-corner test totals, and the
issue-7 targets checked against the figures. Standard library only.

Usage: scripts/analysis/bench_tables.py OUT [--compare OTHER_OUT]
  --compare: also print idy's figures of OTHER_OUT next to OUT's (before / after).
"""
import argparse
import json
import math
import os
import sys
from collections import defaultdict

SCENES = ["city", "parking_lot"]
LEVELS = ["none", "low", "mid", "high"]
MODES = ["baseline", "ransac", "seg", "idy", "idy-pre", "idy-ba"]


def merge(summary, timing):
    for k, v in timing.items():
        if isinstance(v, dict):
            merge(summary.setdefault(k, {}), v)
        else:
            summary[k] = v


def load(out):
    path = os.path.join(out, "results.json")
    try:
        with open(path) as f:
            results = json.load(f)
    except (OSError, ValueError) as e:
        sys.exit(f"{path}: cannot read the benchmark's results ({e})")
    # Timing (wall time, "..._ms") lives in timing.json beside results.json since bench --plan.
    timing = {}
    if os.path.exists(os.path.join(out, "timing.json")):
        timing = {(t["sequence"], t["mode"]): t["timing"] for t in json.load(open(os.path.join(out, "timing.json")))}
    runs = {}
    for r in results:
        seq, mode, s = r["sequence"], r["mode"], r.get("summary")
        if isinstance(s, dict):
            merge(s, timing.get((seq, mode), {}))
        key, seed = seq.rsplit("_s", 1)
        runs[(key, int(seed), mode)] = s if isinstance(s, dict) else None
    return runs


def ate(s):
    if not s or "ate_rmse_m" not in s:
        return math.nan
    if s["ate_rmse_m"] > 0.1 * s.get("path_length_m", math.inf):
        return math.nan
    return s["ate_rmse_m"]


def mean(v):
    return sum(v) / len(v) if v and not any(math.isnan(x) for x in v) else math.nan


def seeds_of(runs):
    return sorted({k[1] for k in runs})


def per_key(runs, key, mode, f):
    return [f(runs.get((key, seed, mode))) for seed in seeds_of(runs) if (key, seed, mode) in runs]


def cls(name, default=math.nan):
    def get(s):
        if not s or not s.get("classification"):
            return default
        return s["classification"].get(name, default)
    return get


def fmt(x, d=3, pct=False):
    if math.isnan(x):
        return "–"
    return f"{100 * x:.{d}f} %" if pct else f"{x:.{d}f}"


def tables(runs):
    seeds = seeds_of(runs)
    modes = [m for m in MODES if any(k[2] == m for k in runs)]
    print("Per seed (m):\n")
    print("| sequence | " + " | ".join(modes) + " |")
    print("| --- |" + " --- |" * len(modes))
    for scene in SCENES:
        for level in LEVELS:
            for seed in seeds:
                key = f"{scene}_{level}"
                print(f"| {key}_s{seed} | " + " | ".join(fmt(ate(runs.get((key, seed, m)))) for m in modes) + " |")
    print("\nClassification (mean over seeds; brackets: tracks seen in at least two frames):\n")
    print("| sequence | mode | moving flagged (tracks ≥ 2 frames) | static flagged | static map on moving (ever) |")
    print("| --- | --- | --- | --- | --- |")
    for scene in SCENES:
        for level in LEVELS:
            key = f"{scene}_{level}"
            for m in modes:
                if level == "none" and m != "idy":
                    continue
                if level == "low" and m != "idy":
                    continue
                mv = mean(per_key(runs, key, m, cls("moving_detected_fraction")))
                mvt = mean(per_key(runs, key, m, cls("moving_detected_fraction_tracked")))
                st = mean(per_key(runs, key, m, cls("static_flagged_fraction")))
                mp = mean(per_key(runs, key, m, cls("static_map_fraction_on_moving")))
                mpe = mean(per_key(runs, key, m, cls("static_map_fraction_ever_on_moving")))
                if level == "none":
                    print(f"| {key} | {m} | – | {fmt(st, 2, True)} | – |")
                else:
                    print(f"| {key} | {m} | {fmt(mv, 1, True)} ({fmt(mvt, 1, True)}) | {fmt(st, 2, True)} | "
                          f"{fmt(mp, 2, True)} ({fmt(mpe, 2, True)}) |")
    print("\nidy static flagged per seed: " + "; ".join(
        f"{scene}_{level} " + " / ".join(fmt(x, 2, True) for x in per_key(runs, f"{scene}_{level}", "idy",
                                                                          cls("static_flagged_fraction")))
        for scene in SCENES for level in LEVELS))
    print("\nLost-corner test (idy, mean per sequence), tested / judged moving: " + "; ".join(
        f"{scene} {level} "
        f"{mean(per_key(runs, f'{scene}_{level}', 'idy', lambda s: (s or {}).get('lost_new_corners_tested', math.nan))):.0f}"
        f" / {mean(per_key(runs, f'{scene}_{level}', 'idy', lambda s: (s or {}).get('lost_new_corners_moving', math.nan))):.0f}"
        for scene in SCENES for level in LEVELS))


def targets(runs):
    def m(key, mode):
        return mean(per_key(runs, key, mode, ate))

    rows = []
    for level, bound in (("high", 0.6), ("mid", 0.8), ("none", 1.05)):
        qs = {sc: m(f"{sc}_{level}", "idy") / m(f"{sc}_{level}", "baseline") for sc in SCENES}
        ok = all(q <= bound for q in qs.values())
        rows.append((f"{level}: idy ≤ {bound} × baseline", ", ".join(f"{sc} {q:.2f}×" for sc, q in qs.items()), ok))
    beats = {(sc, lv): (m(f"{sc}_{lv}", "idy"), m(f"{sc}_{lv}", "ransac")) for sc in SCENES for lv in ("high", "mid")}
    rows.append(("idy beats ransac at high and mid",
                 ", ".join(f"{sc} {lv} {a:.3f} vs {b:.3f}" for (sc, lv), (a, b) in beats.items()),
                 all(a < b for a, b in beats.values())))
    rec = {(sc, lv): mean(per_key(runs, f"{sc}_{lv}", "idy", cls("moving_detected_fraction")))
           for sc in SCENES for lv in LEVELS[1:]}
    rows.append(("≥ 85 % of moving observations flagged", ", ".join(f"{sc} {lv} {fmt(x, 1, True)}" for (sc, lv), x in rec.items()),
                 all(x >= 0.85 for x in rec.values())))
    st = {(sc, lv): mean(per_key(runs, f"{sc}_{lv}", "idy", cls("static_flagged_fraction")))
          for sc in SCENES for lv in LEVELS}
    rows.append(("≤ 3 % of static observations flagged", ", ".join(f"{sc} {lv} {fmt(x, 2, True)}" for (sc, lv), x in st.items()),
                 all(x <= 0.03 for x in st.values())))
    mp = {(sc, lv): mean(per_key(runs, f"{sc}_{lv}", "idy", cls("static_map_fraction_on_moving")))
          for sc in SCENES for lv in LEVELS[1:]}
    rows.append(("static map ≤ 1 % on moving", ", ".join(f"{sc} {lv} {fmt(x, 2, True)}" for (sc, lv), x in mp.items()),
                 all(x <= 0.01 for x in mp.values())))
    pre = [s.get("mean_filter_ms", math.nan) for (k, seed, mode), s in runs.items() if mode == "idy" and s]
    rows.append(("dynamic preprocessing ≤ 1 ms per frame", f"max over idy runs {max(pre):.3f} ms", max(pre) <= 1.0))
    opt = {}
    for lv in LEVELS:
        for mode in ("idy", "baseline"):
            opt[(lv, mode)] = mean([s["mean_optimization_ms"] for (k, seed, md), s in runs.items()
                                    if md == mode and s and k.endswith("_" + lv)])
    rows.append(("idy mean optimization ≤ baseline's",
                 ", ".join(f"{lv} {opt[(lv, 'idy')]:.2f} vs {opt[(lv, 'baseline')]:.2f} ms" for lv in LEVELS),
                 all(opt[(lv, "idy")] <= opt[(lv, "baseline")] for lv in LEVELS)))
    print("\n| target | measured | |\n| --- | --- | --- |")
    for name, text, ok in rows:
        print(f"| {name} | {text} | {'met' if ok else '**missed**'} |")


def compare(runs, other):
    print("\nidy before (--compare) → after, mean over seeds: ATE m / static flagged / moving flagged\n")
    for scene in SCENES:
        for level in LEVELS:
            key = f"{scene}_{level}"
            cells = []
            for r in (other, runs):
                cells.append(f"{fmt(mean(per_key(r, key, 'idy', ate)))} / "
                             f"{fmt(mean(per_key(r, key, 'idy', cls('static_flagged_fraction'))), 2, True)} / "
                             f"{fmt(mean(per_key(r, key, 'idy', cls('moving_detected_fraction'))), 1, True)}")
            print(f"- {key}: {cells[0]} → {cells[1]}")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out")
    ap.add_argument("--compare")
    a = ap.parse_args()
    runs = load(a.out)
    tables(runs)
    targets(runs)
    if a.compare:
        compare(runs, load(a.compare))


if __name__ == "__main__":
    main()
