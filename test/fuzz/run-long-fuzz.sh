#!/usr/bin/env bash
# Long libFuzzer pass (issue 11): every fuzz target of test/fuzz, or the ones named, RUNS inputs each (10^6 by
# default), one target at a time in one process (one core), from a fixed random seed (-seed), starting from a
# scratch copy of its seeds (the real files copied by the fuzz build's configure step, test/fuzz/seeds/ and
# test/fuzz/regressions/; neither the repository nor the build tree's corpora are modified). Prints for each target:
# executions, wall seconds, exec/s, corpus size before and after, outcome; then a summary table.
#
#   bash test/fuzz/run-long-fuzz.sh [options] [TARGET...]      TARGET: camera_dso, parameters, ... (default: all)
#     --build DIR        the fuzz build (default build-fuzz in the repository, as `bash cmake/run.sh test` makes it).
#                        Configured (clang, -DHSLAM_FUZZ=ON, as cmake/sanitizers.sh) when missing, then its fuzz
#                        targets are brought up to date (JOBS parallel jobs, default nproc), unless --no-build
#     --no-build         run the programs as they are (the ctest tests fuzz_long.<target> call it so)
#     --runs N           inputs per target (default 1000000)
#     --seed S           libFuzzer's random seed (default 1)
#     --max-total-time S stop a target after S seconds even below RUNS inputs (default 0: no limit)
#     --timeout S        one input running longer is a hang (default 10)
#     --rss-limit-mb MB  memory above this is a finding (default 2048)
#     --max-len BYTES    largest input (default 16384, as the short pass; the seeds are cut to 16 KB)
#     --keep             keep the scratch corpora (their folder is printed)
# Logs: BUILD/test/fuzz/long/<target>.log; an input that crashed, leaked, hung or ran out of memory is saved in
# BUILD/test/fuzz/artifacts/<target>/ (name printed). Exit status: 0 all clean, 1 a finding or failure, 77 skipped
# (no clang++ or no libFuzzer runtime: Debian packages clang and libclang-rt-dev).
set -euo pipefail

repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
build=$repo/build-fuzz
do_build=1
runs=1000000
seed=1
max_total_time=0
timeout=10
rss_limit_mb=2048
max_len=16384
keep=0
targets=()
while [ $# -gt 0 ]; do
  case "$1" in
    --build) build=$2; shift 2 ;;
    --no-build) do_build=0; shift ;;
    --runs) runs=$2; shift 2 ;;
    --seed) seed=$2; shift 2 ;;
    --max-total-time) max_total_time=$2; shift 2 ;;
    --timeout) timeout=$2; shift 2 ;;
    --rss-limit-mb) rss_limit_mb=$2; shift 2 ;;
    --max-len) max_len=$2; shift 2 ;;
    --keep) keep=1; shift ;;
    -h | --help)
      sed -n '2,/^set -euo/p' "${BASH_SOURCE[0]}" | sed '$d; s/^# \{0,1\}//'
      exit 0
      ;;
    -*)
      echo "run-long-fuzz.sh: unknown option $1 (see --help)" >&2
      exit 2
      ;;
    *) targets+=("${1#fuzz_}"); shift ;;
  esac
done
build=$(mkdir -p "$build" && cd "$build" && pwd)

# --- clang and libFuzzer ----------------------------------------------------------------------------------------------
if [ "$do_build" = 1 ]; then
  if ! command -v clang++ >/dev/null 2>&1; then
    echo "SKIP: the long fuzz pass needs clang++ with libFuzzer (Debian: apt-get install clang libclang-rt-dev)"
    exit 77
  fi
  probe=$(mktemp -d)
  echo 'extern "C" int LLVMFuzzerTestOneInput(const unsigned char *, unsigned long) { return 0; }' >"$probe/p.cpp"
  if ! clang++ -fsanitize=fuzzer,address,undefined "$probe/p.cpp" -o "$probe/p" >"$probe/log" 2>&1; then
    echo "SKIP: clang++ cannot link a libFuzzer program (Debian: apt-get install libclang-rt-dev):"
    sed 's/^/  /' "$probe/log"
    rm -rf "$probe"
    exit 77
  fi
  rm -rf "$probe"
  if [ ! -f "$build/CMakeCache.txt" ]; then
    echo "== configuring the fuzz build in $build (clang, -DHSLAM_FUZZ=ON)"
    cmake -S "$repo" -B "$build" -DCMAKE_BUILD_TYPE=Release -DHSLAM_BUILD_BENCHMARKS=OFF \
      -DCMAKE_CXX_COMPILER=clang++ -DHSLAM_FUZZ=ON -DHSLAM_BUILD_TUTORIALS=OFF >"$build.configure.log" 2>&1 || {
      cat "$build.configure.log"
      exit 1
    }
  fi
  if ! grep -q '^HSLAM_FUZZ:BOOL=ON$' "$build/CMakeCache.txt"; then
    echo "run-long-fuzz.sh: $build is not a fuzz build (HSLAM_FUZZ=ON); give another --build" >&2
    exit 2
  fi
  echo "== building the fuzz targets in $build"
  cmake --build "$build" -j "${JOBS:-$(nproc)}" --target hslam_fuzz_targets
fi
dir=$build/test/fuzz
if [ ! -d "$dir/seeds-initial" ]; then
  echo "SKIP: no libFuzzer build in $build (configure it with clang++ and -DHSLAM_FUZZ=ON, or drop --no-build)"
  exit 77
fi
if [ ${#targets[@]} -eq 0 ]; then
  for d in "$dir"/seeds-initial/*/; do
    targets+=("$(basename "$d")")
  done
fi
for t in "${targets[@]}"; do
  if [ ! -x "$dir/fuzz_$t" ]; then
    echo "run-long-fuzz.sh: no fuzz target fuzz_$t in $dir" >&2
    exit 2
  fi
done

# Same sanitizer settings as the short pass (cmake/sanitizers.sh): third-party suppressions, stop at the first report.
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$repo/cmake/sanitizers/lsan.supp}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-halt_on_error=1:print_stacktrace=1:suppressions=$repo/cmake/sanitizers/ubsan.supp}

scratch=$(mktemp -d "${TMPDIR:-/tmp}/hslam-long-fuzz.XXXXXX")
if [ "$keep" = 1 ]; then
  echo "== scratch corpora kept in $scratch"
else
  trap 'rm -rf "$scratch"' EXIT
fi
mkdir -p "$dir/long"

count() { find "$1" -type f | wc -l; }
stat_of() { # log, libFuzzer final statistic name
  sed -n "s/^stat::$2: *\([0-9.]*\).*/\1/p" "$1" | tail -n 1
}

echo "== libFuzzer long pass: ${targets[*]}"
echo "   $runs inputs each, -seed=$seed -max_len=$max_len -timeout=$timeout -rss_limit_mb=$rss_limit_mb" \
  "-max_total_time=$max_total_time; one process at a time"
echo "   machine: $(nproc) cores,$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2-); $(clang++ --version | head -n 1)"
summary=()
failed=0
for t in "${targets[@]}"; do
  corpus=$scratch/$t
  mkdir -p "$corpus" "$dir/artifacts/$t"
  cp -R "$dir/seeds-initial/$t"/. "$corpus"/
  if [ -d "$repo/test/fuzz/regressions/$t" ]; then
    cp -R "$repo/test/fuzz/regressions/$t"/. "$corpus"/
  fi
  before=$(count "$corpus")
  log=$dir/long/$t.log
  echo "-- fuzz_$t: $before seed inputs, log $log"
  start=$(date +%s.%N)
  rc=0
  (cd "$scratch" && "$dir/fuzz_$t" -runs="$runs" -seed="$seed" -max_len="$max_len" -timeout="$timeout" \
    -rss_limit_mb="$rss_limit_mb" -max_total_time="$max_total_time" -print_final_stats=1 \
    -artifact_prefix="$dir/artifacts/$t/" "$corpus") >"$log" 2>&1 || rc=$?
  end=$(date +%s.%N)
  seconds=$(awk -v a="$start" -v b="$end" 'BEGIN { printf "%.1f", b - a }')
  execs=$(stat_of "$log" number_of_executed_units)
  if [ -z "$execs" ]; then # no final statistics: the last status line
    execs=$(sed -n 's/^#\([0-9][0-9]*\).*/\1/p' "$log" | tail -n 1)
  fi
  execs=${execs:-0}
  rate=$(awk -v n="$execs" -v a="$start" -v b="$end" 'BEGIN { printf "%.0f", (b > a) ? n / (b - a) : 0 }')
  after=$(count "$corpus")
  new=$(stat_of "$log" new_units_added)
  peak=$(stat_of "$log" peak_rss_mb)
  artifact=$(sed -n 's/.*Test unit written to \(.*\)$/\1/p' "$log" | tail -n 1)
  if grep -q 'ERROR: LeakSanitizer' "$log"; then
    outcome="LEAK"
  elif grep -q 'ERROR: libFuzzer: timeout' "$log"; then
    outcome="HANG (an input ran over $timeout s)"
  elif grep -q 'ERROR: libFuzzer: out-of-memory' "$log"; then
    outcome="OUT OF MEMORY (over $rss_limit_mb MB)"
  elif grep -q 'ERROR: AddressSanitizer' "$log"; then
    outcome="ASAN: $(sed -n 's/.*ERROR: AddressSanitizer: \([^ ]*\).*/\1/p' "$log" | head -n 1)"
  elif grep -q 'runtime error:' "$log"; then
    outcome="UBSAN: $(grep -m1 'runtime error:' "$log" | sed 's/.*runtime error: //')"
  elif grep -q 'ERROR: libFuzzer: deadly signal' "$log"; then
    outcome="CRASH ($(grep -m1 -E "terminate called|what\(\)|uncaught" "$log" || echo 'deadly signal'))"
  elif [ "$rc" != 0 ]; then
    outcome="FAILED (exit status $rc)"
  elif [ "$execs" -lt "$runs" ]; then
    outcome="clean, stopped at -max_total_time=$max_total_time s before $runs inputs"
  else
    outcome="clean"
  fi
  case "$outcome" in
    clean*) ;;
    *)
      failed=1
      if [ -n "$artifact" ]; then
        outcome="$outcome, input $artifact"
      fi
      # The report: from libFuzzer's or the sanitizer's first error line on (the full output is in the log).
      sed -n '/^ALARM\|ERROR: \|runtime error:\|^==[0-9]*==/,$p' "$log" | head -n 40
      ;;
  esac
  echo "   fuzz_$t: executions $execs, $seconds s, $rate exec/s, corpus $before -> $after files" \
    "(${new:-?} new units), peak RSS ${peak:-?} MB: $outcome"
  summary+=("| $t | $execs | $seconds | $rate | $before -> $after | $outcome |")
done

echo "== summary (seed $seed)"
echo "| target | executions | seconds | exec/s | corpus (files) | outcome |"
echo "|---|---|---|---|---|---|"
printf '%s\n' "${summary[@]}"
exit "$failed"
