// The identification Jacobian, pose by pose, as used by the experiment design (design/).
//
// One source: the rows are the automatic derivatives of the very residual functions the
// identification's Ceres cost functors evaluate (identify/residuals.h), taken here with a Jet
// of 6 directions that covers every column (the geometry's 3M entries, then the pose's x, z,
// theta) through the residuals' structure (column compression, jacobian.cc).
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
#include "model/geometry.h"
#include "model/kind.h"
#include "model/robot.h"

namespace cablecal {

// Columns of one pose's rows: the 3m geometric parameters a1x a1z ... amx amz l10 ... lm0,
// then the pose's own unknowns x, z, theta (m = robot.num_cables()). `robot` carries the
// geometry (exit points) the rows are taken at; the rows do not depend on the initial lengths
// or on the readings. The sizes are run-time ones: the design's criteria are written once for
// every cable count, and compile-time sizes would instantiate them (on nested Jets) seven
// times, minutes of compilation for no measurable gain.
inline int RowColumns(int num_cables) { return PlanarLayout(num_cables).size() + PlanarKind::kPoseDim; }
template <typename T>
using Rows = Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic>;

// The functions below are defined in jacobian.cc for T = double and T =
// nested_jet::InnerJet<3> (the design's pose derivatives) only.

// d r_ij / d(geometry, x_j, z_j, theta_j) of the length residuals r_ij = l_i - (dl_ij + l_i0)
// (residuals.h LengthResiduals), in metres and unscaled: pose j's rows of the paper-form
// Jacobian without the squares (Eq. 6); m x RowColumns(m). Row i belongs to cable i: its
// geometry entries sit in cable i's three columns.
template <typename T>
Rows<T> LengthResidualRows(const Robot& robot, const Pose<T>& q);

// The maximum-likelihood estimator's whitened rows for one pose (residuals.h MlResiduals):
// m encoder rows (the length rows over the encoder's sigma, as MlLengthResiduals scales
// them), the laser row and the inclinometer row (MlSensorResiduals, differentiated);
// (m + kNumPlanarSensors) x RowColumns(m).
template <typename T>
Rows<T> MlResidualRows(const Robot& robot, const Pose<T>& q);

// One pose's contribution to the information of the geometric parameters once its own
// unknowns are eliminated (Schur complement): S_j = G'(I - P (P'P)^-1 P')G over the rows of
// MlResidualRows, G the geometric columns kept by the gauge (a1x dropped: 3m - 1 of them), P
// the pose columns. The projector onto the complement of P's columns has rank m - 1 (m + 2
// rows, 3 pose unknowns). It is formed from an orthonormal basis E of P's columns (modified
// Gram-Schmidt, repeated once, which keeps E orthonormal to rounding): G_perp = G - E (E'G),
// S_j = G_perp' G_perp. No normal equations of P (whose whitened columns differ in scale by
// the sensors' sigmas), and S_j is symmetric positive semi-definite by construction, to the
// last bit. The information of the whole experiment is the sum over its poses.
// Written as plain loops: a double and an InnerJet's value then go through the very same
// operations, so the design's two evaluations (with and without pose derivatives) agree to
// the last bit.
template <typename T>
Rows<T> ReducedInformation(const Rows<T>& ml_rows);

}  // namespace cablecal
