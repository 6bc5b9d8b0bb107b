// calibration_report: `identify --report DIR` (README, "Calibration report"): report.md, the
// document a lab hands on with a calibration, and the data files its figures are drawn from
// (scripts/plot_report.py reads them and writes the PNGs beside report.md). The text is made
// here, once, for the CLI and the Python module alike; the caller chooses how the figures are
// drawn (the CLI: its plotting-script runner; Python: its own interpreter).
// Depends on identify/ (the result, the validation of held-out readings) and common/ (the
// output folder).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "common/atomic_output.h"
#include "identify/identify.h"
#include "identify/validate.h"
#include "model/robot.h"

namespace cablecal {

// Every name a report may write into its folder, the figures and the validation's files
// included: the folder's owned set, so that an earlier report's files (its validation, say)
// never stay beside a new report that has none.
const std::vector<std::string>& ReportFileNames();

// What the report says about where it came from (its provenance section).
struct ReportSources {
  std::string command_line;
  std::string measurements;  // the identification's readings: a path, or what they were
  std::string holdout;       // the held-out readings' path; empty: none given
};

// The held-out readings (already corrected as the identification's were, for a robot file
// with systematic sensor errors) predicted by the calibrated robot, the nominal one with the
// identified geometry, and by the nominal one (identify/validate.h). Throws Validate's
// InputError for readings a robot cannot hold.
ValidationResult ValidateCalibration(const Robot& nominal, const IdentifyResult& result,
                                     const std::vector<Measurement>& holdout, const ReportSources& sources);

struct ReportFile {
  std::string name;  // in the report folder
  std::string content;
};

// The files the figures are drawn from, also a lab's numbers to reuse: result.yaml (as given),
// parameters.csv, correlation.csv, singular_values.csv, residuals.csv (one row per reading and
// sensor) and, with held-out readings, validation.csv and validation.yaml.
std::vector<ReportFile> ReportDataFiles(const Robot& nominal, const IdentifyResult& result,
                                        const std::string& result_yaml, const ValidationResult* validation,
                                        const ReportSources& sources);

// The PNGs plot_report.py draws for this result, in the report's order.
std::vector<std::string> ReportFigures(const IdentifyResult& result, bool with_validation);

// report.md. `figure_error`: empty when every figure was drawn; otherwise why not, said where
// the figures would be.
std::string ReportMarkdown(const Robot& nominal, const IdentifyResult& result, const ValidationResult* validation,
                           const ReportSources& sources, const std::string& figure_error);

// Runs scripts/plot_report.py with these arguments (the folder holding the data files first);
// returns "" or why it failed.
using DrawReportFigures = std::function<std::string(const std::vector<std::string>& script_arguments)>;

// What a command says after committing a report whose figures failed (`figure_error`).
std::string ReportWithoutFiguresMessage(const std::string& dir, const std::string& figure_error);

// Stages the whole report in `folder` (the caller commits it): the data files, then the
// figures through `draw` (a failure, or a figure it did not make, leaves none of them: the
// report says why instead), then report.md. Returns "" or the figures' failure, which the
// caller reports after the commit (results are never lost for a figure).
std::string StageReport(const OutputFolder& folder, const Robot& nominal, const IdentifyResult& result,
                        const std::string& result_yaml, const ValidationResult* validation,
                        const ReportSources& sources, const DrawReportFigures& draw);

// report.md's pieces that the spatial report (identify/spatial_calibration_report.h) shares:
// inline code whatever the text holds, a name in running text with markdown's characters
// escaped, a figure's link (or why it is not there), and the provenance section.
std::string MarkdownCode(const std::string& text);
std::string MarkdownEscaped(const std::string& text);
std::string MarkdownFigure(const std::string& file, const std::string& caption, const std::string& figure_error);
std::string ReportProvenanceSection(const ReportSources& sources);

}  // namespace cablecal
