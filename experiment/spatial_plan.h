// A spatial robot's pose plan (README, "Spatial robots"): measurement poses, each an
// equilibrium of the nominal robot with its tensions, cable lengths and encoder commands from
// home; random feasible poses (sample); the plan CSV's writer, reader and check against a robot.
// Depends on model/ (the spatial statics and forward model).
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <istream>
#include <string>
#include <vector>

#include "model/kind.h"
#include "model/spatial_robot.h"
#include "model/spatial_statics.h"

namespace cablecal {

struct SpatialPlanPose {
  SpatialPose<double> q = SpatialPose<double>::Zero();  // an equilibrium of the nominal robot
  Eigen::VectorXd tensions_N;
  Eigen::VectorXd lengths_m;        // l_i, exit point -> anchor along the cable
  // dl_i: the encoder command from home, the change of the cable paid out (the unstretched
  // length, model/forward_statics.h CommandedUnstretchedLengths; the length itself for an
  // inextensible cable) from its value at the home equilibrium.
  Eigen::VectorXd length_change_m;
};

// The home equilibrium (EvaluateSpatialHome; SolverFailure naming the robot when it has none)
// and the cables' paid-out lengths there, where the encoders read zero (a cable's
// initial_length where the robot file gives one: a calibrated robot's identified l_i0).
struct SpatialHomeReference {
  SpatialEquilibrium equilibrium;
  Eigen::VectorXd paid_out_m;
};
SpatialHomeReference SpatialHome(const SpatialRobot& robot);

SpatialPlanPose MakeSpatialPlanPose(const SpatialRobot& robot, const SpatialEquilibrium& equilibrium,
                                    const SpatialHomeReference& home);

// The default yaw range of sample: +-30 degrees around home's yaw. A lab calibrates over the
// yaws it works at; turning further mostly winds cables round each other on suspended robots.
constexpr double kDefaultSampleYawRange_rad = 30.0 * M_PI / 180.0;

// n poses drawn uniformly over the feasible region by rejection: (x, y, z) uniform in the frame
// box shrunk by the margin, roll and pitch uniform in +-tilt_max, yaw uniform in home's yaw
// +-yaw_range_rad, each draw kept when EvaluateSpatialPose calls it feasible. With fewer than 6
// cables only the controlled coordinates (ControlledCoordinates) are the draw's; the others
// are home's as the solver's first guess and come out of the equilibrium. Six uniforms are drawn
// per candidate whatever the cable count, from Rng(seed), and candidates are evaluated in
// batches in parallel but kept in draw order: the plan does not depend on the thread count.
// InputError for n < 1 or a yaw range outside (0, pi]; SolverFailure if no more than n - 1
// feasible poses turn up in 10 (10000 + 1000 n) draws: an empty or tiny workspace.
std::vector<SpatialPlanPose> SampleSpatialPoses(const SpatialRobot& robot, int n, std::uint64_t seed,
                                                double yaw_range_rad = kDefaultSampleYawRange_rad);

// The peer's pose set, side^3 poses (side 2 or 3: the 2x2x2 and 3x3x3 grids that a published
// self-calibration, Zoffoli, Ida and Carricato, Robotica 2025, picks its 8 and 27 poses from),
// as cablecal builds it: the constant-orientation workspace at home's orientation on its
// default grid (workspace/spatial_workspace.h), the bounding box of its feasible points, the
// centres of the box's side x side x side equal cells (x innermost, then y, then z), and for
// each centre in that order the nearest feasible workspace point not taken yet (ties to the
// lower grid index): an evenly spaced set of positions, each made statically feasible. With
// fewer than 6 cables the positions and home's yaw are the controlled coordinates; roll and
// pitch follow from the equilibrium. No random draw: the same set every time. InputError for
// a side outside 2..4; SolverFailure when the workspace has fewer than side^3 feasible points.
std::vector<SpatialPlanPose> GridSpatialPoses(const SpatialRobot& robot, int side);

// Plan CSV: pose,x,y,z,roll,pitch,yaw,t1..tm,l1..lm,dl1..dlm (m, rad, N), poses numbered from 1.
std::string SpatialPlanCsv(const std::vector<SpatialPlanPose>& plan, const std::string& provenance);
// Reads it; '#' lines are comments. InputError naming file, line and column on a wrong header
// (another cable count, a planar plan), a bad number, a duplicate or non-positive pose id; at
// most kMaxPlanPoses rows (experiment/plan.h). `pose_ids`, when given, receives each row's pose
// id (simulate numbers its readings by it, and identify --plan matches them by it).
std::vector<SpatialPlanPose> ReadSpatialPlanCsv(const std::string& path, int num_cables,
                                                std::vector<int>* pose_ids = nullptr);
std::vector<SpatialPlanPose> ReadSpatialPlanCsv(std::istream& in, const std::string& name, int num_cables,
                                                std::vector<int>* pose_ids = nullptr);

// A plan read from a file must be one of `robot`'s: p inside the frame box, the tilt within
// tilt_max, each pose an equilibrium of its statics with the plan's tensions (residual below
// 1e-6 of the weight), and the lengths and commands those of its model (1e-6 m). InputError
// naming the file, the pose and the column otherwise.
void CheckSpatialPlanMatchesRobot(const SpatialRobot& robot, const std::vector<SpatialPlanPose>& plan,
                                  const std::string& source);

}  // namespace cablecal
