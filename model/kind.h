// The kinds of robot cablecal serves, in one place: what a pose is (its coordinates, their
// names and units), what a point is (its dimension), and the layout of the geometry a
// calibration identifies (model/geometry.h). The stages read a kind's numbers and names;
// none spells a pose's size or a point's. A second kind (spatial: a 6-DoF pose, 3-D points)
// is a second struct of the same shape. Depends on model/geometry.h.
#pragma once

#include <array>
#include <vector>

#include "model/geometry.h"

namespace cablecal {

// The planar robot: the platform moves in the x-z plane of F (z up); pose (x, z, theta), theta
// the platform's angle, counter-clockwise from F's x axis.
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

}  // namespace cablecal
