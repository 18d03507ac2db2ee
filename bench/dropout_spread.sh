#!/usr/bin/env bash
# How far a sequence's ATE moves when a few of its tracks go: each static sequence (no traffic)
# of simulated sets run as is and once per seed with `track_dropout_permille` of its tracks
# withheld from the back end (a different few per seed; docs/cli.md). A difference between two
# systems or two settings inside this spread is not one a single run can show.
# Usage: bench/dropout_spread.sh IDYVINS OUT LABEL=DATA_DIR [LABEL=DATA_DIR ...]
#   DATA_DIR: a folder of simulated sequences (bench --data); its *_none_s* are used
#   environment: SEEDS (default "1 2 3 4 5 6"), PERMILLE (default 20), MODES (default
#   "baseline"), JOBS (default 2: runs at the same time, one core each)
# Prints a markdown table of ATE RMSE (SE3, `idyvins run`, all estimated poses): as is, and the
# median, minimum and maximum over the seeds. Finished runs (a stats.json, not partial) are not redone.
# With two or more MODES, a second table: each further mode's ATE over the first's, seed by seed
# (same seed, so the same track ids withheld), as is and the median, range and count at or below 1.0x
# over the seeds.
set -euo pipefail
if [ $# -lt 3 ]; then
  sed -n '2,14p' "$0" | sed 's/^# \{0,1\}//' >&2
  exit 2
fi
IDY=$1; OUT=$2; shift 2
SEEDS=${SEEDS:-1 2 3 4 5 6}
PERMILLE=${PERMILLE:-20}
MODES=${MODES:-baseline}
JOBS=${JOBS:-2}
mkdir -p "$OUT"

# shellcheck source=bench/sim_runs.sh
. "$(dirname "$0")/sim_runs.sh"

# One run: LABEL SEQ MODE SEED (seed 0: as is).
run_one() {
  local label=$1 seq=$2 mode=$3 seed=$4 dir keys
  dir=$OUT/$label/$(basename "$seq")_${mode}_s$seed
  keys=(track_dropout_permille= track_dropout_seed=)
  [ "$seed" = 0 ] || keys=("track_dropout_permille=$PERMILLE" "track_dropout_seed=$seed")
  sim_run "$IDY" "$dir" "$seq" "$mode" "${keys[@]}"
}
export -f run_one sim_run
export OUT IDY PERMILLE

sim_sequences '*_none_s*' "$@"
for item in "${seqs[@]}"; do
  for mode in $MODES; do
    for seed in 0 $SEEDS; do echo "$item $mode $seed"; done
  done
done | xargs -P "$JOBS" -L 1 bash -c 'run_one "$0" "$1" "$2" "$3"'

# The tables, from the runs' stats.json: each mode's ATE, then (two or more MODES) each further
# mode over the first, seed by seed (the same seed withholds the same track ids in both).
/usr/bin/python3 - "$OUT" "$PERMILLE" "$MODES" "$SEEDS" "${seqs[@]}" <<'EOF'
import json, os, statistics, sys
out, permille, modes, seeds, items = sys.argv[1], sys.argv[2], sys.argv[3].split(), sys.argv[4].split(), sys.argv[5:]

def ate(label, name, mode, seed):
    try:
        summary = json.load(open(f'{out}/{label}/{name}_{mode}_s{seed}/stats.json'))['summary']
        return None if summary.get('partial') else summary['ate_rmse_m']
    except (OSError, KeyError, ValueError):
        return None

def row(label, name, mode, as_is, runs, fmt, count):
    cells = [fmt % as_is if as_is is not None else 'x']
    cells += [fmt % statistics.median(runs), (fmt % min(runs)).rstrip('×') + '–' + fmt % max(runs)] if runs else ['x', 'x']
    print(f'| {label} | {name} | {mode} | ' + ' | '.join(cells) + f' | {count(runs)} |')

def ratio(label, name, mode, seed):
    a, b = ate(label, name, mode, seed), ate(label, name, modes[0], seed)
    return a / b if a is not None and b else None

seqs = [(item.split(' ', 1)[0], os.path.basename(item.split(' ', 1)[1])) for item in items]
print(f'| images | sequence | mode | ATE as is (m) | {permille} ‰ of tracks withheld: median (m) | min–max (m) | seeds |')
print('| --- | --- | --- | --- | --- | --- | --- |')
for label, name in seqs:
    for mode in modes:
        runs = [a for a in (ate(label, name, mode, s) for s in seeds) if a is not None]
        row(label, name, mode, ate(label, name, mode, 0), runs, '%.4f', lambda r: f'{len(r)} of {len(seeds)}')
if len(modes) >= 2:
    print(f'\n| images | sequence | mode / {modes[0]} | as is | withheld: median | min–max | seeds at or below 1.0× |')
    print('| --- | --- | --- | --- | --- | --- | --- |')
    for label, name in seqs:
        for mode in modes[1:]:
            runs = [r for r in (ratio(label, name, mode, s) for s in seeds) if r is not None]
            row(label, name, mode, ratio(label, name, mode, 0), runs, '%.2f×',
                lambda r: f'{sum(x <= 1.0 for x in r)} of {len(r)}')
EOF
