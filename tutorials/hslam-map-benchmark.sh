#!/usr/bin/env bash
# The global map (issue 9): vo-strict (window only, DSO-like) against vo-reuse (marginalised points kept as a global
# map and re-used in the window) on the shared real sequences and on synthetic sequences that drive the same loop
# several times, and the memory a marginalised keyframe costs on a long run.
#
#   bash tutorials/hslam-map-benchmark.sh [BUILD_DIR] [-- extra options for tutorial-hslam-dataset]
#   e.g. bash tutorials/hslam-map-benchmark.sh build -- --config data/hslam-fast.yaml
#
# Runs are deterministic runs of tutorial-hslam-dataset evaluated with tutorial-hslam-evaluate (Sim(3) ATE). Sections:
#   real    per shared sequence, tracking mode (TRACKING) and map mode: median ATE of the runs with
#           features.desiredImmatureDensity = 490 495 500 505 510 (one run says little: see the hybrid benchmark's
#           spread), the runs' ATEs, mapping ms per keyframe (median of the runs' medians), re-activated and fused
#           global points per keyframe, share of the window's points from the global map, culled keyframes
#   laps    synthetic room (tutorial-hslam-synthetic, LAP_FRAMES frames a lap, LAPS laps, 320x240, noise, motion
#           blur, exposure changes, vignette, response) per tracking and map mode: ATE, the drift between start and
#           end of the run (TUM monoVO alignment error with 3 s segments: the loop ends where it started), mapping ms,
#           re-use counts, stored and culled keyframes, memory per marginalised keyframe
#   memory  test/hslam_soak in vo-reuse (4000 frames of the 640x480 loop, real-time mode, one run): resident
#           memory growth per keyframe after the first 50 keyframes against the statistics' memory per marginalised
#           keyframe (needs the test programs built: HSLAM_BUILD_TESTS)
# Environment: DATA (default <repo>/../shared/data), OUT (default /tmp/hslam-map-bench), SEQUENCES, TRACKING
# (default "hybrid direct"), SECTIONS (default "real laps memory"), LAPS (default "2 3"), LAP_FRAMES (default 300),
# SOAK_FRAMES (default 4000).
set -uo pipefail # not -e: one failed run must not end the benchmark

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="$repo/build"
if [[ $# -ge 1 && "$1" != "--" ]]; then
  build="$1"
  shift
fi
if [[ "${1:-}" == "--" ]]; then shift; fi
extra=("$@")
data="${DATA:-$repo/../shared/data}"
out="${OUT:-/tmp/hslam-map-bench}"
sequences="${SEQUENCES:-7scenes_redkitchen_000-299 tsukuba_cg_000-149 kitti06_000-050}"
tracking_modes="${TRACKING:-hybrid direct}"
sections="${SECTIONS:-real laps memory}"
laps_list="${LAPS:-2 3}"
lap_frames="${LAP_FRAMES:-300}"
soak_frames="${SOAK_FRAMES:-4000}"
source "$repo/tutorials/benchmark-common.sh"

reuse_columns() { # PREFIX... -> medians of the re-use statistics of the runs
  local r=() f=() s=() c=() m=() p
  for p in "$@"; do
    r+=("$(json "$p.json" reactivated_points_per_keyframe)")
    f+=("$(json "$p.json" fused_points_per_keyframe)")
    s+=("$(json "$p.json" window_share_from_global)")
    m+=("$(json "$p.json" mapping_ms_per_keyframe_median)")
    c+=("$(awk -v a="$(json "$p.json" culled_keyframes)" -v b="$(json "$p.json" marginalized_keyframes)" \
      'BEGIN { print (b > 0 ? a / b : 0) }')")
  done
  printf "%8.2f %7.2f %7.2f %7.3f %7.2f" "$(median "${m[@]}")" "$(median "${r[@]}")" "$(median "${f[@]}")" \
    "$(median "${s[@]}")" "$(median "${c[@]}")"
}

if has_section real; then
  echo "== real sequences: median of 5 runs (point budget 490..510)"
  printf "%-28s %-7s %-9s %9s %8s %7s %7s %7s %7s   %s\n" sequence track map ate map_ms react fused share culled runs
  for seq in $sequences; do
    [[ -d "$data/$seq" ]] || { echo "$seq: not found under $data, skipped"; continue; }
    for track in $tracking_modes; do
      for mode in vo-strict vo-reuse; do
        ates=()
        prefixes=()
        for value in 490 495 500 505 510; do
          prefix="$out/$seq.$track.$mode.p$value"
          if run "$prefix" "$seq" --tracking-mode "$track" --mode "$mode" \
            --set "features.desiredImmatureDensity=$value"; then
            ates+=("$(ate "$prefix")")
            prefixes+=("$prefix")
          else
            ates+=(nan)
          fi
        done
        [[ ${#prefixes[@]} -gt 0 ]] || continue
        printf "%-28s %-7s %-9s %9.4f %s   %s\n" "$seq" "$track" "$mode" "$(median "${ates[@]}")" \
          "$(reuse_columns "${prefixes[@]}")" "${ates[*]}"
      done
    done
  done
  echo
fi

if has_section laps; then
  synthetic="$build/tutorials/tutorial-hslam-synthetic"
  echo "== synthetic loop driven several times (320x240, noise, blur, exposure changes, vignette, response)"
  printf "%-5s %-7s %-9s %9s %9s %8s %7s %7s %7s %11s %8s\n" laps track map ate drift map_ms react fused share \
    stored/cull kb_kf
  for laps in $laps_list; do
    frames=$((laps * lap_frames + 1))
    seq="$out/synthetic-${laps}laps-$lap_frames"
    if [[ ! -f "$seq/complete" ]]; then
      rm -rf "$seq"
      "$synthetic" --output "$seq" --frames "$frames" --laps "$laps" --width 320 --height 240 --noise 4 \
        --motion-blur --exposure-changes --vignette --response > "$out/synthetic-$laps.log" 2>&1 &&
        touch "$seq/complete" || { echo "synthetic $laps laps: generation failed, see $out/synthetic-$laps.log"; continue; }
    fi
    for track in $tracking_modes; do
      for mode in vo-strict vo-reuse; do
        prefix="$out/synthetic-$laps.$track.$mode"
        run "$prefix" "$seq" --tracking-mode "$track" --mode "$mode" || continue
        drift="$("$evaluate" --groundtruth "$seq/groundtruth.txt" --estimate "$prefix.txt" --segment-length 3 \
          2>/dev/null | sed -n 's/^alignment_error_m=//p')"
        printf "%-5s %-7s %-9s %9.5f %9.5f %s %5s/%-5s %8.1f\n" "$laps" "$track" "$mode" "$(ate "$prefix")" \
          "${drift:-nan}" "$(reuse_columns "$prefix" | awk '{ printf "%8.2f %7.2f %7.2f %7.3f", $1, $2, $3, $4 }')" \
          "$(json "$prefix.json" marginalized_keyframes)" "$(json "$prefix.json" culled_keyframes)" \
          "$(awk -v m="$(json "$prefix.json" memory_mb_per_keyframe)" 'BEGIN { print m * 1024 }')"
      done
    done
  done
  echo
fi

if has_section memory; then
  soak="$build/test/hslam_soak"
  echo "== memory: $soak_frames frames of the 640x480 loop in vo-reuse, real-time mode"
  if [[ -x "$soak" ]]; then
    soak_options=()
    for ((i = 0; i + 1 < ${#extra[@]}; ++i)); do # the soak takes --config of the extra options, nothing else
      [[ "${extra[$i]}" == --config ]] && soak_options=(--config "${extra[$((i + 1))]}")
    done
    "$soak" --frames "$soak_frames" --mode vo-reuse "${soak_options[@]}" --out "$out/soak-reuse" \
      > "$out/soak-reuse.log" 2>&1 || { echo "soak failed, see $out/soak-reuse.log"; failures=$((failures + 1)); }
    grep -E "^frames|^global map|FAIL" "$out/soak-reuse.log"
  else
    echo "$soak not built (configure with -DHSLAM_BUILD_TESTS=ON), skipped"
  fi
  echo
fi
echo "(ATE and drift in ground-truth units: metres, Tsukuba centimetres; map_ms: mapping ms per keyframe; react/fused:"
echo " global points re-activated / fused per keyframe; share: of the window's active points, from the global map;"
echo " culled: share of the marginalised keyframes culled; kb_kf: memory per marginalised keyframe; files in $out)"
if [[ $failures -gt 0 ]]; then
  echo "$failures run(s) failed"
  exit 1
fi
