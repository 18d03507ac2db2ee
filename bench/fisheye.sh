#!/usr/bin/env bash
# Fisheye end to end (issue "one camera + IMU, the fisheye lenses people fly"): the same scene and
# trajectory rendered through the family's pinhole, the two full-frame 150 deg fisheye
# lenses of `simulate --lens` (Kannala-Brandt, MEI) and the circular 185 deg one (kb185), 20 s
# streets of both families, no traffic and
# mid traffic; baseline and idy on each; ATE RMSE (SE3, whole file) and its ratio to the pinhole
# render, and idy's moving / static flagged fractions (the dynamic classification).
# Usage: bench/fisheye.sh IDYVINS WORK   (JOBS runs at a time, default 2; finished runs are kept)
set -euo pipefail
IDY=$1; WORK=$2
JOBS=${JOBS:-2}
HERE=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$WORK/runs"
# shellcheck source=bench/sim_runs.sh
. "$HERE/sim_runs.sh"
SEQS=("standard city --seed 1" "validation city --seed 2")
jobs=(); names=()
for s in "${SEQS[@]}"; do
  set -- $s
  for level in none mid; do
    for lens in pinhole kb mei kb185; do
      n=$1_$2_s${4}_${level}_$lens; S=$WORK/$n
      [ -f "$S/meta.json" ] || "$IDY" simulate --family "$1" --scene "$2" --level $level "${@:3}" --duration 20 \
        --lens $lens --out "$S" > /dev/null 2>&1
      for mode in baseline idy; do jobs+=("$WORK/runs/$n.$mode $S $mode"); done
    done
    names+=("$1_$2_s${4}_${level}")
  done
done
export IDY
export -f sim_run
printf '%s\n' "${jobs[@]}" | xargs -P "$JOBS" -L 1 bash -c 'sim_run "$IDY" "$0" "$1" "$2"'
/usr/bin/python3 - "$WORK" "${names[@]}" <<'PY'
import json, math, os, sys
work, names = sys.argv[1], sys.argv[2:]
def summ(run):
    try:
        return json.load(open(os.path.join(work, "runs", run, "stats.json")))["summary"]
    except (OSError, ValueError, KeyError):
        return {}
def ate(run):
    return summ(run).get("ate_rmse_m", float("nan"))
def flagged(run):
    s = summ(run)
    c = s.get("classification", {})
    nan = float("nan")
    return 100 * c.get("moving_detected_fraction", nan), 100 * c.get("static_flagged_fraction", nan)
print("| sequence | lens | baseline | / pinhole | idy | / pinhole | idy: moving flagged | static flagged |")
print("| --- " * 8 + "|")
for n in names:
    pb, pi = ate(n + "_pinhole.baseline"), ate(n + "_pinhole.idy")
    for lens in ("pinhole", "kb", "mei", "kb185"):
        b, i = ate("%s_%s.baseline" % (n, lens)), ate("%s_%s.idy" % (n, lens))
        mv, st = flagged("%s_%s.idy" % (n, lens))
        r = lambda a, ref: "x" if math.isnan(a) or math.isnan(ref) else "%.2fx" % (a / ref)
        print("| %s | %s | %.4f | %s | %.4f | %s | %.1f %% | %.2f %% |" % (n, lens, b, r(b, pb), i, r(i, pi), mv, st))
PY
