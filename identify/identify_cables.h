// Internal to identify/: the identification for a robot of M cables, written once on M so
// that the cost functors and their Jets have compile-time sizes (residuals M + 2 or M,
// geometry 3M). Identify (identify.cc) dispatches on the robot's cable count; each M is
// instantiated in a translation unit of its own (identify/CMakeLists.txt generates them from
// identify_cables.cc.in), so that the compiler inlines the residuals' Jet arithmetic as it
// does for one M alone: all seven in one unit cost the 2-cable solve 6 % more instructions
// (GCC stops inlining as a unit grows).
#pragma once

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "common/error.h"
#include "common/format.h"
#include "identify/cost_functors.h"
#include "identify/identify.h"
#include "identify/residuals.h"
#include "identify/schur.h"
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
double StartingX(const Robot& nominal, const GeometryVector& g, const Measurement& m) {
  using Jet1 = ceres::Jet<double, 1>;
  const Eigen::Matrix2d R = Rotation(m.theta_rad);
  double sum = 0.0;
  int count = 0;
  for (int i = 0; i < M; ++i) {
    const Cable& c = nominal.cables[i];
    const Eigen::Vector2d r_anchor = R * c.p_P_anchor_m;
    const double length = g(2 * M + i) + m.dl_m(i);
    const double dz = g(2 * i + 1) - (m.z_m + r_anchor.y());
    const double horizontal2 = length * length - dz * dz;
    if (horizontal2 <= 0.0) continue;
    sum += g(2 * i) + SideSign(c.side) * std::sqrt(horizontal2) - r_anchor.x();
    ++count;
  }
  double x = count > 0 ? sum / count : nominal.p_F_home_m.x();
  Jet1 geometry[3 * M];
  for (int k = 0; k < 3 * M; ++k) geometry[k] = Jet1(g(k));
  const PoseReadings<M> readings = ReadingsOf<M>(m);
  for (int it = 0; it < 6; ++it) {
    Jet1 r[M];
    LengthResiduals<M, Jet1>(nominal, geometry, Pose<Jet1>(Jet1(x, 0), Jet1(m.z_m), Jet1(m.theta_rad)),
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

// "%.4g" of a null direction's coefficient (identify.cc).
std::string FormatCoefficient(double c);

// The whole identification for a robot of M cables: the cost functors and their Jets have
// compile-time sizes (residuals M + 2 or M, geometry 3M), dispatched once per call below.
template <int M>
IdentifyResult IdentifyWithCables(const Robot& nominal, const std::vector<Measurement>& measurements,
                                  const IdentifyOptions& options) {
  constexpr int kGeometry = 3 * M;
  const bool ml = options.estimator == Estimator::kMaximumLikelihood;
  const int n = static_cast<int>(measurements.size());

  // Enough equations for the unknowns (paper, Eq. 7; the gauge removes one unknown): per
  // pose M + 2 readings (ml) or M (paper), 3 or 1 pose unknowns; 3M geometric unknowns, 3M - 1
  // with a1x held; the prior adds 2M equations.
  const int per_pose_unknowns = ml ? 3 : 1;
  const int rows_per_pose = ml ? M + 2 : M;
  const int prior_rows = options.gauge == Gauge::kPrior ? 2 * M : 0;
  const int geometry_cols = options.gauge == Gauge::kA1x ? kGeometry - 1 : kGeometry;
  const int equations = rows_per_pose * n + prior_rows;
  const int unknowns = geometry_cols + per_pose_unknowns * n;
  if (equations < unknowns) {
    int needed = n;
    while (rows_per_pose * needed + prior_rows < geometry_cols + per_pose_unknowns * needed) ++needed;
    throw InputError(options.source, "",
                     std::to_string(n) + " poses give " + std::to_string(equations) + " equations for " +
                         std::to_string(unknowns) + " unknowns (estimator " + ToString(options.estimator) +
                         ", gauge " + ToString(options.gauge) + "): at least " + std::to_string(needed) +
                         " poses are needed");
  }
  const SensorNoise& s = nominal.sensors;
  if (ml) {
    if (!(s.encoder_sigma_m > 0.0)) {
      throw InputError(nominal.source, "sensors.encoder.sigma", "must be > 0 for the ml estimator");
    }
    if (!(s.laser_sigma_m() > 0.0)) {
      throw InputError(nominal.source, "sensors.laser", "accuracy or repeatability must be > 0 for the ml estimator");
    }
    if (!(s.inclinometer_sigma_rad() > 0.0)) {
      throw InputError(nominal.source, "sensors.inclinometer",
                       "accuracy or repeatability must be > 0 for the ml estimator");
    }
  }
  if (options.gauge == Gauge::kPrior && !s.tracker_sigma_m) {
    throw InputError(nominal.source, "sensors.tracker.sigma", "is needed for --gauge prior");
  }

  IdentifyResult result;
  result.estimator = options.estimator;
  result.gauge = options.gauge;
  result.geometry_std = GeometryVector::Zero(kGeometry);
  result.geometry_correlation = Eigen::MatrixXd::Identity(kGeometry, kGeometry);

  const GeometryVector nominal_geometry = GeometryOf(nominal);
  const std::vector<std::string> geometry_names = GeometryNames(M);
  double geometry[kGeometry];
  for (int k = 0; k < kGeometry; ++k) geometry[k] = nominal_geometry(k);
  std::vector<std::array<double, 3>> poses(n);
  for (int j = 0; j < n; ++j) {
    poses[j] = {internal::StartingX<M>(nominal, nominal_geometry, measurements[j]), measurements[j].z_m,
                measurements[j].theta_rad};
  }

  ceres::Problem problem;
  problem.AddParameterBlock(geometry, kGeometry);
  if (options.gauge == Gauge::kA1x) problem.SetManifold(geometry, new ceres::SubsetManifold(kGeometry, {0}));
  const ReadingWeights weights = ml ? WeightsOf(s) : ReadingWeights{};
  for (int j = 0; j < n; ++j) {
    const PoseReadings<M> readings = internal::ReadingsOf<M>(measurements[j]);
    if (ml) {
      auto* lengths = new ceres::AutoDiffCostFunction<internal::MlLengthCost<M>, M, kGeometry, 3>(
          new internal::MlLengthCost<M>{&nominal, readings, weights});
      problem.AddResidualBlock(lengths, nullptr, geometry, poses[j].data());
      auto* sensors = new ceres::AutoDiffCostFunction<internal::MlSensorCost<M>, 2, 3>(
          new internal::MlSensorCost<M>{readings, weights});
      problem.AddResidualBlock(sensors, nullptr, poses[j].data());
    } else {
      auto* cost = new ceres::AutoDiffCostFunction<internal::PaperPoseCost<M>, M, kGeometry, 1>(
          new internal::PaperPoseCost<M>{&nominal, readings});
      problem.AddResidualBlock(cost, nullptr, geometry, poses[j].data());
    }
  }
  if (options.gauge == Gauge::kPrior) {
    auto* prior = new ceres::AutoDiffCostFunction<internal::ExitPointPriorCost<M>, 2 * M, kGeometry>(
        new internal::ExitPointPriorCost<M>{nominal_geometry.head<2 * M>(), 1.0 / *s.tracker_sigma_m});
    problem.AddResidualBlock(prior, nullptr, geometry);
  }

  // Schur complement: eliminate the per-pose blocks first, leaving a 3M x 3M reduced system.
  auto* ordering = new ceres::ParameterBlockOrdering;
  for (int j = 0; j < n; ++j) ordering->AddElementToGroup(poses[j].data(), 0);
  ordering->AddElementToGroup(geometry, 1);
  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::DENSE_SCHUR;
  solver_options.linear_solver_ordering.reset(ordering);
  solver_options.minimizer_type = ceres::TRUST_REGION;
  solver_options.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  solver_options.max_num_iterations = options.max_iterations;
  // Relative cost change 1e-10 at the minimum means parameter steps of ~1e-4 sigma: far below
  // any uncertainty reported, and noise-free data are still recovered to 1e-7 m (tested).
  solver_options.function_tolerance = 1e-10;
  solver_options.gradient_tolerance = 1e-12;
  solver_options.parameter_tolerance = 1e-10;
  // The start is close (nominal geometry, per-pose x from the lengths), so start LM as
  // nearly Gauss-Newton; it still shrinks the region after a step that raises the cost.
  solver_options.initial_trust_region_radius = 1e8;
  solver_options.num_threads = 1;  // parallelism is over Monte Carlo trials, not inside one solve
  solver_options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(solver_options, &problem, &summary);

  result.iterations = static_cast<int>(summary.iterations.size()) - 1;
  result.final_cost = summary.final_cost;
  result.geometry = Eigen::Map<const GeometryVector>(geometry, kGeometry);
  bool finite = result.geometry.allFinite();
  for (const auto& p : poses) finite = finite && std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
  if (summary.termination_type != ceres::CONVERGENCE || !finite) {
    result.status = IdentifyStatus::kNotConverged;
    result.message = "Levenberg-Marquardt did not converge after " + std::to_string(result.iterations) +
                     " iterations: " + summary.message;
    return result;
  }
  result.status = IdentifyStatus::kConverged;

  // Per-pose estimates, residual RMS per sensor in physical units, and every reading's
  // whitened residual for the per-reading test below (ml: each reading over its sigma; paper:
  // each length residual over the laser's sigma, as the global test).
  struct Reading {
    double sigmas;
    int pose_id;
    int sensor;  // 0 .. M - 1: encoders; M: laser; M + 1: inclinometer
  };
  std::vector<Reading> readings;
  readings.reserve(rows_per_pose * n);
  const double length_sigma = ml ? s.encoder_sigma_m : std::max(s.laser_sigma_m(), s.encoder_sigma_m);
  double sum_enc = 0.0, sum_laser = 0.0, sum_inc = 0.0;
  for (int j = 0; j < n; ++j) {
    const Measurement& m = measurements[j];
    PoseEstimate e;
    e.pose_id = m.pose_id;
    e.q = ml ? Eigen::Vector3d(poses[j][0], poses[j][1], poses[j][2])
             : Eigen::Vector3d(poses[j][0], m.z_m, m.theta_rad);
    double length_residuals[M];
    LengthResiduals<M, double>(nominal, geometry, e.q, m.dl_m.data(), length_residuals);
    for (int i = 0; i < M; ++i) {
      const double r = length_residuals[i];
      sum_enc += r * r;
      readings.push_back({std::abs(r) / length_sigma, m.pose_id, i});
    }
    sum_laser += (e.q(1) - m.z_m) * (e.q(1) - m.z_m);
    sum_inc += (e.q(2) - m.theta_rad) * (e.q(2) - m.theta_rad);
    if (ml) {
      readings.push_back({std::abs(e.q(1) - m.z_m) / s.laser_sigma_m(), m.pose_id, M});
      readings.push_back({std::abs(e.q(2) - m.theta_rad) / s.inclinometer_sigma_rad(), m.pose_id, M + 1});
    }
    result.poses.push_back(e);
  }
  result.rms_encoder_m = std::sqrt(sum_enc / (static_cast<double>(M) * n));
  result.rms_laser_m = std::sqrt(sum_laser / n);
  result.rms_inclinometer_rad = std::sqrt(sum_inc / n);

  // Goodness of fit. With the right model the whitened residuals have RMS near 1 (ml), and
  // the paper estimator's length residuals are of the order of the laser's noise, which
  // z_j carries into them. Ten times that is not noise: the result is flagged, not returned.
  constexpr double kPoorFitFactor = 10.0;
  const double fit = ml ? std::sqrt(2.0 * summary.final_cost / summary.num_residuals)
                        : result.rms_encoder_m / std::max(s.laser_sigma_m(), s.encoder_sigma_m);
  if (!(fit <= kPoorFitFactor)) {
    result.status = IdentifyStatus::kPoorFit;
    char buffer[160];
    std::snprintf(buffer, sizeof(buffer),
                  "the residuals are %.3g times the sensors' noise (more than %g): the measurements do not fit "
                  "this robot", fit, kPoorFitFactor);
    result.message = buffer;
    return result;
  }

  // Per reading: one bad reading among many hardly moves the global RMS above, yet drags the
  // estimate by many sigma. Every whitened residual (collected above) beyond kOutlierSigmas
  // refuses the fit, naming the worst readings. For clean data a whitened residual is at most
  // N(0, 1) (less, by its leverage), so 200 readings (n = 50) trip 4.5 sigma with probability
  // 200 * 6.8e-6 = 0.14 % (measured for 2 cables: 0 of 6000 ml trials, 8 of 2000 paper trials
  // at n = 6 and 28). With the ml estimator and 2 cables a pose has 4 readings for its 3
  // unknowns: one bad reading shows in that pose's residuals along their one redundant
  // direction, so the pose is named reliably but the largest residual may sit on another
  // sensor of the same pose (more cables give more redundant directions).
  const std::size_t tripped = static_cast<std::size_t>(std::count_if(
      readings.begin(), readings.end(), [](const Reading& r) { return !(r.sigmas <= kOutlierSigmas); }));
  const auto refuse_outliers = [&] {
    const std::size_t worst_count = std::min<std::size_t>(3, readings.size());
    std::partial_sort(readings.begin(), readings.begin() + worst_count, readings.end(),
                      [](const Reading& a, const Reading& b) { return a.sigmas > b.sigmas; });
    const auto sensor_name = [](int sensor) {
      return sensor < M ? "encoder " + std::to_string(sensor + 1) : sensor == M ? "laser" : "inclinometer";
    };
    std::string worst;
    for (std::size_t k = 0; k < worst_count && !(readings[k].sigmas <= kOutlierSigmas); ++k) {
      char buffer[96];
      std::snprintf(buffer, sizeof(buffer), "%spose %d: %s %.3g sigma", k ? ", " : "", readings[k].pose_id,
                    sensor_name(readings[k].sensor).c_str(), readings[k].sigmas);
      worst += buffer;
    }
    result.status = IdentifyStatus::kPoorFit;
    char buffer[128];
    std::snprintf(buffer, sizeof(buffer), " (%zu reading%s beyond %g sigma)", tripped, tripped == 1 ? "" : "s",
                  kOutlierSigmas);
    result.message = "readings that do not fit this robot: " + worst + buffer +
                     "; check those readings or drop their poses";
  };
  // A few bad readings explain an implausible estimate better than wrong units do (one
  // inclinometer reading of 0 among 20 poses drags a2x off the frame): name them first.
  if (tripped > 0 && tripped <= std::max<std::size_t>(kFewOutliers, readings.size() / 20)) {
    refuse_outliers();
    return result;
  }

  // An estimate no real robot of this file can have: an exit point off the frame (by more than
  // the robot file's own tolerance, kExitOffFrameTolerance_m) or any parameter more than kImplausibleChange_m from
  // nominal. Measurements in other units, or of another robot, converge there.
  if (options.check_plausible_geometry) {
    constexpr double kImplausibleChange_m = 0.5;
    constexpr double kOffFrame_m = kExitOffFrameTolerance_m;
    for (int k = 0; k < kGeometry; ++k) {
      const double change = result.geometry(k) - nominal_geometry(k);
      std::string why;
      if (k < 2 * M) {  // an exit coordinate
        const double v = result.geometry(k);
        const double hi = k % 2 == 0 ? nominal.frame_width_m : nominal.frame_height_m;
        if (v < -kOffFrame_m || v > hi + kOffFrame_m) why = "outside the frame";
      }
      if (why.empty() && std::abs(change) > kImplausibleChange_m) why = "more than 0.5 m from nominal";
      if (!why.empty()) {
        result.status = IdentifyStatus::kPoorFit;
        result.message = "the identified " + geometry_names[k] + " = " + FormatDouble(result.geometry(k)) +
                         " m is " + why + " (nominal " + FormatDouble(nominal_geometry(k)) +
                         " m): are the readings in the file's units (m, rad), and of this robot? A single wrong reading can "
                         "do this too (the fit absorbs it: one inclinometer angle of 0 among 20 poses does), so check "
                         "for one";
        return result;
      }
    }
  }

  if (tripped > 0) {
    refuse_outliers();
    return result;
  }

  const int expected_null = options.gauge == Gauge::kNone ? 1 : 0;
  if (!options.compute_identifiability && !options.compute_covariance) return result;

  // The whitened Jacobian at the solution, in the tangent space (a1x's column is absent when
  // held), by blocks: its rows come in the order the residual blocks were added, one block per
  // pose, then the prior. Covariance and identifiability from it cost O(n) (identify/schur.h).
  BlockJacobian blocks;
  {
    ceres::Problem::EvaluateOptions eval;
    eval.parameter_blocks.push_back(geometry);
    for (int j = 0; j < n; ++j) eval.parameter_blocks.push_back(poses[j].data());
    ceres::CRSMatrix crs;
    problem.Evaluate(eval, nullptr, nullptr, nullptr, &crs);
    CABLECAL_CHECK(crs.num_rows == rows_per_pose * n + prior_rows &&
                       crs.num_cols == geometry_cols + per_pose_unknowns * n,
                   "the Jacobian has one row block per pose and the prior's");
    blocks.poses.assign(n, PoseBlock{Eigen::MatrixXd::Zero(rows_per_pose, geometry_cols),
                                     Eigen::MatrixXd::Zero(rows_per_pose, per_pose_unknowns)});
    blocks.prior = Eigen::MatrixXd::Zero(prior_rows, geometry_cols);
    for (int r = 0; r < crs.num_rows; ++r) {
      const int j = r / rows_per_pose, row_in_block = r % rows_per_pose;
      for (int k = crs.rows[r]; k < crs.rows[r + 1]; ++k) {
        const int c = crs.cols[k];
        if (j >= n) {
          CABLECAL_CHECK(c < geometry_cols, "prior rows touch the geometry only");
          blocks.prior(r - rows_per_pose * n, c) = crs.values[k];
        } else if (c < geometry_cols) {
          blocks.poses[j].geometry(row_in_block, c) = crs.values[k];
        } else {
          const int pose_col = c - geometry_cols - per_pose_unknowns * j;
          CABLECAL_CHECK(pose_col >= 0 && pose_col < per_pose_unknowns, "a pose's rows touch its own unknowns only");
          blocks.poses[j].pose(row_in_block, pose_col) = crs.values[k];
        }
      }
    }
  }
  // A null direction: singular value below 1e-9 of the largest (rounding, not data).
  const BlockAnalysis analysis = AnalyzeBlocks(blocks, 1e-9);

  if (options.compute_identifiability) {
    Identifiability& id = result.identifiability;
    for (int k = (options.gauge == Gauge::kA1x ? 1 : 0); k < kGeometry; ++k) {
      id.geometry_names.push_back(geometry_names[k]);
    }
    id.names = id.geometry_names;
    for (const Measurement& m : measurements) {
      const std::string p = std::to_string(m.pose_id);
      id.names.push_back("x" + p);
      if (ml) {
        id.names.push_back("z" + p);
        id.names.push_back("theta" + p);
      }
    }
    id.singular_values = analysis.singular_values;
    const double s_min = id.singular_values(id.singular_values.size() - 1);
    id.condition_number = analysis.null_vectors.empty() && s_min > 0.0
                              ? id.singular_values(0) / s_min
                              : std::numeric_limits<double>::infinity();
    if (analysis.weakest_pose >= 0) {
      id.weakest_pose_id = measurements[analysis.weakest_pose].pose_id;
      id.weakest_pose_singular_value = analysis.poses[analysis.weakest_pose].min_singular_value;
    }
    for (Eigen::VectorXd v : analysis.null_vectors) {
      Eigen::Index big;
      v.cwiseAbs().maxCoeff(&big);
      if (v(big) < 0) v = -v;
      std::string text;
      for (int c = 0; c < v.size(); ++c) {
        if (std::abs(v(c)) < 1e-6) continue;
        text += (text.empty() ? "" : (v(c) < 0 ? " - " : " + ")) +
                internal::FormatCoefficient(text.empty() ? v(c) : std::abs(v(c))) + " " + id.names[c];
      }
      id.null_directions.push_back(text);
      id.null_vectors.push_back(v);
    }
    if (static_cast<int>(id.null_directions.size()) > expected_null) {
      result.status = IdentifyStatus::kRankDeficient;
      result.message = "the measurements cannot determine " +
                       std::to_string(id.null_directions.size() - expected_null) +
                       " direction(s) beyond the declared gauge; null directions: ";
      for (std::size_t k = 0; k < id.null_directions.size(); ++k) {
        result.message += (k ? "; " : "") + id.null_directions[k];
      }
      return result;
    }
  }

  if (options.compute_covariance && static_cast<int>(analysis.null_vectors.size()) == expected_null) {
    // gauge none: the Moore-Penrose pseudo-inverse (identify/schur.h).
    if (const std::optional<BlockCovariance> cov = CovarianceOf(blocks, analysis)) {
      // paper: residuals are not whitened, so scale by the residual variance s^2.
      double scale = 1.0;
      if (!ml) {
        const int dof = summary.num_residuals - (summary.num_effective_parameters - expected_null);
        scale = dof > 0 ? 2.0 * summary.final_cost / dof : std::numeric_limits<double>::quiet_NaN();
      }
      // Back from the tangent space: a held a1x has no variance.
      Eigen::MatrixXd C = Eigen::MatrixXd::Zero(kGeometry, kGeometry);
      C.bottomRightCorner(geometry_cols, geometry_cols) = scale * cov->geometry;
      result.geometry_std = C.diagonal().cwiseMax(0.0).cwiseSqrt();
      for (int a = 0; a < kGeometry; ++a) {
        for (int b = 0; b < kGeometry; ++b) {
          const double d = result.geometry_std(a) * result.geometry_std(b);
          result.geometry_correlation(a, b) = a == b ? 1.0 : (d > 0.0 ? C(a, b) / d : 0.0);
        }
      }
      for (int j = 0; j < n; ++j) {
        for (int k = 0; k < per_pose_unknowns; ++k) {
          result.poses[j].std_dev(k) = std::sqrt(std::max(0.0, scale * cov->poses[j](k, k)));
        }
      }
      result.has_covariance = true;
    }
  }
  return result;
}

}  // namespace cablecal::internal
