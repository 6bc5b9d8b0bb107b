// Internal to design/: the criteria's minimised objectives and their exact gradients with
// respect to every pose's (x, z, theta), for any cable count m. The Jacobian rows are
// identify/jacobian.h's, automatic derivatives of the identification's own residuals; their
// derivatives with respect to the pose come from the same evaluation with nested Jets.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "design/design.h"

namespace cablecal::internal {

// Sharpness of the smooth surrogates (objective.cc): the minimiser of the condition-number
// surrogate has kappa within d^(1/p) of the optimum, d = 3m - 1 + n columns (m = 2, n = 50:
// 1.13); the E surrogate is within (3m - 1)^(1/p) of lambda_min (m = 2: 1.05, m = 8: 1.11).
constexpr double kConditionPower = 32.0;
constexpr double kEigenvaluePower = 32.0;

// What Ipopt minimises: the smooth surrogate of log kappa (condition), -log det S (d),
// log trace S^-1 (a), the smooth surrogate of -log lambda_min(S) (e). Returns +inf where
// the set cannot identify the geometry. If `gradient` is given it receives
// d objective / d(x_j, z_j, theta_j), 3 per pose.
// `power` overrides the surrogates' sharpness (0: the defaults above); the design starts
// with a smoother surrogate and sharpens it (continuation, kContinuationPower).
constexpr double kContinuationPower = 8.0;
// `prior` (D, A, E only): information already gathered, added to the poses' (design --prior).
double DesignObjective(const Robot& robot, Criterion criterion, const std::vector<PlanarPose>& poses,
                       Eigen::VectorXd* gradient, double power = 0.0, const PriorInformation* prior = nullptr);

// The same criteria exactly (log kappa, -log lambda_min without surrogate), for reporting.
double ExactObjective(const Robot& robot, Criterion criterion, const std::vector<PlanarPose>& poses,
                      const PriorInformation* prior = nullptr);

}  // namespace cablecal::internal
