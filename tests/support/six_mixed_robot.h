// Test support: a new user's 6-cable suspended robot (an 8 kg platform, two of its six cables
// stretching, one swivel axis tilted 5 degrees, an offset centre of mass, exits at different
// heights), as robot-file text with its home given: its optimum at 12 designed poses is unstable
// with the stretch (design's test), and at home (1.3, 0, 1.2) no tensions balance it (the
// loader's test).
#pragma once

#include <string>

namespace cablecal::testing {

inline std::string SixMixedRobotYaml(const std::string& home = "[0.05, 0.0, 1.2]") {
  return R"(name: six-mixed
kind: spatial
gravity: 9.81
frame: {min: [-1.5, -1.2, 0.0], max: [1.6, 1.3, 2.5]}
platform:
  mass: 8.0
  com: [0.02, -0.015, 0.10]
  mass_sigma: 0.1
  com_sigma: 0.004
  anchors: [[0.19, -0.08, 0.0], [-0.04, 0.12, 0.3], [-0.12, -0.18, 0.3], [0.06, 0.18, 0.0], [0.18, 0.07, 0.3],
            [-0.08, -0.12, 0.3]]
cables:
  - {exit: [1.5, -0.6, 2.40], swivel_axis: [0, 0, 1], pulley_radius: 0.03, stiffness: 60000.0}
  - {exit: [1.5, 0.7, 2.35], swivel_axis: [0.0872, 0, 0.9962], pulley_radius: 0.03}
  - {exit: [0.1, 1.25, 2.45], swivel_axis: [0, 0, 1], pulley_radius: 0.03, stiffness: 80000.0}
  - {exit: [-1.45, 0.6, 2.30], swivel_axis: [0, 0, 1], pulley_radius: 0.025}
  - {exit: [-1.4, -0.65, 2.42], swivel_axis: [0, 0, 1], pulley_radius: 0.025}
  - {exit: [0.0, -1.15, 2.38], swivel_axis: [0, 0, 1], pulley_radius: 0.03}
tension: {min: 5.0, max: 400.0}
limits: {tilt_max_deg: 20, margin: 0.05}
home: )" + home + R"(
sensors:
  encoder: {sigma: 0.0001}
  inclinometer: {accuracy_deg: 0.1, repeatability_deg: 0.05}
  laser: {accuracy: 0.003, repeatability: 0.001}
)";
}

}  // namespace cablecal::testing
