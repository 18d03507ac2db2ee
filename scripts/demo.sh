#!/usr/bin/env bash
# The showcase: simulate a 20 s `city high` sequence (generated once, cached in
# data_sim/), run `baseline` and `idy` on it, and print both side by side:
# trajectory error, dynamic-feature statistics, maps; then write their report page
# (idyvins report). Outputs in out/demo/.
set -euo pipefail
BUILD=${1:-build}
ROOT=$(cd "$(dirname "$0")/.." && pwd)
BIN="$ROOT/$BUILD/apps/idyvins"
DATA="$ROOT/data_sim/demo_city_high_s1"
OUT="$ROOT/out/demo"
# A render cached by an earlier version carries every key at that day's default (the simulator now writes
# only the changed ones, under this comment line): render it again so that today's defaults apply.
if [ -f "$DATA/meta.json" ] && ! grep -q "^# Keys not written here have their defaults" "$DATA/config/sim_stereo_imu_config.yaml"; then
  echo "== the cached sequence's config pins old defaults: rendering it again"
  rm -rf "$DATA"
fi
if [ ! -f "$DATA/meta.json" ]; then
  echo "== simulating a 20 s city high sequence (once; cached in $DATA)"
  "$BIN" simulate --scene city --level high --seed 1 --duration 20 --out "$DATA"
fi
for mode in baseline idy; do
  echo
  echo "== idyvins run --mode $mode"
  "$BIN" run --config "$DATA/config/sim_stereo_imu_config.yaml" --dataset "$DATA" --out "$OUT/$mode" --mode "$mode"
done
echo
echo "== side by side"
/usr/bin/python3 - "$OUT" <<'PY'
import json, sys
rows = []
for mode in ("baseline", "idy"):
    s = json.load(open(f"{sys.argv[1]}/{mode}/stats.json"))["summary"]
    c = s.get("classification") or {}
    rows.append((mode, s.get("ate_rmse_m", float("nan")), s.get("path_length_m", float("nan")),
                 c.get("moving_detected_fraction", 0), c.get("static_flagged_fraction", 0),
                 s["map_static_points"], c.get("static_map_fraction_on_moving", 0), s["map_dynamic_points"],
                 s["mean_optimization_ms"], s["mean_filter_ms"]))
print(f"{'mode':9} {'ATE (m)':>8} {'ATE/path':>9} {'moving flagged':>15} {'static flagged':>15} "
      f"{'static map':>11} {'on moving':>10} {'dynamic map':>12} {'opt ms':>7} {'dyn ms':>7}")
for m, ate, path, mov, sta, smap, smov, dmap, opt, dyn in rows:
    print(f"{m:9} {ate:8.3f} {100*ate/path:8.2f}% {100*mov:14.1f}% {100*sta:14.2f}% {smap:11d} {100*smov:9.2f}% "
          f"{dmap:12d} {opt:7.1f} {dyn:7.3f}")
PY
echo
"$BIN" report "$OUT/baseline" "$OUT/idy" --html "$OUT/report.html"
echo
echo "Trajectories (TUM, EuRoC CSV), stats.json and PLY maps are in $OUT/{baseline,idy}/."
echo "Open the report (offline, one file): $OUT/report.html"
