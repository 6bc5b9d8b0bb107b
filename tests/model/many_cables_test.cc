// Statics of robots with 3 to 8 cables: the tension distribution (unique for 3 cables, the
// minimum-norm one within bounds for 4 and more), the full-pose feasibility test, and the
// forward kinematics, on the two robot files with more cables and on random robots.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "common/random.h"
#include "model/cable.h"
#include "model/statics.h"
#include "tests/support/random_robot.h"
#include "tests/support/random_spatial_robot.h"

namespace cablecal {
namespace {

Robot RobotFile(const char* name) { return LoadRobotFile(std::string(CABLECAL_SOURCE_DIR) + "/robots/" + name); }

// Robots with m = 3..8 cables: the two files, then random suspended and fully constrained ones.
std::vector<Robot> ManyCableRobots() {
  std::vector<Robot> robots = {RobotFile("planar3_suspended.yaml"), RobotFile("planar4_fully_constrained.yaml")};
  Rng rng(2024);
  for (int m = 3; m <= 8; ++m) {
    robots.push_back(testing::RandomRobotWithCables(rng, "suspended" + std::to_string(m), m, false));
    if (m >= 4) robots.push_back(testing::RandomRobotWithCables(rng, "constrained" + std::to_string(m), m, true));
  }
  return robots;
}

// A pose drawn over the frame box and the inclinometer range.
Eigen::Vector3d RandomPose(const Robot& r, Rng& rng) {
  // theta, z, x: the order GCC drew the arguments this replaced (tests/support/random_robot.h).
  const double theta = rng.Uniform(-r.theta_max_rad, r.theta_max_rad);
  const double z = rng.Uniform(r.margin_m, std::min(r.frame_height_m - r.margin_m, r.laser_range_m));
  const double x = rng.Uniform(r.margin_m, r.frame_width_m - r.margin_m);
  return Eigen::Vector3d(x, z, theta);
}

// The exact minimum-norm distribution of a 4-cable robot, independently of the LDP: the null
// space of W is one line t = t_p + lambda n, the bounds cut it to an interval of lambda, and the
// point of least norm is the unconstrained minimiser (lambda = -n't_p) clamped to it.
bool ExactFourCableDistribution(const Robot& r, const Eigen::Vector3d& q, Eigen::VectorXd* t) {
  const Eigen::Matrix<double, 3, Eigen::Dynamic> W = WrenchMatrix<double>(r, q);
  const Eigen::Matrix<double, 3, 4> W4 = W;
  Eigen::FullPivLU<Eigen::Matrix<double, 3, 4>> lu(W4);
  const Eigen::Vector4d n = lu.kernel().col(0).normalized();
  const Eigen::Vector4d t_any = lu.solve(-GravityWrench<double>(r, q));
  const Eigen::Vector4d t_p = t_any - n * n.dot(t_any);
  double lo = -1e300, hi = 1e300;
  for (int i = 0; i < 4; ++i) {
    if (std::abs(n(i)) < 1e-14) {
      if (t_p(i) < r.tension_min_N || t_p(i) > r.tension_max_N) return false;
      continue;
    }
    const double a = (r.tension_min_N - t_p(i)) / n(i), b = (r.tension_max_N - t_p(i)) / n(i);
    lo = std::max(lo, std::min(a, b));
    hi = std::min(hi, std::max(a, b));
  }
  if (lo > hi) return false;
  *t = t_p + n * std::clamp(0.0, lo, hi);  // t_p is orthogonal to n: |t|^2 = |t_p|^2 + lambda^2
  return true;
}

TEST(ManyCables, FourCableDistributionIsTheExactMinimumNorm) {
  Rng rng(5);
  std::vector<Robot> robots = {RobotFile("planar4_fully_constrained.yaml")};
  for (int k = 0; k < 4; ++k) robots.push_back(testing::RandomRobotWithCables(rng, "c4", 4, true));
  for (int k = 0; k < 2; ++k) robots.push_back(testing::RandomRobotWithCables(rng, "s4", 4, false));
  int feasible = 0, infeasible = 0;
  for (const Robot& r : robots) {
    for (int k = 0; k < 400; ++k) {
      const Eigen::Vector3d q = RandomPose(r, rng);
      bool valid = true;
      for (const Cable& c : r.cables) valid = valid && CableGeometryValid(CableAtPose<double>(c, q), c.pulley_radius_m);
      if (!valid) continue;
      const TensionDistribution d = DistributeTensions(r, q);
      Eigen::VectorXd exact;
      const bool exists = ExactFourCableDistribution(r, q, &exact);
      EXPECT_EQ(d.feasibility == Feasibility::kFeasible, exists) << r.name << " q " << q.transpose();
      if (exists && d.feasibility == Feasibility::kFeasible) {
        EXPECT_LT((d.tensions_N - exact).cwiseAbs().maxCoeff(), 1e-9 * r.tension_max_N) << r.name << " q " << q.transpose();
        ++feasible;
      } else {
        ++infeasible;
      }
    }
  }
  EXPECT_GT(feasible, 100);
  EXPECT_GT(infeasible, 100);
}

// For every m: a feasible distribution balances gravity within the bounds and no other tension
// vector within the bounds that balances gravity is shorter (sampled over the null space of W);
// an infeasible verdict has no such vector among the samples either.
TEST(ManyCables, DistributionBalancesWithinBoundsAndNoSampleIsShorter) {
  Rng rng(9);
  int feasible = 0;
  for (const Robot& r : ManyCableRobots()) {
    const double weight_N = r.platform_mass_kg * r.gravity_mps2;
    for (int k = 0; k < 150; ++k) {
      const Eigen::Vector3d q = RandomPose(r, rng);
      const TensionDistribution d = DistributeTensions(r, q);
      const Eigen::Matrix<double, 3, Eigen::Dynamic> W = WrenchMatrix<double>(r, q);
      if (!W.allFinite()) continue;
      Eigen::JacobiSVD<Eigen::MatrixXd> svd(W, Eigen::ComputeFullU | Eigen::ComputeFullV);
      const Eigen::VectorXd t_p = svd.solve(-GravityWrench<double>(r, q));
      const Eigen::MatrixXd N = svd.matrixV().rightCols(r.num_cables() - 3);
      const bool ok = d.feasibility == Feasibility::kFeasible;
      if (ok) {
        ++feasible;
        EXPECT_LT(EquilibriumResidual<double>(r, q, d.tensions_N).norm(), 1e-9 * weight_N) << r.name;
        EXPECT_GE(d.tensions_N.minCoeff(), r.tension_min_N) << r.name;
        EXPECT_LE(d.tensions_N.maxCoeff(), r.tension_max_N) << r.name;
      }
      if (N.cols() == 0) continue;
      const double scale = ok ? d.tensions_N.norm() : r.tension_max_N;
      for (int s = 0; s < 300; ++s) {
        Eigen::VectorXd lambda(N.cols());
        for (int c = 0; c < N.cols(); ++c) lambda(c) = rng.Normal(0.0, scale);
        Eigen::VectorXd t = t_p + N * lambda;
        if (ok) t = d.tensions_N + N * (lambda * rng.Uniform(0.0, 0.05));  // near the optimum too
        if (t.minCoeff() < r.tension_min_N || t.maxCoeff() > r.tension_max_N) continue;
        EXPECT_TRUE(ok) << r.name << ": a sample within bounds where the verdict is " << ToString(d.feasibility);
        if (ok) {
          EXPECT_GE(t.norm(), d.tensions_N.norm() - 1e-9 * weight_N) << r.name;
        }
      }
    }
  }
  EXPECT_GT(feasible, 100);
}

// The distribution written for any kind of robot, on 6-row wrench matrices (a spatial platform:
// force and moment) built from random cable directions and anchors, m = 6 to 12: m = 6 the
// unique solution of W t = -w_g; m = 7 the exact minimum norm by the one-line construction above,
// independent of the LDP; every m balances within bounds and no sampled balancing t within
// bounds is shorter. The planar robots' distribution is this function with 3 rows (above).
TEST(ManyCables, SixRowWrenchDistributionForAnyCableCount) {
  Rng rng(77);
  int feasible = 0, checked_exact = 0;
  for (int trial = 0; trial < 1400; ++trial) {
    const int m = trial < 400 ? 7 : 6 + trial % 7;  // m = 7 often: the exact comparison
    Eigen::MatrixXd W(6, m);
    for (int i = 0; i < m; ++i) {
      // Sequenced draws (an argument list's order is unspecified), last coordinate first.
      Eigen::Vector3d u;
      for (int a = 2; a >= 0; --a) u(a) = rng.Normal();
      u = u.normalized();
      u.z() = std::abs(u.z()) + 0.2;  // mostly upward: a suspended platform's cables
      u.normalize();
      const Eigen::Vector3d b = testing::DrawVector3(rng, {-0.3, -0.3, -0.1}, {0.3, 0.3, 0.1});
      W.col(i) << u, b.cross(u);
    }
    const double weight_N = rng.Uniform(10.0, 500.0);
    Eigen::VectorXd w_g(6);
    const Eigen::Vector3d com = testing::DrawVector3(rng, Eigen::Vector3d::Constant(-0.05), Eigen::Vector3d::Constant(0.05));
    const Eigen::Vector3d f_g(0.0, 0.0, -weight_N);
    w_g << f_g, com.cross(f_g);
    const double lo = 0.02 * weight_N, hi = 4.0 * weight_N;
    const TensionDistribution d = DistributeTensions(W, w_g, lo, hi, weight_N);
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(W, Eigen::ComputeFullU | Eigen::ComputeFullV);
    const Eigen::VectorXd t_p = svd.solve(-w_g);
    const bool ok = d.feasibility == Feasibility::kFeasible;
    if (ok) {
      ++feasible;
      EXPECT_LT((W * d.tensions_N + w_g).norm(), 1e-9 * weight_N) << "m = " << m;
      EXPECT_GE(d.tensions_N.minCoeff(), lo);
      EXPECT_LE(d.tensions_N.maxCoeff(), hi);
    }
    if (m == 6) {
      const bool within = t_p.minCoeff() >= lo && t_p.maxCoeff() <= hi;
      EXPECT_EQ(ok, within) << "m = 6: the unique solution decides";
      if (ok) {
        EXPECT_LT((d.tensions_N - t_p).cwiseAbs().maxCoeff(), 1e-9 * weight_N);
      }
      continue;
    }
    const Eigen::MatrixXd N = svd.matrixV().rightCols(m - 6);
    if (m == 7) {
      const Eigen::VectorXd n = N.col(0);
      double lambda_lo = -1e300, lambda_hi = 1e300;
      for (int i = 0; i < m; ++i) {
        const double a = (lo - t_p(i)) / n(i), b = (hi - t_p(i)) / n(i);
        lambda_lo = std::max(lambda_lo, std::min(a, b));
        lambda_hi = std::min(lambda_hi, std::max(a, b));
      }
      const bool exists = lambda_lo <= lambda_hi;
      EXPECT_EQ(ok, exists) << "m = 7";
      if (exists && ok) {
        const Eigen::VectorXd exact = t_p + n * std::clamp(0.0, lambda_lo, lambda_hi);
        EXPECT_LT((d.tensions_N - exact).cwiseAbs().maxCoeff(), 1e-9 * hi);
        ++checked_exact;
      }
    }
    for (int s = 0; s < 200; ++s) {
      Eigen::VectorXd lambda(N.cols());
      for (int c = 0; c < N.cols(); ++c) lambda(c) = rng.Normal(0.0, ok ? d.tensions_N.norm() : hi);
      Eigen::VectorXd t = t_p + N * lambda;
      if (ok) t = d.tensions_N + N * (lambda * rng.Uniform(0.0, 0.05));
      if (t.minCoeff() < lo || t.maxCoeff() > hi) continue;
      EXPECT_TRUE(ok) << "m = " << m << ": a sample within bounds where the verdict is " << ToString(d.feasibility);
      if (ok) {
        EXPECT_GE(t.norm(), d.tensions_N.norm() - 1e-9 * weight_N);
      }
    }
  }
  EXPECT_GT(feasible, 150);
  EXPECT_GT(checked_exact, 30);
  std::printf("six-row distributions: %d feasible of 1400, %d compared with the exact one (m = 7)\n", feasible,
              checked_exact);
}

// Forward kinematics: from the lengths at a feasible pose, with and without a guess, back to
// the pose and its tension distribution.
TEST(ManyCables, ForwardKinematicsRoundTrip) {
  Rng rng(13);
  int checked = 0;
  for (const Robot& r : ManyCableRobots()) {
    int found = 0;
    for (int k = 0; k < 20000 && found < 8; ++k) {
      const Eigen::Vector3d q = RandomPose(r, rng);
      const PoseEvaluation e = EvaluatePose(r, q);
      if (!e.feasible()) continue;
      ++found;
      const Eigen::VectorXd L = CableLengths(r, q);
      const Eigen::Vector3d guess = q + Eigen::Vector3d(0.01, -0.01, 0.01);
      for (const Eigen::Vector3d* g : {&guess, static_cast<const Eigen::Vector3d*>(nullptr)}) {
        const ForwardResult f = SolveForwardGeometricoStatic(r, L, g);
        if (!g && f.status != ForwardStatus::kConverged) continue;  // a cold start may find another assembly
        ASSERT_EQ(f.status, ForwardStatus::kConverged) << r.name << " q " << q.transpose();
        EXPECT_LT((f.equilibrium.q - q).cwiseAbs().maxCoeff(), 1e-9) << r.name << " q " << q.transpose();
        EXPECT_LT((f.equilibrium.tensions_N - e.equilibrium.tensions_N).cwiseAbs().maxCoeff(), 1e-6 * r.tension_max_N);
        EXPECT_LT(f.length_residual_m, 1e-11);
      }
      ++checked;
    }
    EXPECT_GT(found, 0) << r.name << ": no feasible pose in 20000 draws";
  }
  EXPECT_GT(checked, 60);
}

// With 4 or more cables, lengths the robot cannot meet all at once give the least-squares pose:
// the gradient J'r vanishes there while the residual does not.
TEST(ManyCables, InconsistentLengthsGiveTheLeastSquaresPose) {
  const Robot r = RobotFile("planar4_fully_constrained.yaml");
  const Eigen::Vector3d q(1.4, 0.9, 0.02);
  Eigen::VectorXd L = CableLengths(r, q);
  L(0) += 0.002;
  const ForwardResult f = SolveForwardGeometricoStatic(r, L, &q);
  ASSERT_EQ(f.status, ForwardStatus::kConverged);
  const Eigen::VectorXd residual = CableLengths(r, f.equilibrium.q) - L;
  const Eigen::MatrixXd J = -WrenchMatrix<double>(r, Pose<double>(f.equilibrium.q)).transpose();
  // At the least-squares pose the gradient J' r vanishes. Gauss-Newton stops on a step below
  // 1e-13 (m, rad), where J' r = J'J step is at most |J'J| 1e-13, about 1e-12 here: 1e-11
  // allows a tenfold margin, and a pose off the minimum by a micrometre fails it by far.
  EXPECT_LT((J.transpose() * residual).norm(), 1e-11);
  EXPECT_GT(f.length_residual_m, 1e-4);
  EXPECT_NEAR(f.length_residual_m, residual.cwiseAbs().maxCoeff(), 1e-15);
}

// A guess far from where the lengths put the platform: another assembly, said so.
TEST(ManyCables, FarFromTheGuessIsAnotherAssembly) {
  const Robot r = RobotFile("planar3_suspended.yaml");
  const Eigen::Vector3d q(1.5, 1.0, 8.0 * M_PI / 180.0);
  const Eigen::VectorXd L = CableLengths(r, q);
  const Eigen::Vector3d near = q + Eigen::Vector3d(0.02, 0.02, 0.01);
  EXPECT_EQ(SolveForwardGeometricoStatic(r, L, &near).status, ForwardStatus::kConverged);
  const Eigen::Vector3d far = q + Eigen::Vector3d(0.0, 0.0, 0.7);
  const ForwardResult f = SolveForwardGeometricoStatic(r, L, &far);
  EXPECT_NE(f.status, ForwardStatus::kConverged) << f.equilibrium.q.transpose();
}

TEST(ManyCables, FeasibilityReasonsKeepTheirNames) {
  const Robot p3 = RobotFile("planar3_suspended.yaml");
  const double home_theta = p3.home_theta_rad;
  EXPECT_TRUE(EvaluatePose(p3, Eigen::Vector3d(1.5, 1.0, home_theta)).feasible());
  EXPECT_EQ(EvaluatePose(p3, Eigen::Vector3d(-0.1, 1.0, 0.0)).feasibility, Feasibility::kOutsideFrame);
  EXPECT_EQ(EvaluatePose(p3, Eigen::Vector3d(1.5, 1.0, -20.0 * M_PI / 180.0)).feasibility, Feasibility::kNoEquilibrium);
  Robot narrow = p3;
  narrow.theta_max_rad = 2.0 * M_PI / 180.0;
  EXPECT_EQ(EvaluatePose(narrow, Eigen::Vector3d(1.5, 1.0, home_theta)).feasibility, Feasibility::kThetaLimit);
  Robot weak = p3;
  weak.tension_max_N = 2.0;
  EXPECT_EQ(EvaluatePose(weak, Eigen::Vector3d(1.5, 1.0, home_theta)).feasibility, Feasibility::kTensionHigh);
  Robot taut = p3;
  taut.tension_min_N = 6.0;
  EXPECT_EQ(EvaluatePose(taut, Eigen::Vector3d(1.5, 1.0, home_theta)).feasibility, Feasibility::kTensionLow);
  // The fully constrained robot holds its home pose with internal force: a minimum above the
  // weight's share still has a distribution, until no cable can be that slack.
  const Robot p4 = RobotFile("planar4_fully_constrained.yaml");
  const PoseEvaluation home = EvaluatePose(p4, Eigen::Vector3d(1.5, 1.0, 0.0));
  ASSERT_TRUE(home.feasible());
  EXPECT_NEAR(home.equilibrium.tensions_N.minCoeff(), p4.tension_min_N, 1e-9);  // the least internal force
  Robot p4_short = p4;
  p4_short.laser_range_m = 0.5;
  EXPECT_EQ(EvaluatePose(p4_short, Eigen::Vector3d(1.5, 1.0, 0.0)).feasibility, Feasibility::kLaserRange);
}

}  // namespace
}  // namespace cablecal
