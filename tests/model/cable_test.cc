// Cable length with pulley wrap: the closed form of model/cable.h against an independent
// numerical construction, and its Jet derivatives against finite differences.
#include <ceres/jet.h>
#include <gtest/gtest.h>

#include <cmath>

#include "common/random.h"
#include "model/cable.h"
#include "model/statics.h"
#include "tests/support/cable_construction.h"

namespace cablecal {
namespace {

using testing::LengthByConstruction;

constexpr double kLengthTol_m = 1e-12;   // exact geometry; double rounding only
constexpr double kDerivativeRelTol = 1e-6;

TEST(CableGeometry, MatchesIndependentTangencyConstructionBothSides) {
  const Robot& robot = BuiltinRobot();
  Rng rng(7);
  int checked = 0;
  for (int side = 0; side < 2; ++side) {
    for (const double r : {0.025, 0.1, 0.3}) {
      const Eigen::Vector2d A = side == 0 ? Eigen::Vector2d(0.0, 2.8) : Eigen::Vector2d(5.209, 2.8);
      const PulleySide ps = side == 0 ? PulleySide::kLeft : PulleySide::kRight;
      for (int k = 0; k < 300; ++k) {
        // Anchors anywhere in the frame below the pulley's top, outside the pulley.
        // Drawn z first (GCC's order of the arguments this replaced: tests/support/random_robot.h).
        const double z = rng.Uniform(0.0, 2.8 + 0.5 * r);
        const Eigen::Vector2d B(rng.Uniform(0.05, robot.frame_width_m - 0.05), z);
        const Eigen::Vector2d C(A.x() + SideSign(ps) * r, A.y());
        if ((B - C).norm() < 1.5 * r) continue;
        const CableState<double> s = CableGeometry<double>(A, r, PulleySigns{SideSign(ps), 1.0}, B);
        ASSERT_TRUE(CableGeometryValid(s, r)) << "B = " << B.transpose();
        EXPECT_NEAR(s.length_m, LengthByConstruction(A, r, ps, B), kLengthTol_m)
            << "side " << side << " r " << r << " B = " << B.transpose();
        // The returned tangent point is on the circle and the segment is tangent there.
        EXPECT_NEAR((s.p_F_tangent_m - C).norm(), r, 1e-14);
        EXPECT_NEAR((B - s.p_F_tangent_m).dot(s.p_F_tangent_m - C), 0.0, 1e-13);
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 1500);
}

// wrap: under (pulleys below the platform): the closed form against the same construction,
// anchors anywhere above the pulley's bottom, on both sides and for several radii.
TEST(CableGeometry, UnderWrapMatchesIndependentTangencyConstruction) {
  Rng rng(11);
  int checked = 0;
  for (int side = 0; side < 2; ++side) {
    for (const double r : {0.025, 0.1, 0.3}) {
      const Eigen::Vector2d A = side == 0 ? Eigen::Vector2d(0.0, 0.1) : Eigen::Vector2d(4.0, 0.1);
      const PulleySide ps = side == 0 ? PulleySide::kLeft : PulleySide::kRight;
      const Eigen::Vector2d C(A.x() + SideSign(ps) * r, A.y());
      for (int k = 0; k < 300; ++k) {
        const double z = rng.Uniform(0.1 - 0.5 * r, 2.5);  // z first, as above
        const Eigen::Vector2d B(rng.Uniform(0.05, 3.95), z);
        if ((B - C).norm() < 1.5 * r) continue;
        const CableState<double> s = CableGeometry<double>(A, r, PulleySigns{SideSign(ps), -1.0}, B);
        ASSERT_TRUE(CableGeometryValid(s, r)) << "B = " << B.transpose();
        EXPECT_NEAR(s.length_m, LengthByConstruction(A, r, ps, B, PulleyWrap::kUnder), kLengthTol_m)
            << "side " << side << " r " << r << " B = " << B.transpose();
        EXPECT_NEAR((s.p_F_tangent_m - C).norm(), r, 1e-14);
        EXPECT_NEAR((B - s.p_F_tangent_m).dot(s.p_F_tangent_m - C), 0.0, 1e-13);
        // Under the pulley the cable pulls the platform down toward the floor's pulleys when
        // the anchor is above them.
        if (B.y() > C.y() + r) {
          EXPECT_LT(s.u_F_cable.y(), 0.0);
        }
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 1500);
}

TEST(CableGeometry, AnchorStraightBelowPulleyWrapsHalfATurn) {
  // Where the paper's Eq. (2) with its stated gamma gives phi = 0, the construction gives pi.
  const Eigen::Vector2d A(0.0, 2.8);
  const double r = 0.025;
  const Eigen::Vector2d B(2 * r, 1.0);  // straight below the pulley's inner side: leaves horizontally
  const CableState<double> s = CableGeometry<double>(A, r, PulleySigns{1.0, 1.0}, B);
  EXPECT_NEAR(s.wrap_angle_rad, M_PI, 1e-15);
  EXPECT_NEAR(s.length_m, r * M_PI + 1.8, 1e-14);
}

TEST(CableGeometry, AnchorLevelWithPulleyWrapsQuarterTurn) {
  const Eigen::Vector2d A(5.209, 2.8);
  const double r = 0.025;
  const Eigen::Vector2d B(2.0, 2.8 + r);  // level with the top of the right pulley
  const CableState<double> s = CableGeometry<double>(A, r, PulleySigns{-1.0, 1.0}, B);
  EXPECT_NEAR(s.wrap_angle_rad, M_PI / 2, 1e-14);
  EXPECT_NEAR(s.length_m, r * M_PI / 2 + (5.209 - r - 2.0), 1e-13);
}

// Central differences with step cbrt(eps) * max(1, |x|).
template <typename F>
Eigen::VectorXd CentralDifference(const F& f, Eigen::VectorXd x) {
  Eigen::VectorXd g(x.size());
  for (int k = 0; k < x.size(); ++k) {
    const double h = std::cbrt(std::numeric_limits<double>::epsilon()) * std::max(1.0, std::abs(x(k)));
    Eigen::VectorXd xp = x, xm = x;
    xp(k) += h;
    xm(k) -= h;
    g(k) = (f(xp) - f(xm)) / (2 * h);
  }
  return g;
}

TEST(CableGeometry, JetDerivativesMatchCentralDifferences) {
  // Variables: exit point (2), pulley radius, anchor (2): everything the identification
  // and the design differentiate.
  using Jet5 = ceres::Jet<double, 5>;
  Rng rng(11);
  for (int side = 0; side < 2; ++side) {
    const double s = side == 0 ? 1.0 : -1.0;
    for (int k = 0; k < 100; ++k) {
      Eigen::VectorXd x(5);
      x << (side == 0 ? 0.0 : 5.209) + rng.Uniform(-0.05, 0.05), 2.8 + rng.Uniform(-0.05, 0.05), 0.025,
          rng.Uniform(0.3, 4.9), rng.Uniform(0.1, 2.5);
      auto length = [&](const Eigen::VectorXd& v) {
        return CableGeometry<double>(v.head<2>(), v(2), PulleySigns{s, 1.0}, v.tail<2>()).length_m;
      };
      Eigen::Matrix<Jet5, 5, 1> xj;
      for (int i = 0; i < 5; ++i) xj(i) = Jet5(x(i), i);
      const Jet5 l = CableGeometry<Jet5>(xj.head<2>(), xj(2), PulleySigns{s, 1.0}, xj.tail<2>()).length_m;
      EXPECT_DOUBLE_EQ(l.a, length(x));
      const Eigen::VectorXd fd = CentralDifference(length, x);
      for (int i = 0; i < 5; ++i) {
        EXPECT_NEAR(l.v(i), fd(i), kDerivativeRelTol * std::max(1.0, std::abs(fd(i))))
            << "variable " << i << " at " << x.transpose();
      }
    }
  }
}

TEST(Wrench, WrenchMatrixIsMinusLengthGradient) {
  // Virtual work: column i of W equals -dl_i/dq, with q = (x, z, theta).
  const Robot& robot = BuiltinRobot();
  using Jet3 = ceres::Jet<double, 3>;
  Rng rng(3);
  for (int k = 0; k < 200; ++k) {
    // theta, z, x: the order GCC drew the arguments this replaced (tests/support/random_robot.h).
    const double theta = rng.Uniform(-1.0, 1.0), z = rng.Uniform(0.2, 2.4), x = rng.Uniform(0.5, 4.7);
    const Eigen::Vector3d q(x, z, theta);
    Pose<Jet3> qj;
    for (int i = 0; i < 3; ++i) qj(i) = Jet3(q(i), i);
    const Eigen::Matrix<double, 3, Eigen::Dynamic> W = WrenchMatrix<double>(robot, q);
    for (int c = 0; c < 2; ++c) {
      const Jet3 l = CableAtPose<Jet3>(robot.cables[c], qj).length_m;
      for (int i = 0; i < 3; ++i) EXPECT_NEAR(W(i, c), -l.v(i), 1e-12) << "cable " << c << " row " << i;
    }
  }
}

TEST(Wrench, GravityWrenchIsMinusPotentialGradient) {
  Robot robot = BuiltinRobot();
  robot.p_P_com_m = Eigen::Vector2d(0.07, -0.12);  // off-centre, so the moment row is exercised
  using Jet3 = ceres::Jet<double, 3>;
  for (const double theta : {-0.9, -0.2, 0.0, 0.4, 1.1}) {
    const Eigen::Vector3d q(2.0, 1.0, theta);
    Pose<Jet3> qj;
    for (int i = 0; i < 3; ++i) qj(i) = Jet3(q(i), i);
    const Jet3 V = PotentialEnergy<Jet3>(robot, qj);
    const Eigen::Vector3d w = GravityWrench<double>(robot, q);
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(w(i), -V.v(i), 1e-12);
  }
}

}  // namespace
}  // namespace cablecal
