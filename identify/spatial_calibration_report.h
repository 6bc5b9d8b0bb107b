// The calibration report of a spatial robot (`identify --report DIR` on a `kind: spatial` file;
// README, "Spatial robots"): report.md and the data files its figures are drawn from, as the
// planar report (identify/calibration_report.h), with the spatial figures:
//   exits.png      the exit points, nominal and identified, in a top (x-y) and a side (x-z) view
//                  with their 1-sigma ellipses from the covariance (exits.csv)
//   residuals.png  every reading's whitened residual per pose and sensor (residuals.csv)
// drawn by scripts/plot_spatial_report.py. Depends on identify/.
#pragma once

#include <string>
#include <vector>

#include "common/atomic_output.h"
#include "identify/calibration_report.h"  // ReportSources, DrawReportFigures
#include "identify/spatial_identify.h"
#include "identify/spatial_validate.h"
#include "model/spatial_robot.h"

namespace cablecal {

// Every name the spatial report may write into its folder.
const std::vector<std::string>& SpatialReportFileNames();

// The data files: result.yaml (as given), parameters.csv, exits.csv, residuals.csv and, with
// held-out readings (identify --holdout), validation.csv and validation.yaml.
std::vector<ReportFile> SpatialReportDataFiles(const SpatialRobot& nominal, const SpatialIdentifyOptions& options,
                                               const SpatialIdentifyResult& result, const std::string& result_yaml,
                                               const SpatialValidationResult* validation, const ReportSources& sources);

std::string SpatialReportMarkdown(const SpatialRobot& nominal, const SpatialIdentifyOptions& options,
                                  const SpatialIdentifyResult& result, const SpatialValidationResult* validation,
                                  const ReportSources& sources, const std::string& figure_error);

// Stages the report in `folder` (the caller commits it), as StageReport: data files, figures
// through `draw` (scripts/plot_spatial_report.py's arguments: the staging folder first), then
// report.md. Returns "" or why the figures failed.
std::string StageSpatialReport(const OutputFolder& folder, const SpatialRobot& nominal,
                               const SpatialIdentifyOptions& options, const SpatialIdentifyResult& result,
                               const std::string& result_yaml, const SpatialValidationResult* validation,
                               const ReportSources& sources, const DrawReportFigures& draw);

}  // namespace cablecal
