#!/usr/bin/env bash
# Quick start, command 1: install what is missing, build, and run the main job on the built-in robot.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
"$root/scripts/setup.sh"
# The default build (test.sh turns MPI on in the same folder), of the CLI alone: the main job
# needs nothing else (the tests, benchmarks and Python module are built by test.sh or build.sh).
CABLECAL_BUILD_TARGETS=cablecal "$root/scripts/build.sh" -DCABLECAL_MPI=OFF
build="${CABLECAL_BUILD_DIR:-$root/build}"
cd "$root"
mkdir -p results
"$build/cablecal" workspace --out results/workspace.csv --plot results/workspace.png
"$build/cablecal" reproduce --out results "$@"
# The spatial study (cogiro and irma4u) into results/spatial/ (README, "The spatial study"):
# optimized, random and grid sets (616 s wall on 2 cores at 58db6f2: results/spatial/README.md).
"$build/cablecal" reproduce --study spatial --out results "$@"
