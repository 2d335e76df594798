#!/usr/bin/env bash
# Metric poses from an AprilTag (issue 53, docs/metric-tag-frame.md): the synthetic tag room of test_system_tag
# (test/system/TagRoom.h) over point budgets, and the detector on ViSP's real tag picture.
#
#   bash tutorials/hslam-tag-benchmark.sh [BUILD_DIR]
#
# Per point budget (features.desiredImmatureDensity), one deterministic run of build/test/hslam_tag_room, which feeds
# three systems at once: the 20 cm tag seen on both laps, seen on the first lap only, and no tag. For each variant the
# script prints the median and range over the budgets of: the scale error and the frame's offset and rotation (the
# Sim(3) that best aligns the final trajectory onto the truth in the tag's frame; 0 / 0 / 0 is perfect), the ATE with
# no alignment (metres; "no tag" is not metric, so there it is in map units and only the Sim(3)-aligned ATE means
# anything) and the Sim(3)-aligned ATE (the map's shape), how many runs ended metric, and the range of the corrections
# the tag asked for when seen again (slam mode: the sightings bend the map, docs/metric-tag-frame.md). Verdict per tag variant: "ok" when every run is metric and the medians
# are within the issue's bounds (1 %, 1 cm, 0.5 degree), else "NO". Then test_tag_detector's detector checks.
# Environment: OUT (default /tmp/hslam-tag-bench), BUDGETS (default 480 490 500 510 520), MODE (default slam).
set -uo pipefail # not -e: one failed run must not end the benchmark

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${1:-$repo/build}"
out="${OUT:-/tmp/hslam-tag-bench}"
budgets="${BUDGETS:-480 490 500 510 520}"
mode="${MODE:-slam}"
room="$build/test/hslam_tag_room"
detector_test="$build/test/test_tag_detector"
for program in "$room" "$detector_test"; do
  [[ -x "$program" ]] || { echo "error: $program not built (cmake --build $build --target $(basename "$program"))" >&2; exit 1; }
done
# shellcheck disable=SC2034 # read by benchmark-common.sh
data="" sections="" extra=()
# shellcheck source=tutorials/benchmark-common.sh
source "$repo/tutorials/benchmark-common.sh" # median, and the output folder
status=0

range() { printf '%s\n' "$@" | sort -g | awk 'NR == 1 { lo = $1 } { hi = $1 } END { printf "%s..%s", lo, hi }'; }
field() { # field LINE KEY
  tr ' ' '\n' <<<"$1" | awk -F= -v k="$2" '$1 == k { print $2 }'
}

echo "machine: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//'), $(nproc) cores; mode $mode; budgets $budgets"
declare -A lines=()
for budget in $budgets; do
  log="$out/room-$budget.log"
  if ! "$room" --budget "$budget" --mode "$mode" >"$log" 2>&1; then
    echo "run failed: budget $budget (see $log)"
    status=1
    continue
  fi
  for variant in both first-lap none; do
    lines[$variant]+="$(grep "^variant=$variant " "$log")"$'\n'
  done
done

printf '%-10s %-6s %-22s %-22s %-22s %-22s %-22s %-9s %-11s %s\n' variant metric "scale error %" "frame offset cm" \
  "frame deg" "ATE no alignment m" "ATE Sim(3)-aligned m" "tag ms" corrections verdict
for variant in both first-lap none; do
  scale=() offset=() deg=() ate=() sim3=() ms=() corrections=()
  metric=0 runs=0
  while IFS= read -r line; do
    [[ -z "$line" ]] && continue
    runs=$((runs + 1))
    [[ "$(field "$line" metric)" == 1 ]] && metric=$((metric + 1))
    scale+=("$(awk -v x="$(field "$line" scale_error)" 'BEGIN { print 100 * x }')")
    offset+=("$(awk -v x="$(field "$line" frame_offset_m)" 'BEGIN { print 100 * x }')")
    deg+=("$(field "$line" frame_deg)")
    ate+=("$(field "$line" ate_unaligned_m)")
    sim3+=("$(field "$line" ate_sim3_m)")
    ms+=("$(field "$line" tag_ms)")
    corrections+=("$(field "$line" tag_corrections)")
  done <<<"${lines[$variant]:-}"
  [[ $runs -eq 0 ]] && continue
  s="$(median "${scale[@]}")" o="$(median "${offset[@]}")" d="$(median "${deg[@]}")"
  verdict=""
  if [[ $variant != none ]]; then
    verdict="$(awk -v s="$s" -v o="$o" -v d="$d" -v m="$metric" -v r="$runs" \
      'BEGIN { print (m == r && s <= 1 && o <= 1 && d <= 0.5) ? "ok" : "NO" }')"
  fi
  printf '%-10s %-6s %-22s %-22s %-22s %-22s %-22s %-9s %-11s %s\n' "$variant" "$metric/$runs" \
    "$s [$(range "${scale[@]}")]" "$o [$(range "${offset[@]}")]" "$d [$(range "${deg[@]}")]" \
    "$(median "${ate[@]}") [$(range "${ate[@]}")]" "$(median "${sim3[@]}") [$(range "${sim3[@]}")]" \
    "$(median "${ms[@]}")" "$(range "${corrections[@]}")" "$verdict"
done

echo
echo "detector (test_tag_detector: ViSP's AprilTag picture against its reference poses; the rendered tag):"
if ! "$detector_test" --gtest_brief=1 2>&1 | grep -E "sightings|PASSED|FAILED" ; then
  status=1
fi
exit $status
