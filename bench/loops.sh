#!/bin/bash
# Loop-closure and map-reuse benchmark (issue 39; docs/loop-closure.md#benchmark).
#   bench/loops.sh [IDYVINS] [DATA_DIR] [OUT_DIR]
# Renders (once) 3-minute looping sequences - laps of the garage (parking_lot) and of a city block
# (--route block), no and high traffic, seeds 1-3 - and two 2-minute runs through each place with
# other traffic and temporarily parked cars moved (--traffic-seed 11 / 12, --parked 6); runs each
# looping sequence in baseline and idy with loop_closure 1; builds a map from traffic seed 11 in
# each mode (--save-map) and localizes traffic seed 12 in it (--load-map --localization-only);
# and, to validate the loop parameters on data no default is tuned on, 120 s of garage laps of the
# validation family (handheld, EuRoC's intrinsics; none and high traffic) in idy;
# then bench/loops_eval.py writes OUT_DIR/loops.md and OUT_DIR/loops.json. Finished parts are kept
# (delete a folder to redo it). Hours on 2 cores: the renders take about real time, the runs 1-4x.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
B=${1:-$here/../build/apps/idyvins}
D=${2:-$here/../data_sim/loops}
O=${3:-$here/../out/loops}
mkdir -p "$D" "$O"
render() {  # NAME ARGS...: one sequence, unless rendered
  local out=$D/$1; shift
  [ -f "$out/meta.json" ] && return 0
  rm -rf "$out"
  "$B" simulate "$@" --out "$out" > /dev/null
  { sed '/^loop_closure:/d' "$out/config/sim_stereo_imu_config.yaml"; echo "loop_closure: 1"; } > "$out/config/loop.yaml"
}
run() {  # SEQ MODE OUT [ARGS...]: one run, unless done
  local seq=$1 mode=$2 out=$3; shift 3
  [ -f "$out/stats.json" ] && return 0
  [ -f "$D/$seq/config/loop.yaml" ] ||
    { sed '/^loop_closure:/d' "$D/$seq/config/sim_stereo_imu_config.yaml"; echo "loop_closure: 1"; } > "$D/$seq/config/loop.yaml"
  "$B" run -c "$D/$seq/config/loop.yaml" -d "$D/$seq" -o "$out" --mode "$mode" "$@" > "$out.log" 2>&1
}
seqs=()
for s in 1 2 3; do for l in none high; do
  render garage_${l}_s$s --scene parking_lot --level $l --seed $s --duration 180
  render block_${l}_s$s --scene city --route block --level $l --seed $s --duration 180
  seqs+=(garage_${l}_s$s block_${l}_s$s)
done; done
for l in none high; do  # the validation family (handheld, EuRoC's intrinsics): no default is tuned on it
  render validation_garage_${l}_s1 --family validation --scene parking_lot --level $l --seed 1 --duration 120
done
for t in 11 12; do
  render reuse_garage_t$t --scene parking_lot --level high --seed 1 --traffic-seed $t --parked 6 --duration 120
  render reuse_block_t$t --scene city --route block --level high --seed 1 --traffic-seed $t --parked 6 --duration 120
done
for seq in "${seqs[@]}"; do for mode in idy baseline; do run "$seq" $mode "$O/${seq}_$mode"; done; done
for l in none high; do run validation_garage_${l}_s1 idy "$O/validation_garage_${l}_s1_idy"; done
for place in garage block; do for mode in baseline idy; do
  run reuse_${place}_t11 $mode "$O/reuse_${place}_map_$mode" --save-map "$O/reuse_${place}_map_$mode.map"
  run reuse_${place}_t12 $mode "$O/reuse_${place}_loc_$mode" --load-map "$O/reuse_${place}_map_$mode.map" --localization-only
done; done
/usr/bin/python3 "$here/loops_eval.py" "$D" "$O"
