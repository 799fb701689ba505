#!/usr/bin/env bash
# The readers' part of the test suite under AddressSanitizer and UBSan, then a short fuzz round.
#
#   scripts/sanitize.sh [--fuzz-seconds S]   (S per fuzz target, default 30; 0 skips the round)
#
# Builds build-asan/ (GCC; TEXFAB_SANITIZE=ON: ASan + UBSan, UBSan halting at its first report) and
# runs every test of core_tests (images in and out), geometry_tests (meshes in and out, corrupt and
# mutated models, repairs) and fuzz_regression_tests (every fuzz target on its seeds and on the
# inputs that once failed); then scripts/fuzz.sh --time S (clang and libFuzzer, build-fuzz/).
# About 25 minutes of building and 2 of tests on 2 cores, plus 17 x S / cores for the fuzz round.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=30
while [ $# -gt 0 ]; do
  case "$1" in
    --fuzz-seconds) seconds="$2"; shift 2 ;;
    -h|--help) sed -n '2,10p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "sanitize.sh: unknown option $1" >&2; exit 1 ;;
  esac
done

scripts/install-deps.sh --fuzz >/dev/null
cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DTEXFAB_SANITIZE=ON -DTEXFAB_BUILD_BENCH=OFF \
  -DTEXFAB_PYTHON=OFF -DTEXFAB_VULKAN=OFF >/dev/null
cmake --build build-asan --parallel "$(nproc)" --target core_tests geometry_tests fuzz_regression_tests
# use_tls=0: GCC 12's LeakSanitizer misreads glibc 2.36's dynamic TLS blocks of dlopen'ed libraries
# (OpenImageIO's) and crashes at exit ("Tracer caught signal 11", "DTLS ... at 0x1d24"); without TLS
# scanning, what libraries keep only in thread-local storage counts as leaked (lsan.supp). The
# options are the GCC build's only: scripts/fuzz.sh (clang) sets its own.
for suite in core_tests geometry_tests fuzz_regression_tests; do
  echo "sanitize.sh: $suite"
  ASAN_OPTIONS="detect_leaks=1:abort_on_error=1" \
    LSAN_OPTIONS="suppressions=$(pwd)/tests/fuzz/lsan.supp:print_suppressions=0:use_tls=0" \
    UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1" "build-asan/tests/$suite" --gtest_brief=1
done
if [ "$seconds" -gt 0 ]; then scripts/fuzz.sh --runs 1000000000 --time "$seconds"; fi
