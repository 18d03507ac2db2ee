#!/usr/bin/env bash
# idyvins (baseline and idy) beside the public VINS-Fusion on the static sequences (no
# traffic) of simulated sets, same files, all load-independent (VINS-Fusion's time cap
# lifted: max_solver_time 10 s; idyvins stops solves on iterations and convergence).
# Usage: bench/peers_static.sh IDYVINS PEERS_ROOT OUT LABEL=DATA_DIR [LABEL=DATA_DIR ...]
#   PEERS_ROOT: where ../shared/peers/build_vins_fusion.sh built VINS-Fusion
#   DATA_DIR:   a folder of simulated sequences (bench --data); its *_none_s* are used
#   JOBS (environment, default 2): sequences run at the same time (each run uses one core)
#   MODES (environment, default "baseline idy"): idyvins modes
# Prints a markdown table of ATE RMSE (SE3, VINS-Fusion's by the peers' ate.py, idyvins' by
# `idyvins run` = `idyvins eval`, both over all estimated poses) and the ratios to VINS-Fusion.
set -euo pipefail
IDY=$1; PEERS_ROOT=$2; OUT=$3; shift 3
JOBS=${JOBS:-2}
MODES=${MODES:-baseline idy}
HERE=$(cd "$(dirname "$0")" && pwd)
PEERS=$HERE/../../shared/peers
mkdir -p "$OUT"

# One sequence: VINS-Fusion and each idyvins mode, each skipped when its result exists.
run_one() {
  local label=$1 seq=$2 name cfg res
  name=$(basename "$seq")
  cfg=$OUT/cfg/$label/$name
  res=$OUT/res/$label
  mkdir -p "$cfg" "$res"
  if [ ! -f "$res/vins_fusion_$name.ate.json" ]; then
    cp "$seq"/config/*.yaml "$cfg/"
    # VINS-Fusion's keys on top of the sequence's own config; the wall-clock cap lifted.
    # (the topics are dropped first: OpenCV's FileStorage refuses a key written twice)
    sed -i -e 's/^max_solver_time:.*/max_solver_time: 10.0/' -e '/^mode:/d' -e '/^lambda_dy/d' \
      -e '/^imu_topic:/d' -e '/^image[01]_topic:/d' \
      "$cfg/sim_stereo_imu_config.yaml"
    printf 'imu_topic: "/imu0"\nimage0_topic: "/cam0/image_raw"\nimage1_topic: "/cam1/image_raw"\noutput_path: "%s/"\nuse_imu: 1\nmultiple_thread: 0\nshow_track: 0\nload_previous_pose_graph: 0\npose_graph_save_path: "%s/"\nsave_image: 0\n' \
      "$OUT" "$OUT" >> "$cfg/sim_stereo_imu_config.yaml"
    PEERS_ROOT=$PEERS_ROOT "$PEERS/run_sequence.sh" vins_fusion "$seq" "$res" "$cfg/sim_stereo_imu_config.yaml" > /dev/null ||
      echo "VINS-Fusion failed on $seq" >&2
  fi
  for mode in $MODES; do
    [ -f "$res/${mode}_$name/stats.json" ] ||
      "$IDY" run -c "$seq/config/sim_stereo_imu_config.yaml" -d "$seq" -o "$res/${mode}_$name" --mode "$mode" \
        --threads 1 > "$res/${mode}_$name.log" 2>&1 || echo "idyvins $mode failed on $seq" >&2
  done
}
export -f run_one
export OUT PEERS PEERS_ROOT IDY MODES

specs=()
for spec in "$@"; do
  label=${spec%%=*}; data=${spec#*=}
  for seq in "$data"/*_none_s*; do
    [ -f "$seq/meta.json" ] && specs+=("$label $seq")
  done
done
printf '%s\n' "${specs[@]}" | xargs -P "$JOBS" -L 1 bash -c 'run_one "$0" "$1"'

ate_vins() { /usr/bin/python3 -c "import json,sys; print('%.4f' % json.load(open(sys.argv[1]))['rmse'])" "$1" 2>/dev/null || echo x; }
ate_idy() { /usr/bin/python3 -c "import json,sys; print('%.4f' % json.load(open(sys.argv[1]))['summary']['ate_rmse_m'])" "$1" 2>/dev/null || echo x; }
ratio() { /usr/bin/python3 -c "import sys; a,b=sys.argv[1:]; print('x' if 'x' in (a,b) else '%.2fx' % (float(a)/float(b)))" "$1" "$2"; }

header="| images | sequence | VINS-Fusion ATE (m) |"; rule="| --- | --- | --- |"
for mode in $MODES; do header="$header $mode ATE (m) | $mode / VINS-Fusion |"; rule="$rule --- | --- |"; done
echo "$header"; echo "$rule"
for item in "${specs[@]}"; do
  label=${item%% *}; seq=${item#* }; name=$(basename "$seq"); res=$OUT/res/$label
  vins=$(ate_vins "$res/vins_fusion_$name.ate.json")
  row="| $label | $name | $vins |"
  for mode in $MODES; do
    a=$(ate_idy "$res/${mode}_$name/stats.json")
    row="$row $a | $(ratio "$a" "$vins") |"
  done
  echo "$row"
done
