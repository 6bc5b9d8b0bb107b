// identify: estimates the robot's real geometry (exit points a_i, initial lengths l_i0) and
// the unmeasured pose coordinates from encoder, laser and inclinometer readings, for a robot
// of any cable count (2 to 8), with uncertainties (Ceres: Levenberg-Marquardt, Schur elimination of the per-pose blocks,
// autodiff through model/cable.h; covariance and identifiability through the same block
// structure, identify/schur.h, so the cost is linear in the number of poses).
//   experiment.h  simulated or measured readings, measurement CSV
//   residuals.h   the templated residuals (shared with design/)
//   identify.h    Identify(), its options and result; result.yaml, written and read back
//                 (report.cc: its one writer and one reader)
//   validate.h    Validate(): a robot's predictions of held-out poses against the readings
//   calibration_report.h  identify --report: report.md and the data files of its figures
// Depends on model/, workspace/ (pose plans) and common/.
//
// The gauge (README, "Identification"): encoders, a vertical laser and an inclinometer cannot see a
// common shift of every a_ix and x_j, so the problem has one null direction unless the
// gauge is fixed: `a1x` holds a1x at its nominal value; `prior` adds a laser-tracker prior
// on every exit point; `none` keeps the paper's rank-deficient problem (covariance then by
// pseudo-inverse, and the output says so).
#pragma once

#include <Eigen/Core>
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "experiment/experiment.h"
#include "model/robot.h"
#include "model/kind.h"
#include "model/sensors.h"

namespace YAML {
class Emitter;
class Node;
}

namespace cablecal {

enum class Estimator {
  kMaximumLikelihood,  // "ml": every sensor's residual whitened by its sigma; z_j, theta_j unknown too
  kPaper,              // "paper": Eq. (6) residuals, z and theta taken as measured
};
enum class Gauge { kA1x, kPrior, kNone };

// A robust loss on every reading (identify --loss, README "Robust identification"): Ceres'
// HuberLoss or CauchyLoss with scale a = scale_sigmas, applied to each whitened reading on
// its own, so a reading counts in full up to about a of its sensor's sigma and less beyond.
// The defaults keep 99.95 % of least squares' efficiency on clean Gaussian readings (the
// estimates then move by about 0.02 sigma), while a gross reading weighs next to nothing.
enum class LossKind { kNone, kHuber, kCauchy };
struct RobustLoss {
  LossKind kind = LossKind::kNone;
  double scale_sigmas = 0.0;
};
constexpr double kDefaultHuberScaleSigmas = 3.0;
constexpr double kDefaultCauchyScaleSigmas = 10.0;
// "none", "huber", "cauchy", or either with ":SCALE" (in sigmas, > 0); InputError naming --loss.
RobustLoss ParseLoss(const std::string& text);
std::string ToString(const RobustLoss& loss);  // "none", "huber:3", ...
// The weight rho'(s) the loss gives a reading whose whitened residual is `sigmas` (1: full).
double LossWeight(const RobustLoss& loss, double sigmas);

Estimator ParseEstimator(const std::string& text);  // InputError naming --estimator
Gauge ParseGauge(const std::string& text);          // InputError naming --gauge
const char* ToString(Estimator e);
const char* ToString(Gauge g);

// The largest Levenberg-Marquardt iteration limit accepted (--max-iterations, Python's
// max_iterations): a fit that needs more is lost, not slow.
constexpr int kMaxIdentifyIterations = 100000;

// identify --equilibrium's default (on|off); the centre of mass's uncertainty taken when the
// robot file gives no platform.com_sigma is kDefaultComSigma_m (model/robot.h). Off for now (README, "The
// equilibrium"): each pose's row is independent, while a wrong centre of mass is one error
// shared by every pose, and with the file's centre of mass exact the predicted sigmas run 15-40 %
// above the spread (Consistency tests); the design's information does not have the rows yet.
constexpr bool kDefaultEquilibrium = false;
// The equilibrium row's sigma for `robot`: platform.com_sigma, else kDefaultComSigma_m.
double EquilibriumSigma(const Robot& robot);

struct IdentifyOptions {
  Estimator estimator = Estimator::kMaximumLikelihood;
  Gauge gauge = Gauge::kA1x;
  bool compute_covariance = true;     // off in the Monte Carlo, which needs only the estimates
  bool compute_identifiability = true;
  // Refuse estimates no robot of this file can have (an exit point off the frame, a parameter
  // more than 0.5 m from nominal) as poor_fit. Off in the Monte Carlo: there a wild estimate
  // from a poor pose set is a result to count, not a sign of wrong data.
  bool check_plausible_geometry = true;
  int max_iterations = 100;             // 1 .. kMaxIdentifyIterations
  RobustLoss loss;                      // ml only
  // A Gaussian prior on every geometric parameter about its nominal value with this standard
  // deviation (m; 0: none; ml only): what the lab knew before measuring, so that the result is
  // never less informed than that (identify --geometry-prior, README "Identification").
  std::optional<double> geometry_prior_sigma_m;  // none: no prior; given, it must be in range
  // ml with fewer cables than the pose's 3 DoF (m = 2): each pose's static equilibrium as a
  // residual of its own, its sigma the robot file's platform.com_sigma (kDefaultComSigma_m if
  // absent; README, "Identification"). No effect for `paper` or m >= 3 (identify --equilibrium).
  bool equilibrium = kDefaultEquilibrium;
  std::string source = "measurements";  // names the data in messages
  // The readings as a lab read them (identify, Python's identify): first corrected for the
  // robot file's systematic sensor errors and checked against what its sensors can read
  // (experiment/correction.h, CorrectedReadings), result.corrected_for saying what was
  // removed. Off for simulated readings (the Monte Carlo's have no systematic errors).
  bool readings_as_read = false;
};

// "no 'z' column (laser) and no 'theta' column (inclinometer)" for IdentifyResult::missing_sensors.
std::string MissingSensorsText(const std::vector<std::string>& missing_sensors);

// --geometry-prior's accepted range, m: below a micrometre no lab knows its geometry; beyond
// 0.5 m the robot file is wrong, not uncertain (design's kMaxGeometrySigma_m).
constexpr double kMinGeometryPriorSigma_m = 1e-6;
constexpr double kMaxGeometryPriorSigma_m = 0.5;
// With a geometry prior, a parameter whose standard deviation stays above this share of the
// prior's (more than half its variance left) is one the data add little to.
constexpr double kDataAddLittle = 0.7;

// A reading whose whitened residual exceeds this many sigma refuses the fit (poor_fit).
constexpr double kOutlierSigmas = 4.5;
// Up to this many such readings (or 5 % of them) are named as the cause even when the estimate
// they drag is also implausible; more point to wrong units or another robot.
constexpr std::size_t kFewOutliers = 8;

enum class IdentifyStatus {
  kConverged,
  kNotConverged,   // Ceres stopped without meeting its tolerances: not a result
  kRankDeficient,  // a null direction beyond the declared gauge: the data cannot fix it
  kPoorFit,        // converged, but the residuals are far larger than the sensors' noise:
                   // the data do not come from this robot (wrong file, units, outliers)
};
const char* ToString(IdentifyStatus s);

// How one reading (a row of the measurement CSV) fits: each sensor's residual, model minus
// reading, over that sensor's sigma (for `paper`, the length residuals over the length sigma
// of the global test, and no laser or inclinometer residual: it fixes z and theta), and the
// weight the robust loss gave it (1 without --loss).
struct ReadingFit {
  int pose_id = 0;
  std::string where;                    // "file:line" when read from a file
  Eigen::VectorXd encoder_sigmas;       // one per cable, signed
  // Each other sensor's (model/sensors.h), by SensorId; absent: no such reading, or `paper`.
  std::array<std::optional<double>, kNumSensorIds> sensor_sigmas;
  Eigen::VectorXd encoder_weights;      // one per cable
  std::array<double, kNumSensorIds> sensor_weights = {1.0, 1.0};
  // The smallest error of each value alone (encoders, then the sensors in kPlanarSensors'
  // order), in its sigmas, that the other poses would show beyond kOutlierSigmas
  // (identify/schur.h, CheckPosesAgainstTheOthers); infinite where nothing checks it. Empty
  // when not computed (paper, gauge none, a robust loss).
  Eigen::VectorXd min_detectable_sigmas;
  // Whether value `row` (encoders, then the sensors) was read and fitted.
  bool HasValue(int row) const {
    const int m = static_cast<int>(encoder_sigmas.size());
    return row < m || sensor_sigmas[static_cast<int>(kPlanarSensors[row - m].id)].has_value();
  }
};

struct PoseEstimate {
  int pose_id = 0;
  PlanarPose q = PlanarPose::Zero();          // (x, z, theta) estimated (paper: z, theta measured)
  PlanarPose std_dev = PlanarPose::Zero();    // 0 where not estimated
  // With the equilibrium row (IdentifyOptions::equilibrium, m = 2): its residual at the
  // estimate over its sigma, and as an angle, theta minus the equilibrium angle at (x, z)
  // (residuals.h, EquilibriumThetaError).
  std::optional<double> equilibrium_sigmas;
  std::optional<double> equilibrium_theta_error_rad;
};

// What the data can and cannot determine, from the whitened Jacobian at the solution. Its
// geometric part is the reduced Jacobian that is left once every pose's own unknowns are
// eliminated (identify/schur.h): the information the data hold on the geometry alone.
struct Identifiability {
  std::vector<std::string> geometry_names;  // columns of the reduced Jacobian (a1x absent when held)
  Eigen::VectorXd singular_values;          // of the reduced Jacobian, descending
  double condition_number = 0.0;  // largest / smallest of those (inf if any null direction)
  int weakest_pose_id = 0;                  // the pose whose own block has the smallest singular value
  double weakest_pose_singular_value = 0.0;
  std::vector<std::string> names;  // every estimated coordinate: geometry_names, then x, z, theta per pose
  // Below 1e-9 x the largest singular value of any block, as "0.5 a1x + 0.5 a2x + ..." and as
  // unit vectors over `names`.
  std::vector<std::string> null_directions;
  std::vector<Eigen::VectorXd> null_vectors;
};

struct IdentifyResult {
  // The nominal robot's name (its file's `name`): result.yaml records it, and a result is
  // refused beside a robot of another name (RequireResultOfRobot).
  std::string robot_name;
  IdentifyStatus status = IdentifyStatus::kNotConverged;
  std::string message;
  Estimator estimator = Estimator::kMaximumLikelihood;
  Gauge gauge = Gauge::kA1x;
  int iterations = 0;
  double final_cost = 0.0;  // Ceres' cost: half the sum of squared residuals
  // Residual RMS per sensor in physical units (m, m, rad): encoder length residuals, laser
  // z_j - z_meas, inclinometer theta_j - theta_meas (zero for `paper`, which fixes them).
  double rms_encoder_m = 0.0;
  std::array<double, kNumSensorIds> rms_sensor = {0.0, 0.0};  // by SensorId, in the sensor's unit
  GeometryVector geometry;  // 3m entries, GeometryNames(m) order (model/geometry.h)
  bool has_covariance = false;
  // The entries the gauge held at their nominal values (gauge a1x: a1x), increasing: no unknowns.
  std::vector<int> held_geometry;
  GeometryVector geometry_std;           // 3m entries, 0 for a held entry (all 0 without covariance)
  Eigen::MatrixXd geometry_correlation;  // 3m x 3m, the same order (identity without covariance)
  std::vector<PoseEstimate> poses;  // one per pose id, in the order of their first reading
  std::vector<ReadingFit> readings;  // one per reading, in the data's order (empty if not converged)
  RobustLoss loss;
  // Readings beyond kOutlierSigmas that the robust loss kept (down-weighted) rather than
  // refusing the fit: "pose 7: laser 199 sigma (weight 0.015)".
  std::vector<std::string> down_weighted;
  // Poses whose readings do not fit the others and that a robust fit followed too far: the
  // result is the fit without them (their readings stay in `readings`, at weight 0).
  std::vector<int> dropped_pose_ids;
  double geometry_prior_sigma_m = 0.0;  // the options' (0: no geometry prior)
  int data_add_little = 0;  // parameters whose sigma stays above kDataAddLittle x the prior's
  // The equilibrium rows' sigma (platform.com_sigma, m) when the fit had them (m = 2, ml,
  // IdentifyOptions::equilibrium); none otherwise. result.yaml's `equilibrium`.
  std::optional<double> equilibrium_com_sigma_m;
  std::vector<std::string> missing_sensors;  // "laser", "inclinometer": no such column in the data
  std::vector<std::string> warnings;         // a result, but one to read with care
  Identifiability identifiability;
  // The robot file's systematic sensor errors the laser and inclinometer readings were
  // corrected for before the solve (IdentifyOptions::readings_as_read); none: the readings
  // were used as read. result.yaml says which.
  std::optional<SystematicSensorErrors> corrected_for;
  bool converged() const { return status == IdentifyStatus::kConverged; }
};

// Identifies the geometry from `measurements`, starting from the nominal robot. Throws
// InputError for data that cannot determine the unknowns (fewer equations than unknowns,
// non-positive sigmas for `ml`, a missing tracker sigma for `prior`); a solve that does not
// converge or is rank-deficient is a status, not an exception.
IdentifyResult Identify(const Robot& nominal, const std::vector<Measurement>& measurements,
                        const IdentifyOptions& options);

// Where a reading's pose starts, for `robot` with `geometry` (GeometryOf(robot)): the measured z
// and theta, with the x where the model best explains the encoder readings there; a missing z
// or theta from where the robot settles with these lengths. Identify's start for each pose, and
// Validate's start for the forward model (both need a start near the platform's real pose; home
// is too far for some poses, and some lengths hold the platform in two places).
PlanarPose StartingPose(const Robot& robot, const GeometryVector& geometry, const Measurement& reading);

// What `identify` (the CLI and the Python module) makes of a result that is not one: a
// rank-deficient or poor fit is an InputError naming `source` (the data cannot calibrate
// this robot), a solve that did not converge a SolverFailure. Returns quietly otherwise.
void RequireUsableResult(const IdentifyResult& result, const std::string& source);

// The provenance every result and summary YAML opens with: `cablecal: {version, commit}` and
// `command` (the command line).
void EmitProvenance(YAML::Emitter& out, const std::string& command_line);

// The `sensor_correction` map of result.yaml and of validate's summary: the robot file's
// systematic sensor errors the readings were corrected for, and `when` ("before the solve").
void EmitSensorCorrection(YAML::Emitter& out, const SystematicSensorErrors& errors, const std::string& when);

// A result (`result_source` names it: a file, or "result") may be combined only with the robot it
// was identified for: InputError naming both robots (and robot.source) when the cable counts
// differ, or when the names differ and both are known (`result_robot_name` empty: a
// result.yaml of an older version, which did not record it).
void RequireResultOfRobot(const std::string& result_source, const std::string& result_robot_name,
                          int result_cables, const Robot& robot);
// The same for any kind of robot: its file (source), name and cable count.
void RequireResultOfRobot(const std::string& result_source, const std::string& result_robot_name,
                          int result_cables, const std::string& robot_source, const std::string& robot_name,
                          int robot_cables);

// Whether geometric parameter k was held rather than estimated (held_geometry): its std
// is then 0 by construction, and what a person reads says "held", not "std 0".
bool IsHeld(const IdentifyResult& result, int k);

// result.yaml (README, "identify").
std::string IdentifyResultYaml(const IdentifyResult& result, const std::string& command_line);
// What a result.yaml knows of the geometry, read back (its one reader, beside its writer):
// the estimates and the covariance of every parameter but a1x (a1z a2x .. lm0; a1x is the gauge
// or a tracked exit point), for calibrating in rounds (design --prior). Only a converged result
// for `nominal`'s robot, with standard deviations, in a gauge that fixes the frame, knows it:
// InputError naming the file and key otherwise.
struct IdentifiedGeometry {
  GeometryVector geometry;
  Eigen::MatrixXd covariance;  // (3m - 1) x (3m - 1); its definiteness is left to the caller
};
IdentifiedGeometry ReadIdentifiedGeometry(const Robot& nominal, const std::string& result_yaml_path);
// A result.yaml (planar or spatial) read back, with its status and parameters: InputError naming
// the file for a folder, a file that cannot be read, text that is not YAML or not a result.
// What ReadIdentifiedGeometry and ReadSpatialIdentifiedGeometry then check is their own.
YAML::Node LoadIdentifyResultYaml(const std::string& result_yaml_path);
// The same content as one line of JSON (identify --json; common/json.h's conventions), the
// per-pose and per-reading tables written directly rather than parsed back from the YAML.
std::string IdentifyResultJson(const IdentifyResult& result, const std::string& command_line);

}  // namespace cablecal
