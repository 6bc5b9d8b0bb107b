#!/usr/bin/env bash
# What the 2-cable equilibrium rows gain and what a wrong centre of mass costs (issue 24, item
# 3; bench/README.md, "The equilibrium in identification"). Two parts, on the built-in and the
# asymmetric robot:
#   1. Monte Carlo, random pose sets of 10 to 40 poses, 200 trials per cell: the estimates' RMS
#      error with --equilibrium off, on (com_sigma 5 mm, the default) and on with the true
#      centre of mass 5 and 10 mm off the file's (--com-error), and off with 10 mm.
#   2. The issue's symptom: the calibrated robot's prediction of its own training poses' theta
#      (validate on the training file), RMS over SEEDS experiments of 20 random poses, true
#      geometry 10 mm off nominal, with and without the equilibrium.
# Usage: [PART=symptom] [SEEDS=20] bench/equilibrium.sh [build dir] [out dir]   (about 10 min on 2 cores)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$root/build}"
out="${2:-/tmp/cablecal_equilibrium}"
cablecal="$build/cablecal"
mkdir -p "$out"
robots=("$root/robots/wang2022.yaml" "$root/robots/asymmetric.yaml")

summarise() {  # RMS (mm) of a1z a2x a2z l10 l20 and x_all per n, from summary.csv
  python3 - "$1" <<'EOF'
import csv, sys
rows = list(csv.DictReader(l for l in open(sys.argv[1]) if not l.startswith('#')))
params = ['a1z', 'a2x', 'a2z', 'l10', 'l20', 'x_all']
ns = sorted({int(r['n']) for r in rows})
for n in ns:
    cells = {r['parameter']: r for r in rows if int(r['n']) == n and r['design'] == 'random'}
    vals = ' '.join('%s %.3g' % (p, 1e3 * float(cells[p]['rms'])) for p in params)
    print('    n=%d  rms mm: %s  failures %s' % (n, vals, cells['a1z']['failures']))
EOF
}

for robot in "${robots[@]}"; do
  [ "${PART:-all}" = symptom ] && break
  name="$(basename "$robot" .yaml)"
  echo "== $name: Monte Carlo (random poses 10:40:10, 200 trials)"
  for run in "off 0" "on 0" "on 0.005" "on 0.01" "off 0.01"; do
    set -- $run
    dir="$out/mc_${name}_$1_$2"
    "$cablecal" -q montecarlo --robot "$robot" --poses 10:40:10 --trials 200 --designs random \
      --equilibrium "$1" --com-error "$2" --no-plot --out "$dir"
    echo "  --equilibrium $1 --com-error $2"
    summarise "$dir/summary.csv"
  done
done

seeds="${SEEDS:-20}"
for robot in "${robots[@]}"; do
  name="$(basename "$robot" .yaml)"
  for eq in off on; do
    sum=0
    : >"$out/train_${name}_${eq}.txt"
    for seed in $(seq 1 "$seeds"); do
      d="$out/train_${name}_$seed"
      mkdir -p "$d"
      "$cablecal" -q sample --robot "$robot" --poses 20 --seed "$seed" --out "$d/plan.csv"
      "$cablecal" -q simulate --robot "$robot" --plan "$d/plan.csv" --geometry-sigma 0.01 --seed "$((seed + 1000))" \
        --out "$d/meas.csv" --truth-out "$d/truth.yaml" 2>/dev/null || continue
      "$cablecal" -q identify --robot "$robot" --measurements "$d/meas.csv" --equilibrium "$eq" \
        --out "$d/result_$eq.yaml" --calibrated-robot "$d/cal_$eq.yaml" || continue
      "$cablecal" -q validate --robot "$d/cal_$eq.yaml" --measurements "$d/meas.csv" --out "$d/val_$eq.csv" \
        --summary "$d/val_$eq.yaml"
      python3 -c "import yaml,sys; v=yaml.safe_load(open('$d/val_$eq.yaml')); print(v['calibrated']['theta']['rms_rad'], v['calibrated']['z']['rms_m'])" \
        >>"$out/train_${name}_${eq}.txt"
    done
    python3 - "$out/train_${name}_${eq}.txt" "$name" "$eq" <<'EOF'
import math, sys
rows = [list(map(float, l.split())) for l in open(sys.argv[1]) if l.strip()]
th = math.sqrt(sum(r[0] ** 2 for r in rows) / len(rows))
z = math.sqrt(sum(r[1] ** 2 for r in rows) / len(rows))
print('== %s, --equilibrium %s: training-pose prediction over %d experiments: theta RMS %.3g mrad, z RMS %.3g mm'
      % (sys.argv[2], sys.argv[3], len(rows), 1e3 * th, 1e3 * z))
EOF
  done
done
