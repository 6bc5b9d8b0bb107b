#!/usr/bin/env bash
# Times `cablecal design --poses N --starts 8` for every N in 6..50 (or the N given as
# arguments) and records the condition number against the median of 100 random feasible
# sets, and the improvement factor on the design's own criterion (CRITERION, default a, the
# design's default). Prints a Markdown table (bench/README.md). Usage:
#   [CRITERION=condition|a|d|e] bench/design_sweep.sh [N ...] > table.md
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
bin="${CABLECAL_BUILD_DIR:-$root/build}/cablecal"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
sizes=("$@")
[ ${#sizes[@]} -gt 0 ] || sizes=($(seq 6 50))
criterion="${CRITERION:-a}"
echo "| N | wall time (s) | peak RSS (MB) | converged starts | condition number | random median | ratio | improvement on $criterion |"
echo "|---|---|---|---|---|---|---|---|"
for n in "${sizes[@]}"; do
  /usr/bin/time -v "$bin" design --poses "$n" --starts 8 --seed 1 --criterion "$criterion" --out "$work/plan.csv" \
      --summary "$work/summary.yaml" > "$work/out.txt" 2> "$work/time.txt"
  wall=$(grep "Elapsed (wall clock)" "$work/time.txt" | awk '{print $NF}' | awk -F: '{ if (NF==2) print $1*60+$2; else print $1*3600+$2*60+$3 }')
  rss=$(grep "Maximum resident set size" "$work/time.txt" | awk '{printf "%.0f", $NF/1024}')
  conv=$(grep "^starts:" "$work/summary.yaml" | sed 's/.*converged: \([0-9]*\).*/\1/')
  opt=$(grep "^condition_number:" "$work/summary.yaml" | sed 's/.*optimized: \([^,]*\),.*/\1/')
  med=$(grep "^condition_number:" "$work/summary.yaml" | sed 's/.*random_median: \([^}]*\)}.*/\1/')
  ratio=$(awk -v a="$opt" -v b="$med" 'BEGIN { printf "%.3f", a / b }')
  own=$(sed -n '/^improvement_over_random_median:/,/^[a-z]/p' "$work/summary.yaml" | grep "^  $criterion:" | awk '{printf "%.2f", $2}')
  printf "| %d | %s | %s | %s/8 | %.1f | %.1f | %s | %s |\n" "$n" "$wall" "$rss" "$conv" "$opt" "$med" "$ratio" "$own"
done
