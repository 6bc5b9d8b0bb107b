#!/bin/bash
# The spatial study's irma4u cell (reproduce --study spatial: encoders, swivel encoders and the
# inclinometer; cables given E*A 1e5 N; centre of mass known to 0.5 mm; its plan margins) at the
# fewest poses, run alone: how many of its simulated identifications converge, and the wall
# time. bench/README.md, "Ill-conditioned identifications".
#   bench/irma4u_convergence.sh [POSES] [TRIALS] [BUILD_DIR]
set -euo pipefail
poses=${1:-4}
trials=${2:-100}
build=${3:-build}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# robots/irma4u.yaml with the study's changes: stiffness on every cable, the centre of mass's
# prior, and only the sensors the study reads (the encoders, swivel and inclinometer).
sed -e 's/pulley_radius: 0.03}/pulley_radius: 0.03, stiffness: 1.0e5}/' \
    -e 's/^  mass: 12.992 .*/  mass: 12.992\n  com_sigma: 0.0005/' \
    -e '/^  heading:/d' -e '/^  load_cell:/d' robots/irma4u.yaml > "$work/irma4u_study.yaml"
/usr/bin/time -f "%e s wall, %U s user" "$build/cablecal" --quiet montecarlo --robot "$work/irma4u_study.yaml" \
  --poses "$poses" --trials "$trials" --designs optimized --design-starts 2 --geometry-sigma 0.0005 \
  --tension-margin 20 --frame-margin 0.005 --tilt-margin-deg 0.5 --seed 2022 --no-plot --out "$work/out"
failed=$(tail -n +2 "$work/out/failures.csv" | cut -d, -f4 | sort | uniq -c)
echo "failed trials by cause (of $trials): ${failed:-none}"
