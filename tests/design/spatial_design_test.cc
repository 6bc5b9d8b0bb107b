// The spatial experiment design (design/spatial_information.h, design/spatial_design.h).
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <cstdio>
#include <optional>
#include <limits>

#include <omp.h>

#include "common/random.h"
#include "design/spatial_design.h"
#include "design/spatial_information.h"
#include "model/forward_statics.h"
#include "experiment/spatial_plan.h"
#include "experiment/spatial_simulation.h"
#include "identify/spatial_identify.h"
#include "identify/spatial_report.h"
#include "model/builtin_spatial_robots.h"
#include "model/spatial_robot.h"
#include "tests/support/random_spatial_robot.h"
#include "tests/support/six_mixed_robot.h"
#include "tests/support/temp_dir.h"


namespace cablecal {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

// Readings without noise: what the identification itself leaves is under test.
SpatialSimulationOptions NoiseFree() {
  SpatialSimulationOptions quiet;
  quiet.noisy = NoisySensors::kNone;
  quiet.encoder_noise = false;
  return quiet;
}

// cogiro with an inclinometer and a laser instead of its position sensor: three null directions
// (the translations along x and y, the turn about z), held by the gauge.
SpatialRobot CogiroWithInclinometerAndLaser() {
  SpatialRobot robot = BuiltinSpatialRobot("cogiro");
  robot.sensors.position.reset();
  robot.sensors.inclinometer_rad = RangedNoise{0.002, 0.001};
  robot.sensors.laser_m = RangedNoise{0.003, 0.001};
  return robot;
}

// The identification's predicted covariance at noise-free readings of `plan` on the nominal
// robot itself: the estimate is the nominal geometry, so its covariance is the inverse of the
// information at the same poses, independently computed (Ceres' residual blocks there). The
// whole result too, if `result` is given.
MatrixXd IdentificationCovariance(const SpatialRobot& robot, const std::vector<SpatialPlanPose>& plan,
                                  std::vector<std::string>* held, SpatialRobot* at,
                                  std::vector<SpatialPlanPose>* estimated, SpatialIdentifyResult* result = nullptr) {
  Rng rng(3);
  const SimulatedSpatialExperiment sim = SimulateSpatialExperiment(robot, robot, plan, NoiseFree(), rng);
  const SpatialIdentifyResult r = IdentifySpatial(robot, sim.measurements, SpatialIdentifyOptions{});
  EXPECT_TRUE(r.converged()) << r.message << " after " << r.iterations << " iterations, cost " << r.final_cost;
  if (result) *result = r;
  *held = r.held;
  // The estimate is the nominal geometry and poses to the solver's tolerance only: the
  // information is compared where the covariance was computed, at the estimated exits, poses
  // and tensions (the other unknowns enter the readings linearly).
  *at = robot;
  for (int i = 0; i < robot.num_cables(); ++i) at->cables[i].p_F_exit_m = r.geometry.segment<3>(3 * i);
  estimated->clear();
  for (std::size_t j = 0; j < r.poses.size(); ++j) {
    SpatialPlanPose p = plan[j];
    p.q = r.poses[j];
    if (!r.tensions_N.empty()) p.tensions_N = r.tensions_N[j];
    estimated->push_back(p);
  }
  return r.covariance;
}

void ExpectInformationIsInverseCovariance(const SpatialRobot& robot, int n, std::uint64_t seed) {
  SCOPED_TRACE(robot.name);
  const std::vector<SpatialPlanPose> plan = SampleSpatialPoses(robot, n, seed);
  const SpatialInformationLayout L = SpatialDesignLayout(robot, plan);
  std::vector<std::string> held;
  SpatialRobot at;
  std::vector<SpatialPlanPose> estimated;
  const MatrixXd covariance = IdentificationCovariance(robot, plan, &held, &at, &estimated);
  std::vector<std::string> layout_held;
  for (int h : L.held) layout_held.push_back(L.names[h]);
  EXPECT_EQ(layout_held, held);
  ASSERT_EQ(covariance.rows(), L.geometry_size());
  // Where the statics are modelled, the full information's inverse (the mass and centre of mass
  // too: their prior and the equilibrium rows) is the covariance of every free unknown, and S,
  // the platform's unknowns eliminated, is of the geometry's (below).
  const MatrixXd S = L.platform ? SpatialFullInformation(at, L, estimated) : SpatialInformation(at, L, estimated);
  EXPECT_EQ(L.platform, L.tensions);
  // Inverted with S scaled to a unit diagonal (exits in m and offsets in rad differ by orders).
  const VectorXd d = S.diagonal().cwiseSqrt().cwiseInverse();
  const MatrixXd scaled = d.asDiagonal() * S * d.asDiagonal();
  const MatrixXd predicted = d.asDiagonal() * scaled.ldlt().solve(MatrixXd::Identity(S.rows(), S.cols())) * d.asDiagonal();
  const int f = static_cast<int>(L.free.size());
  MatrixXd identified(f, f);
  for (int r = 0; r < f; ++r) {
    for (int c = 0; c < f; ++c) identified(r, c) = covariance(L.free[r], L.free[c]);
  }
  // Inverting S loses cond(S) times the rounding of its entries (the identification's SVD of
  // the unsquared Jacobian loses only the square root of that): ipanema1 with its encoders,
  // inclinometer and laser sees a2y to 11 m, cond(S) ~ 1e11, and agrees to 8e-6 there.
  const Eigen::SelfAdjointEigenSolver<MatrixXd> eig(scaled);
  const double cond = eig.eigenvalues().maxCoeff() / eig.eigenvalues().minCoeff();
  const double tolerance = std::max(1e-8, 1e-15 * cond);
  const double relative = (predicted - identified).norm() / identified.norm();
  std::printf("%s: relative %.3g, cond %.3g\n", robot.name.c_str(), relative, cond);
  EXPECT_LT(relative, tolerance) << "information^-1 vs the identification's covariance, cond(S) " << cond;
  // Every variance on its own too (the small ones hide in the matrix norm).
  for (int k = 0; k < f; ++k) {
    EXPECT_NEAR(predicted(k, k), identified(k, k), tolerance * identified(k, k)) << L.names[L.free[k]];
  }
  if (!L.platform) return;
  // S is the geometry's information: its inverse, the covariance's geometry block.
  const int g = L.information_size();
  ASSERT_EQ(g, f - 4);
  const MatrixXd S_geometry = SpatialInformation(at, L, estimated);
  ASSERT_EQ(S_geometry.rows(), g);
  const VectorXd dg = S_geometry.diagonal().cwiseSqrt().cwiseInverse();
  const MatrixXd geometry_covariance =
      dg.asDiagonal() * (dg.asDiagonal() * S_geometry * dg.asDiagonal()).ldlt().solve(MatrixXd::Identity(g, g)) *
      dg.asDiagonal();
  EXPECT_LT((geometry_covariance - identified.topLeftCorner(g, g)).norm(), tolerance * identified.topLeftCorner(g, g).norm());
}

TEST(SpatialInformation, InverseIsTheIdentificationsCovarianceOnTheBuiltinRobots) {
  for (const char* name : {"cogiro", "ipanema1", "irma4u"}) {
    ExpectInformationIsInverseCovariance(BuiltinSpatialRobot(name), 14, 5);
  }
}

TEST(SpatialInformation, InverseIsTheIdentificationsCovarianceOnRandomRobots) {
  Rng rng(2801);
  for (int m : {4, 5, 8}) {
    SpatialRobot robot = testing::RandomSpatialRobot(rng, "random" + std::to_string(m), m);
    // A simulatable robot (at most 6 inextensible cables) with an inclinometer and a laser, so
    // that more than the encoders' gauge is exercised.
    for (int i = 6; i < m; ++i) robot.cables[i].stiffness_N = 2e6;
    robot.sensors.inclinometer_rad = RangedNoise{0.002, 0.001};
    robot.sensors.laser_m = RangedNoise{0.003, 0.001};
    ExpectInformationIsInverseCovariance(robot, 12, 7);
  }
}

// Design and identification count the fewest poses alike: MinSpatialDesignPoses poses of
// noise-free readings pass the identification's count of values against unknowns (the rigid
// motions the gauge holds not among them), one pose fewer is refused as too few. Before, the
// identification counted the held coordinates too and refused a 4-cable robot's 3 designed poses.
TEST(SpatialDesign, FewestPosesAreTheIdentificationsFewest) {
  Rng rng(2911);
  std::vector<SpatialRobot> robots = {BuiltinSpatialRobot("irma4u"), BuiltinSpatialRobot("cogiro"),
                                      CogiroWithInclinometerAndLaser()};
  for (int m : {4, 5, 7}) {
    SpatialRobot robot = testing::RandomSpatialRobot(rng, "random" + std::to_string(m), m);
    for (int i = 6; i < m; ++i) robot.cables[i].stiffness_N = 2e6;
    robot.sensors.inclinometer_rad = RangedNoise{0.002, 0.001};
    robots.push_back(robot);
  }
  // One swivel axis tilted by 10 degrees: the turn about z is barely seen, and design holds it
  // (a fourth coordinate) with an inclinometer alone, and with a laser alone on stretching cables.
  for (const bool laser : {false, true}) {
    SpatialRobot robot = testing::RandomSpatialRobot(rng, laser ? "random4-tilted-laser" : "random4-tilted", 4);
    robot.cables[2].k_F_swivel_axis = Eigen::Vector3d(std::sin(0.17), 0.0, std::cos(0.17));
    robot.sensors = SpatialSensors{};
    robot.sensors.encoder_sigma_m = 5e-5;
    if (laser) {
      robot.sensors.laser_m = RangedNoise{0.006, 0.0015};
      for (SpatialCable& cable : robot.cables) cable.stiffness_N = 5e4;
    } else {
      robot.sensors.inclinometer_rad = RangedNoise{0.1 * M_PI / 180.0, 0.05 * M_PI / 180.0};
    }
    robots.push_back(robot);
  }
  for (const SpatialRobot& robot : robots) {
    SCOPED_TRACE(robot.name);
    const SpatialInformationLayout layout = SpatialDesignLayout(robot, SampleSpatialPoses(robot, 20, 9));
    const int fewest = MinSpatialDesignPoses(robot, layout);
    std::printf("%s: fewest %d poses, %zu held (%zu weakly seen)\n", robot.name.c_str(), fewest, layout.held.size(),
                layout.weakly_seen_held.size());
    ASSERT_GE(fewest, 1);
    ASSERT_LE(fewest, 40);
    // Identify's default gauge, and the hold: list design says reproduces its covariance.
    SpatialIdentifyOptions hold;
    hold.gauge.kind = SpatialGaugeKind::kHold;
    for (int h : layout.held) hold.gauge.held.push_back(layout.names[h]);
    for (const SpatialIdentifyOptions& options : {SpatialIdentifyOptions{}, hold}) {
      if (options.gauge.kind == SpatialGaugeKind::kHold && options.gauge.held.empty()) continue;
      // A weakly seen direction held as nearly rigid (within kSpatialNearlyRigid of a rigid
      // motion) is so at the design's poses; the default gauge decides it again at the
      // identification's, other poses, which may see it beyond that bound and then hold one
      // coordinate fewer, needing a pose more (random4-tilted-laser at 13 poses: 2 held, where
      // the design's 20 held 3). The hold: list design gives is exact at any poses.
      const int more = options.gauge.kind == SpatialGaugeKind::kHold ? 0 : static_cast<int>(layout.weakly_seen_held.size());
      for (int n : {fewest + more, fewest - 1}) {
        if (n < 1) continue;
        Rng noise(4);
        const SimulatedSpatialExperiment sim =
            SimulateSpatialExperiment(robot, robot, SampleSpatialPoses(robot, n, 11), NoiseFree(), noise);
        std::string error;
        try {
          AnalyzeSpatialGauge(robot, sim.measurements, options);
        } catch (const InputError& e) {
          error = e.what();
        }
        const bool too_few = error.find("too few to determine the geometry") != std::string::npos;
        EXPECT_EQ(too_few, n < fewest) << n << " poses of at least " << fewest << ", gauge "
                                       << ToString(options.gauge) << ": " << error;
      }
    }
  }
}

// Calibrating in rounds (--prior): the information a first round's result.yaml gives, written
// and read back, is the information of its poses (the inverse of its covariance, independently
// computed by the identification), and the second round's design counts it: its criteria are
// those of S(new poses) + that information, better than the new poses' alone and than the
// first round's alone.
TEST(SpatialDesign, PriorIsTheFirstRoundsInformationAndTheSecondRoundCountsIt) {
  const SpatialRobot robot = CogiroWithInclinometerAndLaser();
  const std::vector<SpatialPlanPose> first = SampleSpatialPoses(robot, 12, 31);
  std::vector<std::string> held;
  SpatialRobot at;
  std::vector<SpatialPlanPose> estimated;
  SpatialIdentifyResult r;
  IdentificationCovariance(robot, first, &held, &at, &estimated, &r);
  ASSERT_TRUE(r.converged()) << r.message;
  // The first round's result.yaml, as identify writes it.
  const std::string path = ::testing::TempDir() + "cablecal_spatial_prior_result.yaml";
  {
    std::ofstream out(path);
    out << SpatialIdentifyResultYaml(robot, SpatialIdentifyOptions{}, r, "test");
  }
  const SpatialIdentifiedGeometry known = ReadSpatialIdentifiedGeometry(robot, path);
  EXPECT_EQ(known.names, r.names);
  EXPECT_EQ(known.held, r.held);
  EXPECT_LT((known.geometry - r.geometry).cwiseAbs().maxCoeff(), 1e-12);
  SpatialInformationLayout L = SpatialDesignLayout(robot, SampleSpatialPoses(robot, 12, 9));
  HoldAsThePrior(&L, known.held, path);
  std::vector<std::string> layout_held;
  for (const int h : L.held) layout_held.push_back(L.names[h]);
  EXPECT_EQ(layout_held, known.held);
  const MatrixXd prior = SpatialPriorInformation(L, known.names, known.held, known.covariance, path);
  // The first round's poses' information with the platform's prior, as the identification had.
  const MatrixXd F_first = SpatialFullInformation(at, L, estimated);  // L without the prior yet
  L.prior_information = prior;
  const double first_relative = (prior - F_first).norm() / F_first.norm();
  EXPECT_LT(first_relative, 1e-6) << "the result's information against its poses' (YAML's 17 digits)";
  // The second round.
  SpatialDesignOptions options;
  options.poses = 10;
  options.starts = 1;
  options.random_sets = 3;
  options.seed = 4;
  options.geometry_sigma_m = 0.0;
  options.prior = known;
  const SpatialRobot second_robot = CalibratedSpatialRobot(robot, known);
  const SpatialDesignResult second = DesignSpatialPoses(second_robot, options);
  EXPECT_EQ(second.layout.held, L.held);
  const MatrixXd F_second = SpatialFullInformation(second_robot, L, second.poses);  // L counts the prior
  SpatialInformationLayout without = L;
  without.prior_information.resize(0, 0);
  // The second round's poses alone (with the platform's prior, which the first round's holds).
  const MatrixXd F_new = SpatialFullInformation(second_robot, without, second.poses);
  const MatrixXd platform_prior = SpatialFullInformation(second_robot, without, {});
  ASSERT_TRUE(L.platform) << "cogiro's stretch is modelled: its mass and centre of mass are unknowns";
  EXPECT_GT((platform_prior.bottomRightCorner<4, 4>().trace()), 0.0);
  EXPECT_LT((F_second - (F_new - platform_prior) - prior).norm(), 1e-9 * F_second.norm());
  const MatrixXd S_second = SpatialGeometryInformation(L, F_second);
  EXPECT_LT((S_second - SpatialInformation(second_robot, L, second.poses)).norm(), 1e-12 * S_second.norm());
  const CriteriaValues counted = SpatialCriteria(S_second),
                       alone = SpatialCriteria(SpatialGeometryInformation(L, F_new)),
                       before = SpatialCriteria(SpatialGeometryInformation(L, prior));
  EXPECT_NEAR(second.criteria.a_trace_covariance_m2, counted.a_trace_covariance_m2, 1e-9 * counted.a_trace_covariance_m2);
  EXPECT_LT(counted.a_trace_covariance_m2, alone.a_trace_covariance_m2);
  EXPECT_LT(counted.a_trace_covariance_m2, before.a_trace_covariance_m2);
  std::printf("trace of the covariance: first round %.3g, second round's poses alone %.3g, both %.3g m^2\n",
              before.a_trace_covariance_m2, alone.a_trace_covariance_m2, counted.a_trace_covariance_m2);
  const std::string summary = SpatialDesignSummaryYaml(second_robot, second, options, "test");
  EXPECT_NE(summary.find("prior: \"" + path + "\""), std::string::npos) << summary;
  std::remove(path.c_str());
}

// Two rounds of one calibration on one true robot: the second round commanded from the first
// round's calibrated robot file, its encoders still counting from the true robot's zero (the
// truth file's initial lengths, which simulate keeps), so that both rounds' noise-free readings
// are one experiment: identified together they fit to the rounding. Before simulate kept that
// zero, the second round's encoders were zeroed at the calibrated home lengths, and the joint
// fit was refused (a new user: 6.8 sigma with noise-free readings).
TEST(SpatialDesign, TwoSimulatedRoundsAreOneExperiment) {
  const SpatialRobot robot = CogiroWithInclinometerAndLaser();
  SpatialSimulationOptions quiet = NoiseFree();
  quiet.skip_infeasible = true;  // a pose near the tension bounds may not hold on the true robot
  const SpatialPlanSimulation first =
      SimulateSpatialPlan(robot, std::nullopt, 0.0005, SampleSpatialPoses(robot, 14, 41), quiet, 8, "first");
  SpatialIdentifyOptions id;
  const SpatialIdentifyResult r1 = IdentifySpatial(robot, first.experiment.measurements, id);
  ASSERT_TRUE(r1.converged()) << r1.message;
  // The first round's estimate with the errors noisy readings leave (noise-free ones leave
  // none): initial lengths off by 2 mm, which the second round's zero must not adopt.
  SpatialRobot calibrated = CalibratedSpatialRobot(robot, r1);
  for (int i = 0; i < robot.num_cables(); ++i) *calibrated.cables[i].initial_length_m += i % 2 ? 0.002 : -0.002;
  const SpatialPlanSimulation second =
      SimulateSpatialPlan(calibrated, first.truth, 0.0, SampleSpatialPoses(calibrated, 10, 42), quiet, 9, "second");
  for (int i = 0; i < robot.num_cables(); ++i) {
    EXPECT_EQ(*second.truth.cables[i].initial_length_m, *first.truth.cables[i].initial_length_m) << "cable " << i + 1;
  }
  std::vector<SpatialMeasurement> both = first.experiment.measurements;
  for (SpatialMeasurement m : second.experiment.measurements) {
    m.pose_id += 100;
    both.push_back(m);
  }
  const SpatialIdentifyResult joint = IdentifySpatial(robot, both, id);
  ASSERT_TRUE(joint.converged()) << joint.message;
  EXPECT_LT(std::abs(joint.worst_residual), 1e-3) << joint.worst_sensor << " of pose " << joint.worst_pose_id;
}

// What a prior cannot be, each an InputError naming the file and key.
TEST(SpatialDesign, PriorsThatCannotBeAreRefusedNamingTheKey) {
  const SpatialRobot robot = CogiroWithInclinometerAndLaser();
  const std::vector<SpatialPlanPose> plan = SampleSpatialPoses(robot, 20, 31);
  Rng rng(3);
  const SimulatedSpatialExperiment sim = SimulateSpatialExperiment(robot, robot, plan, NoiseFree(), rng);
  const std::string path = ::testing::TempDir() + "cablecal_spatial_bad_prior.yaml";
  const auto refusal = [&](const SpatialRobot& nominal, const SpatialIdentifyOptions& id, const SpatialRobot& designed) {
    const SpatialIdentifyResult r = IdentifySpatial(nominal, sim.measurements, id);
    std::ofstream(path) << SpatialIdentifyResultYaml(nominal, id, r, "test");
    try {
      const SpatialIdentifiedGeometry known = ReadSpatialIdentifiedGeometry(designed, path);
      SpatialInformationLayout L = SpatialDesignLayout(designed, plan);
      HoldAsThePrior(&L, known.held, path);
      SpatialPriorInformation(L, known.names, known.held, known.covariance, path);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  SpatialIdentifyOptions none;
  none.gauge.kind = SpatialGaugeKind::kNone;
  EXPECT_NE(refusal(robot, none, robot).find(path + ": gauge: a result identified with --gauge none"), std::string::npos);
  SpatialRobot other = robot;
  other.name = "another";
  EXPECT_NE(refusal(robot, {}, other).find("a result of another robot"), std::string::npos);
  // The design's robot has no laser: the result's held coordinates (its laser saw z) leave the
  // frame's height free.
  SpatialRobot no_laser = robot;
  no_laser.sensors.laser_m.reset();
  EXPECT_NE(refusal(robot, {}, no_laser).find(path + ": held: holds a1x,a2y,a6y, which leaves 1 of the 4 directions"),
            std::string::npos)
      << refusal(robot, {}, no_laser);
  std::ofstream(path) << "status: converged\nparameters: {}\n";
  try {
    ReadSpatialIdentifiedGeometry(robot, path);
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(path + ": robot: not the result of a spatial robot"), std::string::npos)
        << e.what();
  }
  std::remove(path.c_str());
}

// The gradient of every criterion against central differences of the objective.
TEST(SpatialInformation, GradientMatchesDifferences) {
  Rng rng(2802);
  SpatialRobot random = testing::RandomSpatialRobot(rng, "random5", 5);
  random.sensors.swivel_rad = RangedNoise{0.01, 0.0};
  random.sensors.heading_rad = RangedNoise{0.02, 0.0};
  for (const SpatialRobot& robot : {BuiltinSpatialRobot("cogiro"), BuiltinSpatialRobot("irma4u"), random}) {
    SCOPED_TRACE(robot.name);
    const std::vector<SpatialPlanPose> plan = SampleSpatialPoses(robot, 12, 11);
    const SpatialInformationLayout L = SpatialDesignLayout(robot, plan);
    const int m = robot.num_cables();
    for (Criterion c : {Criterion::kCondition, Criterion::kD, Criterion::kA, Criterion::kE}) {
      SCOPED_TRACE(ToString(c));
      const double power = (c == Criterion::kD || c == Criterion::kA) ? 0.0 : 8.0;
      VectorXd g;
      const double f0 = SpatialDesignObjective(robot, L, c, plan, &g, power);
      ASSERT_TRUE(std::isfinite(f0));
      ASSERT_EQ(g.size(), 12 * (6 + m));
      double scale = g.cwiseAbs().maxCoeff();
      for (int j : {0, 5}) {
        for (int k = 0; k < 6 + m; ++k) {
          // 1e-5, not smaller: the objective's rounding (the equilibrium rows' weights, the
          // platform's unknowns eliminated from information of 1e8 / m^2) is ~1e-11, which a
          // step of 1e-6 already lifts to 1e-5 of the gradient; the truncation stays ~1e-10.
          const double h = k < 6 ? 1e-5 : 1e-5 * robot.tension_max_N;
          std::vector<SpatialPlanPose> plus = plan, minus = plan;
          if (k < 6) {
            plus[j].q(k) += h;
            minus[j].q(k) -= h;
          } else {
            plus[j].tensions_N(k - 6) += h;
            minus[j].tensions_N(k - 6) -= h;
          }
          const double fd = (SpatialDesignObjective(robot, L, c, plus, nullptr, power) -
                             SpatialDesignObjective(robot, L, c, minus, nullptr, power)) /
                            (2 * h);
          const double unit = k < 6 ? 1.0 : robot.tension_max_N;  // compare per natural step
          EXPECT_NEAR(g((6 + m) * j + k) * unit, fd * unit, 1e-5 * scale * unit + 1e-7) << "pose " << j << " var " << k;
        }
      }
    }
  }
}

// Designed poses hold: each a feasible equilibrium of the nominal robot, and the forward model
// with the plan's commanded lengths settles the platform there (the robot taken as true).
void ExpectDesignHolds(const SpatialRobot& robot, int extra_poses, Criterion criterion,
                       std::optional<double> geometry_sigma_m = std::nullopt) {
  SCOPED_TRACE(robot.name);
  SpatialDesignOptions options;
  options.geometry_sigma_m = geometry_sigma_m;
  // The layout (what is held, what is free) from 12 random poses: more than any of these robots'
  // fewest, and sampling is most of this test's time (irma4u: 0.25 s a pose).
  options.poses = MinSpatialDesignPoses(robot, SpatialDesignLayout(robot, SampleSpatialPoses(robot, 12, 9))) + extra_poses;
  options.starts = 2;
  // 9 random sets: the improvements are 10 to 100 times (measured), far from the 2x asserted;
  // more sets would steady the median, not change what the test shows.
  options.random_sets = 9;
  options.criterion = criterion;
  options.seed = 28;
  const SpatialDesignResult r = DesignSpatialPoses(robot, options);
  ASSERT_EQ(static_cast<int>(r.poses.size()), options.poses);
  for (std::size_t j = 0; j < r.poses.size(); ++j) {
    const SpatialPlanPose& p = r.poses[j];
    EXPECT_EQ(CheckSpatialFeasibility(robot, p.q, p.tensions_N), Feasibility::kFeasible) << "pose " << j + 1;
    const SpatialForwardResult settled =
        SolveForwardStatics(robot, CommandedUnstretchedLengths(robot, p.lengths_m, p.tensions_N), &p.q);
    EXPECT_EQ(settled.status, ForwardStatus::kConverged) << "pose " << j + 1;
    EXPECT_LT((settled.equilibrium.q - p.q).cwiseAbs().maxCoeff(), 1e-6) << "pose " << j + 1;
  }
  const double factor = Improvement(criterion, r.criteria, r.random_median);
  std::printf("%s: %d poses, %s improvement %.3g over the random median, %.1f s\n", robot.name.c_str(), options.poses,
              ToString(criterion), factor, r.wall_time_s);
  EXPECT_GE(factor, 2.0);
}

// Each start's Ipopt solve in a child process (the default, so that starts solve at once) gives
// the design the same solves in this process give, bit for bit: statuses, iterations, each
// start's criterion and the plan.
TEST(SpatialDesign, SolvesInChildProcessesEqualSolvesInProcess) {
  const SpatialRobot robot = BuiltinSpatialRobot("cogiro");
  SpatialDesignOptions options;
  options.poses = 13;
  options.starts = 2;
  options.random_sets = 0;
  options.seed = 5;
  options.geometry_sigma_m = 0.0;  // the robust re-solves take the same path; without them 4 times faster
  options.solve_in_child_processes = true;
  const SpatialDesignResult children = DesignSpatialPoses(robot, options);
  options.solve_in_child_processes = false;
  const SpatialDesignResult here = DesignSpatialPoses(robot, options);
  EXPECT_EQ(SpatialPlanCsv(children.poses, ""), SpatialPlanCsv(here.poses, ""));
  ASSERT_EQ(children.starts.size(), here.starts.size());
  for (std::size_t k = 0; k < here.starts.size(); ++k) {
    EXPECT_EQ(children.starts[k].ipopt_status, here.starts[k].ipopt_status) << "start " << k;
    EXPECT_EQ(children.starts[k].iterations, here.starts[k].iterations) << "start " << k;
    EXPECT_EQ(children.starts[k].objective, here.starts[k].objective) << "start " << k;
  }
}

// A solve ends when its criterion stalls (README, "Experiment design" of spatial robots): on
// cogiro's 30 poses Ipopt's own tolerance takes 448 iterations, the last third for an
// infeasibility the verification removes. The stalled solve's poses are its best clean iterate:
// verified, and their criterion within a thousandth of the full solve's (measured 6e-5).
TEST(SpatialDesign, AStalledSolveStopsEarlyWithinAThousandthOfTheFullSolvesCriterion) {
  const SpatialRobot robot = BuiltinSpatialRobot("cogiro");
  SpatialDesignOptions options;
  options.poses = 30;
  options.starts = 1;
  options.random_sets = 0;
  options.geometry_sigma_m = 0.0;
  const SpatialDesignResult stalled = DesignSpatialPoses(robot, options);
  options.stop_when_stalled = false;
  const SpatialDesignResult full = DesignSpatialPoses(robot, options);
  ASSERT_EQ(stalled.starts.size(), 1u);
  ASSERT_EQ(full.starts.size(), 1u);
  EXPECT_EQ(stalled.starts[0].ipopt_status, "Criterion_Stalled");
  EXPECT_TRUE(stalled.starts[0].verified);
  EXPECT_NE(full.starts[0].ipopt_status, "Criterion_Stalled");
  EXPECT_LT(stalled.starts[0].iterations, full.starts[0].iterations * 3 / 4);
  std::printf("stalled after %d iterations at trace %.9g m^2, Ipopt's tolerance after %d at %.9g m^2\n",
              stalled.starts[0].iterations, stalled.criteria.a_trace_covariance_m2, full.starts[0].iterations,
              full.criteria.a_trace_covariance_m2);
  EXPECT_NEAR(std::log(stalled.criteria.a_trace_covariance_m2), std::log(full.criteria.a_trace_covariance_m2), 1e-3);
}

// With robustness the starts are made robust two at a time, those whose first solves have the
// lowest criteria first, until one holds; the plan is the best that holds and the same whatever
// the thread count (the pairs are fixed, not the threads').
TEST(SpatialDesign, StartsAreMadeRobustTwoAtATimeLowestFirstCriterionFirst) {
  const SpatialRobot robot = BuiltinSpatialRobot("cogiro");
  SpatialDesignOptions options;
  options.poses = 13;
  options.starts = 5;
  options.random_sets = 0;
  options.seed = 3;
  omp_set_num_threads(1);
  const SpatialDesignResult one = DesignSpatialPoses(robot, options);
  omp_set_num_threads(2);
  const SpatialDesignResult r = DesignSpatialPoses(robot, options);
  EXPECT_EQ(SpatialPlanCsv(one.poses, ""), SpatialPlanCsv(r.poses, ""));
  ASSERT_EQ(r.starts.size(), 5u);
  int made = 0;
  double highest_made = -std::numeric_limits<double>::infinity();
  double lowest_left = std::numeric_limits<double>::infinity();
  for (const SpatialStartReport& s : r.starts) {
    if (s.made_robust) {
      ++made;
      highest_made = std::max(highest_made, s.first_objective);
    } else {
      EXPECT_EQ(s.robust_rounds, 0);
      EXPECT_FALSE(s.verified);  // only its first solve was
      EXPECT_TRUE(std::isfinite(s.first_objective));
      lowest_left = std::min(lowest_left, s.first_objective);
    }
  }
  std::printf("%d of 5 starts made robust; their first criteria at most %.6g, the others' at least %.6g\n", made,
              highest_made, lowest_left);
  EXPECT_EQ(made, 2);  // measured: the first pair holds
  EXPECT_LE(highest_made, lowest_left);
  ASSERT_GE(r.best_start, 0);
  EXPECT_TRUE(r.starts[r.best_start].made_robust);
  EXPECT_TRUE(r.starts[r.best_start].verified);
  EXPECT_GT(r.starts[r.best_start].robust_rounds, 0);
}

// As the planar design's test: a stray ipopt.opt in the working directory is not read (here
// one that would make Ipopt write a journal; one iteration is enough to show it).
TEST(SpatialDesign, AnIpoptOptionsFileInTheWorkingDirectoryIsNotRead) {
  const SpatialRobot robot = BuiltinSpatialRobot("cogiro");
  SpatialDesignOptions options;
  options.poses = 13;
  options.starts = 1;
  options.random_sets = 0;
  options.geometry_sigma_m = 0.0;
  options.max_iterations = 1;
  options.solve_in_child_processes = false;
  testing_support::TempDir dir;
  dir.Write("ipopt.opt", "output_file journal.txt\nfile_print_level 5\n");
  try {
    const testing_support::ScopedWorkingDirectory in_dir(dir.path());
    DesignSpatialPoses(robot, options);
  } catch (const SolverFailure&) {
    // one iteration converges to nothing: expected
  }
  EXPECT_FALSE(std::filesystem::exists(dir.Path("journal.txt")));
}

// cogiro's and ipanema1's robust designs are the RobustPlansHold* and RobustnessIsLowered* tests
// (below): here their nominal designs, four times faster, for the criterion against random sets.
TEST(SpatialDesign, CogiroHoldsAndBeatsRandom) {
  ExpectDesignHolds(BuiltinSpatialRobot("cogiro"), 2, Criterion::kA, 0.0);
}

TEST(SpatialDesign, Irma4uHoldsAndBeatsRandom) { ExpectDesignHolds(BuiltinSpatialRobot("irma4u"), 2, Criterion::kA); }

// ipanema1: its encoders, inclinometer and laser leave the turn about the vertical unseen (its
// swivel axes are all vertical). Until the identification's gauge analysis balanced each
// start's tensions, a misfit start made that turn look weakly seen (cond(S) ~ 1e12, a2y "seen"
// to about 11 m), and both starts ended at Ipopt's iteration cap; now it designs in seconds.
TEST(SpatialDesign, Ipanema1HoldsAndBeatsRandom) {
  ExpectDesignHolds(BuiltinSpatialRobot("ipanema1"), 10, Criterion::kA, 0.0);
}

// What labs do today: the peer's 3x3x3 grid of positions at home's orientation (27 poses,
// experiment/spatial_plan.h GridSpatialPoses). A designed set of as many poses beats it on its
// criterion, on each built-in robot with its file's sensors and on a random one (nominal
// designs, one start: the comparison, not the robustness, is under test).
TEST(SpatialDesign, TwentySevenDesignedPosesBeatTheThreeByThreeByThreeGrid) {
  Rng rng(2816);
  SpatialRobot random = testing::RandomSpatialRobot(rng, "random6", 6);
  random.sensors.inclinometer_rad = RangedNoise{0.002, 0.001};
  random.sensors.laser_m = RangedNoise{0.001, 0.0005};
  for (const SpatialRobot& robot : {BuiltinSpatialRobot("cogiro"), BuiltinSpatialRobot("ipanema1"),
                                    BuiltinSpatialRobot("irma4u"), random}) {
    SCOPED_TRACE(robot.name);
    SpatialDesignOptions options;
    options.poses = 27;
    options.starts = 1;
    options.random_sets = 0;
    options.seed = 6;
    options.geometry_sigma_m = 0.0;
    const SpatialDesignResult designed = DesignSpatialPoses(robot, options);
    const CriteriaValues grid = SpatialCriteria(SpatialInformation(robot, designed.layout, GridSpatialPoses(robot, 3)));
    const double factor = Improvement(Criterion::kA, designed.criteria, grid);
    std::printf("%s: 27 designed poses %.3g x better on A than the 3x3x3 grid (trace %.3g against %.3g), %.1f s\n",
                robot.name.c_str(), factor, designed.criteria.a_trace_covariance_m2, grid.a_trace_covariance_m2,
                designed.wall_time_s);
    std::fflush(stdout);  // before the next design's child processes inherit the buffer
    EXPECT_GT(factor, 1.0);
  }
}

// One swivel axis tilted 8.5 degrees among cogiro's vertical ones (encoders, inclinometer,
// laser): the turn about z, unseen with every axis vertical, is barely seen (relative singular
// value about 3e-6), and the gauge holds it as it holds the unseen one. Before it did, the A
// criterion on it was nearly singular and every start ended at Ipopt's iteration cap.
TEST(SpatialDesign, OneTiltedSwivelAxisDesignsWithItsBarelySeenTurnHeld) {
  SpatialRobot robot = BuiltinSpatialRobot("cogiro");
  robot.name = "cogiro-tilted";
  robot.cables[2].k_F_swivel_axis = Eigen::Vector3d(std::sin(0.148), 0.0, std::cos(0.148));
  robot.sensors = SpatialSensors{};
  robot.sensors.encoder_sigma_m = 5e-5;
  robot.sensors.inclinometer_rad = RangedNoise{0.1 * M_PI / 180.0, 0.05 * M_PI / 180.0};
  robot.sensors.laser_m = RangedNoise{0.006, 0.0015};
  const SpatialInformationLayout layout = SpatialDesignLayout(robot, SampleSpatialPoses(robot, 12, 9));
  ASSERT_EQ(layout.weakly_seen_held.size(), 1u);
  EXPECT_EQ(layout.weakly_seen_held[0].rfind("nearly a rotation about z of the frame", 0), 0u) << layout.weakly_seen_held[0];
  EXPECT_EQ(layout.held.size(), 3u);  // the translations along x and y, and the turn
  ExpectDesignHolds(robot, 2, Criterion::kA, 0.0);
}

TEST(SpatialDesign, RandomRobotHoldsAndBeatsRandom) {
  Rng rng(2803);
  SpatialRobot robot = testing::RandomSpatialRobot(rng, "random4", 4);
  robot.sensors.inclinometer_rad = RangedNoise{0.002, 0.001};
  ExpectDesignHolds(robot, 2, Criterion::kD);
}

// Robustness (design/spatial_design.h): a plan is run open loop on a robot whose exits are off
// by ~sigma, so a designed pose must hold on such true robots, checked as the simulation checks a
// lab's experiment (the forward model settles the platform under the plan's commanded lengths,
// within the true robot's limits). The same design without robustness puts its poses on the
// limits, where true robots drawn the same way fail: that is what the robustness is for, and it
// shows this test can fail.
// True robots are drawn at a third of the plan's achieved k: exits with k / 3 x geometry_sigma_m,
// the platform with k / 3 times its priors, so that the plan's k sigma is their 3 sigma.
int TrueRobotsThatCannotHoldThePlan(const SpatialRobot& robot, const std::vector<SpatialPlanPose>& plan,
                                    double achieved_k, double geometry_sigma_m, int draws, std::string* first) {
  const double scale = achieved_k / 3.0;
  const Eigen::Vector4d platform_sigma = scale * SpatialPlatformPriorSigma(robot);
  const SpatialSimulationOptions quiet = NoiseFree();
  Rng rng(StreamSeed(2811, {}));
  int failed = 0;
  for (int d = 0; d < draws; ++d) {
    SpatialRobot truth = PerturbSpatialGeometry(robot, scale * geometry_sigma_m, rng);
    // The platform too, as the Monte Carlo draws it.
    truth.mass_sigma_kg = platform_sigma(0);
    truth.com_sigma_m = platform_sigma(1);
    PerturbSpatialPlatform(&truth, rng);
    try {
      Rng noise(1);
      SimulateSpatialExperiment(robot, truth, plan, quiet, noise);
    } catch (const SolverFailure& e) {
      if (first->empty()) *first = e.what();
      ++failed;
    }
  }
  return failed;
}

// With the robustness the design achieved (k x sigma, perhaps lowered, at least `least_k`), true
// robots are drawn with k / 3 x sigma per exit coordinate, so that the plan's k sigma is their 3
// sigma.
void ExpectRobustDesignHoldsOnTrueRobots(const SpatialRobot& robot, int n, double least_k,
                                         std::optional<double> sigma_m = std::nullopt, double requested_k = 3.0) {
  SCOPED_TRACE(robot.name);
  ASSERT_TRUE(robot.sensors.tracker_sigma_m.has_value());
  SpatialDesignOptions options;
  options.geometry_sigma_m = sigma_m;
  options.poses = n;
  options.starts = 1;  // the robust rounds are per start: one shows them, in half the time
  options.random_sets = 0;
  options.seed = 11;
  options.robust_sigmas = requested_k;
  const SpatialDesignResult robust = DesignSpatialPoses(robot, options);
  EXPECT_EQ(robust.geometry_sigma_m, sigma_m.value_or(*robot.sensors.tracker_sigma_m));  // default: the tracker's
  EXPECT_GE(robust.robust_sigmas_achieved, least_k) << robust.robustness_note;
  ASSERT_GT(robust.robust_sigmas_achieved, 0.0);
  const double k = robust.robust_sigmas_achieved, draw_sigma_m = k / 3.0 * robust.geometry_sigma_m;
  std::string first;
  constexpr int kDraws = 20;
  const int robust_failed = TrueRobotsThatCannotHoldThePlan(robot, robust.poses, k, robust.geometry_sigma_m, kDraws, &first);
  EXPECT_EQ(robust_failed, 0) << first;
  options.geometry_sigma_m = 0.0;
  const SpatialDesignResult nominal = DesignSpatialPoses(robot, options);
  first.clear();
  const int nominal_failed = TrueRobotsThatCannotHoldThePlan(robot, nominal.poses, k, robust.geometry_sigma_m, kDraws, &first);
  std::printf("%s: %d poses, robust to k = %g; true robots (sigma %.3g m) that cannot hold the plan: %d of %d robust "
              "(%.1f s), %d of %d without robustness (%s)\n", robot.name.c_str(), n, robust.robust_sigmas_achieved,
              draw_sigma_m, robust_failed, kDraws, robust.wall_time_s, nominal_failed, kDraws, first.c_str());
  EXPECT_GT(nominal_failed, 0);
}

TEST(SpatialDesign, RobustPlansHoldOnTrueCogiros) {
  // Measured since the platform's mass and centre of mass are among the scenario robots: k = 3
  // (one robust design, 14 s). An earlier version gave 2.95 when another test's in-process design
  // ran first; at 38dca35 the whole file in one process gives k = 3 here too, and three equal
  // robust cogiro designs in one Python process are the same plan byte for byte.
  ExpectRobustDesignHoldsOnTrueRobots(BuiltinSpatialRobot("cogiro"), 13, 2.5);
}

TEST(SpatialDesign, RobustPlansHoldOnTrueRandomRobots) {
  // A random 6-cable robot (stiff and inextensible cables mixed, tilted swivel axes, an offset
  // centre of mass) surveyed to 50 micrometres: with the file's 0.5 mm its stiff cables hold
  // plans only to k = 0.55 (the search's, measured: 81 s), which the ipanema1 test covers.
  // Measured: k = 1.15 of the requested 3 since the platform is among the scenario robots (1.5
  // before; 2.25 before the platform's mass and centre of mass were unknowns: another optimum; 3
  // before its turn about z, weakly seen, was held by the gauge). The search for that k took 70
  // s of the suite and is what the ipanema1 test below shows; here k = 1 is asked (one design,
  // 4 s) and the property is the plan's: it holds where the nominal plan does not.
  Rng rng(2816);
  SpatialRobot robot = testing::RandomSpatialRobot(rng, "random6", 6);
  robot.sensors.inclinometer_rad = RangedNoise{0.002, 0.001};
  robot.sensors.laser_m = RangedNoise{0.001, 0.0005};
  ExpectRobustDesignHoldsOnTrueRobots(robot, 12, 1.0, 5e-5, /*requested_k=*/1.0);
}

// Where no start holds at the requested robustness the design runs at the largest k that does
// and says so (design never gives up for robustness alone): ipanema1's steel cables (E A 3.1e6
// N over about 2 m) turn 0.5 mm of exit error into hundreds of newtons.
TEST(SpatialDesign, RobustnessIsLoweredWhereNoPlanHoldsAndSaid) {
  const SpatialRobot robot = BuiltinSpatialRobot("ipanema1");
  SpatialDesignOptions options;
  options.poses = 14;
  options.starts = 1;
  options.random_sets = 0;
  const SpatialDesignResult r = DesignSpatialPoses(robot, options);
  EXPECT_EQ(r.robust_sigmas_requested, 3.0);
  EXPECT_TRUE(r.robustness_lowered());
  EXPECT_GT(r.robust_sigmas_achieved, 0.0);
  EXPECT_NE(r.robustness_note.find("not the requested 3 x 5.0e-04 m"), std::string::npos) << r.robustness_note;
  const std::string summary = SpatialDesignSummaryYaml(robot, r, options, "test");
  EXPECT_NE(summary.find("robustness_lowered: "), std::string::npos) << summary;
  // And why the requested k gave none: the starts' failures there (helper-25: it was not said).
  EXPECT_NE(r.failure_at_requested.find("starts gave verified poses holding for true exit points "
                                        "within 3 x"),
            std::string::npos)
      << r.failure_at_requested;
  EXPECT_NE(summary.find("failure_at_requested_k: "), std::string::npos) << summary;
  // What was achieved holds: on true robots within the achieved k sigma, drawn at a third of it.
  std::string first;
  EXPECT_EQ(TrueRobotsThatCannotHoldThePlan(robot, r.poses, r.robust_sigmas_achieved, *robot.sensors.tracker_sigma_m, 20, &first),
            0)
      << first;
  options.lower_robustness = false;
  EXPECT_THROW(DesignSpatialPoses(robot, options), SolverFailure);
}


// A new user's 6-cable robot with only two cables stretching (an 8 kg platform, a tilted swivel
// axis, an offset centre of mass): 12 poses from one start end at a pose that is unstable with the
// stretch. Refused as before, and the message now says why such a plan fails and what may help.
TEST(SpatialDesign, AnUnstableOptimumIsSaidToBeTheStretchsNotTheSolvers) {
  const SpatialRobot robot = LoadSpatialRobotFromString(testing::SixMixedRobotYaml(), "six-mixed.yaml");
  SpatialDesignOptions options;
  options.poses = 12;
  options.starts = 1;
  options.random_sets = 0;
  options.geometry_sigma_m = 0.0;
  options.solve_in_child_processes = false;
  try {
    DesignSpatialPoses(robot, options);
    ADD_FAILURE() << "a plan was found: this test's robot no longer shows an unstable optimum";
  } catch (const SolverFailure& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("unstable"), std::string::npos) << what;
    EXPECT_NE(what.find("the stability of a pose is checked after the optimization"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace cablecal
