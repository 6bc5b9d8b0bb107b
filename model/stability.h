// The static stability of an equilibrium, written once for both kinds of robot (the planar
// Robot and the SpatialRobot): the Hessian of the potential energy (gravity plus the elastic
// energy of stretched cables) plus the Lagrangian term of the inextensible cables, in pose
// coordinates q, reduced to the motions that keep every inextensible cable's length.
//
// With the generalized force f(q) = E(q)^T (W(q) t(q) + w_g(q)) (E the map from dq to the
// platform's twist: the identity for the planar pose, [I 0; 0 E_omega(rpy)] for the spatial
// one; t fixed for inextensible cables, the Lagrange multipliers of their length constraints,
// and t_i(q) = t_i + k_i (l_i(q) - l_i(q0)) for elastic ones), f = -dL/dq, L the Lagrangian,
// so H = -df/dq is its Hessian. The term of dE/dq multiplies W t + w_g, zero at equilibrium;
// H is symmetrised to drop what rounding leaves of it. One layer of ceres::Jet gives df/dq and
// the length gradients dl/dq in the same pass.
// Depends on Eigen, model/kind.h, model/robot.h and model/spatial_robot.h.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <limits>

#include "model/kind.h"
#include "model/robot.h"
#include "model/spatial_robot.h"

namespace cablecal {

struct StabilityResult {
  // The smallest eigenvalue of the reduced Hessian (N m per unit of q, the free directions
  // orthonormal in q's coordinates: m and rad). NaN when no motion is free.
  double min_eigenvalue = std::numeric_limits<double>::quiet_NaN();
  int free_motions = 0;  // the dimension of the null space of the inextensible cables' dl/dq
  // The reduced Hessian is positive definite (min_eigenvalue > 0), or no motion is free: the
  // inextensible cables hold the pose (a motion shortening no taut cable raises the potential
  // by t' dl >= 0 to first order).
  bool stable = false;
};

// Per cable, axial_stiffness_Npm: +infinity = inextensible and taut (a length constraint whose
// multiplier is its tension), a finite k > 0 = an elastic taut cable with axial stiffness
// k = EA / L_unstretched (N/m), 0 = slack (carries nothing, whatever tensions_N says).
// tensions_N are the cables' tensions at q (an equilibrium: W t + w_g = 0).
StabilityResult StaticStability(const Robot& robot, const PlanarPose& q, const Eigen::VectorXd& tensions_N,
                                const Eigen::VectorXd& axial_stiffness_Npm);
StabilityResult StaticStability(const SpatialRobot& robot, const SpatialPose<double>& q,
                                const Eigen::VectorXd& tensions_N, const Eigen::VectorXd& axial_stiffness_Npm);

// Every cable inextensible: the stiffness vector StaticStability takes for a pose held by
// length constraints alone.
inline Eigen::VectorXd InextensibleCables(int num_cables) {
  return Eigen::VectorXd::Constant(num_cables, std::numeric_limits<double>::infinity());
}

// The platform's angular velocity in F per rate of (roll, pitch, yaw), for
// R = Rz(yaw) Ry(pitch) Rx(roll): omega = E_omega (roll', pitch', yaw')'. Its columns are the
// three rotation axes in F: Rz Ry e_x, Rz e_y, e_z.
template <typename T>
Eigen::Matrix<T, 3, 3> AngularVelocityMap(const T& pitch_rad, const T& yaw_rad) {
  using std::cos;
  using std::sin;
  const T cp = cos(pitch_rad), sp = sin(pitch_rad), cy = cos(yaw_rad), sy = sin(yaw_rad);
  Eigen::Matrix<T, 3, 3> E;
  E << cy * cp, -sy, T(0.0),  //
      sy * cp, cy, T(0.0),    //
      -sp, T(0.0), T(1.0);
  return E;
}

// The twist map of a spatial pose, [I 0; 0 E_omega]: (dp, omega) = TwistMap(q) dq. A wrench w
// (force, moment about p) does the virtual work w' TwistMap(q) dq.
template <typename T>
Eigen::Matrix<T, 6, 6> TwistMap(const SpatialPose<T>& q) {
  Eigen::Matrix<T, 6, 6> E = Eigen::Matrix<T, 6, 6>::Zero();
  E.template topLeftCorner<3, 3>().setIdentity();
  E.template bottomRightCorner<3, 3>() = AngularVelocityMap<T>(q(4), q(5));
  return E;
}

}  // namespace cablecal
