#!/usr/bin/env bash
# Check that modules/hslam configures and builds UNCHANGED inside a ViSP 3.5 source build, as a contrib module:
#   cmake <visp-src> -DVISP_CONTRIB_MODULES_PATH=<repo>/modules
# then builds visp_hslam and the module's own test (run with ViSP's "-c -d" options) and runs it with ctest, and
# builds test/package/consumer against that ViSP build with find_package(VISP REQUIRED COMPONENTS visp_hslam).
#
#   bash cmake/check-contrib-build.sh [WORK_DIR]      (default WORK_DIR: /tmp/hslam-contrib-check)
#
# ViSP's source comes from Debian's archive (apt-get source visp, Debian's patches applied), so this needs a
# deb-src entry for bookworm; as root the script adds one when missing. It is slow (about 15-25 min on 2 cores,
# most of it building visp_core), so CI does not run it. Only the ViSP modules visp_hslam needs are enabled.
set -euo pipefail
repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
work=${1:-/tmp/hslam-contrib-check}
jobs=${JOBS:-$(nproc)}
mkdir -p "$work"

if [ ! -d "$work/visp-3.5.0" ]; then
  if ! grep -rqs "^Types:.*deb-src" /etc/apt/sources.list.d/ && ! grep -qs "^deb-src" /etc/apt/sources.list; then
    if [ "$(id -u)" -ne 0 ]; then
      echo "no deb-src entry for bookworm: add one (see docs/running.md) or run as root" >&2
      exit 1
    fi
    cat >/etc/apt/sources.list.d/hslam-debian-src.sources <<'SRC'
Types: deb-src
URIs: http://deb.debian.org/debian
Suites: bookworm
Components: main
Signed-By: /usr/share/keyrings/debian-archive-keyring.gpg
SRC
  fi
  [ "$(id -u)" -eq 0 ] && apt-get update -qq
  (cd "$work" && apt-get source -qq visp)
fi
src=$(ls -d "$work"/visp-3.5.0)

# ViSP modules visp_hslam does not need are switched off to keep the check short.
off=()
for m in imgproc klt me ar blob robot visual_features vs vision detection mbt tt tt_mi gui; do
  off+=("-DBUILD_MODULE_visp_$m=OFF")
done

cmake -S "$src" -B "$work/build" -DCMAKE_BUILD_TYPE=Release -DVISP_CONTRIB_MODULES_PATH="$repo/modules" \
  -DBUILD_TESTS=ON -DBUILD_EXAMPLES=OFF -DBUILD_DEMOS=OFF -DBUILD_TUTORIALS=OFF -DBUILD_APPS=OFF \
  -DBUILD_JAVA=OFF "${off[@]}" | tee "$work/configure.log" | grep -iE "hslam|error" || true
grep -q "visp_hslam" "$work/build/VISPModules.cmake" 2>/dev/null || grep -q "visp_hslam" "$work/configure.log" || {
  echo "FAIL: ViSP's configure did not pick up visp_hslam" >&2
  exit 1
}
cmake --build "$work/build" -j "$jobs" --target visp_hslam testHSlamModule
(cd "$work/build" && ctest -R testHSlamModule --output-on-failure)
# A user's project against this ViSP build: find_package(VISP REQUIRED COMPONENTS visp_hslam).
cmake --build "$work/build" -j "$jobs" --target visp_io visp_sensor
cmake -S "$repo/test/package/consumer" -B "$work/consumer" -DCMAKE_BUILD_TYPE=Release -DHSLAM_CONSUMER_CONTRIB=ON \
  -DVISP_DIR="$work/build" >"$work/consumer-configure.log" || { cat "$work/consumer-configure.log"; exit 1; }
cmake --build "$work/consumer" -j "$jobs"
data="$repo/../shared/data/kitti06_000-050"
if [ -d "$data" ]; then
  "$work/consumer/first-pose" "$data" 20 | tail -1
fi
echo "contrib-mode check passed: visp_hslam built inside ViSP $(basename "$src") from $repo/modules"
