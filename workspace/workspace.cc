#include "workspace/workspace.h"

#include <cmath>
#include <fstream>
#include <set>
#include <vector>
#include <sstream>

#include "common/parallel.h"
#include "common/csv.h"
#include "common/error.h"
#include "common/format.h"
#include "common/random.h"
#include "common/yaml_writer.h"
#include "model/cable.h"

namespace cablecal {

WorkspaceGrid ComputeWorkspaceGrid(const Robot& robot, double step_m) {
  if (!(step_m > 0.0) || !std::isfinite(step_m)) {
    throw InputError("--step", "", "must be a positive number of metres (got " + FormatDouble(step_m) + ")");
  }
  // Fewer than 5 points a side says nothing about the workspace (one point, "area 0", was exit 0).
  const double coarsest_step_m = 0.25 * std::min(robot.frame_width_m, robot.frame_height_m);
  if (!(step_m <= coarsest_step_m)) {
    throw InputError("--step", "", FormatDouble(step_m) + " m leaves fewer than 5 grid points along a side of the " +
                                       FormatDouble(robot.frame_width_m) + " x " + FormatDouble(robot.frame_height_m) +
                                       " m frame (at most " + FormatDouble(coarsest_step_m) + " m)");
  }
  // Guard against a step so small the grid would not fit in memory.
  const double nx_d = std::floor(robot.frame_width_m / step_m + 1e-9) + 1;
  const double nz_d = std::floor(robot.frame_height_m / step_m + 1e-9) + 1;
  if (nx_d * nz_d > kMaxGridPoints) {
    throw InputError("--step", "", FormatDouble(step_m) + " m makes a grid of more than 2,000,000 points (the limit: about 30 s, 0.5 GB and a 175 MB CSV; a coarser step)");
  }
  if (robot.theta_is_free() && nx_d * nz_d > kMaxThetaScanGridPoints) {
    throw InputError("--step", "", FormatDouble(step_m) + " m makes a grid of more than 40,000 points, each scanned over theta (" +
                                       std::to_string(robot.num_cables()) +
                                       " cables; the limit: about a minute on 2 cores; a coarser step)");
  }
  const int nx = static_cast<int>(nx_d), nz = static_cast<int>(nz_d);
  WorkspaceGrid grid;
  grid.step_m = step_m;
  grid.points.resize(static_cast<std::size_t>(nx) * nz);
  ParallelFor(static_cast<long>(nx) * nz, 16, [&](long k) {
    WorkspacePoint& p = grid.points[k];
    p.x_m = (k % nx) * step_m;
    p.z_m = (k / nx) * step_m;
    if (robot.theta_is_free()) {
      ThetaScan scan = ScanTheta(robot, p.x_m, p.z_m);
      p.evaluation = std::move(scan.evaluation);
      p.theta_min_rad = scan.theta_min_rad;
      p.theta_max_rad = scan.theta_max_rad;
    } else {
      p.evaluation = EvaluatePose(robot, p.x_m, p.z_m);
    }
  });
  for (const WorkspacePoint& p : grid.points) grid.num_feasible += p.evaluation.feasible();
  return grid;
}

std::string WorkspaceCsv(const Robot& robot, const WorkspaceGrid& grid, const std::string& provenance) {
  std::string out = provenance;
  out += "x,z,theta";
  for (int i = 1; i <= robot.num_cables(); ++i) out += ",t" + std::to_string(i);
  out += ",feasible,reason";
  const bool band = robot.theta_is_free();
  if (band) out += ",theta_min,theta_max";
  out += "\n";
  for (const WorkspacePoint& p : grid.points) {
    out += FormatDouble(p.x_m) + "," + FormatDouble(p.z_m) + ",";
    if (p.evaluation.has_equilibrium) {
      out += FormatDouble(p.evaluation.equilibrium.q(2));
      for (int i = 0; i < robot.num_cables(); ++i) {
        out += "," + FormatDouble(p.evaluation.equilibrium.tensions_N(i));
      }
    } else {
      for (int i = 0; i < robot.num_cables(); ++i) out += ",";
    }
    out += std::string(",") + (p.evaluation.feasible() ? "1" : "0") + "," + ToString(p.evaluation.feasibility);
    if (band) {
      out += std::isnan(p.theta_min_rad) ? ",," : "," + FormatDouble(p.theta_min_rad) + "," + FormatDouble(p.theta_max_rad);
    }
    out += "\n";
  }
  return out;
}

}  // namespace cablecal
