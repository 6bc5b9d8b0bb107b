// A lab's readings of its measurement poses: one Measurement per row of the measurement CSV
// (the encoders' length changes, then each sensor of the robot kind, model/sensors.h), the
// CSV's reader and writer, what a file says that its author likely did not mean, and the
// readings no sensor of a robot can give. Depends on model/ (the robot and its sensors).
#pragma once

#include <Eigen/Core>
#include <array>
#include <functional>
#include <istream>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "model/robot.h"
#include "model/sensors.h"

namespace cablecal {

// One reading of a pose. dl: encoder length changes from the home pose (m), one per cable;
// then each of the robot kind's other sensors' values (model/sensors.h: the planar laser's
// height z in m, the inclinometer's angle theta in rad). A lab without a laser or an
// inclinometer has no value for it (has() false; value() then 0, unused). Several readings may
// share a pose_id: repeated measurements of one pose, fitted with one set of pose unknowns.
struct Measurement {
  int pose_id = 0;
  std::string where;  // "file:line" when read from a file, for messages; empty when simulated
  Eigen::VectorXd dl_m;
  // By SensorId; empty where the data lack that sensor.
  std::array<Eigen::VectorXd, kNumSensorIds> sensor_values;

  bool has(SensorId id) const { return sensor_values[static_cast<int>(id)].size() > 0; }
  double value(SensorId id, int k = 0) const { return has(id) ? sensor_values[static_cast<int>(id)](k) : 0.0; }
  void set(SensorId id, double v) { sensor_values[static_cast<int>(id)] = Eigen::VectorXd::Constant(1, v); }
  double& at(SensorId id, int k = 0) { return sensor_values[static_cast<int>(id)](k); }  // a value the reading has
  void drop(SensorId id) { sensor_values[static_cast<int>(id)].resize(0); }
  // The sensors this reading has, by SensorId.
  std::array<bool, kNumSensorIds> sensors() const {
    std::array<bool, kNumSensorIds> out{};
    for (int k = 0; k < kNumSensorIds; ++k) out[k] = sensor_values[k].size() > 0;
    return out;
  }
};
// Measurement CSV: header pose,dl1..dlm,z,theta (m, m, m, rad); z or theta left out when the
// readings have no laser or inclinometer.
std::string MeasurementsCsv(const std::vector<Measurement>& measurements, const std::string& provenance);
// Throws InputError naming file, line and column (wrong header or count, non-finite number,
// non-positive pose id). A pose id may repeat (repeated readings of one pose); the z and
// theta columns may be absent (no laser, no inclinometer: has_laser / has_inclinometer false).
// CheckReadingsPlausible (below) then checks them against a robot's sensors.
// At most kMaxMeasuredPoses rows (readings; the file is streamed and rejected at the next row).
// The file is read by column name (a lab's log): pose, dl1..dlm, z and theta in any order,
// other columns (a timestamp, a temperature) ignored and named once to `on_ignored`; cells
// split at `delimiter` (',', ';' or '\t'); an empty cell is refused with line and column.
// `on_warning` hears what is read but likely not meant (MeasurementWarnings below), once each.
std::vector<Measurement> ReadMeasurementsCsv(const std::string& path, int num_cables, char delimiter = ',',
                                             const std::function<void(const std::vector<std::string>&)>& on_ignored = {},
                                             const std::function<void(const std::string&)>& on_warning = {});
std::vector<Measurement> ReadMeasurementsCsv(std::istream& in, const std::string& name, int num_cables,
                                             char delimiter = ',',
                                             const std::function<void(const std::vector<std::string>&)>& on_ignored = {},
                                             const std::function<void(const std::string&)>& on_warning = {});

// What a measurement file says that its author likely did not mean, as warnings naming the file:
// an ignored column that looks like the laser's or the inclinometer's in other units or case
// ('theta_deg', 'z_mm', 'Theta') while the file has no 'z' or 'theta' column (that sensor is
// then taken as missing); a pose id that comes again after other poses (1, 2, 3, 1), which is
// read as a repeated reading of that pose, not as another pose (a reused id). `readings` as read.
std::vector<std::string> MeasurementWarnings(const std::string& source, const std::vector<std::string>& ignored,
                                             const std::vector<Measurement>& readings);
// A pose id that comes again after other poses (1, 2, 3, 1), read as a repeated reading of that
// pose: a warning naming the first such reading (its `where`, else `source` and its index), the
// earlier one and the count; nullopt when none. For planar and spatial readings alike (both
// carry pose_id and where).
template <typename Reading>
std::optional<std::string> ReusedPoseIdWarning(const std::string& source, const std::vector<Reading>& readings) {
  std::unordered_map<int, std::size_t> first;  // pose id -> index of its first reading
  std::size_t reused = 0, first_reused = 0;
  for (std::size_t k = 0; k < readings.size(); ++k) {
    const int id = readings[k].pose_id;
    const bool fresh = first.emplace(id, k).second;
    if (fresh || readings[k - 1].pose_id == id) continue;  // a new pose, or a repeat in a row
    if (reused++ == 0) first_reused = k;
  }
  if (reused == 0) return std::nullopt;
  const Reading& m = readings[first_reused];
  const Reading& earlier = readings[first.at(m.pose_id)];
  const std::string where = m.where.empty() ? source + ": reading " + std::to_string(first_reused + 1) : m.where;
  return where + ": pose " + std::to_string(m.pose_id) + " read again after other poses (first at " +
         (earlier.where.empty() ? "reading " + std::to_string(first.at(m.pose_id) + 1) : earlier.where) +
         "): taken as a repeated reading of the same pose; if it is another pose give it its own id" +
         (reused > 1 ? " (" + std::to_string(reused) + " readings in all repeat a pose id after other poses)" : "");
}

// The delimiter of --delimiter: ",", ";", "tab" (or a tab character); InputError otherwise.
char ParseDelimiter(const std::string& text);
constexpr int kMaxMeasuredPoses = 100000;

// Readings no sensor of `robot` can give: an encoder length change longer than the frame's
// diagonal, a laser height below 0, above the laser range or above the frame, an
// inclinometer angle beyond its range, the last two limits widened by 5 sigma of
// that sensor's noise (a pose at the edge of a range reads a little past it). Throws
// InputError naming the file, line and column (or the pose), the value and the limit;
// "units?" where it fits.
void CheckReadingsPlausible(const Robot& robot, const std::vector<Measurement>& measurements,
                            const std::string& source);
}  // namespace cablecal
