#include "workspace/spatial_workspace.h"

#include <algorithm>
#include <cmath>

#include "common/csv.h"
#include "common/error.h"
#include "common/format.h"
#include "common/parallel.h"

namespace cablecal {

double DefaultSpatialStep(const SpatialRobot& robot) {
  const double finest_m = (robot.p_F_frame_max_m - robot.p_F_frame_min_m).maxCoeff() / 40.0;
  const double decade = std::pow(10.0, std::floor(std::log10(finest_m)));
  for (const double mantissa : {1.0, 2.0, 5.0, 10.0}) {
    if (mantissa * decade >= finest_m * (1.0 - 1e-12)) return mantissa * decade;
  }
  return 10.0 * decade;
}

Eigen::Vector3d WorkspaceOrientation(const Eigen::Vector3d& rpy_deg) {
  const std::string got = " (got " + FormatDouble(rpy_deg(0)) + ", " + FormatDouble(rpy_deg(1)) + ", " +
                          FormatDouble(rpy_deg(2)) + ")";
  if (!(std::abs(rpy_deg(0)) < 90.0 && std::abs(rpy_deg(1)) < 90.0)) {
    throw InputError("--rpy-deg", "", "roll and pitch must be within (-90, 90) degrees" + got);
  }
  if (!(std::abs(rpy_deg(2)) <= 180.0)) throw InputError("--rpy-deg", "", "yaw must be within [-180, 180] degrees" + got);
  return rpy_deg * M_PI / 180.0;
}

SpatialWorkspaceGrid ComputeSpatialWorkspace(const SpatialRobot& robot, const Eigen::Vector3d& rpy_rad, double step_m) {
  if (!(step_m > 0.0) || !std::isfinite(step_m)) {
    throw InputError("--step", "", "must be a positive number of metres (got " + FormatDouble(step_m) + ")");
  }
  const Eigen::Vector3d size_m = robot.p_F_frame_max_m - robot.p_F_frame_min_m;
  // Fewer than 5 points along a side says nothing about the workspace.
  const double coarsest_step_m = 0.25 * size_m.minCoeff();
  if (!(step_m <= coarsest_step_m)) {
    throw InputError("--step", "", FormatDouble(step_m) + " m leaves fewer than 5 grid points along the shortest side of the " +
                                       FormatDouble(size_m.x()) + " x " + FormatDouble(size_m.y()) + " x " +
                                       FormatDouble(size_m.z()) + " m frame box (at most " +
                                       FormatDouble(coarsest_step_m) + " m)");
  }
  Eigen::Vector3d counts_d;
  for (int a = 0; a < 3; ++a) counts_d(a) = std::floor(size_m(a) / step_m + 1e-9) + 1;
  if (counts_d.prod() > kMaxSpatialGridPoints) {
    throw InputError("--step", "", FormatDouble(step_m) + " m makes a grid of " + FormatDouble(counts_d.prod()) +
                                       " points, more than 200,000 (the limit: about a minute on 2 cores and a 40 MB "
                                       "CSV; a coarser step)");
  }
  SpatialWorkspaceGrid grid;
  grid.step_m = step_m;
  grid.rpy_rad = rpy_rad;
  grid.counts = counts_d.cast<int>();
  const long nx = grid.counts.x(), ny = grid.counts.y(), n = nx * ny * grid.counts.z();
  grid.points.resize(n);
  ParallelFor(n, 8, [&](long k) {
    SpatialWorkspacePoint& point = grid.points[k];
    const Eigen::Vector3d index(k % nx, (k / nx) % ny, k / (nx * ny));
    // Rounded to the picometre so that the CSV reads 0.3, not 0.30000000000000004 (a grep for a
    // slice's height must find it).
    point.p_F_m = ((robot.p_F_frame_min_m + step_m * index) * 1e12).array().round() / 1e12;
    SpatialPose<double> q;
    q << point.p_F_m, rpy_rad;
    point.evaluation = EvaluateSpatialPose(robot, q);
  });
  for (const SpatialWorkspacePoint& p : grid.points) grid.num_feasible += p.evaluation.feasible();
  return grid;
}

std::string SpatialWorkspaceCsv(const SpatialRobot& robot, const SpatialWorkspaceGrid& grid,
                                const std::string& provenance) {
  const int m = robot.num_cables();
  std::string out = provenance + "x,y,z,roll,pitch,yaw";
  for (int i = 1; i <= m; ++i) out += ",t" + std::to_string(i);
  out += ",feasible,reason\n";
  for (const SpatialWorkspacePoint& p : grid.points) {
    out += FormatDouble(p.p_F_m.x()) + "," + FormatDouble(p.p_F_m.y()) + "," + FormatDouble(p.p_F_m.z());
    const SpatialPoseEvaluation& e = p.evaluation;
    if (e.has_equilibrium) {
      for (int k = 3; k < 6; ++k) out += "," + FormatDouble(e.equilibrium.q(k));
      for (int i = 0; i < m; ++i) out += "," + FormatDouble(e.equilibrium.tensions_N(i));
    } else {
      out += std::string(3 + m, ',');
    }
    out += std::string(",") + (e.feasible() ? "1" : "0") + "," + ToString(e.feasibility) + "\n";
  }
  return out;
}

}  // namespace cablecal
