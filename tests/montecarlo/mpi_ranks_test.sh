#!/usr/bin/env bash
# The Monte Carlo under MPI (CTest, label "mpi"; built with -DCABLECAL_MPI=ON):
#   identical  mpirun -np 1, 2 and 3 (oversubscribed) write the same result files, byte for
#              byte, as one process without mpirun, whatever the threads per rank;
#   failure    a rank that fails its share makes the run exit 4, naming the rank and the
#              cells it lost, once, with nothing written; a rank that dies writes nothing;
#   input      bad input under mpirun is reported once, exit 2.
# Usage: mpi_ranks_test.sh MODE CABLECAL_BINARY MPIEXEC WORK_DIR
set -euo pipefail
mode="$1" bin="$2" mpiexec="$3" work="$4"
rm -rf "$work" && mkdir -p "$work" && cd "$work"

# Open MPI refuses to start as root (CI containers) unless told; these do nothing otherwise.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
# Containers often forbid the cross-memory attach of the shared-memory transport.
export OMPI_MCA_btl_vader_single_copy_mechanism=none
# A run that hangs (ranks waiting for each other) fails after two minutes, not at CTest's limit.
mpirun_() { timeout 120 "$mpiexec" --quiet "$@"; }

fail() { echo "FAIL: $*" >&2; exit 1; }
# 3 pose counts x 2 designs: 3 designed sets (one per rank at -np 3) and 6 cells of 10
# trials (15 chunks of 4, crossing cell boundaries); a few seconds per run.
study=(montecarlo --poses 6:8 --designs random,optimized --trials 10 --design-starts 1 --seed 5 --no-plot)

# run.yaml without its provenance lines (command, processes, threads, wall time).
results_of() { grep -v -E '^(command|processes|threads|wall_time_s):' "$1/run.yaml"; }

case "$mode" in
identical)
  "$bin" "${study[@]}" --threads 2 --out ref >/dev/null
  [ -s ref/errors.csv ] || fail "the single-process run wrote no errors.csv"
  runs=("1 2" "2 1" "3 2")
  for run in "${runs[@]}"; do
    read -r np threads <<<"$run"
    out="np$np"
    mpirun_ -np "$np" --oversubscribe "$bin" "${study[@]}" --threads "$threads" --out "$out" >/dev/null
    for f in errors.csv summary.csv summary.md; do
      cmp -s "ref/$f" "$out/$f" || fail "$f differs at -np $np --threads $threads: $(diff "ref/$f" "$out/$f" | head -5)"
    done
    diff <(results_of ref) <(results_of "$out") >/dev/null || fail "run.yaml differs at -np $np"
    grep -q "^processes: $np$" "$out/run.yaml" || fail "run.yaml does not record $np processes"
    echo "-np $np x $threads threads: identical to the single-process run"
  done
  ;;
failure)
  set +e
  CABLECAL_TEST_FAIL_RANK=1 mpirun_ -np 3 --oversubscribe "$bin" "${study[@]}" --threads 1 --out failed \
    >stdout.txt 2>stderr.txt
  code=$?
  set -e
  [ "$code" -eq 4 ] || fail "a failed rank should exit 4, got $code: $(cat stderr.txt)"
  [ ! -e failed ] || fail "a failed run wrote $(ls failed)"
  [ "$(grep -c 'MPI run failed' stderr.txt)" -eq 1 ] || fail "expected the failure once: $(cat stderr.txt)"
  grep -q 'rank 1 of 3: test fault injected' stderr.txt || fail "the failed rank is not named: $(cat stderr.txt)"
  grep -q 'lost its trials of n=6 random (4 of 10 trials)' stderr.txt || fail "the lost cells are not named"
  echo "failed rank: exit 4, named once with its cells, nothing written"

  set +e
  CABLECAL_TEST_FAIL_RANK=2:crash mpirun_ -np 3 --oversubscribe "$bin" "${study[@]}" --threads 1 --out crashed \
    >/dev/null 2>crash.txt
  code=$?
  set -e
  [ "$code" -ne 0 ] || fail "a crashed rank left mpirun exiting 0"
  [ ! -e crashed ] || fail "a crashed run wrote $(ls crashed)"
  echo "crashed rank: mpirun exits $code, nothing written"
  ;;
input)
  set +e
  mpirun_ -np 2 "$bin" montecarlo --poses 3 --trials 2 --out bad >/dev/null 2>stderr.txt
  code=$?
  set -e
  [ "$code" -eq 2 ] || fail "bad input should exit 2, got $code"
  [ "$(grep -c 'at least 5 poses' stderr.txt)" -eq 1 ] || fail "expected the message once: $(cat stderr.txt)"
  set +e
  mpirun_ -np 2 "$bin" sample --poses 5 --out plan.csv >/dev/null 2>stderr.txt
  code=$?
  set -e
  [ "$code" -eq 2 ] || fail "sample under mpirun -np 2 should exit 2, got $code"
  [ "$(grep -c 'only montecarlo and reproduce run on several MPI processes' stderr.txt)" -eq 1 ] ||
    fail "expected the refusal once: $(cat stderr.txt)"
  [ ! -e plan.csv ] || fail "sample wrote plan.csv under mpirun"
  echo "bad input and other subcommands: one message, exit 2"
  ;;
*)
  fail "unknown mode $mode"
  ;;
esac
