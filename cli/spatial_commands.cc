// workspace, sample, simulate and design for a robot file with `kind: spatial` (README, "Spatial
// robots"): the same flags and outputs as the planar commands, in the spatial formats.
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <optional>
#include <sstream>

#include <yaml-cpp/yaml.h>

#include "cli/commands.h"
#include "cli/sigint.h"
#include "common/atomic_output.h"
#include "common/error.h"
#include "common/format.h"
#include "common/json.h"
#include "common/version.h"
#include "common/yaml_writer.h"
#include "design/design.h"  // kMaxGeometrySigma_m
#include "design/spatial_design.h"
#include "experiment/plan.h"  // PlanJsonYaml
#include "experiment/spatial_plan.h"
#include "experiment/spatial_simulation.h"
#include "model/spatial_robot.h"
#include "workspace/spatial_workspace.h"

namespace cablecal::cli {

namespace {

constexpr double kDegPerRad = 180.0 / M_PI;

std::string TripleArg(const std::string& flag, const Eigen::Vector3d& v) {
  return "--" + flag + "=" + FormatDouble(v.x()) + "," + FormatDouble(v.y()) + "," + FormatDouble(v.z());
}

// --rpy-deg R,P,Y: three finite numbers of degrees, roll and pitch within +-90, yaw within +-180.
Eigen::Vector3d ParseRpyDeg(const std::string& text) {
  std::vector<std::string> parts;
  std::stringstream in(text);
  for (std::string part; std::getline(in, part, ',');) parts.push_back(part);
  Eigen::Vector3d rpy_deg;
  const bool ok = parts.size() == 3 && ParseFiniteDouble(parts[0], &rpy_deg(0)) &&
                  ParseFiniteDouble(parts[1], &rpy_deg(1)) && ParseFiniteDouble(parts[2], &rpy_deg(2));
  if (!ok || text.back() == ',') {
    throw InputError("--rpy-deg", "", "must be three numbers R,P,Y: roll, pitch and yaw in degrees, e.g. 0,5,-10 (got '" +
                                          PrintableText(text) + "')");
  }
  return WorkspaceOrientation(rpy_deg);
}

std::string DegreesText(const Eigen::Vector3d& rpy_rad) {
  return "roll " + Rounded(rpy_rad(0) * kDegPerRad) + ", pitch " + Rounded(rpy_rad(1) * kDegPerRad) + ", yaw " +
         Rounded(rpy_rad(2) * kDegPerRad) + " deg";
}


}  // namespace

bool IsSpatialRobotFile(const std::string& robot_path) {
  return !robot_path.empty() && RobotKindOfFile(robot_path) == RobotKind::kSpatial;
}

void RefuseSpatialOnlyFlag(bool given, const std::string& flag) {
  if (given) throw InputError(flag, "", "serves spatial robots only (a robot file with kind: spatial)");
}

int RunSpatialWorkspace(const Context& ctx, const WorkspaceOptions& options) {
  const SpatialRobot robot = LoadSpatialRobotFile(options.robot_path);
  const Eigen::Vector3d rpy_rad = options.rpy_deg.empty() ? robot.home_rpy_rad : ParseRpyDeg(options.rpy_deg);
  const double step_m = options.step_m < 0.0 ? DefaultSpatialStep(robot) : options.step_m;
  const SpatialWorkspaceGrid grid = ComputeSpatialWorkspace(robot, rpy_rad, step_m);
  AtomicOutput output;
  std::string figure_error;
  const std::string temp_csv =
      output.WriteText(options.out_path, SpatialWorkspaceCsv(robot, grid, ProvenanceComment(ctx.command_line)));
  if (!options.plot_path.empty()) {
    std::vector<std::string> args = {temp_csv, output.Add(options.plot_path), TripleArg("frame-min", robot.p_F_frame_min_m),
                                     TripleArg("frame-max", robot.p_F_frame_max_m), TripleArg("home", robot.p_F_home_m)};
    for (const SpatialCable& c : robot.cables) args.push_back(TripleArg("exit", c.p_F_exit_m));
    const int m = robot.num_cables();
    const std::string orientation =
        m >= 6 ? DegreesText(rpy_rad)
               : (m >= 4 ? "yaw " + Rounded(rpy_rad(2) * kDegPerRad) + " deg, roll and pitch"
                         : "roll, pitch and yaw") +
                     std::string(" from each point's equilibrium (") + std::to_string(m) + " cables)";
    args.push_back("--title=" + robot.name + ", constant orientation: " + orientation + "; step " +
                   FormatDouble(step_m) + " m");
    figure_error = TryPlot(output, options.plot_path, "plot_spatial_workspace.py", args);
  }
  output.Commit();
  std::printf("workspace of %s at %s: %d of %zu grid points feasible (step %s m), volume ~ %.4g m^3\n",
              PrintableText(robot.name).c_str(), DegreesText(rpy_rad).c_str(), grid.num_feasible, grid.points.size(),
              FormatDouble(step_m).c_str(), grid.feasible_volume_m3());
  if (robot.num_cables() < 6) {
    std::printf("  %d cables: %s each point's equilibrium (the CSV's orientation columns)\n", robot.num_cables(),
                robot.num_cables() >= 4 ? "roll and pitch follow from" : "the orientation follows from");
  }
  // Not exit 3: the map of why no point is feasible is the answer a lab asked for.
  if (grid.num_feasible == 0 && !ctx.quiet) {
    std::fprintf(stderr, "cablecal: warning: no grid point is feasible at %s: the CSV's reason column says why at "
                 "each; another --rpy-deg (home's is %s) or a finer --step may find some\n",
                 DegreesText(rpy_rad).c_str(), DegreesText(robot.home_rpy_rad).c_str());
  }
  if (!figure_error.empty()) throw FigureFailure(figure_error + "; " + options.out_path + " was written");
  return kExitOk;
}

int RunSpatialSample(const Context& ctx, const SampleOptions& options) {
  const SpatialRobot robot = LoadSpatialRobotFile(options.robot_path);
  const double yaw_range_rad =
      options.yaw_range_deg >= 0.0 ? options.yaw_range_deg / kDegPerRad : kDefaultSampleYawRange_rad;
  const std::vector<SpatialPlanPose> plan = SampleSpatialPoses(robot, options.poses, options.seed, yaw_range_rad);
  AtomicOutput output;
  output.WriteText(options.out_path, SpatialPlanCsv(plan, ProvenanceComment(ctx.command_line)));
  output.Commit();
  std::printf("wrote %zu random feasible poses of %s (seed %llu; tilt within %s deg, yaw within +-%s deg of home's) to %s\n",
              plan.size(), PrintableText(robot.name).c_str(), options.seed, Rounded(robot.tilt_max_rad * kDegPerRad).c_str(),
              Rounded(yaw_range_rad * kDegPerRad).c_str(), options.out_path.c_str());
  return kExitOk;
}

int RunSpatialSimulate(const Context& ctx, const SimulateOptions& options) {
  const SpatialRobot nominal = LoadSpatialRobotFile(options.robot_path);
  if (options.systematic_errors) {
    throw InputError("--systematic-errors", "", "a spatial robot file has no systematic sensor errors to add (" +
                                                    PrintableText(options.robot_path) + ")");
  }
  if (options.geometry_sigma_m > kMaxGeometrySigma_m) {  // as the planar command's
    throw InputError("--geometry-sigma", "", "must be at most " + FormatDouble(kMaxGeometrySigma_m) +
                                                 " m: a larger error is not a calibration problem (got " +
                                                 FormatDouble(options.geometry_sigma_m) + ")");
  }
  if (!options.truth_path.empty() && options.geometry_sigma_m >= 0.0) {
    throw InputError("--truth", "", "give either --truth or --geometry-sigma, not both");
  }
  SpatialSimulationOptions sim;
  sim.noisy = ParseNoisySensors(options.sensors);
  sim.encoder_noise = !options.no_encoder_noise;
  sim.require_feasible = true;
  sim.skip_infeasible = options.skip_infeasible;
  std::optional<SpatialRobot> given_truth;
  if (!options.truth_path.empty()) given_truth = LoadSpatialRobotFile(options.truth_path);
  const std::vector<SpatialPlanPose> plan = ReadSpatialPlanCsv(options.plan_path, nominal.num_cables(), &sim.pose_ids);
  CheckSpatialPlanMatchesRobot(nominal, plan, options.plan_path);
  const SpatialPlanSimulation run = SimulateSpatialPlan(nominal, given_truth, std::max(options.geometry_sigma_m, 0.0),
                                                        plan, sim, options.seed, options.plan_path);
  const SimulatedSpatialExperiment& experiment = run.experiment;
  AtomicOutput output;
  output.WriteText(options.out_path, SpatialMeasurementsCsv(experiment.measurements, ProvenanceComment(ctx.command_line)));
  if (!options.truth_out_path.empty()) {
    output.WriteText(options.truth_out_path,
                     ProvenanceComment(ctx.command_line) + SpatialTruthYaml(run.truth, experiment));
  }
  output.Commit();
  if (!ctx.quiet) {
    for (const SpatialSkippedPose& skipped : experiment.skipped) {
      std::fprintf(stderr, "cablecal: skipped pose %d of %s: %s\n", skipped.pose_id, options.plan_path.c_str(),
                   skipped.reason.c_str());
    }
  }
  std::string sensors;
  for (const SpatialSensor s : kSpatialSensors) {
    if (HasSpatialSensor(nominal, s)) sensors += std::string(sensors.empty() ? "" : ", ") + ToString(s);
  }
  std::printf("simulated %s of %s%s (encoders%s%s; noisy sensors: %s, encoder noise %s) to %s\n",
              Counted(experiment.measurements.size(), "pose").c_str(), PrintableText(nominal.name).c_str(),
              SkippedPosesText(options.skip_infeasible, experiment.skipped.size(), plan.size()).c_str(),
              sensors.empty() ? "" : ", ", sensors.c_str(), ToString(sim.noisy), sim.encoder_noise ? "on" : "off",
              options.out_path.c_str());
  return kExitOk;
}

// The workspace figure is not served for spatial robots yet: its flag is refused, never
// silently ignored. --geometry-sigma not given: the robot file's tracker sigma (its exits'
// survey), else the planar default (SpatialDesignOptions). --prior: the next round is planned
// around the earlier estimate, counting the information gathered (as planar).
int RunSpatialDesign(const Context& ctx, const DesignCommandOptions& options) {
  const std::string not_yet = "is not yet served for spatial robots";
  if (!options.plot_path.empty()) {
    throw InputError("--plot", "", "a figure of a spatial plan " + not_yet + " (the plan CSV has every pose's x, y, z)");
  }
  SpatialRobot robot = LoadSpatialRobotFile(options.robot_path);
  SpatialDesignOptions design;
  if (!options.prior_path.empty()) {
    design.prior = ReadSpatialIdentifiedGeometry(robot, options.prior_path);
    robot = CalibratedSpatialRobot(robot, *design.prior);
  }
  design.poses = options.poses;
  design.criterion = ParseCriterion(options.criterion);
  design.starts = options.starts;
  design.seed = options.seed;
  design.min_spacing_m = options.min_spacing_m;
  design.random_sets = options.random_sets;
  if (options.geometry_sigma_given) design.geometry_sigma_m = options.geometry_sigma_m;
  design.robust_sigmas = options.robust_sigmas;
  const SigintScope sigint;  // Ctrl-C: Ipopt stops at its next iteration, exit 130, nothing written
  design.interrupted = &SigintFlag();
  if (!ctx.quiet) design.progress = ProgressBar("design", "starts");
  if (!ctx.quiet && !options.json) design.trying_robustness = TryingRobustnessNotice(design.robust_sigmas);
  const SpatialDesignResult result = DesignSpatialPoses(robot, design);
  const std::string summary = SpatialDesignSummaryYaml(robot, result, design, ctx.command_line);
  AtomicOutput output;
  if (!options.out_path.empty()) {
    output.WriteText(options.out_path, SpatialPlanCsv(result.poses, ProvenanceComment(ctx.command_line)));
  }
  if (!options.summary_path.empty()) output.WriteText(options.summary_path, summary);
  output.Commit();
  if (options.json) {
    // The summary's content, and the poses as the plan CSV's columns.
    YAML::Node doc = YAML::Load(summary);
    doc["plan"] = YAML::Load(PlanJsonYaml<SpatialKind>(result.poses));
    std::printf("%s\n", ToJson(doc).c_str());
    return kExitOk;
  }
  int verified = 0, made_robust = 0;
  for (const SpatialStartReport& s : result.starts) {
    verified += s.verified ? 1 : 0;
    made_robust += s.made_robust ? 1 : 0;
  }
  // Where starts were left without robust rounds (a pair with lower first-solve criteria held), how many had them.
  const std::string robust_count =
      made_robust < design.starts ? ", " + std::to_string(made_robust) + " made robust" : std::string();
  std::printf("designed %zu poses of %s (criterion %s, best of %d start%s, %d converged, %d verified%s%s): %s",
              result.poses.size(), PrintableText(robot.name).c_str(), ToString(design.criterion), design.starts,
              design.starts == 1 ? "" : "s", result.converged_starts, verified, robust_count.c_str(),
              design.prior ? ", counting the prior's information" : "",
              DescribeCriterion(design.criterion, result.criteria).c_str());
  if (design.random_sets > 0) {
    const double factor = Improvement(design.criterion, result.criteria, result.random_median);
    std::printf(", %s", ImprovementText(factor, design.random_sets).c_str());
    if (!(factor > 1.0) && !ctx.quiet) {
      std::fprintf(stderr, "cablecal: warning: the designed set is no better than the median random set on its "
                           "criterion: try more --starts, or another --seed\n");
    }
  }
  std::printf(", %.1f s\n", result.wall_time_s);
  std::string held;
  for (int h : result.layout.held) held += (held.empty() ? "" : " ") + result.layout.names[h];
  if (held.empty()) held = "nothing (the robot file's sensors see every direction of the geometry)";
  const std::vector<std::string>& weak = result.layout.weakly_seen_held;
  if (!weak.empty()) {
    std::string words;
    for (const std::string& d : weak) words += (words.empty() ? "" : "; ") + d.substr(0, d.find(':'));
    held += " (with the weakly seen direction" + std::string(weak.size() > 1 ? "s " : " ") + words + ")";
  }
  // identify's default gauge holds as many, but the coordinates it picks depend on the readings.
  if (!result.layout.held.empty()) {
    std::string list;
    for (int h : result.layout.held) list += (list.empty() ? "" : ",") + result.layout.names[h];
    held += "; identify with --gauge hold:" + list + " for the covariance it predicts";
  }
  // Where the exits' sigma came from, unless the user gave it.
  std::string sigma_from;
  if (!options.geometry_sigma_given && result.robust_sigmas_achieved * result.geometry_sigma_m > 0.0) {
    sigma_from = robot.sensors.tracker_sigma_m
                     ? " (sigma: the robot file's tracker)"
                     : " (sigma: the default, the robot file gives no sensors.tracker; --geometry-sigma sets it)";
  }
  std::printf("  the gauge holds %s; %s%s\n", held.c_str(), SpatialRobustnessText(robot, result).c_str(),
              sigma_from.c_str());
  if (!result.prior_note.empty() && !ctx.quiet) std::fprintf(stderr, "cablecal: warning: %s\n", result.prior_note.c_str());
  if (!result.redundancy_note.empty() && !ctx.quiet) {
    std::fprintf(stderr, "cablecal: warning: %s\n", result.redundancy_note.c_str());
  }
  if (result.robustness_lowered() && !ctx.quiet) {
    std::fprintf(stderr, "cablecal: warning: robustness lowered: %s\n", result.robustness_note.c_str());
  }
  return kExitOk;
}

}  // namespace cablecal::cli
