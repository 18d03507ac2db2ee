#!/usr/bin/env bash
# `make fuzz`: every reader of user input under libFuzzer with ASan + UBSan (Debian's clang),
# FUZZ_SECONDS (60) each, seeded from the shipped configs and the shared data. Findings (inputs
# that crash, trip a sanitizer or throw anything but InputError) land in BUILD/findings/ and make
# the script fail; each fixed one belongs in tests/fuzz/regressions/ (replayed by CTest).
#
# Usage: scripts/fuzz.sh [BUILD_DIR]   (default build-fuzz; FUZZ_TARGETS="camera bag" for some only)
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${1:-$ROOT/build-fuzz}
SECONDS_EACH=${FUZZ_SECONDS:-60}
SHARED=$ROOT/../shared/data
CC=clang CXX=clang++ cmake -S "$ROOT" -B "$BUILD" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DIDYVINS_FUZZ=ON \
  -DIDYVINS_SANITIZE=ON -DIDYVINS_BUILD_TESTS=OFF -DIDYVINS_BUILD_BENCH=OFF -DIDYVINS_BUILD_CLI=OFF \
  -DIDYVINS_BUILD_ROS=OFF > "$BUILD.configure.log"
TARGETS=(${FUZZ_TARGETS:-config camera imu_csv image_csv groundtruth_csv trajectory bag})
cmake --build "$BUILD" -j"${JOBS:-2}" --target $(printf 'fuzz_%s ' "${TARGETS[@]}") > "$BUILD.build.log"

# Seed corpora: real files of each kind.
seed() {  # seed TARGET FILE...
  mkdir -p "$BUILD/corpus/$1"
  shift_target=$1; shift
  for f in "$@"; do [ -f "$f" ] && cp "$f" "$BUILD/corpus/$shift_target/$(basename "$(dirname "$f")")_$(basename "$f")"; done
  return 0
}
seed config "$ROOT"/config/*/*config*.yaml
seed camera "$ROOT"/config/*/cam*.yaml
seed imu_csv "$SHARED"/euroc_v101_micro/mav0/imu0/data.csv
seed image_csv "$SHARED"/euroc_v101_micro/mav0/cam0/data.csv
seed groundtruth_csv "$SHARED"/euroc_v101_micro/mav0/state_groundtruth_estimate0/data.csv
seed trajectory "$SHARED"/euroc_v101_micro/mav0/state_groundtruth_estimate0/data.csv
if [ ! -f "$BUILD/seed.bag" ]; then
  /usr/bin/python3 "$ROOT/tests/make_test_bag.py" "$SHARED/euroc_v101_micro" "$BUILD/seed.bag" --frames 2 \
    > /dev/null 2>&1 || true
fi
seed bag "$BUILD/seed.bag"
# Inputs small enough for libFuzzer to mutate: keep the first 4 KiB of the large seeds.
for f in "$BUILD"/corpus/*/*; do [ "$(stat -c %s "$f")" -gt 4096 ] && head -c 4096 "$f" > "$f.tmp" && mv "$f.tmp" "$f"; done

mkdir -p "$BUILD/findings"
status=0
printf '| reader | executions | seconds | findings |\n| --- | --- | --- | --- |\n' > "$BUILD/fuzz.md"
for t in "${TARGETS[@]}"; do
  log=$BUILD/fuzz_$t.log
  set +e
  ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 \
    "$BUILD/tests/fuzz/fuzz_$t" "$BUILD/corpus/$t" -max_total_time="$SECONDS_EACH" -max_len=8192 \
    -artifact_prefix="$BUILD/findings/${t}_" -print_final_stats=1 > "$log" 2>&1
  rc=$?
  set -e
  runs=$(grep -oE 'stat::number_of_executed_units: *[0-9]+' "$log" | grep -oE '[0-9]+$' || echo 0)
  found=$(find "$BUILD/findings" -name "${t}_*" | wc -l)
  printf '| %s | %s | %s | %s |\n' "$t" "$runs" "$SECONDS_EACH" "$found" >> "$BUILD/fuzz.md"
  [ "$rc" = 0 ] && [ "$found" = 0 ] || status=1
done
cat "$BUILD/fuzz.md"
exit $status
