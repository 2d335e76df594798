#!/usr/bin/env bash
# One entry point for a fresh Debian 12 machine (see README.md):
#   bash cmake/run.sh demo   install what is missing, build, run the main job on data reachable by default
#   bash cmake/run.sh test   install what is missing, build, run the test suite (benchmarks excluded), then the
#                            suite (but its longest system tests) built with AddressSanitizer + UBSan
#                            ($BUILD_DIR-asan), the threaded tests built with ThreadSanitizer ($BUILD_DIR-tsan)
#                            and the fuzz targets ($BUILD_DIR-fuzz); any sanitizer report fails
#   bash cmake/run.sh bench  install what is missing, build, run the benchmarks (ctest label "benchmark")
# Environment: BUILD_DIR (default build), JOBS (default nproc), HSLAM_SKIP_INSTALL=1 to skip apt-get,
# HSLAM_SANITIZERS=0 to skip the sanitizer passes of `test`, CCACHE_DIR (default $BUILD_DIR-ccache) when ccache is
# installed.
set -euo pipefail

cmd=${1:-}
case "$cmd" in
  demo | test | bench) ;;
  *)
    echo "usage: bash cmake/run.sh demo|test|bench" >&2
    exit 2
    ;;
esac

repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${BUILD_DIR:-$repo/build}
jobs=${JOBS:-$(nproc)}

# Debian packages the build, the tests and the demo need. Installed only when missing. clang, its sanitizer
# runtimes (libclang-rt-dev, libFuzzer included) and LLVM's OpenMP (ViSP's flags ask for -fopenmp) serve the fuzz
# targets of `test`; ccache lets the sanitizer pass re-use the normal build's test programs; doxygen the
# documentation test, xvfb and xauth the live-window test (a virtual X server); libapriltag-dev draws the AprilTag
# the tag tests hang in the synthetic room (the module itself detects tags with ViSP's vpDetectorAprilTag).
packages=(g++ cmake make pkg-config ccache libvisp-dev libopencv-dev libeigen3-dev libceres-dev libgtest-dev
  libbenchmark-dev libv4l-dev libzip-dev zlib1g-dev libjpeg-dev libpng-dev visp-images-data clang libclang-rt-dev
  libomp-dev doxygen xvfb xauth libapriltag-dev)

if [ "${HSLAM_SKIP_INSTALL:-0}" != 1 ]; then
  missing=()
  for p in "${packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  if [ ${#missing[@]} -gt 0 ]; then
    echo "== installing missing Debian packages: ${missing[*]}"
    sudo_cmd=()
    [ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
    "${sudo_cmd[@]}" apt-get update -qq
    DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
  fi
fi

# ccache, when installed, for every build of this script (the normal one and the sanitizer and fuzz builds of
# cmake/sanitizers.sh, through CMake's CMAKE_CXX_COMPILER_LAUNCHER environment variable). Its cache sits beside the
# build folder; paths under the repository are hashed relative to the build folder, so that the AddressSanitizer
# pass, which compiles the test programs with the normal build's flags, finds them cached. The module's files include
# a precompiled header (HSLAM_PRECOMPILED_HEADERS): ccache caches them only with the sloppiness below (it then hashes
# the precompiled header's content, not its defines or time stamps; the project uses no __DATE__ or __TIME__).
if command -v ccache >/dev/null 2>&1; then
  export CMAKE_CXX_COMPILER_LAUNCHER=ccache CMAKE_C_COMPILER_LAUNCHER=ccache
  export CCACHE_DIR=${CCACHE_DIR:-$build-ccache} CCACHE_BASEDIR=${CCACHE_BASEDIR:-$repo}
  export CCACHE_SLOPPINESS=${CCACHE_SLOPPINESS:-pch_defines,time_macros,include_file_mtime,include_file_ctime}
fi

echo "== configuring and building in $build"
cmake -S "$repo" -B "$build" -DCMAKE_BUILD_TYPE=Release >"$build.configure.log" 2>&1 || {
  cat "$build.configure.log"
  exit 1
}
cmake --build "$build" -j "$jobs"

# A test that hangs fails after this many seconds instead of stalling the whole run.
test_timeout=${HSLAM_TEST_TIMEOUT:-900}

case "$cmd" in
  test)
    echo "== running the tests"
    ctest --test-dir "$build" -LE benchmark --output-on-failure -j "$jobs" --timeout "$test_timeout"
    if [ "${HSLAM_SANITIZERS:-1}" != 0 ]; then
      bash "$repo/cmake/sanitizers.sh" "$build" "$jobs" "$test_timeout"
    fi
    ;;
  bench)
    echo "== running the benchmarks (machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2-))"
    ctest --test-dir "$build" -L benchmark -V
    ;;
  demo)
    out=${HSLAM_DEMO_DIR:-$build/demo}
    mkdir -p "$out"
    # The main job on data every machine has: a synthetic room rendered from ViSP's image data with exact ground
    # truth, filmed wall after wall twice round (odometry drifts; the second lap revisits the first), with sensor
    # noise, motion blur, exposure changes, vignette and response. It runs through the same reader, rectifier and
    # system as a real sequence, with the default settings (slam: loop closure), then without loop closure
    # (vo-strict), and both are evaluated: the two top views are the "before / after" of closing the loop.
    seq="$out/synthetic-loop"
    if [ ! -f "$seq/complete" ]; then
      echo "== rendering a synthetic sequence into $seq (2 laps, 801 frames, 320x240; about a minute)"
      rm -rf "$seq"
      "$build/tutorials/tutorial-hslam-synthetic" --output "$seq" --frames 801 --laps 2 --look-outward --width 320 \
        --height 240 --noise 4 --motion-blur --exposure-changes --vignette --response
      touch "$seq/complete"
    fi
    for mode in slam vo-strict; do
      echo "== running H-SLAM on it, mode $mode (deterministic)"
      "$build/tutorials/tutorial-hslam-dataset" --input "$seq" --deterministic --no-display --mode "$mode" \
        --trajectory "$out/trajectory-$mode.txt" --keyframes "$out/keyframes-$mode.txt" --stats "$out/stats-$mode.json"
      echo "== evaluating it against the exact ground truth"
      "$build/tutorials/tutorial-hslam-evaluate" --groundtruth "$seq/groundtruth.txt" \
        --estimate "$out/trajectory-$mode.txt" --plot "$out/top-view-$mode.png"
    done
    echo "== loops closed: $(grep -o '"loops_corrected": [0-9]*' "$out/stats-slam.json" | grep -o '[0-9]*$') (slam);" \
      "top views without and with loop closure: $out/top-view-vo-strict.png, $out/top-view-slam.png"
    ;;
esac
