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

// Robots with more cables: the full-pose test (a tension distribution: a 3 x 3 solve for 3
// cables, the least-distance problem for 4), the forward kinematics, and the grid with its
// theta scan (181 orientations per point for planar3's +-45 degrees, 121 for planar4's +-30).
Robot ManyCableRobot(int m) {
  return LoadRobotFile(std::string(CABLECAL_SOURCE_DIR) +
                       (m == 3 ? "/robots/planar3_suspended.yaml" : "/robots/planar4_fully_constrained.yaml"));
}

void BM_EvaluateFullPose(benchmark::State& state) {
  const Robot robot = ManyCableRobot(static_cast<int>(state.range(0)));
  const Eigen::Vector3d q(robot.p_F_home_m.x(), robot.p_F_home_m.y(), robot.home_theta_rad);
  for (auto _ : state) benchmark::DoNotOptimize(EvaluatePose(robot, q));
}
BENCHMARK(BM_EvaluateFullPose)->Arg(3)->Arg(4);

void BM_ForwardKinematics(benchmark::State& state) {
  const Robot robot = ManyCableRobot(static_cast<int>(state.range(0)));
  const Eigen::Vector3d q(robot.p_F_home_m.x() - 0.2, robot.p_F_home_m.y() + 0.1, robot.home_theta_rad);
  const Eigen::VectorXd lengths = CableLengths(robot, q);
  const Eigen::Vector3d guess = q + Eigen::Vector3d(0.005, -0.005, 0.01);
  for (auto _ : state) benchmark::DoNotOptimize(SolveForwardGeometricoStatic(robot, lengths, &guess));
}
BENCHMARK(BM_ForwardKinematics)->Arg(3)->Arg(4);

void BM_WorkspaceGridManyCables(benchmark::State& state) {
  const Robot robot = ManyCableRobot(static_cast<int>(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(ComputeWorkspaceGrid(robot, 0.05));
}
BENCHMARK(BM_WorkspaceGridManyCables)->Arg(3)->Arg(4)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
