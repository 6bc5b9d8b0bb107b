#include "design/spatial_design.h"

#include <IpIpoptApplication.hpp>
#include <IpSolveStatistics.hpp>
#include <IpTNLP.hpp>
#include <ceres/jet.h>
#include <yaml-cpp/yaml.h>

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <functional>
#include <limits>
#include <optional>

#include "common/error.h"
#include "common/format.h"
#include "common/parallel.h"
#include "common/random.h"
#include "common/version.h"
#include "common/yaml_writer.h"
#include "design/ipopt_nlp.h"
#include "design/robustness_search.h"
#include "design/solve_process.h"
#include "model/forward_statics.h"
#include "model/spatial_statics.h"
#include "model/swivel.h"

namespace cablecal {

namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;
using Ipopt::Index;
using Ipopt::Number;

// The condition-number and E criteria are minimised through a smooth surrogate of this
// sharpness on S's eigenvalues (32 on the Jacobian's singular values, as planar).
constexpr double kSpatialSurrogatePower = 16.0;
// Bounds tightened so that poses re-solved exactly by the model still hold the exact bounds.
// Ipopt relaxes every bound by 1e-8 of its size (bound_relax_factor): a tension bound of 5000 N
// by 5e-5 N.
constexpr double kMargin_m = 1e-6, kMargin_rad = 1e-6;
// And a pose re-solved by the model comes back with tensions off Ipopt's (3e-5 N on irma4u,
// 1.5e-4 N on a random 6-cable robot whose bounds span 2000 N: Ipopt's equilibrium rows hold
// to its tolerance, not exactly): a thousandth of the tension range.
double TensionMargin(const SpatialRobot& robot) { return 1e-4 + 1e-3 * (robot.tension_max_N - robot.tension_min_N); }
// A re-solved pose is the same as Ipopt's within this (m, rad).
constexpr double kSamePose = 1e-6;
constexpr double kEquilibriumTolerance = 1e-6;  // of the weight
double Weight(const SpatialRobot& robot) { return robot.platform_mass_kg * robot.gravity_mps2; }
// A solve also ends when its criterion has stalled (README, "Spatial robots", "Experiment
// design"): no iterate in the last kStallIterations lowered the best clean one's criterion by
// kStallChange (the criteria are logarithms: a relative change of the trace, determinant or
// condition number), the best clean iterate then the solve's poses. Measured on cogiro, 30 poses:
// Ipopt's first solve takes 448 iterations to its tolerance, the last third on an infeasibility
// that the verification's projection removes anyway; the rule ends it after 262, its criterion
// 6e-5 above (1e-5 and 30 iterations: after 288, the same iterate).
constexpr double kStallChange = 1e-4;
constexpr int kStallIterations = 20;
// Clean: every bound kept (the NLP's, with its margins) and the equilibrium rows within this
// fraction of the weight: with 6 or more cables the verification projects the tensions onto the
// equilibrium (a shift of newtons at most against the thousandth of the tension range
// TensionMargin keeps), with fewer it re-solves the pose, which must not move by kSamePose.
constexpr double kCleanEquilibriumProjected = 1e-4, kCleanEquilibriumResolved = 1e-9;

constexpr std::uint64_t kStartStream = 1, kRandomSetStream = 2, kGaugeStream = 3;
// The platform's uncertain values a scenario robot moves: the mass and the centre of mass's 3
// coordinates (SpatialPlatformPriorSigma), after the 3m exit coordinates.
constexpr int kPlatformScenarioValues = 4;

// The NLP's variables per pose: q then t; Jets of the largest robot's.
constexpr int kMaxV = 6 + kMaxSpatialCables;
using Jet = ceres::Jet<double, kMaxV>;

// Pose rows: 6 equilibrium, cos(tilt), centre of mass and anchors (3 each) in the box, each
// anchor's clearance from its pulley.
int PoseRowCount(int m) { return 6 + 1 + 3 * (m + 1) + m; }

template <typename T>
bool PoseRows(const SpatialRobot& robot, const T* y, T* out) {
  const int m = robot.num_cables();
  SpatialPose<T> q;
  for (int a = 0; a < 6; ++a) q(a) = y[a];
  Eigen::Matrix<T, Eigen::Dynamic, 1> t(m);
  for (int i = 0; i < m; ++i) t(i) = y[6 + i];
  const Eigen::Matrix<T, 3, 3> R = Rotation<T>(q);
  Eigen::Matrix<T, 6, 1> w = GravityWrench<T>(robot, q);
  int r = 6;
  out[r++] = R(2, 2);
  const Vec3<T> com = AnchorInF<T>(q, R, robot.p_P_com_m.cast<T>());
  for (int a = 0; a < 3; ++a) out[r++] = com(a);
  for (int i = 0; i < m; ++i) {
    const SpatialCable& c = robot.cables[i];
    const Vec3<T> B = AnchorInF<T>(q, R, c.p_P_anchor_m.cast<T>());
    for (int a = 0; a < 3; ++a) out[r++] = B(a);
    const SwivelCableState<T> s = SwivelCable<T>(c.p_F_exit_m.cast<T>(), c.k_F_swivel_axis.cast<T>(),
                                                 T(c.pulley_radius_m), B);
    if (!s.valid()) return false;
    w += t(i) * WrenchColumn<T>(R * c.p_P_anchor_m.cast<T>(), s);
  }
  for (int i = 0; i < m; ++i) {
    const SpatialCable& c = robot.cables[i];
    const Vec3<T> B = AnchorInF<T>(q, R, c.p_P_anchor_m.cast<T>());
    const SwivelCableState<T> s = SwivelCable<T>(c.p_F_exit_m.cast<T>(), c.k_F_swivel_axis.cast<T>(),
                                                 T(c.pulley_radius_m), B);
    out[r++] = (B - s.p_F_centre_m).norm() - T(c.pulley_radius_m);
  }
  for (int a = 0; a < 6; ++a) out[a] = w(a);
  return true;
}

// The names of a pose's bounded quantities, in the order of its variables (q, t) and its rows
// (PoseRows; the 6 equilibrium rows are not bounds and have no name).
struct PoseQuantityNames {
  std::vector<std::string> x, g;
};
PoseQuantityNames QuantityNames(int m) {
  PoseQuantityNames n;
  n.x = {"x", "y", "z", "roll", "pitch", "yaw"};
  for (int i = 0; i < m; ++i) n.x.push_back("t" + std::to_string(i + 1));
  n.g.assign(6, "");
  n.g.push_back("tilt");
  const char* axes[3] = {" x", " y", " z"};
  for (int a = 0; a < 3; ++a) n.g.push_back(std::string("centre of mass") + axes[a]);
  for (int i = 0; i < m; ++i) {
    for (int a = 0; a < 3; ++a) n.g.push_back("anchor " + std::to_string(i + 1) + axes[a]);
  }
  for (int i = 0; i < m; ++i) n.g.push_back("clearance " + std::to_string(i + 1));
  return n;
}

// The bounds a pose's variables (q, t) and rows (PoseRows) keep on the robot file's limits.
struct PoseBounds {
  VectorXd x_lo, x_hi, g_lo, g_hi;
};
PoseBounds ExactPoseBounds(const SpatialRobot& robot) {
  const int m = robot.num_cables();
  const double inf = std::numeric_limits<double>::infinity();
  PoseBounds b;
  b.x_lo = VectorXd::Constant(6 + m, -inf);
  b.x_hi = VectorXd::Constant(6 + m, inf);
  b.g_lo = VectorXd::Constant(PoseRowCount(m), -inf);
  b.g_hi = VectorXd::Constant(PoseRowCount(m), inf);
  const Eigen::Vector3d lo = robot.p_F_frame_min_m.array() + robot.margin_m;
  const Eigen::Vector3d hi = robot.p_F_frame_max_m.array() - robot.margin_m;
  b.x_lo.head<3>() = lo;
  b.x_hi.head<3>() = hi;
  b.x_lo.segment<2>(3).setConstant(-robot.tilt_max_rad);
  b.x_hi.segment<2>(3).setConstant(robot.tilt_max_rad);
  b.x_lo(5) = robot.home_rpy_rad.z() - kDefaultSampleYawRange_rad;
  b.x_hi(5) = robot.home_rpy_rad.z() + kDefaultSampleYawRange_rad;
  b.x_lo.tail(m).setConstant(robot.tension_min_N);
  b.x_hi.tail(m).setConstant(robot.tension_max_N);
  b.g_lo.head<6>().setZero();
  b.g_hi.head<6>().setZero();
  b.g_lo(6) = std::cos(robot.tilt_max_rad);
  for (int k = 0; k < m + 1; ++k) {
    b.g_lo.segment<3>(7 + 3 * k) = lo;
    b.g_hi.segment<3>(7 + 3 * k) = hi;
  }
  b.g_lo.tail(m).setConstant(robot.margin_m);
  return b;
}

// How far each of a pose's bounds is drawn in for robustness (units of the quantity).
struct PoseTightening {
  VectorXd x, g;
};

// Bounds drawn in by t; bounds that would cross meet in the middle (the NLP is then infeasible
// there, which the robustness search reads as no design at this robustness).
void DrawIn(double t, double* lo, double* hi) {
  constexpr double kInfinite = 1e19;
  const bool lo_finite = *lo > -kInfinite, hi_finite = *hi < kInfinite;
  if (lo_finite) *lo += t;
  if (hi_finite) *hi -= t;
  if (lo_finite && hi_finite && *lo > *hi) *lo = *hi = 0.5 * (*lo + *hi);
}

class SpatialDesignNlp : public Ipopt::TNLP {
 public:
  SpatialDesignNlp(const SpatialRobot& robot, const SpatialInformationLayout& layout,
                   const SpatialDesignOptions& options, const std::vector<SpatialPlanPose>& start,
                   const std::vector<PoseTightening>* tightening,
                   std::function<bool(const std::vector<SpatialPlanPose>&)> holds)
      : robot_(robot), layout_(layout), options_(options), start_(start), tightening_(tightening), holds_(std::move(holds)),
        n_(static_cast<int>(start.size())), m_(robot.num_cables()), V(6 + m_), C(PoseRowCount(m_)) {}

  int NumPairs() const { return options_.min_spacing_m > 0.0 ? n_ * (n_ - 1) / 2 : 0; }
  // The squared distance of the k-th pair of reference points (pairs (0, 1), (0, 2), ..., (1, 2), ...).
  double PairDistance2(const Number* x, int k) const {
    int a = 0;
    while (k >= n_ - 1 - a) k -= n_ - 1 - a++;
    const int b = a + 1 + k;
    double d2 = 0.0;
    for (int c = 0; c < 3; ++c) d2 += (x[V * a + c] - x[V * b + c]) * (x[V * a + c] - x[V * b + c]);
    return d2;
  }

  bool get_nlp_info(Index& n, Index& m, Index& nnz_jac_g, Index& nnz_h_lag, IndexStyleEnum& style) override {
    n = V * n_;
    m = C * n_ + NumPairs();
    nnz_jac_g = n_ * C * V + NumPairs() * 6;
    nnz_h_lag = 0;
    style = C_STYLE;
    return true;
  }

  // The robot file's limits (ExactPoseBounds) drawn in by the NLP's own margins, then by the
  // robustness tightening if any.
  bool get_bounds_info(Index, Number* x_l, Number* x_u, Index, Number* g_l, Number* g_u) override {
    constexpr double kInf = 2e19;
    const PoseBounds exact = ExactPoseBounds(robot_);
    VectorXd x_margin(V), g_margin = VectorXd::Constant(C, kMargin_m);
    x_margin << Eigen::Vector3d::Constant(kMargin_m), Eigen::Vector3d::Constant(kMargin_rad),
        VectorXd::Constant(m_, TensionMargin(robot_));
    g_margin.head<6>().setZero();
    const auto bound = [](double exact_bound, double finite_value, double infinite_value) {
      return std::isfinite(exact_bound) ? finite_value : infinite_value;
    };
    for (int j = 0; j < n_; ++j) {
      Number* xl = x_l + V * j;
      Number* xu = x_u + V * j;
      for (int c = 0; c < V; ++c) {
        xl[c] = bound(exact.x_lo(c), exact.x_lo(c) + x_margin(c), -kInf);
        xu[c] = bound(exact.x_hi(c), exact.x_hi(c) - x_margin(c), kInf);
      }
      Number* gl = g_l + C * j;
      Number* gu = g_u + C * j;
      for (int r = 0; r < C; ++r) {
        gl[r] = bound(exact.g_lo(r), exact.g_lo(r) + g_margin(r), -kInf);
        gu[r] = bound(exact.g_hi(r), exact.g_hi(r) - g_margin(r), kInf);
      }
      gl[6] = std::cos(robot_.tilt_max_rad - kMargin_rad);  // the tilt's margin is on its angle
      if (tightening_ == nullptr) continue;
      const PoseTightening& t = (*tightening_)[j];
      for (int c = 0; c < V; ++c) DrawIn(t.x(c), xl + c, xu + c);
      for (int r = 6; r < C; ++r) DrawIn(t.g(r), gl + r, gu + r);
    }
    const double d = options_.min_spacing_m + kMargin_m;
    for (int k = 0; k < NumPairs(); ++k) {
      g_l[C * n_ + k] = d * d;
      g_u[C * n_ + k] = kInf;
    }
    return true;
  }

  bool get_starting_point(Index, bool init_x, Number* x, bool init_z, Number*, Number*, Index, bool init_lambda,
                          Number*) override {
    if (!init_x || init_z || init_lambda) return false;
    for (int j = 0; j < n_; ++j) {
      for (int a = 0; a < 6; ++a) x[V * j + a] = start_[j].q(a);
      for (int i = 0; i < m_; ++i) x[V * j + 6 + i] = start_[j].tensions_N(i);
    }
    return true;
  }

  bool eval_f(Index, const Number* x, bool, Number& f) override {
    f = SpatialDesignObjective(robot_, layout_, options_.criterion, Poses(x), nullptr, Power());
    return std::isfinite(f);
  }

  // Ipopt evaluates the gradient and the constraints' Jacobian at each accepted iterate: their
  // point and values are kept for the stall rule (intermediate_callback).
  bool eval_grad_f(Index n, const Number* x, bool, Number* grad) override {
    VectorXd g;
    const double f = SpatialDesignObjective(robot_, layout_, options_.criterion, Poses(x), &g, Power());
    if (!std::isfinite(f)) return false;
    std::copy(g.data(), g.data() + n, grad);
    gradient_x_.assign(x, x + n);
    gradient_f_ = f;
    return true;
  }

  bool eval_g(Index, const Number* x, bool, Index, Number* g) override {
    std::vector<double> out(C);
    for (int j = 0; j < n_; ++j) {
      if (!PoseRows<double>(robot_, x + V * j, g + C * j)) return false;
    }
    for (int k = 0; k < NumPairs(); ++k) g[C * n_ + k] = PairDistance2(x, k);
    return true;
  }

  bool eval_jac_g(Index, const Number* x, bool, Index, Index, Index* iRow, Index* jCol, Number* values) override {
    int e = 0;
    if (values == nullptr) {
      for (int j = 0; j < n_; ++j) {
        for (int r = 0; r < C; ++r) {
          for (int c = 0; c < V; ++c, ++e) {
            iRow[e] = C * j + r;
            jCol[e] = V * j + c;
          }
        }
      }
      int k = 0;
      for (int a = 0; a < n_ && NumPairs() > 0; ++a) {
        for (int b = a + 1; b < n_; ++b, ++k) {
          for (int c = 0; c < 3; ++c) {
            iRow[e] = C * n_ + k;
            jCol[e++] = V * a + c;
            iRow[e] = C * n_ + k;
            jCol[e++] = V * b + c;
          }
        }
      }
      return true;
    }
    std::vector<Jet> y(V), out(C);
    jacobian_x_.clear();
    jacobian_g_.resize(C * n_);
    for (int j = 0; j < n_; ++j) {
      for (int c = 0; c < V; ++c) y[c] = Jet(x[V * j + c], c);
      if (!PoseRows<Jet>(robot_, y.data(), out.data())) return false;
      for (int r = 0; r < C; ++r) {
        jacobian_g_[C * j + r] = out[r].a;
        for (int c = 0; c < V; ++c) values[e++] = out[r].v[c];
      }
    }
    jacobian_x_.assign(x, x + V * n_);
    for (int a = 0; a < n_ && NumPairs() > 0; ++a) {
      for (int b = a + 1; b < n_; ++b) {
        for (int c = 0; c < 3; ++c) {
          const double d = x[V * a + c] - x[V * b + c];
          values[e++] = 2 * d;
          values[e++] = -2 * d;
        }
      }
    }
    return true;
  }

  // Tensions and equilibrium rows in units of the weight, so that every variable and row is
  // of order one.
  bool get_scaling_parameters(Number& obj_scaling, bool& use_x_scaling, Index n, Number* x_scaling,
                              bool& use_g_scaling, Index m, Number* g_scaling) override {
    const double weight_N = robot_.platform_mass_kg * robot_.gravity_mps2;
    obj_scaling = 1.0;
    use_x_scaling = true;
    for (Index k = 0; k < n; ++k) x_scaling[k] = (k % V >= 6) ? 1.0 / weight_N : 1.0;
    use_g_scaling = true;
    for (Index k = 0; k < m; ++k) g_scaling[k] = 1.0;
    for (int j = 0; j < n_; ++j) {
      for (int r = 0; r < 6; ++r) g_scaling[C * j + r] = 1.0 / weight_N;
    }
    return true;
  }

  // The stall rule (kStallChange): ends the solve, its poses the best clean iterate's.
  bool intermediate_callback(Ipopt::AlgorithmMode mode, Index iteration, Number objective, Number, Number, Number,
                             Number, Number, Number, Number, Index, const Ipopt::IpoptData*,
                             Ipopt::IpoptCalculatedQuantities*) override {
    if (options_.interrupted && options_.interrupted->load()) return false;
    if (!options_.stop_when_stalled || mode != Ipopt::RegularMode) return true;
    if (objective < best_f_ - kStallChange) last_progress_ = iteration;
    // The kept values are this iterate's when the gradient's value is the objective Ipopt reports.
    const bool known = !gradient_x_.empty() && gradient_x_ == jacobian_x_ &&
                       std::abs(gradient_f_ - objective) <= 1e-12 * (1.0 + std::abs(objective));
    if (known && gradient_f_ < best_f_ && Clean()) {
      if (gradient_f_ < best_f_ - kStallChange) last_progress_ = iteration;
      best_f_ = gradient_f_;
      best_x_ = gradient_x_;
    }
    if (std::isfinite(best_f_) && iteration - last_progress_ >= kStallIterations) {
      stalled_ = true;
      return false;
    }
    return true;
  }

  void finalize_solution(Ipopt::SolverReturn, Index, const Number* x, const Number*, const Number*, Index,
                         const Number*, const Number*, Number, const Ipopt::IpoptData*,
                         Ipopt::IpoptCalculatedQuantities*) override {
    final_ = Poses(stalled_ ? best_x_.data() : x);
  }
  const std::vector<SpatialPlanPose>& final_poses() const { return final_; }
  bool stalled() const { return stalled_; }

 private:
  // Whether the kept iterate (jacobian_x_, jacobian_g_) is clean: its equilibrium rows within the
  // clean tolerance and every bound kept within the NLP's margins (cheap), then its poses verified.
  bool Clean() {
    const int rows = C * n_ + NumPairs(), vars = V * n_;
    if (bounds_x_l_.empty()) {
      bounds_x_l_.resize(vars);
      bounds_x_u_.resize(vars);
      bounds_g_l_.resize(rows);
      bounds_g_u_.resize(rows);
      get_bounds_info(vars, bounds_x_l_.data(), bounds_x_u_.data(), rows, bounds_g_l_.data(), bounds_g_u_.data());
    }
    for (int k = 0; k < vars; ++k) {
      if (jacobian_x_[k] < bounds_x_l_[k] - kMargin_m || jacobian_x_[k] > bounds_x_u_[k] + kMargin_m) return false;
    }
    const double equilibrium = Weight(robot_) * (m_ >= 6 ? kCleanEquilibriumProjected : kCleanEquilibriumResolved);
    for (int j = 0; j < n_; ++j) {
      for (int r = 0; r < C; ++r) {
        const double g = jacobian_g_[C * j + r];
        if (r < 6 ? std::abs(g) > equilibrium : g < bounds_g_l_[C * j + r] - kMargin_m || g > bounds_g_u_[C * j + r] + kMargin_m) {
          return false;
        }
      }
    }
    for (int k = 0; k < NumPairs(); ++k) {
      if (PairDistance2(jacobian_x_.data(), k) < bounds_g_l_[C * n_ + k]) return false;
    }
    return holds_(Poses(jacobian_x_.data()));
  }

  double Power() const {
    return options_.criterion == Criterion::kCondition || options_.criterion == Criterion::kE ? kSpatialSurrogatePower
                                                                                            : 0.0;
  }
  std::vector<SpatialPlanPose> Poses(const Number* x) const {
    std::vector<SpatialPlanPose> p(n_);
    for (int j = 0; j < n_; ++j) {
      p[j].q = Eigen::Map<const SpatialPose<double>>(x + V * j);
      p[j].tensions_N = Eigen::Map<const VectorXd>(x + V * j + 6, m_);
    }
    return p;
  }

  const SpatialRobot& robot_;
  const SpatialInformationLayout& layout_;
  const SpatialDesignOptions& options_;
  const std::vector<SpatialPlanPose>& start_;
  const std::vector<PoseTightening>* tightening_;  // nullptr: none
  const std::function<bool(const std::vector<SpatialPlanPose>&)> holds_;  // the verification passes
  const int n_, m_, V, C;
  std::vector<SpatialPlanPose> final_;
  // The stall rule's state: the last gradient's and Jacobian's points and values, the best clean iterate.
  std::vector<double> gradient_x_, jacobian_x_, jacobian_g_, best_x_;
  double gradient_f_ = 0.0, best_f_ = std::numeric_limits<double>::infinity();
  std::vector<double> bounds_x_l_, bounds_x_u_, bounds_g_l_, bounds_g_u_;
  int last_progress_ = 0;
  bool stalled_ = false;
};

struct Outcome {
  std::string status;
  int iterations = 0;
  bool converged = false;
  std::vector<SpatialPlanPose> poses;
};

const char* StatusName(Ipopt::ApplicationReturnStatus s) {
  switch (s) {
    case Ipopt::Solve_Succeeded: return "Solve_Succeeded";
    case Ipopt::Solved_To_Acceptable_Level: return "Solved_To_Acceptable_Level";
    case Ipopt::Infeasible_Problem_Detected: return "Infeasible_Problem_Detected";
    case Ipopt::Search_Direction_Becomes_Too_Small: return "Search_Direction_Becomes_Too_Small";
    case Ipopt::Diverging_Iterates: return "Diverging_Iterates";
    case Ipopt::User_Requested_Stop: return "User_Requested_Stop";
    case Ipopt::Maximum_Iterations_Exceeded: return "Maximum_Iterations_Exceeded";
    case Ipopt::Restoration_Failed: return "Restoration_Failed";
    case Ipopt::Error_In_Step_Computation: return "Error_In_Step_Computation";
    case Ipopt::Invalid_Number_Detected: return "Invalid_Number_Detected";
    default: return "Ipopt_Error";
  }
}

std::string Verify(const SpatialRobot& robot, const SpatialInformationLayout& layout,
                   const SpatialDesignOptions& options, const std::vector<SpatialPlanPose>& ipopt,
                   const SpatialHomeReference& home, std::vector<SpatialPlanPose>* verified);

Outcome SolveNlp(const SpatialRobot& robot, const SpatialInformationLayout& layout, const SpatialDesignOptions& options,
                 const SpatialHomeReference& home, const std::vector<SpatialPlanPose>& start,
                 const std::vector<PoseTightening>* tightening) {
  const auto holds = [&](const std::vector<SpatialPlanPose>& poses) {
    std::vector<SpatialPlanPose> verified;
    return Verify(robot, layout, options, poses, home, &verified).empty();
  };
  Ipopt::SmartPtr<SpatialDesignNlp> nlp = new SpatialDesignNlp(robot, layout, options, start, tightening, holds);
  Ipopt::SmartPtr<Ipopt::IpoptApplication> app = IpoptApplicationFactory();
  // The planar design's settings (design/ipopt_nlp.cc says why each).
  app->Options()->SetStringValue("hessian_approximation", "limited-memory");
  // A longer memory than planar's 6: with 6 the spatial problems (14 variables per pose on cogiro)
  // ran into the iteration cap with the equilibrium rows violated by newtons.
  app->Options()->SetIntegerValue("limited_memory_max_history", 20);
  app->Options()->SetStringValue("limited_memory_aug_solver", "extended");
  app->Options()->SetIntegerValue("max_iter", options.max_iterations);
  app->Options()->SetNumericValue("tol", 1e-6);
  app->Options()->SetNumericValue("constr_viol_tol", 1e-9);
  app->Options()->SetNumericValue("acceptable_tol", 1e-3);
  app->Options()->SetIntegerValue("acceptable_iter", 15);
  app->Options()->SetNumericValue("acceptable_constr_viol_tol", 1e-9);
  app->Options()->SetNumericValue("acceptable_compl_inf_tol", 1e-3);
  app->Options()->SetNumericValue("acceptable_obj_change_tol", 1e-6);
  app->Options()->SetStringValue("mu_strategy", "adaptive");
  app->Options()->SetStringValue("nlp_scaling_method", "user-scaling");
  app->Options()->SetStringValue("sb", "yes");
  app->Options()->SetIntegerValue("print_level", 0);
  if (tightening != nullptr) {
    // A re-solve starts from verified poses near the optimum: a small barrier parameter and
    // bound push keep Ipopt from first pushing them far into the interior.
    app->Options()->SetNumericValue("mu_init", 1e-4);
    app->Options()->SetNumericValue("bound_push", 1e-6);
    app->Options()->SetNumericValue("bound_frac", 1e-6);
  }
  Outcome out;
  if (!internal::InitializeIpopt(*app)) {
    out.status = "Invalid_Option";
    return out;
  }
  const Ipopt::ApplicationReturnStatus status = app->OptimizeTNLP(nlp);
  out.status = StatusName(status);
  out.converged = status == Ipopt::Solve_Succeeded || status == Ipopt::Solved_To_Acceptable_Level;
  if (status == Ipopt::User_Requested_Stop && nlp->stalled()) {
    out.status = "Criterion_Stalled";
    out.converged = true;
  }
  if (Ipopt::IsValid(app->Statistics())) out.iterations = app->Statistics()->IterationCount();
  out.poses = nlp->final_poses();
  return out;
}

// An outcome through a child process's pipe (design/solve_process.h).
std::string Encode(const Outcome& o) {
  internal::ByteWriter w;
  w.PutString(o.status);
  w.Put(static_cast<std::int32_t>(o.iterations));
  w.Put(static_cast<std::int32_t>(o.converged));
  w.Put(static_cast<std::int64_t>(o.poses.size()));
  for (const SpatialPlanPose& p : o.poses) {
    for (int a = 0; a < 6; ++a) w.Put(p.q(a));
    w.Put(static_cast<std::int64_t>(p.tensions_N.size()));
    for (Eigen::Index i = 0; i < p.tensions_N.size(); ++i) w.Put(p.tensions_N(i));
  }
  return w.bytes;
}

Outcome Decode(const std::string& bytes) {
  internal::ByteReader r{bytes};
  Outcome o;
  o.status = r.GetString();
  o.iterations = r.Get<std::int32_t>();
  o.converged = r.Get<std::int32_t>() != 0;
  o.poses.resize(static_cast<std::size_t>(r.Get<std::int64_t>()));
  for (SpatialPlanPose& p : o.poses) {
    for (int a = 0; a < 6; ++a) p.q(a) = r.Get<double>();
    p.tensions_N.resize(r.Get<std::int64_t>());
    for (Eigen::Index i = 0; i < p.tensions_N.size(); ++i) p.tensions_N(i) = r.Get<double>();
  }
  return o;
}

// SolveNlp in a child process of its own when asked and one can be had (the starts then solve
// at once, the outcome the same bit for bit), else in this process, one solve at a time
// (Debian's MUMPS is not thread-safe; the planar design's solves take the same turns).
Outcome SolveNlpSomewhere(const SpatialRobot& robot, const SpatialInformationLayout& layout,
                          const SpatialDesignOptions& options, const SpatialHomeReference& home,
                          const std::vector<SpatialPlanPose>& start,
                          const std::vector<PoseTightening>* tightening = nullptr) {
  if (options.solve_in_child_processes) {
    const std::optional<std::string> bytes = internal::RunInChildProcess(
        [&] { return Encode(SolveNlp(robot, layout, options, home, start, tightening)); }, options.interrupted);
    if (bytes) return Decode(*bytes);
  }
  Outcome outcome;
  std::exception_ptr solve_error;  // an exception must not leave the critical section
#pragma omp critical(cablecal_ipopt)
  {
    try {
      outcome = SolveNlp(robot, layout, options, home, start, tightening);
    } catch (...) {
      solve_error = std::current_exception();
    }
  }
  if (solve_error) std::rethrow_exception(solve_error);
  return outcome;
}


// The file comment's verification; "" when every pose holds, else the first failure.
std::string Verify(const SpatialRobot& robot, const SpatialInformationLayout& layout,
                   const SpatialDesignOptions& options, const std::vector<SpatialPlanPose>& ipopt,
                   const SpatialHomeReference& home, std::vector<SpatialPlanPose>* verified) {
  verified->clear();
  const int m = robot.num_cables();
  for (std::size_t j = 0; j < ipopt.size(); ++j) {
    const std::string pose = "pose " + std::to_string(j + 1) + ": ";
    SpatialEquilibrium eq;
    if (m < 6) {
      const SpatialEquilibriumResult r = SolveSpatialEquilibrium(robot, ipopt[j].q);
      if (r.status != EquilibriumStatus::kFound) return pose + "no stable equilibrium at Ipopt's pose";
      if ((r.equilibrium.q - ipopt[j].q).cwiseAbs().maxCoeff() > kSamePose) {
        return pose + "the model's stable equilibrium is not Ipopt's pose";
      }
      eq = r.equilibrium;
    } else if (!layout.tensions) {
      const SpatialPoseEvaluation e = EvaluateSpatialPose(robot, ipopt[j].q);
      if (!e.has_equilibrium) return pose + "no tension distribution holds Ipopt's pose (" + ToString(e.feasibility) + ")";
      eq = e.equilibrium;
    } else {
      const MatrixXd W = WrenchMatrix<double>(robot, ipopt[j].q);
      const VectorXd residual = EquilibriumResidual<double>(robot, ipopt[j].q, VectorXd(ipopt[j].tensions_N));
      eq.q = ipopt[j].q;
      eq.tensions_N = ipopt[j].tensions_N - W.completeOrthogonalDecomposition().solve(residual);
      eq.residual_N = EquilibriumResidual<double>(robot, eq.q, VectorXd(eq.tensions_N)).norm();
    }
    if (!(eq.residual_N < kEquilibriumTolerance * Weight(robot))) return pose + "equilibrium residual too large";
    int cable = -1;
    const Feasibility f = CheckSpatialFeasibility(robot, eq.q, eq.tensions_N, &cable);
    if (f != Feasibility::kFeasible) {
      char detail[160];
      std::snprintf(detail, sizeof(detail), " (tensions %.9g .. %.9g N, Ipopt's %.9g .. %.9g N)", eq.tensions_N.minCoeff(),
                    eq.tensions_N.maxCoeff(), ipopt[j].tensions_N.minCoeff(), ipopt[j].tensions_N.maxCoeff());
      return pose + ToString(f) + (cable >= 0 ? " (cable " + std::to_string(cable + 1) + ")" : "") +
             (f == Feasibility::kTensionLow || f == Feasibility::kTensionHigh ? detail : "");
    }
    verified->push_back(MakeSpatialPlanPose(robot, eq, home));
  }
  for (std::size_t a = 0; a < verified->size(); ++a) {
    for (std::size_t b = a + 1; b < verified->size(); ++b) {
      if (((*verified)[a].q.head<3>() - (*verified)[b].q.head<3>()).norm() < options.min_spacing_m) {
        return "poses " + std::to_string(a + 1) + " and " + std::to_string(b + 1) + " closer than --min-spacing";
      }
    }
  }
  return "";
}

// A settled state's bounded quantities: its variables (q, t) and its rows (PoseRows). False
// where the cable geometry is invalid.
bool StateQuantities(const SpatialRobot& robot, const SpatialPose<double>& q, const VectorXd& t, VectorXd* x,
                     VectorXd* g) {
  const int m = robot.num_cables();
  x->resize(6 + m);
  *x << q, t;
  g->resize(PoseRowCount(m));
  return PoseRows<double>(robot, x->data(), g->data());
}

// The file comment's scenario check of verified poses at half-width k_sigma (m).
struct ScenarioCheck {
  std::string failure;        // the first failure, "" when every pose holds on every scenario robot
  std::vector<bool> failing;  // per pose
  // Per pose: sqrt(sum over the exit coordinates and the platform's 4 values ((c+ - c-) / 2)^2),
  // k |dc/dg|_2 over the whitened uncertain values to first order.
  std::vector<PoseTightening> spread;
};

bool Stretches(const SpatialRobot& robot) {
  return std::any_of(robot.cables.begin(), robot.cables.end(),
                     [](const SpatialCable& c) { return c.stiffness_N.has_value(); });
}

ScenarioCheck CheckScenarios(const SpatialRobot& robot, const std::vector<SpatialPlanPose>& plan, double k_sigma,
                             double robust_sigmas, const SpatialHomeReference& home) {
  const int m = robot.num_cables(), n = static_cast<int>(plan.size());
  const int V = 6 + m, C = PoseRowCount(m);
  const char* axes[3] = {"x", "y", "z"};
  ScenarioCheck out;
  out.failing.assign(n, false);
  out.spread.assign(n, PoseTightening{VectorXd::Zero(V), VectorXd::Zero(C)});
  // (parameter, sign): -1 the nominal robot (only when a cable stretches: an inextensible robot
  // holds its verified equilibria by construction).
  struct Scenario {
    int parameter;
    double sign;
  };
  std::vector<Scenario> scenarios;
  if (Stretches(robot)) scenarios.push_back({-1, 0.0});
  // Parameters 0 .. 3m-1 the exit coordinates, moved by k_sigma; 3m .. 3m+3 the platform's mass
  // and centre of mass, moved by robust_sigmas times their prior sigmas (the Monte Carlo draws
  // each trial's true platform from those priors).
  const Eigen::Vector4d platform_step = robust_sigmas * SpatialPlatformPriorSigma(robot);
  if (k_sigma > 0.0) {
    for (int p = 0; p < 3 * m + kPlatformScenarioValues; ++p) {
      scenarios.push_back({p, -1.0});
      scenarios.push_back({p, 1.0});
    }
  }
  // Each pose's quantities on the minus robot of the current parameter, for the difference.
  std::vector<VectorXd> minus_x(n), minus_g(n);
  std::vector<bool> have_minus(n, false);
  for (const Scenario& sc : scenarios) {
    SpatialRobot truth = robot;
    std::string name = "the nominal robot (its cables stretched)";
    if (sc.parameter >= 3 * m) {
      const int c = sc.parameter - 3 * m;
      const double step = sc.sign * platform_step(c);
      if (c == 0) {
        truth.platform_mass_kg += step;
      } else {
        truth.p_P_com_m(c - 1) += step;
      }
      name = std::string("a true platform with its ") + (c == 0 ? "mass" : std::string("centre of mass's ") + axes[c - 1]) +
             (sc.sign > 0 ? " +" : " -") + FormatDouble(robust_sigmas) + " sigma";
    } else if (sc.parameter >= 0) {
      truth.cables[sc.parameter / 3].p_F_exit_m(sc.parameter % 3) += sc.sign * k_sigma;
      name = "a true robot with a" + std::to_string(sc.parameter / 3 + 1) + axes[sc.parameter % 3] +
             (sc.sign > 0 ? " +" : " -") + FormatDouble(robust_sigmas) + " sigma";
    }
    for (int j = 0; j < n; ++j) {
      const SpatialPlanPose& p = plan[j];
      const SpatialForwardResult f = SolveForwardStatics(truth, home.paid_out_m + p.length_change_m, &p.q);
      std::string why;
      VectorXd x, g;
      if (f.status != ForwardStatus::kConverged) {
        why = ToString(f.status);
      } else if ((f.equilibrium.q.head<3>() - p.q.head<3>()).norm() > 10.0 * k_sigma + 0.05) {
        why = "settles far from the commanded pose";
      } else {
        int cable = -1;
        const VectorXd t = SnapTensionsToBounds(f.equilibrium.tensions_N, truth.tension_min_N, truth.tension_max_N);
        const Feasibility feas = CheckSpatialFeasibility(truth, f.equilibrium.q, t, &cable);
        if (feas != Feasibility::kFeasible) {
          why = std::string(ToString(feas)) + (cable >= 0 ? " (cable " + std::to_string(cable + 1) + ")" : "");
        }
        if (!StateQuantities(truth, f.equilibrium.q, t, &x, &g) && why.empty()) why = "invalid cable geometry";
      }
      const bool settled = f.status == ForwardStatus::kConverged && x.size() == V;
      if (!why.empty()) {
        if (out.failure.empty()) out.failure = "pose " + std::to_string(j + 1) + " on " + name + ": " + why;
        out.failing[j] = true;
      }
      if (sc.parameter < 0) continue;
      if (sc.sign < 0) {
        have_minus[j] = settled;
        if (settled) {
          minus_x[j] = x;
          minus_g[j] = g;
        }
        continue;
      }
      if (!settled || !have_minus[j]) continue;  // failing already: its spread is widened instead
      out.spread[j].x += (0.5 * (x - minus_x[j])).cwiseAbs2();
      out.spread[j].g += (0.5 * (g - minus_g[j])).cwiseAbs2();
    }
  }
  for (PoseTightening& s : out.spread) {
    s.x = s.x.cwiseSqrt();
    s.g = s.g.cwiseSqrt();
    s.g.head<6>().setZero();  // the equilibrium rows are equalities, not bounds
  }
  return out;
}

// Whether every verified pose keeps every bound with its spread (the linearised worst case over
// the ellipsoid); "" if so, else the first quantity that does not.
std::string LinearisedRobustnessFailure(const SpatialRobot& robot, const std::vector<SpatialPlanPose>& plan,
                                        const std::vector<PoseTightening>& spread) {
  const PoseBounds b = ExactPoseBounds(robot);
  const PoseQuantityNames names = QuantityNames(robot.num_cables());
  const auto beyond = [](double c, double s, double lo, double hi) {
    const double slack = 1e-9 * (1.0 + std::abs(c));
    return c - s < lo - slack || c + s > hi + slack;
  };
  for (std::size_t j = 0; j < plan.size(); ++j) {
    VectorXd x, g;
    if (!StateQuantities(robot, plan[j].q, plan[j].tensions_N, &x, &g)) return "pose " + std::to_string(j + 1) + ": invalid cable geometry";
    const std::string pose = "pose " + std::to_string(j + 1) + ": ";
    for (Eigen::Index c = 0; c < x.size(); ++c) {
      if (beyond(x(c), spread[j].x(c), b.x_lo(c), b.x_hi(c))) return pose + names.x[c] + " reaches its bound to first order";
    }
    for (Eigen::Index r = 6; r < g.size(); ++r) {
      if (beyond(g(r), spread[j].g(r), b.g_lo(r), b.g_hi(r))) return pose + names.g[r] + " reaches its bound to first order";
    }
  }
  return "";
}

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// One start: solved, verified, then (with robustness, or cables that stretch) checked on the
// scenario robots and re-solved with the bounds drawn in until it holds (the file comment).
struct StartOutcome {
  Outcome outcome;
  std::vector<SpatialPlanPose> verified;
  std::string failure;  // "" when `verified` holds
  int robust_rounds = 0;
};

// A re-solve draws each pose's bounds in by this much more than its own spread (the poses move,
// and their spreads with them), a pose that failed a scenario by kRobustWidening^round times
// that. After kRobustOwnSpreadRounds re-solves every pose takes the largest spread of any pose
// instead: more conservative (cogiro, 14 poses: a criterion 1.5 times worse), but a pose moved
// along a bound then meets a spread it was already drawn in for, so the rounds end.
constexpr double kRobustHeadroom = 1.5, kRobustWidening = 1.3;
// Starts made robust at once (DesignSpatialPoses): a fixed number, so that the outcome does not
// depend on the thread count; two, one for each core of a small machine.
constexpr std::size_t kRobustTogether = 2;
constexpr int kRobustOwnSpreadRounds = 2;

// The first solve of a start, without robustness: the same at every k, so the robustness
// search solves it once.
StartOutcome FirstSolve(const SpatialRobot& robot, const SpatialInformationLayout& layout,
                        const SpatialDesignOptions& options, const std::vector<SpatialPlanPose>& start,
                        const SpatialHomeReference& home) {
  StartOutcome s;
  s.outcome = SolveNlpSomewhere(robot, layout, options, home, start);
  if (s.outcome.converged) s.failure = Verify(robot, layout, options, s.outcome.poses, home, &s.verified);
  return s;
}

// From a start's first solve, the robust rounds at half-width k_sigma.
StartOutcome MakeRobust(const SpatialRobot& robot, const SpatialInformationLayout& layout,
                        const SpatialDesignOptions& options, StartOutcome s, const SpatialHomeReference& home,
                        double k_sigma, double robust_sigmas) {
  if (!s.outcome.converged || !s.failure.empty() || (k_sigma == 0.0 && !Stretches(robot))) return s;
  const int m = robot.num_cables();
  std::vector<PoseTightening> tight(s.verified.size(), PoseTightening{VectorXd::Zero(6 + m), VectorXd::Zero(PoseRowCount(m))});
  const PoseBounds b = ExactPoseBounds(robot);
  const PoseQuantityNames names = QuantityNames(m);
  for (int round = 1;; ++round) {
    const ScenarioCheck check = CheckScenarios(robot, s.verified, k_sigma, robust_sigmas, home);
    const std::string linear = LinearisedRobustnessFailure(robot, s.verified, check.spread);
    if (check.failure.empty() && linear.empty()) return s;
    s.failure = check.failure.empty() ? linear : check.failure;
    if (round > kSpatialRobustRounds || (options.interrupted && options.interrupted->load())) return s;
    PoseTightening largest = check.spread.front();
    for (const PoseTightening& p : check.spread) {
      largest.x = largest.x.cwiseMax(p.x);
      largest.g = largest.g.cwiseMax(p.g);
    }
    const bool uniform = round > kRobustOwnSpreadRounds;
    for (std::size_t j = 0; j < tight.size(); ++j) {
      const double widen = check.failing[j] ? std::pow(kRobustWidening, round) : 1.0;
      tight[j].x = (widen * tight[j].x).cwiseMax(widen * kRobustHeadroom * (uniform ? largest.x : check.spread[j].x));
      tight[j].g = (widen * tight[j].g).cwiseMax(widen * kRobustHeadroom * (uniform ? largest.g : check.spread[j].g));
    }
    // Bounds that would cross leave the NLP no pose: said at once, not found by Ipopt's search.
    const auto crossing = [&](const VectorXd& t, const VectorXd& lo, const VectorXd& hi,
                              const std::vector<std::string>& name) -> std::string {
      for (Eigen::Index c = 0; c < t.size(); ++c) {
        if (std::isfinite(lo(c)) && std::isfinite(hi(c)) && lo(c) < hi(c) && lo(c) + t(c) > hi(c) - t(c)) {
          char drawn[32];
          std::snprintf(drawn, sizeof(drawn), "%.4g", t(c));
          return name[c] + "'s bounds [" + FormatDouble(lo(c)) + ", " + FormatDouble(hi(c)) + "] drawn in by " + drawn +
                 " each (its spread for true exit points within " + FormatDouble(robust_sigmas) +
                 " sigma, with headroom) leave no room";
        }
      }
      return "";
    };
    for (std::size_t j = 0; j < tight.size(); ++j) {
      std::string why = crossing(tight[j].x, b.x_lo, b.x_hi, names.x);
      if (why.empty()) why = crossing(tight[j].g, b.g_lo, b.g_hi, names.g);
      if (!why.empty()) {
        s.failure = "pose " + std::to_string(j + 1) + ": " + why + " (before it: " + s.failure + ")";
        return s;
      }
    }
    ++s.robust_rounds;
    const Outcome again = SolveNlpSomewhere(robot, layout, options, home, s.verified, &tight);
    s.outcome.iterations += again.iterations;
    s.outcome.status = again.status;
    if (!again.converged) {
      s.failure = "Ipopt " + again.status + " with the bounds drawn in for robustness (round " +
                  std::to_string(round) + "; before it: " + s.failure + ")";
      return s;
    }
    s.failure = Verify(robot, layout, options, again.poses, home, &s.verified);
    if (!s.failure.empty()) return s;
  }
}

}  // namespace

double DefaultSpatialGeometrySigma(const SpatialRobot& robot) {
  return robot.sensors.tracker_sigma_m.value_or(kDefaultSpatialGeometrySigma_m);
}

std::string SpatialRobustnessText(const SpatialRobot& robot, const SpatialDesignResult& r) {
  const bool stretches = Stretches(robot);
  const double k = r.robust_sigmas_achieved;
  if (!(k * r.geometry_sigma_m > 0.0)) {
    return std::string("each pose holds on the nominal geometry only (no robustness to the true geometry)") +
           (stretches ? ", checked with the elastic forward model" : "");
  }
  const int scenarios = 2 * (3 * robot.num_cables() + kPlatformScenarioValues) + (stretches ? 1 : 0);
  const Eigen::Vector4d platform_sigma = SpatialPlatformPriorSigma(robot);
  return "each pose holds on true robots with exit points within " + FormatDouble(k) + " x " +
         FormatDouble(r.geometry_sigma_m) + " m of nominal and a platform within " + FormatDouble(k) + " x " +
         Rounded(platform_sigma(0)) + " kg (mass) and " + FormatDouble(k) + " x " + Rounded(platform_sigma(1)) +
         " m (centre of mass) of the file's: to first order, and on " + std::to_string(scenarios) +
         " scenario robots with the " + (stretches ? "elastic " : "") + "forward model";
}

int MinSpatialDesignPoses(const SpatialRobot& robot, const SpatialInformationLayout& layout) {
  const int net = SpatialValuesPerPose(robot, layout) - layout.local();
  // The platform's unknowns have their prior's 4 values (the identification counts them so).
  const int unknowns = layout.information_size();
  return net > 0 ? (unknowns + net - 1) / net : std::numeric_limits<int>::max();
}

SpatialDesignResult DesignSpatialPoses(const SpatialRobot& robot, const SpatialDesignOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  const int n = options.poses;
  if (n > kMaxDesignPoses) {
    throw InputError("--poses", "", "at most " + std::to_string(kMaxDesignPoses) + " poses (got " + std::to_string(n) + ")");
  }
  if (options.starts < 1) throw InputError("--starts", "", "must be at least 1");
  if (options.random_sets < 0) throw InputError("--random-sets", "", "must not be negative");
  CheckMinSpacing(options.min_spacing_m, n,
                  ((robot.p_F_frame_max_m.array() - robot.margin_m) - (robot.p_F_frame_min_m.array() + robot.margin_m))
                      .max(0.0)
                      .matrix()
                      .norm(),
                  "the frame box");
  const double sigma_m = options.geometry_sigma_m.value_or(DefaultSpatialGeometrySigma(robot));
  if (!(sigma_m >= 0.0 && sigma_m <= kMaxGeometrySigma_m)) {
    throw InputError("--geometry-sigma", "", "must be between 0 and " + FormatDouble(kMaxGeometrySigma_m) + " m (got " +
                                                 FormatDouble(sigma_m) + ")");
  }
  if (!(options.robust_sigmas >= 0.0 && options.robust_sigmas <= 10.0)) {
    throw InputError("--robust-sigmas", "", "must be between 0 and 10 (got " + FormatDouble(options.robust_sigmas) + ")");
  }
  // The gauge from a reference set large enough for any sensor set (every geometry unknown
  // counted, before any is held): its own stream of the seed.
  SpatialInformationLayout probe = SpatialSensorLayout(robot);
  const int net = SpatialValuesPerPose(robot, probe) - probe.local();
  if (net <= 0) {
    throw InputError(robot.source, "sensors",
                     "each pose gives " + std::to_string(SpatialValuesPerPose(robot, probe)) + " reading values for " +
                         std::to_string(probe.local()) +
                         " unknowns of its own: these sensors cannot calibrate the geometry at any number of poses");
  }
  const int reference_size = (probe.geometry_size() + net - 1) / net + 2;
  std::string prior_note;
  SpatialInformationLayout layout = SpatialDesignLayout(
      robot, SampleSpatialPoses(robot, reference_size, StreamSeed(options.seed, {kGaugeStream})));
  if (options.prior) {
    const SpatialIdentifiedGeometry& prior = *options.prior;
    const std::size_t needed = layout.held.size();
    HoldAsThePrior(&layout, prior.held, prior.source);
    if (layout.held.size() > needed) {
      std::string list;
      for (const int h : layout.held) list += (list.empty() ? "" : ",") + layout.names[h];
      prior_note = prior.source + " holds " + list + ", " + std::to_string(layout.held.size() - needed) +
                   " more than this robot file's sensors need (" + std::to_string(needed) +
                   "): the design takes them as known; a result of fewer sensors than the robot file's, or of a "
                   "lab's hold:?";
    }
    layout.prior_information = SpatialPriorInformation(layout, prior.names, prior.held, prior.covariance, prior.source);
  }
  const int n_min = MinSpatialDesignPoses(robot, layout);
  if (n < n_min) {
    throw InputError("--poses", "", "at least " + std::to_string(n_min) + " poses are needed to identify the " +
                                        std::to_string(layout.information_size()) +
                                        " gauge-fixed geometric unknowns with these sensors (got " + std::to_string(n) +
                                        ")");
  }
  const SpatialHomeReference home = SpatialHome(robot);
  const int K = options.starts;
  std::vector<std::vector<SpatialPlanPose>> starts(K);
  ParallelFor(K, 1, [&](long k) {
    starts[k] = SampleSpatialPoses(robot, n, StreamSeed(options.seed, {kStartStream, static_cast<std::uint64_t>(k)}));
  });
  // The design at robustness k: every start's first solve (in a child process of its own, as many
  // at once as threads), made once at the first k tried; then the starts made robust
  // kRobustTogether at a time, the lowest first-solve criterion first, until one holds (a start
  // whose first solve did not verify is not made robust); the best that holds, or SolverFailure.
  std::vector<StartOutcome> first(K);
  std::vector<double> first_objective(K, std::numeric_limits<double>::infinity());
  std::vector<int> by_first;  // the starts whose first solves verified, lowest criterion first
  bool first_solved = false;
  std::string without_robustness;  // when no first solve gave verified poses: why (no k can help)
  const auto design_at = [&](double k) {
    if (!without_robustness.empty()) throw SolverFailure(without_robustness);
    if (k != options.robust_sigmas && options.trying_robustness) options.trying_robustness(k);
    const double k_sigma = k * sigma_m;
    if (!first_solved) {
      std::atomic<long> starts_done{0};
      ParallelFor(K, 1, [&](long s) {
        if (options.interrupted && options.interrupted->load()) return;
        first[s] = FirstSolve(robot, layout, options, starts[s], home);
        if (first[s].outcome.converged && first[s].failure.empty()) {
          first_objective[s] = SpatialDesignObjective(robot, layout, options.criterion, first[s].verified, nullptr, 0.0);
        }
        const long done = ++starts_done;
        if (options.progress) {
#pragma omp critical(cablecal_design_progress)
          options.progress(done, K);
        }
      });
      if (options.interrupted && options.interrupted->load()) throw Interrupted();
      first_solved = true;
      for (int s = 0; s < K; ++s) {
        if (std::isfinite(first_objective[s])) by_first.push_back(s);
      }
      std::stable_sort(by_first.begin(), by_first.end(), [&](int a, int b) { return first_objective[a] < first_objective[b]; });
    }
    std::vector<StartOutcome> outcomes = first;
    std::vector<bool> made_robust(K, true);
    if (k_sigma > 0.0 || Stretches(robot)) {
      for (const int s : by_first) made_robust[s] = false;
      for (std::size_t begin = 0; begin < by_first.size(); begin += kRobustTogether) {
        const std::size_t end = std::min(by_first.size(), begin + kRobustTogether);
        ParallelFor(static_cast<long>(end - begin), 1, [&](long i) {
          if (options.interrupted && options.interrupted->load()) return;
          const int s = by_first[begin + i];
          outcomes[s] = MakeRobust(robot, layout, options, first[s], home, k_sigma, k);
        });
        if (options.interrupted && options.interrupted->load()) throw Interrupted();
        bool held = false;
        for (std::size_t i = begin; i < end; ++i) {
          made_robust[by_first[i]] = true;
          held = held || outcomes[by_first[i]].failure.empty();
        }
        if (held) break;
      }
    }
    SpatialDesignResult r;
    double best = std::numeric_limits<double>::infinity();
    for (int s = 0; s < K; ++s) {
      SpatialStartReport report;
      report.start = s;
      report.ipopt_status = outcomes[s].outcome.status;
      report.iterations = outcomes[s].outcome.iterations;
      report.converged = outcomes[s].outcome.converged;
      report.robust_rounds = outcomes[s].robust_rounds;
      report.made_robust = made_robust[s];
      report.first_objective = first_objective[s];
      report.objective = std::numeric_limits<double>::infinity();
      if (report.converged) {
        ++r.converged_starts;
        // A start not made robust is not verified at this robustness: only its first solve was.
        report.verification_failure =
            made_robust[s] ? outcomes[s].failure
                           : "not made robust: a pair of starts with lower first-solve criteria was, and one held";
        report.verified = made_robust[s] && outcomes[s].failure.empty();
        if (report.verified) {
          report.objective = SpatialDesignObjective(robot, layout, options.criterion, outcomes[s].verified, nullptr, 0.0);
          if (report.objective < best) {
            best = report.objective;
            r.best_start = s;
          }
        }
      }
      r.starts.push_back(report);
    }
    if (r.best_start < 0) {
      std::string statuses;
      for (const SpatialStartReport& st : r.starts) {
        statuses += (statuses.empty() ? "" : "; ") + ("start " + std::to_string(st.start) + ": ") + st.ipopt_status +
                    (st.converged && !st.verified ? " (re-verification failed: " + st.verification_failure + ")" : "");
      }
      const bool all_capped = std::all_of(r.starts.begin(), r.starts.end(), [](const SpatialStartReport& st) {
        return st.ipopt_status == "Maximum_Iterations_Exceeded";
      });
      if (all_capped) {
        statuses += " (every start reached Ipopt's cap of " + std::to_string(options.max_iterations) +
                    " iterations: more starts, another seed or fewer poses may converge: design's --starts, --seed, --poses; "
                    "montecarlo's --design-starts)";
      }
      // Stability is checked after the NLP, not one of its constraints: with stretching cables
      // an optimum can sit where the platform would not stay (a robot with only some cables
      // elastic, measured: 12 poses none of 3 starts, 8 poses fine).
      const bool any_unstable = std::any_of(r.starts.begin(), r.starts.end(), [](const SpatialStartReport& st) {
        return st.converged && !st.verified && st.verification_failure.find("unstable") != std::string::npos;
      });
      if (any_unstable) {
        statuses += " (the stability of a pose is checked after the optimization, not one of its constraints: where "
                    "stretching cables let an optimum sit at an unstable pose, more starts (--starts, --seed), fewer "
                    "poses or the stiffness of every cable given may find a plan)";
      }
      if (std::none_of(first.begin(), first.end(),
                       [](const StartOutcome& f) { return f.outcome.converged && f.failure.empty(); })) {
        without_robustness = "none of the " + std::to_string(K) + " starts gave verified poses: " + statuses;
      }
      throw SolverFailure("none of the " + std::to_string(K) + " starts gave verified poses" +
                          (k_sigma > 0.0 ? " holding for true exit points within " + FormatDouble(k) + " x " +
                                               FormatDouble(sigma_m) + " m of nominal"
                                         : std::string()) +
                          ": " + statuses);
    }
    r.poses = outcomes[r.best_start].verified;
    return r;
  };
  SpatialDesignResult result;
  RobustnessSearch search;
  if (options.lower_robustness && options.robust_sigmas * sigma_m > 0.0) {
    result = DesignAtLargestRobustness(options.robust_sigmas, design_at, &search);
  } else {
    result = design_at(options.robust_sigmas);
    search.requested_k = search.achieved_k = options.robust_sigmas;
  }
  result.layout = layout;
  result.prior_note = prior_note;
  if (n == n_min) {
    // Measured: a 4-cable robot with one tilted swivel axis, an inclinometer: its 6 designed
    // poses (76 values, 76 unknowns) were not identified from noise-free readings (not converged
    // from the nominal geometry, rank deficient at the estimate with design's hold:), 7 were.
    const int spare = n * (SpatialValuesPerPose(robot, layout) - layout.local()) - layout.information_size();
    result.redundancy_note = std::to_string(n) + " poses are the fewest for these sensors: their readings leave " +
                             std::to_string(spare) + " value" + (spare == 1 ? "" : "s") + " beyond the " +
                             std::to_string(layout.information_size()) +
                             " gauge-fixed unknowns and the poses' own, so an identification fits their noise almost "
                             "exactly (its residuals check little) and may not converge; plan a pose or more beyond";
  }
  result.geometry_sigma_m = sigma_m;
  result.robust_sigmas_requested = search.requested_k;
  result.robust_sigmas_achieved = search.achieved_k;
  if (search.lowered()) {
    // The spatial scenarios move the platform too, at the same k (the holds sentence gives its sigmas).
    result.robustness_note = LoweredRobustnessText(search, sigma_m) +
                             (search.achieved_k > 0.0
                                  ? "; the platform's mass and centre of mass within the same k times their priors"
                                  : "");
    result.failure_at_requested = search.failure_at_requested;
  }
  result.criteria = SpatialCriteria(SpatialInformation(robot, layout, result.poses));
  const int R = options.random_sets;
  if (R > 0) {
    std::vector<CriteriaValues> random(R);
    ParallelFor(R, 1, [&](long r) {
      const auto set =
          SampleSpatialPoses(robot, n, StreamSeed(options.seed, {kRandomSetStream, static_cast<std::uint64_t>(r)}));
      random[r] = SpatialCriteria(SpatialInformation(robot, layout, set));
    });
    std::vector<double> c, d, a, e;
    for (const CriteriaValues& v : random) {
      c.push_back(v.condition_number);
      d.push_back(v.d_log_det_information);
      a.push_back(v.a_trace_covariance_m2);
      e.push_back(v.e_min_eigenvalue);
    }
    result.random_median = {Median(c), Median(d), Median(a), Median(e), layout.information_size()};
  }
  result.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return result;
}

std::string SpatialDesignSummaryYaml(const SpatialRobot& robot, const SpatialDesignResult& r,
                                     const SpatialDesignOptions& options, const std::string& command_line) {
  using YAML::BeginMap;
  using YAML::EndMap;
  using YAML::Flow;
  using YAML::Key;
  using YAML::Value;
  YAML::Emitter o;
  const auto criteria = [&o](const CriteriaValues& v) {
    o << Flow << BeginMap << Key << "condition_number" << Value << YamlNumber{v.condition_number} << Key
      << "d_log_det_information" << Value << YamlNumber{v.d_log_det_information} << Key << "a_trace_covariance"
      << Value << YamlNumber{v.a_trace_covariance_m2} << Key << "e_min_eigenvalue" << Value
      << YamlNumber{v.e_min_eigenvalue} << EndMap;
  };
  o << YAML::Comment(
           "cablecal design summary, spatial robot (README, \"Spatial robots\"). Criteria of the returned set are\n"
           "recomputed from its verified poses. S: information of the gauge-fixed geometry (1/m^2, 1/rad^2 for\n"
           "offsets), the unknowns under `free`; the gauge holds the exit coordinates under `held`; the platform's\n"
           "mass and centre of mass, unknowns with their priors when the statics are modelled, are eliminated.")
    << BeginMap;
  o << Key << "cablecal" << Value << Flow << BeginMap << Key << "version" << Value << YamlString{Version()} << Key
    << "commit" << Value << YamlString{GitCommit()} << EndMap;
  o << Key << "command" << Value << YamlString{command_line};
  o << Key << "robot" << Value << YamlString{robot.name};
  o << Key << "poses" << Value << options.poses;
  o << Key << "criterion" << Value << ToString(options.criterion);
  o << Key << "seed" << Value << options.seed;
  o << Key << "min_spacing_m" << Value << YamlNumber{options.min_spacing_m};
  o << Key << "information" << Value << BeginMap;
  o << Key << "tensions_unknown" << Value << r.layout.tensions;
  o << Key << "held" << Value << Flow << YAML::BeginSeq;
  for (int h : r.layout.held) o << r.layout.names[h];
  o << YAML::EndSeq;
  if (!r.layout.weakly_seen_held.empty()) {
    o << Key << "weakly_seen_held" << Value
      << YAML::Comment("held besides the null directions: seen by no pose set much (README, \"Spatial robots\")")
      << YAML::BeginSeq;
    for (const std::string& d : r.layout.weakly_seen_held) o << YamlString{d};
    o << YAML::EndSeq;
  }
  o << Key << "free" << Value << Flow << YAML::BeginSeq;  // a list, as `held`
  for (int c : r.layout.information_unknowns()) o << r.layout.names[c];
  o << YAML::EndSeq;
  if (options.prior) {
    o << Key << "prior" << Value << YamlString{options.prior->source}
      << YAML::Comment("an earlier identification: the robot is its estimate, S counts its information");
    if (!r.prior_note.empty()) o << Key << "prior_note" << Value << YamlString{r.prior_note};
  }
  if (!r.redundancy_note.empty()) o << Key << "redundancy_note" << Value << YamlString{r.redundancy_note};
  o << EndMap;
  o << Key << "criteria" << Value;
  criteria(r.criteria);
  if (options.random_sets > 0) {
    o << Key << "random_sets" << Value << Flow << BeginMap << Key << "count" << Value << options.random_sets << Key
      << "median" << Value;
    criteria(r.random_median);
    o << EndMap;
    o << Key << "improvement_over_random_median" << Value << YAML::Comment("factor, > 1 is better (see README)")
      << BeginMap;
    for (const Criterion c : {Criterion::kCondition, Criterion::kD, Criterion::kA, Criterion::kE}) {
      o << Key << ToString(c) << Value << YamlNumber{Improvement(c, r.criteria, r.random_median)};
    }
    o << EndMap;
    o << Key << "comparison" << Value
      << YamlString{"on its criterion (" + std::string(ToString(options.criterion)) + "), the designed set is " +
                    ImprovementText(Improvement(options.criterion, r.criteria, r.random_median), options.random_sets)};
  }
  o << Key << "starts" << Value << Flow << BeginMap << Key << "count" << Value << options.starts << Key << "converged"
    << Value << r.converged_starts << Key << "best" << Value << r.best_start << EndMap;
  o << Key << "per_start" << Value << YAML::BeginSeq;
  for (const SpatialStartReport& st : r.starts) {
    o << Flow << BeginMap << Key << "start" << Value << st.start << Key << "ipopt_status" << Value << st.ipopt_status
      << Key << "iterations" << Value << st.iterations << Key << "verified" << Value << st.verified;
    if (st.verified) o << Key << "objective" << Value << YamlNumber{st.objective};
    o << Key << "robust_rounds" << Value << st.robust_rounds;
    if (std::isfinite(st.first_objective)) o << Key << "first_solve_objective" << Value << YamlNumber{st.first_objective};
    if (!st.made_robust) o << Key << "made_robust" << Value << false;
    if (st.converged && !st.verified) o << Key << "verification_failure" << Value << YamlString{st.verification_failure};
    o << EndMap;
  }
  o << YAML::EndSeq;
  // robust_sigmas: the k the plan holds for; the keys below it only when that is less than asked.
  o << Key << "robustness" << Value << BeginMap << Key << "geometry_sigma_m" << Value << YamlNumber{r.geometry_sigma_m}
    << Key << "geometry_sigma_from" << Value
    << (options.geometry_sigma_m ? "given (--geometry-sigma)"
                                 : robot.sensors.tracker_sigma_m ? "the robot file's tracker sigma" : "the default")
    << Key << "robust_sigmas" << Value << YamlNumber{r.robust_sigmas_achieved} << Key << "holds" << Value
    << YamlString{SpatialRobustnessText(robot, r)};
  if (r.robustness_lowered()) {
    o << Key << "robustness_requested_k" << Value << YamlNumber{r.robust_sigmas_requested};
    o << Key << "robustness_achieved_k" << Value << YamlNumber{r.robust_sigmas_achieved};
    o << Key << "robustness_lowered" << Value << YamlString{r.robustness_note};
    o << Key << "failure_at_requested_k" << Value << YamlString{r.failure_at_requested};
  }
  o << EndMap;
  o << Key << "wall_time_s" << Value << YamlNumber{std::round(r.wall_time_s * 1000.0) / 1000.0};
  o << EndMap;
  return YamlText(o);
}

}  // namespace cablecal
