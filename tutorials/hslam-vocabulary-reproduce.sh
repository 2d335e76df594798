#!/usr/bin/env bash
# Re-trains the shipped vocabulary data/hslam-orb.hvoc and checks that the result is byte-identical.
#   bash tutorials/hslam-vocabulary-reproduce.sh [BUILD_DIR]
# It was trained on every image under Debian's visp-images-data (/usr/share/visp-images-data/ViSP-images, 1025
# files, sorted by path), 1000 ORB features each, k = 10, L = 6, seed 1 (about 20 s on one core). Byte identity
# needs the same OpenCV ORB (Debian 12's OpenCV 4.6) and the same package version of visp-images-data.
set -euo pipefail
repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${1:-$repo/build}
images=${VISP_IMAGES:-/usr/share/visp-images-data/ViSP-images}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
"$build/tutorials/tutorial-hslam-vocabulary" --images "$images" --output "$out/hslam-orb.hvoc" \
  --branching 10 --levels 6 --features 1000 --seed 1
if cmp "$out/hslam-orb.hvoc" "$repo/data/hslam-orb.hvoc"; then
  echo "reproduced: byte-identical to data/hslam-orb.hvoc"
else
  echo "NOT identical to data/hslam-orb.hvoc" >&2
  exit 1
fi
