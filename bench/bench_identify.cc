// Wall time of one identification (see bench/README.md for the figures and the command).
// "Solve" is what the Monte Carlo runs (no covariance, no SVD report); "Full" is what
// `cablecal identify` runs.
#include <benchmark/benchmark.h>

#include "identify/experiment.h"
#include "identify/identify.h"
#include "workspace/workspace.h"

namespace {

using namespace cablecal;

std::vector<Measurement> NoisyExperiment(int n) {
  const Robot& nominal = BuiltinRobot();
  const auto plan = SampleFeasiblePoses(nominal, n, 1000 + n);
  Rng geometry(1), noise(2);
  const Robot truth = PerturbGeometry(nominal, 0.005, geometry);
  return SimulateExperiment(nominal, truth, plan, SimulationOptions{}, noise).measurements;
}

void Run(benchmark::State& state, Estimator estimator, bool full) {
  const int n = static_cast<int>(state.range(0));
  const std::vector<Measurement> measurements = NoisyExperiment(n);
  IdentifyOptions options;
  options.estimator = estimator;
  options.compute_covariance = full;
  options.compute_identifiability = full;
  int iterations = 0;
  for (auto _ : state) {
    const IdentifyResult r = Identify(BuiltinRobot(), measurements, options);
    if (!r.converged()) state.SkipWithError("identification did not converge");
    iterations = r.iterations;
  }
  state.counters["lm_iterations"] = iterations;
}

void BM_IdentifySolveMl(benchmark::State& s) { Run(s, Estimator::kMaximumLikelihood, false); }
void BM_IdentifySolvePaper(benchmark::State& s) { Run(s, Estimator::kPaper, false); }
void BM_IdentifyFullMl(benchmark::State& s) { Run(s, Estimator::kMaximumLikelihood, true); }
BENCHMARK(BM_IdentifySolveMl)->Arg(6)->Arg(20)->Arg(50)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_IdentifySolvePaper)->Arg(6)->Arg(20)->Arg(50)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_IdentifyFullMl)->Arg(50)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
