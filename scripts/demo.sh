#!/usr/bin/env bash
# The main job on built-in data. Today the estimator does not exist yet, so the
# demo runs what does: `idyvins info` validates and describes the real EuRoC
# excerpt shipped in ../shared/data with the shipped EuRoC config.
set -euo pipefail
BUILD=${1:-build}
ROOT=$(cd "$(dirname "$0")/.." && pwd)
DATA="$ROOT/../shared/data/euroc_v101_micro"
if [ ! -d "$DATA" ]; then
  echo "demo: $DATA not found (the shared data folder must sit beside the repository)" >&2
  exit 1
fi
echo "== idyvins demo: dataset reader and validator on the real EuRoC excerpt"
"$ROOT/$BUILD/apps/idyvins" info "$DATA" --config "$ROOT/config/euroc/euroc_stereo_imu_config.yaml"
echo
echo "== The estimator (idyvins run) is not built yet: see the open issues. Only"
echo "   configuration and dataset I/O exist so far; this demo will run the system"
echo "   end to end once they land."
