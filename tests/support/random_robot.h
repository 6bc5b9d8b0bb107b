// Test support: robots drawn at random within the ranges the design must handle (README,
// "Experiment design", robots nobody tuned for). Exit points at different heights and up to
// 0.3 m below the frame top, pulley radii 10-50 mm, centre of mass and anchors offset by up
// to 0.1 m, masses 0.5-10 kg, tension ranges scaled to the weight. Each draw goes through the
// robot-file loader (RobotToYaml, LoadRobotFromString), so it is a valid robot file; draws
// the loader rejects (a home pose outside the feasible workspace) are drawn again.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>
#include <string>

#include "common/error.h"
#include "common/random.h"
#include "model/robot.h"
#include "model/statics.h"

namespace cablecal::testing {

// The draws below are sequenced by hand: a function's arguments are evaluated in an unspecified
// order (GCC right to left, clang left to right), so Vector2d(rng.Uniform(..), rng.Uniform(..))
// drew other robots under clang. Each pair draws its second coordinate first, as GCC did, so
// that the robots the tests were written against stay the same.
inline Eigen::Vector2d DrawPair(Rng& rng, double x_lo, double x_hi, double z_lo, double z_hi) {
  const double z = rng.Uniform(z_lo, z_hi);
  const double x = rng.Uniform(x_lo, x_hi);
  return Eigen::Vector2d(x, z);
}

inline Robot RandomValidRobot(Rng& rng, const std::string& name) {
  for (int attempt = 0; attempt < 1000; ++attempt) {
    Robot r = BuiltinRobot();
    r.name = name;
    r.source = name;
    r.frame_width_m = rng.Uniform(2.5, 5.5);
    r.frame_height_m = rng.Uniform(2.0, 3.0);
    r.platform_mass_kg = rng.Uniform(0.5, 10.0);
    r.p_P_com_m = DrawPair(rng, -0.1, 0.1, -0.1, 0.1);
    const double half_bar = rng.Uniform(0.15, 0.3);
    r.cables[0].p_P_anchor_m = Eigen::Vector2d(-half_bar, 0.0) + DrawPair(rng, -0.1, 0.1, -0.1, 0.1);
    r.cables[1].p_P_anchor_m = Eigen::Vector2d(half_bar, 0.0) + DrawPair(rng, -0.1, 0.1, -0.1, 0.1);
    r.cables[0].p_F_exit_m = Eigen::Vector2d(0.0, r.frame_height_m - rng.Uniform(0.0, 0.3));
    r.cables[1].p_F_exit_m = Eigen::Vector2d(r.frame_width_m, r.frame_height_m - rng.Uniform(0.0, 0.3));
    for (Cable& c : r.cables) {
      c.pulley_radius_m = rng.Uniform(0.010, 0.050);
      c.initial_length_m.reset();
    }
    const double weight_N = r.platform_mass_kg * r.gravity_mps2;
    r.tension_min_N = weight_N * rng.Uniform(0.02, 0.1);
    r.tension_max_N = weight_N * rng.Uniform(3.5, 6.0);
    r.p_F_home_m = Eigen::Vector2d(r.frame_width_m / 2 + rng.Uniform(-0.2, 0.2), r.frame_height_m / 2);
    try {
      return LoadRobotFromString(RobotToYaml(r), name);
    } catch (const InputError&) {
      // not a valid robot (its home is not feasible): draw again
    }
  }
  throw std::runtime_error("no valid random robot in 1000 draws");
}

// A random robot with m = 2..8 cables. Suspended (fully_constrained false): every cable
// wraps over a pulley on or near the top beam, the outer two at the frame's corners, the rest
// anywhere between 20 % and 80 % of the width, anchors spread along the platform's top edge
// and the centre of mass below them. Fully constrained (m >= 4): about half the cables over
// pulleys at the top, the rest under pulleys low on the frame (wrap: under), each on the
// platform edge facing its pulley. The home pose is near the frame's centre at the middle of
// its feasible theta band (found by scanning), so that the loader accepts it. m >= 4: every
// cable elastic, E*A = kRandomStiffnessOverMaxTension x tension.max.
constexpr double kRandomStiffnessOverMaxTension = 3000.0;
inline Robot RandomRobotWithCables(Rng& rng, const std::string& name, int m, bool fully_constrained) {
  if (m == 2 && !fully_constrained) return RandomValidRobot(rng, name);
  for (int attempt = 0; attempt < 1000; ++attempt) {
    Robot r = BuiltinRobot();
    r.name = name;
    r.source = name;
    r.frame_width_m = rng.Uniform(2.5, 4.5);
    r.frame_height_m = rng.Uniform(2.0, 3.0);
    r.platform_mass_kg = rng.Uniform(0.5, 10.0);
    r.theta_max_rad = 45.0 * M_PI / 180.0;
    const double W = r.frame_width_m, H = r.frame_height_m;
    const double half_w = rng.Uniform(0.15, 0.3), half_h = rng.Uniform(0.05, 0.15);
    const int top = fully_constrained ? (m + 1) / 2 : m;
    r.cables.assign(m, Cable{});
    // Exit x positions along a beam: both corners, then the rest inside, sorted left to right.
    auto beam = [&](int count) {
      std::vector<double> xs = {0.0, W};
      while (static_cast<int>(xs.size()) < count) xs.push_back(rng.Uniform(0.2 * W, 0.8 * W));
      std::sort(xs.begin(), xs.end());
      return xs;
    };
    const std::vector<double> top_x = beam(top);
    for (int i = 0; i < top; ++i) {
      Cable& c = r.cables[i];
      c.p_F_exit_m = Eigen::Vector2d(top_x[i], H - rng.Uniform(0.0, 0.3));
      c.side = top_x[i] < W / 2 ? PulleySide::kLeft : PulleySide::kRight;
      c.wrap = PulleyWrap::kOver;
      const double along = top == 1 ? 0.0 : -half_w + 2.0 * half_w * i / (top - 1);
      c.p_P_anchor_m = Eigen::Vector2d(along, fully_constrained ? half_h : 0.0) + DrawPair(rng, -0.03, 0.03, 0.0, 0.05);
    }
    if (fully_constrained) {
      const std::vector<double> bottom_x = beam(m - top);
      for (int k = 0; k < m - top; ++k) {
        Cable& c = r.cables[top + k];
        c.p_F_exit_m = Eigen::Vector2d(bottom_x[k], rng.Uniform(0.05, 0.3));
        c.side = bottom_x[k] < W / 2 ? PulleySide::kLeft : PulleySide::kRight;
        c.wrap = PulleyWrap::kUnder;
        const double along = m - top == 1 ? 0.0 : -half_w + 2.0 * half_w * k / (m - top - 1);
        const Eigen::Vector2d d = DrawPair(rng, -0.03, 0.03, 0.0, 0.05);
        c.p_P_anchor_m = Eigen::Vector2d(along + d.x(), -half_h - d.y());
      }
    }
    for (Cable& c : r.cables) {
      c.pulley_radius_m = rng.Uniform(0.010, 0.050);
      c.initial_length_m.reset();
    }
    r.p_P_com_m = fully_constrained ? DrawPair(rng, -0.05, 0.05, -0.05, 0.05) : DrawPair(rng, -0.05, 0.05, -0.12, -0.02);
    const double weight_N = r.platform_mass_kg * r.gravity_mps2;
    r.tension_min_N = weight_N * rng.Uniform(0.02, 0.1);
    r.tension_max_N = weight_N * rng.Uniform(fully_constrained ? 6.0 : 3.5, fully_constrained ? 10.0 : 6.0);
    // m >= 4: rigid cables over-determine the pose, and a true robot that differs from the
    // nominal one is simulated with elastic ones (model/forward_statics.h). E*A = 3000 x
    // tension.max on every cable (0.033 % stretch at the largest tension, a steel wire rope's
    // ratio; no draw, so the robots are the ones drawn before stiffness existed).
    for (Cable& c : r.cables) {
      if (m >= 4) c.stiffness_N = kRandomStiffnessOverMaxTension * r.tension_max_N;
    }
    r.p_F_home_m = Eigen::Vector2d(W / 2 + rng.Uniform(-0.2, 0.2), H / 2);
    // The middle of the feasible theta band at home, on a 0.5-degree scan.
    double lo = 1e9, hi = -1e9;
    for (int k = -80; k <= 80; ++k) {
      const double theta = k * 0.5 * M_PI / 180.0;
      if (EvaluatePose(r, Eigen::Vector3d(r.p_F_home_m.x(), r.p_F_home_m.y(), theta)).feasible()) {
        lo = std::min(lo, theta);
        hi = std::max(hi, theta);
      }
    }
    if (lo > hi) continue;
    r.home_theta_rad = std::round((0.5 * (lo + hi)) * 180.0 / M_PI) * M_PI / 180.0;
    try {
      return LoadRobotFromString(RobotToYaml(r), name);
    } catch (const InputError&) {
      // the rounded home angle left the band, or another check: draw again
    }
  }
  throw std::runtime_error("no valid random robot with " + std::to_string(m) + " cables in 1000 draws");
}

}  // namespace cablecal::testing
