// The spatial Monte Carlo (montecarlo/spatial_montecarlo.h): its trials recover the true robot
// in the study's gauge when the sensors are nearly perfect (so that identified minus true is
// an error, not a choice of frame), the same bytes whatever the thread count, the peer's grid
// pose sets, and the refusals.
#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <string>

#include "common/error.h"
#include "common/random.h"
#include "experiment/spatial_plan.h"
#include "experiment/spatial_simulation.h"
#include "model/builtin_spatial_robots.h"
#include "model/spatial_sensor_model.h"
#include "model/spatial_statics.h"
#include "montecarlo/spatial_montecarlo.h"
#include "tests/support/random_spatial_robot.h"

namespace cablecal {
namespace {

// A random robot of m cables, inextensible, read by its encoders, an inclinometer and a laser
// with the given sigmas. Its platform is known to a nanometre and a billionth of its mass (finer
// than a robot file may say, 1e-6): these tests are of the exits, lengths and noise, and the
// Monte Carlo draws each true platform from the priors (with the default 5 mm, sampled poses
// near a tension bound lose it: 5 of 6 trials failed here; with 1e-6 m, the noise-free 4-cable
// trials' exits are off by up to 40 um, the prior pulling the centre of mass, which they see
// through the platform's tilt, back toward the file's).
SpatialRobot RandomRobot(std::uint64_t seed, int m, double encoder_sigma_m, double sensor_sigma) {
  Rng rng(seed);
  SpatialRobot r = testing::RandomSpatialRobot(rng, "random-" + std::to_string(m), m);
  r.com_sigma_m = 1e-9;
  r.mass_sigma_kg = 1e-9 * r.platform_mass_kg;
  for (SpatialCable& c : r.cables) c.stiffness_N.reset();
  r.sensors.encoder_sigma_m = encoder_sigma_m;
  r.sensors.inclinometer_rad = RangedNoise{sensor_sigma, 0.0};
  r.sensors.laser_m = RangedNoise{sensor_sigma, 0.0};
  return r;
}

SpatialMonteCarloOptions Study(int n, int trials, double geometry_sigma_m) {
  SpatialMonteCarloOptions o;
  o.study.pose_counts = {n};
  o.study.designs = {PoseSetDesign::kRandom};
  o.study.trials = trials;
  o.study.geometry_sigma_m = geometry_sigma_m;
  o.study.seed = 11;
  return o;
}

std::string InputErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "no InputError";
}

// Noise-free readings: every trial's error is then the solver's, far below a micrometre, for
// every exit coordinate and initial length and every pose's x. A true robot drawn in another
// frame than the one the identification holds, or a wrong true l_i0, would show up here as
// millimetres.
TEST(SpatialMonteCarlo, NoiseFreeTrialsRecoverTheTrueRobotInTheStudysGauge) {
  for (const int m : {4, 6}) {
    const SpatialRobot robot = RandomRobot(40 + m, m, 5e-5, 1e-3);
    SpatialMonteCarloOptions o = Study(12, m == 4 ? 2 : 4, 0.0005);
    o.study.sensors = NoisySensors::kNone;
    o.encoder_noise = false;
    const MonteCarloResult r = RunSpatialMonteCarlo(robot, o);
    ASSERT_EQ(r.cells.size(), 1u);
    EXPECT_FALSE(r.held_names.empty());
    ASSERT_EQ(r.geometry_names.size(), static_cast<std::size_t>(4 * m));
    int ok = 0;
    for (const TrialOutcome& t : r.cells[0].trials) {
      if (!t.ok) {
        ADD_FAILURE() << "m=" << m << ": " << t.failure;
        continue;
      }
      ++ok;
      ASSERT_EQ(t.errors_m.size(), static_cast<std::size_t>(4 * m + 12));
      for (std::size_t k = 0; k < t.errors_m.size(); ++k) {
        const std::string name = k < r.geometry_names.size() ? r.geometry_names[k] : "x" + std::to_string(k - 4 * m + 1);
        EXPECT_LT(std::abs(t.errors_m[k]), 1e-6) << "m=" << m << " " << name;
      }
      for (const std::string& h : r.held_names) {
        const std::size_t k = std::find(r.geometry_names.begin(), r.geometry_names.end(), h) - r.geometry_names.begin();
        EXPECT_EQ(t.errors_m[k], 0.0) << h;
      }
    }
    EXPECT_EQ(ok, m == 4 ? 2 : 4) << "m=" << m;
  }
}

// The spatial study's irma4u cell at its fewest poses (4 designed poses; encoders, swivel
// encoders and an inclinometer; 21 free geometry unknowns against 7 values to spare, 6 nearly
// hard equilibrium rows per pose): barely determined, the Schur complement's condition the
// square of a poor Jacobian's. Every simulated identification must converge. Before the
// solver's orthogonal fallback step and its pose refits, 10 of 100 such trials did not (the
// linear solve failing five times in a row, or 2000 iterations crawling; mean 470 iterations);
// Ceres' DENSE_SCHUR did no better (11 of 100). bench/README.md, "Ill-conditioned identifications".
TEST(SpatialMonteCarlo, BarelyDeterminedIrma4uIdentificationsConverge) {
  SpatialRobot robot = BuiltinSpatialRobot("irma4u");
  robot.sensors = KeepSpatialSensors(robot.sensors, {"swivel", "inclinometer"});
  for (SpatialCable& c : robot.cables) c.stiffness_N = 1e5;
  robot.com_sigma_m = 0.0005;
  SpatialMonteCarloOptions o;
  o.study.pose_counts = {4};
  o.study.designs = {PoseSetDesign::kOptimized};
  o.study.trials = 40;
  o.study.geometry_sigma_m = 0.0005;
  o.study.design_starts = 2;
  o.study.seed = 2022;
  o.plan_tension_margin_N = 20.0;
  o.plan_margin_m = 0.005;
  o.plan_tilt_margin_rad = 0.5 * M_PI / 180.0;
  const MonteCarloResult r = RunSpatialMonteCarlo(robot, o);
  ASSERT_EQ(r.cells.size(), 1u);
  EXPECT_EQ(r.cells[0].failures("design"), 0);
  EXPECT_EQ(r.cells[0].failures("identification"), 0);
  for (const TrialOutcome& t : r.cells[0].trials) {
    EXPECT_TRUE(t.ok || t.failure.rfind("simulation", 0) == 0) << t.failure;
  }
  EXPECT_GE(r.cells[0].trials.size() - r.cells[0].failures(), 36u);
}

// With a lab's sensors the errors are the noise's, propagated linearly: every sensor's sigma
// doubled (the same standard normal draws, the same true robots), every trial's error vector
// doubles, in size and direction, to the linearisation's accuracy.
TEST(SpatialMonteCarlo, ErrorsAreTheNoisesAndDoubleWithIt) {
  MonteCarloResult r[2];
  for (int k = 0; k < 2; ++k) {
    const double scale = k + 1.0;
    // A position sensor besides: every direction well seen, so that the errors stay where
    // the model is linear (with an inclinometer and laser alone this robot sees some
    // directions weakly, and its errors reach centimetres).
    SpatialRobot robot = RandomRobot(46, 6, scale * 5e-6, scale * 1e-4);
    robot.sensors.position = SpatialSensors::Position{RangedNoise{scale * 1e-4, 0.0}, Eigen::Vector3d::Zero()};
    r[k] = RunSpatialMonteCarlo(robot, Study(20, 6, 0.0002));
  }
  int compared = 0;
  double largest = 0.0;
  for (int t = 0; t < 6; ++t) {
    const TrialOutcome &one = r[0].cells[0].trials[t], &two = r[1].cells[0].trials[t];
    ASSERT_EQ(one.ok, two.ok) << one.failure << two.failure;
    if (!one.ok) continue;
    ++compared;
    // The trial's whole error vector (a single small component carries the second-order term
    // relatively more: up to 7 % here).
    const Eigen::Map<const Eigen::VectorXd> e1(one.errors_m.data(), one.errors_m.size()),
        e2(two.errors_m.data(), two.errors_m.size());
    EXPECT_NEAR(e2.norm() / e1.norm(), 2.0, 0.04) << "trial " << t;
    EXPECT_GT(e2.normalized().dot(e1.normalized()), 0.999) << "trial " << t;
    largest = std::max(largest, e1.cwiseAbs().maxCoeff());
  }
  EXPECT_GE(compared, 4);
  EXPECT_GT(largest, 1e-6);  // not zero: the noise is there
  EXPECT_LT(largest, 1e-3);  // and of its size (0.1 mm sensors), not a wrong minimum's
}

// Each trial's true platform (PerturbSpatialPlatform): the file's mass and centre of mass plus
// draws of the file's priors (here a 2 % mass and a 3 mm centre of mass), each independently:
// over 4000 draws the means within 4 standard errors and the standard deviations within 5 %
// (4.5 standard errors) of the priors.
TEST(SpatialMonteCarlo, TruePlatformsAreDrawnFromThePriors) {
  SpatialRobot robot = RandomRobot(48, 5, 5e-5, 1e-3);
  robot.mass_sigma_kg = 0.02 * robot.platform_mass_kg;
  robot.com_sigma_m = 0.003;
  const Eigen::Vector4d sigma(*robot.mass_sigma_kg, 0.003, 0.003, 0.003);
  constexpr int kDraws = 4000;
  Rng rng(5);
  Eigen::Vector4d sum = Eigen::Vector4d::Zero(), squares = Eigen::Vector4d::Zero();
  double cross = 0.0;
  for (int k = 0; k < kDraws; ++k) {
    SpatialRobot truth = robot;
    PerturbSpatialPlatform(&truth, rng);
    EXPECT_EQ(truth.cables[0].p_F_exit_m, robot.cables[0].p_F_exit_m);
    const Eigen::Vector4d d = (truth.platform_values() - robot.platform_values()).cwiseQuotient(sigma);
    sum += d;
    squares += d.cwiseAbs2();
    cross += d(1) * d(2);
  }
  const Eigen::Vector4d mean = sum / kDraws;
  for (int a = 0; a < 4; ++a) {
    EXPECT_LT(std::abs(mean(a)), 4.0 / std::sqrt(kDraws)) << a;
    EXPECT_NEAR(std::sqrt(squares(a) / kDraws - mean(a) * mean(a)), 1.0, 0.05) << a;
  }
  EXPECT_LT(std::abs(cross / kDraws), 4.0 / std::sqrt(kDraws));  // comx and comy independent
}

TEST(SpatialMonteCarlo, SameBytesWhateverTheThreadCount) {
  const SpatialRobot robot = RandomRobot(47, 5, 5e-5, 1e-3);
  SpatialMonteCarloOptions o = Study(10, 4, 0.0002);
  o.study.pose_counts = {10, 12};
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const std::string one = ErrorsCsv(RunSpatialMonteCarlo(robot, o));
  omp_set_num_threads(2);
  const std::string two = ErrorsCsv(RunSpatialMonteCarlo(robot, o));
  omp_set_num_threads(threads);
  EXPECT_EQ(one, two);
  EXPECT_GT(one.size(), 1000u);
}

// The peer's grid: side^3 distinct feasible poses at home's yaw, the same every time.
TEST(SpatialMonteCarlo, GridPosesAreFeasibleDistinctAndOnePerCell) {
  for (const SpatialRobot& robot : {BuiltinSpatialRobot("cogiro"), RandomRobot(48, 6, 5e-5, 1e-3)}) {
    for (const int side : {2, 3}) {
      const std::vector<SpatialPlanPose> grid = GridSpatialPoses(robot, side);
      ASSERT_EQ(grid.size(), static_cast<std::size_t>(side * side * side)) << robot.name;
      Eigen::Vector3d lo = grid[0].q.head<3>(), hi = lo;
      for (const SpatialPlanPose& p : grid) {
        lo = lo.cwiseMin(p.q.head<3>());
        hi = hi.cwiseMax(p.q.head<3>());
        EXPECT_TRUE(EvaluateSpatialPose(robot, p.q).feasible()) << robot.name;
        EXPECT_NEAR(p.q(5), robot.home_rpy_rad.z(), 1e-12) << robot.name;
      }
      for (std::size_t k = 0; k < grid.size(); ++k) {
        for (std::size_t l = 0; l < k; ++l) EXPECT_GT((grid[k].q - grid[l].q).norm(), 1e-9) << robot.name;
      }
      // On cogiro, whose feasible region at home orientation is box-like: every pose in its own
      // cell of the box the poses span, in the grid's order. (A random robot's region is not
      // box-like: a centre outside it takes the nearest feasible point, in another cell.)
      for (int k = 0; robot.name == "cogiro" && k < static_cast<int>(grid.size()); ++k) {
        const Eigen::Vector3i cell((k % side), (k / side) % side, k / (side * side));
        for (int a = 0; a < 3; ++a) {
          const double f = (grid[k].q(a) - lo(a)) / (hi(a) - lo(a));
          EXPECT_GE(f, cell(a) / double(side) - 1e-9) << robot.name << " pose " << k << " axis " << a;
          EXPECT_LE(f, (cell(a) + 1) / double(side) + 1e-9) << robot.name << " pose " << k << " axis " << a;
        }
      }
      const std::vector<SpatialPlanPose> again = GridSpatialPoses(robot, side);
      for (std::size_t k = 0; k < grid.size(); ++k) EXPECT_EQ(grid[k].q, again[k].q);
    }
  }
}

// A trial whose skipped poses leave too few to identify fails in the simulation, saying so:
// the remedy is the plan's margins, not the identification's (a new user's trials read
// "identification: refused (readings: no readings ...)" and the advice was more poses or
// --loss cauchy). cogiro's stiff cables at 3 mm lose a few of 12 poses in every trial.
TEST(SpatialMonteCarlo, SkippedPosesLeavingTooFewFailTheSimulation) {
  SpatialMonteCarloOptions o = Study(12, 4, 0.003);
  o.study.seed = 3;
  o.skip_infeasible = true;
  const MonteCarloResult r = RunSpatialMonteCarlo(BuiltinSpatialRobot("cogiro"), o);
  ASSERT_EQ(r.cells.size(), 1u);
  EXPECT_EQ(r.cells[0].failures("identification"), 0);
  EXPECT_GT(r.cells[0].failures("simulation"), 0);
  for (const TrialOutcome& t : r.cells[0].trials) {
    if (t.ok) continue;
    EXPECT_GT(t.skipped_poses, 0);
    EXPECT_NE(t.failure.find(std::to_string(t.skipped_poses) +
                             " of 12 poses the true robot could not hold within its limits (--skip-infeasible)"),
              std::string::npos)
        << t.failure;
  }
  EXPECT_NE(TallyFailures(r).hint.find("--tension-margin"), std::string::npos) << TallyFailures(r).hint;
}

// --skip-infeasible: a trial whose true robot cannot hold some poses skips them (their x error
// NaN, out of every statistic and of errors.csv) and identifies from the rest, where without
// it the trial fails.
TEST(SpatialMonteCarlo, SkippedPosesAreCountedAndLeftOutOfTheStatistics) {
  const SpatialRobot robot = RandomRobot(46, 6, 5e-5, 1e-3);
  SpatialMonteCarloOptions o = Study(20, 6, 0.002);
  const MonteCarloResult failing = RunSpatialMonteCarlo(robot, o);
  o.skip_infeasible = true;
  const MonteCarloResult skipping = RunSpatialMonteCarlo(robot, o);
  EXPECT_GT(failing.cells[0].failures("simulation"), 0);
  // Every pose the true robot cannot hold is skipped; a trial still fails when it cannot hold
  // home (its sensors' zero): one of the 6 here (measured).
  for (const TrialOutcome& t : skipping.cells[0].trials) {
    if (t.failure.rfind("simulation: ", 0) != 0) continue;
    EXPECT_NE(t.failure.find("the home pose"), std::string::npos) << t.failure;
  }
  EXPECT_LT(skipping.cells[0].failures("simulation"), failing.cells[0].failures("simulation"));
  int skipped = 0;
  for (const TrialOutcome& t : skipping.cells[0].trials) {
    skipped += t.skipped_poses;  // failed trials' too
    if (!t.ok) continue;
    int nan = 0;
    for (const double e : t.errors_m) nan += std::isnan(e);
    EXPECT_EQ(nan, t.skipped_poses);
  }
  EXPECT_GT(skipped, 0);
  EXPECT_TRUE(std::isfinite(Summarise(skipping.cells[0], skipping.geometry_names, "x_all").std));
  EXPECT_EQ(ErrorsCsv(skipping).find("nan"), std::string::npos);
  EXPECT_NE(SummaryMarkdown(skipping, "t").find("skipped " + std::to_string(skipped) + " poses"), std::string::npos);
}

// A designed set that cannot be made, even with the retry's four times as many starts and the
// robustness lowered: the cell's trials fail as "design", and stderr says that both attempts
// were made (the design's own "none of the 4 starts" read wrong beside --design-starts 1).
// Ipopt held to one iteration makes every start fail quickly.
TEST(SpatialMonteCarlo, ADesignThatCannotBeMadeSaysBothAttempts) {
  SpatialMonteCarloOptions o = Study(12, 2, 0.0005);
  o.study.designs = {PoseSetDesign::kOptimized};
  o.study.design_starts = 1;
  o.study.design_in_child_processes = false;
  o.design_max_iterations = 1;
  ::testing::internal::CaptureStderr();
  const MonteCarloResult r = RunSpatialMonteCarlo(BuiltinSpatialRobot("cogiro"), o);
  const std::string err = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(r.cells[0].failures("design"), 2) << err;
  EXPECT_NE(err.find("no pose set for n=12, optimized: with 1 start, then with 4 and the robustness lowered where "
                     "needed: none of the 4 starts"),
            std::string::npos)
      << err;
}

TEST(SpatialMonteCarlo, RefusesWhatItDoesNotServe) {
  const SpatialRobot robot = RandomRobot(49, 6, 5e-5, 1e-3);
  SpatialMonteCarloOptions o = Study(10, 2, 0.002);
  o.study.designs = {PoseSetDesign::kGrid2};
  EXPECT_NE(InputErrorOf([&] { ValidateSpatialMonteCarloOptions(robot, o); }).find("run it with --poses 8"),
            std::string::npos);
  o.study.designs = {PoseSetDesign::kRandom};
  o.study.estimator = Estimator::kPaper;
  EXPECT_NE(InputErrorOf([&] { ValidateSpatialMonteCarloOptions(robot, o); }).find("--estimator"), std::string::npos);
  o.study.estimator = Estimator::kMaximumLikelihood;
  // Encoders alone on 6 inextensible cables: every pose takes all its values, nothing is left
  // for the geometry.
  SpatialRobot encoders_only = robot;
  encoders_only.sensors.inclinometer_rad.reset();
  encoders_only.sensors.laser_m.reset();
  const std::string few = InputErrorOf([&] { RunSpatialMonteCarlo(encoders_only, o); });
  EXPECT_NE(few.find("--poses"), std::string::npos) << few;
  EXPECT_NE(few.find("cannot identify the geometry"), std::string::npos) << few;
  // A planar study refuses the grids.
  MonteCarloOptions planar = o.study;
  planar.designs = {PoseSetDesign::kGrid3};
  planar.pose_counts = {27};
  EXPECT_NE(InputErrorOf([&] { ValidateOptions(planar); }).find("spatial robot's pose set"), std::string::npos);
  EXPECT_EQ(ParseDesigns("random,grid:3x3x3")[1], PoseSetDesign::kGrid3);
}

}  // namespace
}  // namespace cablecal
