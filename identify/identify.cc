#include "identify/identify.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <type_traits>
#include <vector>

#include "common/error.h"
#include "common/format.h"
#include "model/sensors.h"

namespace cablecal {

Estimator ParseEstimator(const std::string& text) {
  if (text == "ml") return Estimator::kMaximumLikelihood;
  if (text == "paper") return Estimator::kPaper;
  throw InputError("--estimator", "", "must be ml or paper (got '" + text + "')");
}

Gauge ParseGauge(const std::string& text) {
  if (text == "a1x") return Gauge::kA1x;
  if (text == "prior") return Gauge::kPrior;
  if (text == "none") return Gauge::kNone;
  throw InputError("--gauge", "", "must be a1x, prior or none (got '" + text + "')");
}

RobustLoss ParseLoss(const std::string& text) {
  const std::string::size_type colon = text.find(':');
  const std::string kind = text.substr(0, colon);
  RobustLoss loss;
  if (kind == "none" && colon == std::string::npos) return loss;
  if (kind == "huber") {
    loss = {LossKind::kHuber, kDefaultHuberScaleSigmas};
  } else if (kind == "cauchy") {
    loss = {LossKind::kCauchy, kDefaultCauchyScaleSigmas};
  } else {
    throw InputError("--loss", "", "must be none, huber or cauchy, optionally with :SCALE in sigmas, e.g. huber:3 (got '" +
                                       text + "')");
  }
  if (colon != std::string::npos) {
    double scale = 0.0;
    // Below half a sigma every clean reading would count as an outlier.
    if (!ParseFiniteDouble(text.substr(colon + 1), &scale) || !(scale >= 0.5) || !(scale <= 1e6)) {
      throw InputError("--loss", "", "the scale after ':' must be a number from 0.5 to 1e6, in sigmas (got '" + text + "')");
    }
    loss.scale_sigmas = scale;
  }
  return loss;
}

std::string ToString(const RobustLoss& loss) {
  switch (loss.kind) {
    case LossKind::kNone: return "none";
    case LossKind::kHuber: return "huber:" + FormatDouble(loss.scale_sigmas);
    case LossKind::kCauchy: return "cauchy:" + FormatDouble(loss.scale_sigmas);
  }
  return "unknown";
}

double LossWeight(const RobustLoss& loss, double sigmas) {
  const double a = loss.scale_sigmas, r = std::abs(sigmas);
  switch (loss.kind) {
    case LossKind::kNone: return 1.0;
    case LossKind::kHuber: return r <= a ? 1.0 : a / r;  // Ceres' HuberLoss: rho'(s) for s = r^2
    case LossKind::kCauchy: return 1.0 / (1.0 + (r / a) * (r / a));
  }
  return 1.0;
}

std::string MissingSensorsText(const std::vector<std::string>& missing_sensors) {
  std::string text;
  for (const std::string& sensor : missing_sensors) {
    std::string column;
    for (const SensorUnit& u : kPlanarSensors) {
      if (sensor == u.name) column = u.column;
    }
    text += (text.empty() ? "no '" : " and no '") + column + "' column (" + sensor + ")";
  }
  return text;
}

double EquilibriumSigma(const Robot& robot) { return robot.com_sigma_m.value_or(kDefaultComSigma_m); }

const char* ToString(Estimator e) { return e == Estimator::kPaper ? "paper" : "ml"; }
const char* ToString(Gauge g) {
  switch (g) {
    case Gauge::kA1x: return "a1x";
    case Gauge::kPrior: return "prior";
    case Gauge::kNone: return "none";
  }
  return "unknown";
}
const char* ToString(IdentifyStatus s) {
  switch (s) {
    case IdentifyStatus::kConverged: return "converged";
    case IdentifyStatus::kNotConverged: return "not_converged";
    case IdentifyStatus::kRankDeficient: return "rank_deficient";
    case IdentifyStatus::kPoorFit: return "poor_fit";
  }
  return "unknown";
}

namespace internal {

std::string FormatCoefficient(double c) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.4g", c);
  return buffer;
}

// The identification for M cables and its per-pose start: identify_cables.h, instantiated
// for each M in its own translation unit (generated from identify_cables.cc.in).
template <int M>
IdentifyResult IdentifyWithCables(const Robot& nominal, const std::vector<Measurement>& measurements,
                                  const IdentifyOptions& options);
template <int M>
PlanarPose StartingPose(const Robot& robot, const GeometryVector& g, const Measurement& m);

}  // namespace internal

IdentifyResult Identify(const Robot& nominal, const std::vector<Measurement>& measurements,
                        const IdentifyOptions& options) {
  if (options.readings_as_read) {
    IdentifyOptions corrected_options = options;
    corrected_options.readings_as_read = false;
    IdentifyResult result = Identify(nominal, CorrectedReadings(nominal, measurements, options.source), corrected_options);
    if (nominal.sensors.systematic.any()) result.corrected_for = nominal.sensors.systematic;
    return result;
  }
  IdentifyResult result = WithCableCount(nominal.num_cables(), [&](auto m) {
    return internal::IdentifyWithCables<decltype(m)::value>(nominal, measurements, options);
  });
  result.robot_name = nominal.name;  // so that the result is never combined with another robot's file
  return result;
}

PlanarPose StartingPose(const Robot& robot, const GeometryVector& geometry, const Measurement& reading) {
  CABLECAL_CHECK(reading.dl_m.size() == robot.num_cables() && geometry.size() == GeometrySize(robot.num_cables()),
                 "one encoder reading and three geometry entries per cable");
  return WithCableCount(robot.num_cables(), [&](auto m) {
    return internal::StartingPose<decltype(m)::value>(robot, geometry, reading);
  });
}

void RequireResultOfRobot(const std::string& result_source, const std::string& result_robot_name,
                          int result_cables, const Robot& robot) {
  RequireResultOfRobot(result_source, result_robot_name, result_cables, robot.source, robot.name, robot.num_cables());
}

void RequireResultOfRobot(const std::string& result_source, const std::string& result_robot_name,
                          int result_cables, const std::string& robot_source, const std::string& robot_name,
                          int robot_cables) {
  const std::string result_robot = result_robot_name.empty() ? "a robot" : "robot '" + PrintableText(result_robot_name) + "'";
  const std::string against = PrintableText(robot_source) + " is robot '" + PrintableText(robot_name) + "' with " +
                              std::to_string(robot_cables) + " cables";
  if (result_cables != robot_cables) {
    throw InputError(result_source, "", "identified for " + result_robot + " with " + std::to_string(result_cables) +
                                            " cables, but " + against + ": a result of another robot");
  }
  if (!result_robot_name.empty() && result_robot_name != robot_name) {
    throw InputError(result_source, "", "identified for " + result_robot + ", but " + against +
                                            ": a result of another robot (its changes from nominal would be the "
                                            "difference between two robots)");
  }
}

void RequireUsableResult(const IdentifyResult& result, const std::string& source) {
  if (result.status == IdentifyStatus::kRankDeficient || result.status == IdentifyStatus::kPoorFit) {
    throw InputError(source, "", result.message);
  }
  if (!result.converged()) throw SolverFailure(source + ": " + result.message);
}

}  // namespace cablecal
