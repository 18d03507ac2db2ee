#!/usr/bin/env bash
# Runs a command and, when IDYVINS_TIMES names a file, appends "STEP<TAB>SECONDS<TAB>EXIT" to it
# (what .ci/run prints as its per-step table). Usage: scripts/timed.sh STEP CMD [ARGS...]
set -uo pipefail
step=$1
shift
start=$(date +%s)
"$@"
code=$?
if [ -n "${IDYVINS_TIMES:-}" ]; then printf '%s\t%d\t%d\n' "$step" $(($(date +%s) - start)) "$code" >> "$IDYVINS_TIMES"; fi
exit $code
