// Tension distribution of a robot with at least as many cables m as its wrench has rows d
// (planar d = 3, spatial d = 6; statics.h, DistributeTensions).
//
// W t = b (b = -w_g) has the solutions t = t_p + N lambda, with t_p = W^+ b the minimum-norm
// one and N an orthonormal basis of W's null space (m - d columns). t_p is orthogonal to N's
// columns, so |t|^2 = |t_p|^2 + |lambda|^2: the minimum-norm t within the bounds is the
// lambda of least norm with lo - t_p <= N lambda <= hi - t_p, a least-distance problem (LDP).
// Lawson & Hanson (Solving Least Squares Problems, 1974, ch. 23) solve LDP exactly through one
// non-negative least-squares problem, and say when it is infeasible: no iteration count or
// tolerance decides the answer, only the NNLS's finite active-set steps.
#include <Eigen/Dense>
#include <cmath>
#include <limits>
#include <optional>
#include <vector>

#include "common/error.h"
#include "model/cable.h"
#include "model/statics.h"

namespace cablecal {
namespace {

// Lawson-Hanson NNLS: min |E u - f| subject to u >= 0 (the book's algorithm NNLS, ch. 23).
Eigen::VectorXd NonNegativeLeastSquares(const Eigen::MatrixXd& E, const Eigen::VectorXd& f) {
  const int n = static_cast<int>(E.cols());
  Eigen::VectorXd u = Eigen::VectorXd::Zero(n);
  std::vector<bool> passive(n, false);
  const double tol = 1e-12 * std::max(1.0, E.cwiseAbs().maxCoeff()) * std::max(1.0, f.cwiseAbs().maxCoeff());
  // Each outer step adds one column to the passive set and the inner loop only removes
  // columns, so 3n outer steps are far more than the algorithm needs; the cap only guards
  // against rounding cycling.
  for (int outer = 0; outer < 3 * n + 3; ++outer) {
    const Eigen::VectorXd w = E.transpose() * (f - E * u);
    int t = -1;
    double w_max = tol;
    for (int j = 0; j < n; ++j) {
      if (!passive[j] && w(j) > w_max) {
        w_max = w(j);
        t = j;
      }
    }
    if (t < 0) break;
    passive[t] = true;
    for (int inner = 0; inner < 3 * n + 3; ++inner) {
      std::vector<int> cols;
      for (int j = 0; j < n; ++j) {
        if (passive[j]) cols.push_back(j);
      }
      Eigen::MatrixXd Ep(E.rows(), static_cast<Eigen::Index>(cols.size()));
      for (std::size_t k = 0; k < cols.size(); ++k) Ep.col(static_cast<Eigen::Index>(k)) = E.col(cols[k]);
      const Eigen::VectorXd zp = Ep.colPivHouseholderQr().solve(f);
      Eigen::VectorXd z = Eigen::VectorXd::Zero(n);
      for (std::size_t k = 0; k < cols.size(); ++k) z(cols[k]) = zp(static_cast<Eigen::Index>(k));
      bool positive = true;
      for (int j : cols) positive = positive && z(j) > 0.0;
      if (positive) {
        u = z;
        break;
      }
      // Step from u toward z as far as u stays non-negative; columns reaching 0 leave.
      double alpha = 1.0;
      for (int j : cols) {
        if (z(j) <= 0.0) alpha = std::min(alpha, u(j) / (u(j) - z(j)));
      }
      u += alpha * (z - u);
      for (int j : cols) {
        if (u(j) <= 1e-15 * std::max(1.0, u.cwiseAbs().maxCoeff())) {
          u(j) = 0.0;
          passive[j] = false;
        }
      }
    }
  }
  return u;
}

// Least-distance programming: the x of least norm with G x >= h, or nothing if none exists.
std::optional<Eigen::VectorXd> LeastDistance(const Eigen::MatrixXd& G, const Eigen::VectorXd& h) {
  const int k = static_cast<int>(G.cols());
  const int p = static_cast<int>(G.rows());
  Eigen::MatrixXd E(k + 1, p);
  E.topRows(k) = G.transpose();
  E.row(k) = h.transpose();
  Eigen::VectorXd f = Eigen::VectorXd::Zero(k + 1);
  f(k) = 1.0;
  const Eigen::VectorXd u = NonNegativeLeastSquares(E, f);
  const Eigen::VectorXd r = E * u - f;
  // |r| = 0 (to rounding): the constraints are inconsistent (Lawson & Hanson, Theorem 23.4).
  if (!(std::abs(r(k)) > 1e-9)) return std::nullopt;
  return Eigen::VectorXd(-r.head(k) / r(k));
}

// The minimum-norm t with W t = b and lo <= t <= hi (hi may be +inf), for m >= 4; rows of
// the constraints are scaled by `scale_N` so that the NNLS works with numbers near one.
std::optional<Eigen::VectorXd> MinimumNormWithin(const Eigen::VectorXd& t_p, const Eigen::MatrixXd& N, double lo,
                                                 double hi, double scale_N) {
  const int m = static_cast<int>(t_p.size());
  const int k = static_cast<int>(N.cols());
  const bool upper = std::isfinite(hi);
  Eigen::MatrixXd G((upper ? 2 : 1) * m, k);
  Eigen::VectorXd h((upper ? 2 : 1) * m);
  G.topRows(m) = N;  // N lambda >= lo - t_p
  h.head(m) = (Eigen::VectorXd::Constant(m, lo) - t_p) / scale_N;
  if (upper) {
    G.bottomRows(m) = -N;  // -N lambda >= t_p - hi
    h.tail(m) = (t_p - Eigen::VectorXd::Constant(m, hi)) / scale_N;
  }
  const std::optional<Eigen::VectorXd> lambda = LeastDistance(G, h);
  if (!lambda) return std::nullopt;
  Eigen::VectorXd t = t_p + N * (*lambda * scale_N);
  // The solution sits on some bounds; rounding may leave it a few ulps outside them.
  const double slack = 1e-9 * scale_N;
  for (int i = 0; i < m; ++i) {
    if (t(i) < lo && t(i) > lo - slack) t(i) = lo;
    if (upper && t(i) > hi && t(i) < hi + slack) t(i) = hi;
  }
  return t;
}

}  // namespace

TensionDistribution DistributeTensions(const Eigen::MatrixXd& W, const Eigen::VectorXd& gravity_wrench,
                                       double tension_min_N, double tension_max_N, double weight_N) {
  const int d = static_cast<int>(W.rows());
  const int m = static_cast<int>(W.cols());
  CABLECAL_CHECK(m >= d && gravity_wrench.size() == d, "a tension distribution needs at least as many cables as "
                                                       "the wrench has rows, and a gravity wrench of that size");
  TensionDistribution out;
  const Eigen::VectorXd b = -gravity_wrench;
  if (!W.allFinite()) return out;
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(W, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::VectorXd& sv = svd.singularValues();
  // Force rows are unit vectors and moment rows lever arms of the platform's size: a
  // singular value this small is a singular pose (cables in a line), not a small lever.
  if (!(sv(d - 1) > 1e-9 * std::max(1.0, sv(0)))) return out;
  const double positive_N = 1e-9 * weight_N;  // "taut": strictly above 0, beyond rounding
  if (m == d) {
    const Eigen::VectorXd t = svd.solve(b);
    if (!(t.minCoeff() > positive_N)) return out;
    out.tensions_N = t;
    out.feasibility = t.minCoeff() < tension_min_N   ? Feasibility::kTensionLow
                      : t.maxCoeff() > tension_max_N ? Feasibility::kTensionHigh
                                                     : Feasibility::kFeasible;
    return out;
  }
  const Eigen::VectorXd t_p = svd.solve(b);
  const Eigen::MatrixXd N = svd.matrixV().rightCols(m - d);
  constexpr double kInf = std::numeric_limits<double>::infinity();
  if (auto t = MinimumNormWithin(t_p, N, tension_min_N, tension_max_N, weight_N)) {
    out.feasibility = Feasibility::kFeasible;
    out.tensions_N = *t;
  } else if (auto t_low = MinimumNormWithin(t_p, N, tension_min_N, kInf, weight_N)) {
    out.feasibility = Feasibility::kTensionHigh;
    out.tensions_N = *t_low;
  } else if (auto t_pos = MinimumNormWithin(t_p, N, positive_N, kInf, weight_N)) {
    out.feasibility = Feasibility::kTensionLow;
    out.tensions_N = *t_pos;
  }
  return out;
}

TensionDistribution DistributeTensions(const Robot& robot, const Eigen::Vector3d& q) {
  CABLECAL_CHECK(robot.num_cables() >= 3, "a tension distribution is chosen for 3 or more cables; 2 cables fix theta");
  return DistributeTensions(WrenchMatrix<double>(robot, q), GravityWrench<double>(robot, q), robot.tension_min_N,
                            robot.tension_max_N, robot.platform_mass_kg * robot.gravity_mps2);
}

}  // namespace cablecal
