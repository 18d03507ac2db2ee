#!/usr/bin/env bash
# Runs job INDEX (1-based: line INDEX) of a plan written by `idyvins bench --plan PLAN`.
#   scripts/jobs/bench_job.sh PLAN INDEX
# The line skips itself when its run folder is finished, so running it again is safe. Used by the
# Slurm array (bench.sbatch) and the Kubernetes Indexed Job (bench-k8s.yaml); GNU parallel runs
# the plan's lines directly (docs/cli.md#bench-as-independent-jobs).
set -euo pipefail
if [ $# -ne 2 ]; then echo "usage: $0 PLAN INDEX (1-based line of the plan)" >&2; exit 2; fi
plan=$1 index=$2
if [ ! -f "$plan" ]; then echo "$plan: no such plan" >&2; exit 1; fi
lines=$(wc -l < "$plan")
if ! [[ "$index" =~ ^[0-9]+$ ]] || [ "$index" -lt 1 ] || [ "$index" -gt "$lines" ]; then
  echo "$plan: job $index does not exist (the plan has $lines jobs, 1-$lines)" >&2
  exit 1
fi
line=$(sed -n "${index}p" "$plan")
exec bash -c "$line"
