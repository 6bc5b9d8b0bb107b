// Internal to design/: what a measurement pose must keep within bounds, on the nominal robot
// and, to first order, on every true robot the geometry uncertainty allows.
//
// A plan is run open loop: the controller commands the nominal robot's lengths, and the true
// robot (exit points and initial lengths off by ~sigma) settles where its own statics put it.
// With m cables, y = (x, z, theta, t1..tm) (3 + m) and g = (a1x a1z .. amx amz l10 .. lm0) (3m),
// the true pose and tensions satisfy
//   R(y, g) = [l_i(q; a_i) - l_i0 - dl_i ; W(q; a) t + w_g(q)] = 0   (dl_i fixed, m + 3 rows).
// m = 2 and m = 3: R is square in y and (away from folds) dR/dy is invertible, so
// dy/dg = -(dR/dy)^-1 dR/dg (implicit function theorem). With m = 3 the length rows alone fix
// q (dR/dy is block-triangular) and the equilibrium rows then fix the unique t.
// m >= 4: rigid cables make the tensions statically indeterminate and dR/dy singular (m length
// rows in 3 unknowns). The simulator's true robot has elastic cables (model/forward_statics.h:
// it settles where its energy is least, the stretch taking up what the lengths cannot all
// meet); the linearisation here keeps its stiff-cable limit for equal cables, the least-squares
// pose of the commanded lengths,
//   dq/dg = -(J'J)^-1 J' dr/dg,  J = dl/dq,  r = l(q; a) - l0 - dl,
// with the tensions chosen by the controller (an approximation of the elastic robot, whose
// tensions follow its stretch; the scenario check in design.cc settles the elastic model). Rule for the tensions (m >= 4): the NLP keeps a
// tension vector t within bounds at the nominal pose (its variables), and the tensions on a true
// robot are t corrected by the least change that restores its equilibrium there,
//   dt/dg = -W^+ (d(W t + w_g)/dq dq/dg + d(W t + w_g)/dg),  W^+ = W'(W W')^-1,
// so the rows below say, to first order, that every true robot within k sigma has a tension
// vector within bounds at the pose it settles in. The model's distribution (minimum-norm within
// bounds, DistributeTensions) exists exactly when some vector within bounds does, and that is
// what design.cc's scenario check verifies on the true robots. The plan lists the model's
// distribution at the nominal pose and, as its worst-case columns, the range of the model's
// distribution over the nominal and the scenario true robots (design.cc, VerifyRobustness).
//
// Every bounded quantity c (each tension, theta, z against the laser range, each anchor's
// clearance from its pulley, each platform point's coordinates against the frame) then has the
// sensitivity
//   dc/dg = dc/dy dy/dg + dc/dg|_y,
// and the design keeps c -+ k sigma |dc/dg|_2 within c's bounds: the worst case over the
// ellipsoid |dg / sigma|_2 <= k, linearised. Under g ~ N(nominal, sigma^2 I) that is each
// bound held with probability Phi(k) (k = 3: 99.87 %) to first order. A pose near a fold of
// the equilibrium (m = 2, where the robot would lose stability) or a singular configuration
// (m >= 3, J rank-deficient) has unbounded sensitivities, so the same rows keep poses away from
// both. The returned poses are then checked on scenario robots with the full nonlinear forward
// model (design.cc).
//
// The derivatives with respect to (y, g) come from one Jet layer through the model's
// templated cable geometry and wrench matrix, sized at compile time for each cable count
// (robust.cc dispatches once per call on m = 2..8), so m = 2 does exactly the arithmetic it
// always did.
#pragma once

#include <Eigen/Dense>
#include <limits>
#include <string>
#include <vector>

#include "model/cable.h"
#include "model/geometry.h"
#include "model/kind.h"
#include "model/robot.h"

namespace cablecal::internal {

// Sizes for m cables: y = (x, z, theta, t1..tm), g = (a1x a1z .. amx amz l10 .. lm0).
inline int PoseVariables(int num_cables) { return PlanarKind::kPoseDim + num_cables; }
inline int GeometryParameters(int num_cables) { return PlanarLayout(num_cables).size(); }

// One bounded quantity of a pose; lo or hi may be infinite.
struct PoseQuantity {
  std::string name;  // for messages: "t1", "theta", "clearance2", "anchor1 x", ...
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  double bound_margin = 0.0;  // tightening inside Ipopt (see ipopt_nlp.h)
  bool is_variable = false;   // the quantity is one of y's own variables (bounded there too)
};

// The platform points kept inside the frame: the reference point p, the anchors, and the
// centre of mass if it is not p.
std::vector<Eigen::Vector2d> FramePoints(const Robot& robot);

// The quantities, in the order RobustQuantities returns them: t_i (m), theta, z (laser
// range), the clearance of each anchor from its pulley (m), then x and z of each frame point.
std::vector<PoseQuantity> PoseQuantities(const Robot& robot);

// What RobustQuantities finds at one pose.
struct PoseRobustness {
  std::vector<double> value;   // c, per quantity (PoseQuantities' order)
  std::vector<double> spread;  // |dc/dg|_2, per quantity
  Eigen::MatrixXd dvalue_dy;   // dc/dy, one row per quantity, 3 + m columns (only with derivatives)
  // W t + w_g at y (the NLP's equality rows)
  Eigen::Matrix<double, PlanarKind::kWrenchDim, 1> equilibrium_N = Eigen::Matrix<double, PlanarKind::kWrenchDim, 1>::Zero();
  Eigen::MatrixXd dequilibrium_dy;  // its Jacobian, 3 x (3 + m) (only with derivatives)
};

// Values c and spreads |dc/dg|_2 of every quantity at y = (q, t) (3 + m entries, an equilibrium
// of the nominal robot), and the equilibrium residual there; with `with_derivatives`, also the
// exact derivatives of the values and of the residual with respect to y, which the same Jets
// carry. Returns false where the sensitivity is undefined (dR/dy singular for m <= 3, J'J or
// W W' singular for m >= 4, or not finite). The spreads' own derivatives (second derivatives
// of the model) are taken by central differences in the NLP: they enter the rows multiplied
// by k sigma, a few cm.
bool RobustQuantities(const Robot& robot, const std::vector<Eigen::Vector2d>& points,
                      const Eigen::VectorXd& y, PoseRobustness* out, bool with_derivatives = false);

}  // namespace cablecal::internal
