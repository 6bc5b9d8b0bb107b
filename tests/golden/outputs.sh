#!/usr/bin/env bash
# The outputs of every command on every planar robots/*.yaml, written to one folder, so that two
# builds can be compared byte for byte (tests/golden/compare.sh): a refactoring that must not
# change any output is checked by running this with the build before and after it.
#
#   tests/golden/outputs.sh BINARY OUT_DIR
#
# Each command's files, stdout and stderr land in OUT_DIR/<robot>/<step>.*; the exit code in
# <step>.rc. Seeds are fixed; the Monte Carlo runs one small study per robot on 2 threads.
# Figures (PNG) are skipped: matplotlib's bytes are not ours to keep equal.
set -uo pipefail
bin="$(realpath "$1")"
out="$2"
root="$(cd "$(dirname "$0")/../.." && pwd)"
rm -rf "$out" && mkdir -p "$out"
out="$(realpath "$out")"

# run STEP ARGS...: run the binary in OUT/<robot>, keeping stdout, stderr and the exit code.
run() {
  local step="$1"; shift
  (cd "$dir" && "$bin" "$@" >"$step.stdout" 2>"$step.stderr"; echo $? >"$step.rc")
}

for robot_file in "$root"/robots/*.yaml; do
  # Spatial robot files (kind: spatial) are skipped: every command here serves planar robots
  # only so far and refuses them (exit 2), so their folders would hold nothing but the refusal,
  # and a folder made before they existed would differ by them alone: the comparison stays one
  # of planar outputs.
  if grep -qE '^kind:[[:space:]]*spatial' "$robot_file"; then continue; fi
  name="$(basename "$robot_file" .yaml)"
  dir="$out/$name" && mkdir -p "$dir"
  r=(--robot "$robot_file")
  run workspace workspace "${r[@]}" --step 0.1 --out workspace.csv
  run sample sample "${r[@]}" --poses 30 --seed 3 --out plan.csv
  run simulate simulate "${r[@]}" --plan plan.csv --geometry-sigma 0.005 --skip-infeasible --seed 4 --out meas.csv --truth-out truth.yaml
  run simulate_hold simulate "${r[@]}" --plan plan.csv --geometry-sigma 0.005 --skip-infeasible --seed 5 --out holdout.csv
  run identify identify "${r[@]}" --measurements meas.csv --out result.yaml --calibrated-robot calibrated.yaml
  run identify_json identify "${r[@]}" --measurements meas.csv --json
  run identify_huber identify "${r[@]}" --measurements meas.csv --loss huber --out result_huber.yaml
  run identify_prior identify "${r[@]}" --measurements meas.csv --gauge prior --geometry-prior 0.01 --out result_prior.yaml
  run identify_none identify "${r[@]}" --measurements meas.csv --gauge none --out result_none.yaml
  run identify_paper identify "${r[@]}" --measurements meas.csv --estimator paper --out result_paper.yaml
  run identify_eq identify "${r[@]}" --measurements meas.csv --equilibrium on --out result_eq.yaml
  run identify_report identify "${r[@]}" --measurements meas.csv --out result_r.yaml --holdout holdout.csv --report report
  rm -f "$dir"/report/*.png
  run validate validate --robot calibrated.yaml --nominal "$robot_file" --measurements holdout.csv --out validate.csv --summary validate.yaml
  run validate_json validate --robot calibrated.yaml --measurements holdout.csv --json
  run design design "${r[@]}" --poses 6 --starts 2 --random-sets 20 --seed 6 --out design.csv --summary design.yaml
  run design_d design "${r[@]}" --poses 8 --criterion d --starts 2 --random-sets 20 --seed 7 --json
  run design_prior design "${r[@]}" --poses 4 --starts 2 --random-sets 10 --seed 8 --prior result.yaml --out design_prior.csv
  run montecarlo montecarlo "${r[@]}" --poses 6:10:4 --trials 12 --threads 2 --seed 9 --no-plot --out mc
  run montecarlo_opts montecarlo "${r[@]}" --poses 8 --trials 8 --threads 2 --seed 10 --no-plot \
      --designs random --loss cauchy --outliers 0.05 --geometry-prior --out mc_opts
  # Bad input: the messages and exit codes are outputs too.
  run bad_plan simulate "${r[@]}" --plan "$robot_file" --out bad.csv
  run bad_meas identify "${r[@]}" --measurements plan.csv --out bad.yaml
done
rm -f "$out"/*/mc/*.png "$out"/*/mc_opts/*.png
echo "outputs written to $out"
