#!/usr/bin/env bash
# Quick start, command 2: install what is missing, build, and run every test:
#   1. the Release build, with MPI (CABLECAL_MPI), and its whole test suite (ctest),
#      including the mpirun tests (label "mpi");
#   2. the same suite built with AddressSanitizer + UndefinedBehaviorSanitizer (build-sanitize/);
#   3. the libFuzzer targets (clang, build-fuzz/), each for CABLECAL_FUZZ_SECONDS (default 30).
# Set CABLECAL_QUICK=1 to run step 1 only.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
"$root/scripts/setup.sh" --tests
jobs="$(nproc)"

echo "== Release build (with MPI) and tests"
"$root/scripts/build.sh" -DCABLECAL_MPI=ON
(cd "${CABLECAL_BUILD_DIR:-$root/build}" && ctest --output-on-failure --parallel "$jobs" --timeout 900)

if [ "${CABLECAL_QUICK:-0}" = "1" ]; then exit 0; fi

# The sanitizer build is the default one, without MPI: both configurations get tested.
echo "== Sanitizer build (ASan + UBSan, without MPI) and tests"
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:strict_string_checks=1"
export LSAN_OPTIONS="suppressions=$root/tests/sanitizers/lsan.supp:print_suppressions=0"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
# -O1: sanitizer reports stay readable and the (Ceres-template-heavy) build stays short.
CABLECAL_BUILD_DIR="$root/build-sanitize" CMAKE_BUILD_TYPE=RelWithDebInfo \
  "$root/scripts/build.sh" -DCABLECAL_SANITIZE=ON -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g"
# The design-quality sizes N = 15 and 30 run the same code as N = 6 (which stays) and were
# 190 s of the instrumented suite's ~530 s of test time; the 40 random robots (2 x ~25 s in
# Release) run the same design code as the other design tests. The Release stage runs them.
(cd "$root/build-sanitize" && ctest --output-on-failure --parallel "$jobs" --timeout 1800 \
  -E '^(Sizes/ConditionQuality\.AtMostHalfTheRandomMedian/(15|30)|Shards/RandomRobots\..*)$')

echo "== Fuzzers (libFuzzer, ${CABLECAL_FUZZ_SECONDS:-30} s each)"
CC=clang CXX=clang++ CABLECAL_BUILD_DIR="$root/build-fuzz" CMAKE_BUILD_TYPE=RelWithDebInfo \
  "$root/scripts/build.sh" -DCABLECAL_FUZZ=ON -DCABLECAL_FUZZ_SECONDS="${CABLECAL_FUZZ_SECONDS:-30}" \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g"
(cd "$root/build-fuzz" && ctest --output-on-failure --parallel "$jobs" -L fuzz)
