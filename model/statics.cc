#include "model/statics.h"

#include <ceres/jet.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "common/error.h"
#include "model/cable.h"
#include "model/stability.h"

namespace cablecal {
namespace {

// The theta search covers the bar's orientations short of vertical, on a ~5-degree grid
// (36 intervals); two roots closer than that are a fold at the workspace boundary and are
// left out. Each bracket is then refined by the Illinois method.
constexpr double kThetaSearchMax_rad = 89.0 * kDegToRad;
constexpr int kThetaSearchSteps = 36;
// The scan's angles are the same at every (x, z): their rotations once, when the program
// starts (not a function-local static: its first-use lock could be held across a fork of the
// design's child processes).
const std::array<Eigen::Matrix2d, kThetaSearchSteps + 1> kScanRotations = [] {
  const double step = 2.0 * kThetaSearchMax_rad / kThetaSearchSteps;
  std::array<Eigen::Matrix2d, kThetaSearchSteps + 1> r;
  r[0] = Rotation(-kThetaSearchMax_rad);
  for (int k = 1; k <= kThetaSearchSteps; ++k) r[k] = Rotation(-kThetaSearchMax_rad + k * step);
  return r;
}();
// A force matrix this close to singular means parallel cables: no equilibrium there.
constexpr double kParallelCablesDet = 1e-12;
// Root refinement stops at this bracket width (rad): double rounding near theta = O(1).
constexpr double kThetaTol_rad = 1e-15;

// Moment balance with the forces solved exactly for this theta (Cramer's rule). Returns
// det(F) * M(theta), which is continuous where det(F) changes sign, unlike M itself.
struct MomentBalance {
  bool valid = false;
  double scaled_moment = 0.0;  // det(F) * M
  double det = 0.0;
  Eigen::Vector2d tensions_N = Eigen::Vector2d::Zero();
};

MomentBalance EvaluateMomentBalance(const Robot& robot, double x_m, double z_m, double theta_rad,
                                    const Eigen::Matrix2d* rotation = nullptr) {
  MomentBalance b;
  // One rotation and one state per cable, shared by the validity test, W and the gravity
  // wrench (the same arithmetic as CableAtPose, WrenchMatrix and GravityWrench, so the same
  // bits): the sampler's theta scans call this some 50 times per pose, and computing each
  // sine, cosine and arctangent once made sampling twice as fast.
  const Eigen::Matrix2d R = rotation ? *rotation : Rotation(theta_rad);
  const Eigen::Vector2d p(x_m, z_m);
  Eigen::Matrix<double, 3, 2> W;
  for (int i = 0; i < 2; ++i) {
    const Cable& c = robot.cables[i];
    const Eigen::Vector2d r_F_anchor = R * c.p_P_anchor_m;
    const CableState<double> s = CableGeometry<double>(c.p_F_exit_m, c.pulley_radius_m, SignsOf(c), p + r_F_anchor);
    if (!CableGeometryValid(s, c.pulley_radius_m)) return b;
    W.col(i) = WrenchColumn<double>(r_F_anchor, s);
  }
  const Eigen::Vector3d w_g = GravityWrench<double>(robot, R);
  const Eigen::Matrix2d F = W.topRows<2>();
  b.det = F.determinant();
  Eigen::Matrix2d adj;
  adj << F(1, 1), -F(0, 1), -F(1, 0), F(0, 0);
  const Eigen::Vector2d adj_t = adj * (-w_g.head<2>());  // det * t
  b.scaled_moment = W.row(2).dot(adj_t) + b.det * w_g(2);
  if (std::abs(b.det) > kParallelCablesDet) b.tensions_N = adj_t / b.det;
  b.valid = std::isfinite(b.scaled_moment);
  return b;
}

double ResidualNorm(const Robot& robot, const Eigen::Vector3d& q, const Eigen::VectorXd& t) {
  return EquilibriumResidual<double>(robot, q, t).norm();
}

// m >= 3: pose q held by tensions t (a tension distribution with every t_i > 0). No reduced
// stiffness: the lengths leave no motion; taut cables hold the pose (Equilibrium's comment).
Equilibrium HeldPose(const Robot& robot, const Eigen::Vector3d& q, const Eigen::VectorXd& tensions_N) {
  Equilibrium eq;
  eq.q = q;
  eq.tensions_N = tensions_N;
  eq.residual_N = ResidualNorm(robot, q, tensions_N);
  eq.reduced_stiffness = std::numeric_limits<double>::quiet_NaN();
  eq.stable = true;
  return eq;
}

}  // namespace

double ReducedStiffness(const Robot& robot, const Eigen::Vector3d& q,
                        const Eigen::VectorXd& tensions_N) {
  CABLECAL_CHECK(robot.num_cables() == 2, "the statics are implemented for 2 cables");
  return StaticStability(robot, q, tensions_N, InextensibleCables(2)).min_eigenvalue;
}

EquilibriumResult SolveEquilibrium(const Robot& robot, double x_m, double z_m) {
  CABLECAL_CHECK(robot.num_cables() == 2, "the statics are implemented for 2 cables");
  EquilibriumResult result;
  bool any_valid = false, any_taut = false, any_found = false;
  double best_abs_theta = std::numeric_limits<double>::infinity();

  auto consider_root = [&](double theta_rad) {
    const MomentBalance b = EvaluateMomentBalance(robot, x_m, z_m, theta_rad);
    if (!b.valid || std::abs(b.det) <= kParallelCablesDet) return;
    Equilibrium eq;
    eq.q = Eigen::Vector3d(x_m, z_m, theta_rad);
    eq.tensions_N = b.tensions_N;
    eq.residual_N = ResidualNorm(robot, eq.q, eq.tensions_N);
    // A sign change of det*M through a pole of M is not a root: its residual is large.
    const double weight_N = robot.platform_mass_kg * robot.gravity_mps2;
    if (!(eq.residual_N < 1e-6 * weight_N)) return;
    if (!(eq.tensions_N.minCoeff() > 0.0)) return;
    any_taut = true;
    eq.reduced_stiffness = ReducedStiffness(robot, eq.q, eq.tensions_N);
    eq.stable = eq.reduced_stiffness > 0.0;
    if (!eq.stable) return;
    if (std::abs(theta_rad) < best_abs_theta) {
      best_abs_theta = std::abs(theta_rad);
      result.equilibrium = eq;
      any_found = true;
    }
  };

  // Refines a sign change of det*M in [lo, hi] (both ends valid) and considers the root.
  auto refine = [&](double lo, double hi, double g_lo, double g_hi) {
    // Illinois (modified regula falsi): superlinear, and keeps the bracket.
    int side = 0;
    for (int it = 0; it < 100 && hi - lo > kThetaTol_rad; ++it) {
      double mid = (lo * g_hi - hi * g_lo) / (g_hi - g_lo);
      if (!(mid > lo && mid < hi)) mid = 0.5 * (lo + hi);
      const MomentBalance m = EvaluateMomentBalance(robot, x_m, z_m, mid);
      if (!m.valid) break;
      if (m.scaled_moment == 0.0) {
        lo = hi = mid;
        break;
      }
      if ((m.scaled_moment < 0.0) == (g_lo < 0.0)) {
        lo = mid;
        g_lo = m.scaled_moment;
        if (side == -1) g_hi *= 0.5;
        side = -1;
      } else {
        hi = mid;
        g_hi = m.scaled_moment;
        if (side == 1) g_lo *= 0.5;
        side = 1;
      }
    }
    // Keep the bracket end with the smaller residual.
    const MomentBalance b_lo = EvaluateMomentBalance(robot, x_m, z_m, lo);
    const MomentBalance b_hi = EvaluateMomentBalance(robot, x_m, z_m, hi);
    consider_root(std::abs(b_lo.scaled_moment) <= std::abs(b_hi.scaled_moment) ? lo : hi);
  };
  auto changes_sign = [](const MomentBalance& a, const MomentBalance& b) {
    return a.scaled_moment != 0.0 && b.scaled_moment != 0.0 && (a.scaled_moment < 0.0) != (b.scaled_moment < 0.0);
  };

  const double step = 2.0 * kThetaSearchMax_rad / kThetaSearchSteps;
  double theta_prev = -kThetaSearchMax_rad;
  MomentBalance prev = EvaluateMomentBalance(robot, x_m, z_m, theta_prev, &kScanRotations[0]);
  any_valid = prev.valid;
  for (int k = 1; k <= kThetaSearchSteps; ++k) {
    const double theta = -kThetaSearchMax_rad + k * step;
    const MomentBalance cur = EvaluateMomentBalance(robot, x_m, z_m, theta, &kScanRotations[k]);
    any_valid = any_valid || cur.valid;
    if (prev.valid && cur.valid) {
      if (cur.scaled_moment == 0.0) {
        consider_root(theta);
      } else if (changes_sign(prev, cur)) {
        refine(theta_prev, theta, prev.scaled_moment, cur.scaled_moment);
      }
    } else if (prev.valid != cur.valid) {
      // The cable geometry turns invalid (an anchor sweeping through its pulley) inside
      // this interval: a root between the valid end and that boundary would be missed by
      // the scan alone. Bisect for the last valid angle and bracket from there.
      double valid = prev.valid ? theta_prev : theta, invalid = prev.valid ? theta : theta_prev;
      MomentBalance at_valid = prev.valid ? prev : cur;
      const MomentBalance end = at_valid;
      for (int it = 0; it < 60 && std::abs(invalid - valid) > kThetaTol_rad; ++it) {
        const double mid = 0.5 * (valid + invalid);
        const MomentBalance m = EvaluateMomentBalance(robot, x_m, z_m, mid);
        if (m.valid) {
          valid = mid;
          at_valid = m;
        } else {
          invalid = mid;
        }
      }
      const double end_theta = prev.valid ? theta_prev : theta;
      if (at_valid.scaled_moment == 0.0) {
        consider_root(valid);
      } else if (changes_sign(end, at_valid)) {
        if (end_theta < valid) refine(end_theta, valid, end.scaled_moment, at_valid.scaled_moment);
        else refine(valid, end_theta, at_valid.scaled_moment, end.scaled_moment);
      }
    }
    prev = cur;
    theta_prev = theta;
  }

  if (any_found) {
    result.status = EquilibriumStatus::kFound;
  } else if (any_taut) {
    result.status = EquilibriumStatus::kUnstable;
  } else if (!any_valid) {
    result.status = EquilibriumStatus::kCableGeometry;
  } else {
    result.status = EquilibriumStatus::kNoEquilibrium;
  }
  return result;
}

Eigen::VectorXd CableLengths(const Robot& robot, const Eigen::Vector3d& q) {
  Eigen::VectorXd l(robot.num_cables());
  for (int i = 0; i < robot.num_cables(); ++i) {
    l(i) = CableAtPose<double>(robot.cables[i], q).length_m;
  }
  return l;
}

const char* ToString(Feasibility f) {
  switch (f) {
    case Feasibility::kFeasible: return "feasible";
    case Feasibility::kOutsideFrame: return "outside_frame";
    case Feasibility::kLaserRange: return "laser_range";
    case Feasibility::kCableGeometry: return "cable_geometry";
    case Feasibility::kNoEquilibrium: return "no_equilibrium";
    case Feasibility::kUnstable: return "unstable";
    case Feasibility::kThetaLimit: return "theta_limit";
    case Feasibility::kTensionLow: return "tension_low";
    case Feasibility::kTensionHigh: return "tension_high";
    case Feasibility::kTiltLimit: return "tilt_limit";
    case Feasibility::kSwivelAxis: return "swivel_axis";
    case Feasibility::kInsidePulley: return "inside_pulley";
    case Feasibility::kWrap: return "wrap";
  }
  return "unknown";
}

const char* ToString(ForwardStatus s) {
  switch (s) {
    case ForwardStatus::kConverged: return "converged";
    case ForwardStatus::kNotConverged: return "not_converged";
    case ForwardStatus::kSlack: return "slack_cable";
    case ForwardStatus::kUnstable: return "unstable";
    case ForwardStatus::kOtherAssembly: return "other_assembly";
  }
  return "unknown";
}

namespace {

bool InsideFrame(const Robot& robot, const Eigen::Vector2d& p_F_m) {
  return p_F_m.x() >= robot.margin_m && p_F_m.x() <= robot.frame_width_m - robot.margin_m &&
         p_F_m.y() >= robot.margin_m && p_F_m.y() <= robot.frame_height_m - robot.margin_m;
}

}  // namespace

Feasibility CheckFeasibility(const Robot& robot, const Eigen::Vector3d& q,
                             const Eigen::VectorXd& tensions_N) {
  if (!InsideFrame(robot, q.head<2>())) return Feasibility::kOutsideFrame;
  if (q(1) > robot.laser_range_m) return Feasibility::kLaserRange;
  for (const Cable& c : robot.cables) {
    const CableState<double> s = CableAtPose<double>(c, q);
    if (!CableGeometryValid(s, c.pulley_radius_m)) return Feasibility::kCableGeometry;
    // The pulleys are part of the frame: an anchor keeps the frame margin from its pulley
    // too. Without this, robots whose exit points lie below the frame top let the platform
    // climb into a pulley, where the equilibrium degenerates (README, "Model").
    if (s.centre_distance_m - c.pulley_radius_m < robot.margin_m) return Feasibility::kCableGeometry;
  }
  if (std::abs(q(2)) > robot.theta_max_rad) return Feasibility::kThetaLimit;
  if (!InsideFrame(robot, PlatformPointInF<double>(q, robot.p_P_com_m))) {
    return Feasibility::kOutsideFrame;
  }
  for (const Cable& c : robot.cables) {
    if (!InsideFrame(robot, PlatformPointInF<double>(q, c.p_P_anchor_m))) {
      return Feasibility::kOutsideFrame;
    }
  }
  if (tensions_N.minCoeff() < robot.tension_min_N) return Feasibility::kTensionLow;
  if (tensions_N.maxCoeff() > robot.tension_max_N) return Feasibility::kTensionHigh;
  return Feasibility::kFeasible;
}

PoseEvaluation EvaluatePose(const Robot& robot, double x_m, double z_m) {
  PoseEvaluation e;
  if (!InsideFrame(robot, Eigen::Vector2d(x_m, z_m))) {
    e.feasibility = Feasibility::kOutsideFrame;
    return e;
  }
  if (z_m > robot.laser_range_m) {
    e.feasibility = Feasibility::kLaserRange;
    return e;
  }
  const EquilibriumResult eq = SolveEquilibrium(robot, x_m, z_m);
  switch (eq.status) {
    case EquilibriumStatus::kFound: break;
    case EquilibriumStatus::kNoEquilibrium: e.feasibility = Feasibility::kNoEquilibrium; return e;
    case EquilibriumStatus::kUnstable: e.feasibility = Feasibility::kUnstable; return e;
    case EquilibriumStatus::kCableGeometry: e.feasibility = Feasibility::kCableGeometry; return e;
  }
  e.has_equilibrium = true;
  e.equilibrium = eq.equilibrium;
  e.feasibility = CheckFeasibility(robot, e.equilibrium.q, e.equilibrium.tensions_N);
  return e;
}

PoseEvaluation EvaluatePose(const Robot& robot, const Eigen::Vector3d& q) {
  CABLECAL_CHECK(robot.theta_is_free(), "a full pose is evaluated for 3 or more cables; 2 cables fix theta");
  PoseEvaluation e;
  e.equilibrium.q = q;
  if (!InsideFrame(robot, q.head<2>())) {
    e.feasibility = Feasibility::kOutsideFrame;
    return e;
  }
  if (q(1) > robot.laser_range_m) {
    e.feasibility = Feasibility::kLaserRange;
    return e;
  }
  for (const Cable& c : robot.cables) {
    if (!CableGeometryValid(CableAtPose<double>(c, q), c.pulley_radius_m)) {
      e.feasibility = Feasibility::kCableGeometry;
      return e;
    }
  }
  const TensionDistribution t = DistributeTensions(robot, q);
  if (t.feasibility == Feasibility::kNoEquilibrium) {
    e.feasibility = Feasibility::kNoEquilibrium;
    return e;
  }
  e.has_equilibrium = true;
  e.equilibrium = HeldPose(robot, q, t.tensions_N);
  e.feasibility = CheckFeasibility(robot, q, t.tensions_N);
  return e;
}

ThetaScan ScanTheta(const Robot& robot, double x_m, double z_m) {
  CABLECAL_CHECK(robot.theta_is_free(), "theta is scanned for 3 or more cables");
  const int half = static_cast<int>(std::floor(robot.theta_max_rad / kThetaScanStep_rad + 1e-9));
  std::vector<PoseEvaluation> evaluations;
  evaluations.reserve(2 * half + 1);
  for (int k = -half; k <= half; ++k) {
    evaluations.push_back(EvaluatePose(robot, Eigen::Vector3d(x_m, z_m, k * kThetaScanStep_rad)));
  }
  ThetaScan scan;
  // The longest run of consecutive feasible samples; its middle sample is reported.
  int best_start = -1, best_length = 0;
  for (int k = 0; k < static_cast<int>(evaluations.size());) {
    if (!evaluations[k].feasible()) {
      ++k;
      continue;
    }
    int end = k;
    while (end < static_cast<int>(evaluations.size()) && evaluations[end].feasible()) ++end;
    scan.feasible_count += end - k;
    if (std::isnan(scan.theta_min_rad)) scan.theta_min_rad = (k - half) * kThetaScanStep_rad;
    scan.theta_max_rad = (end - 1 - half) * kThetaScanStep_rad;
    if (end - k > best_length) {
      best_length = end - k;
      best_start = k;
    }
    k = end;
  }
  if (best_start >= 0) {
    scan.evaluation = evaluations[best_start + best_length / 2];
    return scan;
  }
  // Nothing feasible: the reason most orientations give (the first in scan order on a tie).
  int counts[kNumFeasibility] = {0};
  for (const PoseEvaluation& e : evaluations) ++counts[static_cast<int>(e.feasibility)];
  int best = 0;
  for (std::size_t k = 1; k < evaluations.size(); ++k) {
    if (counts[static_cast<int>(evaluations[k].feasibility)] > counts[static_cast<int>(evaluations[best].feasibility)]) {
      best = static_cast<int>(k);
    }
  }
  scan.evaluation = evaluations[best];
  return scan;
}

InversePose InverseModel(const Robot& robot, double x_m, double z_m) {
  InversePose inv;
  inv.evaluation = EvaluatePose(robot, x_m, z_m);
  if (inv.evaluation.has_equilibrium) {
    inv.lengths_m = CableLengths(robot, inv.evaluation.equilibrium.q);
  }
  return inv;
}

PoseEvaluation EvaluateHome(const Robot& robot) {
  return robot.theta_is_free()
             ? EvaluatePose(robot, Eigen::Vector3d(robot.p_F_home_m.x(), robot.p_F_home_m.y(), robot.home_theta_rad))
             : EvaluatePose(robot, robot.p_F_home_m.x(), robot.p_F_home_m.y());
}

PoseEvaluation HomeEvaluation(const Robot& robot) {
  const PoseEvaluation home = EvaluateHome(robot);
  if (!home.feasible()) {
    throw InputError(robot.source, "home",
                     std::string("the home pose is not in the feasible workspace (") + ToString(home.feasibility) + ")");
  }
  return home;
}

Eigen::VectorXd InitialLengths(const Robot& robot) {
  Eigen::VectorXd l0(robot.num_cables());
  bool all_given = true;
  for (int i = 0; i < robot.num_cables(); ++i) {
    all_given = all_given && robot.cables[i].initial_length_m.has_value();
  }
  Eigen::VectorXd home_lengths;
  if (!all_given) home_lengths = CableLengths(robot, HomeEvaluation(robot).equilibrium.q);
  for (int i = 0; i < robot.num_cables(); ++i) {
    l0(i) = robot.cables[i].initial_length_m.value_or(all_given ? 0.0 : home_lengths(i));
  }
  return l0;
}

namespace {

// Starting pose for the forward model at orientation theta, pulleys ignored: anchor i then
// lies on the circle of radius L_i about A_i, so p lies on the circle about A_i - R b_i;
// the lower intersection of the two circles. Returns false if the circles do not meet.
bool CircleIntersectionGuess(const Robot& robot, const Eigen::VectorXd& lengths_m, double theta_rad,
                             Eigen::Vector3d* guess) {
  const Eigen::Matrix2d R = Rotation(theta_rad);
  const Eigen::Vector2d c1 = robot.cables[0].p_F_exit_m - R * robot.cables[0].p_P_anchor_m;
  const Eigen::Vector2d c2 = robot.cables[1].p_F_exit_m - R * robot.cables[1].p_P_anchor_m;
  const double d = (c2 - c1).norm();
  const double r1 = lengths_m(0), r2 = lengths_m(1);
  if (d <= 0.0 || r1 + r2 < d || std::abs(r1 - r2) > d) return false;
  const double a = (r1 * r1 - r2 * r2 + d * d) / (2.0 * d);
  const double h = std::sqrt(std::max(0.0, r1 * r1 - a * a));
  const Eigen::Vector2d e = (c2 - c1) / d;
  const Eigen::Vector2d perp(-e.y(), e.x());
  const Eigen::Vector2d p1 = c1 + a * e + h * perp, p2 = c1 + a * e - h * perp;
  const Eigen::Vector2d p = p1.y() < p2.y() ? p1 : p2;
  *guess = Eigen::Vector3d(p.x(), p.y(), theta_rad);
  return true;
}


// Damped Newton from one starting pose.
ForwardResult ForwardNewton(const Robot& robot, const Eigen::VectorXd& lengths_m, const Eigen::Vector3d& start) {
  constexpr int kMaxIterations = 60;
  constexpr double kLengthTol_m = 1e-11;   // a few hundred ulps of a 3 m length
  constexpr double kWrenchTol_N = 1e-9;
  using Jet5 = ceres::Jet<double, 5>;
  using Vector5d = Eigen::Matrix<double, 5, 1>;
  const double weight_N = robot.platform_mass_kg * robot.gravity_mps2;

  // Unknowns y = (x, z, theta, t1, t2); wrench rows are divided by the weight so that the
  // Newton merit function weighs metres and newtons alike.
  auto residual = [&](const Vector5d& y, Eigen::Matrix<double, 5, 5>* jacobian) {
    Eigen::Matrix<Jet5, 5, 1> yj;
    for (int k = 0; k < 5; ++k) yj(k) = Jet5(y(k), k);
    const Pose<Jet5> q = yj.head<3>();
    const Eigen::Matrix<Jet5, Eigen::Dynamic, 1> t = yj.tail<2>();
    // [l(q) - L; W t + w_g] with one rotation and one state per cable, as in
    // EvaluateMomentBalance (the same arithmetic as CableAtPose and EquilibriumResidual).
    Eigen::Matrix<Jet5, 5, 1> r;
    const Eigen::Matrix<Jet5, 2, 2> R = Rotation(q(2));
    Eigen::Matrix<Jet5, 3, Eigen::Dynamic> W(3, 2);
    for (int i = 0; i < 2; ++i) {
      const Cable& c = robot.cables[i];
      const Vec2<Jet5> r_F_anchor = R * c.p_P_anchor_m.cast<Jet5>();
      const CableState<Jet5> s = CableGeometry<Jet5>(c.p_F_exit_m.cast<Jet5>(), Jet5(c.pulley_radius_m), SignsOf(c),
                                                     Vec2<Jet5>(q(0), q(1)) + r_F_anchor);
      r(i) = s.length_m - lengths_m(i);
      W.col(i) = WrenchColumn<Jet5>(r_F_anchor, s);
    }
    r.tail<3>() = (W * t + GravityWrench<Jet5>(robot, R)) / weight_N;
    Vector5d value;
    for (int k = 0; k < 5; ++k) {
      value(k) = r(k).a;
      if (jacobian) jacobian->row(k) = r(k).v.transpose();
    }
    return value;
  };

  Vector5d y;
  y.head<3>() = start;
  {
    const Pose<double> q0 = y.head<3>();
    const Eigen::Matrix<double, 3, Eigen::Dynamic> W = WrenchMatrix<double>(robot, q0);
    y.tail<2>() = W.colPivHouseholderQr().solve(-GravityWrench<double>(robot, q0));
  }

  ForwardResult result;
  Eigen::Matrix<double, 5, 5> J;
  Vector5d r = residual(y, &J);
  for (int it = 0; it < kMaxIterations; ++it) {
    result.iterations = it;
    if (!r.allFinite()) break;
    if (r.head<2>().cwiseAbs().maxCoeff() < kLengthTol_m &&
        r.tail<3>().norm() * weight_N < kWrenchTol_N) {
      result.status = ForwardStatus::kConverged;
      break;
    }
    const Vector5d step = J.fullPivLu().solve(-r);
    if (!step.allFinite()) break;
    // Backtracking on |r|^2 keeps Newton from jumping to another branch far away.
    double lambda = 1.0;
    Vector5d y_new, r_new;
    Eigen::Matrix<double, 5, 5> J_new;
    for (int ls = 0; ls < 30; ++ls) {
      y_new = y + lambda * step;
      r_new = residual(y_new, &J_new);
      if (r_new.allFinite() && r_new.squaredNorm() < r.squaredNorm()) break;
      lambda *= 0.5;
    }
    if (!r_new.allFinite() || !(r_new.squaredNorm() <= r.squaredNorm())) {
      // No descent possible: accept only if already at rounding level.
      break;
    }
    y = y_new;
    r = r_new;
    J = J_new;
  }

  Equilibrium& eq = result.equilibrium;
  eq.q = y.head<3>();
  eq.tensions_N = y.tail<2>();
  eq.residual_N = r.tail<3>().norm() * weight_N;
  result.length_residual_m = r.head<2>().cwiseAbs().maxCoeff();
  if (result.status != ForwardStatus::kConverged) return result;
  if (!(eq.tensions_N.minCoeff() > 0.0)) {
    result.status = ForwardStatus::kSlack;
    return result;
  }
  eq.reduced_stiffness = ReducedStiffness(robot, eq.q, eq.tensions_N);
  eq.stable = eq.reduced_stiffness > 0.0;
  if (!eq.stable) result.status = ForwardStatus::kUnstable;
  return result;
}


// m >= 3: Gauss-Newton on l(q) = L from one start (dl/dq = -W', model/cable.h); the
// least-squares pose when m >= 4 lengths are inconsistent.
ForwardResult GaussNewtonLengths(const Robot& robot, const Eigen::VectorXd& lengths_m, const Eigen::Vector3d& start) {
  constexpr int kMaxIterations = 60;
  constexpr double kStepTol = 1e-13;  // m and rad: at the least-squares minimum to rounding
  ForwardResult result;
  Eigen::Vector3d q = start;
  auto residual = [&](const Eigen::Vector3d& at, Eigen::VectorXd* r) {
    *r = CableLengths(robot, at) - lengths_m;
    return r->allFinite();
  };
  Eigen::VectorXd r;
  if (!residual(q, &r)) return result;
  for (int it = 0; it < kMaxIterations; ++it) {
    result.iterations = it + 1;
    const Eigen::MatrixXd J = -WrenchMatrix<double>(robot, Pose<double>(q)).transpose();
    const Eigen::Vector3d step = J.colPivHouseholderQr().solve(-r);
    if (!step.allFinite()) break;
    double lambda = 1.0;
    Eigen::Vector3d q_new;
    Eigen::VectorXd r_new;
    bool descent = false;
    for (int ls = 0; ls < 30; ++ls) {
      q_new = q + lambda * step;
      if (residual(q_new, &r_new) && r_new.squaredNorm() <= r.squaredNorm()) {
        descent = true;
        break;
      }
      lambda *= 0.5;
    }
    if (!descent) {
      // No decrease along a Gauss-Newton step: at the minimum to rounding if the step is tiny.
      if (step.cwiseAbs().maxCoeff() < 1e3 * kStepTol) result.status = ForwardStatus::kConverged;
      break;
    }
    q = q_new;
    r = r_new;
    if ((lambda * step).cwiseAbs().maxCoeff() < kStepTol || r.cwiseAbs().maxCoeff() < 1e-13) {
      result.status = ForwardStatus::kConverged;
      break;
    }
  }
  // A cold start can converge a turn away: the same pose, reported in (-pi, pi].
  q(2) = std::remainder(q(2), 2.0 * M_PI);
  result.equilibrium.q = q;
  result.length_residual_m = r.cwiseAbs().maxCoeff();
  return result;
}

// m >= 3: the pose the lengths fix, then the tensions that hold it there.
ForwardResult ForwardKinematics(const Robot& robot, const Eigen::VectorXd& lengths_m, const Eigen::Vector3d* guess) {
  const auto other_assembly = [&](const Eigen::Vector3d& q) {
    for (const Cable& c : robot.cables) {
      if (!CableGeometryValid(CableAtPose<double>(c, q), c.pulley_radius_m)) return true;
    }
    if (!(q(0) >= 0.0 && q(0) <= robot.frame_width_m && q(1) >= 0.0 && q(1) <= robot.frame_height_m)) return true;
    return guess && ((q.head<2>() - guess->head<2>()).norm() > kOtherAssemblyDistance_m ||
                     std::abs(q(2) - (*guess)(2)) > kOtherAssemblyAngle_rad);
  };
  std::vector<Eigen::Vector3d> starts;
  if (guess) {
    starts.push_back(*guess);
  } else {
    starts.emplace_back(robot.p_F_home_m.x(), robot.p_F_home_m.y(), robot.home_theta_rad);
    for (const double theta_deg : {0.0, 25.0, -25.0, 50.0, -50.0}) {
      Eigen::Vector3d start;
      if (CircleIntersectionGuess(robot, lengths_m, theta_deg * kDegToRad, &start)) starts.push_back(start);
    }
  }
  ForwardResult last;
  for (const Eigen::Vector3d& start : starts) {
    last = GaussNewtonLengths(robot, lengths_m, start);
    if (last.status != ForwardStatus::kConverged) continue;
    if (other_assembly(last.equilibrium.q)) {
      last.status = ForwardStatus::kOtherAssembly;
      continue;
    }
    const TensionDistribution t = DistributeTensions(robot, last.equilibrium.q);
    if (t.feasibility == Feasibility::kNoEquilibrium) {
      last.status = ForwardStatus::kSlack;
      continue;
    }
    last.equilibrium = HeldPose(robot, last.equilibrium.q, t.tensions_N);
    return last;
  }
  return last;
}

}  // namespace

ForwardResult LeastSquaresPoseGuess(const Robot& robot, const Eigen::VectorXd& lengths_m,
                                    const Eigen::Vector3d* guess) {
  CABLECAL_CHECK(lengths_m.size() == robot.num_cables(), "one length per cable");
  if (robot.theta_is_free()) return ForwardKinematics(robot, lengths_m, guess);
  return SolveForwardGeometricoStatic(robot, lengths_m, guess);
}

ForwardResult SolveForwardGeometricoStatic(const Robot& robot, const Eigen::VectorXd& lengths_m,
                                           const Eigen::Vector3d* guess) {
  CABLECAL_CHECK(lengths_m.size() == robot.num_cables(), "one length per cable");
  CABLECAL_CHECK(robot.num_cables() <= 3, "more than 3 inextensible cables over-determine the pose (forward_statics.h)");
  if (robot.theta_is_free()) return ForwardKinematics(robot, lengths_m, guess);
  ForwardResult last;
  if (guess) {
    last = ForwardNewton(robot, lengths_m, *guess);
    if (last.status == ForwardStatus::kConverged) return last;
  }
  // Cold start (or a guess that failed): Newton from the circle intersections at a few
  // orientations, first taut and stable solution kept. Near the posts the platform tilts
  // far from level, where a single level start can stall.
  for (const double theta_deg : {0.0, 25.0, -25.0, 50.0, -50.0, 75.0, -75.0}) {
    Eigen::Vector3d start;
    if (!CircleIntersectionGuess(robot, lengths_m, theta_deg * kDegToRad, &start)) continue;
    last = ForwardNewton(robot, lengths_m, start);
    if (last.status == ForwardStatus::kConverged) return last;
  }
  return last;
}

}  // namespace cablecal
