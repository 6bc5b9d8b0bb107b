// `cablecal montecarlo` and `cablecal reproduce`.
#include <omp.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "cli/commands.h"
#include "cli/sigint.h"
#include "common/atomic_output.h"
#include "common/error.h"
#include "common/format.h"
#include "common/yaml_writer.h"
#include "common/version.h"
#include "model/builtin_spatial_robots.h"
#include "model/spatial_robot.h"
#include "model/spatial_sensor_model.h"
#include "montecarlo/montecarlo.h"
#include "montecarlo/spatial_montecarlo.h"
#ifdef CABLECAL_WITH_MPI
#include "montecarlo/mpi.h"
#endif

namespace cablecal::cli {
namespace {

// Every name a study may write into its folder (the figures only with plots).
const std::vector<std::string> kStudyFiles = {"errors.csv",     "summary.csv",   "failures.csv",
                                              "summary.md",     "run.yaml",      "sigma_vs_n.png",
                                              "distributions.png", "one_calibration.png"};
const std::vector<std::string> kStudyFigures = {"sigma_vs_n.png", "distributions.png", "one_calibration.png"};

// The robot studied, as run.yaml names it; a spatial study also says its kind and the exit
// coordinates its gauge held.
struct StudiedRobot {
  std::string name, source;
  bool spatial = false;
  bool skip_infeasible = false;
  double tension_margin_N = 0.0, frame_margin_m = 0.0, tilt_margin_deg = 0.0;
  int random_pool = 0;
  bool exact_platform = false;
  bool statics = true;
  std::vector<std::string> sensors;  // the readings the trials take (spatial), encoders first
};

StudiedRobot PlanarStudied(const Robot& robot) {
  StudiedRobot s;
  s.name = robot.name;
  s.source = robot.source;
  return s;
}

StudiedRobot Studied(const SpatialRobot& robot, const SpatialMonteCarloOptions& o) {
  StudiedRobot s{robot.name,         robot.source,   true,
                 o.skip_infeasible,  o.plan_tension_margin_N, o.plan_margin_m,
                 o.plan_tilt_margin_rad * 180.0 / M_PI, o.random_pool, o.exact_platform, o.statics, {}};
  s.sensors = SpatialSensorNames(robot.sensors);
  return s;
}

std::string RunYaml(const StudiedRobot& robot, const MonteCarloOptions& o, const std::string& poses_text,
                    const MonteCarloResult& r, const Context& ctx, int threads) {
  using YAML::Key;
  using YAML::Value;
  int failures = 0;
  long trials = 0;
  for (const MonteCarloCell& c : r.cells) {
    failures += c.failures();
    trials += static_cast<long>(c.trials.size());
  }
  YAML::Emitter y;
  y << YAML::BeginMap;
  y << Key << "cablecal" << Value << YAML::Flow << YAML::BeginMap << Key << "version" << Value << YamlString{Version()}
    << Key << "commit" << Value << YamlString{GitCommit()} << YAML::EndMap;
  y << Key << "command" << Value << YamlString{ctx.command_line};
  y << Key << "robot" << Value << YAML::Flow << YAML::BeginMap << Key << "name" << Value << YamlString{robot.name}
    << Key << "source" << Value << YamlString{robot.source};
  if (robot.spatial) y << Key << "kind" << Value << "spatial";
  y << YAML::EndMap;
  y << Key << "poses" << Value << YamlString{poses_text};
  y << Key << "designs" << Value << YAML::Flow << YAML::BeginSeq;
  for (PoseSetDesign d : o.designs) y << ToString(d);
  y << YAML::EndSeq;
  y << Key << "trials" << Value << o.trials;
  if (robot.spatial) {
    y << Key << "gauge_held" << Value << YAML::Flow << YAML::BeginSeq;
    for (const std::string& h : r.held_names) y << YamlString{h};
    y << YAML::EndSeq << YAML::Comment("chosen from noise-free readings at the fewest poses");
  } else {
    y << Key << "estimator" << Value << ToString(o.estimator);
    y << Key << "gauge" << Value << ToString(o.gauge);
  }
  y << Key << "sensors" << Value << ToString(o.sensors);
  y << Key << "geometry_sigma_m" << Value << YamlNumber{o.geometry_sigma_m};
  y << Key << "geometry_prior" << Value << o.geometry_prior;
  y << Key << "loss" << Value << ToString(o.loss);
  y << Key << "equilibrium" << Value << (o.equilibrium ? "on" : "off");
  y << Key << "com_error_m" << Value << YamlNumber{o.com_error_m};
  y << Key << "outliers" << Value << YAML::Flow << YAML::BeginMap << Key << "rate" << Value
    << YamlNumber{o.outliers.rate} << Key << "size_sigmas" << Value << YamlNumber{o.outliers.size_sigmas}
    << YAML::EndMap;
  if (robot.spatial) {
    long skipped = 0;
    for (const MonteCarloCell& c : r.cells) {
      for (const TrialOutcome& t : c.trials) skipped += t.skipped_poses;
    }
    y << Key << "skip_infeasible" << Value << robot.skip_infeasible;
    y << Key << "true_platform" << Value << (robot.exact_platform ? "exact" : "drawn")
      << YAML::Comment(robot.exact_platform ? "the robot file's mass and centre of mass"
                                            : "mass and centre of mass drawn from platform.mass_sigma, com_sigma");
    y << Key << "skipped_poses" << Value << skipped << YAML::Comment("over every trial");
    y << Key << "readings" << Value << YAML::Flow << YAML::BeginSeq;
    for (const std::string& s : robot.sensors) y << s;
    y << YAML::EndSeq;
    y << Key << "statics" << Value << (robot.statics ? "on" : "off")
      << YAML::Comment(robot.statics ? "tensions, equilibrium and stretch modelled where they carry information"
                                     : "left out: cables identified as inextensible");
    y << Key << "plan_margins" << Value << YAML::Flow << YAML::BeginMap << Key << "tension_N" << Value
      << YamlNumber{robot.tension_margin_N} << Key << "frame_m" << Value << YamlNumber{robot.frame_margin_m} << Key
      << "tilt_deg" << Value << YamlNumber{robot.tilt_margin_deg} << YAML::EndMap
      << YAML::Comment("the plans keep these from the file's limits");
    y << Key << "random_pool" << Value << robot.random_pool
      << YAML::Comment(robot.random_pool > 0 ? "random sets drawn from this many poses sampled once per study"
                                             : "a fresh random set per trial");
  }
  y << Key << "design_starts" << Value << o.design_starts;
  y << Key << "seed" << Value << o.seed;
  y << Key << "blas" << Value << YamlString{LoadedLibraryPath("libblas.so")};
  y << Key << "lapack" << Value << YamlString{LoadedLibraryPath("liblapack.so")};
  y << Key << "processes" << Value << ctx.processes.count;
  y << Key << "threads" << Value << threads << YAML::Comment("per process");
  y << Key << "trials_run" << Value << trials;
  y << Key << "failed_trials" << Value << failures;
  y << Key << "wall_time_s" << Value << YamlNumber{std::round(r.wall_time_s * 1000.0) / 1000.0};
  y << YAML::EndMap;
  return YamlText(y);
}

// Writes the data files of one study into `folder` under `prefix` (staged; the caller commits).
void WriteStudy(const OutputFolder& folder, const std::string& prefix, const StudiedRobot& robot, const MonteCarloOptions& o,
                const std::string& poses_text, const MonteCarloResult& r, const Context& ctx, int threads,
                const std::string& title) {
  folder.WriteText(prefix + "errors.csv", ErrorsCsv(r));
  folder.WriteText(prefix + "summary.csv", SummaryCsv(r));
  folder.WriteText(prefix + "failures.csv", FailuresCsv(r));
  folder.WriteText(prefix + "summary.md", SummaryMarkdown(r, title));
  folder.WriteText(prefix + "run.yaml", RunYaml(robot, o, poses_text, r, ctx, threads));
}

// Plots into the staging folder before the commit. A failed plot leaves no figure (a
// partial one is removed) and returns the message: the data are committed anyway.
std::string TryPlotStudy(const OutputFolder& folder, const std::vector<std::string>& args,
                         const std::vector<std::string>& figures) {
  try {
    RunPlotScript("plot_montecarlo.py", args);
    return "";
  } catch (const FigureFailure& e) {
    for (const std::string& f : figures) std::filesystem::remove(folder.Path(f));
    // The commit replaces the earlier figures too: none is left beside data it does not show.
    return std::string(e.what()) + "; the earlier run's figures in the folder were removed";
  }
}

// Ctrl-C stops the run at the next trial (SIGINT reaches every rank under srun; mpirun
// ends the ranks itself). Nothing is written either way (cli/sigint.h).

// Runs one study on every process of the run (agreed: all succeed or all fail together);
// the whole result is on rank 0, an empty one elsewhere.
MonteCarloResult RunStudy(const Context& ctx, const Robot& robot, MonteCarloOptions o, const std::string& label) {
  MonteCarloResult r;
  RunAgreed(ctx.processes, [&] {
    const SigintScope sigint;
    o.interrupted = &SigintFlag();
    if (ctx.processes.root() && !ctx.quiet) o.progress = ProgressBar(label, "trials");
#ifdef CABLECAL_WITH_MPI
    r = ctx.processes.count > 1 ? RunMonteCarloMpi(robot, o) : RunMonteCarlo(robot, o);
#else
    r = RunMonteCarlo(robot, o);
#endif
    if (r.interrupted) throw Interrupted();
  });
  return r;
}

}  // namespace

// A spatial robot's study (montecarlo/spatial_montecarlo.h): the planar command's files, on one
// process (its shares are not yet sent between MPI ranks).
int RunSpatialMonteCarloCommand(const Context& ctx, const MonteCarloCommandOptions& options) {
  if (ctx.processes.count > 1) {
    throw InputError("montecarlo", "", "a spatial robot's study runs on one process for now (got " +
                                           std::to_string(ctx.processes.count) + "); use the threads of one machine");
  }
  const SpatialRobot robot = LoadSpatialRobotFile(options.robot_path);
  SpatialMonteCarloOptions o;
  o.study.pose_counts = ParsePoseCounts(options.poses);
  o.study.designs = ParseDesigns(options.designs);
  o.study.trials = options.trials;
  o.study.estimator = ParseEstimator(options.estimator);
  o.study.gauge = ParseGauge(options.gauge);
  o.study.sensors = ParseNoisySensors(options.sensors);
  o.study.geometry_sigma_m = options.geometry_sigma_m;
  o.study.loss = ParseLoss(options.loss);
  o.study.geometry_prior = options.geometry_prior;
  o.study.equilibrium = options.equilibrium == "on";
  o.study.com_error_m = options.com_error_m;
  o.study.outliers = ParseOutliers(options.outliers);
  o.study.seed = options.seed;
  o.study.design_starts = options.design_starts;
  o.skip_infeasible = options.skip_infeasible;
  o.exact_platform = options.exact_platform;
  o.plan_tension_margin_N = options.tension_margin_N;
  o.plan_margin_m = options.frame_margin_m;
  o.plan_tilt_margin_rad = options.tilt_margin_deg * M_PI / 180.0;
  o.random_pool = options.random_pool;
  ValidateSpatialMonteCarloOptions(robot, o);
  if (options.threads > 0) omp_set_num_threads(options.threads);
  const int threads = omp_get_max_threads();
  OutputFolder folder("--out", options.out_dir, kStudyFiles);
  folder.RefuseInputs({{"--robot", options.robot_path}});
  const SigintScope sigint;
  o.study.interrupted = &SigintFlag();
  if (!ctx.quiet) o.study.progress = ProgressBar("montecarlo", "trials");
  const MonteCarloResult r = RunSpatialMonteCarlo(robot, o);
  if (r.interrupted) throw Interrupted();
  RefuseIfEveryTrialFailed(r);
  WriteStudy(folder, "", Studied(robot, o), o.study, options.poses, r, ctx, threads,
             "Monte Carlo: " + robot.name);
  std::string figure_error;
  if (options.plot) figure_error = TryPlotStudy(folder, {folder.staging()}, kStudyFigures);
  folder.Commit();
  const FailureTally tally = TallyFailures(r);
  std::printf("ran %zu cells x %d trials in %.1f s on %d threads (%ld failed trials); the gauge held %zu exit "
              "coordinates; wrote %s/\n",
              r.cells.size(), o.study.trials, r.wall_time_s, threads, tally.failed, r.held_names.size(),
              options.out_dir.c_str());
  if (!ctx.quiet && 2 * tally.failed > tally.trials) {
    std::fprintf(stderr, "cablecal: warning: %ld of %ld trials failed (%s): the statistics speak of the few that did "
                 "not; failures.csv says why (%s)\n", tally.failed, tally.trials, tally.by_cause.c_str(),
                 tally.hint.c_str());
  }
  if (!figure_error.empty()) throw FigureFailure(figure_error + "; the study's data were written to " + options.out_dir);
  return kExitOk;
}

int RunMonteCarloCommand(const Context& ctx, const MonteCarloCommandOptions& options) {
  if (IsSpatialRobotFile(options.robot_path)) return RunSpatialMonteCarloCommand(ctx, options);
  RefuseSpatialOnlyFlag(options.skip_infeasible, "--skip-infeasible");
  RefuseSpatialOnlyFlag(options.exact_platform, "--exact-platform");
  RefuseSpatialOnlyFlag(options.tension_margin_N != 0.0, "--tension-margin");
  RefuseSpatialOnlyFlag(options.frame_margin_m != 0.0, "--frame-margin");
  RefuseSpatialOnlyFlag(options.tilt_margin_deg != 0.0, "--tilt-margin-deg");
  RefuseSpatialOnlyFlag(options.random_pool != 0, "--random-pool");
  Robot robot;
  MonteCarloOptions o;
  RunAgreed(ctx.processes, [&] {
    robot = LoadRobotOption(options.robot_path);
    o.pose_counts = ParsePoseCounts(options.poses);
    o.designs = ParseDesigns(options.designs);
    o.trials = options.trials;
    o.estimator = ParseEstimator(options.estimator);
    o.gauge = ParseGauge(options.gauge);
    o.sensors = ParseNoisySensors(options.sensors);
    o.geometry_sigma_m = options.geometry_sigma_m;
    o.loss = ParseLoss(options.loss);
    o.geometry_prior = options.geometry_prior;
    o.equilibrium = options.equilibrium == "on";
    o.com_error_m = options.com_error_m;
    o.outliers = ParseOutliers(options.outliers);
    o.seed = options.seed;
    o.design_starts = options.design_starts;
    ValidateOptions(o, &robot);
  });
  if (options.threads > 0) omp_set_num_threads(options.threads);
  const int threads = omp_get_max_threads();
  // The folder is checked (and created) before any work; results go into it as one set.
  std::unique_ptr<OutputFolder> folder;
  RunAgreed(ctx.processes, [&] {
    if (!ctx.processes.root()) return;
    folder = std::make_unique<OutputFolder>("--out", options.out_dir, kStudyFiles);
    folder->RefuseInputs({{"--robot", options.robot_path}});
  });
  const SigintScope sigint;  // until the commit: Ctrl-C while plotting writes nothing either
  const MonteCarloResult r = RunStudy(ctx, robot, o, "montecarlo");
  std::string figure_error;
  RunAgreed(ctx.processes, [&] {
    if (!ctx.processes.root()) return;
    RefuseIfEveryTrialFailed(r);
    WriteStudy(*folder, "", PlanarStudied(robot), o, options.poses, r, ctx, threads, "Monte Carlo: " + robot.name);
    if (options.plot) figure_error = TryPlotStudy(*folder, {folder->staging()}, kStudyFigures);
    folder->Commit();
  });
  if (!ctx.processes.root()) return kExitOk;
  int failures = 0;
  for (const MonteCarloCell& c : r.cells) failures += c.failures();
  std::printf("ran %zu cells x %d trials in %.1f s on %d process%s x %d threads (%d failed trials); wrote %s/\n",
              r.cells.size(), o.trials, r.wall_time_s, ctx.processes.count, ctx.processes.count > 1 ? "es" : "",
              threads, failures, options.out_dir.c_str());
  const std::vector<std::string> worse = CellsThatAddLittle(r, true);
  if (!worse.empty() && !ctx.quiet) {
    std::fprintf(stderr,
                 "cablecal: warning: in %zu cell%s the calibration knows a geometric parameter less well than the %.3g mm "
                 "known before measuring (%s%s); see summary.md%s\n",
                 worse.size(), worse.size() == 1 ? "" : "s", 1e3 * o.geometry_sigma_m, worse.front().c_str(),
                 worse.size() > 1 ? "; ..." : "",
                 o.geometry_prior ? "" : "; --geometry-prior identifies with that knowledge as a prior");
  }
  if (!figure_error.empty()) throw FigureFailure(figure_error + "; the study's data were written to " + options.out_dir);
  return kExitOk;
}

namespace {

// One configuration of the spatial study (README, "The spatial study"): a built-in robot, the
// sensors it calibrates with, what the lab knows before measuring, and how it plans.
struct SpatialStudyConfiguration {
  std::string folder;  // under results/spatial/
  std::string robot;   // a built-in spatial robot
  std::string title;
  std::vector<std::string> sensors;  // kept of the file's (KeepSpatialSensors), besides the encoders
  bool add_inclinometer_laser = false;  // the planar study's inclinometer and laser (robots/wang2022.yaml)
  bool statics = true;
  double geometry_sigma_m = 0.0;
  double tension_margin_N = 0.0, frame_margin_m = 0.0, tilt_margin_deg = 0.0;  // the plans' (PlanningRobot)
  int random_pool_per_pose = 0;  // random sets drawn from a pool of this many times the largest n (0: fresh samples)
  std::vector<int> poses;  // the random and optimized cells' pose counts, from the fewest the sensors need to 40
  double stiffness_N = 0.0;  // E*A given to every cable that has none (0: the file's cables as they are)
  int design_starts = 1;     // Ipopt starts per optimized set (four times as many where none holds)
  double com_sigma_m = 0.0;  // the platform's centre-of-mass prior (0: the file's, or the default 5 mm)
};

std::string PoseCountsText(const std::vector<int>& poses) {
  std::string text;
  for (const int n : poses) text += (text.empty() ? "" : ",") + std::to_string(n);
  return text;
}

std::vector<SpatialStudyConfiguration> SpatialStudyConfigurations() {
  // cogiro's exits were surveyed with a laser tracker (its file's tracker sigma, 0.5 mm): the
  // study's true robots are drawn with that. Its cables are stiff (E*A 8.2e5 N over about 9 m):
  // a length error of 0.5 mm moves a tension by up to about 45 N, so its plans keep 150 N from
  // the tension bounds (with 50 N, 6 of 100 random trials failed on a tension; 150 N, none), 5 mm
  // more from the frame and 0.5 degrees from the tilt limit (a designed pose sits on them: without
  // these every optimized trial failed, the platform settling just outside).
  // irma4u: its file's cables are inextensible, and then its four-cable platform is a
  // four-legged table: on a true robot whose exits are off by as little as 0.1 mm one cable goes
  // slack at home already (every trial failed in the simulation at 0.1, 1, 3 and 10 mm). The
  // study gives its cables E*A = 1e5 N (our choice: a synthetic fibre rope of a few mm; at its
  // ~35 N a cable stretches about 0.4 mm a metre, which takes up the true robot's 0.5 mm), draws
  // its exits with a 0.5 mm survey (it has none: our choice, as cogiro's), keeps its plans 20 N
  // from the tension bounds (5 % of the range; with none, 4 of 10 random trials failed on
  // tension_low), and draws its random sets from a pool (its sampler: 0.13 s a pose). Its
  // designs take four Ipopt starts: with one, the 27-pose set was a poor optimum (a4y 27.9 mm,
  // worse than random sets' 18.2); with two the best of them gave 13.7 mm (100 trials, seed
  // 2022; four starts 11.7 mm), but the 40-pose set knew a4y no better than random sets (sigma
  // ratio 1.018 over 500 trials, 0.98 over 100); with four, 0.71 (100 trials, every parameter's
  // ratio at most 0.83), at 1.5 times the design time (180 against 124 s for that cell). Its platform's centre of mass is known
  // to 0.5 mm (weighed and balanced: our choice): each trial's true platform is drawn from the
  // priors, and four cables fixed in length let a few millimetres of centre of mass move a
  // tension by tens of newtons (with the default 5 mm, 206 of 300 simulated 20-pose experiments
  // lost a cable; 0.5 mm, none of 1000: bench/README.md, irma4u).
  SpatialStudyConfiguration laser{"cogiro_inclinometer_laser", "cogiro", "cogiro: encoders, inclinometer and laser",
                                  {}, true, true, 0.0005, 150.0, 0.005, 0.5, 0, {11, 20, 27, 40}};
  SpatialStudyConfiguration encoders{"cogiro_encoders", "cogiro", "cogiro: encoders alone (statics left out)",
                                     {}, false, false, 0.0005, 150.0, 0.005, 0.5, 0, {16, 27, 40}};
  SpatialStudyConfiguration irma4u{"irma4u_swivel_inclinometer", "irma4u",
                                   "irma4u: encoders, swivel and inclinometer (cables given E*A 1e5 N)",
                                   {"swivel", "inclinometer"}, false, true, 0.0005, 20.0, 0.005, 0.5, 3, {4, 8, 27, 40},
                                   1e5, 4, 0.0005};
  return {laser, encoders, irma4u};
}

SpatialRobot StudyRobot(const SpatialStudyConfiguration& c) {
  SpatialRobot robot = BuiltinSpatialRobot(c.robot);
  robot.sensors = KeepSpatialSensors(robot.sensors, c.sensors);
  if (c.stiffness_N > 0.0) {
    for (SpatialCable& cable : robot.cables) {
      if (!cable.stiffness_N) cable.stiffness_N = c.stiffness_N;
    }
  }
  if (c.com_sigma_m > 0.0) robot.com_sigma_m = c.com_sigma_m;
  if (c.add_inclinometer_laser) {
    const SensorNoise& planar = BuiltinRobot().sensors;
    robot.sensors.inclinometer_rad = RangedNoise{planar.inclinometer_accuracy_rad, planar.inclinometer_repeatability_rad};
    robot.sensors.laser_m = RangedNoise{planar.laser_accuracy_m, planar.laser_repeatability_m};
  }
  return robot;
}

// `reproduce --study spatial`: every configuration's random and optimized cells, then the grids
// at their pose counts, into OUT/spatial/<configuration>/ (the montecarlo command's files and
// figures) and OUT/spatial/comparison.md. One process (the spatial study's shares are not sent
// between MPI ranks).
int RunSpatialReproduce(const Context& ctx, const ReproduceOptions& options) {
  if (!options.robot_path.empty()) {
    throw InputError("--robot", "", "the spatial study runs on the built-in cogiro and irma4u; give no --robot");
  }
  if (ctx.processes.count > 1) {
    throw InputError("reproduce", "", "the spatial study runs on one process for now (got " +
                                          std::to_string(ctx.processes.count) + "); use the threads of one machine");
  }
  const std::vector<SpatialStudyConfiguration> configurations = SpatialStudyConfigurations();
  const std::vector<PoseSetDesign> designs =
      ParseDesigns(options.designs.empty() ? "random,optimized,grid:2x2x2,grid:3x3x3" : options.designs);
  const auto has = [&designs](PoseSetDesign d) { return std::find(designs.begin(), designs.end(), d) != designs.end(); };
  // Every study's options, checked before any work.
  struct Planned {
    SpatialStudyConfiguration c;
    SpatialRobot robot;
    std::vector<SpatialMonteCarloOptions> runs;  // the random/optimized cells, then each grid alone
    std::string poses_text;
  };
  std::vector<Planned> planned;
  for (const SpatialStudyConfiguration& c : configurations) {
    Planned p{c, StudyRobot(c), {}, ""};
    SpatialMonteCarloOptions base;
    base.study.trials = options.trials;
    base.study.seed = options.seed;
    base.study.geometry_sigma_m = c.geometry_sigma_m;
    base.study.design_starts = c.design_starts;
    base.statics = c.statics;
    base.skip_infeasible = false;
    base.plan_tension_margin_N = c.tension_margin_N;
    base.plan_margin_m = c.frame_margin_m;
    base.plan_tilt_margin_rad = c.tilt_margin_deg * M_PI / 180.0;
    SpatialMonteCarloOptions cells = base;
    cells.study.pose_counts = c.poses;
    if (options.pose_counts > 0 && options.pose_counts < static_cast<int>(cells.study.pose_counts.size())) {
      cells.study.pose_counts.resize(options.pose_counts);
    }
    const int largest = *std::max_element(cells.study.pose_counts.begin(), cells.study.pose_counts.end());
    base.random_pool = cells.random_pool = c.random_pool_per_pose * largest;
    p.poses_text = PoseCountsText(cells.study.pose_counts);
    for (const PoseSetDesign d : {PoseSetDesign::kRandom, PoseSetDesign::kOptimized}) {
      if (has(d)) cells.study.designs.push_back(d);
    }
    for (const PoseSetDesign d : designs) {
      if (GridSide(d) == 0 && d != PoseSetDesign::kRandom && d != PoseSetDesign::kOptimized) {
        throw InputError("--designs", "", std::string("the spatial study runs random, optimized and the grids (got ") +
                                              ToString(d) + ")");
      }
    }
    if (!cells.study.designs.empty()) p.runs.push_back(cells);
    const int fewest = *std::min_element(cells.study.pose_counts.begin(), cells.study.pose_counts.end());
    for (const PoseSetDesign d : {PoseSetDesign::kGrid2, PoseSetDesign::kGrid3}) {
      const int n = GridSide(d) * GridSide(d) * GridSide(d);
      if (!has(d) || n < fewest) continue;  // a grid of fewer poses than the configuration needs is not run
      SpatialMonteCarloOptions grid = base;
      grid.study.pose_counts = {n};
      grid.study.designs = {d};
      p.runs.push_back(grid);
      p.poses_text += std::string(", ") + std::to_string(n) + " (" + ToString(d) + ")";
    }
    for (const SpatialMonteCarloOptions& run : p.runs) ValidateSpatialMonteCarloOptions(p.robot, run);
    planned.push_back(std::move(p));
  }
  std::vector<std::string> owned = {"comparison.md"};
  for (const Planned& p : planned) owned.push_back(p.c.folder + "/");
  // OUT is made as the planar study's would be (its parent must exist), and removed again if
  // the run ends without writing (OutputFolder checks and makes OUT/spatial itself).
  struct MadeFolder {
    std::filesystem::path path;
    bool made = false;
    ~MadeFolder() {
      std::error_code ignored;
      if (made) std::filesystem::remove(path, ignored);  // only if still empty
    }
  } made_out{options.out_dir};
  {
    std::error_code ec;
    const std::filesystem::path parent = std::filesystem::absolute(options.out_dir).parent_path();
    if (!std::filesystem::exists(options.out_dir, ec) && std::filesystem::is_directory(parent, ec)) {
      made_out.made = std::filesystem::create_directory(options.out_dir, ec);
    }
  }
  OutputFolder folder("--out", (std::filesystem::path(options.out_dir) / "spatial").string(), owned);
  if (options.threads > 0) omp_set_num_threads(options.threads);
  const int threads = omp_get_max_threads();
  const auto t0 = std::chrono::steady_clock::now();
  const SigintScope sigint;
  std::string comparison =
      "# The spatial study: optimized against random and the grids\n\n"
      "Written by `cablecal reproduce --study spatial` (results/spatial/README.md reads it). Per configuration and n:\n"
      "of the geometric parameters the gauge leaves free, how many the optimized sets know better (a smaller sigma)\n"
      "than the other design's, the median and the largest ratio sigma(optimized) / sigma(other), the failed trials\n"
      "of both, and whether optimized holds there (every sigma smaller, at most 2 % of the trials more failed).\n";
  std::string figure_error;
  for (const Planned& p : planned) {
    MonteCarloResult all;
    SpatialMonteCarloOptions described = p.runs.front();
    described.study.designs.clear();
    for (std::size_t k = 0; k < p.runs.size(); ++k) {
      SpatialMonteCarloOptions o = p.runs[k];
      if (k > 0) o.held = all.held_names;  // one gauge for the configuration (SpatialMonteCarloOptions::held)
      o.study.interrupted = &SigintFlag();
      if (!ctx.quiet) o.study.progress = ProgressBar(p.c.folder + (k == 0 ? "" : ", grid"), "trials");
      MonteCarloResult r = RunSpatialMonteCarlo(p.robot, o);
      if (r.interrupted) throw Interrupted();
      if (k == 0) {
        all = std::move(r);
      } else {
        // Errors of different gauges would not compare.
        CABLECAL_CHECK(r.held_names == all.held_names, "one gauge for every run of a configuration");
        all.cells.insert(all.cells.end(), r.cells.begin(), r.cells.end());
        all.wall_time_s += r.wall_time_s;
      }
      for (const PoseSetDesign d : o.study.designs) described.study.designs.push_back(d);
    }
    WriteStudy(folder, p.c.folder + "/", Studied(p.robot, described), described.study, p.poses_text, all, ctx, threads,
               "The spatial study, " + p.c.title);
    comparison += "\n## " + p.c.title + "\n\n" + DesignComparisonMarkdown(all, PoseSetDesign::kOptimized);
    std::vector<std::string> figures;
    for (const std::string& f : kStudyFigures) figures.push_back(p.c.folder + "/" + f);
    const std::string e = options.plot ? TryPlotStudy(folder, {folder.Path(p.c.folder)}, figures) : "";
    if (!e.empty() && figure_error.empty()) figure_error = e;
  }
  folder.WriteText("comparison.md", comparison);
  folder.Commit();
  made_out.made = false;
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("reproduced the spatial study in %.1f s on %d threads; wrote %s/\n", wall, threads,
              (std::filesystem::path(options.out_dir) / "spatial").string().c_str());
  if (!figure_error.empty()) throw FigureFailure(figure_error + "; the study's data were written to " + options.out_dir);
  return kExitOk;
}

}  // namespace

int RunReproduce(const Context& ctx, const ReproduceOptions& options) {
  if (options.study == "spatial") return RunSpatialReproduce(ctx, options);
  if (options.pose_counts > 0 || !options.designs.empty()) {
    throw InputError(options.designs.empty() ? "--pose-counts" : "--designs", "", "applies to --study spatial only");
  }
  Robot robot;
  std::unique_ptr<OutputFolder> folder;
  RunAgreed(ctx.processes, [&] {
    robot = LoadRobotOption(options.robot_path);
    if (!ctx.processes.root()) return;
    folder = std::make_unique<OutputFolder>("--out", options.out_dir, std::vector<std::string>{"study/", "ablation/"});
    folder->RefuseInputs({{"--robot", options.robot_path}});
  });
  // One scope over every phase: Ctrl-C between two studies is seen at the next check, and
  // nothing is written (the set is committed only at the end).
  const SigintScope sigint;
  const auto check_interrupted = [] {
    if (SigintFlag()) throw Interrupted();
  };
  if (options.threads > 0) omp_set_num_threads(options.threads);
  const int threads = omp_get_max_threads();
  const auto t0 = std::chrono::steady_clock::now();
  MonteCarloOptions base;
  base.trials = options.trials;
  base.seed = options.seed;
  base.geometry_sigma_m = 0.01;
  // 1. The paper's study: random pose sets for every n; sets optimized with the default
  // criterion (A) and with the paper's condition number every 4th n; D- and E-optimal sets
  // every 8th n.
  MonteCarloOptions random = base;
  random.pose_counts = ParsePoseCounts("6:50");
  random.designs = {PoseSetDesign::kRandom};
  MonteCarloOptions optimized = base;
  optimized.pose_counts = ParsePoseCounts("6:50:4");
  optimized.designs = {PoseSetDesign::kOptimized, PoseSetDesign::kCondition};
  MonteCarloOptions others = base;
  others.pose_counts = ParsePoseCounts("6:50:8");
  others.designs = {PoseSetDesign::kD, PoseSetDesign::kE};
  MonteCarloResult study = RunStudy(ctx, robot, random, "study, random sets   ");
  for (const auto& [o, label] : {std::make_pair(optimized, "study, optimized sets"),
                                 std::make_pair(others, "study, D and E sets   ")}) {
    const MonteCarloResult r = RunStudy(ctx, robot, o, label);
    study.cells.insert(study.cells.end(), r.cells.begin(), r.cells.end());
    study.wall_time_s += r.wall_time_s;
  }
  MonteCarloOptions described = base;
  described.pose_counts = random.pose_counts;
  described.designs = {PoseSetDesign::kRandom, PoseSetDesign::kOptimized, PoseSetDesign::kCondition, PoseSetDesign::kD,
                       PoseSetDesign::kE};
  RunAgreed(ctx.processes, [&] {
    check_interrupted();
    if (!ctx.processes.root()) return;
    WriteStudy(*folder, "study/", PlanarStudied(robot), described,
               "6:50 (random), 6:50:4 (optimized = A-optimal, condition), 6:50:8 (d, e)", study, ctx, threads,
               "The paper's study: " + robot.name);
  });
  // 2. The sensor ablation at n = 50 (the paper's Section 4.2, Fig. 10).
  for (const NoisySensors s : {NoisySensors::kBoth, NoisySensors::kLaser, NoisySensors::kInclinometer, NoisySensors::kNone}) {
    MonteCarloOptions ab = base;
    ab.pose_counts = {50};
    ab.designs = {PoseSetDesign::kRandom};
    ab.sensors = s;
    const MonteCarloResult r = RunStudy(ctx, robot, ab, std::string("ablation, ") + ToString(s) + "          ");
    RunAgreed(ctx.processes, [&] {
      check_interrupted();
      if (!ctx.processes.root()) return;
      WriteStudy(*folder, std::string("ablation/") + ToString(s) + "/", PlanarStudied(robot), ab, "50", r, ctx, threads,
                 std::string("Sensor ablation, noisy sensors: ") + ToString(s));
    });
  }
  std::string figure_error;
  RunAgreed(ctx.processes, [&] {
    check_interrupted();
    if (!ctx.processes.root()) return;
    std::vector<std::string> figures;
    for (const std::string& f : kStudyFigures) figures.push_back("study/" + f);
    figures.push_back("ablation/ablation.png");
    if (options.plot) {
      figure_error = TryPlotStudy(*folder, {folder->Path("study"), "--ablation", folder->Path("ablation")}, figures);
    }
    folder->Commit();
  });
  if (!ctx.processes.root()) return kExitOk;
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("reproduced the study in %.1f s on %d process%s x %d threads; wrote %s/\n", wall, ctx.processes.count,
              ctx.processes.count > 1 ? "es" : "", threads, options.out_dir.c_str());
  if (!figure_error.empty()) throw FigureFailure(figure_error + "; the study's data were written to " + options.out_dir);
  return kExitOk;
}

}  // namespace cablecal::cli
