// A pose plan: the measurement poses of an experiment, each an equilibrium of the nominal
// robot with its tensions, cable lengths and the encoder commands from home.
//   SampleFeasiblePoses    uniform random feasible poses, seeded; reused by design and
//                          the Monte Carlo
//   PosePlanCsv            the pose plan CSV shared by sample, design and simulate (its one
//                          reader and writer; PosePlanJsonYaml, the same for --json)
// Depends on workspace/ (the feasibility of a pose) and model/.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <istream>
#include <string>
#include <vector>

#include "common/yaml_writer.h"
#include "model/robot.h"
#include "model/kind.h"
#include "model/statics.h"

namespace cablecal {

// One measurement pose of a plan.
struct PlanPose {
  PlanarPose q = PlanarPose::Zero();  // (x_m, z_m, theta_rad), an equilibrium
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
// The same for a plan of any kind (PlanPose, SpatialPlanPose: q, tensions_N, lengths_m,
// length_change_m): one flow map per pose, the plan CSV's columns.
template <typename Kind, typename PoseOfPlan>
std::string PlanJsonYaml(const std::vector<PoseOfPlan>& poses) {
  YAML::Emitter o;
  o << YAML::BeginSeq;
  for (std::size_t j = 0; j < poses.size(); ++j) {
    const PoseOfPlan& p = poses[j];
    o << YAML::Flow << YAML::BeginMap << YAML::Key << "pose" << YAML::Value << j + 1;
    for (int k = 0; k < Kind::kPoseDim; ++k) {
      o << YAML::Key << Kind::kPoseNames[k] << YAML::Value << YamlNumber{p.q(k)};
    }
    const std::pair<const char*, const Eigen::VectorXd*> columns[3] = {
        {"t", &p.tensions_N}, {"l", &p.lengths_m}, {"dl", &p.length_change_m}};
    for (const auto& [prefix, values] : columns) {
      for (Eigen::Index i = 0; i < values->size(); ++i) {
        o << YAML::Key << prefix + std::to_string(i + 1) << YAML::Value << YamlNumber{(*values)(i)};
      }
    }
    o << YAML::EndMap;
  }
  o << YAML::EndSeq;
  return YamlText(o);
}

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

// The plan checks' length test, shared by both kinds: InputError naming `where` and column
// l<cable+1> when the plan's length differs from the model's by more than tolerance_m.
void RequirePlanLength(const std::string& where, const std::string& robot_name, int cable, double model_length_m,
                       double plan_length_m, double tolerance_m);

// The plan checks' tension and equilibrium tests, shared by both kinds: InputError naming
// `where` and column t<i> for a negative tension (no cable pushes; checked first, as an
// equilibrium held by a pushing cable is no plan's), then the columns `pose_columns`,t1..tm when
// |W t + w_g| = residual_N exceeds 1e-6 of the weight.
void RequirePlanEquilibrium(const std::string& where, const std::string& robot_name, const Eigen::VectorXd& tensions_N,
                            double residual_N, double weight_N, const std::string& pose_columns);

}  // namespace cablecal
