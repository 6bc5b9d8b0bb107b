#include "identify/validate.h"

#include <cmath>
#include <algorithm>
#include <cstdio>
#include <limits>
#include <set>

#include "common/error.h"
#include "common/format.h"
#include "common/version.h"
#include "common/yaml_writer.h"
#include "experiment/simulation.h"
#include "identify/identify.h"
#include "model/forward_statics.h"
#include "model/statics.h"

namespace cablecal {
namespace {

std::string Where(const Measurement& m, const std::string& source) {
  return m.where.empty() ? source + ": pose " + std::to_string(m.pose_id) : m.where;
}

// A message's length in m (angle in rad) to the millimetre (milliradian): what a reader compares.
std::string Millimetres(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3f", value);
  return text;
}

// "the nominal robot (robots/x.yaml)": which model failed, for messages.
std::string RobotLabel(const std::string& role, const Robot& robot) { return "the " + role + " robot (" + robot.source + ")"; }

// Where `robot` holds the reading's lengths l_i0 + dl_i. The start is the pose the sensors saw
// (StartingPose: the measured z and theta, with the x that best explains the encoders there).
// The platform was within millimetres of it (a centimetre or two for an uncalibrated model),
// so Newton lands on the equilibrium the lab's platform was in, not on another one a cold
// start from home could reach; and a solution far from the readings means they are not this
// robot's.
// Returns false with `why` (the message after the reading's place) when it cannot.
bool PredictPose(const Robot& robot, const std::string& role, const GeometryVector& geometry, const Measurement& m,
                 PlanarPose* q_out, std::string* why) {
  const int cables = robot.num_cables();
  const PlanarPose start = StartingPose(robot, geometry, m);
  const Eigen::VectorXd lengths = geometry.tail(cables) + m.dl_m;  // l_i0 + dl_i
  // The encoders read the cable paid out: with stiffness, the unstretched lengths settle the
  // platform (model/forward_statics.h, as simulate's true robot); without, 2 or 3 rigid cables
  // fix it, and more meet their lengths only in least squares (the rigid model's best pose).
  ForwardResult fwd;
  if (HasStiffness(robot)) {
    fwd = SolveForwardStatics(robot, HomeUnstretchedLengths(robot, geometry.tail(cables)) + m.dl_m, &start);
  } else if (cables <= PlanarKind::kPoseDim) {
    fwd = SolveForwardGeometricoStatic(robot, lengths, &start);
  } else {
    fwd = LeastSquaresPoseGuess(robot, lengths, &start);
  }
  const std::string hint = ": readings of another robot, or a pose outside its workspace?";
  if (fwd.status != ForwardStatus::kConverged) {
    *why = RobotLabel(role, robot) + " cannot hold these lengths, its initial lengths + dl (" +
           CannotHoldReason(fwd.status, "where the sensors saw the platform") + ")" + hint;
    return false;
  }
  // With 2 cables the forward model falls back on cold starts and keeps any stable
  // equilibrium: the bounds 3 or more cables get (kOtherAssembly) keep it honest. Only what
  // was measured is compared: a missing reading's start came from the model itself.
  const PlanarPose& q = fwd.equilibrium.q;
  const double dz_m = q(1) - m.value(SensorId::kLaser), dtheta_rad = q(2) - m.value(SensorId::kInclinometer);
  if ((m.has(SensorId::kLaser) && std::abs(dz_m) > kOtherAssemblyDistance_m) ||
      (m.has(SensorId::kInclinometer) && std::abs(dtheta_rad) > kOtherAssemblyAngle_rad)) {
    std::string off = "(" + Millimetres(q(0)) + ", " + Millimetres(q(1)) + ") m, " + Millimetres(q(2)) + " rad:";
    if (m.has(SensorId::kLaser)) off += " " + Millimetres(std::abs(dz_m)) + " m from the laser's z";
    if (m.has(SensorId::kInclinometer)) {
      off += std::string(m.has(SensorId::kLaser) ? " and " : " ") + Millimetres(std::abs(dtheta_rad)) + " rad from the inclinometer's theta";
    }
    *why = RobotLabel(role, robot) + " holds these lengths only at " + off + hint;
    return false;
  }
  *q_out = q;
  return true;
}

ErrorSummary Stats(const std::vector<double>& errors) {
  ErrorSummary s;
  double sum2 = 0.0;
  for (const double e : errors) {
    sum2 += e * e;
    s.max_abs = std::max(s.max_abs, std::abs(e));
  }
  s.rms = errors.empty() ? 0.0 : std::sqrt(sum2 / errors.size());
  return s;
}

// One robot's predictions of the readings `keep` says to keep.
RobotPrediction Predict(const Robot& robot, const std::string& role, const std::vector<Measurement>& measurements,
                        const std::vector<PlanarPose>& q, const std::vector<bool>& keep) {
  RobotPrediction p;
  p.name = role;
  p.robot = robot.name;
  p.source = robot.source;
  for (std::size_t j = 0; j < measurements.size(); ++j) {
    if (!keep[j]) continue;
    const Measurement& m = measurements[j];
    p.q.push_back(q[j]);
    if (m.has(SensorId::kLaser)) p.z_error_m.push_back(q[j](1) - m.value(SensorId::kLaser));
    if (m.has(SensorId::kInclinometer)) p.theta_error_rad.push_back(q[j](2) - m.value(SensorId::kInclinometer));
  }
  if (measurements.front().has(SensorId::kLaser)) p.z_m = Stats(p.z_error_m);
  if (measurements.front().has(SensorId::kInclinometer)) p.theta_rad = Stats(p.theta_error_rad);
  return p;
}

double Ratio(const ValidationResult& r, std::optional<ErrorSummary> RobotPrediction::*stats) {
  if (r.robots.size() < 2 || !(r.robots[0].*stats)) return std::numeric_limits<double>::quiet_NaN();
  return (r.robots[1].*stats)->rms / (r.robots[0].*stats)->rms;
}

// The CSV's columns, in order, and each row's values: one place for the CSV and the JSON.
std::vector<std::string> Columns(const ValidationResult& r) {
  std::vector<std::string> c = {"pose"};
  if (r.has_laser) c.push_back("z_measured_m");
  if (r.has_inclinometer) c.push_back("theta_measured_rad");
  for (const RobotPrediction& p : r.robots) {
    c.insert(c.end(), {"x_" + p.name + "_m", "z_" + p.name + "_m", "theta_" + p.name + "_rad"});
    if (r.has_laser) c.push_back("z_error_" + p.name + "_m");
    if (r.has_inclinometer) c.push_back("theta_error_" + p.name + "_rad");
  }
  return c;
}
std::vector<double> Row(const ValidationResult& r, std::size_t j) {
  std::vector<double> v;
  if (r.has_laser) v.push_back(r.z_measured_m[j]);
  if (r.has_inclinometer) v.push_back(r.theta_measured_rad[j]);
  for (const RobotPrediction& p : r.robots) {
    v.insert(v.end(), {p.q[j](0), p.q[j](1), p.q[j](2)});
    if (r.has_laser) v.push_back(p.z_error_m[j]);
    if (r.has_inclinometer) v.push_back(p.theta_error_rad[j]);
  }
  return v;
}

void EmitStats(YAML::Emitter& o, const char* key, const char* unit, const std::optional<ErrorSummary>& s) {
  if (!s) return;
  o << YAML::Key << key << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key << std::string("rms_") + unit
    << YAML::Value << YamlNumber{s->rms} << YAML::Key << std::string("max_abs_") + unit << YAML::Value
    << YamlNumber{s->max_abs} << YAML::EndMap;
}

}  // namespace

ValidationResult Validate(const Robot& calibrated, const std::optional<Robot>& nominal,
                          const std::vector<Measurement>& measurements, const std::string& source,
                          bool skip_infeasible) {
  if (measurements.empty()) throw InputError(source, "", "no readings to validate on");
  const int m = calibrated.num_cables();
  if (nominal && nominal->num_cables() != m) {
    throw InputError(nominal->source, "", "the nominal robot has " + std::to_string(nominal->num_cables()) +
                                              " cables, the calibrated robot " + std::to_string(m) +
                                              ": a file for another robot?");
  }
  ValidationResult result;
  result.has_laser = measurements.front().has(SensorId::kLaser);
  result.has_inclinometer = measurements.front().has(SensorId::kInclinometer);
  for (const Measurement& r : measurements) {
    if (r.dl_m.size() != m) {
      throw InputError(Where(r, source), "", std::to_string(r.dl_m.size()) + " encoder readings for a robot with " +
                                                 std::to_string(m) + " cables");
    }
    if (r.has(SensorId::kLaser) != result.has_laser || r.has(SensorId::kInclinometer) != result.has_inclinometer) {
      throw InputError(Where(r, source), "", "a laser or inclinometer reading here but not in the first reading, or "
                                             "the other way round: one set of readings has one set of sensors");
    }
  }
  if (!result.has_laser && !result.has_inclinometer) {
    throw InputError(source, "", "nothing to compare the predictions with: the data have " +
                                     MissingSensorsText({"laser", "inclinometer"}) +
                                     " (validate compares the predicted z and theta with those readings)");
  }
  // Every reading predicted by every robot; a reading one of them cannot hold is refused, or
  // with skip_infeasible left out for all of them (the rows stay one per kept reading).
  std::vector<const Robot*> robots = {&calibrated};
  std::vector<std::string> roles = {"calibrated"};
  if (nominal) robots.push_back(&*nominal), roles.push_back("nominal");
  std::vector<std::vector<PlanarPose>> q(robots.size(), std::vector<PlanarPose>(measurements.size()));
  std::vector<bool> keep(measurements.size(), true);
  for (std::size_t k = 0; k < robots.size(); ++k) {
    const GeometryVector geometry = GeometryOf(*robots[k]);
    for (std::size_t j = 0; j < measurements.size(); ++j) {
      if (!keep[j]) continue;
      std::string why;
      if (PredictPose(*robots[k], roles[k], geometry, measurements[j], &q[k][j], &why)) continue;
      if (!skip_infeasible) throw InputError(Where(measurements[j], source), "", why);
      keep[j] = false;
      result.skipped.push_back({measurements[j].pose_id, Where(measurements[j], source), why, j});
    }
  }
  // In the readings' order, whichever robot failed first.
  std::stable_sort(result.skipped.begin(), result.skipped.end(),
                   [&](const SkippedReading& a, const SkippedReading& b) { return a.index < b.index; });
  if (!result.skipped.empty() && result.skipped.size() == measurements.size()) {
    throw InputError(source, "", "no reading is left to validate on: every one of the " +
                                     std::to_string(measurements.size()) +
                                     " was skipped, a robot cannot hold it (the first, " + result.skipped.front().where +
                                     ": " + result.skipped.front().reason + ")");
  }
  for (std::size_t j = 0; j < measurements.size(); ++j) {
    if (!keep[j]) continue;
    const Measurement& r = measurements[j];
    result.pose_ids.push_back(r.pose_id);
    if (r.has(SensorId::kLaser)) result.z_measured_m.push_back(r.value(SensorId::kLaser));
    if (r.has(SensorId::kInclinometer)) result.theta_measured_rad.push_back(r.value(SensorId::kInclinometer));
  }
  result.num_poses = static_cast<int>(std::set<int>(result.pose_ids.begin(), result.pose_ids.end()).size());
  for (std::size_t k = 0; k < robots.size(); ++k) {
    result.robots.push_back(Predict(*robots[k], roles[k], measurements, q[k], keep));
  }
  result.skip_infeasible = skip_infeasible;
  result.laser_sigma_m = calibrated.sensors.laser_sigma_m();
  result.inclinometer_sigma_rad = calibrated.sensors.inclinometer_sigma_rad();
  // The calibrated model against the noise: far above it, something the model leaves out.
  const RobotPrediction& cal = result.robots.front();
  const auto check = [&](const std::optional<ErrorSummary>& e, double sigma, const char* what, const char* sensor,
                         double unit, const char* unit_name) {
    if (!e || !(sigma > 0.0) || !(e->rms > kUnexplainedNoiseFactor * sigma)) return;
    char buffer[256];
    std::snprintf(buffer, sizeof(buffer),
                  "the calibrated robot's %s RMS error on these readings is %.3g %s, %.3g times the %s's sigma (%.3g %s; "
                  "more than %g)", what, unit * e->rms, unit_name, e->rms / sigma, sensor, unit * sigma, unit_name,
                  kUnexplainedNoiseFactor);
    result.warnings.push_back(std::string(buffer) +
                              ": the calibrated model does not explain these held-out readings. Check the robot file's "
                              "platform (mass, com, anchors) and pulleys, which the calibration does not identify, and "
                              "the sensors' error model (cablecal sensors fit); a 2-cable robot calibrated with "
                              "--equilibrium off predicts theta less well");
  };
  check(cal.z_m, result.laser_sigma_m, "z", "laser", 1e3, "mm");
  check(cal.theta_rad, result.inclinometer_sigma_rad, "theta", "inclinometer", 1e3, "mrad");
  return result;
}

double ZRmsRatio(const ValidationResult& result) { return Ratio(result, &RobotPrediction::z_m); }
double ThetaRmsRatio(const ValidationResult& result) { return Ratio(result, &RobotPrediction::theta_rad); }

std::string NotCompared(const ValidationResult& result) {
  std::vector<std::string> missing;
  if (!result.has_laser) missing.push_back("laser");
  if (!result.has_inclinometer) missing.push_back("inclinometer");
  return MissingSensorsText(missing);
}

std::string ValidationCsv(const ValidationResult& result, const std::string& provenance) {
  return PoseTableCsv(Columns(result), result.pose_ids, [&](std::size_t j) { return Row(result, j); }, provenance);
}

std::string ValidationRowsJson(const ValidationResult& result) {
  return PoseTableRowsJson(Columns(result), result.pose_ids, [&](std::size_t j) { return Row(result, j); });
}

std::string ValidationSummaryYaml(const ValidationResult& result, const std::string& command_line) {
  YAML::Emitter o;
  o << YAML::Comment("cablecal validation summary (README, \"Validation\"). SI units: m, rad. error = predicted - measured")
    << YAML::BeginMap;
  EmitProvenance(o, command_line);
  o << YAML::Key << "readings" << YAML::Value << result.pose_ids.size();
  o << YAML::Key << "poses" << YAML::Value << result.num_poses;
  // Only with --skip-infeasible: a summary without it reads as before.
  if (result.skip_infeasible) {
    o << YAML::Key << "skipped" << YAML::Value << result.skipped.size()
      << YAML::Comment("readings left out: a robot cannot hold them (--skip-infeasible)");
    o << YAML::Key << "skipped_readings" << YAML::Value;
    if (result.skipped.empty()) o << YAML::Flow;
    o << YAML::BeginSeq;
    for (const SkippedReading& k : result.skipped) {
      o << YAML::Flow << YAML::BeginMap << YAML::Key << "pose" << YAML::Value << k.pose_id << YAML::Key << "where"
        << YAML::Value << YamlString{k.where} << YAML::Key << "reason" << YAML::Value << YamlString{k.reason}
        << YAML::EndMap;
    }
    o << YAML::EndSeq;
  }
  o << YAML::Key << "compared" << YAML::Value << YAML::Flow << YAML::BeginSeq;
  if (result.has_laser) o << "z";
  if (result.has_inclinometer) o << "theta";
  o << YAML::EndSeq;
  if (!NotCompared(result).empty()) o << YAML::Key << "not_compared" << YAML::Value << YamlString{NotCompared(result)};
  o << YAML::Key << "sensor_noise" << YAML::Value << YAML::Flow << YAML::BeginMap;
  if (result.has_laser) o << YAML::Key << "laser_sigma_m" << YAML::Value << YamlNumber{result.laser_sigma_m};
  if (result.has_inclinometer) {
    o << YAML::Key << "inclinometer_sigma_rad" << YAML::Value << YamlNumber{result.inclinometer_sigma_rad};
  }
  o << YAML::EndMap << YAML::Comment("the least RMS errors a perfect model shows: more where encoder noise moves the predicted pose");
  if (result.corrected_for) EmitSensorCorrection(o, *result.corrected_for, "before the comparison");
  for (const RobotPrediction& p : result.robots) {
    o << YAML::Key << p.name << YAML::Value << YAML::BeginMap;
    o << YAML::Key << "robot" << YAML::Value << YamlString{p.robot};
    o << YAML::Key << "file" << YAML::Value << YamlString{p.source};
    EmitStats(o, "z", "m", p.z_m);
    EmitStats(o, "theta", "rad", p.theta_rad);
    o << YAML::EndMap;
  }
  if (result.robots.size() > 1) {
    o << YAML::Key << "nominal_over_calibrated" << YAML::Value << YAML::Flow << YAML::BeginMap;
    if (result.has_laser) o << YAML::Key << "z_rms" << YAML::Value << YamlNumber{ZRmsRatio(result)};
    if (result.has_inclinometer) o << YAML::Key << "theta_rms" << YAML::Value << YamlNumber{ThetaRmsRatio(result)};
    o << YAML::EndMap << YAML::Comment("> 1: the calibration helped");
  }
  if (!result.warnings.empty()) {
    o << YAML::Key << "warnings" << YAML::Value << YAML::BeginSeq;
    for (const std::string& w : result.warnings) o << YamlString{w};
    o << YAML::EndSeq;
  }
  o << YAML::EndMap;
  return YamlText(o);
}

}  // namespace cablecal
