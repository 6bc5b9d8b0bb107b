#!/usr/bin/env bash
# cablecal's spatial identification against an independent scipy one
# (bench/scipy_spatial_identify.py), same problem (bench/spatial_experiment.h: cogiro, encoders
# + inclinometer + laser, N noisy poses, default N 30), same held coordinates, in one run;
# prints both median times, the ratio, both final costs and the largest difference between the
# two geometry estimates (they solve the same problem, so it is small).
#   bench/spatial_identify_vs_scipy.sh [BUILD_DIR] [N] [SCIPY_REPETITIONS]
# Needs Debian's python3-scipy and python3-yaml (scripts/setup.sh --bench).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$root/build}"
n="${2:-30}"
reps="${3:-3}"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
taskset -c 0 "$build/bench/time_spatial_identify" "$n" "$work/meas.csv" 50 >"$work/cablecal.txt"
held="$(sed -n 3p "$work/cablecal.txt" | cut -d' ' -f2-)"
# shellcheck disable=SC2086
taskset -c 0 env OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 /usr/bin/python3 "$root/bench/scipy_spatial_identify.py" \
  "$root/robots/cogiro.yaml" "$work/meas.csv" "$reps" $held >"$work/scipy.txt"
/usr/bin/python3 - "$work/cablecal.txt" "$work/scipy.txt" "$n" <<'PY'
import sys
def read(path):
    out = {}
    for line in open(path):
        f = line.split()
        if len(f) == 2 and not f[0].startswith("pose"):
            try:
                out[f[0]] = float(f[1])
            except ValueError:
                pass
    return out
c, s = read(sys.argv[1]), read(sys.argv[2])
c_cost = open(sys.argv[1]).read().split("final_cost")[1].split()[0]
s_cost = open(sys.argv[2]).read().split(" cost ")[1].split()[0]
names = [k for k in c if k in s and k != "median_s"]
diff = max(abs(c[k] - s[k]) for k in names)
print(f"n = {sys.argv[3]}: cablecal {c['median_s'] * 1e3:.2f} ms (cost {c_cost}), scipy least_squares "
      f"{s['median_s'] * 1e3:.0f} ms (cost {s_cost}), ratio {s['median_s'] / c['median_s']:.0f}x; "
      f"largest estimate difference {diff:.2e} m")
PY
