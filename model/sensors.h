// The sensors a calibration reads besides the drives' encoders, each a small unit: its name
// (messages, the robot file's sensors.<name> block, simulate --sensors), its CSV column, its
// unit, the pose coordinate it reads, its noise from the robot file, and its residual,
// templated on the scalar (Ceres' Jets, the design's nested Jets, doubles). The encoders,
// which every reading has, are the cable model's (identify/residuals.h). The stages loop over
// a kind's sensors; none names one. Depends on model/robot.h (the noise) and model/kind.h.
#pragma once

#include <array>
#include <optional>
#include <string>

#include "model/kind.h"
#include "model/robot.h"

namespace cablecal {

// Every sensor of every kind, by one id (the index of a reading's value, Measurement).
enum class SensorId : int { kLaser = 0, kInclinometer = 1 };
inline constexpr int kNumSensorIds = 2;

struct SensorUnit {
  SensorId id;
  const char* name;     // "laser"
  const char* column;   // its CSV column: "z"
  const char* unit;     // of the column: "m"
  int pose_coordinate;  // the pose coordinate the reading is of
  const char* quantity;  // what it reads, for a person: "height"
  // One reading's standard deviation from the robot file (accuracy and repeatability combined).
  double (*sigma)(const SensorNoise& noise);

  // The residual of a reading `value` at pose q: model - reading, in the column's unit.
  template <typename T>
  T Residual(const T* q, double value) const {
    return q[pose_coordinate] - value;
  }
};

// The planar robot's: a vertical laser reading the platform's height z, an inclinometer its
// angle theta, in this order (the CSV's columns after the encoders', the residuals after theirs).
inline constexpr std::array<SensorUnit, 2> kPlanarSensors = {{
    {SensorId::kLaser, "laser", "z", "m", 1, "height", [](const SensorNoise& s) { return s.laser_sigma_m(); }},
    {SensorId::kInclinometer, "inclinometer", "theta", "rad", 2, "angle",
     [](const SensorNoise& s) { return s.inclinometer_sigma_rad(); }},
}};

inline constexpr int kNumPlanarSensors = static_cast<int>(kPlanarSensors.size());

inline const SensorUnit& Unit(SensorId id) { return kPlanarSensors[static_cast<int>(id)]; }

// The unit named `name` ("laser"), if any.
inline std::optional<SensorId> SensorNamed(const std::string& name) {
  for (const SensorUnit& u : kPlanarSensors) {
    if (name == u.name) return u.id;
  }
  return std::nullopt;
}

}  // namespace cablecal
