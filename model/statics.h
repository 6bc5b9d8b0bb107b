// Statics of the platform: equilibrium at a given position, its stability, the tension
// distribution, the feasible-pose test, and the inverse and forward geometrico-static models.
//
// With m = 2 cables and 3 DoF the platform is under-constrained: for given (x, z) the
// force and moment balance W t + w_g = 0 fixes theta and the tensions; for given cable
// lengths the platform settles where its potential energy is least with both cables taut.
// With m >= 3 the lengths fix the whole pose (x, z, theta) and the tensions must balance
// gravity within [min, max]: unique for m = 3, a choice for m >= 4 (DistributeTensions).
#pragma once

#include <Eigen/Core>
#include <limits>
#include <string>

#include "model/robot.h"

namespace cablecal {

struct Equilibrium {
  Eigen::Vector3d q = Eigen::Vector3d::Zero();  // (x_m, z_m, theta_rad)
  Eigen::VectorXd tensions_N;
  double residual_N = 0.0;   // |W t + w_g| (force and moment rows together)
  // Curvature of the potential energy along the one motion the fixed cable lengths allow
  // (reduced Hessian of the Lagrangian, direction normalised in (m, m, rad)). > 0: stable.
  // m >= 3: no such motion (NaN); taut cables at a full-rank W hold the pose to first order
  // (a motion shortening no cable raises the potential by t' dl >= 0), so `stable` is true.
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
  // Spatial robots (model/spatial_statics.h); the planar code reports kCableGeometry and
  // kThetaLimit instead.
  kTiltLimit,      // the platform's tilt beyond limits.tilt_max_deg
  kSwivelAxis,     // an anchor on its swivel axis (model/swivel.h)
  kInsidePulley,   // an anchor inside its pulley, or closer to it than the margin
  kWrap,           // a wrap angle outside [0, 270] degrees
};
// The number of reasons (kWrap is the last): the size of a table indexed by reason.
constexpr int kNumFeasibility = static_cast<int>(Feasibility::kWrap) + 1;
const char* ToString(Feasibility f);  // "feasible", "outside_frame", ...

struct PoseEvaluation {
  Feasibility feasibility = Feasibility::kNoEquilibrium;
  bool has_equilibrium = false;  // equilibrium below is meaningful (also for theta/tension failures)
  Equilibrium equilibrium;
  bool feasible() const { return feasibility == Feasibility::kFeasible; }
};

// The feasible cable-tension workspace test (README, "Model and conventions") at (x, z),
// for m = 2 (theta follows from the equilibrium).
PoseEvaluation EvaluatePose(const Robot& robot, double x_m, double z_m);

// The same at a full pose q = (x, z, theta), for m >= 3: the frame, laser and cable-geometry
// tests, then a tension distribution (below) and the remaining limits.
PoseEvaluation EvaluatePose(const Robot& robot, const Eigen::Vector3d& q);

// m >= 3: the orientations feasible at a position (x, z), scanned every kThetaScanStep_rad over
// the inclinometer range (0.5 degree: the feasible band of a suspended robot is a few degrees
// wide or more, so it is not missed). The workspace grid reports it per point; the robot-file
// loader names it when a home orientation is infeasible.
constexpr double kThetaScanStep_rad = 0.5 * M_PI / 180.0;
struct ThetaScan {
  // The pose at the middle of the longest run of feasible samples, or, where none is
  // feasible, the evaluation at the orientation whose reason is the most common over the scan.
  PoseEvaluation evaluation;
  // The feasible samples' [min, max] (rad); NaN where none is feasible.
  double theta_min_rad = std::numeric_limits<double>::quiet_NaN();
  double theta_max_rad = std::numeric_limits<double>::quiet_NaN();
  int feasible_count = 0;
};
ThetaScan ScanTheta(const Robot& robot, double x_m, double z_m);

// A tension distribution of a robot with m >= 3 cables at pose q: tensions t with
// W t + w_g = 0. m = 3: the unique solution. m >= 4: the minimum-norm t within
// [tension.min, tension.max] (a least-distance problem, Lawson & Hanson's LDP through NNLS),
// the least internal force that holds the platform. feasibility is one of
//   kFeasible       t within bounds
//   kTensionHigh    no t within bounds, but one with every t_i >= min (reported)
//   kTensionLow     none with every t_i >= min, but one with every t_i > 0 (reported)
//   kNoEquilibrium  no t > 0 balances gravity (or W is singular): some cable would push
// tensions_N is empty for kNoEquilibrium.
struct TensionDistribution {
  Feasibility feasibility = Feasibility::kNoEquilibrium;
  Eigen::VectorXd tensions_N;
};
TensionDistribution DistributeTensions(const Robot& robot, const Eigen::Vector3d& q);

// The same for any kind of robot: a wrench matrix W (d x m, d the platform's wrench size, m >= d
// cables) and the gravity wrench w_g at one pose, the tension bounds, and the platform's weight
// (the scale of "taut" and of the least-distance problem). m = d: the unique solution.
TensionDistribution DistributeTensions(const Eigen::MatrixXd& W, const Eigen::VectorXd& gravity_wrench,
                                       double tension_min_N, double tension_max_N, double weight_N);

// Checks the conditions of EvaluatePose for an already known equilibrium (q, t), e.g. one
// returned by the design optimiser. Does not re-solve.
Feasibility CheckFeasibility(const Robot& robot, const Eigen::Vector3d& q,
                             const Eigen::VectorXd& tensions_N);

// The home pose: for m = 2 the equilibrium at home (x, z); for m >= 3 (x, z, home_theta).
// EvaluateHome says whether it is feasible; HomeEvaluation throws InputError naming `home` if not.
PoseEvaluation EvaluateHome(const Robot& robot);
PoseEvaluation HomeEvaluation(const Robot& robot);

// Initial cable lengths l_i0: the file's initial_length if given, else the length at the
// home pose. Throws InputError if the home pose is not feasible.
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
  kOtherAssembly,  // m >= 3: the lengths are met, but by another assembly of the robot (a cable
                   // off its pulley, the platform out of the frame, or far from the guess)
};
const char* ToString(ForwardStatus s);

struct ForwardResult {
  ForwardStatus status = ForwardStatus::kNotConverged;
  Equilibrium equilibrium;
  int iterations = 0;
  double length_residual_m = 0.0;
};

// Forward geometrico-static model of inextensible cables: cable lengths (exit point -> anchor)
// -> the pose where the platform settles. Requires m = 2 or 3 (more rigid cables over-determine
// the pose: a true robot with them is elastic, model/forward_statics.h).
// m = 2: Newton on the square system [l(q) - L; W(q) t + w_g(q)] = 0 in (x, z, theta, t),
// started from `guess` (e.g. the commanded pose) and, if that fails or no guess is given,
// from the intersections of the length circles at a few orientations.
// m = 3 (forward kinematics): Gauss-Newton on l(q) = L from `guess` (else the home pose, then
// circle intersections); then the tension distribution there (kSlack when no t > 0 holds it). A
// solution more than kOtherAssemblyDistance from the guess, with a cable off its pulley or the
// platform outside the frame is kOtherAssembly.
ForwardResult SolveForwardGeometricoStatic(const Robot& robot, const Eigen::VectorXd& lengths_m,
                                           const Eigen::Vector3d* guess = nullptr);

// A geometric starting guess, not where a true robot settles: m >= 3, the pose whose lengths are
// nearest `lengths_m` in least squares, the cables taken as rigid (the m = 3 forward kinematics
// above, which for m >= 4 inconsistent lengths meets only in least squares: length_residual_m
// says by how much), with the tension distribution there; m = 2, SolveForwardGeometricoStatic.
// The identification's starting poses and validate's pose for a robot of more than 3 cables
// without stiffness (identify/identify_cables.h, identify/validate.cc) use it.
ForwardResult LeastSquaresPoseGuess(const Robot& robot, const Eigen::VectorXd& lengths_m,
                                    const Eigen::Vector3d* guess = nullptr);
// "Far from the guess" for kOtherAssembly: a true robot settles millimetres from its
// commanded pose, another assembly tens of centimetres or degrees away.
constexpr double kOtherAssemblyDistance_m = 0.25;
constexpr double kOtherAssemblyAngle_rad = 0.5;

}  // namespace cablecal
