// The identification Jacobian, pose by pose, as used by the experiment design.
//
// Its entries follow from the cable geometry the whole tool shares (model/cable.h): with u_i
// the unit vector from anchor B_i toward the pulley, dl_i/dB_i = -u_i and dl_i/da_i = +u_i
// (the exit point moves the pulley centre; the tangent point's motion does not change the
// length to first order), and dl_i/dq = -W(:, i)' (virtual work). Writing the rows from u_i
// and W keeps them in one scalar template the design can evaluate with single-level Jets
// for their pose derivatives. tests/identify/jacobian_test.cc checks them against automatic
// differentiation of the identification's residuals (residuals.h) and against the Jacobian
// Ceres evaluates inside Identify.
#pragma once

#include <Eigen/Dense>

#include "model/cable.h"
#include "model/robot.h"

namespace cablecal {

// Columns of one pose's rows: the 6 geometric parameters a1x a1z a2x a2z l10 l20, then the
// pose's own unknowns. `robot` carries the geometry (exit points) the rows are taken at.
template <typename T>
using LengthRows = Eigen::Matrix<T, 2, 7>;  // pose unknown: x
template <typename T>
using MlRows = Eigen::Matrix<T, 4, 9>;      // pose unknowns: x, z, theta

// d r_ij / d(geometry, x_j) of the length residuals r_ij = l_i - (dl_ij + l_i0), in metres
// and unscaled: pose j's rows of the paper-form Jacobian without the squares (Eq. 6).
template <typename T>
LengthRows<T> LengthResidualRows(const Robot& robot, const Pose<T>& q) {
  const Eigen::Matrix<T, 3, Eigen::Dynamic> W = WrenchMatrix<T>(robot, q);
  LengthRows<T> rows = LengthRows<T>::Zero();
  for (int i = 0; i < 2; ++i) {
    rows(i, 2 * i) = W(0, i);      // dl/da_ix = u_x
    rows(i, 2 * i + 1) = W(1, i);  // dl/da_iz = u_z
    rows(i, 4 + i) = T(-1.0);      // d/dl_i0
    rows(i, 6) = -W(0, i);         // dl/dx = -u_x
  }
  return rows;
}

// The maximum-likelihood estimator's whitened rows for one pose: two encoder rows (length
// residual / sigma_enc), the laser row and the inclinometer row; columns: geometry (6),
// then x, z, theta.
template <typename T>
MlRows<T> MlResidualRows(const Robot& robot, const Pose<T>& q) {
  const Eigen::Matrix<T, 3, Eigen::Dynamic> W = WrenchMatrix<T>(robot, q);
  const double inv_enc = 1.0 / robot.sensors.encoder_sigma_m;
  MlRows<T> rows = MlRows<T>::Zero();
  for (int i = 0; i < 2; ++i) {
    rows(i, 2 * i) = W(0, i) * inv_enc;
    rows(i, 2 * i + 1) = W(1, i) * inv_enc;
    rows(i, 4 + i) = T(-inv_enc);
    for (int k = 0; k < 3; ++k) rows(i, 6 + k) = -W(k, i) * inv_enc;
  }
  rows(2, 7) = T(1.0 / robot.sensors.laser_sigma_m());
  rows(3, 8) = T(1.0 / robot.sensors.inclinometer_sigma_rad());
  return rows;
}

// One pose's contribution to the information of the geometric parameters once its own
// unknowns are eliminated (Schur complement): S_j = G'(I - P (P'P)^-1 P')G over the rows of
// MlResidualRows, G the geometric columns kept by the gauge (a1x dropped: 5 x 5), P the pose
// columns. With 4 rows and 3 pose unknowns the projector onto the complement of P's columns
// has rank one, I - P (P'P)^-1 P' = n n' with n the unit normal of P's columns (their
// generalised cross product in R^4), so S_j = g g' with g = G'n: no normal equations, no
// cancellation. The information of the whole experiment is the sum over its poses.
template <typename T>
Eigen::Matrix<T, 5, 5> ReducedInformation(const MlRows<T>& rows) {
  const Eigen::Matrix<T, 4, 5> G = rows.template block<4, 5>(0, 1);
  const Eigen::Matrix<T, 4, 3> P = rows.template block<4, 3>(0, 6);
  Eigen::Matrix<T, 4, 1> n;
  for (int i = 0; i < 4; ++i) {
    Eigen::Matrix<T, 3, 3> minor;
    for (int r = 0, k = 0; r < 4; ++r) {
      if (r != i) minor.row(k++) = P.row(r);
    }
    n(i) = (i % 2 == 0 ? T(1.0) : T(-1.0)) * minor.determinant();
  }
  using std::sqrt;
  n /= sqrt(n.squaredNorm());
  const Eigen::Matrix<T, 5, 1> g = G.transpose() * n;
  return g * g.transpose();
}

}  // namespace cablecal
