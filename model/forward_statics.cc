#include "model/forward_statics.h"

#include <ceres/jet.h>

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "common/error.h"
#include "common/flatten.h"
#include "model/cable.h"
#include "model/stability.h"
#include "model/swivel.h"

namespace cablecal {
namespace {

// What the one solver below needs of a kind of robot: its pose size, the model's lengths,
// wrench matrix and gravity wrench (templated on the scalar: Jets give the Newton Jacobian), the
// cables' stiffness, the stability test, and the checks that tell this robot's assembly from
// another one.
struct PlanarAdapter {
  using RobotType = Robot;
  using Result = ForwardResult;
  static constexpr int kDim = PlanarKind::kPoseDim;
  template <typename T>
  using PoseOf = Eigen::Matrix<T, kDim, 1>;
  using PoseD = PoseOf<double>;

  template <typename T>
  static Eigen::Matrix<T, Eigen::Dynamic, 1> Lengths(const Robot& robot, const PoseOf<T>& q) {
    Eigen::Matrix<T, Eigen::Dynamic, 1> l(robot.num_cables());
    for (int i = 0; i < robot.num_cables(); ++i) l(i) = CableAtPose<T>(robot.cables[i], q).length_m;
    return l;
  }
  template <typename T>
  static Eigen::Matrix<T, kDim, Eigen::Dynamic> Wrench(const Robot& robot, const PoseOf<T>& q) {
    return WrenchMatrix<T>(robot, q);
  }
  template <typename T>
  static Eigen::Matrix<T, kDim, 1> Gravity(const Robot& robot, const PoseOf<T>& q) {
    return GravityWrench<T>(robot, q);
  }
  template <typename T>
  static void LengthsAndWrench(const Robot& robot, const PoseOf<T>& q, Eigen::Matrix<T, Eigen::Dynamic, 1>* l,
                               Eigen::Matrix<T, kDim, Eigen::Dynamic>* W) {
    *l = Lengths<T>(robot, q);
    *W = Wrench<T>(robot, q);
  }
  static const std::optional<double>& Stiffness(const Robot& robot, int i) { return robot.cables[i].stiffness_N; }
  static PoseD Home(const Robot& robot) { return PoseD(robot.p_F_home_m.x(), robot.p_F_home_m.y(), robot.home_theta_rad); }
  static StabilityResult Stability(const Robot& robot, const PoseD& q, const Eigen::VectorXd& t,
                                   const Eigen::VectorXd& k) {
    return StaticStability(robot, q, t, k);
  }
  static bool GeometryValid(const Robot& robot, const PoseD& q) {
    for (const Cable& c : robot.cables) {
      if (!CableGeometryValid(CableAtPose<double>(c, q), c.pulley_radius_m)) return false;
    }
    return true;
  }
  static bool InsideFrame(const Robot& robot, const PoseD& q) {
    return q(0) >= 0.0 && q(0) <= robot.frame_width_m && q(1) >= 0.0 && q(1) <= robot.frame_height_m;
  }
  static bool NearGuess(const PoseD& q, const PoseD& guess) {
    return (q.head<2>() - guess.head<2>()).norm() <= kOtherAssemblyDistance_m &&
           std::abs(q(2) - guess(2)) <= kOtherAssemblyAngle_rad;
  }
  // A cold start can converge a turn away: the same pose, reported in (-pi, pi].
  static void Normalise(PoseD& q) { q(2) = std::remainder(q(2), 2.0 * M_PI); }
};

struct SpatialAdapter {
  using RobotType = SpatialRobot;
  using Result = SpatialForwardResult;
  static constexpr int kDim = SpatialKind::kPoseDim;
  template <typename T>
  using PoseOf = SpatialPose<T>;
  using PoseD = PoseOf<double>;

  template <typename T>
  static Eigen::Matrix<T, Eigen::Dynamic, 1> Lengths(const SpatialRobot& robot, const PoseOf<T>& q) {
    return CableLengths<T>(robot, q);
  }
  template <typename T>
  static Eigen::Matrix<T, kDim, Eigen::Dynamic> Wrench(const SpatialRobot& robot, const PoseOf<T>& q) {
    return WrenchMatrix<T>(robot, q);
  }
  template <typename T>
  static Eigen::Matrix<T, kDim, 1> Gravity(const SpatialRobot& robot, const PoseOf<T>& q) {
    return GravityWrench<T>(robot, q);
  }
  template <typename T>
  static void LengthsAndWrench(const SpatialRobot& robot, const PoseOf<T>& q, Eigen::Matrix<T, Eigen::Dynamic, 1>* l,
                               Eigen::Matrix<T, kDim, Eigen::Dynamic>* W) {
    CableLengthsAndWrench<T>(robot, q, l, W);
  }
  static const std::optional<double>& Stiffness(const SpatialRobot& robot, int i) {
    return robot.cables[i].stiffness_N;
  }
  static PoseD Home(const SpatialRobot& robot) { return robot.home_pose(); }
  static StabilityResult Stability(const SpatialRobot& robot, const PoseD& q, const Eigen::VectorXd& t,
                                   const Eigen::VectorXd& k) {
    return StaticStability(robot, q, t, k);
  }
  static bool GeometryValid(const SpatialRobot& robot, const PoseD& q) { return CableGeometryAt(robot, q).valid(); }
  static bool InsideFrame(const SpatialRobot& robot, const PoseD& q) {
    return (q.head<3>().array() >= robot.p_F_frame_min_m.array()).all() &&
           (q.head<3>().array() <= robot.p_F_frame_max_m.array()).all();
  }
  // The orientations compared by the angle of the rotation between them (roll, pitch and yaw
  // differences mean little near a large pitch).
  static bool NearGuess(const PoseD& q, const PoseD& guess) {
    const Eigen::Matrix3d relative = Rotation<double>(guess).transpose() * Rotation<double>(q);
    return (q.head<3>() - guess.head<3>()).norm() <= kOtherAssemblyDistance_m &&
           Eigen::AngleAxisd(relative).angle() <= kOtherAssemblyAngle_rad;
  }
  // Angles wrapped to (-pi, pi], and the one orientation written with |pitch| <= pi / 2: Newton
  // may end on the other roll-pitch-yaw triple of the same rotation, (roll + pi, pi - pitch,
  // yaw + pi), and an inclinometer reads roll and pitch of the usual one (seen on ipanema1 at
  // a pitch of 0.3 rad: roll 2.98, pitch 2.87).
  static void Normalise(PoseD& q) {
    for (int k = 3; k < 6; ++k) q(k) = std::remainder(q(k), 2.0 * M_PI);
    if (std::abs(q(4)) > 0.5 * M_PI) {
      q(3) = std::remainder(q(3) + M_PI, 2.0 * M_PI);
      q(4) = std::remainder(M_PI - q(4), 2.0 * M_PI);
      q(5) = std::remainder(q(5) + M_PI, 2.0 * M_PI);
    }
  }
};

// Newton's tolerances: lengths to a few hundred ulps of a 10 m cable; the wrench to 1e-9 of the
// platform's weight.
constexpr double kLengthTol_m = 1e-11;
constexpr double kRelativeWrenchTol = 1e-9;
constexpr int kMaxIterations = 100;
constexpr int kMaxHalvings = 40;
constexpr double kMaxPoseStep = 0.1;
constexpr double kSlackAtStart_m = 0.05;

// The cables' roles in one Newton solve. Every taut cable's tension is an unknown with the row
//   l_i(q) - L_i - (L_i / EA_i) t_i = 0
// (l = L (1 + t / EA); compliance L / EA = 0 for an inextensible cable, whose tension is then
// its multiplier): the same roots as the energy's t_i = EA (l / L - 1), and well conditioned
// however stiff the cable (EA -> infinity is the inextensible row). A slack elastic cable
// (t = 0, l <= L) has neither unknown nor row: the active set below decides which are.
struct Cables {
  std::vector<int> taut;                 // cables with a tension unknown and a length row
  std::vector<double> compliance_mpN;    // per cable, L / EA; 0 for an inextensible one
  std::vector<bool> elastic;
  double weight_N = 1.0;
  double wrench_tol_N = 0.0;
  int count() const { return static_cast<int>(taut.size()); }
};

template <class A>
Cables CablesOf(const typename A::RobotType& robot, const Eigen::VectorXd& L) {
  Cables cables;
  for (int i = 0; i < robot.num_cables(); ++i) {
    const std::optional<double>& ea = A::Stiffness(robot, i);
    cables.elastic.push_back(ea.has_value());
    cables.compliance_mpN.push_back(ea ? L(i) / *ea : 0.0);
    cables.taut.push_back(i);
  }
  cables.weight_N = std::max(1e-9, robot.platform_mass_kg * robot.gravity_mps2);
  cables.wrench_tol_N = kRelativeWrenchTol * cables.weight_N;
  return cables;
}

// The residual at y = (q, t_taut): [(W t + w_g) / weight; l_i - L_i - c_i t_i over the taut
// cables] (the wrench rows in units of the platform's weight, so that the merit function weighs
// metres and newtons alike), and its Jacobian (pose columns from Jets, tension columns W's and
// the compliances).
template <class A>
CABLECAL_FLATTEN bool NewtonResidual(const typename A::RobotType& robot, const Cables& cables, const Eigen::VectorXd& L,
                    const Eigen::VectorXd& y, Eigen::VectorXd* r, Eigen::MatrixXd* J) {
  constexpr int d = A::kDim;
  using Jet = ceres::Jet<double, d>;
  const int k = cables.count();
  typename A::template PoseOf<Jet> q;
  for (int c = 0; c < d; ++c) q(c) = Jet(y(c), c);
  Eigen::Matrix<Jet, Eigen::Dynamic, 1> l;
  Eigen::Matrix<Jet, d, Eigen::Dynamic> W;
  A::template LengthsAndWrench<Jet>(robot, q, &l, &W);
  Eigen::Matrix<Jet, d, 1> f = A::template Gravity<Jet>(robot, q);
  for (int j = 0; j < k; ++j) f += W.col(cables.taut[j]) * Jet(y(d + j));
  r->resize(d + k);
  J->setZero(d + k, d + k);
  for (int row = 0; row < d; ++row) {
    (*r)(row) = f(row).a / cables.weight_N;
    J->row(row).head<d>() = f(row).v.transpose() / cables.weight_N;
    for (int j = 0; j < k; ++j) (*J)(row, d + j) = W(row, cables.taut[j]).a / cables.weight_N;
  }
  for (int j = 0; j < k; ++j) {
    const int i = cables.taut[j];
    (*r)(d + j) = l(i).a - L(i) - cables.compliance_mpN[i] * y(d + j);
    J->row(d + j).head<d>() = l(i).v.transpose();
    (*J)(d + j, d + j) = -cables.compliance_mpN[i];
  }
  return r->allFinite() && J->allFinite();
}

template <int d>
bool Converged(const Cables& cables, const Eigen::VectorXd& r) {
  const double length_residual = cables.count() > 0 ? r.tail(cables.count()).cwiseAbs().maxCoeff() : 0.0;
  return length_residual < kLengthTol_m && r.template head<d>().norm() * cables.weight_N < cables.wrench_tol_N;
}

// Damped Newton for one active set from y (updated in place); true when converged.
template <class A>
bool NewtonSolve(const typename A::RobotType& robot, const Cables& cables, const Eigen::VectorXd& L,
                 Eigen::VectorXd& y, Eigen::VectorXd& r, int* iterations) {
  constexpr int d = A::kDim;
  Eigen::MatrixXd J;
  if (!NewtonResidual<A>(robot, cables, L, y, &r, &J)) return false;
  for (int it = 0; it < kMaxIterations; ++it, ++*iterations) {
    if (Converged<d>(cables, r)) return true;
    const Eigen::VectorXd step = J.colPivHouseholderQr().solve(-r);
    if (!step.allFinite()) return false;
    // Backtracking on |r|^2 keeps Newton on the branch it started on, and a pose step of at
    // most kMaxPoseStep (m, rad) keeps it near the start: a platform settles near where it was
    // commanded, and a long step far from it is the linearisation's, not the robot's.
    const double largest = step.head<d>().cwiseAbs().maxCoeff();
    double lambda = largest > kMaxPoseStep ? kMaxPoseStep / largest : 1.0;
    Eigen::VectorXd y_new, r_new;
    Eigen::MatrixXd J_new;
    bool descent = false;
    for (int ls = 0; ls < kMaxHalvings; ++ls) {
      y_new = y + lambda * step;
      descent = NewtonResidual<A>(robot, cables, L, y_new, &r_new, &J_new) && r_new.squaredNorm() < r.squaredNorm();
      if (descent) break;
      lambda *= 0.5;
    }
    if (!descent) return Converged<d>(cables, r);
    y = y_new;
    r = r_new;
    J = J_new;
  }
  return Converged<d>(cables, r);
}

// Newton from one start with an active set of elastic cables: an elastic cable whose tension
// comes out negative goes slack (dropped, the most negative first), a slack one stretched
// beyond its unstretched length is taut again; repeated until neither happens. The result's
// status is kConverged or kNotConverged (the physical checks are the caller's).
template <class A>
typename A::Result NewtonFrom(const typename A::RobotType& robot, const Cables& all, const Eigen::VectorXd& L,
                              const typename A::PoseD& start) {
  constexpr int d = A::kDim;
  const int m = robot.num_cables();
  typename A::Result result;
  Cables cables = all;
  Eigen::VectorXd tensions = Eigen::VectorXd::Zero(m), r;
  typename A::PoseD q = start;
  // The first active set: every cable but the elastic ones paid out more than kSlackAtStart_m
  // beyond their length at the start (taut, such a cable would start under a compression Newton
  // creeps out of; one a little long is taut where the platform settles as often as not).
  {
    const Eigen::VectorXd l = A::template Lengths<double>(robot, q);
    cables.taut.clear();
    for (int i = 0; i < m; ++i) {
      if (!all.elastic[i] || l(i) > L(i) - kSlackAtStart_m) cables.taut.push_back(i);
    }
  }
  bool converged = false;
  for (int round = 0; round <= 2 * m && !converged; ++round) {
    const int k = cables.count();
    Eigen::VectorXd y(d + k);
    y.head<d>() = q;
    for (int j = 0; j < k; ++j) y(d + j) = tensions(cables.taut[j]);
    // The tensions that balance the platform best at the start.
    if (round == 0 && k > 0) {
      Eigen::MatrixXd J;
      if (!NewtonResidual<A>(robot, cables, L, y, &r, &J)) return result;
      y.tail(k) = J.topRightCorner(d, k).colPivHouseholderQr().solve(-r.head<d>() + J.topRightCorner(d, k) * y.tail(k));
    }
    if (!NewtonSolve<A>(robot, cables, L, y, r, &result.iterations)) break;
    q = y.head<d>();
    tensions.setZero();
    for (int j = 0; j < k; ++j) tensions(cables.taut[j]) = y(d + j);
    // The active set: the most negative elastic tension goes slack; else a slack cable that
    // is stretched comes back.
    int slacken = -1, tighten = -1;
    for (int j = 0; j < k; ++j) {
      const int i = cables.taut[j];
      if (all.elastic[i] && tensions(i) < 0.0 && (slacken < 0 || tensions(i) < tensions(slacken))) slacken = i;
    }
    if (slacken < 0) {
      const Eigen::VectorXd l = A::template Lengths<double>(robot, q);
      for (int i = 0; i < m; ++i) {
        const bool is_taut = std::find(cables.taut.begin(), cables.taut.end(), i) != cables.taut.end();
        if (!is_taut && l(i) > L(i) + kLengthTol_m) tighten = i;
      }
    }
    if (slacken >= 0) {
      cables.taut.erase(std::find(cables.taut.begin(), cables.taut.end(), slacken));
      tensions(slacken) = 0.0;
    } else if (tighten >= 0) {
      cables.taut.insert(std::upper_bound(cables.taut.begin(), cables.taut.end(), tighten), tighten);
    } else {
      converged = true;
    }
  }
  A::Normalise(q);
  result.status = converged ? ForwardStatus::kConverged : ForwardStatus::kNotConverged;
  result.equilibrium.q = q;
  result.equilibrium.tensions_N = tensions;
  result.equilibrium.residual_N = r.size() >= d ? r.head<d>().norm() * cables.weight_N : 0.0;
  result.equilibrium.reduced_stiffness = std::numeric_limits<double>::quiet_NaN();
  result.equilibrium.stable = false;
  // The inextensible cables' length errors (the elastic ones' rows are their tensions).
  const Eigen::VectorXd l = A::template Lengths<double>(robot, q);
  result.length_residual_m = 0.0;
  for (int i = 0; i < m; ++i) {
    if (!all.elastic[i]) result.length_residual_m = std::max(result.length_residual_m, std::abs(l(i) - L(i)));
  }
  return result;
}

// A geometric starting guess: the pose whose cable lengths are nearest the unstretched ones in
// least squares (Gauss-Newton, every cable taken as rigid), from home.
template <class A>
typename A::PoseD LeastSquaresGuess(const typename A::RobotType& robot, const Eigen::VectorXd& L) {
  constexpr int d = A::kDim;
  using Jet = ceres::Jet<double, d>;
  typename A::PoseD q = A::Home(robot);
  for (int it = 0; it < 30; ++it) {
    typename A::template PoseOf<Jet> qj;
    for (int c = 0; c < d; ++c) qj(c) = Jet(q(c), c);
    const Eigen::Matrix<Jet, Eigen::Dynamic, 1> l = A::template Lengths<Jet>(robot, qj);
    Eigen::VectorXd r(l.size());
    Eigen::MatrixXd J(l.size(), d);
    for (int i = 0; i < l.size(); ++i) {
      r(i) = l(i).a - L(i);
      J.row(i) = l(i).v.transpose();
    }
    const Eigen::VectorXd step = J.colPivHouseholderQr().solve(-r);
    if (!step.allFinite() || !r.allFinite()) break;
    // At most 0.2 m or rad at once: a start, not an answer, should not fly off the frame.
    const double largest = step.cwiseAbs().maxCoeff();
    q += (largest > 0.2 ? 0.2 / largest : 1.0) * step;
    if (largest < 1e-10) break;
  }
  return q;
}

// The physical checks of a converged solution (SolveForwardStatics' comment), in order.
template <class A>
void Check(const typename A::RobotType& robot, const Eigen::VectorXd& L, const typename A::PoseD* guess,
           typename A::Result& result) {
  auto& eq = result.equilibrium;
  const int m = robot.num_cables();
  Eigen::VectorXd axial_stiffness_Npm(m);
  for (int i = 0; i < m; ++i) {
    const std::optional<double>& ea = A::Stiffness(robot, i);
    if (!ea) {
      if (!(eq.tensions_N(i) > 0.0)) {
        result.status = ForwardStatus::kSlack;
        return;
      }
      axial_stiffness_Npm(i) = std::numeric_limits<double>::infinity();
    } else {
      axial_stiffness_Npm(i) = eq.tensions_N(i) > 0.0 ? *ea / L(i) : 0.0;
    }
  }
  const StabilityResult stability = A::Stability(robot, eq.q, eq.tensions_N, axial_stiffness_Npm);
  eq.reduced_stiffness = stability.min_eigenvalue;
  eq.stable = stability.stable;
  if (!eq.stable) {
    result.status = ForwardStatus::kUnstable;
    return;
  }
  if (!A::GeometryValid(robot, eq.q) || !A::InsideFrame(robot, eq.q) || (guess && !A::NearGuess(eq.q, *guess))) {
    result.status = ForwardStatus::kOtherAssembly;
  }
}

template <class A>
typename A::Result Solve(const typename A::RobotType& robot, const Eigen::VectorXd& L,
                         const typename A::PoseD* guess) {
  CABLECAL_CHECK(L.size() == robot.num_cables(), "one unstretched length per cable");
  const Cables cables = CablesOf<A>(robot, L);
  // The starts in order: the guess, home, the least-squares pose (computed only when the
  // first two do not pass: most calls end at the guess).
  const int count = guess ? 3 : 2;
  const auto start_at = [&](int k) -> typename A::PoseD {
    if (guess && k == 0) return *guess;
    return k + 1 < count ? A::Home(robot) : LeastSquaresGuess<A>(robot, L);
  };
  // Reported when no start passes: the first that converged (from the guess, when it did), as
  // its status says most about why the commanded pose cannot be held.
  std::optional<typename A::Result> first_converged;
  typename A::Result last;
  for (int k = 0; k < count; ++k) {
    last = NewtonFrom<A>(robot, cables, L, start_at(k));
    if (last.status != ForwardStatus::kConverged) continue;
    Check<A>(robot, L, guess, last);
    if (last.status == ForwardStatus::kConverged) return last;
    if (!first_converged) first_converged = last;
  }
  return first_converged ? *first_converged : last;
}

template <class A>
Eigen::VectorXd CommandedLengths(const typename A::RobotType& robot, const Eigen::VectorXd& lengths_m,
                                 const Eigen::VectorXd& tensions_N) {
  CABLECAL_CHECK(lengths_m.size() == robot.num_cables() && tensions_N.size() == robot.num_cables(),
                 "one length and one tension per cable");
  Eigen::VectorXd L(robot.num_cables());
  for (int i = 0; i < robot.num_cables(); ++i) {
    L(i) = UnstretchedLength<double>(A::Stiffness(robot, i), lengths_m(i), tensions_N(i));
  }
  return L;
}

template <class A>
void CheckSimulatableKind(const typename A::RobotType& robot, const char* kind) {
  std::vector<int> inextensible;
  for (int i = 0; i < robot.num_cables(); ++i) {
    if (!A::Stiffness(robot, i)) inextensible.push_back(i);
  }
  const int count = static_cast<int>(inextensible.size());
  if (count <= A::kDim) return;
  const int first = inextensible.front();
  throw InputError(robot.source, "cables[" + std::to_string(first) + "].stiffness",
                   std::to_string(count) + " of the " + std::to_string(robot.num_cables()) +
                       " cables have no stiffness (inextensible), more than the " + std::to_string(A::kDim) +
                       " degrees of freedom of a " + kind +
                       " platform: the lengths the controller commands from the nominal model cannot all hold "
                       "on a true robot that differs from it (by as little as rounding), so it cannot be simulated. "
                       "Give E*A (N) of at least " +
                       std::to_string(count - A::kDim) + (count - A::kDim == 1 ? " cable" : " cables") +
                       " (key stiffness; README, \"Any number of cables\")");
}

}  // namespace

ForwardResult SolveForwardStatics(const Robot& robot, const Eigen::VectorXd& unstretched_lengths_m,
                                  const PlanarPose* guess) {
  return Solve<PlanarAdapter>(robot, unstretched_lengths_m, guess);
}

SpatialForwardResult SolveForwardStatics(const SpatialRobot& robot, const Eigen::VectorXd& unstretched_lengths_m,
                                         const SpatialPose<double>* guess) {
  return Solve<SpatialAdapter>(robot, unstretched_lengths_m, guess);
}

Eigen::VectorXd CommandedUnstretchedLengths(const Robot& robot, const Eigen::VectorXd& lengths_m,
                                            const Eigen::VectorXd& tensions_N) {
  return CommandedLengths<PlanarAdapter>(robot, lengths_m, tensions_N);
}

Eigen::VectorXd CommandedUnstretchedLengths(const SpatialRobot& robot, const Eigen::VectorXd& lengths_m,
                                            const Eigen::VectorXd& tensions_N) {
  return CommandedLengths<SpatialAdapter>(robot, lengths_m, tensions_N);
}

Eigen::VectorXd PaidOutLengths(const SpatialRobot& robot, const SpatialEquilibrium& equilibrium) {
  return CommandedUnstretchedLengths(robot, CableLengths<double>(robot, equilibrium.q), equilibrium.tensions_N);
}

void CheckSimulatable(const SpatialRobot& robot) { CheckSimulatableKind<SpatialAdapter>(robot, "spatial"); }

Eigen::VectorXd SnapTensionsToBounds(Eigen::VectorXd tensions_N, double tension_min_N, double tension_max_N) {
  const double tol_N = kTensionRounding * tension_max_N;
  for (double& t : tensions_N) {
    if (std::abs(t - tension_min_N) < tol_N) t = tension_min_N;
    if (std::abs(t - tension_max_N) < tol_N) t = tension_max_N;
  }
  return tensions_N;
}

bool HasStiffness(const Robot& robot) {
  for (const Cable& c : robot.cables) {
    if (c.stiffness_N) return true;
  }
  return false;
}

ForwardResult SettlePlanar(const Robot& robot, const Eigen::VectorXd& unstretched_lengths_m, const PlanarPose* guess) {
  if (HasStiffness(robot)) return SolveForwardStatics(robot, unstretched_lengths_m, guess);
  return SolveForwardGeometricoStatic(robot, unstretched_lengths_m, guess);
}

}  // namespace cablecal
