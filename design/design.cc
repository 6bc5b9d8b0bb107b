#include "design/design.h"

#include <omp.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

#include <Eigen/Dense>
#include <yaml-cpp/yaml.h>

#include "common/error.h"
#include "common/format.h"
#include "common/parallel.h"
#include "common/yaml_writer.h"
#include "common/random.h"
#include "common/version.h"
#include "design/ipopt_nlp.h"
#include "design/solve_process.h"
#include "design/objective.h"
#include "design/robust.h"
#include "design/robustness_search.h"
#include "experiment/experiment.h"
#include "identify/identify.h"
#include "model/cable.h"
#include "model/kind.h"
#include "experiment/simulation.h"
#include "model/forward_statics.h"
#include "model/statics.h"

namespace cablecal {

Criterion ParseCriterion(const std::string& text) {
  if (text == "condition") return Criterion::kCondition;
  if (text == "d") return Criterion::kD;
  if (text == "a") return Criterion::kA;
  if (text == "e") return Criterion::kE;
  throw InputError("--criterion", "", "must be condition, d, a or e (got '" + text + "')");
}

const char* ToString(Criterion c) {
  switch (c) {
    case Criterion::kCondition: return "condition";
    case Criterion::kD: return "d";
    case Criterion::kA: return "a";
    case Criterion::kE: return "e";
  }
  return "unknown";
}

std::string DescribeCriterion(Criterion c, const CriteriaValues& v, bool with_name) {
  char buf[96];
  switch (c) {
    case Criterion::kCondition:
      std::snprintf(buf, sizeof(buf), "%s%.4g", with_name ? "condition number " : "", v.condition_number);
      break;
    case Criterion::kD:
      std::snprintf(buf, sizeof(buf), "%s%.4g", with_name ? "log det of the information " : "", v.d_log_det_information);
      break;
    case Criterion::kA:
      std::snprintf(buf, sizeof(buf), "%s%.4g m^2", with_name ? "trace of the covariance " : "", v.a_trace_covariance_m2);
      break;
    case Criterion::kE:
      std::snprintf(buf, sizeof(buf), "%s%.4g 1/m^2", with_name ? "smallest information eigenvalue " : "",
                    v.e_min_eigenvalue);
      break;
  }
  return buf;
}

namespace {

// Stream ids under the user's seed: starts and the random reference sets never share draws.
constexpr std::uint64_t kStartStream = 1;
constexpr std::uint64_t kRandomSetStream = 2;
constexpr std::uint64_t kRobustProbeStream = 3;  // EmptyRobustWorkspaceHint
// Re-verification of Ipopt's poses with the model.
constexpr double kEquilibriumTol_N = 1e-8;
constexpr double kSameRootTol_rad = 1e-6;  // the model's equilibrium is Ipopt's, not another root
// Widening of a pose's linearised robustness rows when it fails the scenario check.
constexpr double kRobustEscalation = 1.3;
constexpr int kRobustRounds = 4;
// Feasible poses drawn per start pose for robots with 3 or more cables (RobustStart).
constexpr int kStartPool = 10;
// Random feasible poses probed for the hint when no start gives verified poses.
constexpr int kRobustProbes = 200;

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

std::vector<PlanarPose> PosesOf(const std::vector<PlanPose>& plan) {
  std::vector<PlanarPose> q;
  for (const PlanPose& p : plan) q.push_back(p.q);
  return q;
}

// Re-evaluates every pose of Ipopt's with the model and checks it. m = 2: the equilibrium
// re-solved at Ipopt's (x, z) must be the same root, with a residual below tolerance. m >= 3:
// the full pose is evaluated as it stands (EvaluatePose(robot, q)); its tension distribution
// (unique for m = 3; for m >= 4 the minimum-norm one within bounds, which may differ from the
// tensions Ipopt found) must balance gravity to the same tolerance and is what the plan
// lists. Then every workspace bound held exactly, and the spacing kept. Returns "" when all
// hold, else the first failure.
std::string VerifyPoses(const Robot& robot, const DesignOptions& options, const std::vector<PlanarPose>& ipopt_poses,
                        const Eigen::VectorXd& l0, std::vector<PlanPose>* verified) {
  verified->clear();
  for (std::size_t j = 0; j < ipopt_poses.size(); ++j) {
    const PlanarPose& q = ipopt_poses[j];
    const std::string pose = "pose " + std::to_string(j + 1) + ": ";
    if (robot.theta_is_free()) {
      const PoseEvaluation e = EvaluatePose(robot, q);
      if (!e.has_equilibrium) return pose + "no tension distribution holds Ipopt's pose (" + ToString(e.feasibility) + ")";
      if (!(e.equilibrium.residual_N < kEquilibriumTol_N)) return pose + "equilibrium residual too large";
      if (!e.feasible()) return pose + ToString(e.feasibility);
      verified->push_back(MakePlanPose(robot, e.equilibrium, l0));
      continue;
    }
    const EquilibriumResult eq = SolveEquilibrium(robot, q(0), q(1));
    if (eq.status != EquilibriumStatus::kFound) return pose + "no stable equilibrium at Ipopt's position";
    if (std::abs(eq.equilibrium.q(2) - q(2)) > kSameRootTol_rad) return pose + "Ipopt's theta is not the model's equilibrium";
    if (!(eq.equilibrium.residual_N < kEquilibriumTol_N)) return pose + "equilibrium residual too large";
    const Feasibility f = CheckFeasibility(robot, eq.equilibrium.q, eq.equilibrium.tensions_N);
    if (f != Feasibility::kFeasible) return pose + ToString(f);
    verified->push_back(MakePlanPose(robot, eq.equilibrium, l0));
  }
  for (std::size_t a = 0; a < verified->size(); ++a) {
    for (std::size_t b = a + 1; b < verified->size(); ++b) {
      const double d = ((*verified)[a].q.head<2>() - (*verified)[b].q.head<2>()).norm();
      if (d < options.min_spacing_m) {
        return "poses " + std::to_string(a + 1) + " and " + std::to_string(b + 1) + " closer than --min-spacing";
      }
    }
  }
  return "";
}

// The robustness the NLP enforced to first order (robust.h), checked with the full model: for
// each geometry parameter moved by +-k sigma alone (6m true robots), the commanded lengths of
// every pose must be held -- the forward model converges to a taut equilibrium (stable, for
// m = 2) near the commanded pose that passes every workspace test of the true robot (for
// m >= 4: the least-squares pose of the lengths, where the true robot's tension distribution,
// minimum-norm within bounds, must exist). Fills each pose's worst-case tensions: for m <= 3 the
// linearised worst case over the ellipsoid, t -+ k sigma |dt/dg|; for m >= 4, where the
// tensions are the controller's choice, the range of the model's distribution over the nominal
// and the scenario robots (it contains the plan's tensions, and lies within bounds whenever the
// check passes). Returns "" when all hold, else the first failure. `failing`, if given,
// receives every pose that fails some scenario.
std::string VerifyRobustness(const Robot& robot, const DesignOptions& options, std::vector<PlanPose>* plan,
                             std::vector<bool>* failing = nullptr) {
  const double k_sigma = options.robust_sigmas * options.geometry_sigma_m;
  const std::vector<Eigen::Vector2d> points = internal::FramePoints(robot);
  const int m = robot.num_cables();
  const bool linearised_tensions = m <= 3;
  for (std::size_t j = 0; j < plan->size(); ++j) {
    PlanPose& pose = (*plan)[j];
    Eigen::VectorXd y(internal::PoseVariables(m));
    y << pose.q, pose.tensions_N;
    internal::PoseRobustness at;
    if (!internal::RobustQuantities(robot, points, y, &at)) {
      return "pose " + std::to_string(j + 1) + (robot.theta_is_free()
                                                    ? ": a singular configuration (the cable lengths do not fix the pose)"
                                                    : ": the equilibrium is singular (a fold of the statics)");
    }
    pose.tensions_worst_min_N = pose.tensions_N;
    pose.tensions_worst_max_N = pose.tensions_N;
    if (linearised_tensions) {
      for (int i = 0; i < m; ++i) {
        pose.tensions_worst_min_N(i) = at.value[i] - k_sigma * at.spread[i];
        pose.tensions_worst_max_N(i) = at.value[i] + k_sigma * at.spread[i];
      }
    }
  }
  // Without robustness an inextensible robot holds its nominal equilibria by construction; an
  // elastic one settles where its stretch puts it, so the nominal robot itself is the scenario.
  const bool elastic = std::any_of(robot.cables.begin(), robot.cables.end(), [](const Cable& c) { return c.stiffness_N.has_value(); });
  if (k_sigma == 0.0 && !elastic) return "";
  if (failing) failing->assign(plan->size(), false);
  std::string first;
  const GeometryVector nominal = GeometryOf(robot);
  const std::vector<std::string> names = GeometryNames(m);
  const CableCommands commands(robot);
  for (int k = 0; k < (k_sigma == 0.0 ? 1 : nominal.size()); ++k) {
    for (const double sign : {-1.0, 1.0}) {
      if (k_sigma == 0.0 && sign > 0) continue;
      GeometryVector g = nominal;
      g(k) += sign * k_sigma;
      const Robot truth = WithGeometry(robot, g);
      const Eigen::VectorXd truth_home_unstretched = HomeUnstretchedLengths(truth, g.tail(m));
      const std::string scenario = k_sigma == 0.0 ? std::string("its elastic cables (nominal geometry)")
                                                  : names[k] + (sign > 0 ? " +" : " -") +
                                                        FormatDouble(options.robust_sigmas) + " sigma";
      for (std::size_t j = 0; j < plan->size(); ++j) {
        if (failing && (*failing)[j]) continue;
        PlanPose& pose = (*plan)[j];
        const Eigen::VectorXd lengths = truth_home_unstretched + commands.PaidOutFromHome(pose);
        const ForwardResult f = SettlePlanar(truth, lengths, &pose.q);
        const std::string where = "pose " + std::to_string(j + 1) + " on a true robot with " + scenario + ": ";
        std::string why;
        if (f.status != ForwardStatus::kConverged) {
          why = ToString(f.status);
        } else if ((f.equilibrium.q - pose.q).head<2>().norm() > 10.0 * k_sigma + 0.05) {
          why = "settles far from the commanded pose";
        } else {
          const Feasibility feas = CheckFeasibility(truth, f.equilibrium.q, f.equilibrium.tensions_N);
          if (feas != Feasibility::kFeasible) why = ToString(feas);
        }
        if (why.empty()) {
          if (!linearised_tensions) {
            pose.tensions_worst_min_N = pose.tensions_worst_min_N.cwiseMin(f.equilibrium.tensions_N);
            pose.tensions_worst_max_N = pose.tensions_worst_max_N.cwiseMax(f.equilibrium.tensions_N);
          }
          continue;
        }
        if (first.empty()) first = where + why;
        if (!failing) return first;
        (*failing)[j] = true;
      }
    }
  }
  return first;
}

// How far pose p breaks the NLP's linearised robustness rows (robust.h) at half-width k_sigma:
// the largest excess of c -+ k sigma |dc/dg| over c's bounds, relative to each bound's scale
// (tensions in weights, the rest in m or rad); <= 0 where every row holds, +inf at a singular
// pose. For m >= 4, p's tensions first become the vector nearest the middle of the tension
// range that balances it, if within bounds (the rows on the tensions then have their largest
// margins), else they stay the model's distribution.
double RobustViolation(const Robot& robot, double k_sigma, const std::vector<Eigen::Vector2d>& points,
                       const std::vector<internal::PoseQuantity>& quantities, PlanPose* p) {
  const int m = robot.num_cables();
  if (m >= 4) {
    // Nearest to the middle c among W t + w_g = 0: t = c - W^+ (W c + w_g).
    const Eigen::VectorXd middle = Eigen::VectorXd::Constant(m, 0.5 * (robot.tension_min_N + robot.tension_max_N));
    const Eigen::MatrixXd W = WrenchMatrix<double>(robot, Pose<double>(p->q));
    const Eigen::Vector3d imbalance = W * middle + GravityWrench<double>(robot, Pose<double>(p->q));
    const Eigen::VectorXd t = middle - W.transpose() * (W * W.transpose()).ldlt().solve(imbalance);
    if (t.allFinite() && t.minCoeff() >= robot.tension_min_N && t.maxCoeff() <= robot.tension_max_N) p->tensions_N = t;
  }
  Eigen::VectorXd y(internal::PoseVariables(m));
  y << p->q, p->tensions_N;
  internal::PoseRobustness at;
  if (!internal::RobustQuantities(robot, points, y, &at)) return std::numeric_limits<double>::infinity();
  const double weight_N = robot.platform_mass_kg * robot.gravity_mps2;
  double violation = -std::numeric_limits<double>::infinity();
  for (std::size_t c = 0; c < quantities.size(); ++c) {
    const double scale = static_cast<int>(c) < m ? weight_N : 1.0;
    const double below = quantities[c].lo - (at.value[c] - k_sigma * at.spread[c]);
    const double above = at.value[c] + k_sigma * at.spread[c] - quantities[c].hi;
    violation = std::max(violation, std::max(below, above) / scale);
  }
  return violation;
}

// A start for a robot with m >= 3 cables. With rigid cables the lengths fix the pose, so a
// centimetre of geometry error moves and turns the platform far more than with 2 cables, and
// the robust part of the feasible workspace (where the NLP's rows hold) is often a small part
// of it: Ipopt started from uniform feasible poses then mostly ends infeasible. So each of the
// n start poses is the one, of kStartPool feasible poses drawn in turn from the start's stream,
// whose rows are violated least (RobustViolation; ties in draw order): the poses stay
// independent draws, spread over the robust part where it is not too small, instead of
// clustering where the rows hold best. Without robustness it is the sampler's first n.
std::vector<PlanPose> RobustStart(const Robot& robot, const DesignOptions& options, int n, std::uint64_t stream) {
  const double k_sigma = options.robust_sigmas * options.geometry_sigma_m;
  if (k_sigma == 0.0) return SampleFeasiblePoses(robot, n, stream);
  std::vector<PlanPose> pool = SampleFeasiblePoses(robot, kStartPool * n, stream);
  const std::vector<Eigen::Vector2d> points = internal::FramePoints(robot);
  const std::vector<internal::PoseQuantity> quantities = internal::PoseQuantities(robot);
  std::vector<double> violation(pool.size());
  for (std::size_t j = 0; j < pool.size(); ++j) violation[j] = RobustViolation(robot, k_sigma, points, quantities, &pool[j]);
  std::vector<PlanPose> start;
  for (int j = 0; j < n; ++j) {
    const auto first = violation.begin() + static_cast<long>(j) * kStartPool;
    start.push_back(pool[std::min_element(first, first + kStartPool) - violation.begin()]);
  }
  return start;
}

// When no start gives verified poses with robustness on: whether the robust workspace looks
// empty, i.e. none of kRobustProbes random feasible poses keeps every linearised robustness
// row. Returns the hint for the message, or "".
std::string EmptyRobustWorkspaceHint(const Robot& robot, const DesignOptions& options) {
  const double k_sigma = options.robust_sigmas * options.geometry_sigma_m;
  if (k_sigma == 0.0) return "";
  std::vector<PlanPose> probes;
  try {
    probes = SampleFeasiblePoses(robot, kRobustProbes, StreamSeed(options.seed, {kRobustProbeStream}));
  } catch (const SolverFailure&) {
    return "";
  }
  const std::vector<Eigen::Vector2d> points = internal::FramePoints(robot);
  const std::vector<internal::PoseQuantity> quantities = internal::PoseQuantities(robot);
  for (PlanPose& p : probes) {
    if (RobustViolation(robot, k_sigma, points, quantities, &p) <= 0.0) return "";
  }
  return ". None of " + std::to_string(kRobustProbes) + " random feasible poses of " + robot.name +
         " stays within every bound, to first order, for true exit points and initial lengths within " +
         FormatDouble(options.robust_sigmas) + " x " + FormatDouble(options.geometry_sigma_m) +
         " m of nominal: its robust workspace looks empty (README, \"Experiment design\"); a smaller "
         "--geometry-sigma (a better-known geometry) or --robust-sigmas may leave room";
}

// The geometric parameters the default gauge leaves to identify (3m - 1: all but a1x).
int GaugeFixedCount(int num_cables) {
  return static_cast<int>(PlanarKind::FreeByDefault(PlanarLayout(num_cables)).size());
}

}  // namespace

int MinDesignPoses(int num_cables) {
  // Each pose adds m length equations for its one unknown beyond the readings (x): n (m - 1)
  // >= the gauge-fixed geometry's 3m - 1, so n = ceil((3m - 1) / (m - 1)).
  const int m = num_cables;
  const int gauge_fixed = GaugeFixedCount(m);
  return (gauge_fixed + (m - 2)) / (m - 1);
}

namespace {

// The median of each criterion over options.random_sets random feasible sets of n poses, each
// from its own stream (seed, r): the same sets whatever the robustness.
CriteriaValues RandomMedian(const Robot& robot, int n, const DesignOptions& options, const PriorInformation* prior) {
  const int R = options.random_sets;
  std::vector<CriteriaValues> random(R);
  ParallelFor(R, 1, [&](long r) {
    const auto set = SampleFeasiblePoses(robot, n, StreamSeed(options.seed, {kRandomSetStream, static_cast<std::uint64_t>(r)}));
    random[r] = EvaluateCriteria(robot, PosesOf(set), prior);
  });
  std::vector<double> c, d, a, e;
  for (const CriteriaValues& v : random) {
    c.push_back(v.condition_number);
    d.push_back(v.d_log_det_information);
    a.push_back(v.a_trace_covariance_m2);
    e.push_back(v.e_min_eigenvalue);
  }
  return {Median(c), Median(d), Median(a), Median(e), GaugeFixedCount(robot.num_cables())};
}

// Long (~175 lines) for a reason: the design's one sequence (checks, robustness, multi-start
// Ipopt, verification, random-set comparison), each step using the ones before it. At the
// options' robustness exactly.
DesignResult DesignPosesAt(const Robot& robot, const DesignOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  const int n = options.poses;
  const int m = robot.num_cables();
  if (n < MinDesignPoses(m)) {
    throw InputError("--poses", "", "at least " + std::to_string(MinDesignPoses(m)) + " poses are needed to identify the " +
                                        std::to_string(GaugeFixedCount(m)) +
                                        " gauge-fixed geometric parameters and the per-pose unknowns (got " +
                                        std::to_string(n) + ")");
  }
  if (n > kMaxDesignPoses) {
    throw InputError("--poses", "", "at most " + std::to_string(kMaxDesignPoses) + " poses (got " + std::to_string(n) + ")");
  }
  if (options.starts < 1) throw InputError("--starts", "", "must be at least 1");
  if (options.random_sets < 0) throw InputError("--random-sets", "", "must not be negative");
  CheckMinSpacing(options.min_spacing_m, n,
                  std::hypot(std::max(0.0, robot.frame_width_m - 2.0 * robot.margin_m),
                             std::max(0.0, robot.frame_height_m - 2.0 * robot.margin_m)),
                  "the frame");
  if (!(options.geometry_sigma_m >= 0.0 && options.geometry_sigma_m <= kMaxGeometrySigma_m)) {
    throw InputError("--geometry-sigma", "", "must be between 0 and " + FormatDouble(kMaxGeometrySigma_m) +
                                                 " m (got " + FormatDouble(options.geometry_sigma_m) + ")");
  }
  if (!(options.robust_sigmas >= 0.0 && options.robust_sigmas <= 10.0)) {
    throw InputError("--robust-sigmas", "", "must be between 0 and 10 (got " + FormatDouble(options.robust_sigmas) + ")");
  }
  if (options.prior_information && options.criterion == Criterion::kCondition) {
    throw InputError("--prior", "", "the condition-number criterion cannot count an earlier identification's "
                                    "information: use --criterion a, d or e");
  }
  if (options.prior_information) {
    const int gauge_fixed = GaugeFixedCount(m);
    CABLECAL_CHECK(options.prior_information->rows() == gauge_fixed && options.prior_information->cols() == gauge_fixed,
                   "the prior information is (3m - 1) x (3m - 1) for the robot's m cables");
  }
  const PriorInformation* prior = options.prior_information ? &*options.prior_information : nullptr;
  const Eigen::VectorXd l0 = InitialLengths(robot);
  const int K = options.starts;

  // Feasible random starts, each from its own stream (seed, start index).
  std::vector<std::vector<PlanPose>> starts(K);
  std::vector<std::string> start_errors(K);
  ParallelFor(K, 1, [&](long k) {
    try {
      const std::uint64_t stream = StreamSeed(options.seed, {kStartStream, static_cast<std::uint64_t>(k)});
      starts[k] = robot.theta_is_free() ? RobustStart(robot, options, n, stream) : SampleFeasiblePoses(robot, n, stream);
    } catch (const SolverFailure& e) {
      start_errors[k] = e.what();
    }
  });
  for (int k = 0; k < K; ++k) {
    if (!start_errors[k].empty()) throw SolverFailure("cannot draw a feasible start: " + start_errors[k]);
  }

  // Each start: Ipopt, then the re-verification with the model. If only the robustness check
  // fails (the linearisation underestimates a tension that is strongly nonlinear in the
  // geometry, near the frame top), the poses that failed get their rows' half-width widened
  // by kRobustEscalation and the start is solved again from where it ended, at most
  // kRobustRounds times: the rows stay first-order, the guarantee is the scenario check.
  std::vector<internal::StartOutcome> outcomes(K);
  std::vector<std::vector<PlanPose>> verified(K);
  std::vector<std::string> failures(K);
  std::vector<double> widest(K, 1.0);
  std::atomic<long> starts_done{0};
  ParallelFor(K, 1, [&](long k) {
    std::vector<double> widening(n, 1.0);
    std::vector<PlanPose> from = starts[k];
    for (int round = 0; round <= kRobustRounds; ++round) {
      if (options.interrupted && options.interrupted->load()) break;
      // MUMPS, Ipopt's linear solver in Debian, is not thread-safe (coin-or/Ipopt#733): each
      // solve runs in a child process of its own, so the starts' solves run at once; where
      // that is off or no process can be had, the solves take turns in this one.
      std::optional<internal::StartOutcome> in_child;
      if (options.solve_in_child_processes) {
        in_child = internal::SolveDesignNlpInChildProcess(robot, options, from, &widening);
      }
      internal::StartOutcome outcome;
      if (in_child) {
        outcome = std::move(*in_child);
      } else {
        // An exception must not leave the critical section (its lock would stay taken).
        std::exception_ptr solve_error;
#pragma omp critical(cablecal_ipopt)
        {
          try {
            outcome = internal::SolveDesignNlp(robot, options, from, &widening);
          } catch (...) {
            solve_error = std::current_exception();
          }
        }
        if (solve_error) std::rethrow_exception(solve_error);
      }
      outcomes[k].iterations += outcome.iterations;
      outcomes[k].status = outcome.status;
      outcomes[k].converged = outcome.converged;
      outcomes[k].poses = outcome.poses;
      if (!outcome.converged) break;
      failures[k] = VerifyPoses(robot, options, outcome.poses, l0, &verified[k]);
      if (!failures[k].empty()) break;
      std::vector<bool> failing;
      failures[k] = VerifyRobustness(robot, options, &verified[k], &failing);
      if (failures[k].empty() || options.robust_sigmas * options.geometry_sigma_m == 0.0) break;
      for (int j = 0; j < n; ++j) {
        if (failing[j]) widening[j] *= kRobustEscalation;
        widest[k] = std::max(widest[k], widening[j]);
      }
      from = verified[k];  // warm start: Ipopt's poses with their tensions
      if (m >= 4) {
        // The plan lists the model's distribution; Ipopt continues from its own (certified) one.
        for (int j = 0; j < n; ++j) from[j].tensions_N = outcome.tensions_N[j];
      }
    }
    const long done = ++starts_done;
    if (options.progress) {
#pragma omp critical(cablecal_design_progress)
      options.progress(done, K);
    }
  });

  if (options.interrupted && options.interrupted->load()) throw Interrupted();
  DesignResult result;
  result.num_cables = m;
  double best = std::numeric_limits<double>::infinity();
  for (int k = 0; k < K; ++k) {
    StartReport report;
    report.start = k;
    report.ipopt_status = outcomes[k].status;
    report.iterations = outcomes[k].iterations;
    report.converged = outcomes[k].converged;
    report.robust_sigmas = options.robust_sigmas * widest[k];
    report.objective = std::numeric_limits<double>::infinity();
    if (report.converged) {
      ++result.converged_starts;
      report.verification_failure = failures[k];
      report.verified = report.verification_failure.empty();
      if (report.verified) {
        report.objective = internal::ExactObjective(robot, options.criterion, PosesOf(verified[k]), prior);
        if (report.objective < best) {  // ties keep the lowest start index
          best = report.objective;
          result.best_start = k;
        }
      }
    }
    result.starts.push_back(report);
  }
  if (result.best_start < 0) {
    std::string statuses;
    for (const StartReport& r : result.starts) {
      statuses += (statuses.empty() ? "" : ", ") + r.ipopt_status +
                  (r.converged && !r.verified ? " (re-verification failed: " + r.verification_failure + ")" : "");
    }
    throw SolverFailure("none of the " + std::to_string(K) + " starts gave verified poses: " + statuses +
                        EmptyRobustWorkspaceHint(robot, options));
  }
  result.poses = verified[result.best_start];
  result.criteria = EvaluateCriteria(robot, PosesOf(result.poses), prior);
  result.robust_sigmas_requested = result.robust_sigmas_achieved = options.robust_sigmas;

  // Reference: random feasible sets of the same size (random_sets 0: none; the Monte Carlo needs none).
  if (options.random_sets > 0) result.random_median = RandomMedian(robot, n, options, prior);
  result.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return result;
}

}  // namespace

DesignResult DesignPoses(const Robot& robot, const DesignOptions& options) {
  if (!options.lower_robustness || !(options.robust_sigmas * options.geometry_sigma_m > 0.0)) {
    return DesignPosesAt(robot, options);
  }
  const auto t0 = std::chrono::steady_clock::now();
  RobustnessSearch search;
  bool first = true;
  // The requested k as it always ran; the search's designs without the random reference,
  // which does not depend on k and is drawn once for the plan kept.
  DesignResult result = DesignAtLargestRobustness(
      options.robust_sigmas,
      [&](double k) {
        DesignOptions at = options;
        at.robust_sigmas = k;
        if (!first) {
          at.random_sets = 0;
          if (options.trying_robustness) options.trying_robustness(k);
        }
        first = false;
        return DesignPosesAt(robot, at);
      },
      &search);
  if (!search.lowered()) return result;
  result.robust_sigmas_requested = search.requested_k;
  result.robust_sigmas_achieved = search.achieved_k;
  result.robustness_note = LoweredRobustnessText(search, options.geometry_sigma_m);
  result.robustness_designs = search.designs;
  if (options.random_sets > 0) {
    result.random_median = RandomMedian(robot, options.poses, options,
                                        options.prior_information ? &*options.prior_information : nullptr);
  }
  result.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return result;
}

DesignPrior LoadDesignPrior(const Robot& nominal, const std::string& path) {
  const IdentifiedGeometry known = ReadIdentifiedGeometry(nominal, path);
  const Eigen::MatrixXd& cov = known.covariance;
  const int m = nominal.num_cables();
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(0.5 * (cov + cov.transpose()));
  if (!cov.allFinite() || !(eig.eigenvalues()(0) > 0.0)) {
    throw InputError(path, "correlation", "the covariance of " + GeometryNameList(m, 1) + " is not positive definite");
  }
  DesignPrior prior;
  prior.robot = WithGeometry(nominal, known.geometry);
  prior.information = eig.eigenvectors() * eig.eigenvalues().cwiseInverse().asDiagonal() * eig.eigenvectors().transpose();
  return prior;
}

void CheckMinSpacing(double min_spacing_m, int poses, double reach_m, const std::string& region) {
  if (!(min_spacing_m >= 0.0) || !std::isfinite(min_spacing_m)) {
    throw InputError("--min-spacing", "", "must be a non-negative number of metres");
  }
  if (poses >= 2 && min_spacing_m > reach_m) {
    throw InputError("--min-spacing", "",
                     FormatDouble(min_spacing_m) + " m is more than any two poses can be apart: the diagonal of " +
                         region + " less its margin is " + Rounded(reach_m) + " m");
  }
}

std::string ImprovementText(double factor, int random_sets) {
  const std::string median = "the median of " + std::to_string(random_sets) + " random set" + (random_sets == 1 ? "" : "s");
  char buffer[64];
  if (!(factor > 0.0) || !std::isfinite(factor)) return "not comparable with " + median;
  if (std::abs(factor - 1.0) < 0.01) return "as good as " + median;
  std::snprintf(buffer, sizeof(buffer), "%.3g x %s than ", factor > 1.0 ? factor : 1.0 / factor,
                factor > 1.0 ? "better" : "worse");
  return buffer + median;
}

std::string NoBetterThanRandomWarning(const DesignOptions& options, const std::string& sigma_option) {
  return "the designed set is no better than the median random set on its criterion: the poses that stay holdable "
         "for geometry errors of " + FormatDouble(options.robust_sigmas) + " x " + FormatDouble(options.geometry_sigma_m) +
         " m are a small part of the nominal workspace the random sets are drawn from (compare with " + sigma_option +
         " 0). If the exit points and initial lengths are known better than that (a tape, a laser tracker), say so "
         "with a smaller " + sigma_option + " (e.g. 0.005 or 0.001 m); a robot whose cable lines nearly meet at one "
         "point of the platform needs it (README, \"Any number of cables\")";
}

std::string DesignSummaryYaml(const DesignResult& r, const DesignOptions& options, const std::string& command_line) {
  const int m = r.num_cables;
  using YAML::BeginMap;
  using YAML::EndMap;
  using YAML::Flow;
  using YAML::Key;
  using YAML::Value;
  YAML::Emitter o;
  const auto criteria = [&o](const CriteriaValues& v) {
    o << Flow << BeginMap << Key << "condition_number" << Value << YamlNumber{v.condition_number} << Key
      << "d_log_det_information" << Value << YamlNumber{v.d_log_det_information} << Key << "a_trace_covariance_m2"
      << Value << YamlNumber{v.a_trace_covariance_m2} << Key << "e_min_eigenvalue" << Value
      << YamlNumber{v.e_min_eigenvalue} << EndMap;
  };
  o << YAML::Comment(
           "cablecal design summary (README, \"Experiment design\"). Criteria of the returned set are\n"
           "recomputed from its verified poses. S: information of " + GeometryNameList(m, 1) + " (1/m^2).")
    << BeginMap;
  o << Key << "cablecal" << Value << Flow << BeginMap << Key << "version" << Value << YamlString{Version()} << Key
    << "commit" << Value << YamlString{GitCommit()} << EndMap;
  o << Key << "command" << Value << YamlString{command_line};
  o << Key << "poses" << Value << options.poses;
  o << Key << "criterion" << Value << ToString(options.criterion);
  o << Key << "seed" << Value << options.seed;
  o << Key << "min_spacing_m" << Value << YamlNumber{options.min_spacing_m};
  o << Key << "criteria" << Value;
  criteria(r.criteria);
  if (options.random_sets > 0) {
    o << Key << "random_sets" << Value << Flow << BeginMap << Key << "count" << Value << options.random_sets << Key
      << "median" << Value;
    criteria(r.random_median);
    o << EndMap;
    o << Key << "condition_number" << Value << Flow << BeginMap << Key << "optimized" << Value
      << YamlNumber{r.criteria.condition_number} << Key << "random_median" << Value
      << YamlNumber{r.random_median.condition_number} << EndMap;
    o << Key << "improvement_over_random_median" << Value << YAML::Comment("factor, > 1 is better (see README)")
      << BeginMap;
    for (const Criterion c : {Criterion::kCondition, Criterion::kD, Criterion::kA, Criterion::kE}) {
      o << Key << ToString(c) << Value << YamlNumber{Improvement(c, r.criteria, r.random_median)};
    }
    o << EndMap;
    o << Key << "comparison" << Value
      << YamlString{"on its criterion (" + std::string(ToString(options.criterion)) + "), the designed set is " +
                    ImprovementText(Improvement(options.criterion, r.criteria, r.random_median), options.random_sets)};
  } else {
    o << Key << "random_sets" << Value << Flow << BeginMap << Key << "count" << Value << 0 << EndMap
      << YAML::Comment("no random reference (--random-sets 0)");
  }
  o << Key << "starts" << Value << Flow << BeginMap << Key << "count" << Value << options.starts << Key << "converged"
    << Value << r.converged_starts << Key << "best" << Value << r.best_start << EndMap;
  o << Key << "per_start" << Value << YAML::BeginSeq;
  for (const StartReport& st : r.starts) {
    o << Flow << BeginMap << Key << "start" << Value << st.start << Key << "ipopt_status" << Value << st.ipopt_status
      << Key << "iterations" << Value << st.iterations << Key << "verified" << Value << st.verified;
    if (st.verified) o << Key << "objective" << Value << YamlNumber{st.objective};
    o << Key << "robust_sigmas_in_nlp" << Value << YamlNumber{std::round(st.robust_sigmas * 1e6) / 1e6};
    if (st.converged && !st.verified) o << Key << "verification_failure" << Value << YamlString{st.verification_failure};
    o << EndMap;
  }
  o << YAML::EndSeq;
  // robust_sigmas: the k the plan holds for; the keys below it only when that is less than asked.
  o << Key << "robustness" << Value << Flow << BeginMap << Key << "geometry_sigma_m" << Value
    << YamlNumber{options.geometry_sigma_m} << Key << "robust_sigmas" << Value
    << YamlNumber{r.robustness_lowered() ? r.robust_sigmas_achieved : options.robust_sigmas} << Key << "scenarios"
    << Value << YamlString{"each of " + GeometryNameList(m, 0) + " moved by +-k sigma alone"} << EndMap;
  if (r.robustness_lowered()) {
    o << Key << "robustness_requested_k" << Value << YamlNumber{r.robust_sigmas_requested};
    o << Key << "robustness_achieved_k" << Value << YamlNumber{r.robust_sigmas_achieved};
    o << Key << "robustness_lowered" << Value << YamlString{r.robustness_note};
    o << Key << "robustness_search_designs" << Value << r.robustness_designs;
  }
  o << Key << "poses_worst_case_tensions_N" << Value
    << YAML::Comment("linearised over the geometry uncertainty, per cable [min, max]") << YAML::BeginSeq;
  for (std::size_t j = 0; j < r.poses.size(); ++j) {
    const PlanPose& p = r.poses[j];
    o << Flow << BeginMap << Key << "pose" << Value << j + 1;
    for (int i = 0; i < p.tensions_worst_min_N.size(); ++i) {
      o << Key << ("t" + std::to_string(i + 1)) << Value << Flow << YAML::BeginSeq
        << YamlNumber{p.tensions_worst_min_N(i)} << YamlNumber{p.tensions_worst_max_N(i)} << YAML::EndSeq;
    }
    o << EndMap;
  }
  o << YAML::EndSeq;
  o << Key << "wall_time_s" << Value << YamlNumber{std::round(r.wall_time_s * 1000.0) / 1000.0};
  o << EndMap;
  return YamlText(o);
}

}  // namespace cablecal
