// montecarlo: how accurate will the calibration be? Simulates the whole experiment many
// times (true geometry, pose set, sensor noise, identification) and collects the error of
// every identified variable, per pose count n and pose-set design.
//
// Every trial's random stream is derived from (seed, n, design, trial) alone and every
// trial writes its own slot, so results are bit-identical for any thread count. A failed
// trial (the true robot cannot hold a pose, or the identification does not converge) is
// counted per cell, never dropped silently.
// Depends on design/ (optimized pose sets), identify/, workspace/, model/.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "identify/experiment.h"
#include "identify/identify.h"
#include "model/robot.h"
#include "workspace/workspace.h"

namespace cablecal {

// Pose-set designs: a fresh random feasible set per trial, or a set designed once per n
// with one of the experiment-design criteria ("optimized" is the condition number).
enum class PoseSetDesign { kRandom = 0, kOptimized = 1, kD = 2, kA = 3, kE = 4 };
const char* ToString(PoseSetDesign d);
std::vector<PoseSetDesign> ParseDesigns(const std::string& text);  // "random,optimized,d"
// "6:50" or "6:50:2" (first:last[:step]); InputError naming --poses otherwise.
std::vector<int> ParsePoseCounts(const std::string& text);

struct MonteCarloOptions {
  std::vector<int> pose_counts;
  std::vector<PoseSetDesign> designs;
  int trials = 0;
  Estimator estimator = Estimator::kMaximumLikelihood;
  Gauge gauge = Gauge::kA1x;
  NoisySensors sensors = NoisySensors::kBoth;
  double geometry_sigma_m = 0.01;
  std::uint64_t seed = 1;
  int design_starts = 2;  // Ipopt starts per designed set (4x as many if none converges)
  // Called from one thread now and then with (trials done, trials in all).
  std::function<void(long, long)> progress;
  const std::atomic<bool>* interrupted = nullptr;  // set (e.g. by SIGINT) to stop early
};

struct TrialOutcome {
  bool ok = false;
  std::string failure;             // "simulation: ..." or "identification: ..."
  std::vector<double> errors_m;    // identified - true: a1x a1z a2x a2z l10 l20 x1..xn
};

struct MonteCarloCell {
  int n = 0;
  PoseSetDesign design = PoseSetDesign::kRandom;
  std::vector<TrialOutcome> trials;
  int failures() const;
};

struct MonteCarloResult {
  std::vector<MonteCarloCell> cells;  // n-major, then designs in the order given
  bool interrupted = false;
  double wall_time_s = 0.0;
};

// Throws InputError for bad options and SolverFailure if a designed set cannot be made.
MonteCarloResult RunMonteCarlo(const Robot& nominal, const MonteCarloOptions& options);

// The true geometry of one trial: nominal with every parameter perturbed by N(0, sigma^2),
// except what the gauge defines: a1x under `a1x` (the frame's origin is exit point 1), and
// under `prior` the exit points by the tracker's sigma (what the prior assumes).
Robot TrueGeometryForTrial(const Robot& nominal, double sigma_m, Gauge gauge, Rng& rng);

// Parameter names of the summary: the geometric ones, x4 (the 4th pose's x, as the paper's
// figures) and x_all (every pose's x pooled).
std::vector<std::string> SummaryParameters();

struct ErrorStats {
  int count = 0;
  double mean = 0, std = 0, rms = 0, max_abs = 0, share_within_5mm = 0;
};
ErrorStats Summarise(const MonteCarloCell& cell, const std::string& parameter);

std::string ErrorsCsv(const MonteCarloResult& r);   // n,design,trial,parameter,error
std::string SummaryCsv(const MonteCarloResult& r);  // n,design,parameter,mean,std,rms,max_abs,share_within_5mm,failures
std::string SummaryMarkdown(const MonteCarloResult& r, const std::string& title);

}  // namespace cablecal
