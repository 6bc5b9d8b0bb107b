// montecarlo: how accurate will the calibration be? Simulates the whole experiment many
// times (true geometry, pose set, sensor noise, identification) and collects the error of
// every identified variable, per pose count n and pose-set design.
//
// Every trial's random stream is derived from (seed, n, design, trial) alone and every
// trial writes its own slot, so results are bit-identical for any thread count. A failed
// trial (the true robot cannot hold a pose, or the identification does not converge) is
// counted per cell, never dropped silently.
//
// A study can also be split into shares (one per MPI rank, say): each share makes some of
// the designed sets and runs some of the trials, and the shares' outcomes are assembled
// into exactly the result of the whole run (montecarlo/mpi.h does this over MPI).
// Depends on design/ (optimized pose sets), identify/, workspace/, model/.
#pragma once

#include <exception>
#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "design/design.h"  // Criterion
#include "experiment/experiment.h"
#include "identify/identify.h"
#include "model/robot.h"
#include "workspace/workspace.h"

namespace cablecal {

// Pose-set designs: a fresh random feasible set per trial, or a set designed once per n
// with one of the experiment-design criteria: "optimized" is the design's default criterion
// (A-optimality, README "Experiment design"), "condition" the paper's condition number. The
// numbers are part of every trial's seed stream: never renumber them. The grids (spatial robots
// only, "grid:2x2x2", "grid:3x3x3") are the peer's pose sets, evenly spaced positions at home's
// orientation (experiment/spatial_plan.h GridSpatialPoses): side^3 poses, so a study runs them
// at that n alone.
enum class PoseSetDesign { kRandom = 0, kOptimized = 1, kD = 2, kA = 3, kE = 4, kCondition = 5, kGrid2 = 6, kGrid3 = 7 };
const char* ToString(PoseSetDesign d);
std::vector<PoseSetDesign> ParseDesigns(const std::string& text);  // "random,optimized,d,grid:2x2x2"
// The grid's side (2, 3), or 0 for a design that is not a grid.
int GridSide(PoseSetDesign d);
// A criterion design's criterion ("optimized": the design's default, A).
Criterion CriterionOf(PoseSetDesign d);
// "6:50" or "6:50:2" (first:last[:step]); InputError naming --poses otherwise.
std::vector<int> ParsePoseCounts(const std::string& text);
// Per pose set of a study (ParsePoseCounts, ValidateOptions): bounds a study's trials and
// errors. A designed set is a design and stops at design.h's kMaxDesignPoses.
constexpr int kMaxPosesPerSet = 1000;

struct MonteCarloOptions {
  std::vector<int> pose_counts;
  std::vector<PoseSetDesign> designs;
  int trials = 0;
  Estimator estimator = Estimator::kMaximumLikelihood;
  Gauge gauge = Gauge::kA1x;
  NoisySensors sensors = NoisySensors::kBoth;
  double geometry_sigma_m = 0.01;
  RobustLoss loss;       // of every trial's identification (identify --loss)
  // Identify every trial with a prior on the geometry of geometry_sigma_m (identify
  // --geometry-prior): what the lab knew before measuring, so a trial never knows less.
  bool geometry_prior = false;
  bool equilibrium = kDefaultEquilibrium;  // of every trial's identification (identify --equilibrium)
  // The true robot's centre of mass off the nominal file's by this along the platform's x (m):
  // the identification assumes the file's, so this is what a wrong platform.com costs.
  double com_error_m = 0.0;
  OutlierModel outliers;  // gross readings added to every trial's (experiment/simulation.h)
  std::uint64_t seed = 1;
  int design_starts = 2;  // Ipopt starts per designed set (4x as many if none converges)
  // The designs' Ipopt solves in child processes (DesignOptions::solve_in_child_processes);
  // off on MPI ranks, where a fork is unwelcome.
  bool design_in_child_processes = true;
  // Called from one thread now and then with (trials done, trials in all).
  std::function<void(long, long)> progress;
  const std::atomic<bool>* interrupted = nullptr;  // set (e.g. by SIGINT) to stop early
};

struct TrialOutcome {
  bool ok = false;
  std::string failure;  // "<cause>: why", cause one of FailureCauses()
  std::vector<double> errors_m;    // identified - true: the 3m geometric parameters (a1x a1z ... l10 ...), x1..xn
  // Spatial studies with skip_infeasible: the poses this trial's true robot could not hold
  // (their x error is NaN, left out of every statistic and of errors.csv).
  int skipped_poses = 0;
};

struct MonteCarloCell {
  int n = 0;
  PoseSetDesign design = PoseSetDesign::kRandom;
  std::vector<TrialOutcome> trials;
  int failures() const;
  int failures(const std::string& cause) const;
};

// Why a trial failed: "design" (no verified pose set for its cell), "sampling" (no random
// feasible set), "simulation" (the true robot cannot hold a commanded pose, or settles
// outside its workspace: beyond a tension limit, the inclinometer range or the margin),
// "identification" (not converged, rank-deficient or poor fit).
const std::vector<std::string>& FailureCauses();

struct MonteCarloResult {
  // The geometric errors' names, in the order of TrialOutcome::errors_m (the robot's kind's
  // layout: a1x a1z ... l10 ... planar, a1x a1y a1z ... l10 ... spatial); then each pose's x.
  std::vector<std::string> geometry_names;
  // The ones the gauge holds (equal in the identified and the true geometry: the frame's
  // definition, not estimates): a1x planar, the data's choice spatial.
  std::vector<std::string> held_names;
  std::vector<MonteCarloCell> cells;  // n-major, then designs in the order given
  bool interrupted = false;
  double wall_time_s = 0.0;
  double geometry_sigma_m = 0.0;  // what the lab knew before measuring (the options')
  bool geometry_prior = false;    // the trials were identified with it as a prior
  bool geometry_prior_served = true;  // --geometry-prior exists for this kind (not yet spatial)
};

// A run's failed trials: how many of how many, by cause ("simulation 4, design 2": the causes
// with none left out, in FailureCauses' order), and the first failed trial (nullptr if none).
struct FailureTally {
  long trials = 0;
  long failed = 0;
  std::string by_cause;
  const TrialOutcome* first = nullptr;
  // What may help, for the cause with the most failures (the first in FailureCauses' order on a
  // tie); empty when none failed.
  std::string hint;
};
FailureTally TallyFailures(const MonteCarloResult& result);

// A run in which no trial succeeded has no statistics: SolverFailure counting the failures by
// cause and quoting the first trial's reason (the montecarlo command's exit 3 with nothing
// written, Python's SolverError), not a table of zeros or n/a. (reproduce keeps a configuration
// whose every trial fails: it is a row of its study.)
void RefuseIfEveryTrialFailed(const MonteCarloResult& result);

// The cells whose calibration knows a geometric parameter hardly better than the lab did before
// measuring (its sigma above kDataAddLittle x geometry_sigma_m), worst first within each cell:
// "n=6 random: a2z 13.1 mm, l20 11.2 mm". `worse` keeps only those above geometry_sigma_m.
std::vector<std::string> CellsThatAddLittle(const MonteCarloResult& r, bool worse);

// Throws InputError for bad options and SolverFailure if a designed set cannot be made.
MonteCarloResult RunMonteCarlo(const Robot& nominal, const MonteCarloOptions& options);
// The InputErrors of RunMonteCarlo; with `nominal`, also what the options need of the robot
// (a tracker sigma for --gauge prior).
// The memory bound counts 3m geometric errors per trial (m = 2 without `nominal`).
void ValidateOptions(const MonteCarloOptions& options, const Robot* nominal = nullptr);
constexpr double kMaxStudyBytes = 4e9;  // the errors a study keeps in memory, at most
// The checks of any study, whatever the robot's kind: trials, memory (geometry_count errors
// plus one per pose, per successful trial), pose counts, designs, geometry sigma.
void ValidateStudyOptions(const MonteCarloOptions& options, int geometry_count);

// ---- Splitting a study into shares -------------------------------------------------------
// Items are the study's trials numbered cell by cell (cells n-major, then designs in the
// order given). Share k of K owns the chunks of kChunkTrials consecutive items whose chunk
// index is k modulo K, so every share gets a similar mix of cheap (small n) and costly
// items; designed sets are dealt round-robin too. Every item's result depends only on its
// own seed stream, so how a study is split never changes a number.
struct StudyShare {
  int index = 0;
  int count = 1;
};
constexpr long kChunkTrials = 4;
long StudyItems(const MonteCarloOptions& options);  // cells x trials
bool OwnsItem(const StudyShare& share, long item);
long ItemsOwned(const StudyShare& share, long items);

// The designed sets a study needs, one per (n, non-random design), in a fixed order; the
// i-th is made by share i modulo K.
struct DesignedSetKey {
  int n = 0;
  PoseSetDesign design = PoseSetDesign::kRandom;
};
std::vector<DesignedSetKey> DesignedSetKeys(const MonteCarloOptions& options);
using DesignedSets = std::map<std::pair<int, int>, std::vector<PlanPose>>;  // (n, design)
// An empty set if no start gives verified poses, even after 4x as many starts (the reason
// goes to stderr, naming n and the criterion): that cell's trials then fail with cause "design".
std::vector<PlanPose> MakeDesignedSet(const Robot& nominal, const MonteCarloOptions& options,
                                      const DesignedSetKey& key);
// Calls make(i) for every key i on the OpenMP threads, the largest n first; each designed set
// depends on its own seed stream only, so the order changes no number. An exception of any
// call is rethrown once all have ended (common/parallel.h).
void ForEachDesignedSet(const std::vector<DesignedSetKey>& keys, const std::function<void(std::size_t)>& make);

struct ShareResult {
  std::vector<TrialOutcome> outcomes;  // one per owned item, in increasing item order
  bool interrupted = false;
  std::string failure;  // why this share could not finish (not a failed trial); then no outcomes
  std::exception_ptr error;  // the exception behind `failure`, rethrown by a run of one process
};
// Runs the share's trials with OpenMP, whatever the robot's kind: run_trial(n, design, trial)
// is one trial's outcome, depending on its own seed stream only (a failed trial is an outcome).
// An unexpected exception in a trial stops the share and is returned in `failure`.
using TrialFunction = std::function<TrialOutcome(int n, PoseSetDesign design, int trial)>;
ShareResult RunShareTrials(const MonteCarloOptions& options, const StudyShare& share, const TrialFunction& run_trial);
// The planar robot's trials; `designed` holds at least the sets of its cells.
ShareResult RunShare(const Robot& nominal, const MonteCarloOptions& options, const DesignedSets& designed,
                     const StudyShare& share);
// The result of the whole study from shares[k] = the result of share k of shares.size().
// Every share must have finished (no failure, not interrupted).
// `names`: what the errors are (MonteCarloResult::geometry_names, held_names).
struct StudyNames {
  std::vector<std::string> geometry, held;
};
StudyNames PlanarStudyNames(int num_cables);  // GeometryNames; a1x held
MonteCarloResult AssembleShares(const MonteCarloOptions& options, std::vector<ShareResult>&& shares,
                                const StudyNames& names);
// The cells in which `share` owns trials, as "n=6 random (8 of 20 trials), ...", at most
// `max_cells` of them named: what is lost when that share fails.
std::string DescribeShareCells(const MonteCarloOptions& options, const StudyShare& share, int max_cells = 12);

// Byte encodings for sending outcomes and pose sets between processes of one job (same
// architecture: doubles are copied bit for bit). Decoding throws std::runtime_error on a
// malformed buffer.
std::string EncodeOutcomes(const std::vector<TrialOutcome>& outcomes);
std::vector<TrialOutcome> DecodeOutcomes(const std::string& bytes);
std::string EncodePoses(const std::vector<PlanPose>& poses);
std::vector<PlanPose> DecodePoses(const std::string& bytes);

// The true geometry of one trial: PerturbGeometry's one rule (experiment/simulation.h): every
// parameter but a1x (which fixes F's x origin, under every gauge) perturbed by N(0, sigma^2),
// the exit points by the tracker's sigma under `prior` (what the prior assumes).
Robot TrueGeometryForTrial(const Robot& nominal, double sigma_m, Gauge gauge, Rng& rng);

// Parameter names of the summary: the geometric ones (3 per cable), x4 (the 4th pose's x, as
// the paper's figures) and x_all (every pose's x pooled).
std::vector<std::string> SummaryParameters(const std::vector<std::string>& geometry_names);

struct ErrorStats {
  int count = 0;
  double mean = 0, std = 0, rms = 0, max_abs = 0, share_within_5mm = 0;
};
ErrorStats Summarise(const MonteCarloCell& cell, const std::vector<std::string>& geometry_names,
                     const std::string& parameter);

// The study's files (montecarlo/report.cc, their one writer).
std::string ErrorsCsv(const MonteCarloResult& r);    // n,design,trial,parameter,error
std::string SummaryCsv(const MonteCarloResult& r);   // n,design,parameter,mean,std,rms,max_abs,share_within_5mm,failures
std::string FailuresCsv(const MonteCarloResult& r);  // n,design,trial,cause,reason: one row per failed trial
std::string SummaryMarkdown(const MonteCarloResult& r, const std::string& title);
// How the cells of `design` compare with every other design's cell at the same n (a markdown
// table, one row per pair): of the geometric parameters the gauge leaves free, how many have a
// smaller sigma under `design`, the median and the largest ratio sigma(design) / sigma(other)
// (naming its parameter), the failed trials of both, and whether `design` holds there: every
// sigma smaller and at most kComparisonFailureSlack of the trials more failed. A pair with a
// cell of fewer than two successful trials is n/a.
constexpr double kComparisonFailureSlack = 0.02;
std::string DesignComparisonMarkdown(const MonteCarloResult& r, PoseSetDesign design);

}  // namespace cablecal
