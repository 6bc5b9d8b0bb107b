#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "common/error.h"
#include "montecarlo/montecarlo.h"
#include "experiment/experiment.h"

namespace cablecal {
namespace {

MonteCarloOptions Small() {
  MonteCarloOptions o;
  o.pose_counts = {6, 9};  // small: this runs twice, and again under the sanitizers
  o.designs = {PoseSetDesign::kRandom, PoseSetDesign::kOptimized};
  o.trials = 10;
  o.seed = 9;
  return o;
}

TEST(MonteCarlo, BitIdenticalForOneAndTwoThreads) {
  const Robot& robot = BuiltinRobot();
  omp_set_num_threads(1);
  const MonteCarloResult one = RunMonteCarlo(robot, Small());
  omp_set_num_threads(2);
  const MonteCarloResult two = RunMonteCarlo(robot, Small());
  EXPECT_EQ(ErrorsCsv(one), ErrorsCsv(two));
  EXPECT_EQ(SummaryCsv(one), SummaryCsv(two));
  EXPECT_GT(ErrorsCsv(one).size(), 1000u);
}

TEST(MonteCarlo, TrialStreamsDependOnlyOnTheirIndices) {
  // Adding pose counts or designs does not change the trials already there.
  const Robot& robot = BuiltinRobot();
  MonteCarloOptions a = Small();
  a.pose_counts = {9};
  a.designs = {PoseSetDesign::kRandom};
  const MonteCarloResult ra = RunMonteCarlo(robot, a);
  const MonteCarloResult rb = RunMonteCarlo(robot, Small());
  const MonteCarloCell* cell = nullptr;
  for (const MonteCarloCell& c : rb.cells) {
    if (c.n == 9 && c.design == PoseSetDesign::kRandom) cell = &c;
  }
  ASSERT_NE(cell, nullptr);
  for (int t = 0; t < a.trials; ++t) EXPECT_EQ(ra.cells[0].trials[t].errors_m, cell->trials[t].errors_m);
}

TEST(MonteCarlo, ErrorsShrinkWithMorePosesAndMatchTheNoiseFreeLimit) {
  const Robot& robot = BuiltinRobot();
  MonteCarloOptions o;
  o.pose_counts = {6, 30};
  o.designs = {PoseSetDesign::kRandom};
  o.trials = 60;
  const MonteCarloResult r = RunMonteCarlo(robot, o);
  EXPECT_GT(Summarise(r.cells[0], GeometryNames(2), "a2x").std, 2.0 * Summarise(r.cells[1], GeometryNames(2), "a2x").std);
  // No sensor noise at all: identification errors vanish (encoders keep their 0.05 mm).
  o.sensors = NoisySensors::kNone;
  o.pose_counts = {30};
  const MonteCarloResult quiet = RunMonteCarlo(robot, o);
  EXPECT_LT(Summarise(quiet.cells[0], GeometryNames(2), "a2x").std, 0.2 * Summarise(r.cells[1], GeometryNames(2), "a2x").std);
  // Gauge a1x: the true a1x is the nominal one, so its error is exactly zero.
  EXPECT_EQ(Summarise(r.cells[1], GeometryNames(2), "a1x").max_abs, 0.0);
}

// --outliers: gross readings make least squares refuse most trials (poor fit); Cauchy's loss
// calibrates them about as well as clean data; and the outliers' own stream leaves a study
// without them unchanged.
TEST(MonteCarlo, OutliersFailLeastSquaresAndCauchyRecovers) {
  const Robot& robot = BuiltinRobot();
  MonteCarloOptions o;
  o.pose_counts = {20};
  o.designs = {PoseSetDesign::kRandom};
  o.trials = 30;
  const MonteCarloResult clean = RunMonteCarlo(robot, o);
  // P(a trial has one) = 1 - 0.98^80 = 80 %; many are absorbed unseen (an encoder's 5 mm, an
  // inclinometer's 3.5 degrees), the laser's 0.2 m are not.
  o.outliers = ParseOutliers("0.02:100");
  const MonteCarloResult rough = RunMonteCarlo(robot, o);
  o.loss = ParseLoss("cauchy");
  const MonteCarloResult robust = RunMonteCarlo(robot, o);
  EXPECT_EQ(clean.cells[0].failures("identification"), 0);
  EXPECT_GE(rough.cells[0].failures("identification"), 4);
  EXPECT_LE(robust.cells[0].failures("identification"), 1);
  for (const char* p : {"a2x", "l10"}) {
    EXPECT_LT(Summarise(robust.cells[0], GeometryNames(2), p).std, 1.5 * Summarise(clean.cells[0], GeometryNames(2), p).std) << p;
  }
  o.outliers = OutlierModel{};
  o.loss = RobustLoss{};
  EXPECT_EQ(ErrorsCsv(RunMonteCarlo(robot, o)), ErrorsCsv(clean));
}

// A 3-cable robot at its fewest poses calibrates some parameters worse than the lab knew them
// before measuring (the true geometry drawn with 10 mm): the summary says so, naming the cells.
// With --geometry-prior no parameter's spread exceeds the prior's by more than sampling allows.
TEST(MonteCarlo, SaysWhenTheCalibrationKnowsLessThanThePriorAndThePriorMendsIt) {
  const Robot robot = LoadRobotFile(CABLECAL_SOURCE_DIR "/robots/planar3_suspended.yaml");
  MonteCarloOptions o;
  o.pose_counts = {4};
  o.designs = {PoseSetDesign::kRandom};
  o.trials = 60;
  o.seed = 4;
  const MonteCarloResult plain = RunMonteCarlo(robot, o);
  ASSERT_FALSE(CellsThatAddLittle(plain, true).empty()) << SummaryMarkdown(plain, "t");
  EXPECT_EQ(CellsThatAddLittle(plain, true).front().rfind("n=4 random: ", 0), 0u);
  EXPECT_NE(SummaryMarkdown(plain, "t").find("**less** well"), std::string::npos);
  o.geometry_prior = true;
  const MonteCarloResult prior = RunMonteCarlo(robot, o);
  for (const std::string& p : GeometryNames(3)) {
    const ErrorStats s = Summarise(prior.cells[0], GeometryNames(3), p);
    ASSERT_GT(s.count, 30) << p;
    // The spread of 60 draws of a sigma-0.01 quantity stays below 1.4 x it but for 1 in 10^4.
    EXPECT_LT(s.std, 1.4 * o.geometry_sigma_m) << p;
  }
  EXPECT_NE(SummaryMarkdown(prior, "t").find("identified with that knowledge as a prior"), std::string::npos);
}

TEST(MonteCarlo, FailuresAreCountedNotDropped) {
  // A large geometry error makes some commanded poses unreachable for the true robot.
  const Robot& robot = BuiltinRobot();
  MonteCarloOptions o;
  o.pose_counts = {20};
  o.designs = {PoseSetDesign::kRandom};
  o.trials = 40;
  o.geometry_sigma_m = 0.05;
  const MonteCarloResult r = RunMonteCarlo(robot, o);
  const MonteCarloCell& c = r.cells[0];
  int failed = 0;
  for (const TrialOutcome& t : c.trials) {
    if (!t.ok) {
      ++failed;
      EXPECT_FALSE(t.failure.empty());
    }
  }
  EXPECT_EQ(c.failures(), failed);
  EXPECT_GT(failed, 0);
  EXPECT_EQ(Summarise(c, GeometryNames(2), "a2x").count, o.trials - failed);
  // Every failure has exactly one cause, and the summary counts them per cause.
  int by_cause = 0;
  for (const std::string& cause : FailureCauses()) by_cause += c.failures(cause);
  EXPECT_EQ(by_cause, failed);
  EXPECT_GT(c.failures("simulation"), 0);
  const std::string expected_tail = "," + std::to_string(failed) + "," + std::to_string(c.failures("design")) + "," +
                                    std::to_string(c.failures("sampling")) + "," +
                                    std::to_string(c.failures("simulation")) + "," +
                                    std::to_string(c.failures("identification")) + "\n";
  EXPECT_NE(SummaryCsv(r).find(expected_tail), std::string::npos) << SummaryCsv(r);
  EXPECT_NE(SummaryCsv(r).find("failures,failed_design,failed_sampling,failed_simulation,failed_identification\n"),
            std::string::npos);
  // failures.csv: one row per failed trial with its cause and reason.
  const std::string failures = FailuresCsv(r);
  EXPECT_EQ(std::count(failures.begin(), failures.end(), '\n'), failed + 1) << failures;
  EXPECT_NE(failures.find("\n20,random,"), std::string::npos);
  EXPECT_NE(failures.find(",simulation,\"pose "), std::string::npos) << failures;
}

// A designed set that could not be made fails its own cell's trials (cause "design"), and
// every other cell still runs; the table says n/a rather than a zero sigma.
TEST(MonteCarlo, AFailedDesignFailsOnlyItsCell) {
  const Robot& robot = BuiltinRobot();
  MonteCarloOptions o;
  o.pose_counts = {6, 8};
  o.designs = {PoseSetDesign::kRandom, PoseSetDesign::kOptimized};
  o.trials = 6;
  DesignedSets designed;
  designed[{6, static_cast<int>(PoseSetDesign::kOptimized)}] = {};  // as MakeDesignedSet returns on failure
  designed[{8, static_cast<int>(PoseSetDesign::kOptimized)}] = SampleFeasiblePoses(robot, 8, 5);
  std::vector<ShareResult> shares = {RunShare(robot, o, designed, StudyShare{0, 1})};
  ASSERT_TRUE(shares[0].failure.empty()) << shares[0].failure;
  const MonteCarloResult r = AssembleShares(o, std::move(shares), PlanarStudyNames(robot.num_cables()));
  ASSERT_EQ(r.cells.size(), 4u);
  for (const MonteCarloCell& c : r.cells) {
    const bool broken = c.n == 6 && c.design == PoseSetDesign::kOptimized;
    EXPECT_EQ(c.failures("design"), broken ? o.trials : 0) << c.n << " " << ToString(c.design);
    if (!broken) {
      EXPECT_LT(c.failures(), o.trials) << c.n << " " << ToString(c.design);
    }
  }
  const std::string md = SummaryMarkdown(r, "t");
  EXPECT_NE(md.find("| 6 | optimized | n/a |"), std::string::npos) << md;
  EXPECT_NE(md.find("(design 6)"), std::string::npos) << md;
  EXPECT_NE(SummaryCsv(r).find("\n6,optimized,a2x,,,,,,6,6,0,0,0\n"), std::string::npos) << SummaryCsv(r);
}

// One successful trial has no spread over trials: every column n/a, x_all too, whose pooled
// poses from that one trial once read as a sigma (a new user's trial: "0.761" from one trial).
TEST(MonteCarlo, OneSuccessfulTrialShowsNoSpreadAnywhere) {
  MonteCarloResult r;
  r.geometry_names = GeometryNames(2);
  r.held_names = {"a1x"};
  MonteCarloCell one;
  one.n = 6;
  TrialOutcome ok;
  ok.ok = true;
  for (int k = 0; k < 6 + 6; ++k) ok.errors_m.push_back(0.014 + 0.001 * k);
  TrialOutcome failed;
  failed.failure = "simulation: pose 3";
  one.trials = {ok, failed, failed};
  MonteCarloCell two = one;
  two.n = 8;
  ok.errors_m.assign(6 + 8, 0.002);
  two.trials = {ok, ok, failed};
  r.cells = {one, two};
  const std::string md = SummaryMarkdown(r, "t");
  EXPECT_NE(md.find("| 6 | random | n/a | n/a | n/a | n/a | n/a | n/a | n/a | n/a | n/a | 2 / 3"), std::string::npos)
      << md;
  EXPECT_EQ(md.find("| 8 | random | n/a"), std::string::npos) << md;  // two trials: a spread
  const std::string csv = SummaryCsv(r);
  const std::size_t row = csv.find("\n6,random,x_all,");
  ASSERT_NE(row, std::string::npos) << csv;
  std::vector<std::string> cells;
  std::stringstream line(csv.substr(row + 1, csv.find('\n', row + 1) - row - 1));
  for (std::string cell; std::getline(line, cell, ',');) cells.push_back(cell);
  ASSERT_GE(cells.size(), 5u);
  EXPECT_FALSE(cells[3].empty()) << "a mean from the one trial";
  EXPECT_TRUE(cells[4].empty()) << "no std from one trial: " << cells[4];
}

TEST(MonteCarlo, AStudyTooLargeForMemoryIsRefusedWithItsSize) {
  MonteCarloOptions o;
  o.pose_counts = ParsePoseCounts("6:50");
  o.designs = {PoseSetDesign::kRandom};
  o.trials = 100000000;
  try {
    ValidateOptions(o);
    FAIL() << "accepted a study of " << o.trials << " trials per cell";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("GB of errors"), std::string::npos) << e.what();
  }
  o.trials = 1000;
  EXPECT_NO_THROW(ValidateOptions(o));
}

TEST(MonteCarlo, GaugePriorWithThePaperEstimatorIsBadInput) {
  MonteCarloOptions o = Small();
  o.gauge = Gauge::kPrior;
  o.estimator = Estimator::kPaper;
  try {
    RunMonteCarlo(BuiltinRobot(), o);
    FAIL() << "ran the paper estimator with the tracker prior";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--gauge prior"), std::string::npos) << e.what();
  }
}

TEST(MonteCarlo, GaugePriorWithoutATrackerIsBadInput) {
  Robot robot = BuiltinRobot();
  robot.sensors.tracker_sigma_m.reset();
  MonteCarloOptions o = Small();
  o.gauge = Gauge::kPrior;
  try {
    RunMonteCarlo(robot, o);
    FAIL() << "ran --gauge prior without a tracker sigma";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("sensors.tracker.sigma: is needed for --gauge prior"), std::string::npos)
        << e.what();
  }
}

// The flag raised once trials are running (as SIGINT would be), not before the call: that
// would return before the first trial and leave the trials' own check untried.
TEST(MonteCarlo, InterruptStopsEarly) {
  std::atomic<bool> stop{false};
  MonteCarloOptions o = Small();
  o.designs = {PoseSetDesign::kRandom};
  o.trials = 50;
  o.interrupted = &stop;
  long last_done = 0, total = 0;
  o.progress = [&](long done, long all) {
    last_done = done;
    total = all;
    if (done >= 2) stop = true;
  };
  EXPECT_TRUE(RunMonteCarlo(BuiltinRobot(), o).interrupted);
  EXPECT_TRUE(stop.load()) << "interrupted before the flag was raised";
  // The study's end reports (total, total); an interrupted one stops short of it.
  EXPECT_EQ(total, 100);
  EXPECT_LT(last_done, total);
}

TEST(MonteCarlo, ParsesPoseRangesAndDesigns) {
  EXPECT_EQ(ParsePoseCounts("6:10"), (std::vector<int>{6, 7, 8, 9, 10}));
  EXPECT_EQ(ParsePoseCounts("6:50:22"), (std::vector<int>{6, 28, 50}));
  EXPECT_EQ(ParsePoseCounts("7"), (std::vector<int>{7}));
  for (const char* bad : {"10:6", "6:x", "6:10:0", "", "6.5:10", "0:4"}) {
    EXPECT_THROW(ParsePoseCounts(bad), InputError) << bad;
  }
  // The fewest poses depend on the robot (design.h MinDesignPoses): 5 for 2 cables, 4 for 3.
  MonteCarloOptions o;
  o.trials = 1;
  o.designs = {PoseSetDesign::kRandom};
  o.pose_counts = ParsePoseCounts("4:10");
  EXPECT_THROW(ValidateOptions(o, &BuiltinRobot()), InputError);
  const Robot three = LoadRobotFile(CABLECAL_SOURCE_DIR "/robots/planar3_suspended.yaml");
  EXPECT_NO_THROW(ValidateOptions(o, &three));
  o.pose_counts = {3};
  EXPECT_THROW(ValidateOptions(o, &three), InputError);
  EXPECT_EQ(ParseDesigns("random,e").size(), 2u);
  EXPECT_EQ(ParseDesigns("condition"), (std::vector<PoseSetDesign>{PoseSetDesign::kCondition}));
  EXPECT_THROW(ParseDesigns("random,random"), InputError);
  EXPECT_THROW(ParseDesigns("optimized,a"), InputError);
  try {
    ParsePoseCounts("6:1000000");
    FAIL() << "a million poses accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("at most 1000 poses per set"), std::string::npos) << e.what();
  }  // the same A-optimal cells twice
  EXPECT_THROW(ParseDesigns("a,random,optimized"), InputError);
  EXPECT_THROW(ParseDesigns("best"), InputError);
}

}  // namespace
}  // namespace cablecal
