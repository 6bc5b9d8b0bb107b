// cablecal: plan, identify and predict the calibration of cable-driven parallel robots.
// Parses the command line (CLI11) and maps every failure to a documented exit code:
// 0 success, 1 internal error, 2 bad input (file, flag, value), 3 solver failure, 4 a
// process of an MPI run failed, 5 a figure failed (results written), 130 interrupted.
#include <CLI/CLI.hpp>
#include <glog/logging.h>

#include <algorithm>
#include <charconv>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "cli/commands.h"
#include "cli/processes.h"
#include "common/error.h"
#include "identify/identify.h"
#include "common/format.h"
#include "common/version.h"
#include "experiment/plan.h"  // kMaxPlanPoses

namespace {

using cablecal::cli::Context;

// CLI11's own number checks print their limits as 310-digit numbers ("not in range 0.000000
// to 1797...") and call 0 out of range 0..; these say what is wanted.
CLI::Validator NumberAbove(double lowest, bool inclusive) {
  const std::string wanted = std::string(inclusive ? ">= " : "> ") + cablecal::FormatDouble(lowest);
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        double v = 0.0;
        if (!cablecal::ParseFiniteDouble(text, &v) || !(inclusive ? v >= lowest : v > lowest)) {
          return "must be a number " + wanted + " (got '" + text + "')";
        }
        return "";
      },
      "NUMBER " + wanted);
}
const CLI::Validator kPositive = NumberAbove(0.0, false);
const CLI::Validator kNonNegative = NumberAbove(0.0, true);
constexpr int kMaxThreads = 1024;
// CLI11 reads an integer with a leading 0 as octal ("010" is 8): a count or seed typed with
// leading zeros is read as the decimal number it looks like. Called once the text is all digits,
// by the validators below, which are therefore given with ->transform (->check runs on a copy).
void AsDecimal(std::string& digits) {
  const std::size_t first = digits.find_first_not_of('0');
  digits.erase(0, first == std::string::npos ? digits.size() - 1 : first);
}

// Seeds are unsigned 64-bit integers; CLI11 would wrap "-1" to 18446744073709551615 and
// saturate 18446744073709551616 to it: a seed out of range is refused, never another run's.
const CLI::Validator kSeed(
    [](std::string& text) -> std::string {
      std::uint64_t value = 0;
      const char* end = text.data() + text.size();
      const bool digits = !text.empty() && text.find_first_not_of("0123456789") == std::string::npos;
      if (!digits || std::from_chars(text.data(), end, value).ec != std::errc()) {
        return "must be a whole number from 0 to 18446744073709551615 (got '" + text + "')";
      }
      AsDecimal(text);
      return "";
    },
    "SEED");

// Counts (poses, trials, starts, threads): CLI11's Range says "Value abc not in range 1 to
// 1000" for a word or "1e3"; this says what is wanted.
CLI::Validator WholeNumberIn(long long lowest, long long highest) {
  const std::string wanted = "a whole number from " + std::to_string(lowest) + " to " + std::to_string(highest);
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        const bool digits = !text.empty() && text.size() <= 18 && text.find_first_not_of("0123456789") == std::string::npos;
        if (!digits || std::stoll(text) < lowest || std::stoll(text) > highest) {
          return "must be " + wanted + " (got '" + text + "')";
        }
        AsDecimal(text);
        return "";
      },
      "INT in [" + std::to_string(lowest) + ", " + std::to_string(highest) + "]");
}

void AddRobotOption(CLI::App* app, std::string* path) {
  app->add_option("--robot", *path, "robot YAML file (default: the built-in wang2022 robot)")
      ->check(CLI::ExistingFile);
}

}  // namespace

// Long (~280 lines) for a reason: the command line is one declarative table, every
// subcommand's options in the order --help prints them; split, the table would be harder to
// read against the README's "Commands".
int main(int argc, char** argv) {
  const cablecal::cli::ProcessSession session(&argc, &argv);
  Context ctx;
  ctx.processes = session.processes();
  const bool root = ctx.processes.root();
  // argv[0] is recorded as "cablecal" so that outputs do not depend on where it was built.
  std::vector<std::string> args(argv, argv + argc);
  args[0] = "cablecal";
  ctx.command_line = cablecal::CommandLine(args);

  CLI::App app{"cablecal: plan, identify and predict the calibration of cable-driven parallel robots"};
  const std::string version = std::string("cablecal ") + cablecal::Version() + " (commit " + cablecal::GitCommit() + ")";
  app.set_version_flag("--version", version);
  app.require_subcommand(1);

  cablecal::cli::WorkspaceOptions ws;
  CLI::App* ws_cmd = app.add_subcommand("workspace", "grid the feasible cable-tension workspace to CSV (and PNG)");
  AddRobotOption(ws_cmd, &ws.robot_path);
  ws_cmd->add_option("--step", ws.step_m,
                     "grid spacing in m (default 0.05; spatial robots: the frame box's longest side / 40, rounded up "
                     "to 1, 2 or 5 times a power of ten)")
      ->check(kPositive);
  ws_cmd->add_option("--out", ws.out_path,
                     "workspace CSV (x,z,theta,t1..tm,feasible,reason; theta_min,theta_max with 3 or more cables; "
                     "spatial robots: x,y,z,roll,pitch,yaw,t1..tm,feasible,reason)")
      ->required();
  ws_cmd->add_option("--rpy-deg", ws.rpy_deg,
                     "spatial robots: the orientation R,P,Y (degrees) of the constant-orientation workspace "
                     "(default: home's; with fewer than 6 cables only the controlled entries)");
  ws_cmd->add_option("--plot", ws.plot_path, "PNG of the feasible region, tensions and exit points");

  cablecal::cli::SampleOptions sample;
  CLI::App* sample_cmd = app.add_subcommand("sample", "draw random feasible poses as a pose plan CSV");
  AddRobotOption(sample_cmd, &sample.robot_path);
  sample_cmd->add_option("--poses", sample.poses, "number of poses")->required()->transform(WholeNumberIn(1, 100000));
  sample_cmd->add_option("--seed", sample.seed, "random seed")->capture_default_str()->transform(kSeed);
  sample_cmd->add_option("--out", sample.out_path, "pose plan CSV")->required();
  sample_cmd->add_option("--yaw-range-deg", sample.yaw_range_deg,
                         "spatial robots: draw yaw within home's yaw +- this many degrees (default 30)")
      ->check(NumberAbove(0.0, false));

  cablecal::cli::SimulateOptions sim;
  CLI::App* sim_cmd = app.add_subcommand("simulate", "simulate an experiment: true robot, forward motion, sensor noise");
  AddRobotOption(sim_cmd, &sim.robot_path);
  sim_cmd->add_option("--truth", sim.truth_path, "true robot file (default: the nominal robot)")->check(CLI::ExistingFile);
  sim_cmd->add_option("--geometry-sigma", sim.geometry_sigma_m,
                      "perturb nominal exit points and initial lengths (spatial robots: every exit coordinate) by "
                      "N(0, S^2), S in m")
      ->check(kNonNegative);
  sim_cmd->add_option("--plan", sim.plan_path, "pose plan CSV")->required()->check(CLI::ExistingFile);
  sim_cmd->add_option("--seed", sim.seed, "random seed")->capture_default_str()->transform(kSeed);
  sim_cmd->add_option("--sensors", sim.sensors, "noisy sensors: both|laser|inclinometer|none")
      ->capture_default_str()
      ->check(CLI::IsMember({"both", "laser", "inclinometer", "none"}));
  sim_cmd->add_flag("--no-encoder-noise", sim.no_encoder_noise, "encoders read the commanded changes exactly");
  sim_cmd->add_flag("--systematic-errors", sim.systematic_errors,
                    "also add the robot file's systematic laser and inclinometer errors (sensors fit)");
  sim_cmd->add_flag("--skip-infeasible", sim.skip_infeasible,
                    "skip the plan's poses the true robot cannot hold or holds outside its workspace (each named on "
                    "stderr) instead of stopping at the first; an error still if it can hold none");
  sim_cmd->add_option("--out", sim.out_path,
                      "measurement CSV (pose,dl1..dlm,z,theta; spatial robots: pose,dl1..dlm and each sensor's columns)")
      ->required();
  sim_cmd->add_option("--truth-out", sim.truth_out_path, "true robot and true poses (YAML)");

  cablecal::cli::IdentifyCommandOptions ident;
  CLI::App* id_cmd = app.add_subcommand("identify", "identify exit points, initial lengths and poses (Ceres)");
  AddRobotOption(id_cmd, &ident.robot_path);
  id_cmd->add_option("--measurements", ident.measurements_path, "measurement CSV")->required()->check(CLI::ExistingFile);
  id_cmd->add_option("--estimator", ident.estimator, "ml (all sensors whitened) or paper (Eq. 6)")
      ->capture_default_str()
      ->check(CLI::IsMember({"ml", "paper"}));
  // Spatial robots also take auto and hold:a1x,a1y,... (ParseSpatialGauge); the planar choices
  // keep CLI11's own check and message.
  const CLI::Validator planar_gauge = CLI::IsMember({"a1x", "prior", "none"});
  CLI::Option* gauge_option =
      id_cmd
          ->add_option("--gauge", ident.gauge,
                       "planar robots: a1x (the default: hold a1x), prior (tracker prior on exits) or none; spatial "
                       "robots: auto (the default: hold the exit coordinates the readings leave unseen), none, prior or "
                       "hold:a1x,a1y,...")
          ->check(CLI::Validator(
              [planar_gauge](std::string& text) {
                if (text == "auto" || text.rfind("hold:", 0) == 0 || planar_gauge(text).empty()) return std::string();
                return "'" + text +
                       "' is no gauge: a1x, prior or none for a planar robot; auto, none, prior or hold:a1x,a1y,... "
                       "for a spatial one";
              },
              "a1x|prior|none (planar), auto|none|prior|hold:... (spatial)"));
  CLI::Option* max_iterations_option =
      id_cmd->add_option("--max-iterations", ident.max_iterations,
                         "Levenberg-Marquardt iteration limit (default: 100 for planar robots, 200 for spatial ones)")
      ->transform(WholeNumberIn(1, cablecal::kMaxIdentifyIterations));
  id_cmd->add_option("--identify", ident.identify,
                     "spatial robots: exits (default: the exit points and initial lengths) or anchors (the platform "
                     "anchors b1x .. bmz too)");
  id_cmd->add_option("--plan", ident.plan_path,
                     "spatial robots: the pose plan CSV the readings were taken at (as sample or design write it): "
                     "each pose's search starts from its commanded pose, matched by pose id, instead of from home")
      ->check(CLI::ExistingFile);
  id_cmd->add_option("--out", ident.out_path, "result YAML (required unless --json)");
  id_cmd->add_flag("--json", ident.json, "print the result (the YAML's content) as JSON on stdout");
  id_cmd->add_option("--delimiter", ident.delimiter, "the measurement CSV's separator: ',', ';' or tab")
      ->capture_default_str();
  id_cmd->add_option("--calibrated-robot", ident.calibrated_robot_path, "robot file with the identified geometry");
  id_cmd->add_option("--loss", ident.loss,
                     "robust loss on each reading: none, huber or cauchy, optionally :SCALE in sigmas "
                     "(defaults huber:3, cauchy:10; ml only)")
      ->capture_default_str();
  id_cmd->add_option("--geometry-prior", ident.geometry_prior_sigma_m,
                     "standard deviation of the nominal exit points and initial lengths, m: a prior, so that the "
                     "result knows at least what the robot file did (ml only; default none)")
      ->each([&ident](const std::string&) { ident.geometry_prior_given = true; });
  CLI::Option* equilibrium_option = id_cmd->add_option("--equilibrium", ident.equilibrium,
                     std::string("on: with 2 cables each pose's static equilibrium is a residual, its sigma the robot "
                                 "file's platform.com_sigma (default 5 mm); off: theta free per pose (ml only); default ") +
                         (cablecal::kDefaultEquilibrium ? "on" : "off") +
                         " for planar robots; spatial robots: the statics (tensions, load cells, equilibrium, stretch), "
                         "on unless given off")
      ->check(CLI::IsMember({"on", "off"}));
  id_cmd->add_option("--report", ident.report_dir,
                     "folder for a calibration report: report.md with the estimates, figures and provenance, and the "
                     "data files behind them (created if new; its parent must exist)");
  id_cmd->add_option("--holdout", ident.holdout_path,
                     "held-out measurement CSV: the report compares the calibrated and nominal robots' predictions "
                     "with its laser and inclinometer readings (needs --report)")
      ->check(CLI::ExistingFile);

  cablecal::cli::ValidateCommandOptions val;
  CLI::App* val_cmd =
      app.add_subcommand("validate", "compare a calibrated (and the nominal) robot's predictions with held-out poses");
  val_cmd->add_option("--robot", val.robot_path, "the robot to validate (e.g. identify --calibrated-robot's file)")
      ->required()
      ->check(CLI::ExistingFile);
  val_cmd->add_option("--nominal", val.nominal_path, "the nominal robot file, validated beside it for comparison")
      ->check(CLI::ExistingFile);
  val_cmd->add_option("--measurements", val.measurements_path, "measurement CSV of poses not used to calibrate")
      ->required()
      ->check(CLI::ExistingFile);
  val_cmd->add_option("--delimiter", val.delimiter, "the measurement CSV's separator: ',', ';' or tab")
      ->capture_default_str();
  val_cmd->add_option("--out", val.out_path, "CSV, one row per reading: measured and predicted z, theta and their errors (required unless --json)");
  val_cmd->add_option("--summary", val.summary_path, "summary YAML: RMS and largest errors per robot");
  val_cmd->add_flag("--json", val.json, "print the summary and the per-pose rows as JSON on stdout");
  val_cmd->add_flag("--skip-infeasible", val.skip_infeasible,
                    "skip the readings a robot cannot hold (each named on stderr and in the summary) instead of "
                    "stopping at the first; an error still if every reading is skipped");

  cablecal::cli::SensorsFitOptions sfit;
  CLI::App* sensors_cmd = app.add_subcommand("sensors", "the laser's and inclinometer's error models");
  sensors_cmd->require_subcommand(1);
  CLI::App* sfit_cmd = sensors_cmd->add_subcommand(
      "fit", "fit systematic errors, accuracy and repeatability from bench readings to a robot file's sensors block");
  AddRobotOption(sfit_cmd, &sfit.robot_path);
  sfit_cmd->add_option("--inclinometer", sfit.inclinometer_path, "inclinometer bench CSV (reference_rad,reading_rad)")
      ->check(CLI::ExistingFile);
  sfit_cmd->add_option("--laser", sfit.laser_path, "laser bench CSV (reference_m,reading_m)")->check(CLI::ExistingFile);
  sfit_cmd->add_option("--delimiter", sfit.delimiter, "the bench CSVs' separator: ',', ';' or tab")->capture_default_str();
  sfit_cmd->add_option("--out", sfit.out_path, "the sensors: block (YAML) for a robot file")->required();
  sfit_cmd->add_option("--robot-out", sfit.robot_out_path,
                       "also write the whole robot file (--robot's, or the built-in one) with the fitted sensors block "
                       "in place of its own");

  cablecal::cli::DesignCommandOptions des;
  CLI::App* des_cmd = app.add_subcommand("design", "choose optimal measurement poses (Ipopt)");
  AddRobotOption(des_cmd, &des.robot_path);
  des_cmd->add_option("--poses", des.poses,
                     "number of poses (at least 5 with 2 cables, 4 with 3 to 8; spatial robots: as their sensors need, "
                     "named when too few)")
      ->required()
      ->transform(WholeNumberIn(1, cablecal::kMaxPlanPoses));  // the design says its own bound
  des_cmd->add_option("--criterion", des.criterion, "a|d|e|condition")
      ->capture_default_str()
      ->check(CLI::IsMember({"condition", "d", "a", "e"}));
  des_cmd->add_option("--starts", des.starts, "random feasible starts (best kept)")
      ->capture_default_str()
      ->transform(WholeNumberIn(1, 1000));
  des_cmd->add_option("--seed", des.seed, "random seed")->capture_default_str()->transform(kSeed);
  des_cmd->add_option("--min-spacing", des.min_spacing_m, "minimum distance between poses, m")
      ->capture_default_str()
      ->check(kNonNegative);
  des_cmd->add_option("--random-sets", des.random_sets, "random sets for the reference median (0: none)")
      ->capture_default_str()
      ->transform(WholeNumberIn(0, 100000));
  des_cmd->add_option("--geometry-sigma", des.geometry_sigma_m,
                      "uncertainty of the true exit points and initial lengths the plan must survive, m (0: off; "
                      "spatial robots: the exit points, default the robot file's tracker sigma if it has one)")
      ->capture_default_str()
      ->each([&des](const std::string&) { des.geometry_sigma_given = true; });
  des_cmd->add_option("--robust-sigmas", des.robust_sigmas,
                      "k: poses hold for geometry errors up to k sigma")
      ->capture_default_str()
      ->each([&des](const std::string&) { des.robust_sigmas_given = true; });
  des_cmd->add_option("--prior", des.prior_path,
                      "result.yaml of an earlier identification: plan the next poses around its estimate and "
                      "count its information");
  des_cmd->add_option("--out", des.out_path, "pose plan CSV (required unless --json)");
  des_cmd->add_flag("--json", des.json, "print the summary and the poses as JSON on stdout");
  des_cmd->add_option("--summary", des.summary_path, "summary YAML");
  des_cmd->add_option("--plot", des.plot_path, "PNG of the workspace with the chosen poses");

  cablecal::cli::MonteCarloCommandOptions mc;
  CLI::App* mc_cmd = app.add_subcommand(
      "montecarlo", cablecal::cli::BuiltWithMpi() ? "predict the calibration accuracy by Monte Carlo (OpenMP, MPI)"
                                                  : "predict the calibration accuracy by Monte Carlo (OpenMP)");
  AddRobotOption(mc_cmd, &mc.robot_path);
  mc_cmd->add_option("--poses", mc.poses, "pose counts first:last[:step], e.g. 6:50 or 6:50:4")->required();
  mc_cmd->add_option("--trials", mc.trials, "trials per cell")->required()->transform(WholeNumberIn(1, 100000000));
  mc_cmd->add_option("--designs", mc.designs, "comma list of random, optimized (= a), condition, d, a, e; for spatial robots also grid:2x2x2, grid:3x3x3")->capture_default_str();
  mc_cmd->add_option("--estimator", mc.estimator, "ml|paper")->capture_default_str()->check(CLI::IsMember({"ml", "paper"}));
  mc_cmd->add_option("--gauge", mc.gauge, "a1x|prior|none")->capture_default_str()->check(CLI::IsMember({"a1x", "prior", "none"}));
  mc_cmd->add_option("--sensors", mc.sensors, "noisy sensors: both|laser|inclinometer|none")
      ->capture_default_str()
      ->check(CLI::IsMember({"both", "laser", "inclinometer", "none"}));
  mc_cmd->add_option("--geometry-sigma", mc.geometry_sigma_m, "true geometry's deviation from nominal, m")
      ->capture_default_str()
      ->check(kNonNegative);
  mc_cmd->add_flag("--geometry-prior", mc.geometry_prior,
                   "identify every trial with a prior of --geometry-sigma on the geometry (identify --geometry-prior)");
  mc_cmd->add_option("--loss", mc.loss, "robust loss of every identification, as identify --loss")
      ->capture_default_str();
  mc_cmd->add_option("--equilibrium", mc.equilibrium, "every identification's 2-cable equilibrium rows, as identify")
      ->capture_default_str()
      ->check(CLI::IsMember({"on", "off"}));
  mc_cmd->add_option("--com-error", mc.com_error_m,
                     "the true robot's centre of mass off the robot file's by this along the platform's x, m "
                     "(what a wrong platform.com costs)")
      ->capture_default_str();
  mc_cmd->add_option("--outliers", mc.outliers,
                     "RATE[:SIZE]: each reading off by SIZE sigmas (default 100) with probability RATE")
      ->capture_default_str();
  mc_cmd->add_option("--design-starts", mc.design_starts, "Ipopt starts per designed set")
      ->capture_default_str()
      ->transform(WholeNumberIn(1, 1000));
  mc_cmd->add_option("--threads", mc.threads, "OpenMP threads (default: all cores)")
      ->transform(WholeNumberIn(1, kMaxThreads));
  mc_cmd->add_option("--seed", mc.seed, "random seed")->capture_default_str()->transform(kSeed);
  mc_cmd->add_flag("--skip-infeasible", mc.skip_infeasible,
                    "spatial robots: each trial skips the poses its true robot cannot hold within its limits (as simulate "
                    "--skip-infeasible) and identifies from the rest, instead of failing");
  mc_cmd->add_flag("--exact-platform", mc.exact_platform,
                    "spatial robots: every trial's true platform has the robot file's mass and centre of mass, instead "
                    "of values drawn from platform.mass_sigma and platform.com_sigma (defaults 1 % and 5 mm)");
  mc_cmd->add_option("--tension-margin", mc.tension_margin_N,
                     "spatial robots: N; plan every pose set with the tension bounds narrowed by this, so the true robot's "
                     "tensions keep room (its limits stay the file's)")
      ->capture_default_str();
  mc_cmd->add_option("--frame-margin", mc.frame_margin_m,
                     "spatial robots: m; plan every pose set with the frame margin widened by this")
      ->capture_default_str();
  mc_cmd->add_option("--tilt-margin-deg", mc.tilt_margin_deg,
                     "spatial robots: degrees; plan every pose set with the tilt limit lowered by this")
      ->capture_default_str();
  mc_cmd->add_option("--random-pool", mc.random_pool,
                     "spatial robots: draw each trial's random set from P poses sampled once per study (0: a fresh sample "
                     "per trial)")
      ->capture_default_str()
      ->transform(WholeNumberIn(0, 100000));
  mc_cmd->add_flag("!--no-plot", mc.plot, "skip the figures");
  mc_cmd->add_option("--out", mc.out_dir, "output folder")->required();

  cablecal::cli::ReproduceOptions rep;
  CLI::App* rep_cmd = app.add_subcommand(
      "reproduce", "run the paper's study on the built-in robot into results/ (--study spatial: the spatial study into "
                   "results/spatial/)");
  AddRobotOption(rep_cmd, &rep.robot_path);
  rep_cmd->add_option("--study", rep.study, "paper (the planar study) or spatial (the built-in cogiro and irma4u)")
      ->capture_default_str()
      ->check(CLI::IsMember({"paper", "spatial"}));
  // A testing aid of the spatial study (README, "The spatial study"): hidden from --help.
  // Read as text and checked after parsing: CLI11 names a hidden option's errors with an empty
  // name (": must be ...").
  std::string pose_counts_text;
  rep_cmd->add_option("--pose-counts", pose_counts_text, "spatial study: the first K pose counts of each configuration")
      ->group("");
  rep_cmd->add_option("--designs", rep.designs,
                      "spatial study: the designs run, of random,optimized,grid:2x2x2,grid:3x3x3 (default: all four)");
  rep_cmd->add_flag("!--no-plot", rep.plot, "skip the figures");
  rep_cmd->add_option("--trials", rep.trials, "trials per cell")->capture_default_str()->transform(WholeNumberIn(1, 100000000));
  rep_cmd->add_option("--threads", rep.threads, "OpenMP threads (default: all cores)")
      ->transform(WholeNumberIn(1, kMaxThreads));
  rep_cmd->add_option("--seed", rep.seed, "random seed")->capture_default_str()->transform(kSeed);
  rep_cmd->add_option("--out", rep.out_dir, "output folder")->capture_default_str();

  // On every subcommand: --version, and -v / -q given after the subcommand's name.
  bool verbose = false, quiet = false;
  CLI::Option* verbose_flag = app.add_flag("-v,--verbose", verbose, "also show the solvers' (Ceres') log lines");
  app.add_flag("-q,--quiet", quiet, "print nothing but errors (no summary, progress or warnings)")->excludes(verbose_flag);
  std::vector<std::string> commands;
  for (CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) {
    commands.push_back(sub->get_name());
    sub->fallthrough();
    sub->set_version_flag("--version", version);
    for (CLI::App* nested : sub->get_subcommands([](CLI::App*) { return true; })) {
      nested->fallthrough();
      nested->set_version_flag("--version", version);
    }
  }
  // A misspelt command: CLI11 would call it an unexpected argument.
  if (argc > 1 && argv[1][0] != '-' &&
      std::find(commands.begin(), commands.end(), std::string(argv[1])) == commands.end()) {
    if (root) {
      const std::string guess = cablecal::cli::Closest(argv[1], commands);
      std::string list;
      for (const std::string& c : commands) list += (list.empty() ? "" : ", ") + c;
      std::fprintf(stderr, "cablecal: error: unknown command '%s'%s; the commands are %s\nRun with --help for usage.\n",
                   cablecal::PrintableText(argv[1]).c_str(),
                   guess.empty() ? "" : (" (did you mean '" + guess + "'?)").c_str(), list.c_str());
    }
    return cablecal::kExitBadInput;
  }

  // Every rank parses the same arguments; only rank 0 prints what parsing says.
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return root ? app.exit(e) : e.get_exit_code();
  } catch (const CLI::CallForAllHelp& e) {
    return root ? app.exit(e) : e.get_exit_code();
  } catch (const CLI::CallForVersion& e) {
    return root ? app.exit(e) : e.get_exit_code();
  } catch (const CLI::ParseError& e) {
    if (root) std::fprintf(stderr, "cablecal: error: %s\nRun with --help for usage.\n", e.what());
    return cablecal::kExitBadInput;
  }
  if (ctx.processes.count > 1 && !mc_cmd->parsed() && !rep_cmd->parsed()) {
    if (root) {
      std::fprintf(stderr, "cablecal: error: only montecarlo and reproduce run on several MPI processes (got %d); "
                           "run '%s' without mpirun or srun\n", ctx.processes.count,
                   app.get_subcommands().front()->get_name().c_str());
    }
    return cablecal::kExitBadInput;
  }

  // Ceres logs through glog: its lines ("Linear solver failure ...") only with -v, and then
  // without glog's "Logging before InitGoogleLogging()" line.
  FLAGS_logtostderr = true;
  FLAGS_minloglevel = verbose ? google::GLOG_INFO : google::GLOG_FATAL;
  google::InitGoogleLogging("cablecal");
  ctx.quiet = quiet;
  ident.gauge_given = gauge_option->count() > 0;
  ident.max_iterations_given = max_iterations_option->count() > 0;
  ident.equilibrium_given = equilibrium_option->count() > 0;
  const bool json = (id_cmd->parsed() && ident.json) || (des_cmd->parsed() && des.json) || (val_cmd->parsed() && val.json);
  if (quiet && !json && std::freopen("/dev/null", "w", stdout) == nullptr) {
    std::fprintf(stderr, "cablecal: error: --quiet: cannot silence the standard output\n");
    return cablecal::kExitInternal;
  }

  try {
    if (ws_cmd->parsed()) return cablecal::cli::RunWorkspace(ctx, ws);
    if (sample_cmd->parsed()) return cablecal::cli::RunSample(ctx, sample);
    if (sim_cmd->parsed()) return cablecal::cli::RunSimulate(ctx, sim);
    if (id_cmd->parsed()) return cablecal::cli::RunIdentify(ctx, ident);
    if (val_cmd->parsed()) return cablecal::cli::RunValidate(ctx, val);
    if (des_cmd->parsed()) return cablecal::cli::RunDesign(ctx, des);
    if (sfit_cmd->parsed()) return cablecal::cli::RunSensorsFit(ctx, sfit);
    if (mc_cmd->parsed()) return cablecal::cli::RunMonteCarloCommand(ctx, mc);
    if (rep_cmd->parsed()) {
      if (rep_cmd->count("--pose-counts") > 0) {
        std::string text = pose_counts_text;
        const std::string wrong = WholeNumberIn(1, 100)(text);
        if (!wrong.empty()) throw cablecal::InputError("--pose-counts", "", wrong);
        rep.pose_counts = std::stoi(text);
      }
      return cablecal::cli::RunReproduce(ctx, rep);
    }
  } catch (const cablecal::AlreadyReported& e) {
    return e.exit_code();  // every process knows; the message is out
  } catch (...) {
    const int code = cablecal::cli::ReportCurrentError(ctx.processes);
    // The other processes may be waiting for this one: end them all.
    if (ctx.processes.count > 1) cablecal::cli::AbortJob(code);
    return code;
  }
  return cablecal::kExitInternal;
}
