#!/usr/bin/env bash
# IMU dropouts carried by stereo alone (bridge_imu_gaps): rendered 20 s static streets of both
# families, clean and realistic, each with its IMU silent for 0.5 s and 2 s from 8 s on
# (`idyvins perturb --fault imu-gap`), run in baseline mode with bridge_imu_gaps 1 (now) and 0
# (the segment ends, as before). Prints a markdown table: ATE RMSE (SE3, whole file), resets and
# frames carried on stereo alone, against the fault-free run and its target 2x + 1 cm.
# Usage: bench/imu_gap.sh IDYVINS WORK   (JOBS runs at a time, default 2; finished runs are kept)
set -euo pipefail
IDY=$1; WORK=$2; JOBS=${JOBS:-2}
HERE=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$WORK"
# shellcheck source=bench/sim_runs.sh
. "$HERE/sim_runs.sh"
SEQS=("standard city --seed 1" "standard city --seed 1 --realism euroc" "validation city --seed 2"
      "validation city --seed 2 --realism euroc")
name() { echo "$1" | sed -e 's/--seed /s/; s/ --realism euroc/_realism/; s/ /_/g'; }
jobs=()
for s in "${SEQS[@]}"; do
  set -- $s
  n=$(name "$s"); S=$WORK/$n
  [ -f "$S/meta.json" ] || "$IDY" simulate --family "$1" --scene "$2" --level none "${@:3}" --duration 20 --out "$S" \
    > /dev/null 2>&1
  for g in 0.5 2; do
    [ -f "$S.gap$g/meta.json" ] || "$IDY" perturb "$S" "$S.gap$g" --fault imu-gap --at 8 --duration $g > /dev/null
  done
  jobs+=("$WORK/runs/$n.free $S" "$WORK/runs/$n.gap0.5.bridge $S.gap0.5" "$WORK/runs/$n.gap0.5.reset $S.gap0.5 bridge_imu_gaps=0"
         "$WORK/runs/$n.gap2.bridge $S.gap2" "$WORK/runs/$n.gap2.reset $S.gap2 bridge_imu_gaps=0")
done
export IDY
export -f sim_run
printf '%s\n' "${jobs[@]}" | xargs -P "$JOBS" -L 1 bash -c 'sim_run "$IDY" "$0" "$1" baseline "${@:2}"'
val() { /usr/bin/python3 -c "import json,sys; s=json.load(open(sys.argv[1]))['summary']; print('%.4f %d %d' % (s.get('ate_rmse_m', float('nan')), len(s['resets']), s.get('frames_stereo_only', 0)))" "$1/stats.json"; }
printf "| sequence | fault-free ATE | target | 0.5 s gap: segment ends (before) | 0.5 s gap: stereo alone (now) | 2 s: before | 2 s: now |\n"
printf "| --- | --- | --- | --- | --- | --- | --- |\n"
for s in "${SEQS[@]}"; do
  n=$(name "$s"); R=$WORK/runs/$n
  read -r free _ _ <<< "$(val "$R.free")"
  row="| $n | $free m | $(awk -v a="$free" 'BEGIN { printf "%.4f", 2 * a + 0.01 }') m"
  for g in 0.5 2; do
    read -r a r _ <<< "$(val "$R.gap$g.reset")"; row="$row | $a m, $r reset(s)"
    read -r a r f <<< "$(val "$R.gap$g.bridge")"; row="$row | $a m, $r reset(s), $f frames on stereo"
  done
  echo "$row |"
done
