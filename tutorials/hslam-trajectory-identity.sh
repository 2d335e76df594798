#!/usr/bin/env bash
# Behaviour unchanged across a refactor (issue 51): deterministic runs of the shared sequences in every mode, their
# trajectories (and keyframes, and the saved map) recorded once with the old build and compared byte for byte with
# the new build's.
#
#   bash tutorials/hslam-trajectory-identity.sh record DIR [BUILD_DIR]   # before the change: reference outputs
#   bash tutorials/hslam-trajectory-identity.sh check DIR [BUILD_DIR]    # after it: exit 1 on any difference
#
# Runs (each sequence of SEQUENCES, default the four shared ones): vo-strict, vo-reuse, slam (the defaults), slam
# played there and back (loops close on the way back), the same with globalMap.reuse=false, hybrid and indirect
# tracking, one stride-4 run (relocalisation and new segments), and a map saved by slam then used in
# localisation-only. Deterministic mode only: real-time runs depend on thread timing and are not comparable.
# Environment: DATA (default <repo>/../shared/data), SEQUENCES.
set -uo pipefail

usage() { echo "usage: $0 record|check DIR [BUILD_DIR]" >&2; exit 2; }
[[ $# -ge 2 ]] || usage
action="$1"
dir="$2"
[[ "$action" == record || "$action" == check ]] || usage
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${3:-$repo/build}"
data="${DATA:-$repo/../shared/data}"
dataset="$build/tutorials/tutorial-hslam-dataset"
[[ -x "$dataset" ]] || { echo "error: $dataset not built" >&2; exit 1; }
[[ -d "$data" ]] || { echo "error: no shared data at $data" >&2; exit 1; }
sequences="${SEQUENCES:-7scenes_redkitchen_000-299 tsukuba_cg_000-149 kitti06_000-050 euroc_V1_01_easy_first95}"

if [[ "$action" == record ]]; then
  out="$dir"
else
  [[ -d "$dir" ]] || { echo "error: no reference outputs in $dir (record them first)" >&2; exit 1; }
  out="$(mktemp -d)"
  trap 'rm -rf "$out"' EXIT
fi
mkdir -p "$out" || exit 1

configs=(
  "vo-strict|--mode vo-strict"
  "vo-reuse|--mode vo-reuse"
  "slam|--mode slam --save-map @MAP@"
  "slam-tab|--mode slam --there-and-back"
  "slam-tab-noreuse|--mode slam --there-and-back --set globalMap.reuse=false"
  "hybrid|--mode slam --tracking-mode hybrid"
  "indirect|--mode slam --tracking-mode indirect"
  "stride4|--mode slam --stride 4"
  "localization|--load-map @MAP@ --localization-only --start-frame 10"
)

differences=0
runs=0
# same A B: both files absent (a run that wrote nothing, both times) or byte for byte equal
same() { [[ ! -e "$1" && ! -e "$2" ]] || cmp -s "$1" "$2"; }
for seq in $sequences; do
  [[ -d "$data/$seq" ]] || { echo "$seq: not found under $data, skipped"; continue; }
  for entry in "${configs[@]}"; do
    name="${entry%%|*}"
    options="${entry#*|}"
    prefix="$out/$seq.$name"
    options="${options//@MAP@/$out/$seq.slam.hmap}"
    # shellcheck disable=SC2086
    "$dataset" --input "$data/$seq" --deterministic --no-display --quiet --trajectory "$prefix.txt" \
      --keyframes "$prefix.kf.txt" $options > "$prefix.log" 2>&1
    echo "exit $?" > "$prefix.exit"
    runs=$((runs + 1))
    [[ "$action" == check ]] || continue
    for suffix in exit txt kf.txt; do
      if ! same "$prefix.$suffix" "$dir/$seq.$name.$suffix"; then
        echo "DIFFERENT: $seq $name ($suffix)"
        differences=$((differences + 1))
      fi
    done
    # the segment files written after a loss of tracking
    for reference in "$dir/$seq.$name".txt.seg*.txt; do
      [[ -e "$reference" ]] || continue
      same "$reference" "$out/$(basename "$reference")" ||
        { echo "DIFFERENT: $seq $name ($(basename "$reference"))"; differences=$((differences + 1)); }
    done
    if [[ "$name" == slam ]] && ! same "$prefix.hmap" "$dir/$seq.slam.hmap"; then
      echo "DIFFERENT: $seq slam (saved map)"
      differences=$((differences + 1))
    fi
  done
done

if [[ "$action" == record ]]; then
  echo "recorded $runs runs in $out"
  exit 0
fi
if [[ $differences -gt 0 ]]; then
  echo "$differences outputs differ over $runs runs"
  exit 1
fi
echo "identical: $runs runs, trajectories, keyframes and saved maps byte for byte"
