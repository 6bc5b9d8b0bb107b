// workspace: the feasible cable-tension workspace of a robot (README, "Model and
// conventions"): ComputeWorkspaceGrid, every grid point's equilibrium and feasibility (with
// the reason), and its CSV. The pose plans drawn from it are experiment/plan.h's.
// Depends on model/ and common/.
#pragma once

#include <cstdint>
#include <istream>
#include <limits>
#include <string>
#include <vector>

#include "model/robot.h"
#include "model/statics.h"

namespace cablecal {

struct WorkspacePoint {
  double x_m = 0.0, z_m = 0.0;
  // m = 2: the equilibrium at (x, z). m >= 3: the pose at the middle of the longest run of
  // feasible orientations at (x, z) (ScanTheta, model/statics.h), or, where none is feasible, the
  // evaluation at the orientation whose reason is the most common over the scan.
  PoseEvaluation evaluation;
  // m >= 3 only: the feasible orientations found at (x, z), [min, max] over the scan (rad);
  // NaN where none is feasible or m = 2.
  double theta_min_rad = std::numeric_limits<double>::quiet_NaN();
  double theta_max_rad = std::numeric_limits<double>::quiet_NaN();
};


struct WorkspaceGrid {
  double step_m = 0.0;
  std::vector<WorkspacePoint> points;  // row-major: z outer, x inner
  int num_feasible = 0;
  // Area estimate: each feasible grid point stands for a step x step cell (m^2).
  double feasible_area_m2() const { return num_feasible * step_m * step_m; }
};

// Grid over the frame [0, width] x [0, height] with spacing step_m (> 0). Points are
// evaluated in parallel (OpenMP); the result does not depend on the thread count. A step
// that makes more than kMaxGridPoints points is an InputError naming --step: 2e6 points take
// about 30 s and 0.5 GB on 2 cores and write a 175 MB CSV (bench/README.md).
constexpr double kMaxGridPoints = 2e6;
// With 3 or more cables every point is a scan of theta (ThetaScan, 120 to 180 full-pose tests):
// at most kMaxThetaScanGridPoints then (planar4 at step 0.05 m, 2501 points: 0.8 s CPU,
// bench/README.md; the limit about a minute on 2 cores).
constexpr double kMaxThetaScanGridPoints = 40000;
WorkspaceGrid ComputeWorkspaceGrid(const Robot& robot, double step_m);

// Workspace CSV: header x,z,theta,t1..tm,feasible,reason (m, rad, N); theta and tensions
// empty where no equilibrium exists. m >= 3 adds theta_min,theta_max, the feasible band
// (empty where none is feasible).
std::string WorkspaceCsv(const Robot& robot, const WorkspaceGrid& grid, const std::string& provenance);

}  // namespace cablecal
