// The identification Jacobian, pose by pose, as used by the experiment design (design/).
//
// One source: the rows are the automatic derivatives of the very residual functions the
// identification's Ceres cost functors evaluate (identify/residuals.h), taken here with a Jet
// of 6 directions that covers every column (the geometry's 3M entries, then the pose's x, z,
// theta) through the residuals' structure (column compression, below).
// To give the design the rows' derivatives with respect to the pose as well, the scalar T
// may itself be a Jet over the pose, nested_jet::InnerJet<3> (identify/nested_jet.h): the
// result's entries then carry d(row entry)/d(x, z, theta), exact second derivatives.
// tests/identify/jacobian_test.cc checks the rows against the Jacobian Ceres evaluates inside
// Identify and against the virtual-work form (dl_i/da_i = u_i, dl_i/dq = -W(:, i)').
#pragma once

#include <ceres/jet.h>

#include <Eigen/Dense>

#include "identify/nested_jet.h"
#include "identify/residuals.h"
#include "model/cable.h"
#include "model/robot.h"

namespace cablecal {

// Columns of one pose's rows: the 3M geometric parameters a1x a1z ... aMx aMz l10 ... lM0,
// then the pose's own unknowns x, z, theta. `robot` carries the geometry (exit points) the
// rows are taken at; the rows do not depend on the initial lengths or on the readings.
template <int M>
constexpr int kRowColumns = 3 * M + 3;
template <int M, typename T>
using LengthRows = Eigen::Matrix<T, M, kRowColumns<M>>;  // d r_ij, the length residuals (m)
template <int M, typename T>
using MlRows = Eigen::Matrix<T, M + 2, kRowColumns<M>>;  // the ml estimator's whitened residuals

namespace jacobian_internal {

// Column compression (Curtis, Powell and Reid): cable i's residual depends on its own exit
// point and initial length only, and the laser's and inclinometer's on the pose only, so the
// columns a_1x .. a_Mx can share one Jet direction, a_1z .. a_Mz another, l_10 .. l_M0 a third,
// and x, z, theta take one each: 6 directions whatever M, and the Jacobian is read back
// exactly from where each column's entries can be. (tests/identify/jacobian_test.cc compares
// the result with the full Jacobian Ceres evaluates, which would show any other dependence.)
constexpr int kDirections = 6;
constexpr int kExitX = 0, kExitZ = 1, kInitialLength = 2, kPose = 3;

// The Jet over those directions, on top of T (double, or an InnerJet for pose derivatives).
template <typename T>
struct DirectionJet {
  using type = ceres::Jet<T, kDirections>;
};
template <int K>
struct DirectionJet<nested_jet::InnerJet<K>> {
  using type = nested_jet::Outer<K, kDirections>;
};

// Seeds the geometry (the robot's exit points; initial lengths 0: they enter linearly) and
// the pose.
template <int M, typename T, typename J>
void Seed(const Robot& robot, const Pose<T>& q, J* geometry, J* pose) {
  for (int i = 0; i < M; ++i) {
    geometry[2 * i] = J(T(robot.cables[i].p_F_exit_m.x()), kExitX);
    geometry[2 * i + 1] = J(T(robot.cables[i].p_F_exit_m.y()), kExitZ);
    geometry[2 * M + i] = J(T(0.0), kInitialLength);
  }
  for (int k = 0; k < 3; ++k) pose[k] = J(q(k), kPose + k);
}

// Row i < M belongs to cable i: its geometry entries sit in cable i's three columns.
// Rows M and beyond (laser, inclinometer) have pose entries only.
template <int M, typename J, typename Rows>
void Unpack(const J* residual, Rows* rows) {
  rows->setZero();
  for (int r = 0; r < rows->rows(); ++r) {
    if (r < M) {
      (*rows)(r, 2 * r) = residual[r].v[kExitX];
      (*rows)(r, 2 * r + 1) = residual[r].v[kExitZ];
      (*rows)(r, 2 * M + r) = residual[r].v[kInitialLength];
    }
    for (int k = 0; k < 3; ++k) (*rows)(r, 3 * M + k) = residual[r].v[kPose + k];
  }
}

}  // namespace jacobian_internal

// d r_ij / d(geometry, x_j, z_j, theta_j) of the length residuals r_ij = l_i - (dl_ij + l_i0)
// (residuals.h LengthResiduals), in metres and unscaled: pose j's rows of the paper-form
// Jacobian without the squares (Eq. 6).
template <int M, typename T>
LengthRows<M, T> LengthResidualRows(const Robot& robot, const Pose<T>& q) {
  using J = typename jacobian_internal::DirectionJet<T>::type;
  J geometry[3 * M], pose[3], residual[M];
  jacobian_internal::Seed<M, T, J>(robot, q, geometry, pose);
  const double dl_m[M] = {};
  LengthResiduals<M, J>(robot, geometry, Pose<J>(pose[0], pose[1], pose[2]), dl_m, residual);
  LengthRows<M, T> rows;
  jacobian_internal::Unpack<M>(residual, &rows);
  return rows;
}

// The maximum-likelihood estimator's whitened rows for one pose (residuals.h MlResiduals):
// M encoder rows, the laser row and the inclinometer row.
template <int M, typename T>
MlRows<M, T> MlResidualRows(const Robot& robot, const Pose<T>& q) {
  using J = typename jacobian_internal::DirectionJet<T>::type;
  J geometry[3 * M], pose[3], residual[M + 2];
  jacobian_internal::Seed<M, T, J>(robot, q, geometry, pose);
  MlResiduals<M, J>(robot, PoseReadings<M>{}, WeightsOf(robot.sensors), geometry, pose, residual);
  MlRows<M, T> rows;
  jacobian_internal::Unpack<M>(residual, &rows);
  return rows;
}

// One pose's contribution to the information of the geometric parameters once its own
// unknowns are eliminated (Schur complement): S_j = G'(I - P (P'P)^-1 P')G over the rows of
// MlResidualRows, G the geometric columns kept by the gauge (a1x dropped: 3M - 1 of them), P
// the pose columns. The projector onto the complement of P's columns has rank M - 1 (M + 2
// rows, 3 pose unknowns). It is formed from an orthonormal basis E of P's columns (modified
// Gram-Schmidt, repeated once, which keeps E orthonormal to rounding): G_perp = G - E (E'G),
// S_j = G_perp' G_perp. No normal equations of P (whose whitened columns differ in scale by
// the sensors' sigmas), and S_j is symmetric positive semi-definite by construction. The
// information of the whole experiment is the sum over its poses.
template <int M, typename T>
Eigen::Matrix<T, 3 * M - 1, 3 * M - 1> ReducedInformation(const MlRows<M, T>& rows) {
  using std::sqrt;
  const Eigen::Matrix<T, M + 2, 3 * M - 1> G = rows.template block<M + 2, 3 * M - 1>(0, 1);
  Eigen::Matrix<T, M + 2, 3> E = rows.template block<M + 2, 3>(0, 3 * M);
  for (int k = 0; k < 3; ++k) {
    for (int pass = 0; pass < 2; ++pass) {
      for (int l = 0; l < k; ++l) {
        const T projection = E.col(l).dot(E.col(k));
        E.col(k) -= projection * E.col(l);
      }
    }
    // Times the inverse, not divided: the same operations on a double as on an InnerJet's
    // value (a Jet divides that way), so that both give the same S_j to the last bit.
    const T inverse_norm = T(1.0) / sqrt(E.col(k).squaredNorm());
    E.col(k) *= inverse_norm;
  }
  const Eigen::Matrix<T, M + 2, 3 * M - 1> G_perp = G - E * (E.transpose() * G);
  return G_perp.transpose() * G_perp;
}

}  // namespace cablecal
