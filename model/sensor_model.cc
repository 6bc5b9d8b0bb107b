#include "model/sensor_model.h"

#include <cmath>
#include <cstdio>

#include "common/format.h"

namespace cablecal {
namespace {

constexpr double kDegToRad = M_PI / 180.0;

}  // namespace

double LaserError(const SystematicSensorErrors& e) { return e.laser_offset_m; }

double InclinometerError(const SystematicSensorErrors& e, double theta_true_rad) {
  return e.inclinometer_offset_rad + e.inclinometer_sec_coefficient_rad * (1.0 / std::cos(theta_true_rad) - 1.0);
}

double InclinometerErrorSlope(const SystematicSensorErrors& e, double theta_rad) {
  return e.inclinometer_sec_coefficient_rad * std::tan(theta_rad) / std::cos(theta_rad);
}

double LaserReading(const SystematicSensorErrors& e, double z_true_m) { return z_true_m + LaserError(e); }

double InclinometerReading(const SystematicSensorErrors& e, double theta_true_rad) {
  return theta_true_rad + InclinometerError(e, theta_true_rad);
}

double CorrectedLaserReading(const SystematicSensorErrors& e, double reading_m) { return reading_m - LaserError(e); }

double CorrectedInclinometerReading(const SystematicSensorErrors& e, double reading_rad) {
  // sec blows up at +-90 degrees; such a reading is no inclinometer's and is refused later.
  if (!(std::abs(reading_rad) < 0.5 * M_PI)) return reading_rad;
  double theta = reading_rad;
  for (int k = 0; k < kInclinometerCorrectionIterations; ++k) theta = reading_rad - InclinometerError(e, theta);
  return theta;
}

std::optional<SensorModelProblem> CheckSystematicErrors(const SystematicSensorErrors& e, double theta_max_rad) {
  if (!(std::abs(e.laser_offset_m) <= kMaxLaserOffset_m)) {
    return SensorModelProblem{"sensors.laser.offset", FormatDouble(e.laser_offset_m) + " m is more than " +
                                                          FormatDouble(kMaxLaserOffset_m) +
                                                          " m: units? (the laser's keys are in m)"};
  }
  const double offset_deg = e.inclinometer_offset_rad / kDegToRad;
  if (!(std::abs(offset_deg) <= kMaxInclinometerSystematic_deg)) {
    return SensorModelProblem{"sensors.inclinometer.offset_deg",
                              FormatDouble(offset_deg) + " degrees is more than " +
                                  FormatDouble(kMaxInclinometerSystematic_deg) + ": units? (the key is in degrees)"};
  }
  const double k_deg = e.inclinometer_sec_coefficient_rad / kDegToRad;
  if (!(std::abs(k_deg) <= kMaxInclinometerSystematic_deg)) {
    return SensorModelProblem{"sensors.inclinometer.sec_coefficient_deg",
                              FormatDouble(k_deg) + " degrees is more than " +
                                  FormatDouble(kMaxInclinometerSystematic_deg) + ": units? (the key is in degrees)"};
  }
  const double slope = std::abs(InclinometerErrorSlope(e, theta_max_rad));
  if (!(slope <= kMaxInclinometerErrorSlope)) {
    char shown[32];
    std::snprintf(shown, sizeof(shown), "%.3g", slope);
    return SensorModelProblem{
        "sensors.inclinometer.sec_coefficient_deg",
        FormatDouble(k_deg) + " degrees makes the error change by " + shown +
            " rad per rad at the inclinometer's range (limits.theta_max_deg " + FormatDouble(theta_max_rad / kDegToRad) +
            "), more than " + FormatDouble(kMaxInclinometerErrorSlope) +
            ": the readings could not be corrected reliably (a smaller coefficient, or a smaller range)"};
  }
  return std::nullopt;
}

}  // namespace cablecal
