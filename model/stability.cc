#include "model/stability.h"

#include <ceres/jet.h>

#include <Eigen/Dense>

#include "common/error.h"
#include "common/flatten.h"
#include "model/cable.h"
#include "model/swivel.h"

namespace cablecal {
namespace {

// The kind-specific pieces, as small overloads on the robot type: the cable lengths and the
// generalized force E^T (W t + w_g) at q.
template <typename T>
Eigen::Matrix<T, Eigen::Dynamic, 1> KindLengths(const Robot& robot, const Pose<T>& q) {
  Eigen::Matrix<T, Eigen::Dynamic, 1> l(robot.num_cables());
  for (int i = 0; i < robot.num_cables(); ++i) l(i) = CableAtPose<T>(robot.cables[i], q).length_m;
  return l;
}
template <typename T>
Eigen::Matrix<T, Eigen::Dynamic, 1> KindLengths(const SpatialRobot& robot, const SpatialPose<T>& q) {
  return CableLengths<T>(robot, q);
}

template <typename T>
Vec3<T> GeneralizedForce(const Robot& robot, const Pose<T>& q, const Eigen::Matrix<T, Eigen::Dynamic, 1>& t) {
  return EquilibriumResidual<T>(robot, q, t);  // the planar twist is dq itself
}
template <typename T>
SpatialPose<T> GeneralizedForce(const SpatialRobot& robot, const SpatialPose<T>& q,
                                const Eigen::Matrix<T, Eigen::Dynamic, 1>& t) {
  return TwistMap<T>(q).transpose() * EquilibriumResidual<T>(robot, q, t);
}

// Rank of the constraint rows: singular values below this fraction of the largest are zero.
// The rows are length gradients (unit vectors in m/m, levers in m/rad): a dependent set
// leaves rounding, some 1e-16 of the largest.
constexpr double kRankTolerance = 1e-9;

// A curvature this small against the largest entry of the Hessian's gravity-and-tension part
// (the springs' k g g' left out: a stiff cable's 1e11 N/m would drown the 10 N/m of gravity that
// decides the motions the springs do not resist) is rounding of a zero: a neutral direction (a
// bar whose centre of mass lies on its anchors' line spins freely about that line), which holds
// the platform no more than a negative one. Rounding leaves some 1e-15 of it.
constexpr double kNeutralCurvature = 1e-9;

template <int D, typename RobotT>
StabilityResult Stability(const RobotT& robot, const Eigen::Matrix<double, D, 1>& q, const Eigen::VectorXd& tensions_N,
                          const Eigen::VectorXd& axial_stiffness_Npm) {
  const int m = robot.num_cables();
  CABLECAL_CHECK(tensions_N.size() == m && axial_stiffness_Npm.size() == m, "one tension and one stiffness per cable");
  using J = ceres::Jet<double, D>;
  Eigen::Matrix<J, D, 1> q_jet;
  for (int k = 0; k < D; ++k) q_jet(k) = J(q(k), k);
  const Eigen::Matrix<J, Eigen::Dynamic, 1> l = KindLengths<J>(robot, q_jet);
  Eigen::Matrix<J, Eigen::Dynamic, 1> t(m);
  int constraints = 0;
  for (int i = 0; i < m; ++i) {
    const double k = axial_stiffness_Npm(i);
    CABLECAL_CHECK(k >= 0.0, "an axial stiffness is >= 0 (0: slack)");
    if (std::isinf(k)) {
      t(i) = J(tensions_N(i));
      ++constraints;
    } else if (k > 0.0) {
      // l - l(q0): zero value, the length's gradient as derivative.
      t(i) = J(tensions_N(i)) + k * (l(i) - J(l(i).a));
    } else {
      t(i) = J(0.0);
    }
  }
  // The free motions first: where the inextensible cables hold every coordinate (6 or more
  // taut cables of full rank, the sampler's every candidate) the platform is held and the
  // Hessian, a second swivel construction per cable in Jets, is not needed.
  Eigen::Matrix<double, D, Eigen::Dynamic> N;  // orthonormal basis of the free motions
  if (constraints == 0) {
    N = Eigen::Matrix<double, D, D>::Identity();
  } else {
    Eigen::MatrixXd A(constraints, D);
    for (int i = 0, row = 0; i < m; ++i) {
      if (std::isinf(axial_stiffness_Npm(i))) A.row(row++) = l(i).v.transpose();
    }
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(A, Eigen::ComputeFullV);
    const Eigen::VectorXd& s = svd.singularValues();
    int rank = 0;
    while (rank < s.size() && s(rank) > kRankTolerance * s(0)) ++rank;
    N = svd.matrixV().rightCols(D - rank);
  }
  StabilityResult result;
  result.free_motions = static_cast<int>(N.cols());
  if (result.free_motions == 0) {
    result.stable = true;
    return result;
  }
  const Eigen::Matrix<J, D, 1> f = GeneralizedForce<J>(robot, q_jet, t);
  Eigen::Matrix<double, D, D> H;
  for (int r = 0; r < D; ++r) H.row(r) = -f(r).v.transpose();
  H = (0.5 * (H + H.transpose())).eval();
  Eigen::Matrix<double, D, D> H_geometric = H;  // without the springs: the neutral test's scale
  for (int i = 0; i < m; ++i) {
    const double k = axial_stiffness_Npm(i);
    if (k > 0.0 && !std::isinf(k)) H_geometric -= k * l(i).v * l(i).v.transpose();
  }
  const Eigen::MatrixXd H_reduced = N.transpose() * H * N;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(H_reduced, Eigen::EigenvaluesOnly);
  result.min_eigenvalue = eig.eigenvalues()(0);
  result.stable = result.min_eigenvalue > kNeutralCurvature * H_geometric.cwiseAbs().maxCoeff();
  return result;
}

}  // namespace

StabilityResult StaticStability(const Robot& robot, const PlanarPose& q, const Eigen::VectorXd& tensions_N,
                                const Eigen::VectorXd& axial_stiffness_Npm) {
  return Stability<PlanarKind::kPoseDim>(robot, q, tensions_N, axial_stiffness_Npm);
}

// Flattened (common/flatten.h): the spatial Monte Carlo tests every simulated pose, and its Jets'
// arithmetic called out of line was a third of the sampler's time (bench/README.md).
CABLECAL_FLATTEN StabilityResult StaticStability(const SpatialRobot& robot, const SpatialPose<double>& q,
                                                 const Eigen::VectorXd& tensions_N,
                                                 const Eigen::VectorXd& axial_stiffness_Npm) {
  return Stability<SpatialKind::kPoseDim>(robot, q, tensions_N, axial_stiffness_Npm);
}

}  // namespace cablecal
