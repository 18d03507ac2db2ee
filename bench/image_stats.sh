#!/usr/bin/env bash
# Image statistics of the real EuRoC excerpt beside simulated sequences without and with
# camera realism (`simulate --realism euroc`), from `idyvins track --image-stats`.
# Usage: bench/image_stats.sh IDYVINS WORK [SHARED_DATA]
# Simulates city none seed 1, 5 s, twice into WORK; prints a markdown table and whether
# each statistic of the realism sequence lies within 25 % of the real excerpt's.
set -euo pipefail
IDY=$1; WORK=$2
HERE=$(cd "$(dirname "$0")" && pwd)
DATA=${3:-$HERE/../../shared/data}
mkdir -p "$WORK"
for r in none euroc; do
  S=$WORK/city_none_$r
  [ -f "$S/meta.json" ] || "$IDY" simulate --scene city --level none --seed 1 --duration 5 --realism $r --out "$S" > /dev/null 2>&1
  "$IDY" track -c "$S/config/sim_stereo_imu_config.yaml" -d "$S" --image-stats --json "$WORK/stats_$r.json" > /dev/null 2>&1
done
"$IDY" track -c "$HERE/../config/euroc/euroc_stereo_imu_config.yaml" -d "$DATA/euroc_v101_micro" --image-stats \
  --json "$WORK/stats_real.json" > /dev/null 2>&1
# The real excerpt with the simulator's tracker settings too (no equalization, 2 px epipolar gate).
mkdir -p "$WORK/euroc_plain" && cp "$HERE"/../config/euroc/*.yaml "$WORK/euroc_plain/"
sed -i -e 's/^equalize: 1/equalize: 0/' -e 's/^stereo_epipolar_px: 1.0/stereo_epipolar_px: 2.0/' \
  "$WORK/euroc_plain/euroc_stereo_imu_config.yaml"
"$IDY" track -c "$WORK/euroc_plain/euroc_stereo_imu_config.yaml" -d "$DATA/euroc_v101_micro" \
  --json "$WORK/stats_real_plain.json" > /dev/null 2>&1
/usr/bin/python3 - "$WORK" <<'PY'
import json, sys
w = sys.argv[1]
real, none, eu = (json.load(open(f"{w}/stats_{k}.json")) for k in ("real", "none", "euroc"))
plain = json.load(open(f"{w}/stats_real_plain.json"))
rows = [("brightness mean", "brightness_mean", "{:.1f}"), ("brightness std (within a frame)", "brightness_std", "{:.1f}"),
        ("frame-to-frame brightness variation", "frame_mean_variation", "{:.2%}"),
        ("gradient magnitude median (gray/px)", "gradient_median", "{:.2f}"),
        ("gradient magnitude p90 (gray/px)", "gradient_p90", "{:.2f}"),
        ("flat pixels (gradient < 2 gray/px)", "flat_fraction", "{:.1%}"),
        ("Shi-Tomasi corners (quality 0.01, 30 px)", "corners", "{:.0f}"),
        ("right / left brightness", "right_left_ratio", "{:.3f}")]
print("| statistic | real EuRoC excerpt | simulated, realism none | simulated, realism euroc | euroc within 25 % |")
print("| --- | --- | --- | --- | --- |")
def within(a, b):
    return "yes" if a and abs(b / a - 1) <= 0.25 else "**no**"
for name, key, fmt in rows:
    a, n, e = real["images"][key], none["images"][key], eu["images"][key]
    print(f"| {name} | {fmt.format(a)} | {fmt.format(n)} | {fmt.format(e)} | {within(a, e)} |")
for i in range(1, 5):
    a, n, e = (x["images"]["vignetting"][i] for x in (real, none, eu))
    print(f"| vignetting: ring {i} mean / centre ring | {a:.3f} | {n:.3f} | {e:.3f} | {within(a, e)} |")
a, n, e = real["right_fraction"], none["right_fraction"], eu["right_fraction"]
print(f"| stereo LK matches at the simulator's tracker settings (real: equalize 0, 2 px gate) | {plain['right_fraction']:.1%} | {n:.1%} | {e:.1%} | {within(plain['right_fraction'], e)} |")
print(f"| stereo LK matches, config/euroc settings (equalize 1, 1 px gate) | {a:.1%} | | | |")
print(f"| tracking ms per frame (config/euroc for the real excerpt) | {real['tracking_ms']:.2f} | {none['tracking_ms']:.2f} | {eu['tracking_ms']:.2f} | |")
PY
