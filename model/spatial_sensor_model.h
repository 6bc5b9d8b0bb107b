// The spatial robot's sensors (README, "Spatial robots"): what each reads of a pose, written
// once on the scalar type T (doubles for simulate, ceres::Jet for identification), their CSV
// columns, and their noise from the robot file. The encoders, which every reading has, read
// the cables' paid-out lengths (experiment/spatial_plan.h).
//
// The relative sensors (swivel encoders, heading) are zeroed with the encoders, at the home
// pose the platform actually holds: a SpatialSensorZero taken there.
// Depends on Eigen, model/kind.h, model/spatial_robot.h and model/swivel.h.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "model/kind.h"
#include "model/spatial_robot.h"
#include "model/swivel.h"
#include "model/vectors.h"

namespace cablecal {

// The spatial sensors besides the encoders, in the order of the measurement CSV's columns
// and of the simulation's noise draws.
enum class SpatialSensor : int { kInclinometer = 0, kLaser, kPosition, kSwivel, kHeading, kLoadCell };
inline constexpr int kNumSpatialSensors = 6;
inline constexpr std::array<SpatialSensor, kNumSpatialSensors> kSpatialSensors = {
    SpatialSensor::kInclinometer, SpatialSensor::kLaser,   SpatialSensor::kPosition,
    SpatialSensor::kSwivel,       SpatialSensor::kHeading, SpatialSensor::kLoadCell};

// The robot file's name of the sensor (sensors.<name>): "inclinometer", ..., "load_cell".
inline const char* ToString(SpatialSensor s) {
  switch (s) {
    case SpatialSensor::kInclinometer: return "inclinometer";
    case SpatialSensor::kLaser: return "laser";
    case SpatialSensor::kPosition: return "position";
    case SpatialSensor::kSwivel: return "swivel";
    case SpatialSensor::kHeading: return "heading";
    case SpatialSensor::kLoadCell: return "load_cell";
  }
  return "?";
}

// The SI unit of the sensor's values: m (laser, position), N (load cells), rad (the angles).
inline const char* SpatialSensorUnit(SpatialSensor s) {
  switch (s) {
    case SpatialSensor::kLaser:
    case SpatialSensor::kPosition: return "m";
    case SpatialSensor::kLoadCell: return "N";
    default: return "rad";
  }
}

// How many values one reading of the sensor has on a robot of m cables.
inline int SpatialSensorSize(SpatialSensor s, int num_cables) {
  switch (s) {
    case SpatialSensor::kInclinometer: return 2;
    case SpatialSensor::kLaser: return 1;
    case SpatialSensor::kPosition: return 3;
    case SpatialSensor::kSwivel: return num_cables;
    case SpatialSensor::kHeading: return 1;
    case SpatialSensor::kLoadCell: return num_cables;
  }
  return 0;
}

// Its CSV columns: roll,pitch / z / px,py,pz / sw1..swm / yaw / f1..fm (rad, m, m, rad, rad, N).
inline std::vector<std::string> SpatialSensorColumns(SpatialSensor s, int num_cables) {
  const auto numbered = [num_cables](const char* prefix) {
    std::vector<std::string> c;
    for (int i = 1; i <= num_cables; ++i) c.push_back(prefix + std::to_string(i));
    return c;
  };
  switch (s) {
    case SpatialSensor::kInclinometer: return {"roll", "pitch"};
    case SpatialSensor::kLaser: return {"z"};
    case SpatialSensor::kPosition: return {"px", "py", "pz"};
    case SpatialSensor::kSwivel: return numbered("sw");
    case SpatialSensor::kHeading: return {"yaw"};
    case SpatialSensor::kLoadCell: return numbered("f");
  }
  return {};
}

// The robot file's noise of the sensor; nullopt when the robot has no such sensor.
inline std::optional<RangedNoise> SpatialSensorNoise(const SpatialSensors& sensors, SpatialSensor s) {
  switch (s) {
    case SpatialSensor::kInclinometer: return sensors.inclinometer_rad;
    case SpatialSensor::kLaser: return sensors.laser_m;
    case SpatialSensor::kPosition:
      return sensors.position ? std::optional<RangedNoise>(sensors.position->noise_m) : std::nullopt;
    case SpatialSensor::kSwivel: return sensors.swivel_rad;
    case SpatialSensor::kHeading: return sensors.heading_rad;
    case SpatialSensor::kLoadCell: return sensors.load_cell_N;
  }
  return std::nullopt;
}

inline bool HasSpatialSensor(const SpatialRobot& robot, SpatialSensor s) {
  return SpatialSensorNoise(robot.sensors, s).has_value();
}

// The readings a robot with these sensors takes: "encoder", then each sensor it has in
// SpatialSensor order (the tracker is a prior on the exit points, not a reading).
inline std::vector<std::string> SpatialSensorNames(const SpatialSensors& sensors) {
  std::vector<std::string> names = {"encoder"};
  for (const SpatialSensor s : kSpatialSensors) {
    if (SpatialSensorNoise(sensors, s)) names.push_back(ToString(s));
  }
  return names;
}

// The sensors with only the named ones of kSpatialSensors kept (by their robot-file names), the
// encoders and the tracker's prior as they are: how a study calibrates with a subset of what a
// robot file carries. A named sensor the file lacks stays absent.
inline SpatialSensors KeepSpatialSensors(const SpatialSensors& sensors, const std::vector<std::string>& keep) {
  const auto kept = [&keep](SpatialSensor s) { return std::find(keep.begin(), keep.end(), ToString(s)) != keep.end(); };
  SpatialSensors out = sensors;
  if (!kept(SpatialSensor::kInclinometer)) out.inclinometer_rad.reset();
  if (!kept(SpatialSensor::kLaser)) out.laser_m.reset();
  if (!kept(SpatialSensor::kPosition)) out.position.reset();
  if (!kept(SpatialSensor::kSwivel)) out.swivel_rad.reset();
  if (!kept(SpatialSensor::kHeading)) out.heading_rad.reset();
  if (!kept(SpatialSensor::kLoadCell)) out.load_cell_N.reset();
  return out;
}

// An angle wrapped into (-pi, pi], through atan2 so that Jets carry its derivative (1).
template <typename T>
T WrappedAngle(const T& angle_rad) {
  using std::atan2;
  using std::cos;
  using std::sin;
  return atan2(sin(angle_rad), cos(angle_rad));
}

// The 2-axis inclinometer: roll and pitch of the pose (model/kind.h: gravity in P does not
// depend on yaw, so these are what a gravity sensor on the platform reads).
template <typename T>
Vec2<T> InclinometerReading(const SpatialPose<T>& q) {
  return Vec2<T>(q(3), q(4));
}

// The vertical laser: the height of the reference point p above the floor z = floor_z_m (the
// frame box's bottom).
template <typename T>
T LaserReading(const SpatialPose<T>& q, double floor_z_m) {
  return q(2) - T(floor_z_m);
}

// A tracker (laser tracker, motion capture) reading the platform point `target` (in P) in F:
// p + R target.
template <typename T>
Vec3<T> PositionReading(const SpatialPose<T>& q, const Eigen::Matrix<T, 3, 3>& R, const Vec3<T>& p_P_target_m) {
  return AnchorInF<T>(q, R, p_P_target_m);
}

// An IMU's heading: the yaw relative to its zero, wrapped into (-pi, pi] (a platform turned
// by 190 degrees reads -170).
template <typename T>
T HeadingReading(const SpatialPose<T>& q, const T& zero_yaw_rad) {
  return WrappedAngle<T>(q(5) - zero_yaw_rad);
}

// A swivel-angle encoder: the angle of the pulley plane's u about k from its zero u_zero
// (model/swivel.h, SwivelAngle). An eyelet has no pulley to turn: its u is still the direction
// of the anchor off the axis, which is what a swivelling eyelet's encoder would read.
template <typename T>
T SwivelReading(const SwivelCableState<T>& cable, const Vec3<T>& k_F_swivel_axis, const Vec3<T>& u_F_zero) {
  return SwivelAngle<T>(k_F_swivel_axis, u_F_zero, cable.u_F);
}

// Where the relative sensors read zero: each cable's u and the yaw at the pose where they
// were zeroed (the home pose the platform holds).
struct SpatialSensorZero {
  std::vector<Eigen::Vector3d> u_F;  // per cable
  double yaw_rad = 0.0;
};
inline SpatialSensorZero SensorZeroAt(const SpatialRobot& robot, const SpatialPose<double>& q_zero) {
  const Eigen::Matrix3d R = Rotation<double>(q_zero);
  SpatialSensorZero zero;
  for (const SpatialCable& c : robot.cables) zero.u_F.push_back(SwivelCableAtPose<double>(c, q_zero, R).u_F);
  zero.yaw_rad = q_zero(5);
  return zero;
}

// Every sensor's noise-free reading at pose q with cable tensions t, whether the robot has the
// sensor or not, indexed by SpatialSensor (each SpatialSensorSize values).
template <typename T>
std::array<Eigen::Matrix<T, Eigen::Dynamic, 1>, kNumSpatialSensors> SpatialSensorReadings(
    const SpatialRobot& robot, const SpatialPose<T>& q, const Eigen::Matrix<T, Eigen::Dynamic, 1>& tensions_N,
    const SpatialSensorZero& zero) {
  using VecX = Eigen::Matrix<T, Eigen::Dynamic, 1>;
  const int m = robot.num_cables();
  const Eigen::Matrix<T, 3, 3> R = Rotation<T>(q);
  std::array<VecX, kNumSpatialSensors> out;
  out[static_cast<int>(SpatialSensor::kInclinometer)] = InclinometerReading<T>(q);
  out[static_cast<int>(SpatialSensor::kLaser)] = VecX::Constant(1, LaserReading<T>(q, robot.p_F_frame_min_m.z()));
  const Eigen::Vector3d target =
      robot.sensors.position ? robot.sensors.position->p_P_target_m : Eigen::Vector3d::Zero();
  out[static_cast<int>(SpatialSensor::kPosition)] = PositionReading<T>(q, R, target.cast<T>());
  VecX swivel(m);
  for (int i = 0; i < m; ++i) {
    const SpatialCable& c = robot.cables[i];
    swivel(i) = SwivelReading<T>(SwivelCableAtPose<T>(c, q, R), c.k_F_swivel_axis.cast<T>(), zero.u_F[i].cast<T>());
  }
  out[static_cast<int>(SpatialSensor::kSwivel)] = swivel;
  out[static_cast<int>(SpatialSensor::kHeading)] = VecX::Constant(1, HeadingReading<T>(q, T(zero.yaw_rad)));
  out[static_cast<int>(SpatialSensor::kLoadCell)] = tensions_N;
  return out;
}

}  // namespace cablecal
