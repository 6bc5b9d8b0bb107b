// Test support: spatial robots drawn at random, so that no spatial test depends on a built-in
// robot's symmetry. Ranges (all uniform unless said):
//   frame box   x from -[1.5, 3.5] to +[1.5, 3.5] m and y from -[1.0, 3.0] to +[1.0, 3.0] m, each
//               side drawn on its own (asymmetric), z from 0 to [2.0, 4.0] m;
//   cables      m given (3 to 12); for m >= 6 about 2/3 "upper" exits at z in [H - 0.6, H], the
//               rest "lower" at z in [0, 0.5]; for m < 6 (underactuated: the platform hangs)
//               every exit upper; each on a random point of the box's side faces;
//   swivel axes upper: +z tilted by up to 40 degrees toward a random direction; lower: -z tilted
//               likewise; one cable in four instead horizontal, pointing away from the frame's
//               centre (IRMA4U's arrangement: the cable arrives travelling outward);
//   pulleys     radius [0.01, 0.08] m; one in eight an eyelet (r = 0);
//   platform    anchors anywhere in a box of half-sides [0.1, 0.4] x [0.1, 0.4] x [0.05, 0.3] m;
//               for m < 6 each anchor's x-y direction faces its exit at the home yaw, within
//               +-20 degrees, on the ellipse of those half-sides (crossed cables twist a hanging
//               platform: no equilibrium near home);
//               centre of mass offset by up to 0.1 m in each axis; mass [1, 100] kg;
//   tensions    min [1, 20] N, max min + [200, 2000] N; optional stiffness on half the cables,
//               E*A in [1e5, 1e7] N;
//   home        the frame's centre +-0.3 m in x and y, z in [0.35, 0.6] of the height, roll and
//               pitch +-10 degrees, yaw +-30 degrees.
// Each draw goes through the spatial robot file (SpatialRobotToYaml, LoadSpatialRobotFromString),
// so it is a valid robot file (home inside the frame with the margin, valid cable geometry at
// home, home a feasible, stable equilibrium: model/spatial_statics.h); a draw the loader refuses
// is drawn again, at most kMaxDraws times (measured over 20 robots each: about 15 refused draws
// per robot for m = 3 to 5, 120 for m = 6, 23 for m = 7, under 11 for m >= 8; 0.1 s at most). Fixed seeds in the tests: deterministic.
#pragma once

#include <Eigen/Geometry>
#include <cmath>
#include <stdexcept>
#include <string>

#include "common/error.h"
#include "common/random.h"
#include "model/spatial_robot.h"

namespace cablecal::testing {

// Draws sequenced by hand, as tests/support/random_robot.h's: a function's arguments are
// evaluated in an unspecified order (GCC right to left, clang left to right), so
// Vector3d(rng.Uniform(..), rng.Uniform(..), rng.Uniform(..)) drew other robots under clang
// (and the clang build's tests then ran on robots nobody had run them on). Each draws its last
// coordinate first, as GCC did, so the robots the tests were written against stay the same.
inline Eigen::Vector3d DrawVector3(Rng& rng, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  const double z = rng.Uniform(lo.z(), hi.z());
  const double y = rng.Uniform(lo.y(), hi.y());
  const double x = rng.Uniform(lo.x(), hi.x());
  return Eigen::Vector3d(x, y, z);
}
inline Eigen::Vector2d DrawVector2(Rng& rng, const Eigen::Vector2d& lo, const Eigen::Vector2d& hi) {
  const double y = rng.Uniform(lo.y(), hi.y());
  const double x = rng.Uniform(lo.x(), hi.x());
  return Eigen::Vector2d(x, y);
}

// A unit vector `base` tilted by up to max_tilt_rad toward a random direction.
inline Eigen::Vector3d TiltedAxis(Rng& rng, const Eigen::Vector3d& base, double max_tilt_rad) {
  const Eigen::Vector3d any = std::abs(base.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d e1 = base.cross(any).normalized();
  const Eigen::Vector3d e2 = base.cross(e1);
  const double tilt = rng.Uniform(0.0, max_tilt_rad), around = rng.Uniform(-M_PI, M_PI);
  return (std::cos(tilt) * base + std::sin(tilt) * (std::cos(around) * e1 + std::sin(around) * e2)).normalized();
}

// A random point on the side faces of the box [lo, hi] (x-y rectangle's perimeter) at height z.
inline Eigen::Vector3d PointOnSideFaces(Rng& rng, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, double z) {
  const double wx = hi.x() - lo.x(), wy = hi.y() - lo.y();
  double s = rng.Uniform(0.0, 2.0 * (wx + wy));
  if (s < wx) return Eigen::Vector3d(lo.x() + s, lo.y(), z);
  s -= wx;
  if (s < wy) return Eigen::Vector3d(hi.x(), lo.y() + s, z);
  s -= wy;
  if (s < wx) return Eigen::Vector3d(hi.x() - s, hi.y(), z);
  s -= wx;
  return Eigen::Vector3d(lo.x(), hi.y() - s, z);
}

// The draws before giving up: m = 6 needs the most (its unique tensions must all be positive),
// about 1 in 120 accepted, so 5000 refusals in a row happen with probability e^-40.
constexpr int kMaxDraws = 5000;

inline SpatialRobot RandomSpatialRobot(Rng& rng, const std::string& name, int num_cables) {
  for (int attempt = 0; attempt < kMaxDraws; ++attempt) {
    SpatialRobot r;
    r.name = name;
    r.gravity_mps2 = 9.81;
    const double H = rng.Uniform(2.0, 4.0);
    r.p_F_frame_min_m << -DrawVector2(rng, {1.5, 1.0}, {3.5, 3.0}), 0.0;
    r.p_F_frame_max_m << DrawVector2(rng, {1.5, 1.0}, {3.5, 3.0}), H;
    const Eigen::Vector3d centre = 0.5 * (r.p_F_frame_min_m + r.p_F_frame_max_m);
    r.platform_mass_kg = rng.Uniform(1.0, 100.0);
    r.p_P_com_m = DrawVector3(rng, Eigen::Vector3d::Constant(-0.1), Eigen::Vector3d::Constant(0.1));
    const Eigen::Vector3d half = DrawVector3(rng, {0.1, 0.1, 0.05}, {0.4, 0.4, 0.3});
    for (int i = 0; i < num_cables; ++i) {
      SpatialCable c;
      const bool upper = rng.Uniform() < 2.0 / 3.0 || num_cables < 6;
      const double z = upper ? rng.Uniform(H - 0.6, H) : rng.Uniform(0.0, 0.5);
      c.p_F_exit_m = PointOnSideFaces(rng, r.p_F_frame_min_m, r.p_F_frame_max_m, z);
      if (rng.Uniform() < 0.25) {
        Eigen::Vector3d outward = c.p_F_exit_m - centre;
        outward.z() = 0.0;
        c.k_F_swivel_axis = outward.normalized();
      } else {
        c.k_F_swivel_axis = TiltedAxis(rng, Eigen::Vector3d(0.0, 0.0, upper ? 1.0 : -1.0), 40.0 * M_PI / 180.0);
      }
      c.pulley_radius_m = rng.Uniform() < 0.125 ? 0.0 : rng.Uniform(0.01, 0.08);
      if (rng.Uniform() < 0.5) c.stiffness_N = rng.Uniform(1e5, 1e7);
      c.p_P_anchor_m = DrawVector3(rng, -half, half);
      r.cables.push_back(c);
    }
    r.tension_min_N = rng.Uniform(1.0, 20.0);
    r.tension_max_N = r.tension_min_N + rng.Uniform(200.0, 2000.0);
    r.tilt_max_rad = 30.0 * M_PI / 180.0;
    r.margin_m = 0.05;
    const Eigen::Vector3d home_draw = DrawVector3(rng, {-0.3, -0.3, 0.35}, {0.3, 0.3, 0.6});
    r.p_F_home_m = Eigen::Vector3d(centre.x() + home_draw.x(), centre.y() + home_draw.y(), H * home_draw.z());
    const double deg = M_PI / 180.0;
    r.home_rpy_rad = deg * DrawVector3(rng, {-10.0, -10.0, -30.0}, {10.0, 10.0, 30.0});
    if (num_cables < 6) {
      // A hanging robot's anchors face their exits (else the cables cross and no orientation
      // near the drawn one balances the platform): anchor i's x-y direction in P is its exit's
      // azimuth from home, at the home yaw, within +-20 degrees; its height as drawn.
      for (SpatialCable& c : r.cables) {
        const Eigen::Vector3d to_exit = c.p_F_exit_m - r.p_F_home_m;
        const double a = std::atan2(to_exit.y(), to_exit.x()) - r.home_rpy_rad.z() + rng.Uniform(-20.0, 20.0) * deg;
        c.p_P_anchor_m.head<2>() = Eigen::Vector2d(half.x() * std::cos(a), half.y() * std::sin(a));
      }
    }
    r.sensors.encoder_sigma_m = 5e-5;
    r.sensors.tracker_sigma_m = 5e-4;
    try {
      return LoadSpatialRobotFromString(SpatialRobotToYaml(r), name);
    } catch (const InputError&) {
      // refused (a coincident exit, invalid geometry at home, ...): draw again
    }
  }
  throw std::runtime_error("no valid random spatial robot in " + std::to_string(kMaxDraws) + " draws");
}

}  // namespace cablecal::testing
