// The identification's residuals, written once on the scalar type T and the cable count M:
// Ceres evaluates them with Jets inside Identify (identify.cc), and identify/jacobian.h
// differentiates the same functions for the experiment design (design/). The geometry is
// the identification's vector a1x a1z ... aMx aMz l10 ... lM0 (identify/experiment.h).
#pragma once

#include <Eigen/Core>

#include "model/cable.h"
#include "model/robot.h"

namespace cablecal {

// What one pose's readings say and how much each is trusted: the M encoder length changes
// from home (m), the laser height (m), the inclinometer angle (rad), and the inverse sigmas
// that whiten them (the ml estimator).
template <int M>
struct PoseReadings {
  Eigen::Matrix<double, M, 1> dl_m = Eigen::Matrix<double, M, 1>::Zero();
  double z_m = 0.0;
  double theta_rad = 0.0;
};

struct ReadingWeights {
  double inv_sigma_encoder = 1.0, inv_sigma_laser = 1.0, inv_sigma_inclinometer = 1.0;
};
inline ReadingWeights WeightsOf(const SensorNoise& s) {
  return {1.0 / s.encoder_sigma_m, 1.0 / s.laser_sigma_m(), 1.0 / s.inclinometer_sigma_rad()};
}

// Length residual of cable i at a pose: r_ij = l_i(B_i; a_i) - (dl_ij + l_i0), in m, with
// B_i the anchor in F (PlatformPointInF). This is the paper's Eq. (6) without the squares.
// CableResidual takes the cable's own parameters (exit point a_i, initial length l_i0);
// LengthResidual picks them out of the geometry vector.
template <typename T>
T CableResidual(const Cable& cable, const Vec2<T>& p_F_exit_m, const T& initial_length_m, const Vec2<T>& p_F_anchor_m,
                double dl_m) {
  const T length = CableLength<T>(p_F_exit_m, T(cable.pulley_radius_m), SignsOf(cable), p_F_anchor_m);
  return length - (T(dl_m) + initial_length_m);
}
template <int M, typename T>
T LengthResidual(const Cable& cable, int cable_index, const T* geometry, const Vec2<T>& p_F_anchor_m, double dl_m) {
  const Vec2<T> p_F_exit(geometry[2 * cable_index], geometry[2 * cable_index + 1]);
  return CableResidual<T>(cable, p_F_exit, geometry[2 * M + cable_index], p_F_anchor_m, dl_m);
}

// Every cable's length residual at pose q = (x, z, theta), the rotation computed once.
template <int M, typename T>
void LengthResiduals(const Robot& robot, const T* geometry, const Pose<T>& q, const double* dl_m, T* residual) {
  const Eigen::Matrix<T, 2, 2> R = Rotation(q(2));
  const Vec2<T> p(q(0), q(1));
  for (int i = 0; i < M; ++i) {
    const Vec2<T> p_F_anchor = p + R * robot.cables[i].p_P_anchor_m.template cast<T>();
    residual[i] = LengthResidual<M, T>(robot.cables[i], i, geometry, p_F_anchor, dl_m[i]);
  }
}

// The maximum-likelihood estimator's residuals of one pose (errors in variables: x, z and
// theta all unknown): M length residuals over the encoder's sigma, then the laser's
// (z - z_meas) and the inclinometer's (theta - theta_meas) over theirs. M + 2 residuals.
// Identify gives Ceres the two parts as residual blocks of their own (cost_functors.h).
template <int M, typename T>
void MlLengthResiduals(const Robot& robot, const PoseReadings<M>& readings, const ReadingWeights& weights,
                       const T* geometry, const T* pose, T* residual) {
  LengthResiduals<M, T>(robot, geometry, Pose<T>(pose[0], pose[1], pose[2]), readings.dl_m.data(), residual);
  for (int i = 0; i < M; ++i) residual[i] = residual[i] * weights.inv_sigma_encoder;
}

template <int M, typename T>
void MlSensorResiduals(const PoseReadings<M>& readings, const ReadingWeights& weights, const T* pose, T* residual) {
  residual[0] = (pose[1] - readings.z_m) * weights.inv_sigma_laser;
  residual[1] = (pose[2] - readings.theta_rad) * weights.inv_sigma_inclinometer;
}

template <int M, typename T>
void MlResiduals(const Robot& robot, const PoseReadings<M>& readings, const ReadingWeights& weights,
                 const T* geometry, const T* pose, T* residual) {
  MlLengthResiduals<M, T>(robot, readings, weights, geometry, pose, residual);
  MlSensorResiduals<M, T>(readings, weights, pose, residual + M);
}

// The paper's Eq. (6) itself, f_ij = l_model^2 - (dl_ij + l_i0)^2 in m^2, with z_j and theta_j
// taken as measured: only x_j is unknown. M residuals.
template <int M, typename T>
void PaperResiduals(const Robot& robot, const PoseReadings<M>& readings, const T* geometry, const T* x,
                    T* residual) {
  LengthResiduals<M, T>(robot, geometry, Pose<T>(x[0], T(readings.z_m), T(readings.theta_rad)),
                        readings.dl_m.data(), residual);
  for (int i = 0; i < M; ++i) {
    const T measured = T(readings.dl_m(i)) + geometry[2 * M + i];
    const T model = residual[i] + measured;
    residual[i] = model * model - measured * measured;
  }
}

}  // namespace cablecal
