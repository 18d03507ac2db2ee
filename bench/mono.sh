#!/usr/bin/env bash
# One camera + IMU beside two (issue "One camera + IMU, the fisheye lenses people fly, and every
# rig VINS-Fusion ships a config for"): 20 s streets of both families (static clean and
# --realism euroc, mid and high traffic), baseline and idy with num_of_cam 1 (cam0 of the same
# files) and 2, and, when PEERS_ROOT holds it, VINS-Fusion with num_of_cam 1 on the same files
# (its time cap lifted: max_solver_time 10 s).
# Usage: bench/mono.sh IDYVINS WORK [PEERS_ROOT]   (JOBS runs at a time, default 2; finished
# runs are kept, so a second call only prints the table)
set -euo pipefail
IDY=$1; WORK=$2; PEERS_ROOT=${3:-}
JOBS=${JOBS:-2}
HERE=$(cd "$(dirname "$0")" && pwd)
PEERS=$HERE/../../shared/peers
VINS=${PEERS_ROOT:+$PEERS_ROOT/vins-fusion/build/vins_fusion_euroc}
[ -n "$VINS" ] && [ ! -x "$VINS" ] && { echo "no VINS-Fusion in $PEERS_ROOT (../shared/peers/README.md)" >&2; VINS=; }
mkdir -p "$WORK/mono" "$WORK/vins_mono"
# shellcheck source=bench/sim_runs.sh
. "$HERE/sim_runs.sh"
SEQS=("standard city --seed 1 --level none" "standard city --seed 1 --level none --realism euroc"
      "standard city --seed 1 --level mid" "standard city --seed 1 --level high"
      "validation city --seed 2 --level none" "validation city --seed 2 --level none --realism euroc"
      "validation city --seed 2 --level mid" "validation city --seed 2 --level high")
name() { echo "$1" | sed -e 's/--seed /s/; s/ --level none//; s/ --level /_/; s/ --realism euroc/_realism/; s/ /_/g'; }

jobs=(); names=()
for s in "${SEQS[@]}"; do
  set -- $s
  n=$(name "$s"); S=$WORK/$n
  [ -f "$S/meta.json" ] || "$IDY" simulate --family "$1" --scene "$2" "${@:3}" --duration 20 --out "$S" > /dev/null 2>&1
  names+=("$n")
  for mode in baseline idy; do
    jobs+=("idy $WORK/mono/$n.$mode.mono $S $mode num_of_cam=1" "idy $WORK/mono/$n.$mode.stereo $S $mode")
  done
  [ -n "$VINS" ] && jobs+=("vins $n $S")
done

# vins_mono NAME SEQ: VINS-Fusion with num_of_cam 1 on SEQ's own config, the wall-clock cap lifted.
vins_mono() {
  local n=$1 seq=$2 cfg=$WORK/vins_mono/$1.cfg
  [ -f "$WORK/vins_mono/vins_fusion_$n.ate.json" ] && return 0
  rm -rf "$cfg"; mkdir -p "$cfg"
  cp "$seq"/config/*.yaml "$cfg/"
  sed -i -e 's/^max_solver_time:.*/max_solver_time: 10.0/' -e 's/^num_of_cam:.*/num_of_cam: 1/' \
    "$cfg/sim_stereo_imu_config.yaml"
  ln -sfn "$seq" "$WORK/vins_mono/$n"
  PEERS_ROOT=$PEERS_ROOT "$PEERS/run_sequence.sh" vins_fusion "$WORK/vins_mono/$n" "$WORK/vins_mono" \
    "$cfg/sim_stereo_imu_config.yaml" > /dev/null 2>&1 || echo "VINS-Fusion failed on $n" >&2
}
one_run() {
  local kind=$1
  shift
  if [ "$kind" = vins ]; then vins_mono "$@"; else
    local dir=$1 seq=$2 mode=$3
    shift 3
    sim_run "$IDY" "$dir" "$seq" "$mode" "$@"
  fi
}
export -f one_run vins_mono sim_run
export IDY WORK PEERS PEERS_ROOT
printf '%s\n' "${jobs[@]}" | xargs -P "$JOBS" -I{} bash -c 'one_run {}'

# The table: ATE (m), moving / static observations flagged (idy), first pose.
ate() { grep -o 'ATE RMSE (SE3) [0-9.]*' "$1.log" 2>/dev/null | awk '{print $4}' || true; }
flags() { grep -o 'vs ground-truth masks: [0-9.]*% [a-z ]*dynamic, [0-9.]*%' "$1.log" 2>/dev/null |
  awk '{print $4 " / " $(NF)}' || true; }
init() { grep -o 'initialized at [0-9.]* s' "$1.log" 2>/dev/null | awk '{print $3}' || true; }
echo "| sequence | mono baseline | mono idy (x baseline) | mono idy flagged moving / static | first pose (s) | stereo baseline | stereo idy | VINS-Fusion mono |"
echo "| --- | --- | --- | --- | --- | --- | --- | --- |"
for n in "${names[@]}"; do
  M=$WORK/mono/$n
  mb=$(ate "$M.baseline.mono"); mi=$(ate "$M.idy.mono")
  ratio=$(awk -v a="$mi" -v b="$mb" 'BEGIN { if (b > 0) printf "%.2fx", a / b }')
  v=$(grep -o '"rmse": [0-9.]*' "$WORK/vins_mono/vins_fusion_$n.ate.json" 2>/dev/null | awk '{printf "%.4f", $2}' || true)
  echo "| $n | $mb | $mi ($ratio) | $(flags "$M.idy.mono") | $(init "$M.baseline.mono") | $(ate "$M.baseline.stereo") |" \
    "$(ate "$M.idy.stereo") | ${v:--} |"
done
