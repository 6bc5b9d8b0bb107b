// Wall time of one identification (see bench/README.md for the figures and the command).
// "Solve" is what the Monte Carlo runs (no covariance, no SVD report); "Full" is what
// `cablecal identify` runs. The *Cables benchmarks take the 3- and 4-cable robot files
// (robots/planar3_suspended.yaml, robots/planar4_fully_constrained.yaml) at n = 50.
#include <benchmark/benchmark.h>

#include <string>

#include "common/error.h"
#include "experiment/experiment.h"
#include "identify/identify.h"
#include "identify/spatial_identify.h"
#include "common/random.h"
#include "model/swivel.h"
#include "workspace/workspace.h"
#include "bench/spatial_experiment.h"

namespace {

using namespace cablecal;

std::vector<Measurement> NoisyExperiment(int n) {
  const Robot& nominal = BuiltinRobot();
  const auto plan = SampleFeasiblePoses(nominal, n, 1000 + n);
  Rng geometry(1), noise(2);
  const Robot truth = PerturbGeometry(nominal, 0.005, geometry);
  return SimulateExperiment(nominal, truth, plan, SimulationOptions{}, noise).measurements;
}

// robots/<name>, found from this file's path (the source tree's bench/ folder).
Robot RobotFile(const std::string& name) {
  const std::string here = __FILE__;
  return LoadRobotFile(here.substr(0, here.rfind("/bench/")) + "/robots/" + name);
}

const Robot& ManyCableRobot(int m) {
  static const Robot planar3 = RobotFile("planar3_suspended.yaml");
  static const Robot planar4 = RobotFile("planar4_fully_constrained.yaml");
  return m == 3 ? planar3 : planar4;
}

// n poses of the m-cable robot's sampler that a true robot 1 mm off nominal holds (these small
// platforms turn by tenths of a radian for 1 cm of geometry error, so that a larger one would
// leave many poses slack), simulated with the sensors' noise.
std::vector<Measurement> ManyCableExperiment(int m, int n) {
  const Robot& nominal = ManyCableRobot(m);
  Rng geometry(1);
  const Robot truth = PerturbGeometry(nominal, 0.001, geometry);
  std::vector<PlanPose> plan;
  for (const PlanPose& p : SampleFeasiblePoses(nominal, 2 * n, 1000 + n)) {
    Rng rng(0);
    try {
      SimulateExperiment(nominal, truth, {p}, SimulationOptions{}, rng);
      plan.push_back(p);
    } catch (const SolverFailure&) {
      // not holdable by this true robot
    }
    if (static_cast<int>(plan.size()) == n) break;
  }
  Rng noise(2);
  return SimulateExperiment(nominal, truth, plan, SimulationOptions{}, noise).measurements;
}

void Run(benchmark::State& state, const Robot& nominal, const std::vector<Measurement>& measurements,
         Estimator estimator, bool full) {
  IdentifyOptions options;
  options.estimator = estimator;
  options.compute_covariance = full;
  options.compute_identifiability = full;
  int iterations = 0;
  for (auto _ : state) {
    const IdentifyResult r = Identify(nominal, measurements, options);
    if (!r.converged()) state.SkipWithError("identification did not converge");
    iterations = r.iterations;
  }
  state.counters["lm_iterations"] = iterations;
  state.counters["poses"] = static_cast<double>(measurements.size());
}

void Run(benchmark::State& state, Estimator estimator, bool full) {
  Run(state, BuiltinRobot(), NoisyExperiment(static_cast<int>(state.range(0))), estimator, full);
}

void RunCables(benchmark::State& state, Estimator estimator, bool full) {
  const int m = static_cast<int>(state.range(0));
  Run(state, ManyCableRobot(m), ManyCableExperiment(m, 50), estimator, full);
}

void BM_IdentifySolveMl(benchmark::State& s) { Run(s, Estimator::kMaximumLikelihood, false); }
void BM_IdentifySolvePaper(benchmark::State& s) { Run(s, Estimator::kPaper, false); }
void BM_IdentifyFullMl(benchmark::State& s) { Run(s, Estimator::kMaximumLikelihood, true); }
BENCHMARK(BM_IdentifySolveMl)->Arg(6)->Arg(20)->Arg(50)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_IdentifySolvePaper)->Arg(6)->Arg(20)->Arg(50)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_IdentifyFullMl)->Arg(50)->Unit(benchmark::kMicrosecond);

// Argument: the cable count (3: planar3_suspended, 4: planar4_fully_constrained), 50 poses.
void BM_IdentifySolveMlCables(benchmark::State& s) { RunCables(s, Estimator::kMaximumLikelihood, false); }
void BM_IdentifySolvePaperCables(benchmark::State& s) { RunCables(s, Estimator::kPaper, false); }
void BM_IdentifyFullMlCables(benchmark::State& s) { RunCables(s, Estimator::kMaximumLikelihood, true); }
BENCHMARK(BM_IdentifySolveMlCables)->Arg(3)->Arg(4)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_IdentifySolvePaperCables)->Arg(3)->Arg(4)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_IdentifyFullMlCables)->Arg(3)->Arg(4)->Unit(benchmark::kMicrosecond);

}  // namespace


// Spatial identification (identify/spatial_identify.h) of bench/spatial_experiment.h's problem
// (cogiro, encoders + inclinometer + laser, noisy readings): the whole call, default gauge
// (gauge analysis, starting poses, the block-arrow Levenberg-Marquardt, covariance).
void SpatialIdentifyBench(benchmark::State& state, const SpatialIdentifyOptions& options) {
  const SpatialRobot nominal = bench::SpatialBenchRobot(CABLECAL_SOURCE_DIR);
  const std::vector<SpatialMeasurement> readings = bench::SpatialBenchReadings(nominal, static_cast<int>(state.range(0)));
  int iterations = 0;
  for (auto _ : state) {
    const SpatialIdentifyResult result = IdentifySpatial(nominal, readings, options);
    if (!result.converged()) state.SkipWithError(result.message.c_str());
    iterations = result.iterations;
    benchmark::DoNotOptimize(result.geometry.data());
  }
  state.counters["lm_iterations"] = iterations;
  state.counters["us_per_pose"] = benchmark::Counter(static_cast<double>(state.range(0)) * state.iterations(),
                                                     benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
void BM_SpatialIdentifyCogiroEncodersInclinometerLaser(benchmark::State& state) { SpatialIdentifyBench(state, {}); }
BENCHMARK(BM_SpatialIdentifyCogiroEncodersInclinometerLaser)
    ->Arg(30)->Arg(100)->Arg(300)->Arg(1000)->Arg(3000)->Unit(benchmark::kMillisecond);
// The same with the platform anchors free (--identify anchors): 24 more unknowns.
void BM_SpatialIdentifyCogiroFreeAnchors(benchmark::State& state) {
  SpatialIdentifyOptions options;
  options.anchors = true;
  SpatialIdentifyBench(state, options);
}
BENCHMARK(BM_SpatialIdentifyCogiroFreeAnchors)->Arg(30)->Arg(300)->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
