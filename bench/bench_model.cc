// Model and workspace timings (see bench/README.md for the figures and the command).
#include <benchmark/benchmark.h>

#include "model/cable.h"
#include "model/statics.h"
#include "workspace/workspace.h"

namespace {

using namespace cablecal;

void BM_CableLengths(benchmark::State& state) {
  const Robot& robot = BuiltinRobot();
  const Eigen::Vector3d q(2.0, 1.2, 0.1);
  for (auto _ : state) benchmark::DoNotOptimize(CableLengths(robot, q));
}
BENCHMARK(BM_CableLengths);

void BM_SolveEquilibrium(benchmark::State& state) {
  const Robot& robot = BuiltinRobot();
  for (auto _ : state) benchmark::DoNotOptimize(SolveEquilibrium(robot, 2.0, 1.2));
}
BENCHMARK(BM_SolveEquilibrium);

void BM_ForwardGeometricoStatic(benchmark::State& state) {
  const Robot& robot = BuiltinRobot();
  const InversePose inv = InverseModel(robot, 2.0, 1.2);
  const Eigen::Vector3d guess = inv.evaluation.equilibrium.q + Eigen::Vector3d(0.005, -0.005, 0.01);
  for (auto _ : state) benchmark::DoNotOptimize(SolveForwardGeometricoStatic(robot, inv.lengths_m, &guess));
}
BENCHMARK(BM_ForwardGeometricoStatic);

void BM_WorkspaceGrid(benchmark::State& state) {
  const Robot& robot = BuiltinRobot();
  const double step = state.range(0) / 1000.0;
  for (auto _ : state) benchmark::DoNotOptimize(ComputeWorkspaceGrid(robot, step));
}
BENCHMARK(BM_WorkspaceGrid)->Arg(50)->Arg(20)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
