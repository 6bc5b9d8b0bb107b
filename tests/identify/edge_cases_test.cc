// Numerical edge cases (hardening): each ends in a clear error or a flagged result, never a
// silent wrong number.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "common/error.h"
#include "experiment/experiment.h"
#include "identify/identify.h"
#include "model/cable.h"
#include "model/statics.h"
#include "tests/support/temp_dir.h"
#include "workspace/workspace.h"

namespace cablecal {
namespace {

namespace fs = std::filesystem;

TEST(EdgeCases, AnchorInsideThePulleyIsInvalidGeometry) {
  const Eigen::Vector2d A(0.0, 2.8);
  const double r = 0.025;
  for (const Eigen::Vector2d& B : {Eigen::Vector2d(r, 2.8), Eigen::Vector2d(r + 0.5 * r, 2.8), Eigen::Vector2d(2 * r, 2.8)}) {
    EXPECT_FALSE(CableGeometryValid(CableGeometry<double>(A, r, PulleySigns{1.0, 1.0}, B), r)) << B.transpose();
  }
  // A platform pushed into the pulley (its left anchor on the pulley's centre): no
  // orientation balances it with valid cables.
  Robot robot = BuiltinRobot();
  robot.margin_m = 0.0;
  EXPECT_EQ(EvaluatePose(robot, r + 0.25, 2.8).feasibility, Feasibility::kNoEquilibrium);
  // A known pose with an anchor inside its pulley, or within the margin of it, is refused as
  // cable geometry whatever its tensions.
  const Eigen::Vector3d q(r + 0.25 + 0.01, 2.8, 0.0);  // anchor 1 at 10 mm from the centre
  EXPECT_EQ(CheckFeasibility(robot, q, Eigen::Vector2d(10.0, 10.0)), Feasibility::kCableGeometry);
  robot.margin_m = 0.05;
  const Eigen::Vector3d q2(r + 0.25 + 0.04, 2.7, 0.0);  // anchor 1 about 0.11 m from the centre
  robot.frame_height_m = 3.0;                             // keep the frame test out of the way
  EXPECT_EQ(CheckFeasibility(robot, q2, Eigen::Vector2d(10.0, 10.0)), Feasibility::kFeasible);
  robot.margin_m = 0.1;
  EXPECT_EQ(CheckFeasibility(robot, q2, Eigen::Vector2d(10.0, 10.0)), Feasibility::kCableGeometry);
}

TEST(EdgeCases, PosesOnTheWorkspaceBoundaryAreJudgedConsistently) {
  // Walk up from the centre until infeasible: the last feasible and first infeasible points
  // bracket the boundary, and the reason at the first infeasible one is a real bound.
  const Robot& robot = BuiltinRobot();
  double z = 1.4;
  PoseEvaluation last = EvaluatePose(robot, 2.6045, z);
  ASSERT_TRUE(last.feasible());
  while (z < 3.0) {
    const PoseEvaluation e = EvaluatePose(robot, 2.6045, z + 0.001);
    if (!e.feasible()) {
      EXPECT_EQ(e.feasibility, Feasibility::kTensionHigh) << "z = " << z;
      EXPECT_LE(last.equilibrium.tensions_N.maxCoeff(), robot.tension_max_N);
      EXPECT_GT(e.equilibrium.tensions_N.maxCoeff(), robot.tension_max_N);
      return;
    }
    last = e;
    z += 0.001;
  }
  FAIL() << "no upper boundary found";
}

TEST(EdgeCases, MeasurementsFarFromAnyReachablePoseAreFlagged) {
  std::vector<Measurement> m;
  for (int j = 1; j <= 8; ++j) {
    Measurement r;
    r.pose_id = j;
    r.dl_m = Eigen::Vector2d(5.0 * j, -7.0 * j);  // lengths no robot of this frame can have
    r.set(SensorId::kLaser, 0.1 * j);
    r.set(SensorId::kInclinometer, 0.05 * j);
    m.push_back(r);
  }
  for (const Estimator e : {Estimator::kMaximumLikelihood, Estimator::kPaper}) {
    IdentifyOptions options;
    options.estimator = e;
    const IdentifyResult r = Identify(BuiltinRobot(), m, options);
    EXPECT_NE(r.status, IdentifyStatus::kConverged) << ToString(e) << ": " << r.message;
  }
}

// Good readings shifted by 0.8 m in every encoder (a wrong zero, or another robot): the fit
// converges, but to initial lengths no robot of this file has, and is refused with the cause.
TEST(EdgeCases, ImplausibleIdentifiedGeometryIsRefusedWithTheLikelyCause) {
  const Robot& robot = BuiltinRobot();
  const auto plan = SampleFeasiblePoses(robot, 12, 4);
  Rng rng(2);
  SimulatedExperiment sim = SimulateExperiment(robot, robot, plan, SimulationOptions{}, rng);
  ASSERT_TRUE(Identify(robot, sim.measurements, IdentifyOptions{}).converged());
  for (Measurement& m : sim.measurements) m.dl_m.array() -= 0.8;
  const IdentifyResult r = Identify(robot, sim.measurements, IdentifyOptions{});
  EXPECT_EQ(r.status, IdentifyStatus::kPoorFit) << r.message;
  EXPECT_NE(r.message.find("more than 0.5 m from nominal"), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("units"), std::string::npos) << r.message;
}

TEST(EdgeCases, MillionRowCsvIsStreamedAndRejectedAtTheCap) {
  const testing_support::TempDir tmp;
  const fs::path path = tmp.Path("million.csv");
  {
    std::ofstream out(path);
    out << "pose,dl1,dl2,z,theta\n";
    for (int j = 1; j <= 1000000; ++j) out << j << ",0.01,-0.01,1.2,0.05\n";
  }
  try {
    ReadMeasurementsCsv(path.string(), 2);
    FAIL() << "10^6 rows accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), path.string() + ":" + std::to_string(kMaxMeasuredPoses + 2) +
                                         ": more than " + std::to_string(kMaxMeasuredPoses) + " readings");
  }
}

TEST(EdgeCases, RobotFileWithBomCrlfAndCommentsLoads) {
  // A byte-order mark, a comment, CRLF line ends and trailing blanks on every line.
  std::string yaml = "\xEF\xBB\xBF# exported on a lab PC\r\n";
  std::istringstream in(BuiltinRobotYaml());
  std::string line;
  while (std::getline(in, line)) yaml += line + "   \r\n";
  const Robot r = LoadRobotFromString(yaml, "crlf.yaml");
  EXPECT_EQ(RobotToYaml(r), RobotToYaml(BuiltinRobot()));
}

TEST(EdgeCases, PlanCsvNonFiniteNumbersAreRejectedWithLineAndColumn) {
  std::istringstream in("pose,x,z,theta,t1,t2,l1,l2,dl1,dl2\n1,2,1,0,10,10,2,2,0,0\n2,2,1,0,10,10,2,2,1e400,0\n");
  try {
    ReadPosePlanCsv(in, "plan.csv", 2);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), "plan.csv:3: column 'dl1': must be a finite number (got '1e400')");
  }
}

}  // namespace
}  // namespace cablecal

namespace cablecal {
namespace {

// A pose at the edge of a sensor's range reads past it by its noise: up to 5 sigma passes,
// more is refused (as is a reading on the wrong side of the laser's zero).
TEST(EdgeCases, ReadingsPastASensorRangeByItsNoiseOnlyAreAccepted) {
  const Robot& robot = BuiltinRobot();
  const double theta_sigma = robot.sensors.inclinometer_sigma_rad();
  const double z_sigma = robot.sensors.laser_sigma_m();
  const double z_top = std::min(robot.laser_range_m, robot.frame_height_m);
  Measurement m;
  m.pose_id = 1;
  m.dl_m = Eigen::VectorXd::Zero(2);
  const auto check = [&](double z, double theta) {
    m.set(SensorId::kLaser, z);
    m.set(SensorId::kInclinometer, theta);
    CheckReadingsPlausible(robot, {m}, "test");
  };
  EXPECT_NO_THROW(check(1.0, robot.theta_max_rad + 4.5 * theta_sigma));
  EXPECT_NO_THROW(check(1.0, -robot.theta_max_rad - 4.5 * theta_sigma));
  EXPECT_NO_THROW(check(-4.5 * z_sigma, 0.0));
  EXPECT_NO_THROW(check(z_top + 4.5 * z_sigma, 0.0));
  EXPECT_THROW(check(1.0, robot.theta_max_rad + 5.5 * theta_sigma), InputError);
  EXPECT_THROW(check(-5.5 * z_sigma, 0.0), InputError);
  EXPECT_THROW(check(z_top + 5.5 * z_sigma, 0.0), InputError);
  // Encoder length changes in millimetres: more than the frame's diagonal.
  m.dl_m << 1349.0, -12.0;
  try {
    check(1.0, 0.0);
    FAIL() << "a length change of 1349 m accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("column 'dl1': 1349 m is more than the frame's diagonal"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("millimetres?"), std::string::npos) << e.what();
  }
}

// The global fit test: every sensor 30 times noisier than the robot file says makes every
// residual too large (no single one stands out), which is poor_fit naming the factor.
TEST(EdgeCases, ResidualsFarAboveTheSensorsNoiseArePoorFit) {
  const Robot& robot = BuiltinRobot();
  const auto plan = SampleFeasiblePoses(robot, 30, 12);
  Rng rng(3);
  SimulatedExperiment exp = SimulateExperiment(robot, robot, plan, SimulationOptions{}, rng);
  const SensorNoise& s = robot.sensors;
  for (Measurement& m : exp.measurements) {
    for (int i = 0; i < m.dl_m.size(); ++i) m.dl_m(i) += rng.Normal(0.0, 30.0 * s.encoder_sigma_m);
    m.at(SensorId::kLaser) += rng.Normal(0.0, 30.0 * s.laser_sigma_m());
    m.at(SensorId::kInclinometer) += rng.Normal(0.0, 30.0 * s.inclinometer_sigma_rad());
  }
  const IdentifyResult r = Identify(robot, exp.measurements, IdentifyOptions{});
  EXPECT_EQ(r.status, IdentifyStatus::kPoorFit) << r.message;
  EXPECT_NE(r.message.find("times the sensors' noise"), std::string::npos) << r.message;
  // The same data with the noise the file states are a fit.
  Rng clean_rng(3);
  const SimulatedExperiment clean = SimulateExperiment(robot, robot, plan, SimulationOptions{}, clean_rng);
  EXPECT_EQ(Identify(robot, clean.measurements, IdentifyOptions{}).status, IdentifyStatus::kConverged);
}

}  // namespace
}  // namespace cablecal
