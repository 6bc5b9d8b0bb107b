// Internal to identify/: what the identification says of its estimate, in words a lab can act
// on. A fit that did not converge (NotConverged), one whose residuals are far above the
// sensors' noise (FitsTheNoise), readings that do not fit the others (RefuseOutliers), an
// estimate no real robot of this file can have (Plausible), and the warnings of copied
// readings, residuals far below the noise and a robust estimate that strays. Depends on
// problem.h and diagnostics.h (the poses they name).
#pragma once

#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "identify/diagnostics.h"

namespace cablecal::internal {

// The result of a least-squares or robust fit that did not converge; `why` is
// DiagnoseLostFit's text.
template <int M>
IdentifyResult NotConverged(const IdentificationProblem<M>& p, const LeastSquaresSummary& sum, const std::string& why,
                            IdentifyResult result) {
  result.status = IdentifyStatus::kNotConverged;
  result.iterations = sum.iterations;
  const bool at_limit = sum.iterations >= p.options.max_iterations;
  result.message = "Levenberg-Marquardt did not converge after " + std::to_string(result.iterations) +
                   (result.iterations == 1 ? " iteration: " : " iterations: ") + sum.message +
                   (!why.empty() ? why
                    : at_limit   ? " (a grossly wrong reading can do this, and so can readings of another robot with "
                                   "as many cables: check the readings and the robot file, or raise --max-iterations)"
                                 : " (a grossly wrong reading can do this, and so can readings of another robot with "
                                   "as many cables: check the readings and the robot file)");
  if (p.robust) result.message += " (the robust fit starts from least squares' fit, or from the fit without the pose named)";
  return result;
}

// Under gauge prior, a tracker prior that disagrees with the readings (exit points further
// from nominal than sensors.tracker.sigma allows) strains every pose alike and shows as
// readings that do not fit: say that it may be the prior.
template <int M>
std::string PriorNote(const IdentificationProblem<M>& p) {
  if (p.options.gauge == Gauge::kPrior) {
    return " (with --gauge prior this is also what a tracker prior that disagrees with the readings looks like: "
           "are the exit points within a few sensors.tracker.sigma of the robot file's?)";
  }
  if (p.geometry_prior) {
    return " (with --geometry-prior this is also what a nominal geometry further from the real one than the prior's "
           "sigma allows looks like: is " + FormatDouble(p.prior_sigma_m) + " m too small?)";
  }
  return "";
}

// Goodness of fit. With the right model the whitened residuals have RMS near 1 (ml), and
// the paper estimator's length residuals are of the order of the laser's noise, which
// z_j carries into them. Ten times that is not noise: the result is flagged (false), not
// returned. With a robust loss the readings beyond kOutlierSigmas are the outliers it is there
// for and the RMS is taken over the others.
template <int M>
bool FitsTheNoise(const IdentificationProblem<M>& p, const std::vector<Reading>& readings,
                  const std::optional<LeftOut<M>>& left_out, IdentifyResult& result) {
  constexpr double kPoorFitFactor = 10.0;
  double fit = result.rms_encoder_m / std::max(p.s.laser_sigma_m(), p.s.encoder_sigma_m);
  if (p.ml) {
    double sum = 0.0;
    int count = 0;
    for (const Reading& r : readings) {
      if (p.robust && !(r.sigmas <= kOutlierSigmas)) continue;
      sum += r.sigmas * r.sigmas;
      ++count;
    }
    fit = count > 0 ? std::sqrt(sum / count) : std::numeric_limits<double>::infinity();
  }
  if (fit <= kPoorFitFactor) return true;
  result.status = IdentifyStatus::kPoorFit;
  char buffer[160];
  std::snprintf(buffer, sizeof(buffer),
                "the residuals are %.3g times the sensors' noise (more than %g): the measurements do not fit "
                "this robot", fit, kPoorFitFactor);
  // The likely causes a new user hit: dl columns in another order than the robot file's
  // cables ("14.3 times the noise"), readings of another robot with as many cables, units.
  result.message = std::string(buffer) + " (are dl1.." + "dl" + std::to_string(M) +
                   " in the order of the robot file's cables, the readings of this robot, in m and rad?)";
  if (!p.robust && left_out) {
    result.message += "; " + ExplainLeftOut(p, *left_out) + "; " + "drop " +
                      (left_out->poses.size() == 1 ? "that pose" : "those poses") + " or identify with --loss cauchy";
  }
  result.message += PriorNote(p);
  return false;
}

// Per reading: one bad reading among many hardly moves the global RMS, yet drags the
// estimate by many sigma. Every whitened residual beyond kOutlierSigmas refuses the fit,
// naming the poses left out (LeaveOut) or else the worst readings. For clean data a whitened
// residual is at most N(0, 1) (less, by its leverage), so 200 readings (n = 50) trip 4.5
// sigma with probability 200 * 6.8e-6 = 0.14 % (measured for 2 cables: 0 of 6000 ml trials,
// 8 of 2000 paper trials at n = 6 and 28). With the ml estimator and 2 cables a pose has 4
// readings for its 3 unknowns: one bad reading shows in that pose's residuals along their
// one redundant direction, so the pose is named reliably but the sensor named may be another
// of the same pose (more cables give more redundant directions).
template <int M>
void RefuseOutliers(const IdentificationProblem<M>& p, const std::string& advice_without_note,
                    const std::optional<LeftOut<M>>& left_out, const std::vector<Reading>& tripped,
                    const PoseChecks& checks, IdentifyResult& result) {
  const std::string advice = advice_without_note + PriorNote(p);
  result.status = IdentifyStatus::kPoorFit;
  if (left_out && !p.robust) {
    result.message = "readings that do not fit this robot: " + ExplainLeftOut(p, *left_out) + "; " + advice;
    return;
  }
  if (tripped.empty() && checks.flagged_pose >= 0) {
    char buffer[160];
    std::snprintf(buffer, sizeof(buffer), "pose %d does not fit the others (%.3g sigma against their fit; ",
                  p.pose_id_of(checks.flagged_pose), checks.checks[checks.flagged_pose].deleted_residual_sigmas);
    result.message = "readings that do not fit this robot: " + std::string(buffer) +
                     "the fit absorbed it, leaving every residual small); " + advice;
    return;
  }
  std::string worst;
  for (std::size_t k = 0; k < std::min<std::size_t>(3, tripped.size()); ++k) {
    worst += (k ? ", " : "") + p.Describe(tripped[k]);
  }
  char buffer[128];
  std::snprintf(buffer, sizeof(buffer), " (%zu reading%s beyond %g sigma)", tripped.size(),
                tripped.size() == 1 ? "" : "s", kOutlierSigmas);
  result.message = "readings that do not fit this robot: " + worst + buffer + "; " + advice;
}

// An estimate no real robot of this file can have: an exit point off the frame (by more than
// the robot file's own tolerance, kExitOffFrameTolerance_m) or any parameter more than
// kImplausibleChange_m from nominal. Measurements in other units, or of another robot,
// converge there. False (status and message set) for such an estimate.
constexpr double kImplausibleChange_m = 0.5;
template <int M>
bool Plausible(const IdentificationProblem<M>& p, IdentifyResult& result) {
  constexpr GeometryLayout kLayout = IdentificationProblem<M>::kLayout;
  for (int k = 0; k < kLayout.size(); ++k) {
    const double change = result.geometry(k) - p.nominal_geometry(k);
    std::string why;
    if (kLayout.is_exit(k)) {
      const double v = result.geometry(k);
      const double hi = kLayout.axis_of(k) == 0 ? p.nominal.frame_width_m : p.nominal.frame_height_m;
      if (v < -kExitOffFrameTolerance_m || v > hi + kExitOffFrameTolerance_m) why = "outside the frame";
    }
    if (why.empty() && std::abs(change) > kImplausibleChange_m) {
      why = "more than " + FormatDouble(kImplausibleChange_m) + " m from nominal";
    }
    if (!why.empty()) {
      result.status = IdentifyStatus::kPoorFit;
      result.message = "the identified " + p.geometry_names[k] + " = " + FormatDouble(result.geometry(k)) + " m is " +
                       why + " (nominal " + FormatDouble(p.nominal_geometry(k)) +
                       " m): are the readings in the file's units (m, rad), and of this robot? A single wrong reading "
                       "can do this too (the fit absorbs it: one inclinometer angle of 0 among 20 poses does), so "
                       "check for one; and few or bunched poses may not determine the geometry (plan them with "
                       "cablecal design)";
      return false;
    }
  }
  return true;
}

// The verdict on readings beyond kOutlierSigmas (`tripped`) or a pose that does not fit the
// others, and on the estimate's plausibility: false (status and message set) if the result is
// refused. With a robust loss a few such readings are what it down-weights (listed in
// result.down_weighted); many point to wrong units or another robot, which no loss mends.
// Without one, a few bad readings are named before the plausibility check: they explain an
// implausible estimate better than wrong units do (one inclinometer reading of 0 among 20
// poses drags a2x off the frame).
template <int M>
bool Accepted(const IdentificationProblem<M>& p, const std::vector<Reading>& tripped, const PoseChecks& checks,
              const std::optional<LeftOut<M>>& left_out, IdentifyResult& result) {
  const std::size_t few =
      std::max<std::size_t>(kFewOutliers, static_cast<std::size_t>(p.values_per_reading) * p.num_readings / 20);
  const std::string drop_or_loss = std::string("check those readings, drop ") +
                                   (left_out && left_out->poses.size() == 1 ? "that pose" : "their poses") +
                                   ", or identify with --loss cauchy, which down-weights them";
  const bool outliers = !tripped.empty() || checks.flagged_pose >= 0;
  if (p.robust) {
    if (tripped.size() > few) {
      RefuseOutliers(p,
                     "too many for a robust loss to be trusted: are the readings in the file's units (m, rad), and "
                     "of this robot?",
                     left_out, tripped, checks, result);
      return false;
    }
    for (const Reading& r : tripped) {
      char buffer[48];
      std::snprintf(buffer, sizeof(buffer), " (weight %.2g)", LossWeight(p.options.loss, r.sigmas));
      result.down_weighted.push_back(p.Describe(r) + buffer);
    }
  } else if (outliers && (tripped.size() <= few || left_out)) {
    RefuseOutliers(p, drop_or_loss, left_out, tripped, checks, result);
    return false;
  }
  if (p.options.check_plausible_geometry && !Plausible(p, result)) return false;
  if (!p.robust && outliers) {
    RefuseOutliers(p, drop_or_loss, left_out, tripped, checks, result);
    return false;
  }
  return true;
}

// Readings identical in every value to another pose's (IdentificationProblem::copied).
template <int M>
void WarnOfCopiedReadings(const IdentificationProblem<M>& p, IdentifyResult& result) {
  if (p.copied_count == 0) return;
  std::string list;
  for (std::size_t k = 0; k < p.copied.size(); ++k) list += (k ? ", " : "") + p.copied[k];
  if (p.copied_count > static_cast<int>(p.copied.size())) list += ", ...";
  result.warnings.push_back(std::to_string(p.copied_count) + (p.copied_count == 1 ? " reading is" : " readings are") +
                            " identical in every value to another pose's (" + list +
                            "): copied rows? Real readings of two poses always differ by their noise; a copy "
                            "counts one pose twice and makes the standard deviations too small. If it is the "
                            "same pose read again, give it the same pose id");
}

// Residuals far below the sensors' noise are as suspect as residuals far above it: copied
// readings, data simulated without noise, or sigmas in the robot file far larger than the
// sensors' (then every standard deviation is too large). With the right sigmas the sum of
// squared whitened residuals is about chi-square with `dof` degrees of freedom; a mean square
// below its 5-sigma lower bound (Wilson-Hilferty: ((1 - 2/9k) - 5 sqrt(2/9k))^3) happens in
// fewer than one clean experiment in a million. ml least squares only.
template <int M>
void WarnOfResidualsBelowTheNoise(const IdentificationProblem<M>& p, const std::vector<Reading>& readings,
                                  IdentifyResult& result) {
  if (!p.ml || p.robust) return;
  const int dof = p.equations - p.prior_equations - p.unknowns;
  const double h = 2.0 / (9.0 * dof);
  const double lower = std::pow(std::max(0.0, 1.0 - h - 5.0 * std::sqrt(h)), 3);
  double sum = 0.0;
  for (const Reading& r : readings) sum += r.sigmas * r.sigmas;
  if (dof >= 10 && sum / dof < lower) {
    char buffer[256];
    std::snprintf(buffer, sizeof(buffer),
                  "the residuals are far below the sensors' noise: their RMS is %.3g of the robot file's sigmas, "
                  "where clean readings give about 1 (and below %.3g in fewer than one experiment in a million)",
                  std::sqrt(sum / dof), std::sqrt(lower));
    result.warnings.push_back(std::string(buffer) +
                              ": readings copied from other poses, simulated without noise, or sensor sigmas far "
                              "larger than the sensors' (the standard deviations are then too large)");
  }
}

// Huber's loss never ignores a reading: at a pose of high leverage it can pull the estimate
// back toward least squares' (measured on the built-in robot with a 0.3 m laser error). Say
// so when its estimate strays from the fit without the poses the leave-out test named,
// naming the parameter furthest from that fit, in its sigmas.
template <int M>
void WarnOfRobustStray(const IdentificationProblem<M>& p, const LeftOut<M>& left_out, IdentifyResult& result) {
  const Apart stray =
      FurthestApart(result.geometry.data(), left_out.geometry_values, result.geometry_std, kRobustStraySigmas);
  if (stray.k < 0) return;
  const int worst = stray.k;
  char buffer[96];
  std::snprintf(buffer, sizeof(buffer), "%.3g mm (%.3g sigma)",
                1e3 * std::abs(result.geometry(worst) - left_out.geometry_values[worst]), stray.sigmas);
  result.warnings.push_back("the " + ToString(p.options.loss) + " estimate of " + p.geometry_names[worst] + " is " +
                            buffer + " from the fit without pose " + LeftOutIds(p, left_out) +
                            " (readings that do not fit the others): " +
                            (p.options.loss.kind == LossKind::kHuber
                                 ? "Huber's loss never ignores a reading and follows them; --loss cauchy rejects them"
                                 : "a smaller scale rejects them sooner"));
}

}  // namespace cablecal::internal
