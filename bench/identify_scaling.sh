#!/usr/bin/env bash
# Wall time and peak memory of `cablecal identify` (with covariance and identifiability) as
# the number of poses grows: it should grow linearly. Usage: bench/identify_scaling.sh [build]
set -euo pipefail
BIN="$(cd "${1:-build}" && pwd)/cablecal"
WORK="$(mktemp -d)"
trap 'rm -rf "$WORK"' EXIT
cd "$WORK"
printf '| poses | wall time | peak memory |\n|---|---|---|\n'
for n in 100 1000 10000 100000; do
  "$BIN" sample --poses "$n" --seed 3 --out plan.csv >/dev/null
  "$BIN" simulate --plan plan.csv --seed 4 --out meas.csv --truth-out truth.yaml >/dev/null
  /usr/bin/time -f '%e %M' -o time.txt "$BIN" identify --measurements meas.csv --out result.yaml >/dev/null
  read -r seconds kb < time.txt
  grep -q '^status: converged' result.yaml || { echo "n = $n: not converged" >&2; exit 1; }
  printf '| %s | %s s | %s MB |\n' "$n" "$seconds" "$((kb / 1024))"
done
