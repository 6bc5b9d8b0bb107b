// The swivel-pulley cable model (model/swivel.h): against the planar model for robots in the
// plane y = 0, against an independent numerical tangency construction in 3-D, its Jet
// derivatives, the wrench matrix against virtual work, and the invalid configurations.
#include <ceres/jet.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "common/random.h"
#include "experiment/plan.h"
#include "model/cable.h"
#include "model/statics.h"
#include "model/swivel.h"
#include "tests/support/random_robot.h"
#include "tests/support/random_spatial_robot.h"
#include "tests/support/swivel_construction.h"

namespace cablecal {
namespace {

// A pose near the robot's home: each position coordinate within +-position_m of home's, each
// angle within +-angle_rad (drawn x, y, z, roll, pitch, yaw in that order).
SpatialPose<double> PoseNearHome(const SpatialRobot& robot, Rng& rng, double position_m, double angle_rad) {
  SpatialPose<double> q = robot.home_pose();
  for (int j = 0; j < 3; ++j) q(j) += rng.Uniform(-position_m, position_m);
  for (int j = 3; j < 6; ++j) q(j) += rng.Uniform(-angle_rad, angle_rad);
  return q;
}

// The same geometry by two formulas (planar closed form, spatial closed form): rounding only.
constexpr double kEquivalenceTol = 1e-12;
// Closed form against the numerical construction: bisection to ~1e-16 rad on the circle, then
// lengths of metres summed in 3-D.
constexpr double kConstructionTol_m = 1e-10;
// A Jet derivative against the closed-form unit vector: rounding only.
constexpr double kGradientTol = 1e-12;
// The wrench matrix against the virtual work of the Jets: rounding in entries of order 1.
constexpr double kWrenchTol = 1e-10;

using Vec3d = Eigen::Vector3d;
using testing::Tangency;
using testing::TangencyConstruction;

Robot RobotFile(const std::string& name) {
  return LoadRobotFile(std::string(CABLECAL_SOURCE_DIR) + "/robots/" + name);
}

// The planar pose (x, z, theta) as the spatial pose (x, 0, z, 0, -theta, 0) (model/kind.h).
SpatialPose<double> SpatialOfPlanar(const Eigen::Vector3d& q) {
  SpatialPose<double> s;
  s << q(0), 0.0, q(1), 0.0, -q(2), 0.0;
  return s;
}

bool AllFinite(const SwivelCableState<double>& s) {
  return std::isfinite(s.length_m) && std::isfinite(s.wrap_angle_rad) && std::isfinite(s.free_length_m) &&
         std::isfinite(s.axis_distance_m) && s.u_F.allFinite() && s.p_F_centre_m.allFinite() &&
         s.p_F_tangent_m.allFinite() && s.e_F_free.allFinite();
}

// ---- Planar equivalence ------------------------------------------------------------------

// Compares the planar model and the spatial model of PlanarAsSpatial(planar) at each pose
// whose anchors are all on their pulleys' inner side (there the swivel pulley faces the way
// the planar one does; beyond it the swivel pulley turns round, the planar one wraps on).
// Returns the number of poses compared.
int ExpectPlanarEquivalence(const Robot& planar, const std::vector<Eigen::Vector3d>& poses) {
  const SpatialRobot spatial = PlanarAsSpatial(planar);
  int compared = 0;
  for (const Eigen::Vector3d& q : poses) {
    bool inner = true;
    for (const Cable& c : planar.cables) {
      const Eigen::Vector2d B = PlatformPointInF<double>(q, c.p_P_anchor_m);
      inner = inner && SideSign(c.side) * (B.x() - c.p_F_exit_m.x()) > 0.0;
    }
    if (!inner) continue;
    ++compared;
    const SpatialPose<double> qs = SpatialOfPlanar(q);
    const std::string where = planar.name + " at q = (" + std::to_string(q(0)) + ", " + std::to_string(q(1)) + ", " +
                              std::to_string(q(2)) + ")";
    EXPECT_TRUE(CableGeometryAt(spatial, qs).valid()) << where;
    const Eigen::VectorXd lp = CableLengths(planar, q);
    const Eigen::VectorXd ls = CableLengths<double>(spatial, qs);
    for (int i = 0; i < planar.num_cables(); ++i) EXPECT_NEAR(ls(i), lp(i), kEquivalenceTol) << where << " cable " << i;
    // Planar wrench rows (f_x, f_z, moment) are the spatial (f_x, f_z, -m_y); the rest is zero.
    const Eigen::Matrix<double, 3, Eigen::Dynamic> Wp = WrenchMatrix<double>(planar, q);
    const Eigen::Matrix<double, 6, Eigen::Dynamic> Ws = WrenchMatrix<double>(spatial, qs);
    for (int i = 0; i < planar.num_cables(); ++i) {
      EXPECT_NEAR(Ws(0, i), Wp(0, i), kEquivalenceTol) << where << " cable " << i;
      EXPECT_NEAR(Ws(2, i), Wp(1, i), kEquivalenceTol) << where << " cable " << i;
      EXPECT_NEAR(-Ws(4, i), Wp(2, i), kEquivalenceTol) << where << " cable " << i;
      for (const int row : {1, 3, 5}) EXPECT_NEAR(Ws(row, i), 0.0, kEquivalenceTol) << where << " row " << row;
    }
    const Eigen::Vector3d gp = GravityWrench<double>(planar, q);
    const Eigen::Matrix<double, 6, 1> gs = GravityWrench<double>(spatial, qs);
    EXPECT_NEAR(gs(0), gp(0), kEquivalenceTol) << where;
    EXPECT_NEAR(gs(2), gp(1), kEquivalenceTol) << where;
    EXPECT_NEAR(-gs(4), gp(2), kEquivalenceTol * planar.platform_mass_kg * planar.gravity_mps2) << where;
  }
  return compared;
}

std::vector<Eigen::Vector3d> SampledPoses(const Robot& robot, int n, std::uint64_t seed) {
  std::vector<Eigen::Vector3d> poses;
  for (const PlanPose& p : SampleFeasiblePoses(robot, n, seed)) poses.push_back(p.q);
  return poses;
}

TEST(SwivelPlanarEquivalence, BuiltInPlanarRobotsAtSampledFeasiblePoses) {
  for (const char* file : {"wang2022.yaml", "planar3_suspended.yaml", "planar4_fully_constrained.yaml",
                           "asymmetric.yaml"}) {
    const Robot robot = RobotFile(file);
    const std::vector<Eigen::Vector3d> poses = SampledPoses(robot, 60, 5);
    const int compared = ExpectPlanarEquivalence(robot, poses);
    // Every anchor of these robots' feasible poses is on its pulley's inner side (planar3's
    // middle pulley, at x = 0.5 m, could see the apex on its far side; its samples do not).
    EXPECT_EQ(compared, 60) << file;
  }
}

TEST(SwivelPlanarEquivalence, RandomPlanarRobots) {
  Rng rng(2026);
  int compared = 0;
  for (int m = 2; m <= 8; ++m) {
    for (const bool fully_constrained : {false, true}) {
      if (fully_constrained && m < 4) continue;
      const Robot robot = testing::RandomRobotWithCables(rng, "random" + std::to_string(m), m, fully_constrained);
      compared += ExpectPlanarEquivalence(robot, SampledPoses(robot, 40, 100 + m));
    }
  }
  // Pulleys on the beams between the corners have anchors on either side: about half the
  // poses have every anchor on its pulley's inner side.
  EXPECT_GE(compared, 200);
}

// PlanarAsSpatial keeps the home pose (theta from the equilibrium with 2 cables), the sensors'
// sigmas and the exits; a converted robot with 3 or more cables is a valid spatial robot file
// unless its home is not a stable equilibrium in space (the fully constrained one).
TEST(SwivelPlanarEquivalence, PlanarAsSpatialKeepsHomeSensorsAndExits) {
  for (const char* file : {"wang2022.yaml", "planar3_suspended.yaml", "planar4_fully_constrained.yaml",
                           "asymmetric.yaml"}) {
    const Robot planar = RobotFile(file);
    const SpatialRobot s = PlanarAsSpatial(planar);
    const Eigen::Vector3d home = EvaluateHome(planar).equilibrium.q;
    EXPECT_LT((s.home_pose() - SpatialOfPlanar(home)).cwiseAbs().maxCoeff(), 1e-15) << file;
    EXPECT_NEAR(s.sensors.laser_m->sigma(), planar.sensors.laser_sigma_m(), 1e-18) << file;
    EXPECT_NEAR(s.sensors.inclinometer_rad->sigma(), planar.sensors.inclinometer_sigma_rad(), 1e-18) << file;
    EXPECT_EQ(s.sensors.encoder_sigma_m, planar.sensors.encoder_sigma_m);
    for (int i = 0; i < planar.num_cables(); ++i) {
      EXPECT_EQ(s.cables[i].p_F_exit_m, Vec3d(planar.cables[i].p_F_exit_m.x(), 0.0, planar.cables[i].p_F_exit_m.y()));
    }
    EXPECT_TRUE(CableGeometryAt(s, s.home_pose()).valid()) << file;
    if (planar.num_cables() < kMinSpatialCables) continue;
    if (std::string(file) == "planar4_fully_constrained.yaml") {
      // In space its four coplanar cables, two of them pulling down, hold the platform at home
      // only unstably: out of the plane the lower cables tip it (tests/model/spatial_statics_test.cc).
      try {
        LoadSpatialRobotFromString(SpatialRobotToYaml(s), file);
        ADD_FAILURE() << file << " loaded as a spatial robot";
      } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find(" degrees (home_rpy_deg) is not in the feasible workspace: unstable"),
                  std::string::npos)
            << e.what();
      }
    } else {
      EXPECT_NO_THROW(LoadSpatialRobotFromString(SpatialRobotToYaml(s), file)) << file;
    }
  }
}

// The swivel pulley of a planar cable wraps like it: arriving up (k = +z, over) or down (k = -z,
// under), whichever side the anchor is on, in closed form against cable.h's both signs.
TEST(SwivelPlanarEquivalence, BothWrapsAndSidesAgainstCableH) {
  Rng rng(3);
  int compared = 0;
  for (const double wrap : {1.0, -1.0}) {
    for (const double side : {1.0, -1.0}) {
      for (int k = 0; k < 200; ++k) {
        const double r = rng.Uniform(0.01, 0.2);
        const Eigen::Vector2d A = testing::DrawVector2(rng, {-1.0, -1.0}, {1.0, 1.0});
        const Eigen::Vector2d AB = testing::DrawVector2(rng, {0.0, -2.0}, {2.0, 2.0});
        const Eigen::Vector2d B(A.x() + side * AB.x(), A.y() + AB.y());
        const CableState<double> p = CableGeometry<double>(A, r, PulleySigns{side, wrap}, B);
        if (!CableGeometryValid(p, r)) continue;
        const SwivelCableState<double> s =
            SwivelCable<double>(Vec3d(A.x(), 0.0, A.y()), Vec3d(0.0, 0.0, wrap), r, Vec3d(B.x(), 0.0, B.y()));
        ASSERT_TRUE(s.valid()) << ToString(s.geometry);
        EXPECT_NEAR(s.length_m, p.length_m, kEquivalenceTol);
        EXPECT_NEAR(s.wrap_angle_rad, p.wrap_angle_rad, kEquivalenceTol);
        EXPECT_NEAR(s.p_F_tangent_m.x(), p.p_F_tangent_m.x(), kEquivalenceTol);
        EXPECT_NEAR(s.p_F_tangent_m.z(), p.p_F_tangent_m.y(), kEquivalenceTol);
        ++compared;
      }
    }
  }
  EXPECT_GE(compared, 600);
}

// ---- Closed form against a numerical tangency construction in 3-D --------------------------

Vec3d RandomUnit(Rng& rng) {
  for (;;) {
    const Vec3d v = testing::DrawVector3(rng, {-1.0, -1.0, -1.0}, {1.0, 1.0, 1.0});
    if (v.norm() > 0.1 && v.norm() <= 1.0) return v.normalized();
  }
}

TEST(SwivelCable, MatchesNumericalTangencyForRandomAxesAndAnchors) {
  Rng rng(17);
  int compared = 0, wraps = 0;
  for (int k = 0; k < 4000; ++k) {
    const Vec3d D = testing::DrawVector3(rng, {-3.0, -3.0, 0.0}, {3.0, 3.0, 3.0});
    const Vec3d axis = RandomUnit(rng);
    const double r = rng.Uniform(0.01, 0.2);
    // Anchors anywhere within 3 m, near the pulley (a third), or behind it close to the axis
    // (a third: where the wrap passes 3 pi / 2).
    Vec3d B;
    if (k % 3 == 0) {
      B = D + testing::DrawVector3(rng, {-3.0, -3.0, -3.0}, {3.0, 3.0, 3.0});
    } else if (k % 3 == 1) {
      B = D + 4.0 * r * testing::DrawVector3(rng, {-1.0, -1.0, -1.0}, {1.0, 1.0, 1.0});
    } else {
      const Vec3d w = axis.cross(RandomUnit(rng)).normalized();
      const double across = rng.Uniform(0.0, 1.5 * r), along = rng.Uniform(-3.0 * r, 0.0);
      B = D + across * w + along * axis;
    }
    const SwivelCableState<double> s = SwivelCable<double>(D, axis, r, B);
    ASSERT_TRUE(AllFinite(s));
    if (s.geometry == SwivelGeometry::kSwivelAxis || s.geometry == SwivelGeometry::kInsidePulley) continue;
    const Tangency t = TangencyConstruction(D, axis, r, B);
    ASSERT_TRUE(t.found) << "B = " << B.transpose();
    // The closed form refuses exactly the configurations whose wrap exceeds 3 pi / 2.
    EXPECT_EQ(s.geometry == SwivelGeometry::kWrap, t.arc_rad > kMaxWrapAngle_rad) << "arc " << t.arc_rad;
    if (!s.valid()) {
      ++wraps;
      continue;
    }
    EXPECT_NEAR(s.length_m, t.length_m, kConstructionTol_m) << "D " << D.transpose() << " k " << axis.transpose();
    EXPECT_NEAR(s.wrap_angle_rad, t.arc_rad, kConstructionTol_m / r);
    EXPECT_LT((s.p_F_tangent_m - t.p_F_tangent_m).norm(), kConstructionTol_m);
    EXPECT_LT((s.e_F_free - (B - t.p_F_tangent_m).normalized()).norm(), kConstructionTol_m);
    // The state's own invariants: T on the circle, the segment tangent there, u normal to k.
    EXPECT_NEAR((s.p_F_tangent_m - s.p_F_centre_m).norm(), r, 1e-13);
    EXPECT_NEAR((B - s.p_F_tangent_m).dot(s.p_F_tangent_m - s.p_F_centre_m), 0.0, 1e-12);
    // rho_perp loses digits to cancellation when the anchor is near the axis: |rho| / |rho_perp| ulps.
    EXPECT_NEAR(s.u_F.dot(axis), 0.0, 1e-15 * (1.0 + 4.0 * (B - D).norm() / s.axis_distance_m));
    ++compared;
  }
  EXPECT_GE(compared, 2000);
  EXPECT_GE(wraps, 40);  // the wrap bound was exercised
}

// Poses of random spatial robots near home: every valid cable against the construction.
TEST(SwivelCable, RandomSpatialRobotsMatchTheConstruction) {
  Rng rng(29);
  int compared = 0, eyelets = 0;
  for (int robot_index = 0; robot_index < 20; ++robot_index) {
    const SpatialRobot robot = testing::RandomSpatialRobot(rng, "random", 3 + robot_index % 10);
    for (int pose = 0; pose < 10; ++pose) {
      const SpatialPose<double> q = PoseNearHome(robot, rng, 0.4, 0.3);
      const Eigen::Matrix3d R = Rotation<double>(q);
      for (const SpatialCable& c : robot.cables) {
        const SwivelCableState<double> s = SwivelCableAtPose<double>(c, q, R);
        const Vec3d B = AnchorInF<double>(q, R, c.p_P_anchor_m);
        if (!s.valid()) continue;
        if (c.pulley_radius_m == 0.0) {  // an eyelet: straight from D
          EXPECT_NEAR(s.length_m, (B - c.p_F_exit_m).norm(), kEquivalenceTol);
          ++eyelets;
          continue;
        }
        const Tangency t = TangencyConstruction(c.p_F_exit_m, c.k_F_swivel_axis, c.pulley_radius_m, B);
        ASSERT_TRUE(t.found);
        EXPECT_NEAR(s.length_m, t.length_m, kConstructionTol_m);
        ++compared;
      }
    }
  }
  EXPECT_GE(compared, 800);
  EXPECT_GE(eyelets, 20);
}

// ---- Derivatives --------------------------------------------------------------------------

template <int N>
using Jet = ceres::Jet<double, N>;

TEST(SwivelCable, LengthGradientIsTheFreeSegmentsUnitVector) {
  Rng rng(41);
  int checked = 0;
  for (int k = 0; k < 2000; ++k) {
    const Vec3d D = testing::DrawVector3(rng, {-3.0, -3.0, 0.0}, {3.0, 3.0, 3.0});
    const Vec3d axis = RandomUnit(rng);
    const double r = k % 10 == 0 ? 0.0 : rng.Uniform(0.01, 0.2);  // eyelets too
    const Vec3d B = D + testing::DrawVector3(rng, {-3.0, -3.0, -3.0}, {3.0, 3.0, 3.0});
    const SwivelCableState<double> s = SwivelCable<double>(D, axis, r, B);
    if (!s.valid()) continue;
    Vec3<Jet<3>> Bj, Dj;
    for (int j = 0; j < 3; ++j) {
      Bj(j) = Jet<3>(B(j), j);
      Dj(j) = Jet<3>(D(j), j);
    }
    const Jet<3> l_B = SwivelCable<Jet<3>>(D.cast<Jet<3>>(), axis.cast<Jet<3>>(), Jet<3>(r), Bj).length_m;
    const Jet<3> l_D = SwivelCable<Jet<3>>(Dj, axis.cast<Jet<3>>(), Jet<3>(r), B.cast<Jet<3>>()).length_m;
    EXPECT_NEAR(l_B.a, s.length_m, 1e-15 * (1.0 + s.length_m));
    const Vec3d grad_B = l_B.v, grad_D = l_D.v;
    EXPECT_LT((grad_B - s.e_F_free).norm(), kGradientTol) << grad_B.transpose() << " vs " << s.e_F_free.transpose();
    EXPECT_NEAR(s.e_F_free.norm(), 1.0, 1e-15);
    // l depends on B - D alone (the axis is a direction): dl/dD = -dl/dB, finite.
    ASSERT_TRUE(grad_D.allFinite());
    EXPECT_LT((grad_D + s.e_F_free).norm(), kGradientTol);
    ++checked;
  }
  EXPECT_GE(checked, 1500);
}

// The derivatives with respect to the pulley radius and the swivel axis (which identification
// will estimate) against central differences.
TEST(SwivelCable, RadiusAndAxisDerivativesMatchCentralDifferences) {
  Rng rng(43);
  int checked = 0;
  for (int k = 0; k < 300; ++k) {
    const Vec3d D = testing::DrawVector3(rng, {-3.0, -3.0, 0.0}, {3.0, 3.0, 3.0});
    const Vec3d axis = RandomUnit(rng);
    const double r = rng.Uniform(0.01, 0.2);
    const Vec3d B = D + testing::DrawVector3(rng, {-3.0, -3.0, -3.0}, {3.0, 3.0, 3.0});
    if (!SwivelCable<double>(D, axis, r, B).valid()) continue;
    // Parameters (r, kx, ky, kz): the axis as given, not renormalised (a direction's length
    // does not enter k . rho and rho_perp in the same way, and Jets see what the code computes).
    Eigen::Vector4d p(r, axis.x(), axis.y(), axis.z());
    const auto length = [&](const Eigen::Vector4d& x) {
      return SwivelCable<double>(D, x.tail<3>(), x(0), B).length_m;
    };
    Vec3<Jet<4>> kj;
    for (int j = 0; j < 3; ++j) kj(j) = Jet<4>(axis(j), j + 1);
    const Jet<4> l = SwivelCable<Jet<4>>(D.cast<Jet<4>>(), kj, Jet<4>(r, 0), B.cast<Jet<4>>()).length_m;
    for (int j = 0; j < 4; ++j) {
      const double h = std::cbrt(std::numeric_limits<double>::epsilon()) * std::max(1.0, std::abs(p(j)));
      Eigen::Vector4d plus = p, minus = p;
      plus(j) += h;
      minus(j) -= h;
      const double fd = (length(plus) - length(minus)) / (2.0 * h);
      EXPECT_NEAR(l.v(j), fd, 1e-6 * std::max(1.0, std::abs(fd))) << "parameter " << j;
    }
    ++checked;
  }
  EXPECT_GE(checked, 200);
}

// ---- Platform: orientation, wrench matrix, gravity ----------------------------------------

TEST(SpatialPlatform, RotationIsZYXEulerAngles) {
  Rng rng(5);
  for (int k = 0; k < 100; ++k) {
    const double roll = rng.Uniform(-M_PI, M_PI), pitch = rng.Uniform(-1.5, 1.5), yaw = rng.Uniform(-M_PI, M_PI);
    const Eigen::Matrix3d expected = (Eigen::AngleAxisd(yaw, Vec3d::UnitZ()) * Eigen::AngleAxisd(pitch, Vec3d::UnitY()) *
                                      Eigen::AngleAxisd(roll, Vec3d::UnitX()))
                                         .toRotationMatrix();
    EXPECT_LT((Rotation<double>(roll, pitch, yaw) - expected).cwiseAbs().maxCoeff(), 1e-15);
    SpatialPose<double> q;
    q << 0, 0, 0, roll, pitch, yaw;
    // The tilt is the angle between the platform's z axis and F's.
    EXPECT_NEAR(TiltAngle(q), std::acos(expected.col(2).dot(Vec3d::UnitZ())), 1e-12);
  }
  // The planar angle theta turns x toward z: the spatial pitch -theta.
  const Eigen::Matrix3d R = Rotation<double>(0.0, -0.3, 0.0);
  EXPECT_NEAR(R(2, 0), std::sin(0.3), 1e-16);
  EXPECT_NEAR(R(0, 0), std::cos(0.3), 1e-16);
}

// The Euler rate axes against Jets of the rotation itself: d(R b)/d(angle_a) = axis_a x (R b)
// for every angle, including pitches near the limits and a yaw beyond pi.
TEST(SpatialPlatform, EulerRateAxesGiveTheRotationsDerivative) {
  Rng rng(59);
  for (int trial = 0; trial < 200; ++trial) {
    const double roll = rng.Uniform(-1.5, 1.5), pitch = rng.Uniform(-1.5, 1.5), yaw = rng.Uniform(-4.0, 4.0);
    const Vec3d b(rng.Uniform(-1.0, 1.0), rng.Uniform(-1.0, 1.0), rng.Uniform(-1.0, 1.0));
    const Eigen::Matrix<Jet<3>, 3, 3> Rj = Rotation<Jet<3>>(Jet<3>(roll, 0), Jet<3>(pitch, 1), Jet<3>(yaw, 2));
    const Vec3<Jet<3>> rj = Rj * b.cast<Jet<3>>();
    const Eigen::Matrix3d R = Rotation<double>(roll, pitch, yaw);
    const Eigen::Matrix3d axes = EulerRateAxes<double>(R, yaw);
    for (int a = 0; a < 3; ++a) {
      const Vec3d expected(rj(0).v(a), rj(1).v(a), rj(2).v(a));
      EXPECT_LT((axes.col(a).cross(R * b) - expected).norm(), 1e-14) << "angle " << a << " at trial " << trial;
    }
  }
}

// Virtual work: for a rigid displacement xi = (dp, dphi) in F, B_i = p + dp + R b_i +
// dphi x R b_i to first order, and the Jets' dl/dxi must be -W^T; and the gravity wrench is
// -dV/dxi of V = m g z_com.
TEST(SpatialPlatform, WrenchMatrixIsMinusTheLengthJacobianOfARigidDisplacement) {
  Rng rng(53);
  int checked = 0;
  for (int robot_index = 0; robot_index < 20; ++robot_index) {
    const SpatialRobot robot = testing::RandomSpatialRobot(rng, "random", 3 + robot_index % 10);
    for (int pose = 0; pose < 5; ++pose) {
      const SpatialPose<double> q = PoseNearHome(robot, rng, 0.3, 0.2);
      if (!CableGeometryAt(robot, q).valid()) continue;
      const Eigen::Matrix3d R = Rotation<double>(q);
      Vec3<Jet<6>> dp, dphi;
      for (int j = 0; j < 3; ++j) {
        dp(j) = Jet<6>(0.0, j);
        dphi(j) = Jet<6>(0.0, 3 + j);
      }
      const Vec3<Jet<6>> p = q.head<3>().cast<Jet<6>>() + dp;
      const auto moved = [&](const Vec3d& b_P) {
        const Vec3<Jet<6>> lever = (R * b_P).cast<Jet<6>>();
        return Vec3<Jet<6>>(p + lever + dphi.cross(lever));
      };
      Eigen::Matrix<double, Eigen::Dynamic, 6> J(robot.num_cables(), 6);
      for (int i = 0; i < robot.num_cables(); ++i) {
        const SpatialCable& c = robot.cables[i];
        J.row(i) = SwivelCable<Jet<6>>(c.p_F_exit_m.cast<Jet<6>>(), c.k_F_swivel_axis.cast<Jet<6>>(),
                                       Jet<6>(c.pulley_radius_m), moved(c.p_P_anchor_m))
                       .length_m.v.transpose();
      }
      const Eigen::Matrix<double, 6, Eigen::Dynamic> W = WrenchMatrix<double>(robot, q);
      EXPECT_LT((W + J.transpose()).cwiseAbs().maxCoeff(), kWrenchTol) << "W\n" << W << "\n-J^T\n" << -J.transpose();
      Eigen::VectorXd t(robot.num_cables());
      for (int i = 0; i < robot.num_cables(); ++i) t(i) = rng.Uniform(1.0, 100.0);
      EXPECT_LT((W * t + J.transpose() * t).norm(), kWrenchTol * 100.0 * robot.num_cables());
      const Jet<6> V = Jet<6>(robot.platform_mass_kg * robot.gravity_mps2) * moved(robot.p_P_com_m).z();
      const Eigen::Matrix<double, 6, 1> w_g = GravityWrench<double>(robot, q);
      EXPECT_LT((w_g + V.v).cwiseAbs().maxCoeff(), kWrenchTol * robot.platform_mass_kg * robot.gravity_mps2);
      ++checked;
    }
  }
  EXPECT_GE(checked, 60);
}

// Signs: a symmetric platform hanging level from four cables over pulleys above it is held
// by four equal positive tensions, W t + w_g = 0 (the cables pull the anchors up toward the
// pulleys; gravity pulls down).
TEST(SpatialPlatform, SymmetricHangingPlatformIsHeldByEqualPositiveTensions) {
  SpatialRobot robot;
  robot.platform_mass_kg = 10.0;
  robot.p_P_com_m = Vec3d(0.0, 0.0, -0.1);
  for (const double sx : {1.0, -1.0}) {
    for (const double sy : {1.0, -1.0}) {
      SpatialCable c;
      c.p_F_exit_m = Vec3d(sx * 1.5, sy * 1.0, 2.5);
      c.k_F_swivel_axis = Vec3d::UnitZ();
      c.pulley_radius_m = 0.04;
      c.p_P_anchor_m = Vec3d(sx * 0.1, sy * 0.1, 0.0);
      robot.cables.push_back(c);
    }
  }
  SpatialPose<double> q;
  q << 0.0, 0.0, 1.0, 0.0, 0.0, 0.0;
  const Eigen::Matrix<double, 6, Eigen::Dynamic> W = WrenchMatrix<double>(robot, q);
  const Eigen::Matrix<double, 6, 1> w_g = GravityWrench<double>(robot, q);
  const Eigen::VectorXd t = W.colPivHouseholderQr().solve(-w_g);
  EXPECT_LT(EquilibriumResidual<double>(robot, q, t).norm(), 1e-9);
  const double weight = robot.platform_mass_kg * robot.gravity_mps2;
  for (int i = 0; i < 4; ++i) {
    EXPECT_GT(W(2, i), 0.0) << "cable " << i << " must pull up";
    EXPECT_NEAR(t(i), weight / (4.0 * W(2, i)), 1e-9);
  }
  // Lowering an anchor lengthens its cable: dl/dB_z = e_z < 0.
  const SwivelCableState<double> s = SwivelCableAtPose<double>(robot.cables[0], q, Rotation<double>(q));
  EXPECT_LT(s.e_F_free.z(), 0.0);
}

// ---- Invalid geometry and the swivel angle ------------------------------------------------

TEST(SwivelCable, InvalidConfigurationsAreNamedNeverNaN) {
  const Vec3d D(0.0, 0.0, 2.0), k = Vec3d::UnitZ();
  const double r = 0.05;
  struct Case {
    Vec3d B;
    SwivelGeometry expected;
  };
  const Case cases[] = {
      {Vec3d(0.0, 0.0, 1.0), SwivelGeometry::kSwivelAxis},          // straight below the exit point
      {Vec3d(0.0, 0.0, 3.0), SwivelGeometry::kSwivelAxis},          // straight ahead of it
      {D, SwivelGeometry::kSwivelAxis},                              // at it
      {Vec3d(1e-8, 0.0, 1.0), SwivelGeometry::kSwivelAxis},         // within the tolerance of the axis
      {Vec3d(0.06, 0.0, 2.01), SwivelGeometry::kInsidePulley},      // |m| = 0.0141 < r
      {Vec3d(0.05, 0.0, 2.0), SwivelGeometry::kInsidePulley},       // at the centre
      {Vec3d(0.01, 0.0, 2.0 - 0.045), SwivelGeometry::kWrap},       // under the pulley, near the axis: 278 degrees
      {Vec3d(0.3, 0.0, 1.0), SwivelGeometry::kValid},
  };
  for (const Case& c : cases) {
    const SwivelCableState<double> s = SwivelCable<double>(D, k, r, c.B);
    EXPECT_EQ(s.geometry, c.expected) << "B = " << c.B.transpose() << ": " << ToString(s.geometry);
    EXPECT_TRUE(AllFinite(s)) << "B = " << c.B.transpose();
    // Jets too: no NaN or infinity in a derivative.
    Vec3<Jet<3>> Bj;
    for (int j = 0; j < 3; ++j) Bj(j) = Jet<3>(c.B(j), j);
    const SwivelCableState<Jet<3>> sj = SwivelCable<Jet<3>>(D.cast<Jet<3>>(), k.cast<Jet<3>>(), Jet<3>(r), Bj);
    EXPECT_EQ(sj.geometry, c.expected);
    EXPECT_TRUE(std::isfinite(sj.length_m.a) && sj.length_m.v.allFinite()) << "B = " << c.B.transpose();
  }
  // On a tilted axis, where rounding leaves |rho_perp| at 1e-16 m rather than 0.
  const Vec3d tilted = Vec3d(1.0, 2.0, 3.0).normalized();
  const SwivelCableState<double> rounded = SwivelCable<double>(D, tilted, r, Vec3d(D + 1.7 * tilted));
  EXPECT_EQ(rounded.geometry, SwivelGeometry::kSwivelAxis) << "|rho_perp| = " << rounded.axis_distance_m;
  EXPECT_TRUE(AllFinite(rounded));
  EXPECT_STREQ(ToString(SwivelGeometry::kSwivelAxis), "swivel_axis");
  EXPECT_STREQ(ToString(SwivelGeometry::kInsidePulley), "inside_pulley");
  EXPECT_STREQ(ToString(SwivelGeometry::kWrap), "wrap");
  // An eyelet: valid on its axis (l = |rho|), invalid only at the exit point itself.
  const SwivelCableState<double> on_axis = SwivelCable<double>(D, k, 0.0, Vec3d(0.0, 0.0, 1.0));
  EXPECT_TRUE(on_axis.valid());
  EXPECT_DOUBLE_EQ(on_axis.length_m, 1.0);
  const SwivelCableState<double> at_exit = SwivelCable<double>(D, k, 0.0, D);
  EXPECT_EQ(at_exit.geometry, SwivelGeometry::kInsidePulley);
  EXPECT_TRUE(AllFinite(at_exit));
}

// Turning the anchor about the swivel axis turns the pulley with it: the swivel angle reads the
// turn and the length does not change (the construction is symmetric about the axis).
TEST(SwivelCable, SwivelAngleReadsATurnAboutTheAxis) {
  Rng rng(61);
  for (int k = 0; k < 200; ++k) {
    const Vec3d D = testing::DrawVector3(rng, {-2.0, -2.0, 0.0}, {2.0, 2.0, 3.0});
    const Vec3d axis = RandomUnit(rng);
    const double r = rng.Uniform(0.01, 0.1);
    const Vec3d B = D + testing::DrawVector3(rng, {-2.0, -2.0, -2.0}, {2.0, 2.0, 2.0});
    const SwivelCableState<double> home = SwivelCable<double>(D, axis, r, B);
    if (!home.valid()) continue;
    const double turn = rng.Uniform(-3.0, 3.0);
    const Vec3d turned = D + Eigen::AngleAxisd(turn, axis) * (B - D);
    const SwivelCableState<double> s = SwivelCable<double>(D, axis, r, turned);
    ASSERT_TRUE(s.valid());
    EXPECT_NEAR(SwivelAngle<double>(axis, home.u_F, s.u_F), turn, 1e-12);
    EXPECT_NEAR(s.length_m, home.length_m, 1e-12);
    EXPECT_NEAR(SwivelAngle<double>(axis, home.u_F, home.u_F), 0.0, 1e-15);
  }
}

// Unstretched length: l = L (1 + t / EA), L = l without a stiffness.
TEST(SwivelCable, UnstretchedLengthInvertsTheStretch) {
  SpatialCable c;
  EXPECT_EQ(UnstretchedLength(c, 2.0, 500.0), 2.0);
  c.stiffness_N = 1e5;
  const double L = UnstretchedLength(c, 2.0, 500.0);
  EXPECT_NEAR(L * (1.0 + 500.0 / 1e5), 2.0, 1e-15);
  EXPECT_LT(L, 2.0);
}

}  // namespace
}  // namespace cablecal
