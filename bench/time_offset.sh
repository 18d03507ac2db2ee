#!/usr/bin/env bash
# Camera-IMU time offset: ATE with offsets of 0, 5, 10 and 20 ms in the data, the offset
# estimated (estimate_td: 1) or not (the config's td: 0), and how fast and how close the
# estimate comes to the truth.
# Usage: bench/time_offset.sh IDYVINS OUT [FAMILY ...]
#   FAMILY: standard and/or validation (default both); one static city sequence each
#   (seed 1, DURATION seconds, default 30), rendered once per offset into OUT/data
#   JOBS (environment, default 2): runs at the same time (each uses one core)
#   MODE (environment, default baseline): the idyvins mode
# Prints a markdown table; the per-frame estimate is stats.json's frames[].td_s.
set -euo pipefail
IDY=$1; OUT=$2; shift 2
FAMILIES=${*:-standard validation}
JOBS=${JOBS:-2}
MODE=${MODE:-baseline}
DURATION=${DURATION:-30}
OFFSETS="0 5 10 20"
mkdir -p "$OUT/data" "$OUT/res"

for fam in $FAMILIES; do
  for td in $OFFSETS; do
    d=$OUT/data/${fam}_td$td
    [ -f "$d/meta.json" ] || "$IDY" simulate --scene city --level none --seed 1 --duration "$DURATION" \
      --family "$fam" --td-ms "$td" -o "$d" > "$OUT/data/${fam}_td$td.log"
    for est in 0 1; do
      { sed '/^estimate_td:/d' "$d/config/sim_stereo_imu_config.yaml"; echo "estimate_td: $est"; } > "$d/config/estimate_td_$est.yaml"
    done
  done
done

run_one() {
  local fam=$1 td=$2 est=$3 d=$OUT/data/${1}_td$2 r=$OUT/res/${1}_td$2_est$3
  [ -f "$r/stats.json" ] || "$IDY" run -c "$d/config/estimate_td_$est.yaml" -d "$d" -o "$r" --mode "$MODE" \
    --threads 1 > "$r.log" 2>&1 || echo "idyvins failed on $d (estimate_td $est)" >&2
}
export -f run_one
export IDY OUT MODE
for fam in $FAMILIES; do for td in $OFFSETS; do for est in 0 1; do echo "$fam $td $est"; done; done; done |
  xargs -P "$JOBS" -L 1 bash -c 'run_one "$@"' _

PY=/usr/bin/python3
"$PY" - "$OUT" $FAMILIES <<'EOF'
import json, sys
out, fams = sys.argv[1], sys.argv[2:]
print("| family | offset (ms) | ATE, td not estimated (m) | ATE, estimated (m) | estimate at 10 s (ms) | mean estimate after 10 s (ms) | first time within 0.5 ms for 2 s (s) |")
print("| --- | --- | --- | --- | --- | --- | --- |")
for fam in fams:
    for td in (0, 5, 10, 20):
        row = [fam, str(td)]
        for est in (0, 1):
            s = json.load(open(f"{out}/res/{fam}_td{td}_est{est}/stats.json"))
            row.append("%.4f" % s["summary"]["ate_rmse_m"] if "ate_rmse_m" in s.get("summary", {}) else "n/a")
        frames = json.load(open(f"{out}/res/{fam}_td{td}_est1/stats.json"))["frames"]
        t0 = frames[0]["t_ns"]
        t = [(f["t_ns"] - t0) * 1e-9 for f in frames]
        e = [f["td_s"] * 1e3 for f in frames]
        at10 = next((x for tt, x in zip(t, e) if tt >= 10.0), float("nan"))
        late = [x for tt, x in zip(t, e) if tt >= 10.0]
        mean_late = sum(late) / len(late) if late else float("nan")
        conv = "never"
        for i in range(len(t)):  # within 0.5 ms of the truth and staying there for 2 s
            j = i
            while j < len(t) and t[j] - t[i] <= 2.0 and abs(e[j] - td) <= 0.5:
                j += 1
            if j < len(t) and t[j] - t[i] > 2.0 and abs(e[i] - td) <= 0.5:
                conv = "%.1f" % t[i]
                break
        row += ["%.2f" % at10, "%.2f" % mean_late, conv]
        print("| " + " | ".join(row) + " |")
EOF
