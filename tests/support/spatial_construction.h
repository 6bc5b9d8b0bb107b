// Test support: spatial cable lengths by an independent construction, without the model's
// closed form (model/swivel.h): the swivel tests check the closed form against it, the spatial
// identification tests make their readings with it.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>

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
inline Tangency TangencyConstruction(const Eigen::Vector3d& D, const Eigen::Vector3d& k, double r,
                                     const Eigen::Vector3d& B) {
  using Vec3d = Eigen::Vector3d;
  const Vec3d rho = B - D;
  const Vec3d u = (rho - rho.dot(k) * k).normalized();
  const Vec3d C = D + r * u;
  const Vec3d e1 = (D - C) / r;
  const Vec3d e2 = k.cross(u).normalized().cross(e1);  // = k: the cable's direction at D
  const auto point = [&](double a) { return Vec3d(C + r * (std::cos(a) * e1 + std::sin(a) * e2)); };
  const auto along = [&](double a) { return Vec3d(-std::sin(a) * e1 + std::cos(a) * e2); };
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

// The platform's orientation for (roll, pitch, yaw) composed of Eigen's angle-axis rotations
// (yaw about z, then pitch about y, then roll about x), not the model's matrix.
inline Eigen::Matrix3d RotationByAngleAxis(double roll, double pitch, double yaw) {
  return (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

// A cable's length from exit D (axis k, radius r; r = 0 an eyelet) to the anchor B, by the
// construction; NaN when it finds no tangent.
inline double LengthByConstruction(const Eigen::Vector3d& D, const Eigen::Vector3d& k, double r,
                                   const Eigen::Vector3d& B) {
  if (r == 0.0) return (B - D).norm();
  const Tangency t = TangencyConstruction(D, k, r, B);
  return t.found ? t.length_m : NAN;
}

}  // namespace cablecal::testing
