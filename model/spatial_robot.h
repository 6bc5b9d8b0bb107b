// The spatial robot description: constant data, loaded and validated once, as Robot is for the
// planar kind (model/robot.h). A robot file with `kind: spatial` (README, "Spatial robots").
// Frames: F is the workspace frame (z up, gravity along -z; the frame box is given in it); P is
// the platform frame (origin at the platform reference point p). Pose and orientation
// convention: model/kind.h (SpatialPose, R = Rz(yaw) Ry(pitch) Rx(roll)). SI units throughout;
// angles in rad inside the program (the file's *_deg keys are converted on loading). The cable
// geometry (swivel pulleys) is model/swivel.h.
// Depends on Eigen, model/kind.h and model/robot.h (the planar robot, for the conversion and
// the shared bounds).
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "model/kind.h"
#include "model/robot.h"

namespace cablecal {

// The cable count of a spatial robot file: at least 3 (fewer hold a platform in space only on
// a line through their common exit region), at most 12 (the largest robots built have 8 to 12).
constexpr int kMinSpatialCables = 3;
constexpr int kMaxSpatialCables = 12;

struct SpatialCable {
  // D_i in F: where the cable, arriving along the swivel axis, first touches the pulley; it
  // stays put as the pulley swivels (the pulley turns about the line through D_i along k_i).
  Eigen::Vector3d p_F_exit_m = Eigen::Vector3d::Zero();
  // k_i in F, unit: the direction in which the cable travels as it arrives at D_i (from the
  // winch). Normalised on loading.
  Eigen::Vector3d k_F_swivel_axis = Eigen::Vector3d::UnitZ();
  double pulley_radius_m = 0.0;        // 0: an eyelet, the cable runs straight from D_i
  // E*A (N): a cable of unstretched length L is L (1 + t / EA) long under tension t. Absent:
  // inextensible.
  std::optional<double> stiffness_N;
  // The cable paid out at home, where the encoder reads zero (m): what an identification
  // estimates as l_i0 (identify --calibrated-robot writes it). Absent: the model's, the
  // home equilibrium's length (unstretched for a cable with a stiffness).
  std::optional<double> initial_length_m;
  Eigen::Vector3d p_P_anchor_m = Eigen::Vector3d::Zero();  // b_i in P
};

// A sensor given by two +- ranges, each three standard deviations of a zero-mean Gaussian
// drawn separately for every reading (as the planar robot file's laser and inclinometer).
// Units: the sensor's (m, rad or N); the file gives degrees for angles.
struct RangedNoise {
  double accuracy = 0.0;
  double repeatability = 0.0;
  // Standard deviation of one reading: the two draws add, so their variances add.
  double sigma() const { return std::hypot(accuracy, repeatability) / 3.0; }
};

// The sensors of a spatial robot (README, "Spatial robots"). Only the encoders are required.
struct SpatialSensors {
  double encoder_sigma_m = 0.0;               // one standard deviation, every cable
  std::optional<RangedNoise> inclinometer_rad;  // 2-axis: roll and pitch of the pose
  std::optional<RangedNoise> laser_m;         // height of p above the floor z = frame min z
  struct Position {                           // a tracker reading the point `target` of P in F
    RangedNoise noise_m;
    Eigen::Vector3d p_P_target_m = Eigen::Vector3d::Zero();  // optional in the file: default p
  };
  std::optional<Position> position;
  std::optional<RangedNoise> swivel_rad;      // swivel-angle encoders, relative to home
  std::optional<RangedNoise> heading_rad;     // an IMU's yaw, relative to home
  std::optional<RangedNoise> load_cell_N;     // cable tensions, every cable
  std::optional<double> tracker_sigma_m;      // a prior on the exit points, per coordinate
};

struct SpatialRobot {
  std::string name;
  std::string source;  // where it was loaded from, for messages
  double gravity_mps2 = 9.81;
  // The box the platform must stay inside, in F.
  Eigen::Vector3d p_F_frame_min_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d p_F_frame_max_m = Eigen::Vector3d::Zero();
  double platform_mass_kg = 0.0;
  Eigen::Vector3d p_P_com_m = Eigen::Vector3d::Zero();
  // Optional in the file (platform.mass_sigma, platform.com_sigma): how well the mass (kg) and
  // the centre of mass (m, per axis) are known, one standard deviation; the spatial
  // identification's priors on them and the Monte Carlo's spread of true platforms
  // (SpatialPlatformPriorSigma below).
  std::optional<double> mass_sigma_kg;
  std::optional<double> com_sigma_m;
  std::vector<SpatialCable> cables;
  double tension_min_N = 0.0;
  double tension_max_N = 0.0;
  double tilt_max_rad = 0.0;  // largest angle between P's z axis and F's z axis
  double margin_m = 0.0;      // every platform point keeps this distance from the frame box
  Eigen::Vector3d p_F_home_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d home_rpy_rad = Eigen::Vector3d::Zero();  // (roll, pitch, yaw) at home
  SpatialSensors sensors;

  int num_cables() const { return static_cast<int>(cables.size()); }
  // The platform's mass and centre of mass: the platform's 4 values the statics read.
  Eigen::Vector4d platform_values() const { return {platform_mass_kg, p_P_com_m.x(), p_P_com_m.y(), p_P_com_m.z()}; }
  SpatialPose<double> home_pose() const {
    SpatialPose<double> q;
    q << p_F_home_m, home_rpy_rad;
    return q;
  }
};

// The bound on a swivel axis's length before normalising: shorter is no direction (a zero
// typed for an axis), refused by the loader.
constexpr double kMinSwivelAxisLength = 1e-9;

// Parses and validates a spatial robot file (format: README, "Spatial robots"). Throws one
// InputError naming file, line and key on any problem: a missing, unknown or repeated key, a
// wrong type, a non-finite or out-of-range value, a swivel axis of zero length, an exit point
// more than kExitOffFrameTolerance_m outside the frame box, fewer than kMinSpatialCables or
// more than kMaxSpatialCables cables, an anchor count other than the cable count, anchors all
// on one line, tension min <= 0 or >= max, and a home pose outside the frame, beyond the tilt
// limit, with a platform point within the margin of the frame box or with invalid cable
// geometry (model/swivel.h). A file without `kind: spatial` is refused by its kind.
SpatialRobot LoadSpatialRobotFile(const std::string& path);
SpatialRobot LoadSpatialRobotFromString(const std::string& yaml_text, const std::string& source);

// The kind a robot file declares (its `kind` key alone; absent: planar). Throws InputError
// for a file that cannot be read, is not YAML, or names another kind.
RobotKind RobotKindOfFile(const std::string& path);
RobotKind RobotKindOfText(const std::string& yaml_text, const std::string& source);

// Serialises a spatial robot in the file format; LoadSpatialRobotFromString of the text gives
// the robot back (the swivel axes as stored: unit).
std::string SpatialRobotToYaml(const SpatialRobot& robot);

// The depth of the frame box a planar robot gets in y when made spatial (PlanarAsSpatial):
// the planar model has none; a box 1 m deep keeps every platform point, at y = 0, half a
// metre from it.
constexpr double kPlanarAsSpatialDepth_m = 1.0;

// A planar robot as the spatial robot it is, in the plane y = 0 of F: exit D_i = (a_x, 0, a_z),
// swivel axis k = +z (wrap: over, the cable arrives travelling up) or -z (wrap: under,
// travelling down), anchors (b_x, 0, b_z), centre of mass likewise, the frame box
// [0, width] x [-depth/2, depth/2] x [0, height], home (x, 0, z) with pitch -theta (the
// planar pose (x, z, theta) is the spatial (x, 0, z, 0, -theta, 0)); 2-cable robots take theta
// from the home equilibrium. Sensors: encoder, laser, inclinometer and tracker as given.
// The swivel pulley equals the planar one wherever the anchor is on the pulley's inner side,
// s_i (B_x - a_x) > 0; beyond it the swivel pulley turns round and the planar one wraps on.
// Keeps the cable count, so a 2-cable robot makes a SpatialRobot the robot file would refuse
// (fewer than kMinSpatialCables): the model's functions take any count.
SpatialRobot PlanarAsSpatial(const Robot& planar);

// The mass's prior sigma when the robot file gives no platform.mass_sigma: this fraction of the
// mass (a platform weighed, its cables and fittings estimated: 1 %).
constexpr double kDefaultMassSigmaRelative = 0.01;
// How well the platform's mass (kg) and centre of mass (m, each axis) are known: the robot
// file's platform.mass_sigma and platform.com_sigma, else kDefaultMassSigmaRelative of the mass
// and kDefaultComSigma_m (model/robot.h).
inline Eigen::Vector4d SpatialPlatformPriorSigma(const SpatialRobot& robot) {
  const double com_sigma_m = robot.com_sigma_m.value_or(kDefaultComSigma_m);
  return {robot.mass_sigma_kg.value_or(kDefaultMassSigmaRelative * robot.platform_mass_kg), com_sigma_m, com_sigma_m,
          com_sigma_m};
}

}  // namespace cablecal
