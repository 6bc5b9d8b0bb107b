// Internal to identify/: Levenberg-Marquardt written for the ml estimator's least squares
// (no robust loss), the problem every Monte Carlo trial solves. Its Jacobian is block-arrow:
// each reading's rows touch the geometry and its own pose's (x, z, theta) only, so each
// step eliminates the poses' 3 x 3 blocks and solves a 3M x 3M Schur complement, as Ceres'
// DENSE_SCHUR does, without Ceres' general machinery (building a Problem, preprocessing,
// block-sparse bookkeeping), which was half of every 50-pose solve (bench/README.md, issue 15).
//
// The iterations are Ceres' Levenberg-Marquardt's (LevenbergMarquardtSettings below): the damping
// mu diag(J^T J) with mu = 1 / radius (diagonal clamped to [1e-6, 1e32]), the radius updated
// from the step's quality as Ceres does, and its three convergence tests (gradient 1e-12,
// step 1e-10, relative cost change 1e-10; the step that meets the last is not taken). The
// estimates therefore agree with Ceres' to rounding (tests/identify/least_squares_test.cc).
//
// The residuals are identify/residuals.h's. The length rows' derivatives take CableResidual
// with a 2-lane Jet on the anchor: a cable's length depends on its exit point and anchor
// only through their difference (cable.h), so d r/d(exit) = -d r/d(anchor), d r/d l_i0 = -1,
// and d r/d(pose) = d r/d(anchor) d(anchor)/d(pose), the anchor from a 3-lane Jet over the
// pose (4 to 9 times fewer derivative lanes than a Jet over every column).
#pragma once

#include <ceres/jet.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "experiment/experiment.h"
#include "identify/residuals.h"
#include "model/cable.h"
#include "model/geometry.h"
#include "model/kind.h"
#include "model/robot.h"

namespace cablecal::internal {

// The problem: readings grouped by pose (readings_of[j]: indices into measurements), the
// weights that whiten them (a missing sensor's weight is 0; weights.inv_sigma_equilibrium > 0
// adds each pose's equilibrium row when M < 3), the entries the gauge holds
// and the priors on the geometry: the tracker's on the exit points (gauge prior) and
// --geometry-prior's on every parameter, as one inverse sigma per coordinate (0: none).
template <int M>
struct MlLeastSquaresProblem {
  static constexpr GeometryLayout kLayout = PlanarLayout(M);
  const Robot* robot = nullptr;
  const std::vector<Measurement>* measurements = nullptr;
  const std::vector<std::vector<int>>* readings_of = nullptr;
  ReadingWeights weights;
  std::vector<int> held;  // geometry entries the gauge holds (gauge a1x: a1x): no unknowns
  Eigen::Matrix<double, kLayout.size(), 1> prior_geometry = Eigen::Matrix<double, kLayout.size(), 1>::Zero();
  Eigen::Matrix<double, kLayout.size(), 1> prior_inv_sigma = Eigen::Matrix<double, kLayout.size(), 1>::Zero();
  int max_iterations = 100;
};

// Levenberg-Marquardt's settings, one set for Ceres' solves (identify/problem.h,
// ApplyLevenbergMarquardt) and for SolveMlLeastSquares below, whose iterations are Ceres'.
struct LevenbergMarquardtSettings {
  // Relative cost change 1e-10 at the minimum means parameter steps of ~1e-4 sigma: far below
  // any uncertainty reported, and noise-free data are still recovered to 1e-7 m (tested).
  double function_tolerance = 1e-10;
  double gradient_tolerance = 1e-12;
  double parameter_tolerance = 1e-10;
  // The start is close (nominal geometry, per-pose x from the lengths), so start LM as
  // nearly Gauss-Newton; it still shrinks the region after a step that raises the cost.
  double initial_trust_region_radius = 1e8;
};

struct LeastSquaresSummary {
  bool converged = false;
  int iterations = 0;       // steps taken or rejected, as Ceres counts them
  double final_cost = 0.0;  // 1/2 sum of squared whitened residuals, at the estimate
  std::string message;      // why it stopped
};

namespace least_squares {

using PoseValues = std::vector<PlanarPoseValues>;

constexpr int kPose = PlanarKind::kPoseDim;
using PoseMatrix = Eigen::Matrix<double, kPose, kPose>;

// One pose's share of the normal equations J^T J and J^T r: its own block A (pose x pose), its
// coupling with the geometry B (3M x pose) and its gradient b (pose).
template <int M>
struct PoseNormal {
  PoseMatrix a;
  Eigen::Matrix<double, PlanarLayout(M).size(), kPose> b;
  PlanarPose gradient;
  PoseMatrix damped_inverse;  // (A + mu D)^-1 of the current step
};

// A reading's sensor residuals at pose q (residuals.h, MlSensorResiduals), in kPlanarSensors' order.
template <int M>
Eigen::Matrix<double, kNumPlanarSensors, 1> SensorResiduals(const MlLeastSquaresProblem<M>& p, const Measurement& m,
                                                            const PlanarPoseValues& q) {
  PoseReadings<M> readings;
  for (int k = 0; k < kNumSensorIds; ++k) readings.sensor_values[k] = m.value(static_cast<SensorId>(k));
  Eigen::Matrix<double, kNumPlanarSensors, 1> r;
  MlSensorResiduals<M, double>(readings, p.weights, q.data(), r.data());
  return r;
}

// The priors' residual on geometry coordinate k (cost_functors.h, GeometryPriorCost).
template <int M>
double PriorResidual(const MlLeastSquaresProblem<M>& p, const double* g, int k) {
  return (g[k] - p.prior_geometry(k)) * p.prior_inv_sigma(k);
}

// 1/2 sum of squared whitened residuals over the poses in `use`; infinite where a residual is
// not finite (an anchor inside its pulley).
template <int M>
double Cost(const MlLeastSquaresProblem<M>& p, const double* g, const PoseValues& q, const std::vector<char>& use) {
  double sum = 0.0;
  const int n = static_cast<int>(q.size());
  for (int j = 0; j < n; ++j) {
    if (!use[j]) continue;
    for (const int k : (*p.readings_of)[j]) {
      const Measurement& m = (*p.measurements)[k];
      double r[M];
      LengthResiduals<M, double>(*p.robot, g, Pose<double>(q[j][0], q[j][1], q[j][2]), m.dl_m.data(), r);
      for (int i = 0; i < M; ++i) sum += r[i] * r[i] * (p.weights.inv_sigma_encoder * p.weights.inv_sigma_encoder);
      sum += SensorResiduals<M>(p, m, q[j]).squaredNorm();
    }
    if constexpr (EquilibriumRows(M) > 0) {
      if (p.weights.inv_sigma_equilibrium > 0.0) {
        double r;
        MlEquilibriumResidual<M, double>(*p.robot, p.weights, g, q[j].data(), &r);
        sum += r * r;
      }
    }
  }
  for (int k = 0; k < PlanarLayout(M).size(); ++k) {
    if (p.prior_inv_sigma(k) > 0.0) sum += PriorResidual<M>(p, g, k) * PriorResidual<M>(p, g, k);
  }
  return std::isfinite(sum) ? 0.5 * sum : std::numeric_limits<double>::infinity();
}

// The normal equations at (g, q): per pose A, B and its gradient; the geometry's H_gg and
// gradient. Returns the cost (infinite if a residual is not finite).
template <int M>
double Normal(const MlLeastSquaresProblem<M>& p, const double* g, const PoseValues& q, const std::vector<char>& use,
              std::vector<PoseNormal<M>>& poses,
              Eigen::Matrix<double, PlanarLayout(M).size(), PlanarLayout(M).size()>& h_gg,
              Eigen::Matrix<double, PlanarLayout(M).size(), 1>& gradient_g) {
  constexpr GeometryLayout kLayout = PlanarLayout(M);
  constexpr int kExits = kLayout.exit_coordinates();
  using Jet2 = ceres::Jet<double, 2>;
  using Jet3 = ceres::Jet<double, kPose>;
  const ReadingWeights& w = p.weights;
  h_gg.setZero();
  gradient_g.setZero();
  double sum = 0.0;
  const int n = static_cast<int>(q.size());
  for (int j = 0; j < n; ++j) {
    if (!use[j]) continue;
    PoseNormal<M>& pose = poses[j];
    pose.a.setZero();
    pose.b.setZero();
    pose.gradient.setZero();
    // The anchors and their derivatives with respect to (x, z, theta): the same at every
    // reading of this pose.
    const Eigen::Matrix<Jet3, 2, 2> R = Rotation(Jet3(q[j][2], 2));
    const Vec2<Jet3> position(Jet3(q[j][0], 0), Jet3(q[j][1], 1));
    Vec2<double> anchor[M];
    Eigen::Matrix<double, kLayout.point_dim, kPose> anchor_by_pose[M];
    for (int i = 0; i < M; ++i) {
      const Vec2<Jet3> b = position + R * p.robot->cables[i].p_P_anchor_m.template cast<Jet3>();
      anchor[i] = Vec2<double>(b.x().a, b.y().a);
      anchor_by_pose[i].row(0) = b.x().v.transpose();
      anchor_by_pose[i].row(1) = b.y().v.transpose();
    }
    for (const int k : (*p.readings_of)[j]) {
      const Measurement& m = (*p.measurements)[k];
      for (int i = 0; i < M; ++i) {
        const Cable& cable = p.robot->cables[i];
        const Jet2 r = CableResidual<Jet2>(cable, Vec2<Jet2>(Jet2(g[kLayout.exit(i, 0)]), Jet2(g[kLayout.exit(i, 1)])),
                                           Jet2(g[kLayout.initial_length(i)]),
                                           Vec2<Jet2>(Jet2(anchor[i].x(), 0), Jet2(anchor[i].y(), 1)), m.dl_m(i));
        const double residual = r.a * w.inv_sigma_encoder;
        const Eigen::Vector2d by_anchor = r.v * w.inv_sigma_encoder;
        const PlanarPose row_pose = anchor_by_pose[i].transpose() * by_anchor;
        // a_ix, a_iz, l_i0
        const Eigen::Matrix<double, kLayout.point_dim + 1, 1> row_cable(-by_anchor.x(), -by_anchor.y(),
                                                                        -w.inv_sigma_encoder);
        constexpr int kPerCable = kLayout.point_dim + 1;
        const int cols[kPerCable] = {kLayout.exit(i, 0), kLayout.exit(i, 1), kLayout.initial_length(i)};
        sum += residual * residual;
        pose.a.noalias() += row_pose * row_pose.transpose();
        pose.gradient += row_pose * residual;
        for (int c = 0; c < kPerCable; ++c) {
          pose.b.row(cols[c]) += row_cable(c) * row_pose.transpose();
          gradient_g(cols[c]) += row_cable(c) * residual;
          for (int d = 0; d < kPerCable; ++d) h_gg(cols[c], cols[d]) += row_cable(c) * row_cable(d);
        }
      }
      // Each sensor reads one pose coordinate c (the laser z, the inclinometer theta): a row w e_c.
      const Eigen::Matrix<double, kNumPlanarSensors, 1> sensors = SensorResiduals<M>(p, m, q[j]);
      sum += sensors.squaredNorm();
      for (int k = 0; k < kNumPlanarSensors; ++k) {
        const int c = kPlanarSensors[k].pose_coordinate;
        const double w_k = w.inv_sigma_sensor[static_cast<int>(kPlanarSensors[k].id)];
        pose.a(c, c) += w_k * w_k;
        pose.gradient(c) += w_k * sensors(k);
      }
    }
    // The pose's equilibrium row (M < 3; residuals.h, MlEquilibriumResidual): one per pose,
    // whatever its readings, on the exit points and the pose, by a Jet over those 2M + 3.
    if constexpr (EquilibriumRows(M) > 0) {
      if (w.inv_sigma_equilibrium > 0.0) {
        using JetE = ceres::Jet<double, kExits + kPose>;
        JetE exits[kExits], pose_jet[kPose];
        for (int k = 0; k < kExits; ++k) exits[k] = JetE(g[k], k);
        for (int c = 0; c < kPose; ++c) pose_jet[c] = JetE(q[j][c], kExits + c);
        JetE r;
        MlEquilibriumResidual<M, JetE>(*p.robot, w, exits, pose_jet, &r);
        const Eigen::Matrix<double, kExits, 1> row_exits = r.v.template head<kExits>();
        const PlanarPose row_pose = r.v.template tail<kPose>();
        sum += r.a * r.a;
        pose.a.noalias() += row_pose * row_pose.transpose();
        pose.gradient += row_pose * r.a;
        pose.b.template topRows<kExits>().noalias() += row_exits * row_pose.transpose();
        gradient_g.template head<kExits>() += row_exits * r.a;
        h_gg.template topLeftCorner<kExits, kExits>().noalias() += row_exits * row_exits.transpose();
      }
    }
  }
  for (int k = 0; k < PlanarLayout(M).size(); ++k) {
    if (!(p.prior_inv_sigma(k) > 0.0)) continue;
    const double r = PriorResidual<M>(p, g, k);
    sum += r * r;
    h_gg(k, k) += p.prior_inv_sigma(k) * p.prior_inv_sigma(k);
    gradient_g(k) += p.prior_inv_sigma(k) * r;
  }
  for (const int k : p.held) {  // a held entry is no unknown: its column is out of J
    h_gg.row(k).setZero();
    h_gg.col(k).setZero();
    gradient_g(k) = 0.0;
    for (int j = 0; j < n; ++j) {
      if (use[j]) poses[j].b.row(k).setZero();
    }
  }
  return std::isfinite(sum) ? 0.5 * sum : std::numeric_limits<double>::infinity();
}

// Ceres' Levenberg-Marquardt diagonal: diag(J^T J) clamped to [1e-6, 1e32].
template <typename Derived>
auto LmDiagonal(const Eigen::MatrixBase<Derived>& normal) {
  return normal.diagonal().cwiseMax(1e-6).cwiseMin(1e32);
}

}  // namespace least_squares

// One function of ~150 lines: as in Ceres' own trust-region minimiser, every step's decisions
// (accept, shrink, stop) share the loop's state (radius, cost, the normal equations, the
// invalid-step count); split, each part would take all of it.
// Minimises the ml estimator's cost over the geometry g (3M values: a1x a1z ... l10 ...) and
// the poses in `use` (q[j] = x, z, theta), in place, from their values on entry.
template <int M>
LeastSquaresSummary SolveMlLeastSquares(const MlLeastSquaresProblem<M>& p, double* g,
                                        std::vector<PlanarPoseValues>& q, const std::vector<char>& use) {
  using namespace least_squares;
  constexpr int G = PlanarLayout(M).size();
  using MatrixG = Eigen::Matrix<double, G, G>;
  using VectorG = Eigen::Matrix<double, G, 1>;
  constexpr LevenbergMarquardtSettings kSettings;
  constexpr double kFunctionTolerance = kSettings.function_tolerance, kGradientTolerance = kSettings.gradient_tolerance,
                   kParameterTolerance = kSettings.parameter_tolerance;
  constexpr double kMinRelativeDecrease = 1e-3, kMaxRadius = 1e16, kMinRadius = 1e-32;
  constexpr int kMaxConsecutiveInvalidSteps = 5;
  double radius = kSettings.initial_trust_region_radius, decrease_factor = 2.0;

  const int n = static_cast<int>(q.size());
  LeastSquaresSummary summary;
  std::vector<PoseNormal<M>> poses(n);
  MatrixG h_gg;
  VectorG gradient_g;
  double cost = Normal<M>(p, g, q, use, poses, h_gg, gradient_g);
  if (!std::isfinite(cost)) {
    summary.message = "a residual is not finite at the start (an anchor inside its pulley?)";
    return summary;
  }
  const auto stop = [&](bool converged, const std::string& why) {
    summary.converged = converged;
    summary.final_cost = cost;
    summary.message = why;
    return summary;
  };
  // The gradient test, in Ceres' form: max |x - (x - gradient)|.
  const auto gradient_small = [&]() {
    double largest = gradient_g.cwiseAbs().maxCoeff();
    for (int j = 0; j < n; ++j) {
      if (use[j]) largest = std::max(largest, poses[j].gradient.cwiseAbs().maxCoeff());
    }
    return largest <= kGradientTolerance;
  };
  if (gradient_small()) return stop(true, "gradient tolerance reached");

  PoseValues candidate_q = q;
  std::vector<PlanarPose> step_q(n);
  int invalid_steps = 0;
  // The limit counts the steps taken or rejected; a step that only finds the minimum reached
  // (a tolerance met, not counted) is still computed at the limit, so that a solve that
  // reports k iterations also converges with max_iterations = k.
  const auto at_limit = [&]() { return summary.iterations >= p.max_iterations; };
  const std::string limit_reached = "the iteration limit was reached";
  for (;;) {
    // The damped step: eliminate each pose's block, solve the geometry's Schur complement,
    // back-substitute (a held entry: its row and column of S the identity, its step 0).
    const double mu = 1.0 / radius;
    bool valid = true;
    MatrixG s = h_gg;
    s.diagonal() += mu * LmDiagonal(h_gg);
    VectorG rhs = gradient_g;
    for (int j = 0; j < n && valid; ++j) {
      if (!use[j]) continue;
      PoseNormal<M>& pose = poses[j];
      PoseMatrix damped = pose.a;
      damped.diagonal() += mu * LmDiagonal(pose.a);
      const Eigen::LLT<PoseMatrix> llt(damped);
      if (llt.info() != Eigen::Success) {
        valid = false;
        break;
      }
      pose.damped_inverse = llt.solve(PoseMatrix::Identity());
      const Eigen::Matrix<double, G, kPose> bc = pose.b * pose.damped_inverse;
      s.noalias() -= bc * pose.b.transpose();
      rhs.noalias() -= bc * pose.gradient;
    }
    VectorG step_g = VectorG::Zero();
    if (valid) {
      for (const int k : p.held) {
        s.row(k).setZero();
        s.col(k).setZero();
        s(k, k) = 1.0;
        rhs(k) = 0.0;
      }
      const Eigen::LDLT<MatrixG> ldlt(s);
      step_g = -ldlt.solve(rhs);
      valid = ldlt.info() == Eigen::Success && step_g.allFinite();
    }
    // The model's decrease: -gradient' step - 1/2 |J step|^2 (undamped J).
    double model_decrease = 0.0, step_norm2 = step_g.squaredNorm(), x_norm2 = 0.0;
    if (valid) {
      double jstep2 = step_g.dot(h_gg * step_g);
      model_decrease = -gradient_g.dot(step_g);
      for (int j = 0; j < n; ++j) {
        if (!use[j]) continue;
        const PoseNormal<M>& pose = poses[j];
        step_q[j] = -pose.damped_inverse * (pose.gradient + pose.b.transpose() * step_g);
        jstep2 += step_q[j].dot(pose.a * step_q[j]) + 2.0 * step_g.dot(pose.b * step_q[j]);
        model_decrease -= pose.gradient.dot(step_q[j]);
        step_norm2 += step_q[j].squaredNorm();
      }
      model_decrease -= 0.5 * jstep2;
      valid = std::isfinite(model_decrease) && model_decrease > 0.0;
    }
    if (!valid) {
      if (at_limit()) return stop(false, limit_reached);
      ++summary.iterations;
      if (++invalid_steps >= kMaxConsecutiveInvalidSteps) {
        return stop(false, "the linear solve failed " + std::to_string(kMaxConsecutiveInvalidSteps) + " times in a row");
      }
      radius /= decrease_factor;
      decrease_factor *= 2.0;
      if (radius < kMinRadius) return stop(false, "the trust region became too small");
      continue;
    }
    invalid_steps = 0;
    // The step-size test: |step| <= tol (|x| + tol).
    for (int k = 0; k < G; ++k) x_norm2 += g[k] * g[k];
    for (int j = 0; j < n; ++j) {
      if (use[j]) x_norm2 += q[j][0] * q[j][0] + q[j][1] * q[j][1] + q[j][2] * q[j][2];
    }
    if (std::sqrt(step_norm2) <= kParameterTolerance * (std::sqrt(x_norm2) + kParameterTolerance)) {
      return stop(true, "parameter tolerance reached");
    }
    double candidate_g[G];
    for (int k = 0; k < G; ++k) candidate_g[k] = g[k] + step_g(k);
    for (int j = 0; j < n; ++j) {
      if (!use[j]) continue;
      for (int c = 0; c < least_squares::kPose; ++c) candidate_q[j][c] = q[j][c] + step_q[j](c);
    }
    const double candidate_cost = Cost<M>(p, candidate_g, candidate_q, use);
    const double cost_change = cost - candidate_cost;
    if (std::isfinite(candidate_cost) && std::abs(cost_change) <= kFunctionTolerance * cost) {
      return stop(true, "function tolerance reached");
    }
    const double quality = cost_change / model_decrease;
    if (at_limit()) return stop(false, limit_reached);
    ++summary.iterations;  // the step that meets a tolerance above is not counted, as in Ceres
    if (!std::isfinite(candidate_cost) || !(quality > kMinRelativeDecrease)) {
      radius /= decrease_factor;
      decrease_factor *= 2.0;
      if (radius < kMinRadius) return stop(false, "the trust region became too small");
      continue;
    }
    // Accepted: move, widen the region by the step's quality, and take the new normal equations.
    std::copy(candidate_g, candidate_g + G, g);
    for (int j = 0; j < n; ++j) {
      if (use[j]) q[j] = candidate_q[j];
    }
    radius = std::min(kMaxRadius, radius / std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * quality - 1.0, 3)));
    decrease_factor = 2.0;
    cost = Normal<M>(p, g, q, use, poses, h_gg, gradient_g);
    if (gradient_small()) return stop(true, "gradient tolerance reached");
  }
}

}  // namespace cablecal::internal
