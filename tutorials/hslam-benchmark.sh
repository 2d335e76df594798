#!/usr/bin/env bash
# Accuracy and speed of H-SLAM on the shared real sequences (the acceptance runs of the direct core).
#
#   bash tutorials/hslam-benchmark.sh [BUILD_DIR] [RUNS] [-- extra options for tutorial-hslam-dataset]
#
# For each sequence of ../shared/data: RUNS deterministic runs of tutorial-hslam-dataset (no display), each
# evaluated with tutorial-hslam-evaluate (Sim(3)-aligned ATE of every frame with a pose, and of the keyframes only),
# then one line per sequence with the MEDIAN over the runs of: ATE (all frames, keyframes), tracked share,
# keyframes, tracking ms median/p95, mapping ms per keyframe, CPU seconds, wall seconds, video seconds, real-time
# factor (video / CPU), peak memory and memory per keyframe. Per-run files go to $OUT (default /tmp/hslam-bench).
# Environment: DATA (default <repo>/../shared/data), OUT, SEQUENCES (space-separated folder names).
set -euo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${1:-$repo/build}"
runs="${2:-3}"
shift $(( $# >= 2 ? 2 : $# ))
if [[ "${1:-}" == "--" ]]; then shift; fi
extra=("$@")
data="${DATA:-$repo/../shared/data}"
out="${OUT:-/tmp/hslam-bench}"
sequences="${SEQUENCES:-7scenes_redkitchen_000-299 tsukuba_cg_000-149 kitti06_000-050 euroc_V1_01_easy_first95}"
dataset="$build/tutorials/tutorial-hslam-dataset"
evaluate="$build/tutorials/tutorial-hslam-evaluate"
for program in "$dataset" "$evaluate"; do
  [[ -x "$program" ]] || { echo "error: $program not built (cmake --build $build --target $(basename "$program"))" >&2; exit 1; }
done
mkdir -p "$out"

groundtruth() {
  case "$1" in
    kitti*) echo "$data/$1/groundtruth_tum.txt" ;;
    euroc*) echo "$data/$1/groundtruth_cam0_tum.txt" ;;
    *) echo "$data/$1/groundtruth.txt" ;;
  esac
}

json() { # json FILE KEY
  sed -n "s/^ *\"$2\": *\([^,]*\),\{0,1\}$/\1/p" "$1" | head -n 1
}

median() { # numbers on stdin -> median
  sort -g | awk '{ a[NR] = $1 } END { if (NR == 0) { print "nan" } else if (NR % 2) { print a[(NR + 1) / 2] } else { print (a[NR / 2] + a[NR / 2 + 1]) / 2 } }'
}

printf "%-28s %9s %9s %7s %4s %7s %7s %8s %6s %6s %6s %6s %7s %6s\n" sequence ate_all ate_kf tracked kf trk_ms trk_p95 map_ms cpu_s wall_s video_s rt_cpu peak_mb mb_kf
for seq in $sequences; do
  [[ -d "$data/$seq" ]] || { echo "$seq: not found under $data, skipped"; continue; }
  gt="$(groundtruth "$seq")"
  : > "$out/$seq.runs"
  for ((r = 1; r <= runs; ++r)); do
    prefix="$out/$seq.run$r"
    if ! "$dataset" --input "$data/$seq" --deterministic --no-display --quiet --trajectory "$prefix.txt" \
      --keyframes "$prefix.kf.txt" --stats "$prefix.json" "${extra[@]}" > "$prefix.log" 2>&1; then
      echo "$seq run $r: tutorial-hslam-dataset failed, see $prefix.log"
    fi
    ate_all="$("$evaluate" --groundtruth "$gt" --estimate "$prefix.txt" 2>/dev/null | sed -n "s/^ate_rmse_m=//p" || true)"
    ate_kf="$("$evaluate" --groundtruth "$gt" --estimate "$prefix.kf.txt" 2>/dev/null | sed -n "s/^ate_rmse_m=//p" || true)"
    frames="$(json "$prefix.json" frames)"
    tracked="$(json "$prefix.json" tracked_frames)"
    echo "${ate_all:-nan} ${ate_kf:-nan} $(awk -v t="$tracked" -v f="$frames" 'BEGIN { print (f > 0 ? t / f : 0) }') \
$(json "$prefix.json" keyframes) $(json "$prefix.json" tracking_ms_median) $(json "$prefix.json" tracking_ms_p95) \
$(json "$prefix.json" mapping_ms_per_keyframe_median) $(json "$prefix.json" cpu_s) $(json "$prefix.json" wall_s) \
$(json "$prefix.json" video_s) $(json "$prefix.json" peak_rss_mb) $(json "$prefix.json" memory_mb_per_keyframe)" >> "$out/$seq.runs"
  done
  col() { awk -v c="$1" '{ print $c }' "$out/$seq.runs" | median; }
  cpu="$(col 8)"; video="$(col 10)"
  printf "%-28s %9.4f %9.4f %7.3f %4.0f %7.2f %7.2f %8.1f %6.2f %6.2f %6.2f %6.2f %7.1f %6.2f\n" "$seq" \
    "$(col 1)" "$(col 2)" "$(col 3)" "$(col 4)" "$(col 5)" "$(col 6)" "$(col 7)" "$cpu" "$(col 9)" "$video" \
    "$(awk -v v="$video" -v c="$cpu" 'BEGIN { print (c > 0 ? v / c : 0) }')" "$(col 11)" "$(col 12)"
done
echo "(ATE in ground-truth units: metres, Tsukuba centimetres; medians over $runs run(s); rt_cpu = video s / CPU s)"
