#include "model/sensor_model.h"

#include <cmath>
#include <cstdio>

#include "common/format.h"

namespace cablecal {
namespace {

// "%.6g": a value in a message, as typed for most.
std::string Shown(double v) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.6g", v);
  return text;
}

// A range key (as typed: m, or degrees) outside [0, most].
std::optional<SensorModelProblem> RangeProblem(const std::string& key, double value, double most, const char* unit) {
  // The degrees come back from radians: a value typed as the bound may be an ulp above it.
  if (value >= 0.0 && value <= most * (1.0 + 1e-12)) return std::nullopt;
  return SensorModelProblem{key, "must be from 0 to " + Shown(most) + " " + unit + ", a +- range taken as 3 sigma (got " +
                                     Shown(value) + ")" + (value > most ? ": units?" : "")};
}

// A sigma key (m) outside [kMinSensorSigma_m, kMaxSensorLength_m].
std::optional<SensorModelProblem> SigmaProblem(const std::string& key, double sigma_m) {
  if (sigma_m >= kMinSensorSigma_m && sigma_m <= kMaxSensorLength_m) return std::nullopt;
  return SensorModelProblem{
      key, "must be from " + Shown(kMinSensorSigma_m) + " to " + Shown(kMaxSensorLength_m) +
               " m, one standard deviation (got " + Shown(sigma_m) + ")" +
               (sigma_m > kMaxSensorLength_m ? ": units? (lengths are in m)"
                                             : ": every reading is weighed by 1/sigma, and no sensor is that precise")};
}

// The sigma a sensor's two ranges give, hypot(accuracy, repeatability) / 3, below the least.
std::optional<SensorModelProblem> CombinedProblem(const std::string& key, double sigma, double least,
                                                  const std::string& shown_sigma, const char* unit) {
  if (sigma >= least) return std::nullopt;
  return SensorModelProblem{key, "accuracy and repeatability give a sigma of " + shown_sigma + " " + unit +
                                     " (hypot(accuracy, repeatability) / 3), below " + Shown(least) + " " + unit +
                                     ": every reading is weighed by 1/sigma, and no sensor is that precise"};
}

}  // namespace

std::optional<SensorModelProblem> CheckSensorNoise(const SensorNoise& s) {
  const double deg = 1.0 / kDegToRad;
  const std::optional<SensorModelProblem> problems[] = {
      RangeProblem("sensors.laser.accuracy", s.laser_accuracy_m, kMaxSensorLength_m, "m"),
      RangeProblem("sensors.laser.repeatability", s.laser_repeatability_m, kMaxSensorLength_m, "m"),
      CombinedProblem("sensors.laser", s.laser_sigma_m(), kMinSensorSigma_m, Shown(s.laser_sigma_m()), "m"),
      RangeProblem("sensors.inclinometer.accuracy_deg", s.inclinometer_accuracy_rad * deg, kMaxInclinometerRange_deg,
                   "degrees"),
      RangeProblem("sensors.inclinometer.repeatability_deg", s.inclinometer_repeatability_rad * deg,
                   kMaxInclinometerRange_deg, "degrees"),
      CombinedProblem("sensors.inclinometer", s.inclinometer_sigma_rad(), kMinSensorSigma_rad,
                      Shown(s.inclinometer_sigma_rad()), "rad"),
      SigmaProblem("sensors.encoder.sigma", s.encoder_sigma_m),
      s.tracker_sigma_m ? SigmaProblem("sensors.tracker.sigma", *s.tracker_sigma_m) : std::nullopt,
  };
  for (const std::optional<SensorModelProblem>& p : problems) {
    if (p) return p;
  }
  return std::nullopt;
}

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
