#!/usr/bin/env bash
# Peak memory of reading and running on a ROS1 bag 10x longer than a short one
# (/usr/bin/time -v), and the same data as EuRoC folders, so that the bag reader's
# share of the growth is visible. Usage: bench/bag_memory.sh IDYVINS WORK
# (simulates city high seed 2 for 10 s and 100 s into WORK; the 100 s bag is 1.5 GB).
set -euo pipefail
IDY=$1; WORK=$2
HERE=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$WORK"
for d in 10 100; do
  S=$WORK/seq$d
  [ -f "$S/meta.json" ] || "$IDY" simulate --scene city --level high --seed 2 --duration $d --out "$S" > /dev/null 2>&1
  [ -f "$S.bag" ] || /usr/bin/python3 "$HERE/../tests/make_test_bag.py" "$S" "$S.bag"
done
peak() { grep 'Maximum resident' "$1" | awk '{print $NF}'; }
printf "| what | 10 s | 100 s | ratio |\n| --- | --- | --- | --- |\n"
for what in "info bag" "run bag" "run folder"; do
  set -- $what
  for d in 10 100; do
    S=$WORK/seq$d; D=$S; [ "$2" = bag ] && D=$S.bag
    C=$S/config/sim_stereo_imu_config.yaml
    if [ "$1" = info ]; then
      /usr/bin/time -v "$IDY" info "$D" -c "$C" --groundtruth-topic /odometry > /dev/null 2> "$WORK/time_$1_$2_$d"
    else
      /usr/bin/time -v "$IDY" run -c "$C" -d "$D" -o "$WORK/out_$2_$d" --groundtruth-topic /odometry > /dev/null 2> "$WORK/time_$1_$2_$d"
    fi
  done
  a=$(peak "$WORK/time_$1_$2_10"); b=$(peak "$WORK/time_$1_$2_100")
  awk -v w="$what" -v a="$a" -v b="$b" 'BEGIN { printf "| %s | %.1f MB | %.1f MB | %.2fx |\n", w, a / 1024, b / 1024, b / a }' 
done
