#!/usr/bin/env bash
# idyvins' baseline beside the public VINS-Fusion on the static sequences (no traffic) of
# simulated sets, same files, both load-independent (VINS-Fusion's time cap lifted:
# max_solver_time 10 s; idyvins stops solves on iterations and convergence).
# Usage: bench/peers_static.sh IDYVINS PEERS_ROOT OUT LABEL=DATA_DIR [LABEL=DATA_DIR ...]
#   PEERS_ROOT: where ../shared/peers/build_vins_fusion.sh built VINS-Fusion
#   DATA_DIR:   a folder of simulated sequences (bench --data); its *_none_s* are used
# Prints a markdown table of ATE RMSE (SE3, VINS-Fusion's by the peers' ate.py, idyvins' by
# `idyvins eval`, both over all estimated poses).
set -euo pipefail
IDY=$1; PEERS_ROOT=$2; OUT=$3; shift 3
HERE=$(cd "$(dirname "$0")" && pwd)
PEERS=$HERE/../../shared/peers
mkdir -p "$OUT"
rows=()
for spec in "$@"; do
  label=${spec%%=*}; data=${spec#*=}
  for seq in "$data"/*_none_s*; do
    [ -f "$seq/meta.json" ] || continue
    name=$(basename "$seq")
    cfg=$OUT/cfg/$label/$name
    mkdir -p "$cfg"
    cp "$seq"/config/*.yaml "$cfg/"
    # VINS-Fusion's keys on top of the sequence's own config; the wall-clock cap lifted.
    sed -i -e 's/^max_solver_time:.*/max_solver_time: 10.0/' -e '/^mode:/d' -e '/^lambda_dy/d' \
      "$cfg/sim_stereo_imu_config.yaml"
    printf 'imu_topic: "/imu0"\nimage0_topic: "/cam0/image_raw"\nimage1_topic: "/cam1/image_raw"\noutput_path: "%s/"\nuse_imu: 1\nmultiple_thread: 0\nshow_track: 0\nload_previous_pose_graph: 0\npose_graph_save_path: "%s/"\nsave_image: 0\n' \
      "$OUT" "$OUT" >> "$cfg/sim_stereo_imu_config.yaml"
    res=$OUT/res/$label
    mkdir -p "$res"
    [ -f "$res/vins_fusion_$name.ate.json" ] ||
      PEERS_ROOT=$PEERS_ROOT "$PEERS/run_sequence.sh" vins_fusion "$seq" "$res" "$cfg/sim_stereo_imu_config.yaml" > /dev/null
    vins=$(/usr/bin/python3 -c "import json,sys; print('%.3f' % json.load(open(sys.argv[1]))['rmse'])" "$res/vins_fusion_$name.ate.json" 2>/dev/null || echo x)
    [ -f "$res/idy_$name/stats.json" ] ||
      "$IDY" run -c "$seq/config/sim_stereo_imu_config.yaml" -d "$seq" -o "$res/idy_$name" --mode baseline --threads 1 > /dev/null 2>&1
    idy=$(/usr/bin/python3 -c "import json,sys; print('%.3f' % json.load(open(sys.argv[1]))['summary']['ate_rmse_m'])" "$res/idy_$name/stats.json")
    rows+=("| $label | $name | $vins | $idy |")
  done
done
printf "| images | sequence | VINS-Fusion ATE (m) | idyvins baseline ATE (m) |\n| --- | --- | --- | --- |\n"
printf "%s\n" "${rows[@]}"
