// The design on robots nobody tuned for, and plans that survive the unknown true geometry.
#include <gtest/gtest.h>
#include <omp.h>

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
#include "experiment/experiment.h"
#include "identify/identify.h"
#include "experiment/simulation.h"
#include "model/forward_statics.h"
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

// Where a true robot settles with a plan pose's commands, as simulate's true robot does
// (experiment/simulation.h): its home unstretched lengths plus the cable paid out.
ForwardResult Settle(const Robot& nominal, const Robot& truth, const Eigen::VectorXd& true_initial_lengths_m,
                     const PlanPose& p) {
  const Eigen::VectorXd lengths =
      HomeUnstretchedLengths(truth, true_initial_lengths_m) + CableCommands(nominal).PaidOutFromHome(p);
  return SettlePlanar(truth, lengths, &p.q);
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
      const ForwardResult f = Settle(nominal, truth, l0, p);
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
  Eigen::VectorXd y(5);
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

// ---------------------------------------------------------------------------------------------
// Any number of cables.

Robot RobotFile(const std::string& name) { return LoadRobotFile(std::string(CABLECAL_SOURCE_DIR "/robots/") + name); }

// A designed pose of a robot with m >= 3 cables is a feasible full pose of the model, and the
// plan lists the model's tension distribution there, its lengths and length changes.
void ExpectFeasibleFullPoses(const Robot& robot, const std::vector<PlanPose>& plan) {
  const Eigen::VectorXd l0 = InitialLengths(robot);
  for (std::size_t j = 0; j < plan.size(); ++j) {
    const PlanPose& p = plan[j];
    const PoseEvaluation e = EvaluatePose(robot, p.q);
    EXPECT_TRUE(e.feasible()) << robot.name << " pose " << j + 1 << ": " << ToString(e.feasibility);
    EXPECT_EQ(p.tensions_N, e.equilibrium.tensions_N) << robot.name << " pose " << j + 1;
    EXPECT_LT(EquilibriumResidual<double>(robot, p.q, p.tensions_N).norm(), 1e-8) << robot.name;
    EXPECT_LT((p.lengths_m - CableLengths(robot, p.q)).cwiseAbs().maxCoeff(), 1e-12) << robot.name;
    EXPECT_LT((p.length_change_m - (p.lengths_m - l0)).cwiseAbs().maxCoeff(), 1e-12) << robot.name;
    ASSERT_EQ(p.tensions_worst_min_N.size(), robot.num_cables());
    for (int i = 0; i < robot.num_cables(); ++i) {
      EXPECT_GE(p.tensions_worst_min_N(i), robot.tension_min_N - 1e-6) << robot.name << " pose " << j + 1;
      EXPECT_LE(p.tensions_worst_max_N(i), robot.tension_max_N + 1e-6) << robot.name << " pose " << j + 1;
    }
  }
}

// The scenario true robots: each of the 3m geometric parameters moved by +-k_sigma alone; every
// pose's commanded lengths (plus the true initial lengths) must be held: the forward model
// converges near the commanded pose to a feasible pose of that true robot. Returns the number
// of (scenario, pose) pairs that fail.
int UnholdableOnScenarioRobots(const Robot& robot, const std::vector<PlanPose>& plan, double k_sigma_m) {
  const Eigen::VectorXd g0 = GeometryOf(robot);
  EXPECT_EQ(g0.size(), 3 * robot.num_cables());
  int bad = 0;
  for (int k = 0; k < g0.size(); ++k) {
    for (const double sign : {-1.0, 1.0}) {
      Eigen::VectorXd g = g0;
      g(k) += sign * k_sigma_m;
      const Robot truth = WithGeometry(robot, g);
      const Eigen::VectorXd l0 = InitialLengths(truth);
      for (const PlanPose& p : plan) {
        const ForwardResult f = Settle(robot, truth, l0, p);
        if (f.status != ForwardStatus::kConverged ||
            CheckFeasibility(truth, f.equilibrium.q, f.equilibrium.tensions_N) != Feasibility::kFeasible ||
            (f.equilibrium.q - p.q).head<2>().norm() > 0.1) {
          ++bad;
        }
      }
    }
  }
  return bad;
}

// Issue 14's "must show": design --poses 10 with the defaults (criterion A, 3 x 1 cm robustness)
// on the 3- and 4-cable robots returns poses every check holds and beats the random median by 2x.
class ManyCables : public ::testing::TestWithParam<const char*> {};

// The robots' files spread their cable lines (README, "Any number of cables"): with lines that
// nearly meet at the platform, no pose holds on every 3 x 1 cm true robot and design exits 3.
TEST_P(ManyCables, TenPosesHoldableAndTwiceBetterThanTheRandomMedian) {
  const Robot robot = RobotFile(GetParam());
  DesignOptions options;
  options.poses = 10;
  options.starts = 4;
  options.random_sets = 50;
  const DesignResult r = DesignPoses(robot, options);
  ASSERT_EQ(r.poses.size(), 10u);
  EXPECT_EQ(r.num_cables, robot.num_cables());
  ExpectFeasibleFullPoses(robot, r.poses);
  EXPECT_EQ(UnholdableOnScenarioRobots(robot, r.poses, options.robust_sigmas * options.geometry_sigma_m), 0);
  // theta is a design variable: the poses do not all share one orientation.
  double theta_lo = 1e9, theta_hi = -1e9;
  for (const PlanPose& p : r.poses) {
    theta_lo = std::min(theta_lo, p.q(2));
    theta_hi = std::max(theta_hi, p.q(2));
  }
  EXPECT_GT(theta_hi - theta_lo, 1e-3) << robot.name;
  const double factor = Improvement(options.criterion, r.criteria, r.random_median);
  std::printf("%s: A %.4g m^2 against the random median %.4g m^2: %.2fx; %d of %d starts converged\n",
              robot.name.c_str(), r.criteria.a_trace_covariance_m2, r.random_median.a_trace_covariance_m2, factor,
              r.converged_starts, options.starts);
  EXPECT_GE(factor, 2.0) << robot.name;
}

INSTANTIATE_TEST_SUITE_P(Robots, ManyCables,
                         ::testing::Values("planar3_suspended.yaml", "planar4_fully_constrained.yaml"),
                         [](const auto& info) { return std::string(info.param).substr(0, 7); });

// Property: on random robots with 3 to 5 cables, suspended and fully constrained, the design
// converges and returns verified, holdable poses. RandomRobotWithCables' platforms are small
// (0.3-0.6 m) in 2.5-4.5 m frames with every cable converging on them, so with rigid cables a
// centimetre of length error turns them by 0.1-0.3 rad: at the default 3 x 1 cm most have no
// robust workspace (design says so, below); the property is checked for a geometry known to
// 1 mm (3 x 1 mm).
struct CableCase {
  int m;
  bool fully_constrained;
};

class RandomRobotsWithCables : public ::testing::TestWithParam<CableCase> {};

TEST_P(RandomRobotsWithCables, DesignConvergesToVerifiedPoses) {
  const CableCase c = GetParam();
  Rng rng(StreamSeed(14, {static_cast<std::uint64_t>(c.m), c.fully_constrained ? 1u : 0u}));
  const std::string name = "random robot, " + std::to_string(c.m) + " cables" + (c.fully_constrained ? ", fully constrained" : ", suspended");
  const Robot robot = testing::RandomRobotWithCables(rng, name, c.m, c.fully_constrained);
  DesignOptions options;
  options.poses = 8;
  options.starts = 2;
  options.random_sets = 20;
  options.geometry_sigma_m = 0.001;
  DesignResult r;
  try {
    r = DesignPoses(robot, options);
  } catch (const SolverFailure& e) {
    FAIL() << name << ": " << e.what();
  }
  EXPECT_GE(r.converged_starts, 1);
  ASSERT_EQ(r.poses.size(), 8u);
  ExpectFeasibleFullPoses(robot, r.poses);
  EXPECT_EQ(UnholdableOnScenarioRobots(robot, r.poses, r.robust_sigmas_achieved * options.geometry_sigma_m), 0) << name;
  EXPECT_TRUE(std::isfinite(r.criteria.a_trace_covariance_m2) && r.criteria.a_trace_covariance_m2 > 0.0) << name;
  std::printf("%s: %d of 2 starts converged, %d verified; A %.4g m^2, %.2fx the median of 20 random sets\n",
              name.c_str(), r.converged_starts,
              static_cast<int>(std::count_if(r.starts.begin(), r.starts.end(), [](const StartReport& s) { return s.verified; })),
              r.criteria.a_trace_covariance_m2, Improvement(options.criterion, r.criteria, r.random_median));
}

INSTANTIATE_TEST_SUITE_P(Cables, RandomRobotsWithCables,
                         ::testing::Values(CableCase{3, false}, CableCase{3, true}, CableCase{4, false},
                                           CableCase{4, true}, CableCase{5, false}, CableCase{5, true}),
                         [](const auto& info) {
                           return std::to_string(info.param.m) + (info.param.fully_constrained ? "_full" : "_suspended");
                         });

// The starts of robots with 3 or more cables (the least robustness-violating of several draws
// per pose) are as deterministic as the rest: the thread count changes nothing.
TEST(RobustDesign, ManyCablesSameResultWhateverTheThreadCount) {
  Rng rng(StreamSeed(14, {4u, 0u}));
  const Robot robot = testing::RandomRobotWithCables(rng, "random robot, 4 cables", 4, false);
  DesignOptions options;
  options.poses = 6;
  options.starts = 3;
  options.random_sets = 8;
  options.geometry_sigma_m = 0.001;
  omp_set_num_threads(1);
  const DesignResult one = DesignPoses(robot, options);
  omp_set_num_threads(2);
  const DesignResult two = DesignPoses(robot, options);
  EXPECT_EQ(PosePlanCsv(one.poses, ""), PosePlanCsv(two.poses, ""));
  EXPECT_EQ(one.best_start, two.best_start);
  EXPECT_EQ(one.random_median.a_trace_covariance_m2, two.random_median.a_trace_covariance_m2);
}

// Central-difference derivatives of the forward model with respect to geometry parameter k of a
// true robot, at the commanded lengths of `p`: the settled pose (and, through `tensions`, what
// the caller makes of the true robot there).
template <typename F>
Eigen::VectorXd ForwardDifference(const Robot& robot, const PlanPose& p, int k, double h, F quantity) {
  Eigen::VectorXd at[2];
  for (int s = 0; s < 2; ++s) {
    Eigen::VectorXd g = GeometryOf(robot);
    g(k) += s ? h : -h;
    const Robot truth = WithGeometry(robot, g);
    const ForwardResult f = Settle(robot, truth, InitialLengths(truth), p);
    EXPECT_EQ(f.status, ForwardStatus::kConverged);
    at[s] = quantity(truth, f.equilibrium);
  }
  return (at[1] - at[0]) / (2 * h);
}

// m = 3: the implicit-function sensitivities of robust.h against the forward model, for every
// tension (unique) and for theta and z.
TEST(RobustDesign, ThreeCableSpreadsMatchTheForwardModel) {
  const Robot robot = RobotFile("planar3_suspended.yaml");
  const PoseEvaluation e = HomeEvaluation(robot);
  ASSERT_TRUE(e.feasible());
  const PlanPose p = MakePlanPose(robot, e.equilibrium, InitialLengths(robot));
  Eigen::VectorXd y(6);
  y << p.q, p.tensions_N;
  internal::PoseRobustness at;
  ASSERT_TRUE(internal::RobustQuantities(robot, internal::FramePoints(robot), y, &at));
  Eigen::VectorXd sum2 = Eigen::VectorXd::Zero(5);  // t1 t2 t3 theta z
  for (int k = 0; k < 9; ++k) {
    const Eigen::VectorXd d = ForwardDifference(robot, p, k, 1e-5, [](const Robot&, const Equilibrium& eq) {
      Eigen::VectorXd v(5);
      v << eq.tensions_N, eq.q(2), eq.q(1);
      return v;
    });
    sum2 += d.cwiseAbs2();
  }
  for (int c = 0; c < 5; ++c) {
    const double fd = std::sqrt(sum2(c));
    EXPECT_NEAR(at.spread[c], fd, 1e-4 * fd + 1e-9) << "quantity " << c;
    EXPECT_GT(fd, 0.0);
  }
}

// m = 4: the least-squares pose of the commanded lengths (theta, z and the frame points' spreads
// against the forward model), and the tension rule: the tensions on a true robot are the
// design's vector corrected by the least change that restores equilibrium at the pose it
// settles in, -W^+ (W_true t + w_g,true), reconstructed here from the forward model.
TEST(RobustDesign, FourCableSpreadsMatchTheForwardModelAndTheTensionRule) {
  const Robot robot = RobotFile("planar4_fully_constrained.yaml");
  const PoseEvaluation e = EvaluatePose(robot, Eigen::Vector3d(1.3, 1.1, 0.05));
  ASSERT_TRUE(e.feasible());
  const PlanPose p = MakePlanPose(robot, e.equilibrium, InitialLengths(robot));
  // Not the minimum-norm distribution: some other vector within bounds (internal force added).
  const Eigen::Matrix<double, 3, Eigen::Dynamic> W = WrenchMatrix<double>(robot, Pose<double>(p.q));
  const Eigen::FullPivLU<Eigen::MatrixXd> lu(W);
  const Eigen::VectorXd null = lu.kernel().col(0).normalized();
  const Eigen::VectorXd t = p.tensions_N + 3.0 * (null(0) > 0 ? null : Eigen::VectorXd(-null));
  ASSERT_LT(EquilibriumResidual<double>(robot, p.q, t).norm(), 1e-9);
  Eigen::VectorXd y(7);
  y << p.q, t;
  internal::PoseRobustness at;
  ASSERT_TRUE(internal::RobustQuantities(robot, internal::FramePoints(robot), y, &at));
  const Eigen::MatrixXd W_pinv = W.transpose() * (W * W.transpose()).inverse();
  const std::vector<Eigen::Vector2d> points = internal::FramePoints(robot);
  const int np = static_cast<int>(points.size());
  Eigen::VectorXd sum2 = Eigen::VectorXd::Zero(4 + 2 + 2 * np);  // t1..t4 theta z, then frame points
  for (int k = 0; k < 12; ++k) {
    const Eigen::VectorXd d = ForwardDifference(robot, p, k, 1e-5, [&](const Robot& truth, const Equilibrium& eq) {
      Eigen::VectorXd v(4 + 2 + 2 * np);
      v.head(4) = t - W_pinv * EquilibriumResidual<double>(truth, eq.q, t);
      v(4) = eq.q(2);
      v(5) = eq.q(1);
      for (int i = 0; i < np; ++i) v.segment(6 + 2 * i, 2) = PlatformPointInF<double>(eq.q, points[i]);
      return v;
    });
    sum2 += d.cwiseAbs2();
  }
  // PoseQuantities' order: t1..t4, theta, z, 4 clearances, then x and z of each frame point.
  std::vector<int> index = {0, 1, 2, 3, 4, 5};
  for (int i = 0; i < 2 * np; ++i) index.push_back(10 + i);
  for (int c = 0; c < static_cast<int>(index.size()); ++c) {
    const double fd = std::sqrt(sum2(c));
    EXPECT_NEAR(at.spread[index[c]], fd, 1e-4 * fd + 1e-9) << "quantity " << index[c];
  }
  for (int i = 0; i < 4; ++i) EXPECT_GT(std::sqrt(sum2(i)), 0.0);
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
  for (int k = 0; k < 6; ++k) EXPECT_NEAR(g(k), id.geometry(k), 1e-12) << GeometryNames(2)[k];
  // Its information is the inverse of the estimated covariance of a1z a2x a2z l10 l20.
  PriorInformation cov(5, 5);
  for (int a = 0; a < 5; ++a) {
    for (int b = 0; b < 5; ++b) {
      cov(a, b) = id.geometry_correlation(a + 1, b + 1) * id.geometry_std(a + 1) * id.geometry_std(b + 1);
    }
  }
  EXPECT_LT((prior.information * cov - PriorInformation::Identity(5, 5)).cwiseAbs().maxCoeff(), 1e-6);

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
