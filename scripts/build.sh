#!/usr/bin/env bash
# Configures and builds cablecal (Release by default) into build/ (or $CABLECAL_BUILD_DIR).
# Every target by default; CABLECAL_BUILD_TARGETS="cablecal ..." builds those alone (and what
# they need): scripts/run.sh builds the CLI only, scripts/test.sh what its tests run.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${CABLECAL_BUILD_DIR:-$root/build}"
type="${CMAKE_BUILD_TYPE:-Release}"
# Ninja for a new build folder when it is installed: it compiles a target's objects while the
# libraries they link are still building (make waits for them), which keeps both cores busy to
# the end. A folder configured before keeps its generator (CMake refuses to switch).
generator=()
if [ -z "${CMAKE_GENERATOR:-}" ] && [ ! -f "$build/CMakeCache.txt" ] && command -v ninja >/dev/null; then
  generator=(-G Ninja)
fi
cmake -S "$root" -B "$build" "${generator[@]}" -DCMAKE_BUILD_TYPE="$type" "$@" >/dev/null
targets=()
for t in ${CABLECAL_BUILD_TARGETS:-}; do targets+=(--target "$t"); done
cmake --build "$build" --parallel "$(nproc)" "${targets[@]}"
