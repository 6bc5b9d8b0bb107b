#include "design/robust.h"

#include <ceres/jet.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "common/error.h"
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

bool RobustQuantities(const Robot& robot, const std::vector<Eigen::Vector2d>& points,
                      const Eigen::Matrix<double, kPoseVariables, 1>& y, PoseRobustness* out, bool with_derivatives) {
  constexpr int N = kPoseVariables + kGeometryParameters;
  using U = ceres::Jet<double, N>;
  const int m = robot.num_cables();
  CABLECAL_CHECK(m == 2, "the robust design is implemented for 2 cables");
  Eigen::Matrix<U, kPoseVariables, 1> yu;
  for (int k = 0; k < kPoseVariables; ++k) yu(k) = U(y(k), k);
  Vec2<U> exits[kMaxCables];
  U l0[kMaxCables];
  for (int i = 0; i < m; ++i) {
    for (int c = 0; c < 2; ++c) exits[i](c) = U(robot.cables[i].p_F_exit_m(c), kPoseVariables + 2 * i + c);
    l0[i] = U(0.0, kPoseVariables + 2 * m + i);  // only its derivative matters: dl_i is fixed
  }
  const Pose<U> q = yu.head<3>();
  const Eigen::Matrix<U, 2, 2> rot = Rotation(q(2));
  const Vec2<U> p(q(0), q(1));

  // R(y, g) = [l_i(q; a_i) - l_i0 - dl_i; W(q; a) t + w_g(q)] and the quantities c(y, g).
  Eigen::Matrix<U, kPoseVariables, 1> R;
  std::vector<U> c;
  for (int i = 0; i < m; ++i) c.push_back(yu(3 + i));  // t_i
  c.push_back(q(2));                                    // theta
  c.push_back(q(1));                                    // z against the laser range
  Eigen::Matrix<U, Eigen::Dynamic, 1> t(m);
  for (int i = 0; i < m; ++i) {
    const Cable& cable = robot.cables[i];
    const Vec2<U> anchor = p + rot * cable.p_P_anchor_m.cast<U>();
    const CableState<U> s = CableGeometry<U>(exits[i], U(cable.pulley_radius_m), SideSign(cable.side), anchor);
    R(i) = s.length_m - l0[i];
    t(i) = yu(3 + i);
    c.push_back(s.centre_distance_m - U(cable.pulley_radius_m));  // clearance of anchor i from its pulley
  }
  R.tail<3>() = WrenchMatrix<U>(robot, q, exits) * t + GravityWrench<U>(robot, q);
  for (const Eigen::Vector2d& b : points) {
    const Vec2<U> point = p + rot * b.cast<U>();
    c.push_back(point.x());
    c.push_back(point.y());
  }

  Eigen::Matrix<double, kPoseVariables, kPoseVariables> A;
  Eigen::Matrix<double, kPoseVariables, kGeometryParameters> B;
  for (int r = 0; r < kPoseVariables; ++r) {
    A.row(r) = R(r).v.head<kPoseVariables>().transpose();
    B.row(r) = R(r).v.tail<kGeometryParameters>().transpose();
  }
  for (int r = 0; r < 3; ++r) out->equilibrium_N(r) = R(m + r).a;
  if (with_derivatives) out->dequilibrium_dy = A.bottomRows<3>();
  Eigen::FullPivLU<Eigen::Matrix<double, kPoseVariables, kPoseVariables>> lu(A);
  if (!lu.isInvertible()) return false;
  const Eigen::Matrix<double, kPoseVariables, kGeometryParameters> dy_dg = -lu.solve(B);
  out->value.resize(c.size());
  out->spread.resize(c.size());
  if (with_derivatives) out->dvalue_dy.resize(static_cast<Eigen::Index>(c.size()), kPoseVariables);
  for (std::size_t k = 0; k < c.size(); ++k) {
    const Eigen::Matrix<double, 1, kGeometryParameters> dc_dg =
        c[k].v.head<kPoseVariables>().transpose() * dy_dg + c[k].v.tail<kGeometryParameters>().transpose();
    out->value[k] = c[k].a;
    out->spread[k] = dc_dg.norm();
    if (with_derivatives) out->dvalue_dy.row(static_cast<Eigen::Index>(k)) = c[k].v.head<kPoseVariables>().transpose();
    if (!std::isfinite(out->spread[k]) || !std::isfinite(out->value[k])) return false;
  }
  return true;
}

}  // namespace cablecal::internal
