// The sensors' systematic error models (README, "Sensor error models"), in one place for the
// simulation that adds them (simulate --systematic-errors), the identification that removes
// them from a lab's readings (identify) and the bench fit that estimates them (sensors/):
//   laser         reading = z + offset
//   inclinometer  reading = theta + offset + k (sec theta - 1)
// with z and theta the true height and angle. The inclinometer's form is the paper's sec(theta)
// fit (Wang, Cardou & Caro, ARK 2022, Section 2.2) with the offset taken at theta = 0, so that
// `offset` and `k` are nearly uncorrelated on a bench symmetric about 0.
#pragma once

#include <optional>
#include <string>

#include "model/robot.h"

namespace cablecal {

// Beyond these an offset is a unit slip (mm typed as m, radians typed as degrees), not a sensor.
constexpr double kMaxLaserOffset_m = 0.1;
constexpr double kMaxInclinometerSystematic_deg = 5.0;
// The correction inverts the inclinometer's error by fixed-point iteration, which contracts by
// |de/dtheta| = |k| sec(theta) tan(theta) per step; the robot file keeps it at most this over
// the inclinometer's range, so kInclinometerCorrectionIterations steps leave at most 0.5^50
// (1e-15) of the error's size there. A reading just beyond the range (noise) starts where the
// slope is a little steeper and still ends within 1e-12 rad; a typical k (0.1 degree: 0.006 per
// step at 60 degrees) is exact to rounding after a handful (tests/model/sensor_model_test.cc).
constexpr double kMaxInclinometerErrorSlope = 0.5;
constexpr int kInclinometerCorrectionIterations = 50;

// The systematic error of a reading at the true value.
double LaserError(const SystematicSensorErrors& e);
double InclinometerError(const SystematicSensorErrors& e, double theta_true_rad);
// d(error)/d(theta) at theta: what the fixed-point correction contracts by.
double InclinometerErrorSlope(const SystematicSensorErrors& e, double theta_rad);

// What the sensor reads at the true value, its noise aside.
double LaserReading(const SystematicSensorErrors& e, double z_true_m);
double InclinometerReading(const SystematicSensorErrors& e, double theta_true_rad);

// The true value that reads `reading` (the inverse of the above). The inclinometer's error
// depends on the true angle, so theta = reading - e(theta) is iterated
// kInclinometerCorrectionIterations times from theta = reading. A reading at or beyond
// +-90 degrees (no inclinometer reads there; the readings' plausibility check refuses it) is
// returned as it is.
double CorrectedLaserReading(const SystematicSensorErrors& e, double reading_m);
double CorrectedInclinometerReading(const SystematicSensorErrors& e, double reading_rad);

// Why a robot with inclinometer range theta_max_rad cannot use `e`: the robot-file key and
// the problem (an offset beyond the bounds above, or a sec coefficient whose error changes
// faster than kMaxInclinometerErrorSlope within the range); nullopt if it can.
struct SensorModelProblem {
  std::string key;
  std::string problem;
};
std::optional<SensorModelProblem> CheckSystematicErrors(const SystematicSensorErrors& e, double theta_max_rad);

}  // namespace cablecal
