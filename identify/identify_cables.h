// Internal to identify/: the identification for a robot of M cables, written once on M so
// that the cost functors and their Jets have compile-time sizes (residuals M + 2 or M,
// geometry 3M). Identify (identify.cc) dispatches on the robot's cable count; each M is
// instantiated in a translation unit of its own (identify/CMakeLists.txt generates them from
// identify_cables.cc.in), so that the compiler inlines the residuals' Jet arithmetic as it
// does for one M alone: all seven in one unit cost the 2-cable solve 6 % more instructions
// (GCC stops inlining as a unit grows).
//
// This file is the driver and each pose's start. Its parts: problem.h (the problem: readings,
// weights, solves, residuals, Jacobian blocks), diagnostics.h (readings that do not fit),
// verdicts.h (what is said of the estimate), uncertainty.h (identifiability, covariance).
#pragma once

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "common/error.h"
#include "common/format.h"
#include "identify/cost_functors.h"
#include "identify/diagnostics.h"
#include "identify/identify.h"
#include "identify/problem.h"
#include "identify/residuals.h"
#include "identify/uncertainty.h"
#include "identify/verdicts.h"
#include "model/statics.h"

namespace cablecal::internal {


// Starting x for one pose: where the nominal model best explains the measured lengths at
// the measured z and theta (README, "Identification": starting every x_j at home sends LM to wrong minima).
// Start from the mean over the cables of each one's straight-cable estimate (the anchor on its
// pulley's inner side, by the side sign), then Gauss-Newton in x on every cable's length
// residual. A cable from the middle of a beam may reach the platform from its other side,
// which puts that start off by up to twice the cable's horizontal run; Gauss-Newton recovers
// from it (measured on planar3 and 18 random robots with 3 to 8 cables: every one of 400
// identifications converged, in the same iterations as from the best single-cable estimate).
template <int M>
double StartingX(const Robot& nominal, const GeometryVector& g, const Measurement& m, double z_m, double theta_rad) {
  using Jet1 = ceres::Jet<double, 1>;
  constexpr GeometryLayout kLayout = PlanarLayout(M);
  const Eigen::Matrix2d R = Rotation(theta_rad);
  double sum = 0.0;
  int count = 0;
  for (int i = 0; i < M; ++i) {
    const Cable& c = nominal.cables[i];
    const Eigen::Vector2d r_anchor = R * c.p_P_anchor_m;
    const double length = g(kLayout.initial_length(i)) + m.dl_m(i);
    const double dz = g(kLayout.exit(i, 1)) - (z_m + r_anchor.y());
    const double horizontal2 = length * length - dz * dz;
    if (horizontal2 <= 0.0) continue;
    sum += g(kLayout.exit(i, 0)) + SideSign(c.side) * std::sqrt(horizontal2) - r_anchor.x();
    ++count;
  }
  double x = count > 0 ? sum / count : nominal.p_F_home_m.x();
  Jet1 geometry[kLayout.size()];
  for (int k = 0; k < kLayout.size(); ++k) geometry[k] = Jet1(g(k));
  const PoseReadings<M> readings = ReadingsOf<M>(m);
  for (int it = 0; it < 6; ++it) {
    Jet1 r[M];
    LengthResiduals<M, Jet1>(nominal, geometry, Pose<Jet1>(Jet1(x, 0), Jet1(z_m), Jet1(theta_rad)),
                             readings.dl_m.data(), r);
    double num = 0.0, den = 0.0;
    for (int i = 0; i < M; ++i) {
      num += r[i].v(0) * r[i].a;
      den += r[i].v(0) * r[i].v(0);
    }
    if (!(den > 0.0) || !std::isfinite(num)) break;
    const double step = num / den;
    x -= step;
    if (std::abs(step) < 1e-9) break;  // a start, not the estimate: LM refines it
  }
  return std::isfinite(x) ? x : nominal.p_F_home_m.x();
}

// Starting pose for one reading (identify's x_j, z_j, theta_j; validate's forward model): the
// measured z and theta (each sensor's pose coordinate) with StartingX's x. A coordinate no
// sensor read starts at the pose these lengths give the rigid-cable model (LeastSquaresPoseGuess
// from cold; home, level, if it finds nothing).
template <int M>
PlanarPose StartingPose(const Robot& robot, const GeometryVector& g, const Measurement& m) {
  PlanarPose q = PlanarPose::Zero();
  bool every_sensor = true;
  for (const SensorUnit& u : kPlanarSensors) every_sensor = every_sensor && m.has(u.id);
  if (!every_sensor) {
    const Eigen::VectorXd lengths = g.tail<M>() + m.dl_m;
    const ForwardResult fwd = LeastSquaresPoseGuess(robot, lengths);
    q = fwd.status == ForwardStatus::kConverged ? fwd.equilibrium.q
                                                : PlanarPose(robot.p_F_home_m.x(), robot.p_F_home_m.y(), 0.0);
  }
  for (const SensorUnit& u : kPlanarSensors) {
    if (m.has(u.id)) q(u.pose_coordinate) = m.value(u.id);
  }
  q(0) = StartingX<M>(robot, g, m, q(1), q(2));
  return q;
}

// The result before any solve: what was asked, and no uncertainty yet.
template <int M>
IdentifyResult EmptyResult(const IdentificationProblem<M>& p) {
  IdentifyResult result;
  result.estimator = p.options.estimator;
  result.gauge = p.options.gauge;
  result.held_geometry = p.held;
  result.loss = p.options.loss;
  result.missing_sensors = p.missing_sensors;
  if (p.equilibrium_rows > 0) result.equilibrium_com_sigma_m = EquilibriumSigma(p.nominal);
  result.geometry_std = GeometryVector::Zero(p.kGeometry);
  result.geometry_correlation = Eigen::MatrixXd::Identity(p.kGeometry, p.kGeometry);
  result.geometry_prior_sigma_m = p.prior_sigma_m;
  return result;
}

// The identification: least squares; the readings that do not fit found (diagnostics.h);
// with a robust loss its fit, started from the fit without them; what is said of the
// estimate (verdicts.h); its uncertainty (uncertainty.h). The order of the verdicts is the
// order in which a lab should act on them.
template <int M>
IdentifyResult IdentifyWithCables(const Robot& nominal, const std::vector<Measurement>& measurements,
                                  const IdentifyOptions& options) {
  constexpr int kGeometry = IdentificationProblem<M>::kGeometry;
  const IdentificationProblem<M> p(nominal, measurements, options);
  IdentifyResult result = EmptyResult(p);
  double geometry[kGeometry];
  PoseValues poses;
  p.ResetToStart(geometry, poses);
  const std::vector<char> every_pose(p.n, 1);
  // Least squares first, also under a robust loss: its residuals say whether there is anything
  // to down-weight, and where to start.
  LeastSquaresSummary summary = p.LeastSquares(geometry, poses, every_pose, options.max_iterations);
  LostFitDiagnosis<M> lost;
  // Ceres' problem at the estimate, for the Jacobian blocks: built when first needed (the
  // Monte Carlo needs none); a robust fit's replaces it.
  std::unique_ptr<ceres::Problem> problem;
  const auto problem_at_estimate = [&]() -> ceres::Problem& {
    if (!problem) problem = p.Build(geometry, poses, every_pose, RobustLoss{});
    return *problem;
  };
  // Least squares lost: a robust loss can still start from the fit without the one pose whose
  // absence lets the rest converge and fit (a 0.3 m laser error at one of 19 poses of a new
  // user's robot: least squares needed 106 iterations, --loss cauchy exited 3 at the default
  // 100), or else from where least squares started.
  const bool least_squares_lost = !p.Converged(summary, geometry, poses, every_pose);
  if (least_squares_lost && !p.robust) return NotConverged(p, summary, DiagnoseLostFit(p, lost).text, result);
  if (least_squares_lost && !DiagnoseLostFit(p, lost).culprit) p.ResetToStart(geometry, poses);
  std::vector<Reading> readings = p.ResidualsAt(geometry, poses, every_pose, &result);
  std::vector<Reading> tripped = Beyond(readings);

  PoseChecks checks;
  if (p.ml && !p.held.empty() && (options.compute_covariance || p.robust) && !least_squares_lost) {
    checks = CheckPoses(p, problem_at_estimate(), geometry, poses);
  }
  std::optional<LeftOut<M>> left_out;
  if (least_squares_lost) {
    left_out = lost.culprit;
  } else if (!tripped.empty() || checks.flagged_pose >= 0) {
    left_out = LeaveOut(p, geometry, poses);
  }
  // The check against the others is linear: it divides the pose's residual by how much of it
  // the others see, and where they see little (few poses, centimetres of geometry error) the
  // fit's curvature alone can make a clean pose look far off (measured: a 2-cable robot's 5
  // clean poses, one at 98 sigma). A flag stands only if the refit without the pose confirms
  // it: some pose's readings are then beyond kOutlierSigmas against the others' geometry.
  if (tripped.empty() && checks.flagged_pose >= 0 && (!left_out || left_out->worst.empty())) checks.flagged_pose = -1;

  if (p.robust) {
    // Start the robust fit where it should end: from the fit without the culprits when least
    // squares found any (a redescending loss such as Cauchy's then stays there; Huber's, which
    // never ignores a reading, may move back toward least squares: warned below).
    if (left_out) {
      std::copy(left_out->geometry_values, left_out->geometry_values + kGeometry, geometry);
      poses = left_out->pose_values;
    }
    problem = p.Build(geometry, poses, every_pose, options.loss);
    summary = FromCeres(p.SolveWithCeres(*problem, geometry, poses, every_pose, false, options.max_iterations));
    if (!p.Converged(summary, geometry, poses, every_pose)) {
      return NotConverged(p, summary, DiagnoseLostFit(p, lost).text, result);
    }
    if (left_out && !left_out->worst.empty()) {
      if (std::optional<IdentifyResult> without = FitWithoutLeftOut(p, *left_out, geometry)) return *without;
    }
  }
  result.iterations = summary.iterations;
  result.final_cost = summary.final_cost;
  result.geometry = Eigen::Map<const GeometryVector>(geometry, kGeometry);
  result.status = IdentifyStatus::kConverged;
  if (p.robust) {
    readings = p.ResidualsAt(geometry, poses, every_pose, &result);
    tripped = Beyond(readings);
  }
  if (!FitsTheNoise(p, readings, left_out, result)) return result;

  if (!Accepted(p, tripped, checks, left_out, result)) return result;
  WarnOfCopiedReadings(p, result);
  WarnOfResidualsBelowTheNoise(p, readings, result);
  if (!options.compute_identifiability && !options.compute_covariance) return result;

  // Least squares' blocks are reused where no robust fit followed (the same problem at the
  // same values). A null direction: singular value below 1e-9 of the largest (rounding, not data).
  const bool reuse = !p.robust && checks.blocks.has_value();
  const BlockJacobian blocks =
      reuse ? std::move(*checks.blocks) : p.JacobianBlocks(problem_at_estimate(), geometry, poses, p.robust, nullptr);
  const BlockAnalysis analysis = reuse ? std::move(*checks.analysis) : AnalyzeBlocks(blocks, 1e-9);
  // Gauge none: the directions the default gauge would hold are expected null.
  const int expected_null =
      options.gauge == Gauge::kNone ? static_cast<int>(PlanarKind::HeldByDefault(p.kLayout).size()) : 0;
  if (options.compute_identifiability && !AddIdentifiability(p, analysis, expected_null, result)) return result;
  if (options.compute_covariance && static_cast<int>(analysis.null_vectors.size()) == expected_null) {
    AddCovariance(p, blocks, analysis, expected_null, geometry, poses, summary.final_cost, result);
  }
  // How well the others check each reading (least squares only: the checks are of its fit).
  if (!p.robust && !checks.checks.empty() && !result.readings.empty()) {
    for (int j = 0; j < p.n; ++j) {
      for (std::size_t c = 0; c < p.readings_of[j].size(); ++c) {
        result.readings[p.readings_of[j][c]].min_detectable_sigmas =
            checks.checks[j].min_detectable_sigmas.segment(static_cast<Eigen::Index>(c) * (M + kNumPlanarSensors),
                                                            M + kNumPlanarSensors);
      }
    }
  }
  if (p.robust && left_out && result.has_covariance) WarnOfRobustStray(p, *left_out, result);
  return result;
}

}  // namespace cablecal::internal
