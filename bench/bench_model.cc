// Model and workspace timings (see bench/README.md for the figures and the command).
#include <benchmark/benchmark.h>
#include <ceres/jet.h>

#include "common/random.h"
#include "model/cable.h"
#include "model/forward_statics.h"
#include "model/spatial_robot.h"
#include "model/statics.h"
#include "model/swivel.h"
#include "tests/support/random_spatial_robot.h"
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

// planar3: the inextensible forward kinematics; planar4 (elastic cables): the forward model of
// model/forward_statics.h, from the unstretched lengths commanded for the pose's tensions.
void BM_ForwardKinematics(benchmark::State& state) {
  const Robot robot = ManyCableRobot(static_cast<int>(state.range(0)));
  const Eigen::Vector3d q(robot.p_F_home_m.x() - 0.2, robot.p_F_home_m.y() + 0.1, robot.home_theta_rad);
  const Eigen::VectorXd lengths = CableLengths(robot, q);
  const Eigen::Vector3d guess = q + Eigen::Vector3d(0.005, -0.005, 0.01);
  if (robot.num_cables() <= 3) {
    for (auto _ : state) benchmark::DoNotOptimize(SolveForwardGeometricoStatic(robot, lengths, &guess));
    return;
  }
  const Eigen::VectorXd unstretched =
      CommandedUnstretchedLengths(robot, lengths, DistributeTensions(robot, q).tensions_N);
  for (auto _ : state) benchmark::DoNotOptimize(SolveForwardStatics(robot, unstretched, &guess));
}
BENCHMARK(BM_ForwardKinematics)->Arg(3)->Arg(4);

void BM_WorkspaceGridManyCables(benchmark::State& state) {
  const Robot robot = ManyCableRobot(static_cast<int>(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(ComputeWorkspaceGrid(robot, 0.05));
}
BENCHMARK(BM_WorkspaceGridManyCables)->Arg(3)->Arg(4)->Unit(benchmark::kMillisecond);

// Spatial robots: every cable's length through its swivel pulley at a pose near home, in
// doubles, and with its Jacobian with respect to the pose (ceres::Jet of dimension 6, what the
// spatial identification will evaluate), for m = 4 (irma4u), 6 (a random robot, seed 6) and 8
// (ipanema1).
SpatialRobot SpatialBenchRobot(int m) {
  if (m == 6) {
    Rng rng(6);
    return testing::RandomSpatialRobot(rng, "random6", 6);
  }
  return LoadSpatialRobotFile(std::string(CABLECAL_SOURCE_DIR) + (m == 4 ? "/robots/irma4u.yaml" : "/robots/ipanema1.yaml"));
}

SpatialPose<double> NearHome(const SpatialRobot& robot) {
  SpatialPose<double> q = robot.home_pose();
  q += (SpatialPose<double>() << 0.1, -0.05, 0.08, 0.02, -0.03, 0.05).finished();
  return q;
}

void BM_SpatialCableLengths(benchmark::State& state) {
  const SpatialRobot robot = SpatialBenchRobot(static_cast<int>(state.range(0)));
  const SpatialPose<double> q = NearHome(robot);
  for (auto _ : state) benchmark::DoNotOptimize(CableLengths<double>(robot, q));
}
BENCHMARK(BM_SpatialCableLengths)->Arg(4)->Arg(6)->Arg(8);

void BM_SpatialCableLengthsJacobian(benchmark::State& state) {
  using J = ceres::Jet<double, 6>;
  const SpatialRobot robot = SpatialBenchRobot(static_cast<int>(state.range(0)));
  const SpatialPose<double> q = NearHome(robot);
  SpatialPose<J> qj;
  for (int j = 0; j < 6; ++j) qj(j) = J(q(j), j);
  for (auto _ : state) benchmark::DoNotOptimize(CableLengths<J>(robot, qj));
}
BENCHMARK(BM_SpatialCableLengthsJacobian)->Arg(4)->Arg(6)->Arg(8);

// One spatial forward solve (model/forward_statics.h) from a guess 5 mm and 0.01 rad off the
// pose the robot settles in: irma4u (m = 4, underactuated, inextensible: its lengths at home,
// settled once first), the first 6 cables of ipanema1 (m = 6, its E*A), ipanema1 and cogiro
// (m = 8): the lengths commanded for the home pose's tension distribution where one exists.
struct SpatialForwardCase {
  SpatialRobot robot;
  Eigen::VectorXd unstretched_m;
  SpatialPose<double> settled;
  bool ok = false;
};
SpatialForwardCase MakeSpatialForwardCase(const std::string& name, int keep_cables) {
  SpatialForwardCase c;
  c.robot = LoadSpatialRobotFile(std::string(CABLECAL_SOURCE_DIR) + "/robots/" + name + ".yaml");
  c.robot.cables.resize(keep_cables);
  const SpatialPose<double> home = c.robot.home_pose();
  const Eigen::VectorXd l = CableLengths<double>(c.robot, home);
  c.unstretched_m = l;
  if (keep_cables >= 6) {
    const TensionDistribution t =
        DistributeTensions(WrenchMatrix<double>(c.robot, home), GravityWrench<double>(c.robot, home), c.robot.tension_min_N,
                           c.robot.tension_max_N, c.robot.platform_mass_kg * c.robot.gravity_mps2);
    if (t.feasibility != Feasibility::kNoEquilibrium) c.unstretched_m = CommandedUnstretchedLengths(c.robot, l, t.tensions_N);
  }
  const SpatialForwardResult f = SolveForwardStatics(c.robot, c.unstretched_m, &home);
  c.settled = f.equilibrium.q;
  c.ok = f.status == ForwardStatus::kConverged;
  return c;
}

void BM_SpatialForwardStatics(benchmark::State& state, const std::string& name, int cables) {
  const SpatialForwardCase c = MakeSpatialForwardCase(name, cables);
  if (!c.ok) {
    state.SkipWithError("the robot does not settle near home");
    return;
  }
  SpatialPose<double> guess = c.settled;
  guess += (SpatialPose<double>() << 0.005, -0.005, 0.005, 0.01, -0.01, 0.01).finished();
  int iterations = 0;
  for (auto _ : state) {
    const SpatialForwardResult f = SolveForwardStatics(c.robot, c.unstretched_m, &guess);
    iterations = f.iterations;
    benchmark::DoNotOptimize(f);
  }
  state.counters["newton_iterations"] = iterations;
}
BENCHMARK_CAPTURE(BM_SpatialForwardStatics, irma4u_m4, std::string("irma4u"), 4);
BENCHMARK_CAPTURE(BM_SpatialForwardStatics, ipanema1_first6_m6, std::string("ipanema1"), 6);
BENCHMARK_CAPTURE(BM_SpatialForwardStatics, ipanema1_m8, std::string("ipanema1"), 8);
BENCHMARK_CAPTURE(BM_SpatialForwardStatics, cogiro_m8, std::string("cogiro"), 8);

}  // namespace

BENCHMARK_MAIN();
