// result.yaml of `cablecal identify`.
#include <cmath>
#include <sstream>

#include "common/format.h"
#include "common/version.h"
#include "identify/identify.h"

namespace cablecal {
namespace {

std::string Num(double v) {
  if (std::isinf(v)) return v > 0 ? ".inf" : "-.inf";
  if (std::isnan(v)) return ".nan";
  return FormatDouble(v);
}


}  // namespace

std::string IdentifyResultYaml(const IdentifyResult& r, const std::string& command_line) {
  std::ostringstream o;
  o << "# cablecal identification result (README, \"identify\"). SI units: m, rad.\n";
  o << "cablecal: {version: " << Version() << ", commit: " << GitCommit() << "}\n";
  o << "command: " << YamlQuoted(command_line) << "\n";
  o << "status: " << ToString(r.status) << "\n";
  if (!r.message.empty()) o << "message: " << YamlQuoted(r.message) << "\n";
  o << "estimator: " << ToString(r.estimator) << "\n";
  o << "gauge: " << ToString(r.gauge) << "\n";
  switch (r.gauge) {
    case Gauge::kA1x:
      o << "gauge_note: \"a1x held at its nominal value: the frame's x origin is defined by exit point 1\"\n";
      break;
    case Gauge::kPrior:
      o << "gauge_note: \"laser-tracker prior on every exit point (sensors.tracker.sigma)\"\n";
      break;
    case Gauge::kNone:
      o << "gauge_note: \"no gauge (the paper's problem): a common shift of every a_ix and x_j is unobservable; "
           "standard deviations are from the pseudo-inverse and exclude that direction\"\n";
      break;
  }
  o << "iterations: " << r.iterations << "\n";
  o << "final_cost: " << Num(r.final_cost) << "   # half the sum of squared (whitened, for ml) residuals\n";
  o << "residual_rms: {encoder_m: " << Num(r.rms_encoder_m) << ", laser_m: " << Num(r.rms_laser_m)
    << ", inclinometer_rad: " << Num(r.rms_inclinometer_rad) << "}\n";
  if (r.estimator == Estimator::kPaper) {
    o << "std_note: \"paper estimator: covariance scaled by the residual variance\"\n";
  }
  o << "parameters:\n";
  for (int k = 0; k < 6; ++k) {
    o << "  " << kGeometryNames[k] << ": {value: " << Num(r.geometry(k));
    if (r.has_covariance) o << ", std: " << Num(r.geometry_std(k));
    if (k == 0 && r.gauge == Gauge::kA1x) o << ", held: true";
    o << "}\n";
  }
  if (r.has_covariance) {
    o << "correlation:   # geometric parameters, in the order above\n";
    for (int a = 0; a < 6; ++a) {
      o << "  - [";
      for (int b = 0; b < 6; ++b) o << (b ? ", " : "") << Num(r.geometry_correlation(a, b));
      o << "]\n";
    }
  }
  o << "poses:\n";
  const bool ml = r.estimator == Estimator::kMaximumLikelihood;
  for (const PoseEstimate& p : r.poses) {
    o << "  - {pose: " << p.pose_id << ", x: " << Num(p.q(0));
    if (r.has_covariance) o << ", x_std: " << Num(p.std_dev(0));
    o << ", z: " << Num(p.q(1));
    if (r.has_covariance && ml) o << ", z_std: " << Num(p.std_dev(1));
    o << ", theta: " << Num(p.q(2));
    if (r.has_covariance && ml) o << ", theta_std: " << Num(p.std_dev(2));
    o << "}\n";
  }
  const Identifiability& id = r.identifiability;
  if (!id.names.empty()) {
    o << "identifiability:   # the " << (ml ? "whitened " : "")
      << "Jacobian at the solution, every pose's own unknowns eliminated (README, \"identify\")\n";
    o << "  columns: [";
    for (std::size_t k = 0; k < id.geometry_names.size(); ++k) o << (k ? ", " : "") << id.geometry_names[k];
    o << "]\n  singular_values: [";
    for (int k = 0; k < id.singular_values.size(); ++k) o << (k ? ", " : "") << Num(id.singular_values(k));
    o << "]\n  condition_number: " << Num(id.condition_number) << "\n";
    o << "  weakest_pose: {pose: " << id.weakest_pose_id
      << ", singular_value: " << Num(id.weakest_pose_singular_value) << "}\n";
    o << "  null_directions:";
    if (id.null_directions.empty()) o << " []";
    o << "\n";
    for (const std::string& d : id.null_directions) o << "    - " << YamlQuoted(d) << "\n";
  }
  return o.str();
}

}  // namespace cablecal
