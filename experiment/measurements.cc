#include "experiment/measurements.h"

#include <cctype>
#include <fstream>
#include <optional>
#include <unordered_map>

#include "common/csv.h"
#include "common/error.h"
#include "common/format.h"
#include "common/yaml_writer.h"
#include "model/sensor_model.h"
#include "model/statics.h"

namespace cablecal {

std::string MeasurementsCsv(const std::vector<Measurement>& measurements, const std::string& provenance) {
  std::string out = provenance + "pose";
  const int m = measurements.empty() ? 2 : static_cast<int>(measurements.front().dl_m.size());
  std::array<bool, kNumSensorIds> present{};
  present.fill(true);
  if (!measurements.empty()) present = measurements.front().sensors();
  for (int i = 1; i <= m; ++i) out += ",dl" + std::to_string(i);
  for (const SensorUnit& u : kPlanarSensors) {
    if (present[static_cast<int>(u.id)]) out += std::string(",") + u.column;
  }
  out += "\n";
  for (const Measurement& r : measurements) {
    CABLECAL_CHECK(r.sensors() == present, "one file, one set of sensors");
    out += std::to_string(r.pose_id);
    for (int i = 0; i < m; ++i) out += "," + FormatDouble(r.dl_m(i));
    for (const SensorUnit& u : kPlanarSensors) {
      if (present[static_cast<int>(u.id)]) out += "," + FormatDouble(r.value(u.id));
    }
    out += "\n";
  }
  return out;
}

std::vector<Measurement> ReadMeasurementsCsv(const std::string& path, int num_cables, char delimiter,
                                             const std::function<void(const std::vector<std::string>&)>& on_ignored,
                                             const std::function<void(const std::string&)>& on_warning) {
  std::ifstream in = OpenCsvFile(path);
  return ReadMeasurementsCsv(in, path, num_cables, delimiter, on_ignored, on_warning);
}

namespace {

// Whether an ignored column `column` looks like sensor column `name` in other units or case:
// the name itself in another case, or followed by a separator ("theta_deg", "z (mm)", "Z[m]").
bool LooksLikeColumn(const std::string& column, const std::string& name) {
  std::string lower = column;
  for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (lower.compare(0, name.size(), name) != 0) return false;
  return lower.size() == name.size() || !std::isalnum(static_cast<unsigned char>(lower[name.size()]));
}

}  // namespace

std::vector<std::string> MeasurementWarnings(const std::string& source, const std::vector<std::string>& ignored,
                                             const std::vector<Measurement>& readings) {
  std::vector<std::string> warnings;
  if (readings.empty()) return warnings;
  for (const std::string& column : ignored) {
    for (const SensorUnit& u : kPlanarSensors) {
      if (readings.front().has(u.id) || !LooksLikeColumn(column, u.column)) continue;
      warnings.push_back(source + ": column '" + column + "' ignored: " + u.column + " is read from a column '" +
                         u.column + "' in " + u.unit + ", and without one the " + u.name + " is taken as missing");
    }
  }
  if (const std::optional<std::string> reused = ReusedPoseIdWarning(source, readings)) warnings.push_back(*reused);
  return warnings;
}

char ParseDelimiter(const std::string& text) {
  if (text == ",") return ',';
  if (text == ";") return ';';
  if (text == "tab" || text == "\t") return '\t';
  throw InputError("--delimiter", "", "must be ',', ';' or 'tab' (got '" + text + "')");
}

std::vector<Measurement> ReadMeasurementsCsv(std::istream& in, const std::string& path, int num_cables,
                                             char delimiter,
                                             const std::function<void(const std::vector<std::string>&)>& on_ignored,
                                             const std::function<void(const std::string&)>& on_warning) {
  std::vector<std::string> header = {"pose"};
  for (int i = 1; i <= num_cables; ++i) header.push_back("dl" + std::to_string(i));
  std::vector<Measurement> out;
  // z and theta may be absent (no laser, no inclinometer): Identify then says what the data
  // can no longer determine. The encoders are what is calibrated and always needed.
  std::vector<std::string> ignored;
  const auto note_ignored = [&](const std::vector<std::string>& names) {
    ignored = names;
    if (on_ignored) on_ignored(names);
  };
  std::vector<std::string> optional_columns;
  for (const SensorUnit& u : kPlanarSensors) optional_columns.push_back(u.column);
  ForEachCsvRowByName(in, path, delimiter, header, optional_columns, note_ignored, [&](const CsvRow& row) {
    if (static_cast<int>(out.size()) >= kMaxMeasuredPoses) {
      throw InputError(row.Where(), "", "more than " + std::to_string(kMaxMeasuredPoses) + " readings");
    }
    Measurement m;
    m.where = row.Where();
    m.pose_id = row.PositiveInt(0);
    m.dl_m.resize(num_cables);
    for (int i = 0; i < num_cables; ++i) m.dl_m(i) = row.Number(1 + i);
    for (std::size_t k = 0; k < kPlanarSensors.size(); ++k) {
      const int column = 1 + num_cables + static_cast<int>(k);
      if (row.present[column]) m.set(kPlanarSensors[k].id, row.Number(column));
    }
    out.push_back(m);
  });
  if (on_warning) {
    for (const std::string& w : MeasurementWarnings(path, ignored, out)) on_warning(w);
  }
  return out;
}

void CheckReadingsPlausible(const Robot& robot, const std::vector<Measurement>& measurements,
                            const std::string& source) {
  // A sensor's noise can carry the reading of a pose at the edge of its range a little past
  // it; kNoiseSigmas of that noise is allowed, nothing more.
  constexpr double kNoiseSigmas = 5.0;
  const double z_slack = kNoiseSigmas * robot.sensors.laser_sigma_m();
  const double theta_slack = kNoiseSigmas * robot.sensors.inclinometer_sigma_rad();
  const double z_min = -z_slack, z_max = std::min(robot.laser_range_m, robot.frame_height_m) + z_slack;
  const double theta_max = robot.theta_max_rad + theta_slack;
  // No cable can change its length by more than the frame's diagonal.
  const double dl_max = std::hypot(robot.frame_width_m, robot.frame_height_m);
  for (const Measurement& m : measurements) {
    const std::string where = m.where.empty() ? source + ": pose " + std::to_string(m.pose_id) : m.where;
    for (int i = 0; i < m.dl_m.size(); ++i) {
      if (!(std::abs(m.dl_m(i)) <= dl_max)) {
        throw InputError(where, "column 'dl" + std::to_string(i + 1) + "'",
                         FormatDouble(m.dl_m(i)) + " m is more than the frame's diagonal (" + FormatDouble(dl_max) +
                             " m): no cable of " + robot.name + " changes its length that much (millimetres? "
                             "lengths are in m)");
      }
    }
    if (m.has(SensorId::kLaser) && !(m.value(SensorId::kLaser) >= z_min && m.value(SensorId::kLaser) <= z_max)) {
      throw InputError(where, "column 'z'",
                       FormatDouble(m.value(SensorId::kLaser)) + " m is outside what the laser can read here, [" + FormatDouble(z_min) +
                           ", " + FormatDouble(z_max) + "] m (the laser range and the frame height of " + robot.name +
                           ", widened by 5 sigma of the laser's noise)" +
                           (m.value(SensorId::kLaser) > 10.0 * robot.frame_height_m ? " (millimetres? z is in m)" : ""));
    }
    if (m.has(SensorId::kInclinometer) && !(std::abs(m.value(SensorId::kInclinometer)) <= theta_max)) {
      throw InputError(where, "column 'theta'",
                       FormatDouble(m.value(SensorId::kInclinometer)) + " rad is beyond the inclinometer range of +-" +
                           FormatDouble(robot.theta_max_rad) + " rad (+-" + FormatDouble(theta_max) +
                           " with 5 sigma of its noise)" +
                           (std::abs(m.value(SensorId::kInclinometer)) > M_PI ? " (degrees? theta is in radians)" : ""));
    }
  }
}

}  // namespace cablecal
