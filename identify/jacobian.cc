#include "identify/jacobian.h"

#include <cmath>

namespace cablecal {
namespace {

// Column compression (Curtis, Powell and Reid): cable i's residual depends on its own exit
// point and initial length only, and the laser's and inclinometer's on the pose only, so the
// columns a_1x .. a_Mx can share one Jet direction, a_1z .. a_Mz another, l_10 .. l_M0 a third,
// and x, z, theta take one each: 6 directions whatever M, and the Jacobian is read back
// exactly from where each column's entries can be. (tests/identify/jacobian_test.cc compares
// the result with the full Jacobian Ceres evaluates, which would show any other dependence.)
constexpr int kDirections = 6;
constexpr int kExitX = 0, kExitZ = 1, kInitialLength = 2, kPose = 3;

// The Jet over those directions, on top of T (double, or an InnerJet for pose derivatives).
template <typename T>
struct DirectionJet {
  using type = ceres::Jet<T, kDirections>;
};
template <int K>
struct DirectionJet<nested_jet::InnerJet<K>> {
  using type = nested_jet::Outer<K, kDirections>;
};


// Cable i's row: d r_i / d(a_ix, a_iz, l_i0, x, z, theta) in the directions above, at the
// robot's exit point and initial length 0 (l_i0 enters linearly).
template <typename T>
Eigen::Matrix<T, 1, kDirections> CableRow(const Robot& robot, int cable_index, const Pose<T>& q) {
  using J = typename DirectionJet<T>::type;
  const Cable& cable = robot.cables[cable_index];
  const Vec2<J> p_F_exit(J(T(cable.p_F_exit_m.x()), kExitX), J(T(cable.p_F_exit_m.y()), kExitZ));
  const J initial_length(T(0.0), kInitialLength);
  const Pose<J> q_jet(J(q(0), kPose), J(q(1), kPose + 1), J(q(2), kPose + 2));
  // The anchor as LengthResiduals places it: p + R(theta) b_i.
  const Vec2<J> p_F_anchor = PlatformPointInF<J>(q_jet, cable.p_P_anchor_m.cast<J>());
  const J residual = CableResidual<J>(cable, p_F_exit, initial_length, p_F_anchor, 0.0);
  return residual.v.transpose();
}

}  // namespace

template <typename T>
Rows<T> LengthResidualRows(const Robot& robot, const Pose<T>& q) {
  const int m = robot.num_cables();
  const GeometryLayout layout = LayoutOf(robot);
  Rows<T> rows = Rows<T>::Zero(m, RowColumns(m));
  for (int i = 0; i < m; ++i) {
    const Eigen::Matrix<T, 1, kDirections> row = CableRow<T>(robot, i, q);
    rows(i, layout.exit(i, 0)) = row(kExitX);
    rows(i, layout.exit(i, 1)) = row(kExitZ);
    rows(i, layout.initial_length(i)) = row(kInitialLength);
    for (int k = 0; k < PlanarKind::kPoseDim; ++k) rows(i, layout.size() + k) = row(kPose + k);
  }
  return rows;
}

template <typename T>
Rows<T> MlResidualRows(const Robot& robot, const Pose<T>& q) {
  using J = ceres::Jet<T, PlanarKind::kPoseDim>;
  const int m = robot.num_cables();
  const ReadingWeights weights = WeightsOf(robot.sensors);
  Rows<T> rows = Rows<T>::Zero(m + kNumPlanarSensors, RowColumns(m));
  rows.topRows(m) = LengthResidualRows<T>(robot, q) * weights.inv_sigma_encoder;
  // MlSensorResiduals reads no encoder reading: any PoseReadings will do.
  J pose[PlanarKind::kPoseDim];
  for (int k = 0; k < PlanarKind::kPoseDim; ++k) pose[k] = J(q(k), k);
  J sensor[kNumPlanarSensors];
  MlSensorResiduals<1, J>(PoseReadings<1>{}, weights, pose, sensor);
  for (int r = 0; r < kNumPlanarSensors; ++r) {
    for (int k = 0; k < PlanarKind::kPoseDim; ++k) rows(m + r, LayoutOf(robot).size() + k) = sensor[r].v[k];
  }
  return rows;
}

template <typename T>
Rows<T> ReducedInformation(const Rows<T>& ml_rows) {
  using std::sqrt;
  const int m = static_cast<int>(ml_rows.rows()) - kNumPlanarSensors;
  const std::vector<int> free = PlanarKind::FreeByDefault(PlanarLayout(m));  // a1z .. lm0 (a1x held)
  const int g = static_cast<int>(free.size());
  const int r_count = m + kNumPlanarSensors;
  Rows<T> E = ml_rows.block(0, PlanarLayout(m).size(), r_count, PlanarKind::kPoseDim);
  for (int k = 0; k < PlanarKind::kPoseDim; ++k) {
    for (int pass = 0; pass < 2; ++pass) {
      for (int l = 0; l < k; ++l) {
        T projection(0.0);
        for (int r = 0; r < r_count; ++r) projection += E(r, l) * E(r, k);
        for (int r = 0; r < r_count; ++r) E(r, k) -= projection * E(r, l);
      }
    }
    // Times the inverse, not divided: the same operations on a double as on an InnerJet's
    // value (a Jet divides that way).
    T squared_norm(0.0);
    for (int r = 0; r < r_count; ++r) squared_norm += E(r, k) * E(r, k);
    const T inverse_norm = T(1.0) / sqrt(squared_norm);
    for (int r = 0; r < r_count; ++r) E(r, k) *= inverse_norm;
  }
  Rows<T> G_perp(r_count, g);
  for (int c = 0; c < g; ++c) {
    T EtG[PlanarKind::kPoseDim];
    for (int k = 0; k < PlanarKind::kPoseDim; ++k) {
      EtG[k] = T(0.0);
      for (int r = 0; r < r_count; ++r) EtG[k] += E(r, k) * ml_rows(r, free[c]);
    }
    for (int r = 0; r < r_count; ++r) {
      T projected(0.0);
      for (int k = 0; k < PlanarKind::kPoseDim; ++k) projected += E(r, k) * EtG[k];
      G_perp(r, c) = ml_rows(r, free[c]) - projected;
    }
  }
  Rows<T> S(g, g);
  for (int a = 0; a < g; ++a) {
    for (int b = a; b < g; ++b) {
      T sum(0.0);
      for (int r = 0; r < r_count; ++r) sum += G_perp(r, a) * G_perp(r, b);
      S(a, b) = sum;
      S(b, a) = sum;
    }
  }
  return S;
}

using PoseJet = nested_jet::InnerJet<PlanarKind::kPoseDim>;
template Rows<double> LengthResidualRows<double>(const Robot&, const Pose<double>&);
template Rows<PoseJet> LengthResidualRows<PoseJet>(const Robot&, const Pose<PoseJet>&);
template Rows<double> MlResidualRows<double>(const Robot&, const Pose<double>&);
template Rows<PoseJet> MlResidualRows<PoseJet>(const Robot&, const Pose<PoseJet>&);
template Rows<double> ReducedInformation<double>(const Rows<double>&);
template Rows<PoseJet> ReducedInformation<PoseJet>(const Rows<PoseJet>&);

}  // namespace cablecal
