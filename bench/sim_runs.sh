# shellcheck shell=bash
# Shared by the bench scripts that run `idyvins run` over folders of simulated sequences
# (dropout_spread.sh, rule_ablation.sh). Sourced, not run.

# sim_sequences GLOB LABEL=DATA_DIR[:GLOB] ...: sets the array `seqs` to "LABEL SEQ" for every
# simulated sequence (a folder with meta.json) of each DATA_DIR matching its GLOB (else the first
# argument). Exits 1 when there is none.
sim_sequences() {
  local default_glob=$1 spec label data glob seq
  shift
  seqs=()
  for spec in "$@"; do
    label=${spec%%=*}; data=${spec#*=}; glob=$default_glob
    case $data in *:*) glob=${data#*:}; data=${data%%:*} ;; esac
    for seq in "$data"/$glob; do
      [ -f "$seq/meta.json" ] && seqs+=("$label $seq")
    done
  done
  [ ${#seqs[@]} -gt 0 ] || { echo "no simulated sequences ($default_glob/meta.json) in: $*" >&2; exit 1; }
}

# sim_run IDY DIR SEQ MODE KEY=VALUE ...: `IDY run --threads 1` of SEQ into DIR (log DIR.log) with
# a copy of its config (DIR.config) in which each KEY is removed and, when VALUE is not empty,
# set to VALUE. Nothing is done when DIR holds a finished run (a stats.json, not partial).
sim_run() {
  local idy=$1 dir=$2 seq=$3 mode=$4 cfg kv
  shift 4
  # a run stopped by a signal writes a partial stats.json
  [ -f "$dir/stats.json" ] && ! grep -q '"partial": *true' "$dir/stats.json" && return 0
  rm -rf "$dir"
  mkdir -p "$dir.config"
  cp "$seq"/config/*.yaml "$dir.config/"
  cfg=$dir.config/sim_stereo_imu_config.yaml
  for kv in "$@"; do
    sed -i -e "/^${kv%%=*}:/d" "$cfg"
    [ -z "${kv#*=}" ] || printf '%s: %s\n' "${kv%%=*}" "${kv#*=}" >> "$cfg"
  done
  "$idy" run -c "$cfg" -d "$seq" -o "$dir" --mode "$mode" --threads 1 > "$dir.log" 2>&1 ||
    echo "idyvins $mode failed on $seq ($*): $dir.log" >&2
}
