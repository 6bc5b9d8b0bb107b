// The calibration experiment: what the sensors read at each measurement pose, either
// simulated (SimulateExperiment) or read from a lab's measurement CSV.
//
// Simulation (README, "Commands", simulate): the controller commands the plan's length changes dl_ij,
// computed with the nominal robot; the true robot's cables then have lengths
// l_i0(true) + dl_ij and the platform settles where the true geometry puts it (forward
// geometrico-static model). Sensors read that pose with the paper's noise.
#pragma once

#include <Eigen/Core>
#include <istream>
#include <string>
#include <vector>

#include "common/random.h"
#include "model/robot.h"
#include "workspace/workspace.h"

namespace cablecal {

// One pose's readings. dl: encoder length changes from the home pose (m); z: laser
// height (m); theta: inclinometer angle (rad).
struct Measurement {
  int pose_id = 0;
  std::string where;  // "file:line" when read from a file, for messages; empty when simulated
  Eigen::VectorXd dl_m;
  double z_m = 0.0;
  double theta_rad = 0.0;
};

// The geometric parameters the identification estimates, in this order:
// a1x a1z a2x a2z l10 l20 (exit points in F, initial lengths), m.
using GeometryVector = Eigen::Matrix<double, 6, 1>;
extern const char* const kGeometryNames[6];
GeometryVector GeometryOf(const Robot& robot);              // initial lengths from InitialLengths
Robot WithGeometry(const Robot& robot, const GeometryVector& geometry);  // sets exits and initial_length

// Nominal exit points and initial lengths each perturbed by N(0, sigma^2).
Robot PerturbGeometry(const Robot& nominal, double sigma_m, Rng& rng);

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
};

struct SimulatedExperiment {
  std::vector<Measurement> measurements;
  std::vector<Eigen::Vector3d> true_poses;  // (x, z, theta) where the platform settled
};

// Throws SolverFailure naming the pose if the true robot cannot hold a commanded pose
// (forward model not converged, slack cable, unstable).
SimulatedExperiment SimulateExperiment(const Robot& nominal, const Robot& truth,
                                       const std::vector<PlanPose>& plan, const SimulationOptions& options,
                                       Rng& rng);

// Measurement CSV: header pose,dl1,dl2,z,theta (m, m, m, rad).
std::string MeasurementsCsv(const std::vector<Measurement>& measurements, const std::string& provenance);
// Throws InputError naming file, line and column (wrong header or count, non-finite number,
// duplicate or non-positive pose id).
// CheckReadingsPlausible (below) then checks them against a robot's sensors.
// At most kMaxMeasuredPoses rows (the file is streamed and rejected at the next row).
std::vector<Measurement> ReadMeasurementsCsv(const std::string& path, int num_cables);
std::vector<Measurement> ReadMeasurementsCsv(std::istream& in, const std::string& name, int num_cables);
constexpr int kMaxMeasuredPoses = 100000;

// Readings no sensor of `robot` can give: an encoder length change longer than the frame's
// diagonal, a laser height below 0, above the laser range or above the frame, an
// inclinometer angle beyond its range, the last two limits widened by 5 sigma of
// that sensor's noise (a pose at the edge of a range reads a little past it). Throws
// InputError naming the file, line and column (or the pose), the value and the limit;
// "units?" where it fits.
void CheckReadingsPlausible(const Robot& robot, const std::vector<Measurement>& measurements,
                            const std::string& source);

// Truth file: the true robot in the robot-file format plus its `true_poses` list.
std::string TruthYaml(const Robot& truth, const std::vector<Measurement>& measurements,
                      const std::vector<Eigen::Vector3d>& true_poses);

}  // namespace cablecal
