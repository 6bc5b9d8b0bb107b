#include "model/forward_statics.h"

#include <ceres/jet.h>

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "common/error.h"
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
  static void Normalise(PoseD& q) {
    for (int k = 3; k < 6; ++k) q(k) = std::remainder(q(k), 2.0 * M_PI);
  }
};

// Newton's tolerances: lengths to a few hundred ulps of a 10 m cable; the wrench to 1e-9 of the
// platform's weight, plus the rounding of an elastic tension EA (l / L - 1) (a stiff cable's
// tension is known only to EA times a few ulps of its strain).
constexpr double kLengthTol_m = 1e-11;
constexpr double kRelativeWrenchTol = 1e-9;
constexpr double kStrainRounding = 1e-15;
constexpr int kMaxIterations = 100;
constexpr int kMaxHalvings = 40;

// The cables' roles, fixed for one solve.
template <class A>
struct Cables {
  std::vector<int> inextensible;  // their multipliers are unknowns
  double weight_N = 1.0;
  double wrench_tol_N = 0.0;
  explicit Cables(const typename A::RobotType& robot) {
    double stiffness_sum_N = 0.0;
    for (int i = 0; i < robot.num_cables(); ++i) {
      if (A::Stiffness(robot, i)) {
        stiffness_sum_N += *A::Stiffness(robot, i);
      } else {
        inextensible.push_back(i);
      }
    }
    weight_N = std::max(1e-9, robot.platform_mass_kg * robot.gravity_mps2);
    wrench_tol_N = kRelativeWrenchTol * weight_N + kStrainRounding * stiffness_sum_N;
  }
  int count() const { return static_cast<int>(inextensible.size()); }
};

// The KKT residual at y = (q, t_inextensible): [(W t + w_g) / weight; l_inext - L_inext] (the
// wrench rows in units of the platform's weight, so that the merit function weighs metres and
// newtons alike), its Jacobian (pose columns from Jets, multiplier columns W's), and every
// cable's tension.
template <class A>
bool KktResidual(const typename A::RobotType& robot, const Cables<A>& cables, const Eigen::VectorXd& L,
                 const Eigen::VectorXd& y, Eigen::VectorXd* r, Eigen::MatrixXd* J, Eigen::VectorXd* tensions_N) {
  constexpr int d = A::kDim;
  using Jet = ceres::Jet<double, d>;
  const int m = robot.num_cables(), k = cables.count();
  typename A::template PoseOf<Jet> q;
  for (int c = 0; c < d; ++c) q(c) = Jet(y(c), c);
  const Eigen::Matrix<Jet, Eigen::Dynamic, 1> l = A::template Lengths<Jet>(robot, q);
  const Eigen::Matrix<Jet, d, Eigen::Dynamic> W = A::template Wrench<Jet>(robot, q);
  Eigen::Matrix<Jet, d, 1> f = A::template Gravity<Jet>(robot, q);
  tensions_N->resize(m);
  for (int i = 0, j = 0; i < m; ++i) {
    const std::optional<double>& ea = A::Stiffness(robot, i);
    const Jet t = ea ? ElasticTension<Jet>(*ea, l(i), Jet(L(i))) : Jet(y(d + j++));
    f += W.col(i) * t;
    (*tensions_N)(i) = t.a;
  }
  r->resize(d + k);
  J->setZero(d + k, d + k);
  for (int row = 0; row < d; ++row) {
    (*r)(row) = f(row).a / cables.weight_N;
    J->row(row).head<d>() = f(row).v.transpose() / cables.weight_N;
    for (int j = 0; j < k; ++j) (*J)(row, d + j) = W(row, cables.inextensible[j]).a / cables.weight_N;
  }
  for (int j = 0; j < k; ++j) {
    const int i = cables.inextensible[j];
    (*r)(d + j) = l(i).a - L(i);
    J->row(d + j).head<d>() = l(i).v.transpose();
  }
  return r->allFinite() && J->allFinite();
}

template <class A>
bool Converged(const Cables<A>& cables, const Eigen::VectorXd& r) {
  constexpr int d = A::kDim;
  const double length_residual = cables.count() > 0 ? r.tail(cables.count()).cwiseAbs().maxCoeff() : 0.0;
  return length_residual < kLengthTol_m && r.head<d>().norm() * cables.weight_N < cables.wrench_tol_N;
}

// Damped Newton on the KKT system from one start; the result's status is kConverged or
// kNotConverged (the physical checks are the caller's).
template <class A>
typename A::Result NewtonFrom(const typename A::RobotType& robot, const Cables<A>& cables, const Eigen::VectorXd& L,
                              const typename A::PoseD& start) {
  constexpr int d = A::kDim;
  const int k = cables.count();
  typename A::Result result;
  Eigen::VectorXd y(d + k), r, tensions;
  Eigen::MatrixXd J;
  y.head<d>() = start;
  y.tail(k).setZero();
  // The multipliers that balance the platform best at the start, the elastic cables as they are.
  if (k > 0) {
    if (!KktResidual<A>(robot, cables, L, y, &r, &J, &tensions)) return result;
    y.tail(k) = J.topRightCorner(d, k).colPivHouseholderQr().solve(-r.head<d>());
  }
  if (!KktResidual<A>(robot, cables, L, y, &r, &J, &tensions)) return result;
  for (int it = 0; it < kMaxIterations; ++it) {
    result.iterations = it;
    if (Converged<A>(cables, r)) {
      result.status = ForwardStatus::kConverged;
      break;
    }
    const Eigen::VectorXd step = J.colPivHouseholderQr().solve(-r);
    if (!step.allFinite()) break;
    // Backtracking on |r|^2 keeps Newton on the branch it started on.
    double lambda = 1.0;
    Eigen::VectorXd y_new, r_new, t_new;
    Eigen::MatrixXd J_new;
    bool descent = false;
    for (int ls = 0; ls < kMaxHalvings && !descent; ++ls, lambda *= 0.5) {
      y_new = y + lambda * step;
      descent = KktResidual<A>(robot, cables, L, y_new, &r_new, &J_new, &t_new) && r_new.squaredNorm() < r.squaredNorm();
    }
    if (!descent) break;
    y = y_new;
    r = r_new;
    J = J_new;
    tensions = t_new;
  }
  typename A::PoseD q = y.head<d>();
  A::Normalise(q);
  result.equilibrium.q = q;
  result.equilibrium.tensions_N = tensions;
  result.equilibrium.residual_N = r.head<d>().norm() * cables.weight_N;
  result.equilibrium.reduced_stiffness = std::numeric_limits<double>::quiet_NaN();
  result.equilibrium.stable = false;
  result.length_residual_m = k > 0 ? r.tail(k).cwiseAbs().maxCoeff() : 0.0;
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
  const Cables<A> cables(robot);
  std::vector<typename A::PoseD> starts;
  if (guess) starts.push_back(*guess);
  starts.push_back(A::Home(robot));
  starts.push_back(LeastSquaresGuess<A>(robot, L));
  // Reported when no start passes: the first that converged (from the guess, when it did), as
  // its status says most about why the commanded pose cannot be held.
  std::optional<typename A::Result> first_converged;
  typename A::Result last;
  for (const typename A::PoseD& start : starts) {
    last = NewtonFrom<A>(robot, cables, L, start);
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
  const Cables<A> cables(robot);
  if (cables.count() <= A::kDim) return;
  const int first = cables.inextensible.front();
  throw InputError(robot.source, "cables[" + std::to_string(first) + "].stiffness",
                   std::to_string(cables.count()) + " of the " + std::to_string(robot.num_cables()) +
                       " cables have no stiffness (inextensible), more than the " + std::to_string(A::kDim) +
                       " degrees of freedom of a " + kind +
                       " platform: the lengths the controller commands from the nominal model cannot all hold "
                       "on a true robot that differs from it, so it cannot be simulated. Give E*A (N) of at least " +
                       std::to_string(cables.count() - A::kDim) +
                       " cables (key stiffness; README, \"Any number of cables\")");
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

void CheckSimulatable(const Robot& robot) { CheckSimulatableKind<PlanarAdapter>(robot, "planar"); }
void CheckSimulatable(const SpatialRobot& robot) { CheckSimulatableKind<SpatialAdapter>(robot, "spatial"); }

bool HasStiffness(const Robot& robot) {
  for (const Cable& c : robot.cables) {
    if (c.stiffness_N) return true;
  }
  return false;
}

ForwardResult SettlePlanar(const Robot& robot, const Eigen::VectorXd& unstretched_lengths_m, const PlanarPose* guess) {
  if (HasStiffness(robot)) return SolveForwardStatics(robot, unstretched_lengths_m, guess);
  CABLECAL_CHECK(robot.num_cables() <= PlanarKind::kPoseDim,
                 "a planar robot with more than 3 inextensible cables cannot be simulated (CheckSimulatable)");
  return SolveForwardGeometricoStatic(robot, unstretched_lengths_m, guess);
}

}  // namespace cablecal
