#include "experiment/spatial_simulation.h"

#include "common/error.h"
#include "common/format.h"
#include "common/yaml_writer.h"
#include "model/forward_statics.h"
#include "model/spatial_sensor_model.h"
#include "model/swivel.h"

namespace cablecal {

SpatialRobot PerturbSpatialGeometry(const SpatialRobot& nominal, double sigma_m, Rng& rng) {
  const int m = nominal.num_cables();
  Eigen::VectorXd draw(3 * m);
  for (int k = 0; k < 3 * m; ++k) draw(k) = rng.Normal();  // all first: the stream stays aligned
  SpatialRobot truth = nominal;
  for (int i = 0; i < m; ++i) truth.cables[i].p_F_exit_m += sigma_m * draw.segment<3>(3 * i);
  return truth;
}

void PerturbSpatialPlatform(SpatialRobot* truth, Rng& rng) {
  Eigen::Vector4d draw;
  for (int k = 0; k < 4; ++k) draw(k) = rng.Normal();
  const Eigen::Vector4d values = truth->platform_values() + SpatialPlatformPriorSigma(*truth).cwiseProduct(draw);
  truth->platform_mass_kg = values(0);
  truth->p_P_com_m = values.tail<3>();
}

namespace {

// The draws one pose's readings take (SimulateSpatialExperiment's order).
int DrawsPerPose(int num_cables) {
  int draws = num_cables;
  for (const SpatialSensor s : kSpatialSensors) draws += 2 * SpatialSensorSize(s, num_cables);
  return draws;
}


bool Noisy(NoisySensors noisy, SpatialSensor s) {
  switch (noisy) {
    case NoisySensors::kBoth: return true;
    case NoisySensors::kLaser: return s == SpatialSensor::kLaser;
    case NoisySensors::kInclinometer: return s == SpatialSensor::kInclinometer;
    case NoisySensors::kNone: return false;
  }
  return true;
}

// Where `truth` settles with `zero_paid_out_m` paid out, from the nominal home: the sensors' zero.
SpatialPose<double> SettledHome(const SpatialRobot& truth, const SpatialHomeReference& home,
                                const Eigen::VectorXd& zero_paid_out_m) {
  const SpatialForwardResult fwd = SolveForwardStatics(truth, zero_paid_out_m, &home.equilibrium.q);
  if (fwd.status != ForwardStatus::kConverged) {
    throw SolverFailure("the true robot cannot hold the home pose's commanded lengths (" +
                        CannotHoldReason(fwd.status, "home") + "): its sensors have no zero");
  }
  return fwd.equilibrium.q;
}

}  // namespace

Eigen::VectorXd TrueEncoderZero(const SpatialRobot& truth, const Eigen::VectorXd& nominal_home_paid_out_m) {
  Eigen::VectorXd zero(truth.num_cables());
  for (int i = 0; i < truth.num_cables(); ++i) {
    if (!truth.cables[i].initial_length_m) return nominal_home_paid_out_m;
    zero(i) = *truth.cables[i].initial_length_m;
  }
  return zero;
}

SpatialPose<double> TrueHome(const SpatialRobot& nominal, const SpatialRobot& truth) {
  const SpatialHomeReference home = SpatialHome(nominal);
  return SettledHome(truth, home, TrueEncoderZero(truth, home.paid_out_m));
}

void CheckNoisySensors(const SpatialRobot& robot, NoisySensors noisy) {
  const bool laser = noisy == NoisySensors::kLaser, inclinometer = noisy == NoisySensors::kInclinometer;
  if (!laser && !inclinometer) return;
  const SpatialSensor asked = laser ? SpatialSensor::kLaser : SpatialSensor::kInclinometer;
  if (HasSpatialSensor(robot, asked)) return;
  std::string present;
  for (const SpatialSensor s : kSpatialSensors) {
    if (HasSpatialSensor(robot, s)) present += std::string(present.empty() ? "" : ", ") + ToString(s);
  }
  throw InputError("--sensors", "", std::string(ToString(noisy)) + ": " + robot.name + "'s file has no sensors." +
                                        ToString(asked) + ", so only the encoders would be noisy" +
                                        (present.empty() ? "" : " and its " + present + " read exactly") +
                                        "; give both (every sensor of the file), none, or add the sensor to the file");
}

SimulatedSpatialExperiment SimulateSpatialExperiment(const SpatialRobot& nominal, const SpatialRobot& truth,
                                                     const std::vector<SpatialPlanPose>& plan,
                                                     const SpatialSimulationOptions& options, Rng& rng) {
  CheckNoisySensors(nominal, options.noisy);
  const int m = nominal.num_cables();
  SimulatedSpatialExperiment out;
  const SpatialHomeReference home = SpatialHome(nominal);
  const Eigen::VectorXd zero_paid_out = TrueEncoderZero(truth, home.paid_out_m);
  out.true_home = SettledHome(truth, home, zero_paid_out);
  const SpatialSensorZero zero = SensorZeroAt(truth, out.true_home);
  CABLECAL_CHECK(options.pose_ids.empty() || options.pose_ids.size() == plan.size(), "one pose id per plan row");
  for (std::size_t j = 0; j < plan.size(); ++j) {
    const SpatialPlanPose& p = plan[j];
    const int pose_id = options.pose_ids.empty() ? static_cast<int>(j + 1) : options.pose_ids[j];
    const Eigen::VectorXd commanded = zero_paid_out + p.length_change_m;
    // The commanded (nominal) pose is a good start: the true one is millimetres away.
    const SpatialForwardResult fwd = SolveForwardStatics(truth, commanded, &p.q);
    std::string infeasible;
    if (fwd.status != ForwardStatus::kConverged) {
      infeasible = "the true robot cannot hold the commanded lengths (" +
                   CannotHoldReason(fwd.status, "the commanded pose") + ")";
    } else if (options.require_feasible) {
      int cable = -1;
      const Eigen::VectorXd t = SnapTensionsToBounds(fwd.equilibrium.tensions_N, truth.tension_min_N, truth.tension_max_N);
      const Feasibility f = CheckSpatialFeasibility(truth, fwd.equilibrium.q, t, &cable);
      std::string beyond;  // the value beyond its bound, and the bound
      if (f == Feasibility::kTensionLow || f == Feasibility::kTensionHigh) {
        // The cable furthest beyond its bound, as t1..tm number them.
        Eigen::Index i = 0;
        if (f == Feasibility::kTensionLow) t.minCoeff(&i);
        else t.maxCoeff(&i);
        cable = static_cast<int>(i);
        // A cable at 0 N has gone slack (the forward statics' slack cables carry nothing).
        beyond = (t(i) <= 0.0 ? std::string(" slack, 0 N") : " at " + FormatDouble(std::round(t(i) * 1e3) / 1e3) + " N") +
                 ", bounds [" + FormatDouble(truth.tension_min_N) + ", " + FormatDouble(truth.tension_max_N) + "]";
      }
      if (f == Feasibility::kTiltLimit) {
        beyond = " at " + FormatDouble(std::round(TiltAngle(fwd.equilibrium.q) * 180.0 / M_PI * 1e3) / 1e3) +
                 " deg, limit " + FormatDouble(std::round(truth.tilt_max_rad * 180.0 / M_PI * 1e3) / 1e3) + " deg";
      }
      if (f != Feasibility::kFeasible) {
        infeasible = "the true robot settles outside its workspace (" + std::string(ToString(f)) +
                     (cable >= 0 ? ", cable " + std::to_string(cable + 1) : std::string()) + beyond + ")";
      }
    }
    if (!infeasible.empty()) {
      if (!options.skip_infeasible) throw SolverFailure("pose " + std::to_string(pose_id) + ": " + infeasible);
      out.skipped.push_back({pose_id, infeasible});
      for (int k = 0; k < DrawsPerPose(m); ++k) rng.Normal();  // the others read what they would have
      continue;
    }
    SpatialMeasurement r;
    r.pose_id = pose_id;
    r.dl_m = p.length_change_m;
    for (int i = 0; i < m; ++i) {
      const double e = rng.Normal(0.0, nominal.sensors.encoder_sigma_m);
      if (options.encoder_noise) r.dl_m(i) += e;
    }
    const auto exact = SpatialSensorReadings<double>(truth, fwd.equilibrium.q, fwd.equilibrium.tensions_N, zero);
    for (const SpatialSensor s : kSpatialSensors) {
      const std::optional<RangedNoise> noise = SpatialSensorNoise(nominal.sensors, s);
      const RangedNoise n = noise.value_or(RangedNoise{});
      Eigen::VectorXd v = exact[static_cast<int>(s)];
      for (Eigen::Index k = 0; k < v.size(); ++k) {
        const double accuracy = rng.Normal(0.0, n.accuracy / 3.0);
        const double repeatability = rng.Normal(0.0, n.repeatability / 3.0);
        if (Noisy(options.noisy, s)) v(k) += accuracy + repeatability;
      }
      if (noise) r.values(s) = v;
    }
    out.measurements.push_back(std::move(r));
    out.true_poses.push_back(fwd.equilibrium.q);
    out.true_tensions_N.push_back(fwd.equilibrium.tensions_N);
  }
  return out;
}

std::vector<SpatialMeasurement> PlannedSpatialReadings(const SpatialRobot& robot, const std::vector<SpatialPlanPose>& plan) {
  const SpatialSensorZero zero = SensorZeroAt(robot, SpatialHome(robot).equilibrium.q);
  std::vector<SpatialMeasurement> readings;
  for (std::size_t j = 0; j < plan.size(); ++j) {
    SpatialMeasurement r;
    r.pose_id = static_cast<int>(j + 1);
    r.dl_m = plan[j].length_change_m;
    const auto exact = SpatialSensorReadings<double>(robot, plan[j].q, plan[j].tensions_N, zero);
    for (const SpatialSensor s : kSpatialSensors) {
      if (SpatialSensorNoise(robot.sensors, s)) r.values(s) = exact[static_cast<int>(s)];
    }
    readings.push_back(std::move(r));
  }
  return readings;
}

SpatialPlanSimulation SimulateSpatialPlan(const SpatialRobot& nominal, const std::optional<SpatialRobot>& truth,
                                          double geometry_sigma_m, const std::vector<SpatialPlanPose>& plan,
                                          const SpatialSimulationOptions& options, std::uint64_t seed,
                                          const std::string& plan_source) {
  Rng geometry_rng(StreamSeed(seed, {0}));
  Rng noise_rng(StreamSeed(seed, {1}));
  if (truth && truth->num_cables() != nominal.num_cables()) {
    throw InputError(truth->source, "", "the true robot has " + std::to_string(truth->num_cables()) +
                                            " cables, the nominal robot " + std::to_string(nominal.num_cables()) +
                                            ": a file for another robot?");
  }
  // A truth file (simulate --truth-out) keeps the nominal robot's name.
  if (truth && truth->name != nominal.name) {
    throw InputError(truth->source, "name", "the true robot is '" + truth->name + "', the nominal robot '" + nominal.name +
                                                "': a file for another robot? (a truth file written by simulate "
                                                "--truth-out keeps the nominal robot's name)");
  }
  SpatialPlanSimulation run{nominal, {}};
  if (truth) {
    run.truth = *truth;
  } else if (geometry_sigma_m > 0.0) {
    run.truth = PerturbSpatialGeometry(nominal, geometry_sigma_m, geometry_rng);
  }
  CheckSimulatable(run.truth);
  try {
    run.experiment = SimulateSpatialExperiment(nominal, run.truth, plan, options, noise_rng);
  } catch (const SolverFailure& e) {
    // Not a solver's fault: this plan does not suit this true robot. The plan's pose is named.
    throw InputError(plan_source, "", std::string(e.what()) + ": the plan cannot be run on this true robot");
  }
  if (run.experiment.measurements.empty() && !plan.empty()) {
    const SpatialSkippedPose& first = run.experiment.skipped.front();
    throw InputError(plan_source, "", "the true robot can hold none of the plan's " + std::to_string(plan.size()) +
                                          " poses, so every one was skipped (the first, pose " +
                                          std::to_string(first.pose_id) + ": " + first.reason +
                                          "): the plan cannot be run on this true robot");
  }
  // The true robot's encoders read zero where TrueEncoderZero was paid out: its initial
  // lengths, so that the truth file predicts its own readings (validate --robot) and the next
  // round's simulation keeps the same zero.
  const Eigen::VectorXd zero = TrueEncoderZero(run.truth, SpatialHome(nominal).paid_out_m);
  for (int i = 0; i < run.truth.num_cables(); ++i) run.truth.cables[i].initial_length_m = zero(i);
  return run;
}

std::string SpatialTruthYaml(const SpatialRobot& truth, const SimulatedSpatialExperiment& experiment) {
  FlowRows rows(FlowRows::Syntax::kYaml);
  for (std::size_t j = 0; j < experiment.true_poses.size(); ++j) {
    rows.BeginRow();
    rows.Key("pose");
    rows.Int(experiment.measurements[j].pose_id);
    for (int k = 0; k < SpatialKind::kPoseDim; ++k) {
      rows.Key(SpatialKind::kPoseNames[k]);
      rows.Number(experiment.true_poses[j](k));
    }
    rows.EndRow();
  }
  return SpatialRobotToYaml(truth) +
         rows.Finish("true_poses", "where the platform settled at each measured pose: x, y, z (m), roll, pitch, yaw (rad)");
}

}  // namespace cablecal
