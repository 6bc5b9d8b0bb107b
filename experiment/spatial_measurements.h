// A spatial robot's readings of its measurement poses: one SpatialMeasurement per row of the
// measurement CSV (the encoders' paid-out length changes, then each sensor the robot has,
// model/spatial_sensor_model.h), its writer and reader. Depends on model/.
#pragma once

#include <Eigen/Core>
#include <array>
#include <istream>
#include <string>
#include <vector>

#include "model/spatial_robot.h"
#include "model/spatial_sensor_model.h"

namespace cablecal {

struct SpatialMeasurement {
  int pose_id = 0;
  std::string where;     // "file:line" when read from a file; empty when simulated
  Eigen::VectorXd dl_m;  // the change of each cable's paid-out length from home
  // By SpatialSensor: SpatialSensorSize values, or empty where the data lack that sensor.
  std::array<Eigen::VectorXd, kNumSpatialSensors> sensor_values;

  bool has(SpatialSensor s) const { return sensor_values[static_cast<int>(s)].size() > 0; }
  const Eigen::VectorXd& values(SpatialSensor s) const { return sensor_values[static_cast<int>(s)]; }
  Eigen::VectorXd& values(SpatialSensor s) { return sensor_values[static_cast<int>(s)]; }
};

// Measurement CSV: pose,dl1..dlm, then for each sensor the readings have, in the order of
// SpatialSensor, its columns (roll,pitch / z / px,py,pz / sw1..swm / yaw / f1..fm). Every
// reading has the same sensors.
std::string SpatialMeasurementsCsv(const std::vector<SpatialMeasurement>& readings, const std::string& provenance);

// Reads it by column name, in any order: pose and dl1..dlm required, each sensor's columns
// read when all of them are there. InputError naming file, line and column for a sensor with
// some columns but not all, an unknown column (a misspelt or another robot's: never silently
// dropped), a bad number, a non-positive pose id (ids may repeat: repeated readings), more
// than kMaxMeasuredPoses rows (experiment/measurements.h).
std::vector<SpatialMeasurement> ReadSpatialMeasurementsCsv(const std::string& path, int num_cables,
                                                           char delimiter = ',');
std::vector<SpatialMeasurement> ReadSpatialMeasurementsCsv(std::istream& in, const std::string& name, int num_cables,
                                                           char delimiter = ',');

// Readings no sensor of `robot` can give, refused before any fit (the planar readings' check,
// CheckReadingsPlausible): a length change beyond the frame box's diagonal, a laser height
// outside the box's, an inclinometer angle beyond a quarter turn, a tracker point further
// from the box than its diagonal, a heading beyond a turn; each allowed 5 sigma of its
// sensor's noise past the bound. InputError naming the reading (file:line, or source and
// pose), the column, and the likely unit mistake (millimetres? degrees?).
void CheckSpatialReadingsPlausible(const SpatialRobot& robot, const std::vector<SpatialMeasurement>& readings,
                                   const std::string& source);

}  // namespace cablecal
