#!/usr/bin/env bash
# Quick start, command 1: install what is missing, build, and run the main job on the built-in robot.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
"$root/scripts/setup.sh"
"$root/scripts/build.sh" -DCABLECAL_MPI=OFF  # the default build (test.sh turns MPI on in the same folder)
build="${CABLECAL_BUILD_DIR:-$root/build}"
cd "$root"
mkdir -p results
"$build/cablecal" workspace --out results/workspace.csv --plot results/workspace.png
"$build/cablecal" reproduce --out results "$@"
