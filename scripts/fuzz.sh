#!/usr/bin/env bash
# Fuzzes texfab's readers with libFuzzer under AddressSanitizer and UBSan (tests/fuzz/).
#
#   scripts/fuzz.sh [--runs N] [--time SECONDS] [--jobs J] [--sanitizers LIST] [TARGET...]
#
# Builds build-fuzz/ with clang (TEXFAB_FUZZ=ON; with --sanitizers other than the default
# address,undefined, build-fuzz-<list>/: `undefined` alone runs the image, 3MF and cache readers
# 10-50x faster, since ASan pays for every large buffer those libraries allocate), writes each target's seeds from the test models,
# and runs each target (all when none is named) for N inputs (default 1000000) or SECONDS each,
# whichever ends first, J targets at a time (default: the number of cores). The corpus grows in
# build-fuzz/fuzz/corpus/, shared by every build and kept between runs: `--runs 0` replays it once
# (for example under ASan after a long UBSan round). Findings (crash-*, timeout-*, oom-*, leak-*) are copied into
# tests/fuzz/regressions/<target>/, where the test suite replays them; the script then exits 1.
# A table of executions, coverage and findings per target ends the run (build-fuzz/fuzz/summary.md).
set -euo pipefail
cd "$(dirname "$0")/.."
repo="$(pwd)"

runs=1000000 seconds="" jobs="$(nproc)" sanitizers="address,undefined" targets=()
while [ $# -gt 0 ]; do
  case "$1" in
    --runs) runs="$2"; shift 2 ;;
    --time) seconds="$2"; shift 2 ;;
    --jobs) jobs="$2"; shift 2 ;;
    --sanitizers) sanitizers="$2"; shift 2 ;;
    -h|--help) sed -n '2,17p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    -*) echo "fuzz.sh: unknown option $1" >&2; exit 1 ;;
    *) targets+=("$1"); shift ;;
  esac
done

build=build-fuzz
[ "$sanitizers" = "address,undefined" ] || build="build-fuzz-${sanitizers//,/-}"
scripts/install-deps.sh --fuzz >/dev/null
CC=clang CXX=clang++ cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DTEXFAB_FUZZ=ON \
  -DTEXFAB_FUZZ_SANITIZERS="$sanitizers" -DTEXFAB_BUILD_TESTS=OFF -DTEXFAB_BUILD_BENCH=OFF -DTEXFAB_PYTHON=OFF \
  -DTEXFAB_VULKAN=OFF >/dev/null
cmake --build "$build" --parallel "$(nproc)" --target texfab_fuzz texfab_fuzz_seeds

fuzzer="$repo/$build/tests/fuzz/texfab_fuzz"
work="$repo/build-fuzz/fuzz"
if [ ${#targets[@]} -eq 0 ]; then
  mapfile -t targets < <(TEXFAB_FUZZ_TARGET= "$fuzzer" 2>&1 | awk 'NR > 1 { print $1 }')
fi
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:symbolize=1"
export LSAN_OPTIONS="suppressions=$repo/tests/fuzz/lsan.supp:print_suppressions=0"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
rm -rf "$work/seeds" "$work/logs"
mkdir -p "$work/seeds" "$work/logs"
"$repo/$build/tests/fuzz/texfab_fuzz_seeds" "$work/seeds" "${targets[@]}"
limit=(-runs="$runs")
[ -n "$seconds" ] && limit+=(-max_total_time="$seconds")

fuzz_one() {
  local target="$1"
  rm -rf "$work/findings/$target"  # an earlier run's findings are in tests/fuzz/regressions already
  mkdir -p "$work/corpus/$target" "$work/findings/$target"
  TEXFAB_FUZZ_TARGET="$target" "$fuzzer" "$work/corpus/$target" "$work/seeds/$target" "${limit[@]}" \
    -timeout=10 -rss_limit_mb=4096 -malloc_limit_mb=4096 -print_final_stats=1 \
    -artifact_prefix="$work/findings/$target/" >"$work/logs/$target.log" 2>&1 || true
}
running=0
for target in "${targets[@]}"; do
  ( fuzz_one "$target"; echo "fuzz.sh: $target done" ) &
  running=$((running + 1))
  if [ "$running" -ge "$jobs" ]; then wait -n; running=$((running - 1)); fi
done
wait

found=0
{
  echo "| target | inputs run | coverage (edges) | features | corpus | findings |"
  echo "|---|---|---|---|---|---|"
  for target in "${targets[@]}"; do
    log="$work/logs/$target.log"
    last="$(grep -E '^#[0-9]+' "$log" | tail -1 || true)"
    execs="$(grep -o 'stat::number_of_executed_units: [0-9]*' "$log" | tail -1 | awk '{print $2}' || true)"
    [ -n "$execs" ] || execs="$(grep -oE '^#[0-9]+' <<<"$last" | tr -d '#' || true)"  # a run ended by a finding
    cov="$(grep -o 'cov: [0-9]*' <<<"$last" | awk '{print $2}' || true)"
    ft="$(grep -o 'ft: [0-9]*' <<<"$last" | awk '{print $2}' || true)"
    corp="$(grep -o 'corp: [0-9]*/[0-9A-Za-z]*' <<<"$last" | awk '{print $2}' || true)"
    findings=()
    for f in "$work/findings/$target"/*; do
      [ -f "$f" ] || continue
      case "$(basename "$f")" in slow-unit-*) continue ;; esac  # the slowest input, not a finding
      findings+=("$(basename "$f")")
      mkdir -p "tests/fuzz/regressions/$target"
      cp "$f" "tests/fuzz/regressions/$target/"
    done
    [ ${#findings[@]} -gt 0 ] && found=1
    echo "| $target | ${execs:-?} | ${cov:-?} | ${ft:-?} | ${corp:-?} | ${#findings[@]} ${findings[*]} |"
  done
} | tee "$work/summary.md"
if [ "$found" -ne 0 ]; then
  echo "fuzz.sh: findings copied into tests/fuzz/regressions/ (logs: $work/logs/)" >&2
  exit 1
fi
