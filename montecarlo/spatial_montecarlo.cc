#include "montecarlo/spatial_montecarlo.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <limits>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "common/error.h"
#include "common/format.h"
#include "common/random.h"
#include "design/spatial_design.h"
#include "experiment/spatial_simulation.h"

namespace cablecal {

namespace {

// Noise-free readings of the nominal robot at `n` poses the planning robot samples (the study's
// own stream): what the gauge analysis and the identifiability check look at.
std::vector<SpatialMeasurement> NominalReadings(const SpatialRobot& nominal, const SpatialRobot& planning,
                                                const SpatialMonteCarloOptions& o, int n) {
  const std::vector<SpatialPlanPose> plan =
      SampleSpatialPoses(planning, n, StreamSeed(o.study.seed, {0x9a0e, static_cast<std::uint64_t>(n)}), o.yaw_range_rad);
  SpatialSimulationOptions clean;
  clean.noisy = NoisySensors::kNone;
  clean.encoder_noise = false;
  Rng unused(0);
  return SimulateSpatialExperiment(planning, nominal, plan, clean, unused).measurements;
}

SpatialIdentifyOptions TrialIdentifyOptions(const SpatialMonteCarloOptions& o, const std::vector<std::string>& held) {
  SpatialIdentifyOptions id;
  id.loss = o.study.loss;
  id.statics = o.statics;
  // More than identify's default 200: a direction the sensors see weakly (a rotation about z
  // with one tilted swivel axis, say) takes a few hundred iterations, and a study should show
  // the wide spread it leaves rather than count the trials as failed (a new user's robot: 4 of 4
  // trials not converged at 200, all converged at 2000, sigmas of decimetres).
  id.max_iterations = kSpatialTrialMaxIterations;
  // A wild estimate from a poor pose set is a result to count (the planar Monte Carlo's rule).
  id.check_plausible_geometry = false;
  id.reading_leverage = false;  // no trial reads it
  id.retry_without_plan = false;  // each trial's plan is its readings' own (file comment of the option)
  id.gauge.kind = SpatialGaugeKind::kHold;
  id.gauge.held = held;
  return id;
}

// The exit coordinates the study holds (file comment): the default gauge's choice on noise-free
// readings at the fewest poses, which also says whether those poses can identify the geometry.
std::vector<std::string> StudyGauge(const SpatialRobot& nominal, const SpatialRobot& planning,
                                    const SpatialMonteCarloOptions& o) {
  const int fewest = *std::min_element(o.study.pose_counts.begin(), o.study.pose_counts.end());
  std::vector<SpatialMeasurement> readings;
  try {
    readings = NominalReadings(nominal, planning, o, fewest);
  } catch (const SolverFailure& e) {
    // With plan margins, they are the likelier cause: name them (the flag itself when one is given).
    std::string flag, list;
    int given = 0;
    const auto margin = [&](double value, const char* name, const std::string& shown) {
      if (!(value > 0.0)) return;
      flag = name;
      list += (given++ ? ", " : "") + std::string(name) + " " + shown;
    };
    // Rounded: the tilt margin comes back from radians (0.5 degrees would read 0.49999999999999994).
    margin(o.plan_tension_margin_N, "--tension-margin", Rounded(o.plan_tension_margin_N, 6) + " N");
    margin(o.plan_margin_m, "--frame-margin", Rounded(o.plan_margin_m, 6) + " m");
    margin(o.plan_tilt_margin_rad, "--tilt-margin-deg", Rounded(o.plan_tilt_margin_rad * 180.0 / M_PI, 6));
    if (given > 0) {
      throw InputError(given == 1 ? flag : "--poses", "",
                       "no " + std::to_string(fewest) + " feasible poses to study within the plan margins (" + list +
                           "): " + e.what() + "; reduce the margins");
    }
    throw InputError("--poses", "", "no " + std::to_string(fewest) + " feasible poses to study: " + e.what());
  }
  SpatialIdentifyOptions id;
  id.statics = o.statics;
  SpatialGaugeAnalysis gauge;
  try {
    gauge = AnalyzeSpatialGauge(planning, readings, id);
  } catch (const InputError& e) {
    throw InputError("--poses", "", std::to_string(fewest) + " poses of " + nominal.name +
                                        " with its sensors cannot identify the geometry: " + e.what());
  }
  std::vector<std::string> held;
  for (const int k : gauge.held) held.push_back(gauge.names[k]);
  return held;
}

// n of the pool's poses, drawn without replacement (a partial Fisher-Yates shuffle), in draw order.
std::vector<SpatialPlanPose> DrawFromPool(const std::vector<SpatialPlanPose>& pool, int n, std::uint64_t seed) {
  Rng rng(seed);
  std::vector<int> index(pool.size());
  for (std::size_t k = 0; k < index.size(); ++k) index[k] = static_cast<int>(k);
  std::vector<SpatialPlanPose> drawn;
  for (int k = 0; k < n; ++k) {
    const int left = static_cast<int>(index.size()) - k;
    const int pick = k + std::min(left - 1, static_cast<int>(rng.Uniform() * left));
    std::swap(index[k], index[pick]);
    drawn.push_back(pool[index[k]]);
  }
  return drawn;
}

// `nominal`: the file's robot (the true robot is drawn around it); `planning`: PlanningRobot's,
// which plans, commands and identifies. `pool`: the random sets' pool (empty: a fresh sample).
TrialOutcome RunSpatialTrial(const SpatialRobot& nominal, const SpatialRobot& planning, const SpatialMonteCarloOptions& o,
                             const Eigen::VectorXd& l0_m, const std::vector<int>& held, const SpatialIdentifyOptions& id,
                             const std::vector<SpatialPlanPose>& pool, int n, PoseSetDesign design, int trial,
                             const std::vector<SpatialPlanPose>* designed) {
  const std::uint64_t n64 = static_cast<std::uint64_t>(n), d64 = static_cast<std::uint64_t>(design),
                      t64 = static_cast<std::uint64_t>(trial);
  Rng rng(StreamSeed(o.study.seed, {n64, d64, t64, 0}));
  TrialOutcome out;
  if (designed && designed->empty()) {
    out.failure = "design: no pose set for n=" + std::to_string(n) + ", " + ToString(design);
    return out;
  }
  const int m = nominal.num_cables();
  SpatialRobot truth = PerturbSpatialGeometry(nominal, o.study.geometry_sigma_m, rng);
  for (const int k : held) truth.cables[k / 3].p_F_exit_m(k % 3) = nominal.cables[k / 3].p_F_exit_m(k % 3);
  // Its platform from its own stream: the exits' and the noise's draws stay the trial's.
  if (!o.exact_platform) {
    Rng platform_rng(StreamSeed(o.study.seed, {n64, d64, t64, 2}));
    PerturbSpatialPlatform(&truth, platform_rng);
  }
  std::vector<SpatialPlanPose> sampled;
  if (!designed && !pool.empty()) {
    sampled = DrawFromPool(pool, n, StreamSeed(o.study.seed, {n64, d64, t64, 1}));
  } else if (!designed) {
    try {
      sampled = SampleSpatialPoses(planning, n, StreamSeed(o.study.seed, {n64, d64, t64, 1}), o.yaw_range_rad);
    } catch (const SolverFailure& e) {
      out.failure = std::string("sampling: ") + e.what();
      return out;
    }
  }
  SimulatedSpatialExperiment sim;
  try {
    SpatialSimulationOptions lab;
    lab.noisy = o.study.sensors;
    lab.encoder_noise = o.encoder_noise;
    lab.skip_infeasible = o.skip_infeasible;
    sim = SimulateSpatialExperiment(planning, truth, designed ? *designed : sampled, lab, rng);
  } catch (const SolverFailure& e) {
    out.failure = std::string("simulation: ") + e.what();
    return out;
  }
  out.skipped_poses = static_cast<int>(sim.skipped.size());  // counted in a failed trial too
  // Poses skipped (--skip-infeasible) leaving too few to identify: the simulation's failure, as
  // the remedy is the plan's (margins), not the identification's.
  const auto skipped = [&] {
    return std::to_string(sim.skipped.size()) + " of " + std::to_string(n) +
           " poses the true robot could not hold within its limits (--skip-infeasible)";
  };
  if (sim.measurements.empty()) {
    out.failure = "simulation: " + skipped() + ": none left to identify";
    return out;
  }
  // The lab knows what it commanded: each pose starts from its plan pose (identify --plan).
  SpatialIdentifyOptions commanded = id;
  commanded.pose_starts = PoseStartsFromPlan(designed ? *designed : sampled);
  SpatialIdentifyResult r;
  try {
    r = IdentifySpatial(planning, sim.measurements, commanded);
  } catch (const InputError& e) {
    // The study's check passed at its own poses; these ones leave something unseen. The gauge
    // is the study's, not a flag the user gave: named so.
    std::string why = e.what();
    if (e.where() == "--gauge") {
      std::string held;
      for (const std::string& h : id.gauge.held) held += (held.empty() ? "" : ",") + h;
      why = "the study's gauge (holding " + (held.empty() ? std::string("nothing") : held) + "): " + e.problem();
    }
    out.failure = sim.skipped.empty() ? "identification: refused (" + why + ")"
                                      : "simulation: " + skipped() + ", and the rest refused (" + why + ")";
    return out;
  }
  if (!r.converged()) {
    out.failure = std::string("identification: ") + ToString(r.status) + (r.message.empty() ? "" : " (" + r.message + ")");
    return out;
  }
  CABLECAL_CHECK(static_cast<int>(r.poses.size() + sim.skipped.size()) == n, "one pose estimate per held pose");
  for (int i = 0; i < m; ++i) {
    for (int a = 0; a < 3; ++a) out.errors_m.push_back(r.geometry(3 * i + a) - truth.cables[i].p_F_exit_m(a));
  }
  for (int i = 0; i < m; ++i) out.errors_m.push_back(r.geometry(3 * m + i) - l0_m(i));
  // Pose ids are 1..n in plan order; a skipped pose has no reading, hence no estimate.
  std::vector<double> x_errors(n, std::numeric_limits<double>::quiet_NaN());
  for (std::size_t k = 0; k < r.pose_ids.size(); ++k) {
    x_errors[r.pose_ids[k] - 1] = r.poses[k](0) - sim.true_poses[k](0);
  }
  out.errors_m.insert(out.errors_m.end(), x_errors.begin(), x_errors.end());
  out.ok = true;
  return out;
}

}  // namespace

SpatialRobot PlanningRobot(const SpatialRobot& nominal, const SpatialMonteCarloOptions& o) {
  SpatialRobot planning = nominal;
  planning.tension_min_N += o.plan_tension_margin_N;
  planning.tension_max_N -= o.plan_tension_margin_N;
  planning.margin_m += o.plan_margin_m;
  planning.tilt_max_rad -= o.plan_tilt_margin_rad;
  const auto refuse = [&nominal](const char* flag, const std::string& limits, const std::string& value) {
    throw InputError(flag, "", "must be at least 0 and leave room: " + nominal.name + "'s " + limits + " (got " + value + ")");
  };
  if (!(o.plan_tension_margin_N >= 0.0) || !(planning.tension_min_N < planning.tension_max_N)) {
    refuse("--tension-margin",
           "tensions are [" + FormatDouble(nominal.tension_min_N) + ", " + FormatDouble(nominal.tension_max_N) + "] N",
           FormatDouble(o.plan_tension_margin_N) + " N");
  }
  const Eigen::Vector3d side_m = nominal.p_F_frame_max_m - nominal.p_F_frame_min_m;
  if (!(o.plan_margin_m >= 0.0) || !(2.0 * planning.margin_m < side_m.minCoeff())) {
    refuse("--frame-margin", "frame box's smallest side is " + FormatDouble(side_m.minCoeff()) + " m, its margin " +
                                 FormatDouble(nominal.margin_m) + " m",
           FormatDouble(o.plan_margin_m) + " m");
  }
  if (!(o.plan_tilt_margin_rad >= 0.0) || !(planning.tilt_max_rad > 0.0)) {
    refuse("--tilt-margin-deg", "tilt limit is " + FormatDouble(nominal.tilt_max_rad * 180.0 / M_PI) + " degrees",
           FormatDouble(o.plan_tilt_margin_rad * 180.0 / M_PI) + " degrees");
  }
  return planning;
}

std::vector<SpatialPlanPose> MakeSpatialDesignedSet(const SpatialRobot& planning, const SpatialMonteCarloOptions& o,
                                                    const DesignedSetKey& key) {
  try {
    if (GridSide(key.design) > 0) return GridSpatialPoses(planning, GridSide(key.design));
    SpatialDesignOptions opt;
    opt.poses = key.n;
    opt.criterion = CriterionOf(key.design);
    opt.starts = o.study.design_starts;
    opt.seed = StreamSeed(o.study.seed, {static_cast<std::uint64_t>(key.n), static_cast<std::uint64_t>(key.design), 0xde5});
    opt.random_sets = 0;
    opt.max_iterations = o.design_max_iterations;
    opt.interrupted = o.study.interrupted;
    opt.solve_in_child_processes = o.study.design_in_child_processes;
    // The plan must survive the same true robots. Not when the identification leaves the statics
    // out: the design is then made on the cables taken as inextensible (below), a model the
    // forward statics cannot settle with more than 6 cables, so its plans are not robust.
    opt.geometry_sigma_m = o.statics ? o.study.geometry_sigma_m : 0.0;
    opt.lower_robustness = false;                     // more starts first, at the full robustness
    // No start gave verified poses: add starts, as the planar study does (the first ones are the
    // same streams, so this only extends the search), and if those find none at the full
    // robustness, take the largest k that gives a set, and say so.
    const auto design = [&](const SpatialRobot& robot) {
      try {
        return DesignSpatialPoses(robot, opt);
      } catch (const SolverFailure&) {
        SpatialDesignOptions more = opt;
        more.starts = 4 * opt.starts;
        more.lower_robustness = true;
        SpatialDesignResult r;
        try {
          r = DesignSpatialPoses(robot, more);
        } catch (const SolverFailure& e) {
          // Both attempts, so that "none of the 4 starts" reads right beside --design-starts 1.
          throw SolverFailure("with " + std::to_string(opt.starts) + " start" + (opt.starts == 1 ? "" : "s") +
                              ", then with " + std::to_string(more.starts) +
                              " and the robustness lowered where needed: " + e.what());
        }
        if (r.robustness_lowered()) {
          std::fprintf(stderr, "cablecal: montecarlo: the designed set for n=%d, %s: robustness lowered: %s\n", key.n,
                       ToString(key.design), r.robustness_note.c_str());
        }
        return r;
      }
    };
    if (o.statics) return design(planning).poses;
    // Without the statics the identification takes the cables as inextensible: the design's
    // information is that model's, and each designed pose is then planned on the planning robot
    // (its tensions, and its commands with the stretch the lab expects).
    SpatialRobot rigid = planning;
    for (SpatialCable& c : rigid.cables) c.stiffness_N.reset();
    const SpatialHomeReference home = SpatialHome(planning);
    std::vector<SpatialPlanPose> poses;
    for (const SpatialPlanPose& p : design(rigid).poses) {
      const SpatialPoseEvaluation e = EvaluateSpatialPose(planning, p.q);
      if (!e.feasible()) throw SolverFailure("a designed pose is not feasible with the stretching cables");
      poses.push_back(MakeSpatialPlanPose(planning, e.equilibrium, home));
    }
    return poses;
  } catch (const SolverFailure& e) {
    std::fprintf(stderr, "cablecal: montecarlo: no pose set for n=%d, %s: %s\n", key.n, ToString(key.design), e.what());
    return {};
  }
}

void ValidateSpatialMonteCarloOptions(const SpatialRobot& nominal, const SpatialMonteCarloOptions& o) {
  const MonteCarloOptions defaults;
  const MonteCarloOptions& s = o.study;
  const auto planar_only = [](bool given, const char* flag, const char* why) {
    if (given) throw InputError(flag, "", std::string("applies to planar robots only: ") + why);
  };
  planar_only(s.estimator != defaults.estimator, "--estimator", "a spatial robot's identification is the ml one");
  planar_only(s.gauge != defaults.gauge, "--gauge",
              "a spatial study holds the exit coordinates its sensors leave unseen, chosen from the data");
  planar_only(s.geometry_prior, "--geometry-prior", "not yet served for spatial robots");
  planar_only(s.equilibrium != defaults.equilibrium, "--equilibrium",
              "a spatial robot's equilibrium is modelled whenever it carries information");
  planar_only(s.com_error_m != 0.0, "--com-error", "not yet served for spatial robots");
  planar_only(s.outliers.rate > 0.0, "--outliers", "not yet served for spatial robots");
  ValidateStudyOptions(s, 4 * nominal.num_cables());
  CheckNoisySensors(nominal, s.sensors);
  PlanningRobot(nominal, o);
  if (o.random_pool < 0) throw InputError("--random-pool", "", "must be 0 (a fresh sample per trial) or a pose count");
  const bool any_random = std::find(s.designs.begin(), s.designs.end(), PoseSetDesign::kRandom) != s.designs.end();
  if (o.random_pool > 0 && any_random) {
    for (const int n : s.pose_counts) {
      if (n > o.random_pool) {
        throw InputError("--random-pool", "", "a pool of " + std::to_string(o.random_pool) + " poses cannot give " +
                                                  std::to_string(n) + " distinct ones (--poses)");
      }
    }
  }
  if (!(o.yaw_range_rad > 0.0 && o.yaw_range_rad <= M_PI)) {
    throw InputError("--yaw-range-deg", "", "must be in (0, 180] degrees");
  }
  for (const PoseSetDesign d : s.designs) {
    const int side = GridSide(d);
    for (const int n : s.pose_counts) {
      if (side > 0 && n != side * side * side) {
        throw InputError("--designs", "", std::string(ToString(d)) + " has " + std::to_string(side * side * side) +
                                              " poses: run it with --poses " + std::to_string(side * side * side) +
                                              " (got " + std::to_string(n) + ")");
      }
    }
  }
}

MonteCarloResult RunSpatialMonteCarlo(const SpatialRobot& nominal, const SpatialMonteCarloOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  ValidateSpatialMonteCarloOptions(nominal, o);
  const SpatialRobot planning = PlanningRobot(nominal, o);
  // The fewest poses are checked to identify the geometry whoever chooses the gauge.
  std::vector<std::string> held_names = StudyGauge(nominal, planning, o);
  if (!o.held.empty()) held_names = o.held;
  const std::vector<std::string> names = SpatialGeometryNames(nominal.num_cables(), false, false);
  std::vector<int> held;
  for (const std::string& h : held_names) held.push_back(static_cast<int>(std::find(names.begin(), names.end(), h) - names.begin()));
  SpatialIdentifyOptions id = TrialIdentifyOptions(o, held_names);
  // The true l_i0: what the controller pays out at home (the planning robot's home), on the true
  // robot too; the identification's start of them (the same lengths), solved once here.
  const Eigen::VectorXd l0_m = SpatialHome(planning).paid_out_m;
  id.home_paid_out_m = l0_m;
  // The random sets' pool, sampled once (stream 0x9001): a sampler that cannot give it is the
  // cells' sampling failure, as a fresh sample's would be.
  std::vector<SpatialPlanPose> pool;
  std::string pool_failure;
  const bool any_random =
      std::find(o.study.designs.begin(), o.study.designs.end(), PoseSetDesign::kRandom) != o.study.designs.end();
  if (o.random_pool > 0 && any_random) {
    try {
      pool = SampleSpatialPoses(planning, o.random_pool, StreamSeed(o.study.seed, {0x9001}), o.yaw_range_rad);
    } catch (const SolverFailure& e) {
      pool_failure = std::string("sampling: no pool of ") + std::to_string(o.random_pool) + " poses: " + e.what();
    }
  }
  // The designed sets and grids: one per (n, design), the same in every trial, made first
  // (DesignedSetKeys' order, several at once); an empty one fails its cell's trials (cause
  // "design"), said on stderr.
  const std::vector<DesignedSetKey> keys = DesignedSetKeys(o.study);
  std::vector<std::vector<SpatialPlanPose>> sets(keys.size());
  ForEachDesignedSet(keys, [&](std::size_t i) {
    if (o.study.interrupted && o.study.interrupted->load()) return;
    sets[i] = MakeSpatialDesignedSet(planning, o, keys[i]);
  });
  std::map<std::pair<int, int>, std::vector<SpatialPlanPose>> designed;
  for (std::size_t i = 0; i < keys.size(); ++i) designed[{keys[i].n, static_cast<int>(keys[i].design)}] = std::move(sets[i]);
  std::vector<ShareResult> shares(1);
  shares[0] = RunShareTrials(o.study, StudyShare{0, 1}, [&](int n, PoseSetDesign d, int trial) {
    const auto it = designed.find({n, static_cast<int>(d)});
    if (d == PoseSetDesign::kRandom && !pool_failure.empty()) {
      TrialOutcome failed;
      failed.failure = pool_failure;
      return failed;
    }
    return RunSpatialTrial(nominal, planning, o, l0_m, held, id, pool, n, d, trial,
                           it == designed.end() ? nullptr : &it->second);
  });
  if (shares[0].error) std::rethrow_exception(shares[0].error);
  if (!shares[0].failure.empty()) throw std::runtime_error(shares[0].failure);
  MonteCarloResult result;
  if (shares[0].interrupted) {
    result.interrupted = true;
    return result;
  }
  result = AssembleShares(o.study, std::move(shares), StudyNames{names, held_names});
  result.geometry_prior_served = false;
  result.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return result;
}

}  // namespace cablecal
