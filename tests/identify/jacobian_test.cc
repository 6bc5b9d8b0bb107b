// One source for the identification Jacobian: the design's rows (identify/jacobian.h, automatic
// derivatives of identify/residuals.h) against the Jacobian Ceres evaluates for the
// identification's own cost functor, against the virtual-work form of the rows, and (inside
// Identify) the reduced information they give against the singular values Identify reports;
// the rows' pose derivatives (nested Jets) against central differences. Robots with 2 to 8
// cables: wang2022, the planar3 and planar4 files, and random robots.
#include <ceres/ceres.h>
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <string>
#include <vector>

#include "common/random.h"
#include "identify/cost_functors.h"
#include "experiment/experiment.h"
#include "identify/identify.h"
#include "identify/jacobian.h"
#include "identify/residuals.h"
#include "model/statics.h"
#include "tests/support/random_robot.h"
#include "workspace/workspace.h"

namespace cablecal {
namespace {

constexpr double kRowRelTol = 1e-12;  // same derivatives, two exact routes: rounding only

// The robots of the tests: wang2022, the two new files, random robots with m = 3..8 cables
// (suspended for odd m, fully constrained for even m >= 4), and the asymmetric file.
std::vector<Robot> TestRobots() {
  std::vector<Robot> robots = {BuiltinRobot(),
                               LoadRobotFile(CABLECAL_SOURCE_DIR "/robots/planar3_suspended.yaml"),
                               LoadRobotFile(CABLECAL_SOURCE_DIR "/robots/planar4_fully_constrained.yaml"),
                               LoadRobotFile(CABLECAL_SOURCE_DIR "/robots/asymmetric.yaml")};
  Rng rng(314);
  for (int m = 3; m <= 8; ++m) {
    robots.push_back(testing::RandomRobotWithCables(rng, "random" + std::to_string(m), m, m % 2 == 0));
  }
  return robots;
}

double MaxAbs(const Eigen::MatrixXd& a) { return a.cwiseAbs().maxCoeff(); }

template <int M>
void CheckRowsOfRobot(const Robot& robot) {
  constexpr int kG = 3 * M;
  const std::vector<PlanPose> plan = SampleFeasiblePoses(robot, 12, 17);
  GeometryVector g = GeometryOf(robot);
  const ReadingWeights weights = WeightsOf(robot.sensors);
  for (const PlanPose& pose : plan) {
    const Eigen::Vector3d& q = pose.q;
    // Ceres' Jacobians of the identification's two cost functors (the length rows, then the
    // laser and inclinometer rows, as Identify adds them), at readings of this pose.
    Measurement m;
    m.dl_m = pose.length_change_m;
    m.set(SensorId::kLaser, q(1) + 0.001);  // the rows do not depend on the readings
    m.set(SensorId::kInclinometer, q(2) - 0.002);
    const PoseReadings<M> readings = internal::ReadingsOf<M>(m);
    ceres::AutoDiffCostFunction<internal::MlLengthCost<M>, M, kG, 3> lengths(
        new internal::MlLengthCost<M>{&robot, readings, weights});
    ceres::AutoDiffCostFunction<internal::MlSensorCost<M>, 2, 3> sensors(new internal::MlSensorCost<M>{readings, weights});
    const double* parameters[2] = {g.data(), q.data()};
    Eigen::Matrix<double, M, kG, Eigen::RowMajor> d_geometry;
    Eigen::Matrix<double, M, 3, Eigen::RowMajor> d_pose;
    Eigen::Matrix<double, 2, 3, Eigen::RowMajor> d_pose_sensors;
    double residual[M + 2];
    double* jacobians[2] = {d_geometry.data(), d_pose.data()};
    ASSERT_TRUE(lengths.Evaluate(parameters, residual, jacobians)) << robot.name;
    double* sensor_jacobian[1] = {d_pose_sensors.data()};
    ASSERT_TRUE(sensors.Evaluate(parameters + 1, residual + M, sensor_jacobian)) << robot.name;
    Eigen::MatrixXd ceres_rows(M + 2, kG + 3);
    ceres_rows << d_geometry, d_pose, Eigen::MatrixXd::Zero(2, kG), d_pose_sensors;

    const Eigen::MatrixXd rows = MlResidualRows<double>(robot, q);
    ASSERT_EQ(rows.rows(), M + 2);
    ASSERT_EQ(rows.cols(), RowColumns(M));
    const double scale = MaxAbs(ceres_rows);
    EXPECT_LE(MaxAbs(rows - ceres_rows), kRowRelTol * scale) << robot.name << " q = " << q.transpose();

    // The virtual-work form: dl_i/da_i = u_i (the cable's unit vector from anchor to pulley,
    // W's force rows), dl_i/dl_i0 = -1, dl_i/dq = -W(:, i)'; nothing else.
    const Eigen::MatrixXd length_rows = LengthResidualRows<double>(robot, q);
    const Eigen::Matrix<double, 3, Eigen::Dynamic> W = WrenchMatrix<double>(robot, q);
    Eigen::MatrixXd expected = Eigen::MatrixXd::Zero(M, kG + 3);
    for (int i = 0; i < M; ++i) {
      expected(i, 2 * i) = W(0, i);
      expected(i, 2 * i + 1) = W(1, i);
      expected(i, 2 * M + i) = -1.0;
      for (int k = 0; k < 3; ++k) expected(i, kG + k) = -W(k, i);
    }
    EXPECT_LE(MaxAbs(length_rows - expected), 1e-12 * MaxAbs(expected)) << robot.name << " q = " << q.transpose();
    EXPECT_LE(MaxAbs(length_rows * weights.inv_sigma_encoder - rows.topRows(M)),
              kRowRelTol * scale)
        << robot.name;

    // The nested Jets' pose derivatives against central differences of the rows.
    using PoseJet = nested_jet::InnerJet<3>;
    const Rows<PoseJet> nested =
        MlResidualRows<PoseJet>(robot, Pose<PoseJet>(PoseJet(q(0), 0), PoseJet(q(1), 1), PoseJet(q(2), 2)));
    for (int k = 0; k < 3; ++k) {
      Eigen::MatrixXd value(M + 2, kG + 3), derivative(M + 2, kG + 3);
      for (int r = 0; r < M + 2; ++r) {
        for (int c = 0; c < kG + 3; ++c) {
          value(r, c) = nested(r, c).a;
          derivative(r, c) = nested(r, c).v(k);
        }
      }
      EXPECT_EQ(MaxAbs(value - rows), 0.0) << "the nested evaluation's values are the plain ones";
      const double h = 1e-5;
      Eigen::Vector3d qp = q, qm = q;
      qp(k) += h;
      qm(k) -= h;
      const Eigen::MatrixXd difference = (MlResidualRows<double>(robot, qp) - MlResidualRows<double>(robot, qm)) / (2 * h);
      // Central differences: truncation h^2 times the third derivatives, rounding eps/h.
      EXPECT_LE(MaxAbs(derivative - difference), 1e-6 * std::max(1.0, MaxAbs(derivative)))
          << robot.name << " d/dq" << k;
    }

    // The reduced information against the dense Schur complement (a1x dropped).
    const int G = kG - 1;
    Eigen::MatrixXd A(M + 2, G + 3);
    A << rows.block(0, 1, M + 2, G), rows.block(0, kG, M + 2, 3);
    const Eigen::MatrixXd H = A.transpose() * A;
    const Eigen::MatrixXd S_expected = H.topLeftCorner(G, G) - H.topRightCorner(G, 3) *
                                                                   H.bottomRightCorner(3, 3).inverse() *
                                                                   H.bottomLeftCorner(3, G);
    const Eigen::MatrixXd S = ReducedInformation<double>(rows);
    EXPECT_LE(MaxAbs(S - S_expected), 1e-8 * MaxAbs(S_expected)) << robot.name;
    EXPECT_EQ(MaxAbs(S - S.transpose()), 0.0) << "symmetric by construction";
    // The nested evaluation's information has the plain one as its values, to the last bit.
    const Rows<PoseJet> S_nested = ReducedInformation<PoseJet>(nested);
    for (int a = 0; a < G; ++a) {
      for (int b = 0; b < G; ++b) ASSERT_EQ(S_nested(a, b).a, S(a, b)) << robot.name << " (" << a << ", " << b << ")";
    }
    // Rank M - 1: the pose's readings beyond its 3 unknowns.
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(S);
    EXPECT_GT(eig.eigenvalues()(G - M + 1), 1e-9 * eig.eigenvalues()(G - 1)) << robot.name;
    EXPECT_LT(std::abs(eig.eigenvalues()(G - M)), 1e-9 * eig.eigenvalues()(G - 1)) << robot.name;
  }
}

void CheckRows(const Robot& robot) {
  switch (robot.num_cables()) {
    case 2: return CheckRowsOfRobot<2>(robot);
    case 3: return CheckRowsOfRobot<3>(robot);
    case 4: return CheckRowsOfRobot<4>(robot);
    case 5: return CheckRowsOfRobot<5>(robot);
    case 6: return CheckRowsOfRobot<6>(robot);
    case 7: return CheckRowsOfRobot<7>(robot);
    case 8: return CheckRowsOfRobot<8>(robot);
  }
  FAIL() << robot.num_cables() << " cables";
}

TEST(JacobianRows, AreCeresJacobianOfTheCostFunctorForEveryCableCount) {
  for (const Robot& robot : TestRobots()) {
    SCOPED_TRACE(robot.name);
    CheckRows(robot);
  }
}

// Inside Identify: with noise-free readings of the nominal robot the estimate is the nominal
// geometry and the true poses, where the reduced Jacobian Identify builds from Ceres' own
// Jacobian must give the information the design computes from its rows: its singular values
// squared are the eigenvalues of sum_j S_j.
void CheckInformationOfIdentify(const Robot& robot) {
  const int G = 3 * robot.num_cables() - 1;
  const std::vector<PlanPose> plan = SampleFeasiblePoses(robot, 10, 23);
  Rng rng(1);
  const SimulatedExperiment exp =
      SimulateExperiment(robot, robot, plan, SimulationOptions{NoisySensors::kNone, false}, rng);
  const IdentifyResult r = Identify(robot, exp.measurements, IdentifyOptions{});
  ASSERT_EQ(r.status, IdentifyStatus::kConverged) << robot.name << ": " << r.message;
  Eigen::MatrixXd S = Eigen::MatrixXd::Zero(G, G);
  for (const PlanPose& p : plan) S += ReducedInformation<double>(MlResidualRows<double>(robot, p.q));
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(S);
  const Eigen::VectorXd& sv = r.identifiability.singular_values;
  ASSERT_EQ(sv.size(), G) << robot.name;
  for (int k = 0; k < G; ++k) {
    // Descending singular values against ascending eigenvalues.
    EXPECT_NEAR(sv(k) * sv(k) / eig.eigenvalues()(G - 1 - k), 1.0, 1e-7) << robot.name << " k = " << k;
  }
}

TEST(JacobianRows, GiveTheInformationIdentifyFindsFromCeresJacobian) {
  for (const Robot& robot : TestRobots()) {
    SCOPED_TRACE(robot.name);
    CheckInformationOfIdentify(robot);
  }
}

}  // namespace
}  // namespace cablecal
