// The design on robots nobody tuned for, and plans that survive the unknown true geometry.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <unistd.h>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "tests/support/temp_dir.h"
#include "common/error.h"
#include "common/random.h"
#include "design/design.h"
#include "design/robust.h"
#include "identify/experiment.h"
#include "identify/identify.h"
#include "model/statics.h"
#include "tests/support/random_robot.h"

namespace cablecal {
namespace {

// robots/asymmetric.yaml: exits at different heights below the frame top, offset centre of
// mass, anchors off the bar line, unequal radii.
Robot AsymmetricRobot() { return LoadRobotFile(CABLECAL_SOURCE_DIR "/robots/asymmetric.yaml"); }

std::vector<Eigen::Vector3d> PosesOf(const std::vector<PlanPose>& plan) {
  std::vector<Eigen::Vector3d> q;
  for (const PlanPose& p : plan) q.push_back(p.q);
  return q;
}

// Share of (true robot, pose) pairs a plan cannot hold: for `robots` true geometries drawn
// from N(nominal, sigma^2) per parameter, the commanded lengths of every pose are given to the
// forward model, and the settled pose must be a feasible pose of the true robot.
double UnholdableShare(const Robot& nominal, const std::vector<PlanPose>& plan, double sigma_m, int robots) {
  Rng rng(12345);
  int bad = 0, total = 0;
  for (int k = 0; k < robots; ++k) {
    const Robot truth = PerturbGeometry(nominal, sigma_m, rng);
    const Eigen::VectorXd l0 = InitialLengths(truth);
    for (const PlanPose& p : plan) {
      ++total;
      const ForwardResult f = SolveForwardGeometricoStatic(truth, Eigen::VectorXd(p.length_change_m + l0), &p.q);
      if (f.status != ForwardStatus::kConverged ||
          CheckFeasibility(truth, f.equilibrium.q, f.equilibrium.tensions_N) != Feasibility::kFeasible) {
        ++bad;
      }
    }
  }
  return static_cast<double>(bad) / total;
}

// 40 robots drawn at random (fixed seed) in two shards of 20 so that ctest runs them side by
// side; each shard may miss at most once, so the whole draw succeeds on at least 38 of 40.
class RandomRobots : public ::testing::TestWithParam<int> {};

TEST_P(RandomRobots, DesignSucceedsAndBeatsTheRandomMedianByTwo) {
  const int shard = GetParam();
  Rng rng(StreamSeed(2026, {static_cast<std::uint64_t>(shard)}));
  int misses = 0;
  std::string report;
  for (int k = 0; k < 20; ++k) {
    const std::string name = "random robot " + std::to_string(20 * shard + k);
    const Robot robot = testing::RandomValidRobot(rng, name);
    bool ok = true;
    std::string why;
    for (const int n : {6, 12}) {
      DesignOptions options;
      options.poses = n;
      options.starts = 2;
      options.random_sets = 24;
      options.seed = 7;
      try {
        const DesignResult r = DesignPoses(robot, options);
        const double factor = Improvement(options.criterion, r.criteria, r.random_median);
        if (!(factor >= 2.0)) {
          ok = false;
          why += " n=" + std::to_string(n) + ": only " + std::to_string(factor) + "x the random median;";
        }
        for (const PlanPose& p : r.poses) {
          EXPECT_EQ(CheckFeasibility(robot, p.q, p.tensions_N), Feasibility::kFeasible) << name;
          for (int i = 0; i < 2; ++i) {
            EXPECT_GE(p.tensions_worst_min_N(i), robot.tension_min_N - 1e-6) << name;
            EXPECT_LE(p.tensions_worst_max_N(i), robot.tension_max_N + 1e-6) << name;
          }
        }
      } catch (const SolverFailure& e) {
        ok = false;
        why += " n=" + std::to_string(n) + ": " + e.what() + ";";
      }
    }
    if (!ok) {
      ++misses;
      report += name + ":" + why + "\n";
    }
  }
  EXPECT_LE(misses, 1) << report;
  if (!report.empty()) std::printf("%s", report.c_str());
}

INSTANTIATE_TEST_SUITE_P(Shards, RandomRobots, ::testing::Values(0, 1));

TEST(RobustDesign, AsymmetricRobotAtEightAndTwelvePosesIsAtMostHalfTheRandomMedian) {
  const Robot robot = AsymmetricRobot();
  for (const int n : {8, 12}) {
    DesignOptions options;
    options.poses = n;
    options.criterion = Criterion::kCondition;
    options.starts = 3;
    options.random_sets = 40;
    const DesignResult r = DesignPoses(robot, options);
    EXPECT_LE(r.criteria.condition_number, 0.5 * r.random_median.condition_number) << "n = " << n;
  }
}

// The property the robustness rows exist for: a plan designed for sigma = 1 cm is held by
// true robots 1 cm off nominal, while a plan designed without them is not.
TEST(RobustDesign, RobustPlansSurviveTheTrueGeometryNominalOnesDoNot) {
  const Robot robot = AsymmetricRobot();
  DesignOptions options;
  options.poses = 10;
  options.criterion = Criterion::kCondition;
  options.starts = 3;
  options.random_sets = 0;
  const DesignResult robust = DesignPoses(robot, options);
  options.geometry_sigma_m = 0.0;
  const DesignResult nominal = DesignPoses(robot, options);
  const double robust_share = UnholdableShare(robot, robust.poses, 0.01, 100);
  const double nominal_share = UnholdableShare(robot, nominal.poses, 0.01, 100);
  std::printf("unholdable (true robot, pose) pairs: robust plan %.2f %%, nominal plan %.2f %%\n", 100 * robust_share,
              100 * nominal_share);
  // Linearised 3 sigma bounds checked at 12 axis scenarios leave a little exposed (README).
  EXPECT_LE(robust_share, 0.02) << "nominal design: " << nominal_share;
  EXPECT_GE(nominal_share, 0.05) << "robust design: " << robust_share;
}

// The linearised sensitivities of robust.h against finite differences of the forward model.
TEST(RobustDesign, TensionSpreadMatchesTheForwardModel) {
  const Robot robot = AsymmetricRobot();
  const Eigen::VectorXd l0 = InitialLengths(robot);
  const EquilibriumResult eq = SolveEquilibrium(robot, 1.6, 1.0);
  ASSERT_EQ(eq.status, EquilibriumStatus::kFound);
  Eigen::Matrix<double, 5, 1> y;
  y << eq.equilibrium.q, eq.equilibrium.tensions_N;
  internal::PoseRobustness at;
  ASSERT_TRUE(internal::RobustQuantities(robot, internal::FramePoints(robot), y, &at));
  const std::vector<double>& spread = at.spread;
  const PlanPose p = MakePlanPose(robot, eq.equilibrium, l0);
  const GeometryVector g0 = GeometryOf(robot);
  constexpr double h = 1e-5;
  for (int i = 0; i < 2; ++i) {
    double sum2 = 0.0;
    for (int k = 0; k < 6; ++k) {
      double t[2];
      for (int s = 0; s < 2; ++s) {
        GeometryVector g = g0;
        g(k) += s ? h : -h;
        const Robot truth = WithGeometry(robot, g);
        const ForwardResult f = SolveForwardGeometricoStatic(truth, Eigen::VectorXd(p.length_change_m + g.tail<2>()), &p.q);
        ASSERT_EQ(f.status, ForwardStatus::kConverged);
        t[s] = f.equilibrium.tensions_N(i);
      }
      sum2 += std::pow((t[1] - t[0]) / (2 * h), 2);
    }
    EXPECT_NEAR(spread[i], std::sqrt(sum2), 1e-4 * std::sqrt(sum2)) << "cable " << i + 1;
  }
}

// Calibrating in rounds: round 1 (8 poses) is identified; LoadDesignPrior turns its result.yaml
// into the next round's nominal robot and prior information; the second round then plans
// around the estimate and counts what is already known.
TEST(DesignPrior, SecondRoundCountsTheFirstRoundsInformation) {
  const Robot robot = AsymmetricRobot();
  DesignOptions options;
  options.poses = 8;
  options.starts = 2;
  options.random_sets = 0;
  const DesignResult first = DesignPoses(robot, options);
  Rng rng(3);
  const Robot truth = PerturbGeometry(robot, 0.01, rng);
  const SimulatedExperiment sim = SimulateExperiment(robot, truth, first.poses, SimulationOptions{}, rng);
  const IdentifyResult id = Identify(robot, sim.measurements, IdentifyOptions{});
  ASSERT_TRUE(id.converged());
  const testing_support::TempDir tmp;
  const std::string dir = tmp.path().string();
  const std::string path = dir + "/result.yaml";
  std::ofstream(path) << IdentifyResultYaml(id, "test");

  const DesignPrior prior = LoadDesignPrior(robot, path);
  // The next round's nominal robot is the estimate.
  const GeometryVector g = GeometryOf(prior.robot);
  for (int k = 0; k < 6; ++k) EXPECT_NEAR(g(k), id.geometry(k), 1e-12) << kGeometryNames[k];
  // Its information is the inverse of the estimated covariance of a1z a2x a2z l10 l20.
  PriorInformation cov;
  for (int a = 0; a < 5; ++a) {
    for (int b = 0; b < 5; ++b) {
      cov(a, b) = id.geometry_correlation(a + 1, b + 1) * id.geometry_std(a + 1) * id.geometry_std(b + 1);
    }
  }
  EXPECT_LT((prior.information * cov - PriorInformation::Identity()).cwiseAbs().maxCoeff(), 1e-6);

  options.prior_information = prior.information;
  const DesignResult second = DesignPoses(prior.robot, options);
  // Prior plus new poses beats either alone on the A criterion.
  const double prior_trace = cov.trace();
  EXPECT_LT(second.criteria.a_trace_covariance_m2, 0.9 * prior_trace);
  const CriteriaValues alone = EvaluateCriteria(prior.robot, PosesOf(second.poses));
  const CriteriaValues both = EvaluateCriteria(prior.robot, PosesOf(second.poses), &prior.information);
  EXPECT_NEAR(both.a_trace_covariance_m2, second.criteria.a_trace_covariance_m2,
              1e-9 * second.criteria.a_trace_covariance_m2);
  EXPECT_LT(second.criteria.a_trace_covariance_m2, 0.9 * alone.a_trace_covariance_m2);

  // What cannot be a prior.
  options.criterion = Criterion::kCondition;
  EXPECT_THROW(DesignPoses(prior.robot, options), InputError);
  EXPECT_THROW(LoadDesignPrior(robot, dir + "/missing.yaml"), InputError);
  std::ofstream(dir + "/bad.yaml") << "status: not_converged\nparameters: {}\n";
  EXPECT_THROW(LoadDesignPrior(robot, dir + "/bad.yaml"), InputError);
  std::ofstream(dir + "/notyaml.yaml") << "a: [\n";
  EXPECT_THROW(LoadDesignPrior(robot, dir + "/notyaml.yaml"), InputError);
}

}  // namespace
}  // namespace cablecal
