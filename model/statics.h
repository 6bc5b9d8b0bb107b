// Statics of the suspended platform: equilibrium at a given position, its stability,
// the feasible-pose test, and the inverse and forward geometrico-static models.
//
// With m = 2 cables and 3 DoF the platform is under-constrained: for given (x, z) the
// force and moment balance W t + w_g = 0 fixes theta and the tensions; for given cable
// lengths the platform settles where its potential energy is least with both cables taut.
#pragma once

#include <Eigen/Core>
#include <string>

#include "model/robot.h"

namespace cablecal {

struct Equilibrium {
  Eigen::Vector3d q = Eigen::Vector3d::Zero();  // (x_m, z_m, theta_rad)
  Eigen::VectorXd tensions_N;
  double residual_N = 0.0;   // |W t + w_g| (force and moment rows together)
  // Curvature of the potential energy along the one motion the fixed cable lengths allow
  // (reduced Hessian of the Lagrangian, direction normalised in (m, m, rad)). > 0: stable.
  double reduced_stiffness = 0.0;
  bool stable = false;
};

enum class EquilibriumStatus {
  kFound,          // taut cables (t > 0), stable
  kNoEquilibrium,  // no theta balances the platform with both cables pulling
  kUnstable,       // balance exists with taut cables, but only at a potential-energy maximum
  kCableGeometry,  // an anchor inside its pulley or a cable that cannot touch its pulley
};

struct EquilibriumResult {
  EquilibriumStatus status = EquilibriumStatus::kNoEquilibrium;
  Equilibrium equilibrium;  // meaningful when status == kFound
};

// Equilibrium at platform position (x, z): searches theta in (-89 deg, 89 deg) for roots
// of the moment balance (forces solved exactly for each theta), keeps the stable root with
// taut cables and the smallest |theta|. Requires m = 2.
EquilibriumResult SolveEquilibrium(const Robot& robot, double x_m, double z_m);

// Reduced stiffness at (q, t), see Equilibrium::reduced_stiffness.
double ReducedStiffness(const Robot& robot, const Eigen::Vector3d& q,
                        const Eigen::VectorXd& tensions_N);

// Cable lengths exit point -> anchor at a full pose (x, z, theta) (paper, Eq. 1-2).
Eigen::VectorXd CableLengths(const Robot& robot, const Eigen::Vector3d& q);

// Why a position is or is not in the feasible cable-tension workspace.
enum class Feasibility {
  kFeasible,
  kOutsideFrame,   // the platform (anchors, centre of mass) leaves the frame minus the margin
  kLaserRange,     // z beyond the laser range
  kCableGeometry,
  kNoEquilibrium,
  kUnstable,
  kThetaLimit,     // |theta| beyond the inclinometer range
  kTensionLow,
  kTensionHigh,
};
const char* ToString(Feasibility f);  // "feasible", "outside_frame", ...

struct PoseEvaluation {
  Feasibility feasibility = Feasibility::kNoEquilibrium;
  bool has_equilibrium = false;  // equilibrium below is meaningful (also for theta/tension failures)
  Equilibrium equilibrium;
  bool feasible() const { return feasibility == Feasibility::kFeasible; }
};

// The feasible cable-tension workspace test (README, "Model and conventions") at (x, z).
PoseEvaluation EvaluatePose(const Robot& robot, double x_m, double z_m);

// Checks the conditions of EvaluatePose for an already known equilibrium (q, t), e.g. one
// returned by the design optimiser. Does not re-solve.
Feasibility CheckFeasibility(const Robot& robot, const Eigen::Vector3d& q,
                             const Eigen::VectorXd& tensions_N);

// Initial cable lengths l_i0: the file's initial_length if given, else the length at the
// home pose's equilibrium. Throws InputError if the home pose has no feasible equilibrium.
Eigen::VectorXd InitialLengths(const Robot& robot);

// Inverse model: position (x, z) -> equilibrium pose and cable lengths.
struct InversePose {
  PoseEvaluation evaluation;
  Eigen::VectorXd lengths_m;  // set when evaluation.has_equilibrium
};
InversePose InverseModel(const Robot& robot, double x_m, double z_m);

enum class ForwardStatus {
  kConverged,     // taut, stable equilibrium with the given lengths
  kNotConverged,  // Newton did not reach the tolerances
  kSlack,         // the solution needs a non-positive tension: a cable would go slack
  kUnstable,      // the solution is a potential-energy maximum
};
const char* ToString(ForwardStatus s);

struct ForwardResult {
  ForwardStatus status = ForwardStatus::kNotConverged;
  Equilibrium equilibrium;
  int iterations = 0;
  double length_residual_m = 0.0;
};

// Forward geometrico-static model: cable lengths (exit point -> anchor) -> the pose where
// the platform settles. Newton on the square system [l(q) - L; W(q) t + w_g(q)] = 0 in
// (x, z, theta, t), started from `guess` (e.g. the commanded pose) and, if that fails or no
// guess is given, from the intersections of the length circles at a few orientations.
ForwardResult SolveForwardGeometricoStatic(const Robot& robot, const Eigen::VectorXd& lengths_m,
                                           const Eigen::Vector3d* guess = nullptr);

}  // namespace cablecal
