#!/usr/bin/env bash
# Issue-6 benchmark: baseline mode on the static simulated sequences
# (city and parking_lot, level none, 60 s, seeds 1-3). Prints a Markdown table.
# usage: scripts/bench_baseline.sh [DATA_DIR] [OUT_DIR]   (defaults: data_sim, out/bench_baseline)
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
BIN="$ROOT/build/apps/idyvins"
DATA=${1:-$ROOT/data_sim}
OUT=${2:-$ROOT/out/bench_baseline}
mkdir -p "$DATA" "$OUT"
echo "| sequence | path (m) | ATE RMSE SE3 (m) | ATE / path | init (s) | resets | mean opt (ms) | real-time factor |"
echo "| --- | --- | --- | --- | --- | --- | --- | --- |"
for scene in city parking_lot; do
  for seed in 1 2 3; do
    ds="$DATA/${scene}_none_s${seed}"
    [ -f "$ds/meta.json" ] || "$BIN" simulate --scene "$scene" --level none --seed "$seed" --duration 60 --out "$ds" > /dev/null 2>&1
    run="$OUT/${scene}_none_s${seed}"
    "$BIN" run --config "$ds/config/sim_stereo_imu_config.yaml" --dataset "$ds" --out "$run" --mode baseline > /dev/null 2>&1
    /usr/bin/python3 - "$run/stats.json" "${scene} none s${seed}" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))["summary"]
ate, path = s.get("ate_rmse_m", float("nan")), s.get("path_length_m", float("nan"))
print(f"| {sys.argv[2]} | {path:.1f} | {ate:.3f} | {100 * ate / path:.2f} % | {s['initialized_at_s']:.2f} | "
      f"{len(s['resets'])} | {s['mean_optimization_ms']:.1f} | {s['realtime_factor']:.2f}x |")
PY
  done
done
