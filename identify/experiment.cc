#include "identify/experiment.h"

#include <cctype>
#include <fstream>
#include <optional>
#include <unordered_map>

#include "common/csv.h"
#include "common/error.h"
#include "common/format.h"
#include "common/yaml_writer.h"
#include "model/sensor_model.h"
#include "model/statics.h"

namespace cablecal {

Robot PerturbGeometry(const Robot& nominal, double sigma_m, double exit_sigma_m, Rng& rng) {
  GeometryVector g = GeometryOf(nominal);
  const int size = static_cast<int>(g.size());
  GeometryVector draw(size);
  for (int k = 0; k < size; ++k) draw(k) = rng.Normal();  // all first: the stream stays aligned
  const int exits = 2 * nominal.num_cables();
  for (int k = 1; k < size; ++k) g(k) += (k < exits ? exit_sigma_m : sigma_m) * draw(k);  // k = 0: a1x, held
  return WithGeometry(nominal, g);
}

NoisySensors ParseNoisySensors(const std::string& text) {
  if (text == "both") return NoisySensors::kBoth;
  if (text == "laser") return NoisySensors::kLaser;
  if (text == "inclinometer") return NoisySensors::kInclinometer;
  if (text == "none") return NoisySensors::kNone;
  throw InputError("--sensors", "", "must be both, laser, inclinometer or none (got '" + text + "')");
}

const char* ToString(NoisySensors s) {
  switch (s) {
    case NoisySensors::kBoth: return "both";
    case NoisySensors::kLaser: return "laser";
    case NoisySensors::kInclinometer: return "inclinometer";
    case NoisySensors::kNone: return "none";
  }
  return "unknown";
}

std::string CannotHoldReason(ForwardStatus status, const std::string& expected_pose) {
  std::string why = ToString(status);
  if (status == ForwardStatus::kOtherAssembly) {
    why += ": only another assembly of the robot has these lengths, far from " + expected_pose;
  } else if (status == ForwardStatus::kSlack) {
    why += ": a cable would go slack";
  }
  return why;
}

SimulatedExperiment SimulateExperiment(const Robot& nominal, const Robot& truth,
                                       const std::vector<PlanPose>& plan, const SimulationOptions& options,
                                       Rng& rng) {
  const Eigen::VectorXd l0_true = InitialLengths(truth);
  const bool laser = options.noisy == NoisySensors::kBoth || options.noisy == NoisySensors::kLaser;
  const bool inclinometer = options.noisy == NoisySensors::kBoth || options.noisy == NoisySensors::kInclinometer;
  const SensorNoise& s = nominal.sensors;
  SimulatedExperiment out;
  for (std::size_t j = 0; j < plan.size(); ++j) {
    const PlanPose& p = plan[j];
    const Eigen::VectorXd lengths_true = l0_true + p.length_change_m;
    // The commanded (nominal) pose is a good start: the true one is millimetres away.
    const ForwardResult fwd = SolveForwardGeometricoStatic(truth, lengths_true, &p.q);
    std::string infeasible;
    if (fwd.status != ForwardStatus::kConverged) {
      infeasible = "the true robot cannot hold the commanded lengths (" +
                   CannotHoldReason(fwd.status, "the commanded pose") + ")";
    } else if (options.require_feasible) {
      const Feasibility f = CheckFeasibility(truth, fwd.equilibrium.q, fwd.equilibrium.tensions_N);
      if (f != Feasibility::kFeasible) {
        infeasible = "the true robot settles outside its workspace (" + std::string(ToString(f)) + ")";
      }
    }
    if (!infeasible.empty()) {
      if (!options.skip_infeasible) throw SolverFailure("pose " + std::to_string(j + 1) + ": " + infeasible);
      out.skipped.push_back({static_cast<int>(j + 1), infeasible});
      // The draws this pose's readings would have taken (below): the others' stay the same.
      for (int k = 0; k < p.length_change_m.size() + 4; ++k) rng.Normal();
      continue;
    }
    Measurement m;
    m.pose_id = static_cast<int>(j + 1);
    // m >= 4: the lengths the cables have at the least-squares pose (experiment.h).
    m.dl_m = truth.num_cables() >= 4 ? Eigen::VectorXd(CableLengths(truth, fwd.equilibrium.q) - l0_true)
                                     : p.length_change_m;
    // Draw order is fixed (encoders, laser accuracy, repeatability, inclinometer accuracy,
    // repeatability) and every draw is made whether or not it is used, so that switching
    // a sensor's noise off leaves the other sensors' noise unchanged.
    for (int i = 0; i < m.dl_m.size(); ++i) {
      const double e = rng.Normal(0.0, s.encoder_sigma_m);
      if (options.encoder_noise) m.dl_m(i) += e;
    }
    const double laser_acc = rng.Normal(0.0, s.laser_accuracy_m / 3.0);
    const double laser_rep = rng.Normal(0.0, s.laser_repeatability_m / 3.0);
    const double inc_acc = rng.Normal(0.0, s.inclinometer_accuracy_rad / 3.0);
    const double inc_rep = rng.Normal(0.0, s.inclinometer_repeatability_rad / 3.0);
    // Off, the sensors read the true pose exactly as before the option existed (same bits).
    const SystematicSensorErrors& sys = s.systematic;
    const double z_read = options.systematic_errors ? LaserReading(sys, fwd.equilibrium.q(1)) : fwd.equilibrium.q(1);
    const double theta_read =
        options.systematic_errors ? InclinometerReading(sys, fwd.equilibrium.q(2)) : fwd.equilibrium.q(2);
    m.set(SensorId::kLaser, z_read + (laser ? laser_acc + laser_rep : 0.0));
    m.set(SensorId::kInclinometer, theta_read + (inclinometer ? inc_acc + inc_rep : 0.0));
    out.measurements.push_back(m);
    out.true_poses.push_back(fwd.equilibrium.q);
  }
  return out;
}

PlanSimulation SimulatePlan(const Robot& nominal, const std::optional<Robot>& truth, double geometry_sigma_m,
                            const std::vector<PlanPose>& plan, const SimulationOptions& options, std::uint64_t seed,
                            const std::string& plan_source) {
  Rng geometry_rng(StreamSeed(seed, {0}));
  Rng noise_rng(StreamSeed(seed, {1}));
  PlanSimulation run{nominal, {}};
  if (truth && truth->num_cables() != nominal.num_cables()) {
    throw InputError(truth->source, "", "the true robot has " + std::to_string(truth->num_cables()) +
                                            " cables, the nominal robot " + std::to_string(nominal.num_cables()) +
                                            ": a file for another robot?");
  }
  if (truth) {
    run.truth = *truth;
  } else if (geometry_sigma_m > 0.0) {
    run.truth = PerturbGeometry(nominal, geometry_sigma_m, geometry_rng);
  }
  try {
    run.experiment = SimulateExperiment(nominal, run.truth, plan, options, noise_rng);
  } catch (const SolverFailure& e) {
    // Not a solver's fault: this plan does not suit this true robot. The plan's pose is named.
    throw InputError(plan_source, "", std::string(e.what()) + ": the plan cannot be run on this true robot");
  }
  if (run.experiment.measurements.empty() && !plan.empty()) {
    const SkippedPose& first = run.experiment.skipped.front();
    throw InputError(plan_source, "", "the true robot can hold none of the plan's " + std::to_string(plan.size()) +
                                          " poses, so every one was skipped (the first, pose " +
                                          std::to_string(first.pose_id) + ": " + first.reason +
                                          "): the plan cannot be run on this true robot");
  }
  return run;
}

OutlierModel ParseOutliers(const std::string& text) {
  const std::string::size_type colon = text.find(':');
  OutlierModel model;
  const bool rate_ok = ParseFiniteDouble(text.substr(0, colon), &model.rate) && model.rate >= 0.0 && model.rate <= 1.0;
  const bool size_ok = colon == std::string::npos ||
                       (ParseFiniteDouble(text.substr(colon + 1), &model.size_sigmas) && model.size_sigmas > 0.0);
  if (!rate_ok || !size_ok) {
    throw InputError("--outliers", "",
                     "must be RATE[:SIZE]: the probability of a gross reading, 0 to 1, and its size in sigmas of "
                     "the sensor, > 0 (default 100), e.g. 0.01:100 (got '" + text + "')");
  }
  return model;
}

void AddOutliers(std::vector<Measurement>& readings, const SensorNoise& sensors, const OutlierModel& model, Rng& rng) {
  const auto perturb = [&](double& value, double sigma) {
    const double hit = rng.Uniform(), sign = rng.Uniform() < 0.5 ? -1.0 : 1.0;
    if (hit < model.rate) value += sign * model.size_sigmas * sigma;
  };
  double unread = 0.0;  // a sensor the data lack still takes its draws
  for (Measurement& m : readings) {
    for (int i = 0; i < m.dl_m.size(); ++i) perturb(m.dl_m(i), sensors.encoder_sigma_m);
    for (const SensorUnit& u : kPlanarSensors) {
      Eigen::VectorXd& values = m.sensor_values[static_cast<int>(u.id)];
      perturb(values.size() > 0 ? values(0) : unread, u.sigma(sensors));
    }
  }
}

std::string MeasurementsCsv(const std::vector<Measurement>& measurements, const std::string& provenance) {
  std::string out = provenance + "pose";
  const int m = measurements.empty() ? 2 : static_cast<int>(measurements.front().dl_m.size());
  std::array<bool, kNumSensorIds> present{};
  present.fill(true);
  if (!measurements.empty()) present = measurements.front().sensors();
  for (int i = 1; i <= m; ++i) out += ",dl" + std::to_string(i);
  for (const SensorUnit& u : kPlanarSensors) {
    if (present[static_cast<int>(u.id)]) out += std::string(",") + u.column;
  }
  out += "\n";
  for (const Measurement& r : measurements) {
    CABLECAL_CHECK(r.sensors() == present, "one file, one set of sensors");
    out += std::to_string(r.pose_id);
    for (int i = 0; i < m; ++i) out += "," + FormatDouble(r.dl_m(i));
    for (const SensorUnit& u : kPlanarSensors) {
      if (present[static_cast<int>(u.id)]) out += "," + FormatDouble(r.value(u.id));
    }
    out += "\n";
  }
  return out;
}

std::vector<Measurement> ReadMeasurementsCsv(const std::string& path, int num_cables, char delimiter,
                                             const std::function<void(const std::vector<std::string>&)>& on_ignored,
                                             const std::function<void(const std::string&)>& on_warning) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "", "cannot open the file");
  return ReadMeasurementsCsv(in, path, num_cables, delimiter, on_ignored, on_warning);
}

namespace {

// Whether an ignored column `column` looks like sensor column `name` in other units or case:
// the name itself in another case, or followed by a separator ("theta_deg", "z (mm)", "Z[m]").
bool LooksLikeColumn(const std::string& column, const std::string& name) {
  std::string lower = column;
  for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (lower.compare(0, name.size(), name) != 0) return false;
  return lower.size() == name.size() || !std::isalnum(static_cast<unsigned char>(lower[name.size()]));
}

// A pose id that comes again after other poses (1, 2, 3, 1): the first such reading, and how many.
std::optional<std::string> ReusedPoseIdWarning(const std::string& source, const std::vector<Measurement>& readings) {
  std::unordered_map<int, std::size_t> first;  // pose id -> index of its first reading
  std::size_t reused = 0, first_reused = 0;
  for (std::size_t k = 0; k < readings.size(); ++k) {
    const int id = readings[k].pose_id;
    const auto [at, fresh] = first.emplace(id, k);
    if (fresh || readings[k - 1].pose_id == id) continue;  // a new pose, or a repeat in a row
    if (reused++ == 0) first_reused = k;
  }
  if (reused == 0) return std::nullopt;
  const Measurement& m = readings[first_reused];
  const Measurement& earlier = readings[first.at(m.pose_id)];
  const std::string where = m.where.empty() ? source + ": reading " + std::to_string(first_reused + 1) : m.where;
  return where + ": pose " + std::to_string(m.pose_id) + " read again after other poses (first at " +
         (earlier.where.empty() ? "reading " + std::to_string(first.at(m.pose_id) + 1) : earlier.where) +
         "): taken as a repeated reading of the same pose; if it is another pose give it its own id" +
         (reused > 1 ? " (" + std::to_string(reused) + " readings in all repeat a pose id after other poses)" : "");
}

}  // namespace

std::vector<std::string> MeasurementWarnings(const std::string& source, const std::vector<std::string>& ignored,
                                             const std::vector<Measurement>& readings) {
  std::vector<std::string> warnings;
  if (readings.empty()) return warnings;
  for (const std::string& column : ignored) {
    for (const SensorUnit& u : kPlanarSensors) {
      if (readings.front().has(u.id) || !LooksLikeColumn(column, u.column)) continue;
      warnings.push_back(source + ": column '" + column + "' ignored: " + u.column + " is read from a column '" +
                         u.column + "' in " + u.unit + ", and without one the " + u.name + " is taken as missing");
    }
  }
  if (const std::optional<std::string> reused = ReusedPoseIdWarning(source, readings)) warnings.push_back(*reused);
  return warnings;
}

char ParseDelimiter(const std::string& text) {
  if (text == ",") return ',';
  if (text == ";") return ';';
  if (text == "tab" || text == "\t") return '\t';
  throw InputError("--delimiter", "", "must be ',', ';' or 'tab' (got '" + text + "')");
}

std::vector<Measurement> ReadMeasurementsCsv(std::istream& in, const std::string& path, int num_cables,
                                             char delimiter,
                                             const std::function<void(const std::vector<std::string>&)>& on_ignored,
                                             const std::function<void(const std::string&)>& on_warning) {
  std::vector<std::string> header = {"pose"};
  for (int i = 1; i <= num_cables; ++i) header.push_back("dl" + std::to_string(i));
  std::vector<Measurement> out;
  // z and theta may be absent (no laser, no inclinometer): Identify then says what the data
  // can no longer determine. The encoders are what is calibrated and always needed.
  std::vector<std::string> ignored;
  const auto note_ignored = [&](const std::vector<std::string>& names) {
    ignored = names;
    if (on_ignored) on_ignored(names);
  };
  std::vector<std::string> optional_columns;
  for (const SensorUnit& u : kPlanarSensors) optional_columns.push_back(u.column);
  ForEachCsvRowByName(in, path, delimiter, header, optional_columns, note_ignored, [&](const CsvRow& row) {
    if (static_cast<int>(out.size()) >= kMaxMeasuredPoses) {
      throw InputError(row.Where(), "", "more than " + std::to_string(kMaxMeasuredPoses) + " readings");
    }
    Measurement m;
    m.where = row.Where();
    m.pose_id = row.PositiveInt(0);
    m.dl_m.resize(num_cables);
    for (int i = 0; i < num_cables; ++i) m.dl_m(i) = row.Number(1 + i);
    for (std::size_t k = 0; k < kPlanarSensors.size(); ++k) {
      const int column = 1 + num_cables + static_cast<int>(k);
      if (row.present[column]) m.set(kPlanarSensors[k].id, row.Number(column));
    }
    out.push_back(m);
  });
  if (on_warning) {
    for (const std::string& w : MeasurementWarnings(path, ignored, out)) on_warning(w);
  }
  return out;
}

void CheckReadingsPlausible(const Robot& robot, const std::vector<Measurement>& measurements,
                            const std::string& source) {
  // A sensor's noise can carry the reading of a pose at the edge of its range a little past
  // it; kNoiseSigmas of that noise is allowed, nothing more.
  constexpr double kNoiseSigmas = 5.0;
  const double z_slack = kNoiseSigmas * robot.sensors.laser_sigma_m();
  const double theta_slack = kNoiseSigmas * robot.sensors.inclinometer_sigma_rad();
  const double z_min = -z_slack, z_max = std::min(robot.laser_range_m, robot.frame_height_m) + z_slack;
  const double theta_max = robot.theta_max_rad + theta_slack;
  // No cable can change its length by more than the frame's diagonal.
  const double dl_max = std::hypot(robot.frame_width_m, robot.frame_height_m);
  for (const Measurement& m : measurements) {
    const std::string where = m.where.empty() ? source + ": pose " + std::to_string(m.pose_id) : m.where;
    for (int i = 0; i < m.dl_m.size(); ++i) {
      if (!(std::abs(m.dl_m(i)) <= dl_max)) {
        throw InputError(where, "column 'dl" + std::to_string(i + 1) + "'",
                         FormatDouble(m.dl_m(i)) + " m is more than the frame's diagonal (" + FormatDouble(dl_max) +
                             " m): no cable of " + robot.name + " changes its length that much (millimetres? "
                             "lengths are in m)");
      }
    }
    if (m.has(SensorId::kLaser) && !(m.value(SensorId::kLaser) >= z_min && m.value(SensorId::kLaser) <= z_max)) {
      throw InputError(where, "column 'z'",
                       FormatDouble(m.value(SensorId::kLaser)) + " m is outside what the laser can read here, [" + FormatDouble(z_min) +
                           ", " + FormatDouble(z_max) + "] m (the laser range and the frame height of " + robot.name +
                           ", widened by 5 sigma of the laser's noise)" +
                           (m.value(SensorId::kLaser) > 10.0 * robot.frame_height_m ? " (millimetres? z is in m)" : ""));
    }
    if (m.has(SensorId::kInclinometer) && !(std::abs(m.value(SensorId::kInclinometer)) <= theta_max)) {
      throw InputError(where, "column 'theta'",
                       FormatDouble(m.value(SensorId::kInclinometer)) + " rad is beyond the inclinometer range of +-" +
                           FormatDouble(robot.theta_max_rad) + " rad (+-" + FormatDouble(theta_max) +
                           " with 5 sigma of its noise)" +
                           (std::abs(m.value(SensorId::kInclinometer)) > M_PI ? " (degrees? theta is in radians)" : ""));
    }
  }
}

std::string TruthYaml(const Robot& truth, const std::vector<Measurement>& measurements,
                      const std::vector<Eigen::Vector3d>& true_poses) {
  YAML::Emitter o;
  o << YAML::BeginMap;
  EmitRobotFields(o, truth);
  o << YAML::EndMap;
  // Up to 100,000 rows: written without the emitter's per-node cost, the same text (issue 24).
  FlowRows rows(FlowRows::Syntax::kYaml);
  for (std::size_t j = 0; j < true_poses.size(); ++j) {
    rows.BeginRow();
    rows.Key("pose");
    rows.Int(measurements[j].pose_id);
    for (int k = 0; k < PlanarKind::kPoseDim; ++k) {
      rows.Key(PlanarKind::kPoseNames[k]);
      rows.Number(true_poses[j](k));
    }
    rows.EndRow();
  }
  return YamlText(o) + rows.Finish("true_poses", "where the platform settled at each measured pose: x, z (m), theta (rad)");
}

}  // namespace cablecal
