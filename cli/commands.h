// cli: the `cablecal` command on top of every stage. Each subcommand is a function that
// takes its parsed options and returns an exit code; main.cc parses flags (CLI11) and
// maps errors to exit codes (README, "Exit codes").
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "cli/processes.h"
#include "common/atomic_output.h"
#include "identify/identify.h"
#include "identify/validate.h"  // SkippedReading
#include "model/robot.h"

namespace cablecal::cli {

struct Context {
  std::string command_line;  // for provenance in outputs
  Processes processes;       // MPI ranks (one process without MPI)
  bool quiet = false;        // -q: no progress bars or warnings (main silences stdout itself)
};

// A progress bar on stderr, with the rate and the time left, when stderr is a terminal;
// nullptr (nothing) otherwise. `unit` names what is counted ("trials", "starts").
std::function<void(long, long)> ProgressBar(const std::string& label, const std::string& unit);
// design's line when the requested robustness gave no plan and the search tries k (either kind).
std::function<void(double)> TryingRobustnessNotice(double requested_k);

// The name in `names` closest to `typed` by edit distance, if within 2 edits (or a third of
// its length); empty otherwise. For "did you mean".
std::string Closest(const std::string& typed, const std::vector<std::string>& names);

// The robot of --robot FILE, or the built-in one when the path is empty.
Robot LoadRobotOption(const std::string& robot_path);

struct WorkspaceOptions {
  std::string robot_path, out_path, plot_path;
  double step_m = -1.0;  // < 0: not given (planar 0.05 m, spatial DefaultSpatialStep)
  std::string rpy_deg;  // spatial robots: --rpy-deg R,P,Y (empty: home's orientation)
};
int RunWorkspace(const Context& ctx, const WorkspaceOptions& options);

struct SampleOptions {
  std::string robot_path, out_path;
  int poses = 0;
  unsigned long long seed = 1;
  double yaw_range_deg = -1.0;  // spatial robots: --yaw-range-deg (< 0: not given, the default)
};
int RunSample(const Context& ctx, const SampleOptions& options);

struct SimulateOptions {
  std::string robot_path, truth_path, plan_path, out_path, truth_out_path;
  double geometry_sigma_m = -1.0;  // < 0: not given
  unsigned long long seed = 1;
  std::string sensors = "both";
  bool no_encoder_noise = false;
  bool systematic_errors = false;  // add the robot file's systematic sensor errors
  bool skip_infeasible = false;    // skip the poses the true robot cannot hold (listed on stderr)
};
int RunSimulate(const Context& ctx, const SimulateOptions& options);

// The same three commands for a robot file with `kind: spatial` (cli/spatial_commands.cc):
// RunWorkspace, RunSample and RunSimulate hand such a file over to them.
bool IsSpatialRobotFile(const std::string& robot_path);
int RunSpatialWorkspace(const Context& ctx, const WorkspaceOptions& options);
int RunSpatialSample(const Context& ctx, const SampleOptions& options);
int RunSpatialSimulate(const Context& ctx, const SimulateOptions& options);
// Refuses a spatial-only flag given for a planar robot.
void RefuseSpatialOnlyFlag(bool given, const std::string& flag);

struct IdentifyCommandOptions {
  std::string robot_path, measurements_path, out_path, calibrated_robot_path;
  std::string estimator = "ml", gauge = "a1x";
  int max_iterations = 100;
  bool json = false;  // the result on stdout as JSON (then --out is optional)
  std::string delimiter = ",";  // of the measurement CSV
  std::string loss = "none";     // ParseLoss
  std::string equilibrium = cablecal::kDefaultEquilibrium ? "on" : "off";  // the 2-cable equilibrium rows
  std::string report_dir;        // --report: the calibration report's folder (identify/calibration_report.h)
  std::string holdout_path;      // --holdout: held-out readings the report validates the calibration on
  std::string identify;          // --identify (spatial robots: exits or anchors, ParseSpatialIdentify); "" not given
  std::string plan_path;         // --plan (spatial robots): the experiment's pose plan, each pose's start; "" none
  double geometry_prior_sigma_m = 0.0;  // --geometry-prior, when geometry_prior_given
  bool geometry_prior_given = false;    // (given as 0 it is refused, not taken for none)
  // Whether given: a spatial robot's defaults differ (gauge auto, the library's iteration limit,
  // the statics on).
  bool gauge_given = false, max_iterations_given = false, equilibrium_given = false;
};
int RunIdentify(const Context& ctx, const IdentifyCommandOptions& options);

struct ValidateCommandOptions {
  std::string robot_path, nominal_path, measurements_path, out_path, summary_path;
  std::string delimiter = ",";  // of the measurement CSV
  bool json = false;  // the summary and the per-pose rows on stdout as JSON (then --out is optional)
  bool skip_infeasible = false;  // skip the readings a robot cannot hold (listed on stderr and in the summary)
};
int RunValidate(const Context& ctx, const ValidateCommandOptions& options);
// validate's outputs, both kinds: the CSV and summary written as one set, the skipped readings
// named on stderr, and with --json the summary and rows printed (true: nothing else to print).
bool WriteValidationOutputs(const Context& ctx, const ValidateCommandOptions& options, const std::string& csv,
                            const std::string& summary_yaml, const std::string& rows_json,
                            const std::vector<SkippedReading>& skipped, std::size_t readings);
// "12 poses", or "14 readings (12 poses)" when poses were read more than once.
std::string CountedReadings(std::size_t kept, int num_poses);
// "7 poses", "1 pose": a count and its noun, plural but for one.
std::string Counted(std::size_t n, const std::string& noun);
// validate's console line of nominal / calibrated RMS ratios, (name, ratio) each, and what they
// say: "  nominal / calibrated rms: z 2.1, theta 0.8 (above 1: the calibrated robot predicts
// better; not for theta, where it predicts no better than the nominal one)".
std::string RatioLine(const std::vector<std::pair<std::string, double>>& ratios, bool warned);
// simulate's ", K of N skipped" with --skip-infeasible, the reason said when K > 0; "" without.
std::string SkippedPosesText(bool skip_infeasible, std::size_t skipped, std::size_t planned);

// identify and validate for a robot file with `kind: spatial` (cli/spatial_identify_command.cc):
// RunIdentify and RunValidate hand such a file over to them.
int RunSpatialIdentify(const Context& ctx, const IdentifyCommandOptions& options);
int RunSpatialValidate(const Context& ctx, const ValidateCommandOptions& options);

struct SensorsFitOptions {
  std::string robot_path, inclinometer_path, laser_path, out_path;
  std::string robot_out_path;  // --robot-out: the robot file with the fitted sensors block
  std::string delimiter = ",";  // of the bench CSVs
};
int RunSensorsFit(const Context& ctx, const SensorsFitOptions& options);

struct DesignCommandOptions {
  std::string robot_path, out_path, summary_path, plot_path;
  int poses = 0, starts = 8, random_sets = 100;
  std::string criterion = "a";  // DesignOptions' default
  unsigned long long seed = 1;
  double min_spacing_m = 0.0;
  double geometry_sigma_m = 0.01, robust_sigmas = 3.0;
  bool geometry_sigma_given = false, robust_sigmas_given = false;  // typed (spatial: unset takes the file's tracker sigma)
  std::string prior_path;
  bool json = false;  // the summary and the poses on stdout as JSON (then --out is optional)
};
int RunDesign(const Context& ctx, const DesignCommandOptions& options);
// design for a robot file with `kind: spatial` (cli/spatial_commands.cc): RunDesign hands it over.
int RunSpatialDesign(const Context& ctx, const DesignCommandOptions& options);

struct MonteCarloCommandOptions {
  std::string robot_path, poses, designs = "random,optimized", estimator = "ml", gauge = "a1x", sensors = "both",
                          out_dir, loss = "none", outliers = "0";
  std::string equilibrium = cablecal::kDefaultEquilibrium ? "on" : "off";
  int trials = 0, threads = 0, design_starts = 2;
  double geometry_sigma_m = 0.01;
  double com_error_m = 0.0;  // the true robot's centre of mass off the file's along the platform's x
  unsigned long long seed = 1;
  bool plot = true;
  bool geometry_prior = false;  // --geometry-prior: identify every trial with geometry_sigma_m as a prior
  bool skip_infeasible = false;  // spatial robots: each trial skips the poses its true robot cannot hold
  bool exact_platform = false;   // spatial robots: SpatialMonteCarloOptions::exact_platform
  double tension_margin_N = 0.0;  // spatial robots: SpatialMonteCarloOptions::plan_tension_margin_N
  double frame_margin_m = 0.0;    // spatial robots: SpatialMonteCarloOptions::plan_margin_m
  double tilt_margin_deg = 0.0;   // spatial robots: SpatialMonteCarloOptions::plan_tilt_margin_rad, in degrees
  int random_pool = 0;            // spatial robots: SpatialMonteCarloOptions::random_pool
};
int RunMonteCarloCommand(const Context& ctx, const MonteCarloCommandOptions& options);

struct ReproduceOptions {
  std::string robot_path, out_dir = "results";
  std::string study = "paper";  // "paper" (the planar study) or "spatial" (README, "The spatial study")
  int trials = 500, threads = 0;
  unsigned long long seed = 2022;
  // Spatial study, for tests: only the first `pose_counts` of each configuration's pose counts
  // (0: all) and the designs run (default: random, optimized, grid:2x2x2, grid:3x3x3).
  int pose_counts = 0;
  std::string designs;
  bool plot = true;
};
int RunReproduce(const Context& ctx, const ReproduceOptions& options);

// Runs a plotting script of scripts/ with the python that has matplotlib. Throws
// FigureFailure (exit 5) if the script fails, Interrupted if Ctrl-C came while it ran.
// A figure's path must end in .png (InputError naming the flag otherwise).
void CheckPngPath(const std::string& flag, const std::string& path);

void RunPlotScript(const std::string& script, const std::vector<std::string>& args);

// Runs RunPlotScript; if it fails, drops `figure_path` from `output`, removes an earlier file
// there (it would show another run beside the new data) and returns the message (the caller
// commits the rest, then throws FigureFailure: results are never lost for a figure).
std::string TryPlot(AtomicOutput& output, const std::string& figure_path, const std::string& script,
                    const std::vector<std::string>& args);

}  // namespace cablecal::cli
