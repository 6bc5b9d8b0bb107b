// Cable geometry with the pulley wrap, written once on the scalar type T so that
// doubles, ceres::Jet (identification, design derivatives) and nested Jets (stiffness)
// all share the same formula.
//
// Construction (README, "Model and conventions"): cable i runs up the post and touches pulley i on its outer
// side at the exit point A_i (the pulley's outermost point at the height of its centre
// C_i = A_i + s_i (r, 0), s_i = +1 left, -1 right), wraps over the top and leaves
// tangentially at T_i toward the anchor B_i. Its length from A_i to B_i is
//   l_i = r * phi_i + sqrt(|m_i|^2 - r^2),  m_i = B_i - C_i           (paper, Eq. 1-2)
// Wrap angle convention: in the pulley frame mirrored so that the cable arrives on the
// -x side (x' = s_i (x - C_x), z' = z - C_z), A_i sits at angle pi and the cable wraps
// clockwise to T_i at angle alpha = psi + delta, with psi = atan2(m_z, s_i m_x) the angle
// of m_i and delta = atan2(sqrt(|m|^2 - r^2), r) = acos(r / |m|) the angle between CT and
// CB. Hence phi_i = pi - psi - delta, with phi in [0, 3 pi / 2) for a valid configuration.
// The paper writes phi = pi - beta - gamma with beta = delta and sin(gamma) = (a_z - b_z)/|m|,
// i.e. gamma = -psi for an anchor below the pulley; that is pi - delta + psi, which is
// wrong by 2 psi (an anchor straight below the pulley must give phi = pi, Eq. 2 gives 0).
// tests/model/cable_test.cc checks the closed form against a numerical tangency construction.
//
// A cable that wraps *under* its pulley (wrap: under, pulleys below the platform) is the
// mirror image in z of one that wraps over: the same construction in the pulley frame
// mirrored in z as well (z' = w_i (z - C_z), w_i = +1 over, -1 under), so that
// psi = atan2(w_i m_z, s_i m_x) and T_i = C_i + (s_i r cos alpha, w_i r sin alpha).
//
// Valid while |m_i| > r (the anchor is outside the pulley) and 0 <= phi_i <= 3 pi / 2 (the
// cable touches the pulley and leaves it before passing under it); CableGeometryValid says
// whether a configuration is.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cmath>

#include "model/kind.h"
#include "model/robot.h"
#include "model/vectors.h"

namespace cablecal {

// Platform pose q = (x_m, z_m, theta_rad) in F; theta counter-clockwise (x toward z).
template <typename T>
using Pose = Eigen::Matrix<T, PlanarKind::kPoseDim, 1>;

template <typename T>
Eigen::Matrix<T, 2, 2> Rotation(const T& theta_rad) {
  using std::cos;
  using std::sin;
  Eigen::Matrix<T, 2, 2> R;
  R << cos(theta_rad), -sin(theta_rad), sin(theta_rad), cos(theta_rad);
  return R;
}

// Planar cross product a x b: the moment of force b at lever a, positive counter-clockwise.
template <typename T>
T Cross2(const Vec2<T>& a, const Vec2<T>& b) {
  return a.x() * b.y() - a.y() * b.x();
}

// B = p + R(theta) b: a platform point in F.
template <typename T>
Vec2<T> PlatformPointInF(const Pose<T>& q, const Vec2<T>& p_P_point) {
  return Vec2<T>(q(0), q(1)) + Rotation(q(2)) * p_P_point;
}

template <typename T>
struct CableState {
  T length_m;             // A_i -> B_i: arc + straight segment
  T wrap_angle_rad;       // phi_i
  T segment_length_m;     // straight part T_i -> B_i
  T centre_distance_m;    // |m_i|
  Vec2<T> p_F_tangent_m;  // T_i, where the cable leaves the pulley
  Vec2<T> u_F_cable;      // unit vector from B_i toward T_i: direction of the cable's pull
};

// The pulley's two signs, the axes of its mirrored frame: s_i (side: the pulley centre is at
// exit + s_i (r, 0)) and w_i (wrap: +1 over, -1 under).
struct PulleySigns {
  double side = 1.0;
  double wrap = 1.0;
};

inline PulleySigns SignsOf(const Cable& cable) { return {SideSign(cable.side), WrapSign(cable.wrap)}; }

namespace internal {

template <typename T>
struct Wrap {
  Vec2<T> p_F_centre;
  Vec2<T> m;            // B - C
  T m_squared;          // |m|^2
  T segment_length_m;   // sqrt(|m|^2 - r^2)
  T alpha_rad;          // tangent point's angle in the mirrored pulley frame, = psi + delta
  // |m|^2 (cos alpha, sin alpha): alpha's atan2 arguments, whose length is |m| sqrt(r^2 +
  // segment^2) = |m|^2, so the tangent point needs no sine or cosine (CableGeometry).
  Vec2<T> alpha_direction;
};

template <typename T>
Wrap<T> ComputeWrap(const Vec2<T>& p_F_exit_m, const T& r, PulleySigns signs, const Vec2<T>& p_F_anchor_m) {
  using std::atan2;
  using std::sqrt;
  Wrap<T> w;
  w.p_F_centre = Vec2<T>(p_F_exit_m.x() + signs.side * r, p_F_exit_m.y());
  w.m = p_F_anchor_m - w.p_F_centre;
  w.m_squared = w.m.squaredNorm();
  w.segment_length_m = sqrt(w.m_squared - r * r);
  // psi + delta in one atan2 (angle of the product of (s m_x, w m_z) and (r, segment)): a
  // third fewer transcendental calls in the identification's inner loop. It wraps only
  // where phi would leave [0, 3 pi / 2], which CableGeometryValid rejects.
  const T mx = signs.side * w.m.x();
  const T mz = signs.wrap * w.m.y();
  w.alpha_direction = Vec2<T>(mx * r - mz * w.segment_length_m, mz * r + mx * w.segment_length_m);
  w.alpha_rad = atan2(w.alpha_direction.y(), w.alpha_direction.x());
  return w;
}

}  // namespace internal

// Length from exit point to anchor only (what the identification needs).
template <typename T>
T CableLength(const Vec2<T>& p_F_exit_m, const T& pulley_radius_m, PulleySigns signs, const Vec2<T>& p_F_anchor_m) {
  const internal::Wrap<T> w = internal::ComputeWrap<T>(p_F_exit_m, pulley_radius_m, signs, p_F_anchor_m);
  return pulley_radius_m * (T(M_PI) - w.alpha_rad) + w.segment_length_m;
}

template <typename T>
CableState<T> CableGeometry(const Vec2<T>& p_F_exit_m, const T& pulley_radius_m,
                            PulleySigns signs, const Vec2<T>& p_F_anchor_m) {
  using std::sqrt;
  const T& r = pulley_radius_m;
  const internal::Wrap<T> w = internal::ComputeWrap<T>(p_F_exit_m, r, signs, p_F_anchor_m);
  CableState<T> s;
  s.centre_distance_m = sqrt(w.m_squared);
  s.segment_length_m = w.segment_length_m;
  s.wrap_angle_rad = T(M_PI) - w.alpha_rad;
  s.length_m = r * s.wrap_angle_rad + s.segment_length_m;
  // T = C + r (s_i cos alpha, w_i sin alpha), cos and sin from alpha's atan2 arguments: the
  // sampler's equilibrium scans evaluate this ~100 times per pose, and a sine and cosine were
  // a fifth of a Monte Carlo trial's instructions (bench/README.md).
  const T r_over_m2 = r / w.m_squared;
  s.p_F_tangent_m = Vec2<T>(w.p_F_centre.x() + signs.side * r_over_m2 * w.alpha_direction.x(),
                            w.p_F_centre.y() + signs.wrap * r_over_m2 * w.alpha_direction.y());
  s.u_F_cable = (s.p_F_tangent_m - p_F_anchor_m) / s.segment_length_m;
  return s;
}

// The cable's state at platform pose q, for the robot's nominal exit point.
template <typename T>
CableState<T> CableAtPose(const Cable& cable, const Pose<T>& q) {
  return CableGeometry<T>(cable.p_F_exit_m.cast<T>(), T(cable.pulley_radius_m), SignsOf(cable),
                          PlatformPointInF<T>(q, cable.p_P_anchor_m.cast<T>()));
}

inline bool CableGeometryValid(const CableState<double>& s, double pulley_radius_m) {
  return std::isfinite(s.length_m) && s.centre_distance_m > pulley_radius_m &&
         s.wrap_angle_rad >= 0.0 && s.wrap_angle_rad <= 1.5 * M_PI;
}

// Wrench matrix W (3 x m): column i = [u_i; (R b_i) x u_i], the force and the moment
// about p of a unit tension in cable i. W = -(dl/dq)^T (virtual work), which
// tests/model/statics_test.cc checks with Jets. `p_F_exits_m[i]` is exit point i; the
// overload without it takes the robot's nominal exit points (the design's robustness
// differentiates W with respect to the exit points too).
// One column of W: the cable's pull u and its moment (R b) x u about p, from the anchor's
// lever r_F_anchor = R b and the cable's state there.
template <typename T>
Vec3<T> WrenchColumn(const Vec2<T>& r_F_anchor, const CableState<T>& s) {
  return Vec3<T>(s.u_F_cable.x(), s.u_F_cable.y(), Cross2<T>(r_F_anchor, s.u_F_cable));
}

template <typename T>
Eigen::Matrix<T, 3, Eigen::Dynamic> WrenchMatrix(const Robot& robot, const Pose<T>& q, const Vec2<T>* p_F_exits_m) {
  Eigen::Matrix<T, 3, Eigen::Dynamic> W(3, robot.num_cables());
  const Eigen::Matrix<T, 2, 2> R = Rotation(q(2));
  for (int i = 0; i < robot.num_cables(); ++i) {
    const Cable& c = robot.cables[i];
    const Vec2<T> r_F_anchor = R * c.p_P_anchor_m.cast<T>();
    const Vec2<T> p_F_anchor = Vec2<T>(q(0), q(1)) + r_F_anchor;
    W.col(i) = WrenchColumn<T>(r_F_anchor, CableGeometry<T>(p_F_exits_m[i], T(c.pulley_radius_m), SignsOf(c), p_F_anchor));
  }
  return W;
}

template <typename T>
Eigen::Matrix<T, 3, Eigen::Dynamic> WrenchMatrix(const Robot& robot, const Pose<T>& q) {
  std::array<Vec2<T>, kMaxCables> exits;  // no heap allocation in the statics' inner loop
  for (int i = 0; i < robot.num_cables(); ++i) exits[i] = robot.cables[i].p_F_exit_m.cast<T>();
  return WrenchMatrix<T>(robot, q, exits.data());
}

// Gravity wrench at p: [0; -m g; (R c) x (0, -m g)] = -grad V, R = Rotation(theta).
template <typename T>
Vec3<T> GravityWrench(const Robot& robot, const Eigen::Matrix<T, 2, 2>& R) {
  const T weight_N = T(robot.platform_mass_kg * robot.gravity_mps2);
  const Vec2<T> r_F_com = R * robot.p_P_com_m.cast<T>();
  return Vec3<T>(T(0.0), -weight_N, -weight_N * r_F_com.x());
}
template <typename T>
Vec3<T> GravityWrench(const Robot& robot, const Pose<T>& q) {
  return GravityWrench<T>(robot, Rotation(q(2)));
}

// Gravitational potential energy m g z_com (J); its minimum along the motion the cables
// allow is where the platform settles.
template <typename T>
T PotentialEnergy(const Robot& robot, const Pose<T>& q) {
  return T(robot.platform_mass_kg * robot.gravity_mps2) *
         PlatformPointInF<T>(q, robot.p_P_com_m.cast<T>()).y();
}

// Wrench balance residual W t + w_g (N, N, N m); zero at static equilibrium.
template <typename T>
Vec3<T> EquilibriumResidual(const Robot& robot, const Pose<T>& q,
                            const Eigen::Matrix<T, Eigen::Dynamic, 1>& tensions_N) {
  return WrenchMatrix<T>(robot, q) * tensions_N + GravityWrench<T>(robot, q);
}

}  // namespace cablecal
