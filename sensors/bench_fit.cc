#include "sensors/bench_fit.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>

#include "common/csv.h"
#include "common/error.h"
#include "common/format.h"
#include "common/version.h"
#include "common/yaml_writer.h"
#include "model/sensor_model.h"

namespace cablecal {
namespace {

// Three significant digits, for the comments and messages a reader compares.
std::string Short(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.3g", v);
  return buffer;
}

// The readings grouped by reference value (equal doubles: a reference typed the same way on
// every row of its repeats).
struct ReferenceGroup {
  double reference = 0.0;
  int count = 0;
  double mean_error = 0.0;
};

struct GroupedBench {
  std::vector<ReferenceGroup> groups;  // ascending reference
  double within_sum_squares = 0.0;     // of the errors about their reference's mean
  BenchSummary summary;
};

GroupedBench Group(const std::vector<BenchReading>& readings) {
  std::map<double, std::vector<double>> errors;
  for (const BenchReading& r : readings) errors[r.reference].push_back(r.reading - r.reference);
  GroupedBench out;
  for (const auto& [reference, e] : errors) {
    ReferenceGroup g{reference, static_cast<int>(e.size()), 0.0};
    for (double x : e) g.mean_error += x;
    g.mean_error /= g.count;
    for (double x : e) out.within_sum_squares += (x - g.mean_error) * (x - g.mean_error);
    out.groups.push_back(g);
    if (g.count > 1) ++out.summary.repeated_references;
  }
  out.summary.readings = static_cast<int>(readings.size());
  out.summary.references = static_cast<int>(out.groups.size());
  if (!out.groups.empty()) {
    out.summary.reference_min = out.groups.front().reference;
    out.summary.reference_max = out.groups.back().reference;
  }
  return out;
}

// The systematic part fitted to the per-reference means, with the random part's split.
struct LinearFit {
  Eigen::VectorXd coefficients;
  Eigen::MatrixXd covariance;  // of the coefficients
  double accuracy_sigma = 0.0, repeatability_sigma = 0.0;
};

// Least squares of the per-reference mean errors on `design` (one row per group). Each mean has
// variance sigma_a^2 + sigma_r^2 / n_g: the accuracy's per-reference error plus the mean of n_g
// repeats. The residual variance s^2 estimates it (exactly when every reference has the same
// number of repeats, on average otherwise), so the coefficients' covariance is s^2 (X^T X)^-1
// and sigma_a^2 = s^2 - sigma_r^2 mean(1 / n_g), floored at 0. sigma_r^2 is the pooled variance
// of the repeats about their means, with readings - references degrees of freedom.
LinearFit FitMeans(const GroupedBench& bench, const Eigen::MatrixXd& design) {
  const int g = static_cast<int>(bench.groups.size());
  const int p = static_cast<int>(design.cols());
  Eigen::VectorXd y(g);
  double inverse_count_mean = 0.0;
  for (int k = 0; k < g; ++k) {
    y(k) = bench.groups[k].mean_error;
    inverse_count_mean += 1.0 / bench.groups[k].count / g;
  }
  LinearFit fit;
  const Eigen::MatrixXd xtx_inverse = (design.transpose() * design).inverse();
  fit.coefficients = xtx_inverse * design.transpose() * y;
  const double residual_variance = (y - design * fit.coefficients).squaredNorm() / (g - p);
  fit.covariance = residual_variance * xtx_inverse;
  const double repeat_variance = bench.within_sum_squares / (bench.summary.readings - g);
  fit.repeatability_sigma = std::sqrt(repeat_variance);
  fit.accuracy_sigma = std::sqrt(std::max(0.0, residual_variance - repeat_variance * inverse_count_mean));
  return fit;
}

// The bench's shape must determine the model: enough distinct references for the coefficients
// and a residual, and a repeated reference for the repeatability.
void RequireBench(const GroupedBench& bench, int coefficients, const std::string& what, const std::string& source) {
  const BenchSummary& s = bench.summary;
  if (s.references < coefficients + 1) {
    throw InputError(source, "",
                     std::to_string(s.readings) + " reading" + (s.readings == 1 ? "" : "s") + " of " +
                         std::to_string(s.references) + " reference value" + (s.references == 1 ? "" : "s") + ": " +
                         what + " need readings at " + std::to_string(coefficients + 1) +
                         " or more different reference values");
  }
  if (s.repeated_references == 0) {
    throw InputError(source, "",
                     "no reference value was read more than once: the repeatability is the spread of repeated "
                     "readings of one reference (give each reference several rows)");
  }
}

std::string RangeText(BenchSensor sensor, const BenchSummary& s) {
  return sensor == BenchSensor::kInclinometer ? Short(s.reference_min / kDegToRad) + " to " +
                                                     Short(s.reference_max / kDegToRad) + " degrees"
                                               : Short(s.reference_min) + " to " + Short(s.reference_max) + " m";
}

std::string BenchText(BenchSensor sensor, const BenchSummary& s) {
  return std::to_string(s.readings) + " readings of " + std::to_string(s.references) + " references (" +
         std::to_string(s.repeated_references) + " repeated), " + RangeText(sensor, s);
}

}  // namespace

const char* ToString(BenchSensor sensor) { return sensor == BenchSensor::kInclinometer ? "inclinometer" : "laser"; }

std::vector<std::string> BenchColumns(BenchSensor sensor) {
  if (sensor == BenchSensor::kInclinometer) return {"reference_rad", "reading_rad"};
  return {"reference_m", "reading_m"};
}

void CheckBenchReading(BenchSensor sensor, const BenchReading& r) {
  const std::vector<std::string> columns = BenchColumns(sensor);
  const auto column = [&](int k) { return "column '" + columns[k] + "'"; };
  const double values[2] = {r.reference, r.reading};
  for (int k = 0; k < 2; ++k) {
    const double v = values[k];
    if (!std::isfinite(v)) throw InputError(r.where, column(k), "must be a finite number (got " + FormatDouble(v) + ")");
    if (sensor == BenchSensor::kInclinometer && !(std::abs(v) < 0.5 * M_PI)) {
      const bool degrees = std::abs(v) <= 360.0 && std::abs(v) >= 2.0;
      throw InputError(r.where, column(k),
                       FormatDouble(v) + " rad is at or beyond +-90 degrees, where sec(theta) is infinite" +
                           (degrees ? " (degrees? angles are in radians)" : ""));
    }
    if (sensor == BenchSensor::kLaser && !(v >= 0.0)) {
      throw InputError(r.where, column(k), FormatDouble(v) + " m is negative: a distance cannot be");
    }
    if (sensor == BenchSensor::kLaser && !(v <= kMaxFrameSide_m)) {
      throw InputError(r.where, column(k),
                       FormatDouble(v) + " m is more than " + FormatDouble(kMaxFrameSide_m) +
                           " m: millimetres? distances are in m");
    }
  }
  const double error = r.reading - r.reference;
  const double bound = sensor == BenchSensor::kInclinometer ? kMaxBenchError_rad : kMaxBenchError_m;
  if (!(std::abs(error) <= bound)) {
    throw InputError(r.where, column(1),
                     "differs from the reference by " + FormatDouble(error) +
                         (sensor == BenchSensor::kInclinometer ? " rad" : " m") + ", more than " +
                         (sensor == BenchSensor::kInclinometer ? Short(bound / kDegToRad) + " degrees"
                                                               : FormatDouble(bound) + " m") +
                         ": a reading of another reference, or other units?");
  }
}

std::vector<BenchReading> ReadBenchCsv(BenchSensor sensor, const std::string& path, char delimiter,
                                       const std::function<void(const std::vector<std::string>&)>& on_ignored) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "", "cannot open the file");
  return ReadBenchCsv(sensor, in, path, delimiter, on_ignored);
}

std::vector<BenchReading> ReadBenchCsv(BenchSensor sensor, std::istream& in, const std::string& name, char delimiter,
                                       const std::function<void(const std::vector<std::string>&)>& on_ignored) {
  std::vector<BenchReading> out;
  ForEachCsvRowByName(in, name, delimiter, BenchColumns(sensor), {}, on_ignored, [&](const CsvRow& row) {
    if (static_cast<int>(out.size()) >= kMaxBenchReadings) {
      throw InputError(row.Where(), "", "more than " + std::to_string(kMaxBenchReadings) + " readings");
    }
    BenchReading r{row.Number(0), row.Number(1), row.Where()};
    CheckBenchReading(sensor, r);
    out.push_back(std::move(r));
  });
  return out;
}

namespace {

// A reading's deviation from the mean of its reference's other readings, in sigmas of the
// repeatability pooled without it (the externally studentized residual of the one-way layout).
struct RepeatCheck {
  std::size_t index = 0;
  double sigmas = 0.0, others_mean = 0.0, sigma = 0.0;
};

std::vector<RepeatCheck> RepeatsBeyond(const std::vector<BenchReading>& readings, double bound) {
  std::map<double, std::vector<std::size_t>> by_reference;
  for (std::size_t k = 0; k < readings.size(); ++k) by_reference[readings[k].reference].push_back(k);
  const auto error = [&](std::size_t k) { return readings[k].reading - readings[k].reference; };
  double within = 0.0;  // sum of squares of the errors about their reference's mean
  std::map<double, double> mean;
  for (const auto& [reference, members] : by_reference) {
    double sum = 0.0;
    for (std::size_t k : members) sum += error(k);
    mean[reference] = sum / members.size();
    for (std::size_t k : members) within += std::pow(error(k) - mean[reference], 2);
  }
  // Leaving one reading of a repeated reference out keeps every reference: N - G - 1 degrees.
  const int degrees = static_cast<int>(readings.size()) - static_cast<int>(by_reference.size()) - 1;
  std::vector<RepeatCheck> beyond;
  if (degrees < kBenchOutlierMinDegrees) return beyond;
  for (const auto& [reference, members] : by_reference) {
    const double n = static_cast<double>(members.size());
    if (n < 2) continue;
    for (std::size_t k : members) {
      const double d = error(k) - mean[reference];
      const double within_without = std::max(0.0, within - n / (n - 1.0) * d * d);
      const double sigma = std::sqrt(within_without / degrees);
      if (!(sigma > 0.0)) continue;  // the others read their references exactly
      // e - mean(others) = n/(n-1) d, whose variance is sigma^2 n/(n-1).
      const double sigmas = d * std::sqrt(n / (n - 1.0)) / sigma;
      if (std::abs(sigmas) > bound) {
        beyond.push_back({k, sigmas, (n * mean[reference] - error(k)) / (n - 1.0) + reference, sigma});
      }
    }
  }
  return beyond;
}

}  // namespace

void CheckReadingsAgainstTheirReference(BenchSensor sensor, const std::vector<BenchReading>& readings) {
  const std::vector<RepeatCheck> beyond = RepeatsBeyond(readings, kBenchOutlierSigmas);
  if (beyond.empty()) return;
  const RepeatCheck& worst = *std::max_element(beyond.begin(), beyond.end(), [](const RepeatCheck& a, const RepeatCheck& b) {
    return std::abs(a.sigmas) < std::abs(b.sigmas);
  });
  const BenchReading& r = readings[worst.index];
  const char* unit = sensor == BenchSensor::kInclinometer ? " rad" : " m";
  throw InputError(r.where, "column '" + BenchColumns(sensor)[1] + "'",
                   FormatDouble(r.reading) + unit + " is " + Short(std::abs(worst.sigmas)) +
                       " sigma from the other readings of its reference " + FormatDouble(r.reference) + unit +
                       " (their mean " + Short(worst.others_mean) + unit + "; sigma " + Short(worst.sigma) + unit +
                       ", the repeatability of the bench without it), beyond " + FormatDouble(kBenchOutlierSigmas) +
                       " sigma: a misread or mistyped reading, which would inflate the fitted repeatability; check it, or "
                       "drop that row" +
                       (beyond.size() > 1 ? " (" + std::to_string(beyond.size()) + " readings in all are beyond " +
                                                FormatDouble(kBenchOutlierSigmas) + " sigma)"
                                          : ""));
}

InclinometerFit FitInclinometer(const std::vector<BenchReading>& readings, const std::string& source) {
  const GroupedBench bench = Group(readings);
  const int g = bench.summary.references;
  Eigen::MatrixXd design(g, 2);
  for (int k = 0; k < g; ++k) design.row(k) << 1.0, 1.0 / std::cos(bench.groups[k].reference) - 1.0;
  // sec(theta) - 1 is about theta^2 / 2: references of one |theta| (or within a few
  // hundredths of a degree of it) leave the two columns one. Said before the count of
  // references, which +-theta alone would also fail: this is what to change.
  const double spread = g > 0 ? design.col(1).maxCoeff() - design.col(1).minCoeff() : 0.0;
  if (g > 1 && !(spread > 1e-6)) {
    throw InputError(source, "",
                     "every reference has the same |theta| (" + RangeText(BenchSensor::kInclinometer, bench.summary) +
                         "): the offset and the sec term cannot be told apart; read references of several "
                         "angles (0 to 60 degrees, say)");
  }
  RequireBench(bench, 2, "the offset, the sec coefficient and the accuracy", source);
  const LinearFit fit = FitMeans(bench, design);
  InclinometerFit out;
  out.source = source;
  out.bench = bench.summary;
  out.offset_rad = fit.coefficients(0);
  out.sec_coefficient_rad = fit.coefficients(1);
  out.offset_se_rad = std::sqrt(fit.covariance(0, 0));
  out.sec_coefficient_se_rad = std::sqrt(fit.covariance(1, 1));
  const double se_product = out.offset_se_rad * out.sec_coefficient_se_rad;
  out.correlation = se_product > 0.0 ? fit.covariance(0, 1) / se_product : 0.0;
  out.accuracy_rad = 3.0 * fit.accuracy_sigma;
  out.repeatability_rad = 3.0 * fit.repeatability_sigma;
  return out;
}

LaserFit FitLaser(const std::vector<BenchReading>& readings, const std::string& source) {
  const GroupedBench bench = Group(readings);
  RequireBench(bench, 1, "the offset and the accuracy", source);
  const LinearFit fit = FitMeans(bench, Eigen::MatrixXd::Ones(bench.summary.references, 1));
  LaserFit out;
  out.source = source;
  out.bench = bench.summary;
  out.offset_m = fit.coefficients(0);
  out.offset_se_m = std::sqrt(fit.covariance(0, 0));
  out.accuracy_m = 3.0 * fit.accuracy_sigma;
  out.repeatability_m = 3.0 * fit.repeatability_sigma;
  return out;
}

SensorNoise FittedSensors(const Robot& robot, const SensorsFit& fit) {
  SensorNoise s = robot.sensors;
  if (fit.inclinometer) {
    s.inclinometer_accuracy_rad = fit.inclinometer->accuracy_rad;
    s.inclinometer_repeatability_rad = fit.inclinometer->repeatability_rad;
    s.systematic.inclinometer_offset_rad = fit.inclinometer->offset_rad;
    s.systematic.inclinometer_sec_coefficient_rad = fit.inclinometer->sec_coefficient_rad;
  }
  if (fit.laser) {
    s.laser_accuracy_m = fit.laser->accuracy_m;
    s.laser_repeatability_m = fit.laser->repeatability_m;
    s.systematic.laser_offset_m = fit.laser->offset_m;
  }
  // The block must load as written: the same checks as the robot file's.
  if (std::optional<SensorModelProblem> problem = CheckSensorNoise(s)) {
    const bool laser = problem->key.find(".laser") != std::string::npos;
    const bool fitted = laser ? fit.laser.has_value() : fit.inclinometer.has_value();
    if (fitted) {
      throw InputError(laser ? fit.laser->source : fit.inclinometer->source, "",
                       "the fitted " + problem->key + " would be refused by the robot file of " + robot.name + ": " +
                           problem->problem + " (readings that repeat their reference exactly, or rounded coarsely?)");
    }
  }
  if (const std::optional<SensorModelProblem> problem = CheckSystematicErrors(s.systematic, robot.theta_max_rad)) {
    const bool laser = problem->key.find(".laser.") != std::string::npos;
    throw InputError(laser ? fit.laser->source : fit.inclinometer->source, "",
                     "the fitted " + problem->key + " would be refused by the robot file of " + robot.name + ": " +
                         problem->problem);
  }
  return s;
}

std::vector<std::string> FitWarnings(const Robot& robot, const SensorsFit& fit) {
  std::vector<std::string> warnings;
  if (fit.inclinometer) {
    const BenchSummary& b = fit.inclinometer->bench;
    const double reach = std::max(std::abs(b.reference_min), std::abs(b.reference_max));
    if (reach < robot.theta_max_rad) {
      warnings.push_back(fit.inclinometer->source + ": the references reach " + Short(reach / kDegToRad) +
                         " degrees, the inclinometer range of " + robot.name + " is " +
                         Short(robot.theta_max_rad / kDegToRad) + ": the sec term is extrapolated beyond them");
    }
  }
  if (fit.laser) {
    const BenchSummary& b = fit.laser->bench;
    const double top = std::min(robot.laser_range_m, robot.frame_height_m);
    if (b.reference_max < top) {
      warnings.push_back(fit.laser->source + ": the references reach " + Short(b.reference_max) + " m, the laser of " +
                         robot.name + " reads up to " + Short(top) + " m: the offset is extrapolated beyond them");
    }
  }
  return warnings;
}

std::string FittedRobotYaml(const Robot& robot, const SensorsFit& fit, const std::string& command_line) {
  Robot fitted = robot;
  fitted.sensors = FittedSensors(robot, fit);
  const std::string text = ProvenanceComment(command_line) + "# " + PrintableText(robot.name) +
                           "'s robot file with the sensors block fitted from bench readings (README, \"Sensor error "
                           "models\")\n" + RobotToYaml(fitted);
  LoadRobotFromString(text, "the fitted robot file");  // it loads as written, or nothing is written
  return text;
}

std::string SensorsFitYaml(const Robot& robot, const SensorsFit& fit, const std::string& command_line) {
  const SensorNoise sensors = FittedSensors(robot, fit);
  std::vector<std::string> kept = {"encoder"};
  if (sensors.tracker_sigma_m) kept.push_back("tracker");
  if (!fit.laser) kept.insert(kept.begin(), "laser");
  if (!fit.inclinometer) kept.insert(kept.begin(), "inclinometer");
  std::string kept_text;
  for (std::size_t k = 0; k < kept.size(); ++k) {
    kept_text += (k == 0 ? "" : k + 1 == kept.size() ? " and " : ", ") + kept[k];
  }
  std::string head = ProvenanceComment(command_line);
  head += "# The sensors' error models fitted from bench readings (README, \"Sensor error models\"). The\n"
          "# sensors: block below replaces a robot file's own as it is; its " + kept_text + "\n"
          "# entries are those of " + PrintableText(robot.name) + " (--robot), not fitted.\n";
  if (fit.inclinometer) {
    const InclinometerFit& f = *fit.inclinometer;
    head += "# inclinometer (" + PrintableText(f.source) + "): " + BenchText(BenchSensor::kInclinometer, f.bench) +
            ";\n#   e = offset + k (sec theta - 1): offset " + Short(f.offset_rad / kDegToRad) +
            " degrees (standard error " + Short(f.offset_se_rad / kDegToRad) + "),\n#   k " +
            Short(f.sec_coefficient_rad / kDegToRad) + " degrees (standard error " +
            Short(f.sec_coefficient_se_rad / kDegToRad) + "), correlation " + Short(f.correlation) +
            ";\n#   accuracy " + Short(f.accuracy_rad / kDegToRad) + " degrees, repeatability " +
            Short(f.repeatability_rad / kDegToRad) + " degrees (3-sigma ranges)\n";
  }
  if (fit.laser) {
    const LaserFit& f = *fit.laser;
    head += "# laser (" + PrintableText(f.source) + "): " + BenchText(BenchSensor::kLaser, f.bench) +
            ";\n#   e = offset: offset " + Short(f.offset_m) + " m (standard error " + Short(f.offset_se_m) +
            ");\n#   accuracy " + Short(f.accuracy_m) + " m, repeatability " + Short(f.repeatability_m) +
            " m (3-sigma ranges)\n";
  }
  YAML::Emitter o;
  o << YAML::BeginMap << YAML::Key << "sensors" << YAML::Value;
  EmitSensors(o, sensors);
  o << YAML::EndMap;
  return head + YamlText(o);
}

}  // namespace cablecal
