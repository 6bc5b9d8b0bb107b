// Spatial robot files (model/spatial_robot.h): the built-in ones, the round trip, every
// refusal with file, line and key, and the two loaders refusing each other's files.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "common/error.h"
#include "common/random.h"
#include "model/geometry.h"
#include "model/kind.h"
#include "model/robot.h"
#include "model/spatial_robot.h"
#include "model/swivel.h"
#include "tests/support/readme.h"
#include "tests/support/random_spatial_robot.h"
#include "tests/support/six_mixed_robot.h"

namespace cablecal {
namespace {

constexpr const char* kSpatialFiles[] = {"cogiro.yaml", "ipanema1.yaml", "irma4u.yaml"};
constexpr const char* kPlanarFiles[] = {"wang2022.yaml", "asymmetric.yaml", "planar3_suspended.yaml",
                                        "planar4_fully_constrained.yaml"};

std::string PathOf(const std::string& file) { return std::string(CABLECAL_SOURCE_DIR) + "/robots/" + file; }

std::string TextOf(const std::string& file) {
  std::ifstream in(PathOf(file));
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string Replace(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << "test setup: '" << from << "' not in the robot file";
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

// The InputError message of loading `yaml` as a spatial robot ("" if it loads).
std::string SpatialLoadError(const std::string& yaml) {
  try {
    LoadSpatialRobotFromString(yaml, "bad.yaml");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// The line of the n-th occurrence of `text` in `yaml`, 1-based.
int LineOf(const std::string& yaml, const std::string& text, int occurrence = 1) {
  std::size_t at = yaml.find(text);
  for (int n = 1; n < occurrence && at != std::string::npos; ++n) at = yaml.find(text, at + 1);
  EXPECT_NE(at, std::string::npos) << text;
  if (at == std::string::npos) return -1;
  return 1 + static_cast<int>(std::count(yaml.begin(), yaml.begin() + static_cast<long>(at), '\n'));
}

// The spatial kind: 6 pose coordinates, 3-D points and wrenches, and a geometry layout whose
// names run over three axes.
TEST(SpatialKind, PoseAndLayout) {
  static_assert(SpatialKind::kPoseDim == 6 && SpatialKind::kPointDim == 3 && SpatialKind::kWrenchDim == 6);
  EXPECT_STREQ(SpatialKind::kPoseNames[4], "pitch");
  EXPECT_STREQ(SpatialKind::kPoseUnits[5], "rad");
  const GeometryLayout layout = SpatialKind::Layout(2);
  EXPECT_EQ(layout.size(), 8);
  EXPECT_EQ(layout.exit(1, 2), 5);
  EXPECT_EQ(layout.initial_length(1), 7);
  EXPECT_EQ(layout.axis_of(5), 2);
  const std::vector<std::string> expected = {"a1x", "a1y", "a1z", "a2x", "a2y", "a2z", "l10", "l20"};
  EXPECT_EQ(layout.names(), expected);
  EXPECT_EQ(SpatialKind::Layout(10).names()[29], "a10z");
  EXPECT_EQ(SpatialKind::Layout(10).names()[39], "l100");
}

TEST(SpatialRobotFile, BuiltInFilesLoadWithValidGeometryAtHome) {
  for (const char* file : kSpatialFiles) {
    const SpatialRobot r = LoadSpatialRobotFile(PathOf(file));
    EXPECT_EQ(RobotKindOfFile(PathOf(file)), RobotKind::kSpatial) << file;
    const SpatialPose<double> home = r.home_pose();
    const CableGeometryCheck check = CableGeometryAt(r, home);
    EXPECT_TRUE(check.valid()) << file << ": cable " << check.cable << " " << ToString(check.geometry);
    for (const SpatialCable& c : r.cables) EXPECT_NEAR(c.k_F_swivel_axis.norm(), 1.0, 1e-15) << file;
    EXPECT_LE(TiltAngle(home), r.tilt_max_rad) << file;
  }
  for (const char* file : kPlanarFiles) EXPECT_EQ(RobotKindOfFile(PathOf(file)), RobotKind::kPlanar) << file;
}

TEST(SpatialRobotFile, BuiltInValuesAreTheSources) {
  const SpatialRobot cogiro = LoadSpatialRobotFile(PathOf("cogiro.yaml"));
  ASSERT_EQ(cogiro.num_cables(), 8);
  EXPECT_EQ(cogiro.platform_mass_kg, 91.058);
  EXPECT_EQ(cogiro.p_P_com_m, Eigen::Vector3d(-0.034, -0.013, 0.264));
  EXPECT_EQ(cogiro.cables[0].p_F_exit_m, Eigen::Vector3d(-7.1775, -5.4361, 5.3911));
  EXPECT_EQ(cogiro.cables[7].p_P_anchor_m, Eigen::Vector3d(-0.5045, -0.3463, 0.9976));
  EXPECT_EQ(cogiro.cables[3].k_F_swivel_axis, Eigen::Vector3d::UnitZ());
  EXPECT_EQ(cogiro.cables[0].pulley_radius_m, 0.05);
  EXPECT_EQ(*cogiro.cables[0].stiffness_N, 820510.0);
  EXPECT_EQ(cogiro.p_F_frame_max_m - cogiro.p_F_frame_min_m, Eigen::Vector3d(15.24, 11.24, 5.93));
  EXPECT_EQ(cogiro.tension_min_N, 100.0);
  EXPECT_EQ(cogiro.tension_max_N, 5000.0);

  const SpatialRobot ipanema = LoadSpatialRobotFile(PathOf("ipanema1.yaml"));
  ASSERT_EQ(ipanema.num_cables(), 8);
  EXPECT_EQ(ipanema.platform_mass_kg, 25.0);
  EXPECT_EQ(ipanema.tension_max_N, 720.0);
  for (int i = 0; i < 8; ++i) {
    // Each cable to the platform corner of its exit's signs; upper k = +z, lower k = -z.
    const SpatialCable& c = ipanema.cables[i];
    EXPECT_EQ(c.p_F_exit_m.z(), i < 4 ? 2.0 : 0.0);
    EXPECT_EQ(c.k_F_swivel_axis, Eigen::Vector3d(0.0, 0.0, i < 4 ? 1.0 : -1.0));
    EXPECT_GT(c.p_F_exit_m.x() * c.p_P_anchor_m.x(), 0.0);
    EXPECT_GT(c.p_F_exit_m.y() * c.p_P_anchor_m.y(), 0.0);
  }

  const SpatialRobot irma = LoadSpatialRobotFile(PathOf("irma4u.yaml"));
  ASSERT_EQ(irma.num_cables(), 4);
  EXPECT_EQ(irma.platform_mass_kg, 12.992);
  EXPECT_EQ(irma.cables[0].k_F_swivel_axis, Eigen::Vector3d::UnitX());
  EXPECT_EQ(irma.cables[1].k_F_swivel_axis, Eigen::Vector3d::UnitX());
  EXPECT_EQ(irma.cables[2].k_F_swivel_axis, -Eigen::Vector3d::UnitX());
  EXPECT_EQ(irma.cables[3].k_F_swivel_axis, -Eigen::Vector3d::UnitX());
  EXPECT_EQ(irma.cables[2].p_F_exit_m, Eigen::Vector3d(-1.066, 1.155, 1.839));
  EXPECT_EQ(irma.cables[0].pulley_radius_m, 0.03);
  // The self-calibration's sigmas: 0.01 m, 1 degree, 2 degrees, 10 N.
  const double deg = M_PI / 180.0;
  EXPECT_EQ(irma.sensors.encoder_sigma_m, 0.01);
  ASSERT_TRUE(irma.sensors.swivel_rad && irma.sensors.heading_rad && irma.sensors.inclinometer_rad &&
              irma.sensors.load_cell_N);
  EXPECT_NEAR(irma.sensors.swivel_rad->sigma(), 1.0 * deg, 1e-15);
  EXPECT_NEAR(irma.sensors.heading_rad->sigma(), 2.0 * deg, 1e-15);
  EXPECT_NEAR(irma.sensors.inclinometer_rad->sigma(), 2.0 * deg, 1e-15);
  EXPECT_NEAR(irma.sensors.load_cell_N->sigma(), 10.0, 1e-12);
  EXPECT_FALSE(irma.sensors.laser_m || irma.sensors.position || irma.sensors.tracker_sigma_m);
}

TEST(SpatialRobotFile, RoundTripKeepsEveryValue) {
  std::vector<SpatialRobot> robots;
  for (const char* file : kSpatialFiles) robots.push_back(LoadSpatialRobotFile(PathOf(file)));
  Rng rng(8);
  for (int m = 3; m <= 12; ++m) robots.push_back(testing::RandomSpatialRobot(rng, "random", m));
  // Every optional sensor, once.
  SpatialRobot all = robots[1];
  all.sensors.position = SpatialSensors::Position{RangedNoise{0.0003, 0.0001}, Eigen::Vector3d(0.01, -0.02, 0.03)};
  all.sensors.swivel_rad = RangedNoise{0.1 * M_PI / 180.0, 0.05 * M_PI / 180.0};
  all.sensors.heading_rad = RangedNoise{1.0 * M_PI / 180.0, 0.5 * M_PI / 180.0};
  all.sensors.load_cell_N = RangedNoise{3.0, 1.0};
  all.home_rpy_rad = Eigen::Vector3d(0.05, -0.1, 0.1);  // within IPAnema 1's feasible orientations at home
  robots.push_back(all);
  // A calibrated robot's initial lengths (identify --calibrated-robot).
  SpatialRobot calibrated = robots[0];
  for (int i = 0; i < calibrated.num_cables(); ++i) calibrated.cables[i].initial_length_m = 9.5 + 0.1 * i;
  robots.push_back(calibrated);
  // The platform's priors (the identification's and the Monte Carlo's).
  SpatialRobot weighed = robots[2];
  weighed.mass_sigma_kg = 0.0123;
  weighed.com_sigma_m = 0.0007;
  robots.push_back(weighed);
  for (const SpatialRobot& r : robots) {
    const std::string text = SpatialRobotToYaml(r);
    const SpatialRobot back = LoadSpatialRobotFromString(text, "roundtrip");
    EXPECT_EQ(SpatialRobotToYaml(back), text);
    EXPECT_EQ(back.name, r.name);
    ASSERT_EQ(back.num_cables(), r.num_cables());
    for (int i = 0; i < r.num_cables(); ++i) {
      EXPECT_EQ(back.cables[i].p_F_exit_m, r.cables[i].p_F_exit_m);
      EXPECT_EQ(back.cables[i].k_F_swivel_axis, r.cables[i].k_F_swivel_axis);
      EXPECT_EQ(back.cables[i].p_P_anchor_m, r.cables[i].p_P_anchor_m);
      EXPECT_EQ(back.cables[i].pulley_radius_m, r.cables[i].pulley_radius_m);
      EXPECT_EQ(back.cables[i].stiffness_N, r.cables[i].stiffness_N);
      EXPECT_EQ(back.cables[i].initial_length_m, r.cables[i].initial_length_m);
    }
    EXPECT_EQ(back.p_F_frame_min_m, r.p_F_frame_min_m);
    EXPECT_EQ(back.p_F_frame_max_m, r.p_F_frame_max_m);
    EXPECT_EQ(back.p_P_com_m, r.p_P_com_m);
    EXPECT_EQ(back.mass_sigma_kg, r.mass_sigma_kg);
    EXPECT_EQ(back.com_sigma_m, r.com_sigma_m);
    EXPECT_EQ(back.p_F_home_m, r.p_F_home_m);
    // Degrees are written to 12 significant digits (as the planar file's).
    EXPECT_LT((back.home_rpy_rad - r.home_rpy_rad).cwiseAbs().maxCoeff(), 1e-11);
    EXPECT_EQ(back.tension_min_N, r.tension_min_N);
    EXPECT_EQ(back.sensors.encoder_sigma_m, r.sensors.encoder_sigma_m);
    EXPECT_EQ(back.sensors.tracker_sigma_m, r.sensors.tracker_sigma_m);
    EXPECT_EQ(back.sensors.position.has_value(), r.sensors.position.has_value());
    if (r.sensors.position) {
      EXPECT_EQ(back.sensors.position->p_P_target_m, r.sensors.position->p_P_target_m);
    }
    EXPECT_EQ(back.sensors.load_cell_N.has_value(), r.sensors.load_cell_N.has_value());
  }
}

// An unnormalised axis is normalised on loading.
TEST(SpatialRobotFile, SwivelAxisIsNormalised) {
  const std::string yaml = Replace(TextOf("irma4u.yaml"), "swivel_axis: [1, 0, 0]", "swivel_axis: [2.5, 0, 0]");
  EXPECT_EQ(LoadSpatialRobotFromString(yaml, "x").cables[0].k_F_swivel_axis, Eigen::Vector3d::UnitX());
}

struct BadCase {
  const char* name;
  const char* from;
  const char* to;
  const char* at;        // text whose line the message must name (after the replacement)
  const char* expected;  // regex the message must match
  int occurrence = 1;    // of `at`, when the text occurs more than once
};

class BadSpatialRobotFile : public ::testing::TestWithParam<BadCase> {};

TEST_P(BadSpatialRobotFile, IsRejectedWithFileLineAndKey) {
  const BadCase& c = GetParam();
  const std::string yaml = Replace(TextOf("ipanema1.yaml"), c.from, c.to);
  const std::string message = SpatialLoadError(yaml);
  EXPECT_TRUE(std::regex_search(message, std::regex(c.expected))) << "message: " << message;
  EXPECT_EQ(message.rfind("bad.yaml:" + std::to_string(LineOf(yaml, c.at, c.occurrence)) + ": ", 0), 0u) << "message: " << message;
}

const char kCable1[] = "{exit: [-2.0, 1.5, 2.0], swivel_axis: [0, 0, 1], pulley_radius: 0.1, stiffness: 3.11e6}";

INSTANTIATE_TEST_SUITE_P(
    Rejections, BadSpatialRobotFile,
    ::testing::Values(
        BadCase{"ZeroSwivelAxis", kCable1, "{exit: [-2.0, 1.5, 2.0], swivel_axis: [0, 0, 0], pulley_radius: 0.1}",
                "swivel_axis: [0, 0, 0]", "cables\\[0\\]\\.swivel_axis: has zero length"},
        BadCase{"PositionTargetInMillimetres", "encoder: {sigma: 0.00005}",
                "encoder: {sigma: 0.00005}\n  position: {accuracy: 0.0003, repeatability: 0.0001, target: [0, 0, 20]}",
                "target: [0, 0, 20]",
                "sensors\\.position\\.target: 20 m from the platform frame's origin, more than the frame box's "
                "diagonal .*millimetres\\?"},
        // initial_length far from the cable's length at home: a typo, and millimetres.
        BadCase{"InitialLengthThatCannotReach", kCable1,
                "{exit: [-2.0, 1.5, 2.0], swivel_axis: [0, 0, 1], pulley_radius: 0.1, initial_length: 1.0}",
                "initial_length: 1.0",
                "cables\\[0\\]\\.initial_length: 1 m, but the cable runs [0-9.]+ m from its exit to its anchor at "
                "the home equilibrium \\(it could not reach\\)"},
        BadCase{"InitialLengthInMillimetres", kCable1,
                "{exit: [-2.0, 1.5, 2.0], swivel_axis: [0, 0, 1], pulley_radius: 0.1, initial_length: 2500}",
                "initial_length: 2500", "cables\\[0\\]\\.initial_length: 2500 m, .*\\(it would hang slack\\).* in metres"},
        BadCase{"ExitOutsideTheFrame", "exit: [-2.0, 1.5, 2.0]", "exit: [-2.2, 1.5, 2.0]", "exit: [-2.2",
                "cables\\[0\\]\\.exit: \\(-2\\.2, 1\\.5, 2\\) m is outside the frame box .* by more than 0\\.1 m"},
        BadCase{"ExitAboveTheFrame", "exit: [2.0, 1.5, 2.0]", "exit: [2.0, 1.5, 2.2]", "exit: [2.0, 1.5, 2.2]",
                "cables\\[1\\]\\.exit: .* outside the frame box"},
        BadCase{"UnknownKey", "gravity: 9.81", "gravity: 9.81\ncolour: red", "colour", "colour: unknown key"},
        BadCase{"UnknownCableKey", "pulley_radius: 0.1, stiffness: 3.11e6}", "pulley_radius: 0.1, side: left}",
                "side: left", "cables\\[0\\]\\.side: unknown key"},
        BadCase{"WrongType", "mass: 25.0", "mass: heavy", "mass: heavy",
                "platform\\.mass: must be a finite number \\(got 'heavy'\\)"},
        BadCase{"QuotedNumber", "mass: 25.0", "mass: 25.0\n  mass_sigma: \"0.12\"", "mass_sigma",
                "platform\\.mass_sigma: must be a number, not a quoted string \\(got \"0\\.12\"\\)"},
        BadCase{"ListForANumber", "mass: 25.0", "mass: 25.0\n  com_sigma: [0.001]", "com_sigma",
                "platform\\.com_sigma: must be a number \\(got a list\\)"},
        BadCase{"NothingForANumber", "mass: 25.0", "mass: 25.0\n  com_sigma:", "com_sigma",
                "platform\\.com_sigma: must be a number \\(got nothing\\)"},
        // A key left empty is named at its own line, not at the next key's (yaml-cpp marks the
        // empty value there).
        BadCase{"NothingForAVector", "com: [0.0, 0.0, 0.0]", "com:", "com:",
                "platform\\.com: must be a list of three numbers \\[x, y, z\\]"},
        BadCase{"NothingForAMapping", "frame: {min: [-2.0, -1.5, 0.0], max: [2.0, 1.5, 2.0]}", "frame:", "frame:",
                "frame: must be a mapping"},
        BadCase{"NothingForACablesVector",
                "  - {exit: [-2.0, -1.5, 2.0], swivel_axis: [0, 0, 1], pulley_radius: 0.1, stiffness: 3.11e6}",
                "  - exit:\n    swivel_axis: [0, 0, 1]\n    pulley_radius: 0.1", "- exit:",
                "cables\\[3\\]\\.exit: must be a list of three numbers"},
        BadCase{"WrongVectorSize", "home: [0.0, 0.0, 1.0]", "home: [0.0, 1.0]", "home: [0.0, 1.0]",
                "home: must be a list of three numbers \\[x, y, z\\]"},
        BadCase{"MissingKey", "tension: {min: 10.0, max: 720.0}", "", "name: ipanema1", "tension: missing"},
        BadCase{"NonPositiveMass", "mass: 25.0", "mass: 0", "mass: 0", "platform\\.mass: must be > 0 \\(got 0\\)"},
        BadCase{"MassSigmaAboveHalfTheMass", "mass: 25.0", "mass: 25.0\n  mass_sigma: 13", "mass_sigma",
                "platform\\.mass_sigma: must be at most 12\\.5 kg \\(half the mass\\) \\(got 13\\)"},
        BadCase{"MassSigmaZero", "mass: 25.0", "mass: 25.0\n  mass_sigma: 0", "mass_sigma",
                "platform\\.mass_sigma: must be > 0 \\(got 0\\)"},
        BadCase{"ComSigmaInMillimetres", "mass: 25.0", "mass: 25.0\n  com_sigma: 5", "com_sigma",
                "platform\\.com_sigma: must be at most 0\\.1 m \\(got 5\\)"},
        BadCase{"TensionMinAtMax", "tension: {min: 10.0, max: 720.0}", "tension: {min: 720.0, max: 720.0}",
                "tension: {", "tension: min must be < max"},
        BadCase{"TensionMinZero", "tension: {min: 10.0, max: 720.0}", "tension: {min: 0.0, max: 720.0}", "tension: {",
                "tension\\.min: must be > 0 \\(got 0\\): a slack cable sags"},
        BadCase{"NegativeRadius", kCable1, "{exit: [-2.0, 1.5, 2.0], swivel_axis: [0, 0, 1], pulley_radius: -0.1}",
                "pulley_radius: -0.1", "cables\\[0\\]\\.pulley_radius: must be >= 0"},
        BadCase{"RadiusInMillimetres", kCable1, "{exit: [-2.0, 1.5, 2.0], swivel_axis: [0, 0, 1], pulley_radius: 100}",
                "pulley_radius: 100", "cables\\[0\\]\\.pulley_radius: 100 m is more than a quarter"},
        BadCase{"NegativeStiffness", "stiffness: 3.11e6}", "stiffness: -3.11e6}", "stiffness: -3.11e6",
                "cables\\[0\\]\\.stiffness: must be > 0"},
        BadCase{"StiffnessInKilonewtons", "stiffness: 3.11e6}", "stiffness: 3110}", "stiffness: 3110",
                "cables\\[0\\]\\.stiffness: .* more than 10 % at tension\\.max"},
        BadCase{"AnchorCount", "    - [-0.06, -0.06, 0.0]\ncables:", "cables:", "    - [-0.06, 0.06, 0.0]",
                "platform\\.anchors: needs one anchor per cable \\(8\\), got 7"},
        BadCase{"CoincidentExits", "exit: [-2.0, -1.5, 0.0]", "exit: [-2.0, 1.5, 0.0]", "exit: [-2.0, 1.5, 0.0]",
                "cables\\[7\\]\\.exit: coincides with the exit point of cable 5 \\(cables\\[4\\]\\)", 2},
        BadCase{"HomeOutsideTheFrame", "home: [0.0, 0.0, 1.0]", "home: [0.0, 0.0, 2.5]", "home: [",
                "home: \\(0, 0, 2\\.5\\) m is outside the frame box"},
        BadCase{"HomeWithinTheMargin", "home: [0.0, 0.0, 1.0]", "home: [0.0, 0.0, 0.02]", "home: [",
                "home: the platform's anchors\\[0\\] is at .* within limits\\.margin"},
        BadCase{"HomeTiltBeyondTheLimit", "home_rpy_deg: [0, 0, 0]", "home_rpy_deg: [25, 25, 0]", "home_rpy_deg",
                "home_rpy_deg: the platform's tilt at home, 34\\.77[0-9]* degrees, is beyond limits\\.tilt_max_deg \\(30"},
        BadCase{"HomeGeometryInvalid", kCable1,
                "{exit: [-2.0, 1.5, 2.0], swivel_axis: [1.94, -1.44, -1.0], pulley_radius: 0.1}", "home: [",
                "home: cable 1 \\(cables\\[0\\]\\) has invalid geometry at home: swivel_axis \\(its anchor is on the swivel axis\\)"},
        BadCase{"TiltLimit", "tilt_max_deg: 30", "tilt_max_deg: 90", "tilt_max_deg",
                "limits\\.tilt_max_deg: must be in \\(0, 89\\) degrees"},
        BadCase{"FrameInsideOut", "max: [2.0, 1.5, 2.0]", "max: [2.0, -1.5, 2.0]", "frame:",
                "frame\\.max: .* must exceed frame\\.min"},
        BadCase{"EncoderSigmaZero", "encoder: {sigma: 0.00005}", "encoder: {sigma: 0}", "encoder:",
                "sensors\\.encoder\\.sigma: must be from 1e-06 to 1 m"},
        BadCase{"InclinometerRangeInRadiansAsDegrees", "accuracy_deg: 0.1,", "accuracy_deg: 45,", "accuracy_deg: 45",
                "sensors\\.inclinometer\\.accuracy_deg: must be from 0 to 30 degrees, a \\+- range taken as 3 sigma \\(got 45\\): units\\?"},
        BadCase{"MissingEncoder", "  encoder: {sigma: 0.00005}                        # m, one standard deviation\n", "",
                "inclinometer: {", "sensors\\.encoder: missing"},
        BadCase{"UnknownKind", "kind: spatial", "kind: conical", "kind:",
                "kind: must be 'planar' or 'spatial' \\(got 'conical'\\)"},
        BadCase{"PlanarKind", "kind: spatial", "kind: planar", "kind:",
                "kind: a planar robot \\(kind: planar\\): this reads spatial robots only \\(kind: spatial\\)"},
        BadCase{"SecondDocument", "home_rpy_deg: [0, 0, 0]", "home_rpy_deg: [0, 0, 0]\n---\nname: other", "---",
                "a second YAML document"}),
    [](const ::testing::TestParamInfo<BadCase>& info) { return std::string(info.param.name); });

// Cable counts and collinear anchors, written from a robot whose cables or anchors were
// changed: the message names the key and its line in the written text.
TEST(SpatialRobotFile, CableCountsAndCollinearAnchorsAreRefused) {
  const SpatialRobot ipanema = LoadSpatialRobotFile(PathOf("ipanema1.yaml"));
  const auto message_of = [](const SpatialRobot& r) {
    const std::string yaml = SpatialRobotToYaml(r);
    return std::make_pair(SpatialLoadError(yaml), yaml);
  };
  SpatialRobot two = ipanema;
  two.cables.resize(2);
  auto [m2, y2] = message_of(two);
  EXPECT_EQ(m2.rfind("bad.yaml:" + std::to_string(LineOf(y2, "cables:") + 1) + ": cables: must list 3 to 12 cables (got 2)", 0),
            0u)
      << m2;
  SpatialRobot thirteen = ipanema;
  for (int k = 0; k < 5; ++k) {
    SpatialCable c = ipanema.cables[k];
    c.p_F_exit_m.z() = 1.0 + 0.1 * k;  // distinct exit points on the posts
    thirteen.cables.push_back(c);
  }
  auto [m13, y13] = message_of(thirteen);
  EXPECT_NE(m13.find(": cables: must list 3 to 12 cables (got 13)"), std::string::npos) << m13;
  EXPECT_EQ(m13.rfind("bad.yaml:", 0), 0u) << m13;

  const SpatialRobot irma = LoadSpatialRobotFile(PathOf("irma4u.yaml"));
  SpatialRobot line = irma;
  for (int i = 0; i < 4; ++i) line.cables[i].p_P_anchor_m = Eigen::Vector3d(-0.075 + 0.05 * i, 0.02 * i, 0.266);
  auto [ml, yl] = message_of(line);
  EXPECT_EQ(ml.rfind("bad.yaml:" + std::to_string(LineOf(yl, "anchors:")) + ": platform.anchors: all anchors lie on one line",
                     0),
            0u)
      << ml;
  SpatialRobot point = irma;
  for (SpatialCable& c : point.cables) c.p_P_anchor_m = Eigen::Vector3d(0.0, 0.0, 0.266);
  EXPECT_NE(message_of(point).first.find("platform.anchors: all anchors lie on one line"), std::string::npos);
  // Three anchors off one line by a millimetre span a plane: past the line test (the statics
  // then refuse the home: a platform on a line of anchors hangs tilted 43 degrees).
  SpatialRobot plane = irma;
  for (int i = 0; i < 4; ++i) plane.cables[i].p_P_anchor_m = Eigen::Vector3d(-0.075 + 0.05 * i, i == 2 ? 0.001 : 0.0, 0.266);
  const std::string plane_message = message_of(plane).first;
  EXPECT_EQ(plane_message.find("one line"), std::string::npos) << plane_message;
  EXPECT_NE(plane_message.find(": home: the home pose (0, 0, 1) m at roll, pitch, yaw (0, 0, 0) degrees (home_rpy_deg) is not in the feasible workspace: tilt_limit"),
            std::string::npos)
      << plane_message;
}

// A home where no tensions balance the platform (a new user's 6-cable robot, home pushed 1.3 m
// to one side): the message gives the least-squares tensions and names the cables that would
// have to push, where before it said only no_equilibrium.
TEST(SpatialRobotFile, AHomeWithoutEquilibriumNamesTheCablesThatWouldPush) {
  const std::string text = testing::SixMixedRobotYaml("[1.3, 0.0, 1.2]");
  const int home_line = LineOf(text, "home:");
  std::string message;
  try {
    LoadSpatialRobotFromString(text, "six.yaml");
  } catch (const InputError& e) {
    message = e.what();
  }
  EXPECT_NE(message.find("six.yaml:" + std::to_string(home_line) + ": home: the home pose (1.3, 0, 1.2) m"),
            std::string::npos)
      << message;
  EXPECT_NE(message.find("not in the feasible workspace: no_equilibrium"), std::string::npos) << message;
  const std::size_t at = message.find("The least-squares tensions that balance it are (");
  ASSERT_NE(at, std::string::npos) << message;
  EXPECT_NE(message.find(" would have to push", at), std::string::npos) << message;
  // The cables named are those whose least-squares tension is negative, as printed.
  const std::size_t open = message.find('(', at), close = message.find(')', open);
  std::vector<double> t;
  std::stringstream list(message.substr(open + 1, close - open - 1));
  for (std::string cell; std::getline(list, cell, ',');) t.push_back(std::stod(cell));
  ASSERT_EQ(t.size(), 6u) << message;
  std::string negative;
  for (int i = 0; i < 6; ++i) {
    if (t[i] < 0.0) negative += (negative.empty() ? "" : ", ") + std::to_string(i + 1);
  }
  ASSERT_FALSE(negative.empty()) << message;
  EXPECT_NE(message.find(negative + " would have to push"), std::string::npos) << message;
}

// The README's spatial file (section "Spatial robots") is a valid robot file with every sensor.
TEST(SpatialRobotFile, ReadmeExampleLoads) {
  const std::string yaml = testing::ReadmeYamlAfter("**The file** (`kind: spatial`");
  ASSERT_FALSE(yaml.empty()) << "no yaml block after the heading in README.md";
  EXPECT_EQ(SpatialLoadError(yaml), "");
  const SpatialRobot r = LoadSpatialRobotFromString(yaml, "README.md");
  ASSERT_EQ(r.num_cables(), 3);
  EXPECT_EQ(r.cables[0].stiffness_N, 1.0e5);
  EXPECT_FALSE(r.cables[1].stiffness_N);
  const SpatialSensors& s = r.sensors;
  EXPECT_TRUE(s.inclinometer_rad && s.laser_m && s.position && s.swivel_rad && s.heading_rad && s.load_cell_N &&
              s.tracker_sigma_m);
  // Accuracy and repeatability combine as the planar file's: hypot / 3.
  EXPECT_NEAR(s.laser_m->sigma(), std::hypot(0.006, 0.0015) / 3.0, 1e-18);
  EXPECT_NEAR(s.heading_rad->sigma(), std::hypot(1.0, 0.5) / 3.0 * M_PI / 180.0, 1e-16);
}

// Each loader refuses the other's files with one clear message naming the file and `kind`; the
// planar loader accepts an explicit `kind: planar`.
TEST(SpatialRobotFile, EachLoaderRefusesTheOtherKind) {
  for (const char* file : kSpatialFiles) {
    const std::string path = PathOf(file);
    try {
      LoadRobotFile(path);
      FAIL() << "the planar loader loaded " << file;
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()), path + ":" + std::to_string(LineOf(TextOf(file), "kind: spatial")) +
                                           ": kind: a spatial robot: this command serves planar robots only so far");
      EXPECT_EQ(e.key(), "kind");
    }
  }
  for (const char* file : kPlanarFiles) {
    const std::string path = PathOf(file);
    try {
      LoadSpatialRobotFile(path);
      FAIL() << "the spatial loader loaded " << file;
    } catch (const InputError& e) {
      EXPECT_TRUE(std::regex_search(e.what(), std::regex("^" + path + ":[0-9]+: kind: a planar robot \\(no kind\\)")))
          << e.what();
    }
  }
  const std::string wang = TextOf("wang2022.yaml");
  const Robot explicit_planar = LoadRobotFromString(Replace(wang, "name: wang2022", "name: wang2022\nkind: planar"), "k");
  EXPECT_EQ(RobotToYaml(explicit_planar), RobotToYaml(BuiltinRobot()));
  try {
    LoadRobotFromString(Replace(wang, "name: wang2022", "name: wang2022\nkind: conical"), "k.yaml");
    FAIL() << "an unknown kind loaded";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), "k.yaml:7: kind: must be 'planar' or 'spatial' (got 'conical')");
  }
  EXPECT_EQ(RobotKindOfText(Replace(wang, "name: wang2022", "name: wang2022\nkind: planar"), "k"), RobotKind::kPlanar);
  EXPECT_THROW(RobotKindOfText("kind: [spatial]\n", "k"), InputError);
  EXPECT_THROW(RobotKindOfFile("/nonexistent/robot.yaml"), InputError);
}

// A planar command given a spatial file names the file's own mistake first, as the spatial
// loader would, and only a valid spatial file gets "serves planar robots only" (a new user's
// trial: 23 broken spatial files got that one line). A spatial file without `kind` is told to
// add it rather than have its first spatial key called unknown.
TEST(SpatialRobotFile, PlanarLoaderNamesASpatialFilesOwnMistakesAndAMissingKind) {
  const std::string ipanema = TextOf("ipanema1.yaml");
  const std::string broken = Replace(ipanema, "swivel_axis: [0, 0, 1]", "swivel_axis: [0, 0, 0]");
  const std::string spatial_error = SpatialLoadError(broken);
  ASSERT_NE(spatial_error.find("swivel_axis: has zero length"), std::string::npos) << spatial_error;
  try {
    LoadRobotFromString(broken, "bad.yaml");
    FAIL() << "the planar loader loaded a spatial file";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), spatial_error);
  }
  const std::string no_kind = Replace(ipanema, "kind: spatial\n", "");
  try {
    LoadRobotFromString(no_kind, "nokind.yaml");
    FAIL() << "the planar loader loaded a spatial file without kind";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(": kind: missing: the file has a spatial robot's keys"),
              std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("add kind: spatial"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace cablecal
