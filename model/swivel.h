// Spatial cable geometry through swivel pulleys, written once on the scalar type T so that
// doubles, ceres::Jet and nested Jets share the same formula (as model/cable.h for the planar
// robot), and the platform functions built on it: orientation, anchors, cable lengths, the
// wrench matrix and the gravity wrench of a SpatialRobot.
//
// Construction (Pott, ARK 2012, "Influence of pulley kinematics on cable-driven parallel
// robots"; the same geometry as the planar pulley of model/cable.h, in the plane the pulley
// swivels into). Cable i arrives at the fixed point D_i travelling along the unit swivel axis
// k_i; the pulley turns about the line (D_i, k_i) so that its plane holds the anchor B_i. With
//   rho = B_i - D_i,  rho_k = k . rho,  rho_perp = rho - rho_k k,
// the pulley plane's radial direction is u = rho_perp / |rho_perp| and its centre
// C = D_i + r u. In the pulley plane, with coordinates along (u, k) relative to C, D_i is at
// (-r, 0), the anchor at m = (|rho_perp| - r, rho_k), alpha = atan2(m_k, m_u). The cable runs
// from D_i (angle pi) round the pulley against the angle's sense to the tangent point at angle
//   phi = alpha + acos(r / |m|),
// wrapping beta = pi - phi, and leaves along the tangent toward B_i:
//   l = r beta + sqrt(|m|^2 - r^2).
// phi comes from one atan2 (of the product of m's direction and (r, free length)), as in
// model/cable.h; the tangent point and the free segment's direction need no sine or cosine.
//
// Validity (SwivelGeometry): the anchor off the swivel axis (|rho_perp| > kSwivelAxisTolerance_m,
// else u is undefined: kSwivelAxis), outside the pulley (|m| > r: kInsidePulley), and a wrap
// angle 0 <= beta <= 3 pi / 2 (kWrap otherwise; the planar model's range, model/cable.h).
// beta > 3 pi / 2 happens for an anchor behind the pulley close to the axis: the free segment
// would run back across the arriving cable. beta < 0 would bend the cable away from the
// pulley; the swivel keeps the anchor on the pulley's side of the axis, so only rounding could
// give it. An invalid configuration is a named reason and finite numbers, never a NaN.
//
// Eyelet (r = 0): l = |rho|, the cable runs straight from D_i; valid unless B_i = D_i.
//
// Derivatives: dl/dB_i = e_F_free, the unit vector of the free segment from the tangent point
// toward B_i (the arc's length changes only to second order when T slides), so the wrench
// column of cable i is [d; (R b_i) x d] with d = -e_F_free, pointing from the anchor toward the
// pulley (tests/model/swivel_test.cc checks both with Jets).
// Depends on Eigen, model/kind.h (SpatialPose) and model/spatial_robot.h.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>  // cross products
#include <algorithm>
#include <cmath>

#include "model/kind.h"
#include "model/spatial_robot.h"
#include "model/vectors.h"

namespace cablecal {

// Why the swivel construction does not hold at a configuration; kValid when it does.
enum class SwivelGeometry { kValid, kSwivelAxis, kInsidePulley, kWrap };

// "valid", "swivel_axis", "inside_pulley", "wrap": the names the feasibility code reports.
inline const char* ToString(SwivelGeometry g) {
  switch (g) {
    case SwivelGeometry::kValid: return "valid";
    case SwivelGeometry::kSwivelAxis: return "swivel_axis";
    case SwivelGeometry::kInsidePulley: return "inside_pulley";
    case SwivelGeometry::kWrap: return "wrap";
  }
  return "?";
}

// An anchor closer than this to its swivel axis leaves the pulley plane undetermined: rounding
// in rho_perp (about 1e-16 of |rho|, metres) turns u by 1e-10 rad at this distance, and a real
// anchor is never within a micrometre of the axis (the pulley's hardware is there).
constexpr double kSwivelAxisTolerance_m = 1e-6;
// The largest wrap angle of a valid configuration (see the file comment).
constexpr double kMaxWrapAngle_rad = 1.5 * M_PI;

template <typename T>
struct SwivelCableState {
  T length_m;            // D_i -> B_i along the cable: arc r beta + free segment
  T wrap_angle_rad;      // beta; for an eyelet the cable's deflection at D_i, angle(k, rho)
  T free_length_m;       // |B_i - T_i|
  T axis_distance_m;     // |rho_perp|: the anchor's distance from the swivel axis
  Vec3<T> u_F;           // the pulley plane's radial direction (unit, perpendicular to k);
                         // zero for an eyelet with its anchor on the axis
  Vec3<T> p_F_centre_m;  // C_i (D_i for an eyelet)
  Vec3<T> p_F_tangent_m;  // T_i, where the cable leaves the pulley (D_i for an eyelet)
  Vec3<T> e_F_free;      // unit, from T_i toward B_i: dl/dB_i; the cable pulls B_i along -e_F_free
  SwivelGeometry geometry = SwivelGeometry::kValid;
  bool valid() const { return geometry == SwivelGeometry::kValid; }
};

namespace internal {

// A finite stand-in for a configuration the construction does not cover: the straight
// distance as the length (0 where B = D), every vector zero, the reason named.
template <typename T>
SwivelCableState<T> InvalidSwivelState(const T& rho_squared, const T& axis_distance_m, SwivelGeometry why) {
  using std::sqrt;
  SwivelCableState<T> s;
  s.length_m = rho_squared > T(0.0) ? sqrt(rho_squared) : T(0.0);
  s.wrap_angle_rad = T(0.0);
  s.free_length_m = T(0.0);
  s.axis_distance_m = axis_distance_m;
  s.u_F = s.p_F_centre_m = s.p_F_tangent_m = s.e_F_free = Vec3<T>::Zero();
  s.geometry = why;
  return s;
}

}  // namespace internal

// The swivel-pulley cable from exit point D (p_F_exit_m) with unit swivel axis k and pulley
// radius r to the anchor B (p_F_anchor_m), all in F. The construction of the file comment.
template <typename T>
SwivelCableState<T> SwivelCable(const Vec3<T>& p_F_exit_m, const Vec3<T>& k_F_swivel_axis, const T& pulley_radius_m,
                                const Vec3<T>& p_F_anchor_m) {
  using std::atan2;
  using std::sqrt;
  const T& r = pulley_radius_m;
  const Vec3<T>& k = k_F_swivel_axis;
  const Vec3<T> rho = p_F_anchor_m - p_F_exit_m;
  const T rho_k = k.dot(rho);
  const Vec3<T> rho_perp = rho - rho_k * k;
  const T axis_distance_squared = rho_perp.squaredNorm();
  const T rho_squared = rho.squaredNorm();
  // sqrt only off zero: its derivative there is infinite, and Jets would carry it.
  const T axis_distance = axis_distance_squared > T(0.0) ? sqrt(axis_distance_squared) : T(0.0);
  const bool off_axis = axis_distance > T(kSwivelAxisTolerance_m);

  SwivelCableState<T> s;
  s.axis_distance_m = axis_distance;
  if (!(r > T(0.0))) {  // an eyelet
    if (!(rho_squared > T(0.0))) return internal::InvalidSwivelState<T>(rho_squared, axis_distance, SwivelGeometry::kInsidePulley);
    s.length_m = sqrt(rho_squared);
    s.free_length_m = s.length_m;
    s.wrap_angle_rad = atan2(axis_distance, rho_k);
    s.u_F = off_axis ? Vec3<T>(rho_perp / axis_distance) : Vec3<T>(Vec3<T>::Zero());
    s.p_F_centre_m = s.p_F_tangent_m = p_F_exit_m;
    s.e_F_free = rho / s.length_m;
    s.geometry = SwivelGeometry::kValid;
    return s;
  }
  if (!off_axis) return internal::InvalidSwivelState<T>(rho_squared, axis_distance, SwivelGeometry::kSwivelAxis);

  const Vec3<T> u = rho_perp / axis_distance;
  const T m_u = axis_distance - r;
  const T& m_k = rho_k;
  const T m_squared = m_u * m_u + m_k * m_k;
  if (!(m_squared > r * r)) return internal::InvalidSwivelState<T>(rho_squared, axis_distance, SwivelGeometry::kInsidePulley);
  const T free = sqrt(m_squared - r * r);
  // |m|^2 (cos phi, sin phi): m's direction turned by acos(r / |m|) = atan2(free, r).
  const T phi_u = m_u * r - m_k * free;
  const T phi_k = m_k * r + m_u * free;
  const T phi = atan2(phi_k, phi_u);
  s.wrap_angle_rad = T(M_PI) - phi;
  s.free_length_m = free;
  s.length_m = r * s.wrap_angle_rad + free;
  s.u_F = u;
  s.p_F_centre_m = p_F_exit_m + r * u;
  const T r_over_m2 = r / m_squared;
  s.p_F_tangent_m = s.p_F_centre_m + r_over_m2 * (phi_u * u + phi_k * k);
  // The tangent's direction at phi, (sin phi, -cos phi) in (u, k): m . it = free > 0, so it
  // points from T toward B.
  s.e_F_free = (phi_k * u - phi_u * k) / m_squared;
  // atan2 returns phi in (-pi, pi]: a true phi beyond pi (beta < 0) comes back as phi - 2 pi,
  // beta in (3 pi / 2, 2 pi), which the same bound refuses.
  s.geometry = (s.wrap_angle_rad >= T(0.0) && s.wrap_angle_rad <= T(kMaxWrapAngle_rad)) ? SwivelGeometry::kValid
                                                                                       : SwivelGeometry::kWrap;
  return s;
}

// The swivel angle reading: the angle of u about k, measured from the home pose's u_home
// (counter-clockwise about k, in (-pi, pi]). What a swivel-angle encoder reads relative to home.
template <typename T>
T SwivelAngle(const Vec3<T>& k_F_swivel_axis, const Vec3<T>& u_F_home, const Vec3<T>& u_F) {
  using std::atan2;
  return atan2(k_F_swivel_axis.dot(u_F_home.cross(u_F)), u_F_home.dot(u_F));
}

// R = Rz(yaw) Ry(pitch) Rx(roll): the platform's orientation in F (model/kind.h).
template <typename T>
Eigen::Matrix<T, 3, 3> Rotation(const T& roll_rad, const T& pitch_rad, const T& yaw_rad) {
  using std::cos;
  using std::sin;
  const T cr = cos(roll_rad), sr = sin(roll_rad);
  const T cp = cos(pitch_rad), sp = sin(pitch_rad);
  const T cy = cos(yaw_rad), sy = sin(yaw_rad);
  Eigen::Matrix<T, 3, 3> R;
  R << cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr,  //
      sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr,   //
      -sp, cp * sr, cp * cr;
  return R;
}

template <typename T>
Eigen::Matrix<T, 3, 3> Rotation(const SpatialPose<T>& q) {
  return Rotation<T>(q(3), q(4), q(5));
}

// The axes in F about which roll, pitch and yaw turn the platform, as columns: for any platform
// point b, d(R b)/d(angle_a) = axes.col(a) x (R b). R = Rz(yaw) Ry(pitch) Rx(roll): roll turns
// about P's x axis (R's first column), pitch about Rz(yaw)'s y axis, yaw about F's z axis. The
// identification's hand-written encoder derivatives use them instead of Jets on the angles.
template <typename T>
Eigen::Matrix<T, 3, 3> EulerRateAxes(const Eigen::Matrix<T, 3, 3>& R, const T& yaw_rad) {
  using std::cos;
  using std::sin;
  Eigen::Matrix<T, 3, 3> axes;
  axes.col(0) = R.col(0);
  axes.col(1) << -sin(yaw_rad), cos(yaw_rad), T(0.0);
  axes.col(2) << T(0.0), T(0.0), T(1.0);
  return axes;
}

// The platform's tilt: the angle between P's z axis and F's z axis, acos(cos roll cos pitch).
inline double TiltAngle(const SpatialPose<double>& q) {
  return std::acos(std::min(1.0, std::max(-1.0, Rotation<double>(q)(2, 2))));
}

// B = p + R b: a platform point b (in P) in F.
template <typename T>
Vec3<T> AnchorInF(const SpatialPose<T>& q, const Eigen::Matrix<T, 3, 3>& R, const Vec3<T>& p_P_point_m) {
  return q.template head<3>() + R * p_P_point_m;
}
template <typename T>
Vec3<T> AnchorInF(const SpatialPose<T>& q, const Vec3<T>& p_P_point_m) {
  return AnchorInF<T>(q, Rotation<T>(q), p_P_point_m);
}

// Cable i's state at pose q (rotation R = Rotation(q)), for the robot's nominal exit point and
// axis.
template <typename T>
SwivelCableState<T> SwivelCableAtPose(const SpatialCable& cable, const SpatialPose<T>& q,
                                      const Eigen::Matrix<T, 3, 3>& R) {
  return SwivelCable<T>(cable.p_F_exit_m.cast<T>(), cable.k_F_swivel_axis.cast<T>(), T(cable.pulley_radius_m),
                        AnchorInF<T>(q, R, cable.p_P_anchor_m.cast<T>()));
}

// Every cable's length (exit point -> anchor) at pose q. Lengths of invalid configurations
// are the construction's finite stand-ins: check CableGeometryAt where it matters.
template <typename T>
Eigen::Matrix<T, Eigen::Dynamic, 1> CableLengths(const SpatialRobot& robot, const SpatialPose<T>& q) {
  const Eigen::Matrix<T, 3, 3> R = Rotation<T>(q);
  Eigen::Matrix<T, Eigen::Dynamic, 1> l(robot.num_cables());
  for (int i = 0; i < robot.num_cables(); ++i) l(i) = SwivelCableAtPose<T>(robot.cables[i], q, R).length_m;
  return l;
}

// The first cable whose geometry is invalid at q, and why; {kValid, -1} if none is.
struct CableGeometryCheck {
  SwivelGeometry geometry = SwivelGeometry::kValid;
  int cable = -1;
  bool valid() const { return geometry == SwivelGeometry::kValid; }
};
inline CableGeometryCheck CableGeometryAt(const SpatialRobot& robot, const SpatialPose<double>& q) {
  const Eigen::Matrix3d R = Rotation<double>(q);
  for (int i = 0; i < robot.num_cables(); ++i) {
    const SwivelGeometry g = SwivelCableAtPose<double>(robot.cables[i], q, R).geometry;
    if (g != SwivelGeometry::kValid) return {g, i};
  }
  return {};
}

// One column of the wrench matrix: the pull d = -e_F_free of a unit tension and its moment
// (R b) x d about p, from the anchor's lever r_F_anchor = R b.
template <typename T>
Eigen::Matrix<T, 6, 1> WrenchColumn(const Vec3<T>& r_F_anchor_m, const SwivelCableState<T>& s) {
  const Vec3<T> d = -s.e_F_free;
  Eigen::Matrix<T, 6, 1> column;
  column << d, r_F_anchor_m.cross(d);
  return column;
}

// Wrench matrix W (6 x m): column i = [d_i; (R b_i) x d_i], the force and the moment about p of
// a unit tension in cable i, in F; W t + w_g = 0 at equilibrium. W = -(dl/dxi)^T for the
// rigid displacement xi = (dp, dphi) in F (virtual work; tests/model/swivel_test.cc).
template <typename T>
Eigen::Matrix<T, 6, Eigen::Dynamic> WrenchMatrix(const SpatialRobot& robot, const SpatialPose<T>& q) {
  const Eigen::Matrix<T, 3, 3> R = Rotation<T>(q);
  Eigen::Matrix<T, 6, Eigen::Dynamic> W(6, robot.num_cables());
  for (int i = 0; i < robot.num_cables(); ++i) {
    const SpatialCable& c = robot.cables[i];
    const Vec3<T> r_F_anchor = R * c.p_P_anchor_m.cast<T>();
    W.col(i) = WrenchColumn<T>(r_F_anchor, SwivelCableAtPose<T>(c, q, R));
  }
  return W;
}

// CableLengths and WrenchMatrix from one swivel construction per cable (the forward statics'
// Newton needs both at each step, and the construction is most of their cost): the same
// values, bit for bit, as the two calls.
template <typename T>
void CableLengthsAndWrench(const SpatialRobot& robot, const SpatialPose<T>& q, Eigen::Matrix<T, Eigen::Dynamic, 1>* l,
                           Eigen::Matrix<T, 6, Eigen::Dynamic>* W) {
  const Eigen::Matrix<T, 3, 3> R = Rotation<T>(q);
  l->resize(robot.num_cables());
  W->resize(6, robot.num_cables());
  for (int i = 0; i < robot.num_cables(); ++i) {
    const SpatialCable& c = robot.cables[i];
    const SwivelCableState<T> s = SwivelCableAtPose<T>(c, q, R);
    (*l)(i) = s.length_m;
    W->col(i) = WrenchColumn<T>(R * c.p_P_anchor_m.cast<T>(), s);
  }
}

// Gravity wrench about p: [0; 0; -m g; (R c) x (0, 0, -m g)], c the centre of mass in P; the
// mass and c as scalars of their own where they are unknowns (the spatial identification's).
template <typename T>
Eigen::Matrix<T, 6, 1> GravityWrench(const SpatialPose<T>& q, const T& mass_kg, const Vec3<T>& p_P_com_m,
                                     double gravity_mps2) {
  const Vec3<T> force(T(0.0), T(0.0), -mass_kg * gravity_mps2);
  const Vec3<T> r_F_com = Rotation<T>(q) * p_P_com_m;
  Eigen::Matrix<T, 6, 1> w;
  w << force, r_F_com.cross(force);
  return w;
}
template <typename T>
Eigen::Matrix<T, 6, 1> GravityWrench(const SpatialRobot& robot, const SpatialPose<T>& q) {
  return GravityWrench<T>(q, T(robot.platform_mass_kg), robot.p_P_com_m.cast<T>(), robot.gravity_mps2);
}

// Wrench balance residual W t + w_g (N, N m); zero at static equilibrium.
template <typename T>
Eigen::Matrix<T, 6, 1> EquilibriumResidual(const SpatialRobot& robot, const SpatialPose<T>& q,
                                           const Eigen::Matrix<T, Eigen::Dynamic, 1>& tensions_N) {
  return WrenchMatrix<T>(robot, q) * tensions_N + GravityWrench<T>(robot, q);
}

// The unstretched length L of a cable l long under tension t: l = L (1 + t / EA); L = l for an
// inextensible cable (stiffness absent).
template <typename T>
T UnstretchedLength(const SpatialCable& cable, const T& length_m, const T& tension_N) {
  return UnstretchedLength<T>(cable.stiffness_N, length_m, tension_N);
}

}  // namespace cablecal
