#!/usr/bin/env bash
# Every rig of VINS-Fusion's config/ folder (issue "One camera + IMU, the fisheye lenses people
# fly, and every rig VINS-Fusion ships a config for"): `simulate --rig NAME` renders a 20 s
# static street (standard city, seed 1) with the config's published calibration, the config it
# writes is loaded unchanged, and `run` (baseline and idy, one thread) goes to the end.
# Usage: bench/vins_configs.sh IDYVINS WORK   (JOBS at a time, default 2; finished runs are kept)
set -euo pipefail
IDY=$1; WORK=$2
JOBS=${JOBS:-2}
RIGS=(euroc_mono_imu euroc_stereo euroc_stereo_imu a3_ptgrey_mono_imu a3_ptgrey_stereo a3_ptgrey_stereo_imu
      mynteye_mono_imu mynteye_stereo mynteye_stereo_imu realsense_stereo_imu kitti_odom_00_02 kitti_odom_03
      kitti_odom_04_12 kitti_odom_13_21 kitti_raw_09_30 kitti_raw_10_03 vi_car simulation)
mkdir -p "$WORK/runs"
config_of() { /usr/bin/python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["config"])' "$1/meta.json"; }
one() {
  local rig=$1 seq=$WORK/$1 mode
  [ -f "$seq/meta.json" ] || "$IDY" simulate --scene city --level none --seed 1 --duration 20 --rig "$rig" \
    --threads 1 --out "$seq" > "$WORK/runs/$rig.simulate.log" 2>&1
  local cfg; cfg=$seq/$(config_of "$seq")
  "$IDY" info "$seq" --config "$cfg" > "$WORK/runs/$rig.info.log" 2>&1 || true
  for mode in baseline idy; do
    local out=$WORK/runs/$rig.$mode
    [ -f "$out/stats.json" ] && continue
    "$IDY" run -c "$cfg" -d "$seq" -o "$out" --mode "$mode" --threads 1 > "$out.log" 2>&1 || true
  done
}
export -f one config_of
export IDY WORK
printf '%s\n' "${RIGS[@]}" | xargs -P "$JOBS" -I{} bash -c 'one {}'

ate() { grep -o 'ATE RMSE (SE3) [0-9.]*' "$1.log" 2>/dev/null | awk '{print $4}' || true; }
echo "| rig (\`simulate --rig\`) | VINS-Fusion config | cameras | num_of_cam, imu | loads | baseline ATE (m) | idy ATE (m) | first pose (s) |"
echo "| --- | --- | --- | --- | --- | --- | --- | --- |"
for rig in "${RIGS[@]}"; do
  seq=$WORK/$rig; R=$WORK/runs/$rig
  cfg=$seq/$(config_of "$seq")
  cams=$(grep -h '^model_type' "$seq"/config/*.yaml 2>/dev/null | awk '{print $2}' | sort | uniq -c | awk '{printf "%s%s x%s", (NR>1?", ":""), $2, $1}')
  size=$(grep -E '^image_(width|height):' "$cfg" | awk '{print $2}' | paste -sd x)
  nc=$(grep '^num_of_cam:' "$cfg" | awk '{print $2}'); imu=$(grep '^imu:' "$cfg" | awk '{print $2}')
  if grep -q 'valid: yes' "$R.info.log"; then
    loads=yes; w=$(grep -c '^warning' "$R.info.log" || true); [ "$w" -gt 0 ] && loads="yes, $w warning(s)"
  else
    loads="refused: $(grep -m1 -v '^\s*$' "$R.info.log" | sed 's/.*yaml:[0-9]*: //' | cut -c1-90)"
  fi
  first=$(grep -o 'initialized at [0-9.]* s' "$R.baseline.log" 2>/dev/null | awk '{print $3}' || true)
  echo "| $rig | $(basename "$cfg") | $cams, $size | $nc, $imu | $loads | $(ate "$R.baseline") | $(ate "$R.idy") | ${first:--} |"
done
