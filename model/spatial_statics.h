// PLACEHOLDER until r26-s lands (its model/spatial_statics.h replaces this file at the merge).
#pragma once

#include <Eigen/Core>

#include "model/kind.h"

namespace cablecal {

struct SpatialEquilibrium {
  SpatialPose<double> q;
  Eigen::VectorXd tensions_N;
  double residual_N;
  double reduced_stiffness;
  bool stable;
};

}  // namespace cablecal
