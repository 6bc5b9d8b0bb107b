// A lab's readings corrected for the robot file's systematic sensor errors before the
// identification (identify, CLI and Python alike; README, "Sensor error models").
#pragma once

#include <string>
#include <vector>

#include "experiment/measurements.h"
#include "model/robot.h"

namespace cablecal {

// `readings` with every laser and inclinometer reading replaced by the true value that reads it
// under robot.sensors.systematic (model/sensor_model.h; encoders as read), then checked with
// CheckReadingsPlausible: the limits concern the true pose, and a reading at the edge of the
// laser's range would be refused for its offset alone. A refusal then says that the value it
// names was corrected. Without systematic errors the readings are returned and checked as read.
std::vector<Measurement> CorrectedReadings(const Robot& robot, std::vector<Measurement> readings,
                                           const std::string& source);

}  // namespace cablecal
