#include "montecarlo/montecarlo.h"

#include "model/forward_statics.h"

#include <omp.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <algorithm>
#include <map>
#include <numeric>
#include <sstream>
#include <stdexcept>

#include "common/error.h"
#include "common/format.h"
#include "common/parallel.h"
#include "common/random.h"
#include "design/design.h"
#include "model/geometry.h"

namespace cablecal {

const char* ToString(PoseSetDesign d) {
  switch (d) {
    case PoseSetDesign::kRandom: return "random";
    case PoseSetDesign::kOptimized: return "optimized";
    case PoseSetDesign::kD: return "d";
    case PoseSetDesign::kA: return "a";
    case PoseSetDesign::kE: return "e";
    case PoseSetDesign::kCondition: return "condition";
    case PoseSetDesign::kGrid2: return "grid:2x2x2";
    case PoseSetDesign::kGrid3: return "grid:3x3x3";
  }
  return "unknown";
}

int GridSide(PoseSetDesign d) {
  return d == PoseSetDesign::kGrid2 ? 2 : d == PoseSetDesign::kGrid3 ? 3 : 0;
}

Criterion CriterionOf(PoseSetDesign d) {
  switch (d) {
    case PoseSetDesign::kD: return Criterion::kD;
    case PoseSetDesign::kA: return Criterion::kA;
    case PoseSetDesign::kE: return Criterion::kE;
    case PoseSetDesign::kCondition: return Criterion::kCondition;
    default: return DesignOptions{}.criterion;  // "optimized": the design's default
  }
}

std::vector<PoseSetDesign> ParseDesigns(const std::string& text) {
  std::vector<PoseSetDesign> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    PoseSetDesign d;
    if (item == "random") d = PoseSetDesign::kRandom;
    else if (item == "optimized") d = PoseSetDesign::kOptimized;
    else if (item == "d") d = PoseSetDesign::kD;
    else if (item == "a") d = PoseSetDesign::kA;
    else if (item == "e") d = PoseSetDesign::kE;
    else if (item == "condition") d = PoseSetDesign::kCondition;
    else if (item == "grid:2x2x2") d = PoseSetDesign::kGrid2;
    else if (item == "grid:3x3x3") d = PoseSetDesign::kGrid3;
    else throw InputError("--designs", "", "unknown design '" + item + "' (random, optimized, condition, d, a, e; "
                                           "spatial robots also grid:2x2x2, grid:3x3x3)");
    for (PoseSetDesign seen : out) {
      if (seen == d) throw InputError("--designs", "", "'" + item + "' given twice");
      // "optimized" is the default criterion's set: A-optimal. Both would be the same cells twice.
      const auto is = [&](PoseSetDesign x, PoseSetDesign y) { return seen == x && d == y; };
      if (is(PoseSetDesign::kOptimized, PoseSetDesign::kA) || is(PoseSetDesign::kA, PoseSetDesign::kOptimized)) {
        throw InputError("--designs", "", "'optimized' and 'a' are the same design (A-optimal, the default criterion): "
                                          "give one of them");
      }
    }
    out.push_back(d);
  }
  if (out.empty()) throw InputError("--designs", "", "give at least one design");
  return out;
}

std::vector<int> ParsePoseCounts(const std::string& text) {
  std::vector<int> parts;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ':')) {
    double v = 0.0;
    if (!ParseFiniteDouble(item, &v) || v != std::floor(v) || v < 1) {
      throw InputError("--poses", "", "expected first:last[:step] with whole numbers (got '" + text + "')");
    }
    if (v > kMaxPosesPerSet) {
      throw InputError("--poses", "", "at most " + std::to_string(kMaxPosesPerSet) + " poses per set (got '" + item +
                                          "' in '" + text + "')");
    }
    parts.push_back(static_cast<int>(v));
  }
  if (parts.size() == 1) parts.push_back(parts[0]);
  if (parts.size() < 2 || parts.size() > 3) throw InputError("--poses", "", "expected first:last[:step] (got '" + text + "')");
  const int step = parts.size() == 3 ? parts[2] : 1;
  if (parts[0] > parts[1]) throw InputError("--poses", "", "first must not exceed last (got '" + text + "')");
  std::vector<int> out;
  for (int n = parts[0]; n <= parts[1]; n += step) out.push_back(n);
  return out;
}

int MonteCarloCell::failures() const {
  int f = 0;
  for (const TrialOutcome& t : trials) f += !t.ok;
  return f;
}

const std::vector<std::string>& FailureCauses() {
  static const std::vector<std::string> causes = {"design", "sampling", "simulation", "identification"};
  return causes;
}

FailureTally TallyFailures(const MonteCarloResult& r) {
  FailureTally tally;
  for (const MonteCarloCell& c : r.cells) {
    tally.trials += static_cast<long>(c.trials.size());
    tally.failed += c.failures();
    for (const TrialOutcome& t : c.trials) {
      if (!t.ok && !tally.first) tally.first = &t;
    }
  }
  int most = 0;
  std::string most_cause;
  for (const std::string& cause : FailureCauses()) {
    int count = 0;
    for (const MonteCarloCell& c : r.cells) count += c.failures(cause);
    if (count > 0) tally.by_cause += (tally.by_cause.empty() ? "" : ", ") + cause + " " + std::to_string(count);
    if (count > most) {
      most = count;
      most_cause = cause;
    }
  }
  if (most_cause == "design") {
    tally.hint = "the optimized sets could not be designed: cablecal design on the same robot and --poses says why";
  } else if (most_cause == "sampling") {
    tally.hint = "too few feasible poses for the random sets: fewer --poses, or smaller plan margins";
  } else if (most_cause == "simulation") {
    tally.hint = "the true robots could not hold the poses: a smaller --geometry-sigma, or for a spatial robot "
                 "plan margins (--tension-margin, --frame-margin, --tilt-margin-deg), --skip-infeasible, or "
                 "--exact-platform (true platforms drawn from the file's mass and centre-of-mass sigmas move the "
                 "tensions too)";
  } else if (most_cause == "identification") {
    tally.hint = "the identifications failed: more --poses, another sensor, or --loss cauchy against gross readings";
  }
  return tally;
}

void RefuseIfEveryTrialFailed(const MonteCarloResult& r) {
  const FailureTally tally = TallyFailures(r);
  if (tally.trials == 0 || tally.failed < tally.trials) return;
  throw SolverFailure("every one of the " + std::to_string(tally.trials) + " trials failed (" + tally.by_cause +
                      "): no statistics to write; the first: " + (tally.first ? tally.first->failure : std::string("?")) +
                      " (" + tally.hint + ")");
}

int MonteCarloCell::failures(const std::string& cause) const {
  int f = 0;
  for (const TrialOutcome& t : trials) f += !t.ok && t.failure.compare(0, cause.size() + 1, cause + ":") == 0;
  return f;
}

Robot TrueGeometryForTrial(const Robot& nominal, double sigma_m, Gauge gauge, Rng& rng) {
  // The one rule (experiment/simulation.h PerturbGeometry): a1x held, 3m draws whatever the sigmas.
  const double exit_sigma_m =
      gauge == Gauge::kPrior && nominal.sensors.tracker_sigma_m ? *nominal.sensors.tracker_sigma_m : sigma_m;
  return PerturbGeometry(nominal, sigma_m, exit_sigma_m, rng);
}

namespace {

TrialOutcome RunTrial(const Robot& nominal, const MonteCarloOptions& o, int n, PoseSetDesign design, int trial,
                      const std::vector<PlanPose>* designed) {
  const std::uint64_t n64 = static_cast<std::uint64_t>(n), d64 = static_cast<std::uint64_t>(design),
                      t64 = static_cast<std::uint64_t>(trial);
  Rng rng(StreamSeed(o.seed, {n64, d64, t64, 0}));
  TrialOutcome out;
  if (designed && designed->empty()) {
    out.failure = "design: no verified pose set for n=" + std::to_string(n) + ", " + ToString(design);
    return out;
  }
  try {
    Robot truth = TrueGeometryForTrial(nominal, o.geometry_sigma_m, o.gauge, rng);
    truth.p_P_com_m.x() += o.com_error_m;
    const std::vector<PlanPose> poses =
        designed ? *designed : SampleFeasiblePoses(nominal, n, StreamSeed(o.seed, {n64, d64, t64, 1}));
    SimulatedExperiment sim;
    try {
      sim = SimulateExperiment(nominal, truth, poses, SimulationOptions{o.sensors, true, true}, rng);
    } catch (const SolverFailure& e) {
      out.failure = std::string("simulation: ") + e.what();
      return out;
    }
    if (o.outliers.rate > 0.0) {  // a stream of their own: the other draws stay as without outliers
      Rng outlier_rng(StreamSeed(o.seed, {n64, d64, t64, 2}));
      AddOutliers(sim.measurements, nominal.sensors, o.outliers, outlier_rng);
    }
    IdentifyOptions id;
    id.estimator = o.estimator;
    id.gauge = o.gauge;
    id.loss = o.loss;
    if (o.geometry_prior) id.geometry_prior_sigma_m = o.geometry_sigma_m;
    id.equilibrium = o.equilibrium;
    id.compute_covariance = false;
    id.compute_identifiability = false;
    id.check_plausible_geometry = false;  // a wild estimate from a poor pose set is counted, not refused
    const IdentifyResult r = Identify(nominal, sim.measurements, id);
    if (!r.converged()) {
      out.failure = std::string("identification: ") + ToString(r.status) + (r.message.empty() ? "" : " (" + r.message + ")");
      return out;
    }
    CABLECAL_CHECK(static_cast<int>(r.poses.size()) == n, "one pose estimate per pose");
    const GeometryVector g_true = GeometryOf(truth);
    for (int k = 0; k < g_true.size(); ++k) out.errors_m.push_back(r.geometry(k) - g_true(k));  // paper, Eq. (9)
    for (int j = 0; j < n; ++j) out.errors_m.push_back(r.poses[j].q(0) - sim.true_poses[j](0));
    out.ok = true;
  } catch (const SolverFailure& e) {
    out.failure = std::string("sampling: ") + e.what();
  }
  return out;
}


}  // namespace

void ValidateStudyOptions(const MonteCarloOptions& o, int geometry_count) {
  if (o.trials < 1) throw InputError("--trials", "", "must be at least 1");
  // Every successful trial keeps its geometric errors and one per pose (8 bytes each): refuse a
  // study that would not fit in memory before starting it, naming the size.
  double bytes = 0.0;
  for (const int n : o.pose_counts) {
    bytes += 8.0 * (geometry_count + n) * o.trials * static_cast<double>(o.designs.size());
  }
  if (bytes > kMaxStudyBytes) {
    char buffer[160];
    std::snprintf(buffer, sizeof(buffer), "the study would keep %.3g GB of errors (at most %.3g GB): fewer trials or "
                  "pose counts, or split it into several runs", bytes / 1e9, kMaxStudyBytes / 1e9);
    throw InputError("--trials", "", buffer);
  }
  if (o.pose_counts.empty()) throw InputError("--poses", "", "no pose counts");
  for (const int n : o.pose_counts) {
    if (n > kMaxPosesPerSet) {
      throw InputError("--poses", "", "at most " + std::to_string(kMaxPosesPerSet) + " poses per set (got " +
                                          std::to_string(n) + ")");
    }
  }
  if (o.designs.empty()) throw InputError("--designs", "", "no designs");
  if (!(o.geometry_sigma_m >= 0.0 && o.geometry_sigma_m <= kMaxGeometrySigma_m)) {
    throw InputError("--geometry-sigma", "", "must be between 0 and " + FormatDouble(kMaxGeometrySigma_m) +
                                                 " m: a larger error is not a calibration problem (got " +
                                                 FormatDouble(o.geometry_sigma_m) + ")");
  }
}

void ValidateOptions(const MonteCarloOptions& o, const Robot* nominal) {
  if (o.geometry_prior && !(o.geometry_sigma_m >= kMinGeometryPriorSigma_m)) {
    throw InputError("--geometry-prior", "", "needs --geometry-sigma of at least " + FormatDouble(kMinGeometryPriorSigma_m) +
                                                 " m: the prior is the spread the true geometry is drawn with (got " +
                                                 FormatDouble(o.geometry_sigma_m) + ")");
  }
  if (o.geometry_prior && o.estimator != Estimator::kMaximumLikelihood) {
    throw InputError("--geometry-prior", "", "needs --estimator ml (the paper estimator's residuals are not in sigmas)");
  }
  if (o.gauge == Gauge::kPrior && o.estimator != Estimator::kMaximumLikelihood) {
    throw InputError("--gauge prior", "", "needs --estimator ml: the paper estimator's residuals are not in sigmas, so the tracker's prior, in sigmas, would outweigh every reading (the exits would stay at the robot file's)");
  }
  if (o.equilibrium && (o.estimator != Estimator::kMaximumLikelihood || (nominal && nominal->num_cables() >= 3))) {
    throw InputError("--equilibrium", "",
                     o.estimator != Estimator::kMaximumLikelihood
                         ? std::string("needs --estimator ml (the paper estimator fixes theta at the inclinometer's reading)")
                         : "applies to robots with fewer cables than the pose's 3 degrees of freedom (2 cables): with " +
                               std::to_string(nominal->num_cables()) + " the cables hold theta");
  }
  if (!(std::abs(o.com_error_m) <= 0.1)) throw InputError("--com-error", "", "must be a number of m, at most 0.1 in size");
  if (o.loss.kind != LossKind::kNone && o.estimator != Estimator::kMaximumLikelihood) {
    throw InputError("--loss", "", "needs --estimator ml (the paper estimator's residuals are not in sigmas)");
  }
  if (nominal && o.gauge == Gauge::kPrior && !nominal->sensors.tracker_sigma_m) {
    throw InputError(nominal->source, "sensors.tracker.sigma", "is needed for --gauge prior");
  }
  ValidateStudyOptions(o, PlanarLayout(nominal ? nominal->num_cables() : 2).size());
  // The design's rule (design.h MinDesignPoses): 5 poses for 2 cables, 4 for 3 to 8.
  const int fewest = MinDesignPoses(nominal ? nominal->num_cables() : 2);
  for (const int n : o.pose_counts) {
    if (n < fewest) {
      throw InputError("--poses", "", "at least " + std::to_string(fewest) + " poses are needed to identify the geometry" +
                                          (nominal ? " of " + std::to_string(nominal->num_cables()) + " cables" : "") +
                                          " (got " + std::to_string(n) + ")");
    }
  }
  for (const PoseSetDesign d : o.designs) {
    if (GridSide(d) > 0) {
      throw InputError("--designs", "", std::string(ToString(d)) + " is a spatial robot's pose set (the peer's grid of "
                                        "positions); for a planar robot use random or a criterion");
    }
  }
}

std::vector<PlanPose> MakeDesignedSet(const Robot& nominal, const MonteCarloOptions& o, const DesignedSetKey& key) {
  DesignOptions opt;
  opt.poses = key.n;
  opt.criterion = CriterionOf(key.design);
  opt.starts = o.design_starts;
  opt.seed = StreamSeed(o.seed, {static_cast<std::uint64_t>(key.n), static_cast<std::uint64_t>(key.design), 0xde5});
  opt.random_sets = 0;
  opt.geometry_sigma_m = o.geometry_sigma_m;  // the plan must survive the same true robots
  opt.interrupted = o.interrupted;
  opt.solve_in_child_processes = o.design_in_child_processes;
  opt.lower_robustness = false;  // more starts first, at the full robustness
  try {
    return DesignPoses(nominal, opt).poses;
  } catch (const SolverFailure&) {
    // No start converged within Ipopt's iteration limit: add starts (the first ones are
    // the same streams, so this only extends the search), and if those find none at the
    // full robustness, take the largest k that gives a set, and say so.
    opt.starts = 4 * o.design_starts;
    opt.lower_robustness = true;
  }
  try {
    DesignResult r = DesignPoses(nominal, opt);
    if (r.robustness_lowered()) {
      std::fprintf(stderr, "cablecal: montecarlo: the designed set for n=%d, %s: robustness lowered: %s\n", key.n,
                   ToString(key.design), r.robustness_note.c_str());
    }
    return r.poses;
  } catch (const SolverFailure& e) {
    // This cell's trials fail with cause "design"; the other cells still run.
    std::fprintf(stderr, "cablecal: montecarlo: no designed set for n=%d, %s: %s\n", key.n, ToString(key.design),
                 e.what());
    return {};
  }
}

void ForEachDesignedSet(const std::vector<DesignedSetKey>& keys, const std::function<void(std::size_t)>& make) {
  // The largest sets first (their Ipopt solves take longest), so that no large one is left to
  // finish alone at the end; chunks of one key, handed out as threads free up.
  std::vector<std::size_t> order(keys.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return keys[a].n > keys[b].n; });
  ParallelFor(static_cast<long>(order.size()), 1, [&](long k) { make(order[static_cast<std::size_t>(k)]); });
}

ShareResult RunShare(const Robot& robot, const MonteCarloOptions& o, const DesignedSets& designed,
                     const StudyShare& share) {
  // The nominal initial lengths (the home equilibrium) once, not in every trial's sampling and
  // identification: the same numbers, set in the robot.
  const Robot nominal = WithGeometry(robot, GeometryOf(robot));
  return RunShareTrials(o, share, [&](int n, PoseSetDesign d, int trial) {
    const auto it = designed.find({n, static_cast<int>(d)});
    if (d != PoseSetDesign::kRandom && it == designed.end()) {
      throw std::logic_error("no designed set for n=" + std::to_string(n) + " " + ToString(d));
    }
    return RunTrial(nominal, o, n, d, trial, it == designed.end() ? nullptr : &it->second);
  });
}

ShareResult RunShareTrials(const MonteCarloOptions& o, const StudyShare& share, const TrialFunction& run_trial) {
  const long total = StudyItems(o);
  std::vector<long> items;
  items.reserve(ItemsOwned(share, total));
  for (long item = 0; item < total; ++item) {
    if (OwnsItem(share, item)) items.push_back(item);
  }
  const int designs = static_cast<int>(o.designs.size());
  ShareResult out;
  out.outcomes.resize(items.size());
  const long owned = static_cast<long>(items.size());
  std::atomic<long> done{0};
  std::atomic<bool> stop{false}, interrupted{false};
#pragma omp parallel for schedule(dynamic, 4)
  for (long k = 0; k < owned; ++k) {
    if (stop.load(std::memory_order_relaxed)) continue;
    if (o.interrupted && o.interrupted->load()) {
      interrupted = true;
      stop = true;
      continue;
    }
    const long cell = items[k] / o.trials;
    const int n = o.pose_counts[cell / designs];
    const PoseSetDesign d = o.designs[cell % designs];
    try {
      out.outcomes[k] = run_trial(n, d, static_cast<int>(items[k] % o.trials));
    } catch (...) {
      // Not a failed trial (those are caught in RunTrial) but something that makes the
      // whole share suspect, such as running out of memory: stop and report it.
#pragma omp critical(cablecal_share_failure)
      if (!out.error) {
        out.error = std::current_exception();
        const std::string what = OutcomeOf(out.error).message;  // the message main() would print
        out.failure = what.empty() ? "unknown exception" : what;
      }
      stop = true;
      continue;
    }
    const long now = ++done;
    if (o.progress && omp_get_thread_num() == 0) o.progress(now, owned);
  }
  out.interrupted = interrupted.load();
  if (!out.failure.empty()) out.outcomes.clear();
  if (o.progress && !stop.load()) o.progress(owned, owned);
  return out;
}

MonteCarloResult RunMonteCarlo(const Robot& nominal, const MonteCarloOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  ValidateOptions(o, &nominal);
  MonteCarloResult result;
  // Designed sets first: once per (n, criterion), each from its own seed stream, several at once
  // (each start's Ipopt solve in a process of its own, design.h), so that the threads stay
  // busy while one set's starts take longer than another's.
  const std::vector<DesignedSetKey> keys = DesignedSetKeys(o);
  std::vector<std::vector<PlanPose>> sets(keys.size());
  ForEachDesignedSet(keys, [&](std::size_t i) {
    if (o.interrupted && o.interrupted->load()) return;
    sets[i] = MakeDesignedSet(nominal, o, keys[i]);
  });
  if (o.interrupted && o.interrupted->load()) {
    result.interrupted = true;
    return result;
  }
  DesignedSets designed;
  for (std::size_t i = 0; i < keys.size(); ++i) designed[{keys[i].n, static_cast<int>(keys[i].design)}] = std::move(sets[i]);
  std::vector<ShareResult> shares(1);
  shares[0] = RunShare(nominal, o, designed, StudyShare{0, 1});
  if (shares[0].error) std::rethrow_exception(shares[0].error);  // out of memory: exit 2, as anywhere
  if (!shares[0].failure.empty()) throw std::runtime_error(shares[0].failure);
  if (shares[0].interrupted) {
    result.interrupted = true;
    return result;
  }
  result = AssembleShares(o, std::move(shares), PlanarStudyNames(nominal.num_cables()));
  result.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return result;
}

}  // namespace cablecal
