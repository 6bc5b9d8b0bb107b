// The block-structured covariance and identifiability (identify/schur.h) against the same
// quantities computed densely from the whole Jacobian: full rank, one null direction across
// the geometry and every pose (the gauge), and a pose whose own unknowns its rows cannot fix.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>

#include "identify/schur.h"

namespace cablecal {
namespace {

constexpr int kGeometry = 6;

BlockJacobian RandomBlocks(int n, int rows, int pose_cols, int prior_rows, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  const auto random = [&](int r, int c) {
    Eigen::MatrixXd m(r, c);
    for (int i = 0; i < r; ++i)
      for (int k = 0; k < c; ++k) m(i, k) = normal(rng);
    return m;
  };
  BlockJacobian j;
  for (int p = 0; p < n; ++p) j.poses.push_back({random(rows, kGeometry), random(rows, pose_cols) * 30.0});
  j.prior = random(prior_rows, kGeometry);
  return j;
}

Eigen::MatrixXd Dense(const BlockJacobian& j) {
  int rows = static_cast<int>(j.prior.rows());
  for (const PoseBlock& b : j.poses) rows += static_cast<int>(b.pose.rows());
  Eigen::MatrixXd d = Eigen::MatrixXd::Zero(rows, j.total_cols());
  int row = 0, col = kGeometry;
  for (const PoseBlock& b : j.poses) {
    d.block(row, 0, b.geometry.rows(), kGeometry) = b.geometry;
    d.block(row, col, b.pose.rows(), b.pose.cols()) = b.pose;
    row += static_cast<int>(b.pose.rows());
    col += static_cast<int>(b.pose.cols());
  }
  d.bottomLeftCorner(j.prior.rows(), kGeometry) = j.prior;
  return d;
}

// The Moore-Penrose pseudo-inverse of J^T J, dropping singular values below 1e-9 x the largest.
Eigen::MatrixXd DensePseudoInverse(const Eigen::MatrixXd& d) {
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(d, Eigen::ComputeThinV);
  Eigen::VectorXd inv = svd.singularValues();
  for (int k = 0; k < inv.size(); ++k) inv(k) = inv(k) > 1e-9 * inv(0) ? 1.0 / (inv(k) * inv(k)) : 0.0;
  return svd.matrixV() * inv.asDiagonal() * svd.matrixV().transpose();
}

void ExpectMatchesDense(const BlockJacobian& j, const BlockCovariance& cov) {
  const Eigen::MatrixXd c = DensePseudoInverse(Dense(j));
  const double tol = 1e-9 * c.cwiseAbs().maxCoeff();
  EXPECT_LE((cov.geometry - c.topLeftCorner(kGeometry, kGeometry)).cwiseAbs().maxCoeff(), tol);
  int col = kGeometry;
  for (std::size_t p = 0; p < j.poses.size(); ++p) {
    const int size = static_cast<int>(j.poses[p].pose.cols());
    EXPECT_LE((cov.poses[p] - c.block(col, col, size, size)).cwiseAbs().maxCoeff(), tol) << "pose " << p;
    col += size;
  }
}

TEST(Schur, FullRankCovarianceEqualsTheDenseInverse) {
  for (const int pose_cols : {1, 3}) {
    const BlockJacobian j = RandomBlocks(12, pose_cols + 1, pose_cols, 4, 7 + pose_cols);
    const BlockAnalysis a = AnalyzeBlocks(j, 1e-9);
    EXPECT_TRUE(a.null_vectors.empty());
    const auto cov = CovarianceOf(j, a);
    ASSERT_TRUE(cov.has_value());
    ExpectMatchesDense(j, *cov);
    // The reduced Jacobian's singular values are the square roots of the Schur complement's
    // eigenvalues, the complement computed densely from the normal matrix.
    const Eigen::MatrixXd d = Dense(j);
    const Eigen::MatrixXd h = d.transpose() * d;
    const int p = j.total_cols() - kGeometry;
    const Eigen::MatrixXd s = h.topLeftCorner(kGeometry, kGeometry) -
                              h.topRightCorner(kGeometry, p) *
                                  h.bottomRightCorner(p, p).ldlt().solve(h.bottomLeftCorner(p, kGeometry));
    Eigen::VectorXd expected = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(s).eigenvalues().cwiseSqrt().reverse();
    for (int k = 0; k < kGeometry; ++k) EXPECT_NEAR(a.singular_values(k), expected(k), 1e-9 * expected(0));
  }
}

TEST(Schur, OneNullDirectionGivesTheDensePseudoInverse) {
  // The gauge's kind of null direction: geometry columns 0 and 2 move with every pose's first
  // unknown (a common shift of a1x, a2x and every x_j).
  BlockJacobian j = RandomBlocks(15, 4, 3, 0, 3);
  Eigen::VectorXd u = Eigen::VectorXd::Zero(j.total_cols());
  u(0) = u(2) = 1.0;
  for (std::size_t p = 0; p < j.poses.size(); ++p) {
    PoseBlock& b = j.poses[p];
    b.pose.col(0) = -(b.geometry.col(0) + b.geometry.col(2));
    u(kGeometry + 3 * static_cast<int>(p)) = 1.0;
  }
  u.normalize();
  ASSERT_LE((Dense(j) * u).norm(), 1e-12);
  const BlockAnalysis a = AnalyzeBlocks(j, 1e-9);
  ASSERT_EQ(a.null_vectors.size(), 1u);
  EXPECT_NEAR(std::abs(a.null_vectors[0].dot(u)), 1.0, 1e-12);
  EXPECT_LT(a.singular_values(kGeometry - 1), 1e-9 * a.scale);
  EXPECT_GT(a.singular_values(kGeometry - 2), 1e-3 * a.singular_values(0));
  const auto cov = CovarianceOf(j, a);
  ASSERT_TRUE(cov.has_value());
  ExpectMatchesDense(j, *cov);
}

TEST(Schur, APoseItsRowsCannotFixIsANullDirectionAndNoCovariance) {
  BlockJacobian j = RandomBlocks(8, 4, 3, 0, 5);
  j.poses[5].pose.col(2) = 2.0 * j.poses[5].pose.col(1);  // pose 5: two unknowns, one effect
  const BlockAnalysis a = AnalyzeBlocks(j, 1e-9);
  EXPECT_TRUE(a.pose_block_deficient);
  EXPECT_EQ(a.weakest_pose, 5);
  ASSERT_EQ(a.null_vectors.size(), 1u);
  // Only pose 5's own columns move: (0, 2, -1) / sqrt(5) up to sign.
  Eigen::VectorXd expected = Eigen::VectorXd::Zero(j.total_cols());
  expected.segment(kGeometry + 15 + 1, 2) << 2.0, -1.0;
  EXPECT_NEAR(std::abs(a.null_vectors[0].dot(expected.normalized())), 1.0, 1e-12);
  EXPECT_FALSE(CovarianceOf(j, a).has_value());
}

TEST(Schur, TwoNullDirectionsGiveNoCovariance) {
  BlockJacobian j = RandomBlocks(10, 2, 1, 0, 9);
  for (PoseBlock& b : j.poses) b.geometry.col(4) = b.geometry.col(5) = b.geometry.col(3);
  const BlockAnalysis a = AnalyzeBlocks(j, 1e-9);
  EXPECT_EQ(a.null_vectors.size(), 2u);
  EXPECT_FALSE(CovarianceOf(j, a).has_value());
}

}  // namespace
}  // namespace cablecal
