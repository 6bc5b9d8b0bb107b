#include "model/spatial_statics.h"

#include <ceres/jet.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "common/error.h"
#include "model/stability.h"

namespace cablecal {
namespace {

// Newton on W t + w_g = 0 (divided by the weight): converged at this residual (rounding of
// sums of a few newtons per newton of weight), accepted down to kAcceptedResidual when no step
// decreases it further.
constexpr double kConvergedResidual = 1e-13;
constexpr double kAcceptedResidual = 1e-10;
constexpr int kMaxNewtonIterations = 60;
// A longer step in an angle is cut back to this (rad): the balance is far from linear over
// more, and a full step could jump to another assembly.
constexpr double kMaxAngleStep_rad = 0.3;
// "Taut": strictly above 0, beyond rounding (as DistributeTensions), in units of the weight.
constexpr double kTautFraction = 1e-9;

double Weight(const SpatialRobot& robot) { return robot.platform_mass_kg * robot.gravity_mps2; }

Feasibility ReasonOf(SwivelGeometry g) {
  switch (g) {
    case SwivelGeometry::kValid: return Feasibility::kFeasible;
    case SwivelGeometry::kSwivelAxis: return Feasibility::kSwivelAxis;
    case SwivelGeometry::kInsidePulley: return Feasibility::kInsidePulley;
    case SwivelGeometry::kWrap: return Feasibility::kWrap;
  }
  return Feasibility::kWrap;
}

bool InBoxLessMargin(const SpatialRobot& robot, const Eigen::Vector3d& p_F_m) {
  const Eigen::Vector3d lo = robot.p_F_frame_min_m.array() + robot.margin_m;
  const Eigen::Vector3d hi = robot.p_F_frame_max_m.array() - robot.margin_m;
  return (p_F_m.array() >= lo.array()).all() && (p_F_m.array() <= hi.array()).all();
}

// Every test of CheckSpatialFeasibility but the tension bounds.
Feasibility PoseFeasibility(const SpatialRobot& robot, const SpatialPose<double>& q, int* cable) {
  *cable = -1;
  if (!InBoxLessMargin(robot, q.head<3>())) return Feasibility::kOutsideFrame;
  const Eigen::Matrix3d R = Rotation<double>(q);
  for (int i = 0; i < robot.num_cables(); ++i) {
    const SpatialCable& c = robot.cables[i];
    const SwivelCableState<double> s = SwivelCableAtPose<double>(c, q, R);
    if (!s.valid()) {
      *cable = i;
      return ReasonOf(s.geometry);
    }
    // The pulleys are part of the frame: an anchor keeps the frame margin from its pulley too
    // (as the planar test), else the platform could climb into a pulley where the equilibrium
    // degenerates. |B - C| is the anchor's distance from the pulley's centre in its plane.
    if ((AnchorInF<double>(q, R, c.p_P_anchor_m) - s.p_F_centre_m).norm() - c.pulley_radius_m < robot.margin_m) {
      *cable = i;
      return Feasibility::kInsidePulley;
    }
  }
  if (TiltAngle(q) > robot.tilt_max_rad) return Feasibility::kTiltLimit;
  if (!InBoxLessMargin(robot, AnchorInF<double>(q, R, robot.p_P_com_m))) return Feasibility::kOutsideFrame;
  for (const SpatialCable& c : robot.cables) {
    if (!InBoxLessMargin(robot, AnchorInF<double>(q, R, c.p_P_anchor_m))) return Feasibility::kOutsideFrame;
  }
  return Feasibility::kFeasible;
}

Feasibility TensionFeasibility(const SpatialRobot& robot, const Eigen::VectorXd& tensions_N) {
  if (tensions_N.minCoeff() < robot.tension_min_N) return Feasibility::kTensionLow;
  if (tensions_N.maxCoeff() > robot.tension_max_N) return Feasibility::kTensionHigh;
  return Feasibility::kFeasible;
}

SpatialEquilibrium MakeEquilibrium(const SpatialRobot& robot, const SpatialPose<double>& q,
                                   const Eigen::VectorXd& tensions_N) {
  SpatialEquilibrium eq;
  eq.q = q;
  eq.tensions_N = tensions_N;
  eq.residual_N = EquilibriumResidual<double>(robot, q, tensions_N).norm();
  const StabilityResult s = StaticStability(robot, q, tensions_N, InextensibleCables(robot.num_cables()));
  eq.reduced_stiffness = s.min_eigenvalue;
  eq.stable = s.stable;
  return eq;
}

// The non-controlled orientation coordinates (indices into the pose) of an underactuated robot.
std::vector<int> FreeAngles(const SpatialRobot& robot) {
  const std::vector<int> controlled = ControlledCoordinates(robot);
  std::vector<int> free;
  for (int k = 3; k < 6; ++k) {
    if (std::find(controlled.begin(), controlled.end(), k) == controlled.end()) free.push_back(k);
  }
  return free;
}

struct NewtonRoot {
  bool converged = false;
  SpatialPose<double> q = SpatialPose<double>::Zero();
  Eigen::VectorXd tensions_N;
};

// `base` with its free angles (indices into the pose) set to the first entries of y.
SpatialPose<double> WithFreeAngles(const SpatialPose<double>& base, const std::vector<int>& free,
                                   const Eigen::VectorXd& y) {
  SpatialPose<double> q = base;
  for (std::size_t a = 0; a < free.size(); ++a) q(free[a]) = y(static_cast<Eigen::Index>(a));
  return q;
}

// (W t + w_g) / weight at y = (the free angles, t / weight), the pose's other coordinates
// `base`'s, and, if J is given, its Jacobian: the angles' columns by Jets, the tensions' columns
// W. Without J, in doubles: the same arithmetic as the Jets' values, a quarter of the cost (the
// line search's rejected trials need no Jacobian).
Eigen::Matrix<double, 6, 1> BalanceResidual(const SpatialRobot& robot, const SpatialPose<double>& base,
                                            const std::vector<int>& free, const Eigen::VectorXd& y,
                                            Eigen::Matrix<double, 6, Eigen::Dynamic>* J) {
  using Jet3 = ceres::Jet<double, 3>;
  const int m = robot.num_cables(), na = static_cast<int>(free.size());
  const double weight_N = Weight(robot);
  const SpatialPose<double> q = WithFreeAngles(base, free, y);
  if (!J) {
    const Eigen::Matrix<double, 6, Eigen::Dynamic> W = WrenchMatrix<double>(robot, q);
    const Eigen::VectorXd s = y.tail(m);
    const Eigen::Matrix<double, 6, 1> r = W * s + GravityWrench<double>(robot, q) / weight_N;
    return r;
  }
  SpatialPose<Jet3> qj = q.cast<Jet3>();
  for (int k = 3; k < 6; ++k) qj(k) = Jet3(q(k), k - 3);
  const Eigen::Matrix<Jet3, 6, Eigen::Dynamic> W = WrenchMatrix<Jet3>(robot, qj);
  const Eigen::Matrix<Jet3, Eigen::Dynamic, 1> s = y.tail(m).cast<Jet3>();
  const Eigen::Matrix<Jet3, 6, 1> r = W * s + GravityWrench<Jet3>(robot, qj) / weight_N;
  Eigen::Matrix<double, 6, 1> value;
  for (int row = 0; row < 6; ++row) {
    value(row) = r(row).a;
    for (int a = 0; a < na; ++a) (*J)(row, a) = r(row).v(free[a] - 3);
    for (int i = 0; i < m; ++i) (*J)(row, na + i) = W(row, i).a;
  }
  return value;
}

// Newton from `start` on (W t + w_g) / weight = 0 in y = (the free angles, t / weight), the
// minimum-norm step each time, cut to kMaxAngleStep_rad and backtracked on |r|.
NewtonRoot EquilibriumNewton(const SpatialRobot& robot, const SpatialPose<double>& start, const std::vector<int>& free) {
  const int m = robot.num_cables(), na = static_cast<int>(free.size()), n = na + m;
  const double weight_N = Weight(robot);
  const auto residual = [&](const Eigen::VectorXd& y, Eigen::Matrix<double, 6, Eigen::Dynamic>* J) {
    return BalanceResidual(robot, start, free, y, J);
  };

  Eigen::VectorXd y(n);
  for (int a = 0; a < na; ++a) y(a) = start(free[a]);
  y.tail(m) = WrenchMatrix<double>(robot, start).colPivHouseholderQr().solve(-GravityWrench<double>(robot, start) / weight_N);
  NewtonRoot root;
  Eigen::Matrix<double, 6, Eigen::Dynamic> J(6, n), J_new(6, n);
  Eigen::Matrix<double, 6, 1> r = residual(y, &J);
  for (int it = 0; it < kMaxNewtonIterations && y.allFinite() && r.allFinite(); ++it) {
    if (r.norm() < kConvergedResidual) {
      root.converged = true;
      break;
    }
    Eigen::VectorXd step = -J.completeOrthogonalDecomposition().solve(r);
    if (!step.allFinite()) break;
    const double angle_step = na > 0 ? step.head(na).cwiseAbs().maxCoeff() : 0.0;
    if (angle_step > kMaxAngleStep_rad) step *= kMaxAngleStep_rad / angle_step;
    double lambda = 1.0;
    bool descent = false;
    Eigen::VectorXd y_new;
    Eigen::Matrix<double, 6, 1> r_new;
    for (int ls = 0; ls < 30; ++ls) {
      y_new = y + lambda * step;
      r_new = residual(y_new, nullptr);
      if (r_new.allFinite() && r_new.squaredNorm() < r.squaredNorm()) {
        descent = true;
        r_new = residual(y_new, &J_new);
        break;
      }
      lambda *= 0.5;
    }
    if (!descent) {
      root.converged = r.norm() < kAcceptedResidual;
      break;
    }
    y = y_new;
    r = r_new;
    J = J_new;
  }
  if (!root.converged && r.allFinite() && r.norm() < kConvergedResidual) root.converged = true;
  root.q = WithFreeAngles(start, free, y);
  // A start a turn away can converge there: the same orientation, reported in (-pi, pi].
  for (int k = 3; k < 6; ++k) root.q(k) = std::remainder(root.q(k), 2.0 * M_PI);
  root.tensions_N = y.tail(m) * weight_N;
  root.converged = root.converged && root.q.allFinite() && root.tensions_N.allFinite();
  return root;
}

// Five cables: the equilibria at the controlled coordinates form a curve in (free angles,
// tensions), and Newton's minimum-norm steps end at its point nearest their start, where a cable
// may push while elsewhere on the curve every cable pulls (a new user's 5-cable robot: no
// equilibrium found at home, one at roll 6, pitch 4.9 degrees with every tension above 13 N).
// From such a root, walk along the curve (its tangent: the Jacobian's null vector) the way the
// smallest tension grows, each step corrected back onto the curve by minimum-norm Newton, until
// every cable pulls with at least tension.min (the root returned), or the smallest tension stops
// growing (the root returned if every cable pulls there: the feasibility test then names the
// low tension), the tilt leaves its limit (by more than a step), or kWalkSteps steps (not
// converged). SolveSpatialEquilibrium walks only from the root it kept when that one holds a
// cable below tension.min, or, where no start found a root with every cable pulling, from at
// most kWalkRoots distinct roots: elsewhere its results are as before.
constexpr int kWalkSteps = 30;
constexpr double kWalkAngleStep_rad = 0.05;
constexpr int kWalkRoots = 3;

NewtonRoot WalkToTaut(const SpatialRobot& robot, const NewtonRoot& root, const std::vector<int>& free) {
  const int m = robot.num_cables(), na = static_cast<int>(free.size()), n = na + m;
  const double weight_N = Weight(robot);
  NewtonRoot out;
  if (n != 7) return out;  // a curve only with one unknown more than the 6 rows
  Eigen::VectorXd y(n);
  for (int a = 0; a < na; ++a) y(a) = root.q(free[a]);
  y.tail(m) = root.tensions_N / weight_N;
  Eigen::Matrix<double, 6, Eigen::Dynamic> J(6, n);
  Eigen::VectorXd previous = Eigen::VectorXd::Zero(n);
  const auto tilt_of = [&](const Eigen::VectorXd& v) { return TiltAngle(WithFreeAngles(root.q, free, v)); };
  const auto done = [&](const Eigen::VectorXd& at) {
    out.converged = true;
    out.q = root.q;
    for (int a = 0; a < na; ++a) out.q(free[a]) = std::remainder(at(a), 2.0 * M_PI);
    out.tensions_N = at.tail(m) * weight_N;
    return out;
  };
  for (int step = 0; step < kWalkSteps; ++step) {
    BalanceResidual(robot, root.q, free, y, &J);
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(Eigen::MatrixXd(J), Eigen::ComputeFullV);
    Eigen::VectorXd tangent = svd.matrixV().col(n - 1);
    Eigen::Index weakest = 0;
    y.tail(m).minCoeff(&weakest);
    const double sign = previous.isZero() ? (tangent(na + weakest) >= 0.0 ? 1.0 : -1.0)
                                          : (tangent.dot(previous) >= 0.0 ? 1.0 : -1.0);
    tangent *= sign;
    if (!(tangent(na + weakest) > 0.0)) {  // the smallest tension no longer grows this way
      return y.tail(m).minCoeff() > kTautFraction ? done(y) : out;
    }
    const double angle_rate = tangent.head(na).cwiseAbs().maxCoeff();
    const double h = angle_rate > 0.0 ? kWalkAngleStep_rad / angle_rate : kWalkAngleStep_rad;
    Eigen::VectorXd next = y + h * tangent;
    // Back onto the curve: minimum-norm Newton (a few steps: the step is short).
    bool on_curve = false;
    for (int it = 0; it < 10 && next.allFinite(); ++it) {
      const Eigen::Matrix<double, 6, 1> r = BalanceResidual(robot, root.q, free, next, &J);
      if (r.norm() < kConvergedResidual) {
        on_curve = true;
        break;
      }
      next -= J.completeOrthogonalDecomposition().solve(r);
    }
    if (!on_curve || !(tilt_of(next) <= robot.tilt_max_rad + kWalkAngleStep_rad)) return out;
    previous = tangent;
    y = next;
    if (y.tail(m).minCoeff() * weight_N >= std::max(robot.tension_min_N, kTautFraction * weight_N)) return done(y);
  }
  return y.tail(m).minCoeff() > kTautFraction ? done(y) : out;
}

// The tensions at a root: Newton's, unless W has a null space there (a degenerate robot, e.g.
// every cable in one vertical plane: PlanarAsSpatial of a fully constrained planar robot), where
// the balance leaves a family of tensions and Newton's minimum-norm member may push; then the
// minimum-norm member within the bounds (else >= min, else > 0), as DistributeTensions chooses
// for m >= 7, on the rows of W's range.
Eigen::VectorXd ChooseTensions(const SpatialRobot& robot, const SpatialPose<double>& q, const Eigen::VectorXd& newton_N) {
  const Eigen::Matrix<double, 6, Eigen::Dynamic> W = WrenchMatrix<double>(robot, q);
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(W, Eigen::ComputeThinU);
  const Eigen::VectorXd& sv = svd.singularValues();
  int rank = 0;
  while (rank < sv.size() && sv(rank) > 1e-9 * std::max(1.0, sv(0))) ++rank;
  if (rank == 0 || rank >= robot.num_cables()) return newton_N;
  const Eigen::MatrixXd U = svd.matrixU().leftCols(rank);
  const TensionDistribution t = DistributeTensions(U.transpose() * W, U.transpose() * GravityWrench<double>(robot, q),
                                                   robot.tension_min_N, robot.tension_max_N, Weight(robot));
  return t.feasibility == Feasibility::kNoEquilibrium ? newton_N : t.tensions_N;
}

// The angle of the rotation between two orientations (rad, in [0, pi]).
double OrientationDistance(const SpatialPose<double>& a, const SpatialPose<double>& b) {
  const double c = 0.5 * ((Rotation<double>(a).transpose() * Rotation<double>(b)).trace() - 1.0);
  return std::acos(std::clamp(c, -1.0, 1.0));
}

}  // namespace

std::vector<int> ControlledCoordinates(const SpatialRobot& robot) {
  const int m = robot.num_cables();
  if (m >= 6) return {0, 1, 2, 3, 4, 5};
  if (m >= 4) return {0, 1, 2, 5};
  return {0, 1, 2};
}

SpatialEquilibriumResult SolveSpatialEquilibrium(const SpatialRobot& robot, const SpatialPose<double>& guess) {
  CABLECAL_CHECK(robot.num_cables() < 6, "the underactuated equilibrium is solved for fewer than 6 cables");
  const std::vector<int> free = FreeAngles(robot);
  const int na = static_cast<int>(free.size());
  const double weight_N = Weight(robot);
  constexpr int kOffsets = static_cast<int>(std::size(kSpatialEquilibriumStartsDeg));
  int combinations = 1;
  for (int a = 0; a < na; ++a) combinations *= kOffsets;

  SpatialEquilibriumResult result;
  const CableGeometryCheck at_guess = CableGeometryAt(robot, guess);
  bool any_valid_start = false, any_taut = false;
  CableGeometryCheck invalid_root;  // the first converged root with invalid cable geometry
  double best_distance = std::numeric_limits<double>::infinity();
  std::vector<NewtonRoot> pushing;  // converged roots, valid geometry, a cable pushing
  for (int c = 0; c < combinations; ++c) {
    SpatialPose<double> start = guess;
    for (int a = 0, rest = c; a < na; ++a, rest /= kOffsets) {
      start(free[a]) += kSpatialEquilibriumStartsDeg[rest % kOffsets] * kDegToRad;
    }
    if (!CableGeometryAt(robot, start).valid()) continue;
    any_valid_start = true;
    const NewtonRoot root = EquilibriumNewton(robot, start, free);
    if (!root.converged) continue;
    const CableGeometryCheck geometry = CableGeometryAt(robot, root.q);
    if (!geometry.valid()) {
      if (invalid_root.valid()) invalid_root = geometry;
      continue;
    }
    const Eigen::VectorXd tensions_N = ChooseTensions(robot, root.q, root.tensions_N);
    if (!(tensions_N.minCoeff() > kTautFraction * weight_N)) {
      pushing.push_back(root);
      continue;
    }
    any_taut = true;
    // Only a root nearer than the best so far can be kept: the stability test (the costliest
    // step) is for those alone.
    const double distance = OrientationDistance(guess, root.q);
    if (!(distance < best_distance)) continue;
    const SpatialEquilibrium eq = MakeEquilibrium(robot, root.q, tensions_N);
    if (!eq.stable) continue;
    best_distance = distance;
    result.equilibrium = eq;
    result.status = EquilibriumStatus::kFound;
  }
  // Five cables, a root found but a cable below tension.min there: the curve may hold the
  // platform within the bounds further on (a new user's home read tension_low, 1.8 N of 3, at
  // roll -0.5, pitch -4.5 degrees, while at roll -7.8, pitch -3.8 every cable pulls with 8 N or
  // more): walk from it, and keep where it ends if every cable is then within the bound and the
  // equilibrium stable.
  if (result.status == EquilibriumStatus::kFound && na + robot.num_cables() == 7 &&
      result.equilibrium.tensions_N.minCoeff() < robot.tension_min_N) {
    NewtonRoot found;
    found.converged = true;
    found.q = result.equilibrium.q;
    found.tensions_N = result.equilibrium.tensions_N;
    const NewtonRoot walked = WalkToTaut(robot, found, free);
    if (walked.converged && walked.tensions_N.minCoeff() >= robot.tension_min_N &&
        CableGeometryAt(robot, walked.q).valid()) {
      const Eigen::VectorXd tensions_N = ChooseTensions(robot, walked.q, walked.tensions_N);
      if (tensions_N.minCoeff() >= robot.tension_min_N) {
        const SpatialEquilibrium eq = MakeEquilibrium(robot, walked.q, tensions_N);
        if (eq.stable) result.equilibrium = eq;
      }
    }
  }
  if (result.status == EquilibriumStatus::kFound) return result;
  // Five cables and no root with every cable pulling: walk along the curve from those roots
  // (WalkToTaut), the distinct ones in start order; the first stable one found is kept.
  if (!any_taut && na + robot.num_cables() == 7) {
    std::vector<SpatialPose<double>> walked_from;
    for (const NewtonRoot& root : pushing) {
      if (static_cast<int>(walked_from.size()) >= kWalkRoots) break;
      bool seen = false;
      for (const SpatialPose<double>& q : walked_from) seen = seen || OrientationDistance(q, root.q) < 1e-3;
      if (seen) continue;
      walked_from.push_back(root.q);
      const NewtonRoot walked = WalkToTaut(robot, root, free);
      if (!walked.converged || !CableGeometryAt(robot, walked.q).valid()) continue;
      const Eigen::VectorXd tensions_N = ChooseTensions(robot, walked.q, walked.tensions_N);
      if (!(tensions_N.minCoeff() > kTautFraction * weight_N)) continue;
      any_taut = true;
      const SpatialEquilibrium eq = MakeEquilibrium(robot, walked.q, tensions_N);
      if (!eq.stable) continue;
      result.equilibrium = eq;
      result.status = EquilibriumStatus::kFound;
      return result;
    }
  }
  if (any_taut) {
    result.status = EquilibriumStatus::kUnstable;
  } else if (!any_valid_start || !invalid_root.valid()) {
    const CableGeometryCheck why = !any_valid_start ? at_guess : invalid_root;
    result.status = EquilibriumStatus::kCableGeometry;
    result.geometry = why.valid() ? SwivelGeometry::kInsidePulley : why.geometry;
    result.cable = why.cable;
  } else {
    result.status = EquilibriumStatus::kNoEquilibrium;
  }
  return result;
}

Feasibility CheckSpatialFeasibility(const SpatialRobot& robot, const SpatialPose<double>& q,
                                    const Eigen::VectorXd& tensions_N, int* cable) {
  CABLECAL_CHECK(tensions_N.size() == robot.num_cables(), "one tension per cable");
  int which = -1;
  Feasibility f = PoseFeasibility(robot, q, &which);
  if (f == Feasibility::kFeasible) f = TensionFeasibility(robot, tensions_N);
  if (cable) *cable = which;
  return f;
}

SpatialPoseEvaluation EvaluateSpatialPose(const SpatialRobot& robot, const SpatialPose<double>& q,
                                          SpatialEvaluationDepth depth) {
  SpatialPoseEvaluation e;
  e.equilibrium.q = q;
  const bool verdict = depth == SpatialEvaluationDepth::kVerdict;
  if (robot.num_cables() >= 6) {
    e.feasibility = PoseFeasibility(robot, q, &e.cable);
    if (e.feasibility != Feasibility::kFeasible && (verdict || (e.feasibility != Feasibility::kTiltLimit &&
                                                                e.feasibility != Feasibility::kOutsideFrame))) {
      return e;  // invalid cable geometry: no wrench matrix to distribute over
    }
    const Feasibility pose_feasibility = e.feasibility;
    const TensionDistribution t = DistributeTensions(WrenchMatrix<double>(robot, q), GravityWrench<double>(robot, q),
                                                     robot.tension_min_N, robot.tension_max_N, Weight(robot));
    if (t.feasibility == Feasibility::kNoEquilibrium) {
      // The pose's own failure first, as the order of the tests says.
      e.feasibility = pose_feasibility == Feasibility::kFeasible ? Feasibility::kNoEquilibrium : pose_feasibility;
      return e;
    }
    e.feasibility = pose_feasibility == Feasibility::kFeasible ? TensionFeasibility(robot, t.tensions_N) : pose_feasibility;
    // kVerdict: a pose the tension bounds refuse needs no equilibrium (nor its stability test).
    if (verdict && e.feasibility != Feasibility::kFeasible) return e;
    e.has_equilibrium = true;
    e.equilibrium = MakeEquilibrium(robot, q, t.tensions_N);
    return e;
  }
  if (!InBoxLessMargin(robot, q.head<3>())) {
    e.feasibility = Feasibility::kOutsideFrame;
    return e;
  }
  const SpatialEquilibriumResult eq = SolveSpatialEquilibrium(robot, q);
  switch (eq.status) {
    case EquilibriumStatus::kFound: break;
    case EquilibriumStatus::kNoEquilibrium: e.feasibility = Feasibility::kNoEquilibrium; return e;
    case EquilibriumStatus::kUnstable: e.feasibility = Feasibility::kUnstable; return e;
    case EquilibriumStatus::kCableGeometry:
      e.feasibility = ReasonOf(eq.geometry);
      e.cable = eq.cable;
      return e;
  }
  e.has_equilibrium = true;
  e.equilibrium = eq.equilibrium;
  e.feasibility = CheckSpatialFeasibility(robot, e.equilibrium.q, e.equilibrium.tensions_N, &e.cable);
  return e;
}

SpatialPoseEvaluation EvaluateSpatialHome(const SpatialRobot& robot) {
  return EvaluateSpatialPose(robot, robot.home_pose());
}

SpatialPoseEvaluation SpatialHomeEvaluation(const SpatialRobot& robot) {
  const SpatialPoseEvaluation home = EvaluateSpatialHome(robot);
  if (!home.feasible()) {
    std::string why = ToString(home.feasibility);
    if (home.cable >= 0) why += ", cables[" + std::to_string(home.cable) + "]";
    throw InputError(robot.source, "home", "the home pose is not in the feasible workspace (" + why + ")");
  }
  return home;
}

Eigen::VectorXd SpatialHomeLengths(const SpatialRobot& robot) {
  return CableLengths<double>(robot, SpatialHomeEvaluation(robot).equilibrium.q);
}

}  // namespace cablecal
