// The forward geometrico-static model of a cable robot of either kind, as a true robot behaves:
// the winches have paid out given UNSTRETCHED cable lengths, and the platform settles where its
// potential energy is stationary (a minimum: checked). What `simulate`, the Monte Carlo's true
// robots, the robust design's scenario check and validate's prediction (robots with stiffness)
// use.
//
// Potential energy: gravity m g z_com plus, over the elastic cables (stiffness E*A given), the
// strain energy EA (l - L)^2 / (2 L) while the cable is stretched (l > L; a slack cable carries
// nothing); an inextensible cable (no stiffness) is the constraint l_i(q) = L_i. Its stationary
// points are the roots of the KKT system in (q, t_inext):
//   W(q) t + w_g(q) = 0,   l_inext(q) - L_inext = 0,
// where t of an elastic cable is EA (l / L - 1) when l > L and 0 otherwise (the energy's
// derivative along l), and t of an inextensible cable is its Lagrange multiplier. W = -(dl/dxi)^T
// is the wrench matrix of the kind (model/cable.h, model/swivel.h), so W t + w_g = 0 says the
// energy's gradient vanishes.
//
// Why elastic cables: with more inextensible cables than the platform's degrees of freedom the
// commanded lengths, computed on the nominal model, cannot all hold on a true robot that differs
// from it; an elastic cable takes up the difference, as a real cable does. CheckSimulatable
// refuses a robot without enough of them.
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
// the KKT system above from `guess` (the commanded pose), then from the home pose and the
// least-squares pose of the lengths (a geometric starting guess, the cables taken as rigid);
// the first solution that passes the checks is returned. Checks, in order: every inextensible
// cable's multiplier > 0 (else kSlack: it would go slack), StaticStability stable (else
// kUnstable), every cable's geometry valid, the platform's reference point inside the frame and
// within kOtherAssemblyDistance_m / kOtherAssemblyAngle_rad of the guess (else kOtherAssembly).
// Elastic cables may come back slack (tension 0). length_residual_m: the largest
// |l_i(q) - L_i| over the inextensible cables.
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

// Whether the robot can be simulated: at most as many inextensible cables as the platform has
// degrees of freedom (planar 3, spatial 6). Throws InputError naming robot.source and the key
// cables[i].stiffness of the first cable without it, saying why, otherwise.
void CheckSimulatable(const Robot& robot);
void CheckSimulatable(const SpatialRobot& robot);

// Where a planar true robot settles with the given unstretched lengths, the one rule every
// physical stage uses: a robot without stiffness and 2 or 3 cables keeps the inextensible
// geometrico-static model (SolveForwardGeometricoStatic, the same numbers as before elastic
// cables existed); any robot with stiffness uses SolveForwardStatics. A robot with more than 3
// inextensible cables cannot be simulated (CheckSimulatable: callers check first; here it is
// a programming error).
ForwardResult SettlePlanar(const Robot& robot, const Eigen::VectorXd& unstretched_lengths_m,
                           const PlanarPose* guess = nullptr);

// Whether any cable of the robot has a stiffness.
bool HasStiffness(const Robot& robot);

}  // namespace cablecal
