// Test support: robots drawn at random within the ranges the design must handle (README,
// "Experiment design", robots nobody tuned for). Exit points at different heights and up to
// 0.3 m below the frame top, pulley radii 10-50 mm, centre of mass and anchors offset by up
// to 0.1 m, masses 0.5-10 kg, tension ranges scaled to the weight. Each draw goes through the
// robot-file loader (RobotToYaml, LoadRobotFromString), so it is a valid robot file; draws
// the loader rejects (a home pose outside the feasible workspace) are drawn again.
#pragma once

#include <cstdint>
#include <string>

#include "common/error.h"
#include "common/random.h"
#include "model/robot.h"

namespace cablecal::testing {

inline Robot RandomValidRobot(Rng& rng, const std::string& name) {
  for (int attempt = 0; attempt < 1000; ++attempt) {
    Robot r = BuiltinRobot();
    r.name = name;
    r.source = name;
    r.frame_width_m = rng.Uniform(2.5, 5.5);
    r.frame_height_m = rng.Uniform(2.0, 3.0);
    r.platform_mass_kg = rng.Uniform(0.5, 10.0);
    r.p_P_com_m = Eigen::Vector2d(rng.Uniform(-0.1, 0.1), rng.Uniform(-0.1, 0.1));
    const double half_bar = rng.Uniform(0.15, 0.3);
    r.cables[0].p_P_anchor_m = Eigen::Vector2d(-half_bar + rng.Uniform(-0.1, 0.1), rng.Uniform(-0.1, 0.1));
    r.cables[1].p_P_anchor_m = Eigen::Vector2d(half_bar + rng.Uniform(-0.1, 0.1), rng.Uniform(-0.1, 0.1));
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

}  // namespace cablecal::testing
