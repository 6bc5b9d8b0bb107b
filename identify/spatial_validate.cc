#include "identify/spatial_validate.h"

#include <ceres/jet.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <set>

#include "common/error.h"
#include "common/format.h"
#include "common/yaml_writer.h"
#include "experiment/simulation.h"  // CannotHoldReason
#include "experiment/spatial_plan.h"  // SpatialHome
#include "identify/identify.h"        // EmitProvenance
#include "model/forward_statics.h"
#include "model/spatial_sensor_model.h"
#include "model/swivel.h"

namespace cablecal {
namespace {

std::string Where(const SpatialMeasurement& r, const std::string& source) {
  return r.where.empty() ? source + ": pose " + std::to_string(r.pose_id) : r.where;
}

bool IsAngle(SpatialSensor s) {
  return s == SpatialSensor::kInclinometer || s == SpatialSensor::kSwivel || s == SpatialSensor::kHeading;
}


// The sensors that read the pose in F (not relative to home, not the tensions): the guess
// fits them, and an equilibrium found must agree with them.
constexpr SpatialSensor kAbsoluteSensors[] = {SpatialSensor::kInclinometer, SpatialSensor::kLaser,
                                              SpatialSensor::kPosition, SpatialSensor::kHeading};

// Whether reading r has sensor s and the robot file gives its noise (a sensor it can model).
bool ReadsWith(const SpatialRobot& robot, const SpatialMeasurement& r, SpatialSensor s) {
  return r.has(s) && SpatialSensorNoise(robot.sensors, s).has_value();
}

// `start` with what the reading's absolute sensors read directly put in: the inclinometer's roll
// and pitch, the heading's yaw, the laser's height, the tracked point's position.
SpatialPose<double> WhatTheSensorsRead(const SpatialRobot& robot, const SpatialMeasurement& r,
                                       const SpatialPose<double>& start, const SpatialSensorZero& zero) {
  SpatialPose<double> read = start;
  const auto has = [&](SpatialSensor s) { return ReadsWith(robot, r, s); };
  if (has(SpatialSensor::kInclinometer)) read.segment<2>(3) = r.values(SpatialSensor::kInclinometer);
  if (has(SpatialSensor::kHeading)) read(5) = zero.yaw_rad + r.values(SpatialSensor::kHeading)(0);
  if (has(SpatialSensor::kLaser)) read(2) = r.values(SpatialSensor::kLaser)(0) + robot.p_F_frame_min_m.z();
  if (has(SpatialSensor::kPosition) && robot.sensors.position) {
    read.head<3>() = r.values(SpatialSensor::kPosition) - Rotation<double>(read) * robot.sensors.position->p_P_target_m;
  }
  return read;
}

// Where the forward model starts for a reading: the pose that best explains it with this
// robot's geometry, the cables taken as rigid: its encoders' lengths and the absolute sensors'
// readings (inclinometer, laser, position, heading), each over its sigma. The forward model's
// solution must then lie near what the sensors read, and lengths the platform holds in two places
// give the place the lab saw. Levenberg-Marquardt from `start` with steps of at most 0.2 m or rad
// (a step is taken only where it lowers the misfit): plain Gauss-Newton stopped short of poses
// tilted by 20 degrees or a metre above home on a 4-cable robot, whose own noise-free readings
// validate then refused as another assembly.
SpatialPose<double> SensorGuess(const SpatialRobot& robot, const SpatialMeasurement& r,
                                const Eigen::VectorXd& paid_out_m, const SpatialPose<double>& start,
                                const SpatialSensorZero& zero) {
  using Jet = ceres::Jet<double, 6>;
  const int m = robot.num_cables();
  const double encoder_sigma = std::max(robot.sensors.encoder_sigma_m, 1e-9);
  std::vector<std::pair<SpatialSensor, double>> absolute;
  for (const SpatialSensor s : kAbsoluteSensors) {
    if (ReadsWith(robot, r, s)) absolute.push_back({s, std::max(SpatialSensorNoise(robot.sensors, s)->sigma(), 1e-9)});
  }
  // The whitened misfit at q and its Jacobian.
  const auto evaluate = [&](const SpatialPose<double>& q, Eigen::VectorXd* res, Eigen::MatrixXd* J) {
    SpatialPose<Jet> qj;
    for (int c = 0; c < 6; ++c) qj(c) = Jet(q(c), c);
    const Eigen::Matrix<Jet, Eigen::Dynamic, 1> l = CableLengths<Jet>(robot, qj);
    const auto sensors = SpatialSensorReadings<Jet>(robot, qj, Eigen::Matrix<Jet, Eigen::Dynamic, 1>::Zero(m), zero);
    std::vector<Jet> rows;
    for (int i = 0; i < m; ++i) rows.push_back((l(i) - Jet(paid_out_m(i))) / encoder_sigma);
    for (const auto& [s, sigma] : absolute) {
      const Eigen::VectorXd& reading = r.values(s);
      for (int k = 0; k < reading.size(); ++k) {
        Jet e = sensors[static_cast<int>(s)](k) - Jet(reading(k));
        if (s == SpatialSensor::kHeading) e = WrappedAngle<Jet>(e);
        rows.push_back(e / sigma);
      }
    }
    res->resize(rows.size());
    J->resize(rows.size(), 6);
    for (std::size_t k = 0; k < rows.size(); ++k) {
      (*res)(k) = rows[k].a;
      J->row(k) = rows[k].v.transpose();
    }
    return res->allFinite() && J->allFinite();
  };
  const auto solve = [&](SpatialPose<double> q, double* cost) {
    Eigen::VectorXd res, trial_res;
    Eigen::MatrixXd J, trial_J;
    *cost = std::numeric_limits<double>::infinity();
    if (!evaluate(q, &res, &J)) return q;
    *cost = res.squaredNorm();
    double lambda = 1e-6;
    for (int it = 0; it < 200 && lambda < 1e12; ++it) {
      const Eigen::MatrixXd H = J.transpose() * J;
      Eigen::MatrixXd damped = H;
      damped.diagonal() += lambda * (H.diagonal().array() + 1e-12).matrix();
      Eigen::VectorXd step = damped.ldlt().solve(-J.transpose() * res);
      if (!step.allFinite()) break;
      const double largest = step.cwiseAbs().maxCoeff();
      if (largest > 0.2) step *= 0.2 / largest;
      const SpatialPose<double> trial = q + step;
      if (evaluate(trial, &trial_res, &trial_J) && trial_res.squaredNorm() < *cost) {
        q = trial;
        *cost = trial_res.squaredNorm();
        res.swap(trial_res);
        J.swap(trial_J);
        lambda = std::max(lambda / 10.0, 1e-12);
        if (largest < 1e-10) break;
      } else {
        if (largest < 1e-10) break;
        lambda *= 10.0;
      }
    }
    return q;
  };
  // A second start with what the absolute sensors read directly put in (the inclinometer's
  // roll and pitch, the heading's yaw, the laser's height, the tracked point's position): from
  // home alone a 4-cable robot's pose 0.4 rad in roll ended at a yaw of -0.9 rad, matching the
  // encoders there. The better fit of the two is kept.
  const SpatialPose<double> read = WhatTheSensorsRead(robot, r, start, zero);
  double cost_home = 0.0, cost_read = 0.0;
  const SpatialPose<double> from_home = solve(start, &cost_home);
  const SpatialPose<double> from_read = solve(read, &cost_read);
  return cost_read < cost_home ? from_read : from_home;
}

// Whether an equilibrium's absolute sensor readings (inclinometer, laser, position, heading) lie
// within the other-assembly tolerances (kOtherAssemblyDistance_m, kOtherAssemblyAngle_rad) of a
// reading's, and the reading has at least one of them.
bool AgreesWithAbsoluteSensors(const SpatialRobot& robot, const SpatialMeasurement& r, const SpatialForwardResult& fwd,
                               const SpatialSensorZero& zero) {
  const auto predicted = SpatialSensorReadings<double>(robot, fwd.equilibrium.q, fwd.equilibrium.tensions_N, zero);
  int compared = 0;
  for (const SpatialSensor s : kAbsoluteSensors) {
    if (!ReadsWith(robot, r, s)) continue;
    Eigen::VectorXd e = predicted[static_cast<int>(s)] - r.values(s);
    if (s == SpatialSensor::kHeading) e(0) = WrappedAngle<double>(e(0));
    const double tolerance = IsAngle(s) ? kOtherAssemblyAngle_rad : kOtherAssemblyDistance_m;
    if (!(e.cwiseAbs().maxCoeff() <= tolerance)) return false;
    ++compared;
  }
  return compared > 0;
}

// One robot's model of the lab: its home lengths, the pose they hold (the relative sensors'
// zero), and the pose of each reading.
struct RobotModel {
  const SpatialRobot* robot = nullptr;
  Eigen::VectorXd home_paid_out_m;
  SpatialPose<double> zero_pose;
  SpatialSensorZero zero;
};

RobotModel ModelOf(const SpatialRobot& robot) {
  CheckSimulatable(robot);
  RobotModel model;
  model.robot = &robot;
  const SpatialHomeReference home = SpatialHome(robot);
  model.home_paid_out_m = home.paid_out_m;
  const SpatialForwardResult fwd = SolveForwardStatics(robot, home.paid_out_m, &home.equilibrium.q);
  if (fwd.status != ForwardStatus::kConverged) {
    throw InputError(robot.source, "home", "the robot " + robot.name + " cannot hold its home lengths (" +
                                               CannotHoldReason(fwd.status, "home") +
                                               "): its encoders and relative sensors have no zero");
  }
  model.zero_pose = fwd.equilibrium.q;
  model.zero = SensorZeroAt(robot, model.zero_pose);
  return model;
}

}  // namespace

// Long (~110 lines) for a reason: the checks, every robot's prediction of every reading, and
// the summaries, in the order the result is read.
SpatialValidationResult ValidateSpatial(const SpatialRobot& calibrated, const std::optional<SpatialRobot>& nominal,
                                        const std::vector<SpatialMeasurement>& readings, const std::string& source,
                                        bool skip_infeasible) {
  if (readings.empty()) throw InputError(source, "", "no readings to validate on");
  const int m = calibrated.num_cables();
  if (nominal && nominal->num_cables() != m) {
    throw InputError(nominal->source, "", "the nominal robot has " + std::to_string(nominal->num_cables()) +
                                              " cables, the calibrated robot " + std::to_string(m) +
                                              ": a file for another robot?");
  }
  SpatialValidationResult result;
  for (const SpatialSensor s : kSpatialSensors) result.compared[static_cast<int>(s)] = readings.front().has(s);
  for (const SpatialMeasurement& r : readings) {
    if (r.dl_m.size() != m) {
      throw InputError(Where(r, source), "", std::to_string(r.dl_m.size()) + " encoder readings for a robot with " +
                                                 std::to_string(m) + " cables");
    }
  }
  if (std::none_of(result.compared.begin(), result.compared.end(), [](bool b) { return b; })) {
    throw InputError(source, "", "nothing to compare the predictions with: the readings have encoders only "
                                 "(validate compares the predicted sensor readings with the sensors' own)");
  }
  std::vector<const SpatialRobot*> robots = {&calibrated};
  std::vector<std::string> roles = {"calibrated"};
  if (nominal) robots.push_back(&*nominal), roles.push_back("nominal");
  std::vector<RobotModel> models;
  for (const SpatialRobot* robot : robots) models.push_back(ModelOf(*robot));
  using Readings = std::array<Eigen::VectorXd, kNumSpatialSensors>;
  std::vector<std::vector<SpatialPose<double>>> q(robots.size(), std::vector<SpatialPose<double>>(readings.size()));
  std::vector<std::vector<Readings>> predicted(robots.size(), std::vector<Readings>(readings.size()));
  std::vector<bool> keep(readings.size(), true);
  for (std::size_t k = 0; k < robots.size(); ++k) {
    const RobotModel& model = models[k];
    for (std::size_t j = 0; j < readings.size(); ++j) {
      if (!keep[j]) continue;
      const SpatialMeasurement& r = readings[j];
      const Eigen::VectorXd commanded = model.home_paid_out_m + r.dl_m;
      const SpatialPose<double> guess = SensorGuess(*model.robot, r, commanded, model.zero_pose, model.zero);
      SpatialForwardResult fwd = SolveForwardStatics(*model.robot, commanded, &guess);
      if (fwd.status != ForwardStatus::kConverged) {
        // The guess takes the cables as rigid: with stretching cables and few absolute sensors it
        // can lie far from where the platform hangs (a 4-cable robot of E*A 2e4 N read by an
        // inclinometer alone: a yaw of -2.1 rad guessed, -0.016 held; from another guess, an
        // unstable equilibrium). The forward model is then started again where the equilibrium
        // it found lies, at home and at what the sensors read; an equilibrium it keeps (stable,
        // a valid assembly, the solver staying there) that agrees with every absolute sensor
        // within the other-assembly tolerances is the one the lab saw.
        std::vector<SpatialPose<double>> starts;
        if (fwd.status == ForwardStatus::kOtherAssembly) starts.push_back(fwd.equilibrium.q);
        starts.push_back(model.zero_pose);
        starts.push_back(WhatTheSensorsRead(*model.robot, r, model.zero_pose, model.zero));
        for (const SpatialPose<double>& start : starts) {
          SpatialForwardResult again = SolveForwardStatics(*model.robot, commanded, &start);
          if (again.status == ForwardStatus::kOtherAssembly) {
            const SpatialPose<double> found = again.equilibrium.q;
            again = SolveForwardStatics(*model.robot, commanded, &found);
          }
          if (again.status == ForwardStatus::kConverged &&
              AgreesWithAbsoluteSensors(*model.robot, r, again, model.zero)) {
            fwd = again;
            break;
          }
        }
      }
      if (fwd.status == ForwardStatus::kConverged) {
        q[k][j] = fwd.equilibrium.q;
        predicted[k][j] = SpatialSensorReadings<double>(*model.robot, fwd.equilibrium.q, fwd.equilibrium.tensions_N,
                                                        model.zero);
        continue;
      }
      // Named by its flag and file's name: --robot is often the calibrated file, but may be any
      // (a truth file, the nominal one).
      const std::string who = k == 0 ? "--robot's robot " + robots[k]->name : "the --nominal robot " + robots[k]->name;
      const std::string why = who + " cannot hold the commanded lengths (" +
                              CannotHoldReason(fwd.status, "the pose the sensors read") + ")";
      if (!skip_infeasible) throw InputError(Where(r, source), "", why);
      keep[j] = false;
      result.skipped.push_back({r.pose_id, Where(r, source), why, j});
    }
  }
  std::stable_sort(result.skipped.begin(), result.skipped.end(),
                   [](const SkippedReading& a, const SkippedReading& b) { return a.index < b.index; });
  if (!result.skipped.empty() && result.skipped.size() == readings.size()) {
    throw InputError(source, "", "no reading is left to validate on: every one of the " +
                                     std::to_string(readings.size()) + " was skipped, a robot cannot hold it (the first, " +
                                     result.skipped.front().where + ": " + result.skipped.front().reason + ")");
  }
  for (std::size_t j = 0; j < readings.size(); ++j) {
    if (!keep[j]) continue;
    result.pose_ids.push_back(readings[j].pose_id);
    result.measured.push_back(readings[j]);
  }
  result.num_poses = static_cast<int>(std::set<int>(result.pose_ids.begin(), result.pose_ids.end()).size());
  for (std::size_t k = 0; k < robots.size(); ++k) {
    SpatialRobotPrediction p;
    p.name = roles[k];
    p.robot = robots[k]->name;
    p.source = robots[k]->source;
    for (const SpatialSensor s : kSpatialSensors) {
      const int i = static_cast<int>(s);
      if (!result.compared[i]) continue;
      double sum = 0.0, largest = 0.0;
      long count = 0;
      for (std::size_t j = 0; j < readings.size(); ++j) {
        if (!keep[j]) continue;
        Eigen::VectorXd e = predicted[k][j][i] - readings[j].values(s);
        if (IsAngle(s)) e = e.unaryExpr([](double a) { return WrappedAngle<double>(a); });
        sum += e.squaredNorm();
        largest = std::max(largest, e.cwiseAbs().maxCoeff());
        count += e.size();
        p.errors[i].push_back(e);
      }
      p.summary[i] = ErrorSummary{std::sqrt(sum / std::max(1L, count)), largest};
    }
    for (std::size_t j = 0; j < readings.size(); ++j) {
      if (keep[j]) p.q.push_back(q[k][j]);
    }
    result.robots.push_back(std::move(p));
  }
  result.skip_infeasible = skip_infeasible;
  for (const SpatialSensor s : kSpatialSensors) {
    const std::optional<RangedNoise> noise = SpatialSensorNoise(calibrated.sensors, s);
    const int i = static_cast<int>(s);
    result.sigma[i] = noise ? noise->sigma() : std::numeric_limits<double>::quiet_NaN();
    const std::optional<ErrorSummary>& e = result.robots.front().summary[i];
    if (!e || !(result.sigma[i] > 0.0) || !(e->rms > kUnexplainedNoiseFactor * result.sigma[i])) continue;
    char buffer[256];
    std::snprintf(buffer, sizeof(buffer),
                  "the calibrated robot's %s RMS error on these readings is %.3g %s, %.3g times its sigma (%.3g %s; more "
                  "than %g)",
                  ToString(s), e->rms, SpatialSensorUnit(s), e->rms / result.sigma[i], result.sigma[i], SpatialSensorUnit(s),
                  kUnexplainedNoiseFactor);
    result.warnings.push_back(std::string(buffer) +
                              ": the calibrated model does not explain these held-out readings. Check the robot file's "
                              "platform (mass, com, anchors), pulleys and stiffness, which the calibration does not "
                              "identify, and the sensors' sigma; or the calibration knows the geometry less well "
                              "than the nominal file did (few or bunched poses: compare result.yaml's sigmas with "
                              "the survey's, and plan the poses with cablecal design)");
  }
  return result;
}

double SpatialRmsRatio(const SpatialValidationResult& result, SpatialSensor sensor) {
  const int i = static_cast<int>(sensor);
  if (result.robots.size() < 2 || !result.compared[i]) return std::numeric_limits<double>::quiet_NaN();
  const double calibrated = result.robots[0].summary[i]->rms, nominal = result.robots[1].summary[i]->rms;
  return calibrated > 0.0 ? nominal / calibrated : std::numeric_limits<double>::infinity();
}

std::string SpatialNotCompared(const SpatialValidationResult& result) {
  std::string out;
  for (const SpatialSensor s : kSpatialSensors) {
    const int i = static_cast<int>(s);
    if (result.compared[i] || !std::isfinite(result.sigma[i])) continue;  // compared, or not in the robot file
    out += (out.empty() ? "" : ", ") + std::string(ToString(s));
  }
  return out.empty() ? out : "no columns of " + out;
}

namespace {

std::vector<std::string> Columns(const SpatialValidationResult& result) {
  const int m = result.measured.empty() ? 0 : static_cast<int>(result.measured.front().dl_m.size());
  std::vector<std::string> columns = {"pose"};
  for (const SpatialSensor s : kSpatialSensors) {
    if (!result.compared[static_cast<int>(s)]) continue;
    for (const std::string& c : SpatialSensorColumns(s, m)) columns.push_back(c);
  }
  for (const SpatialRobotPrediction& p : result.robots) {
    for (const char* name : SpatialKind::kPoseNames) columns.push_back(std::string(name) + "_" + p.name);
    for (const SpatialSensor s : kSpatialSensors) {
      if (!result.compared[static_cast<int>(s)]) continue;
      for (const std::string& c : SpatialSensorColumns(s, m)) columns.push_back(c + "_error_" + p.name);
    }
  }
  return columns;
}

std::vector<double> Row(const SpatialValidationResult& result, std::size_t j) {
  std::vector<double> row;
  for (const SpatialSensor s : kSpatialSensors) {
    if (!result.compared[static_cast<int>(s)]) continue;
    const Eigen::VectorXd& v = result.measured[j].values(s);
    row.insert(row.end(), v.data(), v.data() + v.size());
  }
  for (const SpatialRobotPrediction& p : result.robots) {
    for (int k = 0; k < SpatialKind::kPoseDim; ++k) row.push_back(p.q[j](k));
    for (const SpatialSensor s : kSpatialSensors) {
      if (!result.compared[static_cast<int>(s)]) continue;
      const Eigen::VectorXd& e = p.errors[static_cast<int>(s)][j];
      row.insert(row.end(), e.data(), e.data() + e.size());
    }
  }
  return row;
}

}  // namespace

std::string SpatialValidationCsv(const SpatialValidationResult& result, const std::string& provenance) {
  return PoseTableCsv(Columns(result), result.pose_ids, [&](std::size_t j) { return Row(result, j); }, provenance);
}

std::string SpatialValidationRowsJson(const SpatialValidationResult& result) {
  return PoseTableRowsJson(Columns(result), result.pose_ids, [&](std::size_t j) { return Row(result, j); });
}

std::string SpatialValidationSummaryYaml(const SpatialValidationResult& result, const std::string& command_line) {
  YAML::Emitter o;
  o << YAML::Comment("cablecal validation summary (README, \"Validation\"; spatial robot). SI units: m, rad, N. "
                     "error = predicted - measured")
    << YAML::BeginMap;
  EmitProvenance(o, command_line);
  o << YAML::Key << "readings" << YAML::Value << result.pose_ids.size();
  o << YAML::Key << "poses" << YAML::Value << result.num_poses;
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
  for (const SpatialSensor s : kSpatialSensors) {
    if (result.compared[static_cast<int>(s)]) o << ToString(s);
  }
  o << YAML::EndSeq;
  if (!SpatialNotCompared(result).empty()) {
    o << YAML::Key << "not_compared" << YAML::Value << YamlString{SpatialNotCompared(result)};
  }
  o << YAML::Key << "sensor_noise" << YAML::Value << YAML::Flow << YAML::BeginMap;
  for (const SpatialSensor s : kSpatialSensors) {
    const int i = static_cast<int>(s);
    if (result.compared[i] && std::isfinite(result.sigma[i])) {
      o << YAML::Key << std::string(ToString(s)) + "_sigma_" + SpatialSensorUnit(s) << YAML::Value << YamlNumber{result.sigma[i]};
    }
  }
  o << YAML::EndMap << YAML::Comment("the least RMS errors a perfect model shows: more where encoder noise moves the predicted pose");
  for (const SpatialRobotPrediction& p : result.robots) {
    o << YAML::Key << p.name << YAML::Value << YAML::BeginMap;
    o << YAML::Key << "robot" << YAML::Value << YamlString{p.robot};
    o << YAML::Key << "file" << YAML::Value << YamlString{p.source};
    for (const SpatialSensor s : kSpatialSensors) {
      const std::optional<ErrorSummary>& e = p.summary[static_cast<int>(s)];
      if (!e) continue;
      o << YAML::Key << ToString(s) << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key
        << std::string("rms_") + SpatialSensorUnit(s) << YAML::Value << YamlNumber{e->rms} << YAML::Key
        << std::string("max_abs_") + SpatialSensorUnit(s) << YAML::Value << YamlNumber{e->max_abs} << YAML::EndMap;
    }
    o << YAML::EndMap;
  }
  if (result.robots.size() > 1) {
    o << YAML::Key << "nominal_over_calibrated" << YAML::Value << YAML::Flow << YAML::BeginMap;
    for (const SpatialSensor s : kSpatialSensors) {
      if (!result.compared[static_cast<int>(s)]) continue;
      o << YAML::Key << std::string(ToString(s)) + "_rms" << YAML::Value << YamlNumber{SpatialRmsRatio(result, s)};
    }
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
