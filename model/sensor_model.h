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

// Bounds on the sensors' noise (README, "Robot file"). Every reading is weighed by 1/sigma of its
// sensor: a sigma of 0 (or 1e-300) turns residuals and Jacobians into infinities, which failed
// deep inside the solvers (Ipopt's Invalid_Number_Detected, "an anchor inside its pulley?"). A
// micrometre or a microradian is finer than any sensor of a cable robot (its cables stretch
// more than that under a newton), and the identification still converges there: the built-in
// robot with an encoder sigma of 1e-6 m took 15 iterations, 1e-7 m 321 (beyond the default
// limit of 100), and 1e-8 m failed, the encoders weighing 10^5 times the laser.
constexpr double kMinSensorSigma_m = 1e-6;
constexpr double kMinSensorSigma_rad = 1e-6;
// The most a length key of the sensors block may be (encoder and tracker sigma, laser accuracy
// and repeatability ranges): frames are a few metres (at most kMaxFrameSide_m), the
// identification refuses estimates 0.5 m from nominal, so a metre of sensor noise measures
// nothing; more is a unit slip (6 typed for 6 mm).
constexpr double kMaxSensorLength_m = 1.0;
// The most an inclinometer range may be: the range of angles is below 89 degrees, and an
// inclinometer wrong by 30 degrees measures nothing in it.
constexpr double kMaxInclinometerRange_deg = 30.0;

// Why `s` is no sensor (the robot-file key, "sensors.encoder.sigma", or "sensors.laser" for
// the sigma its two ranges give, and the problem), nullopt if it is one: each range in [0, its
// maximum], each sigma (encoder, tracker, and hypot(accuracy, repeatability) / 3 of the laser and
// the inclinometer) at least the minimum above. The robot file and the bench fit check with it.
std::optional<SensorModelProblem> CheckSensorNoise(const SensorNoise& s);

}  // namespace cablecal
