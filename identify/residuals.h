// The identification's residuals, written once on the scalar type T and the cable count M:
// Ceres evaluates them with Jets inside Identify (identify.cc), and identify/jacobian.h
// differentiates the same functions for the experiment design (design/). The geometry is
// the identification's vector a1x a1z ... aMx aMz l10 ... lM0 (model/geometry.h).
#pragma once

#include <ceres/jet.h>

#include <Eigen/Core>
#include <array>

#include "model/cable.h"
#include "model/geometry.h"
#include "model/robot.h"
#include "model/sensors.h"

namespace cablecal {

// What one pose's readings say: the M encoder length changes from home (m), then each other
// sensor's value by SensorId (model/sensors.h; 0 where the data lack it, its weight then 0).
template <int M>
struct PoseReadings {
  Eigen::Matrix<double, M, 1> dl_m = Eigen::Matrix<double, M, 1>::Zero();
  std::array<double, kNumSensorIds> sensor_values{};
};

struct ReadingWeights {
  double inv_sigma_encoder = 1.0;
  std::array<double, kNumSensorIds> inv_sigma_sensor = {1.0, 1.0};  // by SensorId; 0: the data lack it
  // The static equilibrium's row of each pose (robots with fewer cables than the pose's 3
  // DoF, MlEquilibriumResidual below): 1 / platform.com_sigma, in 1/m; 0: no such row.
  double inv_sigma_equilibrium = 0.0;
};
inline ReadingWeights WeightsOf(const SensorNoise& s) {
  ReadingWeights w;
  w.inv_sigma_encoder = 1.0 / s.encoder_sigma_m;
  for (const SensorUnit& u : kPlanarSensors) w.inv_sigma_sensor[static_cast<int>(u.id)] = 1.0 / u.sigma(s);
  return w;
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
  constexpr GeometryLayout kLayout = PlanarLayout(M);
  const Vec2<T> p_F_exit(geometry[kLayout.exit(cable_index, 0)], geometry[kLayout.exit(cable_index, 1)]);
  return CableResidual<T>(cable, p_F_exit, geometry[kLayout.initial_length(cable_index)], p_F_anchor_m, dl_m);
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
// theta all unknown): M length residuals over the encoder's sigma, then each sensor's
// (model/sensors.h: the laser's z - z_meas, the inclinometer's theta - theta_meas) over its
// own. M + kNumPlanarSensors residuals.
// Identify gives Ceres the two parts as residual blocks of their own (cost_functors.h).
template <int M, typename T>
void MlLengthResiduals(const Robot& robot, const PoseReadings<M>& readings, const ReadingWeights& weights,
                       const T* geometry, const T* pose, T* residual) {
  LengthResiduals<M, T>(robot, geometry, Pose<T>(pose[0], pose[1], pose[2]), readings.dl_m.data(), residual);
  for (int i = 0; i < M; ++i) residual[i] = residual[i] * weights.inv_sigma_encoder;
}

template <int M, typename T>
void MlSensorResiduals(const PoseReadings<M>& readings, const ReadingWeights& weights, const T* pose, T* residual) {
  for (std::size_t k = 0; k < kPlanarSensors.size(); ++k) {
    const int id = static_cast<int>(kPlanarSensors[k].id);
    residual[k] = kPlanarSensors[k].Residual(pose, readings.sensor_values[id]) * weights.inv_sigma_sensor[id];
  }
}

template <int M, typename T>
void MlResiduals(const Robot& robot, const PoseReadings<M>& readings, const ReadingWeights& weights,
                 const T* geometry, const T* pose, T* residual) {
  MlLengthResiduals<M, T>(robot, readings, weights, geometry, pose, residual);
  MlSensorResiduals<M, T>(readings, weights, pose, residual + M);
}

// ---- The static equilibrium (robots with fewer cables than the pose's 3 DoF) ----------------
// With m < 3 cables the lengths leave the platform 3 - m degrees of freedom, and the statics
// decide them: at a pose the platform can hold, gravity's wrench w_g lies in the span of the
// m cable wrenches (the columns of W, the cables' unit pulls u_i along their straight
// segments, tangent point to anchor, and their moments (R b_i) x u_i; model/cable.h). Pose j's
// unknowns then meet 3 - m conditions besides its readings: rows of its block in the ml fit.
// The planar tool has m >= 2, so one condition (m = 2); a spatial robot of m < 6 cables would
// have 6 - m.
constexpr int EquilibriumRows(int num_cables) { return num_cables < 3 ? 3 - num_cables : 0; }

// m = 2: the tensions that balance gravity's force (u_1 t_1 + u_2 t_2 = (0, m g), solved by
// Cramer's rule) leave the moment e = sum_i t_i (R b_i) x u_i - m g (R c)_x about the
// reference point p. Their resultant is the vertical force m g through the intersection I of
// the two cable lines, so e = m g (x_I - x_c): the platform balances when its centre of mass c
// hangs plumb below (or stands above) the point where the cables' lines meet. Returned is
// that horizontal offset x_I - x_c, in m; it does not depend on the mass. Exit points from
// `geometry` (a1x a1z a2x a2z ...), the anchors, pulleys and centre of mass from `robot`.
template <int M, typename T>
T EquilibriumOffset(const Robot& robot, const T* geometry, const Pose<T>& q) {
  static_assert(M == 2, "the planar equilibrium condition is written for 2 cables (EquilibriumRows)");
  const Eigen::Matrix<T, 2, 2> R = Rotation(q(2));
  const Vec2<T> p(q(0), q(1));
  Vec2<T> u[M];
  T moment[M];
  for (int i = 0; i < M; ++i) {
    const Cable& c = robot.cables[i];
    const Vec2<T> r_F_anchor = R * c.p_P_anchor_m.template cast<T>();
    const Vec2<T> p_F_exit(geometry[PlanarLayout(M).exit(i, 0)], geometry[PlanarLayout(M).exit(i, 1)]);
    u[i] = CableGeometry<T>(p_F_exit, T(c.pulley_radius_m), SignsOf(c), p + r_F_anchor).u_F_cable;
    moment[i] = Cross2<T>(r_F_anchor, u[i]);
  }
  const T det = u[0].x() * u[1].y() - u[0].y() * u[1].x();
  // t_1 / (m g) = -u_2x / det, t_2 / (m g) = u_1x / det.
  const T x_intersection = (u[0].x() * moment[1] - u[1].x() * moment[0]) / det;
  const T x_com = (R * robot.p_P_com_m.template cast<T>()).x();
  return x_intersection - x_com;
}

// The ml estimator's equilibrium row of one pose: that offset over platform.com_sigma, the
// uncertainty of the centre of mass (per axis; friction at the pulleys can be folded into it as
// an equivalent shift): a centre of mass off by delta moves x_c by delta cos(theta) along the
// platform's x and -delta sin(theta) along its z, so the offset's standard deviation is
// com_sigma whatever the pose. Touches the exit points and the pose, not the initial lengths.
// Nothing to evaluate (no row) when weights.inv_sigma_equilibrium is 0 or M >= 3.
template <int M, typename T>
void MlEquilibriumResidual(const Robot& robot, const ReadingWeights& weights, const T* geometry, const T* pose,
                           T* residual) {
  residual[0] = EquilibriumOffset<M, T>(robot, geometry, Pose<T>(pose[0], pose[1], pose[2])) *
                weights.inv_sigma_equilibrium;
}

// The same condition as an angle, for a person: theta minus the platform's equilibrium angle at
// the pose's (x, z), to first order, the offset divided by its derivative along theta (the
// pose's rotational stiffness over m g, in m/rad). Exact where the offset is 0; d rad from an
// equilibrium it is d (1 + O(d)).
template <int M>
double EquilibriumThetaError(const Robot& robot, const double* geometry, const Pose<double>& q) {
  using Jet1 = ceres::Jet<double, 1>;
  Jet1 g[PlanarLayout(M).exit_coordinates()];
  for (int k = 0; k < PlanarLayout(M).exit_coordinates(); ++k) g[k] = Jet1(geometry[k]);
  const Jet1 offset = EquilibriumOffset<M, Jet1>(robot, g, Pose<Jet1>(Jet1(q(0)), Jet1(q(1)), Jet1(q(2), 0)));
  return offset.a / offset.v(0);
}

// The paper's Eq. (6) itself, f_ij = l_model^2 - (dl_ij + l_i0)^2 in m^2, with z_j and theta_j
// taken as measured: only x_j is unknown. M residuals.
template <int M, typename T>
void PaperResiduals(const Robot& robot, const PoseReadings<M>& readings, const T* geometry, const T* x,
                    T* residual) {
  LengthResiduals<M, T>(robot, geometry,
                        Pose<T>(x[0], T(readings.sensor_values[static_cast<int>(SensorId::kLaser)]),
                                T(readings.sensor_values[static_cast<int>(SensorId::kInclinometer)])),
                        readings.dl_m.data(), residual);
  for (int i = 0; i < M; ++i) {
    const T measured = T(readings.dl_m(i)) + geometry[PlanarLayout(M).initial_length(i)];
    const T model = residual[i] + measured;
    residual[i] = model * model - measured * measured;
  }
}

}  // namespace cablecal
