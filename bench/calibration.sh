#!/usr/bin/env bash
# A rig as it comes off the bench (issue "camera-IMU extrinsics estimated online, a time offset
# found from any start, the window carried on stereo alone"): the whole target table on rendered
# 20 s static streets of both families, clean and --realism euroc, idyvins (baseline mode) and,
# when PEERS_ROOT holds it, the public VINS-Fusion on the same files and keys (its time cap
# lifted: max_solver_time 10 s; idyvins stops solves on iterations and convergence).
#   extrinsic: the rig moved against the IMU (`idyvins perturb --fault extrinsic`, both cameras,
#              the stereo pair kept) by 1 deg/1 cm and 3 deg/3 cm, estimate_extrinsic 0 (before:
#              the key was read and ignored) and 1; exact with 1 (its cost); 2 from identity
#              rotations (the translations as written).
#   offset:    images stamped -50, -20, +10, +30, +50 ms off (`perturb --fault time-offset`):
#              td given, and estimate_td 1 from td 0 (VINS-Fusion: VINS_OFFSETS, default -50 30 50).
#   IMU gap:   0.5 s and 2 s without IMU samples from 8 s on (bridge_imu_gaps 1).
#   no IMU:    imu: 0 (stereo alone).
#   traffic:   mid and high traffic, baseline and idy, as rendered, with estimate_extrinsic 1 and
#              estimate_td 1 from td 0 (exact calibration), and with imu: 0 (idy's constant-velocity prior).
# Usage: bench/calibration.sh IDYVINS WORK [PEERS_ROOT]   (JOBS runs at a time, default 2, both
# programs in one queue;
# finished runs are kept, so a second call only prints the tables)
set -euo pipefail
IDY=$1; WORK=$2; PEERS_ROOT=${3:-}
JOBS=${JOBS:-2}
HERE=$(cd "$(dirname "$0")" && pwd)
PEERS=$HERE/../../shared/peers
VINS=${PEERS_ROOT:+$PEERS_ROOT/vins-fusion/build/vins_fusion_euroc}
[ -n "$VINS" ] && [ ! -x "$VINS" ] && { echo "no VINS-Fusion in $PEERS_ROOT (../shared/peers/README.md)" >&2; VINS=; }
mkdir -p "$WORK/runs" "$WORK/vins"
# shellcheck source=bench/sim_runs.sh
. "$HERE/sim_runs.sh"
SEQS=("standard city --seed 1" "standard city --seed 1 --realism euroc" "validation city --seed 2"
      "validation city --seed 2 --realism euroc")
OFFSETS=(-50 -20 10 30 50)
VINS_OFFSETS=${VINS_OFFSETS:-"-50 30 50"}  # VINS-Fusion's offset runs (each costs it as much as idyvins)
# VINS_SEQS: the sequence names VINS-Fusion runs on (default every one)
CFG=config/sim_stereo_imu_config.yaml
name() { echo "$1" | sed -e 's/--seed /s/; s/ --realism euroc/_realism/; s/ /_/g'; }

# identity_rotation CFG: body_T_cam0's rotation set to identity, body_T_cam1 moved with it (the
# stereo pair kept), the translations as written: a rig without a usable rotation guess.
identity_rotation() {
  /usr/bin/python3 - "$1" <<'EOF'
import re, sys
import numpy as np
path = sys.argv[1]
text = open(path).read()
def get(key):
    m = re.search(key + r":.*?data:\s*\[([^\]]*)\]", text, re.S)
    return np.array([float(x) for x in m.group(1).split(",")]).reshape(4, 4), m
T0, _ = get("body_T_cam0")
T1, _ = get("body_T_cam1")
N0 = np.eye(4); N0[:3, 3] = T0[:3, 3]
N1 = N0 @ np.linalg.inv(T0) @ T1
for key, T in (("body_T_cam0", N0), ("body_T_cam1", N1)):
    _, m = get(key)
    data = ", ".join("%.12g" % v for v in T.reshape(-1))
    text = text[:m.start(1)] + data + text[m.end(1):]
open(path, "w").write(text)
EOF
}

# Sequences and their faults.
idy_jobs=(); vins_jobs=(); TRAFFIC=()
for s in "${SEQS[@]}"; do
  set -- $s
  n=$(name "$s"); S=$WORK/$n
  [ -f "$S/meta.json" ] || "$IDY" simulate --family "$1" --scene "$2" --level none "${@:3}" --duration 20 --out "$S" \
    > /dev/null 2>&1
  for e in 1 3; do
    [ -f "$S.ex$e/perturb.json" ] || "$IDY" perturb "$S" "$S.ex$e" --fault extrinsic --config "$S/$CFG" \
      --rotation-deg $e --translation-cm $e > /dev/null
  done
  if [ ! -f "$S.id/perturb.json" ]; then
    "$IDY" perturb "$S" "$S.id" --fault extrinsic --config "$S/$CFG" --rotation-deg 0.001 --translation-cm 0.001 > /dev/null
    cp "$S/$CFG" "$S.id/$CFG" && identity_rotation "$S.id/$CFG"
  fi
  for m in "${OFFSETS[@]}"; do
    [ -f "$S.td$m/perturb.json" ] || "$IDY" perturb "$S" "$S.td$m" --fault time-offset --magnitude "$m" > /dev/null
  done
  for g in 0.5 2; do
    [ -f "$S.gap$g/perturb.json" ] || "$IDY" perturb "$S" "$S.gap$g" --fault imu-gap --at 8 --duration $g > /dev/null
  done
  R=$WORK/runs/$n
  idy_jobs+=("$R.exact $S" "$R.exact.est1 $S estimate_extrinsic=1" "$R.id.est2 $S.id estimate_extrinsic=2"
             "$R.noimu $S imu=0" "$R.gap0.5 $S.gap0.5" "$R.gap2 $S.gap2")
  vins_here=0; case " ${VINS_SEQS:-$n} " in *" $n "*) vins_here=1 ;; esac  # VINS-Fusion on VINS_SEQS (default all)
  [ $vins_here = 1 ] && vins_jobs+=("$n.exact $S" "$n.id.est2 $S.id estimate_extrinsic=2" "$n.noimu $S imu=0" "$n.gap0.5 $S.gap0.5"
              "$n.gap2 $S.gap2")
  for e in 1 3; do
    idy_jobs+=("$R.ex$e.est0 $S.ex$e" "$R.ex$e.est1 $S.ex$e estimate_extrinsic=1")
    [ $vins_here = 1 ] && vins_jobs+=("$n.ex$e.est0 $S.ex$e estimate_extrinsic=0" "$n.ex$e.est1 $S.ex$e estimate_extrinsic=1")
  done
  for m in "${OFFSETS[@]}"; do
    td=$(awk -v m="$m" 'BEGIN { printf "%.3f", m / 1000 }')
    idy_jobs+=("$R.td$m.given $S.td$m td=$td" "$R.td$m.est $S.td$m estimate_td=1 td=0")
    case " $VINS_OFFSETS " in *" $m "*) [ $vins_here = 1 ] && vins_jobs+=("$n.td$m.given $S.td$m td=$td" "$n.td$m.est $S.td$m estimate_td=1 td=0") ;; esac
  done
done

# Traffic with both estimates on (the idy targets: mid <= 0.8x, high <= 0.6x the baseline), and
# idy's constant-velocity prior without the IMU against the baseline without it.
declare -A MODE_OF
for s in "standard city --seed 1" "validation city --seed 2"; do
  set -- $s
  for level in mid high; do
    n=$(name "$s")_$level; S=$WORK/$n; R=$WORK/runs/$n
    [ -f "$S/meta.json" ] || "$IDY" simulate --family "$1" --scene "$2" --level $level "${@:3}" --duration 20 \
      --out "$S" > /dev/null 2>&1
    for mode in baseline idy; do
      idy_jobs+=("$R.$mode.plain $S" "$R.$mode.est $S estimate_extrinsic=1 estimate_td=1 td=0" "$R.$mode.noimu $S imu=0")
      MODE_OF[$R.$mode.plain]=$mode; MODE_OF[$R.$mode.est]=$mode; MODE_OF[$R.$mode.noimu]=$mode
    done
    TRAFFIC+=("$n")
  done
done

# vins_run NAME SEQ KEY=VALUE ...: VINS-Fusion on SEQ with the sequence's own config, its keys set.
vins_run() {
  local n=$1 seq=$2 cfg=$WORK/vins/$1.cfg kv
  shift 2
  [ -f "$WORK/vins/vins_fusion_$n.ate.json" ] && return 0
  rm -rf "$cfg"; mkdir -p "$cfg"
  cp "$seq"/config/*.yaml "$cfg/"
  local f=$cfg/sim_stereo_imu_config.yaml
  # as bench/peers_static.sh: VINS-Fusion's keys on top, the wall-clock cap lifted
  sed -i -e 's/^max_solver_time:.*/max_solver_time: 10.0/' -e '/^mode:/d' -e '/^lambda_dy/d' \
    -e '/^imu_topic:/d' -e '/^image[01]_topic:/d' "$f"
  printf 'imu_topic: "/imu0"\nimage0_topic: "/cam0/image_raw"\nimage1_topic: "/cam1/image_raw"\noutput_path: "%s/"\nmultiple_thread: 0\nshow_track: 0\nload_previous_pose_graph: 0\npose_graph_save_path: "%s/"\nsave_image: 0\n' \
    "$WORK/vins" "$WORK/vins" >> "$f"
  for kv in "$@"; do
    sed -i -e "/^${kv%%=*}:/d" "$f"
    printf '%s: %s\n' "${kv%%=*}" "${kv#*=}" >> "$f"
  done
  # the link to the folder the run is named after, so the peers' files carry its name
  ln -sfn "$seq" "$WORK/vins/$n"
  PEERS_ROOT=$PEERS_ROOT "$PEERS/run_sequence.sh" vins_fusion "$WORK/vins/$n" "$WORK/vins" "$f" > /dev/null 2>&1 ||
    echo "VINS-Fusion failed on $n" >&2
}
# one_run KIND NAME ...: an idyvins (sim_run, baseline unless the keys say mode=) or VINS-Fusion run.
one_run() {
  local kind=$1
  shift
  case $kind in
    idy) sim_run "$IDY" "$@" ;;
    vins) [ -n "$VINS" ] && vins_run "$@" ;;
  esac
  return 0
}
export IDY WORK PEERS PEERS_ROOT VINS
export -f sim_run vins_run one_run
# One queue for both programs, JOBS at a time (the longest, idyvins', first).
{
  # no trailing blank: xargs -L continues such a line onto the next
  for j in "${idy_jobs[@]}"; do set -- $j; echo "idy $1 $2 ${MODE_OF[$1]:-baseline}${3:+ ${*:3}}"; done
  for j in "${vins_jobs[@]}"; do echo "vins $j"; done
} | xargs -P "$JOBS" -L 1 bash -c 'one_run "$0" "$@"'

# The tables.
/usr/bin/python3 "$HERE/calibration_table.py" "$WORK" "${OFFSETS[*]}" "${TRAFFIC[*]}" \
  $(for s in "${SEQS[@]}"; do name "$s"; done)
