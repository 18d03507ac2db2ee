#!/usr/bin/env bash
# Issue-7 measurement (until `idyvins bench` exists): baseline / ransac / idy on the
# simulated city and parking_lot sequences (none, mid, high; 60 s; seed 1).
# usage: scripts/bench_dynamic.sh [DATA_DIR] [OUT_DIR]   (defaults: data_sim, out/bench_dynamic)
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
BIN="$ROOT/build/apps/idyvins"
DATA=${1:-$ROOT/data_sim}
OUT=${2:-$ROOT/out/bench_dynamic}
SEED=${SEED:-1}
mkdir -p "$DATA" "$OUT"
echo "| sequence | mode | ATE RMSE (m) | ATE / path | moving obs. flagged | static obs. flagged | static map on moving | opt ms | dyn. preprocess ms |"
echo "| --- | --- | --- | --- | --- | --- | --- | --- | --- |"
for scene in city parking_lot; do
  for level in none mid high; do
    ds="$DATA/${scene}_${level}_s${SEED}"
    [ -f "$ds/meta.json" ] || "$BIN" simulate --scene "$scene" --level "$level" --seed "$SEED" --duration 60 --out "$ds" > /dev/null 2>&1
    for mode in baseline ransac idy; do
      run="$OUT/${scene}_${level}_s${SEED}_${mode}"
      "$BIN" run --config "$ds/config/sim_stereo_imu_config.yaml" --dataset "$ds" --out "$run" --mode "$mode" > /dev/null 2>&1 || true
      /usr/bin/python3 - "$run/stats.json" "${scene} ${level}" "$mode" <<'PY'
import json, sys
try:
    s = json.load(open(sys.argv[1]))["summary"]
except Exception:
    print(f"| {sys.argv[2]} | {sys.argv[3]} | x | x | | | | | |"); sys.exit()
c = s.get("classification") or {}
ate, path = s.get("ate_rmse_m", float("nan")), s.get("path_length_m", float("nan"))
print(f"| {sys.argv[2]} | {sys.argv[3]} | {ate:.3f} | {100*ate/path:.2f} % | {100*c.get('moving_detected_fraction',0):.1f} % | "
      f"{100*c.get('static_flagged_fraction',0):.2f} % | {100*c.get('static_map_fraction_on_moving',0):.2f} % | "
      f"{s['mean_optimization_ms']:.1f} | {s['mean_filter_ms']:.3f} |")
PY
    done
  done
done
