#include "identify/identify.h"

#include <algorithm>

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <optional>

#include "common/error.h"
#include "common/format.h"
#include "identify/residuals.h"
#include "identify/schur.h"
#include "model/statics.h"

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

// A trial step of Levenberg-Marquardt can put an anchor inside its pulley, where the cable
// length is undefined (NaN). Saying so (false) makes Ceres reject the step quietly, exactly
// as it does for a NaN it finds itself, but without a multi-line warning per block.
template <typename T, int kCount>
bool AllFinite(const T* residual) {
  using std::isfinite;  // ceres::isfinite for Jets, by argument-dependent lookup
  for (int i = 0; i < kCount; ++i) {
    if (!isfinite(residual[i])) return false;
  }
  return true;
}

// Maximum likelihood, errors in variables: per pose, both cables' length residuals and the
// laser and inclinometer residuals, each whitened by its sensor's sigma.
struct MlPoseCost {
  const Robot* robot;
  Eigen::Vector2d dl_m;
  double z_meas_m, theta_meas_rad;
  double inv_sigma_encoder, inv_sigma_laser, inv_sigma_inclinometer;

  template <typename T>
  bool operator()(const T* geometry, const T* pose, T* residual) const {
    const auto anchors = AnchorsInF<T>(*robot, Pose<T>(pose[0], pose[1], pose[2]));
    for (int i = 0; i < 2; ++i) {
      residual[i] = LengthResidual<T>(robot->cables[i], i, geometry, anchors[i], dl_m(i)) * inv_sigma_encoder;
    }
    residual[2] = (pose[1] - z_meas_m) * inv_sigma_laser;
    residual[3] = (pose[2] - theta_meas_rad) * inv_sigma_inclinometer;
    return AllFinite<T, 2>(residual);
  }
};

// The paper's estimator: Eq. (6) with z_j and theta_j taken as measured; only x_j unknown.
struct PaperPoseCost {
  const Robot* robot;
  Eigen::Vector2d dl_m;
  double z_meas_m, theta_meas_rad;

  template <typename T>
  bool operator()(const T* geometry, const T* x, T* residual) const {
    const auto anchors = AnchorsInF<T>(*robot, Pose<T>(x[0], T(z_meas_m), T(theta_meas_rad)));
    for (int i = 0; i < 2; ++i) residual[i] = PaperResidual<T>(robot->cables[i], i, geometry, anchors[i], dl_m(i));
    return AllFinite<T, 2>(residual);
  }
};

// Laser-tracker prior on the exit points (gauge `prior`).
struct ExitPointPriorCost {
  Eigen::Vector4d nominal;  // a1x a1z a2x a2z
  double inv_sigma;
  template <typename T>
  bool operator()(const T* geometry, T* residual) const {
    for (int k = 0; k < 4; ++k) residual[k] = (geometry[k] - nominal(k)) * inv_sigma;
    return true;
  }
};

// Starting x for one pose: where the nominal model best explains the measured lengths at
// the measured z and theta (README, "Identification": starting every x_j at home sends LM to wrong minima).
// Start from the straight-cable estimate of each cable, then Gauss-Newton in x.
double StartingX(const Robot& nominal, const GeometryVector& g, const Measurement& m) {
  using Jet1 = ceres::Jet<double, 1>;
  const Eigen::Matrix2d R = Rotation(m.theta_rad);
  double sum = 0.0;
  int count = 0;
  for (int i = 0; i < 2; ++i) {
    const Cable& c = nominal.cables[i];
    const Eigen::Vector2d r_anchor = R * c.p_P_anchor_m;
    const double length = g(4 + i) + m.dl_m(i);
    const double dz = g(2 * i + 1) - (m.z_m + r_anchor.y());
    const double horizontal2 = length * length - dz * dz;
    if (horizontal2 <= 0.0) continue;
    sum += g(2 * i) + SideSign(c.side) * std::sqrt(horizontal2) - r_anchor.x();
    ++count;
  }
  double x = count > 0 ? sum / count : nominal.p_F_home_m.x();
  Jet1 geometry[6];
  for (int k = 0; k < 6; ++k) geometry[k] = Jet1(g(k));
  for (int it = 0; it < 6; ++it) {
    const auto anchors = AnchorsInF<Jet1>(nominal, Pose<Jet1>(Jet1(x, 0), Jet1(m.z_m), Jet1(m.theta_rad)));
    double num = 0.0, den = 0.0;
    for (int i = 0; i < 2; ++i) {
      const Jet1 r = LengthResidual<Jet1>(nominal.cables[i], i, geometry, anchors[i], m.dl_m(i));
      num += r.v(0) * r.a;
      den += r.v(0) * r.v(0);
    }
    if (!(den > 0.0) || !std::isfinite(num)) break;
    const double step = num / den;
    x -= step;
    if (std::abs(step) < 1e-9) break;  // a start, not the estimate: LM refines it
  }
  return std::isfinite(x) ? x : nominal.p_F_home_m.x();
}

std::string FormatCoefficient(double c) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.4g", c);
  return buffer;
}

}  // namespace internal

IdentifyResult Identify(const Robot& nominal, const std::vector<Measurement>& measurements,
                        const IdentifyOptions& options) {
  CABLECAL_CHECK(nominal.num_cables() == 2, "identification is implemented for 2 cables");
  const bool ml = options.estimator == Estimator::kMaximumLikelihood;
  const int n = static_cast<int>(measurements.size());

  // Enough equations for the unknowns (paper, Eq. 7; the gauge removes one unknown).
  const int per_pose_unknowns = ml ? 3 : 1;
  const int equations = (ml ? 4 : 2) * n + (options.gauge == Gauge::kPrior ? 4 : 0);
  const int unknowns = (options.gauge == Gauge::kA1x ? 5 : 6) + per_pose_unknowns * n;
  if (equations < unknowns) {
    int needed = n;
    while ((ml ? 4 : 2) * needed + (options.gauge == Gauge::kPrior ? 4 : 0) <
           (options.gauge == Gauge::kA1x ? 5 : 6) + per_pose_unknowns * needed) {
      ++needed;
    }
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

  const GeometryVector nominal_geometry = GeometryOf(nominal);
  double geometry[6];
  for (int k = 0; k < 6; ++k) geometry[k] = nominal_geometry(k);
  std::vector<std::array<double, 3>> poses(n);
  for (int j = 0; j < n; ++j) {
    poses[j] = {internal::StartingX(nominal, nominal_geometry, measurements[j]), measurements[j].z_m,
                measurements[j].theta_rad};
  }

  ceres::Problem problem;
  problem.AddParameterBlock(geometry, 6);
  if (options.gauge == Gauge::kA1x) problem.SetManifold(geometry, new ceres::SubsetManifold(6, {0}));
  for (int j = 0; j < n; ++j) {
    const Measurement& m = measurements[j];
    const Eigen::Vector2d dl = m.dl_m.head<2>();
    if (ml) {
      auto* cost = new ceres::AutoDiffCostFunction<internal::MlPoseCost, 4, 6, 3>(new internal::MlPoseCost{
          &nominal, dl, m.z_m, m.theta_rad, 1.0 / s.encoder_sigma_m, 1.0 / s.laser_sigma_m(),
          1.0 / s.inclinometer_sigma_rad()});
      problem.AddResidualBlock(cost, nullptr, geometry, poses[j].data());
    } else {
      auto* cost = new ceres::AutoDiffCostFunction<internal::PaperPoseCost, 2, 6, 1>(
          new internal::PaperPoseCost{&nominal, dl, m.z_m, m.theta_rad});
      problem.AddResidualBlock(cost, nullptr, geometry, poses[j].data());
    }
  }
  if (options.gauge == Gauge::kPrior) {
    auto* prior = new ceres::AutoDiffCostFunction<internal::ExitPointPriorCost, 4, 6>(
        new internal::ExitPointPriorCost{nominal_geometry.head<4>(), 1.0 / *s.tracker_sigma_m});
    problem.AddResidualBlock(prior, nullptr, geometry);
  }

  // Schur complement: eliminate the per-pose blocks first, leaving a 6 x 6 reduced system.
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
  for (int k = 0; k < 6; ++k) result.geometry(k) = geometry[k];
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
    int sensor;  // 0, 1: encoders; 2: laser; 3: inclinometer
  };
  std::vector<Reading> readings;
  readings.reserve((ml ? 4 : 2) * n);
  const double length_sigma = ml ? s.encoder_sigma_m : std::max(s.laser_sigma_m(), s.encoder_sigma_m);
  double sum_enc = 0.0, sum_laser = 0.0, sum_inc = 0.0;
  for (int j = 0; j < n; ++j) {
    const Measurement& m = measurements[j];
    PoseEstimate e;
    e.pose_id = m.pose_id;
    e.q = ml ? Eigen::Vector3d(poses[j][0], poses[j][1], poses[j][2])
             : Eigen::Vector3d(poses[j][0], m.z_m, m.theta_rad);
    const auto anchors = AnchorsInF<double>(nominal, e.q);
    for (int i = 0; i < 2; ++i) {
      const double r = LengthResidual<double>(nominal.cables[i], i, geometry, anchors[i], m.dl_m(i));
      sum_enc += r * r;
      readings.push_back({std::abs(r) / length_sigma, m.pose_id, i});
    }
    sum_laser += (e.q(1) - m.z_m) * (e.q(1) - m.z_m);
    sum_inc += (e.q(2) - m.theta_rad) * (e.q(2) - m.theta_rad);
    if (ml) {
      readings.push_back({std::abs(e.q(1) - m.z_m) / s.laser_sigma_m(), m.pose_id, 2});
      readings.push_back({std::abs(e.q(2) - m.theta_rad) / s.inclinometer_sigma_rad(), m.pose_id, 3});
    }
    result.poses.push_back(e);
  }
  result.rms_encoder_m = std::sqrt(sum_enc / (2.0 * n));
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
  // 200 * 6.8e-6 = 0.14 % (measured: 0 of 6000 ml trials, 8 of 2000 paper trials at n = 6
  // and 28). With the ml estimator a pose has 4 readings for its 3 unknowns: one bad reading
  // shows in that pose's residuals along their one redundant direction, so the pose is named
  // reliably but the largest residual may sit on another sensor of the same pose.
  const std::size_t tripped = static_cast<std::size_t>(std::count_if(
      readings.begin(), readings.end(), [](const Reading& r) { return !(r.sigmas <= kOutlierSigmas); }));
  const auto refuse_outliers = [&] {
    const std::size_t worst_count = std::min<std::size_t>(3, readings.size());
    std::partial_sort(readings.begin(), readings.begin() + worst_count, readings.end(),
                      [](const Reading& a, const Reading& b) { return a.sigmas > b.sigmas; });
    const char* const sensor_names[4] = {"encoder 1", "encoder 2", "laser", "inclinometer"};
    std::string worst;
    for (std::size_t k = 0; k < worst_count && !(readings[k].sigmas <= kOutlierSigmas); ++k) {
      char buffer[96];
      std::snprintf(buffer, sizeof(buffer), "%spose %d: %s %.3g sigma", k ? ", " : "", readings[k].pose_id,
                    sensor_names[readings[k].sensor], readings[k].sigmas);
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
    for (int k = 0; k < 6; ++k) {
      const double change = result.geometry(k) - nominal_geometry(k);
      std::string why;
      if (k < 4) {
        const double v = result.geometry(k);
        const double hi = k % 2 == 0 ? nominal.frame_width_m : nominal.frame_height_m;
        if (v < -kOffFrame_m || v > hi + kOffFrame_m) why = "outside the frame";
      }
      if (why.empty() && std::abs(change) > kImplausibleChange_m) why = "more than 0.5 m from nominal";
      if (!why.empty()) {
        result.status = IdentifyStatus::kPoorFit;
        result.message = std::string("the identified ") + kGeometryNames[k] + " = " + FormatDouble(result.geometry(k)) +
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
  const int geometry_cols = options.gauge == Gauge::kA1x ? 5 : 6;
  const int rows_per_pose = ml ? 4 : 2;
  BlockJacobian blocks;
  {
    ceres::Problem::EvaluateOptions eval;
    eval.parameter_blocks.push_back(geometry);
    for (int j = 0; j < n; ++j) eval.parameter_blocks.push_back(poses[j].data());
    ceres::CRSMatrix crs;
    problem.Evaluate(eval, nullptr, nullptr, nullptr, &crs);
    const int prior_rows = options.gauge == Gauge::kPrior ? 4 : 0;
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
    for (int k = (options.gauge == Gauge::kA1x ? 1 : 0); k < 6; ++k) id.geometry_names.push_back(kGeometryNames[k]);
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
      Eigen::Matrix<double, 6, 6> C = Eigen::Matrix<double, 6, 6>::Zero();
      C.bottomRightCorner(geometry_cols, geometry_cols) = scale * cov->geometry;
      result.geometry_std = C.diagonal().cwiseMax(0.0).cwiseSqrt();
      for (int a = 0; a < 6; ++a) {
        for (int b = 0; b < 6; ++b) {
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

}  // namespace cablecal
