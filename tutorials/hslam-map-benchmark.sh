#!/usr/bin/env bash
# The global map and loop closure (issues 9, 10): vo-strict (window only, DSO-like), vo-reuse (marginalised points
# kept as a global map and re-used in the window) and slam (vo-reuse + loop detection, pose-graph
# correction and global bundle adjustment) on
# the shared real sequences and on synthetic sequences that drive the same loop several times, and the memory a
# marginalised keyframe costs on a long run.
#
#   bash tutorials/hslam-map-benchmark.sh [BUILD_DIR] [-- extra options for tutorial-hslam-dataset]
#   e.g. bash tutorials/hslam-map-benchmark.sh build -- --config data/hslam-fast.yaml
#
# Runs are deterministic runs of tutorial-hslam-dataset evaluated with tutorial-hslam-evaluate (Sim(3) ATE). Sections:
#   real    per shared sequence, tracking mode (TRACKING) and map mode (MODES): median ATE of the runs with
#           features.desiredImmatureDensity in BUDGETS (one run says little: see the hybrid benchmark's
#           spread), the runs' ATEs, mapping ms per keyframe (median of the runs' medians), re-activated and fused
#           global points per keyframe, share of the window's points from the global map, culled keyframes,
#           loops detected (sum over the runs: these sequences have none); each map mode after the first is
#           compared with the first (ratio of the median ATEs, its 90 % bootstrap interval: compare_medians)
#   loop    the synthetic room filmed wall after wall (--look-outward), LOOP_LAPS laps of 400 frames, 320x240 with
#           the effects below: a loop a sliding window cannot close by itself. Per tracking and map mode, the same runs and
#           medians as "real", plus loops detected / corrected, the longest correction and lap_rpe: the translation
#           RPE over one lap (400 frames), i.e. how far the estimate at a place is from the estimate one lap earlier
#           at the same place (after the Sim(3) scale): 0 when the later laps are registered onto the first
#   laps    synthetic room (tutorial-hslam-synthetic, LAP_FRAMES frames a lap, LAPS laps, 320x240, noise, motion
#           blur, exposure changes, vignette, response) per tracking and map mode: ATE, the drift between start and
#           end of the run (TUM monoVO alignment error with 3 s segments: the loop ends where it started), mapping ms,
#           re-use counts, stored and culled keyframes, memory per marginalised keyframe
#   localization  per shared sequence and tracking mode: a slam run saves its map (--save-map), then the same
#           sequence is run in localisation-only mode in that map (--load-map --localization-only): frames located,
#           ATE of both runs, their ratio, localisation ms per frame (median, p95), whether the map file is unchanged
#           (saved again after the localisation run: the same bytes), map file size in KB per keyframe
#   memory  test/hslam_soak in vo-reuse (4000 frames of the 640x480 loop, real-time mode, one run): resident
#           memory growth per keyframe after the first 50 keyframes against the statistics' memory per marginalised
#           keyframe (needs the test programs built: HSLAM_BUILD_TESTS)
# Environment: DATA (default <repo>/../shared/data), OUT (default /tmp/hslam-map-bench), SEQUENCES, TRACKING
# (default "hybrid direct"), MODES (default "vo-strict vo-reuse slam"), SECTIONS (default "real loop laps
# localization memory"),
# LOOP_LAPS (laps of the outward loop, default "2 3"), LAPS (default "2 3"), LAP_FRAMES (default 300), SOAK_FRAMES (default 4000), BUDGETS (the point budgets
# features.desiredImmatureDensity of the runs whose median is reported, default "490 495 500 505 510").
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
sections="${SECTIONS:-real loop laps localization memory}"
map_modes="${MODES:-vo-strict vo-reuse slam}"
laps_list="${LAPS:-2 3}"
loop_laps_list="${LOOP_LAPS:-2 3}"
lap_frames="${LAP_FRAMES:-300}"
soak_frames="${SOAK_FRAMES:-4000}"
budgets="${BUDGETS:-490 495 500 505 510}"
read -r -a budget_list <<< "$budgets"
source "$repo/tutorials/benchmark-common.sh"

sum_json() { # KEY PREFIX... -> sum of the key over the runs' statistics
  local key="$1" total=0 p
  shift
  for p in "$@"; do
    total=$((total + $(json "$p.json" "$key" | sed 's/nan/0/')))
  done
  echo "$total"
}

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

run_budgets() { # PREFIX SEQUENCE TRACKING MODE -> one run per point budget; sets ates (nan for a failed run), prefixes
  local base="$1" seq="$2" track="$3" mode="$4" value prefix
  ates=()
  prefixes=()
  for value in $budgets; do
    prefix="$base.p$value"
    if run "$prefix" "$seq" --tracking-mode "$track" --mode "$mode" --set "features.desiredImmatureDensity=$value"; then
      ates+=("$(ate "$prefix")")
      prefixes+=("$prefix")
    else
      ates+=(nan)
    fi
  done
}

# against_first MODE: after the first map mode of a (sequence, tracking) group, the ratio of this mode's median ATE to
# the first one's, its 90 % bootstrap interval (compare_medians) and the runs it won; remembers the first mode's ATEs.
against_first() {
  if [[ "$1" == "$first_map_mode" ]]; then
    first_ates="${ates[*]}"
    return
  fi
  read -r ratio lo hi wins pairs <<< "$(compare_medians "$first_ates" "${ates[*]}")"
  printf "   %s / %s: ATE ratio %s, 90 %% interval [%s, %s], better in %s of %s runs\n" "$1" "$first_map_mode" "$ratio" \
    "$lo" "$hi" "$wins" "$pairs"
}
read -r first_map_mode _ <<< "$map_modes"
first_ates=""

if has_section real; then
  echo "== real sequences: median of ${#budget_list[@]} runs (point budgets $budgets)"
  printf "%-28s %-7s %-9s %9s %8s %7s %7s %7s %7s %5s   %s\n" sequence track map ate map_ms react fused share culled \
    loops runs
  for seq in $sequences; do
    [[ -d "$data/$seq" ]] || { echo "$seq: not found under $data, skipped"; continue; }
    for track in $tracking_modes; do
      for mode in $map_modes; do
        run_budgets "$out/$seq.$track.$mode" "$seq" "$track" "$mode"
        [[ ${#prefixes[@]} -gt 0 ]] || continue
        printf "%-28s %-7s %-9s %9.4f %s %5s   %s\n" "$seq" "$track" "$mode" "$(median "${ates[@]}")" \
          "$(reuse_columns "${prefixes[@]}")" "$(sum_json loops_detected "${prefixes[@]}")" "${ates[*]}"
        against_first "$mode"
      done
    done
  done
  echo
fi

if has_section loop; then
  synthetic="$build/tutorials/tutorial-hslam-synthetic"
  # One lap of the generator's loop: 400 frames at its 30 Hz (the ground truth repeats itself after it).
  loop_lap_frames=400
  loop_lap_seconds=$(awk -v n="$loop_lap_frames" 'BEGIN { printf "%.4f", n / 30 }')
  for loop_laps in $loop_laps_list; do
    loop_frames=$((loop_laps * loop_lap_frames + 1))
    seq="$out/synthetic-outward-${loop_laps}laps"
    echo "== loop: the room filmed wall after wall, $loop_laps laps of $loop_lap_frames frames (320x240, noise 4, blur,"
    echo "   exposure, vignette, response); median of ${#budget_list[@]} runs (point budgets $budgets)"
    if [[ ! -f "$seq/complete" ]]; then
      rm -rf "$seq"
      "$synthetic" --output "$seq" --frames "$loop_frames" --laps "$loop_laps" --look-outward --width 320 \
        --height 240 --noise 4 --motion-blur --exposure-changes --vignette --response \
        > "$out/synthetic-outward-$loop_laps.log" 2>&1 && touch "$seq/complete" ||
        echo "outward loop: generation failed, see $out/synthetic-outward-$loop_laps.log"
    fi
    printf "%-7s %-9s %9s %8s %10s %8s %12s %7s %7s %10s   %s\n" track map ate lap_rpe tracked map_ms loops/corr \
      det_ms max_ver max_corr_ms runs
    for track in $tracking_modes; do
      for mode in $map_modes; do
        run_budgets "$out/outward$loop_laps.$track.$mode" "$seq" "$track" "$mode"
        [[ ${#prefixes[@]} -gt 0 ]] || continue
        maps=()
        tracks=()
        detections=()
        lap_rpes=()
        worst=0
        verification=0
        for p in "${prefixes[@]}"; do
          maps+=("$(json "$p.json" mapping_ms_per_keyframe_median)")
          lap_rpe="$("$evaluate" --groundtruth "$seq/groundtruth.txt" --estimate "$p.txt" --rpe-delta "$loop_lap_seconds" \
            2> /dev/null | sed -n "s/^rpe_trans_rmse_m=//p")"
          lap_rpes+=("${lap_rpe:-nan}")
          tracks+=("$(json "$p.json" tracked_frames)")
          detections+=("$(json "$p.json" loop_detection_ms_mean)")
          worst="$(awk -v a="$worst" -v b="$(json "$p.json" loop_correction_ms_max)" 'BEGIN { print (b > a ? b : a) }')"
          verification="$(awk -v a="$verification" -v b="$(json "$p.json" loop_verification_ms_max)" \
            'BEGIN { print (b > a ? b : a) }')"
        done
        printf "%-7s %-9s %9.4f %8.4f %10s %8.2f %12s %7.2f %7.1f %10.1f   %s\n" "$track" "$mode" \
          "$(median "${ates[@]}")" "$(median "${lap_rpes[@]}")" "$(median "${tracks[@]}")/$loop_frames" \
          "$(median "${maps[@]}")" \
          "$(sum_json loops_detected "${prefixes[@]}")/$(sum_json loops_corrected "${prefixes[@]}")" \
          "$(median "${detections[@]}")" "$verification" "$worst" "${ates[*]}"
        against_first "$mode"
      done
    done
    echo
  done
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
      for mode in $map_modes; do
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

if has_section localization; then
  echo "== localisation-only in a map saved by a slam run of the same sequence"
  printf "%-28s %-7s %9s %9s %9s %6s %10s %8s %8s %9s %7s\n" sequence track located map_ate loc_ate ratio \
    kf loc_ms loc_p95 unchanged kb_kf
  for seq in $sequences; do
    [[ -d "$data/$seq" ]] || { echo "$seq: not found under $data, skipped"; continue; }
    for track in $tracking_modes; do
      mapping="$out/$seq.$track.localization-map"
      located="$out/$seq.$track.localization"
      run "$mapping" "$seq" --tracking-mode "$track" --mode slam --save-map "$mapping.hmap" || continue
      run "$located" "$seq" --load-map "$mapping.hmap" --localization-only --save-map "$located.hmap" || continue
      unchanged=no
      cmp -s "$mapping.hmap" "$located.hmap" && unchanged=yes
      keyframes="$(json "$mapping.json" keyframes_held)"
      printf "%-28s %-7s %9s %9.4f %9.4f %6.2f %10s %8.2f %8.2f %9s %7.1f\n" "$seq" "$track" "$(tracked "$located")" \
        "$(ate "$mapping")" "$(ate "$located")" \
        "$(awk -v a="$(ate "$located")" -v b="$(ate "$mapping")" 'BEGIN { print (b > 0 ? a / b : 0) }')" \
        "$keyframes" "$(json "$located.json" tracking_ms_median)" "$(json "$located.json" tracking_ms_p95)" \
        "$unchanged" \
        "$(awk -v s="$(stat -c %s "$mapping.hmap")" -v k="$keyframes" 'BEGIN { print (k > 0 ? s / k / 1024 : 0) }')"
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
echo " culled: share of the marginalised keyframes culled; kb_kf: memory per marginalised keyframe; loops/corr: loops"
echo " detected / corrected summed over the runs; det_ms: loop detection ms per keyframe (median of the runs);"
echo " max_ver: longest Sim(3) verification of a candidate, ms; max_corr_ms: longest loop correction; lap_rpe:"
echo " translation RPE over one lap of the outward loop, metres (0: later laps registered onto the first); files in"
echo " $out)"
if [[ $failures -gt 0 ]]; then
  echo "$failures run(s) failed"
  exit 1
fi
