#!/usr/bin/env bash
# Loop closure on real revisits (issue 50): every shared real sequence played there and back (--there-and-back: the
# way back revisits every place at the far end of the drift), and forward only (no revisit: no loop may close).
#
#   bash tutorials/hslam-loop-benchmark.sh [BUILD_DIR] [-- extra options for tutorial-hslam-dataset]
#
# Per sequence and configuration, deterministic runs at each point budget of BUDGETS (features.desiredImmatureDensity),
# each evaluated against the ground truth the program writes for the frames it tracked (--groundtruth-out, re-timed
# stamps): median ATE (Sim(3)) with the runs' spread (min..max), loops detected / corrected (sums over the runs),
# the share of window points re-used from the global map (median), real-time factor on one core (video s / CPU s,
# median) and memory per stored keyframe (MB, median). Configurations:
#   vo-strict          the window only (DSO-like odometry)
#   vo-reuse           the global map re-used in the window, no loop closure
#   slam               the defaults (re-use and loop closure)
#   slam-noreuse       slam with globalMap.reuse=false: only loop closure can reconcile the two passes
#   slam-forward       slam on the sequence as recorded (forward only): loops detected must stay 0
# Then the ratios the issue asks for: slam / vo-strict, slam / vo-reuse, slam-noreuse / vo-strict (medians).
# Environment: DATA (default <repo>/../shared/data), OUT (default /tmp/hslam-loop-bench), SEQUENCES (default the
# three real sequences with motion), BUDGETS (default "490 500 510"), CONFIGS (default all five).
set -uo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${1:-$repo/build}"
shift $(($# >= 1 ? 1 : 0))
if [[ "${1:-}" == "--" ]]; then shift; fi
extra=("$@")
data="${DATA:-$repo/../shared/data}"
out="${OUT:-/tmp/hslam-loop-bench}"
sections=""
# shellcheck source=tutorials/benchmark-common.sh
source "$repo/tutorials/benchmark-common.sh"
sequences="${SEQUENCES:-7scenes_redkitchen_000-299 tsukuba_cg_000-149 kitti06_000-050}"
budgets="${BUDGETS:-490 500 510}"
configs="${CONFIGS:-vo-strict vo-reuse slam slam-noreuse slam-forward}"

options_of() { # configuration -> options
  case "$1" in
    vo-strict) echo "--mode vo-strict --there-and-back" ;;
    vo-reuse) echo "--mode vo-reuse --there-and-back" ;;
    slam) echo "--mode slam --there-and-back" ;;
    slam-noreuse) echo "--mode slam --there-and-back --set globalMap.reuse=false" ;;
    slam-forward) echo "--mode slam" ;;
  esac
}

# one PREFIX SEQUENCE CONFIG BUDGET: a run and its evaluation against its own re-timed ground truth (PREFIX.ate)
one() {
  local prefix="$1" seq="$2" config="$3" budget="$4" status=0
  # shellcheck disable=SC2046
  "$dataset" --input "$data/$seq" --deterministic --no-display --quiet --trajectory "$prefix.txt" \
    --stats "$prefix.json" --groundtruth "$(groundtruth "$seq")" --groundtruth-out "$prefix.gt.txt" \
    --set "features.desiredImmatureDensity=$budget" $(options_of "$config") "${extra[@]}" > "$prefix.log" 2>&1 ||
    status=$?
  if [[ $status -ne 0 || ! -s "$prefix.json" ]]; then
    echo "$seq $config $budget: tutorial-hslam-dataset failed (exit $status), see $prefix.log"
    echo nan > "$prefix.ate"
    return
  fi
  "$evaluate" --groundtruth "$prefix.gt.txt" --estimate "$prefix.txt" 2>/dev/null | sed -n "s/^ate_rmse_m=//p" \
    > "$prefix.ate"
  [[ -s "$prefix.ate" ]] || echo nan > "$prefix.ate"
}

sum() { awk '{ s += ($1 == "nan" ? 0 : $1) } END { print s + 0 }'; }
spread() { sort -g | awk 'NR == 1 { lo = $1 } { hi = $1 } END { printf "%s..%s", lo, hi }'; }
ratio() { awk -v a="$1" -v b="$2" 'BEGIN { if (a == "nan" || b == "nan" || b == 0) print "nan"; else printf "%.3f", a / b }'; }

echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ *//'); budgets: $budgets"
printf "%-28s %-13s %9s %-19s %5s %5s %6s %6s %7s\n" sequence config ate_med ate_spread loops corr reuse rt_cpu mb_kf
declare -A medians=()
for seq in $sequences; do
  [[ -d "$data/$seq" ]] || { echo "$seq: not found under $data, skipped"; continue; }
  for config in $configs; do
    ates=() loops=() corrected=() shares=() rts=() mbs=()
    for budget in $budgets; do
      prefix="$out/$seq.$config.$budget"
      one "$prefix" "$seq" "$config" "$budget"
      ates+=("$(cat "$prefix.ate")")
      loops+=("$(json "$prefix.json" loops_detected)")
      corrected+=("$(json "$prefix.json" loops_corrected)")
      shares+=("$(json "$prefix.json" window_share_from_global)")
      rts+=("$(awk -v v="$(json "$prefix.json" video_s)" -v c="$(json "$prefix.json" cpu_s)" \
        'BEGIN { print (c > 0 ? v / c : "nan") }')")
      mbs+=("$(json "$prefix.json" memory_mb_per_keyframe)")
    done
    med="$(median "${ates[@]}")"
    medians[$seq.$config]="$med"
    printf "%-28s %-13s %9s %-19s %5s %5s %6s %6s %7s\n" "$seq" "$config" "$med" \
      "$(printf '%s\n' "${ates[@]}" | spread)" "$(printf '%s\n' "${loops[@]}" | sum)" \
      "$(printf '%s\n' "${corrected[@]}" | sum)" "$(median "${shares[@]}")" "$(median "${rts[@]}")" \
      "$(median "${mbs[@]}")"
  done
  echo "$seq: slam/vo-strict $(ratio "${medians[$seq.slam]:-nan}" "${medians[$seq.vo-strict]:-nan}")" \
    "(issue: <= 0.8), slam/vo-reuse $(ratio "${medians[$seq.slam]:-nan}" "${medians[$seq.vo-reuse]:-nan}") (<= 1)," \
    "slam-noreuse/vo-strict $(ratio "${medians[$seq.slam-noreuse]:-nan}" "${medians[$seq.vo-strict]:-nan}") (<= 0.8)"
done
echo "(ATE in ground-truth units: metres, Tsukuba centimetres; rt_cpu = video s / CPU s; runs in $out)"
