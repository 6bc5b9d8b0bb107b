// Robot file parsing and validation (format: README, "Robot file").
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdio>
#include <set>

#include "common/error.h"
#include "common/format.h"
#include "common/yaml_writer.h"
#include "model/robot.h"
#include "model/sensor_model.h"
#include "model/statics.h"
#include "model/yaml_reader.h"

namespace cablecal {
namespace {

using internal::Reader;

// The node of a key of the sensors block ("sensors.laser" or "sensors.laser.accuracy"), for the
// line of a message.
YAML::Node SensorsNode(const YAML::Node& sensors, const std::string& key) {
  const std::string rest = key.substr(key.find('.') + 1);  // after "sensors."
  const std::size_t dot = rest.find('.');
  const YAML::Node sensor = sensors[rest.substr(0, dot)];
  return dot == std::string::npos ? sensor : sensor[rest.substr(dot + 1)];
}

// Long (~240 lines) for a reason: the robot file's keys in the file's order, each read,
// range-checked and placed once, so that the format can be read against the README's
// robot file section line by line.
Robot Parse(const YAML::Node& root, const Reader& rd) {
  Robot robot;
  robot.source = rd.source();
  // `kind` absent or `planar`: this loader's file. A spatial robot's file has keys of its own,
  // so it is refused by its kind before any of them is called unknown.
  const std::string kind = internal::KindOf(root, rd);
  if (kind == "spatial") {
    // Its own mistakes first (a new user's trial: 23 broken spatial files all got only this line).
    internal::CheckSpatialRobotDocument(root, rd);
    rd.Fail(root["kind"], "kind", "a spatial robot: this command serves planar robots only so far");
  }
  if (kind.empty() && internal::LooksSpatial(root)) {
    rd.Fail(root, "kind",
            "missing: the file has a spatial robot's keys (frame min/max, home_rpy_deg or a cable's swivel_axis); "
            "add kind: spatial (without kind a file is a planar robot's)");
  }
  if (!kind.empty() && kind != "planar") {
    rd.Fail(root["kind"], "kind",
            "must be 'planar' or 'spatial' (got '" + PrintableText(kind.substr(0, 40)) + "')");
  }
  rd.ExpectMap(root, "", {"name", "gravity", "frame", "platform", "cables", "tension", "limits", "home", "sensors"},
               {"true_poses", "home_theta_deg", "kind"});

  robot.name = rd.String(root["name"], "name");
  if (robot.name.empty()) rd.Fail(root["name"], "name", "must not be empty");
  robot.gravity_mps2 = rd.Number(root, "", "gravity");
  rd.Positive(root["gravity"], "gravity", robot.gravity_mps2);
  rd.AtMost(root["gravity"], "gravity", robot.gravity_mps2, kMaxGravity_mps2, "m/s^2");

  const YAML::Node frame = root["frame"];
  rd.ExpectMap(frame, "frame", {"width", "height"}, {});
  robot.frame_width_m = rd.Number(frame, "frame", "width");
  rd.Positive(frame["width"], "frame.width", robot.frame_width_m);
  rd.AtMost(frame["width"], "frame.width", robot.frame_width_m, kMaxFrameSide_m, "m");
  robot.frame_height_m = rd.Number(frame, "frame", "height");
  rd.Positive(frame["height"], "frame.height", robot.frame_height_m);
  rd.AtMost(frame["height"], "frame.height", robot.frame_height_m, kMaxFrameSide_m, "m");

  const YAML::Node platform = root["platform"];
  rd.ExpectMap(platform, "platform", {"mass", "com", "anchors"}, {"com_sigma"});
  robot.platform_mass_kg = rd.Number(platform, "platform", "mass");
  rd.Positive(platform["mass"], "platform.mass", robot.platform_mass_kg);
  rd.AtMost(platform["mass"], "platform.mass", robot.platform_mass_kg, kMaxPlatformMass_kg, "kg");
  robot.p_P_com_m = rd.Vector2(platform["com"], "platform.com");
  if (platform["com_sigma"]) {
    robot.com_sigma_m = rd.Number(platform, "platform", "com_sigma");
    rd.Positive(platform["com_sigma"], "platform.com_sigma", *robot.com_sigma_m);
    // As a sensor's sigma (model/sensor_model.h): below a micrometre the equilibrium row's weight
    // overflows Levenberg-Marquardt (1e-300 gave a non-finite residual at the start).
    rd.AtLeast(platform["com_sigma"], "platform.com_sigma", *robot.com_sigma_m, kMinSensorSigma_m, "m");
    rd.AtMost(platform["com_sigma"], "platform.com_sigma", *robot.com_sigma_m, 0.1, "m");
  }
  const YAML::Node anchors = platform["anchors"];
  if (!anchors.IsSequence()) rd.Fail(anchors, "platform.anchors", "must be a list of [x, z] points");

  const YAML::Node cables = root["cables"];
  if (!cables.IsSequence()) rd.Fail(cables, "cables", "must be a list of cables");
  if (cables.size() < static_cast<std::size_t>(kMinCables) || cables.size() > static_cast<std::size_t>(kMaxCables)) {
    rd.Fail(cables, "cables", "must list " + std::to_string(kMinCables) + " to " + std::to_string(kMaxCables) +
                                  " cables (got " + std::to_string(cables.size()) + ")");
  }
  if (anchors.size() != cables.size()) {
    rd.Fail(anchors, "platform.anchors", "needs one anchor per cable (" + std::to_string(cables.size()) +
                                             "), got " + std::to_string(anchors.size()));
  }
  for (std::size_t i = 0; i < cables.size(); ++i) {
    const std::string key = "cables[" + std::to_string(i) + "]";
    const YAML::Node c = cables[i];
    rd.ExpectMap(c, key, {"exit", "pulley_radius", "side"}, {"initial_length", "wrap", "stiffness"});
    Cable cable;
    if (c["wrap"]) {
      const std::string wrap = rd.String(c["wrap"], key + ".wrap");
      if (wrap == "over") {
        cable.wrap = PulleyWrap::kOver;
      } else if (wrap == "under") {
        cable.wrap = PulleyWrap::kUnder;
      } else {
        rd.Fail(c["wrap"], key + ".wrap", "must be 'over' or 'under' (got '" + wrap + "')");
      }
    }
    cable.p_F_exit_m = rd.Vector2(c["exit"], key + ".exit");
    // The exit point is on the frame: a point well outside it (a typo, or mm for m) would make
    // a robot the workspace and the design still accept. A pulley the cable wraps over hangs
    // above the floor (z > 0); one it wraps under may sit on the floor's edge of the frame.
    constexpr double kOnFrameTol_m = kExitOffFrameTolerance_m;
    const bool under = cable.wrap == PulleyWrap::kUnder;
    const bool z_low_ok = under ? cable.p_F_exit_m.y() >= -kOnFrameTol_m : cable.p_F_exit_m.y() > 0.0;
    if (!(cable.p_F_exit_m.x() >= -kOnFrameTol_m && cable.p_F_exit_m.x() <= robot.frame_width_m + kOnFrameTol_m &&
          z_low_ok && cable.p_F_exit_m.y() <= robot.frame_height_m + kOnFrameTol_m)) {
      rd.Fail(c["exit"], key + ".exit",
              "(" + FormatDouble(cable.p_F_exit_m.x()) + ", " + FormatDouble(cable.p_F_exit_m.y()) +
                  ") m is outside the frame [0, " + FormatDouble(robot.frame_width_m) + "] x " +
                  (under ? "[0, " : "(0, ") + FormatDouble(robot.frame_height_m) + "] m by more than " +
                  FormatDouble(kOnFrameTol_m) + " m: exit points are on the frame");
    }
    cable.pulley_radius_m = rd.Number(c, key, "pulley_radius");
    rd.Positive(c["pulley_radius"], key + ".pulley_radius", cable.pulley_radius_m);
    if (cable.pulley_radius_m > 0.25 * std::min(robot.frame_width_m, robot.frame_height_m)) {
      rd.Fail(c["pulley_radius"], key + ".pulley_radius",
              FormatDouble(cable.pulley_radius_m) + " m is more than a quarter of the frame: radii are in metres "
                                                    "(25 mm is 0.025)");
    }
    const std::string side = rd.String(c["side"], key + ".side");
    if (side == "left") {
      cable.side = PulleySide::kLeft;
    } else if (side == "right") {
      cable.side = PulleySide::kRight;
    } else {
      rd.Fail(c["side"], key + ".side", "must be 'left' or 'right' (got '" + side + "')");
    }
    if (c["initial_length"]) {
      cable.initial_length_m = rd.Number(c, key, "initial_length");
      rd.Positive(c["initial_length"], key + ".initial_length", *cable.initial_length_m);
    }
    if (c["stiffness"]) {
      cable.stiffness_N = rd.Number(c, key, "stiffness");
      rd.Positive(c["stiffness"], key + ".stiffness", *cable.stiffness_N);
    }
    cable.p_P_anchor_m = rd.Vector2(anchors[i], "platform.anchors[" + std::to_string(i) + "]");
    robot.cables.push_back(cable);
  }
  // Two cables suspend the platform from either side: one runs up its post on the pulley's
  // outer (-x) side on the left, the other mirrored on the right. Two of one side, or the
  // "left" one to the right of the other, would run the cables through the frame.
  if (robot.cables.size() == 2) {
    const Cable& a = robot.cables[0];
    const Cable& b = robot.cables[1];
    if (a.side == b.side) {
      rd.Fail(cables[1]["side"], "cables[1].side",
              std::string("both cables are on their pulleys' ") + (a.side == PulleySide::kLeft ? "left" : "right") +
                  " side: one suspends the platform from the left post (side: left), the other from the right");
    }
    const Cable& left = a.side == PulleySide::kLeft ? a : b;
    const Cable& right = a.side == PulleySide::kLeft ? b : a;
    if (!(left.p_F_exit_m.x() < right.p_F_exit_m.x())) {
      rd.Fail(cables[a.side == PulleySide::kLeft ? 0 : 1]["exit"], a.side == PulleySide::kLeft ? "cables[0].exit" : "cables[1].exit",
              "the cable with side: left must leave from the left of the one with side: right");
    }
  }
  // Anchors: two cables may share one (a common design with 3 or more cables) as long as
  // the lengths still fix the orientation, which takes two distinct anchor points. With 2
  // cables that means the two differ; with more, that not all of them are one point.
  constexpr double kSamePoint_m = 1e-6;
  const auto same_anchor = [&](std::size_t i, std::size_t j) {
    return (robot.cables[i].p_P_anchor_m - robot.cables[j].p_P_anchor_m).norm() < kSamePoint_m;
  };
  if (robot.cables.size() == 2 && same_anchor(0, 1)) {
    rd.Fail(anchors[1], "platform.anchors[1]", "coincides with anchors[0]: the platform's orientation would be undetermined");
  }
  bool all_one_anchor = true;
  for (std::size_t j = 1; j < robot.cables.size(); ++j) all_one_anchor = all_one_anchor && same_anchor(0, j);
  if (robot.cables.size() > 2 && all_one_anchor) {
    rd.Fail(anchors, "platform.anchors",
            "all anchors are one point: the platform's orientation would be undetermined (at least two must differ)");
  }
  for (std::size_t i = 0; i < robot.cables.size(); ++i) {
    for (std::size_t j = i + 1; j < robot.cables.size(); ++j) {
      if ((robot.cables[i].p_F_exit_m - robot.cables[j].p_F_exit_m).norm() < kSamePoint_m) {
        rd.Fail(cables[j]["exit"], "cables[" + std::to_string(j) + "].exit",
                "coincides with the exit point of cable " + std::to_string(i));
      }
    }
  }

  const YAML::Node tension = root["tension"];
  rd.ExpectMap(tension, "tension", {"min", "max"}, {});
  robot.tension_min_N = rd.Number(tension, "tension", "min");
  rd.NonNegative(tension["min"], "tension.min", robot.tension_min_N);
  robot.tension_max_N = rd.Number(tension, "tension", "max");
  if (!(robot.tension_min_N < robot.tension_max_N)) {
    rd.Fail(tension, "tension", "min must be < max (got min " + FormatDouble(robot.tension_min_N) +
                                    " N, max " + FormatDouble(robot.tension_max_N) + " N)");
  }
  // The same bound as the spatial file's (README, "Spatial robots").
  for (std::size_t i = 0; i < robot.cables.size(); ++i) {
    internal::CheckCableStiffness(rd, cables, i, robot.cables[i].stiffness_N, robot.tension_max_N);
  }

  const YAML::Node limits = root["limits"];
  rd.ExpectMap(limits, "limits", {"theta_max_deg", "laser_range", "margin"}, {});
  const double theta_max_deg = rd.Number(limits, "limits", "theta_max_deg");
  if (!(theta_max_deg > 0.0 && theta_max_deg < 89.0)) {
    rd.Fail(limits["theta_max_deg"], "limits.theta_max_deg",
            "must be in (0, 89) degrees (got " + FormatDouble(theta_max_deg) + ")");
  }
  robot.theta_max_rad = theta_max_deg * kDegToRad;
  robot.laser_range_m = rd.Number(limits, "limits", "laser_range");
  rd.Positive(limits["laser_range"], "limits.laser_range", robot.laser_range_m);
  robot.margin_m = rd.Number(limits, "limits", "margin");
  rd.NonNegative(limits["margin"], "limits.margin", robot.margin_m);

  const YAML::Node sensors = root["sensors"];
  rd.ExpectMap(sensors, "sensors", {"laser", "inclinometer", "encoder"}, {"tracker"});
  rd.ExpectMap(sensors["laser"], "sensors.laser", {"accuracy", "repeatability"}, {"offset"});
  rd.ExpectMap(sensors["inclinometer"], "sensors.inclinometer", {"accuracy_deg", "repeatability_deg"},
               {"offset_deg", "sec_coefficient_deg"});
  rd.ExpectMap(sensors["encoder"], "sensors.encoder", {"sigma"}, {});
  SensorNoise& s = robot.sensors;
  s.laser_accuracy_m = rd.Number(sensors["laser"], "sensors.laser", "accuracy");
  s.laser_repeatability_m = rd.Number(sensors["laser"], "sensors.laser", "repeatability");
  const double inc_acc_deg = rd.Number(sensors["inclinometer"], "sensors.inclinometer", "accuracy_deg");
  const double inc_rep_deg = rd.Number(sensors["inclinometer"], "sensors.inclinometer", "repeatability_deg");
  s.encoder_sigma_m = rd.Number(sensors["encoder"], "sensors.encoder", "sigma");
  if (sensors["tracker"]) {
    rd.ExpectMap(sensors["tracker"], "sensors.tracker", {"sigma"}, {});
    s.tracker_sigma_m = rd.Number(sensors["tracker"], "sensors.tracker", "sigma");
  }
  if (root["true_poses"] && !root["true_poses"].IsSequence()) {
    rd.Fail(root["true_poses"], "true_poses", "must be a list (it is written by cablecal simulate --truth-out)");
  }
  s.inclinometer_accuracy_rad = inc_acc_deg * kDegToRad;
  s.inclinometer_repeatability_rad = inc_rep_deg * kDegToRad;
  // Every sigma and range within the bounds of model/sensor_model.h, named at its own line.
  if (const std::optional<SensorModelProblem> problem = CheckSensorNoise(s)) {
    rd.Fail(SensorsNode(sensors, problem->key), problem->key, problem->problem);
  }
  // The systematic errors a bench test fitted (cablecal sensors fit); absent means none.
  SystematicSensorErrors& sys = s.systematic;
  if (sensors["laser"]["offset"]) sys.laser_offset_m = rd.Number(sensors["laser"], "sensors.laser", "offset");
  if (sensors["inclinometer"]["offset_deg"]) {
    sys.inclinometer_offset_rad = rd.Number(sensors["inclinometer"], "sensors.inclinometer", "offset_deg") * kDegToRad;
  }
  if (sensors["inclinometer"]["sec_coefficient_deg"]) {
    sys.inclinometer_sec_coefficient_rad =
        rd.Number(sensors["inclinometer"], "sensors.inclinometer", "sec_coefficient_deg") * kDegToRad;
  }
  if (const std::optional<SensorModelProblem> problem = CheckSystematicErrors(sys, robot.theta_max_rad)) {
    const std::string name = problem->key.substr(problem->key.rfind('.') + 1);
    const YAML::Node sensor = sensors[problem->key.find(".laser.") != std::string::npos ? "laser" : "inclinometer"];
    rd.Fail(sensor[name], problem->key, problem->problem);
  }

  robot.p_F_home_m = rd.Vector2(root["home"], "home");
  double home_theta_deg = 0.0;  // as typed, for messages
  if (root["home_theta_deg"]) {
    if (!robot.theta_is_free()) {
      rd.Fail(root["home_theta_deg"], "home_theta_deg",
              "is for robots with 3 or more cables: with 2 cables the equilibrium decides theta at home");
    }
    const double theta_deg = rd.Number(root, "", "home_theta_deg");
    if (!(std::abs(theta_deg) <= theta_max_deg)) {
      rd.Fail(root["home_theta_deg"], "home_theta_deg",
              FormatDouble(theta_deg) + " degrees is beyond limits.theta_max_deg (" + FormatDouble(theta_max_deg) +
                  ")");
    }
    robot.home_theta_rad = theta_deg * kDegToRad;
    home_theta_deg = theta_deg;
  }
  const PoseEvaluation home = EvaluateHome(robot);
  if (!home.feasible()) {
    const std::string pose = "(" + FormatDouble(robot.p_F_home_m.x()) + ", " + FormatDouble(robot.p_F_home_m.y()) +
                             ") m" +
                             (robot.theta_is_free() ? " at theta " + FormatDouble(home_theta_deg) + " degrees (home_theta_deg)"
                                                    : "");
    std::string hint;
    if (robot.theta_is_free() && home.feasibility != Feasibility::kOutsideFrame &&
        home.feasibility != Feasibility::kLaserRange) {
      // The orientations that are feasible at this (x, z): what to type, in whole scan steps.
      const ThetaScan scan = ScanTheta(robot, robot.p_F_home_m.x(), robot.p_F_home_m.y());
      const auto degrees = [](double rad) { return 0.5 * std::round(rad / kThetaScanStep_rad); };
      hint = scan.feasible_count > 0
                 ? "; feasible home_theta_deg at this (x, z): " + FormatDouble(degrees(scan.theta_min_rad)) + " to " +
                       FormatDouble(degrees(scan.theta_max_rad)) + " (0.5-degree scan)"
                 : "; no orientation is feasible at this (x, z) (0.5-degree scan): move home";
    }
    const YAML::Node at = robot.theta_is_free() && root["home_theta_deg"] ? root["home_theta_deg"] : root["home"];
    rd.Fail(at, "home", pose + " is not in the feasible workspace: " + ToString(home.feasibility) + hint);
  }
  return robot;
}

}  // namespace

// Degrees for the file, as the spatial loader writes them too (model/yaml_reader.h).
static double Degrees(double rad) { return internal::DegreesForFile(rad); }

Robot LoadRobotFromString(const std::string& yaml_text, const std::string& source) {
  return internal::ParseRobotText(yaml_text, source, Parse);
}

Robot LoadRobotFile(const std::string& path) {
  return LoadRobotFromString(internal::ReadRobotFileText(path), path);
}

const Robot& BuiltinRobot() {
  static const Robot robot = LoadRobotFromString(BuiltinRobotYaml(), "<built-in wang2022>");
  return robot;
}

void EmitRobotFields(YAML::Emitter& o, const Robot& robot) {
  const auto v2 = [&o](const Eigen::Vector2d& v) {
    o << YAML::Flow << YAML::BeginSeq << YamlNumber{v.x()} << YamlNumber{v.y()} << YAML::EndSeq;
  };
  o << YAML::Key << "name" << YAML::Value << YamlString{robot.name};
  o << YAML::Key << "gravity" << YAML::Value << YamlNumber{robot.gravity_mps2};
  o << YAML::Key << "frame" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key << "width" << YAML::Value
    << YamlNumber{robot.frame_width_m} << YAML::Key << "height" << YAML::Value << YamlNumber{robot.frame_height_m}
    << YAML::EndMap;
  o << YAML::Key << "platform" << YAML::Value << YAML::BeginMap;
  o << YAML::Key << "mass" << YAML::Value << YamlNumber{robot.platform_mass_kg};
  o << YAML::Key << "com" << YAML::Value;
  v2(robot.p_P_com_m);
  if (robot.com_sigma_m) o << YAML::Key << "com_sigma" << YAML::Value << YamlNumber{*robot.com_sigma_m};
  o << YAML::Key << "anchors" << YAML::Value << YAML::Flow << YAML::BeginSeq;
  for (const Cable& c : robot.cables) v2(c.p_P_anchor_m);
  o << YAML::EndSeq << YAML::EndMap;
  o << YAML::Key << "cables" << YAML::Value << YAML::BeginSeq;
  for (const Cable& c : robot.cables) {
    o << YAML::Flow << YAML::BeginMap << YAML::Key << "exit" << YAML::Value;
    v2(c.p_F_exit_m);
    o << YAML::Key << "pulley_radius" << YAML::Value << YamlNumber{c.pulley_radius_m};
    o << YAML::Key << "side" << YAML::Value << (c.side == PulleySide::kLeft ? "left" : "right");
    if (c.wrap == PulleyWrap::kUnder) o << YAML::Key << "wrap" << YAML::Value << "under";
    if (c.initial_length_m) o << YAML::Key << "initial_length" << YAML::Value << YamlNumber{*c.initial_length_m};
    if (c.stiffness_N) o << YAML::Key << "stiffness" << YAML::Value << YamlNumber{*c.stiffness_N};
    o << YAML::EndMap;
  }
  o << YAML::EndSeq;
  EmitNumberMap(o, "tension", {{"min", robot.tension_min_N}, {"max", robot.tension_max_N}});
  o << YAML::Key << "limits" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key << "theta_max_deg"
    << YAML::Value << YamlNumber{Degrees(robot.theta_max_rad)} << YAML::Key << "laser_range" << YAML::Value
    << YamlNumber{robot.laser_range_m} << YAML::Key << "margin" << YAML::Value << YamlNumber{robot.margin_m}
    << YAML::EndMap;
  o << YAML::Key << "home" << YAML::Value;
  v2(robot.p_F_home_m);
  if (robot.theta_is_free()) {
    o << YAML::Key << "home_theta_deg" << YAML::Value << YamlNumber{Degrees(robot.home_theta_rad)};
  }
  o << YAML::Key << "sensors" << YAML::Value;
  EmitSensors(o, robot.sensors);
}

void EmitSensors(YAML::Emitter& o, const SensorNoise& s) {
  // The systematic terms only where they are not zero: a robot without them is written as
  // before this option existed.
  const SystematicSensorErrors& sys = s.systematic;
  o << YAML::BeginMap;
  o << YAML::Key << "laser" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key << "accuracy" << YAML::Value
    << YamlNumber{s.laser_accuracy_m} << YAML::Key << "repeatability" << YAML::Value
    << YamlNumber{s.laser_repeatability_m};
  if (sys.laser_offset_m != 0.0) o << YAML::Key << "offset" << YAML::Value << YamlNumber{sys.laser_offset_m};
  o << YAML::EndMap;
  o << YAML::Key << "inclinometer" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key << "accuracy_deg"
    << YAML::Value << YamlNumber{Degrees(s.inclinometer_accuracy_rad)} << YAML::Key << "repeatability_deg"
    << YAML::Value << YamlNumber{Degrees(s.inclinometer_repeatability_rad)};
  if (sys.inclinometer_offset_rad != 0.0) {
    o << YAML::Key << "offset_deg" << YAML::Value << YamlNumber{Degrees(sys.inclinometer_offset_rad)};
  }
  if (sys.inclinometer_sec_coefficient_rad != 0.0) {
    o << YAML::Key << "sec_coefficient_deg" << YAML::Value << YamlNumber{Degrees(sys.inclinometer_sec_coefficient_rad)};
  }
  o << YAML::EndMap;
  EmitNumberMap(o, "encoder", {{"sigma", s.encoder_sigma_m}});
  if (s.tracker_sigma_m) EmitNumberMap(o, "tracker", {{"sigma", *s.tracker_sigma_m}});
  o << YAML::EndMap;
}

std::string RobotToYaml(const Robot& robot) {
  YAML::Emitter o;
  o << YAML::BeginMap;
  EmitRobotFields(o, robot);
  o << YAML::EndMap;
  return YamlText(o);
}

}  // namespace cablecal
