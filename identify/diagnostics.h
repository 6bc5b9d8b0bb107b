// Internal to identify/: finding the readings that do not fit. Why least squares did not
// converge (DiagnoseLostFit), each pose against the fit of the others (CheckPoses), the
// greedy leave-out test that names the poses whose absence lets the rest fit (LeaveOut), and
// the fit without them that a robust loss falls back to when its estimate strays
// (FitWithoutLeftOut). Depends on problem.h (the problem they refit) and schur.h.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "identify/problem.h"

namespace cablecal::internal {

template <int M>
IdentifyResult IdentifyWithCables(const Robot& nominal, const std::vector<Measurement>& measurements,
                                  const IdentifyOptions& options);

// Each pose left out in turn, for the outlier test and the diagnosis of a fit that did not
// converge: beyond this many poses it would cost too much (n refits per round).
constexpr int kMaxPosesLeftOutTest = 200;
// The leave-out test's rounds: at most this many poses are named.
constexpr int kMaxLeftOut = 3;

// Poses left out, with the fit of the others.
template <int M>
struct LeftOut {
  std::vector<int> poses;                                         // indices into readings_of
  double geometry_values[IdentificationProblem<M>::kGeometry];  // the fit without them
  PoseValues pose_values;    // every pose: the rest's fit, the left-out fitted to that geometry
  std::vector<Reading> worst;  // the left-out poses' readings against the rest's geometry
};

// Why least squares did not converge, computed once when first asked (DiagnoseLostFit), with
// the pose found, if any, and the fit without it (a robust loss starts there).
template <int M>
struct LostFitDiagnosis {
  bool done = false;
  std::string text;  // "; ..." to append to the message, or empty
  std::optional<LeftOut<M>> culprit;
};

// Why least squares did not converge, when one pose's readings say it: a reading that no
// position gives a valid cable length on the nominal robot at its laser height and
// inclinometer angle (the anchor inside or past its pulley), or poses without which the
// others converge (each left out in turn, from the same start; up to kMaxPosesLeftOutTest
// poses, as the outlier test).
template <int M>
const LostFitDiagnosis<M>& DiagnoseLostFit(const IdentificationProblem<M>& p, LostFitDiagnosis<M>& cache) {
  constexpr int kGeometry = IdentificationProblem<M>::kGeometry;
  if (cache.done) return cache;
  cache.done = true;
  for (int j = 0; j < p.n; ++j) {
    for (const int k : p.readings_of[j]) {
      double r[M];
      const Measurement& m = p.measurements[k];
      LengthResiduals<M, double>(p.nominal, p.nominal_geometry.data(),
                                 PlanarPose(p.start_poses[j].data()),
                                 m.dl_m.data(), r);
      for (int i = 0; i < M; ++i) {
        if (std::isfinite(r[i])) continue;
        cache.text = "; pose " + std::to_string(m.pose_id) + (m.where.empty() ? "" : " (" + m.where + ")") +
                     ": at its laser height and inclinometer angle no position gives cable " + std::to_string(i + 1) +
                     " a valid length on the nominal robot (its anchor inside or past the pulley): check that reading";
        return cache;
      }
    }
  }
  if (p.n > kMaxPosesLeftOutTest) return cache;
  // At least Ceres' default limit: a user's low --max-iterations must not make a good pose
  // look guilty because the fit without it happens to converge sooner.
  const int diagnosis_limit = std::max(p.options.max_iterations, 100);
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
  LeftOut<M> found;
  double found_cost = std::numeric_limits<double>::infinity(), next_cost = found_cost;
  for (int j = 0; j < p.n; ++j) {
    std::vector<char> use(p.n, 1);
    use[j] = 0;
    if (!p.EnoughEquations(use)) continue;  // too few poses to tell
    double g[kGeometry];
    PoseValues q;
    p.ResetToStart(g, q);
    const LeastSquaresSummary sum = p.LeastSquares(g, q, use, diagnosis_limit);
    if (!p.Converged(sum, g, q, use)) continue;
    // A fit that converges only to readings that do not fit (the bad one still in: a 0.3 m
    // laser error at one of 30 poses let 8 such leave-outs converge, to poor fits, and so
    // hid the one whose absence lets the rest fit) explains nothing.
    if (!Beyond(p.ResidualsAt(g, q, use, nullptr)).empty()) continue;
    ++converging;
    p.FitToGeometry(g, q, j, diagnosis_limit);
    std::vector<char> only(p.n, 0);
    only[j] = 1;
    const std::vector<Reading> off = Beyond(p.ResidualsAt(g, q, only, nullptr));
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
    return cache;
  }
  cache.culprit = found;
  cache.text = "; " + std::string(converging == 1 ? "only without pose " : "without pose ") +
               std::to_string(p.measurements[culprit->reading].pose_id) +
               (converging == 1 ? " do the other poses converge" : " the other poses converge and fit") +
               ", and against their fit its readings are off by " + p.Describe(*culprit, false) +
               (converging == 1 ? "" : " (the others fit best without it)") + ": check that pose";
  return cache;
}

// Each pose against the fit of the others (schur.h, CheckPosesAgainstTheOthers), with least
// squares' Jacobian blocks and their analysis, kept for the result's covariance and
// identifiability when no robust fit follows (the same problem at the same values).
struct PoseChecks {
  std::vector<PoseCheck> checks;
  int flagged_pose = -1;  // the pose whose readings stand out most, if beyond kOutlierSigmas
  std::optional<BlockJacobian> blocks;
  std::optional<BlockAnalysis> analysis;
};

// A bad reading that least squares absorbed at a pose of high leverage leaves every residual
// small, yet stands out there (measured: a 0.3 m laser error at a random robot's weakest
// pose, all residuals under 1 sigma, 37 sigma off in a1z). ml with gauge a1x (under gauge
// prior, a tracker prior that disagrees with the readings would be blamed on a pose); for a
// person's result or ahead of a robust loss, not in a plain Monte Carlo trial.
template <int M>
PoseChecks CheckPoses(const IdentificationProblem<M>& p, ceres::Problem& at_estimate, double* g, PoseValues& q) {
  PoseChecks out;
  std::vector<Eigen::VectorXd> block_residuals;
  out.blocks = p.JacobianBlocks(at_estimate, g, q, false, &block_residuals);
  out.analysis = AnalyzeBlocks(*out.blocks, 1e-9);
  if (!out.analysis->null_vectors.empty()) return out;
  if (const std::optional<BlockCovariance> cov = CovarianceOf(*out.blocks, *out.analysis)) {
    out.checks = CheckPosesAgainstTheOthers(*out.blocks, *out.analysis, cov->geometry, block_residuals, kOutlierSigmas);
    double worst = kOutlierSigmas;
    for (int j = 0; j < p.n; ++j) {
      if (out.checks[j].deleted_residual_sigmas > worst) {
        worst = out.checks[j].deleted_residual_sigmas;
        out.flagged_pose = j;
      }
    }
  }
  return out;
}

// A bad reading at a pose that decides part of the geometry (high leverage) is absorbed by
// least squares: the estimate moves until that pose fits and other, good, poses do not
// (measured on the built-in robot: a 0.3 m laser error at one of 20 poses leaves that pose's
// residuals under 1 sigma and a dozen others' beyond 4.5). Whose readings are bad shows when
// each pose in turn is left out: the pose whose absence lets the rest fit is the culprit, and
// its readings against the rest's geometry say which sensor. Greedy, up to kMaxLeftOut poses,
// a refit per pose and round (warm-started from least squares' fit g, q: a few iterations
// each); nothing beyond kMaxPosesLeftOutTest poses, where the largest residuals are named instead.
template <int M>
std::optional<LeftOut<M>> LeaveOut(const IdentificationProblem<M>& p, const double* geometry, const PoseValues& poses) {
  constexpr int kGeometry = IdentificationProblem<M>::kGeometry;
  if (p.n > kMaxPosesLeftOutTest) return std::nullopt;
  const int max_iterations = p.options.max_iterations;
  LeftOut<M> out;
  std::copy(geometry, geometry + kGeometry, out.geometry_values);
  out.pose_values = poses;
  std::vector<char> use(p.n, 1);
  for (int round = 0; round < kMaxLeftOut; ++round) {
    double best_cost = std::numeric_limits<double>::infinity();
    int best = -1;
    double best_geometry[kGeometry];
    PoseValues best_poses;
    for (int j = 0; j < p.n; ++j) {
      if (!use[j]) continue;
      use[j] = 0;
      if (p.EnoughEquations(use)) {
        double g[kGeometry];
        std::copy(out.geometry_values, out.geometry_values + kGeometry, g);
        PoseValues q = out.pose_values;
        LeastSquaresSummary sum = p.LeastSquares(g, q, use, max_iterations);
        // Warm-started from a fit that absorbed the bad reading, the refit can stay in that
        // fit's basin and leave a clean pose off (a new user's robot: pose 17's bad laser
        // reading made pose 1 look 112 sigma off; fitted without pose 17 from the nominal
        // start, pose 1 is at 0.8 sigma). Where the warm refit leaves readings off, the
        // nominal start is tried too, and the lower cost kept.
        if (!p.Converged(sum, g, q, use) || !Beyond(p.ResidualsAt(g, q, use, nullptr)).empty()) {
          double g0[kGeometry];
          PoseValues q0;
          p.ResetToStart(g0, q0);
          const LeastSquaresSummary sum0 = p.LeastSquares(g0, q0, use, max_iterations);
          if (p.Converged(sum0, g0, q0, use) && (!p.Converged(sum, g, q, use) || sum0.final_cost < sum.final_cost)) {
            sum = sum0;
            std::copy(g0, g0 + kGeometry, g);
            q = q0;
          }
        }
        if (p.Converged(sum, g, q, use) && sum.final_cost < best_cost) {
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
    if (Beyond(p.ResidualsAt(out.geometry_values, out.pose_values, use, nullptr)).empty()) {
      // The rest fit: fit each left-out pose to their geometry alone, and read its residuals.
      std::vector<char> left(p.n, 0);
      for (const int j : out.poses) {
        left[j] = 1;
        p.FitToGeometry(out.geometry_values, out.pose_values, j, max_iterations);
      }
      out.worst = Beyond(p.ResidualsAt(out.geometry_values, out.pose_values, left, nullptr));
      return out;
    }
  }
  return std::nullopt;
}

// "7", "7 and 12", "3, 7 and 12"
template <int M>
std::string LeftOutIds(const IdentificationProblem<M>& p, const LeftOut<M>& l) {
  std::string names;
  for (std::size_t k = 0; k < l.poses.size(); ++k) {
    names += (k == 0 ? "" : k + 1 == l.poses.size() ? " and " : ", ") + std::to_string(p.pose_id_of(l.poses[k]));
  }
  return names;
}

template <int M>
std::string ExplainLeftOut(const IdentificationProblem<M>& p, const LeftOut<M>& l) {
  const std::string names = LeftOutIds(p, l);
  std::string worst;
  for (std::size_t k = 0; k < std::min<std::size_t>(3, l.worst.size()); ++k) {
    worst += (k ? ", " : "") + p.Describe(l.worst[k], l.poses.size() > 1);
  }
  return std::string(l.poses.size() == 1 ? "pose " : "poses ") + names + (l.poses.size() == 1 ? " does" : " do") +
         " not fit the others: fitted without " + (l.poses.size() == 1 ? "it" : "them") +
         ", every other reading is within " + FormatDouble(kOutlierSigmas) + " sigma, and " +
         (l.poses.size() == 1 ? "its" : "their") + " readings are then off by " + worst;
}

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
inline Apart FurthestApart(const double* a, const double* b, const GeometryVector& sigma, double above) {
  Apart worst{-1, above};
  for (int k = 0; k < sigma.size(); ++k) {
    if (!(sigma(k) > 0.0)) continue;
    const double sigmas = std::abs(a[k] - b[k]) / sigma(k);
    if (sigmas > worst.sigmas) worst = Apart{k, sigmas};
  }
  return worst;
}

// The least-squares fit without the left-out poses, as the result, if the robust estimate
// `geometry` is more than kRobustStraySigmas from it; nothing otherwise.
template <int M>
std::optional<IdentifyResult> FitWithoutLeftOut(const IdentificationProblem<M>& p, const LeftOut<M>& l,
                                                const double* geometry) {
  constexpr int kGeometry = IdentificationProblem<M>::kGeometry;
  const IdentifyOptions& options = p.options;
  std::vector<char> dropped_reading(p.num_readings, 0);
  for (const int j : l.poses) {
    for (const int k : p.readings_of[j]) dropped_reading[k] = 1;
  }
  std::vector<Measurement> kept;
  std::vector<int> row_of_kept;  // each kept reading's index in `measurements`
  for (int k = 0; k < p.num_readings; ++k) {
    if (dropped_reading[k]) continue;
    kept.push_back(p.measurements[k]);
    row_of_kept.push_back(k);
  }
  IdentifyOptions least_squares_options = options;
  least_squares_options.loss = RobustLoss{};
  least_squares_options.compute_covariance = true;  // its sigmas measure the stray
  IdentifyResult without = IdentifyWithCables<M>(p.nominal, kept, least_squares_options);
  if (!without.converged() || !without.has_covariance) return std::nullopt;
  const Apart stray = FurthestApart(geometry, without.geometry.data(), without.geometry_std, kRobustStraySigmas);
  if (stray.k < 0) return std::nullopt;
  // The dropped poses' readings against the returned geometry, each pose fitted to it alone.
  double g[kGeometry];
  for (int k = 0; k < kGeometry; ++k) g[k] = without.geometry(k);
  PoseValues q = l.pose_values;
  std::vector<char> left(p.n, 0);
  for (const int j : l.poses) {
    left[j] = 1;
    p.FitToGeometry(g, q, j, options.max_iterations);
  }
  IdentifyResult dropped_fits;  // the dropped readings' fits, at their rows
  p.ResidualsAt(g, q, left, &dropped_fits);
  if (p.reading_fits) {
    std::vector<ReadingFit> all = std::move(dropped_fits.readings);
    for (std::size_t i = 0; i < row_of_kept.size(); ++i) all[row_of_kept[i]] = std::move(without.readings[i]);
    for (int k = 0; k < p.num_readings; ++k) {
      if (!dropped_reading[k]) continue;
      all[k].encoder_weights.setZero();
      all[k].sensor_weights.fill(0.0);
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
    all.reserve(p.n);
    std::size_t next = 0;
    for (int j = 0; j < p.n; ++j) {
      if (left[j]) {
        PoseEstimate e;
        e.pose_id = p.pose_id_of(j);
        e.q = PlanarPose(q[j].data());
        all.push_back(e);
      } else if (next < without.poses.size()) {
        all.push_back(without.poses[next++]);
      }
    }
    without.poses = std::move(all);
  }
  without.loss = options.loss;
  for (const int j : l.poses) without.dropped_pose_ids.push_back(p.pose_id_of(j));
  char buffer[96];
  std::snprintf(buffer, sizeof(buffer), "%.3g sigma (%.3g mm in %s)", stray.sigmas,
                1e3 * std::abs(geometry[stray.k] - without.geometry(stray.k)), p.geometry_names[stray.k].c_str());
  const bool one = l.poses.size() == 1;
  without.warnings.insert(
      without.warnings.begin(),
      std::string(one ? "pose " : "poses ") + LeftOutIds(p, l) + " dropped: " + ExplainLeftOut(p, l) + "; the " +
          ToString(options.loss) + " estimate with " + (one ? "it" : "them") + " was " + buffer +
          " from the fit without " + (one ? "it" : "them") + ", which is returned" +
          (options.loss.kind == LossKind::kHuber ? " (Huber's loss never ignores a reading)" : ""));
  return without;
}

}  // namespace cablecal::internal
