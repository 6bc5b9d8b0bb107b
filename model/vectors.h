// Fixed-size vectors on a scalar template (double, ceres::Jet, nested Jets), shared by the
// planar cable model (model/cable.h) and the spatial one (model/swivel.h). Depends on Eigen.
#pragma once

#include <Eigen/Core>

namespace cablecal {

template <typename T>
using Vec2 = Eigen::Matrix<T, 2, 1>;
template <typename T>
using Vec3 = Eigen::Matrix<T, 3, 1>;

}  // namespace cablecal
