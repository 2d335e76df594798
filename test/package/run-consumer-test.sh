#!/usr/bin/env bash
# Installs this build into a temporary prefix, builds test/package/consumer against it as a separate CMake project,
# and runs the consumer on a real sequence when one is given (ctest: package.consumer).
#   bash test/package/run-consumer-test.sh BUILD_DIR [DATASET_FOLDER]
set -euo pipefail
build=$1
data=${2:-}
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cmake --install "$build" --prefix "$work/install" >"$work/install.log"
echo "installed into a temporary prefix: $(find "$work/install" -type f | wc -l) files"
test -f "$work/install/lib/cmake/HSLAM/HSLAMConfig.cmake"
test -f "$work/install/include/visp3/hslam/vpHSlam.h"
cmake -S "$here/consumer" -B "$work/consumer" -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$work/install" \
  >"$work/configure.log" || { cat "$work/configure.log"; exit 1; }
cmake --build "$work/consumer" -j 2 >"$work/build.log" || { cat "$work/build.log"; exit 1; }
echo "consumer project built: first-pose, live-camera"
if [ -n "$data" ] && [ -d "$data" ]; then
  "$work/consumer/first-pose" "$data" 20 | tail -3
else
  echo "no dataset folder at ${data:-(none)}: the consumer was built, not run (skipped)"
  exit 77
fi
