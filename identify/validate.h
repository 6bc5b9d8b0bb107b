// validate: how well a robot model predicts held-out poses. For each measured pose, the
// robot's forward geometrico-static model (model/statics.h) puts the platform where the
// commanded lengths l_i0 + dl_i hold it; that prediction's z and theta are compared with the
// laser's and the inclinometer's readings (error = predicted - measured). Run on a calibrated
// robot and, optionally, on the nominal one, the RMS and largest errors of both say what the
// calibration bought on poses it was not fitted to (README, "validate").
// Depends on model/ (the forward model) and identify/ (measurements; identify.h's per-pose x start).
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "identify/experiment.h"
#include "model/robot.h"

namespace cablecal {

struct ErrorSummary {
  double rms = 0.0;
  double max_abs = 0.0;
};

// One robot's predictions, one per measured pose, in the measurements' order.
struct RobotPrediction {
  std::string name;    // "calibrated" or "nominal": the role, used in CSV columns and summary keys
  std::string robot;   // the robot's own name and file, for the summary
  std::string source;
  std::vector<Eigen::Vector3d> q;  // predicted (x, z, theta), m and rad
  std::vector<double> z_error_m, theta_error_rad;
  ErrorSummary z_m, theta_rad;
};

struct ValidationResult {
  std::vector<int> pose_ids;
  std::vector<double> z_measured_m, theta_measured_rad;
  std::vector<RobotPrediction> robots;  // the calibrated robot, then the nominal one when given
  // The sensors' noise (their sigma): the RMS error even a perfect model would show.
  double laser_sigma_m = 0.0, inclinometer_sigma_rad = 0.0;
};

// Predicts every pose of `measurements` with `calibrated` and, when given, `nominal`. Throws
// InputError naming the pose's file and line (or `source` and the pose) when a robot cannot
// hold a pose's lengths (forward model not converged, a slack cable, or the lengths met only
// far from where the sensors saw the platform), for robots of different cable counts or
// measurements of another count, and for no measurements at all.
ValidationResult Validate(const Robot& calibrated, const std::optional<Robot>& nominal,
                          const std::vector<Measurement>& measurements, const std::string& source);

// nominal / calibrated RMS errors (inf when the calibrated one is 0); NaN without a nominal robot.
double ZRmsRatio(const ValidationResult& result);
double ThetaRmsRatio(const ValidationResult& result);

// The per-pose CSV: `provenance`, then pose, z_measured_m, theta_measured_rad and, per robot,
// x_<name>_m, z_<name>_m, theta_<name>_rad, z_error_<name>_m, theta_error_<name>_rad.
std::string ValidationCsv(const ValidationResult& result, const std::string& provenance);

// The summary YAML (validate --summary): provenance, the sensors' noise, each robot's RMS and
// largest errors, and the nominal/calibrated ratios.
std::string ValidationSummaryYaml(const ValidationResult& result, const std::string& command_line);

// The CSV's rows as a YAML sequence of maps with the CSV's column names as keys (validate --json).
std::string ValidationRowsYaml(const ValidationResult& result);

}  // namespace cablecal
