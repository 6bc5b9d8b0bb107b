// Internal to identify/: the identification problem of a robot of M cables, the part every
// other part of the identification reads. It holds the readings grouped by pose, which sensors
// the data have, the weights that whiten them, the priors, the start, and the counts of
// equations and unknowns; it checks the options against the data on construction (an
// InputError names what is wrong) and offers what the driver (identify_cables.h), the
// diagnostics (diagnostics.h) and the uncertainty (uncertainty.h) do with the problem: build
// Ceres' problem over a subset of poses, solve by least squares, every reading's whitened
// residual, and the whitened Jacobian by blocks. Depends on residuals.h, cost_functors.h,
// least_squares.h (its own Levenberg-Marquardt) and schur.h (the block structure).
#pragma once

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "common/error.h"
#include "common/format.h"
#include "identify/cost_functors.h"
#include "identify/identify.h"
#include "identify/least_squares.h"
#include "identify/residuals.h"
#include "identify/schur.h"
#include "model/geometry.h"
#include "model/kind.h"
#include "model/sensors.h"

namespace cablecal::internal {

// Ceres' Levenberg-Marquardt with the identification's settings (least_squares.h).
inline void ApplyLevenbergMarquardt(ceres::Solver::Options* options) {
  constexpr LevenbergMarquardtSettings kSettings;
  options->minimizer_type = ceres::TRUST_REGION;
  options->trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  options->function_tolerance = kSettings.function_tolerance;
  options->gradient_tolerance = kSettings.gradient_tolerance;
  options->parameter_tolerance = kSettings.parameter_tolerance;
  options->initial_trust_region_radius = kSettings.initial_trust_region_radius;
}

template <int M>
PlanarPose StartingPose(const Robot& robot, const GeometryVector& g, const Measurement& m);

// One reading's whitened residual, |r| / sigma.
struct Reading {
  double sigmas;
  int reading;  // index into measurements
  int sensor;   // 0 .. M - 1: encoders; M + k: kPlanarSensors[k]; M + kNumPlanarSensors: the pose's equilibrium
};

// The readings beyond kOutlierSigmas, the largest first.
inline std::vector<Reading> Beyond(const std::vector<Reading>& readings) {
  std::vector<Reading> out;
  for (const Reading& r : readings) {
    if (!(r.sigmas <= kOutlierSigmas)) out.push_back(r);
  }
  std::sort(out.begin(), out.end(), [](const Reading& a, const Reading& b) { return a.sigmas > b.sigmas; });
  return out;
}

using PoseValues = std::vector<PlanarPoseValues>;

template <int M>
struct IdentificationProblem {
  static constexpr GeometryLayout kLayout = PlanarLayout(M);
  static constexpr int kGeometry = kLayout.size();
  static constexpr int kPose = PlanarKind::kPoseDim;

  const Robot& nominal;
  const std::vector<Measurement>& measurements;
  const IdentifyOptions& options;
  const SensorNoise& s;
  bool ml = true;
  bool robust = false;
  int num_readings = 0;

  // The sensors the data have, by SensorId: one set for every reading (a file's columns).
  std::array<bool, kNumSensorIds> present{};
  std::vector<std::string> missing_sensors;
  std::string missing_text;

  // Repeated readings of one pose share its unknowns: readings_of[j] lists pose j's readings
  // (indices into measurements), poses in the order of their first reading.
  std::vector<std::vector<int>> readings_of;
  int n = 0;

  // Readings identical in every value to another pose's: copied rows (the first three named).
  std::vector<std::string> copied;
  int copied_count = 0;

  // The geometry entries the gauge holds at their nominal values (PlanarKind::HeldByDefault
  // under gauge a1x; none under prior or none), in increasing order: no unknowns.
  std::vector<int> held;
  bool IsHeld(int k) const { return std::find(held.begin(), held.end(), k) != held.end(); }

  // Equations and unknowns (paper, Eq. 7; the gauge removes the held entries).
  int per_pose_unknowns = PlanarKind::kPoseDim;
  int values_per_reading = M + kNumPlanarSensors;
  bool geometry_prior = false;
  double prior_sigma_m = 0.0;
  int geometry_cols = kGeometry;  // the tangent space's: a held entry has no column
  int equilibrium_rows = 0;       // per pose
  int prior_rows = 0;             // Ceres' rows of the prior blocks
  int prior_equations = 0;        // the equations they add (a held entry's row is zero)
  int equations = 0, unknowns = 0;

  GeometryVector nominal_geometry;
  std::vector<std::string> geometry_names;
  Eigen::Matrix<double, kGeometry, 1> prior_inv_sigma = Eigen::Matrix<double, kGeometry, 1>::Zero();
  PoseValues start_poses;
  ReadingWeights weights;
  double length_sigma = 1.0;  // the encoder's (ml); the paper's residuals' scale otherwise
  // The per-reading ReadingFits are for a person (the CLI, Python); the Monte Carlo, which asks
  // for neither covariance nor identifiability, is spared their allocations.
  bool reading_fits = false;
  MlLeastSquaresProblem<M> ml_problem;

  // Checks the options against the data and the robot file (InputError naming the flag, the
  // file or the key), in the order a user would fix them.
  IdentificationProblem(const Robot& nominal_robot, const std::vector<Measurement>& readings,
                        const IdentifyOptions& identify_options);
  IdentificationProblem(const IdentificationProblem&) = delete;
  // The constructor's steps, in this order.
  void CheckOptions();
  void GroupReadings();
  void CountEquations();
  void SetUpPriorsStartAndWeights();

  IdentificationProblem& operator=(const IdentificationProblem&) = delete;

  int pose_id_of(int j) const { return measurements[readings_of[j].front()].pose_id; }

  // The identification's start: the nominal geometry and each pose's StartingPose.
  void ResetToStart(double* g, PoseValues& q) const {
    for (int k = 0; k < kGeometry; ++k) g[k] = nominal_geometry(k);
    q = start_poses;
  }

  // Ceres' problem over the poses in `use` at the values in `g` and `q`, each reading's blocks
  // with `loss_kind` (the problem owns its loss function).
  std::unique_ptr<ceres::Problem> Build(double* g, PoseValues& q, const std::vector<char>& use,
                                        const RobustLoss& loss_kind) const;
  // Levenberg-Marquardt with Ceres; with the geometry held (one pose fitted to it alone) a plain QR step.
  ceres::Solver::Summary SolveWithCeres(ceres::Problem& problem, double* g, PoseValues& q, const std::vector<char>& use,
                                        bool hold_geometry, int max_iterations) const;
  // Least squares over the poses in `use`: for ml the block-arrow Levenberg-Marquardt written
  // for it (least_squares.h: the same iterations as Ceres', without its set-up, which was half
  // of every Monte Carlo trial's solve), for the paper's estimator Ceres.
  LeastSquaresSummary LeastSquares(double* g, PoseValues& q, const std::vector<char>& use, int max_iterations) const;
  // The poses in `use` alone have enough equations for their unknowns and the geometry's.
  bool EnoughEquations(const std::vector<char>& use) const;
  // Pose j alone fitted to the geometry g (held), from q[j].
  void FitToGeometry(double* g, PoseValues& q, int j, int max_iterations) const;
  // Converged, with every value finite.
  bool Converged(const LeastSquaresSummary& sum, const double* g, const PoseValues& q, const std::vector<char>& use) const;
  // Every reading's whitened residual at (g, q) (ml: each value over its sigma; paper: each
  // length residual over the length sigma of the global test), for the readings of the poses
  // in `use`; with `fits`, also the per-pose estimates, ReadingFits and RMS into it.
  std::vector<Reading> ResidualsAt(const double* g, const PoseValues& q, const std::vector<char>& use,
                                   IdentifyResult* fits) const;
  // "pose 7: laser 199 sigma", with the reading's line when the pose has several.
  std::string Describe(const Reading& r, bool with_pose = true) const;
  // The whitened Jacobian at (g, q), in the tangent space (a1x's column is absent when held),
  // by blocks: its rows come in the order the residual blocks were added, one block per pose
  // (its readings one after another), then the prior. With a robust loss Ceres scales each row
  // by the square root of its loss weight (apply_loss_function): a down-weighted reading
  // informs less. `residuals`, if given, receives each pose block's residuals in the same order.
  BlockJacobian JacobianBlocks(ceres::Problem& p, double* g, PoseValues& q, bool with_loss,
                               std::vector<Eigen::VectorXd>* residuals) const;
};

inline LeastSquaresSummary FromCeres(const ceres::Solver::Summary& sum) {
  LeastSquaresSummary out;
  out.converged = sum.termination_type == ceres::CONVERGENCE;
  out.iterations = static_cast<int>(sum.iterations.size()) - 1;
  out.final_cost = sum.final_cost;
  // Ceres' own words for its iteration limit repeat the count the caller gives.
  out.message = sum.termination_type == ceres::NO_CONVERGENCE ? "the iteration limit was reached" : sum.message;
  return out;
}

template <int M>
IdentificationProblem<M>::IdentificationProblem(const Robot& nominal_robot, const std::vector<Measurement>& readings,
                                                const IdentifyOptions& identify_options)
    : nominal(nominal_robot), measurements(readings), options(identify_options), s(nominal_robot.sensors) {
  CheckOptions();
  GroupReadings();
  CountEquations();
  SetUpPriorsStartAndWeights();
}

// The sensors the data have, and the options they allow.
template <int M>
void IdentificationProblem<M>::CheckOptions() {
  ml = options.estimator == Estimator::kMaximumLikelihood;
  robust = options.loss.kind != LossKind::kNone;
  num_readings = static_cast<int>(measurements.size());

  present.fill(true);
  if (num_readings > 0) present = measurements.front().sensors();
  for (const Measurement& m : measurements) {
    if (m.sensors() != present) {
      std::string which;  // "laser (z) or inclinometer (theta)"
      for (const SensorUnit& u : kPlanarSensors) {
        which += std::string(which.empty() ? "" : " or ") + u.name + " (" + u.column + ")";
      }
      throw InputError(options.source, "",
                       "some readings have a " + which + " value and others not: give every reading the same sensors");
    }
  }
  for (const SensorUnit& u : kPlanarSensors) {
    if (!present[static_cast<int>(u.id)]) missing_sensors.push_back(u.name);
  }
  missing_text = MissingSensorsText(missing_sensors);
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
  // A new user's trial: paper with the tracker prior returned the file's exit points to 1e-9 m,
  // 24 sigma from the truth, with no warning.
  if (options.gauge == Gauge::kPrior && !ml) throw InputError("--gauge prior", "", "needs --estimator ml: the paper estimator's residuals are not in sigmas, so the tracker's prior, in sigmas, would outweigh every reading (the exits would stay at the robot file's)");
  if (options.geometry_prior_sigma_m &&
      !(*options.geometry_prior_sigma_m >= kMinGeometryPriorSigma_m && *options.geometry_prior_sigma_m <= kMaxGeometryPriorSigma_m)) {
    throw InputError("--geometry-prior", "",
                     "must be between " + FormatDouble(kMinGeometryPriorSigma_m) + " and " +
                         FormatDouble(kMaxGeometryPriorSigma_m) + " m (the standard deviation of the nominal geometry), not " +
                         FormatDouble(*options.geometry_prior_sigma_m));
  }
  if (options.equilibrium && (!ml || EquilibriumRows(M) == 0)) {
    throw InputError("--equilibrium", "",
                     !ml ? std::string("needs --estimator ml (the paper estimator fixes theta at the inclinometer's reading)")
                         : "applies to robots with fewer cables than the pose's 3 degrees of freedom (2 cables): with " +
                               std::to_string(M) + " the cables hold theta, and there is no equilibrium row to add");
  }

}

// Repeated readings of one pose share its unknowns; copied readings are noted.
template <int M>
void IdentificationProblem<M>::GroupReadings() {
  {
    std::map<int, int> index_of;
    for (int k = 0; k < num_readings; ++k) {
      const auto [it, inserted] = index_of.emplace(measurements[k].pose_id, static_cast<int>(readings_of.size()));
      if (inserted) readings_of.emplace_back();
      readings_of[it->second].push_back(k);
    }
  }
  n = static_cast<int>(readings_of.size());
  // Two poses never read alike to the last digit (every sensor has noise): a reading identical
  // in every value to another pose's is a copied row, and counts that pose's information twice
  // (a new user's 5 poses copied under 30 ids fitted exactly, 172 mm off, and nothing said so).
  {
    std::map<std::vector<double>, int> first_with;
    for (int k = 0; k < num_readings; ++k) {
      const Measurement& m = measurements[k];
      std::vector<double> key(m.dl_m.data(), m.dl_m.data() + m.dl_m.size());
      for (const SensorUnit& u : kPlanarSensors) key.push_back(m.value(u.id));
      const auto [it, inserted] = first_with.emplace(std::move(key), k);
      if (inserted || measurements[it->second].pose_id == m.pose_id) continue;
      ++copied_count;
      const auto name = [](const Measurement& r) {
        return "pose " + std::to_string(r.pose_id) + (r.where.empty() ? "" : " (" + r.where + ")");
      };
      if (copied.size() < 3) copied.push_back(name(m) + " = " + name(measurements[it->second]));
    }
  }

}

// Enough equations for the unknowns, and sigmas for every sensor read (InputError otherwise).
template <int M>
void IdentificationProblem<M>::CountEquations() {
  // Enough equations for the unknowns: per reading M encoder values, plus each sensor's the
  // data have, for ml; per pose 3 unknowns (ml) or 1 (paper); 3M geometric unknowns, 3M - 1
  // with a1x held; the tracker prior adds 2M equations, the geometry prior one per geometric
  // unknown (any pose count is then determined). Repeated readings add equations, not
  // information on other poses: the rank test judges them.
  per_pose_unknowns = ml ? PlanarKind::kPoseDim : 1;
  values_per_reading = M;
  for (const SensorUnit& u : kPlanarSensors) values_per_reading += ml && present[static_cast<int>(u.id)] ? 1 : 0;
  geometry_prior = options.geometry_prior_sigma_m.has_value();
  prior_sigma_m = options.geometry_prior_sigma_m.value_or(0.0);
  if (options.gauge == Gauge::kA1x) held = PlanarKind::HeldByDefault(kLayout);
  geometry_cols = kGeometry - static_cast<int>(held.size());
  // ml with fewer cables than the pose's 3 DoF: each pose's static equilibrium, 3 - M rows of its
  // block (residuals.h, MlEquilibriumResidual), whatever the number of its readings.
  equilibrium_rows = ml && options.equilibrium ? EquilibriumRows(M) : 0;
  // Ceres' prior rows (GeometryPriorCost: all 3M; ExitPointPriorCost: the exits).
  prior_rows = geometry_prior ? kGeometry : options.gauge == Gauge::kPrior ? kLayout.exit_coordinates() : 0;
  prior_equations = geometry_prior ? geometry_cols : prior_rows;
  equations = values_per_reading * num_readings + equilibrium_rows * n + prior_equations;
  unknowns = geometry_cols + per_pose_unknowns * n;
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
    for (const SensorUnit& u : kPlanarSensors) {
      if (present[static_cast<int>(u.id)] && !(u.sigma(s) > 0.0)) {
        throw InputError(nominal.source, std::string("sensors.") + u.name,
                         "accuracy or repeatability must be > 0 for the ml estimator");
      }
    }
  }
  if (options.gauge == Gauge::kPrior && !s.tracker_sigma_m) {
    throw InputError(nominal.source, "sensors.tracker.sigma", "is needed for --gauge prior");
  }

}

// The nominal start, the priors' inverse sigmas and the readings' weights.
template <int M>
void IdentificationProblem<M>::SetUpPriorsStartAndWeights() {
  nominal_geometry = GeometryOf(nominal);
  geometry_names = kLayout.names();
  // The priors' inverse sigma per geometric coordinate: the tracker's on the exit points
  // (gauge prior) and the geometry prior's on every one, combined as independent Gaussians
  // about the same nominal value (their precisions add); 0 where there is none.
  {
    Eigen::Matrix<double, kGeometry, 1> precision = Eigen::Matrix<double, kGeometry, 1>::Zero();
    if (options.gauge == Gauge::kPrior) {
      precision.template head<kLayout.exit_coordinates()>().setConstant(1.0 / (*s.tracker_sigma_m * *s.tracker_sigma_m));
    }
    if (geometry_prior) precision.array() += 1.0 / (prior_sigma_m * prior_sigma_m);
    prior_inv_sigma = precision.cwiseSqrt();
  }
  start_poses.resize(n);
  for (int j = 0; j < n; ++j) {
    const PlanarPose start = StartingPose<M>(nominal, nominal_geometry, measurements[readings_of[j].front()]);
    start_poses[j] = {start(0), start(1), start(2)};
  }

  weights = ml ? WeightsOf(s) : ReadingWeights{};
  // No reading, no weight: its row stays in the block (the same block shapes) but is zero.
  for (int k = 0; k < kNumSensorIds; ++k) {
    if (!present[k]) weights.inv_sigma_sensor[k] = 0.0;
  }
  if (equilibrium_rows > 0) weights.inv_sigma_equilibrium = 1.0 / EquilibriumSigma(nominal);
  length_sigma = ml ? s.encoder_sigma_m : std::max(s.laser_sigma_m(), s.encoder_sigma_m);
  reading_fits = options.compute_covariance || options.compute_identifiability;

  ml_problem.robot = &nominal;
  ml_problem.measurements = &measurements;
  ml_problem.readings_of = &readings_of;
  ml_problem.weights = weights;
  ml_problem.held = held;
  ml_problem.prior_geometry = nominal_geometry;
  ml_problem.prior_inv_sigma = prior_inv_sigma;
}

template <int M>
std::unique_ptr<ceres::Problem> IdentificationProblem<M>::Build(double* g, PoseValues& q, const std::vector<char>& use,
                                                               const RobustLoss& loss_kind) const {
  auto problem = std::make_unique<ceres::Problem>();
  problem->AddParameterBlock(g, kGeometry);
  if (!held.empty()) problem->SetManifold(g, new ceres::SubsetManifold(kGeometry, held));
  ceres::LossFunction* loss = nullptr;  // shared by every reading's block
  if (loss_kind.kind == LossKind::kHuber) loss = new ceres::HuberLoss(loss_kind.scale_sigmas);
  if (loss_kind.kind == LossKind::kCauchy) loss = new ceres::CauchyLoss(loss_kind.scale_sigmas);
  for (int j = 0; j < n; ++j) {
    if (!use[j]) continue;
    for (const int k : readings_of[j]) {
      const PoseReadings<M> readings = ReadingsOf<M>(measurements[k]);
      if (ml && loss) {
        for (int i = 0; i < M; ++i) {
          problem->AddResidualBlock(new ceres::AutoDiffCostFunction<MlCableCost<M>, 1, kGeometry, kPose>(
                                        new MlCableCost<M>{&nominal, readings, weights, i}),
                                    loss, g, q[j].data());
        }
        for (int sensor = 0; sensor < kNumPlanarSensors; ++sensor) {
          if (!present[static_cast<int>(kPlanarSensors[sensor].id)]) continue;
          problem->AddResidualBlock(new ceres::AutoDiffCostFunction<MlOneSensorCost<M>, 1, kPose>(
                                        new MlOneSensorCost<M>{readings, weights, sensor}),
                                    loss, q[j].data());
        }
      } else if (ml) {
        auto* lengths = new ceres::AutoDiffCostFunction<MlLengthCost<M>, M, kGeometry, kPose>(
            new MlLengthCost<M>{&nominal, readings, weights});
        problem->AddResidualBlock(lengths, nullptr, g, q[j].data());
        auto* sensors = new ceres::AutoDiffCostFunction<MlSensorCost<M>, kNumPlanarSensors, kPose>(
            new MlSensorCost<M>{readings, weights});
        problem->AddResidualBlock(sensors, nullptr, q[j].data());
      } else {
        auto* cost = new ceres::AutoDiffCostFunction<PaperPoseCost<M>, M, kGeometry, 1>(
            new PaperPoseCost<M>{&nominal, readings});
        problem->AddResidualBlock(cost, nullptr, g, q[j].data());
      }
    }
    if constexpr (EquilibriumRows(M) > 0) {
      if (equilibrium_rows > 0) {  // after the pose's readings: the last row of its block
        problem->AddResidualBlock(new ceres::AutoDiffCostFunction<MlEquilibriumCost<M>, 1, kGeometry, kPose>(
                                      new MlEquilibriumCost<M>{&nominal, weights}),
                                  nullptr, g, q[j].data());
      }
    }
  }
  if (geometry_prior) {
    auto* prior = new ceres::AutoDiffCostFunction<GeometryPriorCost<M>, kGeometry, kGeometry>(
        new GeometryPriorCost<M>{nominal_geometry, prior_inv_sigma});
    problem->AddResidualBlock(prior, nullptr, g);
  } else if (options.gauge == Gauge::kPrior) {
    constexpr int kExits = kLayout.exit_coordinates();
    auto* prior = new ceres::AutoDiffCostFunction<ExitPointPriorCost<M>, kExits, kGeometry>(
        new ExitPointPriorCost<M>{nominal_geometry.template head<kExits>(), 1.0 / *s.tracker_sigma_m});
    problem->AddResidualBlock(prior, nullptr, g);
  }
  return problem;
}

template <int M>
ceres::Solver::Summary IdentificationProblem<M>::SolveWithCeres(ceres::Problem& problem, double* g, PoseValues& q,
                                                                const std::vector<char>& use, bool hold_geometry,
                                                                int max_iterations) const {
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
  ApplyLevenbergMarquardt(&solver_options);
  solver_options.max_num_iterations = max_iterations;
  solver_options.num_threads = 1;  // parallelism is over Monte Carlo trials, not inside one solve
  solver_options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(solver_options, &problem, &summary);
  return summary;
}

template <int M>
LeastSquaresSummary IdentificationProblem<M>::LeastSquares(double* g, PoseValues& q, const std::vector<char>& use,
                                                          int max_iterations) const {
  if (ml) {
    MlLeastSquaresProblem<M> limited = ml_problem;
    limited.max_iterations = max_iterations;
    return SolveMlLeastSquares<M>(limited, g, q, use);
  }
  std::unique_ptr<ceres::Problem> p = Build(g, q, use, RobustLoss{});
  return FromCeres(SolveWithCeres(*p, g, q, use, false, max_iterations));
}

template <int M>
bool IdentificationProblem<M>::EnoughEquations(const std::vector<char>& use) const {
  int values = 0, poses_used = 0;
  for (int p = 0; p < n; ++p) {
    if (!use[p]) continue;
    ++poses_used;
    values += values_per_reading * static_cast<int>(readings_of[p].size()) + equilibrium_rows;
  }
  return values + prior_equations >= geometry_cols + per_pose_unknowns * poses_used;
}

template <int M>
void IdentificationProblem<M>::FitToGeometry(double* g, PoseValues& q, int j, int max_iterations) const {
  std::vector<char> only(n, 0);
  only[j] = 1;
  std::unique_ptr<ceres::Problem> alone = Build(g, q, only, RobustLoss{});
  SolveWithCeres(*alone, g, q, only, true, max_iterations);
}

template <int M>
bool IdentificationProblem<M>::Converged(const LeastSquaresSummary& sum, const double* g, const PoseValues& q,
                                         const std::vector<char>& use) const {
  bool ok = sum.converged;
  for (int k = 0; k < kGeometry; ++k) ok = ok && std::isfinite(g[k]);
  for (int j = 0; j < n; ++j) {
    ok = ok && (!use[j] || (std::isfinite(q[j][0]) && std::isfinite(q[j][1]) && std::isfinite(q[j][2])));
  }
  return ok;
}

template <int M>
std::vector<Reading> IdentificationProblem<M>::ResidualsAt(const double* g, const PoseValues& q,
                                                           const std::vector<char>& use, IdentifyResult* fits) const {
  std::vector<Reading> readings;
  readings.reserve(static_cast<std::size_t>(values_per_reading) * num_readings);
  double sum_enc = 0.0;
  std::array<double, kNumSensorIds> sum_sensor{};
  const bool keep_fits = fits && reading_fits;
  if (fits) {
    fits->readings.assign(keep_fits ? num_readings : 0, ReadingFit{});
    fits->poses.clear();
  }
  for (int j = 0; j < n; ++j) {
    if (!use[j]) continue;
    PoseEstimate e;
    e.pose_id = pose_id_of(j);
    if (ml) {
      e.q = PlanarPose(q[j].data());
    } else {  // z and theta as measured: their mean over the pose's readings
      e.q = PlanarPose(q[j][0], 0.0, 0.0);
      for (const int k : readings_of[j]) {
        e.q.tail<2>() += Eigen::Vector2d(measurements[k].value(SensorId::kLaser), measurements[k].value(SensorId::kInclinometer));
      }
      e.q.tail<2>() /= static_cast<double>(readings_of[j].size());
    }
    for (const int k : readings_of[j]) {
      const Measurement& m = measurements[k];
      const PlanarPose q_k =
          ml ? e.q : PlanarPose(q[j][0], m.value(SensorId::kLaser), m.value(SensorId::kInclinometer));
      double length_residuals[M];
      LengthResiduals<M, double>(nominal, g, q_k, m.dl_m.data(), length_residuals);
      for (int i = 0; i < M; ++i) {
        sum_enc += length_residuals[i] * length_residuals[i];
        readings.push_back({std::abs(length_residuals[i]) / length_sigma, k, i});
      }
      std::array<double, kNumSensorIds> sensor_sigmas{};
      for (int u = 0; u < kNumPlanarSensors; ++u) {
        const SensorUnit& unit = kPlanarSensors[u];
        const int id = static_cast<int>(unit.id);
        const double r = unit.Residual(q_k.data(), m.value(unit.id));
        sensor_sigmas[id] = r / unit.sigma(s);
        if (!ml || !present[id]) continue;
        sum_sensor[id] += r * r;
        readings.push_back({std::abs(sensor_sigmas[id]), k, M + u});
      }
      if (!keep_fits) continue;
      ReadingFit& fit = fits->readings[k];
      fit.pose_id = m.pose_id;
      fit.where = m.where;
      fit.encoder_sigmas = Eigen::Map<const Eigen::Matrix<double, M, 1>>(length_residuals) / length_sigma;
      fit.encoder_weights = fit.encoder_sigmas.unaryExpr([&](double r) { return LossWeight(options.loss, r); });
      for (int id = 0; id < kNumSensorIds; ++id) {
        if (!ml || !present[id]) continue;
        fit.sensor_sigmas[id] = sensor_sigmas[id];
        fit.sensor_weights[id] = LossWeight(options.loss, sensor_sigmas[id]);
      }
    }
    if constexpr (EquilibriumRows(M) > 0) {
      if (equilibrium_rows > 0) {  // the pose's, named by its first reading
        double r;
        MlEquilibriumResidual<M, double>(nominal, weights, g, q[j].data(), &r);
        readings.push_back({std::abs(r), readings_of[j].front(), M + kNumPlanarSensors});
        if (fits) {
          e.equilibrium_sigmas = r;
          e.equilibrium_theta_error_rad = EquilibriumThetaError<M>(nominal, g, e.q);
        }
      }
    }
    if (fits) fits->poses.push_back(e);
  }
  if (fits) {
    fits->rms_encoder_m = std::sqrt(sum_enc / (static_cast<double>(M) * num_readings));
    for (int id = 0; id < kNumSensorIds; ++id) fits->rms_sensor[id] = std::sqrt(sum_sensor[id] / num_readings);
  }
  return readings;
}

template <int M>
std::string IdentificationProblem<M>::Describe(const Reading& r, bool with_pose) const {
  const Measurement& m = measurements[r.reading];
  const bool repeated = readings_of.size() != measurements.size() && !m.where.empty();
  const std::string sensor = r.sensor < M                      ? "encoder " + std::to_string(r.sensor + 1)
                             : r.sensor < M + kNumPlanarSensors ? std::string(kPlanarSensors[r.sensor - M].name)
                                                               : std::string("equilibrium");
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), " %.3g sigma", r.sigmas);
  return (with_pose ? "pose " + std::to_string(m.pose_id) + ": " : std::string()) + sensor +
         (repeated ? " (" + m.where + ")" : "") + buffer;
}

template <int M>
BlockJacobian IdentificationProblem<M>::JacobianBlocks(ceres::Problem& p, double* g, PoseValues& q, bool with_loss,
                                                       std::vector<Eigen::VectorXd>* residuals) const {
  BlockJacobian blocks;
  ceres::Problem::EvaluateOptions eval;
  eval.parameter_blocks.push_back(g);
  for (int j = 0; j < n; ++j) eval.parameter_blocks.push_back(q[j].data());
  ceres::CRSMatrix crs;
  std::vector<double> values;
  p.Evaluate(eval, nullptr, residuals ? &values : nullptr, nullptr, &crs);
  // Ceres rows per reading: the blocks of Build() (a zero row for a missing sensor without a
  // loss, none with one).
  const int rows_per_reading = !ml ? M : with_loss ? values_per_reading : M + kNumPlanarSensors;
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
}

}  // namespace cablecal::internal
