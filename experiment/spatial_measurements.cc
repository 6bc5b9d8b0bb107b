#include "experiment/spatial_measurements.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <optional>

#include "common/csv.h"
#include "common/error.h"
#include "common/format.h"
#include "experiment/measurements.h"  // kMaxMeasuredPoses

namespace cablecal {

std::string SpatialMeasurementsCsv(const std::vector<SpatialMeasurement>& readings, const std::string& provenance) {
  const int m = readings.empty() ? 0 : static_cast<int>(readings.front().dl_m.size());
  std::vector<std::string> header = {"pose"};
  for (int i = 1; i <= m; ++i) header.push_back("dl" + std::to_string(i));
  std::array<bool, kNumSpatialSensors> present{};
  for (const SpatialSensor s : kSpatialSensors) {
    present[static_cast<int>(s)] = !readings.empty() && readings.front().has(s);
    if (!present[static_cast<int>(s)]) continue;
    for (const std::string& c : SpatialSensorColumns(s, m)) header.push_back(c);
  }
  std::string out = provenance + JoinCsv(header) + "\n";
  for (const SpatialMeasurement& r : readings) {
    out += std::to_string(r.pose_id);
    for (int i = 0; i < m; ++i) out += "," + FormatDouble(r.dl_m(i));
    for (const SpatialSensor s : kSpatialSensors) {
      CABLECAL_CHECK(r.has(s) == present[static_cast<int>(s)], "one file, one set of sensors");
      for (Eigen::Index k = 0; k < r.values(s).size(); ++k) out += "," + FormatDouble(r.values(s)(k));
    }
    out += "\n";
  }
  return out;
}

std::vector<SpatialMeasurement> ReadSpatialMeasurementsCsv(const std::string& path, int num_cables, char delimiter) {
  std::ifstream in = OpenCsvFile(path);
  return ReadSpatialMeasurementsCsv(in, path, num_cables, delimiter);
}

std::vector<SpatialMeasurement> ReadSpatialMeasurementsCsv(std::istream& in, const std::string& path, int num_cables,
                                                           char delimiter) {
  std::vector<std::string> required = {"pose"};
  for (int i = 1; i <= num_cables; ++i) required.push_back("dl" + std::to_string(i));
  std::vector<std::string> optional;
  std::array<int, kNumSpatialSensors> first{};  // each sensor's first column in row.header
  for (const SpatialSensor s : kSpatialSensors) {
    first[static_cast<int>(s)] = static_cast<int>(required.size() + optional.size());
    for (const std::string& c : SpatialSensorColumns(s, num_cables)) optional.push_back(c);
  }
  std::vector<SpatialMeasurement> out;
  std::array<bool, kNumSpatialSensors> has{};
  // What a lab likely gave instead: a pose plan (sample's or design's: x, y, z, ..., l1..lm,
  // whose roll, pitch and yaw are also sensor columns) or its own log's extra columns.
  const auto explain = [](const std::vector<std::string>& other) {
    const auto has = [&](const char* c) { return std::find(other.begin(), other.end(), c) != other.end(); };
    if (has("x") && has("l1")) {
      return std::string(": this looks like a pose plan (sample's or design's output), not readings: run it on the "
                         "robot and record what the sensors read, or simulate it (cablecal simulate --plan)");
    }
    return std::string(": a spatial robot's readings have only these columns (remove any other, a timestamp or a "
                       "temperature: an unknown column is refused so that a misspelt sensor column is never dropped "
                       "unsaid)");
  };
  ForEachCsvRowByNameStrict(in, path, delimiter, required, optional, [&](const CsvRow& row) {
    if (out.empty()) {
      // A sensor is read whole or not at all: half a position is a mistake, not a sensor.
      for (const SpatialSensor s : kSpatialSensors) {
        const int begin = first[static_cast<int>(s)], size = SpatialSensorSize(s, num_cables);
        int count = 0;
        for (int k = begin; k < begin + size; ++k) count += row.present[k];
        if (count > 0 && count < size) {
          for (int k = begin; k < begin + size; ++k) {
            if (row.present[k]) continue;
            throw InputError(*row.path + ":" + std::to_string(row.header_line), "column '" + (*row.header)[k] + "'",
                             "missing: the " + std::string(ToString(s)) + " reads " +
                                 JoinCsv(SpatialSensorColumns(s, num_cables)) + ", all of them or none");
          }
        }
        has[static_cast<int>(s)] = count == size;
      }
    }
    if (static_cast<int>(out.size()) >= kMaxMeasuredPoses) {
      throw InputError(row.Where(), "", "more than " + std::to_string(kMaxMeasuredPoses) + " readings");
    }
    SpatialMeasurement m;
    m.where = row.Where();
    m.pose_id = row.PositiveInt(0);
    m.dl_m.resize(num_cables);
    for (int i = 0; i < num_cables; ++i) m.dl_m(i) = row.Number(1 + i);
    for (const SpatialSensor s : kSpatialSensors) {
      if (!has[static_cast<int>(s)]) continue;
      Eigen::VectorXd& v = m.values(s);
      v.resize(SpatialSensorSize(s, num_cables));
      for (Eigen::Index k = 0; k < v.size(); ++k) v(k) = row.Number(first[static_cast<int>(s)] + static_cast<int>(k));
    }
    out.push_back(std::move(m));
  }, explain);
  return out;
}

void CheckSpatialReadingsPlausible(const SpatialRobot& robot, const std::vector<SpatialMeasurement>& readings,
                                   const std::string& source) {
  constexpr double kNoiseSigmas = 5.0;
  const Eigen::Vector3d lo = robot.p_F_frame_min_m, hi = robot.p_F_frame_max_m;
  const double diagonal_m = (hi - lo).norm();
  const auto slack = [&robot](SpatialSensor s) {
    const std::optional<RangedNoise> noise = SpatialSensorNoise(robot.sensors, s);
    return noise ? kNoiseSigmas * noise->sigma() : 0.0;
  };
  for (const SpatialMeasurement& r : readings) {
    const std::string where = r.where.empty() ? source + ": pose " + std::to_string(r.pose_id) : r.where;
    const auto refuse = [&where](const std::string& column, const std::string& why) {
      throw InputError(where, "column '" + column + "'", why);
    };
    for (int i = 0; i < r.dl_m.size(); ++i) {
      if (!(std::abs(r.dl_m(i)) <= diagonal_m + kNoiseSigmas * robot.sensors.encoder_sigma_m)) {
        refuse("dl" + std::to_string(i + 1), FormatDouble(r.dl_m(i)) + " m is more than the frame box's diagonal (" +
                                                 FormatDouble(diagonal_m) + " m): no cable of " + robot.name +
                                                 " changes its length that much (millimetres? lengths are in m)");
      }
    }
    if (r.has(SpatialSensor::kLaser)) {
      const double z = r.values(SpatialSensor::kLaser)(0), s = slack(SpatialSensor::kLaser);
      const double height_m = hi.z() - lo.z();
      if (!(z >= -s && z <= height_m + s)) {
        refuse("z", FormatDouble(z) + " m is outside the frame box's height [0, " + FormatDouble(height_m) + "] m (" +
                        FormatDouble(s) + " m of slack: 5 sigma of the laser's noise)" +
                        (std::abs(z) > 10.0 * height_m ? " (millimetres? z is in m)" : ""));
      }
    }
    if (r.has(SpatialSensor::kInclinometer)) {
      const double bound = M_PI / 2.0 + slack(SpatialSensor::kInclinometer);
      for (int a = 0; a < 2; ++a) {
        const double v = r.values(SpatialSensor::kInclinometer)(a);
        if (!(std::abs(v) <= bound)) {
          refuse(a == 0 ? "roll" : "pitch",
                 FormatDouble(v) + " rad is more than a quarter turn: no platform of " + robot.name +
                     " tilts so far (degrees? angles are in radians)");
        }
      }
    }
    if (r.has(SpatialSensor::kPosition)) {
      const double s = slack(SpatialSensor::kPosition);
      for (int a = 0; a < 3; ++a) {
        const double v = r.values(SpatialSensor::kPosition)(a);
        if (!(v >= lo(a) - diagonal_m - s && v <= hi(a) + diagonal_m + s)) {
          refuse(std::string("p") + "xyz"[a],
                 FormatDouble(v) + " m is further from the frame box than its diagonal (" + FormatDouble(diagonal_m) +
                     " m): no point of the platform is there (millimetres? positions are in m)");
        }
      }
    }
    if (r.has(SpatialSensor::kHeading)) {
      const double v = r.values(SpatialSensor::kHeading)(0);
      if (!(std::abs(v) <= 2.0 * M_PI + slack(SpatialSensor::kHeading))) {
        refuse("yaw", FormatDouble(v) + " rad is more than a turn (degrees? angles are in radians)");
      }
    }
    if (r.has(SpatialSensor::kSwivel)) {
      const Eigen::VectorXd& v = r.values(SpatialSensor::kSwivel);
      for (Eigen::Index i = 0; i < v.size(); ++i) {
        if (!(std::abs(v(i)) <= 2.0 * M_PI + slack(SpatialSensor::kSwivel))) {
          refuse("sw" + std::to_string(i + 1),
                 FormatDouble(v(i)) + " rad is more than a turn (degrees? angles are in radians)");
        }
      }
    }
    // A cable only pulls: a load cell reading a compression beyond its noise was zeroed under
    // load or is wired with the sign reversed, and the equilibrium cannot explain it.
    if (r.has(SpatialSensor::kLoadCell)) {
      const Eigen::VectorXd& v = r.values(SpatialSensor::kLoadCell);
      const double s = slack(SpatialSensor::kLoadCell);
      for (Eigen::Index i = 0; i < v.size(); ++i) {
        if (!(v(i) <= 100.0 * robot.tension_max_N + s)) {
          refuse("f" + std::to_string(i + 1),
                 FormatDouble(v(i)) + " N is more than 100 times tension.max (" + FormatDouble(robot.tension_max_N) +
                     " N): no cable of " + robot.name + " pulls that hard (units? forces are in N)");
        }
        if (!(v(i) >= -s)) {
          refuse("f" + std::to_string(i + 1),
                 FormatDouble(v(i)) + " N is a compression (" + FormatDouble(std::round(s * 1e3) / 1e3) +
                     " N of slack: 5 sigma of the load cell's noise), and a cable only pulls: a load cell "
                     "zeroed under load, or its sign reversed?");
        }
      }
    }
  }
  // Repeated pose ids are repeated readings of one pose: the same commanded lengths and the same
  // settled pose, so encoders, or any other sensor, that disagree beyond 10 sqrt(2) times their
  // noise are two poses under one id (a copied row's id, a typo), which the fit would otherwise
  // report as readings that fit no robot.
  std::map<int, const SpatialMeasurement*> first_of;
  for (const SpatialMeasurement& r : readings) {
    const auto [it, inserted] = first_of.emplace(r.pose_id, &r);
    if (inserted || it->second->dl_m.size() != r.dl_m.size()) continue;
    const auto check = [&](const Eigen::VectorXd& a, const Eigen::VectorXd& b, double sigma,
                           const std::vector<std::string>& columns, const std::string& unit, const std::string& noise) {
      if (a.size() != b.size() || !(sigma > 0.0)) return;
      Eigen::Index i = 0;
      const double apart = (a - b).cwiseAbs().maxCoeff(&i);
      if (apart <= 10.0 * std::sqrt(2.0) * sigma) return;
      const std::string where = r.where.empty() ? source + ": pose " + std::to_string(r.pose_id) : r.where;
      const std::string earlier = it->second->where.empty() ? "an earlier reading" : it->second->where;
      throw InputError(where, "column 'pose'",
                       "pose " + std::to_string(r.pose_id) + " was read before (" + earlier + ") with " + columns[i] +
                           " " + FormatDouble(apart) + " " + unit + " apart, beyond 10 times " + noise +
                           ": repeated ids are repeated readings of one pose; two poses under one id?");
    };
    std::vector<std::string> dl;
    for (Eigen::Index i = 0; i < r.dl_m.size(); ++i) dl.push_back("dl" + std::to_string(i + 1));
    check(r.dl_m, it->second->dl_m, robot.sensors.encoder_sigma_m, dl, "m", "the encoders' noise");
    for (const SpatialSensor s : kSpatialSensors) {
      const std::optional<RangedNoise> noise = SpatialSensorNoise(robot.sensors, s);
      if (!noise || !r.has(s) || !it->second->has(s)) continue;
      check(r.values(s), it->second->values(s), noise->sigma(), SpatialSensorColumns(s, static_cast<int>(r.dl_m.size())),
            SpatialSensorUnit(s), std::string("the ") + ToString(s) + "'s noise");
    }
  }
}

}  // namespace cablecal
