#include "design/ipopt_nlp.h"

#include <IpIpoptApplication.hpp>
#include <IpSolveStatistics.hpp>
#include <IpTNLP.hpp>

#include <algorithm>
#include <cmath>

#include "design/objective.h"
#include "design/robust.h"
#include "model/kind.h"

namespace cablecal::internal {
namespace {

using Ipopt::Index;
using Ipopt::Number;

constexpr int kPose = PlanarKind::kPoseDim;        // a pose's variables come first in its V
constexpr int kWrench = PlanarKind::kWrenchDim;  // its equilibrium rows come first in its R

// Variables: per pose j, [x, z, theta, t1..tm] at V j, V = 3 + m (for every m theta is a variable:
// with m = 2 the equilibrium rows tie it to (x, z), with m >= 3 it is free within the band the
// tension bounds leave).
// Constraints: per pose j, 3 equilibrium rows (W t + w_g = 0), then one row per bound of every
// pose quantity (robust.h): c - k sigma |dc/dg| >= lo and c + k sigma |dc/dg| <= hi, with
// sigma = --geometry-sigma (0: the nominal bounds); then one row per pair of poses for the
// optional minimum spacing.
class DesignNlp : public Ipopt::TNLP {
 public:
  DesignNlp(const Robot& robot, const DesignOptions& options, const std::vector<PlanPose>& start, double power,
            const std::vector<double>* widening)
      : robot_(robot), options_(options), start_(start), n_(static_cast<int>(start.size())), power_(power),
        V(PoseVariables(robot.num_cables())), points_(FramePoints(robot)), quantities_(PoseQuantities(robot)),
        k_sigma_m_(options.robust_sigmas * options.geometry_sigma_m),
        widening_(widening ? *widening : std::vector<double>(start.size(), 1.0)) {
    for (int k = 0; k < static_cast<int>(quantities_.size()); ++k) {
      const PoseQuantity& q = quantities_[k];
      // A variable's own nominal bound is already a variable bound; repeating it as a
      // constraint would only make the constraint Jacobian degenerate.
      if (q.is_variable && k_sigma_m_ == 0.0) continue;
      if (std::isfinite(q.lo)) rows_.push_back({k, -1});
      if (std::isfinite(q.hi)) rows_.push_back({k, +1});
    }
    R = kWrench + static_cast<int>(rows_.size());
  }

  bool get_nlp_info(Index& n, Index& m, Index& nnz_jac_g, Index& nnz_h_lag, IndexStyleEnum& index_style) override {
    n = V * n_;
    m = R * n_ + NumPairs();
    nnz_jac_g = n_ * R * V + NumPairs() * 4;
    nnz_h_lag = 0;  // limited-memory Hessian
    index_style = C_STYLE;
    return true;
  }

  bool get_bounds_info(Index n, Number* x_l, Number* x_u, Index m, Number* g_l, Number* g_u) override {
    constexpr double kIpoptInf = 2e19;
    const double lo = robot_.margin_m + kBoundMargin_m;
    const double x_hi = robot_.frame_width_m - robot_.margin_m - kBoundMargin_m;
    const double z_hi = std::min(robot_.frame_height_m - robot_.margin_m, robot_.laser_range_m) - kBoundMargin_m;
    for (int j = 0; j < n_; ++j) {
      x_l[V * j] = lo;
      x_u[V * j] = x_hi;
      x_l[V * j + 1] = lo;
      x_u[V * j + 1] = z_hi;
      x_l[V * j + 2] = -robot_.theta_max_rad + kBoundMargin_rad;
      x_u[V * j + 2] = robot_.theta_max_rad - kBoundMargin_rad;
      for (int i = 0; i < robot_.num_cables(); ++i) {
        x_l[V * j + kPose + i] = robot_.tension_min_N + kBoundMargin_N;
        x_u[V * j + kPose + i] = robot_.tension_max_N - kBoundMargin_N;
      }
      for (int r = 0; r < kWrench; ++r) g_l[R * j + r] = g_u[R * j + r] = 0.0;
      for (int r = 0; r < static_cast<int>(rows_.size()); ++r) {
        const PoseQuantity& q = quantities_[rows_[r].quantity];
        const int row = R * j + kWrench + r;
        if (rows_[r].sign < 0) {
          g_l[row] = q.lo + q.bound_margin;
          g_u[row] = kIpoptInf;
        } else {
          g_l[row] = -kIpoptInf;
          g_u[row] = q.hi - q.bound_margin;
        }
      }
    }
    const double d = options_.min_spacing_m + kBoundMargin_m;
    const double d2 = d * d;
    for (int k = 0; k < NumPairs(); ++k) {
      g_l[R * n_ + k] = d2;
      g_u[R * n_ + k] = kIpoptInf;
    }
    (void)n;
    (void)m;
    return true;
  }

  bool get_starting_point(Index n, bool init_x, Number* x, bool init_z, Number*, Number*, Index, bool init_lambda,
                          Number*) override {
    if (!init_x || init_z || init_lambda) return false;
    for (int j = 0; j < n_; ++j) {
      for (int k = 0; k < kPose; ++k) x[V * j + k] = start_[j].q(k);
      for (int i = 0; i < robot_.num_cables(); ++i) x[V * j + kPose + i] = start_[j].tensions_N(i);
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
      for (int k = 0; k < kPose; ++k) grad_f[V * j + k] = g(kPose * j + k);
    }
    return true;
  }

  bool eval_g(Index, const Number* x, bool, Index, Number* g) override {
    for (int j = 0; j < n_; ++j) {
      if (!PoseRows(x + V * j, k_sigma_m_ * widening_[j], g + R * j, nullptr)) return false;
    }
    int k = 0;
    for (int a = 0; a < n_; ++a) {
      for (int b = a + 1; b < n_ && NumPairs() > 0; ++b, ++k) {
        const double dx = x[V * a] - x[V * b], dz = x[V * a + 1] - x[V * b + 1];
        g[R * n_ + k] = dx * dx + dz * dz;
      }
    }
    return true;
  }

  bool eval_jac_g(Index, const Number* x, bool, Index, Index, Index* iRow, Index* jCol, Number* values) override {
    int e = 0;
    if (values == nullptr) {
      for (int j = 0; j < n_; ++j) {
        for (int r = 0; r < R; ++r) {
          for (int c = 0; c < V; ++c, ++e) {
            iRow[e] = R * j + r;
            jCol[e] = V * j + c;
          }
        }
      }
      int k = 0;
      for (int a = 0; a < n_; ++a) {
        for (int b = a + 1; b < n_ && NumPairs() > 0; ++b, ++k) {
          const int cols[4] = {V * a, V * a + 1, V * b, V * b + 1};
          for (int c : cols) {
            iRow[e] = R * n_ + k;
            jCol[e++] = c;
          }
        }
      }
      return true;
    }
    std::vector<double> unused(R);
    for (int j = 0; j < n_; ++j) {
      if (!PoseRows(x + V * j, k_sigma_m_ * widening_[j], unused.data(), values + e)) return false;
      e += R * V;
    }
    for (int a = 0; a < n_; ++a) {
      for (int b = a + 1; b < n_ && NumPairs() > 0; ++b) {
        const double dx = x[V * a] - x[V * b], dz = x[V * a + 1] - x[V * b + 1];
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
    for (Index k = 0; k < n; ++k) x_scaling[k] = (k % V >= kPose) ? 1.0 / weight_N : 1.0;
    use_g_scaling = true;
    for (Index k = 0; k < m; ++k) g_scaling[k] = 1.0;
    for (int j = 0; j < n_; ++j) {
      for (int r = 0; r < kWrench; ++r) g_scaling[R * j + r] = 1.0 / weight_N;
      for (int r = 0; r < static_cast<int>(rows_.size()); ++r) {
        if (rows_[r].quantity < robot_.num_cables()) g_scaling[R * j + kWrench + r] = 1.0 / weight_N;  // tensions
      }
    }
    return true;
  }

  // Ctrl-C: returning false makes Ipopt stop at this iteration (User_Requested_Stop).
  bool intermediate_callback(Ipopt::AlgorithmMode, Index, Number, Number, Number, Number, Number, Number, Number,
                             Number, Index, const Ipopt::IpoptData*, Ipopt::IpoptCalculatedQuantities*) override {
    return !(options_.interrupted && options_.interrupted->load());
  }

  void finalize_solution(Ipopt::SolverReturn status, Index, const Number* x, const Number*, const Number*, Index,
                         const Number*, const Number*, Number, const Ipopt::IpoptData*,
                         Ipopt::IpoptCalculatedQuantities*) override {
    final_status_ = status;
    poses_.clear();
    tensions_.clear();
    for (int j = 0; j < n_; ++j) {
      poses_.emplace_back(x[V * j], x[V * j + 1], x[V * j + 2]);
      tensions_.push_back(Eigen::Map<const Eigen::VectorXd>(x + V * j + kPose, robot_.num_cables()));
    }
  }
  const std::vector<Eigen::VectorXd>& tensions() const { return tensions_; }

  Ipopt::SolverReturn final_status() const { return final_status_; }
  const std::vector<PlanarPose>& poses() const { return poses_; }

 private:
  struct Row {
    int quantity;  // index into quantities_
    int sign;      // -1: c - k sigma s >= lo; +1: c + k sigma s <= hi
  };
  int NumPairs() const { return options_.min_spacing_m > 0.0 ? n_ * (n_ - 1) / 2 : 0; }

  // Pose j's R constraint rows from its V variables at xj into g; if `jac` is given, also
  // their R x V Jacobian block, row by row. The equilibrium rows and the quantities' values
  // are differentiated exactly (the Jets of RobustQuantities); the spreads by central
  // differences (robust.h).
  bool PoseRows(const Number* xj, double k_sigma_m, Number* g, Number* jac) const {
    const Eigen::VectorXd y = Eigen::Map<const Eigen::VectorXd>(xj, V);
    PoseRobustness at;
    if (!RobustQuantities(robot_, points_, y, &at, jac != nullptr)) return false;
    for (int r = 0; r < kWrench; ++r) {
      g[r] = at.equilibrium_N(r);
      if (jac) {
        for (int c = 0; c < V; ++c) jac[V * r + c] = at.dequilibrium_dy(r, c);
      }
    }
    for (int r = 0; r < static_cast<int>(rows_.size()); ++r) {
      const int k = rows_[r].quantity;
      g[kWrench + r] = at.value[k] + rows_[r].sign * k_sigma_m * at.spread[k];
      if (jac) {
        for (int c = 0; c < V; ++c) jac[V * (kWrench + r) + c] = at.dvalue_dy(k, c);
      }
    }
    for (int r = 0; r < R; ++r) {
      if (!std::isfinite(g[r])) return false;
    }
    if (jac && k_sigma_m > 0.0) {
      // d spread / dy by central differences; steps of ~cbrt(eps) of each variable's scale.
      const double weight_N = robot_.platform_mass_kg * robot_.gravity_mps2;
      for (int c = 0; c < V; ++c) {
        const double h = 6e-6 * (c >= kPose ? weight_N : 1.0);
        Eigen::VectorXd yp = y, ym = y;
        yp(c) += h;
        ym(c) -= h;
        PoseRobustness plus, minus;
        if (!RobustQuantities(robot_, points_, yp, &plus) || !RobustQuantities(robot_, points_, ym, &minus)) {
          return false;
        }
        for (int r = 0; r < static_cast<int>(rows_.size()); ++r) {
          const int k = rows_[r].quantity;
          jac[V * (kWrench + r) + c] += rows_[r].sign * k_sigma_m * (plus.spread[k] - minus.spread[k]) / (2.0 * h);
        }
      }
    }
    return true;
  }

  double Objective(const Number* x, Eigen::VectorXd* gradient) const {
    std::vector<PlanarPose> q(n_);
    for (int j = 0; j < n_; ++j) q[j] = PlanarPose(x + V * j);
    return DesignObjective(robot_, options_.criterion, q, gradient, power_,
                           options_.prior_information ? &*options_.prior_information : nullptr);
  }

  const Robot& robot_;
  const DesignOptions& options_;
  const std::vector<PlanPose>& start_;
  const int n_;
  const double power_;  // surrogate sharpness; 0: the default
  const int V;          // variables per pose: x, z, theta, one tension per cable
  const std::vector<Eigen::Vector2d> points_;
  const std::vector<PoseQuantity> quantities_;
  const double k_sigma_m_;  // k sigma: the half-width of the linearised worst case
  const std::vector<double> widening_;  // per pose, on k_sigma_m_
  std::vector<Row> rows_;
  int R = 0;  // constraint rows per pose: 3 equilibrium, then rows_
  Ipopt::SolverReturn final_status_ = Ipopt::INTERNAL_ERROR;
  std::vector<PlanarPose> poses_;
  std::vector<Eigen::VectorXd> tensions_;
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

bool InitializeIpopt(Ipopt::IpoptApplication& app) {
  return app.Initialize(std::string()) == Ipopt::Solve_Succeeded;  // an empty name: no options file read
}

namespace {

// One Ipopt run from `start` with surrogate sharpness `power` (0: the default); `next`, if
// given, receives the final point as a start for another run.
StartOutcome RunIpopt(const Robot& robot, const DesignOptions& options, const std::vector<PlanPose>& start,
                      const std::vector<double>* widening, double power, int max_iterations,
                      std::vector<PlanPose>* next) {
  Ipopt::SmartPtr<DesignNlp> nlp = new DesignNlp(robot, options, start, power, widening);
  Ipopt::SmartPtr<Ipopt::IpoptApplication> app = IpoptApplicationFactory();
  app->Options()->SetStringValue("hessian_approximation", "limited-memory");
  app->Options()->SetIntegerValue("limited_memory_max_history", 6);
  // The quasi-Newton Hessian's low-rank part as extra rows and columns of the KKT matrix that
  // MUMPS factors, instead of Sherman-Morrison with 12 extra MUMPS solves per factorization,
  // which were two thirds of every iteration (callgrind). The same search direction in exact
  // arithmetic: on 56 designs (4 criteria, n = 6..50, 2 seeds) 36 ended at the same optimum,
  // 13 at a better and 7 at a worse one (rounding decides between nearly equal local minima),
  // in 34 s instead of 51 s (bench/README.md, "Speed").
  app->Options()->SetStringValue("limited_memory_aug_solver", "extended");
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
    // The robustness rows' second derivatives can be large near the workspace boundary, where
    // a smaller perturbation (DesignOptions) keeps the checker's own truncation error down.
    app->Options()->SetNumericValue("derivative_test_perturbation", options.derivative_test_perturbation);
    app->Options()->SetIntegerValue("max_iter", 0);
  }
  if (!options.ipopt_journal_path.empty()) {
    app->Options()->SetStringValue("output_file", options.ipopt_journal_path);
    app->Options()->SetIntegerValue("file_print_level", 5);
  }
  StartOutcome out;
  if (!InitializeIpopt(*app)) {
    out.status = "Invalid_Option";
    return out;
  }
  const Ipopt::ApplicationReturnStatus status = app->OptimizeTNLP(nlp);
  out.status = StatusName(status);
  out.converged = status == Ipopt::Solve_Succeeded || status == Ipopt::Solved_To_Acceptable_Level;
  if (Ipopt::IsValid(app->Statistics())) out.iterations = app->Statistics()->IterationCount();
  out.poses = nlp->poses();
  out.tensions_N = nlp->tensions();
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

StartOutcome SolveDesignNlp(const Robot& robot, const DesignOptions& options, const std::vector<PlanPose>& start,
                            const std::vector<double>* widening) {
  const bool sharp = options.criterion == Criterion::kCondition || options.criterion == Criterion::kE;
  if (!sharp || options.derivative_test) {
    return RunIpopt(robot, options, start, widening, 0.0, options.max_iterations, nullptr);
  }
  // Continuation: the smooth surrogate (p = 8) brings the poses near the optimum in few
  // iterations; the sharp one (the default p) finishes from there. Only the final run's
  // status counts as the start's convergence; the iterations are the sum of both.
  std::vector<PlanPose> warm;
  const StartOutcome first =
      RunIpopt(robot, options, start, widening, kContinuationPower, options.max_iterations / 2, &warm);
  // Any point is a valid start for the second run, converged or not.
  const bool usable = warm.size() == start.size() && first.status != "Invalid_Number_Detected";
  StartOutcome out = RunIpopt(robot, options, usable ? warm : start, widening, 0.0, options.max_iterations, nullptr);
  out.iterations += first.iterations;
  return out;
}

}  // namespace cablecal::internal
