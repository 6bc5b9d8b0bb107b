// result.yaml of `cablecal identify`: its writer and its reader.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>

#include "common/error.h"
#include "common/format.h"
#include "common/json.h"
#include "common/yaml_writer.h"
#include "common/version.h"
#include "identify/identify.h"
#include "model/geometry.h"
#include "model/kind.h"

namespace cablecal {
namespace {

using YAML::BeginMap;
using YAML::BeginSeq;
using YAML::EndMap;
using YAML::EndSeq;
using YAML::Flow;
using YAML::Key;
using YAML::Value;

}  // namespace

void EmitProvenance(YAML::Emitter& o, const std::string& command_line) {
  o << Key << "cablecal" << Value << Flow << BeginMap << Key << "version" << Value << YamlString{Version()} << Key
    << "commit" << Value << YamlString{GitCommit()} << EndMap;
  o << Key << "command" << Value << YamlString{command_line};
}

void EmitSensorCorrection(YAML::Emitter& o, const SystematicSensorErrors& e, const std::string& when) {
  o << Key << "sensor_correction" << Value << BeginMap << Key << "note" << Value
    << YamlString{"laser and inclinometer readings corrected for the robot file's systematic sensor errors " + when +
                  " (README, \"Sensor error models\")"}
    << Key << "laser_offset_m" << Value << YamlNumber{e.laser_offset_m} << Key << "inclinometer_offset_rad" << Value
    << YamlNumber{e.inclinometer_offset_rad} << Key << "inclinometer_sec_coefficient_rad" << Value
    << YamlNumber{e.inclinometer_sec_coefficient_rad} << EndMap;
}

bool IsHeld(const IdentifyResult& r, int k) {
  return std::find(r.held_geometry.begin(), r.held_geometry.end(), k) != r.held_geometry.end();
}

namespace {

// result.yaml in its parts: the head (a map from the provenance to the correlations), the two
// tables, and the tail (identifiability); YAML text, or with `json` the tables as JSON members.
struct ResultParts {
  std::string head, poses, readings, tail;
};

// Long (~200 lines) for a reason: result.yaml's keys in the file's order, written once.
ResultParts IdentifyResultParts(const IdentifyResult& r, const std::string& command_line, bool json) {
  YAML::Emitter o;
  o << YAML::Comment("cablecal identification result (README, \"identify\"). SI units: m, rad.") << BeginMap;
  EmitProvenance(o, command_line);
  // The robot it was identified for: design --prior and Python refuse the result beside a robot
  // of another name or cable count.
  if (!r.robot_name.empty()) {
    o << Key << "robot" << Value << Flow << BeginMap << Key << "name" << Value << YamlString{r.robot_name} << Key
      << "cables" << Value << static_cast<int>(r.geometry.size()) / 3 << EndMap;
  }
  o << Key << "status" << Value << ToString(r.status);
  if (!r.message.empty()) o << Key << "message" << Value << YamlString{r.message};
  o << Key << "estimator" << Value << ToString(r.estimator);
  o << Key << "gauge" << Value << ToString(r.gauge);
  std::string note;
  switch (r.gauge) {
    case Gauge::kA1x: note = "a1x held at its nominal value: the frame's x origin is defined by exit point 1"; break;
    case Gauge::kPrior: note = "laser-tracker prior on every exit point (sensors.tracker.sigma)"; break;
    case Gauge::kNone:
      note = "no gauge (the paper's problem): a common shift of every a_ix and x_j is unobservable; standard "
             "deviations are from the pseudo-inverse and exclude that direction";
      break;
  }
  o << Key << "gauge_note" << Value << YamlString{note};
  if (r.geometry_prior_sigma_m > 0.0) {  // only when given: a result without one reads as before
    o << Key << "geometry_prior_sigma_m" << Value << YamlNumber{r.geometry_prior_sigma_m}
      << YAML::Comment("a Gaussian prior on every geometric parameter about its nominal value");
  }
  // Only when applied: a result from a robot file without systematic terms reads as before.
  if (r.corrected_for) EmitSensorCorrection(o, *r.corrected_for, "before the solve");
  o << Key << "iterations" << Value << r.iterations;
  o << Key << "final_cost" << Value << YamlNumber{r.final_cost}
    << YAML::Comment("half the sum of squared (whitened, for ml) residuals");
  const auto missing = [&](const char* sensor) {
    return std::find(r.missing_sensors.begin(), r.missing_sensors.end(), sensor) != r.missing_sensors.end();
  };
  o << Key << "residual_rms" << Value << Flow << BeginMap << Key << "encoder_m" << Value << YamlNumber{r.rms_encoder_m};
  for (const SensorUnit& u : kPlanarSensors) {
    if (!missing(u.name)) o << Key << std::string(u.name) + "_" + u.unit << Value << YamlNumber{r.rms_sensor[static_cast<int>(u.id)]};
  }
  o << EndMap;
  if (!r.missing_sensors.empty()) {
    o << Key << "missing_sensors" << Value << Flow << BeginSeq;
    for (const std::string& sensor : r.missing_sensors) o << sensor;
    o << EndSeq << YAML::Comment("no such column in the measurements: see identifiability");
  }
  if (!r.warnings.empty()) {
    o << Key << "warnings" << Value << BeginSeq;
    for (const std::string& w : r.warnings) o << YamlString{w};
    o << EndSeq;
  }
  o << Key << "equilibrium" << Value;
  if (r.equilibrium_com_sigma_m) {
    o << Flow << BeginMap << Key << "com_sigma_m" << Value << YamlNumber{*r.equilibrium_com_sigma_m} << EndMap
      << YAML::Comment("each pose's static equilibrium was a residual (2 cables), with this sigma");
  } else {
    o << "off";
  }
  o << Key << "loss" << Value << ToString(r.loss);
  if (r.loss.kind != LossKind::kNone) {
    o << Key << "down_weighted" << Value
      << YAML::Comment("readings beyond " + FormatDouble(kOutlierSigmas) +
                       " sigma that the loss kept at a reduced weight instead of refusing the fit");
    if (r.down_weighted.empty()) o << Flow;
    o << BeginSeq;
    for (const std::string& d : r.down_weighted) o << YamlString{d};
    o << EndSeq;
    if (!r.dropped_pose_ids.empty()) {
      o << Key << "dropped_poses" << Value << Flow << BeginSeq;
      for (const int id : r.dropped_pose_ids) o << id;
      o << EndSeq
        << YAML::Comment("readings that do not fit the others, which the loss followed: the fit without them");
    }
  }
  if (r.estimator == Estimator::kPaper) {
    o << Key << "std_note" << Value
      << YamlString{std::string(r.gauge == Gauge::kNone
                                    ? "paper estimator: covariance scaled by the residual variance (conservative)"
                                    : "paper estimator: sandwich covariance, the encoder, laser and inclinometer "
                                      "noise propagated through its Eq. (6) residuals")};
  }
  const int geometry_size = static_cast<int>(r.geometry.size());
  const std::vector<std::string> names = GeometryNames(geometry_size / 3);
  o << Key << "parameters" << Value << BeginMap;
  for (int k = 0; k < geometry_size; ++k) {
    o << Key << names[k] << Value << Flow << BeginMap << Key << "value" << Value << YamlNumber{r.geometry(k)};
    if (r.has_covariance) o << Key << "std" << Value << YamlNumber{r.geometry_std(k)};
    if (IsHeld(r, k)) o << Key << "held" << Value << true;
    o << EndMap;
  }
  o << EndMap;
  if (r.has_covariance) {
    o << Key << "correlation" << Value << YAML::Comment("geometric parameters, in the order above");
    EmitMatrixRows(o, geometry_size, [&](int a, int b) { return r.geometry_correlation(a, b); });
  }
  o << EndMap;
  // The per-pose and per-reading tables (up to 100,000 rows each) by a writer of their own: the
  // same text as the emitter's, without its per-node cost (issue 24).
  const FlowRows::Syntax syntax = json ? FlowRows::Syntax::kJson : FlowRows::Syntax::kYaml;
  const bool ml = r.estimator == Estimator::kMaximumLikelihood;
  FlowRows poses(syntax);
  const auto number = [](FlowRows& rows, const std::string& key, double value) {
    rows.Key(key.c_str());
    rows.Number(value);
  };
  for (const PoseEstimate& p : r.poses) {
    poses.BeginRow();
    poses.Key("pose");
    poses.Int(p.pose_id);
    // The paper estimator estimates x alone (z and theta are the laser's and inclinometer's).
    for (int k = 0; k < PlanarKind::kPoseDim; ++k) {
      const std::string name = PlanarKind::kPoseNames[k];
      number(poses, name, p.q(k));
      if (r.has_covariance && (ml || k == 0)) number(poses, name + "_std", p.std_dev(k));
    }
    if (p.equilibrium_sigmas) number(poses, "equilibrium_sigmas", *p.equilibrium_sigmas);
    if (p.equilibrium_theta_error_rad) number(poses, "theta_minus_equilibrium_rad", *p.equilibrium_theta_error_rad);
    poses.EndRow();
  }
  ResultParts parts{YamlText(o), poses.Finish("poses"), "", ""};
  if (!r.readings.empty()) {
    FlowRows readings(syntax);
    const bool robust = r.loss.kind != LossKind::kNone;
    const auto list = [&](const char* key, const Eigen::VectorXd& values) {
      readings.Key(key);
      readings.BeginList();
      for (int i = 0; i < values.size(); ++i) readings.Number(values(i));
      readings.EndList();
    };
    for (std::size_t k = 0; k < r.readings.size(); ++k) {
      const ReadingFit& f = r.readings[k];
      readings.BeginRow();
      readings.Key("reading");
      readings.Int(static_cast<long long>(k + 1));
      readings.Key("pose");
      readings.Int(f.pose_id);
      list("encoder_sigmas", f.encoder_sigmas);
      for (const SensorUnit& u : kPlanarSensors) {
        const std::optional<double>& sigmas = f.sensor_sigmas[static_cast<int>(u.id)];
        if (sigmas) number(readings, std::string(u.name) + "_sigmas", *sigmas);
      }
      if (robust) {
        list("encoder_weights", f.encoder_weights);
        for (const SensorUnit& u : kPlanarSensors) {
          const int id = static_cast<int>(u.id);
          if (f.sensor_sigmas[id]) number(readings, std::string(u.name) + "_weight", f.sensor_weights[id]);
        }
      }
      if (f.min_detectable_sigmas.size() > 0) {
        // Encoders, then the laser and inclinometer the data have (a missing sensor's row is 0).
        readings.Key("detectable_sigmas");
        readings.BeginList();
        for (int i = 0; i < f.min_detectable_sigmas.size(); ++i) {
          if (f.HasValue(i)) readings.Number(f.min_detectable_sigmas(i));
        }
        readings.EndList();
      }
      readings.EndRow();
    }
    parts.readings = readings.Finish(
        "readings", std::string("per reading (data row), each sensor's residual (model - reading) over its sigma") +
                        (r.estimator == Estimator::kPaper ? " (paper: length residuals over the laser's sigma)" : "") +
                        (robust ? "; weights: the loss's, 1 = full" : ""));
  }
  const Identifiability& id = r.identifiability;
  if (!id.names.empty()) {
    YAML::Emitter t;  // the rest of the document's map
    YAML::Emitter& o = t;
    o << BeginMap << Key << "identifiability" << Value
      << YAML::Comment(std::string("the ") + (ml ? "whitened " : "") +
                       "Jacobian at the solution, every pose's own unknowns eliminated (README, \"identify\")")
      << BeginMap;
    o << Key << "columns" << Value << Flow << BeginSeq;
    for (const std::string& name : id.geometry_names) o << name;
    o << EndSeq;
    o << Key << "singular_values" << Value << Flow << BeginSeq;
    for (int k = 0; k < id.singular_values.size(); ++k) o << YamlNumber{id.singular_values(k)};
    o << EndSeq;
    o << Key << "condition_number" << Value << YamlNumber{id.condition_number};
    o << Key << "weakest_pose" << Value << Flow << BeginMap << Key << "pose" << Value << id.weakest_pose_id << Key
      << "singular_value" << Value << YamlNumber{id.weakest_pose_singular_value} << EndMap;
    o << Key << "null_directions" << Value;
    if (id.null_directions.empty()) o << Flow;
    o << BeginSeq;
    for (const std::string& d : id.null_directions) o << YamlString{d};
    o << EndSeq;
    if (!r.missing_sensors.empty()) {
      o << Key << "note" << Value
        << YamlString{"the data have " + MissingSensorsText(r.missing_sensors) +
                      ": every pose's unmeasured coordinates come from the encoders alone; the singular values "
                      "above say what the data still determine"};
    }
    o << EndMap << EndMap;
    parts.tail = YamlText(t);
  }
  return parts;
}

}  // namespace

std::string IdentifyResultYaml(const IdentifyResult& r, const std::string& command_line) {
  const ResultParts parts = IdentifyResultParts(r, command_line, false);
  return parts.head + parts.poses + parts.readings + parts.tail;
}

std::string IdentifyResultJson(const IdentifyResult& r, const std::string& command_line) {
  const ResultParts parts = IdentifyResultParts(r, command_line, true);
  std::vector<std::string> objects = {ToJson(YAML::Load(parts.head)), parts.poses};
  if (!parts.readings.empty()) objects.push_back(parts.readings);
  if (!parts.tail.empty()) objects.push_back(ToJson(YAML::Load(parts.tail)));
  return MergeJsonObjects(objects);
}

YAML::Node LoadIdentifyResultYaml(const std::string& path) {
  YAML::Node root;
  try {
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) {
      throw InputError(path, "", "is a folder, not an identification result (cablecal identify --out)");
    }
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw InputError(path, "", "cannot open the file");
  } catch (const YAML::Exception& e) {
    throw InputError(path, "", std::string("not valid YAML: ") + e.what());
  } catch (const std::ios_base::failure& e) {  // a device, a file that cannot be read
    throw InputError(path, "", std::string("cannot read the file: ") + e.what());
  }
  if (!root.IsMap() || !root["status"] || !root["parameters"]) {
    throw InputError(path, "", "not an identification result (cablecal identify --out): no status or parameters");
  }
  return root;
}

IdentifiedGeometry ReadIdentifiedGeometry(const Robot& nominal, const std::string& path) {
  YAML::Node root = LoadIdentifyResultYaml(path);  // not const: a missing key reads as a null node
  if (root["status"].as<std::string>("") != "converged") {
    throw InputError(path, "status", "the identification did not converge: it cannot be a prior");
  }
  // Gauge none leaves x unfixed: its standard deviations are the pseudo-inverse's, which leave
  // out the null direction, in a frame that floats along it; taken as information they make the
  // next round's plan several times too confident (measured: 4x the covariance trace).
  if (root["gauge"] && root["gauge"].as<std::string>("") == "none") {
    throw InputError(path, "gauge", "a result identified with --gauge none cannot be a prior (its sigmas leave out the "
                                    "direction it does not fix): identify the same data with --gauge a1x or prior");
  }
  // The robot it was identified for (result.yaml records it since this check; older ones are
  // checked by their parameter count below): a prior of another robot would plan around the
  // wrong geometry with confidence.
  const YAML::Node of = root["robot"];
  if (of.IsMap() && of["name"] && of["cables"]) {
    RequireResultOfRobot(path, of["name"].as<std::string>(""), of["cables"].as<int>(0), nominal);
  }
  const int m = nominal.num_cables();
  const int np = LayoutOf(nominal).size();  // a1x a1z .. amx amz l10 .. lm0
  if (!root["parameters"].IsMap() || static_cast<int>(root["parameters"].size()) != np) {
    throw InputError(path, "parameters", "needs the " + std::to_string(np) + " geometric parameters of " + nominal.name +
                                             "'s " + std::to_string(m) + " cables (" + GeometryNameList(m, 0) +
                                             "): a result for another robot?");
  }
  const std::vector<std::string> names = GeometryNames(m);
  // The default gauge's free entries (all but a1x): held a1x, or a tracked exit point's a1x, has
  // no standard deviation a prior could use.
  const std::vector<int> free = PlanarKind::FreeByDefault(LayoutOf(nominal));
  GeometryVector g(np);
  Eigen::VectorXd sd(np);
  for (int k = 0; k < np; ++k) {
    const std::string& name = names[k];
    const YAML::Node p = root["parameters"][name];
    const std::string key = "parameters." + name;
    if (!p || !p["value"]) throw InputError(path, key, "missing");
    g(k) = p["value"].as<double>(NAN);
    const bool held = !std::binary_search(free.begin(), free.end(), k);
    sd(k) = p["std"] ? p["std"].as<double>(NAN) : (held ? 0.0 : NAN);
    if (!std::isfinite(g(k))) throw InputError(path, key + ".value", "must be a finite number");
    if (!held && !(sd(k) > 0.0 && std::isfinite(sd(k)))) {
      throw InputError(path, key + ".std", "needs a positive standard deviation (identify computes it by default)");
    }
  }
  const std::string matrix = "needs the " + std::to_string(np) + " x " + std::to_string(np) + " matrix";
  const YAML::Node corr = root["correlation"];
  if (!corr || !corr.IsSequence() || static_cast<int>(corr.size()) != np) throw InputError(path, "correlation", matrix);
  Eigen::MatrixXd C(np, np);
  for (int a = 0; a < np; ++a) {
    if (!corr[a].IsSequence() || static_cast<int>(corr[a].size()) != np) throw InputError(path, "correlation", matrix);
    for (int b = 0; b < np; ++b) C(a, b) = corr[a][b].as<double>(NAN);
  }
  // Covariance of the free parameters.
  const int nr = static_cast<int>(free.size());
  IdentifiedGeometry known;
  known.geometry = g;
  known.covariance.resize(nr, nr);
  for (int a = 0; a < nr; ++a) {
    for (int b = 0; b < nr; ++b) known.covariance(a, b) = C(free[a], free[b]) * sd(free[a]) * sd(free[b]);
  }
  return known;
}

}  // namespace cablecal
