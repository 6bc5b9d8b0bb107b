// Uses an installed cablecal through find_package: samples poses of a robot file, simulates
// noise-free readings and identifies the geometry back. Prints the largest error and exits 0
// when it is below 1e-6 m.
#include <cstdio>

#include "experiment/experiment.h"
#include "identify/identify.h"
#include "model/robot.h"
#include "workspace/workspace.h"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: consumer ROBOT.yaml\n");
    return 2;
  }
  const cablecal::Robot robot = cablecal::LoadRobotFile(argv[1]);
  const std::vector<cablecal::PlanPose> plan = cablecal::SampleFeasiblePoses(robot, 12, 3);
  cablecal::Rng rng(1);
  const cablecal::SimulatedExperiment exp = cablecal::SimulateExperiment(
      robot, robot, plan, cablecal::SimulationOptions{cablecal::NoisySensors::kNone, false}, rng);
  const cablecal::IdentifyResult r = cablecal::Identify(robot, exp.measurements, cablecal::IdentifyOptions{});
  const double error = (r.geometry - cablecal::GeometryOf(robot)).cwiseAbs().maxCoeff();
  std::printf("%s: %d cables, status %s, largest geometry error %.3g m\n", robot.name.c_str(), robot.num_cables(),
              cablecal::ToString(r.status), error);
  return r.converged() && error < 1e-6 ? 0 : 1;
}
