// The identification's residuals, written once on the scalar type T: Ceres evaluates them
// with Jets (identify.cc) and the experiment design differentiates the same functions to
// build and optimise the identification Jacobian.
#pragma once

#include <array>

#include "model/cable.h"
#include "model/robot.h"

namespace cablecal {

// Length residual of cable i at a pose: r_ij = l_i(B_i; a_i) - (dl_ij + l_i0), in m, with
// B_i the anchor in F (PlatformPointInF). This is the paper's Eq. (6) without the squares;
// `geometry` is a1x a1z a2x a2z l10 l20.
template <typename T>
T LengthResidual(const Cable& cable, int cable_index, const T* geometry, const Vec2<T>& p_F_anchor_m, double dl_m) {
  const Vec2<T> p_F_exit(geometry[2 * cable_index], geometry[2 * cable_index + 1]);
  const T length = CableLength<T>(p_F_exit, T(cable.pulley_radius_m), SideSign(cable.side), p_F_anchor_m);
  return length - (T(dl_m) + geometry[4 + cable_index]);
}

// Both cables' anchors at pose q, computing the rotation once.
template <typename T>
std::array<Vec2<T>, 2> AnchorsInF(const Robot& robot, const Pose<T>& q) {
  const Eigen::Matrix<T, 2, 2> R = Rotation(q(2));
  const Vec2<T> p(q(0), q(1));
  return {p + R * robot.cables[0].p_P_anchor_m.cast<T>(), p + R * robot.cables[1].p_P_anchor_m.cast<T>()};
}

// The paper's Eq. (6) itself: f_ij = l_model^2 - (dl_ij + l_i0)^2, in m^2.
template <typename T>
T PaperResidual(const Cable& cable, int cable_index, const T* geometry, const Vec2<T>& p_F_anchor_m, double dl_m) {
  const T measured = T(dl_m) + geometry[4 + cable_index];
  const T model = LengthResidual<T>(cable, cable_index, geometry, p_F_anchor_m, dl_m) + measured;
  return model * model - measured * measured;
}

}  // namespace cablecal
