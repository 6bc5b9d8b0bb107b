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
    const std::vector<SpatialPoseEvaluation> poses = FeasibleEquilibria(robot, rng, 12);
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
// axis: level is an equilibrium with equal tensions by symmetry. Centre of mass far below the
// anchors: a pendulum, stable; far above (an inverted pendulum on cables): unstable.
SpatialRobot SymmetricThreeCables(double com_height_m) {
  SpatialRobot r;
  r.name = "symmetric3";
  r.source = "symmetric3";
  r.p_F_frame_min_m = Eigen::Vector3d(-2.0, -2.0, 0.0);
  r.p_F_frame_max_m = Eigen::Vector3d(2.0, 2.0, 3.0);
  r.platform_mass_kg = 20.0;
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
  for (const double com_height : {-0.5, 2.0}) {
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

}  // namespace
}  // namespace cablecal
