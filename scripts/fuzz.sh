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
TARGETS=(${FUZZ_TARGETS:-config camera imu_csv image_csv groundtruth_csv trajectory bag mcap cdr})
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
if [ ! -f "$BUILD/seed.mcap" ]; then  # ROS 2: an MCAP written by @mcap/core (tests/ros2), uncompressed and zstd
  (cd "$ROOT/tests/ros2" && [ -d node_modules ] || npm ci --no-audit --no-fund --loglevel=error) > /dev/null 2>&1 || true
  node "$ROOT/tests/ros2/write_bag.mjs" "$SHARED/euroc_v101_micro" "$BUILD/seed.mcap" --frames 2 > /dev/null 2>&1 || true
  node "$ROOT/tests/ros2/write_bag.mjs" "$SHARED/euroc_v101_micro" "$BUILD/seed_zstd.mcap" --frames 2 \
    --compression zstd --chunk-size 2048 > /dev/null 2>&1 || true
fi
seed mcap "$BUILD/seed.mcap" "$BUILD/seed_zstd.mcap"
if [ ! -f "$BUILD/seed_cdr/imu.cdr" ]; then  # one CDR message of each type @foxglove/rosmsg2-serialization writes
  node "$ROOT/tests/ros2/write_bag.mjs" "$SHARED/euroc_v101_micro" "$BUILD/seed_records.json" --frames 1 \
    --storage records > /dev/null 2>&1 &&
    /usr/bin/python3 -c 'import base64, json, os, sys
d = json.load(open(sys.argv[1])); os.makedirs(sys.argv[2], exist_ok=True); seen = set()
for topic, _, b in d["records"]:
    if topic not in seen:
        seen.add(topic); open(os.path.join(sys.argv[2], topic.strip("/").replace("/", "_") + ".cdr"), "wb").write(base64.b64decode(b)[:4096])
' "$BUILD/seed_records.json" "$BUILD/seed_cdr" || true
fi
seed cdr "$BUILD"/seed_cdr/*.cdr
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
