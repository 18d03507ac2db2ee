#!/usr/bin/env bash
# Reading throughput of ROS1 bags against the same data as a EuRoC folder: `idyvins info`
# decodes every image of every stereo pair; pairs/s and MB/s (input size / wall time).
# Usage: bench/bag_read_speed.sh IDYVINS BAG_WORK [MEM_WORK]
# BAG_WORK is the test suite's bag folder (build/tests/bag_check after `make test`:
# the 4 s city high sequence `seq` and the bags python3-rosbag wrote from it).
# MEM_WORK (optional): bench/bag_memory.sh's folder; its 100 s folder and uncompressed bag
# are timed too (the 4 s inputs are short enough for process start-up to count).
# Each input is read once to warm the page cache, then timed three times (median).
set -euo pipefail
IDY=$1; W=$2; M=${3:-}
CFG=$W/seq/config/sim_stereo_imu_config.yaml
inputs=("$W/seq" "$W/plain_mono8_odometry.bag" "$W/lz4_rgb8_pose.bag" "$W/lz4_png_point.bag" "$W/bz2_bgr8_transform.bag")
[ -n "$M" ] && inputs+=("$M/seq100" "$M/seq100.bag")
[ -f "$CFG" ] || { echo "$W: no seq/ folder (run the BagTestDataWritten test first)" >&2; exit 1; }
median3() { printf "%s\n" "$@" | sort -g | sed -n 2p; }
printf "| input | size | pairs | wall (median of 3) | pairs/s | MB/s |\n| --- | --- | --- | --- | --- | --- |\n"
for input in "${inputs[@]}"; do
  gt=(); cfg=$CFG
  case $input in
    *png*) cfg=$W/config_compressed/sim_stereo_imu_config.yaml ;;  # /camN/image_raw/compressed
  esac
  case $input in
    *odometry*|*seq100.bag) gt=(--groundtruth-topic /odometry) ;;
    *pose*) gt=(--groundtruth-topic /pose) ;;
    *point*) gt=(--groundtruth-topic /leica/position) ;;
    *transform*) gt=(--groundtruth-topic /vicon/firefly_sbx/firefly_sbx) ;;
  esac
  "$IDY" info "$input" -c "$cfg" "${gt[@]}" > /dev/null 2>&1 || { echo "info failed on $input" >&2; exit 1; }
  times=()
  for _ in 1 2 3; do
    s=$(date +%s.%N); "$IDY" info "$input" -c "$cfg" "${gt[@]}" > /dev/null 2>&1; e=$(date +%s.%N)
    times+=("$(echo "$e - $s" | bc -l)")
  done
  t=$(median3 "${times[@]}")
  if [ -d "$input" ]; then  # the images info reads, not the masks and CSVs beside them
    bytes=$(( $(du -sb "$input/mav0/cam0/data" | cut -f1) + $(du -sb "$input/mav0/cam1/data" | cut -f1) ))
  else
    bytes=$(stat -c %s "$input")
  fi
  pairs=$("$IDY" info "$input" -c "$cfg" "${gt[@]}" --skip-images --json 2>/dev/null |
          /usr/bin/python3 -c "import json,sys; print(json.load(sys.stdin)['stereo_pairs']['count'])")
  awk -v n="$(basename "$input")" -v b="$bytes" -v p="$pairs" -v t="$t" \
    'BEGIN { printf "| %s | %.1f MB | %d | %.2f s | %.0f | %.1f |\n", n, b / 1e6, p, t, p / t, b / 1e6 / t }'
done
