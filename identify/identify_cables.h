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
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "common/error.h"
#include "common/format.h"
#include "identify/cost_functors.h"
#include "identify/identify.h"
#include "identify/least_squares.h"
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

// Starting pose for one reading (identify's x_j, z_j, theta_j; validate's forward model): the
// measured z and theta with StartingX's x. A missing z or theta starts where `robot` settles
// with these lengths (a cold forward model; home, level, if it finds nothing).
template <int M>
Eigen::Vector3d StartingPose(const Robot& robot, const GeometryVector& g, Measurement m) {
  if (!m.has_laser || !m.has_inclinometer) {
    const Eigen::VectorXd lengths = g.tail<M>() + m.dl_m;
    const ForwardResult fwd = SolveForwardGeometricoStatic(robot, lengths);
    const Eigen::Vector3d q = fwd.status == ForwardStatus::kConverged
                                  ? fwd.equilibrium.q
                                  : Eigen::Vector3d(robot.p_F_home_m.x(), robot.p_F_home_m.y(), 0.0);
    if (!m.has_laser) m.z_m = q(1);
    if (!m.has_inclinometer) m.theta_rad = q(2);
  }
  return Eigen::Vector3d(StartingX<M>(robot, g, m), m.z_m, m.theta_rad);
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
  const bool robust = options.loss.kind != LossKind::kNone;
  const int num_readings = static_cast<int>(measurements.size());
  const SensorNoise& s = nominal.sensors;

  // The sensors the data have: one set for every reading (a file's columns).
  const bool laser = num_readings == 0 || measurements.front().has_laser;
  const bool inclinometer = num_readings == 0 || measurements.front().has_inclinometer;
  for (const Measurement& m : measurements) {
    if (m.has_laser != laser || m.has_inclinometer != inclinometer) {
      throw InputError(options.source, "",
                       "some readings have a laser (z) or inclinometer (theta) value and others not: give every "
                       "reading the same sensors");
    }
  }
  std::vector<std::string> missing_sensors;
  if (!laser) missing_sensors.push_back("laser");
  if (!inclinometer) missing_sensors.push_back("inclinometer");
  const std::string missing_text = MissingSensorsText(missing_sensors);
  if (!ml && !missing_sensors.empty()) {
    throw InputError(options.source, "", "the paper estimator takes z and theta as measured, but the data have " +
                                             missing_text + ": use --estimator ml");
  }
  if (robust && !ml) {
    throw InputError("--loss", "", "needs --estimator ml (the paper estimator's residuals are not in sigmas)");
  }
  if (options.geometry_prior_sigma_m && !ml) {
    throw InputError("--geometry-prior", "", "needs --estimator ml (the paper estimator's residuals are not in sigmas)");
  }
  if (options.geometry_prior_sigma_m &&
      !(*options.geometry_prior_sigma_m >= kMinGeometryPriorSigma_m && *options.geometry_prior_sigma_m <= kMaxGeometryPriorSigma_m)) {
    throw InputError("--geometry-prior", "",
                     "must be between " + FormatDouble(kMinGeometryPriorSigma_m) + " and " +
                         FormatDouble(kMaxGeometryPriorSigma_m) + " m (the standard deviation of the nominal geometry), not " +
                         FormatDouble(*options.geometry_prior_sigma_m));
  }
  if (options.equilibrium && (!ml || M >= 3)) {
    throw InputError("--equilibrium", "",
                     !ml ? std::string("needs --estimator ml (the paper estimator fixes theta at the inclinometer's reading)")
                         : "applies to robots with fewer cables than the pose's 3 degrees of freedom (2 cables): with " +
                               std::to_string(M) + " the cables hold theta, and there is no equilibrium row to add");
  }

  // Repeated readings of one pose share its unknowns: group them by pose id, poses in the order
  // of their first reading.
  std::vector<std::vector<int>> readings_of;
  {
    std::map<int, int> index_of;
    for (int k = 0; k < num_readings; ++k) {
      const auto [it, inserted] = index_of.emplace(measurements[k].pose_id, static_cast<int>(readings_of.size()));
      if (inserted) readings_of.emplace_back();
      readings_of[it->second].push_back(k);
    }
  }
  const int n = static_cast<int>(readings_of.size());
  const auto pose_id_of = [&](int j) { return measurements[readings_of[j].front()].pose_id; };
  // Two poses never read alike to the last digit (every sensor has noise): a reading identical
  // in every value to another pose's is a copied row, and counts that pose's information twice
  // (a new user's 5 poses copied under 30 ids fitted exactly, 172 mm off, and nothing said so).
  std::vector<std::string> copied;  // "pose 6 (lab.csv:7) = pose 1 (lab.csv:2)"
  int copied_count = 0;
  {
    std::map<std::vector<double>, int> first_with;
    for (int k = 0; k < num_readings; ++k) {
      const Measurement& m = measurements[k];
      std::vector<double> key(m.dl_m.data(), m.dl_m.data() + m.dl_m.size());
      key.push_back(m.has_laser ? m.z_m : 0.0);
      key.push_back(m.has_inclinometer ? m.theta_rad : 0.0);
      const auto [it, inserted] = first_with.emplace(std::move(key), k);
      if (inserted || measurements[it->second].pose_id == m.pose_id) continue;
      ++copied_count;
      const auto name = [](const Measurement& r) {
        return "pose " + std::to_string(r.pose_id) + (r.where.empty() ? "" : " (" + r.where + ")");
      };
      if (copied.size() < 3) copied.push_back(name(m) + " = " + name(measurements[it->second]));
    }
  }

  // Enough equations for the unknowns (paper, Eq. 7; the gauge removes one unknown): per
  // reading M encoder values, plus the laser's and the inclinometer's for ml; per pose 3
  // unknowns (ml) or 1 (paper); 3M geometric unknowns, 3M - 1 with a1x held; the tracker prior
  // adds 2M equations, the geometry prior one per geometric unknown (any pose count is then
  // determined).
  // equations. Repeated readings add equations, not information on other poses: the rank test
  // below judges them.
  const int per_pose_unknowns = ml ? 3 : 1;
  const int values_per_reading = ml ? M + (laser ? 1 : 0) + (inclinometer ? 1 : 0) : M;
  const bool geometry_prior = options.geometry_prior_sigma_m.has_value();
  const double prior_sigma_m = options.geometry_prior_sigma_m.value_or(0.0);
  const int geometry_cols = options.gauge == Gauge::kA1x ? kGeometry - 1 : kGeometry;
  // ml with fewer cables than the pose's 3 DoF: each pose's static equilibrium, 3 - M rows of its
  // block (residuals.h, MlEquilibriumResidual), whatever the number of its readings.
  const int equilibrium_rows = ml && options.equilibrium ? EquilibriumRows(M) : 0;
  // Ceres' prior rows (GeometryPriorCost: all 3M; ExitPointPriorCost: the exits) and the
  // equations they add (a held a1x's row is zero).
  const int prior_rows = geometry_prior ? kGeometry : options.gauge == Gauge::kPrior ? 2 * M : 0;
  const int prior_equations = geometry_prior ? geometry_cols : prior_rows;
  const int equations = values_per_reading * num_readings + equilibrium_rows * n + prior_equations;
  const int unknowns = geometry_cols + per_pose_unknowns * n;
  if (equations < unknowns) {
    std::string advice;
    if (values_per_reading + equilibrium_rows <= per_pose_unknowns) {
      advice = "each reading's " + std::to_string(values_per_reading) + " values only fix its pose's own " +
               std::to_string(per_pose_unknowns) + " unknowns, so no number of poses determines the geometry" +
               (missing_text.empty() ? "" : " (the data have " + missing_text + ")");
    } else {
      int needed = n;
      while ((values_per_reading + equilibrium_rows) * needed + prior_equations < geometry_cols + per_pose_unknowns * needed) {
        ++needed;
      }
      advice = "at least " + std::to_string(needed) + " poses are needed";
    }
    throw InputError(options.source, "",
                     std::to_string(n) + " poses" +
                         (num_readings != n ? " (" + std::to_string(num_readings) + " readings)" : "") + " give " +
                         std::to_string(equations) + " equations for " + std::to_string(unknowns) +
                         " unknowns (estimator " + ToString(options.estimator) + ", gauge " +
                         ToString(options.gauge) + "): " + advice);
  }
  if (ml) {
    if (!(s.encoder_sigma_m > 0.0)) {
      throw InputError(nominal.source, "sensors.encoder.sigma", "must be > 0 for the ml estimator");
    }
    if (laser && !(s.laser_sigma_m() > 0.0)) {
      throw InputError(nominal.source, "sensors.laser", "accuracy or repeatability must be > 0 for the ml estimator");
    }
    if (inclinometer && !(s.inclinometer_sigma_rad() > 0.0)) {
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
  result.loss = options.loss;
  result.missing_sensors = missing_sensors;
  if (equilibrium_rows > 0) result.equilibrium_com_sigma_m = EquilibriumSigma(nominal);
  result.geometry_std = GeometryVector::Zero(kGeometry);
  result.geometry_correlation = Eigen::MatrixXd::Identity(kGeometry, kGeometry);

  const GeometryVector nominal_geometry = GeometryOf(nominal);
  const std::vector<std::string> geometry_names = GeometryNames(M);
  result.geometry_prior_sigma_m = prior_sigma_m;
  // The priors' inverse sigma per geometric coordinate: the tracker's on the exit points
  // (gauge prior) and the geometry prior's on every one, combined as independent Gaussians
  // about the same nominal value (their precisions add); 0 where there is none.
  Eigen::Matrix<double, kGeometry, 1> prior_inv_sigma = Eigen::Matrix<double, kGeometry, 1>::Zero();
  {
    Eigen::Matrix<double, kGeometry, 1> precision = Eigen::Matrix<double, kGeometry, 1>::Zero();
    if (options.gauge == Gauge::kPrior) precision.template head<2 * M>().setConstant(1.0 / (*s.tracker_sigma_m * *s.tracker_sigma_m));
    if (geometry_prior) precision.array() += 1.0 / (prior_sigma_m * prior_sigma_m);
    prior_inv_sigma = precision.cwiseSqrt();
  }
  double geometry[kGeometry];
  for (int k = 0; k < kGeometry; ++k) geometry[k] = nominal_geometry(k);
  std::vector<std::array<double, 3>> poses(n);
  for (int j = 0; j < n; ++j) {
    const Eigen::Vector3d start =
        internal::StartingPose<M>(nominal, nominal_geometry, measurements[readings_of[j].front()]);
    poses[j] = {start(0), start(1), start(2)};
  }
  const std::vector<std::array<double, 3>> start_poses = poses;

  ReadingWeights weights = ml ? WeightsOf(s) : ReadingWeights{};
  // No reading, no weight: its row stays in the block (the same block shapes) but is zero.
  if (!laser) weights.inv_sigma_laser = 0.0;
  if (!inclinometer) weights.inv_sigma_inclinometer = 0.0;
  if (equilibrium_rows > 0) weights.inv_sigma_equilibrium = 1.0 / EquilibriumSigma(nominal);
  using PoseValues = std::vector<std::array<double, 3>>;
  // The problem over the poses in `use` at the values in `g` and `q`, each reading's blocks
  // with `loss_kind` (the problem owns its loss function).
  const auto build = [&](double* g, PoseValues& q, const std::vector<char>& use, const RobustLoss& loss_kind) {
    auto problem = std::make_unique<ceres::Problem>();
    problem->AddParameterBlock(g, kGeometry);
    if (options.gauge == Gauge::kA1x) problem->SetManifold(g, new ceres::SubsetManifold(kGeometry, {0}));
    ceres::LossFunction* loss = nullptr;  // shared by every reading's block
    if (loss_kind.kind == LossKind::kHuber) loss = new ceres::HuberLoss(loss_kind.scale_sigmas);
    if (loss_kind.kind == LossKind::kCauchy) loss = new ceres::CauchyLoss(loss_kind.scale_sigmas);
    for (int j = 0; j < n; ++j) {
      if (!use[j]) continue;
      for (const int k : readings_of[j]) {
        const PoseReadings<M> readings = internal::ReadingsOf<M>(measurements[k]);
        if (ml && loss) {
          for (int i = 0; i < M; ++i) {
            problem->AddResidualBlock(new ceres::AutoDiffCostFunction<internal::MlCableCost<M>, 1, kGeometry, 3>(
                                          new internal::MlCableCost<M>{&nominal, readings, weights, i}),
                                      loss, g, q[j].data());
          }
          for (int sensor = 0; sensor < 2; ++sensor) {
            if (!(sensor == 0 ? laser : inclinometer)) continue;
            problem->AddResidualBlock(new ceres::AutoDiffCostFunction<internal::MlOneSensorCost<M>, 1, 3>(
                                          new internal::MlOneSensorCost<M>{readings, weights, sensor}),
                                      loss, q[j].data());
          }
        } else if (ml) {
          auto* lengths = new ceres::AutoDiffCostFunction<internal::MlLengthCost<M>, M, kGeometry, 3>(
              new internal::MlLengthCost<M>{&nominal, readings, weights});
          problem->AddResidualBlock(lengths, nullptr, g, q[j].data());
          auto* sensors = new ceres::AutoDiffCostFunction<internal::MlSensorCost<M>, 2, 3>(
              new internal::MlSensorCost<M>{readings, weights});
          problem->AddResidualBlock(sensors, nullptr, q[j].data());
        } else {
          auto* cost = new ceres::AutoDiffCostFunction<internal::PaperPoseCost<M>, M, kGeometry, 1>(
              new internal::PaperPoseCost<M>{&nominal, readings});
          problem->AddResidualBlock(cost, nullptr, g, q[j].data());
        }
      }
      if constexpr (EquilibriumRows(M) > 0) {
        if (equilibrium_rows > 0) {  // after the pose's readings: the last row of its block
          problem->AddResidualBlock(new ceres::AutoDiffCostFunction<internal::MlEquilibriumCost<M>, 1, kGeometry, 3>(
                                        new internal::MlEquilibriumCost<M>{&nominal, weights}),
                                    nullptr, g, q[j].data());
        }
      }
    }
    if (geometry_prior) {
      auto* prior = new ceres::AutoDiffCostFunction<internal::GeometryPriorCost<M>, kGeometry, kGeometry>(
          new internal::GeometryPriorCost<M>{nominal_geometry, prior_inv_sigma});
      problem->AddResidualBlock(prior, nullptr, g);
    } else if (options.gauge == Gauge::kPrior) {
      auto* prior = new ceres::AutoDiffCostFunction<internal::ExitPointPriorCost<M>, 2 * M, kGeometry>(
          new internal::ExitPointPriorCost<M>{nominal_geometry.head<2 * M>(), 1.0 / *s.tracker_sigma_m});
      problem->AddResidualBlock(prior, nullptr, g);
    }
    return problem;
  };
  // Levenberg-Marquardt; with the geometry held (one pose fitted to it alone) a plain QR step.
  const auto solve = [&](ceres::Problem& problem, double* g, PoseValues& q, const std::vector<char>& use,
                         bool hold_geometry, int max_iterations) {
    ceres::Solver::Options solver_options;
    if (hold_geometry) {
      problem.SetParameterBlockConstant(g);
      solver_options.linear_solver_type = ceres::DENSE_QR;
    } else {
      // Schur complement: eliminate the per-pose blocks first, leaving a 3M x 3M reduced system.
      auto* ordering = new ceres::ParameterBlockOrdering;
      for (int j = 0; j < n; ++j) {
        if (use[j]) ordering->AddElementToGroup(q[j].data(), 0);
      }
      ordering->AddElementToGroup(g, 1);
      solver_options.linear_solver_type = ceres::DENSE_SCHUR;
      solver_options.linear_solver_ordering.reset(ordering);
    }
    solver_options.minimizer_type = ceres::TRUST_REGION;
    solver_options.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
    solver_options.max_num_iterations = max_iterations;
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
    return summary;
  };
  const auto from_ceres = [](const ceres::Solver::Summary& sum) {
    LeastSquaresSummary out;
    out.converged = sum.termination_type == ceres::CONVERGENCE;
    out.iterations = static_cast<int>(sum.iterations.size()) - 1;
    out.final_cost = sum.final_cost;
    // Ceres' own words for its iteration limit repeat the count the caller gives.
    out.message = sum.termination_type == ceres::NO_CONVERGENCE ? "the iteration limit was reached" : sum.message;
    return out;
  };
  // Least squares over the poses in `use`: for ml the block-arrow Levenberg-Marquardt written
  // for it (least_squares.h: the same iterations as Ceres', without its set-up, which was half
  // of every Monte Carlo trial's solve), for the paper's estimator Ceres.
  MlLeastSquaresProblem<M> ml_problem;
  ml_problem.robot = &nominal;
  ml_problem.measurements = &measurements;
  ml_problem.readings_of = &readings_of;
  ml_problem.weights = weights;
  ml_problem.hold_a1x = options.gauge == Gauge::kA1x;
  ml_problem.prior_geometry = nominal_geometry;
  ml_problem.prior_inv_sigma = prior_inv_sigma;
  const auto least_squares = [&](double* g, PoseValues& q, const std::vector<char>& use, int max_iterations) {
    if (ml) {
      MlLeastSquaresProblem<M> limited = ml_problem;
      limited.max_iterations = max_iterations;
      return SolveMlLeastSquares<M>(limited, g, q, use);
    }
    std::unique_ptr<ceres::Problem> p = build(g, q, use, RobustLoss{});
    return from_ceres(solve(*p, g, q, use, false, max_iterations));
  };
  // The poses in `use` alone have enough equations for their unknowns and the geometry's.
  const auto enough_equations = [&](const std::vector<char>& use) {
    int values = 0, poses_used = 0;
    for (int p = 0; p < n; ++p) {
      if (!use[p]) continue;
      ++poses_used;
      values += values_per_reading * static_cast<int>(readings_of[p].size()) + equilibrium_rows;
    }
    return values + prior_equations >= geometry_cols + per_pose_unknowns * poses_used;
  };
  // Pose j alone fitted to the geometry g (held), from q[j].
  const auto fit_to_geometry = [&](double* g, PoseValues& q, int j, int max_iterations) {
    std::vector<char> only(n, 0);
    only[j] = 1;
    std::unique_ptr<ceres::Problem> alone = build(g, q, only, RobustLoss{});
    solve(*alone, g, q, only, true, max_iterations);
  };
  // Each pose left out in turn, for the outlier test and the diagnosis of a fit that did not
  // converge: beyond this many poses it would cost too much (n refits per round).
  constexpr int kMaxPosesLeftOutTest = 200;
  const std::vector<char> every_pose(n, 1);
  // Least squares first, also under a robust loss: its residuals say whether there is anything
  // to down-weight, and where to start (below).
  LeastSquaresSummary summary = least_squares(geometry, poses, every_pose, options.max_iterations);
  // The Ceres problem at the estimate, for the Jacobian blocks of the covariance and the pose
  // checks: built when first needed (the Monte Carlo needs none); a robust fit's replaces it.
  std::unique_ptr<ceres::Problem> problem;
  const auto problem_at_estimate = [&]() -> ceres::Problem& {
    if (!problem) problem = build(geometry, poses, every_pose, RobustLoss{});
    return *problem;
  };
  const auto converged = [&](const LeastSquaresSummary& sum, const double* g, const PoseValues& q,
                             const std::vector<char>& use) {
    bool ok = sum.converged;
    for (int k = 0; k < kGeometry; ++k) ok = ok && std::isfinite(g[k]);
    for (int j = 0; j < n; ++j) ok = ok && (!use[j] || (std::isfinite(q[j][0]) && std::isfinite(q[j][1]) && std::isfinite(q[j][2])));
    return ok;
  };

  // Every reading's whitened residual at (g, q) (ml: each value over its sigma; paper: each
  // length residual over the laser's sigma, as the global test), for the readings of the poses
  // in `use`; with `fits`, also the per-pose estimates, ReadingFits and RMS of the result.
  struct Reading {
    double sigmas;
    int reading;  // index into measurements
    int sensor;   // 0 .. M - 1: encoders; M: laser; M + 1: inclinometer; M + 2: the pose's equilibrium
  };
  const double length_sigma = ml ? s.encoder_sigma_m : std::max(s.laser_sigma_m(), s.encoder_sigma_m);
  // The per-reading ReadingFits are for a person (the CLI, Python); the Monte Carlo, which asks
  // for neither covariance nor identifiability, is spared their allocations.
  const bool reading_fits = options.compute_covariance || options.compute_identifiability;
  const auto residuals_at = [&](const double* g, const PoseValues& q, const std::vector<char>& use, bool fits) {
    std::vector<Reading> readings;
    readings.reserve(static_cast<std::size_t>(values_per_reading) * num_readings);
    double sum_enc = 0.0, sum_laser = 0.0, sum_inc = 0.0;
    const bool keep_fits = fits && reading_fits;
    if (fits) {
      result.readings.assign(keep_fits ? num_readings : 0, ReadingFit{});
      result.poses.clear();
    }
    for (int j = 0; j < n; ++j) {
      if (!use[j]) continue;
      PoseEstimate e;
      e.pose_id = pose_id_of(j);
      if (ml) {
        e.q = Eigen::Vector3d(q[j][0], q[j][1], q[j][2]);
      } else {  // z and theta as measured: their mean over the pose's readings
        e.q = Eigen::Vector3d(q[j][0], 0.0, 0.0);
        for (const int k : readings_of[j]) {
          e.q.tail<2>() += Eigen::Vector2d(measurements[k].z_m, measurements[k].theta_rad);
        }
        e.q.tail<2>() /= static_cast<double>(readings_of[j].size());
      }
      for (const int k : readings_of[j]) {
        const Measurement& m = measurements[k];
        const Eigen::Vector3d q_k = ml ? e.q : Eigen::Vector3d(q[j][0], m.z_m, m.theta_rad);
        double length_residuals[M];
        LengthResiduals<M, double>(nominal, g, q_k, m.dl_m.data(), length_residuals);
        for (int i = 0; i < M; ++i) {
          sum_enc += length_residuals[i] * length_residuals[i];
          readings.push_back({std::abs(length_residuals[i]) / length_sigma, k, i});
        }
        const double laser_sigmas = (q_k(1) - m.z_m) / s.laser_sigma_m();
        const double inclinometer_sigmas = (q_k(2) - m.theta_rad) / s.inclinometer_sigma_rad();
        if (ml && laser) {
          sum_laser += (q_k(1) - m.z_m) * (q_k(1) - m.z_m);
          readings.push_back({std::abs(laser_sigmas), k, M});
        }
        if (ml && inclinometer) {
          sum_inc += (q_k(2) - m.theta_rad) * (q_k(2) - m.theta_rad);
          readings.push_back({std::abs(inclinometer_sigmas), k, M + 1});
        }
        if (!keep_fits) continue;
        ReadingFit& fit = result.readings[k];
        fit.pose_id = m.pose_id;
        fit.where = m.where;
        fit.encoder_sigmas = Eigen::Map<const Eigen::Matrix<double, M, 1>>(length_residuals) / length_sigma;
        fit.encoder_weights = fit.encoder_sigmas.unaryExpr([&](double r) { return LossWeight(options.loss, r); });
        if (ml && laser) {
          fit.laser_sigmas = laser_sigmas;
          fit.laser_weight = LossWeight(options.loss, laser_sigmas);
        }
        if (ml && inclinometer) {
          fit.inclinometer_sigmas = inclinometer_sigmas;
          fit.inclinometer_weight = LossWeight(options.loss, inclinometer_sigmas);
        }
      }
      if constexpr (EquilibriumRows(M) > 0) {
        if (equilibrium_rows > 0) {  // the pose's, named by its first reading
          double r;
          MlEquilibriumResidual<M, double>(nominal, weights, g, q[j].data(), &r);
          readings.push_back({std::abs(r), readings_of[j].front(), M + 2});
          if (fits) {
            e.equilibrium_sigmas = r;
            e.equilibrium_theta_error_rad = EquilibriumThetaError<M>(nominal, g, e.q);
          }
        }
      }
      if (fits) result.poses.push_back(e);
    }
    if (fits) {
      result.rms_encoder_m = std::sqrt(sum_enc / (static_cast<double>(M) * num_readings));
      result.rms_laser_m = std::sqrt(sum_laser / num_readings);
      result.rms_inclinometer_rad = std::sqrt(sum_inc / num_readings);
    }
    return readings;
  };
  const auto beyond = [](const std::vector<Reading>& readings) {
    std::vector<Reading> out;
    for (const Reading& r : readings) {
      if (!(r.sigmas <= kOutlierSigmas)) out.push_back(r);
    }
    std::sort(out.begin(), out.end(), [](const Reading& a, const Reading& b) { return a.sigmas > b.sigmas; });
    return out;
  };
  // "pose 7: laser 199 sigma", with the reading's line when the pose has several.
  const auto describe = [&](const Reading& r, bool with_pose = true) {
    const Measurement& m = measurements[r.reading];
    const bool repeated = readings_of.size() != measurements.size() && !m.where.empty();
    const std::string sensor = r.sensor < M        ? "encoder " + std::to_string(r.sensor + 1)
                               : r.sensor == M     ? std::string("laser")
                               : r.sensor == M + 1 ? std::string("inclinometer")
                                                   : std::string("equilibrium");
    char buffer[64];
    std::snprintf(buffer, sizeof(buffer), " %.3g sigma", r.sigmas);
    return (with_pose ? "pose " + std::to_string(m.pose_id) + ": " : std::string()) + sensor +
           (repeated ? " (" + m.where + ")" : "") + buffer;
  };
  // Why least squares did not converge, when one pose's readings say it: a reading that no
  // position gives a valid cable length on the nominal robot at its laser height and
  // inclinometer angle (the anchor inside or past its pulley), or poses without which the
  // others converge (each left out in turn, from the same start; up to kMaxPosesLeftOutTest
  // poses, as the outlier test below).
  constexpr int kMaxLeftOut = 3;
  struct LeftOut {
    std::vector<int> poses;                 // indices into readings_of
    double geometry_values[kGeometry];      // the fit without them
    PoseValues pose_values;                 // every pose: the rest's fit, the left-out fitted to that geometry
    std::vector<Reading> worst;             // the left-out poses' readings against the rest's geometry
  };
  // The pose found by the diagnosis below, with the fit without it (a robust loss starts there).
  std::optional<LeftOut> lost_fit_culprit;
  std::optional<std::string> why_not_converged_text;  // computed once
  // The identification's start: the nominal geometry and each pose's StartingPose.
  const auto reset_to_start = [&](double* g, PoseValues& q) {
    for (int k = 0; k < kGeometry; ++k) g[k] = nominal_geometry(k);
    q = start_poses;
  };
  const auto diagnose_lost_fit = [&]() -> std::string {
    for (int j = 0; j < n; ++j) {
      for (const int k : readings_of[j]) {
        double r[M];
        const Measurement& m = measurements[k];
        LengthResiduals<M, double>(nominal, nominal_geometry.data(),
                                   Eigen::Vector3d(start_poses[j][0], start_poses[j][1], start_poses[j][2]),
                                   m.dl_m.data(), r);
        for (int i = 0; i < M; ++i) {
          if (std::isfinite(r[i])) continue;
          return "; pose " + std::to_string(m.pose_id) + (m.where.empty() ? "" : " (" + m.where + ")") +
                 ": at its laser height and inclinometer angle no position gives cable " + std::to_string(i + 1) +
                 " a valid length on the nominal robot (its anchor inside or past the pulley): check that reading";
        }
      }
    }
    if (n > kMaxPosesLeftOutTest) return "";
    // At least Ceres' default limit: a user's low --max-iterations must not make a good pose
    // look guilty because the fit without it happens to converge sooner.
    const int diagnosis_limit = std::max(options.max_iterations, 100);
    // Named only if the fit without that pose converges with every reading within
    // kOutlierSigmas, the pose's readings are then off against the others' geometry (that pose
    // alone fitted to it), and no other pose is so: with few poses, leaving out any of several
    // poses may let a merely poorly spread set converge, and a clean pose must not be blamed for
    // it (measured on 6-pose Monte Carlo trials). A leave-out may also converge and fit by
    // absorbing the bad reading, and its clean pose then look off against that fit (a new
    // user's robot, 0.3 m at its last pose, pose 1 left out). With two or more such poses, the
    // one whose absence leaves the lowest cost is named if that cost is lower than the next
    // one's by more than kOutlierSigmas^2 / 2 (one reading at the outlier bound).
    int converging = 0, off_poses = 0;
    std::optional<Reading> culprit;
    LeftOut found;
    double found_cost = std::numeric_limits<double>::infinity(), next_cost = found_cost;
    for (int j = 0; j < n; ++j) {
      std::vector<char> use(n, 1);
      use[j] = 0;
      if (!enough_equations(use)) continue;  // too few poses to tell
      double g[kGeometry];
      PoseValues q;
      reset_to_start(g, q);
      const LeastSquaresSummary sum = least_squares(g, q, use, diagnosis_limit);
      if (!converged(sum, g, q, use)) continue;
      // A fit that converges only to readings that do not fit (the bad one still in: a 0.3 m
      // laser error at one of 30 poses let 8 such leave-outs converge, to poor fits, and so
      // hid the one whose absence lets the rest fit) explains nothing.
      if (!beyond(residuals_at(g, q, use, false)).empty()) continue;
      ++converging;
      fit_to_geometry(g, q, j, diagnosis_limit);
      std::vector<char> only(n, 0);
      only[j] = 1;
      const std::vector<Reading> off = beyond(residuals_at(g, q, only, false));
      if (!off.empty()) {
        ++off_poses;
        if (!(sum.final_cost < found_cost)) {
          next_cost = std::min(next_cost, sum.final_cost);
          continue;
        }
        next_cost = found_cost;
        found_cost = sum.final_cost;
        culprit = off.front();
        found.poses = {j};
        std::copy(g, g + kGeometry, found.geometry_values);
        found.pose_values = q;
        found.worst = off;
      }
    }
    // One pose off while several leave-outs converge is what a clean, poorly spread set gives
    // (a 6-pose trial of the paper's study named a clean pose at 11 sigma): not named.
    if (off_poses == 0 || (off_poses == 1 && converging > 1) ||
        !(found_cost + 0.5 * kOutlierSigmas * kOutlierSigmas < next_cost)) {
      return "";
    }
    lost_fit_culprit = found;
    return "; " + std::string(converging == 1 ? "only without pose " : "without pose ") +
           std::to_string(measurements[culprit->reading].pose_id) +
           (converging == 1 ? " do the other poses converge" : " the other poses converge and fit") +
           ", and against their fit its readings are off by " + describe(*culprit, false) +
           (converging == 1 ? "" : " (the others fit best without it)") + ": check that pose";
  };
  const auto why_not_converged = [&]() -> std::string {
    if (!why_not_converged_text) why_not_converged_text = diagnose_lost_fit();
    return *why_not_converged_text;
  };
  const auto not_converged = [&](const LeastSquaresSummary& sum) {
    result.status = IdentifyStatus::kNotConverged;
    result.iterations = sum.iterations;
    const bool at_limit = sum.iterations >= options.max_iterations;
    const std::string why = why_not_converged();
    result.message = "Levenberg-Marquardt did not converge after " + std::to_string(result.iterations) +
                     (result.iterations == 1 ? " iteration: " : " iterations: ") + sum.message +
                     (!why.empty() ? why
                      : at_limit   ? " (a grossly wrong reading can do this, and so can readings of another robot with "
                                     "as many cables: check the readings and the robot file, or raise --max-iterations)"
                                   : " (a grossly wrong reading can do this, and so can readings of another robot with "
                                     "as many cables: check the readings and the robot file)");
    if (robust) result.message += " (the robust fit starts from least squares' fit, or from the fit without the pose named)";
    return result;
  };
  // Least squares lost: a robust loss can still start from the fit without the one pose whose
  // absence lets the rest converge and fit (a 0.3 m laser error at one of 19 poses of a new
  // user's robot: least squares needed 106 iterations, --loss cauchy exited 3 at the default 100).
  // Without such a pose it starts where least squares did.
  const bool least_squares_lost = !converged(summary, geometry, poses, every_pose);
  if (least_squares_lost && !robust) return not_converged(summary);
  if (least_squares_lost && (why_not_converged(), !lost_fit_culprit)) reset_to_start(geometry, poses);
  std::vector<Reading> readings = residuals_at(geometry, poses, every_pose, true);
  std::vector<Reading> tripped = beyond(readings);
  const std::size_t few = std::max<std::size_t>(kFewOutliers, static_cast<std::size_t>(values_per_reading) * num_readings / 20);

  const int expected_null = options.gauge == Gauge::kNone ? 1 : 0;
  // The whitened Jacobian at the solution, in the tangent space (a1x's column is absent when
  // held), by blocks: its rows come in the order the residual blocks were added, one block per
  // pose (its readings one after another), then the prior. Covariance and identifiability from
  // it cost O(n) (identify/schur.h). With a robust loss Ceres scales each row by the square
  // root of its loss weight (apply_loss_function): a down-weighted reading informs less.
  // `residuals`, if given, receives each pose block's residuals in the same row order.
  const auto jacobian_blocks = [&](ceres::Problem& p, bool with_loss, std::vector<Eigen::VectorXd>* residuals) {
    BlockJacobian blocks;
    ceres::Problem::EvaluateOptions eval;
    eval.parameter_blocks.push_back(geometry);
    for (int j = 0; j < n; ++j) eval.parameter_blocks.push_back(poses[j].data());
    ceres::CRSMatrix crs;
    std::vector<double> values;
    p.Evaluate(eval, nullptr, residuals ? &values : nullptr, nullptr, &crs);
    // Ceres rows per reading: the blocks of build() (a zero row for a missing sensor without a
    // loss, none with one).
    const int rows_per_reading = !ml ? M : with_loss ? values_per_reading : M + 2;
    const int pose_rows = rows_per_reading * num_readings + equilibrium_rows * n;
    CABLECAL_CHECK(crs.num_rows == pose_rows + prior_rows && crs.num_cols == geometry_cols + per_pose_unknowns * n,
                   "the Jacobian has one row block per pose and the prior's");
    std::vector<int> block_of_row(pose_rows), row_in_block(pose_rows);
    if (residuals) residuals->clear();
    for (int j = 0, r = 0; j < n; ++j) {
      const int rows = rows_per_reading * static_cast<int>(readings_of[j].size()) + equilibrium_rows;
      if (residuals) residuals->push_back(Eigen::Map<const Eigen::VectorXd>(values.data() + r, rows));
      for (int k = 0; k < rows; ++k, ++r) {
        block_of_row[r] = j;
        row_in_block[r] = k;
      }
      blocks.poses.push_back(
          PoseBlock{Eigen::MatrixXd::Zero(rows, geometry_cols), Eigen::MatrixXd::Zero(rows, per_pose_unknowns)});
    }
    blocks.prior = Eigen::MatrixXd::Zero(prior_rows, geometry_cols);
    for (int r = 0; r < crs.num_rows; ++r) {
      for (int k = crs.rows[r]; k < crs.rows[r + 1]; ++k) {
        const int c = crs.cols[k];
        if (r >= pose_rows) {
          CABLECAL_CHECK(c < geometry_cols, "prior rows touch the geometry only");
          blocks.prior(r - pose_rows, c) = crs.values[k];
          continue;
        }
        const int j = block_of_row[r];
        if (c < geometry_cols) {
          blocks.poses[j].geometry(row_in_block[r], c) = crs.values[k];
        } else {
          const int pose_col = c - geometry_cols - per_pose_unknowns * j;
          CABLECAL_CHECK(pose_col >= 0 && pose_col < per_pose_unknowns, "a pose's rows touch its own unknowns only");
          blocks.poses[j].pose(row_in_block[r], pose_col) = crs.values[k];
        }
      }
    }
    return blocks;
  };

  // Each pose against the fit of the others (schur.h, CheckPosesAgainstTheOthers): a bad
  // reading that least squares absorbed at a pose of high leverage leaves every residual
  // small, yet stands out there (measured: a 0.3 m laser error at a random robot's weakest
  // pose, all residuals under 1 sigma, 37 sigma off in a1z). ml with gauge a1x (under gauge
  // prior, a tracker prior that disagrees with the readings would be blamed on a pose); for a
  // person's result or ahead of a robust loss, not in a plain Monte Carlo trial.
  std::vector<PoseCheck> checks;
  int flagged_pose = -1;  // the pose whose readings stand out most, if beyond kOutlierSigmas
  // Least squares' Jacobian blocks and their analysis, kept for the result's covariance and
  // identifiability when no robust fit follows (the same problem at the same values).
  std::optional<BlockJacobian> ls_blocks;
  std::optional<BlockAnalysis> ls_analysis;
  if (ml && options.gauge == Gauge::kA1x && (options.compute_covariance || robust) && !least_squares_lost) {
    std::vector<Eigen::VectorXd> block_residuals;
    ls_blocks = jacobian_blocks(problem_at_estimate(), false, &block_residuals);
    ls_analysis = AnalyzeBlocks(*ls_blocks, 1e-9);
    if (ls_analysis->null_vectors.empty()) {
      if (const std::optional<BlockCovariance> cov = CovarianceOf(*ls_blocks, *ls_analysis)) {
        checks = CheckPosesAgainstTheOthers(*ls_blocks, *ls_analysis, cov->geometry, block_residuals, kOutlierSigmas);
        double worst = kOutlierSigmas;
        for (int j = 0; j < n; ++j) {
          if (checks[j].deleted_residual_sigmas > worst) {
            worst = checks[j].deleted_residual_sigmas;
            flagged_pose = j;
          }
        }
      }
    }
  }

  // A bad reading at a pose that decides part of the geometry (high leverage) is absorbed by
  // least squares: the estimate moves until that pose fits and other, good, poses do not
  // (measured on the built-in robot: a 0.3 m laser error at one of 20 poses leaves that pose's
  // residuals under 1 sigma and a dozen others' beyond 4.5). Whose readings are bad shows when
  // each pose in turn is left out: the pose whose absence lets the rest fit is the culprit, and
  // its readings against the rest's geometry say which sensor. Greedy, up to kMaxLeftOut poses,
  // a refit per pose and round (warm-started: a few iterations each); skipped beyond
  // kMaxPosesLeftOutTest poses, where the largest residuals are named instead.
  const auto leave_out = [&]() -> std::optional<LeftOut> {
    if (least_squares_lost) return lost_fit_culprit;
    if ((tripped.empty() && flagged_pose < 0) || n > kMaxPosesLeftOutTest) return std::nullopt;
    LeftOut out;
    std::copy(geometry, geometry + kGeometry, out.geometry_values);
    out.pose_values = poses;
    std::vector<char> use = every_pose;
    for (int round = 0; round < kMaxLeftOut; ++round) {
      double best_cost = std::numeric_limits<double>::infinity();
      int best = -1;
      double best_geometry[kGeometry];
      PoseValues best_poses;
      for (int j = 0; j < n; ++j) {
        if (!use[j]) continue;
        use[j] = 0;
        if (enough_equations(use)) {
          double g[kGeometry];
          std::copy(out.geometry_values, out.geometry_values + kGeometry, g);
          PoseValues q = out.pose_values;
          LeastSquaresSummary sum = least_squares(g, q, use, options.max_iterations);
          // Warm-started from a fit that absorbed the bad reading, the refit can stay in that
          // fit's basin and leave a clean pose off (a new user's robot: pose 17's bad laser
          // reading made pose 1 look 112 sigma off; fitted without pose 17 from the nominal
          // start, pose 1 is at 0.8 sigma). Where the warm refit leaves readings off, the
          // nominal start is tried too, and the lower cost kept.
          if (!converged(sum, g, q, use) || !beyond(residuals_at(g, q, use, false)).empty()) {
            double g0[kGeometry];
            PoseValues q0;
            reset_to_start(g0, q0);
            const LeastSquaresSummary sum0 = least_squares(g0, q0, use, options.max_iterations);
            if (converged(sum0, g0, q0, use) && (!converged(sum, g, q, use) || sum0.final_cost < sum.final_cost)) {
              sum = sum0;
              std::copy(g0, g0 + kGeometry, g);
              q = q0;
            }
          }
          if (converged(sum, g, q, use) && sum.final_cost < best_cost) {
            best_cost = sum.final_cost;
            best = j;
            std::copy(g, g + kGeometry, best_geometry);
            best_poses = q;
          }
        }
        use[j] = 1;
      }
      if (best < 0) return std::nullopt;
      use[best] = 0;
      out.poses.push_back(best);
      std::copy(best_geometry, best_geometry + kGeometry, out.geometry_values);
      out.pose_values = best_poses;
      if (beyond(residuals_at(out.geometry_values, out.pose_values, use, false)).empty()) {
        // The rest fit: fit each left-out pose to their geometry alone, and read its residuals.
        std::vector<char> left(n, 0);
        for (const int j : out.poses) {
          left[j] = 1;
          fit_to_geometry(out.geometry_values, out.pose_values, j, options.max_iterations);
        }
        out.worst = beyond(residuals_at(out.geometry_values, out.pose_values, left, false));
        return out;
      }
    }
    return std::nullopt;
  };
  const std::optional<LeftOut> left_out = leave_out();
  // The check against the others is linear: it divides the pose's residual by how much of it
  // the others see, and where they see little (few poses, centimetres of geometry error) the
  // fit's curvature alone can make a clean pose look far off (measured: a 2-cable robot's 5
  // clean poses, one at 98 sigma). A flag stands only if the refit without the pose confirms
  // it: some pose's readings are then beyond kOutlierSigmas against the others' geometry.
  if (tripped.empty() && flagged_pose >= 0 && (!left_out || left_out->worst.empty())) flagged_pose = -1;
  // "7", "7 and 12", "3, 7 and 12"
  const auto left_out_ids = [&](const LeftOut& l) {
    std::string names;
    for (std::size_t k = 0; k < l.poses.size(); ++k) {
      names += (k == 0 ? "" : k + 1 == l.poses.size() ? " and " : ", ") + std::to_string(pose_id_of(l.poses[k]));
    }
    return names;
  };
  const auto explain_left_out = [&](const LeftOut& l) {
    const std::string names = left_out_ids(l);
    std::string worst;
    for (std::size_t k = 0; k < std::min<std::size_t>(3, l.worst.size()); ++k) {
      worst += (k ? ", " : "") + describe(l.worst[k], l.poses.size() > 1);
    }
    return std::string(l.poses.size() == 1 ? "pose " : "poses ") + names + (l.poses.size() == 1 ? " does" : " do") +
           " not fit the others: fitted without " + (l.poses.size() == 1 ? "it" : "them") +
           ", every other reading is within " + FormatDouble(kOutlierSigmas) + " sigma, and " +
           (l.poses.size() == 1 ? "its" : "their") + " readings are then off by " + worst;
  };

  // A robust loss can follow the readings the leave-out test found bad: Huber's never ignores
  // a reading, and Cauchy's, at a pose of high leverage, can settle back on them (a new user's
  // 2-cable robot, 30 poses, one laser reading 0.3 m off: l20 28 sigma from the truth, 29.9
  // sigma from the fit without that pose). An estimate the tool knows is that far from the fit
  // without the poses whose readings do not fit the others is not returned: when it is more
  // than kRobustStraySigmas (of that fit's own sigmas) from it, that fit is the result, the
  // poses named as dropped, their readings reported against it at weight 0.
  constexpr double kRobustStraySigmas = 2.0;
  // The geometric parameter where `a` is furthest from `b` in `sigma` (held ones skipped), if
  // beyond `above` sigmas: its index (-1 if none) and distance in sigmas.
  struct Apart {
    int k = -1;
    double sigmas = 0.0;
  };
  const auto furthest_apart = [&](const double* a, const double* b, const GeometryVector& sigma, double above) {
    Apart worst{-1, above};
    for (int k = 0; k < kGeometry; ++k) {
      if (!(sigma(k) > 0.0)) continue;
      const double sigmas = std::abs(a[k] - b[k]) / sigma(k);
      if (sigmas > worst.sigmas) worst = Apart{k, sigmas};
    }
    return worst;
  };
  const auto fit_without_left_out = [&](const LeftOut& l) -> std::optional<IdentifyResult> {
    std::vector<char> dropped_reading(num_readings, 0);
    for (const int j : l.poses) {
      for (const int k : readings_of[j]) dropped_reading[k] = 1;
    }
    std::vector<Measurement> kept;
    std::vector<int> row_of_kept;  // each kept reading's index in `measurements`
    for (int k = 0; k < num_readings; ++k) {
      if (dropped_reading[k]) continue;
      kept.push_back(measurements[k]);
      row_of_kept.push_back(k);
    }
    IdentifyOptions least_squares_options = options;
    least_squares_options.loss = RobustLoss{};
    least_squares_options.compute_covariance = true;  // its sigmas measure the stray
    IdentifyResult without = IdentifyWithCables<M>(nominal, kept, least_squares_options);
    if (!without.converged() || !without.has_covariance) return std::nullopt;
    const Apart stray = furthest_apart(geometry, without.geometry.data(), without.geometry_std, kRobustStraySigmas);
    if (stray.k < 0) return std::nullopt;
    // The dropped poses' readings against the returned geometry, each pose fitted to it alone.
    double g[kGeometry];
    for (int k = 0; k < kGeometry; ++k) g[k] = without.geometry(k);
    PoseValues q = l.pose_values;
    std::vector<char> left(n, 0);
    for (const int j : l.poses) {
      left[j] = 1;
      fit_to_geometry(g, q, j, options.max_iterations);
    }
    residuals_at(g, q, left, true);  // into result.readings, at the dropped readings' rows
    if (reading_fits) {
      std::vector<ReadingFit> all = std::move(result.readings);
      for (std::size_t i = 0; i < row_of_kept.size(); ++i) all[row_of_kept[i]] = std::move(without.readings[i]);
      for (int k = 0; k < num_readings; ++k) {
        if (!dropped_reading[k]) continue;
        all[k].encoder_weights.setZero();
        all[k].laser_weight = all[k].inclinometer_weight = 0.0;
        all[k].min_detectable_sigmas.resize(0);
      }
      without.readings = std::move(all);
    } else {
      without.readings.clear();
    }
    // One estimate per pose id, as every result has (the Monte Carlo reads x_j of each): a
    // dropped pose's is its fit to the returned geometry alone, without a standard deviation.
    {
      std::vector<PoseEstimate> all;
      all.reserve(n);
      std::size_t next = 0;
      for (int j = 0; j < n; ++j) {
        if (left[j]) {
          PoseEstimate e;
          e.pose_id = pose_id_of(j);
          e.q = Eigen::Vector3d(q[j][0], q[j][1], q[j][2]);
          all.push_back(e);
        } else if (next < without.poses.size()) {
          all.push_back(without.poses[next++]);
        }
      }
      without.poses = std::move(all);
    }
    without.loss = options.loss;
    for (const int j : l.poses) without.dropped_pose_ids.push_back(pose_id_of(j));
    char buffer[96];
    std::snprintf(buffer, sizeof(buffer), "%.3g sigma (%.3g mm in %s)", stray.sigmas,
                  1e3 * std::abs(geometry[stray.k] - without.geometry(stray.k)), geometry_names[stray.k].c_str());
    const bool one = l.poses.size() == 1;
    without.warnings.insert(
        without.warnings.begin(),
        std::string(one ? "pose " : "poses ") + left_out_ids(l) + " dropped: " + explain_left_out(l) + "; the " +
            ToString(options.loss) + " estimate with " + (one ? "it" : "them") + " was " + buffer +
            " from the fit without " + (one ? "it" : "them") + ", which is returned" +
            (options.loss.kind == LossKind::kHuber ? " (Huber's loss never ignores a reading)" : ""));
    return without;
  };

  if (robust) {
    // Start the robust fit where it should end: from the fit without the culprits when least
    // squares found any (a redescending loss such as Cauchy's then stays there; Huber's, which
    // never ignores a reading, may move back toward least squares: warned below).
    if (left_out) {
      std::copy(left_out->geometry_values, left_out->geometry_values + kGeometry, geometry);
      poses = left_out->pose_values;
    }
    problem = build(geometry, poses, every_pose, options.loss);
    summary = from_ceres(solve(*problem, geometry, poses, every_pose, false, options.max_iterations));
    if (!converged(summary, geometry, poses, every_pose)) return not_converged(summary);
    if (left_out && !left_out->worst.empty()) {
      if (std::optional<IdentifyResult> without = fit_without_left_out(*left_out)) return *without;
    }
  }
  result.iterations = summary.iterations;
  result.final_cost = summary.final_cost;
  result.geometry = Eigen::Map<const GeometryVector>(geometry, kGeometry);
  result.status = IdentifyStatus::kConverged;
  if (robust) {
    readings = residuals_at(geometry, poses, every_pose, true);
    tripped = beyond(readings);
  }

  // Under gauge prior, a tracker prior that disagrees with the readings (exit points further
  // from nominal than sensors.tracker.sigma allows) strains every pose alike and shows as
  // readings that do not fit: say that it may be the prior.
  const std::string prior_note =
      options.gauge == Gauge::kPrior
          ? " (with --gauge prior this is also what a tracker prior that disagrees with the readings looks like: "
            "are the exit points within a few sensors.tracker.sigma of the robot file's?)"
      : geometry_prior
          ? " (with --geometry-prior this is also what a nominal geometry further from the real one than the prior's "
            "sigma allows looks like: is " + FormatDouble(prior_sigma_m) + " m too small?)"
          : "";
  // Goodness of fit. With the right model the whitened residuals have RMS near 1 (ml), and
  // the paper estimator's length residuals are of the order of the laser's noise, which
  // z_j carries into them. Ten times that is not noise: the result is flagged, not returned.
  // With a robust loss the readings beyond kOutlierSigmas are the outliers it is there for and
  // the RMS is taken over the others.
  constexpr double kPoorFitFactor = 10.0;
  double fit = result.rms_encoder_m / std::max(s.laser_sigma_m(), s.encoder_sigma_m);
  if (ml) {
    double sum = 0.0;
    int count = 0;
    for (const Reading& r : readings) {
      if (robust && !(r.sigmas <= kOutlierSigmas)) continue;
      sum += r.sigmas * r.sigmas;
      ++count;
    }
    fit = count > 0 ? std::sqrt(sum / count) : std::numeric_limits<double>::infinity();
  }
  if (!(fit <= kPoorFitFactor)) {
    result.status = IdentifyStatus::kPoorFit;
    char buffer[160];
    std::snprintf(buffer, sizeof(buffer),
                  "the residuals are %.3g times the sensors' noise (more than %g): the measurements do not fit "
                  "this robot", fit, kPoorFitFactor);
    // The likely causes a new user hit: dl columns in another order than the robot file's
    // cables ("14.3 times the noise"), readings of another robot with as many cables, units.
    result.message = std::string(buffer) + " (are dl1.." + "dl" + std::to_string(M) +
                     " in the order of the robot file's cables, the readings of this robot, in m and rad?)";
    if (!robust && left_out) result.message += "; " + explain_left_out(*left_out) + "; " + "drop " + (left_out->poses.size() == 1 ? "that pose" : "those poses") + " or identify with --loss cauchy";
    result.message += prior_note;
    return result;
  }

  // Per reading: one bad reading among many hardly moves the global RMS above, yet drags the
  // estimate by many sigma. Every whitened residual beyond kOutlierSigmas refuses the fit,
  // naming the poses left out above or else the worst readings. For clean data a whitened
  // residual is at most N(0, 1) (less, by its leverage), so 200 readings (n = 50) trip 4.5
  // sigma with probability 200 * 6.8e-6 = 0.14 % (measured for 2 cables: 0 of 6000 ml trials,
  // 8 of 2000 paper trials at n = 6 and 28). With the ml estimator and 2 cables a pose has 4
  // readings for its 3 unknowns: one bad reading shows in that pose's residuals along their
  // one redundant direction, so the pose is named reliably but the sensor named may be another
  // of the same pose (more cables give more redundant directions).
  // With a robust loss a few such readings are what it down-weights; many point to wrong
  // units or another robot, which no loss mends.
  const auto refuse_outliers = [&](const std::string& advice_without_note) {
    const std::string advice = advice_without_note + prior_note;
    result.status = IdentifyStatus::kPoorFit;
    if (left_out && !robust) {
      result.message = "readings that do not fit this robot: " + explain_left_out(*left_out) + "; " + advice;
      return;
    }
    if (tripped.empty() && flagged_pose >= 0) {
      char buffer[160];
      std::snprintf(buffer, sizeof(buffer), "pose %d does not fit the others (%.3g sigma against their fit; ",
                    pose_id_of(flagged_pose), checks[flagged_pose].deleted_residual_sigmas);
      result.message = "readings that do not fit this robot: " + std::string(buffer) +
                       "the fit absorbed it, leaving every residual small); " + advice;
      return;
    }
    std::string worst;
    for (std::size_t k = 0; k < std::min<std::size_t>(3, tripped.size()); ++k) {
      worst += (k ? ", " : "") + describe(tripped[k]);
    }
    char buffer[128];
    std::snprintf(buffer, sizeof(buffer), " (%zu reading%s beyond %g sigma)", tripped.size(),
                  tripped.size() == 1 ? "" : "s", kOutlierSigmas);
    result.message = "readings that do not fit this robot: " + worst + buffer + "; " + advice;
  };
  const std::string drop_or_loss =
      std::string("check those readings, drop ") + (left_out && left_out->poses.size() == 1 ? "that pose" : "their poses") +
      ", or identify with --loss cauchy, which down-weights them";
  if (robust) {
    if (tripped.size() > few) {
      refuse_outliers("too many for a robust loss to be trusted: are the readings in the file's units (m, rad), and "
                      "of this robot?");
      return result;
    }
    for (const Reading& r : tripped) {
      char buffer[48];
      std::snprintf(buffer, sizeof(buffer), " (weight %.2g)", LossWeight(options.loss, r.sigmas));
      result.down_weighted.push_back(describe(r) + buffer);
    }
  } else if ((!tripped.empty() || flagged_pose >= 0) && (tripped.size() <= few || left_out)) {
    // A few bad readings explain an implausible estimate better than wrong units do (one
    // inclinometer reading of 0 among 20 poses drags a2x off the frame): name them first.
    refuse_outliers(drop_or_loss);
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
                         "for one; and few or bunched poses may not determine the geometry (plan them with cablecal "
                         "design)";
        return result;
      }
    }
  }

  if (!robust && (!tripped.empty() || flagged_pose >= 0)) {
    refuse_outliers(drop_or_loss);
    return result;
  }

  if (copied_count > 0) {
    std::string list;
    for (std::size_t k = 0; k < copied.size(); ++k) list += (k ? ", " : "") + copied[k];
    if (copied_count > static_cast<int>(copied.size())) list += ", ...";
    result.warnings.push_back(std::to_string(copied_count) + (copied_count == 1 ? " reading is" : " readings are") +
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
  // fewer than one clean experiment in a million.
  if (ml && !robust) {
    const int dof = values_per_reading * num_readings + equilibrium_rows * n - unknowns;
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

  if (!options.compute_identifiability && !options.compute_covariance) return result;

  // The whitened Jacobian at the solution, in the tangent space (a1x's column is absent when
  // held), by blocks: its rows come in the order the residual blocks were added, one block per
  // pose (its readings one after another), then the prior. Covariance and identifiability from
  // it cost O(n) (identify/schur.h). With a robust loss Ceres scales each row by the square
  // root of its loss weight (apply_loss_function): a down-weighted reading informs less.
  const bool reuse = !robust && ls_blocks.has_value();
  const BlockJacobian blocks = reuse ? std::move(*ls_blocks) : jacobian_blocks(problem_at_estimate(), robust, nullptr);
  // A null direction: singular value below 1e-9 of the largest (rounding, not data).
  const BlockAnalysis analysis = reuse ? std::move(*ls_analysis) : AnalyzeBlocks(blocks, 1e-9);

  if (options.compute_identifiability) {
    Identifiability& id = result.identifiability;
    for (int k = (options.gauge == Gauge::kA1x ? 1 : 0); k < kGeometry; ++k) {
      id.geometry_names.push_back(geometry_names[k]);
    }
    id.names = id.geometry_names;
    for (int j = 0; j < n; ++j) {
      const std::string p = std::to_string(pose_id_of(j));
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
      id.weakest_pose_id = pose_id_of(analysis.weakest_pose);
      id.weakest_pose_singular_value = analysis.poses[analysis.weakest_pose].min_singular_value;
    }
    for (Eigen::VectorXd v : analysis.null_vectors) {
      Eigen::Index big;
      v.cwiseAbs().maxCoeff(&big);
      if (v(big) < 0) v = -v;
      std::string text;
      int terms = 0, more = 0;
      for (int c = 0; c < v.size(); ++c) {
        if (std::abs(v(c)) < 1e-6) continue;
        if (++terms > 12) {  // a direction through every pose would list them all
          ++more;
          continue;
        }
        text += (text.empty() ? "" : (v(c) < 0 ? " - " : " + ")) +
                internal::FormatCoefficient(text.empty() ? v(c) : std::abs(v(c))) + " " + id.names[c];
      }
      if (more > 0) text += " ... (" + std::to_string(more) + " more terms)";
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
      if (!missing_text.empty()) {
        result.message += " (the data have " + missing_text + ")";
        if (!laser && options.gauge != Gauge::kPrior) result.message += "; a tracker prior on the exit points fixes the heights: --gauge prior";
      }
      return result;
    }
  }

  if (options.compute_covariance && static_cast<int>(analysis.null_vectors.size()) == expected_null) {
    // gauge none: the Moore-Penrose pseudo-inverse (identify/schur.h).
    if (std::optional<BlockCovariance> cov = CovarianceOf(blocks, analysis)) {
      double scale = 1.0;
      if (!ml && expected_null == 0) {
        // paper: its residuals f_ij = l_model^2 - (dl_ij + l_i0)^2 take z and theta as exact,
        // yet the laser's and inclinometer's noise enters them through l_model, with the
        // encoder's through dl_ij. The sandwich propagates all three: per reading,
        // Sigma = diag(2 (dl + l0) sigma_enc)^2 + sigma_z^2 b_z b_z^T + sigma_theta^2 b_th b_th^T,
        // b = 2 l_model dl_model/d(z, theta) (schur.h, SandwichCovariance).
        using Jet2 = ceres::Jet<double, 2>;
        Jet2 geometry_jets[kGeometry];
        for (int k = 0; k < kGeometry; ++k) geometry_jets[k] = Jet2(geometry[k]);
        std::vector<Eigen::MatrixXd> sigma(n);
        for (int j = 0; j < n; ++j) {
          const int count = static_cast<int>(readings_of[j].size());
          sigma[j] = Eigen::MatrixXd::Zero(M * count, M * count);
          for (int c = 0; c < count; ++c) {
            const Measurement& m = measurements[readings_of[j][c]];
            Jet2 r[M];
            LengthResiduals<M, Jet2>(nominal, geometry_jets,
                                     Pose<Jet2>(Jet2(poses[j][0]), Jet2(m.z_m, 0), Jet2(m.theta_rad, 1)),
                                     m.dl_m.data(), r);
            Eigen::Matrix<double, M, 1> b_z, b_theta, encoder;
            for (int i = 0; i < M; ++i) {
              const double measured = m.dl_m(i) + geometry[2 * M + i];
              const double model = r[i].a + measured;
              b_z(i) = 2.0 * model * r[i].v(0);
              b_theta(i) = 2.0 * model * r[i].v(1);
              encoder(i) = 2.0 * measured * s.encoder_sigma_m;
            }
            sigma[j].block<M, M>(M * c, M * c) = Eigen::Matrix<double, M, M>(encoder.cwiseAbs2().asDiagonal()) +
                                                   s.laser_sigma_m() * s.laser_sigma_m() * b_z * b_z.transpose() +
                                                   s.inclinometer_sigma_rad() * s.inclinometer_sigma_rad() * b_theta *
                                                       b_theta.transpose();
          }
        }
        cov = SandwichCovariance(blocks, analysis, *cov, sigma);
      } else if (!ml) {
        // gauge none: the covariance scaled by the residual variance s^2 (conservative: the
        // sandwich above is not taken through the pseudo-inverse).
        // Ceres' rows and tangent-space unknowns of this problem (M rows per reading, no prior
        // under gauge none, 3M + n unknowns).
        const int dof = M * num_readings - (kGeometry + n - expected_null);
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
      // A geometry the poses hardly determine is a result, but not one to use: say so, naming
      // the worst-determined parameter (a new user's 5 random poses gave sigmas of kilometres
      // and nothing said so). 0.1 m: far beyond any calibration's aim, far below such sigmas.
      constexpr double kUndetermined_m = 0.1;
      Eigen::Index worst = 0;
      const double worst_std = result.geometry_std.maxCoeff(&worst);
      if (worst_std > kUndetermined_m) {
        char buffer[160];
        std::snprintf(buffer, sizeof(buffer), "the poses hardly determine the geometry: the standard deviation of %s is "
                      "%.3g m", geometry_names[worst].c_str(), worst_std);
        result.warnings.push_back(std::string(buffer) + "; add poses, or plan better-spread ones (cablecal design)");
      }
      // With a geometry prior the result is never less informed than the prior, but it may be
      // hardly more: say which parameters the data leave nearly where the prior had them
      // (the posterior keeps more than half the prior's variance).
      if (geometry_prior) {
        std::string little;
        int count = 0;
        for (int k = 0; k < kGeometry; ++k) {
          if (!(result.geometry_std(k) > kDataAddLittle * prior_sigma_m)) continue;
          if (++count <= 4) {
            char buffer[64];
            std::snprintf(buffer, sizeof(buffer), "%s%s (%.3g mm)", count > 1 ? ", " : "", geometry_names[k].c_str(),
                          1e3 * result.geometry_std(k));
            little += buffer;
          }
        }
        if (count > 4) little += ", ...";
        if (count > 0) {
          result.data_add_little = count;
          result.warnings.push_back(
              "the data add little to the geometry prior (" + FormatDouble(1e3 * prior_sigma_m) +
              " mm) for " + std::to_string(count) + " of " + std::to_string(geometry_cols) + " parameters: " + little +
              "; they are known about as well as before measuring: add poses, or plan ones that see them (cablecal design)");
        }
      }
    }
  }
  // How well the others check each reading (least squares only: the checks are of its fit).
  if (!robust && !checks.empty() && !result.readings.empty()) {
    for (int j = 0; j < n; ++j) {
      for (std::size_t c = 0; c < readings_of[j].size(); ++c) {
        result.readings[readings_of[j][c]].min_detectable_sigmas =
            checks[j].min_detectable_sigmas.segment(static_cast<Eigen::Index>(c) * (M + 2), M + 2);
      }
    }
  }
  // Huber's loss never ignores a reading: at a pose of high leverage it can pull the estimate
  // back toward least squares' (measured on the built-in robot with a 0.3 m laser error). Say
  // so when its estimate strays from the fit without the poses found above.
  // The parameter furthest from that fit, in its sigmas, is named.
  if (robust && left_out && result.has_covariance) {
    const Apart stray =
        furthest_apart(result.geometry.data(), left_out->geometry_values, result.geometry_std, kRobustStraySigmas);
    if (stray.k >= 0) {
      const int worst = stray.k;
      char buffer[96];
      std::snprintf(buffer, sizeof(buffer), "%.3g mm (%.3g sigma)",
                    1e3 * std::abs(result.geometry(worst) - left_out->geometry_values[worst]), stray.sigmas);
      result.warnings.push_back("the " + ToString(options.loss) + " estimate of " + geometry_names[worst] + " is " +
                                buffer + " from the fit without pose " + left_out_ids(*left_out) +
                                " (readings that do not fit the others): " +
                                (options.loss.kind == LossKind::kHuber
                                     ? "Huber's loss never ignores a reading and follows them; --loss cauchy rejects them"
                                     : "a smaller scale rejects them sooner"));
    }
  }
  return result;
}

}  // namespace cablecal::internal
