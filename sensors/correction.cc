#include "sensors/correction.h"

#include "common/error.h"
#include "model/sensor_model.h"

namespace cablecal {

std::vector<Measurement> CorrectedReadings(const Robot& robot, std::vector<Measurement> readings,
                                           const std::string& source) {
  const SystematicSensorErrors& e = robot.sensors.systematic;
  if (!e.any()) {
    CheckReadingsPlausible(robot, readings, source);
    return readings;
  }
  for (Measurement& m : readings) {
    if (m.has_laser) m.z_m = CorrectedLaserReading(e, m.z_m);
    if (m.has_inclinometer) m.theta_rad = CorrectedInclinometerReading(e, m.theta_rad);
  }
  try {
    CheckReadingsPlausible(robot, readings, source);
  } catch (const InputError& error) {
    throw InputError("", "", std::string(error.what()) +
                                 " (the reading corrected for the systematic sensor errors of " + robot.name + ")");
  }
  return readings;
}

}  // namespace cablecal
