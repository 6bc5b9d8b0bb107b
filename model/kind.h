// The kinds of robot cablecal serves, in one place: what a pose is (its coordinates, their
// names and units), what a point is (its dimension), and the layout of the geometry a
// calibration identifies (model/geometry.h). The stages read a kind's numbers and names;
// none spells a pose's size or a point's. A second kind (spatial: a 6-DoF pose, 3-D points)
// is a second struct of the same shape. Depends on model/geometry.h.
#pragma once

#include <array>

#include "model/geometry.h"

namespace cablecal {

// The planar robot: the platform moves in the x-z plane of F (z up); pose (x, z, theta), theta
// the platform's angle, counter-clockwise from F's x axis.
struct PlanarKind {
  static constexpr int kPoseDim = 3;
  static constexpr int kPointDim = kPlanarPointDim;
  static constexpr std::array<const char*, kPoseDim> kPoseNames = {"x", "z", "theta"};
  static constexpr std::array<const char*, kPoseDim> kPoseUnits = {"m", "m", "rad"};
  static constexpr GeometryLayout Layout(int num_cables) { return PlanarLayout(num_cables); }
};

}  // namespace cablecal
