#!/usr/bin/env bash
# Configures and builds cablecal (Release by default) into build/ (or $CABLECAL_BUILD_DIR).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${CABLECAL_BUILD_DIR:-$root/build}"
type="${CMAKE_BUILD_TYPE:-Release}"
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE="$type" "$@" >/dev/null
cmake --build "$build" --parallel "$(nproc)"
