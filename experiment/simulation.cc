#include "experiment/simulation.h"


#include <cctype>
#include <cmath>
#include <fstream>
#include <optional>
#include <unordered_map>

#include "common/csv.h"
#include "common/error.h"
#include "common/format.h"
#include "common/yaml_writer.h"
#include "model/forward_statics.h"
#include "model/sensor_model.h"
#include "model/statics.h"

namespace cablecal {

Robot PerturbGeometry(const Robot& nominal, double sigma_m, double exit_sigma_m, Rng& rng) {
  GeometryVector g = GeometryOf(nominal);
  const int size = static_cast<int>(g.size());
  GeometryVector draw(size);
  for (int k = 0; k < size; ++k) draw(k) = rng.Normal();  // all first: the stream stays aligned
  const int exits = LayoutOf(nominal).exit_coordinates();
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

Eigen::VectorXd HomeUnstretchedLengths(const Robot& robot, const Eigen::VectorXd& initial_lengths_m) {
  if (!HasStiffness(robot)) return initial_lengths_m;
  const PoseEvaluation home = EvaluateHome(robot);
  if (!home.has_equilibrium) return initial_lengths_m;
  return CommandedUnstretchedLengths(robot, initial_lengths_m, home.equilibrium.tensions_N);
}

CableCommands::CableCommands(const Robot& nominal_robot) : nominal(nominal_robot), elastic(HasStiffness(nominal_robot)) {
  if (elastic) home_unstretched_m = HomeUnstretchedLengths(nominal, InitialLengths(nominal));
}

Eigen::VectorXd CableCommands::PaidOutFromHome(const PlanPose& pose) const {
  if (!elastic) return pose.length_change_m;
  return CommandedUnstretchedLengths(nominal, pose.lengths_m, pose.tensions_N) - home_unstretched_m;
}

namespace {

// An elastic robot's tensions on a bound to rounding are on it (SnapTensionsToBounds).
Eigen::VectorXd SnapToBounds(const Robot& robot, const Eigen::VectorXd& tensions_N) {
  if (!HasStiffness(robot)) return tensions_N;
  return SnapTensionsToBounds(tensions_N, robot.tension_min_N, robot.tension_max_N);
}

}  // namespace

SimulatedExperiment SimulateExperiment(const Robot& nominal, const Robot& truth,
                                       const std::vector<PlanPose>& plan, const SimulationOptions& options,
                                       Rng& rng) {
  const CableCommands commands(nominal);
  const Eigen::VectorXd l0_true = InitialLengths(truth);
  const Eigen::VectorXd home_unstretched_true = HomeUnstretchedLengths(truth, l0_true);
  const bool laser = options.noisy == NoisySensors::kBoth || options.noisy == NoisySensors::kLaser;
  const bool inclinometer = options.noisy == NoisySensors::kBoth || options.noisy == NoisySensors::kInclinometer;
  const SensorNoise& s = nominal.sensors;
  SimulatedExperiment out;
  for (std::size_t j = 0; j < plan.size(); ++j) {
    const PlanPose& p = plan[j];
    const Eigen::VectorXd paid_out_m = commands.PaidOutFromHome(p);
    const Eigen::VectorXd lengths_true = home_unstretched_true + paid_out_m;
    // The commanded (nominal) pose is a good start: the true one is millimetres away.
    const ForwardResult fwd = SettlePlanar(truth, lengths_true, &p.q);
    std::string infeasible;
    if (fwd.status != ForwardStatus::kConverged) {
      infeasible = "the true robot cannot hold the commanded lengths (" +
                   CannotHoldReason(fwd.status, "the commanded pose") + ")";
    } else if (options.require_feasible) {
      const Feasibility f = CheckFeasibility(truth, fwd.equilibrium.q, SnapToBounds(truth, fwd.equilibrium.tensions_N));
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
    // The cable paid out (the file comment); rigid m >= 4: the length changes the cables have at
    // the least-squares pose (the rigid-cable convention, simulation.h).
    m.dl_m = !HasStiffness(truth) && truth.num_cables() > PlanarKind::kPoseDim
                 ? Eigen::VectorXd(CableLengths(truth, fwd.equilibrium.q) - l0_true)
                 : paid_out_m;
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

std::string TruthYaml(const Robot& truth, const std::vector<Measurement>& measurements,
                      const std::vector<PlanarPose>& true_poses) {
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
