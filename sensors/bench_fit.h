// The sensors' error models fitted from bench readings (cablecal sensors fit; README, "Sensor
// error models"): each sensor read at known reference values, several times each, as in the
// paper's Section 2.2 "Sensors accuracy test". For an error e = reading - reference:
//   inclinometer  e = offset + k (sec(reference) - 1) + random    (model/sensor_model.h)
//   laser         e = offset + random
// The systematic part is fitted by ordinary least squares on the mean error of each reference
// value; the random part splits into the repeatability (the pooled spread of repeated readings
// of one reference) and the accuracy (the spread of the per-reference means around the fit that
// the repeatability does not explain), each reported as a 3-sigma range, the convention of the
// robot file's sensors block.
#pragma once

#include <cmath>
#include <functional>
#include <istream>
#include <optional>
#include <string>
#include <vector>

#include "model/robot.h"

namespace cablecal {

enum class BenchSensor { kInclinometer, kLaser };
const char* ToString(BenchSensor sensor);  // "inclinometer", "laser"
// The bench CSV's columns: reference_rad,reading_rad or reference_m,reading_m.
std::vector<std::string> BenchColumns(BenchSensor sensor);

// One reading of the sensor at a reference value, SI (rad or m).
struct BenchReading {
  double reference = 0.0;
  double reading = 0.0;
  std::string where;  // "file:line" or "inclinometer: row 3", for messages
};

// A reading whose error is beyond these is not one of this sensor's (a reading of another
// reference, or a unit slip), and would only inflate the fitted accuracy.
constexpr double kMaxBenchError_rad = 10.0 * M_PI / 180.0;
constexpr double kMaxBenchError_m = 0.2;
constexpr int kMaxBenchReadings = 100000;

// Throws InputError naming the reading's place and column: an inclinometer reference or
// reading at or beyond +-90 degrees (sec is infinite there; "degrees?" when it looks like
// degrees), a negative laser distance or one beyond kMaxFrameSide_m ("millimetres?"), an error
// beyond the bounds above.
void CheckBenchReading(BenchSensor sensor, const BenchReading& reading);

// A bench CSV, read by column name as a lab's log comes (common/csv.h): the two columns of
// BenchColumns in any order, other columns ignored and named once to `on_ignored`, cells
// split at `delimiter`; one row per reading, repeated readings of one reference on rows of
// their own. Every reading is checked (CheckBenchReading); at most kMaxBenchReadings.
std::vector<BenchReading> ReadBenchCsv(BenchSensor sensor, const std::string& path, char delimiter = ',',
                                       const std::function<void(const std::vector<std::string>&)>& on_ignored = {});
std::vector<BenchReading> ReadBenchCsv(BenchSensor sensor, std::istream& in, const std::string& name,
                                       char delimiter = ',',
                                       const std::function<void(const std::vector<std::string>&)>& on_ignored = {});

// Each reading against the other readings of its reference, as identify checks each pose
// against the others: the reading's deviation from their mean, over the repeatability sigma
// pooled from every other repeat of the bench (the reading itself left out, so that a gross
// one cannot hide by inflating it). Beyond kBenchOutlierSigmas (identify's 4.5) the reading is
// refused (InputError naming its place and column, with the advice to check or drop it): least
// squares would take it in whole, and a 40-sigma reading made the fitted repeatability 9 to
// 18 times too large. Readings of a reference read once cannot be checked; nor can any when the
// pooled repeats leave fewer than kBenchOutlierMinDegrees degrees of freedom (a t test on fewer
// would refuse clean readings often) or read their references exactly (no spread to compare).
constexpr double kBenchOutlierSigmas = 4.5;
constexpr int kBenchOutlierMinDegrees = 10;
void CheckReadingsAgainstTheirReference(BenchSensor sensor, const std::vector<BenchReading>& readings);

// What the bench held: readings, distinct reference values, those read more than once, and
// the references' span (rad or m).
struct BenchSummary {
  int readings = 0;
  int references = 0;
  int repeated_references = 0;
  double reference_min = 0.0, reference_max = 0.0;
};

// Coefficients with their standard errors (from the residual spread of the per-reference means:
// Student's t with references - coefficients degrees of freedom), ranges as 3 sigma.
struct InclinometerFit {
  std::string source;  // the bench file, or the Python argument
  BenchSummary bench;
  double offset_rad = 0.0, offset_se_rad = 0.0;
  double sec_coefficient_rad = 0.0, sec_coefficient_se_rad = 0.0;
  double correlation = 0.0;  // of the two estimates
  double accuracy_rad = 0.0, repeatability_rad = 0.0;
};
struct LaserFit {
  std::string source;
  BenchSummary bench;
  double offset_m = 0.0, offset_se_m = 0.0;
  double accuracy_m = 0.0, repeatability_m = 0.0;
};

// InputError naming `source` for a bench that cannot determine the model: fewer distinct
// references than coefficients + 1 (3 for the inclinometer, 2 for the laser), no reference read
// twice (no repeatability), or inclinometer references of a single |theta| (the offset and the
// sec term would be one).
InclinometerFit FitInclinometer(const std::vector<BenchReading>& readings, const std::string& source);
LaserFit FitLaser(const std::vector<BenchReading>& readings, const std::string& source);

struct SensorsFit {
  std::optional<InclinometerFit> inclinometer;
  std::optional<LaserFit> laser;
};

// `robot`'s sensors with the fitted ones replaced (accuracy, repeatability and systematic
// terms); the others (encoder, tracker, an unfitted sensor) as they are. InputError naming
// the bench file if the robot file could not hold the result (model/sensor_model.h,
// CheckSystematicErrors against the robot's inclinometer range).
SensorNoise FittedSensors(const Robot& robot, const SensorsFit& fit);

// What the user should know: references that do not reach the robot's inclinometer range or
// laser range (the model is extrapolated there).
std::vector<std::string> FitWarnings(const Robot& robot, const SensorsFit& fit);

// The output of `sensors fit`: provenance comment lines, the fit's figures (standard errors,
// bench sizes) as comments, and the `sensors:` block of FittedSensors, which replaces a robot
// file's own as it is.
std::string SensorsFitYaml(const Robot& robot, const SensorsFit& fit, const std::string& command_line);

// sensors fit --robot-out: `robot`'s whole robot file with the fitted sensors block in place of
// its own (FittedSensors), provenance as comment lines, loadable as a robot file (checked).
std::string FittedRobotYaml(const Robot& robot, const SensorsFit& fit, const std::string& command_line);

}  // namespace cablecal
