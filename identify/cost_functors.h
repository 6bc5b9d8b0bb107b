// The identification's Ceres cost functors: thin wrappers that call the residual functions
// of identify/residuals.h, two residual blocks per pose for ml (one for the paper's
// estimator) and one for the tracker prior, sized at compile time by the cable count M.
// identify_cables.h builds its problem from them; tests wrap them in
// ceres::AutoDiffCostFunction to compare Ceres' Jacobians with identify/jacobian.h.
#pragma once

#include <Eigen/Core>
#include <cmath>

#include "common/error.h"
#include "experiment/experiment.h"
#include "identify/residuals.h"
#include "model/geometry.h"
#include "model/robot.h"

namespace cablecal::internal {

// A trial step of Levenberg-Marquardt can put an anchor inside its pulley, where the cable
// length is undefined (NaN). Saying so (false) makes Ceres reject the step quietly, exactly
// as it does for a NaN it finds itself, but without a multi-line warning per block.
template <typename T, int kCount>
bool AllFinite(const T* residual) {
  using std::isfinite;  // ceres::isfinite for Jets, by argument-dependent lookup
  for (int i = 0; i < kCount; ++i) {
    if (!isfinite(residual[i])) return false;
  }
  return true;
}

template <int M>
PoseReadings<M> ReadingsOf(const Measurement& m) {
  CABLECAL_CHECK(m.dl_m.size() == M, "one encoder reading per cable");
  PoseReadings<M> r;
  r.dl_m = m.dl_m;
  for (int k = 0; k < kNumSensorIds; ++k) r.sensor_values[k] = m.value(static_cast<SensorId>(k));
  return r;
}

// Maximum likelihood, errors in variables: per pose, every cable's length residual and the
// other sensors' residuals (model/sensors.h), each whitened by its sensor's sigma (residuals.h).
// Identify gives Ceres two residual blocks per pose, MlLengthCost (geometry and pose) and
// MlSensorCost (the pose alone): with 2 cables every row block is then 2 rows by a 3-wide pose
// block and a 6-wide geometry block, a shape Ceres' Schur eliminator has a compiled
// specialisation for (<2, 3, 6>); one block of 4 rows takes its generic, dynamic-size path,
// which was half of every 2-cable solve (bench/README.md).
template <int M>
struct MlLengthCost {
  const Robot* robot;
  PoseReadings<M> readings;
  ReadingWeights weights;

  template <typename T>
  bool operator()(const T* geometry, const T* pose, T* residual) const {
    MlLengthResiduals<M, T>(*robot, readings, weights, geometry, pose, residual);
    return AllFinite<T, M>(residual);
  }
};

template <int M>
struct MlSensorCost {
  PoseReadings<M> readings;
  ReadingWeights weights;

  template <typename T>
  bool operator()(const T* pose, T* residual) const {
    MlSensorResiduals<M, T>(readings, weights, pose, residual);
    return true;
  }
};

// The static equilibrium's row of a pose (robots of M < 3 cables; residuals.h,
// MlEquilibriumResidual): one block per pose, after its readings' blocks, never under a robust
// loss (it is no reading).
template <int M>
struct MlEquilibriumCost {
  const Robot* robot;
  ReadingWeights weights;

  template <typename T>
  bool operator()(const T* geometry, const T* pose, T* residual) const {
    MlEquilibriumResidual<M, T>(*robot, weights, geometry, pose, residual);
    return AllFinite<T, 1>(residual);
  }
};

// With a robust loss (identify --loss) every reading is a residual block of its own, so that
// the loss weighs each reading, not a pose's readings together: one cable's length residual,
// and each sensor's (its index in kPlanarSensors, the order of MlSensorResiduals).
template <int M>
struct MlCableCost {
  const Robot* robot;
  PoseReadings<M> readings;
  ReadingWeights weights;
  int cable;

  template <typename T>
  bool operator()(const T* geometry, const T* pose, T* residual) const {
    const Cable& c = robot->cables[cable];
    const Vec2<T> p_F_anchor = PlatformPointInF<T>(Pose<T>(pose[0], pose[1], pose[2]), c.p_P_anchor_m.cast<T>());
    residual[0] = LengthResidual<M, T>(c, cable, geometry, p_F_anchor, readings.dl_m(cable)) * weights.inv_sigma_encoder;
    return AllFinite<T, 1>(residual);
  }
};

template <int M>
struct MlOneSensorCost {
  PoseReadings<M> readings;
  ReadingWeights weights;
  int sensor;  // index in kPlanarSensors

  template <typename T>
  bool operator()(const T* pose, T* residual) const {
    T all[kNumPlanarSensors];
    MlSensorResiduals<M, T>(readings, weights, pose, all);
    residual[0] = all[sensor];
    return true;
  }
};

// The paper's estimator: Eq. (6) with z_j and theta_j taken as measured; only x_j unknown.
template <int M>
struct PaperPoseCost {
  const Robot* robot;
  PoseReadings<M> readings;

  template <typename T>
  bool operator()(const T* geometry, const T* x, T* residual) const {
    PaperResiduals<M, T>(*robot, readings, geometry, x, residual);
    return AllFinite<T, M>(residual);
  }
};

// A prior on every geometric parameter (identify --geometry-prior, with the tracker's on the
// exit points when both are given): (g_k - nominal_k) / sigma_k, a zero row where
// inv_sigma_k = 0 (a coordinate without one).
template <int M>
struct GeometryPriorCost {
  static constexpr int kSize = PlanarLayout(M).size();
  Eigen::Matrix<double, kSize, 1> nominal;
  Eigen::Matrix<double, kSize, 1> inv_sigma;
  template <typename T>
  bool operator()(const T* geometry, T* residual) const {
    for (int k = 0; k < kSize; ++k) residual[k] = (geometry[k] - nominal(k)) * inv_sigma(k);
    return true;
  }
};

// Laser-tracker prior on the exit points (gauge `prior`): a1x a1z ... aMx aMz.
template <int M>
struct ExitPointPriorCost {
  static constexpr int kSize = PlanarLayout(M).exit_coordinates();
  Eigen::Matrix<double, kSize, 1> nominal;
  double inv_sigma;
  template <typename T>
  bool operator()(const T* geometry, T* residual) const {
    for (int k = 0; k < kSize; ++k) residual[k] = (geometry[k] - nominal(k)) * inv_sigma;
    return true;
  }
};

}  // namespace cablecal::internal
