// The forward model as the stationary point of the potential energy (model/forward_statics.h),
// for planar and spatial robots: the stiff-cable limit against the inextensible solvers, the
// stationarity of the result against finite differences of an energy written here from lengths
// the model's gradient code did not compute, slack cables, and random robots near home.
#include "model/forward_statics.h"

#include <gtest/gtest.h>

#include <Eigen/SVD>

#include <cmath>
#include <limits>
#include <string>

#include "common/random.h"
#include "model/cable.h"
#include "model/robot.h"
#include "model/spatial_robot.h"
#include "model/stability.h"
#include "model/statics.h"
#include "model/swivel.h"
#include "tests/support/cable_construction.h"
#include "tests/support/random_robot.h"
#include "tests/support/random_spatial_robot.h"

namespace cablecal {
namespace {

Robot LoadRepoRobot(const std::string& name) {
  return LoadRobotFile(std::string(CABLECAL_SOURCE_DIR) + "/robots/" + name + ".yaml");
}
SpatialRobot LoadRepoSpatialRobot(const std::string& name) {
  return LoadSpatialRobotFile(std::string(CABLECAL_SOURCE_DIR) + "/robots/" + name + ".yaml");
}

// Random planar robots of 4 or more cables are drawn rigid (tests/support/random_robot.h); the
// elastic tests give them E*A = 3000 x tension.max (0.03 % stretch at the largest tension).
constexpr double kRandomStiffnessOverMaxTension = 3000.0;

Robot WithStiffness(Robot r, double ea_N) {
  for (Cable& c : r.cables) c.stiffness_N = ea_N;
  return r;
}
SpatialRobot WithStiffness(SpatialRobot r, double ea_N) {
  for (SpatialCable& c : r.cables) c.stiffness_N = ea_N;
  return r;
}

// The Lagrangian of the test, written here: gravity m g z_com, the strain energy of each
// stretched elastic cable EA (l - L)^2 / (2 L), and the inextensible cables' multiplier terms
// t_i (l_i - L_i), with the planar lengths from the tangency construction of
// tests/support/cable_construction.h (not the model's closed form or its derivatives).
double PlanarLagrangian(const Robot& r, const Eigen::VectorXd& L, const Eigen::VectorXd& t, const Eigen::Vector3d& q) {
  const double c = std::cos(q(2)), s = std::sin(q(2));
  const double z_com = q(1) + s * r.p_P_com_m.x() + c * r.p_P_com_m.y();
  double energy = r.platform_mass_kg * r.gravity_mps2 * z_com;
  for (int i = 0; i < r.num_cables(); ++i) {
    const double l = testing::CableLengthByConstruction(r.cables[i], q);
    if (r.cables[i].stiffness_N) {
      if (l > L(i)) energy += *r.cables[i].stiffness_N * (l - L(i)) * (l - L(i)) / (2.0 * L(i));
    } else {
      energy += t(i) * (l - L(i));
    }
  }
  return energy;
}

// The same for a spatial robot, from the model's length values (CableLengths<double>: the
// solver's gradient is the wrench matrix, the free segments' directions, not these).
double SpatialLagrangian(const SpatialRobot& r, const Eigen::VectorXd& L, const Eigen::VectorXd& t,
                         const SpatialPose<double>& q) {
  const double z_com = (q.head<3>() + Rotation<double>(q) * r.p_P_com_m).z();
  double energy = r.platform_mass_kg * r.gravity_mps2 * z_com;
  const Eigen::VectorXd l = CableLengths<double>(r, q);
  for (int i = 0; i < r.num_cables(); ++i) {
    if (r.cables[i].stiffness_N) {
      if (l(i) > L(i)) energy += *r.cables[i].stiffness_N * (l(i) - L(i)) * (l(i) - L(i)) / (2.0 * L(i));
    } else {
      energy += t(i) * (l(i) - L(i));
    }
  }
  return energy;
}

// Central differences of a Lagrangian in the pose coordinates. The strain energy's second
// derivative jumps where a cable goes slack, which costs central differences EA / L * h / 4 near
// such a cable (7e-5 N for planar4's): a small step, whose rounding (1e-16 of the energy / h)
// stays far below the tolerance.
constexpr double kStep = 1e-8;
template <typename Pose, typename F>
Pose Gradient(const Pose& q, F lagrangian, double h) {
  Pose g;
  for (int k = 0; k < q.size(); ++k) {
    Pose up = q, down = q;
    up(k) += h;
    down(k) -= h;
    g(k) = (lagrangian(up) - lagrangian(down)) / (2.0 * h);
  }
  return g;
}

// Checks (b) on a converged result: elastic tensions are EA (l / L - 1) (0 when slack), the
// inextensible cables meet their lengths, and the Lagrangian is stationary (relative to the
// weight: N for metres, N m for radians).
void ExpectStationaryPlanar(const Robot& r, const Eigen::VectorXd& L, const ForwardResult& f, const std::string& what) {
  ASSERT_EQ(f.status, ForwardStatus::kConverged) << what << ": " << ToString(f.status);
  const Eigen::Vector3d q = f.equilibrium.q;
  const Eigen::VectorXd& t = f.equilibrium.tensions_N;
  for (int i = 0; i < r.num_cables(); ++i) {
    const double l = testing::CableLengthByConstruction(r.cables[i], q);
    if (r.cables[i].stiffness_N) {
      const double expected = std::max(0.0, *r.cables[i].stiffness_N * (l / L(i) - 1.0));
      EXPECT_NEAR(t(i), expected, 1e-6 * (1.0 + expected)) << what << ", cable " << i + 1;
    } else {
      EXPECT_NEAR(l, L(i), 1e-9) << what << ", cable " << i + 1;
    }
  }
  const double weight_N = r.platform_mass_kg * r.gravity_mps2;
  const Eigen::Vector3d g = Gradient(q, [&](const Eigen::Vector3d& at) { return PlanarLagrangian(r, L, t, at); }, kStep);
  EXPECT_LT(g.norm(), 1e-5 * weight_N) << what << ": gradient " << g.transpose();
}

void ExpectStationarySpatial(const SpatialRobot& r, const Eigen::VectorXd& L, const SpatialForwardResult& f,
                             const std::string& what) {
  ASSERT_EQ(f.status, ForwardStatus::kConverged) << what << ": " << ToString(f.status);
  const SpatialPose<double> q = f.equilibrium.q;
  const Eigen::VectorXd& t = f.equilibrium.tensions_N;
  const Eigen::VectorXd l = CableLengths<double>(r, q);
  for (int i = 0; i < r.num_cables(); ++i) {
    if (r.cables[i].stiffness_N) {
      const double expected = std::max(0.0, *r.cables[i].stiffness_N * (l(i) / L(i) - 1.0));
      EXPECT_NEAR(t(i), expected, 1e-6 * (1.0 + expected)) << what << ", cable " << i + 1;
    } else {
      EXPECT_NEAR(l(i), L(i), 1e-9) << what << ", cable " << i + 1;
    }
  }
  const double weight_N = r.platform_mass_kg * r.gravity_mps2;
  const SpatialPose<double> g =
      Gradient(q, [&](const SpatialPose<double>& at) { return SpatialLagrangian(r, L, t, at); }, kStep);
  EXPECT_LT(g.norm(), 1e-5 * weight_N) << what << ": gradient " << g.transpose();
}

// (a) A stiff cable reproduces the inextensible answer: planar m = 2 and 3 against the
// geometrico-static solver, from lengths a few millimetres off the commanded pose's.
TEST(ForwardStatics, StiffCablesReproduceInextensiblePlanar) {
  int compared = 0;
  for (const char* name : {"wang2022", "planar3_suspended"}) {
    const Robot rigid = LoadRepoRobot(name);
    const Robot stiff = WithStiffness(rigid, 1e12);
    Rng rng(StreamSeed(11, {static_cast<std::uint64_t>(rigid.num_cables())}));
    const PoseEvaluation home = HomeEvaluation(rigid);
    for (int k = 0; k < 20; ++k) {
      Eigen::VectorXd L = CableLengths(rigid, home.equilibrium.q);
      for (int i = 0; i < L.size(); ++i) L(i) += rng.Uniform(-0.01, 0.01);
      const Eigen::Vector3d guess = home.equilibrium.q;
      const ForwardResult old = SolveForwardGeometricoStatic(rigid, L, &guess);
      if (old.status != ForwardStatus::kConverged) continue;
      const ForwardResult elastic = SolveForwardStatics(stiff, L, &guess);
      const ForwardResult inextensible = SolveForwardStatics(rigid, L, &guess);
      ASSERT_EQ(elastic.status, ForwardStatus::kConverged) << name << " draw " << k;
      ASSERT_EQ(inextensible.status, ForwardStatus::kConverged) << name << " draw " << k;
      EXPECT_LT((elastic.equilibrium.q - old.equilibrium.q).cwiseAbs().maxCoeff(), 1e-8) << name << " draw " << k;
      EXPECT_LT((inextensible.equilibrium.q - old.equilibrium.q).cwiseAbs().maxCoeff(), 1e-10) << name << " draw " << k;
      EXPECT_LT((elastic.equilibrium.tensions_N - old.equilibrium.tensions_N).cwiseAbs().maxCoeff(),
                1e-4 * old.equilibrium.tensions_N.cwiseAbs().maxCoeff())
          << name << " draw " << k;
      ++compared;
    }
  }
  EXPECT_GE(compared, 30);
}

// (a) spatial m = 6: the lengths of a held pose, fed back, give the pose (inextensible to 1e-9;
// EA = 1e12 within its stretch, 1e-8).
TEST(ForwardStatics, SixCablesInverseRoundTrip) {
  Rng rng(StreamSeed(12, {}));
  int compared = 0, invalid = 0, pushing = 0;
  for (int draw = 0; draw < 40; ++draw) {
    SpatialRobot robot = testing::RandomSpatialRobot(rng, "six-" + std::to_string(draw), 6);
    for (SpatialCable& c : robot.cables) c.stiffness_N.reset();
    for (int k = 0; k < 10; ++k) {
      SpatialPose<double> q = robot.home_pose();
      for (int c = 0; c < 3; ++c) q(c) += rng.Uniform(-0.1, 0.1);
      for (int c = 3; c < 6; ++c) q(c) += rng.Uniform(-0.05, 0.05);
      if (!CableGeometryAt(robot, q).valid()) {
        ++invalid;
        continue;
      }
      // Held where the unique tensions pull; elsewhere the lengths still give the pose back,
      // reported as slack (a cable would push).
      const Eigen::MatrixXd W = WrenchMatrix<double>(robot, q);
      const Eigen::VectorXd t = W.fullPivLu().solve(-GravityWrench<double>(robot, q));
      const Eigen::VectorXd L = CableLengths<double>(robot, q);
      SpatialPose<double> guess = q;
      guess.head<3>() += Eigen::Vector3d(0.004, -0.003, 0.002);
      // Away from singular configurations (where the lengths fix the pose only weakly).
      const Eigen::VectorXd sv = Eigen::JacobiSVD<Eigen::MatrixXd>(W).singularValues();
      if (!(sv(5) > 1e-3 * sv(0))) {
        ++invalid;
        continue;
      }
      const SpatialForwardResult f = SolveForwardStatics(robot, L, &guess);
      if (!(t.minCoeff() > 1.0)) {
        // Not held: reported as slack at the pose, unless another pose with these lengths holds
        // the platform (then a true equilibrium: lengths met, every cable pulling).
        if (f.status == ForwardStatus::kSlack) {
          EXPECT_LT((f.equilibrium.q - q).cwiseAbs().maxCoeff(), 1e-9) << robot.name << " pose " << k;
        } else if (f.status == ForwardStatus::kConverged) {
          EXPECT_LT(f.length_residual_m, 1e-10) << robot.name << " pose " << k;
          EXPECT_GT(f.equilibrium.tensions_N.minCoeff(), 0.0) << robot.name << " pose " << k;
        }
        ++pushing;
        continue;
      }
      EXPECT_LT((f.equilibrium.q - q).cwiseAbs().maxCoeff(), 1e-9) << robot.name << " pose " << k;
      ASSERT_EQ(f.status, ForwardStatus::kConverged) << robot.name << " pose " << k;
      EXPECT_LT((f.equilibrium.tensions_N - t).cwiseAbs().maxCoeff(), 1e-6 * t.maxCoeff()) << robot.name;
      const SpatialRobot stiff = WithStiffness(robot, 1e12);
      const SpatialForwardResult g = SolveForwardStatics(stiff, CommandedUnstretchedLengths(stiff, L, t), &guess);
      ASSERT_EQ(g.status, ForwardStatus::kConverged) << robot.name << " pose " << k;
      EXPECT_LT((g.equilibrium.q - q).cwiseAbs().maxCoeff(), 1e-8) << robot.name << " pose " << k;
      ++compared;
    }
  }
  EXPECT_GE(compared, 5) << invalid << " poses with invalid or near-singular geometry, " << pushing << " not held";
  EXPECT_GE(pushing, 5);
}

// (b) Elastic cables, more than the platform's freedoms: the planar 4-cable robot and random
// 5- to 8-cable ones with lengths off the nominal's, stationary by finite differences.
TEST(ForwardStatics, ElasticPlanarIsStationary) {
  const Robot p4 = WithStiffness(LoadRepoRobot("planar4_fully_constrained"), 5.0e4);  // a 1.5 mm braided Dyneema line
  Rng rng(StreamSeed(13, {}));
  const PoseEvaluation home = HomeEvaluation(p4);
  int solved = 0;
  for (int k = 0; k < 20; ++k) {
    Eigen::VectorXd L = CommandedUnstretchedLengths(p4, CableLengths(p4, home.equilibrium.q), home.equilibrium.tensions_N);
    // The lower cables' stretch at home is a fifth of a millimetre (5 N over 2.6e4 N/m): more
    // than that and they go slack, the crossed upper pair alone holding the platform.
    for (int i = 0; i < L.size(); ++i) L(i) += rng.Uniform(-0.0001, 0.0001);
    const ForwardResult f = SolveForwardStatics(p4, L, &home.equilibrium.q);
    ExpectStationaryPlanar(p4, L, f, "planar4 draw " + std::to_string(k));
    ++solved;
  }
  for (int m = 5; m <= 8; ++m) {
    Robot r = testing::RandomRobotWithCables(rng, "elastic-" + std::to_string(m), m, true);
    r = WithStiffness(r, kRandomStiffnessOverMaxTension * r.tension_max_N);
    const PoseEvaluation h = HomeEvaluation(r);
    Eigen::VectorXd L = CommandedUnstretchedLengths(r, CableLengths(r, h.equilibrium.q), h.equilibrium.tensions_N);
    for (int i = 0; i < L.size(); ++i) L(i) += rng.Uniform(-0.0005, 0.0005);
    ExpectStationaryPlanar(r, L, SolveForwardStatics(r, L, &h.equilibrium.q), r.name);
    ++solved;
  }
  EXPECT_EQ(solved, 24);
}

TEST(ForwardStatics, ElasticSpatialIsStationary) {
  Rng rng(StreamSeed(14, {}));
  const SpatialRobot ipanema = WithStiffness(LoadRepoSpatialRobot("ipanema1"), 2e5);
  const SpatialRobot cogiro = WithStiffness(LoadRepoSpatialRobot("cogiro"), 1e6);
  const SpatialRobot irma4u = WithStiffness(LoadRepoSpatialRobot("irma4u"), 1e5);  // underactuated
  for (const SpatialRobot* r : {&ipanema, &cogiro, &irma4u}) {
    const SpatialPose<double> q0 = r->home_pose();
    for (int k = 0; k < 5; ++k) {
      Eigen::VectorXd L = CableLengths<double>(*r, q0);
      // Shorter than the geometric lengths: every cable starts stretched.
      for (int i = 0; i < L.size(); ++i) L(i) *= 1.0 - rng.Uniform(0.0005, 0.001);
      const SpatialForwardResult f = SolveForwardStatics(*r, L, &q0);
      ExpectStationarySpatial(*r, L, f, r->name + " draw " + std::to_string(k));
    }
  }
}

// A rotation has two roll-pitch-yaw triples, (r, p, y) and (r + pi, pi - p, y + pi); Newton
// started on the second ends there. The inclinometer reads roll and pitch of the first (|pitch|
// <= pi/2), so the solver must return that one, the same rotation (before the fix, a robust
// design's scenario robot on ipanema1 came back with roll 2.98, pitch 2.87).
TEST(ForwardStatics, SpatialPoseComesBackWithTheUsualRollPitchYaw) {
  Rng rng(StreamSeed(15, {}));
  const SpatialRobot cogiro = WithStiffness(LoadRepoSpatialRobot("cogiro"), 1e6);
  const SpatialRobot irma4u = WithStiffness(LoadRepoSpatialRobot("irma4u"), 1e5);
  const SpatialRobot random6 = testing::RandomSpatialRobot(rng, "random6", 6);
  for (const SpatialRobot* r : {&cogiro, &irma4u, &random6}) {
    SCOPED_TRACE(r->name);
    const SpatialPose<double> q0 = r->home_pose();
    const Eigen::VectorXd L = CableLengths<double>(*r, q0);
    const SpatialForwardResult usual = SolveForwardStatics(*r, L, &q0);
    ASSERT_EQ(usual.status, ForwardStatus::kConverged);
    SpatialPose<double> other = usual.equilibrium.q;
    other(3) += M_PI;
    other(4) = M_PI - other(4);
    other(5) += M_PI;
    ASSERT_LT((Rotation<double>(other) - Rotation<double>(usual.equilibrium.q)).norm(), 1e-12);
    const SpatialForwardResult f = SolveForwardStatics(*r, L, &other);
    ASSERT_EQ(f.status, ForwardStatus::kConverged);
    EXPECT_LE(std::abs(f.equilibrium.q(4)), 0.5 * M_PI);
    EXPECT_LT((f.equilibrium.q - usual.equilibrium.q).cwiseAbs().maxCoeff(), 1e-8) << f.equilibrium.q.transpose();
  }
}

// (c) Slack: a cable commanded much longer carries nothing (elastic) or is reported (inextensible).
TEST(ForwardStatics, LongCableGoesSlack) {
  Rng rng(StreamSeed(17, {}));
  Robot r6 = testing::RandomRobotWithCables(rng, "slack-6", 6, true);
  r6 = WithStiffness(r6, kRandomStiffnessOverMaxTension * r6.tension_max_N);
  const PoseEvaluation home = HomeEvaluation(r6);
  Eigen::VectorXd L = CommandedUnstretchedLengths(r6, CableLengths(r6, home.equilibrium.q), home.equilibrium.tensions_N);
  L(5) += 0.3;  // a lower cable, 30 cm of slack: the other five hold the platform
  const ForwardResult f = SolveForwardStatics(r6, L, &home.equilibrium.q);
  ExpectStationaryPlanar(r6, L, f, "6 cables, one slack");
  EXPECT_EQ(f.equilibrium.tensions_N(5), 0.0);
  EXPECT_LT(CableLengths(r6, f.equilibrium.q)(5), L(5) - 0.2);

  const SpatialRobot ipanema = WithStiffness(LoadRepoSpatialRobot("ipanema1"), 2e5);
  const SpatialPose<double> q0 = ipanema.home_pose();
  Eigen::VectorXd Ls = CableLengths<double>(ipanema, q0) * (1.0 - 5e-4);
  Ls(2) += 0.3;
  const SpatialForwardResult g = SolveForwardStatics(ipanema, Ls, &q0);
  ExpectStationarySpatial(ipanema, Ls, g, "ipanema1, one slack");
  EXPECT_EQ(g.equilibrium.tensions_N(2), 0.0);

  const Robot p3 = LoadRepoRobot("planar3_suspended");
  const PoseEvaluation h3 = HomeEvaluation(p3);
  Eigen::VectorXd L3 = CableLengths(p3, h3.equilibrium.q);
  L3(1) += 0.3;
  EXPECT_EQ(SolveForwardStatics(p3, L3, &h3.equilibrium.q).status, ForwardStatus::kSlack);
}

// (d) Random robots near their home: the nominal equilibrium comes back exactly from its own
// commanded unstretched lengths, and lengths a little off give a stationary, stable pose.
TEST(ForwardStatics, RandomPlanarRobotsNearHome) {
  Rng rng(StreamSeed(15, {}));
  int perturbed_solved = 0, perturbed_tried = 0;
  for (int m = 2; m <= 8; ++m) {
    for (int draw = 0; draw < 3; ++draw) {
      // m = 3 suspended and fully constrained; m >= 4 fully constrained (elastic).
      const bool fully = m >= 4 || (m == 3 && draw % 2 == 1);
      Robot r = testing::RandomRobotWithCables(rng, "random-" + std::to_string(m) + "-" + std::to_string(draw), m, fully);
      if (m <= 3 && draw == 2) r = WithStiffness(r, 5000.0 * r.tension_max_N);  // elastic with few cables too
      if (m >= 4) r = WithStiffness(r, kRandomStiffnessOverMaxTension * r.tension_max_N);
      const PoseEvaluation h = HomeEvaluation(r);
      const Eigen::VectorXd L =
          CommandedUnstretchedLengths(r, CableLengths(r, h.equilibrium.q), h.equilibrium.tensions_N);
      Eigen::Vector3d guess = h.equilibrium.q + Eigen::Vector3d(0.01, -0.01, 0.02);
      const ForwardResult f = SolveForwardStatics(r, L, &guess);
      ASSERT_EQ(f.status, ForwardStatus::kConverged) << r.name;
      EXPECT_LT((f.equilibrium.q - h.equilibrium.q).cwiseAbs().maxCoeff(), 1e-9) << r.name;
      EXPECT_LT((f.equilibrium.tensions_N - h.equilibrium.tensions_N).cwiseAbs().maxCoeff(),
                1e-6 * r.tension_max_N)
          << r.name;
      Eigen::VectorXd L_off = L;
      for (int i = 0; i < m; ++i) L_off(i) += rng.Uniform(-0.0003, 0.0003);
      const ForwardResult g = SolveForwardStatics(r, L_off, &h.equilibrium.q);
      ++perturbed_tried;
      if (!HasStiffness(r)) {
        // Rigid cables: what the geometrico-static model says, wherever it converges.
        const ForwardResult old = SolveForwardGeometricoStatic(r, L_off, &h.equilibrium.q);
        if (old.status != ForwardStatus::kConverged) continue;
        ASSERT_EQ(g.status, ForwardStatus::kConverged) << r.name << " off";
        EXPECT_LT((g.equilibrium.q - old.equilibrium.q).cwiseAbs().maxCoeff(), 1e-9) << r.name << " off";
      } else {
        ExpectStationaryPlanar(r, L_off, g, r.name + " off");
      }
      EXPECT_TRUE(g.equilibrium.stable);
      ++perturbed_solved;
    }
  }
  EXPECT_GE(perturbed_solved, perturbed_tried - 3);
}

TEST(ForwardStatics, RandomSpatialRobotsNearHome) {
  Rng rng(StreamSeed(16, {}));
  int exact = 0, stationary = 0, underactuated = 0, unstable_home = 0;
  for (int m = 3; m <= 12; ++m) {
    for (int draw = 0; draw < 6; ++draw) {
      SpatialRobot r = testing::RandomSpatialRobot(rng, "random-" + std::to_string(m) + "-" + std::to_string(draw), m);
      int rigid = 0;
      for (const SpatialCable& c : r.cables) rigid += c.stiffness_N ? 0 : 1;
      if (rigid > 6) {
        EXPECT_THROW(CheckSimulatable(r), InputError) << r.name;
        for (int i = 0; i < m && rigid > 6; ++i) {
          if (!r.cables[i].stiffness_N) {
            r.cables[i].stiffness_N = 1e6;
            --rigid;
          }
        }
      }
      EXPECT_NO_THROW(CheckSimulatable(r)) << r.name;
      const SpatialPose<double> q0 = r.home_pose();
      const Eigen::VectorXd l0 = CableLengths<double>(r, q0);
      if (m >= 6) {
        // Where a tension distribution holds the home pose (a random robot's home need not be an
        // equilibrium), the commanded unstretched lengths must give it back, and lengths a
        // little off a stationary pose near it.
        const double weight_N = r.platform_mass_kg * r.gravity_mps2;
        const TensionDistribution t = DistributeTensions(WrenchMatrix<double>(r, q0), GravityWrench<double>(r, q0),
                                                         r.tension_min_N, r.tension_max_N, weight_N);
        if (t.feasibility == Feasibility::kNoEquilibrium) continue;
        SpatialPose<double> guess = q0;
        guess(2) += 0.01;
        guess(5) += 0.01;
        const Eigen::VectorXd L = CommandedUnstretchedLengths(r, l0, t.tensions_N);
        const SpatialForwardResult f = SolveForwardStatics(r, L, &guess);
        if (f.status != ForwardStatus::kConverged) {
          // Only a stability verdict may refuse it (a distribution balances; with elastic
          // cables it need not be a minimum of the energy).
          EXPECT_EQ(f.status, ForwardStatus::kUnstable) << r.name;
          continue;
        }
        Eigen::VectorXd k(m);  // the axial stiffness EA / L of each cable at the commanded lengths
        for (int i = 0; i < m; ++i) {
          k(i) = r.cables[i].stiffness_N ? *r.cables[i].stiffness_N / L(i) : std::numeric_limits<double>::infinity();
        }
        if (!StaticStability(r, q0, t.tensions_N, k).stable) {
          // The distribution balances q0, but the elastic energy has no minimum there: the
          // platform settles elsewhere, and what is asked is a stable equilibrium (random-6-2
          // of this stream: the smallest eigenvalue -274 at q0, settled 0.13 rad away).
          EXPECT_TRUE(f.equilibrium.stable) << r.name;
          EXPECT_LT(EquilibriumResidual<double>(r, f.equilibrium.q, f.equilibrium.tensions_N).norm() / weight_N, 1e-9)
              << r.name;
          ++unstable_home;
          continue;
        }
        EXPECT_LT((f.equilibrium.q - q0).cwiseAbs().maxCoeff(), 1e-9) << r.name;
        EXPECT_LT((f.equilibrium.tensions_N - t.tensions_N).cwiseAbs().maxCoeff(), 1e-6 * r.tension_max_N) << r.name;
        ++exact;
        Eigen::VectorXd L_off = L;
        for (int i = 0; i < m; ++i) L_off(i) += rng.Uniform(-1e-6, 1e-6);  // stiff cables: 1 um is newtons
        const SpatialForwardResult g = SolveForwardStatics(r, L_off, &q0);
        if (g.status != ForwardStatus::kConverged) continue;  // e.g. a rigid cable unloaded
        ExpectStationarySpatial(r, L_off, g, r.name + " off");
        ++stationary;
      } else {
        // Underactuated: every cable elastic and shorter than at home, the platform swings to
        // where gravity lies in the span of the cables' pulls (a random robot's home is no
        // equilibrium: often far, another assembly); stationary wherever it settles near.
        for (SpatialCable& c : r.cables) c.stiffness_N = 1e6;
        const Eigen::VectorXd L = l0 * (1.0 - 1e-3);
        const SpatialForwardResult g = SolveForwardStatics(r, L, &q0);
        if (g.status != ForwardStatus::kConverged) continue;
        ExpectStationarySpatial(r, L, g, r.name + " underactuated");
        ++underactuated;
      }
    }
  }
  EXPECT_GE(exact, 10);
  EXPECT_GE(stationary, 8);
  std::printf("random spatial: %d exact, %d stationary, %d underactuated, %d unstable homes settled elsewhere\n", exact,
              stationary, underactuated, unstable_home);
}

TEST(ForwardStatics, CommandedUnstretchedLengths) {
  const Robot p4 = WithStiffness(LoadRepoRobot("planar4_fully_constrained"), 5.0e4);  // a 1.5 mm braided Dyneema line
  const Eigen::VectorXd l = Eigen::Vector4d(1.0, 2.0, 1.5, 1.2), t = Eigen::Vector4d(10.0, 50.0, 0.0, 150.0);
  const Eigen::VectorXd L = CommandedUnstretchedLengths(p4, l, t);
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(L(i) * (1.0 + t(i) / *p4.cables[i].stiffness_N), l(i), 1e-15);
  Robot rigid = p4;
  rigid.cables[1].stiffness_N.reset();
  EXPECT_EQ(CommandedUnstretchedLengths(rigid, l, t)(1), l(1));
}

// (e) in the library: a spatial robot with more rigid cables than its 6 freedoms cannot be
// simulated, named by key (a planar one keeps the rigid-cable convention: SettlePlanar).
TEST(ForwardStatics, CheckSimulatableNamesTheKey) {
  SpatialRobot cogiro = LoadRepoSpatialRobot("cogiro");
  for (SpatialCable& c : cogiro.cables) c.stiffness_N.reset();
  EXPECT_THROW(CheckSimulatable(cogiro), InputError);
  cogiro.cables[5].stiffness_N = 1e6;
  cogiro.cables[7].stiffness_N = 1e6;
  EXPECT_NO_THROW(CheckSimulatable(cogiro));
}

}  // namespace
}  // namespace cablecal
