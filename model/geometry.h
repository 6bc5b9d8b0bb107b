// The geometric parameters a calibration identifies, and where each sits in the geometry
// vector: per cable its exit point's coordinates in F (kPointDim of them), then every cable's
// initial length l_i0 (the cable's length at the home pose), in m. Identification, design and
// the Monte Carlo index the vector only through GeometryLayout, so that a robot kind with 3-D
// points has the same stages with another layout. Depends on model/robot.h.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "model/robot.h"

namespace cablecal {

// Planar robots: exit points (x, z) in the x-z plane of F.
inline constexpr int kPlanarPointDim = 2;

// The layout of a geometry vector: a1x a1z ... amx amz (exit coordinates, cable after cable),
// then l10 ... lm0. constexpr, so that the identification's compile-time sizes come from it.
struct GeometryLayout {
  int num_cables = 0;
  int point_dim = kPlanarPointDim;
  const char* axes = "xz";  // the name of each exit coordinate's axis, point_dim letters

  constexpr int size() const { return (point_dim + 1) * num_cables; }
  constexpr int exit_coordinates() const { return point_dim * num_cables; }
  constexpr int exit(int cable, int axis) const { return point_dim * cable + axis; }
  constexpr int initial_length(int cable) const { return point_dim * num_cables + cable; }
  constexpr bool is_exit(int k) const { return k < exit_coordinates(); }
  constexpr int axis_of(int k) const { return k % point_dim; }  // an exit coordinate's axis
  // "a1x", "a1z", ..., "l10", ...: every entry's name, in the vector's order.
  std::vector<std::string> names() const;
};

constexpr GeometryLayout PlanarLayout(int num_cables) { return GeometryLayout{num_cables, kPlanarPointDim, "xz"}; }
// Spatial robots: exit points (x, y, z) in F; a1x a1y a1z ... amx amy amz, then l10 ... lm0.
inline constexpr int kSpatialPointDim = 3;
constexpr GeometryLayout SpatialLayout(int num_cables) { return GeometryLayout{num_cables, kSpatialPointDim, "xyz"}; }
inline GeometryLayout LayoutOf(const Robot& robot) { return PlanarLayout(robot.num_cables()); }

// The geometry vector is dynamic: the cable count lives in the robot alone (the
// identification's cost functors take it as a compile-time M, dispatched once per call).
using GeometryVector = Eigen::VectorXd;
inline int GeometrySize(int num_cables) { return PlanarLayout(num_cables).size(); }
inline int ExitIndex(int cable, int axis) { return PlanarLayout(0).exit(cable, axis); }  // axis 0: x, 1: z
inline int InitialLengthIndex(int num_cables, int cable) { return PlanarLayout(num_cables).initial_length(cable); }
inline std::vector<std::string> GeometryNames(int num_cables) { return PlanarLayout(num_cables).names(); }
// "a1z a2x a2z l10 l20": the names from entry `from` on, space-separated, for messages.
std::string GeometryNameList(int num_cables, int from);
GeometryVector GeometryOf(const Robot& robot);                           // initial lengths from InitialLengths
Robot WithGeometry(const Robot& robot, const GeometryVector& geometry);  // sets exits and initial_length

}  // namespace cablecal
