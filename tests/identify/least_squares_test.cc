// The ml estimator's own Levenberg-Marquardt (identify/least_squares.h) against Ceres solving
// the same problem with the same settings (its cost functors, DENSE_SCHUR, the tolerances and
// initial radius identify used before it): the same estimates to 1e-9 m and the same
// iteration count, on the built-in robot, the asymmetric robot file, random robots of 2 and 4
// cables (suspended and fully constrained) and every gauge; repeated readings of a pose and a
// missing laser; the 2-cable equilibrium rows; and a problem it cannot solve, reported as not
// converged.
#include <gtest/gtest.h>

#include <ceres/ceres.h>

#include <array>
#include <string>
#include <vector>

#include "common/error.h"
#include "identify/cost_functors.h"
#include "experiment/experiment.h"
#include "identify/identify.h"
#include "identify/identify_cables.h"
#include "identify/least_squares.h"
#include "tests/support/random_robot.h"
#include "workspace/workspace.h"

namespace cablecal {
namespace {

using internal::LeastSquaresSummary;
using internal::MlLeastSquaresProblem;
using PoseValues = std::vector<std::array<double, 3>>;

// A noisy experiment of n poses that a true robot `sigma_m` off nominal can hold.
std::vector<Measurement> Experiment(const Robot& nominal, int n, double sigma_m, std::uint64_t seed) {
  Rng geometry(seed);
  const Robot truth = PerturbGeometry(nominal, sigma_m, geometry);
  std::vector<PlanPose> plan;
  for (const PlanPose& p : SampleFeasiblePoses(nominal, 3 * n, seed + 1)) {
    Rng rng(0);
    try {
      SimulateExperiment(nominal, truth, {p}, SimulationOptions{}, rng);
      plan.push_back(p);
    } catch (const SolverFailure&) {
      continue;  // not holdable by this true robot
    }
    if (static_cast<int>(plan.size()) == n) break;
  }
  Rng noise(seed + 2);
  return SimulateExperiment(nominal, truth, plan, SimulationOptions{}, noise).measurements;
}

struct Solution {
  std::vector<double> geometry;
  PoseValues poses;
  LeastSquaresSummary summary;
};

template <int M>
struct Start {
  MlLeastSquaresProblem<M> problem;
  std::vector<std::vector<int>> readings_of;
  std::vector<double> geometry;
  PoseValues poses;
};

// One pose per distinct pose id, in order of first reading (as Identify groups them); the
// nominal geometry and each pose's StartingPose as the start.
template <int M>
Start<M> MakeStart(const Robot& nominal, const std::vector<Measurement>& measurements, Gauge gauge,
                   bool equilibrium = false) {
  Start<M> s;
  std::vector<int> ids;
  for (int k = 0; k < static_cast<int>(measurements.size()); ++k) {
    int j = 0;
    while (j < static_cast<int>(ids.size()) && ids[j] != measurements[k].pose_id) ++j;
    if (j == static_cast<int>(ids.size())) {
      ids.push_back(measurements[k].pose_id);
      s.readings_of.emplace_back();
    }
    s.readings_of[j].push_back(k);
  }
  const GeometryVector g = GeometryOf(nominal);
  s.geometry.assign(g.data(), g.data() + g.size());
  for (const std::vector<int>& r : s.readings_of) {
    const Eigen::Vector3d q = internal::StartingPose<M>(nominal, g, measurements[r.front()]);
    s.poses.push_back({q(0), q(1), q(2)});
  }
  s.problem.robot = &nominal;
  s.problem.readings_of = &s.readings_of;
  s.problem.weights = WeightsOf(nominal.sensors);
  if (!measurements.front().has(SensorId::kLaser)) s.problem.weights.inv_sigma_sensor[static_cast<int>(SensorId::kLaser)] = 0.0;
  if (equilibrium) s.problem.weights.inv_sigma_equilibrium = 1.0 / EquilibriumSigma(nominal);
  if (gauge == Gauge::kA1x) s.problem.held = PlanarKind::HeldByDefault(PlanarLayout(M));
  if (gauge == Gauge::kPrior) {
    s.problem.prior_geometry = g;
    s.problem.prior_inv_sigma.template head<PlanarLayout(M).exit_coordinates()>().setConstant(1.0 / *nominal.sensors.tracker_sigma_m);
  }
  return s;
}

template <int M>
Solution SolveOwn(const Robot& nominal, const std::vector<Measurement>& measurements, Gauge gauge,
                  bool equilibrium = false) {
  Start<M> s = MakeStart<M>(nominal, measurements, gauge, equilibrium);
  s.problem.measurements = &measurements;
  Solution out{s.geometry, s.poses, {}};
  out.summary = internal::SolveMlLeastSquares<M>(s.problem, out.geometry.data(), out.poses,
                                                 std::vector<char>(out.poses.size(), 1));
  return out;
}

// The reference: Ceres with the cost functors and the settings identify used for least squares.
template <int M>
Solution SolveCeres(const Robot& nominal, const std::vector<Measurement>& measurements, Gauge gauge,
                    bool equilibrium = false) {
  const Start<M> s = MakeStart<M>(nominal, measurements, gauge, equilibrium);
  Solution out{s.geometry, s.poses, {}};
  double* g = out.geometry.data();
  ceres::Problem problem;
  problem.AddParameterBlock(g, 3 * M);
  if (gauge == Gauge::kA1x) problem.SetManifold(g, new ceres::SubsetManifold(3 * M, {0}));
  auto* ordering = new ceres::ParameterBlockOrdering;
  for (std::size_t j = 0; j < s.readings_of.size(); ++j) {
    for (const int k : s.readings_of[j]) {
      const PoseReadings<M> readings = internal::ReadingsOf<M>(measurements[k]);
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<internal::MlLengthCost<M>, M, 3 * M, 3>(
                                   new internal::MlLengthCost<M>{&nominal, readings, s.problem.weights}),
                               nullptr, g, out.poses[j].data());
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<internal::MlSensorCost<M>, 2, 3>(
                                   new internal::MlSensorCost<M>{readings, s.problem.weights}),
                               nullptr, out.poses[j].data());
    }
    if constexpr (EquilibriumRows(M) > 0) {
      if (equilibrium) {  // the pose's static equilibrium, one row per pose (identify_cables.h)
        problem.AddResidualBlock(new ceres::AutoDiffCostFunction<internal::MlEquilibriumCost<M>, 1, 3 * M, 3>(
                                     new internal::MlEquilibriumCost<M>{&nominal, s.problem.weights}),
                                 nullptr, g, out.poses[j].data());
      }
    }
    ordering->AddElementToGroup(out.poses[j].data(), 0);
  }
  ordering->AddElementToGroup(g, 1);
  if (gauge == Gauge::kPrior) {
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<internal::ExitPointPriorCost<M>, 2 * M, 3 * M>(
                                 new internal::ExitPointPriorCost<M>{s.problem.prior_geometry.template head<PlanarLayout(M).exit_coordinates()>(), s.problem.prior_inv_sigma(0)}),
                             nullptr, g);
  }
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_SCHUR;
  options.linear_solver_ordering.reset(ordering);
  internal::ApplyLevenbergMarquardt(&options);
  options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  out.summary.converged = summary.termination_type == ceres::CONVERGENCE;
  out.summary.iterations = static_cast<int>(summary.iterations.size()) - 1;
  out.summary.final_cost = summary.final_cost;
  return out;
}

// Gauge none leaves one direction to Levenberg-Marquardt's path: rounding moves the estimate
// along it by ~1e-10 m (measured), still well inside 1e-9 m.
constexpr double kSame_m = 1e-9;

template <int M>
void ExpectSame(const Robot& nominal, const std::vector<Measurement>& measurements, Gauge gauge,
                const std::string& what, bool equilibrium = false) {
  const Solution own = SolveOwn<M>(nominal, measurements, gauge, equilibrium);
  const Solution ceres = SolveCeres<M>(nominal, measurements, gauge, equilibrium);
  const std::string where = what + ", gauge " + ToString(gauge) + (equilibrium ? ", equilibrium" : "");
  ASSERT_TRUE(ceres.summary.converged) << where;
  ASSERT_TRUE(own.summary.converged) << where << ": " << own.summary.message;
  EXPECT_EQ(own.summary.iterations, ceres.summary.iterations) << where;
  EXPECT_NEAR(own.summary.final_cost, ceres.summary.final_cost, 1e-9 * ceres.summary.final_cost) << where;
  for (int k = 0; k < 3 * M; ++k) EXPECT_NEAR(own.geometry[k], ceres.geometry[k], kSame_m) << where << " g" << k;
  for (std::size_t j = 0; j < own.poses.size(); ++j) {
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(own.poses[j][c], ceres.poses[j][c], kSame_m) << where << " pose " << j;
  }
}

template <int M>
void ExpectSameEveryGauge(const Robot& nominal, const std::vector<Measurement>& measurements,
                          const std::string& what) {
  for (const Gauge gauge : {Gauge::kA1x, Gauge::kPrior, Gauge::kNone}) ExpectSame<M>(nominal, measurements, gauge, what);
}

TEST(MlLeastSquares, SameAsCeresOnTheRobotFiles) {
  const Robot& builtin = BuiltinRobot();
  ExpectSameEveryGauge<2>(builtin, Experiment(builtin, 50, 0.005, 1), "built-in");
  const Robot asymmetric = LoadRobotFile(std::string(CABLECAL_SOURCE_DIR) + "/robots/asymmetric.yaml");
  ExpectSameEveryGauge<2>(asymmetric, Experiment(asymmetric, 50, 0.005, 2), "asymmetric");
  ExpectSameEveryGauge<2>(asymmetric, Experiment(asymmetric, 6, 0.005, 3), "asymmetric, 6 poses");
  const Robot planar4 = LoadRobotFile(std::string(CABLECAL_SOURCE_DIR) + "/robots/planar4_fully_constrained.yaml");
  ExpectSameEveryGauge<4>(planar4, Experiment(planar4, 50, 0.001, 4), "planar4");
}

// Property test: random robots of 2 and 4 cables (random_robot.h), suspended and fully
// constrained, fixed seed.
TEST(MlLeastSquares, SameAsCeresOnRandomRobots) {
  Rng rng(2026);
  for (int draw = 0; draw < 3; ++draw) {
    const Robot r2 = testing::RandomValidRobot(rng, "random2");
    ExpectSameEveryGauge<2>(r2, Experiment(r2, 30, 0.003, 10 + draw), "random 2-cable robot " + std::to_string(draw));
  }
  // More cables: the same code on M (each M a compile-time instance of this test's Ceres
  // reference, 10 s of compilation each, so two: suspended and fully constrained).
  for (int draw = 0; draw < 2; ++draw) {
    const Robot r4 = testing::RandomRobotWithCables(rng, "random4", 4, draw == 1);
    ExpectSameEveryGauge<4>(r4, Experiment(r4, 30, 0.001, 21 + draw), "random 4-cable robot " + std::to_string(draw));
  }
}

// The 2-cable equilibrium rows (residuals.h, MlEquilibriumResidual): the own solver's rows in the
// pose blocks against Ceres' autodiff of the same function, every gauge, the robot files and
// random robots; and a pose read three times (still one equilibrium row).
TEST(MlLeastSquares, SameAsCeresWithTheEquilibrium) {
  const Robot& builtin = BuiltinRobot();
  for (const Gauge gauge : {Gauge::kA1x, Gauge::kPrior, Gauge::kNone}) {
    ExpectSame<2>(builtin, Experiment(builtin, 30, 0.005, 1), gauge, "built-in", true);
  }
  const Robot asymmetric = LoadRobotFile(std::string(CABLECAL_SOURCE_DIR) + "/robots/asymmetric.yaml");
  ExpectSame<2>(asymmetric, Experiment(asymmetric, 30, 0.005, 2), Gauge::kA1x, "asymmetric", true);
  ExpectSame<2>(asymmetric, Experiment(asymmetric, 6, 0.005, 3), Gauge::kA1x, "asymmetric, 6 poses", true);
  Rng rng(2026);
  for (int draw = 0; draw < 3; ++draw) {
    const Robot r2 = testing::RandomValidRobot(rng, "random2");
    ExpectSame<2>(r2, Experiment(r2, 30, 0.003, 10 + draw), Gauge::kA1x, "random 2-cable robot " + std::to_string(draw),
                  true);
  }
  const std::vector<Measurement> once = Experiment(builtin, 10, 0.005, 40);
  std::vector<Measurement> repeated;
  for (int copy = 0; copy < 3; ++copy) repeated.insert(repeated.end(), once.begin(), once.end());
  ExpectSame<2>(builtin, repeated, Gauge::kA1x, "built-in, each pose read three times", true);
}

// Three readings of each pose (one set of pose unknowns each), and a file without the laser
// (its weight 0: a 4-cable robot's poses are still fixed by their lengths and angle).
TEST(MlLeastSquares, SameAsCeresWithRepeatedReadingsAndAMissingSensor) {
  const Robot& builtin = BuiltinRobot();
  // The same 20 poses read three times: each copy with noise of its own on the laser and an encoder.
  const std::vector<Measurement> once = Experiment(builtin, 20, 0.005, 40);
  std::vector<Measurement> repeated;
  for (int copy = 0; copy < 3; ++copy) repeated.insert(repeated.end(), once.begin(), once.end());
  Rng noise(8);
  for (Measurement& m : repeated) {
    m.at(SensorId::kLaser) += noise.Normal(0.0, builtin.sensors.laser_sigma_m());
    m.dl_m(0) += noise.Normal(0.0, builtin.sensors.encoder_sigma_m);
  }
  ExpectSame<2>(builtin, repeated, Gauge::kA1x, "built-in, each pose read three times");

  const Robot planar4 = LoadRobotFile(std::string(CABLECAL_SOURCE_DIR) + "/robots/planar4_fully_constrained.yaml");
  std::vector<Measurement> no_laser = Experiment(planar4, 30, 0.001, 41);
  for (Measurement& m : no_laser) m.drop(SensorId::kLaser);
  ExpectSame<4>(planar4, no_laser, Gauge::kA1x, "planar4 without its laser");
}

// The iteration limit counts what the summary reports: a solve that took k iterations also
// converges with the limit k, and not with k - 1.
TEST(MlLeastSquares, ConvergesWithTheLimitAtTheIterationsItReports) {
  const Robot asymmetric = LoadRobotFile(std::string(CABLECAL_SOURCE_DIR) + "/robots/asymmetric.yaml");
  for (const Robot* robot : {&BuiltinRobot(), &asymmetric}) {
    const std::vector<Measurement> measurements = Experiment(*robot, 30, 0.01, 60);
    const auto solve = [&](int limit) {
      Start<2> s = MakeStart<2>(*robot, measurements, Gauge::kA1x);
      s.problem.measurements = &measurements;
      s.problem.max_iterations = limit;
      return internal::SolveMlLeastSquares<2>(s.problem, s.geometry.data(), s.poses,
                                              std::vector<char>(s.poses.size(), 1));
    };
    const LeastSquaresSummary free = solve(100);
    ASSERT_TRUE(free.converged) << free.message;
    ASSERT_GE(free.iterations, 2);
    EXPECT_TRUE(solve(free.iterations).converged) << robot->name;
    EXPECT_FALSE(solve(free.iterations - 1).converged) << robot->name;
  }
}

// What it cannot do is said, not returned as an estimate: out of iterations, and a start where
// a cable's anchor is inside its pulley (the length undefined).
TEST(MlLeastSquares, ReportsFailureAsNotConverged) {
  const Robot& builtin = BuiltinRobot();
  const std::vector<Measurement> measurements = Experiment(builtin, 20, 0.005, 50);
  Start<2> s = MakeStart<2>(builtin, measurements, Gauge::kA1x);
  s.problem.measurements = &measurements;
  s.problem.max_iterations = 1;
  LeastSquaresSummary one = internal::SolveMlLeastSquares<2>(s.problem, s.geometry.data(), s.poses,
                                                              std::vector<char>(s.poses.size(), 1));
  EXPECT_FALSE(one.converged);
  EXPECT_EQ(one.iterations, 1);
  EXPECT_NE(one.message.find("iteration limit"), std::string::npos) << one.message;

  Start<2> inside = MakeStart<2>(builtin, measurements, Gauge::kA1x);
  inside.problem.measurements = &measurements;
  // Pose 1's anchor 1 onto exit point 1's pulley centre.
  const Cable& c = builtin.cables[0];
  inside.poses[0] = {c.p_F_exit_m.x() + SideSign(c.side) * c.pulley_radius_m - c.p_P_anchor_m.x(),
                     c.p_F_exit_m.y() - c.p_P_anchor_m.y(), 0.0};
  const LeastSquaresSummary bad = internal::SolveMlLeastSquares<2>(inside.problem, inside.geometry.data(),
                                                                   inside.poses, std::vector<char>(inside.poses.size(), 1));
  EXPECT_FALSE(bad.converged);
  EXPECT_NE(bad.message.find("not finite"), std::string::npos) << bad.message;
}

}  // namespace
}  // namespace cablecal
