#include "model/forward_statics.h"

#include <gtest/gtest.h>

#include <cstdio>

#include "model/cable.h"
#include "model/robot.h"
#include "model/statics.h"

namespace cablecal {
namespace {

TEST(ForwardStaticsDebug, Planar4) {
  const Robot r = LoadRobotFile(std::string(CABLECAL_SOURCE_DIR) + "/robots/planar4_fully_constrained.yaml");
  const PlanarPose q = PlanarPose(1.4, 1.1, 0.05);
  const TensionDistribution t = DistributeTensions(r, q);
  const Eigen::VectorXd L = CommandedUnstretchedLengths(r, CableLengths(r, q), t.tensions_N);
  Eigen::VectorXd Lp = L;
  Lp(0) += 0.003; Lp(2) -= 0.002;
  const ForwardResult f = SolveForwardStatics(r, Lp, &q);
  std::printf("status %s it %d q %g %g %g res %g t %g %g %g %g\n", ToString(f.status), f.iterations, f.equilibrium.q(0),
              f.equilibrium.q(1), f.equilibrium.q(2), f.equilibrium.residual_N, f.equilibrium.tensions_N(0),
              f.equilibrium.tensions_N(1), f.equilibrium.tensions_N(2), f.equilibrium.tensions_N(3));
}

}  // namespace
}  // namespace cablecal
