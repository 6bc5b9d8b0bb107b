// Test support: spatial cable lengths by an independent construction, without the model's
// closed form (model/swivel.h) or its rotation: the swivel tests check the closed form against
// it, the spatial statics tests differentiate it numerically for an independent equilibrium
// and stability check.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>

#include "model/spatial_robot.h"

namespace cablecal::testing {

struct Tangency {
  bool found = false;
  double length_m = 0.0;
  double arc_rad = 0.0;  // from D to T in the cable's direction, in [0, 2 pi)
  Eigen::Vector3d p_F_tangent_m = Eigen::Vector3d::Zero();
};

// Independent construction: the pulley circle in 3-D (centre C = D + r u, u toward the anchor
// off the axis, normal k x u) parameterised from D by the angle a travelled in the cable's
// direction (a = 0 at D, increasing along k there); the tangent point T solves
// (T - C) . (B - T) = 0 (a scan for sign changes, then bisection), on the branch where the
// cable leaves toward B (dT/da . (B - T) > 0); l = r a_T + |B - T|.
Tangency TangencyConstruction(const Eigen::Vector3d& D, const Eigen::Vector3d& k, double r, const Eigen::Vector3d& B) {
  const Eigen::Vector3d rho = B - D;
  const Eigen::Vector3d u = (rho - rho.dot(k) * k).normalized();
  const Eigen::Vector3d C = D + r * u;
  const Eigen::Vector3d e1 = (D - C) / r;
  const Eigen::Vector3d e2 = k.cross(u).normalized().cross(e1);  // = k: the cable's direction at D
  const auto point = [&](double a) { return Eigen::Vector3d(C + r * (std::cos(a) * e1 + std::sin(a) * e2)); };
  const auto along = [&](double a) { return Eigen::Vector3d(-std::sin(a) * e1 + std::cos(a) * e2); };
  const auto f = [&](double a) { return (point(a) - C).dot(B - point(a)); };
  Tangency t;
  constexpr int kSteps = 1440;
  for (int s = 0; s < kSteps; ++s) {
    double lo = -M_PI + 2.0 * M_PI * s / kSteps, hi = -M_PI + 2.0 * M_PI * (s + 1) / kSteps;
    if ((f(lo) < 0.0) == (f(hi) < 0.0)) continue;
    for (int it = 0; it < 200 && hi - lo > 1e-16; ++it) {
      const double mid = 0.5 * (lo + hi);
      ((f(mid) < 0.0) == (f(lo) < 0.0) ? lo : hi) = mid;
    }
    const double a = 0.5 * (lo + hi);
    if (along(a).dot(B - point(a)) <= 0.0) continue;  // the other tangent
    t.found = true;
    t.arc_rad = std::fmod(a + 2.0 * M_PI, 2.0 * M_PI);
    t.p_F_tangent_m = point(a);
    t.length_m = r * t.arc_rad + (B - t.p_F_tangent_m).norm();
    return t;
  }
  return t;
}

// The platform's orientation R = Rz(yaw) Ry(pitch) Rx(roll) composed from Eigen's angle-axis
// rotations (not model/swivel.h's closed form).
inline Eigen::Matrix3d RotationByComposition(const Eigen::Matrix<double, 6, 1>& q) {
  return (Eigen::AngleAxisd(q(5), Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(q(4), Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(q(3), Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

// A platform point b (in P) in F at pose q, by the composed rotation.
inline Eigen::Vector3d PointByComposition(const Eigen::Matrix<double, 6, 1>& q, const Eigen::Vector3d& p_P_m) {
  return q.head<3>() + RotationByComposition(q) * p_P_m;
}

// Cable `cable`'s length at pose q by the construction (an eyelet: the straight distance);
// NaN where the construction finds no tangent.
inline double SpatialLengthByConstruction(const SpatialCable& cable, const Eigen::Matrix<double, 6, 1>& q) {
  const Eigen::Vector3d B = PointByComposition(q, cable.p_P_anchor_m);
  if (cable.pulley_radius_m == 0.0) return (B - cable.p_F_exit_m).norm();
  const Tangency t = TangencyConstruction(cable.p_F_exit_m, cable.k_F_swivel_axis, cable.pulley_radius_m, B);
  return t.found ? t.length_m : NAN;
}

}  // namespace cablecal::testing
