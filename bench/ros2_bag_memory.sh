#!/usr/bin/env bash
# Peak memory and read speed on ROS 2 bags (rosbag2 folders with one MCAP, written by
# `simulate --format mcap`), a short one and one 10x longer: `info` decoding every image and `run`,
# /usr/bin/time -v, so that the reader's share of the growth is visible.
# Usage: bench/ros2_bag_memory.sh IDYVINS WORK [COMPRESSION]   (none, zstd (default), lz4;
# simulates city high seed 2 for 10 s and 100 s into WORK; the 100 s bag is about 1.4 GB).
set -euo pipefail
IDY=$1; WORK=$2; COMP=${3:-zstd}
mkdir -p "$WORK"
for d in 10 100; do
  S=$WORK/mcap_${COMP}_$d
  [ -f "$S/3_high/metadata.yaml" ] || "$IDY" simulate --scene city --level high --seed 2 --duration $d --out "$S" \
    --format mcap --compression "$COMP" > /dev/null 2>&1
done
peak() { grep 'Maximum resident' "$1" | awk '{print $NF}'; }
wall() { grep 'Elapsed (wall' "$1" | awk '{print $NF}' | awk -F: '{ s = 0; for (i = 1; i <= NF; ++i) s = 60 * s + $i; print s }'; }
printf "| what (%s chunks) | 10 s | 100 s | ratio |\n| --- | --- | --- | --- |\n" "$COMP"
for what in info run; do
  for d in 10 100; do
    S=$WORK/mcap_${COMP}_$d; B=$S/3_high; C=$S/config/sim_stereo_imu_config.yaml
    if [ "$what" = info ]; then
      /usr/bin/time -v "$IDY" info "$B" -c "$C" > /dev/null 2> "$WORK/time_${what}_${COMP}_$d"
    else
      /usr/bin/time -v "$IDY" run -c "$C" -d "$B" -o "$WORK/out_${COMP}_$d" --force > /dev/null 2> "$WORK/time_${what}_${COMP}_$d"
    fi
  done
  a=$(peak "$WORK/time_${what}_${COMP}_10"); b=$(peak "$WORK/time_${what}_${COMP}_100")
  awk -v w="$what" -v a="$a" -v b="$b" 'BEGIN { printf "| %s | %.1f MB | %.1f MB | %.2fx |\n", w, a / 1024, b / 1024, b / a }'
done
for d in 10 100; do
  S=$WORK/mcap_${COMP}_$d
  mb=$(du -sm "$S/3_high" | awk '{print $1}'); t=$(wall "$WORK/time_info_${COMP}_$d")
  pairs=$(grep -c . "$S/3_high/metadata.yaml" > /dev/null; awk '/name: \/cam0\/image_raw/ { f = 1 } f && /message_count/ { print $2; exit }' "$S/3_high/metadata.yaml")
  awk -v d="$d" -v mb="$mb" -v t="$t" -v p="$pairs" 'BEGIN { printf "info %d s: %d MB, %d stereo pairs in %.2f s: %.0f pairs/s, %.0f MB/s\n", d, mb, p, t, p / t, mb / t }'
done
