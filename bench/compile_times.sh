#!/usr/bin/env bash
# What each translation unit of CI's two builds costs to compile: runs scripts/test.sh's
# builds (not its tests) from scratch in OUT_DIR with bench/time_tu.sh as compiler and linker
# launcher, then prints, per stage, the build's wall time, the CPU time of its compiles and
# links, and the costliest translation units. No ccache (CCACHE_DISABLE), so every unit compiles.
#   bench/compile_times.sh OUT_DIR [STAGE...]     STAGE: release or sanitize (default: both)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
out="$(mkdir -p "$1" && cd "$1" && pwd)"
shift
stages=("$@")
[ ${#stages[@]} -gt 0 ] || stages=(release sanitize)
top="${CABLECAL_TOP:-15}"
export CCACHE_DISABLE=1
export CMAKE_CXX_COMPILER_LAUNCHER="$root/bench/time_tu.sh" CMAKE_CXX_LINKER_LAUNCHER="$root/bench/time_tu.sh"
for stage in "${stages[@]}"; do
  rm -rf "${out:?}/$stage" "$out/$stage.log"
  export CABLECAL_TU_LOG="$out/$stage.log"
  start=$(date +%s.%N)
  CABLECAL_CI_BUILD_ONLY="$stage" CABLECAL_CI_BUILD_DIR="$out/$stage" "$root/scripts/test.sh" >"$out/$stage.out" 2>&1
  wall=$(echo "$(date +%s.%N) - $start" | bc)
  awk -v stage="$stage" -v wall="$wall" '{ cpu[$4] += $1; n[$4]++ }
    END { printf "%s: build %.0f s wall; %d compiles %.0f s CPU, %d links %.0f s CPU\n", stage, wall, n["compile"], cpu["compile"], n["link"], cpu["link"] }' "$out/$stage.log"
  awk '$4 == "compile" { f = $6; sub("^(.*/)?CMakeFiles/", "", f); sub("[.]dir/", ": ", f); sub("__/generated/", "", f); sub("[.]o$", "", f); print $1, f }' \
    "$out/$stage.log" | sort -rn | head -n "$top" | awk '{ printf "  %6.1f s  %s %s\n", $1, $2, $3 }'
done
