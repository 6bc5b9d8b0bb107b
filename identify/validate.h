// validate: how well a robot model predicts held-out poses. For each reading, the robot's
// forward geometrico-static model (model/statics.h) puts the platform where the commanded
// lengths l_i0 + dl_i hold it; that prediction's z and theta are compared with the laser's
// and the inclinometer's readings (error = predicted - measured; a sensor the data lack is
// left out). Run on a calibrated robot and, optionally, on the nominal one, the RMS and
// largest errors of both say what the calibration bought on poses it was not fitted to
// (README, "Validation").
// Depends on model/ (the forward model) and identify/ (readings; identify.h's per-pose start).
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "experiment/experiment.h"
#include "model/kind.h"
#include "model/robot.h"

namespace cablecal {

struct ErrorSummary {
  double rms = 0.0;
  double max_abs = 0.0;
};

// One robot's predictions, one per reading, in the readings' order.
struct RobotPrediction {
  std::string name;    // "calibrated" or "nominal": the role, used in CSV columns and summary keys
  std::string robot;   // the robot's own name and file, for the summary
  std::string source;
  std::vector<PlanarPose> q;  // predicted (x, z, theta), m and rad
  // Predicted - measured, per reading; empty (and no summary) for a sensor the data lack.
  std::vector<double> z_error_m, theta_error_rad;
  std::optional<ErrorSummary> z_m, theta_rad;
};

// A reading left out by Validate's skip_infeasible: its pose, file and line, and why.
struct SkippedReading {
  int pose_id = 0;
  std::string where;   // "file:line"
  std::string reason;  // which robot could not hold it, and how
  std::size_t index = 0;  // in the readings given
};

struct ValidationResult {
  std::vector<int> pose_ids;  // one per reading (a pose measured twice appears twice)
  int num_poses = 0;          // distinct pose ids
  // What the readings hold: a laser's z, an inclinometer's theta (a CSV may lack either column).
  bool has_laser = true, has_inclinometer = true;
  std::vector<double> z_measured_m, theta_measured_rad;  // empty for a sensor the data lack
  std::vector<RobotPrediction> robots;  // the calibrated robot, then the nominal one when given
  // The sensors' noise (their sigma): the RMS error even a perfect model would show.
  double laser_sigma_m = 0.0, inclinometer_sigma_rad = 0.0;
  // Set by a caller that corrected the readings for the robot file's systematic sensor errors
  // (CorrectedReadings, experiment/correction.h): said in the summary.
  std::optional<SystematicSensorErrors> corrected_for;
  // With skip_infeasible (validate --skip-infeasible): the readings left out, in their order.
  bool skip_infeasible = false;
  std::vector<SkippedReading> skipped;
  // The calibrated robot's RMS error of z or theta beyond kUnexplainedNoiseFactor times its
  // sensor's sigma: the calibrated model does not explain these readings (Validate fills it;
  // validate prints them, its summary lists them under `warnings`, the report says them).
  std::vector<std::string> warnings;
};

// A calibrated robot predicts held-out z to about the laser's noise (1.1 sigma, README
// "Validation"), and a 2-cable robot's theta to 2-5 sigma (the statics amplify the geometry's
// error; bench/README.md, "The equilibrium in identification"); an RMS error more than this many
// sigma is a model that does not explain the readings (a 5 cm anchor error: over 100 in theta).
constexpr double kUnexplainedNoiseFactor = 10.0;

// Predicts every reading of `measurements` with `calibrated` and, when given, `nominal`. Throws
// InputError naming the reading's file and line (or `source` and the pose) when a robot cannot
// hold its lengths (forward model not converged, a slack cable) or holds them only far from what
// the laser or inclinometer read (another assembly: more than kOtherAssemblyDistance_m in z or
// kOtherAssemblyAngle_rad in theta), and naming `source` for readings with neither a laser nor an
// inclinometer (nothing to compare), robots of different cable counts, readings of another
// count, and no readings at all. With skip_infeasible, a reading a robot cannot hold (either
// reason above) is left out for every robot and listed in `skipped` instead; only a set whose
// every reading is skipped is then refused.
ValidationResult Validate(const Robot& calibrated, const std::optional<Robot>& nominal,
                          const std::vector<Measurement>& measurements, const std::string& source,
                          bool skip_infeasible = false);

// nominal / calibrated RMS errors (inf when the calibrated one is 0); NaN without a nominal
// robot or without that sensor.
double ZRmsRatio(const ValidationResult& result);
double ThetaRmsRatio(const ValidationResult& result);

// The per-reading CSV: `provenance`, then pose, z_measured_m, theta_measured_rad and, per robot,
// x_<name>_m, z_<name>_m, theta_<name>_rad, z_error_<name>_m, theta_error_<name>_rad; a sensor
// the data lack has no measured and no error column.
std::string ValidationCsv(const ValidationResult& result, const std::string& provenance);

// The summary YAML (validate --summary): provenance, the readings and poses counted, what was
// compared (and what not, and why), the sensors' noise, each robot's RMS and largest errors, and
// the nominal/calibrated ratios.
std::string ValidationSummaryYaml(const ValidationResult& result, const std::string& command_line);

// The CSV's rows as the JSON member "rows": a list of objects with the CSV's column names as
// keys (validate --json; MergeJsonObjects, common/json.h, adds it to the summary's object).
std::string ValidationRowsJson(const ValidationResult& result);

// "z" and "theta" not compared, as MissingSensorsText says it ("no 'theta' column
// (inclinometer)"); empty when both were.
std::string NotCompared(const ValidationResult& result);

}  // namespace cablecal
