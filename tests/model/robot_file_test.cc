// Robot files: the built-in robot, and every rejection with its message.
#include <gtest/gtest.h>

#include <algorithm>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

#include "common/error.h"
#include "model/robot.h"
#include "model/statics.h"
#include "tests/support/readme.h"
#include "tests/support/temp_dir.h"
#include "tests/support/load_error.h"

namespace cablecal {
namespace {

std::string Replace(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << "test setup: '" << from << "' not in the robot file";
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

using testing::LoadError;

TEST(RobotFile, BuiltinRobotHasTheDocumentedValues) {
  const Robot& r = BuiltinRobot();
  EXPECT_EQ(r.name, "wang2022");
  ASSERT_EQ(r.num_cables(), 2);
  EXPECT_EQ(r.cables[0].p_F_exit_m, Eigen::Vector2d(0.0, 2.8));
  EXPECT_EQ(r.cables[1].p_F_exit_m, Eigen::Vector2d(5.209, 2.8));
  EXPECT_EQ(r.cables[0].side, PulleySide::kLeft);
  EXPECT_EQ(r.cables[1].side, PulleySide::kRight);
  EXPECT_EQ(r.cables[0].pulley_radius_m, 0.025);
  EXPECT_EQ(r.platform_mass_kg, 2.2);
  EXPECT_EQ(r.tension_min_N, 1.0);
  EXPECT_EQ(r.tension_max_N, 100.0);
  EXPECT_NEAR(r.theta_max_rad, M_PI / 3, 1e-15);
  EXPECT_NEAR(r.sensors.inclinometer_accuracy_rad, 0.1 * M_PI / 180, 1e-18);
  EXPECT_EQ(r.sensors.encoder_sigma_m, 5e-5);
}

// The noise bounds' edges load: a range of 0 beside another (a bench fit floors its accuracy at
// 0), the least sigma (a micrometre), the largest length and angle.
TEST(RobotFile, SensorNoiseAtItsBoundsLoads) {
  std::string text = Replace(BuiltinRobotYaml(), "{accuracy: 0.006, repeatability: 0.0015}", "{accuracy: 0, repeatability: 1}");
  text = Replace(text, "{accuracy_deg: 0.1, repeatability_deg: 0.05}", "{accuracy_deg: 30, repeatability_deg: 0}");
  text = Replace(text, "encoder: {sigma: 0.00005}", "encoder: {sigma: 1e-6}");
  text = Replace(text, "tracker: {sigma: 0.0005}", "tracker: {sigma: 1}");
  const Robot robot = LoadRobotFromString(text, "edges.yaml");
  EXPECT_EQ(robot.sensors.encoder_sigma_m, 1e-6);
  EXPECT_EQ(robot.sensors.laser_sigma_m(), 1.0 / 3.0);
  EXPECT_NEAR(robot.sensors.inclinometer_sigma_rad(), 10.0 * M_PI / 180.0, 1e-15);
  // And the file written from it reads back the same.
  EXPECT_EQ(RobotToYaml(LoadRobotFromString(RobotToYaml(robot), "again.yaml")), RobotToYaml(robot));
}

// The paper's robot (and cablecal's documented defaults where the paper is silent) written
// field by field here, not read from a file: the built-in robot is robots/wang2022.yaml compiled
// in, so comparing the two could never fail; a value changed in the file, or read wrongly by the
// loader, shows here.
Robot Wang2022AsDocumented() {
  constexpr double kDeg = M_PI / 180.0;  // as the loader converts degrees
  Robot r;
  r.name = "wang2022";
  r.gravity_mps2 = 9.81;
  r.frame_width_m = 5.209;
  r.frame_height_m = 2.8;
  r.platform_mass_kg = 2.2;
  r.p_P_com_m = Eigen::Vector2d(0.0, 0.0);
  Cable left;
  left.p_F_exit_m = Eigen::Vector2d(0.0, 2.8);
  left.pulley_radius_m = 0.025;
  left.side = PulleySide::kLeft;
  left.p_P_anchor_m = Eigen::Vector2d(-0.25, 0.0);
  Cable right = left;
  right.p_F_exit_m = Eigen::Vector2d(5.209, 2.8);
  right.side = PulleySide::kRight;
  right.p_P_anchor_m = Eigen::Vector2d(0.25, 0.0);
  r.cables = {left, right};
  r.tension_min_N = 1.0;
  r.tension_max_N = 100.0;
  r.theta_max_rad = 60.0 * kDeg;
  r.laser_range_m = 3.0;
  r.margin_m = 0.05;
  r.p_F_home_m = Eigen::Vector2d(2.6045, 1.4);
  r.sensors.laser_accuracy_m = 0.006;
  r.sensors.laser_repeatability_m = 0.0015;
  r.sensors.inclinometer_accuracy_rad = 0.1 * kDeg;
  r.sensors.inclinometer_repeatability_rad = 0.05 * kDeg;
  r.sensors.encoder_sigma_m = 0.00005;
  r.sensors.tracker_sigma_m = 0.0005;
  return r;
}

TEST(RobotFile, FileOnDiskAndBuiltinAreThePapersRobot) {
  const std::string expected = RobotToYaml(Wang2022AsDocumented());
  EXPECT_EQ(RobotToYaml(LoadRobotFile(std::string(CABLECAL_SOURCE_DIR) + "/robots/wang2022.yaml")), expected);
  EXPECT_EQ(RobotToYaml(BuiltinRobot()), expected);
}

TEST(RobotFile, YamlRoundTrip) {
  Robot r = BuiltinRobot();
  r.cables[0].initial_length_m = 2.9;
  const Robot back = LoadRobotFromString(RobotToYaml(r), "roundtrip");
  EXPECT_EQ(RobotToYaml(back), RobotToYaml(r));
  EXPECT_EQ(*back.cables[0].initial_length_m, 2.9);
  // Any name survives the trip: YAML's special characters are quoted by yaml-cpp's emitter.
  for (const char* name : {"lab: robot #2", "\"quoted\" and \\ back", "two\nlines", "- dash", "1e-04"}) {
    r.name = name;
    EXPECT_EQ(LoadRobotFromString(RobotToYaml(r), "roundtrip").name, name);
  }
}

struct BadCase {
  const char* name;
  const char* from;
  const char* to;
  const char* expected;  // regex the message must match
};

class BadRobotFile : public ::testing::TestWithParam<BadCase> {};

// A key left empty (`com:` alone) is named at its own line: yaml-cpp marks the empty value at
// the next token, the line below.
TEST(RobotFile, AnEmptyKeyIsNamedAtItsOwnLine) {
  const std::string yaml = Replace(BuiltinRobotYaml(), "com: [0.0, 0.0]", "com:");
  const std::size_t at = yaml.find("com:");
  ASSERT_NE(at, std::string::npos);
  const int line = 1 + static_cast<int>(std::count(yaml.begin(), yaml.begin() + at, '\n'));
  const std::string message = LoadError(yaml);
  EXPECT_EQ(message.rfind("bad.yaml:" + std::to_string(line) + ": platform.com: must be a list of two numbers", 0), 0u)
      << message;
}

TEST_P(BadRobotFile, IsRejectedWithKeyAndLine) {
  const BadCase& c = GetParam();
  const std::string message = LoadError(Replace(BuiltinRobotYaml(), c.from, c.to));
  EXPECT_TRUE(std::regex_search(message, std::regex(c.expected))) << "message: " << message;
  EXPECT_TRUE(std::regex_search(message, std::regex("^bad\\.yaml:[0-9]+: "))) << "message: " << message;
}

INSTANTIATE_TEST_SUITE_P(
    Rejections, BadRobotFile,
    ::testing::Values(
        BadCase{"MissingKey", "  mass: 2.2 ", "  # no mass ", "platform\\.mass: missing"},
        BadCase{"WrongType", "mass: 2.2", "mass: heavy", "platform\\.mass: must be a finite number \\(got 'heavy'\\)"},
        BadCase{"NonPositiveMass", "mass: 2.2", "mass: -1", "platform\\.mass: must be > 0 \\(got -1\\)"},
        BadCase{"ZeroRadius", "pulley_radius: 0.025, side: left", "pulley_radius: 0, side: left",
                "cables\\[0\\]\\.pulley_radius: must be > 0"},
        BadCase{"CoincidentAnchors", "[[-0.25, 0.0], [0.25, 0.0]]", "[[0.25, 0.0], [0.25, 0.0]]",
                "platform\\.anchors\\[1\\]: coincides with anchors\\[0\\]"},
        BadCase{"TensionMinNotBelowMax", "{min: 1.0, max: 100.0}", "{min: 100.0, max: 100.0}",
                "tension: min must be < max"},
        BadCase{"HomeOutsideWorkspace", "home: [2.6045, 1.4]", "home: [2.6045, 2.9]",
                "home: .* is not in the feasible workspace: outside_frame"},
        BadCase{"HomeTensionTooHigh", "{min: 1.0, max: 100.0}", "{min: 1.0, max: 5.0}",
                "home: .* is not in the feasible workspace: tension_high"},
        BadCase{"UnknownKey", "gravity: 9.81", "gravity: 9.81\nfriction: 0.1", "friction: unknown key"},
        BadCase{"NotANumber", "gravity: 9.81", "gravity: .nan", "gravity: must be a finite number"},
        BadCase{"Overflow", "gravity: 9.81", "gravity: 1e400", "gravity: must be a finite number"},
        BadCase{"BadSide", "side: right", "side: up", "cables\\[1\\]\\.side: must be 'left' or 'right'"},
        BadCase{"OneCable", "  - {exit: [5.209, 2.8], pulley_radius: 0.025, side: right}\n", "",
                "cables: must list 2 to 8 cables \\(got 1\\)"},
        BadCase{"NineCables", "  - {exit: [5.209, 2.8], pulley_radius: 0.025, side: right}",
                "  - {exit: [5.209, 2.8], pulley_radius: 0.025, side: right}\n"
                "  - {exit: [1, 2.8], pulley_radius: 0.025, side: right}\n  - {exit: [2, 2.8], pulley_radius: 0.025, side: right}\n"
                "  - {exit: [3, 2.8], pulley_radius: 0.025, side: right}\n  - {exit: [4, 2.8], pulley_radius: 0.025, side: right}\n"
                "  - {exit: [1.5, 2.8], pulley_radius: 0.025, side: left}\n  - {exit: [2.5, 2.8], pulley_radius: 0.025, side: left}\n"
                "  - {exit: [3.5, 2.8], pulley_radius: 0.025, side: left}",
                "cables: must list 2 to 8 cables \\(got 9\\)"},
        BadCase{"ThreeCablesTwoAnchors", "  - {exit: [5.209, 2.8], pulley_radius: 0.025, side: right}",
                "  - {exit: [5.209, 2.8], pulley_radius: 0.025, side: right}\n  - {exit: [2, 2.8], pulley_radius: 0.025, side: right}",
                "platform\\.anchors: needs one anchor per cable \\(3\\), got 2"},
        BadCase{"HomeThetaWithTwoCables", "home: [2.6045, 1.4]", "home: [2.6045, 1.4]\nhome_theta_deg: 3",
                "home_theta_deg: is for robots with 3 or more cables"},
        BadCase{"ShortVector", "com: [0.0, 0.0]", "com: [0.0]", "platform\\.com: must be a list of two numbers"},
        // The equilibrium row's weight 1/com_sigma: 1e-300 failed as a non-finite residual at the start.
        BadCase{"TinyComSigma", "com: [0.0, 0.0]", "com: [0.0, 0.0]\n  com_sigma: 1e-300",
                "platform\\.com_sigma: must be at least 1\\.0e-06 m \\(got 1\\.0e-300\\)"},
        BadCase{"NegativeNoise", "encoder: {sigma: 0.00005}", "encoder: {sigma: -0.00005}",
                "sensors\\.encoder\\.sigma: must be from 1e-06 to 1 m, one standard deviation \\(got -5e-05\\)"},
        // Every reading is weighed by 1/sigma: a noiseless sensor failed inside the solvers.
        BadCase{"ZeroEncoderSigma", "encoder: {sigma: 0.00005}", "encoder: {sigma: 0}",
                "sensors\\.encoder\\.sigma: must be from 1e-06 to 1 m, one standard deviation \\(got 0\\): every "
                "reading is weighed by 1/sigma"},
        BadCase{"TinyEncoderSigma", "encoder: {sigma: 0.00005}", "encoder: {sigma: 1e-300}",
                "sensors\\.encoder\\.sigma: must be from 1e-06 to 1 m, one standard deviation \\(got 1e-300\\)"},
        BadCase{"EncoderSigmaBelowAMicrometre", "encoder: {sigma: 0.00005}", "encoder: {sigma: 1e-7}",
                "sensors\\.encoder\\.sigma: must be from 1e-06 to 1 m, one standard deviation \\(got 1e-07\\)"},
        BadCase{"EncoderSigmaInMillimetres", "encoder: {sigma: 0.00005}", "encoder: {sigma: 50}",
                "sensors\\.encoder\\.sigma: must be from 1e-06 to 1 m.*\\(got 50\\): units\\?"},
        BadCase{"ZeroTrackerSigma", "tracker: {sigma: 0.0005}", "tracker: {sigma: 0}",
                "sensors\\.tracker\\.sigma: must be from 1e-06 to 1 m"},
        BadCase{"NoiselessLaser", "{accuracy: 0.006, repeatability: 0.0015}", "{accuracy: 0, repeatability: 1e-300}",
                "sensors\\.laser: accuracy and repeatability give a sigma of 3\\.33333e-301 m \\(hypot\\(accuracy, "
                "repeatability\\) / 3\\), below 1e-06 m"},
        BadCase{"LaserRangeInMillimetres", "{accuracy: 0.006, repeatability: 0.0015}", "{accuracy: 6, repeatability: 0.0015}",
                "sensors\\.laser\\.accuracy: must be from 0 to 1 m, a \\+- range taken as 3 sigma \\(got 6\\): units\\?"},
        BadCase{"NegativeLaserRange", "{accuracy: 0.006, repeatability: 0.0015}", "{accuracy: 0.006, repeatability: -1}",
                "sensors\\.laser\\.repeatability: must be from 0 to 1 m"},
        BadCase{"NoiselessInclinometer", "{accuracy_deg: 0.1, repeatability_deg: 0.05}",
                "{accuracy_deg: 0, repeatability_deg: 0}",
                "sensors\\.inclinometer: accuracy and repeatability give a sigma of 0 rad"},
        BadCase{"InclinometerRangeBeyondThirtyDegrees", "{accuracy_deg: 0.1, repeatability_deg: 0.05}",
                "{accuracy_deg: 45, repeatability_deg: 0.05}",
                "sensors\\.inclinometer\\.accuracy_deg: must be from 0 to 30 degrees"},
        BadCase{"ExitOutsideTheFrame", "exit: [5.209, 2.8]", "exit: [7.0, 2.8]",
                "cables\\[1\\]\\.exit: \\(7, 2\\.8\\) m is outside the frame"},
        BadCase{"ExitAboveTheFrame", "exit: [0.0, 2.8]", "exit: [0.0, 3.5]",
                "cables\\[0\\]\\.exit: \\(0, 3\\.5\\) m is outside the frame"},
        BadCase{"RadiusInMillimetres", "pulley_radius: 0.025, side: left", "pulley_radius: 25, side: left",
                "cables\\[0\\]\\.pulley_radius: 25 m is more than a quarter of the frame"},
        BadCase{"DuplicateKey", "gravity: 9.81", "gravity: 9.81\ngravity: 1.62", "gravity: given twice \\(first at line"},
        BadCase{"DuplicateCables", "cables:", "cables: []\ncables:", "cables: given twice \\(first at line"},
        BadCase{"DuplicateNestedKey", "{width: 5.209, height: 2.8}", "{width: 5.209, height: 2.8, width: 3}",
                "frame\\.width: given twice"},
        BadCase{"SecondDocument", "  tracker: {sigma: 0.0005}", "  tracker: {sigma: 0.0005}\n---\nname: other",
                "a second YAML document"},
        BadCase{"BothSidesLeft", "side: right", "side: left", "cables\\[1\\]\\.side: both cables are on their pulleys' left side"},
        BadCase{"FrameInMillimetres", "{width: 5.209, height: 2.8}", "{width: 5209, height: 2800}",
                "frame\\.width: must be at most 100 m \\(got 5209\\): units\\?"},
        BadCase{"HugeMass", "  mass: 2.2 ", "  mass: 1e308 ", "platform\\.mass: must be at most 10000 kg"},
        BadCase{"GravityInCentimetres", "gravity: 9.81", "gravity: 981", "gravity: must be at most 100 m/s\\^2"},
        BadCase{"LongUnknownKeyIsShortened", "gravity: 9.81",
                "gravity: 9.81\nroot:x:0:0:root:/root:/bin/bash_and_more_that_is_not_a_key: 1",
                "root:x:0:0:root:/root:/bin/bash_and_more\\.\\.\\.: unknown key"},
        BadCase{"InvalidYaml", "frame: {width: 5.209, height: 2.8}", "frame: {width: 5.209, height: [2.8}",
                "not valid YAML"}),
    [](const ::testing::TestParamInfo<BadCase>& info) { return std::string(info.param.name); });

// The same for robots with more cables, from the 3- and 4-cable files in robots/.
std::string RobotFileText(const std::string& name) {
  std::ifstream in(std::string(CABLECAL_SOURCE_DIR) + "/robots/" + name);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

struct ManyCableBadCase {
  const char* name;
  const char* file;
  const char* from;
  const char* to;
  const char* expected;
};

class BadManyCableRobotFile : public ::testing::TestWithParam<ManyCableBadCase> {};

TEST_P(BadManyCableRobotFile, IsRejectedWithKeyAndLine) {
  const ManyCableBadCase& c = GetParam();
  const std::string text = RobotFileText(c.file);
  ASSERT_EQ(LoadError(text), "") << "the unmodified file must load";
  const std::string message = LoadError(Replace(text, c.from, c.to));
  EXPECT_TRUE(std::regex_search(message, std::regex(c.expected))) << "message: " << message;
  EXPECT_TRUE(std::regex_search(message, std::regex("^bad\\.yaml:[0-9]+: "))) << "message: " << message;
}

INSTANTIATE_TEST_SUITE_P(
    Rejections, BadManyCableRobotFile,
    ::testing::Values(
        ManyCableBadCase{"AnchorMissing", "planar3_suspended.yaml", "[[-0.35, 0.0], [0.0, 0.25], [0.35, 0.0]]",
                         "[[-0.35, 0.0], [0.35, 0.0]]", "platform\\.anchors: needs one anchor per cable \\(3\\), got 2"},
        ManyCableBadCase{"AnchorTooMany", "planar4_fully_constrained.yaml", "[0.2, -0.1]]", "[0.2, -0.1], [0, 0]]",
                         "platform\\.anchors: needs one anchor per cable \\(4\\), got 5"},
        ManyCableBadCase{"AllAnchorsOnePoint", "planar4_fully_constrained.yaml",
                         "[[0.2, 0.1], [-0.2, 0.1], [-0.2, -0.1], [0.2, -0.1]]",
                         "[[0.2, 0.1], [0.2, 0.1], [0.2, 0.1], [0.2, 0.1]]",
                         "platform\\.anchors: all anchors are one point"},
        ManyCableBadCase{"WrapSideways", "planar4_fully_constrained.yaml", "wrap: under}", "wrap: sideways}",
                         "cables\\[2\\]\\.wrap: must be 'over' or 'under' \\(got 'sideways'\\)"},
        ManyCableBadCase{"HomeThetaOutsideBand", "planar3_suspended.yaml", "home_theta_deg: 18 ", "home_theta_deg: -20 ",
                         "home: \\(1\\.5, 1\\) m at theta -20 degrees \\(home_theta_deg\\) is not in the feasible "
                         "workspace: no_equilibrium; feasible home_theta_deg at this \\(x, z\\): 3\\.5 to 32\\.5 \\(0\\.5-degree scan\\)"},
        ManyCableBadCase{"HomeThetaBeyondInclinometer", "planar4_fully_constrained.yaml", "home_theta_deg: 0",
                         "home_theta_deg: 40", "home_theta_deg: 40 degrees is beyond limits\\.theta_max_deg \\(30\\)"},
        ManyCableBadCase{"HomeTensionsTooHigh", "planar4_fully_constrained.yaml", "{min: 5.0, max: 150.0}",
                         "{min: 5.0, max: 12.0}", "home: .* is not in the feasible workspace: tension_high"},
        ManyCableBadCase{"UnderExitBelowFloor", "planar4_fully_constrained.yaml", "exit: [3.0, 0.1]", "exit: [3.0, -0.5]",
                         "cables\\[2\\]\\.exit: \\(3, -0\\.5\\) m is outside the frame \\[0, 3\\] x \\[0, 2\\]"}),
    [](const ::testing::TestParamInfo<ManyCableBadCase>& info) { return std::string(info.param.name); });

// The new robot files load, and a robot with wrap: under and a home orientation survives the
// trip through RobotToYaml unchanged.
TEST(RobotFile, ManyCableFilesLoadAndRoundTrip) {
  for (const char* name : {"planar3_suspended.yaml", "planar4_fully_constrained.yaml"}) {
    const Robot r = LoadRobotFromString(RobotFileText(name), name);
    EXPECT_TRUE(r.theta_is_free());
    const Robot back = LoadRobotFromString(RobotToYaml(r), "roundtrip");
    EXPECT_EQ(RobotToYaml(back), RobotToYaml(r));
    EXPECT_EQ(back.num_cables(), r.num_cables());
    EXPECT_DOUBLE_EQ(back.home_theta_rad, r.home_theta_rad);
    for (int i = 0; i < r.num_cables(); ++i) EXPECT_EQ(back.cables[i].wrap, r.cables[i].wrap) << name << " cable " << i;
  }
  const Robot p3 = LoadRobotFromString(RobotFileText("planar3_suspended.yaml"), "p3");
  EXPECT_NEAR(p3.home_theta_rad, 18.0 * M_PI / 180.0, 1e-15);
  const Robot p4 = LoadRobotFromString(RobotFileText("planar4_fully_constrained.yaml"), "p4");
  EXPECT_EQ(p4.num_cables(), 4);
  EXPECT_EQ(p4.cables[2].wrap, PulleyWrap::kUnder);
  EXPECT_EQ(p4.cables[0].wrap, PulleyWrap::kOver);
}

// README's "A complete robot file": the yaml block after that heading loads as it is, sets
// every optional key it shows, and its initial_length is the one the home equilibrium gives.
TEST(RobotFile, ReadmeExampleLoads) {
  const std::string yaml = testing::ReadmeYamlAfter("**A complete robot file**");
  ASSERT_FALSE(yaml.empty()) << "no yaml block after the heading in README.md";
  EXPECT_EQ(LoadError(yaml), "");
  const Robot r = LoadRobotFromString(yaml, "README.md");
  ASSERT_EQ(r.num_cables(), 3);
  EXPECT_TRUE(EvaluateHome(r).feasible());
  EXPECT_NEAR(r.home_theta_rad, 18.0 * M_PI / 180.0, 1e-15);
  EXPECT_EQ(r.cables[0].wrap, PulleyWrap::kOver);
  EXPECT_EQ(r.cables[1].side, PulleySide::kLeft);
  EXPECT_EQ(r.cables[2].side, PulleySide::kRight);
  EXPECT_EQ(r.sensors.systematic.laser_offset_m, 0.002);
  EXPECT_NEAR(r.sensors.systematic.inclinometer_offset_rad, 0.05 * M_PI / 180.0, 1e-15);
  EXPECT_NEAR(r.sensors.systematic.inclinometer_sec_coefficient_rad, -0.2 * M_PI / 180.0, 1e-15);
  ASSERT_TRUE(r.sensors.tracker_sigma_m.has_value());
  EXPECT_EQ(*r.sensors.tracker_sigma_m, 0.0005);
  // The example's initial_length is the computed one (to its 0.1 mm), not an arbitrary number.
  ASSERT_TRUE(r.cables[0].initial_length_m.has_value());
  Robot computed = r;
  computed.cables[0].initial_length_m.reset();
  EXPECT_NEAR(*r.cables[0].initial_length_m, InitialLengths(computed)(0), 1e-4);
}

// With 3 or more cables two cables may share an anchor (a common design): the file loads, and
// the shared anchor still has a feasible workspace around home.
TEST(RobotFile, ManyCablesMayShareAnAnchor) {
  const std::string p4 = RobotFileText("planar4_fully_constrained.yaml");
  const std::string from = "[[0.2, 0.1], [-0.2, 0.1], [-0.2, -0.1], [0.2, -0.1]]";
  ASSERT_NE(p4.find(from), std::string::npos);
  std::string shared = p4;
  shared.replace(shared.find(from), from.size(), "[[0.2, 0.0], [-0.2, 0.0], [-0.2, 0.0], [0.2, 0.0]]");
  EXPECT_EQ(LoadError(shared), "");
  const Robot r = LoadRobotFromString(shared, "shared.yaml");
  EXPECT_EQ(r.cables[1].p_P_anchor_m, r.cables[2].p_P_anchor_m);
  EXPECT_TRUE(EvaluateHome(r).feasible());
}

// An input on which yaml-cpp 0.7's LoadAll never returns (found by the fuzzer; kept in its
// corpus): the loader must answer, here with an InputError.
TEST(RobotFile, InputThatHungYamlLoadAllIsAnswered) {
  std::ifstream in(std::string(CABLECAL_SOURCE_DIR) + "/tests/fuzz/corpus/robot/loadall_hang.yaml", std::ios::binary);
  ASSERT_TRUE(in.good());
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_THROW(LoadRobotFromString(text.str(), "hang.yaml"), InputError);
}

TEST(RobotFile, MissingAndEmptyFiles) {
  try {
    LoadRobotFile("/nonexistent/robot.yaml");
    FAIL() << "loaded a missing file";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/robot.yaml: cannot open"), std::string::npos) << e.what();
  }
  EXPECT_NE(LoadError("").find("empty"), std::string::npos);
  EXPECT_NE(LoadError("# only a comment\n").find("empty"), std::string::npos);
  // Devices and huge files are refused before reading (/dev/zero would never end).
  for (const char* device : {"/dev/zero", "/dev/null", "/tmp"}) {
    try {
      LoadRobotFile(device);
      FAIL() << "loaded " << device;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("is not a regular file"), std::string::npos) << e.what();
    }
  }
  const testing_support::TempDir tmp;
  const std::string big = tmp.Path("big_robot.yaml");
  std::ofstream(big) << BuiltinRobotYaml() << std::string(kMaxRobotFileBytes, '#') << "\n";
  try {
    LoadRobotFile(big);
    FAIL() << "loaded a file over the size cap";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("is larger than 1024 KiB"), std::string::npos) << e.what();
  }
}

TEST(RobotFile, LineNumberPointsAtTheOffendingKey) {
  const std::string yaml = Replace(BuiltinRobotYaml(), "mass: 2.2", "mass: -2.2");
  const std::string message = LoadError(yaml);
  // "mass" is on line 10 of robots/wang2022.yaml.
  std::size_t line = 1;
  for (std::size_t i = 0; i < yaml.find("mass: -2.2"); ++i) line += yaml[i] == '\n';
  EXPECT_EQ(message.rfind("bad.yaml:" + std::to_string(line) + ": platform.mass", 0), 0u) << message;
}

}  // namespace
}  // namespace cablecal
