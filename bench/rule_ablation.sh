#!/usr/bin/env bash
# Each rule of docs/method.md's extension table switched off (or on) alone, on simulated sets: every
# sequence is run once with its config as rendered and once per rule with the rule's keys set in
# a copy of the config. Side by side on the tuning and the validation family, it shows whether a
# rule measured on one holds on the other.
# Usage: bench/rule_ablation.sh IDYVINS OUT LABEL=DATA_DIR[:GLOB] [LABEL=DATA_DIR[:GLOB] ...]
#   DATA_DIR: a folder of simulated sequences (bench --data); GLOB picks some (default '*')
#   environment: RULES (default below: NAME:key=value[,key=value...][@has|@lacks] separated by
#   spaces; @has: only where the rendered config sets the first key, @lacks: only where it does
#   not, e.g. the key `simulate --realism` writes), MODE (default idy), JOBS (default 2)
# Prints two markdown tables from the runs' stats.json (`run --threads 1`): per rule and label,
# the ATE with the rule's keys over the ATE as rendered (geometric mean and range) and the change
# in moving and static observations flagged (points); then every sequence, rule by rule.
# Finished runs (a stats.json, not partial) are not redone.
set -euo pipefail
if [ $# -lt 3 ]; then
  sed -n '2,14p' "$0" | sed 's/^# \{0,1\}//' >&2
  exit 2
fi
IDY=$1; OUT=$2; shift 2
RULES=${RULES:-confirm_outliers:confirm_outliers_dynamic=0 lost_track_test:lost_track_test=0 \
move_with_eliminated:move_with_eliminated_px=0 left_chi2:stereo_motion_left_chi2=0 \
noise_ref:stereo_motion_noise_ref=0 remove_chi2_0:stereo_motion_remove_chi2=0@has \
remove_chi2_80:stereo_motion_remove_chi2=80@lacks follow_eliminated:follow_eliminated=0}
MODE=${MODE:-idy}
JOBS=${JOBS:-2}
mkdir -p "$OUT"

# shellcheck source=bench/sim_runs.sh
. "$(dirname "$0")/sim_runs.sh"

# One run: LABEL SEQ RULE KEYS (rule "default", keys "-": the config as rendered).
run_one() {
  local label=$1 seq=$2 rule=$3 keys=$4 dir when='' config=lacks kvs=()
  dir=$OUT/$label/$rule/$(basename "$seq")
  case $keys in *@*) when=${keys#*@}; keys=${keys%@*} ;; esac
  # @has / @lacks: a rule for the configs that set (or do not set) its first key
  grep -q "^${keys%%=*}:" "$seq/config/sim_stereo_imu_config.yaml" && config=has
  if [ -n "$when" ] && [ "$when" != "$config" ]; then
    mkdir -p "$(dirname "$dir")"
    touch "$dir.na"
    return 0
  fi
  [ "$keys" = - ] || IFS=, read -ra kvs <<< "$keys"
  sim_run "$IDY" "$dir" "$seq" "$MODE" "${kvs[@]}"
}
export -f run_one sim_run
export OUT IDY MODE

rule_re='^[^:]+:[^=,@]+=[^,@]*(,[^=,@]+=[^,@]*)*(@has|@lacks)?$'
for rule in $RULES; do
  [[ $rule =~ $rule_re ]] && continue
  echo "RULES: '$rule' is not NAME:key=value[,key=value...][@has|@lacks]" >&2
  exit 2
done
sim_sequences '*' "$@"
for item in "${seqs[@]}"; do
  echo "$item default -"
  for rule in $RULES; do echo "$item ${rule%%:*} ${rule#*:}"; done
done | xargs -P "$JOBS" -L 1 bash -c 'run_one "$0" "$1" "$2" "$3"'

/usr/bin/python3 - "$OUT" "$RULES" "${seqs[@]}" <<'EOF'
import json, math, os, sys
out, rules, items = sys.argv[1], [r.split(':', 1) for r in sys.argv[2].split()], sys.argv[3:]
seqs = [(i.split(' ', 1)[0], os.path.basename(i.split(' ', 1)[1])) for i in items]

def result(label, rule, name):
    """(ATE m, moving flagged %, static flagged %), 'na' (rule not for this config) or None."""
    path = f'{out}/{label}/{rule}/{name}'
    if os.path.exists(path + '.na'):
        return 'na'
    try:
        s = json.load(open(path + '/stats.json'))['summary']
        c = s['classification']
        moving = 100 * c['recall'] if c['observations_on_moving'] else None
        return None if s.get('partial') else (s['ate_rmse_m'], moving, 100 * c['static_flagged_fraction'])
    except (OSError, KeyError, ValueError, TypeError):
        return None

def signed(x, digits):
    return f'{x:+.{digits}f}'.replace('-', '−')

def change(label, rule, name):
    """(ATE with the keys / as rendered, moving points or None, static points), 'na' or None."""
    on, off = result(label, 'default', name), result(label, rule, name)
    if off == 'na':
        return 'na'
    if not isinstance(on, tuple) or not isinstance(off, tuple):
        return None
    return off[0] / on[0], None if on[1] is None else off[1] - on[1], off[2] - on[2]

print('| rule | keys set | images | runs | ATE with the keys / as rendered: geometric mean (range) '
      '| moving flagged, points: mean (range) | static flagged, points: mean (range) |')
print('| --- | --- | --- | --- | --- | --- | --- |')
for rule, keys in rules:
    for label in dict.fromkeys(l for l, _ in seqs):
        ch = [c for c in (change(label, rule, n) for l, n in seqs if l == label) if isinstance(c, tuple)]
        if not ch:
            continue
        ratios, moving, static = [c[0] for c in ch], [c[1] for c in ch if c[1] is not None], [c[2] for c in ch]
        span = lambda v, d: f'{signed(sum(v) / len(v), d)} ({signed(min(v), d)} to {signed(max(v), d)})' if v else '–'
        gm = math.exp(sum(map(math.log, ratios)) / len(ratios))
        print(f'| {rule} | `{keys}` | {label} | {len(ch)} | {gm:.3f}× ({min(ratios):.3f}–{max(ratios):.3f}×) '
              f'| {span(moving, 1)} | {span(static, 2)} |')

print('\nEach cell: ATE with the rule\'s keys over ATE as rendered (moving, static flagged: change in points); '
      '"–": the rule is not for this config (@has / @lacks).\n')
print('| images | sequence | as rendered: ATE m (moving / static flagged %) | ' + ' | '.join(r for r, _ in rules) + ' |')
print('| --- | --- | --- | ' + ' | '.join('---' for _ in rules) + ' |')
for label, name in seqs:
    on = result(label, 'default', name)
    if not isinstance(on, tuple):
        print(f'| {label} | {name} | x |' + ' |' * len(rules))
        continue
    cells = []
    for rule, _ in rules:
        c = change(label, rule, name)
        if c == 'na':
            cells.append('–')
        elif c is None:
            cells.append('x')
        else:
            moving = '' if c[1] is None else signed(c[1], 1) + ' / '
            cells.append(f'{c[0]:.2f}× ({moving}{signed(c[2], 2)})')
    flagged = ('' if on[1] is None else f'{on[1]:.1f} / ') + f'{on[2]:.2f}'
    print(f'| {label} | {name} | {on[0]:.4f} ({flagged}) | ' + ' | '.join(cells) + ' |')
EOF
