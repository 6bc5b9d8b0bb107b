#include "cli/commands.h"

#include <fcntl.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <optional>

#include "cli/sigint.h"
#include "common/atomic_output.h"
#include "common/error.h"
#include "common/format.h"
#include "common/json.h"
#include "common/yaml_writer.h"
#include "common/version.h"
#include "design/design.h"
#include "design/robustness_search.h"
#include "identify/calibration_report.h"
#include "experiment/experiment.h"
#include "identify/identify.h"
#include "identify/validate.h"
#include "model/sensors.h"
#include "model/forward_statics.h"
#include "model/statics.h"
#include "sensors/sensors.h"
#include "workspace/workspace.h"

namespace cablecal::cli {

Robot LoadRobotOption(const std::string& robot_path) {
  return robot_path.empty() ? BuiltinRobot() : LoadRobotFile(robot_path);
}

namespace {

// "--flag=x,z" for a plotting script.
std::string PointArg(const std::string& flag, const Eigen::Vector2d& p) {
  return "--" + flag + "=" + FormatDouble(p.x()) + "," + FormatDouble(p.y());
}

// The frame and the exit points, which every plot draws.
std::vector<std::string> FrameArgs(const Robot& robot) {
  std::vector<std::string> args = {PointArg("frame", Eigen::Vector2d(robot.frame_width_m, robot.frame_height_m))};
  for (const Cable& c : robot.cables) args.push_back(PointArg("exit", c.p_F_exit_m));
  return args;
}

// The console's line for readings corrected for the robot file's systematic sensor errors.
void PrintSensorCorrection(const SystematicSensorErrors& e) {
  std::printf("  readings corrected for the robot file's systematic sensor errors: laser offset %.3g m, "
              "inclinometer offset %.3g deg, sec coefficient %.3g deg\n",
              e.laser_offset_m, e.inclinometer_offset_rad * 180.0 / M_PI, e.inclinometer_sec_coefficient_rad * 180.0 / M_PI);
}

// --measurements: the CSV read by column name for `robot` (the ignored columns noted on
// stderr unless -q), as read (identify corrects them itself: IdentifyOptions::readings_as_read).
std::vector<Measurement> ReadMeasurementsOption(const Context& ctx, const Robot& robot, const std::string& path,
                                                const std::string& delimiter) {
  const std::vector<Measurement> measurements =
      ReadMeasurementsCsv(
          path, robot.num_cables(), ParseDelimiter(delimiter),
          [&](const std::vector<std::string>& ignored) {
            if (ctx.quiet) return;
            std::fprintf(stderr, "cablecal: note: %s: ignoring column%s %s\n", path.c_str(), ignored.size() > 1 ? "s" : "",
                         QuotedList(ignored).c_str());
          },
          [&](const std::string& warning) {
            if (!ctx.quiet) std::fprintf(stderr, "cablecal: warning: %s\n", PrintableText(warning).c_str());
          });
  return measurements;
}
// The same, corrected for the robot file's systematic sensor errors and checked against what
// its sensors can read (CorrectedReadings): what validate compares with.
std::vector<Measurement> ReadCorrectedMeasurementsOption(const Context& ctx, const Robot& robot, const std::string& path,
                                                         const std::string& delimiter) {
  return CorrectedReadings(robot, ReadMeasurementsOption(ctx, robot, path, delimiter), path);
}

// Whether two paths name one file (the same device and inode: another spelling of the path, a
// symbolic or a hard link); false when either does not exist.
bool SameFile(const std::string& a, const std::string& b) {
  std::error_code ec;
  return std::filesystem::equivalent(a, b, ec) && !ec;
}

// identify --holdout: the report's validation is its main evidence that the calibration
// predicts poses it did not see, so the held-out readings cannot be the training readings.
void RefuseHoldoutThatIsTheMeasurements(const std::string& holdout_path, const std::string& measurements_path) {
  if (holdout_path.empty() || !SameFile(holdout_path, measurements_path)) return;
  throw InputError("--holdout", "",
                   "'" + holdout_path + "' is the --measurements file ('" + measurements_path +
                       "'): held-out readings must not have been used to calibrate, or the report's validation "
                       "only repeats the fit; give the readings of other poses");
}

}  // namespace

// A progress bar with rate and time left when stderr is a terminal; nothing otherwise.
std::function<void(long, long)> ProgressBar(const std::string& label, const std::string& unit) {
  if (!::isatty(2)) return nullptr;
  const auto start = std::chrono::steady_clock::now();
  auto last = std::make_shared<std::chrono::steady_clock::time_point>(start - std::chrono::seconds(1));
  return [=](long done, long total) {
    const auto now = std::chrono::steady_clock::now();
    if (done < total && now - *last < std::chrono::milliseconds(200)) return;
    *last = now;
    const double elapsed = std::chrono::duration<double>(now - start).count();
    const double rate = elapsed > 0 ? done / elapsed : 0.0;
    const double left = rate > 0 ? (total - done) / rate : 0.0;
    const int width = 30, filled = static_cast<int>(width * done / std::max(1L, total));
    std::fprintf(stderr, "\r%s [%s%s] %ld/%ld %s, %.3g/s, %.0f s left   ", label.c_str(),
                 std::string(filled, '#').c_str(), std::string(width - filled, ' ').c_str(), done, total, unit.c_str(),
                 rate, left);
    if (done == total) std::fprintf(stderr, "\n");
  };
}

std::function<void(double)> TryingRobustnessNotice(double requested_k) {
  // The why once, then each k tried: the search designs at up to six values of k.
  return [requested_k, first = true](double k) mutable {
    if (first) {
      std::fprintf(stderr, "cablecal: design: no verified poses at --robust-sigmas %s; searching for the largest k "
                   "below it that has some: trying %s\n", FormatDouble(requested_k).c_str(), FormatDouble(k).c_str());
    } else {
      std::fprintf(stderr, "cablecal: design: trying --robust-sigmas %s\n", FormatDouble(k).c_str());
    }
    first = false;
  };
}

// The figures are PNG: a --plot named otherwise would get PNG bytes under a misleading name.
void CheckPngPath(const std::string& flag, const std::string& path) {
  if (path.empty()) return;
  const std::string ext = std::filesystem::path(path).extension().string();
  if (ext != ".png" && ext != ".PNG") throw InputError(flag, "", "figures are PNG files: name it *.png (got '" + path + "')");
}

std::string Closest(const std::string& typed, const std::vector<std::string>& names) {
  std::string best;
  std::size_t best_distance = std::max<std::size_t>(2, typed.size() / 3) + 1;
  for (const std::string& name : names) {
    // Levenshtein distance, one row at a time.
    std::vector<std::size_t> row(name.size() + 1);
    for (std::size_t j = 0; j <= name.size(); ++j) row[j] = j;
    for (std::size_t i = 1; i <= typed.size(); ++i) {
      std::size_t diagonal = row[0];
      row[0] = i;
      for (std::size_t j = 1; j <= name.size(); ++j) {
        const std::size_t above = row[j];
        row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (typed[i - 1] == name[j - 1] ? 0 : 1)});
        diagonal = above;
      }
    }
    if (row[name.size()] < best_distance) {
      best_distance = row[name.size()];
      best = name;
    }
  }
  return best;
}

// The plotting scripts sit beside the executable, not at a path baked in at build time:
// share/cablecal/scripts under the build folder (copied there at every build) or, once
// installed, under bin/'s parent. CABLECAL_SCRIPTS_DIR overrides both.
std::string PlotScriptsDir() {
  if (const char* env = std::getenv("CABLECAL_SCRIPTS_DIR")) return env;
  std::error_code error;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", error);
  if (error) return "scripts";
  for (const std::filesystem::path& dir : {exe.parent_path() / "share/cablecal/scripts",
                                           exe.parent_path().parent_path() / "share/cablecal/scripts"}) {
    if (std::filesystem::is_directory(dir, error)) return dir.string();
  }
  return (exe.parent_path().parent_path() / "share/cablecal/scripts").string();  // named by the failure
}

namespace {

// The plotting scripts exit with this status when matplotlib or numpy cannot be imported
// (scripts/plot_*.py): a missing library, not a failed figure.
constexpr int kMissingPlotLibraryExit = 3;

// What to do when the figures' python or its libraries are missing.
std::string InstallAdvice() {
  return "install them with scripts/setup.sh or apt-get install python3-matplotlib, or set CABLECAL_PYTHON to a "
         "python3 that has matplotlib";
}

// Starts argv in a child process that dies with cablecal; returns its pid. An exec that fails
// (no such python) is told apart from the script's own failure through a close-on-exec pipe:
// the child writes its errno there only when exec failed. Throws FigureFailure then.
pid_t StartPlotProcess(std::vector<std::string>& argv) {
  std::vector<char*> c_argv;
  for (std::string& a : argv) c_argv.push_back(a.data());
  c_argv.push_back(nullptr);
  int exec_error[2];
  if (::pipe2(exec_error, O_CLOEXEC) != 0) {
    throw FigureFailure(std::string("the figure could not be made: cannot start ") + argv[0]);
  }
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::close(exec_error[0]);
    // The script dies with cablecal: a killed run leaves no orphan writing figures.
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (::getppid() != parent) ::_exit(127);
    ::execvp(c_argv[0], c_argv.data());
    const int error = errno;
    [[maybe_unused]] const ssize_t written = ::write(exec_error[1], &error, sizeof error);
    ::_exit(127);
  }
  ::close(exec_error[1]);
  int error = 0;
  ssize_t got = 0;
  if (pid > 0) {
    do {
      got = ::read(exec_error[0], &error, sizeof error);
    } while (got < 0 && errno == EINTR);
  }
  ::close(exec_error[0]);
  if (pid < 0) throw FigureFailure(std::string("the figure could not be made: cannot start ") + argv[0]);
  if (got == static_cast<ssize_t>(sizeof error)) {
    int status = 0;
    while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    throw FigureFailure("the figure could not be made: cannot run " + argv[0] + " (" + std::strerror(error) +
                        "): the figures need python3 with matplotlib; " + InstallAdvice());
  }
  return pid;
}

}  // namespace

void RunPlotScript(const std::string& script, const std::vector<std::string>& args) {
  const std::string scripts_dir = PlotScriptsDir();
  const char* python_env = std::getenv("CABLECAL_PYTHON");
  // Debian's python3-matplotlib is installed for /usr/bin/python3, which may not be the
  // python3 first on PATH (pyenv, conda).
  std::string python = python_env ? python_env
                                  : (std::filesystem::exists("/usr/bin/python3") ? "/usr/bin/python3" : "python3");
  std::vector<std::string> argv = {python, scripts_dir + "/" + script};
  argv.insert(argv.end(), args.begin(), args.end());
  const std::string command = CommandLine(argv);
  // fork and exec, not std::system: system() ignores SIGINT in cablecal while the script runs,
  // so a Ctrl-C then reached only the script and looked like a failed figure (exit 5, results
  // written) instead of an interruption (exit 130, nothing written).
  const pid_t pid = StartPlotProcess(argv);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) throw FigureFailure("the figure could not be made: lost the plotting script: " + command);
  }
  // Ctrl-C reaches the script too (one process group): the script's failure, or its figures,
  // are then an interruption, not a failed figure (SigintFlag is set only inside a SigintScope).
  if (SigintFlag()) throw Interrupted();
  if (WIFEXITED(status) && WEXITSTATUS(status) == kMissingPlotLibraryExit) {
    throw FigureFailure("the figure could not be made: " + python + " has no matplotlib (or numpy); " + InstallAdvice());
  }
  if (!(WIFEXITED(status) && WEXITSTATUS(status) == 0)) {
    const std::string how = WIFEXITED(status) ? "exit status " + std::to_string(WEXITSTATUS(status))
                                              : "signal " + std::to_string(WIFSIGNALED(status) ? WTERMSIG(status) : 0);
    throw FigureFailure("the figure could not be made: the plotting script failed (" + how + "): " + command);
  }
}

std::string TryPlot(AtomicOutput& output, const std::string& figure_path, const std::string& script,
                    const std::vector<std::string>& args) {
  try {
    RunPlotScript(script, args);
    return "";
  } catch (const FigureFailure& e) {
    output.Drop(figure_path);
    // A figure left from an earlier run would sit beside the new data as if it showed them.
    std::error_code ec;
    if (std::filesystem::remove(figure_path, ec)) {
      return std::string(e.what()) + "; the earlier " + figure_path + " was removed (it showed another run)";
    }
    return e.what();
  }
}

int RunWorkspace(const Context& ctx, const WorkspaceOptions& options) {
  CheckCommandPaths({{"--robot", options.robot_path}},
                    {{"--out", options.out_path}, {"--plot", options.plot_path}});
  CheckPngPath("--plot", options.plot_path);
  if (IsSpatialRobotFile(options.robot_path)) return RunSpatialWorkspace(ctx, options);
  RefuseSpatialOnlyFlag(!options.rpy_deg.empty(), "--rpy-deg");
  const Robot robot = LoadRobotOption(options.robot_path);
  const double step_m = options.step_m < 0.0 ? 0.05 : options.step_m;
  const WorkspaceGrid grid = ComputeWorkspaceGrid(robot, step_m);
  AtomicOutput output;
  std::string figure_error;
  const std::string temp_csv =
      output.WriteText(options.out_path, WorkspaceCsv(robot, grid, ProvenanceComment(ctx.command_line)));
  if (!options.plot_path.empty()) {
    // The script reads the CSV's temporary: final files appear only when both succeeded.
    std::vector<std::string> args = {temp_csv, output.Add(options.plot_path)};
    for (const std::string& a : FrameArgs(robot)) args.push_back(a);
    args.push_back(PointArg("home", robot.p_F_home_m));
    args.push_back("--title=" + robot.name);
    figure_error = TryPlot(output, options.plot_path, "plot_workspace.py", args);
  }
  output.Commit();
  std::printf("workspace of %s: %d of %zu grid points feasible (step %s m), area ~ %.4g m^2\n", PrintableText(robot.name).c_str(),
              grid.num_feasible, grid.points.size(), FormatDouble(step_m).c_str(), grid.feasible_area_m2());
  if (!figure_error.empty()) throw FigureFailure(figure_error + "; " + options.out_path + " was written");
  return kExitOk;
}

int RunSample(const Context& ctx, const SampleOptions& options) {
  CheckCommandPaths({{"--robot", options.robot_path}}, {{"--out", options.out_path}});
  if (IsSpatialRobotFile(options.robot_path)) return RunSpatialSample(ctx, options);
  RefuseSpatialOnlyFlag(options.yaw_range_deg >= 0.0, "--yaw-range-deg");
  const Robot robot = LoadRobotOption(options.robot_path);
  const std::vector<PlanPose> plan = SampleFeasiblePoses(robot, options.poses, options.seed);
  AtomicOutput output;
  output.WriteText(options.out_path, PosePlanCsv(plan, ProvenanceComment(ctx.command_line)));
  output.Commit();
  std::printf("wrote %zu random feasible poses of %s (seed %llu) to %s\n", plan.size(), PrintableText(robot.name).c_str(),
              options.seed, options.out_path.c_str());
  return kExitOk;
}

int RunSimulate(const Context& ctx, const SimulateOptions& options) {
  CheckCommandPaths({{"--robot", options.robot_path}, {"--truth", options.truth_path}, {"--plan", options.plan_path}},
                    {{"--out", options.out_path}, {"--truth-out", options.truth_out_path}});
  if (IsSpatialRobotFile(options.robot_path)) return RunSpatialSimulate(ctx, options);
  const Robot nominal = LoadRobotOption(options.robot_path);
  // A pose where the true robot settles outside its own workspace (beyond a tension limit,
  // the inclinometer range or the margin) would stop a lab's experiment: exit 2 naming the
  // plan's pose (the Monte Carlo counts such a trial as failed).
  SimulationOptions sim{ParseNoisySensors(options.sensors), !options.no_encoder_noise, true};
  sim.systematic_errors = options.systematic_errors;
  sim.skip_infeasible = options.skip_infeasible;
  if (sim.systematic_errors && !nominal.sensors.systematic.any()) {
    throw InputError("--systematic-errors", "",
                     "the robot " + PrintableText(nominal.name) + " (" + (options.robot_path.empty() ? "built in" : options.robot_path) +
                         ") has no systematic sensor errors to add (sensors.laser.offset, "
                         "sensors.inclinometer.offset_deg, sec_coefficient_deg; cablecal sensors fit makes them)");
  }
  if (options.geometry_sigma_m > kMaxGeometrySigma_m) {  // as design's and montecarlo's
    throw InputError("--geometry-sigma", "", "must be at most " + FormatDouble(kMaxGeometrySigma_m) +
                                                 " m: a larger error is not a calibration problem (got " +
                                                 FormatDouble(options.geometry_sigma_m) + ")");
  }
  if (!options.truth_path.empty() && options.geometry_sigma_m >= 0.0) {
    throw InputError("--truth", "", "give either --truth or --geometry-sigma, not both");
  }
  const std::vector<PlanPose> plan = ReadPosePlanCsv(options.plan_path, nominal.num_cables());
  CheckPlanMatchesRobot(nominal, plan, options.plan_path);
  std::optional<Robot> given_truth;
  if (!options.truth_path.empty()) given_truth = LoadRobotFile(options.truth_path);
  const PlanSimulation run = SimulatePlan(nominal, given_truth, std::max(options.geometry_sigma_m, 0.0), plan, sim,
                                          options.seed, options.plan_path);
  const Robot& truth = run.truth;
  const SimulatedExperiment& experiment = run.experiment;
  AtomicOutput output;
  output.WriteText(options.out_path, MeasurementsCsv(experiment.measurements, ProvenanceComment(ctx.command_line)));
  if (!options.truth_out_path.empty()) {
    std::string provenance = ProvenanceComment(ctx.command_line);
    output.WriteText(options.truth_out_path,
                     provenance + TruthYaml(WithGeometry(truth, GeometryOf(truth)), experiment.measurements,
                                            experiment.true_poses));
  }
  output.Commit();
  if (!ctx.quiet) {
    for (const SkippedPose& skipped : experiment.skipped) {
      std::fprintf(stderr, "cablecal: skipped pose %d of %s: %s\n", skipped.pose_id, options.plan_path.c_str(),
                   skipped.reason.c_str());
    }
  }
  std::printf("simulated %s%s (noisy sensors: %s, encoder noise %s%s) to %s\n",
              Counted(experiment.measurements.size(), "pose").c_str(),
              SkippedPosesText(options.skip_infeasible, experiment.skipped.size(), plan.size()).c_str(),
              ToString(sim.noisy), sim.encoder_noise ? "on" : "off",
              sim.systematic_errors ? ", systematic sensor errors added" : "", options.out_path.c_str());
  return kExitOk;
}

// Long (~140 lines) for a reason: the identify command's one sequence (read, identify, write
// every output atomically, print the summary), each output from the same result.
int RunIdentify(const Context& ctx, const IdentifyCommandOptions& options) {
  CheckCommandPaths({{"--robot", options.robot_path},
                     {"--measurements", options.measurements_path},
                     {"--holdout", options.holdout_path},
                     {"--plan", options.plan_path}},
                    {{"--out", options.out_path}, {"--calibrated-robot", options.calibrated_robot_path}});
  if (options.out_path.empty() && !options.json) throw InputError("--out", "", "required (or print the result with --json)");
  if (!options.holdout_path.empty() && options.report_dir.empty()) {
    throw InputError("--holdout", "", "needs --report DIR: the held-out readings are compared in the report");
  }
  RefuseHoldoutThatIsTheMeasurements(options.holdout_path, options.measurements_path);
  if (IsSpatialRobotFile(options.robot_path)) return RunSpatialIdentify(ctx, options);
  RefuseSpatialOnlyFlag(options.gauge == "auto" || options.gauge.rfind("hold:", 0) == 0, "--gauge " + options.gauge);
  RefuseSpatialOnlyFlag(!options.identify.empty(), "--identify " + options.identify);
  RefuseSpatialOnlyFlag(!options.plan_path.empty(), "--plan");
  // The report's folder is checked before any work, and no other file may be one it writes.
  std::unique_ptr<OutputFolder> report;
  if (!options.report_dir.empty()) {
    report = std::make_unique<OutputFolder>("--report", options.report_dir, ReportFileNames());
    report->RefuseInputs({{"--robot", options.robot_path},
                          {"--measurements", options.measurements_path},
                          {"--holdout", options.holdout_path},
                          {"--out", options.out_path},
                          {"--calibrated-robot", options.calibrated_robot_path}});
  }
  const Robot nominal = LoadRobotOption(options.robot_path);
  IdentifyOptions id;
  id.estimator = ParseEstimator(options.estimator);
  id.gauge = ParseGauge(options.gauge);
  id.source = options.measurements_path;
  id.max_iterations = options.max_iterations;
  id.loss = ParseLoss(options.loss);
  if (options.geometry_prior_given) id.geometry_prior_sigma_m = options.geometry_prior_sigma_m;
  id.equilibrium = options.equilibrium == "on";
  id.readings_as_read = true;
  // A robot file with systematic sensor errors (sensors fit) has them removed before the solve.
  const std::vector<Measurement> measurements =
      ReadMeasurementsOption(ctx, nominal, options.measurements_path, options.delimiter);
  // Identify corrects and checks the readings itself (readings_as_read); checked here too, so
  // that a reading no sensor can give is named before the held-out file is read (and its notes
  // printed), as a lab fixes them: its own data first.
  CorrectedReadings(nominal, measurements, options.measurements_path);
  // Read before the solve: a bad held-out file is refused before any work.
  const std::vector<Measurement> holdout =
      options.holdout_path.empty() ? std::vector<Measurement>()
                                   : ReadCorrectedMeasurementsOption(ctx, nominal, options.holdout_path, options.delimiter);
  IdentifyResult result = Identify(nominal, measurements, id);
  RequireUsableResult(result, options.measurements_path);
  // Not made for --json alone: 100,000 poses' tables cost a second (issue 24).
  const std::string result_yaml =
      options.out_path.empty() && !report ? std::string() : IdentifyResultYaml(result, ctx.command_line);
  const ReportSources sources{ctx.command_line, options.measurements_path, options.holdout_path};
  std::optional<ValidationResult> validation;
  if (!holdout.empty()) validation = ValidateCalibration(nominal, result, holdout, sources);
  AtomicOutput output;
  if (!options.out_path.empty()) output.WriteText(options.out_path, result_yaml);
  if (!options.calibrated_robot_path.empty()) {
    const Robot calibrated = WithGeometry(nominal, result.geometry);
    output.WriteText(options.calibrated_robot_path,
                     ProvenanceComment(ctx.command_line) + "# calibrated: exit points and initial lengths identified (" +
                         ToString(id.estimator) + ", gauge " + ToString(id.gauge) + ")\n" + RobotToYaml(calibrated));
  }
  std::string figure_error;
  if (report) {
    const SigintScope sigint;  // Ctrl-C while the figures are drawn: exit 130, nothing written
    const auto draw = [](const std::vector<std::string>& arguments) {
      try {
        RunPlotScript("plot_report.py", arguments);
        return std::string();
      } catch (const FigureFailure& e) {
        return std::string(e.what());
      }
    };
    figure_error = StageReport(*report, nominal, result, result_yaml, validation ? &*validation : nullptr, sources, draw);
    if (SigintFlag()) throw Interrupted();
  }
  output.Commit();
  if (report) report->Commit();
  // Said after the summary below: the results were written, the figures were not.
  if (!figure_error.empty()) figure_error = ReportWithoutFiguresMessage(options.report_dir, figure_error);
  if (options.json) {
    std::printf("%s\n", IdentifyResultJson(result, ctx.command_line).c_str());
    if (!figure_error.empty()) throw FigureFailure(figure_error);
    return kExitOk;
  }
  // The console rounds to what a reader compares (3 significant digits, 0.1 um for lengths);
  // result.yaml keeps every digit.
  std::printf("identified %s from %zu poses", PrintableText(nominal.name).c_str(), result.poses.size());
  if (result.poses.size() != measurements.size()) std::printf(" (%zu readings)", measurements.size());
  std::string settings = id.loss.kind == LossKind::kNone ? "" : ", loss " + ToString(id.loss);
  if (id.geometry_prior_sigma_m) settings += ", geometry prior " + FormatDouble(1e3 * *id.geometry_prior_sigma_m) + " mm";
  if (result.equilibrium_com_sigma_m) settings += ", equilibrium";
  std::printf(" (%s, gauge %s%s): %d iterations, residual rms encoder %.3g m", ToString(id.estimator), ToString(id.gauge),
              settings.c_str(), result.iterations, result.rms_encoder_m);
  const auto has = [&](const char* sensor) {
    return std::find(result.missing_sensors.begin(), result.missing_sensors.end(), sensor) == result.missing_sensors.end();
  };
  for (const SensorUnit& u : kPlanarSensors) {
    if (has(u.name)) std::printf(", %s %.3g %s", u.name, result.rms_sensor[static_cast<int>(u.id)], u.unit);
  }
  std::printf("\n");
  if (!result.missing_sensors.empty()) {
    std::printf("  the data have %s: see identifiability in the result\n", MissingSensorsText(result.missing_sensors).c_str());
  }
  for (const std::string& d : result.down_weighted) std::printf("  down-weighted: %s\n", d.c_str());
  for (const int id : result.dropped_pose_ids) std::printf("  dropped: pose %d (see the warning)\n", id);
  // How large a single wrong reading must be before the other poses show it (median over the
  // readings, per sensor; result.yaml has each reading's).
  if (!result.readings.empty() && result.readings.front().min_detectable_sigmas.size() > 0) {
    const int m = nominal.num_cables();
    std::vector<std::vector<double>> by_sensor(1 + kNumPlanarSensors);  // the encoders, then each sensor
    for (const ReadingFit& f : result.readings) {
      for (int i = 0; i < m + kNumPlanarSensors; ++i) {
        if (f.HasValue(i)) by_sensor[i < m ? 0 : i - m + 1].push_back(f.min_detectable_sigmas(i));
      }
    }
    std::printf("  a single wrong reading shows beyond %s sigma from (median):", Rounded(kOutlierSigmas).c_str());
    for (int k = 0; k < 1 + kNumPlanarSensors; ++k) {
      std::vector<double>& v = by_sensor[k];
      if (v.empty()) continue;
      std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
      std::printf("%s %s %.3g sigma", k ? "," : "", k ? kPlanarSensors[k - 1].name : "encoders", v[v.size() / 2]);
    }
    std::printf("\n");
  }
  if (!ctx.quiet) {
    for (const std::string& w : result.warnings) std::fprintf(stderr, "cablecal: warning: %s\n", w.c_str());
    if (validation) {
      for (const std::string& w : validation->warnings) {
        std::fprintf(stderr, "cablecal: warning: --holdout: %s\n", w.c_str());
      }
    }
  }
  if (result.corrected_for) PrintSensorCorrection(*result.corrected_for);
  const std::vector<std::string> names = GeometryNames(nominal.num_cables());
  for (std::size_t k = 0; k < names.size(); ++k) {
    std::printf("  %s = %.7f m", names[k].c_str(), result.geometry(k));
    // A held parameter's std is 0 by construction: "held" says why (the gauge), "std 0" would
    // read as a perfectly known value.
    if (IsHeld(result, static_cast<int>(k))) {
      std::printf("  (held: the gauge)");
    } else if (result.has_covariance) {
      std::printf("  (std %.3g mm)", 1e3 * result.geometry_std(k));
    }
    std::printf("\n");
  }
  if (report) std::printf("  report: %s/report.md\n", options.report_dir.c_str());
  if (!figure_error.empty()) throw FigureFailure(figure_error);
  return kExitOk;
}

bool WriteValidationOutputs(const Context& ctx, const ValidateCommandOptions& options, const std::string& csv,
                            const std::string& summary_yaml, const std::string& rows_json,
                            const std::vector<SkippedReading>& skipped, std::size_t readings) {
  AtomicOutput output;
  if (!options.out_path.empty()) output.WriteText(options.out_path, csv);
  if (!options.summary_path.empty()) output.WriteText(options.summary_path, summary_yaml);
  output.Commit();
  if (!ctx.quiet) {
    for (const SkippedReading& k : skipped) {
      std::fprintf(stderr, "cablecal: skipped pose %d (%s): %s\n", k.pose_id, PrintableText(k.where).c_str(),
                   PrintableText(k.reason).c_str());
    }
    // Said on stderr only when something was skipped; the console's summary line counts it always.
    if (options.skip_infeasible && !skipped.empty()) {
      std::fprintf(stderr, "cablecal: skipped %zu of %zu readings that a robot cannot hold (--skip-infeasible)\n",
                   skipped.size(), readings);
    }
  }
  if (!options.json) return false;
  std::printf("%s\n", MergeJsonObjects({ToJson(YAML::Load(summary_yaml)), rows_json}).c_str());
  return true;
}

std::string Counted(std::size_t n, const std::string& noun) {
  return std::to_string(n) + " " + noun + (n == 1 ? "" : "s");
}

std::string RatioLine(const std::vector<std::pair<std::string, double>>& ratios, bool warned) {
  std::string values, worse;
  bool any_better = false;
  for (const auto& [name, ratio] : ratios) {
    values += (values.empty() ? "" : ", ") + name + " " + Rounded(ratio);
    if (ratio > 1.0) any_better = true;
    if (!(ratio > 1.0)) worse += (worse.empty() ? "" : ", ") + name;
  }
  std::string said;
  if (worse.empty()) {
    said = "above 1: the calibrated robot predicts better";
  } else if (!any_better) {
    said = "not above 1: the calibrated robot predicts no better than the nominal one";
  } else {
    said = "above 1: the calibrated robot predicts better; not for " + worse + ", where it predicts no better than the nominal one";
  }
  return "  nominal / calibrated rms: " + values + " (" + said + (warned ? "; but see the warning" : "") + ")";
}

std::string SkippedPosesText(bool skip_infeasible, std::size_t skipped, std::size_t planned) {
  if (!skip_infeasible) return "";
  return ", " + std::to_string(skipped) + " of " + std::to_string(planned) + " skipped" +
         (skipped > 0 ? " (the true robot cannot hold them)" : "");
}

std::string CountedReadings(std::size_t kept, int num_poses) {
  return num_poses == static_cast<int>(kept)
             ? Counted(kept, "pose")
             : Counted(kept, "reading") + " (" + Counted(static_cast<std::size_t>(num_poses), "pose") + ")";
}

int RunValidate(const Context& ctx, const ValidateCommandOptions& options) {
  CheckCommandPaths({{"--robot", options.robot_path},
                     {"--nominal", options.nominal_path},
                     {"--measurements", options.measurements_path}},
                    {{"--out", options.out_path}, {"--summary", options.summary_path}});
  if (options.out_path.empty() && !options.json) throw InputError("--out", "", "required (or print the result with --json)");
  if (IsSpatialRobotFile(options.robot_path)) return RunSpatialValidate(ctx, options);
  const Robot calibrated = LoadRobotFile(options.robot_path);
  std::optional<Robot> nominal;
  if (!options.nominal_path.empty()) nominal = LoadRobotFile(options.nominal_path);
  const std::vector<Measurement> measurements =
      ReadCorrectedMeasurementsOption(ctx, calibrated, options.measurements_path, options.delimiter);
  ValidationResult result =
      Validate(calibrated, nominal, measurements, options.measurements_path, options.skip_infeasible);
  if (calibrated.sensors.systematic.any()) result.corrected_for = calibrated.sensors.systematic;
  const std::string summary_yaml = ValidationSummaryYaml(result, ctx.command_line);
  if (WriteValidationOutputs(ctx, options, ValidationCsv(result, ProvenanceComment(ctx.command_line)), summary_yaml,
                             ValidationRowsJson(result), result.skipped, measurements.size())) {
    return kExitOk;
  }
  // Millimetres and milliradians, 3 significant digits: what a reader compares; the files keep
  // every digit.
  const std::size_t kept = result.pose_ids.size();
  const std::string readings = CountedReadings(kept, result.num_poses);
  std::string noise;
  if (result.has_laser) noise += "laser " + Rounded(1e3 * result.laser_sigma_m) + " mm";
  if (result.has_inclinometer) {
    noise += (noise.empty() ? "" : ", ") + std::string("inclinometer ") + Rounded(1e3 * result.inclinometer_sigma_rad) +
             " mrad";
  }
  std::printf("validated on %s of %s (error = predicted - measured; sensor noise: %s)\n", readings.c_str(),
              PrintableText(options.measurements_path).c_str(), noise.c_str());
  if (options.skip_infeasible) {
    std::printf("  skipped %zu of %zu readings that a robot cannot hold (listed on stderr and in the summary)\n",
                result.skipped.size(), measurements.size());
  }
  for (const RobotPrediction& p : result.robots) {
    std::string line;
    if (p.z_m) line += "z rms " + Rounded(1e3 * p.z_m->rms) + " mm (max " + Rounded(1e3 * p.z_m->max_abs) + " mm)";
    if (p.theta_rad) {
      line += (line.empty() ? "" : ", ") + std::string("theta rms ") + Rounded(1e3 * p.theta_rad->rms) + " mrad (max " +
              Rounded(1e3 * p.theta_rad->max_abs) + " mrad)";
    }
    std::printf("  %-10s %s  [%s]\n", p.name.c_str(), line.c_str(), PrintableText(p.source).c_str());
  }
  if (nominal) {
    std::vector<std::pair<std::string, double>> ratios;
    if (result.has_laser) ratios.emplace_back("z", ZRmsRatio(result));
    if (result.has_inclinometer) ratios.emplace_back("theta", ThetaRmsRatio(result));
    std::printf("%s\n", RatioLine(ratios, !result.warnings.empty()).c_str());
  }
  if (!NotCompared(result).empty()) std::printf("  not compared: %s\n", NotCompared(result).c_str());
  if (result.corrected_for) PrintSensorCorrection(*result.corrected_for);
  if (!ctx.quiet) {
    for (const std::string& w : result.warnings) std::fprintf(stderr, "cablecal: warning: %s\n", w.c_str());
  }
  return kExitOk;
}

int RunSensorsFit(const Context& ctx, const SensorsFitOptions& options) {
  CheckCommandPaths({{"--robot", options.robot_path},
                     {"--inclinometer", options.inclinometer_path},
                     {"--laser", options.laser_path}},
                    {{"--out", options.out_path}, {"--robot-out", options.robot_out_path}});
  if (options.inclinometer_path.empty() && options.laser_path.empty()) {
    throw InputError("--inclinometer", "", "give --inclinometer, --laser or both: the bench readings to fit");
  }
  const Robot robot = LoadRobotOption(options.robot_path);
  const char delimiter = ParseDelimiter(options.delimiter);
  const auto note_ignored = [&](const std::string& path) {
    return [&ctx, path](const std::vector<std::string>& ignored) {
      if (ctx.quiet) return;
      std::fprintf(stderr, "cablecal: note: %s: ignoring column%s %s\n", path.c_str(), ignored.size() > 1 ? "s" : "",
                   QuotedList(ignored).c_str());
    };
  };
  // Every reading is checked against its reference's others before the fit takes it in.
  const auto read = [&](BenchSensor sensor, const std::string& path) {
    const std::vector<BenchReading> readings = ReadBenchCsv(sensor, path, delimiter, note_ignored(path));
    CheckReadingsAgainstTheirReference(sensor, readings);
    return readings;
  };
  SensorsFit fit;
  if (!options.inclinometer_path.empty()) {
    const std::string& path = options.inclinometer_path;
    fit.inclinometer = FitInclinometer(read(BenchSensor::kInclinometer, path), path);
  }
  if (!options.laser_path.empty()) {
    const std::string& path = options.laser_path;
    fit.laser = FitLaser(read(BenchSensor::kLaser, path), path);
  }
  AtomicOutput output;
  output.WriteText(options.out_path, SensorsFitYaml(robot, fit, ctx.command_line));
  if (!options.robot_out_path.empty()) {
    output.WriteText(options.robot_out_path, FittedRobotYaml(robot, fit, ctx.command_line));
  }
  output.Commit();
  if (!ctx.quiet) {
    for (const std::string& w : FitWarnings(robot, fit)) std::fprintf(stderr, "cablecal: warning: %s\n", w.c_str());
  }
  constexpr double kDeg = 180.0 / M_PI;
  if (fit.inclinometer) {
    const InclinometerFit& f = *fit.inclinometer;
    std::printf("inclinometer, %d readings of %d references: offset %.3g deg (standard error %.2g), sec coefficient "
                "%.3g deg (standard error %.2g), accuracy %.3g deg, repeatability %.3g deg (3-sigma ranges)\n",
                f.bench.readings, f.bench.references, f.offset_rad * kDeg, f.offset_se_rad * kDeg,
                f.sec_coefficient_rad * kDeg, f.sec_coefficient_se_rad * kDeg, f.accuracy_rad * kDeg,
                f.repeatability_rad * kDeg);
  }
  if (fit.laser) {
    const LaserFit& f = *fit.laser;
    std::printf("laser, %d readings of %d references: offset %.3g m (standard error %.2g), accuracy %.3g m, "
                "repeatability %.3g m (3-sigma ranges)\n",
                f.bench.readings, f.bench.references, f.offset_m, f.offset_se_m, f.accuracy_m, f.repeatability_m);
  }
  std::printf("wrote the sensors block for a robot file to %s\n", options.out_path.c_str());
  if (!options.robot_out_path.empty()) {
    std::printf("wrote the robot file of %s with the fitted sensors to %s\n", PrintableText(robot.name).c_str(),
                options.robot_out_path.c_str());
  }
  return kExitOk;
}

int RunDesign(const Context& ctx, const DesignCommandOptions& options) {
  CheckCommandPaths({{"--robot", options.robot_path}, {"--prior", options.prior_path}},
                    {{"--out", options.out_path}, {"--summary", options.summary_path}, {"--plot", options.plot_path}});
  CheckPngPath("--plot", options.plot_path);
  if (options.out_path.empty() && !options.json) throw InputError("--out", "", "required (or print the poses with --json)");
  if (options.out_path.empty() && !options.plot_path.empty()) throw InputError("--plot", "", "needs --out (the plan it draws)");
  if (IsSpatialRobotFile(options.robot_path)) return RunSpatialDesign(ctx, options);
  Robot robot = LoadRobotOption(options.robot_path);
  DesignOptions design;
  if (!options.prior_path.empty()) {
    // The next round is planned around the estimate, counting the information gathered.
    DesignPrior prior = LoadDesignPrior(robot, options.prior_path);
    robot = prior.robot;
    design.prior_information = prior.information;
  }
  design.poses = options.poses;
  design.criterion = ParseCriterion(options.criterion);
  design.starts = options.starts;
  design.seed = options.seed;
  design.min_spacing_m = options.min_spacing_m;
  design.random_sets = options.random_sets;
  design.geometry_sigma_m = options.geometry_sigma_m;
  design.robust_sigmas = options.robust_sigmas;
  const SigintScope sigint;  // Ctrl-C: Ipopt stops at its next iteration, exit 130, nothing written
  design.interrupted = &SigintFlag();
  if (!ctx.quiet) {
    design.progress = ProgressBar("design", "starts");
    design.trying_robustness = TryingRobustnessNotice(design.robust_sigmas);
  }
  const DesignResult result = DesignPoses(robot, design);
  // The plan holds for the achieved k: the warnings below speak of it.
  DesignOptions achieved = design;
  achieved.robust_sigmas = result.robust_sigmas_achieved;
  AtomicOutput output;
  std::string figure_error;
  const std::string temp_plan =
      options.out_path.empty() ? "" : output.WriteText(options.out_path, PosePlanCsv(result.poses, ProvenanceComment(ctx.command_line)));
  if (!options.summary_path.empty()) {
    output.WriteText(options.summary_path, DesignSummaryYaml(result, design, ctx.command_line));
  }
  if (!options.plot_path.empty()) {
    // The background grid is an input of the plot only: written beside it, removed after,
    // however the plotting ends.
    struct RemovedWhenDone {
      std::string path;
      ~RemovedWhenDone() { std::remove(path.c_str()); }
    } const background{options.plot_path + ".workspace.tmp." + std::to_string(::getpid())};
    std::vector<std::string> args = {temp_plan, output.Add(options.plot_path)};
    const WorkspaceGrid grid = ComputeWorkspaceGrid(robot, 0.05);
    std::ofstream(background.path) << WorkspaceCsv(robot, grid, "");
    args.push_back("--workspace=" + background.path);
    // plot_plan.py pairs the i-th --exit with the i-th --anchor.
    for (const std::string& a : FrameArgs(robot)) args.push_back(a);
    for (const Cable& c : robot.cables) args.push_back(PointArg("anchor", c.p_P_anchor_m));
    std::string title = robot.name + ": " + std::to_string(result.poses.size()) + " poses, criterion " +
                        ToString(design.criterion) + ", " + DescribeCriterion(design.criterion, result.criteria);
    if (design.random_sets > 0) {
      title += " (random median " + DescribeCriterion(design.criterion, result.random_median, false) + ")";
    }
    args.push_back("--title=" + title);
    figure_error = TryPlot(output, options.plot_path, "plot_plan.py", args);
  }
  output.Commit();
  if (options.json) {
    // The summary's content, and the poses as the plan CSV's columns.
    YAML::Node doc = YAML::Load(DesignSummaryYaml(result, design, ctx.command_line));
    YAML::Node plan = YAML::Load(PosePlanJsonYaml(result.poses));
    doc["plan"] = plan;
    std::printf("%s\n", ToJson(doc).c_str());
    if (!figure_error.empty()) throw FigureFailure(figure_error);
    return kExitOk;
  }
  std::printf("designed %zu poses (criterion %s, best of %d starts, %d converged): %s", result.poses.size(),
              ToString(design.criterion), design.starts, result.converged_starts,
              DescribeCriterion(design.criterion, result.criteria).c_str());
  if (design.random_sets > 0) {
    const double factor = Improvement(design.criterion, result.criteria, result.random_median);
    std::printf(", %s", ImprovementText(factor, design.random_sets).c_str());
    if (!(factor > 1.0) && !ctx.quiet) {
      std::fprintf(stderr, "cablecal: warning: %s\n", NoBetterThanRandomWarning(achieved, "--geometry-sigma").c_str());
    }
  }
  std::printf(", %.1f s\n", result.wall_time_s);
  if (result.robustness_lowered()) {
    std::printf("robustness lowered: %s\n", result.robustness_note.c_str());
  } else if (result.robust_sigmas_achieved > 0.0) {
    // Said also when reached in full: a lab reads what the plan holds for on the console.
    std::printf("robustness: %s\n", RobustnessHoldsText(result.robust_sigmas_achieved, design.geometry_sigma_m).c_str());
  }
  if (!figure_error.empty()) {
    throw FigureFailure(figure_error + "; " + options.out_path +
                        (options.summary_path.empty() ? "" : " and " + options.summary_path) + " were written");
  }
  return kExitOk;
}

}  // namespace cablecal::cli
