// The spatial stages below the CLI: the sensor readings against an independent construction
// (and with Jets), the plan and measurement CSVs (round trips, hostile files), sample's poses
// (feasible, consistent with the model, in the documented ranges, independent of the thread
// count), the workspace grid, and a noiseless simulation reading the model's values.
#include <ceres/jet.h>
#include <gtest/gtest.h>
#include <omp.h>

#include <Eigen/Geometry>
#include <cmath>
#include <functional>
#include <sstream>
#include <string>

#include "common/error.h"
#include "common/random.h"
#include "experiment/spatial_measurements.h"
#include "experiment/spatial_plan.h"
#include "experiment/spatial_simulation.h"
#include "model/builtin_spatial_robots.h"
#include "model/forward_statics.h"
#include "model/spatial_sensor_model.h"
#include "model/swivel.h"
#include "tests/support/random_spatial_robot.h"
#include "workspace/spatial_workspace.h"

namespace cablecal {
namespace {

// R = Rz(yaw) Ry(pitch) Rx(roll) from Eigen's axis-angle rotations, not model/swivel.h's.
Eigen::Matrix3d IndependentRotation(const SpatialPose<double>& q) {
  return (Eigen::AngleAxisd(q(5), Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(q(4), Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(q(3), Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

// The pulley plane's radial direction for anchor B: the part of B - D across the axis, unit.
Eigen::Vector3d IndependentU(const SpatialCable& c, const Eigen::Vector3d& B) {
  const Eigen::Vector3d rho = B - c.p_F_exit_m;
  const Eigen::Matrix3d across = Eigen::Matrix3d::Identity() - c.k_F_swivel_axis * c.k_F_swivel_axis.transpose();
  return (across * rho).normalized();
}

// The signed angle from a to b about k (both across k), by the law of cosines and the sign of
// the triple product.
double SignedAngle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& k) {
  const double angle = std::acos(std::clamp(a.dot(b), -1.0, 1.0));
  return k.dot(a.cross(b)) >= 0.0 ? angle : -angle;
}

// A random spatial robot with every sensor, stiff cables on all when m > 6 (simulatable).
SpatialRobot RobotWithEverySensor(std::uint64_t seed, int m) {
  Rng rng(seed);
  SpatialRobot r = testing::RandomSpatialRobot(rng, "random-" + std::to_string(m), m);
  const double deg = M_PI / 180.0;
  r.sensors.inclinometer_rad = RangedNoise{0.1 * deg, 0.05 * deg};
  r.sensors.laser_m = RangedNoise{0.006, 0.0015};
  r.sensors.position = SpatialSensors::Position{RangedNoise{3e-4, 1e-4}, Eigen::Vector3d(0.05, -0.03, 0.02)};
  r.sensors.swivel_rad = RangedNoise{0.1 * deg, 0.05 * deg};
  r.sensors.heading_rad = RangedNoise{1.0 * deg, 0.5 * deg};
  r.sensors.load_cell_N = RangedNoise{3.0, 1.0};
  if (m > 6) {
    for (SpatialCable& c : r.cables) c.stiffness_N = c.stiffness_N.value_or(2e6);
  }
  return LoadSpatialRobotFromString(SpatialRobotToYaml(r), r.name);
}

TEST(SpatialSensors, ReadingsMatchAnIndependentConstruction) {
  for (const int m : {3, 4, 6, 8}) {
    const SpatialRobot robot = RobotWithEverySensor(40 + m, m);
    Rng rng(7);
    const SpatialPose<double> home = robot.home_pose();
    const SpatialSensorZero zero = SensorZeroAt(robot, home);
    for (int trial = 0; trial < 20; ++trial) {
      SpatialPose<double> q = home;
      for (int k = 0; k < 3; ++k) q(k) += rng.Uniform(-0.2, 0.2);
      for (int k = 3; k < 6; ++k) q(k) += rng.Uniform(-0.2, 0.2);
      q(5) += trial == 0 ? 4.0 : 0.0;  // a yaw beyond pi from home: the heading wraps
      Eigen::VectorXd t(m);
      for (int i = 0; i < m; ++i) t(i) = rng.Uniform(10.0, 100.0);
      const auto read = SpatialSensorReadings<double>(robot, q, t, zero);
      const Eigen::Matrix3d R = IndependentRotation(q);
      const auto at = [&](SpatialSensor s) { return read[static_cast<int>(s)]; };
      EXPECT_EQ(at(SpatialSensor::kInclinometer)(0), q(3));
      EXPECT_EQ(at(SpatialSensor::kInclinometer)(1), q(4));
      EXPECT_NEAR(at(SpatialSensor::kLaser)(0), q(2) - robot.p_F_frame_min_m.z(), 1e-15);
      const Eigen::Vector3d target = q.head<3>() + R * robot.sensors.position->p_P_target_m;
      EXPECT_LT((at(SpatialSensor::kPosition) - target).norm(), 1e-14);
      const double dyaw = std::remainder(q(5) - home(5), 2.0 * M_PI);
      EXPECT_NEAR(at(SpatialSensor::kHeading)(0), dyaw, 1e-12);
      EXPECT_LE(std::abs(at(SpatialSensor::kHeading)(0)), M_PI);
      const Eigen::Matrix3d R_home = IndependentRotation(home);
      for (int i = 0; i < m; ++i) {
        const SpatialCable& c = robot.cables[i];
        const Eigen::Vector3d u0 = IndependentU(c, home.head<3>() + R_home * c.p_P_anchor_m);
        const Eigen::Vector3d u = IndependentU(c, q.head<3>() + R * c.p_P_anchor_m);
        EXPECT_NEAR(at(SpatialSensor::kSwivel)(i), SignedAngle(u0, u, c.k_F_swivel_axis), 1e-7) << "cable " << i;
      }
      EXPECT_EQ(at(SpatialSensor::kLoadCell), t);
    }
  }
}

// Written once on the scalar: with Jets the values are the doubles' and the derivatives those
// of the construction (laser dz = 1, heading dyaw = 1, inclinometer the identity).
TEST(SpatialSensors, JetsCarryTheReadingsAndTheirDerivatives) {
  using J = ceres::Jet<double, 6>;
  const SpatialRobot robot = RobotWithEverySensor(46, 6);
  const SpatialPose<double> q = robot.home_pose() + (SpatialPose<double>() << 0.1, -0.05, 0.08, 0.05, -0.04, 0.2).finished();
  SpatialPose<J> qj;
  for (int k = 0; k < 6; ++k) qj(k) = J(q(k), k);
  const Eigen::VectorXd t = Eigen::VectorXd::Constant(6, 50.0);
  const SpatialSensorZero zero = SensorZeroAt(robot, robot.home_pose());
  const auto d = SpatialSensorReadings<double>(robot, q, t, zero);
  const auto j = SpatialSensorReadings<J>(robot, qj, t.cast<J>(), zero);
  for (int s = 0; s < kNumSpatialSensors; ++s) {
    for (Eigen::Index k = 0; k < d[s].size(); ++k) EXPECT_NEAR(j[s](k).a, d[s](k), 1e-14) << s << " " << k;
  }
  EXPECT_EQ(j[static_cast<int>(SpatialSensor::kLaser)](0).v(2), 1.0);
  EXPECT_NEAR(j[static_cast<int>(SpatialSensor::kHeading)](0).v(5), 1.0, 1e-12);
  EXPECT_EQ(j[static_cast<int>(SpatialSensor::kInclinometer)](0).v(3), 1.0);
  EXPECT_EQ(j[static_cast<int>(SpatialSensor::kInclinometer)](1).v(4), 1.0);
  // The position's derivative along x is the unit x.
  EXPECT_EQ(j[static_cast<int>(SpatialSensor::kPosition)](0).v(0), 1.0);
  // A swivel angle's derivative by a finite difference of the doubles.
  const double h = 1e-7;
  for (int k = 0; k < 6; ++k) {
    SpatialPose<double> qh = q;
    qh(k) += h;
    const auto dh = SpatialSensorReadings<double>(robot, qh, t, zero);
    for (int i = 0; i < 6; ++i) {
      const double fd = (dh[static_cast<int>(SpatialSensor::kSwivel)](i) - d[static_cast<int>(SpatialSensor::kSwivel)](i)) / h;
      EXPECT_NEAR(j[static_cast<int>(SpatialSensor::kSwivel)](i).v(k), fd, 1e-5) << "cable " << i << " coordinate " << k;
    }
  }
}

std::vector<SpatialRobot> TestRobots() {
  std::vector<SpatialRobot> robots;
  for (const std::string& name : BuiltinSpatialRobotNames()) robots.push_back(BuiltinSpatialRobot(name));
  robots.push_back(RobotWithEverySensor(11, 8));
  robots.push_back(RobotWithEverySensor(12, 6));
  robots.push_back(RobotWithEverySensor(13, 4));
  return robots;
}

TEST(SpatialSample, EveryPoseIsFeasibleInItsRangesAndItsRowIsTheModels) {
  for (const SpatialRobot& robot : TestRobots()) {
    SCOPED_TRACE(robot.name);
    const double yaw_range = 20.0 * M_PI / 180.0;
    std::vector<SpatialPlanPose> plan;
    try {
      plan = SampleSpatialPoses(robot, 12, 5, yaw_range);
    } catch (const SolverFailure& e) {
      ADD_FAILURE() << e.what();
      continue;
    }
    ASSERT_EQ(plan.size(), 12u);
    const SpatialHomeReference home = SpatialHome(robot);
    const std::vector<int> controlled = ControlledCoordinates(robot);
    const double weight = robot.platform_mass_kg * robot.gravity_mps2;
    for (const SpatialPlanPose& p : plan) {
      const SpatialPoseEvaluation e = EvaluateSpatialPose(robot, p.q);
      EXPECT_TRUE(e.feasible()) << ToString(e.feasibility);
      // In the box shrunk by the margin, the tilt limit, the yaw range (the controlled entries).
      for (int a = 0; a < 3; ++a) {
        EXPECT_GE(p.q(a), robot.p_F_frame_min_m(a) + robot.margin_m);
        EXPECT_LE(p.q(a), robot.p_F_frame_max_m(a) - robot.margin_m);
      }
      EXPECT_LE(TiltAngle(p.q), robot.tilt_max_rad + 1e-12);
      if (std::find(controlled.begin(), controlled.end(), 5) != controlled.end()) {
        EXPECT_LE(std::abs(p.q(5) - robot.home_rpy_rad(2)), yaw_range);
      }
      // The row: an equilibrium, within the tension limits, the model's lengths, the paid-out change.
      EXPECT_LT(EquilibriumResidual<double>(robot, p.q, p.tensions_N).norm(), 1e-6 * weight);
      EXPECT_GE(p.tensions_N.minCoeff(), robot.tension_min_N - 1e-9);
      EXPECT_LE(p.tensions_N.maxCoeff(), robot.tension_max_N + 1e-9);
      const Eigen::Matrix3d R = IndependentRotation(p.q);
      for (int i = 0; i < robot.num_cables(); ++i) {
        const SpatialCable& c = robot.cables[i];
        const double l = SwivelCable<double>(c.p_F_exit_m, c.k_F_swivel_axis, c.pulley_radius_m,
                                             p.q.head<3>() + R * c.p_P_anchor_m)
                             .length_m;
        EXPECT_NEAR(p.lengths_m(i), l, 1e-12);
        const double paid_out = c.stiffness_N ? l / (1.0 + p.tensions_N(i) / *c.stiffness_N) : l;
        EXPECT_NEAR(p.length_change_m(i), paid_out - home.paid_out_m(i), 1e-12);
      }
    }
    EXPECT_NO_THROW(CheckSpatialPlanMatchesRobot(robot, plan, "plan"));
  }
}

TEST(SpatialSample, TheSameForAnyThreadCount) {
  for (const SpatialRobot& robot : {BuiltinSpatialRobot("irma4u"), RobotWithEverySensor(12, 6)}) {
    const int n = robot.num_cables() < 6 ? 5 : 20;  // an underactuated pose costs an equilibrium solve
    omp_set_num_threads(1);
    const std::string one = SpatialPlanCsv(SampleSpatialPoses(robot, n, 9), "");
    omp_set_num_threads(2);
    const std::string two = SpatialPlanCsv(SampleSpatialPoses(robot, n, 9), "");
    EXPECT_EQ(one, two);
    EXPECT_NE(one, SpatialPlanCsv(SampleSpatialPoses(robot, n, 10), ""));  // the seed matters
  }
}

TEST(SpatialSample, RefusesBadArgumentsAndAnEmptyWorkspace) {
  const SpatialRobot robot = BuiltinSpatialRobot("ipanema1");
  EXPECT_THROW(SampleSpatialPoses(robot, 0, 1), InputError);
  EXPECT_THROW(SampleSpatialPoses(robot, 3, 1, 0.0), InputError);
  EXPECT_THROW(SampleSpatialPoses(robot, 3, 1, 4.0), InputError);
  SpatialRobot heavy = robot;
  heavy.platform_mass_kg = 1e4;  // no tension within the limits holds it anywhere
  EXPECT_THROW(SampleSpatialPoses(heavy, 1, 1), SolverFailure);
}

TEST(SpatialPlanCsv, RoundTripsBitForBit) {
  const SpatialRobot robot = RobotWithEverySensor(11, 8);
  const std::vector<SpatialPlanPose> plan = SampleSpatialPoses(robot, 6, 3);
  const std::string csv = SpatialPlanCsv(plan, "# provenance\n");
  EXPECT_EQ(csv.substr(0, csv.find('\n', 14) + 1),
            "# provenance\npose,x,y,z,roll,pitch,yaw,t1,t2,t3,t4,t5,t6,t7,t8,l1,l2,l3,l4,l5,l6,l7,l8,dl1,dl2,dl3,dl4,dl5,"
            "dl6,dl7,dl8\n");
  std::istringstream in(csv);
  const std::vector<SpatialPlanPose> back = ReadSpatialPlanCsv(in, "plan.csv", 8);
  ASSERT_EQ(back.size(), plan.size());
  for (std::size_t j = 0; j < plan.size(); ++j) {
    EXPECT_EQ(back[j].q, plan[j].q);
    EXPECT_EQ(back[j].tensions_N, plan[j].tensions_N);
    EXPECT_EQ(back[j].lengths_m, plan[j].lengths_m);
    EXPECT_EQ(back[j].length_change_m, plan[j].length_change_m);
  }
  EXPECT_EQ(SpatialPlanCsv(back, "# provenance\n"), csv);
}

// The message of the InputError `read` throws.
template <typename F>
std::string ErrorOf(F read) {
  try {
    read();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(SpatialPlanCsv, HostileFilesAreNamedByFileLineAndColumn) {
  const SpatialRobot robot = BuiltinSpatialRobot("irma4u");
  const std::vector<SpatialPlanPose> plan = SampleSpatialPoses(robot, 3, 3);
  const std::string csv = SpatialPlanCsv(plan, "# a comment\n");
  const auto read = [](const std::string& text, int m) {
    std::istringstream in(text);
    return ReadSpatialPlanCsv(in, "p.csv", m);
  };
  // Another cable count; a planar plan.
  EXPECT_NE(ErrorOf([&] { read(csv, 8); }).find("p.csv:2: header"), std::string::npos) << ErrorOf([&] { read(csv, 8); });
  EXPECT_NE(ErrorOf([&] { read("pose,x,z,theta,t1,t2,l1,l2,dl1,dl2\n1,1,1,0,1,1,1,1,0,0\n", 2); }).find("p.csv:1: header"),
            std::string::npos);
  // A bad number at its line and column; a duplicate id.
  std::string bad = csv;
  const std::size_t row3 = bad.find("\n2,") + 1;
  bad.replace(bad.find(',', row3) + 1, 0, "x");
  EXPECT_NE(ErrorOf([&] { read(bad, 4); }).find("p.csv:4: column 'x'"), std::string::npos) << ErrorOf([&] { read(bad, 4); });
  std::string dup = csv;
  dup.replace(row3, 1, "1");
  EXPECT_NE(ErrorOf([&] { read(dup, 4); }).find("p.csv:4: column 'pose': duplicate pose id 1"), std::string::npos);
  // Read fine, but not this robot's plan: the pose and the column named.
  const auto check = [&](std::vector<SpatialPlanPose> edited) {
    return ErrorOf([&] { CheckSpatialPlanMatchesRobot(robot, edited, "p.csv"); });
  };
  std::vector<SpatialPlanPose> e = plan;
  e[1].q(1) = 50.0;
  EXPECT_NE(check(e).find("p.csv: pose 2: column 'y'"), std::string::npos) << check(e);
  e = plan;
  e[2].lengths_m(3) += 1e-4;
  EXPECT_NE(check(e).find("p.csv: pose 3: column 'l4'"), std::string::npos) << check(e);
  e = plan;
  e[0].length_change_m(1) += 1e-4;
  EXPECT_NE(check(e).find("p.csv: pose 1: column 'dl2'"), std::string::npos) << check(e);
  e = plan;
  e[0].tensions_N(0) += 5.0;
  EXPECT_NE(check(e).find("not a static equilibrium"), std::string::npos) << check(e);
  e = plan;
  e[1].tensions_N(2) = -5.0;  // a sign lost in editing: named as the tension it is
  EXPECT_NE(check(e).find("p.csv: pose 2: column 't3': -5 N is a negative tension"), std::string::npos) << check(e);
  e = plan;
  e[0].q(3) = 0.9;  // 52 degrees of roll
  EXPECT_NE(check(e).find("p.csv: pose 1: columns 'roll,pitch'"), std::string::npos) << check(e);
  e = plan;
  e[0].q(5) = 30.0;  // degrees typed for radians
  EXPECT_NE(check(e).find("column 'yaw'"), std::string::npos) << check(e);
}

SpatialMeasurement SomeReading(int id, int m, bool all_sensors) {
  SpatialMeasurement r;
  r.pose_id = id;
  r.dl_m = Eigen::VectorXd::LinSpaced(m, -0.1 * id, 0.2);
  for (const SpatialSensor s : kSpatialSensors) {
    if (!all_sensors && s != SpatialSensor::kLaser && s != SpatialSensor::kSwivel) continue;
    r.values(s) = Eigen::VectorXd::LinSpaced(SpatialSensorSize(s, m), 0.01 * id + static_cast<int>(s), 1.0 / 3.0);
  }
  return r;
}

TEST(SpatialMeasurementsCsv, RoundTripsAndReadsColumnsInAnyOrder) {
  for (const bool all : {true, false}) {
    const std::vector<SpatialMeasurement> readings = {SomeReading(1, 4, all), SomeReading(2, 4, all),
                                                      SomeReading(2, 4, all)};
    const std::string csv = SpatialMeasurementsCsv(readings, "# p\n");
    EXPECT_NE(csv.find(all ? "pose,dl1,dl2,dl3,dl4,roll,pitch,z,px,py,pz,sw1,sw2,sw3,sw4,yaw,f1,f2,f3,f4\n"
                           : "pose,dl1,dl2,dl3,dl4,z,sw1,sw2,sw3,sw4\n"),
              std::string::npos)
        << csv;
    std::istringstream in(csv);
    const std::vector<SpatialMeasurement> back = ReadSpatialMeasurementsCsv(in, "m.csv", 4);
    ASSERT_EQ(back.size(), readings.size());
    for (std::size_t j = 0; j < back.size(); ++j) {
      EXPECT_EQ(back[j].pose_id, readings[j].pose_id);
      EXPECT_EQ(back[j].dl_m, readings[j].dl_m);
      for (const SpatialSensor s : kSpatialSensors) EXPECT_EQ(back[j].values(s), readings[j].values(s));
    }
  }
  // Reordered columns, semicolons.
  std::istringstream in("sw2;z;pose;dl2;sw1;dl1;dl3;sw3\n0.5;1.25;7;0.1;-0.5;0.2;0.3;0.25\n");
  const std::vector<SpatialMeasurement> r = ReadSpatialMeasurementsCsv(in, "m.csv", 3, ';');
  ASSERT_EQ(r.size(), 1u);
  EXPECT_EQ(r[0].pose_id, 7);
  EXPECT_EQ(r[0].dl_m, Eigen::Vector3d(0.2, 0.1, 0.3));
  EXPECT_EQ(r[0].values(SpatialSensor::kLaser), Eigen::VectorXd::Constant(1, 1.25));
  EXPECT_EQ(r[0].values(SpatialSensor::kSwivel), Eigen::Vector3d(-0.5, 0.5, 0.25));
  EXPECT_FALSE(r[0].has(SpatialSensor::kInclinometer));
}

TEST(SpatialMeasurementsCsv, HostileFilesAreNamedByFileLineAndColumn) {
  const auto read = [](const std::string& text) {
    return ErrorOf([&] {
      std::istringstream in(text);
      ReadSpatialMeasurementsCsv(in, "m.csv", 3);
    });
  };
  EXPECT_NE(read("# c\npose,dl1,dl2,dl3,theta\n1,0,0,0,0\n").find("m.csv:2: column 'theta': unknown column"),
            std::string::npos)
      << read("# c\npose,dl1,dl2,dl3,theta\n1,0,0,0,0\n");
  // A lab log's extra column, and a pose plan given as readings: each told what it is.
  EXPECT_NE(read("pose,dl1,dl2,dl3,temp\n1,0,0,0,21\n").find("remove any other, a timestamp or a temperature"),
            std::string::npos);
  const std::string plan =
      read("pose,x,y,z,roll,pitch,yaw,t1,t2,t3,l1,l2,l3,dl1,dl2,dl3\n1,0,0,1,0,0,0,1,1,1,1,1,1,0,0,0\n");
  EXPECT_NE(plan.find("m.csv:1: column 'x': unknown column"), std::string::npos) << plan;
  EXPECT_NE(plan.find("this looks like a pose plan"), std::string::npos) << plan;
  // A byte-order mark before the header below comment lines is read as Excel's at the start is.
  std::istringstream bom("# c\n\xEF\xBB\xBFpose,dl1,dl2,dl3\n4,0.1,0.2,0.3\n");
  EXPECT_EQ(ReadSpatialMeasurementsCsv(bom, "m.csv", 3).at(0).pose_id, 4);
  EXPECT_NE(read("pose,dl1,dl2,dl3,roll\n1,0,0,0,0\n").find("m.csv:1: column 'pitch': missing: the inclinometer"),
            std::string::npos)
      << read("pose,dl1,dl2,dl3,roll\n1,0,0,0,0\n");
  EXPECT_NE(read("pose,dl1,dl2,dl3,px,py\n1,0,0,0,0,0\n").find("column 'pz'"), std::string::npos);
  EXPECT_NE(read("pose,dl1,dl2,dl3,z\n1,0,0,0,0\n2,0,0,0,nan\n").find("m.csv:3: column 'z'"), std::string::npos)
      << read("pose,dl1,dl2,dl3,z\n1,0,0,0,0\n2,0,0,0,nan\n");
  EXPECT_NE(read("pose,dl1,dl2\n1,0,0\n").find("m.csv:1"), std::string::npos) << read("pose,dl1,dl2\n1,0,0\n");
  EXPECT_NE(read("pose,dl1,dl2,dl3\n0,0,0,0\n").find("m.csv:2: column 'pose'"), std::string::npos);
  // A column given twice is named as such, not taken for another robot's cable count.
  const std::string twice = read("pose,dl1,dl1,dl2,dl3\n1,0,0,0,0\n");
  EXPECT_NE(twice.find("m.csv:1: header: column 'dl1' appears 2 times"), std::string::npos) << twice;
  EXPECT_EQ(twice.find("cables"), std::string::npos) << twice;
  EXPECT_NE(read("pose,dl1,dl2,dl3,dl4\n1,0,0,0,0\n").find("the file has columns for 4 cables, the robot has 3"),
            std::string::npos);
  // A cable's column dropped in between is named; the last cables' missing reads as another robot's.
  const std::string dropped = read("pose,dl1,dl3\n1,0,0\n");
  EXPECT_NE(dropped.find("the file has columns for 2 cables, the robot has 3 ('dl2' missing): a column dropped"),
            std::string::npos)
      << dropped;
  const std::string fewer = read("pose,dl1,dl2\n1,0,0\n");
  EXPECT_NE(fewer.find("the robot has 3: a file for another robot?"), std::string::npos) << fewer;
}

TEST(SpatialWorkspace, GridPointsAreTheEvaluationsAndTheThreadCountChangesNothing) {
  for (const SpatialRobot& robot : {BuiltinSpatialRobot("irma4u"), RobotWithEverySensor(12, 6)}) {
    SCOPED_TRACE(robot.name);
    const double step = 0.25 * (robot.p_F_frame_max_m - robot.p_F_frame_min_m).minCoeff();
    const Eigen::Vector3d rpy(0.02, -0.03, 0.1);
    omp_set_num_threads(1);
    const SpatialWorkspaceGrid one = ComputeSpatialWorkspace(robot, rpy, step);
    omp_set_num_threads(2);
    const SpatialWorkspaceGrid two = ComputeSpatialWorkspace(robot, rpy, step);
    EXPECT_EQ(SpatialWorkspaceCsv(robot, one, ""), SpatialWorkspaceCsv(robot, two, ""));
    ASSERT_EQ(static_cast<long>(one.points.size()), static_cast<long>(one.counts.prod()));
    // The grid starts at frame.min, to the picometre its coordinates are rounded to.
    EXPECT_LT((one.points.front().p_F_m - robot.p_F_frame_min_m).cwiseAbs().maxCoeff(), 1e-12);
    const std::vector<int> controlled = ControlledCoordinates(robot);
    for (std::size_t k = 0; k < one.points.size(); k += 7) {
      const SpatialWorkspacePoint& p = one.points[k];
      SpatialPose<double> q;
      q << p.p_F_m, rpy;
      const SpatialPoseEvaluation e = EvaluateSpatialPose(robot, q);
      EXPECT_EQ(p.evaluation.feasibility, e.feasibility);
      if (!e.has_equilibrium) continue;
      for (const int c : controlled) EXPECT_NEAR(p.evaluation.equilibrium.q(c), q(c), 1e-9) << c;
    }
  }
  EXPECT_THROW(ComputeSpatialWorkspace(BuiltinSpatialRobot("cogiro"), Eigen::Vector3d::Zero(), 0.01), InputError);
  EXPECT_THROW(ComputeSpatialWorkspace(BuiltinSpatialRobot("cogiro"), Eigen::Vector3d::Zero(), 3.0), InputError);
  EXPECT_EQ(DefaultSpatialStep(BuiltinSpatialRobot("cogiro")), 0.5);
  EXPECT_NEAR(DefaultSpatialStep(BuiltinSpatialRobot("ipanema1")), 0.1, 1e-15);
}

// Zero noise, zero geometry error: every reading is the model's value at the plan's pose,
// computed here from the plan row (not through the simulation's code path).
TEST(SpatialSimulation, NoiselessReadingsAreTheModelsValues) {
  for (const SpatialRobot& robot : TestRobots()) {
    SCOPED_TRACE(robot.name);
    if (robot.num_cables() > 6 && std::any_of(robot.cables.begin(), robot.cables.end(),
                                              [](const SpatialCable& c) { return !c.stiffness_N; })) {
      continue;  // not simulatable (CheckSimulatable)
    }
    const std::vector<SpatialPlanPose> plan = SampleSpatialPoses(robot, 5, 21);
    SpatialSimulationOptions options;
    options.noisy = NoisySensors::kNone;
    options.encoder_noise = false;
    const SpatialPlanSimulation run = SimulateSpatialPlan(robot, std::nullopt, 0.0, plan, options, 1, "plan");
    ASSERT_EQ(run.experiment.measurements.size(), plan.size());
    const SpatialPose<double> home = SpatialHome(robot).equilibrium.q;
    const Eigen::Matrix3d R_home = IndependentRotation(home);
    const double force_tol = 1e-6 * robot.platform_mass_kg * robot.gravity_mps2;
    for (std::size_t j = 0; j < plan.size(); ++j) {
      const SpatialPlanPose& p = plan[j];
      const SpatialMeasurement& r = run.experiment.measurements[j];
      EXPECT_EQ(r.dl_m, p.length_change_m);
      const Eigen::Matrix3d R = IndependentRotation(p.q);
      const auto expect = [&](SpatialSensor s, const Eigen::VectorXd& model, double tol) {
        if (!HasSpatialSensor(robot, s)) {
          EXPECT_FALSE(r.has(s)) << ToString(s);
          return;
        }
        ASSERT_TRUE(r.has(s)) << ToString(s);
        EXPECT_LT((r.values(s) - model).lpNorm<Eigen::Infinity>(), tol) << ToString(s) << "\n" << r.values(s).transpose()
                                                                       << "\n" << model.transpose();
      };
      expect(SpatialSensor::kInclinometer, p.q.segment<2>(3), 1e-7);
      expect(SpatialSensor::kLaser, Eigen::VectorXd::Constant(1, p.q(2) - robot.p_F_frame_min_m.z()), 1e-7);
      if (robot.sensors.position) {
        expect(SpatialSensor::kPosition, p.q.head<3>() + R * robot.sensors.position->p_P_target_m, 1e-7);
      }
      expect(SpatialSensor::kHeading, Eigen::VectorXd::Constant(1, std::remainder(p.q(5) - home(5), 2 * M_PI)), 1e-7);
      Eigen::VectorXd swivel(robot.num_cables());
      for (int i = 0; i < robot.num_cables(); ++i) {
        const SpatialCable& c = robot.cables[i];
        swivel(i) = SignedAngle(IndependentU(c, home.head<3>() + R_home * c.p_P_anchor_m),
                                IndependentU(c, p.q.head<3>() + R * c.p_P_anchor_m), c.k_F_swivel_axis);
      }
      expect(SpatialSensor::kSwivel, swivel, 1e-6);
      expect(SpatialSensor::kLoadCell, p.tensions_N, force_tol);
      EXPECT_LT((run.experiment.true_poses[j] - p.q).norm(), 1e-7);
    }
  }
}

// The readings at a robot's own plan without a forward solve (the design's gauge analysis):
// those the noise-free simulation gives (checked above against an independent construction),
// and where the robot cannot be simulated (more than 6 inextensible cables) still the model's:
// the encoders the plan's dl, the inclinometer and laser the pose's.
TEST(SpatialSimulation, PlannedReadingsAreTheNoiseFreeSimulationsWithoutAForwardSolve) {
  int unsimulatable = 0;
  std::vector<SpatialRobot> robots = TestRobots();
  SpatialRobot rigid = BuiltinSpatialRobot("cogiro");  // 8 cables, taken as inextensible
  rigid.name = "cogiro-rigid";
  for (SpatialCable& c : rigid.cables) c.stiffness_N.reset();
  robots.push_back(rigid);
  for (const SpatialRobot& robot : robots) {
    SCOPED_TRACE(robot.name);
    const std::vector<SpatialPlanPose> plan = SampleSpatialPoses(robot, 5, 22);
    const std::vector<SpatialMeasurement> planned = PlannedSpatialReadings(robot, plan);
    ASSERT_EQ(planned.size(), plan.size());
    const bool simulatable = robot.num_cables() <= 6 || std::all_of(robot.cables.begin(), robot.cables.end(),
                                                                    [](const SpatialCable& c) { return c.stiffness_N; });
    if (!simulatable) {
      ++unsimulatable;
      for (std::size_t j = 0; j < plan.size(); ++j) {
        EXPECT_EQ(planned[j].dl_m, plan[j].length_change_m);
        if (HasSpatialSensor(robot, SpatialSensor::kInclinometer)) {
          EXPECT_LT((planned[j].values(SpatialSensor::kInclinometer) - plan[j].q.segment<2>(3)).norm(), 1e-12);
        }
        if (HasSpatialSensor(robot, SpatialSensor::kLaser)) {
          EXPECT_NEAR(planned[j].values(SpatialSensor::kLaser)(0), plan[j].q(2) - robot.p_F_frame_min_m.z(), 1e-12);
        }
      }
      continue;
    }
    SpatialSimulationOptions options;
    options.noisy = NoisySensors::kNone;
    options.encoder_noise = false;
    const SpatialPlanSimulation run = SimulateSpatialPlan(robot, std::nullopt, 0.0, plan, options, 1, "plan");
    for (std::size_t j = 0; j < plan.size(); ++j) {
      const SpatialMeasurement &a = planned[j], &b = run.experiment.measurements[j];
      EXPECT_EQ(a.pose_id, b.pose_id);
      EXPECT_EQ(a.dl_m, b.dl_m);
      for (const SpatialSensor sensor : kSpatialSensors) {
        ASSERT_EQ(a.has(sensor), b.has(sensor)) << ToString(sensor);
        if (!a.has(sensor)) continue;
        // The load cells in newtons, the rest in m and rad: the forward solve's tolerance.
        const double tol = sensor == SpatialSensor::kLoadCell ? 1e-6 * robot.platform_mass_kg * robot.gravity_mps2 : 1e-6;
        EXPECT_LT((a.values(sensor) - b.values(sensor)).lpNorm<Eigen::Infinity>(), tol) << ToString(sensor) << " pose " << j;
      }
    }
  }
  EXPECT_GT(unsimulatable, 0) << "no robot of more than 6 inextensible cables among the test robots";
}

TEST(SpatialSimulation, NoiseIsReproducibleAndTheStreamIgnoresWhichSensorsAreNoisy) {
  const SpatialRobot robot = RobotWithEverySensor(12, 6);
  const std::vector<SpatialPlanPose> plan = SampleSpatialPoses(robot, 4, 2);
  // Stiff cables turn a 0.1 mm exit error into tens of newtons: the poses the true robot holds
  // within its tension limits are kept, the same ones whatever the sensors' noise.
  SpatialSimulationOptions all, laser;
  all.skip_infeasible = laser.skip_infeasible = true;
  laser.noisy = NoisySensors::kLaser;
  const auto run = [&](const SpatialSimulationOptions& o, double sigma, std::uint64_t seed) {
    return SimulateSpatialPlan(robot, std::nullopt, sigma, plan, o, seed, "plan");
  };
  const double sigma = 1e-4;
  const SpatialPlanSimulation a = run(all, sigma, 3), b = run(all, sigma, 3), c = run(laser, sigma, 3);
  ASSERT_FALSE(a.experiment.measurements.empty());
  ASSERT_EQ(a.experiment.measurements.size(), c.experiment.measurements.size());
  EXPECT_EQ(SpatialMeasurementsCsv(a.experiment.measurements, ""), SpatialMeasurementsCsv(b.experiment.measurements, ""));
  EXPECT_EQ(SpatialRobotToYaml(a.truth), SpatialRobotToYaml(c.truth));
  for (std::size_t j = 0; j < a.experiment.measurements.size(); ++j) {
    // Same draws: the laser reads the same noisy value with or without the others' noise.
    EXPECT_EQ(a.experiment.measurements[j].values(SpatialSensor::kLaser),
              c.experiment.measurements[j].values(SpatialSensor::kLaser));
    EXPECT_NE(a.experiment.measurements[j].values(SpatialSensor::kHeading),
              c.experiment.measurements[j].values(SpatialSensor::kHeading));
  }
  // The truth: every exit coordinate moved (none held), by about sigma.
  int moved = 0;
  for (int i = 0; i < robot.num_cables(); ++i) {
    const Eigen::Vector3d d = a.truth.cables[i].p_F_exit_m - robot.cables[i].p_F_exit_m;
    moved += (d.array() != 0.0).count();
    EXPECT_LT(d.norm(), 5 * sigma * std::sqrt(3.0));
  }
  EXPECT_EQ(moved, 3 * robot.num_cables());
  // The truth file loads back as the true robot, with its true_poses.
  const std::string truth = SpatialTruthYaml(a.truth, a.experiment);
  EXPECT_NE(truth.find("true_poses:"), std::string::npos);
  EXPECT_EQ(SpatialRobotToYaml(LoadSpatialRobotFromString(truth, "truth.yaml")), SpatialRobotToYaml(a.truth));
}

// Readings in the wrong unit are refused before any fit, naming the reading, the column and the
// likely mistake; readings the robot's sensors give (simulated with noise) pass.
TEST(SpatialMeasurementsCheck, ReadingsNoSensorCanGiveAreRefusedNamingTheUnit) {
  const SpatialRobot robot = RobotWithEverySensor(14, 7);
  const std::vector<SpatialPlanPose> plan = SampleSpatialPoses(robot, 6, 3);
  SpatialSimulationOptions lab;
  lab.skip_infeasible = true;
  const SpatialPlanSimulation sim = SimulateSpatialPlan(robot, std::nullopt, 0.0, plan, lab, 5, "plan");
  const std::vector<SpatialMeasurement>& clean = sim.experiment.measurements;
  ASSERT_FALSE(clean.empty());
  EXPECT_NO_THROW(CheckSpatialReadingsPlausible(robot, clean, "meas.csv"));
  const auto message = [&](const std::function<void(SpatialMeasurement&)>& spoil) {
    std::vector<SpatialMeasurement> bad = clean;
    spoil(bad.back());
    try {
      CheckSpatialReadingsPlausible(robot, bad, "meas.csv");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  const std::string pose = "meas.csv: pose " + std::to_string(clean.back().pose_id);
  const std::vector<std::pair<std::function<void(SpatialMeasurement&)>, std::string>> cases = {
      {[](SpatialMeasurement& r) { r.dl_m *= 1000.0; }, "column 'dl"},
      {[](SpatialMeasurement& r) { r.values(SpatialSensor::kLaser) *= 1000.0; }, "column 'z'"},
      {[](SpatialMeasurement& r) { r.values(SpatialSensor::kInclinometer)(1) = 20.0; }, "column 'pitch'"},
      {[](SpatialMeasurement& r) { r.values(SpatialSensor::kPosition)(2) *= 1000.0; }, "column 'pz'"},
      {[](SpatialMeasurement& r) { r.values(SpatialSensor::kHeading)(0) = 90.0; }, "column 'yaw'"},
      {[](SpatialMeasurement& r) { r.values(SpatialSensor::kSwivel)(1) = 45.0; }, "column 'sw2'"},
      {[](SpatialMeasurement& r) { r.values(SpatialSensor::kLoadCell)(2) = -50.0; }, "column 'f3'"},
      {[&robot](SpatialMeasurement& r) { r.values(SpatialSensor::kLoadCell)(1) = 1000.0 * robot.tension_max_N; },
       "column 'f2'"}};
  for (const auto& [spoil, column] : cases) {
    const std::string m = message(spoil);
    EXPECT_NE(m.find(pose), std::string::npos) << m;
    EXPECT_NE(m.find(column), std::string::npos) << m;
    EXPECT_TRUE(m.find("millimetres?") != std::string::npos || m.find("degrees?") != std::string::npos ||
                m.find("sign reversed?") != std::string::npos || m.find("units? forces are in N") != std::string::npos)
        << m;
  }
  // Two poses under one id: named by the later row, the earlier one and the cable most apart;
  // a repeated reading of one pose (the same lengths, within the encoders' noise) passes.
  {
    std::vector<SpatialMeasurement> twice = clean;
    twice.back().pose_id = twice.front().pose_id;
    std::string m = "accepted";
    try {
      CheckSpatialReadingsPlausible(robot, twice, "meas.csv");
    } catch (const InputError& e) {
      m = e.what();
    }
    EXPECT_NE(m.find("was read before"), std::string::npos) << m;
    EXPECT_NE(m.find("two poses under one id?"), std::string::npos) << m;
    twice.back() = twice.front();
    twice.back().dl_m.array() += 3.0 * robot.sensors.encoder_sigma_m;
    EXPECT_NO_THROW(CheckSpatialReadingsPlausible(robot, twice, "meas.csv"));
    // The other sensors too (a new user's px 5 cm apart under one id reached the solver): each
    // named by its column; each within 3 sigma of the first passes.
    for (const auto& [sensor, column] : std::vector<std::pair<SpatialSensor, std::string>>{
             {SpatialSensor::kPosition, "px"}, {SpatialSensor::kInclinometer, "roll"}, {SpatialSensor::kLoadCell, "f1"}}) {
      const double sigma = SpatialSensorNoise(robot.sensors, sensor)->sigma();
      twice.back() = twice.front();
      twice.back().values(sensor)(0) += 20.0 * sigma;
      m = "accepted";
      try {
        CheckSpatialReadingsPlausible(robot, twice, "meas.csv");
      } catch (const InputError& e) {
        m = e.what();
      }
      EXPECT_NE(m.find("with " + column + " "), std::string::npos) << m;
      EXPECT_NE(m.find("beyond 10 times the " + std::string(ToString(sensor)) + "'s noise"), std::string::npos) << m;
      twice.back().values(sensor)(0) -= 17.0 * sigma;
      EXPECT_NO_THROW(CheckSpatialReadingsPlausible(robot, twice, "meas.csv")) << column;
    }
  }
  // A load cell's reading within its noise of zero passes: a slack cable reads a little below.
  const double slack_N = 5.0 * robot.sensors.load_cell_N->sigma();
  EXPECT_EQ(message([&](SpatialMeasurement& r) { r.values(SpatialSensor::kLoadCell)(2) = -0.9 * slack_N; }), "accepted");
  // A dl just inside the frame box's diagonal passes: the bound is the box's, not tighter.
  const double diagonal_m = (robot.p_F_frame_max_m - robot.p_F_frame_min_m).norm();
  EXPECT_EQ(message([&](SpatialMeasurement& r) { r.dl_m(0) = 0.99 * diagonal_m; }), "accepted");
}


// A pose the true robot holds beyond its tilt limit is named with the tilt and the limit, as a
// tension beyond its bounds is named with the tension and the bounds (a lab reads the margin).
TEST(SpatialSimulation, APoseBeyondTheTiltLimitIsNamedWithTheTiltAndTheLimit) {
  const SpatialRobot nominal = RobotWithEverySensor(13, 4);
  const std::vector<SpatialPlanPose> plan = SampleSpatialPoses(nominal, 6, 21);
  std::size_t most = 0;
  for (std::size_t j = 1; j < plan.size(); ++j) {
    if (TiltAngle(plan[j].q) > TiltAngle(plan[most].q)) most = j;
  }
  const double tilt_rad = TiltAngle(plan[most].q);
  ASSERT_GT(tilt_rad, 0.01);
  SpatialRobot truth = nominal;
  truth.tilt_max_rad = 0.5 * tilt_rad;  // the same robot, with a stricter limit
  SpatialSimulationOptions options;
  options.skip_infeasible = true;
  Rng rng(3);
  const SimulatedSpatialExperiment e = SimulateSpatialExperiment(nominal, truth, plan, options, rng);
  const auto skipped = std::find_if(e.skipped.begin(), e.skipped.end(),
                                    [&](const SpatialSkippedPose& s) { return s.pose_id == static_cast<int>(most + 1); });
  ASSERT_NE(skipped, e.skipped.end());
  const std::string& why = skipped->reason;
  EXPECT_NE(why.find("(tilt_limit"), std::string::npos) << why;
  const std::size_t at = why.find(" at ");
  const std::size_t limit = why.find(" deg, limit ");
  ASSERT_NE(at, std::string::npos) << why;
  ASSERT_NE(limit, std::string::npos) << why;
  EXPECT_NEAR(std::stod(why.substr(at + 4, limit - at - 4)), tilt_rad * 180.0 / M_PI, 0.01) << why;
  EXPECT_NEAR(std::stod(why.substr(limit + 12)), truth.tilt_max_rad * 180.0 / M_PI, 0.001) << why;
}

}  // namespace
}  // namespace cablecal
