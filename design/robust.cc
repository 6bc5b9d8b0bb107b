#include "design/robust.h"

#include <ceres/jet.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "common/error.h"
#include "common/flatten.h"
#include "design/ipopt_nlp.h"

namespace cablecal::internal {

std::vector<Eigen::Vector2d> FramePoints(const Robot& robot) {
  std::vector<Eigen::Vector2d> points = {Eigen::Vector2d::Zero()};
  for (const Cable& c : robot.cables) points.push_back(c.p_P_anchor_m);
  if (robot.p_P_com_m.norm() > 0.0) points.push_back(robot.p_P_com_m);
  return points;
}

std::vector<PoseQuantity> PoseQuantities(const Robot& robot) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const int m = robot.num_cables();
  std::vector<PoseQuantity> q;
  for (int i = 0; i < m; ++i) {
    q.push_back({"t" + std::to_string(i + 1), robot.tension_min_N, robot.tension_max_N, kBoundMargin_N, true});
  }
  q.push_back({"theta", -robot.theta_max_rad, robot.theta_max_rad, kBoundMargin_rad, true});
  q.push_back({"z (laser range)", -kInf, robot.laser_range_m, kBoundMargin_m, true});
  for (int i = 0; i < m; ++i) {
    q.push_back({"anchor " + std::to_string(i + 1) + " clearance from its pulley", robot.margin_m, kInf, kBoundMargin_m,
                 false});
  }
  const std::vector<Eigen::Vector2d> points = FramePoints(robot);
  for (std::size_t k = 0; k < points.size(); ++k) {
    const std::string name = k == 0 ? "platform point p"
                             : k <= static_cast<std::size_t>(m) ? "anchor " + std::to_string(k)
                                                                : "centre of mass";
    q.push_back({name + " x", robot.margin_m, robot.frame_width_m - robot.margin_m, kBoundMargin_m, k == 0});
    q.push_back({name + " z", robot.margin_m, robot.frame_height_m - robot.margin_m, kBoundMargin_m, k == 0});
  }
  return q;
}

namespace {

// `flatten` (common/flatten.h) inlines the Jet arithmetic into RobustQuantitiesM<2>, the paper's robot's (its
// robust design runs it millions of times): with the seven instances in this file GCC's
// inliner otherwise runs out of its unit-growth budget and calls it out of line, which made
// M = 2 a third slower. Only M = 2: flattening all seven took 114 s of this file's 2-core build
// (bench/README.md, "Build and CI time"), and under AddressSanitizer over 17 minutes, so not
// there at all (that build is for correctness, not speed).

// RobustQuantities for M cables: Jets sized at compile time for (y, g), 3 + M + 3M entries
// (M = 2: 11, as before the cable count became general).
template <int M>
bool RobustQuantitiesM(const Robot& robot, const std::vector<Eigen::Vector2d>& points, const Eigen::VectorXd& y_in,
                       PoseRobustness* out, bool with_derivatives) {
  constexpr int kPose = PlanarKind::kPoseDim, kWrench = PlanarKind::kWrenchDim;
  constexpr int P = kPose + M;  // pose variables x, z, theta, t1..tM
  constexpr GeometryLayout kLayout = PlanarLayout(M);
  constexpr int G = kLayout.size();  // geometry a1x a1z .. aMx aMz l10 .. lM0
  constexpr int N = P + G;
  using U = ceres::Jet<double, N>;
  const int m = M;
  const Eigen::Matrix<double, P, 1> y = y_in;
  Eigen::Matrix<U, P, 1> yu;
  for (int k = 0; k < P; ++k) yu(k) = U(y(k), k);
  Vec2<U> exits[kMaxCables];
  U l0[kMaxCables];
  for (int i = 0; i < m; ++i) {
    for (int c = 0; c < kLayout.point_dim; ++c) exits[i](c) = U(robot.cables[i].p_F_exit_m(c), P + kLayout.exit(i, c));
    l0[i] = U(0.0, P + kLayout.initial_length(i));  // only its derivative matters: dl_i is fixed
  }
  const Pose<U> q = yu.template head<kPose>();
  const Eigen::Matrix<U, 2, 2> rot = Rotation(q(2));
  const Vec2<U> p(q(0), q(1));

  // R(y, g) = [l_i(q; a_i) - l_i0 - dl_i; W(q; a) t + w_g(q)] and the quantities c(y, g).
  Eigen::Matrix<U, P, 1> R;
  std::vector<U> c;
  for (int i = 0; i < m; ++i) c.push_back(yu(kPose + i));  // t_i
  c.push_back(q(2));                                    // theta
  c.push_back(q(1));                                    // z against the laser range
  Eigen::Matrix<U, Eigen::Dynamic, 1> t(m);
  for (int i = 0; i < m; ++i) {
    const Cable& cable = robot.cables[i];
    const Vec2<U> anchor = p + rot * cable.p_P_anchor_m.cast<U>();
    const CableState<U> s = CableGeometry<U>(exits[i], U(cable.pulley_radius_m), SignsOf(cable), anchor);
    R(i) = s.length_m - l0[i];
    t(i) = yu(kPose + i);
    c.push_back(s.centre_distance_m - U(cable.pulley_radius_m));  // clearance of anchor i from its pulley
  }
  R.template tail<kWrench>() = WrenchMatrix<U>(robot, q, exits) * t + GravityWrench<U>(robot, q);
  for (const Eigen::Vector2d& b : points) {
    const Vec2<U> point = p + rot * b.cast<U>();
    c.push_back(point.x());
    c.push_back(point.y());
  }

  Eigen::Matrix<double, P, P> A;
  Eigen::Matrix<double, P, G> B;
  for (int r = 0; r < P; ++r) {
    A.row(r) = R(r).v.template head<P>().transpose();
    B.row(r) = R(r).v.template tail<G>().transpose();
  }
  for (int r = 0; r < kWrench; ++r) out->equilibrium_N(r) = R(m + r).a;
  if (with_derivatives) out->dequilibrium_dy = A.template bottomRows<kWrench>();
  Eigen::Matrix<double, P, G> dy_dg;
  if constexpr (M <= kPose) {
    // Square: the implicit function theorem.
    Eigen::FullPivLU<Eigen::Matrix<double, P, P>> lu(A);
    if (!lu.isInvertible()) return false;
    dy_dg = -lu.solve(B);
  } else {
    // Least-squares pose of the commanded lengths, then the least tension change that restores
    // the equilibrium there (header).
    const Eigen::Matrix<double, M, kPose> J = A.template topLeftCorner<M, kPose>();  // dl/dq
    const Eigen::Matrix<double, kWrench, kPose> K = A.template bottomLeftCorner<kWrench, kPose>();  // d(W t + w_g)/dq
    const Eigen::Matrix<double, kWrench, M> W = A.template bottomRightCorner<kWrench, M>();  // d(W t + w_g)/dt
    Eigen::FullPivLU<Eigen::Matrix<double, kPose, kPose>> normal(J.transpose() * J);
    Eigen::FullPivLU<Eigen::Matrix<double, kWrench, kWrench>> wwt(W * W.transpose());
    if (!normal.isInvertible() || !wwt.isInvertible()) return false;
    const Eigen::Matrix<double, kPose, G> dq_dg = -normal.solve(J.transpose() * B.template topRows<M>());
    const Eigen::Matrix<double, kWrench, G> imbalance = K * dq_dg + B.template bottomRows<kWrench>();
    dy_dg.template topRows<kPose>() = dq_dg;
    dy_dg.template bottomRows<M>() = -W.transpose() * wwt.solve(imbalance);
  }
  out->value.resize(c.size());
  out->spread.resize(c.size());
  if (with_derivatives) out->dvalue_dy.resize(static_cast<Eigen::Index>(c.size()), P);
  for (std::size_t k = 0; k < c.size(); ++k) {
    const Eigen::Matrix<double, 1, G> dc_dg =
        c[k].v.template head<P>().transpose() * dy_dg + c[k].v.template tail<G>().transpose();
    out->value[k] = c[k].a;
    out->spread[k] = dc_dg.norm();
    if (with_derivatives) out->dvalue_dy.row(static_cast<Eigen::Index>(k)) = c[k].v.template head<P>().transpose();
    if (!std::isfinite(out->spread[k]) || !std::isfinite(out->value[k])) return false;
  }
  return true;
}

CABLECAL_FLATTEN bool RobustQuantitiesTwoCables(const Robot& robot, const std::vector<Eigen::Vector2d>& points,
                                                const Eigen::VectorXd& y, PoseRobustness* out, bool with_derivatives) {
  return RobustQuantitiesM<2>(robot, points, y, out, with_derivatives);
}

}  // namespace

bool RobustQuantities(const Robot& robot, const std::vector<Eigen::Vector2d>& points, const Eigen::VectorXd& y,
                      PoseRobustness* out, bool with_derivatives) {
  const int m = robot.num_cables();
  CABLECAL_CHECK(y.size() == PoseVariables(m), "y holds x, z, theta and one tension per cable");
  if (m == 2) return RobustQuantitiesTwoCables(robot, points, y, out, with_derivatives);
  return WithCableCount(m, [&](auto cables) {
    return RobustQuantitiesM<decltype(cables)::value>(robot, points, y, out, with_derivatives);
  });
}

}  // namespace cablecal::internal
