#include "design/ipopt_nlp.h"

#include <IpIpoptApplication.hpp>
#include <IpSolveStatistics.hpp>
#include <IpTNLP.hpp>
#include <ceres/jet.h>

#include <algorithm>
#include <cmath>

#include "design/objective.h"
#include "model/cable.h"

namespace cablecal::internal {
namespace {

using Ipopt::Index;
using Ipopt::Number;

// Variables: per pose j, [x, z, theta, t1, t2] at 5 j.
// Constraints: per pose j, 3 equilibrium rows (W t + w_g = 0) then 2 frame rows per platform
// point (x and z of each anchor, and of the centre of mass if it is not p, within the frame
// minus the margin); then one row per pair of poses for the optional minimum spacing.
class DesignNlp : public Ipopt::TNLP {
 public:
  DesignNlp(const Robot& robot, const DesignOptions& options, const std::vector<PlanPose>& start, double power)
      : robot_(robot), options_(options), start_(start), n_(static_cast<int>(start.size())), power_(power) {
    // Platform points that must stay inside the frame: the anchors, and the centre of mass
    // unless it is the reference point p, which the variable bounds already keep inside.
    for (const Cable& c : robot.cables) points_.push_back(c.p_P_anchor_m);
    if (robot.p_P_com_m.norm() > 0.0) points_.push_back(robot.p_P_com_m);
    R = 3 + 2 * P();
  }

  bool get_nlp_info(Index& n, Index& m, Index& nnz_jac_g, Index& nnz_h_lag, IndexStyleEnum& index_style) override {
    n = 5 * n_;
    m = R * n_ + NumPairs();
    nnz_jac_g = n_ * (3 * 5 + 2 * P() * 3) + NumPairs() * 4;
    nnz_h_lag = 0;  // limited-memory Hessian
    index_style = C_STYLE;
    return true;
  }

  bool get_bounds_info(Index n, Number* x_l, Number* x_u, Index m, Number* g_l, Number* g_u) override {
    const double lo = robot_.margin_m + kBoundMargin_m;
    const double x_hi = robot_.frame_width_m - robot_.margin_m - kBoundMargin_m;
    const double z_hi = std::min(robot_.frame_height_m - robot_.margin_m, robot_.laser_range_m) - kBoundMargin_m;
    for (int j = 0; j < n_; ++j) {
      x_l[5 * j] = lo;
      x_u[5 * j] = x_hi;
      x_l[5 * j + 1] = lo;
      x_u[5 * j + 1] = z_hi;
      x_l[5 * j + 2] = -robot_.theta_max_rad + kBoundMargin_rad;
      x_u[5 * j + 2] = robot_.theta_max_rad - kBoundMargin_rad;
      for (int i = 0; i < 2; ++i) {
        x_l[5 * j + 3 + i] = robot_.tension_min_N + kBoundMargin_N;
        x_u[5 * j + 3 + i] = robot_.tension_max_N - kBoundMargin_N;
      }
      for (int r = 0; r < 3; ++r) g_l[R * j + r] = g_u[R * j + r] = 0.0;
      for (int p = 0; p < P(); ++p) {
        g_l[R * j + 3 + 2 * p] = lo;
        g_u[R * j + 3 + 2 * p] = robot_.frame_width_m - robot_.margin_m - kBoundMargin_m;
        g_l[R * j + 4 + 2 * p] = lo;
        g_u[R * j + 4 + 2 * p] = robot_.frame_height_m - robot_.margin_m - kBoundMargin_m;
      }
    }
    const double d = options_.min_spacing_m + kBoundMargin_m;
    const double d2 = d * d;
    for (int k = 0; k < NumPairs(); ++k) {
      g_l[R * n_ + k] = d2;
      g_u[R * n_ + k] = 2e19;  // Ipopt's +infinity
    }
    (void)n;
    (void)m;
    return true;
  }

  bool get_starting_point(Index n, bool init_x, Number* x, bool init_z, Number*, Number*, Index, bool init_lambda,
                          Number*) override {
    if (!init_x || init_z || init_lambda) return false;
    for (int j = 0; j < n_; ++j) {
      for (int k = 0; k < 3; ++k) x[5 * j + k] = start_[j].q(k);
      for (int i = 0; i < 2; ++i) x[5 * j + 3 + i] = start_[j].tensions_N(i);
    }
    (void)n;
    return true;
  }

  bool eval_f(Index, const Number* x, bool, Number& obj_value) override {
    obj_value = Objective(x, nullptr);
    return std::isfinite(obj_value);
  }

  bool eval_grad_f(Index n, const Number* x, bool, Number* grad_f) override {
    Eigen::VectorXd g;
    if (!std::isfinite(Objective(x, &g))) return false;
    std::fill(grad_f, grad_f + n, 0.0);
    for (int j = 0; j < n_; ++j) {
      for (int k = 0; k < 3; ++k) grad_f[5 * j + k] = g(3 * j + k);
    }
    return true;
  }

  bool eval_g(Index, const Number* x, bool, Index, Number* g) override {
    for (int j = 0; j < n_; ++j) {
      const Pose<double> q(x[5 * j], x[5 * j + 1], x[5 * j + 2]);
      const Eigen::VectorXd t = Eigen::Vector2d(x[5 * j + 3], x[5 * j + 4]);
      const Eigen::Vector3d r = EquilibriumResidual<double>(robot_, q, t);
      for (int k = 0; k < 3; ++k) g[R * j + k] = r(k);
      for (int p = 0; p < P(); ++p) {
        const Eigen::Vector2d pf = PlatformPointInF<double>(q, points_[p]);
        g[R * j + 3 + 2 * p] = pf.x();
        g[R * j + 4 + 2 * p] = pf.y();
      }
    }
    int k = 0;
    for (int a = 0; a < n_; ++a) {
      for (int b = a + 1; b < n_ && NumPairs() > 0; ++b, ++k) {
        const double dx = x[5 * a] - x[5 * b], dz = x[5 * a + 1] - x[5 * b + 1];
        g[R * n_ + k] = dx * dx + dz * dz;
      }
    }
    return true;
  }

  bool eval_jac_g(Index, const Number* x, bool, Index, Index, Index* iRow, Index* jCol, Number* values) override {
    int e = 0;
    if (values == nullptr) {
      for (int j = 0; j < n_; ++j) {
        for (int r = 0; r < 3; ++r) {
          for (int c = 0; c < 5; ++c, ++e) {
            iRow[e] = R * j + r;
            jCol[e] = 5 * j + c;
          }
        }
        for (int r = 0; r < 2 * P(); ++r) {
          for (int c = 0; c < 3; ++c, ++e) {
            iRow[e] = R * j + 3 + r;
            jCol[e] = 5 * j + c;
          }
        }
      }
      int k = 0;
      for (int a = 0; a < n_; ++a) {
        for (int b = a + 1; b < n_ && NumPairs() > 0; ++b, ++k) {
          const int cols[4] = {5 * a, 5 * a + 1, 5 * b, 5 * b + 1};
          for (int c : cols) {
            iRow[e] = R * n_ + k;
            jCol[e++] = c;
          }
        }
      }
      return true;
    }
    using Jet5 = ceres::Jet<double, 5>;
    using Jet3 = ceres::Jet<double, 3>;
    for (int j = 0; j < n_; ++j) {
      Pose<Jet5> q;
      for (int k = 0; k < 3; ++k) q(k) = Jet5(x[5 * j + k], k);
      Eigen::Matrix<Jet5, Eigen::Dynamic, 1> t(2);
      t(0) = Jet5(x[5 * j + 3], 3);
      t(1) = Jet5(x[5 * j + 4], 4);
      const Vec3<Jet5> r = EquilibriumResidual<Jet5>(robot_, q, t);
      for (int row = 0; row < 3; ++row) {
        for (int c = 0; c < 5; ++c) values[e++] = r(row).v(c);
      }
      const Pose<Jet3> q3(Jet3(x[5 * j], 0), Jet3(x[5 * j + 1], 1), Jet3(x[5 * j + 2], 2));
      for (int p = 0; p < P(); ++p) {
        const Vec2<Jet3> pf = PlatformPointInF<Jet3>(q3, points_[p].cast<Jet3>());
        for (int c = 0; c < 3; ++c) values[e++] = pf.x().v(c);
        for (int c = 0; c < 3; ++c) values[e++] = pf.y().v(c);
      }
    }
    for (int a = 0; a < n_; ++a) {
      for (int b = a + 1; b < n_ && NumPairs() > 0; ++b) {
        const double dx = x[5 * a] - x[5 * b], dz = x[5 * a + 1] - x[5 * b + 1];
        values[e++] = 2 * dx;
        values[e++] = 2 * dz;
        values[e++] = -2 * dx;
        values[e++] = -2 * dz;
      }
    }
    return true;
  }

  // Tensions are tens of newtons and equilibrium residuals newtons, positions metres: scale
  // both by the platform's weight so that every variable and constraint is of order one.
  bool get_scaling_parameters(Number& obj_scaling, bool& use_x_scaling, Index n, Number* x_scaling,
                              bool& use_g_scaling, Index m, Number* g_scaling) override {
    const double weight_N = robot_.platform_mass_kg * robot_.gravity_mps2;
    obj_scaling = 1.0;
    use_x_scaling = true;
    for (Index k = 0; k < n; ++k) x_scaling[k] = (k % 5 >= 3) ? 1.0 / weight_N : 1.0;
    use_g_scaling = true;
    for (Index k = 0; k < m; ++k) g_scaling[k] = 1.0;
    for (int j = 0; j < n_; ++j) {
      for (int r = 0; r < 3; ++r) g_scaling[R * j + r] = 1.0 / weight_N;
    }
    return true;
  }

  void finalize_solution(Ipopt::SolverReturn status, Index, const Number* x, const Number*, const Number*, Index,
                         const Number*, const Number*, Number, const Ipopt::IpoptData*,
                         Ipopt::IpoptCalculatedQuantities*) override {
    final_status_ = status;
    poses_.clear();
    tensions_.clear();
    for (int j = 0; j < n_; ++j) {
      poses_.emplace_back(x[5 * j], x[5 * j + 1], x[5 * j + 2]);
      tensions_.emplace_back(x[5 * j + 3], x[5 * j + 4]);
    }
  }
  const std::vector<Eigen::Vector2d>& tensions() const { return tensions_; }

  Ipopt::SolverReturn final_status() const { return final_status_; }
  const std::vector<Eigen::Vector3d>& poses() const { return poses_; }

 private:
  int P() const { return static_cast<int>(points_.size()); }
  int NumPairs() const { return options_.min_spacing_m > 0.0 ? n_ * (n_ - 1) / 2 : 0; }

  double Objective(const Number* x, Eigen::VectorXd* gradient) const {
    std::vector<Eigen::Vector3d> q(n_);
    for (int j = 0; j < n_; ++j) q[j] = Eigen::Vector3d(x[5 * j], x[5 * j + 1], x[5 * j + 2]);
    return DesignObjective(robot_, options_.criterion, q, gradient, power_);
  }

  const Robot& robot_;
  const DesignOptions& options_;
  const std::vector<PlanPose>& start_;
  const int n_;
  const double power_;  // surrogate sharpness; 0: the default
  std::vector<Eigen::Vector2d> points_;
  int R = 0;  // constraint rows per pose: 3 equilibrium, 2 per platform point
  Ipopt::SolverReturn final_status_ = Ipopt::INTERNAL_ERROR;
  std::vector<Eigen::Vector3d> poses_;
  std::vector<Eigen::Vector2d> tensions_;
};

const char* StatusName(Ipopt::ApplicationReturnStatus s) {
  switch (s) {
    case Ipopt::Solve_Succeeded: return "Solve_Succeeded";
    case Ipopt::Solved_To_Acceptable_Level: return "Solved_To_Acceptable_Level";
    case Ipopt::Infeasible_Problem_Detected: return "Infeasible_Problem_Detected";
    case Ipopt::Search_Direction_Becomes_Too_Small: return "Search_Direction_Becomes_Too_Small";
    case Ipopt::Diverging_Iterates: return "Diverging_Iterates";
    case Ipopt::User_Requested_Stop: return "User_Requested_Stop";
    case Ipopt::Feasible_Point_Found: return "Feasible_Point_Found";
    case Ipopt::Maximum_Iterations_Exceeded: return "Maximum_Iterations_Exceeded";
    case Ipopt::Restoration_Failed: return "Restoration_Failed";
    case Ipopt::Error_In_Step_Computation: return "Error_In_Step_Computation";
    case Ipopt::Maximum_CpuTime_Exceeded: return "Maximum_CpuTime_Exceeded";
    case Ipopt::Not_Enough_Degrees_Of_Freedom: return "Not_Enough_Degrees_Of_Freedom";
    case Ipopt::Invalid_Problem_Definition: return "Invalid_Problem_Definition";
    case Ipopt::Invalid_Option: return "Invalid_Option";
    case Ipopt::Invalid_Number_Detected: return "Invalid_Number_Detected";
    default: return "Internal_Error";
  }
}

}  // namespace

namespace {

// One Ipopt run from `start` with surrogate sharpness `power` (0: the default); `next`, if
// given, receives the final point as a start for another run.
StartOutcome RunIpopt(const Robot& robot, const DesignOptions& options, const std::vector<PlanPose>& start,
                      double power, int max_iterations, std::vector<PlanPose>* next) {
  Ipopt::SmartPtr<DesignNlp> nlp = new DesignNlp(robot, options, start, power);
  Ipopt::SmartPtr<Ipopt::IpoptApplication> app = IpoptApplicationFactory();
  app->Options()->SetStringValue("hessian_approximation", "limited-memory");
  app->Options()->SetIntegerValue("limited_memory_max_history", 6);
  app->Options()->SetIntegerValue("max_iter", max_iterations);
  // The criteria are logarithms: 1e-6 in them is far below any difference that matters, and
  // tighter tolerances only make L-BFGS dither. Constraint violation stays tight: the poses
  // must be equilibria (they are re-solved exactly afterwards).
  app->Options()->SetNumericValue("tol", 1e-6);
  app->Options()->SetNumericValue("constr_viol_tol", 1e-9);
  // Near its optimum the condition-number surrogate is sharp and L-BFGS zig-zags with a
  // dual infeasibility around 1e-3 while the objective no longer moves: Ipopt's "acceptable"
  // termination (15 such iterations, objective change below 1e-6, constraints still met to
  // 1e-9) ends that as Solved_To_Acceptable_Level instead of running into the iteration cap.
  app->Options()->SetNumericValue("acceptable_tol", 1e-3);
  app->Options()->SetIntegerValue("acceptable_iter", 15);
  app->Options()->SetNumericValue("acceptable_constr_viol_tol", 1e-9);
  app->Options()->SetNumericValue("acceptable_compl_inf_tol", 1e-3);
  app->Options()->SetNumericValue("acceptable_obj_change_tol", 1e-6);
  app->Options()->SetStringValue("mu_strategy", "adaptive");
  app->Options()->SetStringValue("nlp_scaling_method", "user-scaling");
  app->Options()->SetStringValue("sb", "yes");  // no banner
  app->Options()->SetIntegerValue("print_level", 0);
  if (options.derivative_test) {
    app->Options()->SetStringValue("derivative_test", "first-order");
    app->Options()->SetNumericValue("derivative_test_tol", 1e-4);
    // The criteria come from eigenvalues of matrices with condition numbers up to ~1e5, so
    // they carry absolute noise near 1e-12; Ipopt's default 1e-8 perturbation would turn it
    // into 1e-4 of finite-difference error. 1e-6 keeps truncation and noise both small.
    app->Options()->SetNumericValue("derivative_test_perturbation", 1e-6);
    app->Options()->SetIntegerValue("max_iter", 0);
  }
  if (!options.ipopt_journal_path.empty()) {
    app->Options()->SetStringValue("output_file", options.ipopt_journal_path);
    app->Options()->SetIntegerValue("file_print_level", 5);
  }
  StartOutcome out;
  if (app->Initialize() != Ipopt::Solve_Succeeded) {
    out.status = "Invalid_Option";
    return out;
  }
  const Ipopt::ApplicationReturnStatus status = app->OptimizeTNLP(nlp);
  out.status = StatusName(status);
  out.converged = status == Ipopt::Solve_Succeeded || status == Ipopt::Solved_To_Acceptable_Level;
  if (Ipopt::IsValid(app->Statistics())) out.iterations = app->Statistics()->IterationCount();
  out.poses = nlp->poses();
  if (next) {
    *next = start;
    for (std::size_t j = 0; j < next->size() && j < out.poses.size(); ++j) {
      (*next)[j].q = out.poses[j];
      (*next)[j].tensions_N = nlp->tensions()[j];
    }
  }
  return out;
}

}  // namespace

StartOutcome SolveDesignNlp(const Robot& robot, const DesignOptions& options, const std::vector<PlanPose>& start) {
  const bool sharp = options.criterion == Criterion::kCondition || options.criterion == Criterion::kE;
  if (!sharp || options.derivative_test) {
    return RunIpopt(robot, options, start, 0.0, options.max_iterations, nullptr);
  }
  // Continuation: the smooth surrogate (p = 8) brings the poses near the optimum in few
  // iterations; the sharp one (the default p) finishes from there. Only the final run's
  // status counts as the start's convergence; the iterations are the sum of both.
  std::vector<PlanPose> warm;
  const StartOutcome first =
      RunIpopt(robot, options, start, kContinuationPower, options.max_iterations / 2, &warm);
  // Any point is a valid start for the second run, converged or not.
  const bool usable = warm.size() == start.size() && first.status != "Invalid_Number_Detected";
  StartOutcome out = RunIpopt(robot, options, usable ? warm : start, 0.0, options.max_iterations, nullptr);
  out.iterations += first.iterations;
  return out;
}

}  // namespace cablecal::internal
