#include "experiment/plan.h"

#include <cmath>
#include <fstream>
#include <set>
#include <sstream>
#include <vector>

#include "common/csv.h"
#include "common/error.h"
#include "common/format.h"
#include "common/random.h"
#include "common/yaml_writer.h"
#include "model/cable.h"
#include "model/kind.h"
#include "workspace/workspace.h"

namespace cablecal {

PlanPose MakePlanPose(const Robot& robot, const Equilibrium& equilibrium,
                      const Eigen::VectorXd& initial_lengths_m) {
  PlanPose pose;
  pose.q = equilibrium.q;
  pose.tensions_N = equilibrium.tensions_N;
  pose.lengths_m = CableLengths(robot, equilibrium.q);
  pose.length_change_m = pose.lengths_m - initial_lengths_m;
  return pose;
}

std::vector<PlanPose> SampleFeasiblePoses(const Robot& robot, int n, std::uint64_t seed) {
  if (n < 1) throw InputError("--poses", "", "must be at least 1 (got " + std::to_string(n) + ")");
  const Eigen::VectorXd l0 = InitialLengths(robot);
  Rng rng(seed);
  const double x_lo = robot.margin_m, x_hi = robot.frame_width_m - robot.margin_m;
  const double z_lo = robot.margin_m,
               z_hi = std::min(robot.frame_height_m - robot.margin_m, robot.laser_range_m);
  const long max_draws = (10000L + 1000L * n) * (robot.theta_is_free() ? 10 : 1);
  std::vector<PlanPose> plan;
  long draws = 0;
  while (static_cast<int>(plan.size()) < n) {
    if (++draws > max_draws) {
      throw SolverFailure("found only " + std::to_string(plan.size()) + " feasible poses in " +
                          std::to_string(max_draws) + " random draws: the feasible workspace is empty or tiny");
    }
    const double x = rng.Uniform(x_lo, x_hi);
    const double z = rng.Uniform(z_lo, z_hi);
    const PoseEvaluation e = robot.theta_is_free()
                                 ? EvaluatePose(robot, PlanarPose(x, z, rng.Uniform(-robot.theta_max_rad,
                                                                                         robot.theta_max_rad)))
                                 : EvaluatePose(robot, x, z);
    if (e.feasible()) plan.push_back(MakePlanPose(robot, e.equilibrium, l0));
  }
  return plan;
}

std::string PosePlanCsv(const std::vector<PlanPose>& plan, const std::string& provenance) {
  std::string out = provenance + "pose";
  for (const char* name : PlanarKind::kPoseNames) out += std::string(",") + name;
  const int m = plan.empty() ? 2 : static_cast<int>(plan.front().lengths_m.size());
  for (const char* prefix : {"t", "l", "dl"}) {
    for (int i = 1; i <= m; ++i) out += "," + std::string(prefix) + std::to_string(i);
  }
  const bool worst = !plan.empty() && plan.front().tensions_worst_min_N.size() == m;
  if (worst) {
    for (int i = 1; i <= m; ++i) out += ",t" + std::to_string(i) + "_worst_min,t" + std::to_string(i) + "_worst_max";
  }
  out += "\n";
  for (std::size_t j = 0; j < plan.size(); ++j) {
    const PlanPose& p = plan[j];
    out += std::to_string(j + 1);
    for (int k = 0; k < PlanarKind::kPoseDim; ++k) out += "," + FormatDouble(p.q(k));
    for (int i = 0; i < m; ++i) out += "," + FormatDouble(p.tensions_N(i));
    for (int i = 0; i < m; ++i) out += "," + FormatDouble(p.lengths_m(i));
    for (int i = 0; i < m; ++i) out += "," + FormatDouble(p.length_change_m(i));
    if (worst) {
      for (int i = 0; i < m; ++i) {
        out += "," + FormatDouble(p.tensions_worst_min_N(i)) + "," + FormatDouble(p.tensions_worst_max_N(i));
      }
    }
    out += "\n";
  }
  return out;
}


void RequirePlanLength(const std::string& where, const std::string& robot_name, int cable, double model_length_m,
                       double plan_length_m, double tolerance_m) {
  if (std::abs(model_length_m - plan_length_m) <= tolerance_m) return;
  const std::string c = std::to_string(cable + 1);
  throw InputError(where, "column 'l" + c + "'", FormatDouble(plan_length_m) + " m is not the length of cable " + c +
                                                   " of " + robot_name + " at this pose (" + FormatDouble(model_length_m) +
                                                   " m): a plan for another robot?");
}

void RequirePlanEquilibrium(const std::string& where, const std::string& robot_name, const Eigen::VectorXd& tensions_N,
                            double residual_N, double weight_N, const std::string& pose_columns) {
  for (Eigen::Index i = 0; i < tensions_N.size(); ++i) {
    if (!(tensions_N(i) < 0.0)) continue;
    const std::string c = std::to_string(i + 1);
    throw InputError(where, "column 't" + c + "'",
                     FormatDouble(tensions_N(i)) + " N is a negative tension: cable " + c +
                         " would push, which no cable can (the plan's tensions are in N, every one positive)");
  }
  if (residual_N <= 1e-6 * weight_N) return;
  std::string columns = pose_columns;
  for (Eigen::Index i = 1; i <= tensions_N.size(); ++i) columns += ",t" + std::to_string(i);
  throw InputError(where, "columns '" + columns + "'",
                   "not a static equilibrium of " + robot_name + " (force and moment residual " +
                       FormatDouble(residual_N) + " N): the platform would not stay at this pose");
}

void CheckPlanMatchesRobot(const Robot& robot, const std::vector<PlanPose>& plan, const std::string& source) {
  constexpr double kLengthTol_m = 1e-6;  // files hold shortest round-trip doubles: far below
  const double weight_N = robot.platform_mass_kg * robot.gravity_mps2;
  const Eigen::VectorXd l0 = InitialLengths(robot);
  for (std::size_t j = 0; j < plan.size(); ++j) {
    const PlanPose& p = plan[j];
    const std::string where = source + ": pose " + std::to_string(j + 1);
    // The reference point inside the frame first: a pose outside it is named by its own column
    // rather than by the cable lengths that follow from it.
    if (!(p.q(0) >= 0.0 && p.q(0) <= robot.frame_width_m)) {
      throw InputError(where, "column 'x'", FormatDouble(p.q(0)) + " m is outside the frame [0, " +
                                                FormatDouble(robot.frame_width_m) + "] m of " + robot.name +
                                                ": a plan for another robot?");
    }
    if (!(p.q(1) >= 0.0 && p.q(1) <= robot.frame_height_m)) {
      throw InputError(where, "column 'z'", FormatDouble(p.q(1)) + " m is outside the frame [0, " +
                                                FormatDouble(robot.frame_height_m) + "] m of " + robot.name +
                                                ": a plan for another robot?");
    }
    if (!(std::abs(p.q(2)) <= robot.theta_max_rad)) {
      throw InputError(where, "column 'theta'", FormatDouble(p.q(2)) + " rad is beyond the inclinometer range of +-" +
                                                    FormatDouble(robot.theta_max_rad) + " rad" +
                                                    (std::abs(p.q(2)) > M_PI ? " (degrees? theta is in radians)" : ""));
    }
    const Eigen::VectorXd l = CableLengths(robot, p.q);
    for (int i = 0; i < robot.num_cables(); ++i) {
      const std::string c = std::to_string(i + 1);
      RequirePlanLength(where, robot.name, i, l(i), p.lengths_m(i), kLengthTol_m);
      if (!(std::abs(l(i) - l0(i) - p.length_change_m(i)) <= kLengthTol_m)) {
        throw InputError(where, "column 'dl" + c + "'", FormatDouble(p.length_change_m(i)) +
                                                            " m is not l" + c + " minus the initial length " +
                                                            FormatDouble(l0(i)) + " m of " + robot.name);
      }
    }
    RequirePlanEquilibrium(where, robot.name, p.tensions_N,
                           EquilibriumResidual<double>(robot, p.q, p.tensions_N).norm(), weight_N, "x,z,theta");
  }
}

std::string PosePlanJsonYaml(const std::vector<PlanPose>& poses) { return PlanJsonYaml<PlanarKind>(poses); }

std::vector<PlanPose> ReadPosePlanCsv(const std::string& path, int num_cables) {
  std::ifstream in = OpenCsvFile(path);
  return ReadPosePlanCsv(in, path, num_cables);
}

std::vector<PlanPose> ReadPosePlanCsv(std::istream& in, const std::string& path, int num_cables) {
  std::vector<std::string> header = {"pose"};
  for (const char* name : PlanarKind::kPoseNames) header.push_back(name);
  const int first = 1 + PlanarKind::kPoseDim;  // t1's column
  for (const char* prefix : {"t", "l", "dl"}) {
    for (int i = 1; i <= num_cables; ++i) header.push_back(prefix + std::to_string(i));
  }
  std::vector<std::string> worst_columns;  // optional, written by design
  for (int i = 1; i <= num_cables; ++i) {
    worst_columns.push_back("t" + std::to_string(i) + "_worst_min");
    worst_columns.push_back("t" + std::to_string(i) + "_worst_max");
  }
  std::vector<PlanPose> plan;
  std::set<int> ids;
  ForEachCsvRow(in, path, header, worst_columns, [&](const CsvRow& row) {
    if (static_cast<int>(plan.size()) >= kMaxPlanPoses) {
      throw InputError(row.Where(), "", "more than " + std::to_string(kMaxPlanPoses) + " poses");
    }
    const int id = row.PositiveInt(0);
    if (!ids.insert(id).second) {
      throw InputError(row.Where(), "column 'pose'", "duplicate pose id " + std::to_string(id));
    }
    PlanPose p;
    for (int k = 0; k < PlanarKind::kPoseDim; ++k) p.q(k) = row.Number(1 + k);
    p.tensions_N.resize(num_cables);
    p.lengths_m.resize(num_cables);
    p.length_change_m.resize(num_cables);
    for (int i = 0; i < num_cables; ++i) {
      p.tensions_N(i) = row.Number(first + i);
      p.lengths_m(i) = row.Number(first + num_cables + i);
      p.length_change_m(i) = row.Number(first + 2 * num_cables + i);
    }
    if (row.cells.size() > header.size()) {
      p.tensions_worst_min_N.resize(num_cables);
      p.tensions_worst_max_N.resize(num_cables);
      for (int i = 0; i < num_cables; ++i) {
        p.tensions_worst_min_N(i) = row.Number(first + 3 * num_cables + 2 * i);
        p.tensions_worst_max_N(i) = row.Number(first + 3 * num_cables + 2 * i + 1);
      }
    }
    plan.push_back(p);
  });
  return plan;
}

}  // namespace cablecal
