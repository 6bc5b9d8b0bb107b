#include "identify/spatial_report.h"

#include <algorithm>
#include <cmath>
#include <yaml-cpp/yaml.h>

#include "common/error.h"
#include "common/format.h"
#include "common/json.h"
#include "common/yaml_writer.h"
#include "identify/identify.h"  // EmitProvenance, kOutlierSigmas
#include "model/spatial_sensor_model.h"

namespace cablecal {
namespace {

using YAML::BeginMap;
using YAML::BeginSeq;
using YAML::EndMap;
using YAML::EndSeq;
using YAML::Flow;
using YAML::Key;
using YAML::Value;


bool SensorRead(const SpatialIdentifyResult& r, SpatialSensor s) {
  return std::any_of(r.fits.begin(), r.fits.end(),
                     [s](const SpatialReadingFit& f) { return f.sensors[static_cast<int>(s)].size() > 0; });
}

std::string JoinNames(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

bool IsHeldName(const SpatialIdentifyResult& r, const std::string& name) {
  return std::find(r.held.begin(), r.held.end(), name) != r.held.end();
}

std::string GaugeNote(const SpatialIdentifyOptions& options, const SpatialIdentifyResult& r) {
  const std::string held = r.held.empty() ? std::string("nothing") : JoinNames(r.held);
  switch (options.gauge.kind) {
    case SpatialGaugeKind::kAuto: {
      if (r.held.empty()) return "the readings see every direction of the geometry: nothing held";
      const auto nearly_rigid = std::count_if(r.weak_directions.begin(), r.weak_directions.end(),
                                              [](const SpatialDirection& d) { return d.nearly_rigid; });
      const std::size_t null = r.null_directions.size();
      std::string directions;
      if (null > 0) directions = "the " + std::to_string(null) + " null direction" + (null > 1 ? "s" : "");
      if (nearly_rigid > 0) {
        directions += std::string(null > 0 ? " and " : "") + "the " + std::to_string(nearly_rigid) +
                      " weakly seen direction" + (nearly_rigid > 1 ? "s" : "") +
                      " nearly a rigid motion of the frame, which --gauge hold: without " +
                      (nearly_rigid > 1 ? "them" : "it") + " estimates, slowly (raise --max-iterations)";
      }
      return "held at their nominal values: " + held + " (the " +
             (options.anchors ? "exit coordinates, then the anchor coordinates," : "exit coordinates") +
             " a column-pivoted QR picks, one per direction, of " + directions + ")";
    }
    case SpatialGaugeKind::kHold: return "held at their nominal values, the lab's choice: " + held;
    case SpatialGaugeKind::kNone:
      return "no gauge: the null directions below are unobservable; standard deviations are from the "
             "pseudo-inverse and exclude them";
    case SpatialGaugeKind::kPrior: return "laser-tracker prior on every exit coordinate (sensors.tracker.sigma)";
  }
  return "";
}

// `weak`: each direction also says whether it is nearly a rigid motion of the frame (which the
// default gauge holds).
void EmitDirections(YAML::Emitter& o, const char* key, const std::vector<SpatialDirection>& directions,
                    const std::string& comment, bool weak = false) {
  o << Key << key << Value;
  if (!comment.empty()) o << YAML::Comment(comment);
  if (directions.empty()) o << Flow;
  o << BeginSeq;
  for (const SpatialDirection& d : directions) {
    o << BeginMap << Key << "description" << Value << YamlString{d.description} << Key << "relative_singular_value"
      << Value << YamlNumber{d.relative_singular_value};
    if (weak) o << Key << "nearly_rigid" << Value << d.nearly_rigid;
    o << Key << "vector" << Value << Flow << BeginSeq;
    for (int k = 0; k < d.geometry.size(); ++k) o << YamlNumber{d.geometry(k)};
    o << EndSeq << EndMap;
  }
  o << EndSeq;
}

struct ResultParts {
  std::string head, poses, readings;
};

// Long (~150 lines) for a reason: result.yaml's keys in the file's order, written once for
// the YAML and the JSON.
ResultParts Parts(const SpatialRobot& nominal, const SpatialIdentifyOptions& options, const SpatialIdentifyResult& r,
                  const std::string& command_line, bool json) {
  YAML::Emitter o;
  o << YAML::Comment("cablecal identification result (README, \"identify\"; spatial robot). SI units: m, rad, N, kg.")
    << BeginMap;
  EmitProvenance(o, command_line);
  const int m = nominal.num_cables();
  o << Key << "robot" << Value << Flow << BeginMap << Key << "name" << Value << YamlString{nominal.name} << Key
    << "cables" << Value << m << Key << "kind" << Value << "spatial" << EndMap;
  o << Key << "status" << Value << ToString(r.status);
  if (!r.message.empty()) o << Key << "message" << Value << YamlString{r.message};
  o << Key << "estimator" << Value << "ml";
  o << Key << "identify" << Value << SpatialIdentifyName(options.anchors)
    << YAML::Comment(options.anchors ? "exit points, initial lengths and platform anchors"
                                     : "exit points and initial lengths; the anchors the robot file's");
  o << Key << "gauge" << Value << YamlString{ToString(options.gauge)};
  o << Key << "gauge_note" << Value << YamlString{GaugeNote(options, r)};
  o << Key << "held" << Value << Flow << BeginSeq;
  for (const std::string& h : r.held) o << h;
  o << EndSeq;
  EmitDirections(o, "null_directions", r.null_directions,
                 "what no reading sees (at the nominal geometry, before holding anything); vector: over the "
                 "parameters, in their order");
  EmitDirections(o, "weak_directions", r.weak_directions,
                 "seen, but below " + FormatDouble(kSpatialWeakThreshold) +
                     " of the best-seen direction; nearly_rigid: within 5 % of a rigid motion of the frame, "
                     "which the default gauge holds",
                 true);
  o << Key << "iterations" << Value << r.iterations;
  o << Key << "final_cost" << Value << YamlNumber{r.final_cost}
    << YAML::Comment("half the sum of squared whitened residuals");
  o << Key << "residual_rms" << Value << Flow << BeginMap;
  for (const auto& [key, value] : SpatialResidualRms(nominal, r)) o << Key << key << Value << YamlNumber{value};
  o << EndMap;
  const std::vector<std::string> missing = MissingSpatialSensors(nominal, r);
  if (!missing.empty()) {
    o << Key << "missing_sensors" << Value << Flow << BeginSeq;
    for (const std::string& s : missing) o << s;
    o << EndSeq << YAML::Comment("in the robot file, but no such columns in the measurements: not read");
  }
  if (!r.unused_sensors.empty()) {
    o << Key << "unused_sensors" << Value << Flow << BeginSeq;
    for (const std::string& s : r.unused_sensors) o << s;
    o << EndSeq << YAML::Comment("read but not modelled (statics off)");
  }
  o << Key << "worst_reading" << Value << Flow << BeginMap << Key << "pose" << Value << r.worst_pose_id << Key
    << "sensor" << Value << YamlString{r.worst_sensor} << Key << "where" << Value << YamlString{r.worst_where} << Key
    << "sigmas" << Value << YamlNumber{r.worst_residual} << EndMap
    << YAML::Comment("the largest whitened residual (model - reading) / sigma");
  if (!r.warnings.empty()) {
    o << Key << "warnings" << Value << BeginSeq;
    for (const std::string& w : r.warnings) o << YamlString{w};
    o << EndSeq;
  }
  o << Key << "statics" << Value << (options.statics ? "on" : "off");
  o << Key << "loss" << Value << ToString(options.loss);
  const int n = static_cast<int>(r.names.size());
  const bool has_covariance = r.covariance.rows() == n && n > 0;
  o << Key << "parameters" << Value << BeginMap;
  for (int k = 0; k < n; ++k) {
    o << Key << r.names[k] << Value << Flow << BeginMap << Key << "value" << Value << YamlNumber{r.geometry(k)};
    if (has_covariance) o << Key << "std" << Value << YamlNumber{r.sigma(k)};
    if (IsHeldName(r, r.names[k])) o << Key << "held" << Value << true;
    o << EndMap;
  }
  o << EndMap;
  if (has_covariance) {
    // A held parameter has no variance: its correlations are written 0.
    o << Key << "correlation" << Value << YAML::Comment("the parameters, in the order above; held: 0");
    EmitMatrixRows(o, n, [&](int a, int b) {
      const double s = r.sigma(a) * r.sigma(b);
      return s > 0.0 ? r.covariance(a, b) / s : 0.0;
    });
    o << Key << "covariance" << Value << YAML::Comment("the parameters, in the order above (m, rad, kg)");
    EmitMatrixRows(o, n, [&](int a, int b) { return r.covariance(a, b); });
  }
  o << EndMap;

  const FlowRows::Syntax syntax = json ? FlowRows::Syntax::kJson : FlowRows::Syntax::kYaml;
  const auto number = [](FlowRows& rows, const std::string& key, double value) {
    rows.Key(key.c_str());
    rows.Number(value);
  };
  const auto list = [](FlowRows& rows, const std::string& key, const Eigen::VectorXd& values) {
    rows.Key(key.c_str());
    rows.BeginList();
    for (int i = 0; i < values.size(); ++i) rows.Number(values(i));
    rows.EndList();
  };
  FlowRows poses(syntax);
  for (std::size_t j = 0; j < r.poses.size(); ++j) {
    poses.BeginRow();
    poses.Key("pose");
    poses.Int(r.pose_ids[j]);
    for (int k = 0; k < SpatialKind::kPoseDim; ++k) number(poses, SpatialKind::kPoseNames[k], r.poses[j](k));
    if (j < r.tensions_N.size() && r.tensions_N[j].size() > 0) list(poses, "tensions_N", r.tensions_N[j]);
    poses.EndRow();
  }
  FlowRows readings(syntax);
  for (std::size_t k = 0; k < r.fits.size(); ++k) {
    const SpatialReadingFit& f = r.fits[k];
    readings.BeginRow();
    readings.Key("reading");
    readings.Int(static_cast<long long>(k + 1));
    readings.Key("pose");
    readings.Int(f.pose_id);
    list(readings, "encoder_sigmas", f.encoders);
    for (const SpatialSensor s : kSpatialSensors) {
      const Eigen::VectorXd& v = f.sensors[static_cast<int>(s)];
      if (v.size() > 0) list(readings, std::string(ToString(s)) + "_sigmas", v);
    }
    if (f.equilibrium.size() > 0) list(readings, "equilibrium_sigmas", f.equilibrium);
    // Each value's leverage (SpatialReadingLeverage), when computed.
    if (f.leverage.encoders.size() > 0) list(readings, "encoder_leverage", f.leverage.encoders);
    for (const SpatialSensor s : kSpatialSensors) {
      const Eigen::VectorXd& v = f.leverage.sensors[static_cast<int>(s)];
      if (v.size() > 0) list(readings, std::string(ToString(s)) + "_leverage", v);
    }
    readings.EndRow();
  }
  return {YamlText(o),
          poses.Finish("poses", r.tensions_N.empty() ? "identified poses: x, y, z (m), roll, pitch, yaw (rad)"
                                                     : "identified poses: x, y, z (m), roll, pitch, yaw (rad), "
                                                       "cable tensions (N)"),
          readings.Finish("readings",
                          "per reading (data row), each value's residual (model - reading) over its sigma; "
                          "equilibrium: force then moment rows, on a pose's first reading; _leverage: how much of "
                          "each value the fit follows (0 to 1; near 1, no other reading checks it)")};
}

}  // namespace

const char* SpatialGeometryUnit(const std::string& name) {
  if (name == "mass") return "kg";
  return name.rfind("sw", 0) == 0 || name == "yaw0" ? "rad" : "m";
}

std::vector<std::string> MissingSpatialSensors(const SpatialRobot& nominal, const SpatialIdentifyResult& result) {
  std::vector<std::string> missing;
  for (const SpatialSensor s : kSpatialSensors) {
    const bool unused = std::find(result.unused_sensors.begin(), result.unused_sensors.end(), ToString(s)) !=
                        result.unused_sensors.end();
    if (HasSpatialSensor(nominal, s) && !unused && !SensorRead(result, s)) missing.push_back(ToString(s));
  }
  return missing;
}

std::vector<std::pair<std::string, double>> SpatialResidualRms(const SpatialRobot& nominal,
                                                               const SpatialIdentifyResult& r) {
  const auto rms = [&r](const auto& values_of, double sigma) {
    double sum = 0.0;
    long count = 0;
    for (const SpatialReadingFit& f : r.fits) {
      const Eigen::VectorXd& v = values_of(f);
      sum += (v * sigma).squaredNorm();
      count += v.size();
    }
    return count ? std::sqrt(sum / count) : 0.0;
  };
  std::vector<std::pair<std::string, double>> out = {
      {"encoder_m", rms([](const SpatialReadingFit& f) -> const Eigen::VectorXd& { return f.encoders; },
                        nominal.sensors.encoder_sigma_m)}};
  for (const SpatialSensor s : kSpatialSensors) {
    const std::optional<RangedNoise> noise = SpatialSensorNoise(nominal.sensors, s);
    if (!noise || !SensorRead(r, s)) continue;
    const auto values = [s](const SpatialReadingFit& f) -> const Eigen::VectorXd& {
      return f.sensors[static_cast<int>(s)];
    };
    out.emplace_back(std::string(ToString(s)) + "_" + SpatialSensorUnit(s), rms(values, noise->sigma()));
  }
  return out;
}

std::string SpatialIdentifyResultYaml(const SpatialRobot& nominal, const SpatialIdentifyOptions& options,
                                      const SpatialIdentifyResult& result, const std::string& command_line) {
  const ResultParts parts = Parts(nominal, options, result, command_line, false);
  return parts.head + parts.poses + parts.readings;
}

std::string SpatialIdentifyResultJson(const SpatialRobot& nominal, const SpatialIdentifyOptions& options,
                                      const SpatialIdentifyResult& result, const std::string& command_line) {
  const ResultParts parts = Parts(nominal, options, result, command_line, true);
  return MergeJsonObjects({ToJson(YAML::Load(parts.head)), parts.poses, parts.readings});
}

SpatialRobot CalibratedSpatialRobot(const SpatialRobot& nominal, const SpatialIdentifyResult& result) {
  const int m = nominal.num_cables();
  CABLECAL_CHECK(static_cast<int>(result.names.size()) >= 4 * m && result.names[4 * m - 1] == "l" + std::to_string(m) + "0",
                 "a spatial result of another robot");
  SpatialRobot calibrated = nominal;
  // The anchors when identified: b1x .. bmz right after the lengths (the names' order).
  const bool anchors = static_cast<int>(result.names.size()) >= 7 * m && result.names[4 * m] == "b1x";
  for (int i = 0; i < m; ++i) {
    calibrated.cables[i].p_F_exit_m = result.geometry.segment<3>(3 * i);
    calibrated.cables[i].initial_length_m = result.geometry(3 * m + i);
    if (anchors) calibrated.cables[i].p_P_anchor_m = result.geometry.segment<3>(4 * m + 3 * i);
  }
  // The mass and centre of mass when the statics estimated them: the last four names.
  const int p = static_cast<int>(result.names.size());
  if (p >= 4 * m + 4 && result.names[p - 4] == kSpatialPlatformNames[0]) {
    calibrated.platform_mass_kg = result.geometry(p - 4);
    calibrated.p_P_com_m = result.geometry.tail<3>();
  }
  return calibrated;
}

SpatialIdentifiedGeometry ReadSpatialIdentifiedGeometry(const SpatialRobot& nominal, const std::string& path) {
  YAML::Node root = LoadIdentifyResultYaml(path);  // not const: a missing key reads as a null node
  const YAML::Node of = root["robot"];
  if (!of.IsMap() || of["kind"].as<std::string>("") != "spatial") {
    throw InputError(path, "robot", "not the result of a spatial robot's identification");
  }
  RequireResultOfRobot(path, of["name"].as<std::string>(""), of["cables"].as<int>(0), nominal.source, nominal.name,
                       nominal.num_cables());
  if (root["status"].as<std::string>("") != "converged") {
    throw InputError(path, "status", "the identification did not converge: it cannot be a prior");
  }
  if (root["gauge"].as<std::string>("") == "none") {
    throw InputError(path, "gauge", "a result identified with --gauge none cannot be a prior (its sigmas leave out the "
                                    "directions it does not fix): identify the same data with --gauge auto or prior");
  }
  SpatialIdentifiedGeometry known;
  known.source = path;
  const YAML::Node held = root["held"];
  if (held && !held.IsSequence()) throw InputError(path, "held", "must be a list of coordinate names");
  for (const YAML::Node& h : held) known.held.push_back(h.as<std::string>(""));
  const YAML::Node parameters = root["parameters"];
  if (!parameters.IsMap()) throw InputError(path, "parameters", "must be a map of the unknowns");
  for (const auto& entry : parameters) {
    const std::string name = entry.first.as<std::string>("");
    const std::string key = "parameters." + name;
    const YAML::Node value = entry.second["value"];
    if (!value) throw InputError(path, key + ".value", "missing");
    known.names.push_back(name);
    const double v = value.as<double>(NAN);
    if (!std::isfinite(v)) throw InputError(path, key + ".value", "must be a finite number");
    known.geometry.conservativeResize(known.geometry.size() + 1);
    known.geometry(known.geometry.size() - 1) = v;
  }
  const int p = static_cast<int>(known.names.size());
  const int m = nominal.num_cables();
  const std::vector<std::string> exits_and_lengths = SpatialGeometryNames(m, false, false);
  if (p < 4 * m || !std::equal(exits_and_lengths.begin(), exits_and_lengths.end(), known.names.begin())) {
    throw InputError(path, "parameters", "needs " + nominal.name + "'s exit coordinates and initial lengths (a1x .. l" +
                                             std::to_string(m) + "0) first: a result for another robot?");
  }
  const std::string matrix = "needs the " + std::to_string(p) + " x " + std::to_string(p) + " matrix of the parameters";
  const YAML::Node cov = root["covariance"];
  if (!cov || !cov.IsSequence() || static_cast<int>(cov.size()) != p) {
    throw InputError(path, "covariance", matrix + " (identify writes it when it computes standard deviations)");
  }
  known.covariance.resize(p, p);
  for (int a = 0; a < p; ++a) {
    if (!cov[a].IsSequence() || static_cast<int>(cov[a].size()) != p) throw InputError(path, "covariance", matrix);
    for (int b = 0; b < p; ++b) {
      known.covariance(a, b) = cov[a][b].as<double>(NAN);
      if (!std::isfinite(known.covariance(a, b))) {
        throw InputError(path, "covariance", "row " + std::to_string(a + 1) + ": must be finite numbers");
      }
    }
  }
  return known;
}

SpatialRobot CalibratedSpatialRobot(const SpatialRobot& nominal, const SpatialIdentifiedGeometry& known) {
  SpatialIdentifyResult result;
  result.names = known.names;
  result.geometry = known.geometry;
  return CalibratedSpatialRobot(nominal, result);
}

}  // namespace cablecal
