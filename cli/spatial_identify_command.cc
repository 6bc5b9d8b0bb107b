// identify and validate for a robot file with `kind: spatial` (README, "Spatial robots"): the
// planar commands' flags and outputs where they mean something for a spatial robot, the
// planar-only ones refused by name.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>

#include "cli/commands.h"
#include "cli/sigint.h"
#include "common/atomic_output.h"
#include "common/error.h"
#include "common/format.h"
#include "common/json.h"
#include "common/version.h"
#include "experiment/measurements.h"  // ParseDelimiter, ReusedPoseIdWarning
#include "experiment/spatial_measurements.h"
#include "experiment/spatial_plan.h"
#include "identify/spatial_calibration_report.h"
#include "identify/spatial_identify.h"
#include "identify/spatial_report.h"
#include "identify/spatial_validate.h"
#include "model/spatial_robot.h"

namespace cablecal::cli {

namespace {

void RefusePlanarOnlyFlag(bool given, const std::string& flag, const std::string& why) {
  if (given) throw InputError(flag, "", "serves planar robots only; " + why);
}

// The console's value of a geometry unknown: metres to 0.1 um with the std in mm, radians
// with the std in mrad, the mass in kg with its std in g.
void PrintParameter(const SpatialIdentifyResult& r, int k) {
  const std::string& name = r.names[k];
  const std::string unit = SpatialGeometryUnit(name);
  const char* std_unit = unit == "rad" ? "mrad" : unit == "kg" ? "g" : "mm";
  std::printf("  %s = %.7f %s", name.c_str(), r.geometry(k), unit.c_str());
  if (std::find(r.held.begin(), r.held.end(), name) != r.held.end()) {
    std::printf("  (held: the gauge)");
  } else if (r.sigma.size() == r.geometry.size()) {
    std::printf("  (std %.3g %s)", 1e3 * r.sigma(k), std_unit);
  }
  std::printf("\n");
}

std::string Directions(const std::vector<SpatialDirection>& directions) {
  std::string out;
  for (const SpatialDirection& d : directions) out += (out.empty() ? "" : "; ") + d.description;
  return out;
}

}  // namespace

// Long (~130 lines) for a reason: the command's one sequence (flags, read, identify, write every
// output atomically, print the summary), as the planar RunIdentify.
int RunSpatialIdentify(const Context& ctx, const IdentifyCommandOptions& options) {
  RefusePlanarOnlyFlag(options.estimator == "paper", "--estimator paper",
                       "its Eq. (6) is the planar model's: a spatial robot is identified with ml (the default)");
  RefusePlanarOnlyFlag(options.geometry_prior_given, "--geometry-prior",
                       "for a spatial robot --gauge prior puts the robot file's tracker sigma on every exit coordinate");
  // The report's folder is checked before any work, and no other file may be one it writes.
  std::unique_ptr<OutputFolder> report;
  if (!options.report_dir.empty()) {
    report = std::make_unique<OutputFolder>("--report", options.report_dir, SpatialReportFileNames());
    report->RefuseInputs({{"--robot", options.robot_path},
                          {"--measurements", options.measurements_path},
                          {"--holdout", options.holdout_path},
                          {"--plan", options.plan_path},
                          {"--out", options.out_path},
                          {"--calibrated-robot", options.calibrated_robot_path}});
  }
  const SpatialRobot nominal = LoadSpatialRobotFile(options.robot_path);
  SpatialIdentifyOptions id;
  id.gauge = ParseSpatialGauge(options.gauge_given ? options.gauge : "auto");
  id.loss = ParseLoss(options.loss);
  if (options.max_iterations_given) id.max_iterations = options.max_iterations;
  // The statics (tensions, load cells, equilibrium, stretch) are on unless --equilibrium off.
  id.statics = !options.equilibrium_given || options.equilibrium == "on";
  id.anchors = !options.identify.empty() && ParseSpatialIdentify(options.identify);
  const std::vector<SpatialMeasurement> readings =
      ReadSpatialMeasurementsCsv(options.measurements_path, nominal.num_cables(), ParseDelimiter(options.delimiter));
  // Read before the solve: a bad held-out file is refused before any work.
  const std::vector<SpatialMeasurement> holdout =
      options.holdout_path.empty()
          ? std::vector<SpatialMeasurement>()
          : ReadSpatialMeasurementsCsv(options.holdout_path, nominal.num_cables(), ParseDelimiter(options.delimiter));
  CheckSpatialReadingsPlausible(nominal, readings, options.measurements_path);
  CheckSpatialReadingsPlausible(nominal, holdout, options.holdout_path);
  if (const auto reused = ReusedPoseIdWarning(options.measurements_path, readings)) {
    std::fprintf(stderr, "cablecal: warning: %s\n", reused->c_str());
  }
  // --plan: the commanded poses, each its pose's start. The plan must be this robot's (its
  // poses equilibria of the robot file's statics): another robot's would start the search at
  // poses the readings were not taken at.
  if (!options.plan_path.empty()) {
    std::vector<int> plan_ids;
    const std::vector<SpatialPlanPose> plan = ReadSpatialPlanCsv(options.plan_path, nominal.num_cables(), &plan_ids);
    CheckSpatialPlanMatchesRobot(nominal, plan, options.plan_path);
    id.pose_starts = PoseStartsFromPlan(plan, plan_ids);
  }
  // What the readings as a whole cannot do (too few values, a pose they do not determine, a
  // direction nothing fixes) is named by their file, as the other refusals of the data are.
  const SpatialIdentifyResult result = [&] {
    try {
      return IdentifySpatial(nominal, readings, id);
    } catch (const InputError& e) {
      const std::string file = e.where() == "readings" ? options.measurements_path
                               : e.where() == "plan"   ? options.plan_path
                                                       : std::string();
      if (file.empty()) throw;
      throw InputError(file, e.key(), e.problem());
    }
  }();
  if (result.status == SpatialIdentifyStatus::kRankDeficient || result.status == SpatialIdentifyStatus::kPoorFit) {
    // The data cannot calibrate it, or do not fit it (poor_fit): bad input, as planar. With the
    // statics left out, a robot whose cables stretch is fitted as inextensible: a likely cause,
    // said here (a new user's noise-free readings of a robot with two stretching cables did not
    // fit with --equilibrium off, and the message blamed a laser reading).
    const bool stretch = std::any_of(nominal.cables.begin(), nominal.cables.end(),
                                     [](const SpatialCable& c) { return c.stiffness_N.has_value(); });
    const std::string hint =
        result.status == SpatialIdentifyStatus::kPoorFit && !id.statics && stretch
            ? " (--equilibrium off models every cable as inextensible, and this robot's cables with a stiffness "
              "stretch under load: without it the stretch is modelled)"
            : "";
    throw InputError(options.measurements_path, "", result.message + hint);
  }
  if (!result.converged()) throw SolverFailure(options.measurements_path + ": " + result.message);
  const std::string result_yaml = options.out_path.empty() && options.report_dir.empty()
                                      ? std::string()
                                      : SpatialIdentifyResultYaml(nominal, id, result, ctx.command_line);
  // The held-out readings predicted by the calibrated robot and by the nominal one.
  std::optional<SpatialValidationResult> validation;
  if (!holdout.empty()) {
    SpatialRobot calibrated = CalibratedSpatialRobot(nominal, result);
    calibrated.source = "identified from " + options.measurements_path;  // not the nominal file
    validation = ValidateSpatial(calibrated, nominal, holdout, options.holdout_path);
  }
  AtomicOutput output;
  if (!options.out_path.empty()) output.WriteText(options.out_path, result_yaml);
  std::string calibrated_load_error;
  if (!options.calibrated_robot_path.empty()) {
    const std::string text = ProvenanceComment(ctx.command_line) + "# calibrated: " +
                             (id.anchors ? "exit points, initial lengths and platform anchors"
                                         : "exit points and initial lengths") +
                             " identified (ml, gauge " + ToString(id.gauge) + ")\n" +
                             SpatialRobotToYaml(CalibratedSpatialRobot(nominal, result));
    // The file keeps the nominal home, where the loader settles the identified platform: a home
    // the nominal robot barely holds may be no pose of the identified one (a new user's 4-cable
    // robot holding a yaw band of 0.1 degrees: no_equilibrium; at its identified initial lengths
    // one cable is slack). Written all the same (the identification is sound), but said, so that
    // no later command is the first to find it.
    try {
      LoadSpatialRobotFromString(text, options.calibrated_robot_path);
    } catch (const InputError& e) {
      calibrated_load_error = e.what();
    }
    output.WriteText(options.calibrated_robot_path, text);
  }
  std::string figure_error;
  if (report) {
    const SigintScope sigint;
    const auto draw = [](const std::vector<std::string>& arguments) {
      try {
        RunPlotScript("plot_spatial_report.py", arguments);
        return std::string();
      } catch (const FigureFailure& e) {
        return std::string(e.what());
      }
    };
    const ReportSources sources{ctx.command_line, options.measurements_path, options.holdout_path};
    figure_error = StageSpatialReport(*report, nominal, id, result, result_yaml, validation ? &*validation : nullptr,
                                      sources, draw);
    if (SigintFlag()) throw Interrupted();
  }
  output.Commit();
  if (report) report->Commit();
  if (!calibrated_load_error.empty() && !ctx.quiet) {
    // Its home and initial lengths are the nominal home's (l_i0 is the length there): moving
    // home alone does not mend it, as a new user found; what does depends on the reason.
    const bool bound = calibrated_load_error.find("tension_low") != std::string::npos ||
                       calibrated_load_error.find("tension_high") != std::string::npos;
    std::fprintf(stderr,
                 "cablecal: warning: --calibrated-robot: the file was written but does not load: %s (its home and "
                 "initial lengths are the nominal home's, which the identified robot %s; moving home alone does not "
                 "mend it: its initial_length values are the lengths there)\n",
                 calibrated_load_error.c_str(),
                 bound ? "holds only beyond a tension bound: the nominal home was near the bound; widen tension in the "
                         "written file if the lab accepts it, or identify with a nominal home farther from it"
                       : "cannot hold: identify with a nominal home nearer the middle of the workspace");
  }
  if (!figure_error.empty()) figure_error = ReportWithoutFiguresMessage(options.report_dir, figure_error);
  if (options.json) {
    std::printf("%s\n", SpatialIdentifyResultJson(nominal, id, result, ctx.command_line).c_str());
    if (!figure_error.empty()) throw FigureFailure(figure_error);
    return kExitOk;
  }
  std::printf("identified %s from %zu poses", PrintableText(nominal.name).c_str(), result.poses.size());
  if (result.poses.size() != readings.size()) std::printf(" (%zu readings)", readings.size());
  std::string settings = id.loss.kind == LossKind::kNone ? "" : ", loss " + ToString(id.loss);
  if (id.anchors) settings += ", anchors";
  if (!result.tensions_N.empty()) settings += ", statics";
  std::printf(" (ml, gauge %s%s): %d iterations, residual rms", ToString(id.gauge).c_str(), settings.c_str(),
              result.iterations);
  bool first = true;
  for (const auto& [key, value] : SpatialResidualRms(nominal, result)) {
    const std::string::size_type cut = key.rfind('_');
    std::printf("%s %s %.3g %s", first ? "" : ",", key.substr(0, cut).c_str(), value, key.substr(cut + 1).c_str());
    first = false;
  }
  std::printf("\n");
  if (!result.null_directions.empty()) {
    std::printf("  unseen by the readings (%zu): %s\n", result.null_directions.size(),
                Directions(result.null_directions).c_str());
  }
  if (!result.held.empty()) {
    std::string held;
    for (const std::string& h : result.held) held += (held.empty() ? "" : ", ") + h;
    const bool weak_held = id.gauge.kind == SpatialGaugeKind::kAuto &&
                           std::any_of(result.weak_directions.begin(), result.weak_directions.end(),
                                       [](const SpatialDirection& d) { return d.nearly_rigid; });
    std::printf("  held at nominal (the gauge): %s%s\n", held.c_str(),
                weak_held ? " (with the weakly seen direction nearly a rigid motion below)" : "");
  }
  if (!result.weak_directions.empty()) {
    std::printf("  weakly seen (%zu): %s\n", result.weak_directions.size(), Directions(result.weak_directions).c_str());
  }
  const std::vector<std::string> missing = MissingSpatialSensors(nominal, result);
  if (!missing.empty()) {
    std::string list;
    for (const std::string& s : missing) list += (list.empty() ? "" : ", ") + s;
    std::printf("  not in the data (no columns): %s\n", list.c_str());
  }
  std::printf("  worst reading: pose %d (%s), %s, %.3g sigma\n", result.worst_pose_id,
              PrintableText(result.worst_where).c_str(), result.worst_sensor.c_str(), result.worst_residual);
  if (!ctx.quiet) {
    for (const std::string& w : result.warnings) std::fprintf(stderr, "cablecal: warning: %s\n", w.c_str());
    if (validation) {
      for (const std::string& w : validation->warnings) std::fprintf(stderr, "cablecal: warning: --holdout: %s\n", w.c_str());
    }
  }
  for (int k = 0; k < static_cast<int>(result.names.size()); ++k) PrintParameter(result, k);
  if (report) std::printf("  report: %s/report.md\n", options.report_dir.c_str());
  if (!figure_error.empty()) throw FigureFailure(figure_error);
  return kExitOk;
}

int RunSpatialValidate(const Context& ctx, const ValidateCommandOptions& options) {
  const SpatialRobot calibrated = LoadSpatialRobotFile(options.robot_path);
  std::optional<SpatialRobot> nominal;
  if (!options.nominal_path.empty()) {
    if (!IsSpatialRobotFile(options.nominal_path)) {
      throw InputError("--nominal", "", "'" + options.nominal_path + "' is a planar robot file, --robot a spatial one");
    }
    nominal = LoadSpatialRobotFile(options.nominal_path);
  }
  const std::vector<SpatialMeasurement> readings =
      ReadSpatialMeasurementsCsv(options.measurements_path, calibrated.num_cables(), ParseDelimiter(options.delimiter));
  CheckSpatialReadingsPlausible(calibrated, readings, options.measurements_path);
  const SpatialValidationResult result =
      ValidateSpatial(calibrated, nominal, readings, options.measurements_path, options.skip_infeasible);
  const std::string summary_yaml = SpatialValidationSummaryYaml(result, ctx.command_line);
  if (WriteValidationOutputs(ctx, options, SpatialValidationCsv(result, ProvenanceComment(ctx.command_line)),
                             summary_yaml, SpatialValidationRowsJson(result), result.skipped, readings.size())) {
    return kExitOk;
  }
  const std::size_t kept = result.pose_ids.size();
  const std::string counted = CountedReadings(kept, result.num_poses);
  // Millimetres, milliradians and newtons, 3 significant digits; the files keep every digit.
  const auto scaled = [](SpatialSensor s, double v) {
    return s == SpatialSensor::kLoadCell ? Rounded(v) + " N"
                                         : Rounded(1e3 * v) + (s == SpatialSensor::kLaser || s == SpatialSensor::kPosition
                                                                   ? " mm"
                                                                   : " mrad");
  };
  std::string noise;
  for (const SpatialSensor s : kSpatialSensors) {
    const int i = static_cast<int>(s);
    if (result.compared[i] && std::isfinite(result.sigma[i])) {
      noise += (noise.empty() ? "" : ", ") + std::string(ToString(s)) + " " + scaled(s, result.sigma[i]);
    }
  }
  std::printf("validated on %s of %s (error = predicted - measured; sensor noise: %s)\n", counted.c_str(),
              PrintableText(options.measurements_path).c_str(), noise.c_str());
  if (options.skip_infeasible) {
    std::printf("  skipped %zu of %zu readings that a robot cannot hold (listed on stderr and in the summary)\n",
                result.skipped.size(), readings.size());
  }
  for (const SpatialRobotPrediction& p : result.robots) {
    std::string line;
    for (const SpatialSensor s : kSpatialSensors) {
      const std::optional<ErrorSummary>& e = p.summary[static_cast<int>(s)];
      if (!e) continue;
      line += (line.empty() ? "" : ", ") + std::string(ToString(s)) + " rms " + scaled(s, e->rms) + " (max " +
              scaled(s, e->max_abs) + ")";
    }
    std::printf("  %-10s %s  [%s]\n", p.name.c_str(), line.c_str(), PrintableText(p.source).c_str());
  }
  if (nominal) {
    std::vector<std::pair<std::string, double>> ratios;
    for (const SpatialSensor s : kSpatialSensors) {
      if (result.compared[static_cast<int>(s)]) ratios.emplace_back(ToString(s), SpatialRmsRatio(result, s));
    }
    std::printf("%s\n", RatioLine(ratios, !result.warnings.empty()).c_str());
  }
  if (!SpatialNotCompared(result).empty()) std::printf("  not compared: %s\n", SpatialNotCompared(result).c_str());
  if (!ctx.quiet) {
    for (const std::string& w : result.warnings) std::fprintf(stderr, "cablecal: warning: %s\n", w.c_str());
  }
  return kExitOk;
}

}  // namespace cablecal::cli
