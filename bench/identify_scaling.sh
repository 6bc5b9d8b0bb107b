#!/usr/bin/env bash
# Wall time and peak memory of `cablecal identify` (with covariance and identifiability) as
# the number of poses grows: it should grow linearly. Writing result.yaml (--out) and printing
# the JSON instead (--json) are timed separately. Usage: bench/identify_scaling.sh [build [N...]]
set -euo pipefail
BIN="$(cd "${1:-build}" && pwd)/cablecal"
WORK="$(mktemp -d)"
trap 'rm -rf "$WORK"' EXIT
cd "$WORK"
shift || true
if [ $# -gt 0 ]; then SIZES=("$@"); else SIZES=(100 1000 10000 100000); fi
printf '| poses | wall time | peak memory | --json: wall time | --json: peak memory |\n|---|---|---|---|---|\n'
for n in "${SIZES[@]}"; do
  "$BIN" sample --poses "$n" --seed 3 --out plan.csv >/dev/null
  "$BIN" simulate --plan plan.csv --seed 4 --out meas.csv --truth-out truth.yaml >/dev/null
  /usr/bin/time -f '%e %M' -o time.txt "$BIN" identify --measurements meas.csv --out result.yaml >/dev/null
  read -r seconds kb < time.txt
  grep -q '^status: converged' result.yaml || { echo "n = $n: not converged" >&2; exit 1; }
  /usr/bin/time -f '%e %M' -o time.txt "$BIN" identify --measurements meas.csv --json >result.json
  read -r json_seconds json_kb < time.txt
  printf '| %s | %s s | %s MB | %s s | %s MB |\n' "$n" "$seconds" "$((kb / 1024))" "$json_seconds" "$((json_kb / 1024))"
done
