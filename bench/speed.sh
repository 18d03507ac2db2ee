#!/usr/bin/env bash
# Speed of the whole system (issue "Basalt-class speed"): real-time factor, ms per stage and
# peak RSS per sequence, one and two threads, whole-process wall time with /usr/bin/time -v, and
# VINS-Fusion's beside it on the same files when PEERS_ROOT holds its build (shared/peers; its own
# solver settings). Run it on an idle machine, nothing else at the same time.
# Usage: bench/speed.sh IDYVINS WORK [PEERS_ROOT]   (RUNS per case, default 3; MAX_CNT: 150 and 600)
set -euo pipefail
IDY=$1; WORK=$2; PEERS_ROOT=${3:-}
RUNS=${RUNS:-3}
VINS=${PEERS_ROOT:+$PEERS_ROOT/vins-fusion/build/vins_fusion_euroc}
[ -n "$VINS" ] && [ ! -x "$VINS" ] && { echo "no VINS-Fusion in $PEERS_ROOT (../shared/peers/README.md)" >&2; VINS=; }
mkdir -p "$WORK/runs"
SEQS=("city --level none" "parking_lot --level high")
stat() {  # stat FOLDER KEY: a number of stats.json's summary
  /usr/bin/python3 -c 'import json,sys; print("%.2f" % json.load(open(sys.argv[1] + "/stats.json"))["summary"][sys.argv[2]])' "$1" "$2"
}
rss() { awk '/Maximum resident set size/ {printf "%.0f", $6 / 1024}' "$1"; }
wall() { awk '/Elapsed \(wall clock\)/ {n = split($8, t, ":"); s = 0; for (i = 1; i <= n; ++i) s = s * 60 + t[i]; printf "%.1f", s}' "$1"; }
echo "| sequence | landmarks | system | threads | wall (s), median of $RUNS | real time | tracking ms | filter ms | optimization ms | marginalization ms | peak RSS (MB) |"
echo "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"
for s in "${SEQS[@]}"; do
  set -- $s
  n=$1_$3_s1; S=$WORK/$n
  [ -f "$S/meta.json" ] || "$IDY" simulate --scene "$1" "${@:2}" --seed 1 --duration 60 --out "$S" > /dev/null 2>&1
  for cnt in ${MAX_CNT:-150 600}; do
    mkdir -p "$WORK/runs/$n.cfg"
    cp "$S"/config/*.yaml "$WORK/runs/$n.cfg/"
    cfg=$WORK/runs/$n.cfg/max_cnt$cnt.yaml
    sed -e "s/^max_cnt:.*/max_cnt: $cnt/" "$S/config/sim_stereo_imu_config.yaml" > "$cfg"
    for threads in 1 2; do
      walls=()
      for r in $(seq "$RUNS"); do
        out=$WORK/runs/$n.$cnt.t$threads.r$r
        rm -rf "$out"
        /usr/bin/time -v "$IDY" run -c "$cfg" -d "$S" -o "$out" --mode idy --threads "$threads" \
          > "$out.log" 2> "$out.time" || echo "run failed: $out.log" >&2
        walls+=("$(wall "$out.time") $out")
      done
      med=$(printf '%s\n' "${walls[@]}" | sort -n | awk -v k=$(((RUNS + 1) / 2)) 'NR == k {print $2}')
      echo "| $n | $cnt | idyvins idy | $threads | $(wall "$med.time") | $(stat "$med" realtime_factor)x |" \
        "$(stat "$med" mean_tracking_ms) | $(stat "$med" mean_filter_ms) | $(stat "$med" mean_optimization_ms) |" \
        "$(stat "$med" mean_marginalization_ms) | $(rss "$med.time") |"
    done
  done
  if [ -n "$VINS" ]; then
    vcfg=$S/config/sim_stereo_imu_config.yaml  # VINS-Fusion's own solver keys (max_solver_time 0.04, 8 iterations)
    V=$WORK/runs/vins_$n
    VINS_OFFLINE_QUIET=1 /usr/bin/time -v "$VINS" --config "$vcfg" --dataset "$S" --out "$V.tum" --summary "$V.json" \
      > "$V.log" 2> "$V.time" || echo "VINS-Fusion failed on $n: $V.log" >&2
    vs() { /usr/bin/python3 -c 'import json,sys; print("%.2f" % json.load(open(sys.argv[1]))[sys.argv[2]])' "$V.json" "$1"; }
    echo "| $n | its max_cnt | VINS-Fusion be55a93 | its driver | $(wall "$V.time") |" \
      "$(awk -v w="$(wall "$V.time")" 'BEGIN {printf "%.2fx", 60 / w}') | $(vs mean_tracking_ms) | – |" \
      "$(vs mean_optimization_ms) (with marginalization) | – | $(rss "$V.time") |"
  fi
done
