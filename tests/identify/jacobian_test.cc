// The design's Jacobian rows (identify/jacobian.h, written from u_i and W) against automatic
// differentiation of the identification's own residuals (identify/residuals.h).
#include <ceres/jet.h>
#include <gtest/gtest.h>

#include "common/random.h"
#include "identify/experiment.h"
#include "identify/jacobian.h"
#include "identify/residuals.h"

namespace cablecal {
namespace {

constexpr double kRowTol = 1e-12;  // same quantity, two exact routes: rounding only

TEST(JacobianRows, MatchAutodiffOfResiduals) {
  const Robot& robot = BuiltinRobot();
  const GeometryVector g = GeometryOf(robot);
  using Jet9 = ceres::Jet<double, 9>;
  Rng rng(4);
  for (int k = 0; k < 200; ++k) {
    const Eigen::Vector3d q(rng.Uniform(0.5, 4.7), rng.Uniform(0.2, 2.4), rng.Uniform(-1.0, 1.0));
    Jet9 gj[6];
    for (int c = 0; c < 6; ++c) gj[c] = Jet9(g(c), c);
    const Pose<Jet9> qj(Jet9(q(0), 6), Jet9(q(1), 7), Jet9(q(2), 8));
    const auto anchors = AnchorsInF<Jet9>(robot, qj);
    const LengthRows<double> rows = LengthResidualRows<double>(robot, q);
    const MlRows<double> ml = MlResidualRows<double>(robot, q);
    for (int i = 0; i < 2; ++i) {
      const Jet9 r = LengthResidual<Jet9>(robot.cables[i], i, gj, anchors[i], 0.1);
      for (int c = 0; c < 6; ++c) {
        EXPECT_NEAR(rows(i, c), r.v(c), kRowTol) << "cable " << i << " column " << c;
        EXPECT_NEAR(ml(i, c) * robot.sensors.encoder_sigma_m, r.v(c), kRowTol);
      }
      EXPECT_NEAR(rows(i, 6), r.v(6), kRowTol);
      for (int c = 6; c < 9; ++c) EXPECT_NEAR(ml(i, c) * robot.sensors.encoder_sigma_m, r.v(c), kRowTol);
    }
  }
}

TEST(JacobianRows, ReducedInformationIsTheSchurComplement) {
  const Robot& robot = BuiltinRobot();
  const MlRows<double> rows = MlResidualRows<double>(robot, Eigen::Vector3d(1.7, 1.1, -0.2));
  // Eliminating the pose unknowns from the full information matrix (a1x dropped).
  Eigen::Matrix<double, 4, 8> A;
  A << rows.block<4, 5>(0, 1), rows.block<4, 3>(0, 6);
  const Eigen::Matrix<double, 8, 8> M = A.transpose() * A;
  const Eigen::Matrix<double, 5, 5> S_expected =
      M.topLeftCorner<5, 5>() - M.topRightCorner<5, 3>() * M.bottomRightCorner<3, 3>().inverse() * M.bottomLeftCorner<3, 5>();
  const Eigen::Matrix<double, 5, 5> S = ReducedInformation<double>(rows);
  EXPECT_LT((S - S_expected).cwiseAbs().maxCoeff(), 1e-9 * S_expected.cwiseAbs().maxCoeff());
}

}  // namespace
}  // namespace cablecal
