#!/usr/bin/env bash
# Direct, indirect and hybrid tracking compared on the shared real sequences (the paper's ablation), under large
# inter-frame motion, and with the lens covered for a while.
#
#   bash tutorials/hslam-hybrid-benchmark.sh [BUILD_DIR] [-- extra options for tutorial-hslam-dataset]
#   e.g. bash tutorials/hslam-hybrid-benchmark.sh build -- --config data/hslam-fast.yaml
#
# Every run is one deterministic run of tutorial-hslam-dataset (--deterministic --no-display --quiet, then the extra
# options), evaluated with tutorial-hslam-evaluate (Sim(3)-aligned ATE of every frame with a pose; after a loss the
# segments, which have scales of their own, are aligned together, so a loss shows in the ATE). Sections:
#   ablation  per sequence and tracking mode: tracked/frames, segments, ATE, tracking ms median and p95, ORB matches
#             and inliers (medians), K (geometric weight of eq. 4, median)
#   stride    large motion: tracked/frames and ATE per mode with --stride K for each K of STRIDES
#   blackout  covered lens: BLACKOUT_SEQUENCE with --blackout BLACKOUT per mode, against the uninterrupted run:
#             segments, tracked/frames, relocalisations attempted/succeeded, ATE
#   focal     not in the default sections: how much the camera model weighs on FOCAL_SEQUENCE (default
#             7scenes_redkitchen_000-299, whose RGB camera is uncalibrated): its camera.txt copied to $OUT with the
#             focal length replaced by each of FOCALS ("fx" or "fx:fy", default "525 532.57:531.54 550 575 585"),
#             the median ATE per mode over PERTURB_KEY = FOCAL_VALUES (default 475 480 ... 525, 11 runs)
#   spread    how much one deterministic run says: per sequence and mode, runs with PERTURB_KEY set to each of
#             PERTURB_VALUES (default: features.desiredImmatureDensity = 490 495 500 505 510, the fast preset's
#             500 moved by up to 2 %), their ATEs and the median. A 2 % change of the point budget moves the ATE of
#             one run by 10-25 % on these short sequences, so compare modes by these medians, not by single runs;
#             each mode after the first is compared with it (compare_medians in benchmark-common.sh: ratio of the
#             medians and its 90 % bootstrap interval).
# A run that fails prints a line naming its log and the benchmark carries on (the exit status is then 1). Per-run
# files go to $OUT.
# Environment: DATA (default <repo>/../shared/data), OUT (default /tmp/hslam-hybrid-bench), SEQUENCES
# (space-separated folder names), MODES (default "direct indirect hybrid"), STRIDES (default "1 2 3 4 5 6 7 8"),
# SECTIONS (default "ablation spread stride blackout"), PERTURB_KEY, PERTURB_VALUES, BLACKOUT_SEQUENCE (default 7scenes_redkitchen_000-299), BLACKOUT
# (default 120:160), MAP_MODE (--mode of every run, default vo-strict), FOCAL_SEQUENCE, FOCALS, FOCAL_VALUES.
set -uo pipefail # not -e: one failed run must not end the benchmark

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="$repo/build"
if [[ $# -ge 1 && "$1" != "--" ]]; then
  build="$1"
  shift
fi
if [[ "${1:-}" == "--" ]]; then shift; fi
# The tables of docs/hybrid-tracking.md were measured in vo-strict mode (the program's default then); MAP_MODE=slam
# for the default.
extra=(--mode "${MAP_MODE:-vo-strict}" "$@")
data="${DATA:-$repo/../shared/data}"
out="${OUT:-/tmp/hslam-hybrid-bench}"
sequences="${SEQUENCES:-7scenes_redkitchen_000-299 tsukuba_cg_000-149 kitti06_000-050}"
modes="${MODES:-direct indirect hybrid}"
strides="${STRIDES:-1 2 3 4 5 6 7 8}"
sections="${SECTIONS:-ablation spread stride blackout}"
perturb_key="${PERTURB_KEY:-features.desiredImmatureDensity}"
perturb_values="${PERTURB_VALUES:-490 495 500 505 510}"
blackout_sequence="${BLACKOUT_SEQUENCE:-7scenes_redkitchen_000-299}"
blackout="${BLACKOUT:-120:160}"
focal_sequence="${FOCAL_SEQUENCE:-7scenes_redkitchen_000-299}"
focals="${FOCALS:-525 532.57:531.54 550 575 585}"
focal_values="${FOCAL_VALUES:-475 480 485 490 495 500 505 510 515 520 525}"
source "$repo/tutorials/benchmark-common.sh"

# budget_median PREFIX SEQUENCE VALUES OPTIONS...: one run per value of $perturb_key in VALUES (files PREFIX.pVALUE.*);
# sets budget_ates (the runs' ATEs) and budget_med (their median). Not in a subshell: run() counts the failures.
budget_median() {
  local prefix="$1" seq="$2" values="$3"
  shift 3
  local value
  budget_ates=()
  for value in $values; do
    if run "$prefix.p$value" "$seq" "$@" --set "$perturb_key=$value"; then
      budget_ates+=("$(ate "$prefix.p$value")")
    else
      budget_ates+=(nan)
    fi
  done
  budget_med="$(median "${budget_ates[@]}")"
}

available=()
for seq in $sequences; do
  if [[ -d "$data/$seq" ]]; then available+=("$seq"); else echo "$seq: not found under $data, skipped"; fi
done

if has_section ablation; then
  echo "== ablation: one deterministic run per tracking mode"
  printf "%-28s %-8s %9s %4s %9s %7s %7s %7s %7s %6s\n" sequence mode tracked seg ate trk_ms trk_p95 orb_mat orb_inl K
  for seq in "${available[@]}"; do
    for mode in $modes; do
      prefix="$out/$seq.$mode.k1"
      run "$prefix" "$seq" --tracking-mode "$mode" || continue
      printf "%-28s %-8s %9s %4s %9.4f %7.2f %7.2f %7.0f %7.0f %6.3f\n" "$seq" "$mode" "$(tracked "$prefix")" \
        "$(json "$prefix.json" segments)" "$(ate "$prefix")" "$(json "$prefix.json" tracking_ms_median)" \
        "$(json "$prefix.json" tracking_ms_p95)" "$(json "$prefix.json" orb_matches_median)" \
        "$(json "$prefix.json" orb_inliers_median)" "$(json "$prefix.json" geometric_weight_median)"
    done
  done
  echo
fi

if has_section spread; then
  echo "== spread: $perturb_key = $perturb_values; ATE of each run, then the median; against the first mode: ratio"
  echo "   of the medians, its 90 % bootstrap interval (1 inside: not told apart) and the runs where it was better"
  for seq in "${available[@]}"; do
    first_ates=""
    for mode in $modes; do
      budget_median "$out/$seq.$mode" "$seq" "$perturb_values" --tracking-mode "$mode"
      printf "%-28s %-8s median %8s   runs %s\n" "$seq" "$mode" "$budget_med" "${budget_ates[*]}"
      if [[ -z "$first_ates" ]]; then
        first_ates="${budget_ates[*]}"
        first_mode="$mode"
      else
        read -r ratio lo hi wins pairs <<< "$(compare_medians "$first_ates" "${budget_ates[*]}")"
        printf "%-28s %-8s / %-8s %s, 90 %% interval [%s, %s], better in %s of %s runs\n" "" "$mode" "$first_mode" \
          "$ratio" "$lo" "$hi" "$wins" "$pairs"
      fi
    done
  done
  echo
fi

if has_section stride; then
  echo "== large motion: every K-th frame tracked (--stride K); tracked/frames and ATE per mode"
  printf "%-28s %2s" sequence K
  for mode in $modes; do printf "  %-18s" "$mode"; done
  echo
  for seq in "${available[@]}"; do
    for k in $strides; do
      line="$(printf "%-28s %2s" "$seq" "$k")"
      for mode in $modes; do
        prefix="$out/$seq.$mode.k$k"
        if run "$prefix" "$seq" --tracking-mode "$mode" --stride "$k"; then
          line+="$(printf "  %9s %8.4f" "$(tracked "$prefix")" "$(ate "$prefix")")"
        else
          line+="$(printf "  %18s" failed)"
        fi
      done
      echo "$line"
    done
  done
  echo
fi

if has_section blackout; then
  echo "== covered lens: $blackout_sequence, frames $blackout black, against the uninterrupted run"
  if [[ -d "$data/$blackout_sequence" ]]; then
    printf "%-8s %-13s %4s %9s %11s %9s\n" mode run seg tracked reloc_ok/try ate
    for mode in $modes; do
      for variant in uninterrupted blackout; do
        prefix="$out/$blackout_sequence.$mode.k1"
        options=(--tracking-mode "$mode")
        if [[ $variant == blackout ]]; then
          prefix="$out/$blackout_sequence.$mode.blackout"
          options+=(--blackout "$blackout")
        fi
        run "$prefix" "$blackout_sequence" "${options[@]}" || continue
        printf "%-8s %-13s %4s %9s %11s %9.4f\n" "$mode" "$variant" "$(json "$prefix.json" segments)" \
          "$(tracked "$prefix")" \
          "$(json "$prefix.json" relocalizations_succeeded)/$(json "$prefix.json" relocalizations_attempted)" \
          "$(ate "$prefix")"
      done
    done
  else
    echo "$blackout_sequence: not found under $data, skipped"
  fi
  echo
fi
if has_section focal; then
  echo "== camera model: $focal_sequence with its focal length replaced; median ATE over $perturb_key = $focal_values"
  if [[ -f "$data/$focal_sequence/camera.txt" ]]; then
    printf "%-16s" focal
    for mode in $modes; do printf "  %-9s" "$mode"; done
    echo
    for focal in $focals; do
      fx="${focal%%:*}"
      fy="${focal#*:}"
      camera="$out/$focal_sequence.focal-$fx-$fy.txt"
      # DSO camera.txt: the first line is "Pinhole fx fy cx cy [k1]", the rest (sizes, rectification) is kept.
      awk -v fx="$fx" -v fy="$fy" 'NR == 1 { $2 = fx; $3 = fy } { print }' "$data/$focal_sequence/camera.txt" > "$camera"
      line="$(printf "%-16s" "$focal")"
      for mode in $modes; do
        budget_median "$out/$focal_sequence.$mode.focal-$fx-$fy" "$focal_sequence" "$focal_values" \
          --tracking-mode "$mode" --camera "$camera"
        line+="$(printf "  %9s" "$budget_med")"
      done
      echo "$line"
    done
  else
    echo "$focal_sequence: no camera.txt under $data, skipped"
  fi
  echo
fi
echo "(ATE in ground-truth units: metres, Tsukuba centimetres; K: geometric weight, eq. 4; files in $out)"
if [[ $failures -gt 0 ]]; then
  echo "$failures run(s) failed"
  exit 1
fi
