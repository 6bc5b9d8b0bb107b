// Experiment design: derivatives (own finite differences and Ipopt's checker), the
// surrogates' bounds, quality against random sets, verification and determinism.
#include <gtest/gtest.h>
#include <omp.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "tests/support/temp_dir.h"
#include <yaml-cpp/yaml.h>

#include "common/error.h"
#include "common/format.h"
#include "common/random.h"
#include "common/version.h"
#include "design/design.h"
#include "design/ipopt_nlp.h"
#include "design/objective.h"
#include "model/cable.h"
#include "model/statics.h"

namespace cablecal {
namespace {

std::vector<Eigen::Vector3d> RandomSet(int n, std::uint64_t seed) {
  std::vector<Eigen::Vector3d> q;
  for (const PlanPose& p : SampleFeasiblePoses(BuiltinRobot(), n, seed)) q.push_back(p.q);
  return q;
}

class PerCriterion : public ::testing::TestWithParam<Criterion> {};

TEST_P(PerCriterion, GradientMatchesCentralDifferences) {
  const Robot& robot = BuiltinRobot();
  const auto poses = RandomSet(8, 31);
  Eigen::VectorXd g;
  const double f0 = internal::DesignObjective(robot, GetParam(), poses, &g);
  ASSERT_TRUE(std::isfinite(f0));
  for (int j = 0; j < 8; ++j) {
    for (int k = 0; k < 3; ++k) {
      // 1e-5: the criteria carry ~1e-12 of eigenvalue noise (see ipopt_nlp.cc).
      const double h = 1e-5;
      auto plus = poses, minus = poses;
      plus[j](k) += h;
      minus[j](k) -= h;
      const double fd = (internal::DesignObjective(robot, GetParam(), plus, nullptr) -
                         internal::DesignObjective(robot, GetParam(), minus, nullptr)) / (2 * h);
      EXPECT_NEAR(g(3 * j + k), fd, 1e-5 * std::max(1.0, std::abs(fd))) << "pose " << j << " coordinate " << k;
    }
  }
}

TEST_P(PerCriterion, IpoptDerivativeCheckerFindsNoError) {
  const Robot& robot = BuiltinRobot();
  DesignOptions options;
  options.poses = 7;
  options.criterion = GetParam();
  options.min_spacing_m = 0.1;  // exercise the spacing rows too
  options.derivative_test = true;
  const testing_support::TempDir tmp;
  options.ipopt_journal_path = tmp.Path("ipopt.txt");
  internal::SolveDesignNlp(robot, options, SampleFeasiblePoses(robot, 7, 5));
  std::ifstream in(options.ipopt_journal_path);
  std::stringstream journal;
  journal << in.rdbuf();
  EXPECT_NE(journal.str().find("No errors detected by derivative checker"), std::string::npos)
      << journal.str().substr(0, 4000);
}

INSTANTIATE_TEST_SUITE_P(Criteria, PerCriterion,
                         ::testing::Values(Criterion::kCondition, Criterion::kD, Criterion::kA, Criterion::kE),
                         [](const auto& info) { return std::string(ToString(info.param)); });

// The NLP sized from m: Ipopt's derivative checker over every row (equilibrium, robustness
// rows with their central-difference spread derivatives, spacing) on the 3- and 4-cable robots,
// where theta and every tension are free variables.
class ManyCablesNlp : public ::testing::TestWithParam<const char*> {};

TEST_P(ManyCablesNlp, IpoptDerivativeCheckerFindsNoError) {
  const Robot robot = LoadRobotFile(std::string(CABLECAL_SOURCE_DIR "/robots/") + GetParam());
  ASSERT_GE(robot.num_cables(), 3);
  DesignOptions options;
  options.poses = 6;
  options.min_spacing_m = 0.1;
  options.derivative_test = true;
  // The random start has poses near the edge of the tension workspace, where the spreads'
  // third derivatives make the checker's own forward differences at 1e-6 err by 1-3e-4
  // (central differences with Richardson extrapolation agree with the NLP's to 1e-6 there).
  options.derivative_test_perturbation = 1e-7;
  const testing_support::TempDir tmp;
  options.ipopt_journal_path = tmp.Path("ipopt.txt");
  const internal::StartOutcome out = internal::SolveDesignNlp(robot, options, SampleFeasiblePoses(robot, 6, 5));
  std::ifstream in(options.ipopt_journal_path);
  std::stringstream journal;
  journal << in.rdbuf();
  EXPECT_NE(journal.str().find("No errors detected by derivative checker"), std::string::npos)
      << journal.str().substr(0, 4000);
  // Variables per pose: x, z, theta and one tension per cable.
  EXPECT_NE(journal.str().find("Total number of variables............................:       " +
                               std::to_string(6 * (3 + robot.num_cables()))),
            std::string::npos);
  ASSERT_EQ(out.tensions_N.size(), 6u);
  EXPECT_EQ(out.tensions_N[0].size(), robot.num_cables());
}

INSTANTIATE_TEST_SUITE_P(Robots, ManyCablesNlp,
                         ::testing::Values("planar3_suspended.yaml", "planar4_fully_constrained.yaml"),
                         [](const auto& info) { return std::string(info.param).substr(0, 7); });

// A factor below 1 printed as "0.0341 x the median (> 1 is better)" read as an improvement.
TEST(Design, ComparisonWithTheRandomMedianSaysBetterOrWorse) {
  EXPECT_EQ(ImprovementText(0.0341, 100), "29.3 x worse than the median of 100 random sets");
  EXPECT_EQ(ImprovementText(3.2, 20), "3.2 x better than the median of 20 random sets");
  EXPECT_EQ(ImprovementText(1.004, 1), "as good as the median of 1 random set");
  EXPECT_EQ(ImprovementText(std::nan(""), 5), "not comparable with the median of 5 random sets");
}

TEST(Design, FewestPosesFollowTheCableCount) {
  // n (m - 1) net equations against 3m - 1 gauge-fixed parameters.
  EXPECT_EQ(MinDesignPoses(2), 5);
  for (int m = 3; m <= kMaxCables; ++m) {
    EXPECT_EQ(MinDesignPoses(m), 4) << m;
    EXPECT_GE(MinDesignPoses(m) * (m - 1), 3 * m - 1);
    EXPECT_LT((MinDesignPoses(m) - 1) * (m - 1), 3 * m - 1);
  }
  const Robot robot = LoadRobotFile(CABLECAL_SOURCE_DIR "/robots/planar3_suspended.yaml");
  DesignOptions options;
  options.poses = 3;
  try {
    DesignPoses(robot, options);
    ADD_FAILURE() << "3 poses accepted for 3 cables";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("at least 4 poses"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("the 8 gauge-fixed"), std::string::npos) << e.what();
  }
}

// A geometry so uncertain that no pose can stay within bounds for every true robot: held to
// that robustness (lower_robustness off, the Monte Carlo's first try), the failure says the
// robust workspace is empty and what to change, whatever the cable count; by default the
// design lowers the robustness instead and says so.
TEST(Design, EmptyRobustWorkspaceIsNamed) {
  for (const Robot& robot : {BuiltinRobot(), LoadRobotFile(CABLECAL_SOURCE_DIR "/robots/planar3_suspended.yaml")}) {
    DesignOptions options;
    options.poses = 6;
    options.starts = 1;
    options.random_sets = 0;
    options.max_iterations = 50;
    options.geometry_sigma_m = 0.3;
    options.lower_robustness = false;
    try {
      DesignPoses(robot, options);
      ADD_FAILURE() << robot.name << ": designed with 3 x 0.3 m of geometry uncertainty";
    } catch (const SolverFailure& e) {
      EXPECT_NE(std::string(e.what()).find("robust workspace looks empty"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("--geometry-sigma"), std::string::npos) << e.what();
    }
    options.lower_robustness = true;
    const DesignResult lowered = DesignPoses(robot, options);
    EXPECT_TRUE(lowered.robustness_lowered()) << robot.name;
    EXPECT_LT(lowered.robust_sigmas_achieved, 3.0) << robot.name;
    EXPECT_NE(lowered.robustness_note.find("not the requested 3 x 0.3 m"), std::string::npos) << lowered.robustness_note;
  }
  // Not said where the robust workspace is not empty (a start that cannot converge in 1 iteration).
  DesignOptions options;
  options.poses = 6;
  options.starts = 1;
  options.random_sets = 0;
  options.max_iterations = 1;
  try {
    DesignPoses(BuiltinRobot(), options);
    ADD_FAILURE() << "converged in one iteration";
  } catch (const SolverFailure& e) {
    EXPECT_EQ(std::string(e.what()).find("robust workspace"), std::string::npos) << e.what();
  }
}

TEST(Design, SummaryNamesEveryGeometricParameter) {
  DesignResult r;
  r.num_cables = 4;
  r.best_start = 0;
  PlanPose p;
  p.q = Eigen::Vector3d(1.0, 1.0, 0.0);
  p.tensions_worst_min_N = Eigen::VectorXd::Constant(4, 5.0);
  p.tensions_worst_max_N = Eigen::VectorXd::Constant(4, 9.0);
  r.poses = {p};
  DesignOptions options;
  options.poses = 1;
  options.random_sets = 0;
  const YAML::Node y = YAML::Load(DesignSummaryYaml(r, options, "test"));
  EXPECT_EQ(y["robustness"]["scenarios"].as<std::string>(),
            "each of a1x a1z a2x a2z a3x a3z a4x a4z l10 l20 l30 l40 moved by +-k sigma alone");
  EXPECT_TRUE(y["poses_worst_case_tensions_N"][0]["t4"].IsSequence());
  EXPECT_EQ(y["poses_worst_case_tensions_N"][0]["t4"][1].as<double>(), 9.0);
  const std::string text = DesignSummaryYaml(r, options, "test");
  EXPECT_NE(text.find("S: information of a1z a2x a2z a3x a3z a4x a4z l10 l20 l30 l40 (1/m^2)"), std::string::npos)
      << text;
}

// A prior for a 3-cable robot: 9 parameters, the information of the 8 but a1x is the inverse of
// their covariance; a result with another cable count is refused by name.
TEST(DesignPrior, AnyCableCount) {
  const Robot robot = LoadRobotFile(CABLECAL_SOURCE_DIR "/robots/planar3_suspended.yaml");
  const std::vector<std::string> names = {"a1x", "a1z", "a2x", "a2z", "a3x", "a3z", "l10", "l20", "l30"};
  Eigen::VectorXd g(9), sd(9);
  for (int k = 0; k < 6; ++k) g(k) = robot.cables[k / 2].p_F_exit_m(k % 2) + 0.001 * k;
  const Eigen::VectorXd l0 = InitialLengths(robot);
  for (int i = 0; i < 3; ++i) g(6 + i) = l0(i) - 0.002 * i;
  for (int k = 0; k < 9; ++k) sd(k) = 0.001 * (k + 1);
  // A correlation with one off-diagonal pair (a2x, l20).
  Eigen::MatrixXd C = Eigen::MatrixXd::Identity(9, 9);
  C(2, 7) = C(7, 2) = 0.5;
  std::ostringstream yaml;
  yaml << "status: converged\nparameters:\n";
  for (int k = 0; k < 9; ++k) yaml << "  " << names[k] << ": {value: " << FormatDouble(g(k)) << ", std: " << sd(k) << "}\n";
  yaml << "correlation:\n";
  for (int a = 0; a < 9; ++a) {
    yaml << "  - [";
    for (int b = 0; b < 9; ++b) yaml << (b ? ", " : "") << C(a, b);
    yaml << "]\n";
  }
  const testing_support::TempDir tmp;
  tmp.Write("result.yaml", yaml.str());
  const DesignPrior prior = LoadDesignPrior(robot, tmp.Path("result.yaml"));
  ASSERT_EQ(prior.information.rows(), 8);
  ASSERT_EQ(prior.information.cols(), 8);
  Eigen::MatrixXd cov(8, 8);
  for (int a = 0; a < 8; ++a) {
    for (int b = 0; b < 8; ++b) cov(a, b) = C(a + 1, b + 1) * sd(a + 1) * sd(b + 1);
  }
  EXPECT_LT((prior.information * cov - Eigen::MatrixXd::Identity(8, 8)).cwiseAbs().maxCoeff(), 1e-9);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(prior.robot.cables[i].p_F_exit_m, Eigen::Vector2d(g(2 * i), g(2 * i + 1)));
    EXPECT_EQ(prior.robot.cables[i].initial_length_m.value_or(0.0), g(6 + i));
  }
  // The 2-cable robot cannot take it, nor the 3-cable robot a 2-cable result.
  try {
    LoadDesignPrior(BuiltinRobot(), tmp.Path("result.yaml"));
    ADD_FAILURE() << "a 3-cable result accepted for 2 cables";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("a1x a1z a2x a2z l10 l20"), std::string::npos) << e.what();
  }
  std::string two = "status: converged\nparameters:\n";
  for (const char* n : {"a1x", "a1z", "a2x", "a2z", "l10", "l20"}) two += std::string("  ") + n + ": {value: 1.0, std: 0.001}\n";
  tmp.Write("two.yaml", two);
  EXPECT_THROW(LoadDesignPrior(robot, tmp.Path("two.yaml")), InputError);
  // A gauge-none result (its sigmas leave out the null direction) is refused, naming the key.
  tmp.Write("none.yaml", "gauge: none\n" + yaml.str());
  try {
    LoadDesignPrior(robot, tmp.Path("none.yaml"));
    ADD_FAILURE() << "a gauge-none result accepted as a prior";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("gauge"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("--gauge a1x"), std::string::npos) << e.what();
  }
  tmp.Write("a1x.yaml", "gauge: a1x\n" + yaml.str());
  EXPECT_NO_THROW(LoadDesignPrior(robot, tmp.Path("a1x.yaml")));
}

TEST(Surrogates, BoundTheExactCriteria) {
  // kappa <= kappa_p <= d^(1/p) kappa and lambda_min >= surrogate >= lambda_min / 5^(1/p).
  const Robot& robot = BuiltinRobot();
  for (const int n : {6, 20, 50}) {
    for (std::uint64_t s = 0; s < 5; ++s) {
      const auto poses = RandomSet(n, 100 + s);
      const double gap_c = internal::DesignObjective(robot, Criterion::kCondition, poses, nullptr) -
                           internal::ExactObjective(robot, Criterion::kCondition, poses);
      EXPECT_GE(gap_c, -1e-12);
      EXPECT_LE(gap_c, std::log(5.0 + n) / internal::kConditionPower + 1e-12);
      const double gap_e = internal::DesignObjective(robot, Criterion::kE, poses, nullptr) -
                           internal::ExactObjective(robot, Criterion::kE, poses);
      EXPECT_GE(gap_e, -1e-12);
      EXPECT_LE(gap_e, std::log(5.0) / internal::kEigenvaluePower + 1e-12);
    }
  }
}

void ExpectVerified(const Robot& robot, const DesignResult& r, int n) {
  ASSERT_EQ(static_cast<int>(r.poses.size()), n);
  std::vector<Eigen::Vector3d> q;
  for (const PlanPose& p : r.poses) {
    EXPECT_EQ(CheckFeasibility(robot, p.q, p.tensions_N), Feasibility::kFeasible);
    EXPECT_LT(EquilibriumResidual<double>(robot, p.q, p.tensions_N).norm(), 1e-8);
    q.push_back(p.q);
  }
  const CriteriaValues v = EvaluateCriteria(robot, q);
  EXPECT_EQ(v.condition_number, r.criteria.condition_number);  // recomputed, not copied
}

class ConditionQuality : public ::testing::TestWithParam<int> {};

// The paper's criterion on its own terms: nominal bounds only (with the robustness rows, which
// give up some conditioning for holdable poses, bench/README.md measures 0.50-0.55 of the
// random median from N = 20 on).
TEST_P(ConditionQuality, AtMostHalfTheRandomMedian) {
  const Robot& robot = BuiltinRobot();
  DesignOptions options;
  options.poses = GetParam();
  options.criterion = Criterion::kCondition;
  options.geometry_sigma_m = 0.0;
  options.starts = 3;
  options.seed = 7;
  const DesignResult r = DesignPoses(robot, options);
  ExpectVerified(robot, r, options.poses);
  EXPECT_LE(r.criteria.condition_number, 0.5 * r.random_median.condition_number)
      << "n = " << options.poses << ": optimized " << r.criteria.condition_number << ", random median "
      << r.random_median.condition_number;
}

INSTANTIATE_TEST_SUITE_P(Sizes, ConditionQuality, ::testing::Values(6, 15, 30));

class InformationQuality : public ::testing::TestWithParam<Criterion> {};

TEST_P(InformationQuality, BeatsRandomMedianByAFactorOfTwo) {
  const Robot& robot = BuiltinRobot();
  DesignOptions options;
  options.poses = 10;
  options.criterion = GetParam();
  options.starts = 3;
  options.seed = 3;
  const DesignResult r = DesignPoses(robot, options);
  ExpectVerified(robot, r, options.poses);
  EXPECT_GE(Improvement(options.criterion, r.criteria, r.random_median), 2.0) << ToString(options.criterion);
}

INSTANTIATE_TEST_SUITE_P(Criteria, InformationQuality, ::testing::Values(Criterion::kD, Criterion::kA, Criterion::kE),
                         [](const auto& info) { return std::string(ToString(info.param)); });

TEST(Design, SameSeedSameResultWhateverTheThreadCount) {
  const Robot& robot = BuiltinRobot();
  DesignOptions options;
  options.poses = 8;
  options.starts = 4;
  options.random_sets = 20;
  omp_set_num_threads(1);
  const DesignResult one = DesignPoses(robot, options);
  omp_set_num_threads(2);
  const DesignResult two = DesignPoses(robot, options);
  EXPECT_EQ(PosePlanCsv(one.poses, ""), PosePlanCsv(two.poses, ""));
  EXPECT_EQ(one.random_median.condition_number, two.random_median.condition_number);
  EXPECT_EQ(one.best_start, two.best_start);
}

// Each start's Ipopt solve in a child process (the default, so that starts solve at once)
// gives the plan the same solves in this process give, bit for bit: on the asymmetric robot
// and on the 3-cable one, whose solves carry the tensions and theta too.
TEST(Design, SolvesInChildProcessesEqualSolvesInProcess) {
  for (const char* file : {"/robots/asymmetric.yaml", "/robots/planar3_suspended.yaml"}) {
    const Robot robot = LoadRobotFile(std::string(CABLECAL_SOURCE_DIR) + file);
    DesignOptions options;
    options.poses = 7;
    options.starts = 3;
    options.random_sets = 0;
    options.solve_in_child_processes = true;
    const DesignResult children = DesignPoses(robot, options);
    options.solve_in_child_processes = false;
    const DesignResult here = DesignPoses(robot, options);
    EXPECT_EQ(PosePlanCsv(children.poses, ""), PosePlanCsv(here.poses, "")) << file;
    ASSERT_EQ(children.starts.size(), here.starts.size());
    for (std::size_t k = 0; k < here.starts.size(); ++k) {
      EXPECT_EQ(children.starts[k].iterations, here.starts[k].iterations) << file << " start " << k;
      EXPECT_EQ(children.starts[k].ipopt_status, here.starts[k].ipopt_status) << file << " start " << k;
      EXPECT_EQ(children.starts[k].objective, here.starts[k].objective) << file << " start " << k;
    }
  }
}

// Ipopt reads an options file, ipopt.opt, from the working directory unless told not to: a
// stray one (here, one that stops every solve at once) must not change a plan.
TEST(Design, AnIpoptOptionsFileInTheWorkingDirectoryIsNotRead) {
  const Robot& robot = BuiltinRobot();
  DesignOptions options;
  options.poses = 8;
  options.starts = 1;
  options.random_sets = 0;
  const std::string expected = PosePlanCsv(DesignPoses(robot, options).poses, "");
  testing_support::TempDir dir;
  dir.Write("ipopt.opt", "max_iter 0\nmumps_pivot_order 2\n");
  std::string got;
  try {
    const testing_support::ScopedWorkingDirectory in_dir(dir.path());
    got = PosePlanCsv(DesignPoses(robot, options).poses, "");
  } catch (const std::exception& e) {
    got = e.what();
  }
  EXPECT_EQ(got, expected);
}

TEST(Design, SolvesWithTheReferenceBlas) {
  // With ATLAS behind libblas.so.3, the same Ipopt/MUMPS solve ended differently in about
  // one run in six (alignment-dependent kernels), so every executable loads the reference
  // BLAS and LAPACK (CMakeLists.txt). A run-to-run difference is too rare to test for
  // directly; what makes it impossible is checked here.
  const Robot& robot = BuiltinRobot();
  DesignOptions options;
  options.poses = 6;
  options.starts = 1;
  options.random_sets = 0;
  DesignPoses(robot, options);  // Ipopt and MUMPS are loaded and have run
  const std::string blas = LoadedLibraryPath("libblas.so");
  const std::string lapack = LoadedLibraryPath("liblapack.so");
  EXPECT_NE(blas.find("/blas/libblas.so.3"), std::string::npos) << blas;
  EXPECT_NE(lapack.find("/lapack/liblapack.so.3"), std::string::npos) << lapack;
  EXPECT_EQ(LoadedLibraryPath("libopenblas"), "not loaded");
}

TEST(Design, MinSpacingIsHonoured) {
  const Robot& robot = BuiltinRobot();
  DesignOptions options;
  options.poses = 8;
  options.starts = 2;
  options.min_spacing_m = 0.3;
  options.random_sets = 10;
  const DesignResult r = DesignPoses(robot, options);
  for (std::size_t a = 0; a < r.poses.size(); ++a) {
    for (std::size_t b = a + 1; b < r.poses.size(); ++b) {
      EXPECT_GE((r.poses[a].q.head<2>() - r.poses[b].q.head<2>()).norm(), 0.3 - 1e-9);
    }
  }
}

TEST(Design, Rejections) {
  DesignOptions options;
  options.poses = 4;
  EXPECT_THROW(DesignPoses(BuiltinRobot(), options), InputError);
  options.poses = 6;
  options.starts = 1;
  options.random_sets = 5;
  options.min_spacing_m = 10.0;  // no two poses of the frame can be 10 m apart: refused before solving
  EXPECT_THROW(DesignPoses(BuiltinRobot(), options), InputError);
  options.min_spacing_m = 5.0;  // two poses can be, six cannot
  EXPECT_THROW(DesignPoses(BuiltinRobot(), options), SolverFailure);
}

}  // namespace
}  // namespace cablecal
