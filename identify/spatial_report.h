// What `identify` writes for a spatial robot (README, "Spatial robots", "Identification of a
// spatial robot"): result.yaml and its JSON, with the planar result's keys where they apply
// (provenance, robot, status, estimator, gauge, iterations, final_cost, residual_rms, warnings,
// loss, parameters, correlation, poses, readings) and the spatial ones (held, null_directions,
// weak_directions, worst_reading, covariance, statics, unused and missing sensors); the
// calibrated robot file. Depends on identify/ (the planar writer's provenance) and
// identify/spatial_identify.h.
#pragma once

#include <string>
#include <vector>

#include "identify/spatial_identify.h"
#include "model/spatial_robot.h"

namespace cablecal {

// The robot file's sensors whose readings the identification had none of (by the fits: a
// sensor read at no reading), in SpatialSensor order: the data simply did not read them.
std::vector<std::string> MissingSpatialSensors(const SpatialRobot& nominal, const SpatialIdentifyResult& result);

// The RMS of each read sensor's residual (model - reading) in its own unit, the whitened
// residual times the robot file's sigma: "encoder_m", then "inclinometer_rad", "laser_m",
// "position_m", "swivel_rad", "heading_rad", "load_cell_N" for the sensors read.
std::vector<std::pair<std::string, double>> SpatialResidualRms(const SpatialRobot& nominal,
                                                               const SpatialIdentifyResult& result);

// A geometry unknown's unit: "rad" for the swivel offsets and yaw0, "kg" for the mass, "m"
// otherwise.
const char* SpatialGeometryUnit(const std::string& name);

// result.yaml of a spatial identification.
std::string SpatialIdentifyResultYaml(const SpatialRobot& nominal, const SpatialIdentifyOptions& options,
                                      const SpatialIdentifyResult& result, const std::string& command_line);
// The same content as one line of JSON (identify --json).
std::string SpatialIdentifyResultJson(const SpatialRobot& nominal, const SpatialIdentifyOptions& options,
                                      const SpatialIdentifyResult& result, const std::string& command_line);

// The nominal robot with the identified exit points, the identified anchors (when they were
// unknowns: --identify anchors), the identified mass and centre of mass (when the statics were
// modelled; their priors' sigmas stay the file's) and, as each cable's initial_length, the
// identified l_i0 (the cable paid out at home, where its encoder reads zero); every other value
// the nominal robot's. The identified swivel offsets and yaw0 are not robot-file keys: the
// relative sensors are zeroed at home (README). CABLECAL_CHECK on a result of another robot.
SpatialRobot CalibratedSpatialRobot(const SpatialRobot& nominal, const SpatialIdentifyResult& result);

// What a spatial result.yaml knows of the geometry, read back beside its writer, for
// calibrating in rounds (design --prior): the unknowns' names and estimates, the coordinates its
// gauge held, and the covariance (names order; held rows and columns zero). Only a converged
// result of `nominal`'s robot (name, cable count, kind spatial), with standard deviations, in a
// gauge that fixes the frame (not --gauge none) knows it: InputError naming the file and key.
struct SpatialIdentifiedGeometry {
  std::string source;  // the file
  std::vector<std::string> names;
  Eigen::VectorXd geometry;
  std::vector<std::string> held;
  Eigen::MatrixXd covariance;
};
SpatialIdentifiedGeometry ReadSpatialIdentifiedGeometry(const SpatialRobot& nominal, const std::string& result_yaml_path);
// The nominal robot with the read exits and initial lengths (and anchors, when identified), as
// CalibratedSpatialRobot.
SpatialRobot CalibratedSpatialRobot(const SpatialRobot& nominal, const SpatialIdentifiedGeometry& known);

}  // namespace cablecal
