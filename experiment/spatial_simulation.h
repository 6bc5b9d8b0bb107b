// The simulated experiment of a spatial robot (README, "Spatial robots", simulate): a true
// robot drawn around the nominal one, the platform settled where the true robot puts it for
// each commanded pose of a plan (model/forward_statics.h), and its sensors' noisy readings
// there; the truth file.
//
// The controller commands, for each plan pose, the plan's dl from the encoders' zero: the
// winches pay out the zero's length (TrueEncoderZero) plus dl on the true robot (with the
// nominal robot itself, the unstretched lengths its model gives). The encoders and the relative sensors (swivel encoders, heading) are zeroed at home
// on the true robot: where it settles with home's commanded lengths. The encoders then read
// the commanded changes dl (plus noise): they sit on the motor side and see what was paid out,
// not where the platform went.
// Depends on experiment/spatial_plan.h, experiment/spatial_measurements.h and model/.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "common/random.h"
#include "experiment/spatial_measurements.h"
#include "experiment/simulation.h"  // NoisySensors
#include "experiment/spatial_plan.h"
#include "model/spatial_robot.h"

namespace cablecal {

// A true robot drawn around the nominal one: every exit coordinate (x, y, z of every cable)
// gets N(0, sigma_m^2), independently; 3m standard normals are drawn first, in cable order,
// then scaled. No coordinate is held: which rigid motion of the frame the sensors leave unseen
// (the gauge) is the identification's business, not the true robot's.
SpatialRobot PerturbSpatialGeometry(const SpatialRobot& nominal, double sigma_m, Rng& rng);
// The true platform: its mass and each coordinate of its centre of mass get N(0, sigma^2) with
// the robot file's priors on them (SpatialPlatformPriorSigma), 4 standard normals drawn in that
// order. A real platform is not the file's, and the identification estimates them (when the
// statics are modelled) within those priors.
void PerturbSpatialPlatform(SpatialRobot* truth, Rng& rng);

struct SpatialSimulationOptions {
  // Which sensors get noise besides the encoders (simulate --sensors): kBoth every one the
  // robot has, kLaser or kInclinometer that one alone, kNone none.
  NoisySensors noisy = NoisySensors::kBoth;
  bool encoder_noise = true;
  // Refuse a pose where the true robot settles outside its feasible workspace (a tension
  // beyond the limits, the tilt limit, the margin, invalid cable geometry), as a lab's
  // experiment would stop there.
  bool require_feasible = true;
  // Skip a pose the true robot cannot hold (or holds outside its workspace) instead of
  // failing; its noise is drawn all the same.
  bool skip_infeasible = false;
  // Each plan row's pose id (the plan file's pose column: the readings and the skipped poses are
  // numbered by it, as identify --plan matches them); empty: 1..n in plan order.
  std::vector<int> pose_ids;
};

// InputError naming --sensors when it asks for the noise of a sensor the robot file does not
// have (laser or inclinometer): the other sensors would be read without noise, unsaid.
void CheckNoisySensors(const SpatialRobot& robot, NoisySensors noisy);

struct SpatialSkippedPose {
  int pose_id = 0;
  std::string reason;
};

struct SimulatedSpatialExperiment {
  std::vector<SpatialMeasurement> measurements;
  std::vector<SpatialPose<double>> true_poses;  // where the platform settled
  std::vector<Eigen::VectorXd> true_tensions_N;
  std::vector<SpatialSkippedPose> skipped;
  SpatialPose<double> true_home = SpatialPose<double>::Zero();  // where the sensors were zeroed
};

// What the true robot's winches have paid out where its encoders read zero: the truth's own
// initial lengths when its file gives every cable's (a truth file written by simulate
// --truth-out: the physical zero, kept from one round of a calibration to the next, whatever
// robot file the controller then commands from), else the nominal home's paid-out lengths
// (SpatialHome(nominal).paid_out_m).
Eigen::VectorXd TrueEncoderZero(const SpatialRobot& truth, const Eigen::VectorXd& nominal_home_paid_out_m);
// Where the true robot settles with TrueEncoderZero paid out: the sensors' zero. SolverFailure
// when it cannot hold it.
SpatialPose<double> TrueHome(const SpatialRobot& nominal, const SpatialRobot& truth);

// The noise-free readings `robot` gives at its own plan: each pose is its equilibrium with the
// plan's tensions, so no forward solve settles it (a robot whose cables cannot be simulated --
// more than 6 inextensible ones -- has them too); the relative sensors zeroed at its home.
// Every sensor of the robot file is read. What the design's gauge analysis looks at.
std::vector<SpatialMeasurement> PlannedSpatialReadings(const SpatialRobot& robot, const std::vector<SpatialPlanPose>& plan);

// The readings of `plan` (one of nominal's) on `truth`. Noise: per pose, in this order whatever
// sensors the robot has, m encoder draws N(0, encoder sigma), then for each sensor in
// SpatialSensor order and each of its SpatialSensorSize values an accuracy draw and a
// repeatability draw, each N(0, (range / 3)^2) (0 for a sensor the robot lacks): the stream
// does not depend on the sensors present or noisy. Readings carry the sensors the nominal robot
// file has. SolverFailure naming the pose when the true robot cannot hold it, unless
// skip_infeasible (then only if it holds none).
SimulatedSpatialExperiment SimulateSpatialExperiment(const SpatialRobot& nominal, const SpatialRobot& truth,
                                                     const std::vector<SpatialPlanPose>& plan,
                                                     const SpatialSimulationOptions& options, Rng& rng);

// The simulate command's experiment: truth given, or nominal perturbed with geometry_sigma_m
// (stream 0 of seed; 0: the nominal robot itself); noise from stream 1. InputError naming
// plan_source when the plan does not suit the true robot, or a truth with another cable count;
// InputError naming a cable's stiffness when the true robot cannot be simulated
// (CheckSimulatable). The returned truth has each cable's initial_length: the nominal home's
// paid-out length, where its encoder reads zero.
struct SpatialPlanSimulation {
  SpatialRobot truth;
  SimulatedSpatialExperiment experiment;
};
SpatialPlanSimulation SimulateSpatialPlan(const SpatialRobot& nominal, const std::optional<SpatialRobot>& truth,
                                          double geometry_sigma_m, const std::vector<SpatialPlanPose>& plan,
                                          const SpatialSimulationOptions& options, std::uint64_t seed,
                                          const std::string& plan_source);

// Truth file: the true robot in the robot-file format (with its initial lengths, when
// SimulateSpatialPlan made it) plus `true_poses` (pose, x, y, z, roll,
// pitch, yaw: m, rad) where the platform settled, one per reading.
std::string SpatialTruthYaml(const SpatialRobot& truth, const SimulatedSpatialExperiment& experiment);

}  // namespace cablecal
