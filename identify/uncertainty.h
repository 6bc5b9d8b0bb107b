// Internal to identify/: what the estimate knows, from the whitened Jacobian at the solution
// by blocks (problem.h, JacobianBlocks; schur.h, O(n) in the poses). Identifiability: the
// singular values, the condition number, the weakest pose and the null directions, named
// (AddIdentifiability). Covariance: the geometry's and each pose's standard deviations and the
// geometry's correlations, with the paper estimator's sandwich (AddCovariance), and the
// warnings of a geometry the poses hardly determine or the data hardly inform beyond a prior.
#pragma once

#include <ceres/jet.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include "identify/problem.h"

namespace cablecal::internal {

// "%.4g" of a null direction's coefficient (identify.cc).
std::string FormatCoefficient(double c);

// The null directions beyond the gauge's `expected_null` make the result rank deficient
// (status and message set: false returned).
template <int M>
bool AddIdentifiability(const IdentificationProblem<M>& p, const BlockAnalysis& analysis, int expected_null,
                        IdentifyResult& result) {
  Identifiability& id = result.identifiability;
  for (int k = 0; k < p.kGeometry; ++k) {
    if (!p.IsHeld(k)) id.geometry_names.push_back(p.geometry_names[k]);
  }
  id.names = id.geometry_names;
  for (int j = 0; j < p.n; ++j) {
    const std::string pose = std::to_string(p.pose_id_of(j));
    for (int k = 0; k < p.per_pose_unknowns; ++k) id.names.push_back(PlanarKind::kPoseNames[k] + pose);
  }
  id.singular_values = analysis.singular_values;
  const double s_min = id.singular_values(id.singular_values.size() - 1);
  id.condition_number = analysis.null_vectors.empty() && s_min > 0.0 ? id.singular_values(0) / s_min
                                                                      : std::numeric_limits<double>::infinity();
  if (analysis.weakest_pose >= 0) {
    id.weakest_pose_id = p.pose_id_of(analysis.weakest_pose);
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
      text += (text.empty() ? "" : (v(c) < 0 ? " - " : " + ")) + FormatCoefficient(text.empty() ? v(c) : std::abs(v(c))) +
              " " + id.names[c];
    }
    if (more > 0) text += " ... (" + std::to_string(more) + " more terms)";
    id.null_directions.push_back(text);
    id.null_vectors.push_back(v);
  }
  if (static_cast<int>(id.null_directions.size()) <= expected_null) return true;
  result.status = IdentifyStatus::kRankDeficient;
  result.message = "the measurements cannot determine " + std::to_string(id.null_directions.size() - expected_null) +
                   " direction(s) beyond the declared gauge; null directions: ";
  for (std::size_t k = 0; k < id.null_directions.size(); ++k) {
    result.message += (k ? "; " : "") + id.null_directions[k];
  }
  if (!p.missing_text.empty()) {
    result.message += " (the data have " + p.missing_text + ")";
    if (!p.present[static_cast<int>(SensorId::kLaser)] && p.options.gauge != Gauge::kPrior) {
      result.message += "; a tracker prior on the exit points fixes the heights: --gauge prior";
    }
  }
  return false;
}

// The paper estimator's covariance: its residuals f_ij = l_model^2 - (dl_ij + l_i0)^2 take z
// and theta as exact, yet the laser's and inclinometer's noise enters them through l_model,
// with the encoder's through dl_ij. The sandwich propagates all three: per reading,
// Sigma = diag(2 (dl + l0) sigma_enc)^2 + sigma_z^2 b_z b_z^T + sigma_theta^2 b_th b_th^T,
// b = 2 l_model dl_model/d(z, theta) (schur.h, SandwichCovariance).
template <int M>
BlockCovariance PaperSandwich(const IdentificationProblem<M>& p, const BlockJacobian& blocks,
                              const BlockAnalysis& analysis, const BlockCovariance& inverse, const double* geometry,
                              const PoseValues& poses) {
  using Jet2 = ceres::Jet<double, 2>;
  constexpr int kGeometry = IdentificationProblem<M>::kGeometry;
  const SensorNoise& s = p.s;
  Jet2 geometry_jets[kGeometry];
  for (int k = 0; k < kGeometry; ++k) geometry_jets[k] = Jet2(geometry[k]);
  std::vector<Eigen::MatrixXd> sigma(p.n);
  for (int j = 0; j < p.n; ++j) {
    const int count = static_cast<int>(p.readings_of[j].size());
    sigma[j] = Eigen::MatrixXd::Zero(M * count, M * count);
    for (int c = 0; c < count; ++c) {
      const Measurement& m = p.measurements[p.readings_of[j][c]];
      Jet2 r[M];
      LengthResiduals<M, Jet2>(p.nominal, geometry_jets, Pose<Jet2>(Jet2(poses[j][0]), Jet2(m.value(SensorId::kLaser), 0),
                                                                  Jet2(m.value(SensorId::kInclinometer), 1)),
                               m.dl_m.data(), r);
      Eigen::Matrix<double, M, 1> b_z, b_theta, encoder;
      for (int i = 0; i < M; ++i) {
        const double measured = m.dl_m(i) + geometry[p.kLayout.initial_length(i)];
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
  return SandwichCovariance(blocks, analysis, inverse, sigma);
}

// The warnings of a covariance: a geometry the poses hardly determine, and parameters a
// geometry prior's data leave nearly where the prior had them.
template <int M>
void AddCovarianceWarnings(const IdentificationProblem<M>& p, IdentifyResult& result) {
  // A geometry the poses hardly determine is a result, but not one to use: say so, naming
  // the worst-determined parameter (a new user's 5 random poses gave sigmas of kilometres
  // and nothing said so). 0.1 m: far beyond any calibration's aim, far below such sigmas.
  constexpr double kUndetermined_m = 0.1;
  Eigen::Index worst = 0;
  const double worst_std = result.geometry_std.maxCoeff(&worst);
  if (worst_std > kUndetermined_m) {
    char buffer[160];
    std::snprintf(buffer, sizeof(buffer), "the poses hardly determine the geometry: the standard deviation of %s is "
                  "%.3g m", p.geometry_names[worst].c_str(), worst_std);
    result.warnings.push_back(std::string(buffer) + "; add poses, or plan better-spread ones (cablecal design)");
  }
  // With a geometry prior the result is never less informed than the prior, but it may be
  // hardly more: say which parameters the data leave nearly where the prior had them
  // (the posterior keeps more than half the prior's variance).
  if (!p.geometry_prior) return;
  std::string little;
  int count = 0;
  for (int k = 0; k < p.kGeometry; ++k) {
    if (!(result.geometry_std(k) > kDataAddLittle * p.prior_sigma_m)) continue;
    if (++count <= 4) {
      char buffer[64];
      std::snprintf(buffer, sizeof(buffer), "%s%s (%.3g mm)", count > 1 ? ", " : "", p.geometry_names[k].c_str(),
                    1e3 * result.geometry_std(k));
      little += buffer;
    }
  }
  if (count > 4) little += ", ...";
  if (count > 0) {
    result.data_add_little = count;
    result.warnings.push_back("the data add little to the geometry prior (" + FormatDouble(1e3 * p.prior_sigma_m) +
                              " mm) for " + std::to_string(count) + " of " + std::to_string(p.geometry_cols) +
                              " parameters: " + little +
                              "; they are known about as well as before measuring: add poses, or plan ones that see "
                              "them (cablecal design)");
  }
}

// The covariance of the estimate (geometry, poses) from its Jacobian blocks; gauge none: the
// Moore-Penrose pseudo-inverse (schur.h). `final_cost` scales the paper estimator's under
// gauge none.
template <int M>
void AddCovariance(const IdentificationProblem<M>& p, const BlockJacobian& blocks, const BlockAnalysis& analysis,
                   int expected_null, const double* geometry, const PoseValues& poses, double final_cost,
                   IdentifyResult& result) {
  constexpr int kGeometry = IdentificationProblem<M>::kGeometry;
  std::optional<BlockCovariance> cov = CovarianceOf(blocks, analysis);
  if (!cov) return;
  double scale = 1.0;
  if (!p.ml && expected_null == 0) {
    cov = PaperSandwich(p, blocks, analysis, *cov, geometry, poses);
  } else if (!p.ml) {
    // gauge none: the covariance scaled by the residual variance s^2 (conservative: the
    // sandwich is not taken through the pseudo-inverse). Ceres' rows and tangent-space
    // unknowns of this problem (M rows per reading, no prior under gauge none, 3M + n unknowns).
    const int dof = M * p.num_readings - (kGeometry + p.n - expected_null);
    scale = dof > 0 ? 2.0 * final_cost / dof : std::numeric_limits<double>::quiet_NaN();
  }
  // Back from the tangent space (SubsetManifold: the free entries in order): a held entry has
  // no variance.
  std::vector<int> free;
  for (int k = 0; k < kGeometry; ++k) {
    if (!p.IsHeld(k)) free.push_back(k);
  }
  Eigen::MatrixXd C = Eigen::MatrixXd::Zero(kGeometry, kGeometry);
  for (std::size_t a = 0; a < free.size(); ++a) {
    for (std::size_t b = 0; b < free.size(); ++b) C(free[a], free[b]) = scale * (*cov).geometry(a, b);
  }
  result.geometry_std = C.diagonal().cwiseMax(0.0).cwiseSqrt();
  for (int a = 0; a < kGeometry; ++a) {
    for (int b = 0; b < kGeometry; ++b) {
      const double d = result.geometry_std(a) * result.geometry_std(b);
      result.geometry_correlation(a, b) = a == b ? 1.0 : (d > 0.0 ? C(a, b) / d : 0.0);
    }
  }
  for (int j = 0; j < p.n; ++j) {
    for (int k = 0; k < p.per_pose_unknowns; ++k) {
      result.poses[j].std_dev(k) = std::sqrt(std::max(0.0, scale * cov->poses[j](k, k)));
    }
  }
  result.has_covariance = true;
  AddCovarianceWarnings(p, result);
}

}  // namespace cablecal::internal
