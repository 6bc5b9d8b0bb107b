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
#include <limits>
#include <optional>

#include "common/error.h"
#include "common/format.h"
#include "common/parallel.h"
#include "common/random.h"
#include "common/version.h"
#include "common/yaml_writer.h"
#include "design/solve_process.h"
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

constexpr std::uint64_t kStartStream = 1, kRandomSetStream = 2, kGaugeStream = 3;

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

class SpatialDesignNlp : public Ipopt::TNLP {
 public:
  SpatialDesignNlp(const SpatialRobot& robot, const SpatialInformationLayout& layout,
                   const SpatialDesignOptions& options, const std::vector<SpatialPlanPose>& start)
      : robot_(robot), layout_(layout), options_(options), start_(start), n_(static_cast<int>(start.size())),
        m_(robot.num_cables()), V(6 + m_), C(PoseRowCount(m_)) {}

  int NumPairs() const { return options_.min_spacing_m > 0.0 ? n_ * (n_ - 1) / 2 : 0; }

  bool get_nlp_info(Index& n, Index& m, Index& nnz_jac_g, Index& nnz_h_lag, IndexStyleEnum& style) override {
    n = V * n_;
    m = C * n_ + NumPairs();
    nnz_jac_g = n_ * C * V + NumPairs() * 6;
    nnz_h_lag = 0;
    style = C_STYLE;
    return true;
  }

  bool get_bounds_info(Index, Number* x_l, Number* x_u, Index, Number* g_l, Number* g_u) override {
    constexpr double kInf = 2e19;
    const Eigen::Vector3d lo = robot_.p_F_frame_min_m.array() + robot_.margin_m;
    const Eigen::Vector3d hi = robot_.p_F_frame_max_m.array() - robot_.margin_m;
    const double yaw = robot_.home_rpy_rad.z();
    for (int j = 0; j < n_; ++j) {
      Number* xl = x_l + V * j;
      Number* xu = x_u + V * j;
      for (int a = 0; a < 3; ++a) {
        xl[a] = lo(a) + kMargin_m;
        xu[a] = hi(a) - kMargin_m;
      }
      for (int a = 3; a < 5; ++a) {
        xl[a] = -robot_.tilt_max_rad + kMargin_rad;
        xu[a] = robot_.tilt_max_rad - kMargin_rad;
      }
      xl[5] = yaw - kDefaultSampleYawRange_rad + kMargin_rad;
      xu[5] = yaw + kDefaultSampleYawRange_rad - kMargin_rad;
      for (int i = 0; i < m_; ++i) {
        xl[6 + i] = robot_.tension_min_N + TensionMargin(robot_);
        xu[6 + i] = robot_.tension_max_N - TensionMargin(robot_);
      }
      Number* gl = g_l + C * j;
      Number* gu = g_u + C * j;
      for (int r = 0; r < 6; ++r) gl[r] = gu[r] = 0.0;
      gl[6] = std::cos(robot_.tilt_max_rad - kMargin_rad);
      gu[6] = kInf;
      for (int k = 0; k < m_ + 1; ++k) {
        for (int a = 0; a < 3; ++a) {
          gl[7 + 3 * k + a] = lo(a) + kMargin_m;
          gu[7 + 3 * k + a] = hi(a) - kMargin_m;
        }
      }
      for (int i = 0; i < m_; ++i) {
        gl[7 + 3 * (m_ + 1) + i] = robot_.margin_m + kMargin_m;
        gu[7 + 3 * (m_ + 1) + i] = kInf;
      }
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

  bool eval_grad_f(Index n, const Number* x, bool, Number* grad) override {
    VectorXd g;
    const double f = SpatialDesignObjective(robot_, layout_, options_.criterion, Poses(x), &g, Power());
    if (!std::isfinite(f)) return false;
    std::copy(g.data(), g.data() + n, grad);
    return true;
  }

  bool eval_g(Index, const Number* x, bool, Index, Number* g) override {
    std::vector<double> out(C);
    for (int j = 0; j < n_; ++j) {
      if (!PoseRows<double>(robot_, x + V * j, g + C * j)) return false;
    }
    int k = 0;
    for (int a = 0; a < n_ && NumPairs() > 0; ++a) {
      for (int b = a + 1; b < n_; ++b, ++k) {
        double d2 = 0.0;
        for (int c = 0; c < 3; ++c) d2 += (x[V * a + c] - x[V * b + c]) * (x[V * a + c] - x[V * b + c]);
        g[C * n_ + k] = d2;
      }
    }
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
    for (int j = 0; j < n_; ++j) {
      for (int c = 0; c < V; ++c) y[c] = Jet(x[V * j + c], c);
      if (!PoseRows<Jet>(robot_, y.data(), out.data())) return false;
      for (int r = 0; r < C; ++r) {
        for (int c = 0; c < V; ++c) values[e++] = out[r].v[c];
      }
    }
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

  bool intermediate_callback(Ipopt::AlgorithmMode, Index, Number, Number, Number, Number, Number, Number, Number,
                             Number, Index, const Ipopt::IpoptData*, Ipopt::IpoptCalculatedQuantities*) override {
    return !(options_.interrupted && options_.interrupted->load());
  }

  void finalize_solution(Ipopt::SolverReturn, Index, const Number* x, const Number*, const Number*, Index,
                         const Number*, const Number*, Number, const Ipopt::IpoptData*,
                         Ipopt::IpoptCalculatedQuantities*) override {
    final_ = Poses(x);
  }
  const std::vector<SpatialPlanPose>& final_poses() const { return final_; }

 private:
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
  const int n_, m_, V, C;
  std::vector<SpatialPlanPose> final_;
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

Outcome SolveNlp(const SpatialRobot& robot, const SpatialInformationLayout& layout, const SpatialDesignOptions& options,
                 const std::vector<SpatialPlanPose>& start) {
  Ipopt::SmartPtr<SpatialDesignNlp> nlp = new SpatialDesignNlp(robot, layout, options, start);
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
  Outcome out;
  if (app->Initialize() != Ipopt::Solve_Succeeded) {
    out.status = "Invalid_Option";
    return out;
  }
  const Ipopt::ApplicationReturnStatus status = app->OptimizeTNLP(nlp);
  out.status = StatusName(status);
  out.converged = status == Ipopt::Solve_Succeeded || status == Ipopt::Solved_To_Acceptable_Level;
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
                          const SpatialDesignOptions& options, const std::vector<SpatialPlanPose>& start) {
  if (options.solve_in_child_processes) {
    const std::optional<std::string> bytes =
        internal::RunInChildProcess([&] { return Encode(SolveNlp(robot, layout, options, start)); }, options.interrupted);
    if (bytes) return Decode(*bytes);
  }
  Outcome outcome;
  std::exception_ptr solve_error;  // an exception must not leave the critical section
#pragma omp critical(cablecal_ipopt)
  {
    try {
      outcome = SolveNlp(robot, layout, options, start);
    } catch (...) {
      solve_error = std::current_exception();
    }
  }
  if (solve_error) std::rethrow_exception(solve_error);
  return outcome;
}

double Weight(const SpatialRobot& robot) { return robot.platform_mass_kg * robot.gravity_mps2; }

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

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

}  // namespace

int MinSpatialDesignPoses(const SpatialRobot& robot, const SpatialInformationLayout& layout) {
  const int net = SpatialValuesPerPose(robot, layout) - layout.local();
  const int unknowns = static_cast<int>(layout.free.size());
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
  if (!(options.min_spacing_m >= 0.0) || !std::isfinite(options.min_spacing_m)) {
    throw InputError("--min-spacing", "", "must be a non-negative number of metres");
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
  const SpatialInformationLayout layout = SpatialDesignLayout(
      robot, SampleSpatialPoses(robot, reference_size, StreamSeed(options.seed, {kGaugeStream})));
  const int n_min = MinSpatialDesignPoses(robot, layout);
  if (n < n_min) {
    throw InputError("--poses", "", "at least " + std::to_string(n_min) + " poses are needed to identify the " +
                                        std::to_string(layout.free.size()) +
                                        " gauge-fixed geometric unknowns with these sensors (got " + std::to_string(n) +
                                        ")");
  }
  const SpatialHomeReference home = SpatialHome(robot);
  const int K = options.starts;
  std::vector<std::vector<SpatialPlanPose>> starts(K);
  ParallelFor(K, 1, [&](long k) {
    starts[k] = SampleSpatialPoses(robot, n, StreamSeed(options.seed, {kStartStream, static_cast<std::uint64_t>(k)}));
  });
  std::vector<Outcome> outcomes(K);
  std::vector<std::vector<SpatialPlanPose>> verified(K);
  std::vector<std::string> failures(K);
  // Each start in a child process of its own (SolveNlpSomewhere): as many at once as threads.
  std::atomic<long> starts_done{0};
  ParallelFor(K, 1, [&](long k) {
    if (options.interrupted && options.interrupted->load()) return;
    outcomes[k] = SolveNlpSomewhere(robot, layout, options, starts[k]);
    if (outcomes[k].converged) failures[k] = Verify(robot, layout, options, outcomes[k].poses, home, &verified[k]);
    const long done = ++starts_done;
    if (options.progress) {
#pragma omp critical(cablecal_design_progress)
      options.progress(done, K);
    }
  });
  if (options.interrupted && options.interrupted->load()) throw Interrupted();

  SpatialDesignResult result;
  result.layout = layout;
  double best = std::numeric_limits<double>::infinity();
  for (int k = 0; k < K; ++k) {
    SpatialStartReport report;
    report.start = k;
    report.ipopt_status = outcomes[k].status;
    report.iterations = outcomes[k].iterations;
    report.converged = outcomes[k].converged;
    report.objective = std::numeric_limits<double>::infinity();
    if (report.converged) {
      ++result.converged_starts;
      report.verification_failure = failures[k];
      report.verified = failures[k].empty();
      if (report.verified) {
        report.objective = SpatialDesignObjective(robot, layout, options.criterion, verified[k], nullptr, 0.0);
        if (report.objective < best) {
          best = report.objective;
          result.best_start = k;
        }
      }
    }
    result.starts.push_back(report);
  }
  if (result.best_start < 0) {
    std::string statuses;
    for (const SpatialStartReport& r : result.starts) {
      statuses += (statuses.empty() ? "" : ", ") + r.ipopt_status +
                  (r.converged && !r.verified ? " (re-verification failed: " + r.verification_failure + ")" : "");
    }
    throw SolverFailure("none of the " + std::to_string(K) + " starts gave verified poses: " + statuses);
  }
  result.poses = verified[result.best_start];
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
    result.random_median = {Median(c), Median(d), Median(a), Median(e), static_cast<int>(layout.free.size())};
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
  std::string free_names;
  for (int c : r.layout.free) free_names += (free_names.empty() ? "" : " ") + r.layout.names[c];
  o << YAML::Comment(
           "cablecal design summary, spatial robot (README, \"Spatial robots\"). Criteria of the returned set are\n"
           "recomputed from its verified poses. S: information of the gauge-fixed geometry (1/m^2, 1/rad^2 for\n"
           "offsets), the unknowns under `free`; the gauge holds the exit coordinates under `held`.")
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
  o << Key << "free" << Value << YamlString{free_names};
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
    if (st.converged && !st.verified) o << Key << "verification_failure" << Value << YamlString{st.verification_failure};
    o << EndMap;
  }
  o << YAML::EndSeq;
  o << Key << "robustness" << Value << YamlString{"not modelled yet for spatial robots: the poses hold on the nominal geometry"};
  o << Key << "wall_time_s" << Value << YamlNumber{std::round(r.wall_time_s * 1000.0) / 1000.0};
  o << EndMap;
  return YamlText(o);
}

}  // namespace cablecal
