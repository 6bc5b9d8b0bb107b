// Internal to design/: what a measurement pose must keep within bounds, on the nominal robot
// and, to first order, on every true robot the geometry uncertainty allows.
//
// A plan is run open loop: the controller commands the nominal robot's lengths, and the true
// robot (exit points and initial lengths off by ~sigma) settles where its own statics put it.
// With y = (x, z, theta, t1, t2) and g = (a1x a1z a2x a2z l10 l20), the true pose solves
//   R(y, g) = [l_i(q; a_i) - l_i0 - dl_i ; W(q; a) t + w_g(q)] = 0   (dl_i fixed),
// so dy/dg = -(dR/dy)^-1 dR/dg (implicit function theorem). Every bounded quantity c (each
// tension, theta, z against the laser range, each anchor's clearance from its pulley, each
// platform point's coordinates against the frame) then has the sensitivity
//   dc/dg = dc/dy dy/dg + dc/dg|_y,
// and the design keeps c -+ k sigma |dc/dg|_2 within c's bounds: the worst case over the
// ellipsoid |dg / sigma|_2 <= k, linearised. Under g ~ N(nominal, sigma^2 I) that is each
// bound held with probability Phi(k) (k = 3: 99.87 %) to first order. A pose near a fold of
// the equilibrium (dR/dy singular, where the robot would lose stability) has unbounded
// sensitivities, so the same rows keep poses away from instability. The returned poses are
// then checked on scenario robots with the full nonlinear forward model (design.cc).
//
// The derivatives with respect to (y, g) come from one Jet layer through the model's
// templated cable geometry and wrench matrix.
#pragma once

#include <Eigen/Dense>
#include <limits>
#include <string>
#include <vector>

#include "model/cable.h"
#include "model/robot.h"

namespace cablecal::internal {

constexpr int kPoseVariables = 5;       // x, z, theta, t1, t2
constexpr int kGeometryParameters = 6;  // a1x a1z a2x a2z l10 l20

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
  Eigen::MatrixXd dvalue_dy;   // dc/dy, one row per quantity (only with derivatives)
  Eigen::Vector3d equilibrium_N = Eigen::Vector3d::Zero();  // W t + w_g at y (the NLP's equality rows)
  Eigen::Matrix<double, 3, kPoseVariables> dequilibrium_dy;  // its Jacobian (only with derivatives)
};

// Values c and spreads |dc/dg|_2 of every quantity at y (an equilibrium of the nominal robot),
// and the equilibrium residual there; with `with_derivatives`, also the exact derivatives of
// the values and of the residual with respect to y, which the same Jets carry. Returns false
// where the sensitivity is undefined (dR/dy singular or not finite). The spreads' own
// derivatives (second derivatives of the model) are taken by central differences in the NLP:
// they enter the rows multiplied by k sigma, a few cm.
bool RobustQuantities(const Robot& robot, const std::vector<Eigen::Vector2d>& points,
                      const Eigen::Matrix<double, kPoseVariables, 1>& y, PoseRobustness* out,
                      bool with_derivatives = false);

}  // namespace cablecal::internal
