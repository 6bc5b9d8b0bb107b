// Wall time of Monte Carlo trials (see bench/README.md for the figures and the command): a
// trial is what `cablecal montecarlo` repeats (draw a random feasible set of n poses, simulate
// the experiment on a perturbed true robot with noisy sensors, identify), run through
// RunMonteCarlo on one thread, 200 trials per benchmark iteration. The time per trial is
// the benchmark's time / 200; trials whose true robot cannot hold a drawn pose stop at the
// simulation and are cheaper, so the share that failed is reported beside it (`failed`).
// Arguments: the cable count, 2 (the built-in robot) or 4 (robots/planar4_fully_constrained.yaml),
// and the true geometry's standard deviation in mm (montecarlo --geometry-sigma; 10 is its
// default; with 1 mm nearly every trial is whole).
#include <benchmark/benchmark.h>
#include <omp.h>

#include <chrono>
#include <string>

#include "model/robot.h"
#include "montecarlo/montecarlo.h"

namespace {

using namespace cablecal;

constexpr int kTrials = 200;

const Robot& RobotWithCables(int m) {
  static const Robot planar4 = [] {
    const std::string here = __FILE__;
    return LoadRobotFile(here.substr(0, here.rfind("/bench/")) + "/robots/planar4_fully_constrained.yaml");
  }();
  return m == 4 ? planar4 : BuiltinRobot();
}

void BM_MonteCarloTrials(benchmark::State& state) {
  const int m = static_cast<int>(state.range(0));
  omp_set_num_threads(1);
  MonteCarloOptions o;
  o.pose_counts = {50};
  o.designs = {PoseSetDesign::kRandom};
  o.trials = kTrials;
  o.seed = 3;
  o.geometry_sigma_m = 1e-3 * static_cast<double>(state.range(1));
  int failed = 0;
  double seconds = 0.0;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    const MonteCarloResult r = RunMonteCarlo(RobotWithCables(m), o);
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    failed = r.cells.front().failures();
  }
  state.counters["us_per_trial"] = 1e6 * seconds / (static_cast<double>(state.iterations()) * kTrials);
  state.counters["failed"] = static_cast<double>(failed) / kTrials;
}
// The small 4-cable platform turns by tenths of a radian for 1 cm of geometry error, and most
// random poses would leave a cable slack: 1 mm only.
BENCHMARK(BM_MonteCarloTrials)->Args({2, 10})->Args({2, 1})->Args({4, 1})->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
