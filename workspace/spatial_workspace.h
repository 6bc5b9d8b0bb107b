// The constant-orientation workspace of a spatial robot (README, "Spatial robots", workspace):
// every point of a 3-D grid over the frame box evaluated at one orientation (EvaluateSpatialPose:
// its equilibrium, feasibility and reason), and its CSV.
// Depends on model/ and common/.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "model/spatial_robot.h"
#include "model/spatial_statics.h"

namespace cablecal {

struct SpatialWorkspacePoint {
  Eigen::Vector3d p_F_m = Eigen::Vector3d::Zero();
  // At (p, the grid's orientation): m >= 6 the tension distribution there; m < 6 the
  // equilibrium whose controlled coordinates are these (the orientation's uncontrolled entries
  // follow from it).
  SpatialPoseEvaluation evaluation;
};

struct SpatialWorkspaceGrid {
  double step_m = 0.0;
  Eigen::Vector3d rpy_rad = Eigen::Vector3d::Zero();  // the orientation asked for
  Eigen::Vector3i counts = Eigen::Vector3i::Zero();   // points along x, y, z
  std::vector<SpatialWorkspacePoint> points;          // z outermost, then y, x innermost
  int num_feasible = 0;
  // Each feasible point stands for a step^3 cell (m^3).
  double feasible_volume_m3() const { return num_feasible * step_m * step_m * step_m; }
};

// At most this many grid points: a spatial point costs about what a planar theta scan does
// (a 6 x m tension distribution, or an equilibrium solve for m < 6); 200,000 points take about
// a minute on 2 cores and write a 40 MB CSV (bench/README.md).
constexpr double kMaxSpatialGridPoints = 2e5;

// workspace's default step for a spatial robot: the frame box's longest side / 40, rounded up
// to 1, 2 or 5 times a power of ten (cogiro 0.5 m, ipanema1 0.1 m): at most 41 points along
// a side, so that the default runs in seconds on any frame size.
double DefaultSpatialStep(const SpatialRobot& robot);

// The workspace's orientation from roll, pitch, yaw in degrees, in radians: roll and pitch
// within (-90, 90) and yaw within [-180, 180] degrees, the one range in which every orientation
// is written once (a yaw of 720 is a yaw of 0 written otherwise, or radians typed as degrees'
// multiples). InputError naming --rpy-deg otherwise (the CLI's flag; Python names rpy_deg).
Eigen::Vector3d WorkspaceOrientation(const Eigen::Vector3d& rpy_deg);

// The grid frame.min + k step (k = 0, 1, ... while inside the frame box) at orientation
// rpy_rad (roll, pitch, yaw), evaluated in parallel (OpenMP); the result does not depend on the
// thread count. InputError naming --step for a step that is not positive, leaves fewer than 5
// points along the box's shortest side, or makes more than kMaxSpatialGridPoints points.
SpatialWorkspaceGrid ComputeSpatialWorkspace(const SpatialRobot& robot, const Eigen::Vector3d& rpy_rad, double step_m);

// CSV: x,y,z,roll,pitch,yaw,t1..tm,feasible,reason (m, rad, N); the orientation and tensions
// empty where there is no equilibrium.
std::string SpatialWorkspaceCsv(const SpatialRobot& robot, const SpatialWorkspaceGrid& grid,
                                const std::string& provenance);

}  // namespace cablecal
