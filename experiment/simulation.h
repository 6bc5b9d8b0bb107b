// The simulated experiment: a true robot drawn around the nominal one, the platform settled
// where the true robot puts it for each commanded pose of a plan, and the sensors' noisy
// readings there; gross errors for robustness studies; the truth file.
//
// Simulation (README, "Commands", simulate): the controller commands the plan's cables from
// the nominal robot, and the true robot settles where its own potential energy puts it
// (model/forward_statics.h). The winches pay out cable: the command is an UNSTRETCHED length,
// for an elastic cable (stiffness E*A) the one that is the plan's length l_ij under the plan's
// tension t_ij on the nominal robot, L_ij = l_ij / (1 + t_ij / EA) (CommandedUnstretchedLengths),
// for an inextensible one l_ij itself. The true robot's cable i has its own unstretched length
// at home plus the commanded change from home, L_ij - L_i(home) (CableCommands below), and the
// encoders, on the motor side, read that change: for inextensible cables exactly the plan's dl_ij.
// Planar robots without stiffness and with 2 or 3 cables settle by the inextensible
// geometrico-static model as they always did (SettlePlanar); a robot with more inextensible
// cables than the platform's degrees of freedom (planar m >= 4 without stiffness) cannot be
// simulated: its rigid cables could not all have the commanded lengths on a true robot that
// differs from the nominal one (CheckSimulatable, exit 2 naming the key `stiffness`). Sensors
// read the settled pose with the paper's noise.
#pragma once


#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "common/random.h"
#include "experiment/measurements.h"
#include "model/geometry.h"
#include "model/kind.h"
#include "model/robot.h"
#include "model/statics.h"
#include "experiment/plan.h"
#include "workspace/workspace.h"

namespace cablecal {

// The one geometry perturbation (simulate --geometry-sigma, the Monte Carlo's true robots,
// README "Identification"): a true robot drawn around the nominal one.
//  - a1x is never perturbed. It fixes the x origin of F: no encoder, laser or inclinometer
//    reading sees a common shift of every a_ix and x_j (the identification's gauge), so a
//    true robot with a1x moved is the same robot as one with every other x moved back.
//    Holding it makes "identified - true" mean the same thing under every gauge.
//  - Every other exit coordinate gets N(0, exit_sigma_m^2) and every initial length
//    N(0, sigma_m^2), independently (exit_sigma_m: the Monte Carlo's gauge `prior` draws the
//    exit points with the laser tracker's sigma, the error that prior assumes).
//  - 3m standard normals are drawn first, one per entry in the geometry vector's order (a1x's
//    draw made and discarded), then scaled: the random stream after the call does not depend
//    on the sigmas, and m = 2 draws exactly what the Monte Carlo always drew.
Robot PerturbGeometry(const Robot& nominal, double sigma_m, double exit_sigma_m, Rng& rng);
inline Robot PerturbGeometry(const Robot& nominal, double sigma_m, Rng& rng) {
  return PerturbGeometry(nominal, sigma_m, sigma_m, rng);
}

// The cables the controller commands for a plan on an elastic robot (the file comment): the
// nominal robot's unstretched lengths at home (its initial lengths under the home tensions).
struct CableCommands {
  explicit CableCommands(const Robot& nominal);
  // L_ij - L_i(home): what the winches pay out from home for a plan pose; the encoders' noise-free
  // reading. For an inextensible cable the plan's dl_ij (the same bits when no cable is elastic).
  Eigen::VectorXd PaidOutFromHome(const PlanPose& pose) const;
  // The unstretched lengths of the true robot's cables at that pose: its initial lengths (the
  // geometry's l_i0, lengths at home) under the home tensions, plus `paid_out_m`.
  Eigen::VectorXd TrueUnstretchedLengths(const Robot& truth, const Eigen::VectorXd& true_initial_lengths_m,
                                         const Eigen::VectorXd& paid_out_m) const;

  const Robot& nominal;
  bool elastic = false;  // some cable has a stiffness
  Eigen::VectorXd home_tensions_N, home_unstretched_m;
};

// Which sensors get noise (the paper's Section 4.2 ablation switches laser/inclinometer).
enum class NoisySensors { kBoth, kLaser, kInclinometer, kNone };
NoisySensors ParseNoisySensors(const std::string& text);  // InputError on anything else
const char* ToString(NoisySensors s);

struct SimulationOptions {
  NoisySensors noisy = NoisySensors::kBoth;
  bool encoder_noise = true;
  // Also refuse a pose where the true robot settles outside its feasible workspace (a
  // tension beyond the limits, theta beyond the inclinometer range, the margin broken):
  // the Monte Carlo counts such an experiment as failed, as a lab would.
  bool require_feasible = false;
  // Also add the nominal robot file's systematic sensor errors (model/sensor_model.h) to the
  // laser and inclinometer readings, whatever `noisy` says (simulate --systematic-errors).
  bool systematic_errors = false;
  // Skip a pose the true robot cannot hold (or, with require_feasible, holds outside its
  // workspace) instead of failing: it is listed in SimulatedExperiment::skipped and has no
  // reading (simulate --skip-infeasible). Its noise is drawn all the same, so the other poses
  // read what they would have read had it been holdable.
  bool skip_infeasible = false;
};

// A plan's pose that was skipped (SimulationOptions::skip_infeasible), with why.
struct SkippedPose {
  int pose_id = 0;
  std::string reason;
};

struct SimulatedExperiment {
  std::vector<Measurement> measurements;
  std::vector<PlanarPose> true_poses;  // (x, z, theta) where the platform settled
  std::vector<SkippedPose> skipped;         // with skip_infeasible: the poses left out, in plan order
};

// Why a robot cannot hold the lengths SolveForwardGeometricoStatic was given: the status and
// what it means; `expected_pose` names where the platform was expected ("the commanded pose").
std::string CannotHoldReason(ForwardStatus status, const std::string& expected_pose);

// Throws SolverFailure naming the pose if the true robot cannot hold a commanded pose
// (forward model not converged, slack cable, unstable, or the lengths met only by another
// assembly of the robot, far from the commanded pose), unless options.skip_infeasible, which
// skips such poses (and fails only when it would skip every pose).
SimulatedExperiment SimulateExperiment(const Robot& nominal, const Robot& truth,
                                       const std::vector<PlanPose>& plan, const SimulationOptions& options,
                                       Rng& rng);

// The `simulate` command's experiment, shared by the CLI and the Python module: the true
// robot is `truth` when given, else the nominal one perturbed by PerturbGeometry with
// geometry_sigma_m (0: the nominal robot itself). The geometry draws come from stream 0 of
// `seed` and the sensor noise from stream 1, so a seed gives the same true robot whatever the
// sensors' settings. A plan the true robot cannot run (SimulateExperiment's SolverFailure) is
// an InputError naming `plan_source` and the pose: the plan does not suit that robot; with
// skip_infeasible, only a plan whose every pose is skipped is.
struct PlanSimulation {
  Robot truth;
  SimulatedExperiment experiment;
};
PlanSimulation SimulatePlan(const Robot& nominal, const std::optional<Robot>& truth, double geometry_sigma_m,
                            const std::vector<PlanPose>& plan, const SimulationOptions& options, std::uint64_t seed,
                            const std::string& plan_source);

// Gross errors, to study robust identification (montecarlo --outliers RATE[:SIZE]): each
// reading value (every encoder, the laser, the inclinometer) independently, with probability
// `rate`, is off by size_sigmas of its sensor's sigma (laser, inclinometer: the combined
// accuracy and repeatability sigma), with a random sign. SIZE defaults to 100 sigma (0.2 m
// for the built-in robot's laser).
struct OutlierModel {
  double rate = 0.0;
  double size_sigmas = 100.0;
};
OutlierModel ParseOutliers(const std::string& text);  // "RATE[:SIZE]", 0 <= RATE <= 1, SIZE > 0; InputError naming --outliers
// Draws two uniforms per reading value, used or not, so the stream does not depend on the rate.
void AddOutliers(std::vector<Measurement>& readings, const SensorNoise& sensors, const OutlierModel& model, Rng& rng);

// Truth file: the true robot in the robot-file format plus its `true_poses` list.
std::string TruthYaml(const Robot& truth, const std::vector<Measurement>& measurements,
                      const std::vector<PlanarPose>& true_poses);

}  // namespace cablecal
