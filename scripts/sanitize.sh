#!/usr/bin/env bash
# `make sanitize` (and CI after `make test`): the unit tests and one short `idyvins run` built with
# AddressSanitizer + UndefinedBehaviorSanitizer (gcc). Any report fails: UBSan does not recover
# (-fno-sanitize-recover=all), ASan halts on the first error, LeakSanitizer reports leaks at exit.
#
# Usage: scripts/sanitize.sh [BUILD_DIR]   (default build-asan; JOBS=2)
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${1:-$ROOT/build-asan}
JOBS=${JOBS:-2}
SHARED=$ROOT/../shared/data
TIMED=$ROOT/scripts/timed.sh  # each step's seconds to $IDYVINS_TIMES (.ci/run's table)
start=$(date +%s)
# -O1: a third faster to build than -O2, still inlined enough to run the suite in minutes.
# No -Werror: gcc 12 warns falsely (maybe-uninitialized in <regex>) under -fsanitize.
# A unity build (8 sources per translation unit): Eigen's, Ceres' and OpenCV's headers parsed once per
# batch, not per file; a check build, so its objects need not match the Release build's (docs/ci.md).
cmake -S "$ROOT" -B "$BUILD" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" \
  -DCMAKE_UNITY_BUILD=ON \
  -DIDYVINS_SANITIZE=ON -DIDYVINS_BUILD_BENCH=OFF -DIDYVINS_BUILD_ROS=OFF > "$BUILD.configure.log"
"$TIMED" "sanitizers: build (ASan + UBSan, -O1)" cmake --build "$BUILD" -j"$JOBS" > "$BUILD.build.log" 2>&1 ||
  { tail -30 "$BUILD.build.log"; exit 1; }
built=$(date +%s)

export ASAN_OPTIONS=halt_on_error=1:detect_leaks=1:strict_string_checks=1:detect_stack_use_after_return=1
export UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1
export LSAN_OPTIONS=suppressions=$ROOT/scripts/lsan.supp:print_suppressions=0
# The unit tests (GoogleTest, label "unit"), but for the whole-sequence ones below: under ASan they
# take 1.5-8 minutes each (25 of them would add about 40 minutes on 2 cores) and run the same code as
# the run after them. The script-driven tests (bags, ROS, perturb, signals) run whole sequences too.
SLOW='FeatureTracker\.(StereoRefinementTightens|TracksFollowTheTrueProjections|CornersAtTheBorderWithACut|FirstPatchAlignmentRemoves|CornersPrunedNextTo)'
SLOW+='|Estimator\.(ShortCitySequenceEndToEnd|InitializesDespiteAVehicle)|Cli\.RunIsByteIdentical|Cli\.RunIdyWrites'
SLOW+='|Preintegration\.CovarianceMatchesMonteCarlo|Rejection\.(RansacRejectsMost|SegDropsExactly)'
SLOW+='|Estimator\.(OutliersConfirmedDynamic|PostProcessingConfirms|ResetsOnLostTracking)|LostCornerTest\.LostNewCorners'
SLOW+='|PipelineSystem\.[^R]|Faults\.[^T]|PipelineTimeOffset\.|CliRefusals\.(ARun|ASlow)'
# Over 15 s each under ASan (measured 2026-12-02, docs/ci.md): whole sequences through the estimator or the front end.
SLOW+='|Estimator\.(LandmarkShareKeeps|RightMatchesThatSlid|AFailureInsideTheFirstWindows|EstimatedAnchorRays)'
SLOW+='|FeatureTracker\.(StereoMatchesWithLowZncc|EveryEndedTrackIsCounted|HoldsOnTheRealEuroc|LowZnccRightMatchesOnly)'
(cd "$BUILD" && "$TIMED" "sanitizers: unit tests" ctest -L unit -E "$SLOW" -j"$JOBS" --output-on-failure --timeout 1500)
tested=$(date +%s)

# One short run of the whole system: a rendered sequence with moving cars (idy mode, masks), evaluated.
# (The real EuRoC excerpt runs the same code in baseline; the refusal tests above run it briefly.)
work=$BUILD/sanitize_run
rm -rf "$work" && mkdir -p "$work"
"$BUILD/apps/idyvins" simulate --scene city --level high --seed 3 --duration 6 --out "$work/seq" > /dev/null
"$BUILD/apps/idyvins" run -c "$work/seq/config/sim_stereo_imu_config.yaml" -d "$work/seq" -o "$work/out" --mode idy
"$BUILD/apps/idyvins" eval --est "$work/out/trajectory.tum" --gt "$work/seq" > /dev/null
done_at=$(date +%s)
if [ -n "${IDYVINS_TIMES:-}" ]; then
  printf 'sanitizers: one short run (6 s, city high, idy)\t%d\t0\n' $((done_at - tested)) >> "$IDYVINS_TIMES"
fi
printf 'sanitizers: build %d s, unit tests %d s, runs %d s, total %d s, no report\n' $((built - start)) \
  $((tested - built)) $((done_at - tested)) $((done_at - start))
