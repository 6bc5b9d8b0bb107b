// The robot description: constant data, loaded and validated once (Pinocchio's "Model").
// Frames: F is the workspace frame (x right, z up, z = 0 the floor); P is the platform
// frame (origin at the platform reference point p, x along the bar). SI units throughout;
// angles in rad inside the program (the file's *_deg keys are converted on loading).
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

#include "common/error.h"

namespace YAML {
class Emitter;
}

namespace cablecal {

// The side of its pulley a cable arrives on. kLeft: the cable runs up the post on the
// pulley's -x side, so the pulley centre is at exit + (r, 0); kRight mirrors it.
enum class PulleySide { kLeft, kRight };

// +1 for kLeft, -1 for kRight: the pulley centre is at exit + SideSign * (r, 0).
inline double SideSign(PulleySide side) { return side == PulleySide::kLeft ? 1.0 : -1.0; }

// How a cable wraps its pulley. kOver: it runs up the post and over the top of the pulley
// toward the platform (a pulley above the platform); kUnder is the mirror image in z: down
// the post and under the bottom (a pulley below the platform, fully constrained robots).
enum class PulleyWrap { kOver, kUnder };

// +1 for kOver, -1 for kUnder: the z axis of the mirrored pulley frame (model/cable.h).
inline double WrapSign(PulleyWrap wrap) { return wrap == PulleyWrap::kOver ? 1.0 : -1.0; }

// The cable count lives in Robot::cables alone; every stage sizes its vectors and matrices
// from num_cables() (README, "Any number of cables"). These bound it: the loader enforces
// them, and fixed-capacity scratch arrays in the model rely on the upper one.
constexpr int kMinCables = 2;
constexpr int kMaxCables = 8;

// f(std::integral_constant<int, M>{}) for the run-time cable count M: the one switch from a
// count to the compile-time instances (identify's solver, design's robust constraints), so
// that a change of kMinCables..kMaxCables is made here alone.
template <typename F>
decltype(auto) WithCableCount(int num_cables, F&& f) {
  static_assert(kMinCables == 2 && kMaxCables == 8, "one case per cable count below");
  switch (num_cables) {
    case 2: return f(std::integral_constant<int, 2>{});
    case 3: return f(std::integral_constant<int, 3>{});
    case 4: return f(std::integral_constant<int, 4>{});
    case 5: return f(std::integral_constant<int, 5>{});
    case 6: return f(std::integral_constant<int, 6>{});
    case 7: return f(std::integral_constant<int, 7>{});
    case 8: return f(std::integral_constant<int, 8>{});
  }
  CABLECAL_CHECK(false, "the robot loader keeps kMinCables to kMaxCables cables");
  std::abort();
}

// The robot file gives angles in degrees (its *_deg keys); the program works in radians.
constexpr double kDegToRad = M_PI / 180.0;
// Upper bounds of the robot file's sizes (README, "Robot file"): far beyond any robot this
// tool is for, so that a unit slip (981 for 9.81, a frame in mm) is refused by name.
constexpr double kMaxGravity_mps2 = 100.0;
constexpr double kMaxFrameSide_m = 100.0;
constexpr double kMaxPlatformMass_kg = 10000.0;

// The least cable stiffness E*A a robot file (either kind) accepts, as a multiple of
// tension.max: a cable stretching more than a tenth of its length at the largest tension is a
// unit slip (kN typed for N), not a cable.
constexpr double kMinStiffnessOverMaxTension = 10.0;

struct Cable {
  Eigen::Vector2d p_F_exit_m;        // exit point A_i: the pulley's outermost point at centre height
  double pulley_radius_m = 0.0;
  PulleySide side = PulleySide::kLeft;
  PulleyWrap wrap = PulleyWrap::kOver;
  Eigen::Vector2d p_P_anchor_m;      // anchor b_i on the platform, platform frame
  std::optional<double> initial_length_m;  // overrides the length at the home pose
  // E*A (N): a cable of unstretched length L is L (1 + t / EA) long under tension t. Absent:
  // inextensible. Only the forward model (model/forward_statics.h) uses it.
  std::optional<double> stiffness_N;
};

// The unstretched length L of a cable l long under tension t, l = L (1 + t / EA), for either
// kind's cable (its stiffness E*A, absent for an inextensible cable: L = l).
template <typename T>
T UnstretchedLength(const std::optional<double>& stiffness_N, const T& length_m, const T& tension_N) {
  if (!stiffness_N) return length_m;
  return length_m / (T(1.0) + tension_N / T(*stiffness_N));
}

// Its inverse for a cable of unstretched length L stretched to l: t = EA (l / L - 1) while
// l > L, 0 when slack (a cable does not push).
template <typename T>
T ElasticTension(double stiffness_N, const T& length_m, const T& unstretched_length_m) {
  const T strain = length_m / unstretched_length_m - T(1.0);
  return strain > T(0.0) ? T(stiffness_N) * strain : T(0.0);
}

// The sensors' systematic errors (README, "Sensor error models"; the formulas are in
// model/sensor_model.h): what a bench test fits and what is left once they are removed is the
// random noise below. All zero when the robot file gives none, so older files and every
// result made from them are unchanged.
struct SystematicSensorErrors {
  double laser_offset_m = 0.0;                    // laser reading - true height, everywhere
  double inclinometer_offset_rad = 0.0;           // inclinometer error at theta = 0
  double inclinometer_sec_coefficient_rad = 0.0;  // k of k (sec theta - 1)
  bool any() const {
    return laser_offset_m != 0.0 || inclinometer_offset_rad != 0.0 || inclinometer_sec_coefficient_rad != 0.0;
  }
};

struct SensorNoise {
  // Each +- range of the paper is three standard deviations of a zero-mean Gaussian.
  double laser_accuracy_m = 0.0;
  double laser_repeatability_m = 0.0;
  double inclinometer_accuracy_rad = 0.0;
  double inclinometer_repeatability_rad = 0.0;
  double encoder_sigma_m = 0.0;  // one standard deviation (not a range)
  // Laser-tracker measurement of the exit points, one standard deviation per coordinate;
  // used by the identification's `prior` gauge. Optional in the file.
  std::optional<double> tracker_sigma_m;
  // Optional in the file (sensors.laser.offset, sensors.inclinometer.offset_deg and
  // sec_coefficient_deg); simulate adds them only when asked, identify removes them.
  SystematicSensorErrors systematic;

  // Standard deviation of one reading: accuracy and repeatability are drawn separately
  // (each range = 3 sigma) and added, so their variances add.
  double laser_sigma_m() const { return std::hypot(laser_accuracy_m, laser_repeatability_m) / 3.0; }
  double inclinometer_sigma_rad() const {
    return std::hypot(inclinometer_accuracy_rad, inclinometer_repeatability_rad) / 3.0;
  }
};

// The centre of mass's uncertainty per axis (m) when the robot file gives no
// platform.com_sigma: a centre of mass from CAD, known to 5 mm (planar and spatial robots).
constexpr double kDefaultComSigma_m = 0.005;

struct Robot {
  std::string name;
  std::string source;  // where it was loaded from, for messages ("<built-in>" or a path)
  double gravity_mps2 = 9.81;
  double frame_width_m = 0.0;
  double frame_height_m = 0.0;
  double platform_mass_kg = 0.0;
  Eigen::Vector2d p_P_com_m = Eigen::Vector2d::Zero();
  // Optional in the file (platform.com_sigma): the centre of mass's uncertainty per axis, m,
  // the sigma of a 2-cable identification's equilibrium rows (identify/identify.h).
  std::optional<double> com_sigma_m;
  std::vector<Cable> cables;
  double tension_min_N = 0.0;
  double tension_max_N = 0.0;
  double theta_max_rad = 0.0;  // inclinometer range
  double laser_range_m = 0.0;  // largest measurable platform height z
  double margin_m = 0.0;       // platform points keep this distance from the frame
  Eigen::Vector2d p_F_home_m = Eigen::Vector2d::Zero();  // home (x, z)
  // Home orientation for m >= 3 (the file's home_theta_deg). With 2 cables the equilibrium
  // decides theta and this stays 0.
  double home_theta_rad = 0.0;
  SensorNoise sensors;

  int num_cables() const { return static_cast<int>(cables.size()); }
  // With 2 cables the statics fix theta at a position (x, z); with 3 or more the lengths fix
  // the whole pose and theta is free within the band where the tensions stay within bounds.
  bool theta_is_free() const { return num_cables() >= 3; }
};

// Parses and validates a robot file. Throws InputError naming file, line and key on any
// problem: missing or unknown key, wrong type, non-finite or out-of-range value,
// coincident anchors, tension min >= max, or a home pose outside the feasible workspace.
// Exit points lie on the frame to within this: a calibrated or true robot's exit points sit a
// few millimetres off the nominal frame, a typo or a unit error far more (the robot-file loader
// and the identification's plausibility check both use it).
constexpr double kExitOffFrameTolerance_m = 0.1;

// Refuses files larger than kMaxRobotFileBytes and anything that is not a regular file.
Robot LoadRobotFile(const std::string& path);
constexpr std::uintmax_t kMaxRobotFileBytes = 1 << 20;

// The same from YAML text; `source` names it in messages.
Robot LoadRobotFromString(const std::string& yaml_text, const std::string& source);

// The built-in robot: robots/wang2022.yaml, compiled into the binary.
const Robot& BuiltinRobot();
const std::string& BuiltinRobotYaml();

// Serialises a robot back to YAML in the file format (used for calibrated robots and
// truth files); LoadRobotFromString(RobotToYaml(r)) reproduces r.
std::string RobotToYaml(const Robot& robot);
// The same fields into an open block map of `out` (a truth file adds its own after them).
void EmitRobotFields(YAML::Emitter& out, const Robot& robot);
// The value of the file's `sensors:` key, as EmitRobotFields writes it (the sensors fit's
// output is this block, so that it pastes into a robot file as is).
void EmitSensors(YAML::Emitter& out, const SensorNoise& sensors);

}  // namespace cablecal
