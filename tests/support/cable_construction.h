// Test support: cable lengths by an independent construction, without the model's closed
// form (model/cable.h), for tests that need readings the model did not compute: the cable
// tests check the closed form against it, the identification tests make their measurements
// with it.
#pragma once

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cmath>

#include "model/robot.h"

namespace cablecal::testing {

// Independent construction: the tangent point T on the pulley circle is where the straight
// segment to B is perpendicular to the radius (found by bisection on the angle), on the
// branch where the cable leaves in its wrap direction; the arc runs from A to T in that
// direction (left pulley: clockwise from angle pi; right pulley: counter-clockwise from 0).
// A cable wrapping under its pulley travels the other way round (clockwise becomes
// counter-clockwise), which the construction takes from `wrap` without any mirrored frame.
inline double LengthByConstruction(const Eigen::Vector2d& A, double r, PulleySide side, const Eigen::Vector2d& B,
                                   PulleyWrap wrap = PulleyWrap::kOver) {
  const double s = SideSign(side);
  const Eigen::Vector2d C(A.x() + s * r, A.y());
  auto point = [&](double a) { return Eigen::Vector2d(C.x() + r * std::cos(a), C.y() + r * std::sin(a)); };
  const bool clockwise = (side == PulleySide::kLeft) == (wrap == PulleyWrap::kOver);
  auto wrap_dir = [&](double a) {  // travel direction of the cable on the pulley at angle a
    return clockwise ? Eigen::Vector2d(std::sin(a), -std::cos(a)) : Eigen::Vector2d(-std::sin(a), std::cos(a));
  };
  auto f = [&](double a) { return (B - point(a)).dot(point(a) - C); };
  const int kSteps = 720;
  for (int k = 0; k < kSteps; ++k) {
    double lo = -M_PI + 2 * M_PI * k / kSteps, hi = -M_PI + 2 * M_PI * (k + 1) / kSteps;
    if ((f(lo) < 0) == (f(hi) < 0)) continue;
    for (int it = 0; it < 200 && hi - lo > 1e-17; ++it) {
      const double mid = 0.5 * (lo + hi);
      ((f(mid) < 0) == (f(lo) < 0) ? lo : hi) = mid;
    }
    const double a = 0.5 * (lo + hi);
    const Eigen::Vector2d T = point(a);
    if (wrap_dir(a).dot(B - T) <= 0) continue;  // the other tangent
    const double from = side == PulleySide::kLeft ? M_PI : 0.0;
    double phi = clockwise ? from - a : a - from;
    phi = std::fmod(phi + 4 * M_PI, 2 * M_PI);
    return r * phi + (B - T).norm();
  }
  ADD_FAILURE() << "no tangent point found";
  return NAN;
}

// Cable i's length at pose q by the construction above (exit point to anchor).
inline double CableLengthByConstruction(const Cable& cable, const Eigen::Vector3d& q) {
  const double c = std::cos(q(2)), s = std::sin(q(2));
  const Eigen::Vector2d anchor(q(0) + c * cable.p_P_anchor_m.x() - s * cable.p_P_anchor_m.y(),
                               q(1) + s * cable.p_P_anchor_m.x() + c * cable.p_P_anchor_m.y());
  return LengthByConstruction(cable.p_F_exit_m, cable.pulley_radius_m, cable.side, anchor, cable.wrap);
}

}  // namespace cablecal::testing
