// The spatial statics (model/spatial_statics.h) and the stability test (model/stability.h):
// on the built-in spatial robots and random ones (3 to 12 cables, tilted swivel axes, offset
// centres of mass), the equilibria against virtual work computed from an independent length
// construction and potential, the stability against the potential's change along the motions
// the fixed lengths allow, the planar robots placed in space, each feasibility reason at a pose
// built for it, and the m >= 7 tensions against an independent minimum-norm projection.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "common/error.h"
#include "common/random.h"
#include "model/cable.h"
#include "model/spatial_statics.h"
#include "model/stability.h"
#include "model/statics.h"
#include "model/swivel.h"
#include "tests/support/random_spatial_robot.h"
#include "tests/support/swivel_construction.h"

namespace cablecal {
namespace {

using Pose6 = SpatialPose<double>;
using testing::PointByComposition;
using testing::SpatialLengthByConstruction;

// W t + w_g at a solver's equilibrium, per newton of weight: rounding of Newton's last step.
constexpr double kBalanceTol = 1e-9;
// Virtual work by central differences (step kStep) of the construction (bisection to ~1e-16
// rad): truncation ~ kStep^2 and rounding ~ 1e-15 m / kStep, per newton of weight and metre.
constexpr double kStep = 1e-5;
constexpr double kVirtualWorkTol = 1e-6;

SpatialRobot BuiltIn(const std::string& name) {
  return LoadSpatialRobotFile(std::string(CABLECAL_SOURCE_DIR) + "/robots/" + name);
}
Robot PlanarFile(const std::string& name) {
  return LoadRobotFile(std::string(CABLECAL_SOURCE_DIR) + "/robots/" + name);
}

double Weight(const SpatialRobot& r) { return r.platform_mass_kg * r.gravity_mps2; }

// The built-in robots and random ones of 3 to 12 cables (two of each, fixed seed).
std::vector<SpatialRobot> TestRobots() {
  std::vector<SpatialRobot> robots = {BuiltIn("cogiro.yaml"), BuiltIn("ipanema1.yaml"), BuiltIn("irma4u.yaml")};
  Rng rng(2026);
  for (int k = 0; k < 2; ++k) {
    for (int m = 3; m <= 12; ++m) robots.push_back(testing::RandomSpatialRobot(rng, "random" + std::to_string(m), m));
  }
  return robots;
}

// A pose near home: position within +-0.3 m; for m >= 6 each angle within +-8 degrees, for
// m = 4, 5 yaw within +-0.1 degree (a 4-cable platform twisted by half a degree already
// slackens a diagonal pair: IRMA4U's tensions go from 90 N each to 4 and 176 N), the rest from
// the equilibrium (the guess keeps home's).
Pose6 PoseNearHome(const SpatialRobot& robot, Rng& rng) {
  Pose6 q = robot.home_pose();
  for (int j = 0; j < 3; ++j) q(j) += rng.Uniform(-0.3, 0.3);
  const double angle_deg = robot.num_cables() >= 6 ? 8.0 : 0.1;
  for (int j : ControlledCoordinates(robot)) {
    if (j >= 3) q(j) += rng.Uniform(-angle_deg, angle_deg) * M_PI / 180.0;
  }
  return q;
}

// Feasible equilibria of a robot: home and poses near it.
std::vector<SpatialPoseEvaluation> FeasibleEquilibria(const SpatialRobot& robot, Rng& rng, int tries) {
  std::vector<SpatialPoseEvaluation> out = {EvaluateSpatialHome(robot)};
  EXPECT_TRUE(out[0].feasible()) << robot.name << ": " << ToString(out[0].feasibility);
  for (int k = 0; k < tries; ++k) {
    const SpatialPoseEvaluation e = EvaluateSpatialPose(robot, PoseNearHome(robot, rng));
    if (e.feasible()) out.push_back(e);
  }
  return out;
}

// ---- Independent constructions ------------------------------------------------------------

// The potential m g z of the centre of mass, the rotation composed by Eigen (not model/swivel.h).
double PotentialByComposition(const SpatialRobot& robot, const Pose6& q) {
  return Weight(robot) * PointByComposition(q, robot.p_P_com_m).z();
}

Eigen::VectorXd LengthsByConstruction(const SpatialRobot& robot, const Pose6& q) {
  Eigen::VectorXd l(robot.num_cables());
  for (int i = 0; i < robot.num_cables(); ++i) l(i) = SpatialLengthByConstruction(robot.cables[i], q);
  return l;
}

// d l / d q (m x 6) by central differences of the construction.
Eigen::MatrixXd LengthJacobianByDifferences(const SpatialRobot& robot, const Pose6& q, double h = kStep) {
  Eigen::MatrixXd J(robot.num_cables(), 6);
  for (int j = 0; j < 6; ++j) {
    Pose6 a = q, b = q;
    a(j) += h;
    b(j) -= h;
    J.col(j) = (LengthsByConstruction(robot, a) - LengthsByConstruction(robot, b)) / (2.0 * h);
  }
  return J;
}

Eigen::Matrix<double, 6, 1> PotentialGradientByDifferences(const SpatialRobot& robot, const Pose6& q) {
  Eigen::Matrix<double, 6, 1> g;
  for (int j = 0; j < 6; ++j) {
    Pose6 a = q, b = q;
    a(j) += kStep;
    b(j) -= kStep;
    g(j) = (PotentialByComposition(robot, a) - PotentialByComposition(robot, b)) / (2.0 * kStep);
  }
  return g;
}

// The pose nearest `q` (Gauss-Newton, minimum-norm steps) whose constructed lengths are
// `lengths_m`: a point of the constraint manifold. The steps use the model's W only as the
// iteration matrix; the fixed point is the construction's.
Pose6 ProjectOntoLengths(const SpatialRobot& robot, Pose6 q, const Eigen::VectorXd& lengths_m) {
  for (int it = 0; it < 20; ++it) {
    const Eigen::VectorXd r = LengthsByConstruction(robot, q) - lengths_m;
    if (r.cwiseAbs().maxCoeff() < 1e-15) break;
    const Eigen::MatrixXd J = -WrenchMatrix<double>(robot, q).transpose() * TwistMap<double>(q);
    q -= J.completeOrthogonalDecomposition().solve(r);
  }
  return q;
}

// The reduced Hessian of the potential on the constraint manifold {l(q) = l(q*)}, by second
// differences of the potential along the manifold: the free directions are the null space of
// the differenced length Jacobian, each pose projected back onto the lengths.
Eigen::MatrixXd ReducedHessianByDifferences(const SpatialRobot& robot, const Pose6& q_star, double eps) {
  const Eigen::VectorXd L = LengthsByConstruction(robot, q_star);
  const Eigen::MatrixXd J = LengthJacobianByDifferences(robot, q_star);
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(J, Eigen::ComputeFullV);
  int rank = 0;
  while (rank < svd.singularValues().size() && svd.singularValues()(rank) > 1e-6 * svd.singularValues()(0)) ++rank;
  const Eigen::MatrixXd N = svd.matrixV().rightCols(6 - rank);
  const double V0 = PotentialByComposition(robot, q_star);
  const auto curvature = [&](const Eigen::VectorXd& v) {  // d^2 V / d s^2 along q* + s v projected
    const Pose6 plus = ProjectOntoLengths(robot, q_star + eps * v, L);
    const Pose6 minus = ProjectOntoLengths(robot, q_star - eps * v, L);
    return (PotentialByComposition(robot, plus) + PotentialByComposition(robot, minus) - 2.0 * V0) / (eps * eps);
  };
  const int k = static_cast<int>(N.cols());
  Eigen::MatrixXd H(k, k);
  for (int a = 0; a < k; ++a) {
    H(a, a) = curvature(N.col(a));
    for (int b = 0; b < a; ++b) {
      H(a, b) = H(b, a) = 0.25 * (curvature(N.col(a) + N.col(b)) - curvature(N.col(a) - N.col(b)));
    }
  }
  return H;
}

double MinEigenvalue(const Eigen::MatrixXd& H) {
  return Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(H, Eigen::EigenvaluesOnly).eigenvalues()(0);
}

// ---- (a), (b): feasible equilibria, balance and virtual work ---------------------------------

TEST(SpatialStatics, EquilibriaBalanceWithinBoundsAndSatisfyVirtualWork) {
  Rng rng(41);
  int checked = 0, underactuated = 0;
  double worst_balance = 0.0, worst_work = 0.0;
  for (const SpatialRobot& robot : TestRobots()) {
    const double weight = Weight(robot);
    const std::vector<SpatialPoseEvaluation> poses = FeasibleEquilibria(robot, rng, 30);
    EXPECT_GE(poses.size(), 3u) << robot.name;
    for (const SpatialPoseEvaluation& e : poses) {
      const SpatialEquilibrium& eq = e.equilibrium;
      ASSERT_TRUE(e.has_equilibrium);
      ASSERT_EQ(eq.tensions_N.size(), robot.num_cables());
      const double balance = EquilibriumResidual<double>(robot, eq.q, eq.tensions_N).norm() / weight;
      EXPECT_LT(balance, kBalanceTol) << robot.name;
      EXPECT_NEAR(eq.residual_N / weight, balance, 1e-15);
      EXPECT_GE(eq.tensions_N.minCoeff(), robot.tension_min_N) << robot.name;
      EXPECT_LE(eq.tensions_N.maxCoeff(), robot.tension_max_N) << robot.name;
      EXPECT_TRUE(eq.stable);
      // The controlled coordinates are the requested pose's (home's for the first).
      // Virtual work in pose coordinates: grad V = -sum t_i grad l_i.
      const Eigen::Matrix<double, 6, 1> work = PotentialGradientByDifferences(robot, eq.q) +
                                               LengthJacobianByDifferences(robot, eq.q).transpose() * eq.tensions_N;
      EXPECT_LT(work.norm() / weight, kVirtualWorkTol) << robot.name << " q " << eq.q.transpose();
      worst_balance = std::max(worst_balance, balance);
      worst_work = std::max(worst_work, work.norm() / weight);
      underactuated += robot.num_cables() < 6;
      ++checked;
    }
  }
  EXPECT_GE(checked, 200);
  EXPECT_GE(underactuated, 40);
  std::printf("equilibria %d (%d underactuated): worst |W t + w_g| / weight %.2e, virtual work %.2e\n", checked,
              underactuated, worst_balance, worst_work);
}

// The controlled coordinates are kept: the equilibrium differs from the request only in the others.
// A robot file's home, loaded and evaluated: feasible, its equilibrium within the tension
// bounds and the tilt limit, balanced, of zero virtual work by the independent construction, and
// stable. The home's equilibrium is returned for the test's own checks (none if the file is
// refused, as it was before the walk).
std::optional<SpatialEquilibrium> ExpectHomeHeldWithinBounds(const std::string& yaml, const std::string& name,
                                                             SpatialRobot* robot) {
  try {
    *robot = LoadSpatialRobotFromString(yaml, name);
  } catch (const InputError& e) {
    ADD_FAILURE() << name << " refused: " << e.what();
    return std::nullopt;
  }
  const SpatialPoseEvaluation home = EvaluateSpatialHome(*robot);
  if (!home.feasible()) {
    ADD_FAILURE() << name << ": home " << ToString(home.feasibility);
    return std::nullopt;
  }
  const SpatialEquilibrium& eq = home.equilibrium;
  const double weight = Weight(*robot);
  EXPECT_GE(eq.tensions_N.minCoeff(), robot->tension_min_N) << name;
  EXPECT_LE(TiltAngle(eq.q), robot->tilt_max_rad) << name;
  EXPECT_LT(EquilibriumResidual<double>(*robot, eq.q, eq.tensions_N).norm() / weight, kBalanceTol) << name;
  const Eigen::Matrix<double, 6, 1> work = PotentialGradientByDifferences(*robot, eq.q) +
                                           LengthJacobianByDifferences(*robot, eq.q).transpose() * eq.tensions_N;
  EXPECT_LT(work.norm() / weight, kVirtualWorkTol) << name << " " << eq.q.transpose();
  EXPECT_TRUE(eq.stable) << name;
  return eq;
}

// A new user's 5-cable robot (eyelets, exits at five heights, its centre of mass 25 mm off):
// the equilibria at home's position and yaw form a curve in (roll, pitch, tensions), and the
// Newton steps from the starts end where a cable pushes, so home read no_equilibrium and the
// file did not load, though along the curve every cable pulls (the user found roll 6, pitch 4.9
// degrees with tensions of 13 N and more). The walk along the curve (WalkToTaut) finds such an
// equilibrium; it balances and does virtual work zero by the independent construction, within
// the bounds, stable.
TEST(SpatialStatics, FiveCablesWalkTheirCurveToWhereEveryCablePulls) {
  const std::string yaml = R"(name: lab5
kind: spatial
gravity: 9.81
frame: {min: [0.0, 0.0, 0.0], max: [3.0, 2.5, 2.5]}
platform:
  mass: 6.0
  com: [0.02, -0.015, -0.06]
  anchors: [[-0.15, -0.12, 0.05], [0.15, -0.12, 0.05], [0.15, 0.12, 0.05], [-0.15, 0.12, 0.05], [0.0, 0.14, 0.0]]
cables:
  - {exit: [0.05, 0.05, 2.40], swivel_axis: [0, 0, 1], pulley_radius: 0, stiffness: 3.0e4}
  - {exit: [2.95, 0.05, 2.30], swivel_axis: [0, 0, 1], pulley_radius: 0}
  - {exit: [2.95, 2.45, 2.45], swivel_axis: [0, 0, 1], pulley_radius: 0, stiffness: 5.0e4}
  - {exit: [0.05, 2.45, 2.35], swivel_axis: [0, 0, 1], pulley_radius: 0}
  - {exit: [1.50, 2.45, 2.20], swivel_axis: [0, 0, 1], pulley_radius: 0}
tension: {min: 5.0, max: 300.0}
limits: {tilt_max_deg: 25, margin: 0.05}
home: [1.5, 1.2, 1.2]
sensors:
  encoder: {sigma: 0.00005}
)";
  SpatialRobot robot;
  const std::optional<SpatialEquilibrium> held = ExpectHomeHeldWithinBounds(yaml, "lab5.yaml", &robot);
  ASSERT_TRUE(held);
  const SpatialEquilibrium& eq = *held;
  const double weight = Weight(robot);
  EXPECT_EQ(eq.q.head<3>(), robot.p_F_home_m);
  EXPECT_EQ(eq.q(5), 0.0);  // the yaw is held
  // Around home, on a coarse grid at its height: the points found feasible are balanced
  // equilibria too.
  int more = 0;
  for (double x = 1.0; x <= 2.01; x += 0.25) {
    for (double y = 0.7; y <= 1.71; y += 0.25) {
      SpatialPose<double> q = robot.home_pose();
      q(0) = x;
      q(1) = y;
      const SpatialPoseEvaluation e = EvaluateSpatialPose(robot, q);
      if (!e.feasible()) continue;
      ++more;
      EXPECT_LT(EquilibriumResidual<double>(robot, e.equilibrium.q, e.equilibrium.tensions_N).norm() / weight,
                kBalanceTol);
    }
  }
  EXPECT_GE(more, 5);
}

// A second new user's 5-cable robot: its home's nearest equilibrium holds cable 3 at 1.8 N,
// below tension.min (3 N), while further along the curve (roll -7.8, pitch -3.8 degrees) every
// cable pulls with 8 N or more. The walk runs from a found root below the bound too, so the
// home loads; the equilibrium it gives balances and keeps the bounds.
TEST(SpatialStatics, FiveCablesWalkFromARootBelowTheTensionBound) {
  const std::string yaml = R"(name: labB5
kind: spatial
gravity: 9.81
frame: {min: [-1.5, -1.0, 0.2], max: [1.5, 1.0, 2.4]}
platform:
  mass: 4.0
  com: [-0.015, 0.02, -0.05]
  anchors: [[-0.10, -0.08, 0.04], [0.10, -0.08, 0.04], [0.12, 0.06, 0.04], [-0.12, 0.06, 0.04], [0.0, 0.10, 0.02]]
cables:
  - {exit: [-1.45, -0.95, 2.35], swivel_axis: [0, 0, 1], pulley_radius: 0.02}
  - {exit: [1.45, -0.95, 2.20], swivel_axis: [-0.2588, 0, 0.9659], pulley_radius: 0.03, stiffness: 2.0e4}
  - {exit: [1.40, 0.95, 2.30], swivel_axis: [0, 0, 1], pulley_radius: 0.0}
  - {exit: [-1.40, 0.95, 2.05], swivel_axis: [0, 0, 1], pulley_radius: 0.015}
  - {exit: [0.0, 0.98, 2.38], swivel_axis: [0, 0, 1], pulley_radius: 0.04, stiffness: 3.0e4}
tension: {min: 3.0, max: 200.0}
limits: {tilt_max_deg: 25, margin: 0.04}
home: [0.0, 0.0, 1.2]
sensors:
  encoder: {sigma: 0.0001}
)";
  SpatialRobot robot;
  ExpectHomeHeldWithinBounds(yaml, "labB5.yaml", &robot);
}

TEST(SpatialStatics, ControlledCoordinatesAreKept) {
  Rng rng(43);
  for (const SpatialRobot& robot : TestRobots()) {
    const std::vector<int> controlled = ControlledCoordinates(robot);
    EXPECT_EQ(controlled.size(), robot.num_cables() >= 6 ? 6u : robot.num_cables() >= 4 ? 4u : 3u);
    for (int k = 0; k < 5; ++k) {
      const Pose6 q = PoseNearHome(robot, rng);
      const SpatialPoseEvaluation e = EvaluateSpatialPose(robot, q);
      if (!e.has_equilibrium) continue;
      for (int j : controlled) EXPECT_EQ(e.equilibrium.q(j), q(j)) << robot.name << " coordinate " << j;
    }
  }
}

// ---- (c): stability against the potential along the allowed motions --------------------------

TEST(SpatialStability, ReducedHessianMatchesThePotentialAlongTheManifold) {
  Rng rng(47);
  int compared = 0;
  double worst = 0.0;
  for (const SpatialRobot& robot : TestRobots()) {
    if (robot.num_cables() >= 6) continue;
    const std::vector<SpatialPoseEvaluation> poses = FeasibleEquilibria(robot, rng, 6);
    for (const SpatialPoseEvaluation& e : poses) {
      const SpatialEquilibrium& eq = e.equilibrium;
      const StabilityResult s = StaticStability(robot, eq.q, eq.tensions_N, InextensibleCables(robot.num_cables()));
      EXPECT_EQ(s.free_motions, 6 - robot.num_cables());
      EXPECT_EQ(eq.reduced_stiffness, s.min_eigenvalue);
      const double by_differences = MinEigenvalue(ReducedHessianByDifferences(robot, eq.q, 3e-4));
      EXPECT_GT(by_differences, 0.0) << robot.name;  // the potential rises along every allowed motion
      const double tol = 1e-3 * std::abs(s.min_eigenvalue) + 1e-6 * Weight(robot);
      EXPECT_NEAR(by_differences, s.min_eigenvalue, tol) << robot.name;
      worst = std::max(worst, std::abs(by_differences - s.min_eigenvalue) / std::abs(s.min_eigenvalue));
      ++compared;
    }
  }
  EXPECT_GE(compared, 30);
  std::printf("reduced Hessians compared %d: worst relative difference %.2e\n", compared, worst);
}

// Three cables from exits at 120 degrees to anchors at 120 degrees, the centre of mass on the
// axis: level is an equilibrium with equal tensions by symmetry. Centre of mass below the
// anchors: a pendulum, stable; 0.6 m above them (an inverted pendulum on cables; the least
// curvature changes sign at about 0.24 m): unstable.
SpatialRobot SymmetricThreeCables(double com_height_m) {
  SpatialRobot r;
  r.name = "symmetric3";
  r.source = "symmetric3";
  r.p_F_frame_min_m = Eigen::Vector3d(-2.0, -2.0, 0.0);
  r.p_F_frame_max_m = Eigen::Vector3d(2.0, 2.0, 4.0);
  r.platform_mass_kg = 20.0;
  r.sensors.encoder_sigma_m = 1e-4;
  r.p_P_com_m = Eigen::Vector3d(0.0, 0.0, com_height_m);
  for (int i = 0; i < 3; ++i) {
    const double a = 2.0 * M_PI * i / 3.0;
    SpatialCable c;
    c.p_F_exit_m = Eigen::Vector3d(1.8 * std::cos(a), 1.8 * std::sin(a), 3.0);
    c.k_F_swivel_axis = Eigen::Vector3d::UnitZ();
    c.pulley_radius_m = 0.03;
    c.p_P_anchor_m = Eigen::Vector3d(0.3 * std::cos(a), 0.3 * std::sin(a), 0.0);
    r.cables.push_back(c);
  }
  r.tension_min_N = 1.0;
  r.tension_max_N = 1000.0;
  r.tilt_max_rad = 30.0 * kDegToRad;
  r.margin_m = 0.05;
  r.p_F_home_m = Eigen::Vector3d(0.0, 0.0, 1.5);
  return r;
}

// The level equilibrium's tensions: equal by symmetry, from the vertical balance.
Eigen::VectorXd LevelTensions(const SpatialRobot& r) {
  const Pose6 q = r.home_pose();
  const Eigen::Matrix<double, 6, Eigen::Dynamic> W = WrenchMatrix<double>(r, q);
  return Eigen::VectorXd::Constant(3, Weight(r) / W.row(2).sum());
}

TEST(SpatialStability, HighCentreOfMassIsUnstableAndLowIsStable) {
  for (const double com_height : {-0.5, 0.6}) {
    const SpatialRobot r = SymmetricThreeCables(com_height);
    const Pose6 q = r.home_pose();
    const Eigen::VectorXd t = LevelTensions(r);
    ASSERT_LT(EquilibriumResidual<double>(r, q, t).norm(), 1e-12 * Weight(r));
    const StabilityResult s = StaticStability(r, q, t, InextensibleCables(3));
    const double by_differences = MinEigenvalue(ReducedHessianByDifferences(r, q, 1e-3));
    EXPECT_EQ(s.free_motions, 3);
    EXPECT_NEAR(by_differences, s.min_eigenvalue, 1e-3 * std::abs(s.min_eigenvalue)) << com_height;
    if (com_height < 0.0) {
      EXPECT_GT(s.min_eigenvalue, 0.0);
      EXPECT_TRUE(s.stable);
      EXPECT_TRUE(EvaluateSpatialPose(r, q).feasible());
    } else {
      // The potential falls along some allowed motion.
      EXPECT_LT(by_differences, 0.0);
      EXPECT_FALSE(s.stable);
      EXPECT_EQ(EvaluateSpatialPose(r, q).feasibility, Feasibility::kUnstable);
    }
  }
}

// Elastic cables add their axial stiffness: with every cable elastic nothing is constrained
// (free motions 6) and the Hessian is the geometric one plus sum k_i grad l_i grad l_i';
// a stiff cable (k -> infinity) leaves the constrained directions' curvature unchanged and
// the others growing like k. Slack cables (k = 0) carry nothing whatever the tension says.
TEST(SpatialStability, ElasticAndSlackCables) {
  const SpatialRobot r = SymmetricThreeCables(-0.5);
  const Pose6 q = r.home_pose();
  const Eigen::VectorXd t = LevelTensions(r);
  const StabilityResult rigid = StaticStability(r, q, t, InextensibleCables(3));
  const StabilityResult stiff = StaticStability(r, q, t, Eigen::VectorXd::Constant(3, 1e9));
  EXPECT_EQ(stiff.free_motions, 6);
  EXPECT_NEAR(stiff.min_eigenvalue, rigid.min_eigenvalue, 1e-4 * rigid.min_eigenvalue);
  // One slack cable: the other two cannot hold the platform's three free rotations and
  // translations; the Hessian with one cable dropped has a direction of no restoring force at
  // most (a pendulum on two cables swings freely about their line only to second order).
  Eigen::VectorXd k = InextensibleCables(3);
  k(2) = 0.0;
  const StabilityResult slack = StaticStability(r, q, t, k);
  EXPECT_EQ(slack.free_motions, 4);
  Eigen::VectorXd t_big = t;
  t_big(2) = 1e6;  // ignored: slack
  EXPECT_EQ(StaticStability(r, q, t_big, k).min_eigenvalue, slack.min_eigenvalue);
  // No free motion: held.
  const SpatialRobot ipanema = BuiltIn("ipanema1.yaml");
  const SpatialPoseEvaluation home = EvaluateSpatialHome(ipanema);
  const StabilityResult held = StaticStability(ipanema, home.equilibrium.q, home.equilibrium.tensions_N,
                                               InextensibleCables(ipanema.num_cables()));
  EXPECT_EQ(held.free_motions, 0);
  EXPECT_TRUE(held.stable);
  EXPECT_TRUE(std::isnan(held.min_eigenvalue));
}

// The planar 2-cable reduced stiffness is the same function: against the former closed form,
// n' K n with n the unit normal of W's two columns and K = -d(W t + w_g)/dq by differences.
TEST(SpatialStability, PlanarReducedStiffnessAgreesWithTheNormalOfW) {
  const Robot robot = PlanarFile("wang2022.yaml");
  int compared = 0;
  for (double x = 0.6; x < robot.frame_width_m - 0.5; x += 0.4) {
    for (double z = 0.5; z < robot.frame_height_m - 0.3; z += 0.3) {
      const EquilibriumResult eq = SolveEquilibrium(robot, x, z);
      if (eq.status != EquilibriumStatus::kFound) continue;
      const Eigen::Vector3d q = eq.equilibrium.q;
      const Eigen::VectorXd& t = eq.equilibrium.tensions_N;
      const Eigen::Matrix<double, 3, Eigen::Dynamic> W = WrenchMatrix<double>(robot, Pose<double>(q));
      const Eigen::Vector3d n = W.col(0).cross(W.col(1)).normalized();
      Eigen::Matrix3d K;
      for (int j = 0; j < 3; ++j) {
        Eigen::Vector3d a = q, b = q;
        a(j) += 1e-6;
        b(j) -= 1e-6;
        K.col(j) = -(EquilibriumResidual<double>(robot, Pose<double>(a), t) -
                     EquilibriumResidual<double>(robot, Pose<double>(b), t)) / 2e-6;
      }
      const double expected = n.dot(K * n);
      EXPECT_NEAR(ReducedStiffness(robot, q, t), expected, 1e-6 * std::abs(expected));
      EXPECT_NEAR(eq.equilibrium.reduced_stiffness, expected, 1e-6 * std::abs(expected));
      ++compared;
    }
  }
  EXPECT_GE(compared, 10);
}

// ---- (d): planar robots placed in space --------------------------------------------------

// The planar pose (x, z, theta) as the spatial pose (x, 0, z, 0, -theta, 0) (model/kind.h).
Pose6 SpatialOfPlanar(const Eigen::Vector3d& q) {
  Pose6 s;
  s << q(0), 0.0, q(1), 0.0, -q(2), 0.0;
  return s;
}

// The planar equilibria of a grid of positions (m = 2: the equilibrium's theta; m >= 3: the
// feasible theta at the middle of the band ScanTheta finds).
std::vector<PoseEvaluation> PlanarEquilibria(const Robot& robot) {
  std::vector<PoseEvaluation> out;
  for (double x = 0.1; x < 1.0; x += 0.1) {
    for (double z = 0.1; z < 1.0; z += 0.1) {
      const double px = x * robot.frame_width_m, pz = z * robot.frame_height_m;
      const PoseEvaluation e = robot.theta_is_free() ? ScanTheta(robot, px, pz).evaluation : EvaluatePose(robot, px, pz);
      if (e.feasible()) out.push_back(e);
    }
  }
  return out;
}

// Placed in space, a planar robot's equilibria are spatial ones: the same pose and tensions
// where the spatial solver finds them, and it finds them wherever they are stable in space too.
// What is true out of the plane, measured: the asymmetric 2-cable and the 3-cable suspended
// robots hang like pendulums, stable at every planar equilibrium sampled; wang2022's bar has its
// centre of mass on its anchors' line, so it spins freely about that line (neutral: the least
// curvature is rounding, +-1e-14, not stable); the 4-cable fully constrained robot's lower
// cables tip it out of the plane (unstable; SwivelPlanarEquivalence in swivel_test).
TEST(SpatialStatics, PlanarRobotsInSpaceHaveThePlanarEquilibria) {
  for (const char* file : {"wang2022.yaml", "asymmetric.yaml", "planar3_suspended.yaml", "planar4_fully_constrained.yaml"}) {
    const Robot planar = PlanarFile(file);
    const SpatialRobot spatial = PlanarAsSpatial(planar);
    const double weight = planar.platform_mass_kg * planar.gravity_mps2;
    int found = 0, unstable_in_space = 0;
    for (const PoseEvaluation& e : PlanarEquilibria(planar)) {
      const Pose6 q = SpatialOfPlanar(e.equilibrium.q);
      const Eigen::VectorXd& t = e.equilibrium.tensions_N;
      // The planar equilibrium balances the spatial platform.
      EXPECT_LT(EquilibriumResidual<double>(spatial, q, t).norm(), 1e-9 * weight) << file;
      const StabilityResult s = StaticStability(spatial, q, t, InextensibleCables(planar.num_cables()));
      if (!s.stable) {
        ++unstable_in_space;
        continue;
      }
      // m = 2: the solver starts level and must find theta; m >= 3: the planar theta is one
      // of a band, so the guess carries it.
      Pose6 guess = q;
      if (planar.num_cables() == 2) guess(4) = 0.0;
      const SpatialEquilibriumResult r = SolveSpatialEquilibrium(spatial, guess);
      ASSERT_EQ(r.status, EquilibriumStatus::kFound) << file << " at " << q.transpose();
      EXPECT_LT((r.equilibrium.q - q).cwiseAbs().maxCoeff(), 1e-9) << file << " at " << q.transpose();
      EXPECT_LT((r.equilibrium.tensions_N - t).cwiseAbs().maxCoeff(), 1e-9 * weight) << file;
      // In space the in-plane motion is one of the free ones: its curvature bounds the least.
      if (planar.num_cables() == 2) {
        EXPECT_LE(r.equilibrium.reduced_stiffness, e.equilibrium.reduced_stiffness * (1.0 + 1e-9)) << file;
      }
      ++found;
    }
    std::printf("%s in space: %d planar equilibria found stable, %d unstable out of the plane\n", file, found,
                unstable_in_space);
    if (std::string(file) == "wang2022.yaml") {
      EXPECT_EQ(found, 0);
      EXPECT_GE(unstable_in_space, 15);
      EXPECT_EQ(EvaluateSpatialPose(spatial, spatial.home_pose()).feasibility, Feasibility::kUnstable);
    } else if (planar.num_cables() <= 3) {
      EXPECT_GE(found, 15) << file;
      EXPECT_EQ(unstable_in_space, 0) << file;
    } else {
      EXPECT_EQ(found, 0) << file;
      EXPECT_GE(unstable_in_space, 15) << file;
    }
  }
}

// ---- (e): each feasibility reason at a pose built for it -----------------------------------

// A 6-cable robot in general position: a random one (its home is feasible: the loader says so).
SpatialRobot SixCables() {
  Rng rng(61);
  return testing::RandomSpatialRobot(rng, "six", 6);
}

// The pose, near `q`, that puts cable i's anchor at the point p_F (the position moved).
Pose6 WithAnchorAt(const SpatialRobot& r, const Pose6& q, int i, const Eigen::Vector3d& p_F) {
  Pose6 out = q;
  out.head<3>() = p_F - Rotation<double>(q) * r.cables[i].p_P_anchor_m;
  return out;
}

TEST(SpatialFeasibility, EachReasonAtAPoseBuiltForIt) {
  const SpatialRobot six = SixCables();
  const Pose6 home = six.home_pose();
  const SpatialPoseEvaluation at_home = EvaluateSpatialHome(six);
  ASSERT_TRUE(at_home.feasible()) << ToString(at_home.feasibility);
  EXPECT_EQ(at_home.cable, -1);

  // outside_frame: the reference point, then only an anchor, beyond the box less the margin.
  Pose6 q = home;
  q(0) = six.p_F_frame_max_m.x() - 0.04;
  EXPECT_EQ(EvaluateSpatialPose(six, q).feasibility, Feasibility::kOutsideFrame);
  double reach_x = 0.0;  // the anchors' largest x offset from p at home
  for (const SpatialCable& c : six.cables) reach_x = std::max(reach_x, (Rotation<double>(home) * c.p_P_anchor_m).x());
  ASSERT_GT(reach_x, 0.02);
  q(0) = six.p_F_frame_max_m.x() - six.margin_m - 0.5 * reach_x;  // p inside, that anchor beyond
  ASSERT_TRUE(CableGeometryAt(six, q).valid());
  EXPECT_EQ(EvaluateSpatialPose(six, q).feasibility, Feasibility::kOutsideFrame);

  // tilt_limit: a roll 5 degrees beyond the limit, every cable valid and the platform inside.
  q = home;
  q(3) = six.tilt_max_rad + 5.0 * kDegToRad;
  EXPECT_TRUE(CableGeometryAt(six, q).valid());
  EXPECT_EQ(EvaluateSpatialPose(six, q).feasibility, Feasibility::kTiltLimit);

  // Cable geometry: cable 0 (an upper exit, axis +z; the pulley beside its exit) with its anchor
  // on the swivel axis below the exit, within the pulley's circle, and behind the pulley near the
  // axis (a wrap beyond 270 degrees). Checked against model/swivel.h's own reason first.
  SpatialRobot inner = six;  // an exit inside the frame so that the platform can reach it
  inner.cables[0].p_F_exit_m = home.head<3>() + Eigen::Vector3d(-0.6, -0.4, 0.9);
  inner.cables[0].k_F_swivel_axis = Eigen::Vector3d::UnitZ();
  inner.cables[0].pulley_radius_m = 0.04;
  const SpatialCable& c0 = inner.cables[0];
  const double r0 = c0.pulley_radius_m;
  const Eigen::Vector3d u = Eigen::Vector3d(1.0, 0.0, 0.0);  // toward the anchor, normal to k
  const struct {
    Eigen::Vector3d p_F_anchor;
    SwivelGeometry geometry;
    Feasibility reason;
  } cases[] = {
      {c0.p_F_exit_m - 0.8 * c0.k_F_swivel_axis, SwivelGeometry::kSwivelAxis, Feasibility::kSwivelAxis},
      {c0.p_F_exit_m + r0 * u - 0.5 * r0 * c0.k_F_swivel_axis, SwivelGeometry::kInsidePulley,
       Feasibility::kInsidePulley},
      // m = (-0.9 r, -0.5 r) in the pulley plane: just outside the pulley, wrapped 317 degrees.
      {c0.p_F_exit_m + 0.1 * r0 * u - 0.5 * r0 * c0.k_F_swivel_axis, SwivelGeometry::kWrap, Feasibility::kWrap},
  };
  for (const auto& k : cases) {
    const Pose6 at = WithAnchorAt(inner, home, 0, k.p_F_anchor);
    ASSERT_EQ(SwivelCable<double>(c0.p_F_exit_m, c0.k_F_swivel_axis, r0, k.p_F_anchor).geometry, k.geometry);
    const SpatialPoseEvaluation e = EvaluateSpatialPose(inner, at);
    EXPECT_EQ(e.feasibility, k.reason) << ToString(k.geometry);
    EXPECT_EQ(e.cable, 0);
    int cable = -1;
    EXPECT_EQ(CheckSpatialFeasibility(inner, at, at_home.equilibrium.tensions_N, &cable), k.reason);
    EXPECT_EQ(cable, 0);
  }
  // inside_pulley by the clearance alone: valid geometry, the anchor 0.03 m from the pulley.
  {
    const Eigen::Vector3d p = c0.p_F_exit_m + r0 * u + (r0 + 0.03) * Eigen::Vector3d(1.0, 0.0, -1.0).normalized();
    const Pose6 at = WithAnchorAt(inner, home, 0, p);
    ASSERT_TRUE(SwivelCable<double>(c0.p_F_exit_m, c0.k_F_swivel_axis, r0, p).valid());
    const SpatialPoseEvaluation e = EvaluateSpatialPose(inner, at);
    EXPECT_EQ(e.feasibility, Feasibility::kInsidePulley);
    EXPECT_EQ(e.cable, 0);
  }

  // no_equilibrium: every exit on the x = -2 wall (at various heights), the platform at x = 1:
  // each cable pulls toward -x and nothing pulls toward +x, so no t > 0 balances the force.
  SpatialRobot wall = six;
  const Eigen::Vector3d lo = six.p_F_frame_min_m, hi = six.p_F_frame_max_m;
  for (int i = 0; i < 6; ++i) {
    wall.cables[i].p_F_exit_m = Eigen::Vector3d(lo.x(), lo.y() + (hi.y() - lo.y()) * (i + 0.5) / 6.0, i % 2 ? hi.z() : lo.z());
    wall.cables[i].k_F_swivel_axis = Eigen::Vector3d(0.0, 0.0, i % 2 ? 1.0 : -1.0);
  }
  q = home;
  q(0) = hi.x() - 0.5;
  ASSERT_TRUE(CableGeometryAt(wall, q).valid());
  EXPECT_EQ(EvaluateSpatialPose(wall, q).feasibility, Feasibility::kNoEquilibrium);

  // tension_low, tension_high: the unique tensions at home against bounds moved past them.
  const Eigen::VectorXd t = at_home.equilibrium.tensions_N;
  SpatialRobot low = six, high = six;
  low.tension_min_N = t.minCoeff() + 1.0;
  high.tension_max_N = t.maxCoeff() - 1.0;
  EXPECT_EQ(EvaluateSpatialPose(low, home).feasibility, Feasibility::kTensionLow);
  EXPECT_EQ(EvaluateSpatialPose(high, home).feasibility, Feasibility::kTensionHigh);
  EXPECT_EQ(CheckSpatialFeasibility(low, home, t), Feasibility::kTensionLow);
  EXPECT_EQ(CheckSpatialFeasibility(high, home, t), Feasibility::kTensionHigh);

  // Underactuated: unstable (the inverted pendulum above), tension_high and tilt_limit at
  // the equilibrium, and the frame test on the requested position.
  EXPECT_EQ(EvaluateSpatialPose(SymmetricThreeCables(0.6), SymmetricThreeCables(0.6).home_pose()).feasibility,
            Feasibility::kUnstable);
  SpatialRobot heavy = SymmetricThreeCables(-0.5);
  heavy.tension_max_N = 50.0;
  const SpatialPoseEvaluation h = EvaluateSpatialPose(heavy, heavy.home_pose());
  EXPECT_EQ(h.feasibility, Feasibility::kTensionHigh);
  EXPECT_TRUE(h.has_equilibrium);
  SpatialRobot lopsided = SymmetricThreeCables(-0.5);
  lopsided.p_P_com_m.x() = 0.6;  // the platform tilts until the centre of mass hangs below the cables' meeting point
  const SpatialPoseEvaluation tilted = EvaluateSpatialPose(lopsided, lopsided.home_pose());
  EXPECT_EQ(tilted.feasibility, Feasibility::kTiltLimit);
  EXPECT_GT(TiltAngle(tilted.equilibrium.q), lopsided.tilt_max_rad);
  q = heavy.home_pose();
  q(2) = heavy.p_F_frame_min_m.z() + 0.01;
  EXPECT_EQ(EvaluateSpatialPose(heavy, q).feasibility, Feasibility::kOutsideFrame);

  // The names.
  EXPECT_STREQ(ToString(Feasibility::kTiltLimit), "tilt_limit");
  EXPECT_STREQ(ToString(Feasibility::kSwivelAxis), "swivel_axis");
  EXPECT_STREQ(ToString(Feasibility::kInsidePulley), "inside_pulley");
  EXPECT_STREQ(ToString(Feasibility::kWrap), "wrap");
}

// The loader refuses a home that is not a feasible, stable equilibrium, naming `home`.
TEST(SpatialFeasibility, LoaderRefusesAnInfeasibleHome) {
  const auto message = [](const SpatialRobot& r) {
    try {
      LoadSpatialRobotFromString(SpatialRobotToYaml(r), "bad.yaml");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_EQ(message(SymmetricThreeCables(-0.5)), "");
  const std::string unstable = message(SymmetricThreeCables(0.6));
  EXPECT_NE(unstable.find(" degrees (home_rpy_deg) is not in the feasible workspace: unstable"),
            std::string::npos)
      << unstable;
  SpatialRobot high = SixCables();
  high.tension_max_N = EvaluateSpatialHome(high).equilibrium.tensions_N.maxCoeff() - 1.0;
  const std::string tension = message(high);
  EXPECT_NE(tension.find(": home: the home pose ("), std::string::npos) << tension;
  EXPECT_NE(tension.find(" degrees (home_rpy_deg) is not in the feasible workspace: tension_high (cable "), std::string::npos)
      << tension;
  EXPECT_NE(tension.find("; tensions ("), std::string::npos) << tension;
  EXPECT_THROW(SpatialHomeEvaluation(high), InputError);
  EXPECT_THROW(SpatialHomeLengths(high), InputError);
  const SpatialRobot six = SixCables();
  EXPECT_EQ(SpatialHomeLengths(six), CableLengths<double>(six, six.home_pose()));
}

// ---- (f): m >= 7, the minimum-norm tensions within bounds ---------------------------------

// The point of {W t = b, lo <= t <= hi} nearest 0, by Dykstra's alternating projections onto
// the affine set and the box (no least-distance solver, no active set).
Eigen::VectorXd NearestToZeroByDykstra(const Eigen::MatrixXd& W, const Eigen::VectorXd& b, double lo, double hi) {
  const Eigen::MatrixXd WWt_inv = (W * W.transpose()).inverse();
  const auto affine = [&](const Eigen::VectorXd& x) { return Eigen::VectorXd(x - W.transpose() * (WWt_inv * (W * x - b))); };
  const int m = static_cast<int>(W.cols());
  Eigen::VectorXd x = Eigen::VectorXd::Zero(m), p = Eigen::VectorXd::Zero(m), q = Eigen::VectorXd::Zero(m);
  for (int it = 0; it < 200000; ++it) {
    const Eigen::VectorXd y = affine(x + p);
    p = x + p - y;
    const Eigen::VectorXd x_new = (y + q).cwiseMax(lo).cwiseMin(hi);
    q = y + q - x_new;
    const double change = (x_new - x).norm();
    x = x_new;
    if (change < 1e-13 * (1.0 + x.norm()) && (W * x - b).norm() < 1e-11 * (1.0 + b.norm())) break;
  }
  return x;
}

TEST(SpatialStatics, RedundantRobotsTakeTheMinimumNormTensionsWithinBounds) {
  Rng rng(53);
  int compared = 0;
  double worst = 0.0;
  for (const SpatialRobot& robot : TestRobots()) {
    if (robot.num_cables() < 7) continue;
    for (const SpatialPoseEvaluation& e : FeasibleEquilibria(robot, rng, 6)) {
      const Pose6& q = e.equilibrium.q;
      const Eigen::VectorXd& t = e.equilibrium.tensions_N;
      const Eigen::VectorXd expected = NearestToZeroByDykstra(WrenchMatrix<double>(robot, q), -GravityWrench<double>(robot, q),
                                                              robot.tension_min_N, robot.tension_max_N);
      EXPECT_LT((t - expected).norm(), 1e-6 * expected.norm()) << robot.name;
      EXPECT_GE(t.minCoeff(), robot.tension_min_N);
      EXPECT_LE(t.maxCoeff(), robot.tension_max_N);
      worst = std::max(worst, (t - expected).norm() / expected.norm());
      ++compared;
    }
  }
  EXPECT_GE(compared, 40);
  std::printf("m >= 7 tension distributions compared %d: worst relative difference from Dykstra's %.2e\n", compared,
              worst);
}

}  // namespace
}  // namespace cablecal
