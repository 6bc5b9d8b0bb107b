// The sensors' systematic error models: the correction inverts the reading, zero terms change
// nothing, and the robot file reads, checks and writes the optional keys.
#include <gtest/gtest.h>

#include <cmath>
#include <regex>
#include <string>

#include "common/error.h"
#include "model/robot.h"
#include "model/sensor_model.h"
#include "tests/support/load_error.h"

namespace cablecal {
namespace {

constexpr double kDeg = M_PI / 180.0;

SystematicSensorErrors PaperLike() {
  SystematicSensorErrors e;
  e.laser_offset_m = 0.004;
  e.inclinometer_offset_rad = 0.02 * kDeg;
  e.inclinometer_sec_coefficient_rad = -0.24 * kDeg;
  return e;
}

TEST(SensorModel, CorrectionInvertsTheReadingOverTheRange) {
  const SystematicSensorErrors e = PaperLike();
  for (double deg = -60.0; deg <= 60.0; deg += 0.5) {
    const double theta = deg * kDeg;
    const double reading = InclinometerReading(e, theta);
    EXPECT_NEAR(reading - theta, 0.02 * kDeg - 0.24 * kDeg * (1.0 / std::cos(theta) - 1.0), 2e-16) << deg;
    EXPECT_NEAR(CorrectedInclinometerReading(e, reading), theta, 4e-16) << deg;
  }
  EXPECT_NEAR(CorrectedLaserReading(e, LaserReading(e, 1.234)), 1.234, 1e-15);
  EXPECT_EQ(LaserReading(e, 1.0), 1.004);
}

// The largest coefficient a 75-degree robot file accepts (the slope bound, 2 degrees, binds
// there) still inverts to 1e-12 rad, at the range and a degree beyond it (a noisy reading).
TEST(SensorModel, CorrectionConvergesAtTheSteepestAcceptedCoefficient) {
  SystematicSensorErrors e;
  const double theta_max = 75.0 * kDeg;
  e.inclinometer_offset_rad = 0.1 * kDeg;
  e.inclinometer_sec_coefficient_rad = kMaxInclinometerErrorSlope * std::cos(theta_max) / std::tan(theta_max);
  ASSERT_FALSE(CheckSystematicErrors(e, theta_max));
  for (double deg = -76.0; deg <= 76.0; deg += 1.0) {
    const double theta = deg * kDeg;
    EXPECT_NEAR(CorrectedInclinometerReading(e, InclinometerReading(e, theta)), theta, 1e-12) << deg;
  }
}

TEST(SensorModel, ZeroTermsLeaveEveryValueAsItIs) {
  const SystematicSensorErrors none;
  EXPECT_FALSE(none.any());
  for (const double v : {-1.0, -0.3, 0.0, 1e-300, 0.7, 1.2}) {
    EXPECT_EQ(InclinometerReading(none, v), v);
    EXPECT_EQ(CorrectedInclinometerReading(none, v), v);
    EXPECT_EQ(LaserReading(none, v), v);
    EXPECT_EQ(CorrectedLaserReading(none, v), v);
  }
  // Beyond +-90 degrees (no inclinometer's reading) the correction leaves it for the check.
  EXPECT_EQ(CorrectedInclinometerReading(PaperLike(), 2.0), 2.0);
}

TEST(SensorModel, BoundsNameTheKey) {
  SystematicSensorErrors e;
  e.laser_offset_m = 4.0;  // 4 mm typed as m
  EXPECT_EQ(CheckSystematicErrors(e, 1.0)->key, "sensors.laser.offset");
  e = {};
  e.inclinometer_offset_rad = 6.0 * kDeg;
  EXPECT_EQ(CheckSystematicErrors(e, 1.0)->key, "sensors.inclinometer.offset_deg");
  e = {};
  e.inclinometer_sec_coefficient_rad = 1.0 * kDeg;  // fine at 60 degrees, too steep at 88
  EXPECT_FALSE(CheckSystematicErrors(e, 60.0 * kDeg));
  const auto steep = CheckSystematicErrors(e, 88.0 * kDeg);
  ASSERT_TRUE(steep);
  EXPECT_EQ(steep->key, "sensors.inclinometer.sec_coefficient_deg");
  EXPECT_NE(steep->problem.find("could not be corrected reliably"), std::string::npos) << steep->problem;
}

std::string WithSensors(const std::string& laser, const std::string& inclinometer, const std::string& theta_max_deg = "60") {
  std::string text = BuiltinRobotYaml();
  const auto replace = [&](const std::string& from, const std::string& to) {
    const std::size_t at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    text.replace(at, from.size(), to);
  };
  replace("{accuracy: 0.006, repeatability: 0.0015}", laser);
  replace("{accuracy_deg: 0.1, repeatability_deg: 0.05}", inclinometer);
  replace("theta_max_deg: 60", "theta_max_deg: " + theta_max_deg);
  return text;
}

using testing::LoadError;

TEST(SensorModelRobotFile, OptionalKeysReadWriteAndDefaultToZero) {
  EXPECT_FALSE(BuiltinRobot().sensors.systematic.any());
  EXPECT_EQ(RobotToYaml(BuiltinRobot()).find("offset"), std::string::npos) << "absent keys stay absent";
  const Robot r = LoadRobotFromString(
      WithSensors("{accuracy: 0.005, repeatability: 0.0015, offset: -0.0021}",
                  "{accuracy_deg: 0.09, repeatability_deg: 0.05, offset_deg: 0.013, sec_coefficient_deg: -0.24}"),
      "fitted.yaml");
  EXPECT_EQ(r.sensors.systematic.laser_offset_m, -0.0021);
  EXPECT_NEAR(r.sensors.systematic.inclinometer_offset_rad, 0.013 * kDeg, 1e-18);
  EXPECT_NEAR(r.sensors.systematic.inclinometer_sec_coefficient_rad, -0.24 * kDeg, 1e-18);
  const std::string yaml = RobotToYaml(r);
  EXPECT_NE(yaml.find("laser: {accuracy: 0.005, repeatability: 0.0015, offset: -0.0021}"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("offset_deg: 0.013, sec_coefficient_deg: -0.24}"), std::string::npos) << yaml;
  EXPECT_EQ(RobotToYaml(LoadRobotFromString(yaml, "again")), yaml);
}

TEST(SensorModelRobotFile, BadTermsAreRefusedWithKeyAndLine) {
  const struct {
    std::string laser, inclinometer, expected, theta_max_deg = "60";
  } cases[] = {
      {"{accuracy: 0.006, repeatability: 0.0015, offset: 4}", "{accuracy_deg: 0.1, repeatability_deg: 0.05}",
       "^bad\\.yaml:20: sensors\\.laser\\.offset: 4 m is more than 0\\.1 m: units\\?"},
      {"{accuracy: 0.006, repeatability: 0.0015, offset: abc}", "{accuracy_deg: 0.1, repeatability_deg: 0.05}",
       "^bad\\.yaml:20: sensors\\.laser\\.offset: must be a finite number \\(got 'abc'\\)"},
      {"{accuracy: 0.006, repeatability: 0.0015}", "{accuracy_deg: 0.1, repeatability_deg: 0.05, offset_deg: .nan}",
       "^bad\\.yaml:21: sensors\\.inclinometer\\.offset_deg: must be a finite number"},
      {"{accuracy: 0.006, repeatability: 0.0015}", "{accuracy_deg: 0.1, repeatability_deg: 0.05, offset_deg: 0.02}",
       ""},
      {"{accuracy: 0.006, repeatability: 0.0015}",
       "{accuracy_deg: 0.1, repeatability_deg: 0.05, sec_coefficient_deg: 0.2, sec_coefficient_deg: 0.3}",
       "sensors\\.inclinometer\\.sec_coefficient_deg: given twice"},
      {"{accuracy: 0.006, repeatability: 0.0015}", "{accuracy_deg: 0.1, repeatability_deg: 0.05, sec_coefficient_deg: -4.9}",
       ""},
      {"{accuracy: 0.006, repeatability: 0.0015}", "{accuracy_deg: 0.1, repeatability_deg: 0.05, sec_coefficient_deg: -5.1}",
       "^bad\\.yaml:21: sensors\\.inclinometer\\.sec_coefficient_deg: -5\\.1 degrees is more than 5: units\\?"},
      {"{accuracy: 0.006, repeatability: 0.0015}", "{accuracy_deg: 0.1, repeatability_deg: 0.05, sec_coefficient_deg: 2}",
       "^bad\\.yaml:21: sensors\\.inclinometer\\.sec_coefficient_deg: 2 degrees makes the error change by 1\\.14 rad "
       "per rad at the inclinometer's range \\(limits\\.theta_max_deg 80\\)", "80"},
      {"{accuracy: 0.006, repeatability: 0.0015, offset_deg: 0.1}", "{accuracy_deg: 0.1, repeatability_deg: 0.05}",
       "sensors\\.laser\\.offset_deg: unknown key"},
  };
  for (const auto& c : cases) {
    const std::string message = LoadError(WithSensors(c.laser, c.inclinometer, c.theta_max_deg));
    if (c.expected.empty()) {
      EXPECT_EQ(message, "") << c.inclinometer;
    } else {
      EXPECT_TRUE(std::regex_search(message, std::regex(c.expected))) << c.laser << " " << c.inclinometer << "\n" << message;
    }
  }
}

}  // namespace
}  // namespace cablecal
