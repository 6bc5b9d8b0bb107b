#include "identify/validate.h"

#include <cmath>
#include <cstdio>
#include <limits>

#include "common/error.h"
#include "common/format.h"
#include "common/version.h"
#include "common/yaml_writer.h"
#include "identify/identify.h"
#include "model/statics.h"

namespace cablecal {
namespace {

std::string Where(const Measurement& m, const std::string& source) {
  return m.where.empty() ? source + ": pose " + std::to_string(m.pose_id) : m.where;
}

// "the nominal robot (robots/x.yaml)": which model failed, for messages.
std::string RobotLabel(const std::string& role, const Robot& robot) { return "the " + role + " robot (" + robot.source + ")"; }

// Where `robot` holds the pose's lengths l_i0 + dl_i. The start is the pose the sensors saw:
// the measured z and theta, with the x that best explains the encoders there. The platform
// was within millimetres of it (a centimetre or two for an uncalibrated model), so Newton
// lands on the equilibrium the lab's platform was in, not on another one a cold start from
// home could reach; and a solution far from it means the readings are not this robot's.
Eigen::Vector3d PredictPose(const Robot& robot, const std::string& role, const GeometryVector& geometry,
                            const Measurement& m, const std::string& source) {
  const int cables = robot.num_cables();
  const Eigen::Vector3d start(XFromReadings(robot, geometry, m), m.z_m, m.theta_rad);
  const Eigen::VectorXd lengths = geometry.tail(cables) + m.dl_m;  // l_i0 + dl_i
  const ForwardResult fwd = SolveForwardGeometricoStatic(robot, lengths, &start);
  const std::string where = Where(m, source);
  const std::string hint = ": readings of another robot, or a pose outside its workspace?";
  if (fwd.status != ForwardStatus::kConverged) {
    throw InputError(where, "", RobotLabel(role, robot) + " cannot hold these lengths, its initial lengths + dl (" +
                                    CannotHoldReason(fwd.status, "where the laser and inclinometer saw the platform") +
                                    ")" + hint);
  }
  // With 2 cables the forward model falls back on cold starts and keeps any stable
  // equilibrium: the same test as for 3 or more (kOtherAssembly) keeps it honest.
  const Eigen::Vector3d& q = fwd.equilibrium.q;
  const double distance_m = (q.head<2>() - start.head<2>()).norm(), turn_rad = std::abs(q(2) - start(2));
  if (distance_m > kOtherAssemblyDistance_m || turn_rad > kOtherAssemblyAngle_rad) {
    char at[160];
    std::snprintf(at, sizeof at, "(%.3f, %.3f) m, %.3f rad, %.3f m and %.3f rad", q(0), q(1), q(2), distance_m,
                  turn_rad);
    throw InputError(where, "", RobotLabel(role, robot) + " holds these lengths only at " + at +
                                    " from where the laser and inclinometer saw the platform" + hint);
  }
  return q;
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

RobotPrediction Predict(const Robot& robot, const std::string& role, const std::vector<Measurement>& measurements,
                        const std::string& source) {
  RobotPrediction p;
  p.name = role;
  p.robot = robot.name;
  p.source = robot.source;
  const GeometryVector geometry = GeometryOf(robot);
  for (const Measurement& m : measurements) {
    const Eigen::Vector3d q = PredictPose(robot, role, geometry, m, source);
    p.q.push_back(q);
    p.z_error_m.push_back(q(1) - m.z_m);
    p.theta_error_rad.push_back(q(2) - m.theta_rad);
  }
  p.z_m = Stats(p.z_error_m);
  p.theta_rad = Stats(p.theta_error_rad);
  return p;
}

double Ratio(const ValidationResult& r, ErrorSummary RobotPrediction::*stats) {
  if (r.robots.size() < 2) return std::numeric_limits<double>::quiet_NaN();
  return (r.robots[1].*stats).rms / (r.robots[0].*stats).rms;
}

// The CSV's columns, in order, and each row's values: one place for the CSV and the JSON.
std::vector<std::string> Columns(const ValidationResult& r) {
  std::vector<std::string> c = {"pose", "z_measured_m", "theta_measured_rad"};
  for (const RobotPrediction& p : r.robots) {
    for (const char* f : {"x_%_m", "z_%_m", "theta_%_rad", "z_error_%_m", "theta_error_%_rad"}) {
      std::string name = f;
      c.push_back(name.replace(name.find('%'), 1, p.name));
    }
  }
  return c;
}
std::vector<double> Row(const ValidationResult& r, std::size_t j) {
  std::vector<double> v = {r.z_measured_m[j], r.theta_measured_rad[j]};
  for (const RobotPrediction& p : r.robots) {
    v.insert(v.end(), {p.q[j](0), p.q[j](1), p.q[j](2), p.z_error_m[j], p.theta_error_rad[j]});
  }
  return v;
}

void EmitStats(YAML::Emitter& o, const char* key, const char* unit, const ErrorSummary& s) {
  o << YAML::Key << key << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key << std::string("rms_") + unit
    << YAML::Value << YamlNumber{s.rms} << YAML::Key << std::string("max_abs_") + unit << YAML::Value
    << YamlNumber{s.max_abs} << YAML::EndMap;
}

}  // namespace

ValidationResult Validate(const Robot& calibrated, const std::optional<Robot>& nominal,
                          const std::vector<Measurement>& measurements, const std::string& source) {
  if (measurements.empty()) throw InputError(source, "", "no poses to validate on");
  const int m = calibrated.num_cables();
  if (nominal && nominal->num_cables() != m) {
    throw InputError(nominal->source, "", "the nominal robot has " + std::to_string(nominal->num_cables()) +
                                              " cables, the calibrated robot " + std::to_string(m) +
                                              ": a file for another robot?");
  }
  for (const Measurement& r : measurements) {
    if (r.dl_m.size() != m) {
      throw InputError(Where(r, source), "", std::to_string(r.dl_m.size()) + " encoder readings for a robot with " +
                                                 std::to_string(m) + " cables");
    }
  }
  ValidationResult result;
  for (const Measurement& r : measurements) {
    result.pose_ids.push_back(r.pose_id);
    result.z_measured_m.push_back(r.z_m);
    result.theta_measured_rad.push_back(r.theta_rad);
  }
  result.robots.push_back(Predict(calibrated, "calibrated", measurements, source));
  if (nominal) result.robots.push_back(Predict(*nominal, "nominal", measurements, source));
  result.laser_sigma_m = calibrated.sensors.laser_sigma_m();
  result.inclinometer_sigma_rad = calibrated.sensors.inclinometer_sigma_rad();
  return result;
}

double ZRmsRatio(const ValidationResult& result) { return Ratio(result, &RobotPrediction::z_m); }
double ThetaRmsRatio(const ValidationResult& result) { return Ratio(result, &RobotPrediction::theta_rad); }

std::string ValidationCsv(const ValidationResult& result, const std::string& provenance) {
  std::string out = provenance;
  const std::vector<std::string> columns = Columns(result);
  for (std::size_t k = 0; k < columns.size(); ++k) out += (k ? "," : "") + columns[k];
  out += "\n";
  for (std::size_t j = 0; j < result.pose_ids.size(); ++j) {
    out += std::to_string(result.pose_ids[j]);
    for (const double v : Row(result, j)) out += "," + FormatDouble(v);
    out += "\n";
  }
  return out;
}

std::string ValidationRowsYaml(const ValidationResult& result) {
  const std::vector<std::string> columns = Columns(result);
  YAML::Emitter o;
  o << YAML::BeginSeq;
  for (std::size_t j = 0; j < result.pose_ids.size(); ++j) {
    o << YAML::Flow << YAML::BeginMap << YAML::Key << columns[0] << YAML::Value << result.pose_ids[j];
    const std::vector<double> row = Row(result, j);
    for (std::size_t k = 0; k < row.size(); ++k) o << YAML::Key << columns[k + 1] << YAML::Value << YamlNumber{row[k]};
    o << YAML::EndMap;
  }
  o << YAML::EndSeq;
  return YamlText(o);
}

std::string ValidationSummaryYaml(const ValidationResult& result, const std::string& command_line) {
  YAML::Emitter o;
  o << YAML::Comment("cablecal validation summary (README, \"validate\"). SI units: m, rad. error = predicted - measured")
    << YAML::BeginMap;
  o << YAML::Key << "cablecal" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key << "version" << YAML::Value
    << YamlString{Version()} << YAML::Key << "commit" << YAML::Value << YamlString{GitCommit()} << YAML::EndMap;
  o << YAML::Key << "command" << YAML::Value << YamlString{command_line};
  o << YAML::Key << "poses" << YAML::Value << result.pose_ids.size();
  o << YAML::Key << "sensor_noise" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key << "laser_sigma_m"
    << YAML::Value << YamlNumber{result.laser_sigma_m} << YAML::Key << "inclinometer_sigma_rad" << YAML::Value
    << YamlNumber{result.inclinometer_sigma_rad} << YAML::EndMap
    << YAML::Comment("the RMS errors a perfect model would show");
  for (const RobotPrediction& p : result.robots) {
    o << YAML::Key << p.name << YAML::Value << YAML::BeginMap;
    o << YAML::Key << "robot" << YAML::Value << YamlString{p.robot};
    o << YAML::Key << "file" << YAML::Value << YamlString{p.source};
    EmitStats(o, "z", "m", p.z_m);
    EmitStats(o, "theta", "rad", p.theta_rad);
    o << YAML::EndMap;
  }
  if (result.robots.size() > 1) {
    o << YAML::Key << "nominal_over_calibrated" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key << "z_rms"
      << YAML::Value << YamlNumber{ZRmsRatio(result)} << YAML::Key << "theta_rms" << YAML::Value
      << YamlNumber{ThetaRmsRatio(result)} << YAML::EndMap << YAML::Comment("> 1: the calibration helped");
  }
  o << YAML::EndMap;
  return YamlText(o);
}

}  // namespace cablecal
