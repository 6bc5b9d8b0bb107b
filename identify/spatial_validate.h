// validate on a spatial robot (README, "Spatial robots", "validate"): for each held-out reading
// the robot's forward model (model/forward_statics.h) puts the platform where the commanded
// lengths l_i0 + dl_i hold it (l_i0: the cable paid out at home, a calibrated robot file's
// initial_length), and the sensors' readings there (model/spatial_sensor_model.h) are compared
// with the readings of every sensor present: error = predicted - measured. The relative
// sensors (swivel encoders, heading) are zeroed, as on the lab's robot, where the robot settles
// with its home lengths. Run on a calibrated robot and, optionally, the nominal one.
// Depends on model/, experiment/ (SpatialHome, the readings) and identify/validate.h.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "experiment/spatial_measurements.h"
#include "identify/validate.h"  // ErrorSummary, SkippedReading, kUnexplainedNoiseFactor
#include "model/spatial_robot.h"

namespace cablecal {

struct SpatialRobotPrediction {
  std::string name;    // "calibrated" or "nominal"
  std::string robot;   // the robot's name
  std::string source;  // its file
  std::vector<SpatialPose<double>> q;  // predicted, one per kept reading
  // Per sensor compared: predicted - measured per kept reading (angles wrapped into (-pi, pi]).
  std::array<std::vector<Eigen::VectorXd>, kNumSpatialSensors> errors;
  // Over every value of the sensor (roll and pitch together, px, py, pz together, ...).
  std::array<std::optional<ErrorSummary>, kNumSpatialSensors> summary;
};

struct SpatialValidationResult {
  std::vector<int> pose_ids;  // one per kept reading
  int num_poses = 0;          // distinct ids
  std::array<bool, kNumSpatialSensors> compared{};  // the sensors the readings have
  // The calibrated robot file's sigma of each compared sensor (NaN where it has none).
  std::array<double, kNumSpatialSensors> sigma{};
  std::vector<SpatialMeasurement> measured;  // the kept readings
  std::vector<SpatialRobotPrediction> robots;  // calibrated, then nominal
  bool skip_infeasible = false;
  std::vector<SkippedReading> skipped;
  // The calibrated robot's RMS error of a sensor beyond kUnexplainedNoiseFactor times its sigma.
  std::vector<std::string> warnings;
};

// InputError naming the reading's file and line when a robot cannot hold its commanded lengths
// (or with skip_infeasible, the reading left out for every robot and listed), naming `source`
// for readings of another cable count, no readings, or readings with no sensor to compare;
// InputError naming a robot's cable stiffness when it cannot be simulated (more than 6
// inextensible cables) and its home when its home lengths hold no pose.
SpatialValidationResult ValidateSpatial(const SpatialRobot& calibrated, const std::optional<SpatialRobot>& nominal,
                                        const std::vector<SpatialMeasurement>& readings, const std::string& source,
                                        bool skip_infeasible = false);

// nominal / calibrated RMS error of a sensor; NaN without a nominal robot or that sensor.
double SpatialRmsRatio(const SpatialValidationResult& result, SpatialSensor sensor);

// The per-reading CSV: provenance, then pose, each compared sensor's measured columns (the
// measurement CSV's names), and per robot x_<name>, y_<name>, ... yaw_<name> and each
// compared column's error, <column>_error_<name>.
std::string SpatialValidationCsv(const SpatialValidationResult& result, const std::string& provenance);
// The summary YAML: as the planar one, with one entry per compared sensor.
std::string SpatialValidationSummaryYaml(const SpatialValidationResult& result, const std::string& command_line);
// The CSV's rows as the JSON member "rows".
std::string SpatialValidationRowsJson(const SpatialValidationResult& result);
// The calibrated robot file's sensors the readings lack ("no columns of inclinometer, laser");
// empty when every one was compared.
std::string SpatialNotCompared(const SpatialValidationResult& result);

}  // namespace cablecal
