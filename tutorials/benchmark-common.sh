# Shared by the benchmark scripts (sourced, not run): programs, ground truth, the JSON statistics, one evaluated
# run per prefix, and the median of a list. The sourcing script sets build, data, out, sections and extra (options
# added to every run) first.
# shellcheck shell=bash
dataset="$build/tutorials/tutorial-hslam-dataset"
evaluate="$build/tutorials/tutorial-hslam-evaluate"
for program in "$dataset" "$evaluate"; do
  [[ -x "$program" ]] || { echo "error: $program not built (cmake --build $build --target $(basename "$program"))" >&2; exit 1; }
done
mkdir -p "$out" || exit 1

groundtruth() { # ground truth of a shared sequence (folder name) or of a generated one (absolute path)
  case "$1" in
    /*) echo "$1/groundtruth.txt" ;;
    kitti*) echo "$data/$1/groundtruth_tum.txt" ;;
    euroc*) echo "$data/$1/groundtruth_cam0_tum.txt" ;;
    *) echo "$data/$1/groundtruth.txt" ;;
  esac
}

json() { # json FILE KEY -> the value (strings without their quotes), "nan" when absent
  local value
  value="$(sed -n "s/^ *\"$2\": *\([^,]*\),\{0,1\}$/\1/p" "$1" 2>/dev/null | head -n 1 | tr -d '"')"
  [[ -z "$value" || "$value" == null ]] && value=nan
  echo "$value"
}

has_section() { [[ " $sections " == *" $1 "* ]]; }

# run PREFIX SEQUENCE OPTIONS...: SEQUENCE a folder of $data or an absolute path; one run and its evaluation; files PREFIX.{txt,json,log,ate}. A run already made by
# this invocation (same prefix) is reused. Returns non-zero, after printing a line, when the run failed.
declare -A made=()
failures=0
run() {
  local prefix="$1" seq="$2"
  shift 2
  if [[ -n "${made[$prefix]:-}" ]]; then
    return "${made[$prefix]}"
  fi
  rm -f "$prefix.txt" "$prefix.json" "$prefix.ate"
  local status=0
  local input="$data/$seq"
  [[ "$seq" == /* ]] && input="$seq"
  "$dataset" --input "$input" --deterministic --no-display --quiet --trajectory "$prefix.txt" \
    --stats "$prefix.json" "$@" "${extra[@]}" > "$prefix.log" 2>&1 || status=$?
  if [[ $status -ne 0 || ! -s "$prefix.json" ]]; then
    echo "$seq $*: tutorial-hslam-dataset failed (exit $status), see $prefix.log"
    made[$prefix]=1
    failures=$((failures + 1))
    return 1
  fi
  local ate
  ate="$("$evaluate" --groundtruth "$(groundtruth "$seq")" --estimate "$prefix.txt" 2>/dev/null | sed -n "s/^ate_rmse_m=//p")"
  echo "${ate:-nan}" > "$prefix.ate"
  made[$prefix]=0
  return 0
}

tracked() { echo "$(json "$1.json" tracked_frames)/$(json "$1.json" frames)"; }
ate() { cat "$1.ate" 2>/dev/null || echo nan; }

median() { # median of the numbers given (nan ignored), "nan" when none
  printf "%s\n" "$@" | grep -v nan | sort -g |
    awk '{ a[NR] = $1 } END { if (NR == 0) { print "nan" } else if (NR % 2) { print a[(NR + 1) / 2] } else { print (a[NR / 2] + a[NR / 2 + 1]) / 2 } }'
}

# compare_medians "A..." "B..." -> "ratio lo hi wins n": median(B) / median(A) of two lists of ATEs (nan ignored), the
# 5th and 95th percentiles of that ratio over 2000 bootstrap resamples of both lists (fixed seed: the same output for
# the same input), and in how many of the n paired runs (same position in both lists) B was below A. An interval
# that contains 1 says the two are not told apart by these runs.
compare_medians() {
  awk -v a="$1" -v b="$2" '
    function med(x, n,   i, j, t, y) {
      for (i = 1; i <= n; ++i) y[i] = x[i]
      for (i = 2; i <= n; ++i) { t = y[i]; for (j = i - 1; j >= 1 && y[j] > t; --j) y[j + 1] = y[j]; y[j + 1] = t }
      return n % 2 ? y[(n + 1) / 2] : (y[n / 2] + y[n / 2 + 1]) / 2
    }
    BEGIN {
      na = split(a, ra, " "); nb = split(b, rb, " "); n = 0; m = 0; wins = 0; pairs = 0
      for (i = 1; i <= na; ++i) if (ra[i] != "nan") xa[++n] = ra[i]
      for (i = 1; i <= nb; ++i) if (rb[i] != "nan") xb[++m] = rb[i]
      for (i = 1; i <= na && i <= nb; ++i) if (ra[i] != "nan" && rb[i] != "nan") { ++pairs; if (rb[i] + 0 < ra[i] + 0) ++wins }
      if (n == 0 || m == 0 || med(xa, n) <= 0) { print "nan nan nan 0 0"; exit }
      srand(1); resamples = 2000
      for (r = 1; r <= resamples; ++r) {
        for (i = 1; i <= n; ++i) sa[i] = xa[1 + int(rand() * n)]
        for (i = 1; i <= m; ++i) sb[i] = xb[1 + int(rand() * m)]
        ratio[r] = med(sb, m) / med(sa, n)
      }
      # percentiles: sort the ratios (shell sort, 2000 values)
      for (gap = int(resamples / 2); gap > 0; gap = int(gap / 2))
        for (i = gap + 1; i <= resamples; ++i) { t = ratio[i]; for (j = i; j > gap && ratio[j - gap] > t; j -= gap) ratio[j] = ratio[j - gap]; ratio[j] = t }
      printf "%.3f %.3f %.3f %d %d\n", med(xb, m) / med(xa, n), ratio[int(0.05 * resamples) + 1], ratio[int(0.95 * resamples)], wins, pairs
    }'
}
