// Spatial experiment design (README, "Spatial robots", "Experiment design"): n measurement
// poses of a spatial robot, equilibria inside its feasible workspace, that make the
// identification of its geometry from the robot file's sensors best conditioned
// (design/spatial_information.h: the gauge-fixed information S).
//
// Ipopt per start, on every pose's 6 coordinates and m tensions (L-BFGS Hessian, exact first
// derivatives: the criterion's through nested Jets, the constraints' through Jets):
//   W(q) t + w_g(q) = 0 (6 rows; with m < 6 they make the uncontrolled coordinates follow),
//   tensions within [min, max], roll and pitch within the tilt limit and cos(tilt) >=
//   cos(tilt_max), the yaw within home's +-kDefaultSampleYawRange_rad (as sample), the reference
//   point, the centre of mass and every anchor inside the frame box less the margin, every
//   anchor at least the margin from its pulley, and the cable geometry valid (an invalid one
//   is an evaluation error Ipopt steps back from); with --min-spacing every pair of poses'
//   reference points at least that far apart.
// Starts: feasible random sets (SampleSpatialPoses), each from its own stream of the seed,
// solved at once in child processes (as the planar design's); the best verified start wins.
// A solve ends at Ipopt's tolerance or when its criterion has stalled: no iterate of the last 20
// lowered the best clean one's (every bound kept, the poses verified as below) by 1e-4, that
// iterate then the solve's result ("Criterion_Stalled").
// Verified: each pose re-solved by the model (m < 6: the stable equilibrium
// SolveSpatialEquilibrium finds from Ipopt's pose must be that pose; m >= 6: the tensions
// projected exactly onto the equilibrium, or for an identification that does not model the
// tensions the model's own distribution), then CheckSpatialFeasibility.
// Robustness to the unknown true geometry (README, "Spatial robots", "Robust spatial design"):
// the plan is run open loop, so each pose must hold on every true robot whose exit points are
// within k sigma of nominal. Checked with the full forward model (model/forward_statics.h, the
// elastic one for cables with stiffness) on 6m + 8 scenario robots, each exit coordinate moved by
// +-k sigma alone or the platform's mass or one centre-of-mass coordinate by +-k its prior sigma
// (SpatialPlatformPriorSigma: the Monte Carlo draws its true platforms so), and on the nominal
// robot itself when a cable stretches: each pose's commanded
// lengths must settle the platform near the pose, feasible on that robot. The same settled
// states give each bounded quantity c its linearised worst case over the ellipsoid
// |dg / sigma| <= k (g: the exit coordinates and the platform's 4 values, each over its own
// sigma), k |dc/dg|_2 = sqrt(sum over those ((c+ - c-) / 2)^2), and the
// NLP is re-solved from its poses with every bound drawn in by that much (widened for poses
// that failed a scenario), until the poses keep every bound to first order and on every scenario
// robot, or kSpatialRobustRounds re-solves. The starts are made robust two at a time, those
// whose first solves have the lowest criteria first, until one holds (the others are reported
// not made robust). Where no start holds at the requested k, the design
// runs at the largest k that does (design/robustness_search.h) and says so.
// Calibrating in rounds (--prior): the robot is the earlier identification's estimate, and its
// information (SpatialPriorInformation) adds to every S, of the design and of the random sets.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "design/design.h"
#include "design/spatial_information.h"
#include "experiment/spatial_plan.h"
#include "identify/spatial_report.h"  // SpatialIdentifiedGeometry
#include "model/spatial_robot.h"

namespace cablecal {

struct SpatialDesignOptions {
  int poses = 0;
  Criterion criterion = Criterion::kA;  // as planar (README, "Experiment design")
  int starts = 8;
  std::uint64_t seed = 1;
  double min_spacing_m = 0.0;  // 0: off
  int random_sets = 100;       // the median of random feasible sets for comparison (0: none)
  int max_iterations = 3000;   // Ipopt, per start
  // The true exit points' uncertainty the plan must survive, per coordinate (m); unset: the
  // robot file's tracker sigma (its exits' survey) if it has one, else kDefaultSpatialGeometrySigma_m.
  // 0: no robustness (the poses hold on the nominal geometry; a stretching robot's still checked
  // with the elastic forward model).
  std::optional<double> geometry_sigma_m;
  double robust_sigmas = 3.0;    // k (as planar)
  bool lower_robustness = true;  // none holds at k: design at the largest k that does, and say so
  // An earlier identification (design --prior; ReadSpatialIdentifiedGeometry), whose
  // information the criteria count; the robot designed for is then its estimate
  // (CalibratedSpatialRobot), which the caller passes.
  std::optional<SpatialIdentifiedGeometry> prior;
  // Each start's Ipopt solve in a child process of its own, so that starts solve at once on
  // several cores (DesignOptions::solve_in_child_processes: the outcome is the same bit for
  // bit). Off: the solves take turns in this process (Python; montecarlo's
  // design_in_child_processes).
  bool solve_in_child_processes = true;
  // A solve also ends when its criterion has stalled (the file comment); off: only at Ipopt's
  // tolerance (what the tests compare the rule with).
  bool stop_when_stalled = true;
  const std::atomic<bool>* interrupted = nullptr;
  std::function<void(long, long)> progress;  // (starts done, starts), at every k the robustness search tries
  std::function<void(double)> trying_robustness;  // the search is about to design at this k (below the requested)
};

// The fewest poses whose readings can determine the gauge-fixed geometry: each pose adds its
// reading values less its own unknowns (6, and m tensions when the statics are modelled).
int MinSpatialDesignPoses(const SpatialRobot& robot, const SpatialInformationLayout& layout);

struct SpatialStartReport {
  int start = 0;
  std::string ipopt_status;
  int iterations = 0;     // of all its solves, the robust re-solves' included
  bool converged = false;
  bool verified = false;
  std::string verification_failure;
  double objective = 0.0;  // the exact criterion of the verified poses
  int robust_rounds = 0;   // NLP re-solves with the bounds drawn in for robustness
  double first_objective = 0.0;  // the exact criterion of its first solve's verified poses (inf: none)
  // False: not made robust, because starts whose first solves had lower criteria were made robust
  // first and one held (its status and iterations are then its first solve's; it is not verified
  // at the plan's robustness, verification_failure says so, and only first_objective is known).
  bool made_robust = true;
};

struct SpatialDesignResult {
  SpatialInformationLayout layout;
  std::vector<SpatialPlanPose> poses;  // verified equilibria of the best start
  CriteriaValues criteria;             // recomputed from `poses`
  CriteriaValues random_median;        // over options.random_sets random feasible sets
  int best_start = -1;
  int converged_starts = 0;
  std::vector<SpatialStartReport> starts;
  double geometry_sigma_m = 0.0;  // as resolved (options' or the robot file's)
  double robust_sigmas_requested = 0.0;
  double robust_sigmas_achieved = 0.0;  // the k the plan holds for
  std::string robustness_note;          // LoweredRobustnessText when lowered, else ""
  // When lowered: why the requested robustness gave no plan (each start's failure), else "".
  std::string failure_at_requested;
  // With a prior that holds more coordinates than this robot file's sensors need (a result of
  // fewer sensors, or a lab's hold:): which, planned as known; else "".
  std::string prior_note;
  // At the fewest poses (MinSpatialDesignPoses): how few values the readings leave beyond the
  // unknowns, and that such an identification fits the noise exactly and may not converge; else "".
  std::string redundancy_note;
  bool robustness_lowered() const { return robust_sigmas_achieved < robust_sigmas_requested; }
  double wall_time_s = 0.0;
};

// Without a --geometry-sigma and without a tracker survey in the robot file: the planar default.
constexpr double kDefaultSpatialGeometrySigma_m = 0.01;
constexpr int kSpatialRobustRounds = 4;
double DefaultSpatialGeometrySigma(const SpatialRobot& robot);

// What the summary, the console and Python say of the robustness: "each pose holds on the true
// robots with exit points within 3 x 0.0005 m of nominal and a platform within 3 x 0.91 kg and 3 x
// 0.005 m (centre of mass) of the file's (to first order, and on the 57 scenario
// robots with the elastic forward model)".
std::string SpatialRobustnessText(const SpatialRobot& robot, const SpatialDesignResult& result);

// InputError for bad options (too few poses, ...); SolverFailure when no start converges to
// verified poses; Interrupted when options.interrupted was set.
SpatialDesignResult DesignSpatialPoses(const SpatialRobot& robot, const SpatialDesignOptions& options);

// summary.yaml of `cablecal design` on a spatial robot.
std::string SpatialDesignSummaryYaml(const SpatialRobot& robot, const SpatialDesignResult& result,
                                     const SpatialDesignOptions& options, const std::string& command_line);

}  // namespace cablecal
