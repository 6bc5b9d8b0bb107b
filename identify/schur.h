// Covariance and identifiability of an identification through its Jacobian's block-arrow
// structure, at a cost linear in the number of poses.
//
// Each pose's readings depend on the geometry and on that pose's own unknowns only, so the
// whitened Jacobian is block-arrow: per pose j, rows [J_gj | J_pj] (J_pj: r x p, p = 3 for ml,
// 1 for paper), plus prior rows on the geometry alone. The SVD of each small J_pj = U S V^T
// eliminates that pose's unknowns: with U2 the left singular vectors outside J_pj's range, the
// rows U2^T J_gj carry what pose j says about the geometry once its own unknowns are fitted
// (a square-root Schur complement). Stacked with the prior rows they form the reduced geometry
// Jacobian J_r, whose normal matrix is the Schur complement S = H_gg - H_gp H_pp^-1 H_pg, and
//   Cov(g)     = S^-1
//   Cov(p_j)   = (J_pj^T J_pj)^-1 + K_j Cov(g) K_j^T,   K_j = J_pj^+ J_gj
//   Cov(g,p_j) = -Cov(g) K_j^T.
// With one null direction u (gauge none) the Moore-Penrose pseudo-inverse is P C P, P = I - uu^T,
// for any generalised inverse C of J^T J: we take C from J with one geometry column held.
// Depends on Eigen only.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <vector>

namespace cablecal {

struct PoseBlock {
  Eigen::MatrixXd geometry;  // r x G: this pose's rows, geometry columns
  Eigen::MatrixXd pose;      // r x p: the same rows, this pose's own columns (r > p when they fix them)
};

struct BlockJacobian {
  std::vector<PoseBlock> poses;
  Eigen::MatrixXd prior;  // rows on the geometry alone (0 rows if none) x G
  int geometry_cols() const;
  int total_cols() const;  // G + sum of p_j: the columns of the full Jacobian
};

struct PoseElimination {
  Eigen::MatrixXd inverse_normal;  // p x p: (J_p^T J_p)^-1 (pseudo-inverse if J_p is deficient)
  Eigen::MatrixXd k;               // p x G: J_p^+ J_g (how the pose estimate follows the geometry)
  Eigen::MatrixXd u2;              // r x (r - rank): the pose's readings' directions outside J_p's range
  double min_singular_value = 0.0, max_singular_value = 0.0;  // of J_p
};

struct BlockAnalysis {
  std::vector<PoseElimination> poses;
  Eigen::MatrixXd reduced;            // J_r: the reduced geometry Jacobian
  Eigen::VectorXd singular_values;    // of J_r, descending, G of them (zeros if J_r has fewer rows)
  double scale = 0.0;                 // largest singular value of the geometry or of any pose block
  double null_tolerance = 0.0;        // relative to scale
  int weakest_pose = -1;              // index of the pose block with the smallest singular value
  // Directions the data cannot see (singular value below null_tolerance x scale), as unit
  // vectors over every column: the geometry's, then each pose's in order.
  std::vector<Eigen::VectorXd> null_vectors;
  bool pose_block_deficient = false;  // some pose's own unknowns are not fixed by its readings
};

// Eliminates every pose block and finds the null directions. Linear in the number of poses.
BlockAnalysis AnalyzeBlocks(const BlockJacobian& jacobian, double null_tolerance);

struct BlockCovariance {
  Eigen::MatrixXd geometry;            // G x G
  std::vector<Eigen::MatrixXd> poses;  // p_j x p_j each
};

// The covariance (J^T J)^-1, or its pseudo-inverse when `analysis` found exactly one null
// direction with a geometric component; nothing when the problem has more null directions or
// one confined to a pose's own unknowns.
std::optional<BlockCovariance> CovarianceOf(const BlockJacobian& jacobian, const BlockAnalysis& analysis);

// How well the other poses check each pose's readings: deletion diagnostics of a whitened
// least-squares fit, linearised at the solution. Each pose's own unknowns are profiled out
// (U2, as in AnalyzeBlocks), leaving its d = r - p redundant combinations e~ = U2^T e and
// their geometry rows G~ = U2^T J_g; h = G~ Cov(g) G~^T is the pose's leverage on them. With
// I - h = V diag(lambda) V^T, z = diag(lambda)^-1/2 V^T e~ is the pose's residual against the
// fit of the others, standardized: N(0, I) for clean readings. A bad reading that the fit
// absorbed (a pose of high leverage: lambda small) leaves e~ small but z large. An error of
// delta sigma in row i alone moves z by (I - h)^1/2 U2^T e_i delta: the smallest error that
// shows beyond `sigmas` is sigmas / |(I - h)^1/2 U2^T e_i| (infinite where nothing checks it).
struct PoseCheck {
  double deleted_residual_sigmas = 0.0;  // max |z|
  Eigen::VectorXd min_detectable_sigmas;  // per row of the pose's block
};
std::vector<PoseCheck> CheckPosesAgainstTheOthers(const BlockJacobian& jacobian, const BlockAnalysis& analysis,
                                                  const Eigen::MatrixXd& cov_geometry,
                                                  const std::vector<Eigen::VectorXd>& residuals, double sigmas);

// The sandwich covariance C M C of an estimator whose residuals are not whitened (the paper's
// Eq. 6 residuals, which also carry the laser's and inclinometer's noise): C = (J^T J)^-1 as
// `inverse` (CovarianceOf, no null direction), M = J^T Sigma J with Sigma the residuals'
// covariance, block-diagonal by pose (`residual_covariance[j]`: pose j's rows) and the identity
// on the prior rows (whitened). With R_j = J_gj - J_pj K_j (pose j's geometry columns once its
// own unknowns are fitted) and a_j = (J_pj^T J_pj)^-1 J_pj^T:
//   Cov(g)   = C_gg (sum_j R_j^T Sigma_j R_j + P^T P) C_gg
//   Cov(p_j) = K_j Cov(g) K_j^T + a_j Sigma_j a_j^T - (a_j Sigma_j R_j C_gg K_j^T + its transpose).
// Linear in the number of poses.
BlockCovariance SandwichCovariance(const BlockJacobian& jacobian, const BlockAnalysis& analysis,
                                   const BlockCovariance& inverse,
                                   const std::vector<Eigen::MatrixXd>& residual_covariance);

}  // namespace cablecal
