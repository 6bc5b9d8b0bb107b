// The calibration report of `identify --report DIR`: its data files and report.md.
#include "identify/calibration_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "common/format.h"
#include "common/version.h"

namespace cablecal {
namespace {

constexpr const char* kEstimatesFigure = "estimates.png";
constexpr const char* kCorrelationFigure = "correlation.png";
constexpr const char* kResidualsFigure = "residuals.png";
constexpr const char* kSingularValuesFigure = "singular_values.png";
constexpr const char* kValidationFigure = "validation.png";

// How many of the largest residuals and correlations report.md lists (the files hold all).
constexpr std::size_t kListed = 5;
// A change from nominal beyond this many sigma is named below the table: the nominal file
// was off there by more than the noise explains.
constexpr double kNotableChangeSigmas = 3.0;

// printf's "%.*f", without the "-0.000" that a tiny negative number rounds to.
std::string Fixed(double value, int decimals) {
  char text[64];
  std::snprintf(text, sizeof text, "%.*f", decimals, value);
  std::string s = text;
  if (s[0] == '-' && s.find_first_not_of("-0.") == std::string::npos) s.erase(0, 1);
  return s;
}

// With a sign: a change reads as one.
std::string SignedFixed(double value, int decimals) {
  const std::string s = Fixed(value, decimals);
  return s[0] == '-' || s.find_first_not_of("0.") == std::string::npos ? s : "+" + s;
}

// "%#.3g": three significant digits, trailing zeros kept (11.0 mm, not 11), for a column.
std::string Significant3(double value) {
  char text[64];
  std::snprintf(text, sizeof text, "%#.3g", value);
  return text;
}

// Inline code in markdown, whatever the text holds (a backtick in a path, a control character).
std::string Code(const std::string& text) {
  const std::string printable = PrintableText(text);
  return printable.find('`') == std::string::npos ? "`" + printable + "`" : "`` " + printable + " ``";
}

// A name in running text: markdown's own characters (a robot called "arm_2 *new*") read as
// typed, not as emphasis or a link.
std::string Escaped(const std::string& text) {
  std::string out;
  for (const char c : PrintableText(text)) {
    if (std::string("\\`*_[]<>|$#").find(c) != std::string::npos) out += '\\';
    out += c;
  }
  return out;
}

// A table cell: a '|' would end it.
std::string Cell(const std::string& text) {
  std::string out;
  for (const char c : PrintableText(text)) out += c == '|' ? std::string("\\|") : std::string(1, c);
  return out;
}

bool Missing(const IdentifyResult& r, const char* sensor) {
  return std::find(r.missing_sensors.begin(), r.missing_sensors.end(), sensor) != r.missing_sensors.end();
}

// One value of one reading, as residuals.csv has it.
struct SensorResidual {
  std::size_t reading = 0;  // 1-based, the data row as result.yaml counts it
  int pose_id = 0;
  std::string sensor;  // "encoder1".., "laser", "inclinometer"
  double sigmas = 0.0, weight = 1.0;
};

std::vector<SensorResidual> SensorResiduals(const IdentifyResult& r) {
  std::vector<SensorResidual> out;
  for (std::size_t k = 0; k < r.readings.size(); ++k) {
    const ReadingFit& f = r.readings[k];
    for (Eigen::Index i = 0; i < f.encoder_sigmas.size(); ++i) {
      out.push_back({k + 1, f.pose_id, "encoder" + std::to_string(i + 1), f.encoder_sigmas(i), f.encoder_weights(i)});
    }
    for (const SensorUnit& u : kPlanarSensors) {
      const int id = static_cast<int>(u.id);
      if (f.sensor_sigmas[id]) out.push_back({k + 1, f.pose_id, u.name, *f.sensor_sigmas[id], f.sensor_weights[id]});
    }
  }
  return out;
}

// As Identify lists them in down_weighted: beyond kOutlierSigmas, with a robust loss.
bool DownWeighted(const IdentifyResult& r, const SensorResidual& s) {
  return r.loss.kind != LossKind::kNone && !(std::abs(s.sigmas) <= kOutlierSigmas);
}

std::string ParametersCsv(const Robot& nominal, const IdentifyResult& r, const std::string& provenance) {
  const GeometryVector nominal_geometry = GeometryOf(nominal);
  const std::vector<std::string> names = GeometryNames(nominal.num_cables());
  std::ostringstream o;
  o << provenance << "parameter,nominal_m,identified_m,std_m,change_m,change_sigmas,held\n";
  for (std::size_t k = 0; k < names.size(); ++k) {
    const int i = static_cast<int>(k);
    const double change = r.geometry(i) - nominal_geometry(i);
    const bool has_std = r.has_covariance && r.geometry_std(i) > 0.0;
    o << names[k] << "," << FormatDouble(nominal_geometry(i)) << "," << FormatDouble(r.geometry(i)) << ","
      << (r.has_covariance ? FormatDouble(r.geometry_std(i)) : "") << "," << FormatDouble(change) << ","
      << (has_std ? FormatDouble(change / r.geometry_std(i)) : "") << "," << (IsHeld(r, i) ? 1 : 0) << "\n";
  }
  return o.str();
}

std::string CorrelationCsv(const IdentifyResult& r, const std::string& provenance) {
  const std::vector<std::string> names = GeometryNames(static_cast<int>(r.geometry.size() / 3));
  std::ostringstream o;
  o << provenance << "parameter";
  for (const std::string& n : names) o << "," << n;
  o << "\n";
  for (std::size_t a = 0; a < names.size(); ++a) {
    o << names[a];
    for (std::size_t b = 0; b < names.size(); ++b) {
      o << "," << FormatDouble(r.geometry_correlation(static_cast<int>(a), static_cast<int>(b)));
    }
    o << "\n";
  }
  return o.str();
}

std::string SingularValuesCsv(const IdentifyResult& r, const std::string& provenance) {
  std::ostringstream o;
  o << provenance << "index,singular_value\n";
  const Eigen::VectorXd& s = r.identifiability.singular_values;
  for (Eigen::Index k = 0; k < s.size(); ++k) o << k + 1 << "," << FormatDouble(s(k)) << "\n";
  return o.str();
}

std::string ResidualsCsv(const IdentifyResult& r, const std::string& provenance) {
  std::ostringstream o;
  o << provenance << "reading,pose,sensor,residual_sigmas,weight,down_weighted\n";
  for (const SensorResidual& s : SensorResiduals(r)) {
    o << s.reading << "," << s.pose_id << "," << s.sensor << "," << FormatDouble(s.sigmas) << ","
      << FormatDouble(s.weight) << "," << (DownWeighted(r, s) ? 1 : 0) << "\n";
  }
  return o.str();
}

// ---- report.md, a section at a time ----------------------------------------------------------

// A figure, or why it is not there.
std::string Figure(const std::string& file, const std::string& caption, const std::string& figure_error) {
  if (!figure_error.empty()) return "*(" + caption + ": figure not made, see the note at the top)*\n\n";
  return "![" + caption + "](" + file + ")\n\n";
}

std::string Heading(const Robot& nominal, const IdentifyResult& r, const ReportSources& sources,
                    const std::string& figure_error) {
  std::ostringstream o;
  o << "# Calibration report: " << Escaped(nominal.name) << "\n\n";
  const std::size_t readings = r.readings.size(), poses = r.poses.size();
  o << "The exit points and initial lengths of " << Escaped(nominal.name) << " (nominal robot: "
    << Code(nominal.source) << ") identified from " << poses << " poses";
  if (readings != poses) o << " (" << readings << " readings)";
  o << " of " << Code(sources.measurements) << ": estimator `" << ToString(r.estimator) << "`, gauge `"
    << ToString(r.gauge) << "`, loss `" << ToString(r.loss) << "`; " << ToString(r.status) << " after " << r.iterations
    << " iterations.";
  if (!r.missing_sensors.empty()) o << " The data have " << MissingSensorsText(r.missing_sensors) << ".";
  if (r.corrected_for) {
    const SystematicSensorErrors& e = *r.corrected_for;
    o << " The laser and inclinometer readings were first corrected for the robot file's systematic sensor errors "
         "(laser offset "
      << Rounded(1e3 * e.laser_offset_m) << " mm, inclinometer offset " << Rounded(1e3 * e.inclinometer_offset_rad)
      << " mrad, sec coefficient " << Rounded(1e3 * e.inclinometer_sec_coefficient_rad) << " mrad).";
  }
  o << "\n\nUnits: positions and lengths in m, their standard deviations (σ, one standard deviation) and changes "
       "in mm, angles in mrad. Every number comes from the files beside this one, which hold all digits: "
       "`result.yaml` (the identification's result), `parameters.csv`, `correlation.csv`, `singular_values.csv`"
    << (sources.holdout.empty() ? " and `residuals.csv`" : ", `residuals.csv`, `validation.csv` and `validation.yaml`")
    << ".\n\n";
  if (!figure_error.empty()) o << "**The figures could not be made:** " << PrintableText(figure_error) << "\n\n";
  return o.str();
}

std::string EstimatesSection(const Robot& nominal, const IdentifyResult& r, const std::string& figure_error) {
  const GeometryVector nominal_geometry = GeometryOf(nominal);
  const std::vector<std::string> names = GeometryNames(nominal.num_cables());
  std::ostringstream o;
  o << "## Estimates\n\n";
  o << "| parameter | nominal (m) | identified (m) | σ (mm) | identified − nominal (mm) | identified − nominal (σ) |\n"
       "|---|---:|---:|---:|---:|---:|\n";
  std::vector<std::pair<double, std::string>> notable;  // |change| in sigma, "a2x (+5.2 σ)"
  for (std::size_t k = 0; k < names.size(); ++k) {
    const int i = static_cast<int>(k);
    const double change = r.geometry(i) - nominal_geometry(i);
    const bool has_std = r.has_covariance && r.geometry_std(i) > 0.0;
    o << "| " << names[k] << " | " << Fixed(nominal_geometry(i), 6) << " | " << Fixed(r.geometry(i), 6) << " | "
      << (IsHeld(r, i) ? std::string("held") : has_std ? Significant3(1e3 * r.geometry_std(i)) : std::string("–"))
      << " | "
      << SignedFixed(1e3 * change, 3) << " | " << (has_std ? SignedFixed(change / r.geometry_std(i), 2) : "–")
      << " |\n";
    if (has_std && std::abs(change / r.geometry_std(i)) > kNotableChangeSigmas) {
      notable.emplace_back(std::abs(change / r.geometry_std(i)),
                           names[k] + " (" + SignedFixed(change / r.geometry_std(i), 1) + " σ)");
    }
  }
  o << "\n";
  if (r.gauge == Gauge::kA1x) {
    o << "a1x is held at its nominal value (gauge a1x): exit point 1 defines the frame's x origin, and every "
         "identified x is relative to it.\n";
  }
  if (r.has_covariance) {
    std::sort(notable.begin(), notable.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
    o << "Changes beyond " << Rounded(kNotableChangeSigmas) << " σ (the nominal value is off by more than the "
      << "data's noise explains): ";
    if (notable.empty()) o << "none.";
    for (std::size_t k = 0; k < notable.size(); ++k) o << (k ? ", " : "") << notable[k].second;
    o << (notable.empty() ? "" : ".") << "\n";
  }
  o << "\nResidual RMS: encoder " << Rounded(1e3 * r.rms_encoder_m) << " mm";
  if (r.estimator == Estimator::kMaximumLikelihood) {
    for (const SensorUnit& u : kPlanarSensors) {  // in milli-units: mm, mrad
      if (!Missing(r, u.name)) o << ", " << u.name << " " << Rounded(1e3 * r.rms_sensor[static_cast<int>(u.id)]) << " m" << u.unit;
    }
  }
  o << ".\n\n";
  o << Figure(kEstimatesFigure, "Identified − nominal, mm, with ±1 σ and ±3 σ", figure_error);
  return o.str();
}

std::string CorrelationSection(const IdentifyResult& r, const std::string& figure_error) {
  if (!r.has_covariance) return "";
  const std::vector<std::string> names = GeometryNames(static_cast<int>(r.geometry.size() / 3));
  std::ostringstream o;
  o << "## Correlations\n\n";
  o << Figure(kCorrelationFigure, "Correlation matrix of the identified parameters", figure_error);
  std::vector<std::pair<double, std::string>> pairs;
  for (int a = 0; a < static_cast<int>(names.size()); ++a) {
    for (int b = a + 1; b < static_cast<int>(names.size()); ++b) {
      if (IsHeld(r, a)) continue;
      const double c = r.geometry_correlation(a, b);
      pairs.emplace_back(std::abs(c), names[a] + " and " + names[b] + ": " + SignedFixed(c, 3));
    }
  }
  std::sort(pairs.begin(), pairs.end(), [](const auto& x, const auto& y) { return x.first > y.first; });
  o << "Strongest correlations (a correlation near ±1: the data tell those two parameters apart poorly): ";
  for (std::size_t k = 0; k < std::min(kListed, pairs.size()); ++k) o << (k ? "; " : "") << pairs[k].second;
  o << ". The whole matrix: `correlation.csv`.\n\n";
  return o.str();
}

std::string ResidualsSection(const IdentifyResult& r, const std::string& figure_error) {
  std::ostringstream o;
  o << "## Residuals per pose\n\n";
  o << Figure(kResidualsFigure, "Each reading's residual over its sensor's σ, per pose", figure_error);
  o << "Each reading's residual (model − reading) over its sensor's σ"
    << (r.estimator == Estimator::kPaper ? " (estimator `paper`: the cable-length residuals over the laser's σ; it "
                                           "takes z and θ as measured)"
                                         : "")
    << ". Without a robust loss a reading beyond ±" << Rounded(kOutlierSigmas)
    << " σ refuses the fit; clean data stay within about ±3 σ. One row per reading and sensor: `residuals.csv`.\n\n";
  std::vector<SensorResidual> all = SensorResiduals(r);
  std::stable_sort(all.begin(), all.end(),
                   [](const SensorResidual& a, const SensorResidual& b) { return std::abs(a.sigmas) > std::abs(b.sigmas); });
  o << "The largest:\n\n| pose | reading | sensor | residual (σ) | weight |\n|---:|---:|---|---:|---:|\n";
  for (std::size_t k = 0; k < std::min(kListed, all.size()); ++k) {
    const SensorResidual& s = all[k];
    o << "| " << s.pose_id << " | " << s.reading << " | " << s.sensor << " | " << SignedFixed(s.sigmas, 2) << " | "
      << Rounded(s.weight) << (DownWeighted(r, s) ? " (down-weighted)" : "") << " |\n";
  }
  o << "\n";
  return o.str();
}

std::string LossSection(const IdentifyResult& r) {
  std::ostringstream o;
  o << "## Robust loss\n\n";
  if (r.loss.kind == LossKind::kNone) {
    o << "None (`--loss none`, least squares): every reading counts in full, and none is beyond ±"
      << Rounded(kOutlierSigmas) << " σ.\n\n";
    return o.str();
  }
  o << "`" << ToString(r.loss) << "` on every reading (scale in σ of its sensor): a reading counts in full up to "
       "about the scale and less beyond. Readings beyond ±"
    << Rounded(kOutlierSigmas) << " σ kept at a reduced weight" << (r.down_weighted.empty() ? ": none.\n\n" : ":\n\n");
  for (const std::string& d : r.down_weighted) o << "- " << PrintableText(d) << "\n";
  if (!r.down_weighted.empty()) o << "\n";
  if (!r.dropped_pose_ids.empty()) {
    o << "Dropped: pose" << (r.dropped_pose_ids.size() == 1 ? "" : "s");
    for (std::size_t k = 0; k < r.dropped_pose_ids.size(); ++k) o << (k ? ", " : " ") << r.dropped_pose_ids[k];
    o << ". Their readings do not fit the others, and the robust estimate followed them too far: the estimates "
         "are the fit without them (their readings are shown at weight 0).\n\n";
  }
  return o.str();
}

std::string IdentifiabilitySection(const IdentifyResult& r, const std::string& figure_error) {
  const Identifiability& id = r.identifiability;
  if (id.names.empty()) return "";
  std::ostringstream o;
  o << "## Identifiability\n\n";
  o << Figure(kSingularValuesFigure, "Singular values of the reduced Jacobian", figure_error);
  o << "The singular values of the " << (r.estimator == Estimator::kMaximumLikelihood ? "whitened " : "")
    << "Jacobian once every pose's own unknowns are eliminated: the information the data hold on the geometry (columns "
    << QuotedList(id.geometry_names) << "). A small one is a direction of the parameters the poses hardly fix.\n\n";
  o << "| # | singular value |\n|---:|---:|\n";
  for (Eigen::Index k = 0; k < id.singular_values.size(); ++k) {
    o << "| " << k + 1 << " | " << Rounded(id.singular_values(k), 4) << " |\n";
  }
  o << "\n- condition number (largest / smallest): " << Rounded(id.condition_number, 4) << "\n";
  o << "- weakest pose: pose " << id.weakest_pose_id << " (its own unknowns' smallest singular value "
    << Rounded(id.weakest_pose_singular_value, 4) << ")\n";
  o << "- null directions: ";
  if (id.null_directions.empty()) o << "none";
  for (std::size_t k = 0; k < id.null_directions.size(); ++k) o << (k ? "; " : "") << PrintableText(id.null_directions[k]);
  o << "\n- missing sensors: " << (r.missing_sensors.empty() ? "none" : MissingSensorsText(r.missing_sensors)) << "\n\n";
  return o.str();
}

std::string WarningsSection(const IdentifyResult& r) {
  std::ostringstream o;
  o << "## Warnings\n\n";
  if (r.warnings.empty()) o << "None.\n";
  for (const std::string& w : r.warnings) o << "- " << PrintableText(w) << "\n";
  o << "\n";
  return o.str();
}

std::string ValidationSection(const ValidationResult& v, const ReportSources& sources, const std::string& figure_error) {
  std::ostringstream o;
  o << "## Validation on held-out poses\n\n";
  const std::size_t readings = v.pose_ids.size();
  o << "The readings of " << Code(sources.holdout) << " (" << v.num_poses << " poses";
  if (readings != static_cast<std::size_t>(v.num_poses)) o << ", " << readings << " readings";
  o << "), which the identification did not see, predicted by the forward model of each robot (where its commanded "
       "lengths hold the platform) and compared with the laser's z and the inclinometer's θ; error = predicted − "
       "measured. The sensors' own noise, the least RMS error even a perfect model shows (more where the encoders' noise moves the predicted pose):";
  if (v.has_laser) o << " laser " << Rounded(1e3 * v.laser_sigma_m) << " mm";
  if (v.has_inclinometer) o << (v.has_laser ? "," : "") << " inclinometer " << Rounded(1e3 * v.inclinometer_sigma_rad) << " mrad";
  o << ".\n\n| robot |" << (v.has_laser ? " z RMS (mm) | z max (mm) |" : "")
    << (v.has_inclinometer ? " θ RMS (mrad) | θ max (mrad) |" : "") << "\n|---|"
    << (v.has_laser ? "---:|---:|" : "") << (v.has_inclinometer ? "---:|---:|" : "") << "\n";
  for (const RobotPrediction& p : v.robots) {
    o << "| " << p.name << " |";
    for (const std::optional<ErrorSummary>& e : {p.z_m, p.theta_rad}) {
      if (e) o << " " << Rounded(1e3 * e->rms) << " | " << Rounded(1e3 * e->max_abs) << " |";
    }
    o << "\n";
  }
  o << "\n";
  if (v.robots.size() > 1) {
    o << "Nominal / calibrated RMS error:";
    if (v.has_laser) o << " z " << Rounded(ZRmsRatio(v));
    if (v.has_inclinometer) o << (v.has_laser ? "," : "") << " θ " << Rounded(ThetaRmsRatio(v));
    o << " (above 1: the calibration predicts the held-out poses better than the nominal robot" <<
        (v.warnings.empty() ? "" : ", yet see below") << ").\n\n";
  }
  for (const std::string& w : v.warnings) o << "**Warning:** " << PrintableText(w) << ".\n\n";
  if (!NotCompared(v).empty()) o << "Not compared: the held-out readings have " << NotCompared(v) << ".\n\n";
  o << Figure(kValidationFigure, "Held-out poses: predicted − measured, calibrated and nominal robots", figure_error);
  o << "Per reading: `validation.csv`; the summary: `validation.yaml`.\n\n";
  return o.str();
}

std::string ProvenanceSection(const ReportSources& sources) {
  std::ostringstream o;
  o << "## Provenance\n\n| | |\n|---|---|\n";
  o << "| cablecal | " << Version() << " (commit " << GitCommit() << ") |\n";
  o << "| command | " << Cell(Code(sources.command_line)) << " |\n";
  o << "| measurements | " << Cell(Code(sources.measurements)) << " |\n";
  if (!sources.holdout.empty()) o << "| held-out readings | " << Cell(Code(sources.holdout)) << " |\n";
  return o.str();
}

}  // namespace

const std::vector<std::string>& ReportFileNames() {
  static const std::vector<std::string> names = {
      "report.md",          "result.yaml",      "parameters.csv",  "correlation.csv",  "singular_values.csv",
      "residuals.csv",      "validation.csv",   "validation.yaml", kEstimatesFigure,   kCorrelationFigure,
      kResidualsFigure,     kSingularValuesFigure, kValidationFigure};
  return names;
}

ValidationResult ValidateCalibration(const Robot& nominal, const IdentifyResult& result,
                                     const std::vector<Measurement>& holdout, const ReportSources& sources) {
  Robot calibrated = WithGeometry(nominal, result.geometry);
  // Not the nominal file: the summary and any message name where its geometry came from.
  calibrated.source = "identified from " + sources.measurements;
  ValidationResult v = Validate(calibrated, nominal, holdout, sources.holdout);
  if (nominal.sensors.systematic.any()) v.corrected_for = nominal.sensors.systematic;
  return v;
}

std::vector<ReportFile> ReportDataFiles(const Robot& nominal, const IdentifyResult& result,
                                        const std::string& result_yaml, const ValidationResult* validation,
                                        const ReportSources& sources) {
  const std::string provenance = ProvenanceComment(sources.command_line);
  std::vector<ReportFile> files = {{"result.yaml", result_yaml},
                                   {"parameters.csv", ParametersCsv(nominal, result, provenance)},
                                   {"residuals.csv", ResidualsCsv(result, provenance)}};
  if (result.has_covariance) files.push_back({"correlation.csv", CorrelationCsv(result, provenance)});
  if (!result.identifiability.names.empty()) {
    files.push_back({"singular_values.csv", SingularValuesCsv(result, provenance)});
  }
  if (validation) {
    files.push_back({"validation.csv", ValidationCsv(*validation, provenance)});
    files.push_back({"validation.yaml", ValidationSummaryYaml(*validation, sources.command_line)});
  }
  return files;
}

std::vector<std::string> ReportFigures(const IdentifyResult& result, bool with_validation) {
  std::vector<std::string> figures = {kEstimatesFigure};
  if (result.has_covariance) figures.push_back(kCorrelationFigure);
  figures.push_back(kResidualsFigure);
  if (!result.identifiability.names.empty()) figures.push_back(kSingularValuesFigure);
  if (with_validation) figures.push_back(kValidationFigure);
  return figures;
}

std::string ReportMarkdown(const Robot& nominal, const IdentifyResult& result, const ValidationResult* validation,
                           const ReportSources& sources, const std::string& figure_error) {
  return Heading(nominal, result, sources, figure_error) + EstimatesSection(nominal, result, figure_error) +
         CorrelationSection(result, figure_error) + ResidualsSection(result, figure_error) + LossSection(result) +
         IdentifiabilitySection(result, figure_error) + WarningsSection(result) +
         (validation ? ValidationSection(*validation, sources, figure_error) : "") + ProvenanceSection(sources);
}

std::string ReportWithoutFiguresMessage(const std::string& dir, const std::string& figure_error) {
  return figure_error + "; the report (" + dir + "/report.md, without figures) and its data files were written";
}

std::string StageReport(const OutputFolder& folder, const Robot& nominal, const IdentifyResult& result,
                        const std::string& result_yaml, const ValidationResult* validation,
                        const ReportSources& sources, const DrawReportFigures& draw) {
  for (const ReportFile& f : ReportDataFiles(nominal, result, result_yaml, validation, sources)) {
    folder.WriteText(f.name, f.content);
  }
  const std::vector<std::string> figures = ReportFigures(result, validation != nullptr);
  std::vector<std::string> arguments = {folder.staging(), "--title=" + PrintableText(nominal.name)};
  if (result.estimator == Estimator::kMaximumLikelihood) arguments.push_back("--whitened");
  if (!result.identifiability.names.empty()) {
    arguments.push_back("--condition-number=" + Rounded(result.identifiability.condition_number, 4));
  }
  // The held-out errors are drawn against the sensors' noise.
  if (validation && validation->has_laser) arguments.push_back("--laser-sigma=" + FormatDouble(validation->laser_sigma_m));
  if (validation && validation->has_inclinometer) {
    arguments.push_back("--inclinometer-sigma=" + FormatDouble(validation->inclinometer_sigma_rad));
  }
  std::string figure_error = draw(arguments);
  for (const std::string& f : figures) {
    if (figure_error.empty() && !std::filesystem::exists(folder.Path(f))) {
      figure_error = "the plotting script made no " + f;
    }
  }
  // A partial set would sit beside a report that says the figures failed.
  if (!figure_error.empty()) {
    for (const std::string& f : figures) std::filesystem::remove(folder.Path(f));
  }
  folder.WriteText("report.md", ReportMarkdown(nominal, result, validation, sources, figure_error));
  return figure_error;
}

std::string MarkdownCode(const std::string& text) { return Code(text); }
std::string MarkdownEscaped(const std::string& text) { return Escaped(text); }
std::string MarkdownFigure(const std::string& file, const std::string& caption, const std::string& figure_error) {
  return Figure(file, caption, figure_error);
}
std::string ReportProvenanceSection(const ReportSources& sources) { return ProvenanceSection(sources); }

}  // namespace cablecal
