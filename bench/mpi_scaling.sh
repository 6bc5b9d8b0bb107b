#!/usr/bin/env bash
# Wall time of one fixed Monte Carlo study on P MPI ranks x T OpenMP threads, with
# /usr/bin/time -v, and a check that every run wrote the same result files. Needs the MPI
# build (cmake -DCABLECAL_MPI=ON). Prints a Markdown table (bench/README.md). Usage:
#   bench/mpi_scaling.sh ["P T" ...] > table.md        (default: "1 1" "1 2" "2 1")
# The study (override with CABLECAL_BENCH_STUDY): random pose sets for n = 6, 10, ..., 50,
# 3000 trials each, so that the trials (not the designed sets) dominate.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
bin="${CABLECAL_BUILD_DIR:-$root/build}/cablecal"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
read -r -a study <<<"${CABLECAL_BENCH_STUDY:-montecarlo --poses 6:50:4 --designs random --trials 3000 --seed 3 --no-plot}"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
runs=("$@")
[ ${#runs[@]} -gt 0 ] || runs=("1 1" "1 2" "2 1")
seconds() { grep "Elapsed (wall clock)" "$1" | awk '{print $NF}' | awk -F: '{ if (NF==2) print $1*60+$2; else print $1*3600+$2*60+$3 }'; }
echo "| ranks P | threads per rank | cores used | wall time (s) | peak RSS per rank (MB) | speed-up vs 1 x 1 | efficiency | same files as 1 x 1 |"
echo "|---|---|---|---|---|---|---|---|"
base=""
for run in "${runs[@]}"; do
  read -r p t <<<"$run"
  out="$work/p${p}t${t}"
  # --bind-to none: the ranks' OpenMP threads may use every core given to the job.
  /usr/bin/time -v mpirun --quiet --bind-to none -np "$p" "$bin" "${study[@]}" --threads "$t" --out "$out" \
    >/dev/null 2>"$work/time.txt"
  wall=$(seconds "$work/time.txt")
  # time -v reports the largest child, which is one rank.
  rss=$(grep "Maximum resident set size" "$work/time.txt" | awk '{printf "%.0f", $NF/1024}')
  [ -n "$base" ] || { base="$wall"; ref="$out"; }
  same=yes
  for f in errors.csv summary.csv summary.md; do cmp -s "$ref/$f" "$out/$f" || same=no; done
  awk -v p="$p" -v t="$t" -v w="$wall" -v b="$base" -v r="$rss" -v s="$same" \
    'BEGIN { printf "| %d | %d | %d | %.1f | %s | %.2f | %.0f %% | %s |\n", p, t, p*t, w, r, b/w, 100*b/(w*p*t), s }'
done
