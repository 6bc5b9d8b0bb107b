#include "identify/schur.h"

#include <Eigen/Dense>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>

#include "common/error.h"

namespace cablecal {

int BlockJacobian::geometry_cols() const {
  return poses.empty() ? static_cast<int>(prior.cols()) : static_cast<int>(poses.front().geometry.cols());
}

int BlockJacobian::total_cols() const {
  int cols = geometry_cols();
  for (const PoseBlock& b : poses) cols += static_cast<int>(b.pose.cols());
  return cols;
}

BlockAnalysis AnalyzeBlocks(const BlockJacobian& jacobian, double null_tolerance) {
  const int g_cols = jacobian.geometry_cols();
  const int n = static_cast<int>(jacobian.poses.size());
  BlockAnalysis a;
  a.null_tolerance = null_tolerance;
  a.poses.resize(n);

  // Pass 1: each pose block's SVD, and the scale every null decision is relative to.
  std::vector<Eigen::JacobiSVD<Eigen::MatrixXd>> svds;
  svds.reserve(n);
  Eigen::MatrixXd geometry_normal = jacobian.prior.transpose() * jacobian.prior;
  double pose_scale = 0.0;
  int reduced_rows = static_cast<int>(jacobian.prior.rows());
  for (int j = 0; j < n; ++j) {
    const PoseBlock& b = jacobian.poses[j];
    CABLECAL_CHECK(b.geometry.cols() == g_cols && b.geometry.rows() == b.pose.rows() && b.pose.rows() > 0,
                   "a pose block has rows and every pose the same geometry columns");
    geometry_normal.noalias() += b.geometry.transpose() * b.geometry;
    svds.emplace_back(b.pose, Eigen::ComputeFullU | Eigen::ComputeFullV);
    const Eigen::VectorXd& s = svds.back().singularValues();
    a.poses[j].max_singular_value = s(0);
    a.poses[j].min_singular_value = s.size() < b.pose.cols() ? 0.0 : s(s.size() - 1);
    pose_scale = std::max(pose_scale, s(0));
    if (a.weakest_pose < 0 || a.poses[j].min_singular_value < a.poses[a.weakest_pose].min_singular_value) {
      a.weakest_pose = j;
    }
  }
  const double geometry_scale =
      std::sqrt(std::max(0.0, Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(geometry_normal, Eigen::EigenvaluesOnly)
                                  .eigenvalues()
                                  .maxCoeff()));
  a.scale = std::max(geometry_scale, pose_scale);
  const double threshold = null_tolerance * a.scale;

  // Pass 2: eliminate each pose's unknowns; its rows outside J_p's range go to J_r.
  std::vector<int> pose_rank(n);
  for (int j = 0; j < n; ++j) {
    const auto& svd = svds[j];
    const Eigen::VectorXd& s = svd.singularValues();
    int rank = 0;
    while (rank < s.size() && s(rank) >= threshold && s(rank) > 0.0) ++rank;
    pose_rank[j] = rank;
    // Fewer readings than unknowns (a pose without laser or inclinometer) leave some unseen.
    if (rank < jacobian.poses[j].pose.cols()) a.pose_block_deficient = true;
    reduced_rows += static_cast<int>(jacobian.poses[j].pose.rows()) - rank;
  }
  a.reduced.resize(reduced_rows, g_cols);
  int row = 0, offset = g_cols;
  for (int j = 0; j < n; ++j) {
    const PoseBlock& b = jacobian.poses[j];
    const auto& svd = svds[j];
    const int rank = pose_rank[j], r = static_cast<int>(b.pose.rows()), p = static_cast<int>(b.pose.cols());
    const Eigen::MatrixXd& u = svd.matrixU();
    const Eigen::MatrixXd& v = svd.matrixV();
    const Eigen::VectorXd inv_s = svd.singularValues().head(rank).cwiseInverse();
    a.reduced.middleRows(row, r - rank).noalias() = u.rightCols(r - rank).transpose() * b.geometry;
    row += r - rank;
    PoseElimination& e = a.poses[j];
    e.u2 = u.rightCols(r - rank);
    e.k.noalias() = v.leftCols(rank) * inv_s.asDiagonal() * (u.leftCols(rank).transpose() * b.geometry);
    e.inverse_normal.noalias() = v.leftCols(rank) * inv_s.cwiseAbs2().asDiagonal() * v.leftCols(rank).transpose();
    // A direction of this pose's own unknowns that its readings do not see is a null
    // direction of the whole problem (the geometry does not move along it).
    for (int c = rank; c < p; ++c) {
      Eigen::VectorXd full = Eigen::VectorXd::Zero(jacobian.total_cols());
      full.segment(offset, p) = v.col(c);
      a.null_vectors.push_back(full);
    }
    offset += p;
  }
  if (jacobian.prior.rows() > 0) a.reduced.bottomRows(jacobian.prior.rows()) = jacobian.prior;

  // The geometry after elimination: its singular values and null directions, each completed
  // with the pose motions that keep every pose's readings fitted (-K_j v_g).
  Eigen::JacobiSVD<Eigen::MatrixXd> reduced_svd(a.reduced, Eigen::ComputeFullV);
  a.singular_values = Eigen::VectorXd::Zero(g_cols);
  a.singular_values.head(reduced_svd.singularValues().size()) = reduced_svd.singularValues();
  for (int k = 0; k < g_cols; ++k) {
    if (a.singular_values(k) >= threshold && a.singular_values(k) > 0.0) continue;
    const Eigen::VectorXd v_g = reduced_svd.matrixV().col(k);
    Eigen::VectorXd full(jacobian.total_cols());
    full.head(g_cols) = v_g;
    int at = g_cols;
    for (int j = 0; j < n; ++j) {
      const int p = static_cast<int>(jacobian.poses[j].pose.cols());
      full.segment(at, p) = -a.poses[j].k * v_g;
      at += p;
    }
    a.null_vectors.push_back(full.normalized());
  }
  return a;
}

namespace {

// (J_r^T J_r)^-1 with geometry column `held` removed (its row and column left zero), or with
// none removed (held < 0). Empty if that system is itself singular.
std::optional<Eigen::MatrixXd> GeometryInverse(const BlockAnalysis& a, int held) {
  const int g_cols = static_cast<int>(a.reduced.cols());
  Eigen::MatrixXd kept(a.reduced.rows(), held < 0 ? g_cols : g_cols - 1);
  std::vector<int> columns;
  for (int c = 0; c < g_cols; ++c) {
    if (c == held) continue;
    kept.col(static_cast<int>(columns.size())) = a.reduced.col(c);
    columns.push_back(c);
  }
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(kept, Eigen::ComputeThinV);
  const Eigen::VectorXd& s = svd.singularValues();
  if (s.size() < kept.cols() || !(s(s.size() - 1) >= a.null_tolerance * a.scale) || !(s(s.size() - 1) > 0.0)) {
    return std::nullopt;
  }
  const Eigen::MatrixXd inner =
      svd.matrixV() * s.cwiseAbs2().cwiseInverse().asDiagonal() * svd.matrixV().transpose();
  Eigen::MatrixXd c = Eigen::MatrixXd::Zero(g_cols, g_cols);
  for (std::size_t a_i = 0; a_i < columns.size(); ++a_i) {
    for (std::size_t b_i = 0; b_i < columns.size(); ++b_i) c(columns[a_i], columns[b_i]) = inner(a_i, b_i);
  }
  return c;
}

}  // namespace

std::optional<BlockCovariance> CovarianceOf(const BlockJacobian& jacobian, const BlockAnalysis& a) {
  if (a.pose_block_deficient || a.null_vectors.size() > 1) return std::nullopt;
  const int g_cols = jacobian.geometry_cols();
  const int n = static_cast<int>(jacobian.poses.size());
  const bool pseudo = a.null_vectors.size() == 1;
  int held = -1;
  if (pseudo) {
    // Holding the geometry column the null direction moves most makes the rest full rank.
    const Eigen::VectorXd u_g = a.null_vectors.front().head(g_cols);
    if (!(u_g.cwiseAbs().maxCoeff(&held) > 1e-6)) return std::nullopt;
  }
  const std::optional<Eigen::MatrixXd> c_gg = GeometryInverse(a, held);
  if (!c_gg) return std::nullopt;

  BlockCovariance cov;
  cov.geometry = *c_gg;
  cov.poses.resize(n);
  for (int j = 0; j < n; ++j) {
    const PoseElimination& e = a.poses[j];
    cov.poses[j] = e.inverse_normal + e.k * cov.geometry * e.k.transpose();
  }
  if (!pseudo) return cov;

  // Pseudo-inverse: P C P with P = I - u u^T, blockwise. w = C u needs the off-diagonal blocks
  // Cov(g, p_j) = -C_gg K_j^T and Cov(p_i, p_j) = K_i C_gg K_j^T only through s = sum K_j^T u_j.
  const Eigen::VectorXd& u = a.null_vectors.front();
  const Eigen::VectorXd u_g = u.head(g_cols);
  Eigen::VectorXd s = Eigen::VectorXd::Zero(g_cols);
  std::vector<Eigen::VectorXd> u_p(n);
  int offset = g_cols;
  for (int j = 0; j < n; ++j) {
    const int p = static_cast<int>(jacobian.poses[j].pose.cols());
    u_p[j] = u.segment(offset, p);
    offset += p;
    s.noalias() += a.poses[j].k.transpose() * u_p[j];
  }
  const Eigen::VectorXd t = cov.geometry * (u_g - s);
  const Eigen::VectorXd& w_g = t;
  double alpha = u_g.dot(w_g);
  std::vector<Eigen::VectorXd> w_p(n);
  for (int j = 0; j < n; ++j) {
    w_p[j] = a.poses[j].inverse_normal * u_p[j] - a.poses[j].k * t;
    alpha += u_p[j].dot(w_p[j]);
  }
  const auto project = [alpha](Eigen::MatrixXd& block, const Eigen::VectorXd& u_b, const Eigen::VectorXd& w_b) {
    block += -u_b * w_b.transpose() - w_b * u_b.transpose() + alpha * u_b * u_b.transpose();
  };
  project(cov.geometry, u_g, w_g);
  for (int j = 0; j < n; ++j) project(cov.poses[j], u_p[j], w_p[j]);
  return cov;
}

std::vector<PoseCheck> CheckPosesAgainstTheOthers(const BlockJacobian& jacobian, const BlockAnalysis& analysis,
                                                  const Eigen::MatrixXd& cov_geometry,
                                                  const std::vector<Eigen::VectorXd>& residuals, double sigmas) {
  const int n = static_cast<int>(jacobian.poses.size());
  CABLECAL_CHECK(static_cast<int>(residuals.size()) == n, "one residual vector per pose");
  constexpr double kNoLeft = 1e-12;  // 1 - leverage below this: the others do not see it at all
  std::vector<PoseCheck> out(n);
  for (int j = 0; j < n; ++j) {
    const PoseBlock& b = jacobian.poses[j];
    const int r = static_cast<int>(b.pose.rows());
    PoseCheck& check = out[j];
    check.min_detectable_sigmas = Eigen::VectorXd::Constant(r, std::numeric_limits<double>::infinity());
    const Eigen::MatrixXd& u2 = analysis.poses[j].u2;  // AnalyzeBlocks' elimination of the pose's unknowns
    const int d = static_cast<int>(u2.cols());
    if (d == 0) continue;
    const Eigen::MatrixXd g = u2.transpose() * b.geometry;
    const Eigen::MatrixXd h = g * cov_geometry * g.transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(Eigen::MatrixXd::Identity(d, d) - h);
    const Eigen::VectorXd lambda = eig.eigenvalues().cwiseMax(0.0);
    const Eigen::VectorXd e = eig.eigenvectors().transpose() * (u2.transpose() * residuals[j]);
    for (int k = 0; k < d; ++k) {
      if (lambda(k) > kNoLeft) check.deleted_residual_sigmas = std::max(check.deleted_residual_sigmas, std::abs(e(k)) / std::sqrt(lambda(k)));
    }
    // (I - h)^1/2 U2^T, row by row of the block.
    const Eigen::MatrixXd shown = lambda.cwiseSqrt().asDiagonal() * eig.eigenvectors().transpose() * u2.transpose();
    for (int i = 0; i < r; ++i) {
      const double gain = shown.col(i).norm();
      if (gain > 0.0) check.min_detectable_sigmas(i) = sigmas / gain;
    }
  }
  return out;
}

BlockCovariance SandwichCovariance(const BlockJacobian& jacobian, const BlockAnalysis& analysis,
                                   const BlockCovariance& inverse,
                                   const std::vector<Eigen::MatrixXd>& residual_covariance) {
  const int n = static_cast<int>(jacobian.poses.size());
  CABLECAL_CHECK(analysis.null_vectors.empty() && static_cast<int>(residual_covariance.size()) == n,
                 "a sandwich for a full-rank problem, one residual covariance per pose");
  const Eigen::MatrixXd& c_gg = inverse.geometry;
  Eigen::MatrixXd meat = jacobian.prior.transpose() * jacobian.prior;
  std::vector<Eigen::MatrixXd> r(n);
  for (int j = 0; j < n; ++j) {
    const PoseBlock& b = jacobian.poses[j];
    r[j] = b.geometry - b.pose * analysis.poses[j].k;
    meat.noalias() += r[j].transpose() * residual_covariance[j] * r[j];
  }
  BlockCovariance out;
  out.geometry = c_gg * meat * c_gg;
  out.poses.resize(n);
  for (int j = 0; j < n; ++j) {
    const PoseElimination& e = analysis.poses[j];
    const Eigen::MatrixXd a = e.inverse_normal * jacobian.poses[j].pose.transpose();
    const Eigen::MatrixXd cross = a * residual_covariance[j] * r[j] * c_gg * e.k.transpose();
    out.poses[j] = e.k * out.geometry * e.k.transpose() + a * residual_covariance[j] * a.transpose() - cross -
                   cross.transpose();
  }
  return out;
}

}  // namespace cablecal
