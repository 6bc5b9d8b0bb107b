// The calibration report of a spatial robot: its data files and report.md.
#include "identify/spatial_calibration_report.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>

#include "common/format.h"
#include "common/version.h"
#include "identify/spatial_report.h"
#include "model/spatial_sensor_model.h"

namespace cablecal {
namespace {

constexpr const char* kExitsFigure = "exits.png";
constexpr const char* kResidualsFigure = "residuals.png";
// How many of the largest residuals and changes report.md lists (the files hold all).
constexpr std::size_t kListed = 5;

Eigen::VectorXd NominalOf(const SpatialRobot& nominal, const SpatialIdentifyResult& r) {
  const auto has = [&r](const char* name) { return std::find(r.names.begin(), r.names.end(), name) != r.names.end(); };
  return NominalSpatialGeometry(nominal, has("sw10"), has("yaw0"), has("b1x"), has("mass"));
}

bool Held(const SpatialIdentifyResult& r, const std::string& name) {
  return std::find(r.held.begin(), r.held.end(), name) != r.held.end();
}

bool HasCovariance(const SpatialIdentifyResult& r) {
  return r.covariance.rows() == r.geometry.size() && r.geometry.size() > 0;
}

std::string ParametersCsv(const SpatialRobot& nominal, const SpatialIdentifyResult& r, const std::string& provenance) {
  const Eigen::VectorXd g0 = NominalOf(nominal, r);
  std::ostringstream o;
  o << provenance << "parameter,unit,nominal,identified,std,change,change_sigmas,held\n";
  for (std::size_t k = 0; k < r.names.size(); ++k) {
    const int i = static_cast<int>(k);
    const double change = r.geometry(i) - g0(i);
    const bool has_std = HasCovariance(r) && r.sigma(i) > 0.0;
    o << r.names[k] << "," << SpatialGeometryUnit(r.names[k]) << "," << FormatDouble(g0(i)) << ","
      << FormatDouble(r.geometry(i)) << "," << (HasCovariance(r) ? FormatDouble(r.sigma(i)) : "") << ","
      << FormatDouble(change) << "," << (has_std ? FormatDouble(change / r.sigma(i)) : "") << ","
      << (Held(r, r.names[k]) ? 1 : 0) << "\n";
  }
  return o.str();
}

// Per cable: nominal and identified exit point, its 3 x 3 covariance (upper triangle), and how
// many of its coordinates the gauge held.
std::string ExitsCsv(const SpatialRobot& nominal, const SpatialIdentifyResult& r, const std::string& provenance) {
  std::ostringstream o;
  o << provenance
    << "cable,nominal_x_m,nominal_y_m,nominal_z_m,x_m,y_m,z_m,cov_xx,cov_xy,cov_xz,cov_yy,cov_yz,cov_zz,held\n";
  for (int i = 0; i < nominal.num_cables(); ++i) {
    const Eigen::Vector3d& a0 = nominal.cables[i].p_F_exit_m;
    o << i + 1 << "," << FormatDouble(a0.x()) << "," << FormatDouble(a0.y()) << "," << FormatDouble(a0.z());
    for (int c = 0; c < 3; ++c) o << "," << FormatDouble(r.geometry(3 * i + c));
    for (int a = 0; a < 3; ++a) {
      for (int b = a; b < 3; ++b) o << "," << (HasCovariance(r) ? FormatDouble(r.covariance(3 * i + a, 3 * i + b)) : "");
    }
    int held = 0;
    for (const char c : {'x', 'y', 'z'}) held += Held(r, "a" + std::to_string(i + 1) + c) ? 1 : 0;
    o << "," << held << "\n";
  }
  return o.str();
}

struct Residual {
  std::size_t reading = 0;
  int pose_id = 0;
  std::string sensor;
  double sigmas = 0.0;
};

std::vector<Residual> Residuals(const SpatialIdentifyResult& r, int m) {
  std::vector<Residual> out;
  for (std::size_t k = 0; k < r.fits.size(); ++k) {
    const SpatialReadingFit& f = r.fits[k];
    for (int i = 0; i < f.encoders.size(); ++i) out.push_back({k + 1, f.pose_id, "encoder" + std::to_string(i + 1), f.encoders(i)});
    for (const SpatialSensor s : kSpatialSensors) {
      const Eigen::VectorXd& v = f.sensors[static_cast<int>(s)];
      const std::vector<std::string> columns = SpatialSensorColumns(s, m);
      for (int i = 0; i < v.size(); ++i) out.push_back({k + 1, f.pose_id, std::string(ToString(s)) + " " + columns[i], v(i)});
    }
    for (int i = 0; i < f.equilibrium.size(); ++i) {
      out.push_back({k + 1, f.pose_id, std::string("equilibrium ") + (i < 3 ? "force " : "moment ") + "xyz"[i % 3],
                     f.equilibrium(i)});
    }
  }
  return out;
}

// The same columns as the planar report's residuals.csv, so that one plotting function draws
// both; with a robust loss the readings beyond kOutlierSigmas are marked down-weighted (the
// library reports no weights: the planar rule, the loss's own scale aside).
std::string ResidualsCsv(const SpatialIdentifyResult& r, int m, bool robust, const std::string& provenance) {
  std::ostringstream o;
  o << provenance << "reading,pose,sensor,residual_sigmas,weight,down_weighted\n";
  for (const Residual& s : Residuals(r, m)) {
    const bool down = robust && s.sensor.rfind("equilibrium", 0) != 0 && !(std::abs(s.sigmas) <= kOutlierSigmas);
    o << s.reading << "," << s.pose_id << "," << s.sensor << "," << FormatDouble(s.sigmas) << ",1," << (down ? 1 : 0)
      << "\n";
  }
  return o.str();
}

std::string Fixed6(double v) {
  char text[64];
  std::snprintf(text, sizeof text, "%.6f", v);
  return text;
}

// Millimetres, milliradians or newtons, 3 significant digits.
std::string Scaled(SpatialSensor s, double v) {
  if (s == SpatialSensor::kLoadCell) return Rounded(v);
  return Rounded(1e3 * v);
}
const char* ScaledUnit(SpatialSensor s) {
  if (s == SpatialSensor::kLoadCell) return "N";
  return s == SpatialSensor::kLaser || s == SpatialSensor::kPosition ? "mm" : "mrad";
}

std::string ValidationSection(const SpatialValidationResult& v, const ReportSources& sources) {
  std::ostringstream o;
  o << "## Validation on held-out poses\n\n";
  o << "The readings of " << MarkdownCode(sources.holdout) << " (" << v.num_poses << " poses";
  if (v.pose_ids.size() != static_cast<std::size_t>(v.num_poses)) o << ", " << v.pose_ids.size() << " readings";
  o << "), which the identification did not see, predicted by each robot's forward model (where its commanded "
       "lengths hold the platform) and compared with every sensor they have; error = predicted − measured.\n\n";
  o << "| sensor | noise σ | calibrated RMS | calibrated max | nominal RMS | nominal max | nominal / calibrated |\n"
       "|---|---:|---:|---:|---:|---:|---:|\n";
  for (const SpatialSensor s : kSpatialSensors) {
    const int i = static_cast<int>(s);
    if (!v.compared[i]) continue;
    o << "| " << ToString(s) << " (" << ScaledUnit(s) << ") | "
      << (std::isfinite(v.sigma[i]) ? Scaled(s, v.sigma[i]) : std::string("")) << " |";
    for (const SpatialRobotPrediction& p : v.robots) {
      o << " " << Scaled(s, p.summary[i]->rms) << " | " << Scaled(s, p.summary[i]->max_abs) << " |";
    }
    o << " " << Rounded(SpatialRmsRatio(v, s)) << " |\n";
  }
  o << "\n";
  for (const std::string& w : v.warnings) o << "**Warning:** " << PrintableText(w) << ".\n\n";
  if (!SpatialNotCompared(v).empty()) o << "Not compared: the held-out readings have " << SpatialNotCompared(v) << ".\n\n";
  o << "Per reading: `validation.csv`; the summary: `validation.yaml`.\n\n";
  return o.str();
}

// Long (~90 lines) for a reason: report.md's sections in their order, written once.
std::string Markdown(const SpatialRobot& nominal, const SpatialIdentifyOptions& options, const SpatialIdentifyResult& r,
                     const SpatialValidationResult* validation, const ReportSources& sources,
                     const std::string& figure_error) {
  std::ostringstream o;
  o << "# Calibration report: " << MarkdownEscaped(nominal.name) << "\n\n";
  o << (options.anchors ? "The exit points, initial lengths and platform anchors of " : "The exit points and initial lengths of ")
    << MarkdownEscaped(nominal.name) << " (spatial robot, "
    << nominal.num_cables() << " cables; nominal robot: " << MarkdownCode(nominal.source) << ") identified from "
    << r.poses.size() << " poses";
  if (r.fits.size() != r.poses.size()) o << " (" << r.fits.size() << " readings)";
  o << " of " << MarkdownCode(sources.measurements) << ": estimator `ml`, gauge `" << ToString(options.gauge)
    << "`, loss `" << ToString(options.loss) << "`, statics " << (options.statics ? "on" : "off") << "; "
    << ToString(r.status) << " after " << r.iterations << " iterations.";
  const std::vector<std::string> missing = MissingSpatialSensors(nominal, r);
  if (!missing.empty()) o << " The robot file's " << QuotedList(missing) << " had no columns in the data: not read.";
  o << "\n\nUnits: positions and lengths in m, their standard deviations (σ) and changes in mm; angles in rad, their σ "
       "in mrad. Every number comes from the files beside this one, which hold all digits: `result.yaml`, "
       "`parameters.csv`, `exits.csv`, `residuals.csv`"
    << (validation ? ", `validation.csv` and `validation.yaml`" : "") << ".\n\n";
  if (!figure_error.empty()) o << "**The figures could not be made:** " << PrintableText(figure_error) << "\n\n";

  o << "## The gauge\n\n";
  if (r.null_directions.empty()) {
    o << "The readings see every direction of the geometry: nothing is held.\n\n";
  } else {
    o << "The readings do not see " << r.null_directions.size() << " direction(s) of the geometry (at the nominal "
      << "geometry, before holding anything):\n\n";
    for (const SpatialDirection& d : r.null_directions) o << "- " << PrintableText(d.description) << "\n";
    o << "\n";
  }
  if (!r.held.empty()) {
    o << "Held at their nominal values: ";
    for (std::size_t k = 0; k < r.held.size(); ++k) o << (k ? ", " : "") << "`" << r.held[k] << "`";
    o << ".\n\n";
  }
  if (!r.weak_directions.empty()) {
    o << "Weakly seen (below " << FormatDouble(kSpatialWeakThreshold) << " of the best-seen direction):\n\n";
    for (const SpatialDirection& d : r.weak_directions) {
      o << "- " << PrintableText(d.description) << " (relative singular value " << Rounded(d.relative_singular_value)
        << ")\n";
    }
    o << "\n";
  }

  o << "## Estimates\n\n";
  o << MarkdownFigure(kExitsFigure, "Exit points, nominal and identified, top and side views with 1-σ ellipses",
                      figure_error);
  // σ and the change in the thousandth of each parameter's unit, named in each cell: mm, mrad,
  // and g for the platform's mass.
  o << "| parameter | nominal | identified | σ | identified − nominal | (σ) |\n"
       "|---|---:|---:|---:|---:|---:|\n";
  const Eigen::VectorXd g0 = NominalOf(nominal, r);
  std::vector<std::pair<double, std::string>> notable;
  for (std::size_t k = 0; k < r.names.size(); ++k) {
    const int i = static_cast<int>(k);
    const std::string unit = SpatialGeometryUnit(r.names[k]);
    const double change = r.geometry(i) - g0(i);
    const std::string milli = unit == "m" ? " mm" : unit == "rad" ? " mrad" : unit == "kg" ? " g" : " m" + unit;
    o << "| " << r.names[k] << " | " << Fixed6(g0(i)) << " " << unit << " | " << Fixed6(r.geometry(i))
      << " " << unit << " | ";
    if (Held(r, r.names[k])) {
      o << "held | " << Rounded(1e3 * change) << milli << " | |\n";
    } else if (HasCovariance(r) && r.sigma(i) > 0.0) {
      o << Rounded(1e3 * r.sigma(i)) << milli << " | " << Rounded(1e3 * change) << milli << " | "
        << Rounded(change / r.sigma(i)) << " |\n";
      if (std::abs(change / r.sigma(i)) > 3.0) notable.push_back({std::abs(change / r.sigma(i)), r.names[k]});
    } else {
      o << " | " << Rounded(1e3 * change) << milli << " | |\n";
    }
  }
  o << "\n";
  if (!notable.empty()) {
    std::sort(notable.rbegin(), notable.rend());
    o << "Changed from nominal by more than 3 σ (the nominal file was off there):";
    for (std::size_t k = 0; k < std::min(kListed, notable.size()); ++k) {
      o << (k ? "," : "") << " `" << notable[k].second << "` (" << Rounded(notable[k].first) << " σ)";
    }
    o << ".\n\n";
  }

  o << "## Residuals\n\n";
  o << MarkdownFigure(kResidualsFigure, "Whitened residuals per pose and sensor", figure_error);
  o << "Residual RMS:";
  bool first = true;
  for (const auto& [key, value] : SpatialResidualRms(nominal, r)) {
    o << (first ? " " : ", ") << "`" << key << "` " << Rounded(value);
    first = false;
  }
  o << ". The worst reading: pose " << r.worst_pose_id << " (" << MarkdownCode(r.worst_where) << "), "
    << PrintableText(r.worst_sensor) << ", " << Rounded(r.worst_residual) << " σ.\n\n";
  std::vector<Residual> all = Residuals(r, nominal.num_cables());
  std::sort(all.begin(), all.end(), [](const Residual& a, const Residual& b) { return std::abs(a.sigmas) > std::abs(b.sigmas); });
  o << "| reading | pose | sensor | residual (σ) |\n|---:|---:|---|---:|\n";
  for (std::size_t k = 0; k < std::min(kListed, all.size()); ++k) {
    o << "| " << all[k].reading << " | " << all[k].pose_id << " | " << all[k].sensor << " | " << Rounded(all[k].sigmas)
      << " |\n";
  }
  o << "\n## Warnings\n\n";
  if (r.warnings.empty()) o << "None.\n";
  for (const std::string& w : r.warnings) o << "- " << PrintableText(w) << "\n";
  o << "\n";
  if (validation) o << ValidationSection(*validation, sources);
  o << ReportProvenanceSection(sources);
  return o.str();
}

}  // namespace

const std::vector<std::string>& SpatialReportFileNames() {
  static const std::vector<std::string> names = {"report.md",      "result.yaml",     "parameters.csv", "exits.csv",
                                                 "residuals.csv",  "validation.csv",  "validation.yaml", kExitsFigure,
                                                 kResidualsFigure};
  return names;
}

std::vector<ReportFile> SpatialReportDataFiles(const SpatialRobot& nominal, const SpatialIdentifyOptions& options,
                                               const SpatialIdentifyResult& result, const std::string& result_yaml,
                                               const SpatialValidationResult* validation, const ReportSources& sources) {
  const std::string provenance = ProvenanceComment(sources.command_line);
  const bool robust = options.loss.kind != LossKind::kNone;
  std::vector<ReportFile> files = {{"result.yaml", result_yaml},
                                   {"parameters.csv", ParametersCsv(nominal, result, provenance)},
                                   {"exits.csv", ExitsCsv(nominal, result, provenance)},
                                   {"residuals.csv", ResidualsCsv(result, nominal.num_cables(), robust, provenance)}};
  if (validation) {
    files.push_back({"validation.csv", SpatialValidationCsv(*validation, provenance)});
    files.push_back({"validation.yaml", SpatialValidationSummaryYaml(*validation, sources.command_line)});
  }
  return files;
}

std::string SpatialReportMarkdown(const SpatialRobot& nominal, const SpatialIdentifyOptions& options,
                                  const SpatialIdentifyResult& result, const SpatialValidationResult* validation,
                                  const ReportSources& sources, const std::string& figure_error) {
  return Markdown(nominal, options, result, validation, sources, figure_error);
}

std::string StageSpatialReport(const OutputFolder& folder, const SpatialRobot& nominal,
                               const SpatialIdentifyOptions& options, const SpatialIdentifyResult& result,
                               const std::string& result_yaml, const SpatialValidationResult* validation,
                               const ReportSources& sources, const DrawReportFigures& draw) {
  for (const ReportFile& f : SpatialReportDataFiles(nominal, options, result, result_yaml, validation, sources)) {
    folder.WriteText(f.name, f.content);
  }
  const std::vector<std::string> figures = {kExitsFigure, kResidualsFigure};
  const auto v3 = [](const std::string& flag, const Eigen::Vector3d& v) {
    return "--" + flag + "=" + FormatDouble(v.x()) + "," + FormatDouble(v.y()) + "," + FormatDouble(v.z());
  };
  const std::vector<std::string> arguments = {folder.staging(), "--title=" + PrintableText(nominal.name),
                                              v3("frame-min", nominal.p_F_frame_min_m),
                                              v3("frame-max", nominal.p_F_frame_max_m), v3("home", nominal.p_F_home_m)};
  std::string figure_error = draw(arguments);
  for (const std::string& f : figures) {
    if (figure_error.empty() && !std::filesystem::exists(folder.Path(f))) figure_error = "the plotting script made no " + f;
  }
  if (!figure_error.empty()) {
    for (const std::string& f : figures) std::filesystem::remove(folder.Path(f));
  }
  folder.WriteText("report.md", Markdown(nominal, options, result, validation, sources, figure_error));
  return figure_error;
}

}  // namespace cablecal
