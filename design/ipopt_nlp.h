// Internal to design/: the Ipopt adapter, built per start, writing into a StartOutcome.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "design/design.h"

namespace Ipopt {
class IpoptApplication;  // not included here: Ipopt's headers need its pkg-config flags
}

namespace cablecal::internal {

// Bounds are tightened by these amounts so that poses re-solved exactly by the model after
// Ipopt (which may sit on a bound to within its tolerance) still satisfy the exact bounds.
constexpr double kBoundMargin_m = 1e-6;
constexpr double kBoundMargin_rad = 1e-6;
constexpr double kBoundMargin_N = 1e-5;

struct StartOutcome {
  std::string status;
  int iterations = 0;
  bool converged = false;
  std::vector<PlanarPose> poses;       // Ipopt's (x, z, theta)
  std::vector<Eigen::VectorXd> tensions_N;  // Ipopt's tensions, one per cable
};

// One Ipopt solve from `start` (equilibria with their tensions). `widening`, if given, holds
// one factor per pose on the robustness rows' half-width k sigma (design.cc widens the poses
// whose scenario check failed).
StartOutcome SolveDesignNlp(const Robot& robot, const DesignOptions& options, const std::vector<PlanPose>& start,
                            const std::vector<double>* widening = nullptr);

// Initialize() for both designs' Ipopt (planar and spatial) without an options file: Ipopt
// otherwise reads an ipopt.opt from the working directory, so that a stray file (a lab's own
// Ipopt work) would change a plan silently. True when Ipopt initialized (its options valid).
bool InitializeIpopt(Ipopt::IpoptApplication& app);

}  // namespace cablecal::internal
