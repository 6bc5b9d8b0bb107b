#include "identify/identify.h"

#include <cstdio>
#include <string>
#include <vector>

#include "common/error.h"

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

// The identification for M cables: identify_cables.h, instantiated for each M in its own
// translation unit (generated from identify_cables.cc.in).
template <int M>
IdentifyResult IdentifyWithCables(const Robot& nominal, const std::vector<Measurement>& measurements,
                                  const IdentifyOptions& options);

}  // namespace internal

IdentifyResult Identify(const Robot& nominal, const std::vector<Measurement>& measurements,
                        const IdentifyOptions& options) {
  static_assert(kMinCables == 2 && kMaxCables == 8, "one instantiation per cable count below");
  switch (nominal.num_cables()) {
    case 2: return internal::IdentifyWithCables<2>(nominal, measurements, options);
    case 3: return internal::IdentifyWithCables<3>(nominal, measurements, options);
    case 4: return internal::IdentifyWithCables<4>(nominal, measurements, options);
    case 5: return internal::IdentifyWithCables<5>(nominal, measurements, options);
    case 6: return internal::IdentifyWithCables<6>(nominal, measurements, options);
    case 7: return internal::IdentifyWithCables<7>(nominal, measurements, options);
    case 8: return internal::IdentifyWithCables<8>(nominal, measurements, options);
  }
  CABLECAL_CHECK(false, "the robot loader keeps 2 to 8 cables");
  return {};
}

void RequireUsableResult(const IdentifyResult& result, const std::string& source) {
  if (result.status == IdentifyStatus::kRankDeficient || result.status == IdentifyStatus::kPoorFit) {
    throw InputError(source, "", result.message);
  }
  if (!result.converged()) throw SolverFailure(source + ": " + result.message);
}

}  // namespace cablecal
