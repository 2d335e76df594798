#!/usr/bin/env bash
# Sanitizer passes of `bash cmake/run.sh test` (called by it after the normal suite; see docs/reliability.md):
#   1. AddressSanitizer + UndefinedBehaviorSanitizer build in BUILD-asan, the ctest suite without benchmarks and
#      without the longest system tests (listed below with the shorter tests that drive the same code);
#   2. ThreadSanitizer build in BUILD-tsan of the programs that run threads, their threaded tests;
#   3. libFuzzer build (clang) in BUILD-fuzz of the parser fuzz targets, a short run of each (HSLAM_FUZZ_RUNS inputs
#      from a fixed seed).
# Every sanitizer stops the program at its first report (halt_on_error), so a report fails its test.
# Usage: bash cmake/sanitizers.sh BUILD JOBS TIMEOUT_S
set -euo pipefail

build=$1
jobs=$2
timeout=$3
repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)

configure() { # dir, cmake options...
  local dir=$1
  shift
  cmake -S "$repo" -B "$dir" -DCMAKE_BUILD_TYPE=Release -DHSLAM_BUILD_BENCHMARKS=OFF "$@" >"$dir.configure.log" 2>&1 || {
    cat "$dir.configure.log"
    exit 1
  }
}

# --- AddressSanitizer + UndefinedBehaviorSanitizer: the suite -------------------------------------------------------
# The library and the tutorials are instrumented; the test programs' own code is not (HSLAM_SANITIZE_TEST_PROGRAMS=OFF:
# instrumenting GoogleTest's expansions cost as much build time as the library). Compiled with the normal build's
# flags, the test programs come out of ccache when it is there (see cmake/run.sh).
asan="$build-asan"
echo "== AddressSanitizer + UBSan: building in $asan"
start=$(date +%s)
configure "$asan" -DHSLAM_SANITIZE=address,undefined -DHSLAM_SANITIZE_TEST_PROGRAMS=OFF
cmake --build "$asan" -j "$jobs"
echo "== AddressSanitizer + UBSan: running the tests (built in $(($(date +%s) - start)) s)"
start=$(date +%s)
# Suppressions: third-party code only, each with its reason, in cmake/sanitizers/.
export ASAN_OPTIONS=halt_on_error=1:detect_leaks=1:check_initialization_order=1:strict_init_order=1
export UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1:suppressions=$repo/cmake/sanitizers/ubsan.supp
export LSAN_OPTIONS=suppressions=$repo/cmake/sanitizers/lsan.supp
# OpenCV probes USB cameras through libgphoto2 whenever it opens a video file, and libgphoto2 leaks what it finds:
# the gphoto2 back-end is off for this pass (a video file never needs it).
export OPENCV_VIDEOIO_PRIORITY_GPHOTO2=0
# package.consumer builds a separate project against the installed (instrumented) library: it needs the same flags.
export CXXFLAGS="-fsanitize=address,undefined" LDFLAGS="-fsanitize=address,undefined"
# Left out for time (instrumented, 1.5 to 9 minutes each on a 2 GHz core), each a longer run of code that a shorter
# test of this pass already drives:
#   SystemLoop.OutwardLoopIsClosedAndBeatsOdometry: its trajectories are bit-identical to the normal build's (loop
#     closure solves with Eigen's sparse Cholesky, not CHOLMOD's OpenMP pool); the loop code runs in the other loop
#     and map tests;
#   SystemLoop.NoFalseLoopOnSequencesWithoutOne: detection and verification run in RealTimeLoopCorrection and loop.*;
#   SystemReal.SevenScenes{CoveredLens,LongCover,EarlyCover}*,
#     SystemReal.TsukubaCoverIsNotRelocalisedOnARepeatedTexture,
#     SystemReal.KittiCarFoundAgainKeepsItsMotionAndRenewsItsWindow (KittiCoverIsBridged* runs that path),
#     SystemSynthetic.CoveredLensIsRelocalisedWithDirectTracking*,
#     SystemSynthetic.RealTimeHybridCoveredLens*: relocalisation runs in SystemSynthetic.CoveredLensIsRelocalised-
#     InTheSameMap and RecoversFromLostTracking (the real-time one runs under ThreadSanitizer below);
#   SystemMapFile.LocalizationOnlyTracksEveryFrame*: loading and localisation-only run in the two other map tests;
#   ServoTutorial.ConvergesFromAnotherStartWithImageNoise, ServoTutorial.TagMode*: the same program as
#     ConvergesToTheGoalWithSlamInTheLoop (tag mode adds the metric frame, run by map.MetricFrame.*);
#   SystemGlobalMap.TurnInPlaceWithoutSeeding*: TurnInPlaceIsSeededAgain* with the seeding off; the timeout and the
#     new segment it ends in run in SystemSynthetic.RecoversFromLostTracking;
#   SystemGlobalMap.HandHeldTurn*: TurnInPlaceIsTrackedThrough* with the pivot 10 or 20 cm behind the camera, the
#     same code on another path (40 s each instrumented);
#   SystemTag.*: three systems over 801 frames at 640x480 (2 minutes plain); the metric frame's code runs in
#     map.MetricFrame.* and features.TagDetector.* (the detector on rendered tags, the fit on noisy sightings).
long='SystemLoop\.(OutwardLoopIsClosed|NoFalseLoop)|'
long+='SystemReal\.(SevenScenes(CoveredLens|LongCover|EarlyCover)|TsukubaCover|KittiCarFound)|'
long+='SystemSynthetic\.(CoveredLensIsRelocalisedWithDirectTracking|RealTimeHybridCoveredLens)|'
long+='SystemMapFile\.LocalizationOnlyTracksEveryFrame|ServoTutorial\.(ConvergesFromAnotherStart|TagMode)|'
long+='SystemGlobalMap\.(TurnInPlaceWithoutSeeding|HandHeldTurn)|SystemTag\.'
ctest --test-dir "$asan" -LE benchmark -E "$long" --output-on-failure -j "$jobs" --timeout "$timeout" --no-tests=error
echo "== AddressSanitizer + UBSan: tests took $(($(date +%s) - start)) s"
unset ASAN_OPTIONS UBSAN_OPTIONS LSAN_OPTIONS OPENCV_VIDEOIO_PRIORITY_GPHOTO2 CXXFLAGS LDFLAGS

# --- ThreadSanitizer: the tests that run the mapping thread, the worker pool or the real-time program ----------------
# Kernels with many bits of mmap randomisation (vm.mmap_rnd_bits > 28) break TSan's fixed memory layout ("unexpected
# memory mapping"): the build (its test discovery runs the programs) and the tests run with ASLR off when setarch
# allows it.
tsan="$build-tsan"
no_aslr=()
if setarch "$(uname -m)" -R true 2>/dev/null; then
  no_aslr=(setarch "$(uname -m)" -R)
fi
targets=(test_window_threads test_worker_pool test_system_synthetic test_system_inputs test_system_tutorial
  test_faults test_system_loop test_global_bundle_adjustment test_landmark_correction tutorial-hslam-dataset)
# Real-time mode (mapping thread) and the thread pool; the dataset program in real-time mode (signals during mapping);
# the global bundle adjustment's own thread (started, replaced, cancelled).
threaded='WindowThreads|WorkerPool|RealTime|NoFrameMeansNothingToReport|TerminationSignals|BackgroundBundleAdjustment'
# Left out for time: SystemMapFile.RealTimeSaveThenLocalizationOnly (340 s instrumented on a 2 GHz core): saveMap
# waits for the mapping thread as synchronize() does in every real-time test here, and localisation-only leaves the
# mapping thread idle; it runs in the AddressSanitizer pass. Its program (test_system_map_file) is not built here.
echo "== ThreadSanitizer: building ${targets[*]} in $tsan${no_aslr[*]:+ (under ${no_aslr[*]})}"
start=$(date +%s)
configure "$tsan" -DHSLAM_SANITIZE=thread
"${no_aslr[@]}" cmake --build "$tsan" -j "$jobs" --target "${targets[@]}"
echo "== ThreadSanitizer: running the threaded tests (built in $(($(date +%s) - start)) s)"
start=$(date +%s)
# OpenMP (the synthetic renderer) on one thread: libgomp is not instrumented, its own synchronisation is invisible.
OMP_NUM_THREADS=1 TSAN_OPTIONS=halt_on_error=1:second_deadlock_stack=1:suppressions=$repo/cmake/sanitizers/tsan.supp \
  "${no_aslr[@]}" ctest --test-dir "$tsan" -R "$threaded" --output-on-failure -j "$jobs" \
  --timeout "$timeout" --no-tests=error
echo "== ThreadSanitizer: tests took $(($(date +%s) - start)) s"

# --- libFuzzer: every parser of outside input, a short run each (the long runs have the label "benchmark") ----------
fuzz="$build-fuzz"
echo "== libFuzzer: building the fuzz targets in $fuzz (clang)"
start=$(date +%s)
configure "$fuzz" -DCMAKE_CXX_COMPILER=clang++ -DHSLAM_FUZZ=ON -DHSLAM_BUILD_TUTORIALS=OFF \
  -DHSLAM_FUZZ_RUNS="${HSLAM_FUZZ_RUNS:-30000}"
cmake --build "$fuzz" -j "$jobs" --target hslam_fuzz_targets
echo "== libFuzzer: ${HSLAM_FUZZ_RUNS:-30000} inputs of each target (built in $(($(date +%s) - start)) s)"
start=$(date +%s)
LSAN_OPTIONS=suppressions=$repo/cmake/sanitizers/lsan.supp \
  UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1:suppressions=$repo/cmake/sanitizers/ubsan.supp \
  ctest --test-dir "$fuzz" -L fuzz --output-on-failure -j "$jobs" --timeout "$timeout" --no-tests=error
echo "== libFuzzer: runs took $(($(date +%s) - start)) s"
