#include "experiment/correction.h"

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
    if (m.has(SensorId::kLaser)) m.set(SensorId::kLaser, CorrectedLaserReading(e, m.value(SensorId::kLaser)));
    if (m.has(SensorId::kInclinometer)) {
      m.set(SensorId::kInclinometer, CorrectedInclinometerReading(e, m.value(SensorId::kInclinometer)));
    }
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
