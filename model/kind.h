// The kinds of robot cablecal serves, in one place: what a pose is (its coordinates, their
// names and units), what a point is (its dimension), what a wrench is, and the layout of the
// geometry a calibration identifies (model/geometry.h). The stages read a kind's numbers and
// names; none spells a pose's size or a point's. Two kinds: planar (the stages serve it) and
// spatial (a 6-DoF pose, 3-D points; so far the robot file and the model, model/swivel.h).
// Depends on model/geometry.h and Eigen.
#pragma once

#include <Eigen/Core>
#include <array>
#include <vector>

#include "model/geometry.h"

namespace cablecal {

// Which kind a robot file describes: its `kind` key, planar when absent (the files written
// before spatial robots existed). RobotKindOfFile (model/spatial_robot.h) reads it.
enum class RobotKind { kPlanar, kSpatial };
inline const char* ToString(RobotKind kind) { return kind == RobotKind::kPlanar ? "planar" : "spatial"; }

// The planar robot: the platform moves in the x-z plane of F (z up); pose (x, z, theta), theta
// the platform's angle, counter-clockwise from F's x axis. Wrench (f_x, f_z, moment about p),
// the moment positive counter-clockwise (x toward z): the spatial moment's -m_y.
struct PlanarKind {
  static constexpr int kPoseDim = 3;
  static constexpr int kPointDim = kPlanarPointDim;
  static constexpr std::array<const char*, kPoseDim> kPoseNames = {"x", "z", "theta"};
  static constexpr std::array<const char*, kPoseDim> kPoseUnits = {"m", "m", "rad"};
  // The platform's wrench (f_x, f_z, moment about y): the rows of the wrench matrix and of a
  // pose's equilibrium W t + w_g = 0.
  static constexpr int kWrenchDim = 3;
  static constexpr GeometryLayout Layout(int num_cables) { return PlanarLayout(num_cables); }
  // The gauge (README, "The gauge problem"): encoders, laser and inclinometer see nothing of a
  // horizontal shift of every exit point and pose together, so the default gauge holds exit 1's
  // x (a1x) at its nominal value. These are the entries held, in increasing order; their count
  // is the number of null directions the identification expects when nothing is held.
  static std::vector<int> HeldByDefault(const GeometryLayout& layout) { return {layout.exit(0, 0)}; }
  // The entries it leaves free, in increasing order: the geometry columns of the gauge-fixed
  // Jacobian (identify/jacobian.h, design/) and of a prior's covariance (design --prior).
  static std::vector<int> FreeByDefault(const GeometryLayout& layout) {
    const std::vector<int> held = HeldByDefault(layout);
    std::vector<int> free;
    for (int k = 0, h = 0; k < layout.size(); ++k) {
      if (h < static_cast<int>(held.size()) && held[h] == k) {
        ++h;
      } else {
        free.push_back(k);
      }
    }
    return free;
  }
};

// Platform pose of the planar kind, doubles: (x_m, z_m, theta_rad) (model/cable.h's Pose<double>).
using PlanarPose = Eigen::Matrix<double, PlanarKind::kPoseDim, 1>;
// Its coordinates as plain numbers, where a solver keeps them (Ceres' parameter blocks).
using PlanarPoseValues = std::array<double, PlanarKind::kPoseDim>;

// A spatial pose q = (x, y, z, roll, pitch, yaw): the platform reference point p in F (m) and
// its orientation R = Rz(yaw) Ry(pitch) Rx(roll) (rad), so that a platform point b (in P) is
// B = p + R b in F. A 2-axis inclinometer reads roll and pitch of this parameterisation exactly
// (gravity in P does not depend on yaw). The planar pose (x, z, theta) is (x, 0, z, 0, -theta, 0):
// theta turns x toward z, a rotation about -y.
template <typename T>
using SpatialPose = Eigen::Matrix<T, 6, 1>;

// The spatial robot: 6-DoF platform, 3-D exit points, wrench (f_x, f_y, f_z, m_x, m_y, m_z),
// force and moment about the platform reference point p, in F.
// No default gauge here, unlike the planar stages' exit-x gauge: which rigid motions of the
// frame the sensors leave unseen depends on the robot's sensors (an inclinometer fixes two
// rotations, a tracker everything, fixed swivel axes only weakly), so spatial identification
// will choose the gauge from the data.
struct SpatialKind {
  static constexpr int kPoseDim = 6;
  static constexpr int kPointDim = kSpatialPointDim;
  static constexpr int kWrenchDim = 6;
  static constexpr std::array<const char*, kPoseDim> kPoseNames = {"x", "y", "z", "roll", "pitch", "yaw"};
  static constexpr std::array<const char*, kPoseDim> kPoseUnits = {"m", "m", "m", "rad", "rad", "rad"};
  static constexpr GeometryLayout Layout(int num_cables) { return SpatialLayout(num_cables); }
  using Pose = SpatialPose<double>;
};

}  // namespace cablecal
