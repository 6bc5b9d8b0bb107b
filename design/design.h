// design: picks n measurement poses inside the feasible cable-tension workspace that make
// the identification best conditioned (Ipopt, exact first derivatives, L-BFGS Hessian,
// OpenMP multi-start from the workspace sampler).
//
// Criteria (README, "Experiment design"):
//   condition  the condition number of the gauge-fixed length Jacobian: residuals
//              r_ij = l_i(pose_j; a_i) - (dl_ij + l_i0) in m (the paper's Eq. 6 without
//              squares) by the unknowns a1z a2x a2z .. amz l10 .. lm0 x1..xn, at the nominal
//              robot, unscaled. Minimised as log(kappa): the same optimum, a better-scaled function.
//   d, a, e    D-, A-, E-optimality of the information S of the 3m - 1 geometric parameters
//              (a1x held) once every pose's own unknowns (x, z, theta) are eliminated,
//              with the maximum-likelihood estimator's sensor sigmas.
// Every pose's decision variables are (x, z, theta, t1..tm), for any m = 2..8 cables.
// Depends on identify/ (the Jacobian rows), workspace/ (sampler, pose plans), model/.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "model/robot.h"
#include "experiment/plan.h"
#include "model/kind.h"

namespace cablecal {

enum class Criterion { kCondition, kD, kA, kE };
Criterion ParseCriterion(const std::string& text);  // InputError naming --criterion
const char* ToString(Criterion c);

// All four criteria of one pose set.
struct CriteriaValues {
  double condition_number = 0.0;       // kappa of the length Jacobian (lower is better)
  double d_log_det_information = 0.0;  // log det S, S in 1/m^2 (higher is better)
  double a_trace_covariance_m2 = 0.0;  // trace S^-1 (lower is better)
  double e_min_eigenvalue = 0.0;       // smallest eigenvalue of S, 1/m^2 (higher is better)
  int information_size = 0;            // S is square of this size, 3m - 1 (set by EvaluateCriteria)
};

// Information of the 3m - 1 gauge-fixed geometric parameters a1z a2x a2z ... amz l10 ... lm0
// (1/m^2, square of that size) already gathered by an earlier identification.
using PriorInformation = Eigen::MatrixXd;

// Poses as (x, z, theta) equilibria; fewer than MinDesignPoses(m) poses cannot identify the
// geometry (the criteria are then infinite or zero, as appropriate). With `prior`, D, A and E count it too.
CriteriaValues EvaluateCriteria(const Robot& robot, const std::vector<PlanarPose>& poses,
                                const PriorInformation* prior = nullptr);

// Calibrating in rounds (design --prior): an identification's result.yaml (status converged,
// with standard deviations) as the nominal robot for the next round -- `robot` with the
// estimated exit points and initial lengths -- and the information of every geometric
// parameter but a1x (a1z a2x a2z .. l10 .. lm0), the inverse of their estimated covariance.
// InputError naming the file and key otherwise (also for a result with another cable count).
struct DesignPrior {
  Robot robot;
  PriorInformation information;  // (3m - 1) x (3m - 1)
};
DesignPrior LoadDesignPrior(const Robot& nominal, const std::string& result_yaml_path);

// How much better `set` is than `reference` on criterion c, as a factor (> 1: better):
// kappa_ref / kappa; (det S / det S_ref)^(1/(3m - 1)) (per-eigenvalue geometric mean);
// trace_ref / trace; lambda_min / lambda_min_ref.
double Improvement(Criterion c, const CriteriaValues& set, const CriteriaValues& reference);
// The improvement factor in words that cannot be misread: "3.2 x better than the median of
// 100 random sets", "29 x worse than the median of 100 random sets" (a factor 0.0341 printed
// as such read as an improvement), "as good as ..." within 1 %.
std::string ImprovementText(double factor, int random_sets);

// --min-spacing of a design of `poses` poses, planar and spatial alike: a non-negative number of
// metres, and for two poses or more no more than `reach_m`, the farthest two reference points
// can be apart (the diagonal of `region`, the frame or the frame box, less its margin): a larger
// spacing leaves no plan, said before any solve rather than by Ipopt's failing starts.
// InputError naming the flag otherwise.
void CheckMinSpacing(double min_spacing_m, int poses, double reach_m, const std::string& region);

// A geometry error beyond this is not a calibration problem (the robot file is wrong).
constexpr double kMaxGeometrySigma_m = 0.5;

// The most poses one design plans: with --min-spacing every pair of poses is a constraint of
// Ipopt's problem, n (n - 1) / 2 of them (124,750 at 500), so the problem grows as n squared.
// The Monte Carlo's designed sets are designs too, and share this bound (its random sets
// alone go to kMaxPosesPerSet).
constexpr int kMaxDesignPoses = 500;

// "A: trace of the covariance 1.23e-05 m^2" (4 significant digits), for messages and
// titles; without the name if `with_name` is false.
std::string DescribeCriterion(Criterion c, const CriteriaValues& v, bool with_name = true);

struct DesignOptions {
  int poses = 0;
  // The default: A-optimality (README, "Experiment design", for why not the condition number).
  Criterion criterion = Criterion::kA;
  int starts = 8;
  std::uint64_t seed = 1;
  double min_spacing_m = 0.0;  // 0: off
  int random_sets = 100;       // for the median of random feasible sets in the summary (0: none)
  int max_iterations = 500;    // Ipopt, per start
  // Robustness to the unknown true geometry (robust.h): every pose stays holdable, to first
  // order, for true exit points and initial lengths within robust_sigmas x geometry_sigma_m
  // of nominal (0: nominal bounds only).
  double geometry_sigma_m = 0.01;
  double robust_sigmas = 3.0;
  // Where no start gives verified poses at robust_sigmas, design at the largest k below it
  // that gives some (robustness_search.h; README, "Design never gives up for robustness
  // alone") and say so in the result; off: fail there (SolverFailure), as the Monte Carlo's
  // first try does.
  bool lower_robustness = true;
  // Called before each design of that search, with its k (cablecal design's notice on stderr).
  std::function<void(double)> trying_robustness;
  // Set (e.g. by SIGINT) to stop: Ipopt ends at its next iteration and DesignPoses throws
  // Interrupted.
  const std::atomic<bool>* interrupted = nullptr;
  // Called now and then with (starts done, starts in all), one call at a time (cablecal
  // design's progress bar).
  std::function<void(long, long)> progress;
  // Information already gathered (design --prior), counted by the D, A and E criteria.
  std::optional<PriorInformation> prior_information;
  // Each start's Ipopt solve in a child process of its own, so that starts solve at once on
  // several cores (Debian's MUMPS is not thread-safe within a process); the outcome is the
  // same bit for bit. Off: the solves take turns in this process (an MPI rank, where a fork
  // is unwelcome).
  bool solve_in_child_processes = true;
  // Testing aids: run Ipopt's derivative checker (forward differences with this relative
  // perturbation) and keep its journal in this file.
  bool derivative_test = false;
  double derivative_test_perturbation = 1e-6;
  std::string ipopt_journal_path;
};

struct StartReport {
  int start = 0;
  std::string ipopt_status;
  int iterations = 0;
  bool converged = false;  // Ipopt reported success (or an acceptable point)
  bool verified = false;   // every pose re-verified with the model
  std::string verification_failure;  // why not, when converged but not verified
  double robust_sigmas = 0.0;  // the widest k of the NLP's robustness rows (a widened pose's, README)
  double objective = 0.0;  // the criterion's exact objective (log kappa, -log det S, log trace S^-1,
                           // -log lambda_min), recomputed from the verified poses
};

struct DesignResult {
  int num_cables = 0;              // the robot's m
  std::vector<PlanPose> poses;     // verified equilibria of the best start; for m >= 4 with the
                                   // model's tension distribution (robust.h)
  CriteriaValues criteria;         // recomputed from `poses`, not copied from Ipopt
  CriteriaValues random_median;    // per criterion, over options.random_sets random sets
  int best_start = -1;
  int converged_starts = 0;
  std::vector<StartReport> starts;
  double wall_time_s = 0.0;
  // The robustness k asked for and the one the plan holds for (lower only when no start gave
  // verified poses at the asked k: DesignOptions::lower_robustness), and, then, the sentence
  // that says so (LoweredRobustnessText) and the designs the search ran.
  double robust_sigmas_requested = 0.0;
  double robust_sigmas_achieved = 0.0;
  std::string robustness_note;
  int robustness_designs = 1;
  bool robustness_lowered() const { return robust_sigmas_achieved < robust_sigmas_requested; }
};

// The fewest poses that can identify a robot with m cables: each pose adds m encoder, a laser
// and an inclinometer reading against its own 3 unknowns, m - 1 equations net, for the 3m - 1
// gauge-fixed geometric parameters: ceil((3m - 1) / (m - 1)) (5 for m = 2, 4 for m = 3..8).
int MinDesignPoses(int num_cables);

// Throws InputError for bad options (too few poses, spacing that cannot fit) and
// SolverFailure when no start converges to verified poses (with lower_robustness: not even
// without robustness, k = 0).
DesignResult DesignPoses(const Robot& robot, const DesignOptions& options);

// Why a designed set can be no better than the median random set on its criterion, and
// what to do: the warning `cablecal design` prints and the Python module issues.
// `sigma_option` spells the geometry-sigma option the reader knows ("--geometry-sigma",
// "geometry_sigma").
std::string NoBetterThanRandomWarning(const DesignOptions& options, const std::string& sigma_option);

// summary.yaml of `cablecal design`.
std::string DesignSummaryYaml(const DesignResult& result, const DesignOptions& options,
                              const std::string& command_line);

}  // namespace cablecal
