#!/usr/bin/env bash
# Usage: scripts/test.sh [--sanitize]
# Installs what is missing, builds, and runs every test (README, "Quick start", command 2).
# Without arguments, what CI runs (.ci/run): the Release build, with MPI (CABLECAL_MPI), and its
# whole test suite (ctest), including the mpirun tests (label "mpi") and a replay of the
# fuzzers' corpus (label "fuzz").
# --sanitize (or CABLECAL_SANITIZE_STAGE=1) adds a second stage: the same suite built with clang,
# AddressSanitizer and UndefinedBehaviorSanitizer and without MPI (build-sanitize/; the tests
# that only repeat instrumented code for a statistical or determinism property are left to the
# first stage, listed below), and from the same build the libFuzzer targets, each exploring for
# CABLECAL_FUZZ_SECONDS (default 30). It is a second whole build, about 35 minutes on 2 cores
# (bench/README.md, "Build and CI time"): run it before merging a change to memory handling, the
# loaders or the identification; CI's 15-minute budget has no room for it.
# Exit status: 0 when every test passed; 2 for an unknown argument; otherwise that of the step
# that failed (scripts/setup.sh, the build, or ctest when a test failed).
# CABLECAL_CI_BUILD_ONLY=release|sanitize builds that stage alone, into $CABLECAL_CI_BUILD_DIR,
# and runs no test (bench/compile_times.sh times the builds so).
set -euo pipefail
sanitize="${CABLECAL_SANITIZE_STAGE:-0}"
for arg in "$@"; do
  case "$arg" in
    --sanitize) sanitize=1 ;;
    -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0 ;;
    *) echo "cablecal test: unknown argument '$arg' (--sanitize adds the instrumented stage; --help says more)" >&2; exit 2 ;;
  esac
done
root="$(cd "$(dirname "$0")/.." && pwd)"
only="${CABLECAL_CI_BUILD_ONLY:-}"
if [ "$sanitize" = "1" ] || [ "$only" = sanitize ]; then "$root/scripts/setup.sh" --sanitize; else "$root/scripts/setup.sh" --tests; fi
jobs="$(nproc)"
# For the instrumented builds, whose test executables also run while building (the tests'
# discovery) and under the fuzzers; nothing else reads them.
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:strict_string_checks=1"
export LSAN_OPTIONS="suppressions=$root/tests/sanitizers/lsan.supp:print_suppressions=0"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"

# Each stage builds what its tests run and nothing more (target cablecal_tests, tests/CMakeLists.txt:
# not the benchmarks; in the sanitizer build, also the fuzzers).
build_release() {
  CABLECAL_BUILD_TARGETS=cablecal_tests "$root/scripts/build.sh" -DCABLECAL_MPI=ON
}
build_sanitize() {
  # clang: it compiles the instrumented code in two thirds of GCC's time, and its build also
  # holds the fuzzers (libFuzzer is clang's), so the instrumented libraries compile once.
  # -O1: sanitizer reports stay readable and the (Ceres-template-heavy) build stays short.
  CC=clang CXX=clang++ CABLECAL_BUILD_TARGETS=cablecal_tests CMAKE_BUILD_TYPE=RelWithDebInfo \
    "$root/scripts/build.sh" -DCABLECAL_SANITIZE=ON -DCABLECAL_FUZZ_SECONDS="${CABLECAL_FUZZ_SECONDS:-30}" \
    -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1"
}
if [ -n "$only" ]; then
  case "$only" in
    release|sanitize) CABLECAL_BUILD_DIR="${CABLECAL_CI_BUILD_DIR:?}" "build_$only"; exit 0 ;;
    *) echo "cablecal test: CABLECAL_CI_BUILD_ONLY must be release or sanitize" >&2; exit 2 ;;
  esac
fi

echo "== Release build (with MPI) and tests"
build_release
(cd "${CABLECAL_BUILD_DIR:-$root/build}" && ctest --output-on-failure --parallel "$jobs" --timeout 900)

if [ "$sanitize" != "1" ]; then exit 0; fi

# The sanitizer build is the default one, without MPI: both configurations get tested.
echo "== Sanitizer build (clang, ASan + UBSan, without MPI): the tests and the fuzzers"
CABLECAL_BUILD_DIR="$root/build-sanitize" build_sanitize
# Left to the Release stage, which runs them all: tests that repeat code other tests already
# run under the sanitizers, for a statistical or determinism property that instrumentation
# cannot change. The design-quality sizes N = 15 and 30 (N = 6 stays); the 40 random robots;
# the two robust-design studies and the D- and E-criterion qualities (the A one stays); the
# thread-count determinism checks of design and Monte Carlo; the random many-cable robots' designs and
# the 4-cable thread-count check; the spatial sampler's tests and the spatial CLI's end-to-end
# runs, thread-count check and message checks (they sample, grid and simulate whole built-in
# robots: SpatialSample.EveryPose... took 4.2 s in Release and 307 s instrumented, and the CLI
# ones 21 s each in Release), the spatial noiseless simulation and the 100-experiment stretch
# study (the spatial statics, forward model, stages and identification keep their other tests
# here); and this round's whole-robot runs: the 1000-experiment covariance checks, the
# robustness search on random and fixture robots, the spatial designs that must beat random
# sets and the robust ones that must hold on 40 true robots each (their robustness search on
# ipanema1 stays), the spatial Monte Carlo's noise-free and thread-count studies, and the spatial CLI's
# end-to-end identify, design and montecarlo runs (their hostile-input tests stay); the spatial
# design's child-process check (12 s of CPU in Release, and the instrumented build solves in
# process, so that it would compare a solve with itself); and the spatial study's reduced
# run (reproduce --study spatial: three whole-robot studies with designs, twice). Instrumented, the first ones were about
# 570 s of CPU of the stage's ~1100 s (measured in CI, 2 cores). The fuzzers (label fuzz) run
# among the tests. ctest's regular expressions take at most 9 parenthesised groups ("Too many
# parentheses" beyond): add a name as a top-level alternative, not inside a new group.
(cd "$root/build-sanitize" && ctest --output-on-failure --parallel "$jobs" --timeout 1800 \
  -E '^(Sizes/ConditionQuality\.AtMostHalfTheRandomMedian/(15|30)|Shards/RandomRobots\..*|RobustDesign\.(AsymmetricRobotAtEightAndTwelvePosesIsAtMostHalfTheRandomMedian|RobustPlansSurviveTheTrueGeometryNominalOnesDoNot)|Criteria/InformationQuality\.BeatsRandomMedianByAFactorOfTwo/(d|e)( .*)?|MonteCarlo\.BitIdenticalForOneAndTwoThreads|Design\.SameSeedSameResultWhateverTheThreadCount|Cables/RandomRobotsWithCables\..*|RobustDesign\.ManyCablesSameResultWhateverTheThreadCount|SpatialSample\..*|SpatialCli\.(SampleWorkspaceSimulateOnEveryBuiltInAndARandomRobot|WorkspacePlotIsWrittenForEachBuiltIn|OneAndTwoThreadsWriteTheSameBytes|MessagesNameTheTruthTheCableAndTheGrid)|SpatialSimulation\.NoiselessReadingsAreTheModelsValues|SpatialIdentify\.(ElasticStretch.*|PredictedSigmas.*)|RobustnessSearch\.RandomRobotsNeverFailForRobustnessAlone|Fixtures/NamedBadGeometry\..*|SpatialDesign\..*HoldsAndBeatsRandom|SpatialDesign\.RobustPlansHold.*|SpatialDesign\.SolvesInChildProcessesEqualSolvesInProcess|SpatialMonteCarlo\.(NoiseFreeTrialsRecoverTheTrueRobotInTheStudysGauge|SameBytesWhateverTheThreadCount)|SpatialIdentifyCli\.SimulateIdentifyValidateOnABuiltInAndARandomRobot|SpatialDesignCli\.PlanReadsBackAndSimulatesOnIrma4uAndARandomRobot|SpatialCli\.(MonteCarloWritesTheStudyAndRefusesPlanarOnlyFlags|ReproduceSpatialWritesEveryConfigurationTheSameForOneAndTwoThreads))$')
