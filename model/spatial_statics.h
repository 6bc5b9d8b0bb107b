// Statics of the spatial platform (README, "Spatial robots", "Statics and feasibility"): the
// equilibrium at a pose, its stability, and the feasible-pose test.
//
// With m >= 6 cables the lengths fix the whole pose and the tensions must balance gravity
// within [min, max]: unique for m = 6, the minimum-norm distribution for m >= 7
// (DistributeTensions, model/statics.h). With m < 6 the platform is underactuated: the
// lengths control only some of the pose's coordinates (ControlledCoordinates), and the others
// follow from the force and moment balance W t + w_g = 0, solved for the non-controlled
// orientation coordinates and the tensions (SolveSpatialEquilibrium); the equilibrium must be
// stable (model/stability.h).
// Depends on Eigen, model/kind.h, model/spatial_robot.h, model/statics.h (Feasibility,
// EquilibriumStatus) and model/swivel.h.
#pragma once

#include <Eigen/Core>
#include <limits>
#include <vector>

#include "model/kind.h"
#include "model/spatial_robot.h"
#include "model/statics.h"
#include "model/swivel.h"

namespace cablecal {

struct SpatialEquilibrium {
  SpatialPose<double> q = SpatialPose<double>::Zero();
  Eigen::VectorXd tensions_N;
  double residual_N = 0.0;  // |W t + w_g| (force and moment rows together)
  // StaticStability's min_eigenvalue with every cable inextensible: the least curvature of the
  // potential along the motions the fixed lengths allow (NaN: no free motion, m >= 6).
  double reduced_stiffness = std::numeric_limits<double>::quiet_NaN();
  bool stable = false;
};

struct SpatialPoseEvaluation {
  Feasibility feasibility = Feasibility::kNoEquilibrium;
  int cable = -1;  // the cable (0-based) a cable-geometry reason is about, else -1
  bool has_equilibrium = false;  // equilibrium below is meaningful (also for tilt, frame and tension failures)
  SpatialEquilibrium equilibrium;
  bool feasible() const { return feasibility == Feasibility::kFeasible; }
};

// The pose coordinates the cable lengths control, in SpatialKind order (x y z roll pitch yaw):
// m >= 6: all six; m = 4, 5: x, y, z, yaw; m = 3: x, y, z. The others follow from the
// equilibrium.
std::vector<int> ControlledCoordinates(const SpatialRobot& robot);

// The underactuated equilibrium (m < 6): q's controlled coordinates are kept, its other
// coordinates are the first guess. Unknowns: the non-controlled orientation coordinates and the
// m tensions; equations: W t + w_g = 0 (6 rows, divided by the weight). m = 3, 4: a square
// system; m = 5: one unknown more, a curve of equilibria, of which the minimum-norm Newton steps
// (in rad and tension / weight) find the one nearest the guess; where every start's root has a
// cable pushing, or the root kept holds a cable below tension.min, a walk along the curve looks
// for its part where every cable pulls with at least tension.min (the file's WalkToTaut). Newton
// runs from the guess,
// then from a small grid of orientations (kSpatialEquilibriumStartsDeg about the guess); of the
// roots with taut cables (t > 0), valid cable geometry and a stable equilibrium, the one whose
// orientation is nearest the guess's (the angle of R_guess^T R) is kept.
// Status: kFound; kUnstable (taut roots, none stable); kCableGeometry (the cable geometry is
// invalid at the guess and at every start: geometry and cable say which); kNoEquilibrium.
struct SpatialEquilibriumResult {
  EquilibriumStatus status = EquilibriumStatus::kNoEquilibrium;
  SpatialEquilibrium equilibrium;  // meaningful when status == kFound
  SwivelGeometry geometry = SwivelGeometry::kValid;  // kCableGeometry: why
  int cable = -1;                                    // kCableGeometry: which cable
};
SpatialEquilibriumResult SolveSpatialEquilibrium(const SpatialRobot& robot, const SpatialPose<double>& guess);
// The offsets of the starts (degrees) added to each non-controlled angle of the guess.
constexpr double kSpatialEquilibriumStartsDeg[] = {0.0, -25.0, 25.0};

// The feasible-pose test.
// m >= 6: q is the pose. Tests, in this order: the reference point inside the frame box less the
// margin (outside_frame); every cable's geometry (swivel_axis, inside_pulley, wrap: model/swivel.h)
// and each anchor's clearance from its pulley (closer than the margin: inside_pulley); the tilt
// (tilt_limit); every anchor and the centre of mass inside the frame box less the margin
// (outside_frame); a tension distribution (no_equilibrium: no t > 0 holds the platform); the
// tension bounds (tension_low, tension_high).
// m < 6: q's controlled coordinates are kept and its other coordinates are the first guess: the
// reference point's frame test, SolveSpatialEquilibrium (no_equilibrium, unstable, or the cable
// geometry reason), then the same tests at the equilibrium.
// `depth`: kFull also gives the equilibrium of a pose failing the tilt, frame or tension tests
// (the workspace map shows it); kVerdict stops at the first failed test (the sampler, whose
// candidates fail half the time on the pose alone, keeps only the feasible ones), the same
// verdict and, for a feasible pose, the same evaluation to the last bit.
enum class SpatialEvaluationDepth { kFull, kVerdict };
SpatialPoseEvaluation EvaluateSpatialPose(const SpatialRobot& robot, const SpatialPose<double>& q,
                                          SpatialEvaluationDepth depth = SpatialEvaluationDepth::kFull);

// Checks the conditions of EvaluateSpatialPose at a known equilibrium (q, t); does not
// re-solve. *cable (if given) is set to the cable a cable-geometry reason is about, else -1.
Feasibility CheckSpatialFeasibility(const SpatialRobot& robot, const SpatialPose<double>& q,
                                    const Eigen::VectorXd& tensions_N, int* cable = nullptr);

// The home pose: home + home_rpy (for m < 6 the non-controlled angles are the solver's guess).
// SpatialHomeEvaluation throws InputError naming `home` if it is not feasible.
SpatialPoseEvaluation EvaluateSpatialHome(const SpatialRobot& robot);
SpatialPoseEvaluation SpatialHomeEvaluation(const SpatialRobot& robot);
// The cable lengths (exit point -> anchor) at the home equilibrium. Throws as above.
Eigen::VectorXd SpatialHomeLengths(const SpatialRobot& robot);

}  // namespace cablecal
