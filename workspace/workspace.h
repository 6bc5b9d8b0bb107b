// workspace: the feasible cable-tension workspace of a robot (README, "Model and
// conventions") and the pose plans built on it.
//   ComputeWorkspaceGrid   every grid point's equilibrium and feasibility (with the reason)
//   SampleFeasiblePoses    uniform random feasible poses, seeded; reused by design and
//                          the Monte Carlo
//   PosePlan               the pose plan CSV shared by sample, design and simulate (its
//                          one reader and writer; PosePlanJsonYaml, the same for --json)
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

// One measurement pose of a plan.
struct PlanPose {
  Eigen::Vector3d q = Eigen::Vector3d::Zero();  // (x_m, z_m, theta_rad), an equilibrium
  Eigen::VectorXd tensions_N;
  Eigen::VectorXd lengths_m;        // l_i, exit point -> anchor
  Eigen::VectorXd length_change_m;  // dl_i = l_i - l_i0: the encoder command from home
  // Designed plans only (else empty): the tension range each cable may see on a true robot
  // within the design's geometry uncertainty (linearised worst case, README "Experiment
  // design"); written as the optional columns t<i>_worst_min, t<i>_worst_max.
  Eigen::VectorXd tensions_worst_min_N, tensions_worst_max_N;
};

// Fills tensions, lengths and length changes for equilibrium poses.
PlanPose MakePlanPose(const Robot& robot, const Equilibrium& equilibrium,
                      const Eigen::VectorXd& initial_lengths_m);

// n poses drawn uniformly over the feasible region by rejection from the frame box: (x, z)
// for m = 2 (theta from the equilibrium), (x, z, theta) with theta uniform over the
// inclinometer range for m >= 3. The stream is Rng(seed). Throws InputError if n < 1 and
// SolverFailure if no feasible pose turns up in (10000 + 1000 n) draws (m >= 3: ten times
// that, the orientation being drawn too): an empty or tiny workspace.
std::vector<PlanPose> SampleFeasiblePoses(const Robot& robot, int n, std::uint64_t seed);

// Pose plan CSV: header pose,x,z,theta,t1..tm,l1..lm,dl1..dlm (pose numbered from 1), then
// t<i>_worst_min,t<i>_worst_max for each cable when the plan carries them.
std::string PosePlanCsv(const std::vector<PlanPose>& plan, const std::string& provenance);
// The same poses as a YAML sequence of maps, the CSV's columns as keys (pose, x, z, theta in m
// and rad, t1.., l1.., dl1.. in N and m; no worst-case columns), for design --json.
std::string PosePlanJsonYaml(const std::vector<PlanPose>& plan);

// Reads a pose plan CSV; '#' lines are comments. Throws InputError naming file, line and
// column on a wrong header, a bad number, a duplicate or non-positive pose id.
// At most kMaxPlanPoses rows are accepted (the file is streamed and rejected at the next row).
std::vector<PlanPose> ReadPosePlanCsv(const std::string& path, int num_cables);
std::vector<PlanPose> ReadPosePlanCsv(std::istream& in, const std::string& name, int num_cables);
constexpr int kMaxPlanPoses = 100000;

// A plan read from a file must be one of `robot`'s: every pose an equilibrium of its statics
// with the plan's tensions, |theta| within the inclinometer range, and the lengths and length
// changes those of the robot's model at that pose (to 1e-6 m). InputError naming the file,
// the pose and the column otherwise (a plan made for another robot, or edited by hand).
void CheckPlanMatchesRobot(const Robot& robot, const std::vector<PlanPose>& plan, const std::string& source);

}  // namespace cablecal
