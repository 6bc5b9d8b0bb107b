#!/usr/bin/env bash
# cablecal's identification against an independent scipy one (bench/scipy_identify.py), same
# problem, same n, in one run: a simulated experiment of ROBOT (default: the built-in robot's
# file) with N poses (default 50), identified by both (estimator ml, gauge a1x, estimates
# only, as per Monte Carlo trial); prints both median times, the ratio and the largest
# difference between the two estimates (they solve the same problem, so it is small).
# GEOMETRY_SIGMA (m, default 0.002) is the true robot's offset from nominal; the small 4-cable
# platform needs 0.001 or less to hold every random pose.
#   bench/identify_vs_scipy.sh [BUILD_DIR] [N] [ROBOT.yaml] [GEOMETRY_SIGMA]
# Needs Debian's python3-scipy and python3-yaml (scripts/setup.sh --bench).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$root/build}"
n="${2:-50}"
robot="${3:-$root/robots/wang2022.yaml}"
geometry_sigma="${4:-0.002}"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

"$build/cablecal" sample --robot "$robot" --poses "$n" --seed 11 --out "$work/plan.csv" >/dev/null
"$build/cablecal" simulate --robot "$robot" --plan "$work/plan.csv" --geometry-sigma "$geometry_sigma" --seed 5 \
  --out "$work/meas.csv" >/dev/null
# Each on one core, so that the figure is the per-trial cost the Monte Carlo multiplies.
taskset -c 0 "$build/bench/time_identify" "$robot" "$work/meas.csv" 500 >"$work/cablecal.txt"
taskset -c 0 env OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 /usr/bin/python3 "$root/bench/scipy_identify.py" \
  "$robot" "$work/plan.csv" "$work/meas.csv" 20 >"$work/scipy.txt"

/usr/bin/python3 - "$work/cablecal.txt" "$work/scipy.txt" "$n" <<'EOF'
import sys
def read(path):
    return {k: float(v) for k, v in (line.split() for line in open(path))}
c, s, n = read(sys.argv[1]), read(sys.argv[2]), sys.argv[3]
names = [k for k in c if k not in ("median_s", "iterations")]
diff = max(abs(c[k] - s[k]) for k in names)
print(f"n = {n}: cablecal {c['median_s'] * 1e6:.0f} us, scipy least_squares {s['median_s'] * 1e3:.1f} ms, "
      f"ratio {s['median_s'] / c['median_s']:.0f}x; largest estimate difference {diff:.2e} m")
EOF
