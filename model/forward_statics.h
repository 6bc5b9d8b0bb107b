// The forward geometrico-static model of a cable robot of either kind, as a true robot behaves:
// the winches have paid out given UNSTRETCHED cable lengths, and the platform settles where its
// potential energy is stationary (a minimum: checked). What `simulate`, the Monte Carlo's true
// robots, the robust design's scenario check and validate's prediction (robots with stiffness)
// use.
//
// Potential energy: gravity m g z_com plus, over the elastic cables (stiffness E*A given), the
// strain energy EA (l - L)^2 / (2 L) while the cable is stretched (l > L; a slack cable carries
// nothing); an inextensible cable (no stiffness) is the constraint l_i(q) = L_i. Its stationary
// points are where
//   W(q) t + w_g(q) = 0,
// t_i = EA (l_i / L_i - 1) for a stretched elastic cable (the energy's derivative along l), 0 for
// a slack one, and the Lagrange multiplier of l_i(q) = L_i for an inextensible one. W = -(dl/dxi)^T
// is the wrench matrix of the kind (model/cable.h, model/swivel.h), so this says the gradient
// vanishes. The solver writes every taut cable's law as one row, l_i(q) - L_i - (L_i / EA_i) t_i
// = 0 (compliance 0 for an inextensible cable), with t_i an unknown: damped Newton in (q, t_taut)
// then stays well conditioned however stiff a cable is, and EA -> infinity is the inextensible
// row itself. Which elastic cables are taut is an active set (a negative tension goes slack, a
// slack cable stretched comes back).
//
// Why elastic cables: with more inextensible cables than the platform's degrees of freedom the
// commanded lengths, computed on the nominal model, cannot all hold on a true robot that differs
// from it; an elastic cable takes up the difference, as a real cable does. CheckSimulatable
// refuses a spatial robot without enough of them. A planar robot of 4 or more cables without
// stiffness keeps the rigid-cable convention (SettlePlanar): the planar identification does not
// model stretch yet, and with elastic physics such a robot could not be calibrated at all
// (README, "Any number of cables", measured there).
//
// Depends on model/statics.h (planar), model/swivel.h and model/spatial_statics.h (spatial),
// model/stability.h (the stability test of a solution).
#pragma once

#include <Eigen/Core>

#include "model/kind.h"
#include "model/robot.h"
#include "model/spatial_robot.h"
#include "model/spatial_statics.h"
#include "model/statics.h"

namespace cablecal {

// The pose where the platform of `robot`, whose cables have the given unstretched lengths (for
// an inextensible cable, its geometric length exit point -> anchor), settles: damped Newton on
// the system above from `guess` (the commanded pose), then from the home pose and from the
// least-squares pose of the lengths (a geometric starting guess, the cables taken as rigid);
// the first solution that passes the checks is returned, else the first that converged, with
// the check it failed. Checks, in order: every inextensible cable's multiplier > 0 (else
// kSlack: it would go slack), StaticStability stable (else kUnstable), every cable's geometry
// valid, the platform's reference point inside the frame and within kOtherAssemblyDistance_m /
// kOtherAssemblyAngle_rad of the guess (else kOtherAssembly). Elastic cables may come back slack
// (tension 0). length_residual_m: the largest |l_i(q) - L_i| over the inextensible cables.
// reduced_stiffness: StaticStability's smallest eigenvalue (NaN when no motion is free).
ForwardResult SolveForwardStatics(const Robot& robot, const Eigen::VectorXd& unstretched_lengths_m,
                                  const PlanarPose* guess = nullptr);

struct SpatialForwardResult {
  ForwardStatus status = ForwardStatus::kNotConverged;
  SpatialEquilibrium equilibrium;
  int iterations = 0;
  double length_residual_m = 0.0;
};
SpatialForwardResult SolveForwardStatics(const SpatialRobot& robot, const Eigen::VectorXd& unstretched_lengths_m,
                                         const SpatialPose<double>* guess = nullptr);

// The unstretched lengths the controller commands for a nominal equilibrium (geometric lengths l
// at tensions t): L = l / (1 + t / EA) per elastic cable, l for an inextensible one.
Eigen::VectorXd CommandedUnstretchedLengths(const Robot& robot, const Eigen::VectorXd& lengths_m,
                                            const Eigen::VectorXd& tensions_N);
Eigen::VectorXd CommandedUnstretchedLengths(const SpatialRobot& robot, const Eigen::VectorXd& lengths_m,
                                            const Eigen::VectorXd& tensions_N);
// The cables paid out at a spatial equilibrium: CommandedUnstretchedLengths of its lengths and
// tensions (at home, where the encoders read zero: SpatialHome, and the identification's start of l_i0).
Eigen::VectorXd PaidOutLengths(const SpatialRobot& robot, const SpatialEquilibrium& equilibrium);

// Whether a spatial robot can be simulated: at most as many inextensible cables as the
// platform's 6 degrees of freedom. Throws InputError naming robot.source and the key
// cables[i].stiffness of the first cable without it, saying why, otherwise.
void CheckSimulatable(const SpatialRobot& robot);

// Where a planar true robot settles with the given unstretched lengths, the one rule every
// physical stage uses: any robot with stiffness settles by SolveForwardStatics; a robot without
// keeps the inextensible model (SolveForwardGeometricoStatic, the same numbers as before
// elastic cables existed), for 4 or more cables the rigid-cable convention: the least-squares
// pose of the commanded lengths (model/statics.h).
ForwardResult SettlePlanar(const Robot& robot, const Eigen::VectorXd& unstretched_lengths_m,
                           const PlanarPose* guess = nullptr);

// An elastic cable's tension comes from its stretch, EA (l / L - 1): a plan's tension at a bound
// (the minimum-norm distribution puts some there) comes back a few ulps of EA off it, which is
// no tension limit broken. The tensions within kTensionRounding x max of a bound are set on it.
constexpr double kTensionRounding = 1e-9;
Eigen::VectorXd SnapTensionsToBounds(Eigen::VectorXd tensions_N, double tension_min_N, double tension_max_N);

// Whether any cable of the robot has a stiffness.
bool HasStiffness(const Robot& robot);

}  // namespace cablecal
