// Equilibrium, stability, inverse and forward geometrico-static models.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>

#include "common/random.h"
#include "model/cable.h"
#include "model/statics.h"
#include "tests/support/cable_construction.h"

namespace cablecal {
namespace {

constexpr double kEquilibriumTol_N = 1e-9;
constexpr double kRoundTripTol = 1e-9;  // m and rad: forward(inverse(pose))
// Central differences of lengths at a 1e-5 step, times the tensions: rounding of up to 9e-8 N
// over the grid below; an error in the model's statics is orders of magnitude larger.
constexpr double kVirtualWorkTol_N = 1e-6;

TEST(Equilibrium, SymmetricRobotCentredPoseIsLevelWithEqualTensions) {
  const Robot& robot = BuiltinRobot();
  const double x_centre = robot.frame_width_m / 2;
  for (const double z : {0.5, 1.4, 2.2}) {
    const EquilibriumResult r = SolveEquilibrium(robot, x_centre, z);
    ASSERT_EQ(r.status, EquilibriumStatus::kFound) << "z = " << z;
    EXPECT_NEAR(r.equilibrium.q(2), 0.0, 1e-12);
    EXPECT_NEAR(r.equilibrium.tensions_N(0), r.equilibrium.tensions_N(1), 1e-9);
    EXPECT_TRUE(r.equilibrium.stable);
    // Vertical balance: the two tensions' vertical parts carry the weight.
    const Eigen::Matrix<double, 3, Eigen::Dynamic> W = WrenchMatrix<double>(robot, r.equilibrium.q);
    EXPECT_NEAR(W.row(1).dot(r.equilibrium.tensions_N), robot.platform_mass_kg * robot.gravity_mps2, 1e-9);
  }
}

// The equilibrium's residual by virtual work, built apart from the wrench matrix and the gravity
// wrench the solver balances (recomputing EquilibriumResidual would repeat any error in them):
// for each pose coordinate, the work -sum t_i dl_i / dq of the tensions and -m g dz_com / dq of
// gravity, the lengths by the tangency construction, the derivatives by central differences.
Eigen::Vector3d ResidualByVirtualWork(const Robot& robot, const Eigen::Vector3d& q, const Eigen::VectorXd& t) {
  constexpr double kStep = 1e-5;  // m and rad
  const auto com_height = [&](const Eigen::Vector3d& p) {
    return p(1) + std::sin(p(2)) * robot.p_P_com_m.x() + std::cos(p(2)) * robot.p_P_com_m.y();
  };
  Eigen::Vector3d residual;
  for (int k = 0; k < 3; ++k) {
    Eigen::Vector3d up = q, down = q;
    up(k) += kStep;
    down(k) -= kStep;
    double work = -robot.platform_mass_kg * robot.gravity_mps2 * (com_height(up) - com_height(down));
    for (int i = 0; i < robot.num_cables(); ++i) {
      work -= t(i) * (testing::CableLengthByConstruction(robot.cables[i], up) -
                      testing::CableLengthByConstruction(robot.cables[i], down));
    }
    residual(k) = work / (2 * kStep);
  }
  return residual;
}

TEST(Equilibrium, ResidualBelowToleranceOverFeasibleGrid) {
  // The seed robot, and one whose centre of mass is off the bar's centre so that gravity has a
  // moment about p.
  Robot off_centre = BuiltinRobot();
  off_centre.p_P_com_m = Eigen::Vector2d(0.04, -0.03);
  for (const Robot& robot : {BuiltinRobot(), off_centre}) {
    int feasible = 0;
    for (double z = 0.0; z <= robot.frame_height_m; z += 0.1) {
      for (double x = 0.0; x <= robot.frame_width_m; x += 0.1) {
        const PoseEvaluation e = EvaluatePose(robot, x, z);
        if (!e.feasible()) continue;
        ++feasible;
        EXPECT_LT(e.equilibrium.residual_N, kEquilibriumTol_N) << "at " << x << ", " << z;
        EXPECT_LT(ResidualByVirtualWork(robot, e.equilibrium.q, e.equilibrium.tensions_N).norm(), kVirtualWorkTol_N)
            << "at " << x << ", " << z << ", centre of mass " << robot.p_P_com_m.transpose();
        EXPECT_GT(e.equilibrium.reduced_stiffness, 0.0);
      }
    }
    EXPECT_GT(feasible, 300);  // the seed robot's workspace is most of the frame's lower part
  }
}

TEST(Equilibrium, OffCentreThetaTiltsTowardTheNearerPost) {
  // Physically: nearer the left post, the left cable is steeper; the platform tilts so that
  // both cable lines and the vertical through the centre of mass meet in one point.
  const Robot& robot = BuiltinRobot();
  const EquilibriumResult left = SolveEquilibrium(robot, 1.0, 1.4);
  const EquilibriumResult right = SolveEquilibrium(robot, robot.frame_width_m - 1.0, 1.4);
  ASSERT_EQ(left.status, EquilibriumStatus::kFound);
  ASSERT_EQ(right.status, EquilibriumStatus::kFound);
  EXPECT_NEAR(left.equilibrium.q(2), -right.equilibrium.q(2), 1e-10);  // mirror symmetry
  EXPECT_NE(left.equilibrium.q(2), 0.0);
  // Concurrency of the three forces: the cable lines meet on the vertical through the COM.
  const Eigen::Vector3d q = left.equilibrium.q;
  Eigen::Matrix2d lines;
  Eigen::Vector2d rhs;
  const CableState<double> c1 = CableAtPose<double>(robot.cables[0], q);
  const CableState<double> c2 = CableAtPose<double>(robot.cables[1], q);
  const Eigen::Vector2d B1 = PlatformPointInF<double>(q, robot.cables[0].p_P_anchor_m);
  const Eigen::Vector2d B2 = PlatformPointInF<double>(q, robot.cables[1].p_P_anchor_m);
  lines << c1.u_F_cable, -c2.u_F_cable;  // B1 + a u1 = B2 + b u2
  rhs = B2 - B1;
  const Eigen::Vector2d ab = lines.colPivHouseholderQr().solve(rhs);
  const Eigen::Vector2d meet = B1 + ab(0) * c1.u_F_cable;
  EXPECT_NEAR(meet.x(), PlatformPointInF<double>(q, robot.p_P_com_m).x(), 1e-9);
}

// Moves the platform along the one motion that keeps both cable lengths, parametrised by
// theta, and returns the potential energy there (independent of the stiffness formula).
double EnergyAlongFixedLengths(const Robot& robot, const Eigen::Vector3d& q0, const Eigen::VectorXd& L,
                               double theta) {
  Eigen::Vector2d p = q0.head<2>();
  for (int it = 0; it < 50; ++it) {
    const Eigen::Vector3d q(p.x(), p.y(), theta);
    const Eigen::VectorXd r = CableLengths(robot, q) - L;
    if (r.cwiseAbs().maxCoeff() < 1e-15) break;
    const Eigen::Matrix<double, 3, Eigen::Dynamic> W = WrenchMatrix<double>(robot, q);
    const Eigen::Matrix2d J = -W.topRows<2>().transpose();  // dl/d(x, z)
    p -= J.lu().solve(r);
  }
  return PotentialEnergy<double>(robot, Eigen::Vector3d(p.x(), p.y(), theta));
}

TEST(Stability, ReducedStiffnessMatchesEnergyCurvatureAlongFreeMotion) {
  const Robot& robot = BuiltinRobot();
  for (const Eigen::Vector2d& xz : {Eigen::Vector2d(2.6045, 1.4), Eigen::Vector2d(1.2, 0.8), Eigen::Vector2d(4.0, 2.0)}) {
    const EquilibriumResult r = SolveEquilibrium(robot, xz.x(), xz.y());
    ASSERT_EQ(r.status, EquilibriumStatus::kFound);
    const Eigen::Vector3d q = r.equilibrium.q;
    const Eigen::VectorXd L = CableLengths(robot, q);
    const double h = 1e-3;
    const double d2V = (EnergyAlongFixedLengths(robot, q, L, q(2) + h) + EnergyAlongFixedLengths(robot, q, L, q(2) - h) -
                        2 * EnergyAlongFixedLengths(robot, q, L, q(2))) / (h * h);
    // Along the motion parametrised by theta, d2V/dtheta2 = n'Kn / n_theta^2 (|n| = 1).
    const Eigen::Matrix<double, 3, Eigen::Dynamic> W = WrenchMatrix<double>(robot, q);
    const Eigen::Vector3d n = W.col(0).cross(W.col(1)).normalized();
    EXPECT_GT(d2V, 0.0);
    EXPECT_NEAR(d2V, r.equilibrium.reduced_stiffness / (n(2) * n(2)), 1e-4 * std::abs(d2V)) << xz.transpose();
  }
}

TEST(Stability, HighCentreOfMassMakesSomeEquilibriaUnstable) {
  // A centre of mass far above the anchor line is an inverted pendulum hung from two cables:
  // the level equilibrium at the centre becomes a potential-energy maximum.
  Robot robot = BuiltinRobot();
  robot.p_P_com_m = Eigen::Vector2d(0.0, 3.0);
  const double x_centre = robot.frame_width_m / 2;
  const Eigen::Vector3d q(x_centre, 0.5, 0.0);
  Eigen::VectorXd t = WrenchMatrix<double>(robot, q).topRows<2>().lu().solve(-GravityWrench<double>(robot, q).head<2>());
  ASSERT_LT(EquilibriumResidual<double>(robot, q, t).norm(), 1e-12);  // level pose balances by symmetry
  EXPECT_LT(ReducedStiffness(robot, q, t), 0.0);
  // At that position every balance with taut cables is a maximum: the model says so.
  EXPECT_EQ(SolveEquilibrium(robot, x_centre, 0.5).status, EquilibriumStatus::kUnstable);
  EXPECT_EQ(EvaluatePose(robot, x_centre, 0.5).feasibility, Feasibility::kUnstable);
}

TEST(ForwardModel, ForwardOfInverseReturnsThePose) {
  const Robot& robot = BuiltinRobot();
  Rng rng(5);
  int checked = 0;
  while (checked < 200) {
    const double x = rng.Uniform(0.3, 4.9), z = rng.Uniform(0.1, 2.6);
    const InversePose inv = InverseModel(robot, x, z);
    if (!inv.evaluation.feasible()) continue;
    ++checked;
    // Cold start (length circles) and warm start (the pose itself, perturbed).
    const ForwardResult cold = SolveForwardGeometricoStatic(robot, inv.lengths_m);
    ASSERT_EQ(cold.status, ForwardStatus::kConverged) << x << ", " << z << ": " << ToString(cold.status);
    EXPECT_LT((cold.equilibrium.q - inv.evaluation.equilibrium.q).cwiseAbs().maxCoeff(), kRoundTripTol)
        << x << ", " << z;
    EXPECT_LT((cold.equilibrium.tensions_N - inv.evaluation.equilibrium.tensions_N).cwiseAbs().maxCoeff(), 1e-7);
    const Eigen::Vector3d guess = inv.evaluation.equilibrium.q + Eigen::Vector3d(0.01, -0.01, 0.02);
    const ForwardResult warm = SolveForwardGeometricoStatic(robot, inv.lengths_m, &guess);
    ASSERT_EQ(warm.status, ForwardStatus::kConverged);
    EXPECT_LT((warm.equilibrium.q - inv.evaluation.equilibrium.q).cwiseAbs().maxCoeff(), kRoundTripTol);
  }
}

TEST(ForwardModel, LongLengthsHangBelowTheFloorAndShortOnesDoNotConverge) {
  const Robot& robot = BuiltinRobot();
  // Cables longer than the frame is high: the model has no floor, so the platform hangs below
  // z = 0 -- still an exact, taut, stable solution of the statics, which the workspace test
  // (and so simulate and the Monte Carlo) then refuses as outside the frame.
  Eigen::VectorXd L(2);
  L << 5.0, 5.0;
  const ForwardResult r = SolveForwardGeometricoStatic(robot, L);
  ASSERT_EQ(r.status, ForwardStatus::kConverged);
  EXPECT_LT((CableLengths(robot, r.equilibrium.q) - L).cwiseAbs().maxCoeff(), 1e-10);
  EXPECT_GT(r.equilibrium.tensions_N.minCoeff(), 0.0);
  EXPECT_TRUE(r.equilibrium.stable);
  EXPECT_LT(r.equilibrium.q(1), 0.0);
  EXPECT_EQ(CheckFeasibility(robot, r.equilibrium.q, r.equilibrium.tensions_N), Feasibility::kOutsideFrame);
  // Lengths that cannot meet at all (sum shorter than the gap between the posts).
  L << 1.0, 1.0;
  EXPECT_EQ(SolveForwardGeometricoStatic(robot, L).status, ForwardStatus::kNotConverged);
}

// The forward model's other answers: lengths only a pushing cable could hold (the platform
// beyond the right post: both cables pull up and to the left) are slack; an equilibrium that
// is a potential-energy maximum (a centre of mass high above the anchors) is never returned
// as converged: from that guess the model reports it unstable and goes on to the stable
// solution the platform falls to.
TEST(ForwardModel, ReportsSlackAndUnstableSolutions) {
  const Robot& robot = BuiltinRobot();
  const Eigen::Vector3d beyond(robot.frame_width_m + 1.0, 1.5, 0.0);
  const ForwardResult slack = SolveForwardGeometricoStatic(robot, CableLengths(robot, beyond), &beyond);
  EXPECT_EQ(slack.status, ForwardStatus::kSlack) << ToString(slack.status);
  EXPECT_STREQ(ToString(ForwardStatus::kSlack), "slack_cable");

  Robot high = robot;
  high.p_P_com_m = Eigen::Vector2d(0.0, 3.0);
  const Eigen::Vector3d level(high.frame_width_m / 2, 0.5, 0.0);
  ASSERT_LT(ReducedStiffness(high, level,
                             WrenchMatrix<double>(high, level).topRows<2>().lu().solve(
                                 -GravityWrench<double>(high, level).head<2>())),
            0.0);  // the guess is an unstable equilibrium
  const ForwardResult fell = SolveForwardGeometricoStatic(high, CableLengths(high, level), &level);
  ASSERT_EQ(fell.status, ForwardStatus::kConverged) << ToString(fell.status);
  EXPECT_TRUE(fell.equilibrium.stable);
  EXPECT_GT(fell.equilibrium.reduced_stiffness, 0.0);
  EXPECT_GT((fell.equilibrium.q - level).norm(), 0.1);
  EXPECT_STREQ(ToString(ForwardStatus::kUnstable), "unstable");
}

TEST(Feasibility, ReasonsAreReported) {
  const Robot& robot = BuiltinRobot();
  EXPECT_EQ(EvaluatePose(robot, -1.0, 1.0).feasibility, Feasibility::kOutsideFrame);
  EXPECT_EQ(EvaluatePose(robot, 2.6, 2.79).feasibility, Feasibility::kOutsideFrame);
  EXPECT_TRUE(EvaluatePose(robot, 2.6045, 1.4).feasible());
  Robot tight = robot;
  tight.tension_max_N = 5.0;  // below half the weight: nowhere feasible
  EXPECT_EQ(EvaluatePose(tight, 2.6045, 1.4).feasibility, Feasibility::kTensionHigh);
  Robot short_laser = robot;
  short_laser.laser_range_m = 1.0;
  EXPECT_EQ(EvaluatePose(short_laser, 2.6045, 1.4).feasibility, Feasibility::kLaserRange);
  Robot narrow_inclinometer = robot;
  narrow_inclinometer.theta_max_rad = 1e-3;
  EXPECT_EQ(EvaluatePose(narrow_inclinometer, 1.0, 1.4).feasibility, Feasibility::kThetaLimit);
}

TEST(InitialLengths, HomeEquilibriumUnlessOverridden) {
  Robot robot = BuiltinRobot();
  const Eigen::VectorXd l0 = InitialLengths(robot);
  const InversePose home = InverseModel(robot, robot.p_F_home_m.x(), robot.p_F_home_m.y());
  EXPECT_NEAR(l0(0), home.lengths_m(0), 1e-15);
  EXPECT_NEAR(l0(0), l0(1), 1e-12);  // symmetric robot
  robot.cables[1].initial_length_m = 3.0;
  EXPECT_EQ(InitialLengths(robot)(1), 3.0);
  EXPECT_NEAR(InitialLengths(robot)(0), home.lengths_m(0), 1e-15);
}

// Exit point 2 lowered by 0.1 m: at (4.9098, 2.7011) the platform's right anchor is 1.5 mm
// outside pulley 2, the balance root (theta = 0.0787 rad) lies next to orientations where
// the anchor sweeps through the pulley. The scan must still find that root, and the
// feasibility test must refuse the pose: an anchor keeps the frame margin from its pulley.
TEST(Equilibrium, RootNextToInvalidCableGeometryIsFoundAndThePulleyClearanceRefusesIt) {
  Robot robot = BuiltinRobot();
  robot.cables[1].p_F_exit_m.y() = 2.7;
  const EquilibriumResult eq = SolveEquilibrium(robot, 4.9098, 2.7011);
  ASSERT_EQ(eq.status, EquilibriumStatus::kFound);
  EXPECT_NEAR(eq.equilibrium.q(2), 0.0787, 5e-4);
  EXPECT_LT(eq.equilibrium.residual_N, 1e-9);
  EXPECT_EQ(CheckFeasibility(robot, eq.equilibrium.q, eq.equilibrium.tensions_N), Feasibility::kCableGeometry);
  // The same pose is fine once the margin is not asked for.
  robot.margin_m = 0.0;
  EXPECT_EQ(CheckFeasibility(robot, eq.equilibrium.q, eq.equilibrium.tensions_N), Feasibility::kTensionHigh);
}

}  // namespace
}  // namespace cablecal
