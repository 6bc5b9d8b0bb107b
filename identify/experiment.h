// The calibration experiment: what the sensors read at each measurement pose, either
// simulated (SimulateExperiment) or read from a lab's measurement CSV.
//
// Simulation (README, "Commands", simulate): the controller commands the plan's length changes dl_ij,
// computed with the nominal robot; the true robot's cables then have lengths
// l_i0(true) + dl_ij and the platform settles where the true geometry puts it (forward
// geometrico-static model). Sensors read that pose with the paper's noise.
// With m >= 4 cables the commanded lengths over-determine the pose and, on a true geometry
// that differs from the nominal one, are not all consistent: rigid cables cannot all have
// them. The forward model returns the least-squares pose; the encoders then read the length
// changes the cables actually have there, l_i(true, q) - l_i0(true), not the commanded ones
// (a real controller's cables would stretch or slacken by the difference, which is what its
// encoders, on the motor side, would not see; the model has rigid cables). For m <= 3 the two
// are the same up to the forward model's tolerance and the commanded changes are read, as
// always.
#pragma once

#include <Eigen/Core>
#include <array>
#include <functional>
#include <istream>
#include <optional>
#include <string>
#include <vector>

#include "common/random.h"
#include "model/geometry.h"
#include "model/robot.h"
#include "model/sensors.h"
#include "model/statics.h"
#include "workspace/workspace.h"

namespace cablecal {

// One reading of a pose. dl: encoder length changes from the home pose (m), one per cable;
// then each of the robot kind's other sensors' values (model/sensors.h: the planar laser's
// height z in m, the inclinometer's angle theta in rad). A lab without a laser or an
// inclinometer has no value for it (has() false; value() then 0, unused). Several readings may
// share a pose_id: repeated measurements of one pose, fitted with one set of pose unknowns.
struct Measurement {
  int pose_id = 0;
  std::string where;  // "file:line" when read from a file, for messages; empty when simulated
  Eigen::VectorXd dl_m;
  // By SensorId; empty where the data lack that sensor.
  std::array<Eigen::VectorXd, kNumSensorIds> sensor_values;

  bool has(SensorId id) const { return sensor_values[static_cast<int>(id)].size() > 0; }
  double value(SensorId id, int k = 0) const { return has(id) ? sensor_values[static_cast<int>(id)](k) : 0.0; }
  void set(SensorId id, double v) { sensor_values[static_cast<int>(id)] = Eigen::VectorXd::Constant(1, v); }
  double& at(SensorId id, int k = 0) { return sensor_values[static_cast<int>(id)](k); }  // a value the reading has
  void drop(SensorId id) { sensor_values[static_cast<int>(id)].resize(0); }
  // The sensors this reading has, by SensorId.
  std::array<bool, kNumSensorIds> sensors() const {
    std::array<bool, kNumSensorIds> out{};
    for (int k = 0; k < kNumSensorIds; ++k) out[k] = sensor_values[k].size() > 0;
    return out;
  }
};

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
  std::vector<Eigen::Vector3d> true_poses;  // (x, z, theta) where the platform settled
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

// Measurement CSV: header pose,dl1..dlm,z,theta (m, m, m, rad); z or theta left out when the
// readings have no laser or inclinometer.
std::string MeasurementsCsv(const std::vector<Measurement>& measurements, const std::string& provenance);
// Throws InputError naming file, line and column (wrong header or count, non-finite number,
// non-positive pose id). A pose id may repeat (repeated readings of one pose); the z and
// theta columns may be absent (no laser, no inclinometer: has_laser / has_inclinometer false).
// CheckReadingsPlausible (below) then checks them against a robot's sensors.
// At most kMaxMeasuredPoses rows (readings; the file is streamed and rejected at the next row).
// The file is read by column name (a lab's log): pose, dl1..dlm, z and theta in any order,
// other columns (a timestamp, a temperature) ignored and named once to `on_ignored`; cells
// split at `delimiter` (',', ';' or '\t'); an empty cell is refused with line and column.
// `on_warning` hears what is read but likely not meant (MeasurementWarnings below), once each.
std::vector<Measurement> ReadMeasurementsCsv(const std::string& path, int num_cables, char delimiter = ',',
                                             const std::function<void(const std::vector<std::string>&)>& on_ignored = {},
                                             const std::function<void(const std::string&)>& on_warning = {});
std::vector<Measurement> ReadMeasurementsCsv(std::istream& in, const std::string& name, int num_cables,
                                             char delimiter = ',',
                                             const std::function<void(const std::vector<std::string>&)>& on_ignored = {},
                                             const std::function<void(const std::string&)>& on_warning = {});

// What a measurement file says that its author likely did not mean, as warnings naming the file:
// an ignored column that looks like the laser's or the inclinometer's in other units or case
// ('theta_deg', 'z_mm', 'Theta') while the file has no 'z' or 'theta' column (that sensor is
// then taken as missing); a pose id that comes again after other poses (1, 2, 3, 1), which is
// read as a repeated reading of that pose, not as another pose (a reused id). `readings` as read.
std::vector<std::string> MeasurementWarnings(const std::string& source, const std::vector<std::string>& ignored,
                                             const std::vector<Measurement>& readings);
// The delimiter of --delimiter: ",", ";", "tab" (or a tab character); InputError otherwise.
char ParseDelimiter(const std::string& text);
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
