// Spatial robot file parsing, validation and writing (format: README, "Spatial robots"). The
// reading machinery (file checks, one YAML document, file:line:key messages) is the planar
// loader's, model/yaml_reader.h.
#include <yaml-cpp/yaml.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <set>

#include "common/error.h"
#include "common/format.h"
#include "common/yaml_writer.h"
#include "model/sensor_model.h"
#include "model/spatial_robot.h"
#include "model/spatial_statics.h"
#include "model/swivel.h"
#include "model/yaml_reader.h"

namespace cablecal {
namespace {

// A cable in prose: its number as the CSV columns count (t1..tm), and its key in the file.
std::string CableName(int index) {
  return "cable " + std::to_string(index + 1) + " (cables[" + std::to_string(index) + "])";
}

using internal::Reader;

// Two points closer than this are one (anchors, exit points), as in the planar loader.
constexpr double kSamePoint_m = 1e-6;
// initial_length may differ from its cable's length at home by this fraction of it plus
// kInitialLengthSlack_m (the LoadSpatialRobot check): a calibration's home error is centimetres.
constexpr double kInitialLengthSlack = 0.1;
constexpr double kInitialLengthSlack_m = 0.05;
// The least load-cell sigma: a milli-newton is finer than any load cell of a cable robot.
constexpr double kMinLoadCellSigma_N = 1e-3;

std::string Point(const Eigen::Vector3d& v) {
  return "(" + FormatDouble(v.x()) + ", " + FormatDouble(v.y()) + ", " + FormatDouble(v.z()) + ")";
}

// Numbers for a message, to `digits` significant digits: what a user reads, not round trips.
std::string RoundedList(const Eigen::VectorXd& v, int digits) {
  std::string s = "(";
  for (int i = 0; i < v.size(); ++i) s += (i ? ", " : "") + Rounded(v(i), digits);
  return s + ")";
}

// A sensor's two +- ranges (accuracy, repeatability; `_deg` keys for angles), each within
// [0, most] as typed, and the sigma they give at least `least` (in SI).
RangedNoise ReadRanged(const Reader& rd, const YAML::Node& node, const std::string& key, bool degrees, double most,
                       double least, const char* unit, const std::set<std::string>& extra_keys = {}) {
  const std::string acc = degrees ? "accuracy_deg" : "accuracy";
  const std::string rep = degrees ? "repeatability_deg" : "repeatability";
  rd.ExpectMap(node, key, {acc, rep}, extra_keys);
  const double to_si = degrees ? kDegToRad : 1.0;
  const char* typed_unit = degrees ? "degrees" : unit;
  RangedNoise noise;
  for (const std::string& name : {acc, rep}) {
    const double v = rd.Number(node, key, name);
    if (!(v >= 0.0 && v <= most)) {
      rd.Fail(node[name], Reader::Join(key, name),
              "must be from 0 to " + FormatDouble(most) + " " + typed_unit + ", a +- range taken as 3 sigma (got " +
                  FormatDouble(v) + ")" + (v > most ? ": units?" : ""));
    }
    (name == acc ? noise.accuracy : noise.repeatability) = v * to_si;
  }
  if (!(noise.sigma() >= least)) {
    rd.Fail(node, key, "accuracy and repeatability give a sigma of " + Rounded(noise.sigma(), 6) + " " + unit +
                           " (hypot(accuracy, repeatability) / 3), below " + Rounded(least, 6) + " " + unit +
                           ": every reading is weighed by 1/sigma, and no sensor is that precise");
  }
  return noise;
}

double ReadSigma(const Reader& rd, const YAML::Node& node, const std::string& key) {
  rd.ExpectMap(node, key, {"sigma"}, {});
  const double sigma = rd.Number(node, key, "sigma");
  if (!(sigma >= kMinSensorSigma_m && sigma <= kMaxSensorLength_m)) {
    rd.Fail(node["sigma"], key + ".sigma",
            "must be from " + Rounded(kMinSensorSigma_m, 6) + " to " + Rounded(kMaxSensorLength_m, 6) +
                " m, one standard deviation (got " + FormatDouble(sigma) + ")" +
                (sigma > kMaxSensorLength_m ? ": units? (lengths are in m)"
                                            : ": every reading is weighed by 1/sigma, and no sensor is that precise"));
  }
  return sigma;
}

bool InBox(const Eigen::Vector3d& p, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, double slack) {
  return (p.array() >= lo.array() - slack).all() && (p.array() <= hi.array() + slack).all();
}

// Long for the same reason as the planar Parse (robot_yaml.cc): the file's keys in the file's
// order, each read, range-checked and placed once, to be read against the README's format.
SpatialRobot Parse(const YAML::Node& root, const Reader& rd) {
  SpatialRobot robot;
  robot.source = rd.source();
  if (!root.IsMap()) rd.Fail(root, "", "must be a mapping");
  const std::string kind = internal::KindOf(root, rd);
  if (kind != "spatial") {
    rd.Fail(root["kind"] ? root["kind"] : root, "kind",
            kind.empty() || kind == "planar"
                ? "a planar robot (" + std::string(kind.empty() ? "no kind" : "kind: planar") +
                      "): this reads spatial robots only (kind: spatial)"
                : "must be 'planar' or 'spatial' (got '" + PrintableText(kind.substr(0, 40)) + "')");
  }
  rd.ExpectMap(root, "", {"name", "kind", "gravity", "frame", "platform", "cables", "tension", "limits", "home", "sensors"},
               {"home_rpy_deg", "true_poses"});

  robot.name = rd.String(root["name"], "name");
  if (robot.name.empty()) rd.Fail(root["name"], "name", "must not be empty");
  robot.gravity_mps2 = rd.Number(root, "", "gravity");
  rd.Positive(root["gravity"], "gravity", robot.gravity_mps2);
  rd.AtMost(root["gravity"], "gravity", robot.gravity_mps2, kMaxGravity_mps2, "m/s^2");

  const YAML::Node frame = root["frame"];
  rd.ExpectMap(frame, "frame", {"min", "max"}, {});
  robot.p_F_frame_min_m = rd.Vector3(frame["min"], "frame.min");
  robot.p_F_frame_max_m = rd.Vector3(frame["max"], "frame.max");
  const Eigen::Vector3d side = robot.p_F_frame_max_m - robot.p_F_frame_min_m;
  if (!(side.array() > 0.0).all()) {
    rd.Fail(frame["max"], "frame.max", Point(robot.p_F_frame_max_m) + " must exceed frame.min " +
                                           Point(robot.p_F_frame_min_m) + " in x, y and z");
  }
  if (!(side.maxCoeff() <= kMaxFrameSide_m)) {
    rd.Fail(frame["max"], "frame.max", "the frame's sides " + Point(side) + " m must be at most " +
                                           FormatDouble(kMaxFrameSide_m) + " m: units?");
  }

  const YAML::Node platform = root["platform"];
  rd.ExpectMap(platform, "platform", {"mass", "com", "anchors"}, {"mass_sigma", "com_sigma"});
  robot.platform_mass_kg = rd.Number(platform, "platform", "mass");
  rd.Positive(platform["mass"], "platform.mass", robot.platform_mass_kg);
  rd.AtMost(platform["mass"], "platform.mass", robot.platform_mass_kg, kMaxPlatformMass_kg, "kg");
  robot.p_P_com_m = rd.Vector3(platform["com"], "platform.com");
  // The identification's priors on the mass and the centre of mass (README, "Spatial
  // identification"): a centre of mass known better than a sensor's finest sigma would overflow
  // its weight, and a prior looser than half the mass or 0.1 m is no knowledge a lab would file.
  if (platform["mass_sigma"]) {
    robot.mass_sigma_kg = rd.Number(platform, "platform", "mass_sigma");
    rd.Positive(platform["mass_sigma"], "platform.mass_sigma", *robot.mass_sigma_kg);
    rd.AtMost(platform["mass_sigma"], "platform.mass_sigma", *robot.mass_sigma_kg, 0.5 * robot.platform_mass_kg,
              "kg (half the mass)");
  }
  if (platform["com_sigma"]) {
    robot.com_sigma_m = rd.Number(platform, "platform", "com_sigma");
    rd.AtLeast(platform["com_sigma"], "platform.com_sigma", *robot.com_sigma_m, kMinSensorSigma_m, "m");
    rd.AtMost(platform["com_sigma"], "platform.com_sigma", *robot.com_sigma_m, 0.1, "m");
  }
  const YAML::Node anchors = platform["anchors"];
  if (!anchors.IsSequence()) rd.Fail(anchors, "platform.anchors", "must be a list of [x, y, z] points");

  const YAML::Node cables = root["cables"];
  if (!cables.IsSequence()) rd.Fail(cables, "cables", "must be a list of cables");
  if (cables.size() < static_cast<std::size_t>(kMinSpatialCables) ||
      cables.size() > static_cast<std::size_t>(kMaxSpatialCables)) {
    rd.Fail(cables, "cables", "must list " + std::to_string(kMinSpatialCables) + " to " +
                                  std::to_string(kMaxSpatialCables) + " cables (got " + std::to_string(cables.size()) +
                                  ")");
  }
  if (anchors.size() != cables.size()) {
    rd.Fail(anchors, "platform.anchors", "needs one anchor per cable (" + std::to_string(cables.size()) + "), got " +
                                             std::to_string(anchors.size()));
  }
  const double smallest_side = side.minCoeff();
  for (std::size_t i = 0; i < cables.size(); ++i) {
    const std::string key = "cables[" + std::to_string(i) + "]";
    const YAML::Node c = cables[i];
    rd.ExpectMap(c, key, {"exit", "swivel_axis", "pulley_radius"}, {"stiffness", "initial_length"});
    SpatialCable cable;
    cable.p_F_exit_m = rd.Vector3(c["exit"], key + ".exit");
    // Exit points are on the frame: one well outside the box is a typo or a unit slip; the
    // tolerance leaves room for calibrated exit points, as in the planar file.
    if (!InBox(cable.p_F_exit_m, robot.p_F_frame_min_m, robot.p_F_frame_max_m, kExitOffFrameTolerance_m)) {
      rd.Fail(c["exit"], key + ".exit",
              Point(cable.p_F_exit_m) + " m is outside the frame box " + Point(robot.p_F_frame_min_m) + " to " +
                  Point(robot.p_F_frame_max_m) + " m by more than " + FormatDouble(kExitOffFrameTolerance_m) +
                  " m: exit points are on the frame");
    }
    const Eigen::Vector3d axis = rd.Vector3(c["swivel_axis"], key + ".swivel_axis");
    if (!(axis.norm() > kMinSwivelAxisLength)) {
      rd.Fail(c["swivel_axis"], key + ".swivel_axis",
              "has zero length: it is the direction in which the cable arrives at the exit point, e.g. [0, 0, 1]");
    }
    // Normalised, unless unit already to rounding: a written robot then reads back bit for bit.
    cable.k_F_swivel_axis = std::abs(axis.squaredNorm() - 1.0) > 1e-14 ? axis.normalized() : axis;
    cable.pulley_radius_m = rd.Number(c, key, "pulley_radius");
    rd.NonNegative(c["pulley_radius"], key + ".pulley_radius", cable.pulley_radius_m);
    if (cable.pulley_radius_m > 0.25 * smallest_side) {
      rd.Fail(c["pulley_radius"], key + ".pulley_radius",
              FormatDouble(cable.pulley_radius_m) +
                  " m is more than a quarter of the frame's smallest side: radii are in metres (25 mm is 0.025)");
    }
    if (c["stiffness"]) {
      cable.stiffness_N = rd.Number(c, key, "stiffness");
      rd.Positive(c["stiffness"], key + ".stiffness", *cable.stiffness_N);
    }
    if (c["initial_length"]) {
      cable.initial_length_m = rd.Number(c, key, "initial_length");
      rd.Positive(c["initial_length"], key + ".initial_length", *cable.initial_length_m);
    }
    cable.p_P_anchor_m = rd.Vector3(anchors[i], "platform.anchors[" + std::to_string(i) + "]");
    robot.cables.push_back(cable);
  }
  for (std::size_t i = 0; i < robot.cables.size(); ++i) {
    for (std::size_t j = i + 1; j < robot.cables.size(); ++j) {
      if ((robot.cables[i].p_F_exit_m - robot.cables[j].p_F_exit_m).norm() < kSamePoint_m) {
        rd.Fail(cables[j]["exit"], "cables[" + std::to_string(j) + "].exit",
                "coincides with the exit point of " + CableName(static_cast<int>(i)));
      }
    }
  }
  // Anchors: cables may share one, but they must span a plane: anchors all on one line (or at
  // one point) leave the platform's rotation about that line undetermined.
  {
    const Eigen::Vector3d b0 = robot.cables[0].p_P_anchor_m;
    Eigen::Vector3d far = b0;
    for (const SpatialCable& c : robot.cables) {
      if ((c.p_P_anchor_m - b0).norm() > (far - b0).norm()) far = c.p_P_anchor_m;
    }
    double off_line = 0.0;
    if ((far - b0).norm() >= kSamePoint_m) {
      const Eigen::Vector3d dir = (far - b0).normalized();
      for (const SpatialCable& c : robot.cables) {
        const Eigen::Vector3d v = c.p_P_anchor_m - b0;
        off_line = std::max(off_line, (v - v.dot(dir) * dir).norm());
      }
    }
    if (!(off_line >= kSamePoint_m)) {
      rd.Fail(anchors, "platform.anchors",
              "all anchors lie on one line: the platform's rotation about it would be undetermined (they must span a "
              "plane)");
    }
  }

  const YAML::Node tension = root["tension"];
  rd.ExpectMap(tension, "tension", {"min", "max"}, {});
  robot.tension_min_N = rd.Number(tension, "tension", "min");
  // A slack cable sags: its direction is no longer the straight free segment the model
  // assumes, so a pose held only with a cable at 0 N is not one the model describes.
  if (!(robot.tension_min_N > 0.0)) {
    rd.Fail(tension["min"], "tension.min",
            "must be > 0 (got " + FormatDouble(robot.tension_min_N) +
                "): a slack cable sags, and the model's straight cable needs a least pretension");
  }
  robot.tension_max_N = rd.Number(tension, "tension", "max");
  if (!(robot.tension_min_N < robot.tension_max_N)) {
    rd.Fail(tension, "tension", "min must be < max (got min " + FormatDouble(robot.tension_min_N) + " N, max " +
                                    FormatDouble(robot.tension_max_N) + " N)");
  }
  for (std::size_t i = 0; i < robot.cables.size(); ++i) {
    internal::CheckCableStiffness(rd, cables, i, robot.cables[i].stiffness_N, robot.tension_max_N);
  }

  const YAML::Node limits = root["limits"];
  rd.ExpectMap(limits, "limits", {"tilt_max_deg", "margin"}, {});
  const double tilt_max_deg = rd.Number(limits, "limits", "tilt_max_deg");
  if (!(tilt_max_deg > 0.0 && tilt_max_deg < 89.0)) {
    rd.Fail(limits["tilt_max_deg"], "limits.tilt_max_deg",
            "must be in (0, 89) degrees (got " + FormatDouble(tilt_max_deg) + ")");
  }
  robot.tilt_max_rad = tilt_max_deg * kDegToRad;
  robot.margin_m = rd.Number(limits, "limits", "margin");
  rd.NonNegative(limits["margin"], "limits.margin", robot.margin_m);
  if (!(2.0 * robot.margin_m < smallest_side)) {
    rd.Fail(limits["margin"], "limits.margin",
            FormatDouble(robot.margin_m) + " m leaves no room in the frame box (smallest side " +
                FormatDouble(smallest_side) + " m)");
  }

  robot.p_F_home_m = rd.Vector3(root["home"], "home");
  if (!InBox(robot.p_F_home_m, robot.p_F_frame_min_m, robot.p_F_frame_max_m, 0.0)) {
    rd.Fail(root["home"], "home", Point(robot.p_F_home_m) + " m is outside the frame box " +
                                      Point(robot.p_F_frame_min_m) + " to " + Point(robot.p_F_frame_max_m) + " m");
  }
  if (root["home_rpy_deg"]) {
    if (!root["home_rpy_deg"].IsSequence() || root["home_rpy_deg"].size() != 3) {
      rd.Fail(root["home_rpy_deg"], "home_rpy_deg", "must be a list of three angles [roll, pitch, yaw] in degrees");
    }
    const Eigen::Vector3d rpy_deg = rd.Vector3(root["home_rpy_deg"], "home_rpy_deg");
    if (!(rpy_deg.cwiseAbs().maxCoeff() <= 180.0)) {
      rd.Fail(root["home_rpy_deg"], "home_rpy_deg", "each angle must be within +-180 degrees (got " + Point(rpy_deg) + ")");
    }
    robot.home_rpy_rad = rpy_deg * kDegToRad;
  }
  const YAML::Node home_node = root["home_rpy_deg"] ? root["home_rpy_deg"] : root["home"];
  const SpatialPose<double> home = robot.home_pose();
  const double tilt = TiltAngle(home);
  if (!(tilt <= robot.tilt_max_rad)) {
    rd.Fail(home_node, "home_rpy_deg", "the platform's tilt at home, " + Rounded(tilt / kDegToRad, 6) +
                                           " degrees, is beyond limits.tilt_max_deg (" + FormatDouble(tilt_max_deg) + ")");
  }
  const Eigen::Matrix3d R = Rotation<double>(home);
  const auto check_point = [&](const Eigen::Vector3d& p_P, const std::string& what) {
    const Eigen::Vector3d p_F = AnchorInF<double>(home, R, p_P);
    if (!InBox(p_F, robot.p_F_frame_min_m, robot.p_F_frame_max_m, -robot.margin_m)) {
      rd.Fail(root["home"], "home",
              "the platform's " + what + " is at " + Point(p_F) + " m at home, within limits.margin (" +
                  FormatDouble(robot.margin_m) + " m) of the frame box or outside it");
    }
  };
  for (int i = 0; i < robot.num_cables(); ++i) check_point(robot.cables[i].p_P_anchor_m, "anchors[" + std::to_string(i) + "]");
  check_point(robot.p_P_com_m, "centre of mass");
  const CableGeometryCheck geometry = CableGeometryAt(robot, home);
  if (!geometry.valid()) {
    rd.Fail(root["home"], "home",
            CableName(geometry.cable) + " has invalid geometry at home: " + ToString(geometry.geometry) +
                (geometry.geometry == SwivelGeometry::kSwivelAxis     ? " (its anchor is on the swivel axis)"
                 : geometry.geometry == SwivelGeometry::kInsidePulley ? " (its anchor is inside the pulley)"
                                                                       : " (the wrap angle is outside [0, 270] degrees: "
                                                                         "is the swivel axis the way the cable arrives?)"));
  }
  // The statics last: the checks above name the simpler causes first.
  const SpatialPoseEvaluation statics = EvaluateSpatialHome(robot);
  if (!statics.feasible()) {
    std::string why = ToString(statics.feasibility);
    int cable = statics.cable;
    if (statics.has_equilibrium &&
        (statics.feasibility == Feasibility::kTensionLow || statics.feasibility == Feasibility::kTensionHigh)) {
      Eigen::Index extreme = 0;  // the cable furthest beyond its bound
      if (statics.feasibility == Feasibility::kTensionLow) statics.equilibrium.tensions_N.minCoeff(&extreme);
      else statics.equilibrium.tensions_N.maxCoeff(&extreme);
      cable = static_cast<int>(extreme);
    }
    if (cable >= 0) why += " (" + CableName(cable) + ")";
    if (statics.has_equilibrium) {
      why += "; tensions " + RoundedList(statics.equilibrium.tensions_N, 4) + " N, bounds [" + FormatDouble(robot.tension_min_N) +
             ", " + FormatDouble(robot.tension_max_N) + "]";
      if (robot.num_cables() < 6) {
        why += ", equilibrium rpy " + RoundedList(statics.equilibrium.q.tail<3>() / kDegToRad, 4) + " degrees";
      }
    }
    std::string hint;
    if (robot.num_cables() < 6 && !statics.has_equilibrium) {
      // Where an underactuated platform can hang is narrow; the exits' centroid is a start.
      Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
      for (const SpatialCable& c : robot.cables) centroid += c.p_F_exit_m;
      centroid /= robot.num_cables();
      // + 0.0: a centroid of -1e-17 reads 0, not -0.
      const std::string at = "x = " + FormatDouble(std::round(centroid.x() * 1e3) / 1e3 + 0.0) +
                             ", y = " + FormatDouble(std::round(centroid.y() * 1e3) / 1e3 + 0.0) + " m";
      // A home already below the centroid (within a centimetre) is not helped by moving there.
      const bool below_centroid = (robot.p_F_home_m.head<2>() - centroid.head<2>()).norm() < 0.01;
      const bool yaw_held = robot.num_cables() >= 4;
      hint = ". With fewer than 6 cables the platform hangs in equilibrium only where gravity lies in the cables' "
             "span: home_rpy_deg's roll and pitch are only the solver's first guess" +
             std::string(yaw_held ? ", its yaw is held, and such a robot holds a narrow band of yaw" : "") +
             (below_centroid
                  ? "; the home is already below the exits' centroid (" + at + "): look at " +
                        (yaw_held ? "the yaw (that of the exits' and anchors' layout, often 0), " : "") +
                        "the height, the centre of mass and the anchors"
                  : "; try a home below the exits (their centroid is at " + at + ")" +
                        (yaw_held ? " at the yaw of the exits' and anchors' layout (often 0)" : ""));
    }
    if (robot.num_cables() >= 6 && !statics.has_equilibrium && statics.feasibility == Feasibility::kNoEquilibrium) {
      // What the balance asks of the cables: the least-squares tensions (the minimum-norm ones
      // for m > 6) name the cables that would have to push, which is where a lab looks.
      const Eigen::Matrix<double, 6, Eigen::Dynamic> W = WrenchMatrix<double>(robot, home);
      const Eigen::Matrix<double, 6, 1> w_g = GravityWrench<double>(robot, home);
      const Eigen::VectorXd t = Eigen::MatrixXd(W).completeOrthogonalDecomposition().solve(-w_g);
      std::string pushing;
      for (int i = 0; i < robot.num_cables(); ++i) {
        if (t(i) < 0.0) pushing += (pushing.empty() ? "" : ", ") + std::to_string(i + 1);
      }
      if (t.allFinite()) {
        hint = ". The least-squares tensions that balance it are " + RoundedList(t, 4) + " N" +
               (pushing.empty() ? std::string()
                                : ": cable" + std::string(pushing.find(',') == std::string::npos ? " " : "s ") + pushing +
                                      " would have to push; a home nearer the middle of the exits, or those cables' "
                                      "exits and anchors, are where to look");
      }
    }
    rd.Fail(root["home"], "home",
            "the home pose " + Point(robot.p_F_home_m) + " m at roll, pitch, yaw " +
                RoundedList(robot.home_rpy_rad / kDegToRad, 4) + " degrees (home_rpy_deg) is not in the feasible workspace: " +
                why + hint);
  }
  // An initial_length far from its cable's length at home (exit to anchor at the home
  // equilibrium) is no calibration of this robot: millimetres, another cable's, or a typo (a new
  // user's 1.0 m for a cable 2.10 m long loaded, and simulate then blamed the plan). A calibrated
  // file's l_i0 differs from it by its home's own error, centimetres.
  const Eigen::VectorXd home_lengths_m = CableLengths<double>(robot, statics.equilibrium.q);
  for (int i = 0; i < robot.num_cables(); ++i) {
    if (!robot.cables[i].initial_length_m) continue;
    const double length_m = home_lengths_m(i), given_m = *robot.cables[i].initial_length_m;
    if (std::abs(given_m - length_m) <= kInitialLengthSlack * length_m + kInitialLengthSlack_m) continue;
    const std::string key = "cables[" + std::to_string(i) + "].initial_length";
    rd.Fail(root["cables"][i]["initial_length"], key,
            Rounded(given_m, 6) + " m, but the cable runs " + Rounded(length_m, 6) +
                " m from its exit to its anchor at the home equilibrium (" +
                (given_m < length_m ? "it could not reach" : "it would hang slack") +
                "): initial_length is the cable paid out at home, where its encoder reads zero (identify "
                "--calibrated-robot writes it); in metres, of this cable? More than " +
                Rounded(100 * kInitialLengthSlack, 3) + " % + " + Rounded(kInitialLengthSlack_m, 3) +
                " m off is refused");
  }

  const YAML::Node sensors = root["sensors"];
  rd.ExpectMap(sensors, "sensors", {"encoder"},
               {"inclinometer", "laser", "position", "swivel", "heading", "load_cell", "tracker"});
  SpatialSensors& s = robot.sensors;
  s.encoder_sigma_m = ReadSigma(rd, sensors["encoder"], "sensors.encoder");
  if (sensors["inclinometer"]) {
    s.inclinometer_rad = ReadRanged(rd, sensors["inclinometer"], "sensors.inclinometer", true,
                                    kMaxInclinometerRange_deg, kMinSensorSigma_rad, "rad");
  }
  if (sensors["laser"]) {
    s.laser_m = ReadRanged(rd, sensors["laser"], "sensors.laser", false, kMaxSensorLength_m, kMinSensorSigma_m, "m");
  }
  if (sensors["position"]) {
    SpatialSensors::Position position;
    position.noise_m = ReadRanged(rd, sensors["position"], "sensors.position", false, kMaxSensorLength_m,
                                  kMinSensorSigma_m, "m", {"target"});
    if (sensors["position"]["target"]) {
      position.p_P_target_m = rd.Vector3(sensors["position"]["target"], "sensors.position.target");
      // A point of the platform: beyond the frame box's diagonal from its origin it is none
      // (a new user's target of 50 loaded; millimetres typed for metres read so).
      const double diagonal_m = (robot.p_F_frame_max_m - robot.p_F_frame_min_m).norm();
      if (position.p_P_target_m.norm() > diagonal_m) {
        rd.Fail(sensors["position"]["target"], "sensors.position.target",
                Rounded(position.p_P_target_m.norm(), 6) + " m from the platform frame's origin, more than the "
                "frame box's diagonal (" + Rounded(diagonal_m, 6) + " m): the target is a point of the platform, "
                "in metres (millimetres?)");
      }
    }
    s.position = position;
  }
  if (sensors["swivel"]) {
    s.swivel_rad = ReadRanged(rd, sensors["swivel"], "sensors.swivel", true, kMaxInclinometerRange_deg,
                              kMinSensorSigma_rad, "rad");
  }
  if (sensors["heading"]) {
    s.heading_rad = ReadRanged(rd, sensors["heading"], "sensors.heading", true, kMaxInclinometerRange_deg,
                               kMinSensorSigma_rad, "rad");
  }
  if (sensors["load_cell"]) {
    s.load_cell_N = ReadRanged(rd, sensors["load_cell"], "sensors.load_cell", false, robot.tension_max_N,
                               kMinLoadCellSigma_N, "N");
  }
  if (sensors["tracker"]) s.tracker_sigma_m = ReadSigma(rd, sensors["tracker"], "sensors.tracker");
  return robot;
}

}  // namespace

namespace internal {

void CheckSpatialRobotDocument(const YAML::Node& root, const Reader& rd) { (void)Parse(root, rd); }

bool LooksSpatial(const YAML::Node& root) {
  if (!root.IsMap()) return false;
  const YAML::Node frame = root["frame"], cables = root["cables"];
  bool spatial = static_cast<bool>(root["home_rpy_deg"]) || (frame.IsMap() && (frame["min"] || frame["max"]));
  if (cables.IsSequence()) {
    for (const YAML::Node& c : cables) spatial = spatial || (c.IsMap() && c["swivel_axis"]);
  }
  return spatial;
}

}  // namespace internal

SpatialRobot LoadSpatialRobotFromString(const std::string& yaml_text, const std::string& source) {
  return internal::ParseRobotText(yaml_text, source, Parse);
}

SpatialRobot LoadSpatialRobotFile(const std::string& path) {
  return LoadSpatialRobotFromString(internal::ReadRobotFileText(path), path);
}

RobotKind RobotKindOfText(const std::string& yaml_text, const std::string& source) {
  return internal::ParseRobotText(yaml_text, source, [](const YAML::Node& root, const Reader& rd) {
    const std::string kind = internal::KindOf(root, rd);
    if (kind.empty() || kind == "planar") return RobotKind::kPlanar;
    if (kind != "spatial") {
      rd.Fail(root["kind"], "kind", "must be 'planar' or 'spatial' (got '" + PrintableText(kind.substr(0, 40)) + "')");
    }
    return RobotKind::kSpatial;
  });
}

RobotKind RobotKindOfFile(const std::string& path) { return RobotKindOfText(internal::ReadRobotFileText(path), path); }

std::string SpatialRobotToYaml(const SpatialRobot& robot) {
  using internal::DegreesForFile;
  YAML::Emitter o;
  const auto v3 = [&o](const Eigen::Vector3d& v) {
    o << YAML::Flow << YAML::BeginSeq << YamlNumber{v.x()} << YamlNumber{v.y()} << YamlNumber{v.z()} << YAML::EndSeq;
  };
  // A ranged sensor's flow map; the position sensor's target point after its ranges.
  const auto ranged = [&o, &v3](const char* key, const RangedNoise& n, bool degrees,
                                const Eigen::Vector3d* target = nullptr) {
    o << YAML::Key << key << YAML::Value << YAML::Flow << YAML::BeginMap;
    o << YAML::Key << (degrees ? "accuracy_deg" : "accuracy") << YAML::Value
      << YamlNumber{degrees ? DegreesForFile(n.accuracy) : n.accuracy};
    o << YAML::Key << (degrees ? "repeatability_deg" : "repeatability") << YAML::Value
      << YamlNumber{degrees ? DegreesForFile(n.repeatability) : n.repeatability};
    if (target) {
      o << YAML::Key << "target" << YAML::Value;
      v3(*target);
    }
    o << YAML::EndMap;
  };
  o << YAML::BeginMap;
  o << YAML::Key << "name" << YAML::Value << YamlString{robot.name};
  o << YAML::Key << "kind" << YAML::Value << "spatial";
  o << YAML::Key << "gravity" << YAML::Value << YamlNumber{robot.gravity_mps2};
  o << YAML::Key << "frame" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key << "min" << YAML::Value;
  v3(robot.p_F_frame_min_m);
  o << YAML::Key << "max" << YAML::Value;
  v3(robot.p_F_frame_max_m);
  o << YAML::EndMap;
  o << YAML::Key << "platform" << YAML::Value << YAML::BeginMap;
  o << YAML::Key << "mass" << YAML::Value << YamlNumber{robot.platform_mass_kg};
  o << YAML::Key << "com" << YAML::Value;
  v3(robot.p_P_com_m);
  if (robot.mass_sigma_kg) o << YAML::Key << "mass_sigma" << YAML::Value << YamlNumber{*robot.mass_sigma_kg};
  if (robot.com_sigma_m) o << YAML::Key << "com_sigma" << YAML::Value << YamlNumber{*robot.com_sigma_m};
  o << YAML::Key << "anchors" << YAML::Value << YAML::Flow << YAML::BeginSeq;
  for (const SpatialCable& c : robot.cables) v3(c.p_P_anchor_m);
  o << YAML::EndSeq << YAML::EndMap;
  o << YAML::Key << "cables" << YAML::Value << YAML::BeginSeq;
  for (const SpatialCable& c : robot.cables) {
    o << YAML::Flow << YAML::BeginMap << YAML::Key << "exit" << YAML::Value;
    v3(c.p_F_exit_m);
    o << YAML::Key << "swivel_axis" << YAML::Value;
    v3(c.k_F_swivel_axis);
    o << YAML::Key << "pulley_radius" << YAML::Value << YamlNumber{c.pulley_radius_m};
    if (c.stiffness_N) o << YAML::Key << "stiffness" << YAML::Value << YamlNumber{*c.stiffness_N};
    if (c.initial_length_m) o << YAML::Key << "initial_length" << YAML::Value << YamlNumber{*c.initial_length_m};
    o << YAML::EndMap;
  }
  o << YAML::EndSeq;
  EmitNumberMap(o, "tension", {{"min", robot.tension_min_N}, {"max", robot.tension_max_N}});
  o << YAML::Key << "limits" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key << "tilt_max_deg"
    << YAML::Value << YamlNumber{DegreesForFile(robot.tilt_max_rad)} << YAML::Key << "margin" << YAML::Value
    << YamlNumber{robot.margin_m} << YAML::EndMap;
  o << YAML::Key << "home" << YAML::Value;
  v3(robot.p_F_home_m);
  o << YAML::Key << "home_rpy_deg" << YAML::Value;
  v3(Eigen::Vector3d(DegreesForFile(robot.home_rpy_rad.x()), DegreesForFile(robot.home_rpy_rad.y()),
                     DegreesForFile(robot.home_rpy_rad.z())));
  const SpatialSensors& s = robot.sensors;
  o << YAML::Key << "sensors" << YAML::Value << YAML::BeginMap;
  EmitNumberMap(o, "encoder", {{"sigma", s.encoder_sigma_m}});
  if (s.inclinometer_rad) ranged("inclinometer", *s.inclinometer_rad, true);
  if (s.laser_m) ranged("laser", *s.laser_m, false);
  if (s.position) ranged("position", s.position->noise_m, false, &s.position->p_P_target_m);
  if (s.swivel_rad) ranged("swivel", *s.swivel_rad, true);
  if (s.heading_rad) ranged("heading", *s.heading_rad, true);
  if (s.load_cell_N) ranged("load_cell", *s.load_cell_N, false);
  if (s.tracker_sigma_m) EmitNumberMap(o, "tracker", {{"sigma", *s.tracker_sigma_m}});
  o << YAML::EndMap << YAML::EndMap;
  return YamlText(o);
}

}  // namespace cablecal
