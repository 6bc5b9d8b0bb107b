// Spatial identification, first layer (identify/spatial_identify.h).
#include "identify/spatial_identify.h"

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <cstdlib>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <utility>

#include "common/error.h"
#include "common/flatten.h"
#include "common/format.h"
#include "identify/least_squares.h"  // LevenbergMarquardtSettings
#include "model/geometry.h"
#include "model/forward_statics.h"  // PaidOutLengths
#include "model/spatial_sensor_model.h"
#include "model/spatial_statics.h"  // EvaluateSpatialHome
#include "model/swivel.h"

namespace cablecal {

namespace {

using Eigen::MatrixXd;
using Eigen::Vector3d;
using Eigen::VectorXd;

// Where each unknown of the geometry vector lives (names order, the header's file comment).
struct Layout {
  int m = 0;
  bool swivel = false;
  bool heading = false;
  bool anchors = false;
  bool platform = false;  // mass, comx, comy, comz: the statics modelled
  int exit(int i) const { return 3 * i; }
  int length(int i) const { return 3 * m + i; }
  int anchor(int i) const { return 4 * m + 3 * i; }
  int swivel_offset(int i) const { return 4 * m + anchor_coordinates() + i; }
  int yaw0() const { return 4 * m + anchor_coordinates() + (swivel ? m : 0); }
  int platform_block() const { return yaw0() + (heading ? 1 : 0); }
  int size() const { return platform_block() + (platform ? 4 : 0); }
  int exit_coordinates() const { return 3 * m; }
  int anchor_coordinates() const { return anchors ? 3 * m : 0; }
  // The coordinates a gauge may hold, exits first: a1x .. amz, then b1x .. bmz when free.
  std::vector<int> holdable() const {
    std::vector<int> out;
    for (int k = 0; k < exit_coordinates(); ++k) out.push_back(k);
    for (int k = 0; k < anchor_coordinates(); ++k) out.push_back(anchor(0) + k);
    return out;
  }
};

// ---- Residuals: each the model of model/swivel.h or model/spatial_sensor_model.h minus the
// reading, over the sensor's sigma. Pose block first, then the geometry blocks. ----

template <typename T>
SpatialPose<T> PoseOf(const T* q) {
  return Eigen::Map<const SpatialPose<T>>(q);
}

// The cable from the exit block's D through its fixed swivel axis to the anchor at pose q: the
// anchor block's b when the anchors are unknowns (b != nullptr), else the robot file's.
struct CableData {
  Vector3d k_F_swivel_axis;
  double pulley_radius_m;
  Vector3d p_P_anchor_m;
  template <typename T>
  Vec3<T> Anchor(const T* b) const {
    return b ? Vec3<T>(Eigen::Map<const Vec3<T>>(b)) : Vec3<T>(p_P_anchor_m.cast<T>());
  }
  template <typename T>
  SwivelCableState<T> At(const T* q, const T* d, const T* b) const {
    const SpatialPose<T> pose = PoseOf(q);
    const Eigen::Matrix<T, 3, 3> R = Rotation<T>(pose);
    return SwivelCable<T>(Eigen::Map<const Vec3<T>>(d), k_F_swivel_axis.cast<T>(), T(pulley_radius_m),
                          AnchorInF<T>(pose, R, Anchor(b)));
  }
};

// The cable's state at pose q and, when asked, d length / d q (1 x 6, row-major) and
// d length / d D (1 x 3), by the chain rule through the model's own gradient: the length
// depends on B - D only (SwivelCable reads rho = B - D), so dl/dB = e_F_free and dl/dD =
// -e_F_free; dB/dq is the identity on x, y, z and, on the angles, d(R b)/d(angle_a) =
// axis_a x (R b) with model/swivel.h's EulerRateAxes, so dl/d(angle_a) = axis_a . ((R b) x e).
// An AutoDiff of the whole construction on the 10 components of (q, D, l0) cost ten times as
// much (bench/README.md, "Spatial identification"). With a free anchor b (b != nullptr),
// d length / d b = R^T e_F_free (1 x 3): B = p + R b.
struct CableWithGradient {
  SwivelCableState<double> state;
  double d_pose[6];
  double d_exit[3];
  double d_anchor[3];
};

// A pose's cables are evaluated one after another with the same angles: the rotation and its
// rate axes are kept from the last call on this thread instead of computed for each cable
// (bench/README.md, "Spatial identification").
struct RotationMemo {
  double angles_rad[3] = {std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0};
  Eigen::Matrix3d R, axes;
};
const RotationMemo& RotationAt(const double* q) {
  thread_local RotationMemo memo;
  if (!(memo.angles_rad[0] == q[3] && memo.angles_rad[1] == q[4] && memo.angles_rad[2] == q[5])) {
    std::copy(q + 3, q + 6, memo.angles_rad);
    memo.R = Rotation<double>(q[3], q[4], q[5]);
    memo.axes = EulerRateAxes<double>(memo.R, q[5]);
  }
  return memo;
}

CABLECAL_FLATTEN CableWithGradient CableAndGradient(const CableData& cable, const double* q, const double* d,
                                                    const double* b, bool gradient) {
  const SpatialPose<double> pose = PoseOf(q);
  const RotationMemo& rotation = RotationAt(q);
  const Eigen::Matrix3d& R = rotation.R;
  const Vector3d r_F_anchor = R * cable.Anchor(b);
  CableWithGradient out;
  out.state = SwivelCable<double>(Eigen::Map<const Vector3d>(d), cable.k_F_swivel_axis, cable.pulley_radius_m,
                                  pose.head<3>() + r_F_anchor);
  if (!gradient) return out;
  const Vector3d& e = out.state.e_F_free;
  const Vector3d d_angles = rotation.axes.transpose() * r_F_anchor.cross(e);
  for (int a = 0; a < 3; ++a) {
    out.d_pose[a] = e(a);
    out.d_exit[a] = -e(a);
    out.d_pose[3 + a] = d_angles(a);
  }
  if (b) {
    const Vector3d d_anchor = R.transpose() * e;
    for (int k = 0; k < 3; ++k) out.d_anchor[k] = d_anchor(k);
  }
  return out;
}

// A cost's parameter blocks: `sizes`, then the anchor's 3 when it is free.
class CableCost : public ceres::CostFunction {
 protected:
  CableCost(std::initializer_list<int> sizes, bool free_anchor) : free_anchor_(free_anchor) {
    set_num_residuals(1);
    for (int s : sizes) mutable_parameter_block_sizes()->push_back(s);
    if (free_anchor) mutable_parameter_block_sizes()->push_back(3);
  }
  // The anchor block (the last one) when free, else nullptr; and its Jacobian's.
  const double* AnchorBlock(double const* const* p) const { return free_anchor_ ? p[LastBlock()] : nullptr; }
  double* AnchorJacobian(double** J) const { return free_anchor_ && J ? J[LastBlock()] : nullptr; }

 private:
  int LastBlock() const { return static_cast<int>(parameter_block_sizes().size()) - 1; }
  bool free_anchor_;
};

// Encoder: dl = l(q, D) - l0 for an inextensible cable. Parameters: q (6), D (3), l0 (1), and
// b (3) when free.
class EncoderCost final : public CableCost {
 public:
  EncoderCost(const CableData& cable, double dl_m, double inv_sigma, bool free_anchor)
      : CableCost({6, 3, 1}, free_anchor), cable_(cable), dl_m_(dl_m), inv_sigma_(inv_sigma) {}
  bool Evaluate(double const* const* p, double* r, double** J) const override {
    double* j_anchor = AnchorJacobian(J);
    const bool gradient = J != nullptr && (J[0] != nullptr || J[1] != nullptr || j_anchor != nullptr);
    const CableWithGradient c = CableAndGradient(cable_, p[0], p[1], AnchorBlock(p), gradient);
    r[0] = (c.state.length_m - p[2][0] - dl_m_) * inv_sigma_;
    if (J == nullptr) return true;
    if (J[0]) for (int a = 0; a < 6; ++a) J[0][a] = c.d_pose[a] * inv_sigma_;
    if (J[1]) for (int a = 0; a < 3; ++a) J[1][a] = c.d_exit[a] * inv_sigma_;
    if (J[2]) J[2][0] = -inv_sigma_;
    if (j_anchor) for (int a = 0; a < 3; ++a) j_anchor[a] = c.d_anchor[a] * inv_sigma_;
    return true;
  }

 private:
  CableData cable_;
  double dl_m_, inv_sigma_;
};

// Encoder of an elastic cable: the paid-out (unstretched) length at the pose's tension t of the
// cable, model/robot.h's elastic law (UnstretchedLength), less its value at home l0; its
// derivatives in the length and the tension from Jets on those two, the length's as above.
// Parameters: q (6), t (1), D (3), l0 (1), and b (3) when free.
class ElasticEncoderCost final : public CableCost {
 public:
  ElasticEncoderCost(const CableData& cable, std::optional<double> stiffness_N, double dl_m, double inv_sigma,
                     bool free_anchor)
      : CableCost({6, 1, 3, 1}, free_anchor), cable_(cable), stiffness_N_(stiffness_N), dl_m_(dl_m),
        inv_sigma_(inv_sigma) {}
  bool Evaluate(double const* const* p, double* r, double** J) const override {
    using J2 = ceres::Jet<double, 2>;
    double* j_anchor = AnchorJacobian(J);
    const bool gradient = J != nullptr && (J[0] != nullptr || J[2] != nullptr || j_anchor != nullptr);
    const CableWithGradient c = CableAndGradient(cable_, p[0], p[2], AnchorBlock(p), gradient);
    const J2 paid_out = UnstretchedLength<J2>(stiffness_N_, J2(c.state.length_m, 0), J2(p[1][0], 1));
    r[0] = (paid_out.a - p[3][0] - dl_m_) * inv_sigma_;
    if (J == nullptr) return true;
    const double dl = paid_out.v(0) * inv_sigma_;
    if (J[0]) for (int a = 0; a < 6; ++a) J[0][a] = c.d_pose[a] * dl;
    if (J[1]) J[1][0] = paid_out.v(1) * inv_sigma_;
    if (J[2]) for (int a = 0; a < 3; ++a) J[2][a] = c.d_exit[a] * dl;
    if (J[3]) J[3][0] = -inv_sigma_;
    if (j_anchor) for (int a = 0; a < 3; ++a) j_anchor[a] = c.d_anchor[a] * dl;
    return true;
  }

 private:
  CableData cable_;
  std::optional<double> stiffness_N_;
  double dl_m_, inv_sigma_;
};

// Load cell: the cable's tension (the pose block is a parameter only to tie the term to its pose).
struct LoadCellCost {
  double reading_N, inv_sigma;
  template <typename T>
  bool operator()(const T* /*q*/, const T* t, T* r) const {
    r[0] = (t[0] - T(reading_N)) * T(inv_sigma);
    return true;
  }
};

// The pose's equilibrium W(q, D) t + w_g(q, mass, c) (model/swivel.h's EquilibriumResidual, its
// columns WrenchColumn of each cable through the exit block's D rather than the file's, its
// gravity through the platform block's mass and centre of mass), force rows over
// kEquilibriumForceSigmaRelative m g, moment rows over m g kEquilibriumMomentSigma_m (the
// header; m g the file's weight). Parameters: the pose, the m tensions (1 each), the m exit
// points (3 each), the m anchors (3 each) when free, and the platform block (mass, c: 4).
// Cable i's share t_i W_i of the equilibrium's wrench at pose q (R its rotation), exit d, anchor
// b (nullptr: the robot file's).
template <typename T>
Eigen::Matrix<T, 6, 1> CableWrench(const CableData& cable, const Eigen::Matrix<T, 3, 3>& R, const T* q, const T& t,
                                   const T* d, const T* b) {
  const Vec3<T> r_F_anchor = R * cable.Anchor(b);
  return t * WrenchColumn<T>(r_F_anchor, cable.At(q, d, b));
}

struct EquilibriumCost {
  std::shared_ptr<const SpatialRobot> robot;
  std::vector<CableData> cables;
  double inv_force, inv_moment;
  bool free_anchors;
  template <typename T>
  bool operator()(T const* const* p, T* r) const {
    const int m = static_cast<int>(cables.size());
    const SpatialPose<T> pose = PoseOf(p[0]);
    const Eigen::Matrix<T, 3, 3> R = Rotation<T>(pose);
    const T* platform = p[1 + 2 * m + (free_anchors ? m : 0)];
    Eigen::Matrix<T, 6, 1> w =
        GravityWrench<T>(pose, platform[0], Vec3<T>(platform[1], platform[2], platform[3]), robot->gravity_mps2);
    for (int i = 0; i < m; ++i) {
      const T* b = free_anchors ? p[1 + 2 * m + i] : nullptr;
      w += CableWrench<T>(cables[i], R, p[0], p[1 + i][0], p[1 + m + i], b);
    }
    for (int a = 0; a < 3; ++a) {
      r[a] = w(a) * T(inv_force);
      r[3 + a] = w(3 + a) * T(inv_moment);
    }
    return true;
  }
};

// EquilibriumCost with its derivatives cable by cable: one Jet over (pose, t_i, D_i), 10
// derivatives, per cable, summed in the functor's order after gravity's, whose Jet is over
// (pose, mass, c). The same numbers to the last bit as differentiating the whole functor (a
// Jet's components do not mix, and the other cables add exact zeros to t_i's and D_i's), at a
// fraction of the cost: Ceres' dynamic autodiff ran the whole wrench, every pulley, once per 4
// parameters (10 times for 8 cables).
class EquilibriumCostFunction : public ceres::CostFunction {
 public:
  explicit EquilibriumCostFunction(EquilibriumCost f) : f_(std::move(f)) {
    const int m = static_cast<int>(f_.cables.size());
    set_num_residuals(6);
    mutable_parameter_block_sizes()->push_back(6);
    for (int i = 0; i < m; ++i) mutable_parameter_block_sizes()->push_back(1);
    for (int i = 0; i < m; ++i) mutable_parameter_block_sizes()->push_back(3);
    mutable_parameter_block_sizes()->push_back(4);
  }
  // Flattened: GCC otherwise calls the Jets' 10-vector arithmetic out of line (common/flatten.h).
  CABLECAL_FLATTEN bool Evaluate(double const* const* p, double* residuals, double** jacobians) const override {
    if (!jacobians) return f_(p, residuals);
    // pose (0..5), then t_i (6) and D_i (7..9) in a cable's Jet, mass (6) and c (7..9) in gravity's
    using J = ceres::Jet<double, 10>;
    const int m = static_cast<int>(f_.cables.size());
    std::array<J, 6> q;
    for (int a = 0; a < 6; ++a) q[a] = J(p[0][a], a);
    const SpatialPose<J> pose = PoseOf(q.data());
    const Eigen::Matrix<J, 3, 3> R = Rotation<J>(pose);
    const double* platform = p[1 + 2 * m];
    Eigen::Matrix<J, 6, 1> w = GravityWrench<J>(pose, J(platform[0], 6),
                                                Vec3<J>(J(platform[1], 7), J(platform[2], 8), J(platform[3], 9)),
                                                f_.robot->gravity_mps2);
    const double inv[6] = {f_.inv_force, f_.inv_force, f_.inv_force, f_.inv_moment, f_.inv_moment, f_.inv_moment};
    for (int i = 0; i < m; ++i) {
      std::array<J, 3> d;
      for (int a = 0; a < 3; ++a) d[a] = J(p[1 + m + i][a], 7 + a);
      const Eigen::Matrix<J, 6, 1> term =
          CableWrench<J>(f_.cables[i], R, q.data(), J(p[1 + i][0], 6), d.data(), static_cast<const J*>(nullptr));
      for (int a = 0; a < 6; ++a) {
        w(a).a += term(a).a;
        w(a).v.head<6>() += term(a).v.head<6>();
        if (jacobians[1 + i]) jacobians[1 + i][a] = term(a).v(6) * inv[a];
        if (jacobians[1 + m + i]) {
          for (int c = 0; c < 3; ++c) jacobians[1 + m + i][3 * a + c] = term(a).v(7 + c) * inv[a];
        }
      }
    }
    for (int a = 0; a < 6; ++a) {
      residuals[a] = w(a).a * inv[a];
      if (jacobians[0]) {
        for (int c = 0; c < 6; ++c) jacobians[0][6 * a + c] = w(a).v(c) * inv[a];
      }
      // The cables added to the pose's components only: 6..9 are still gravity's.
      if (jacobians[1 + 2 * m]) {
        for (int c = 0; c < 4; ++c) jacobians[1 + 2 * m][4 * a + c] = w(a).v(6 + c) * inv[a];
      }
    }
    return true;
  }

 private:
  EquilibriumCost f_;
};

// Swivel encoder: the pulley's angle about k from the reference direction u_ref (the nominal
// home's), less the encoder's zero offset sw0; the difference from the reading wrapped so that
// a reading near +-pi does not jump. Parameters: q, D, sw0, and b when free (the second call).
struct SwivelCost {
  CableData cable;
  Vector3d u_F_reference;
  double reading_rad, inv_sigma;
  template <typename T>
  bool operator()(const T* q, const T* d, const T* sw0, T* r) const {
    return Residual(q, d, sw0, static_cast<const T*>(nullptr), r);
  }
  template <typename T>
  bool operator()(const T* q, const T* d, const T* sw0, const T* b, T* r) const {
    return Residual(q, d, sw0, b, r);
  }
  template <typename T>
  bool Residual(const T* q, const T* d, const T* sw0, const T* b, T* r) const {
    const T model =
        SwivelReading<T>(cable.At(q, d, b), cable.k_F_swivel_axis.cast<T>(), u_F_reference.cast<T>()) - sw0[0];
    r[0] = WrappedAngle<T>(model - T(reading_rad)) * T(inv_sigma);
    return true;
  }
};

struct InclinometerCost {
  Eigen::Vector2d reading_rad;
  double inv_sigma;
  template <typename T>
  bool operator()(const T* q, T* r) const {
    const Vec2<T> model = InclinometerReading<T>(PoseOf(q));
    for (int a = 0; a < 2; ++a) r[a] = WrappedAngle<T>(model(a) - T(reading_rad(a))) * T(inv_sigma);
    return true;
  }
};

struct LaserCost {
  double floor_z_m, reading_m, inv_sigma;
  template <typename T>
  bool operator()(const T* q, T* r) const {
    r[0] = (LaserReading<T>(PoseOf(q), floor_z_m) - T(reading_m)) * T(inv_sigma);
    return true;
  }
};

struct PositionCost {
  Vector3d p_P_target_m, reading_m;
  double inv_sigma;
  template <typename T>
  bool operator()(const T* q, T* r) const {
    const SpatialPose<T> pose = PoseOf(q);
    const Vec3<T> model = PositionReading<T>(pose, Rotation<T>(pose), p_P_target_m.cast<T>());
    for (int a = 0; a < 3; ++a) r[a] = (model(a) - T(reading_m(a))) * T(inv_sigma);
    return true;
  }
};

struct HeadingCost {
  double reading_rad, inv_sigma;
  template <typename T>
  bool operator()(const T* q, const T* yaw0, T* r) const {
    r[0] = WrappedAngle<T>(HeadingReading<T>(PoseOf(q), yaw0[0]) - T(reading_rad)) * T(inv_sigma);
    return true;
  }
};

// gauge prior: the tracker's survey of an exit point.
struct ExitPriorCost {
  Vector3d nominal_m;
  double inv_sigma;
  template <typename T>
  bool operator()(const T* d, T* r) const {
    for (int a = 0; a < 3; ++a) r[a] = (d[a] - T(nominal_m(a))) * T(inv_sigma);
    return true;
  }
};

// The platform's mass and centre of mass about the robot file's, over their priors' sigmas.
struct PlatformPriorCost {
  Eigen::Vector4d nominal, inv_sigma;
  template <typename T>
  bool operator()(const T* x, T* r) const {
    for (int a = 0; a < 4; ++a) r[a] = (x[a] - T(nominal(a))) * T(inv_sigma(a));
    return true;
  }
};

// One residual block: its cost, the pose it reads (-1: none) and its geometry blocks (offset
// into the geometry vector and size), in the cost's parameter order after the pose.
struct Term {
  std::unique_ptr<ceres::CostFunction> cost;
  int pose = -1;
  std::vector<int> tension_cables;  // the pose's tension blocks it reads, after the pose block
  std::vector<int> block_offset, block_size;
  int reading = -1;  // -1: a prior
  bool gauge_prior = false;  // the tracker's prior on the exits (--gauge prior), not the platform's
  int sensor = -1;   // -1: an encoder; kEquilibriumTerm; else SpatialSensor
  int value = 0;     // the first value of the reading's sensor it computes (the cable, ...)
  int size() const { return cost->num_residuals(); }
};

constexpr int kEquilibriumTerm = -2;

// The vector of a reading's per-value record (SpatialReadingFit, SpatialReadingLeverage) that
// term t's values go into: its sensor's, the encoders' or the equilibrium's.
template <typename PerReading>
VectorXd& ValuesOf(PerReading& f, const Term& t) {
  return t.sensor == kEquilibriumTerm ? f.equilibrium : t.sensor < 0 ? f.encoders : f.sensors[t.sensor];
}

// Value v of term t in words: "encoder 3", "inclinometer roll", "equilibrium force x".
std::string ValueName(const Term& t, int v, int num_cables) {
  if (t.sensor == kEquilibriumTerm) return std::string("equilibrium ") + (v < 3 ? "force " : "moment ") + "xyz"[v % 3];
  const int index = t.value + v;
  if (t.sensor < 0) return "encoder " + std::to_string(index + 1);
  const SpatialSensor sensor = static_cast<SpatialSensor>(t.sensor);
  return std::string(ToString(sensor)) + " " + SpatialSensorColumns(sensor, num_cables)[index];
}

template <typename Functor, int... Sizes>
std::unique_ptr<ceres::CostFunction> Cost(Functor f) {
  return std::make_unique<ceres::AutoDiffCostFunction<Functor, Sizes...>>(new Functor(f));
}

// A pose's term as Ceres sees it when the pose has tensions: one parameter block per pose, its
// 6 coordinates then its tensions (so that the Schur elimination takes them together: a pose's
// blocks may share no residual), the term's own cost evaluated on views of it.
class LocalBlockCost : public ceres::CostFunction {
 public:
  LocalBlockCost(const Term& term, int local) : term_(term), local_(local) {
    set_num_residuals(term.size());
    mutable_parameter_block_sizes()->push_back(local);
    for (int s : term.block_size) mutable_parameter_block_sizes()->push_back(s);
  }
  bool Evaluate(double const* const* p, double* r, double** J) const override {
    const std::vector<int>& tc = term_.tension_cables;
    const int n = num_residuals();
    std::vector<const double*> inner{p[0]};
    for (int i : tc) inner.push_back(p[0] + 6 + i);
    for (std::size_t b = 0; b < term_.block_size.size(); ++b) inner.push_back(p[1 + b]);
    if (J == nullptr) return term_.cost->Evaluate(inner.data(), r, nullptr);
    std::vector<double> pose_jac(J[0] ? n * 6 : 0), tension_jac(J[0] ? n * tc.size() : 0);
    std::vector<double*> inner_jac{J[0] ? pose_jac.data() : nullptr};
    for (std::size_t k = 0; k < tc.size(); ++k) inner_jac.push_back(J[0] ? tension_jac.data() + k * n : nullptr);
    for (std::size_t b = 0; b < term_.block_size.size(); ++b) inner_jac.push_back(J[1 + b]);
    if (!term_.cost->Evaluate(inner.data(), r, inner_jac.data())) return false;
    if (J[0]) {
      std::fill(J[0], J[0] + n * local_, 0.0);
      for (int row = 0; row < n; ++row) {
        for (int c = 0; c < 6; ++c) J[0][row * local_ + c] = pose_jac[row * 6 + c];
        for (std::size_t k = 0; k < tc.size(); ++k) J[0][row * local_ + 6 + tc[k]] = tension_jac[k * n + row];
      }
    }
    return true;
  }

 private:
  const Term& term_;
  int local_;
};

struct Model {
  Layout layout;
  int nt = 0;  // tension unknowns per pose: m when the statics are modelled, else 0
  int local() const { return 6 + nt; }
  std::vector<Term> terms;
  std::vector<int> pose_ids;
  std::vector<std::string> pose_where;       // the first reading's where, per pose
  std::vector<std::vector<int>> pose_terms;  // per pose: its terms
  std::vector<int> pose_values;              // per pose: its residual count
  std::vector<int> prior_terms;
  std::vector<std::string> unused_sensors;
  int num_values = 0;
};

double SigmaOf(const SpatialRobot& robot, SpatialSensor s, const std::string& where) {
  const std::optional<RangedNoise> noise = SpatialSensorNoise(robot.sensors, s);
  if (!noise) {
    throw InputError(where, ToString(s),
                     "the readings have this sensor's columns but the robot file has no sensors." +
                         std::string(ToString(s)) + ": its sigma is unknown");
  }
  if (!(noise->sigma() > 0.0)) throw InputError(robot.source, "sensors." + std::string(ToString(s)), "sigma is 0");
  return noise->sigma();
}

Model BuildModel(const SpatialRobot& robot, const std::vector<SpatialMeasurement>& readings, bool prior,
                 bool statics, bool anchors) {
  Model model;
  const int m = robot.num_cables();
  if (readings.empty()) throw InputError("readings", "", "no readings: nothing to identify");
  Layout& L = model.layout;
  L.m = m;
  L.anchors = anchors;
  // A cable term's geometry blocks: `blocks` (offset, size), then its anchor when free.
  const auto cable_blocks = [&L](int i, std::vector<int> offset, std::vector<int> size) {
    if (L.anchors) {
      offset.push_back(L.anchor(i));
      size.push_back(3);
    }
    return std::make_pair(offset, size);
  };
  bool load_cells = false;
  for (const SpatialMeasurement& r : readings) {
    L.swivel = L.swivel || r.has(SpatialSensor::kSwivel);
    L.heading = L.heading || r.has(SpatialSensor::kHeading);
    load_cells = load_cells || r.has(SpatialSensor::kLoadCell);
  }
  // The statics join when they carry information (the header's file comment).
  int inextensible = 0, first_inextensible = -1;
  for (int i = 0; i < m; ++i) {
    if (robot.cables[i].stiffness_N) continue;
    if (first_inextensible < 0) first_inextensible = i;
    ++inextensible;
  }
  model.nt = statics && (load_cells || inextensible < m || m < 6) ? m : 0;
  L.platform = model.nt > 0;
  if (model.nt > 0 && inextensible > 6) {
    // W t = -w_g fixes 6 combinations of the tensions; a rigid cable's length says nothing of
    // its own, so the rest of more than 6 rigid cables' tensions is free whatever is read.
    const std::string why = std::to_string(inextensible) +
                            " cables without stiffness: their tensions are indeterminate from the readings (the "
                            "equilibrium fixes only 6 combinations of them, and an inextensible cable's length "
                            "says nothing of its tension)";
    if (load_cells) {
      throw InputError(robot.source, "sensors.load_cell",
                       "load-cell readings on a robot with " + why + ": give every cable its stiffness (cables[" +
                           std::to_string(first_inextensible) + "].stiffness, ...) or leave out the f1..f" +
                           std::to_string(m) + " columns");
    }
    throw InputError(robot.source, "cables[" + std::to_string(first_inextensible) + "].stiffness",
                     "some cables stretch but " + why + ": give every cable its stiffness, or none");
  }
  const double weight_N = robot.platform_mass_kg * robot.gravity_mps2;
  if (model.nt > 0 && !(weight_N > 0.0)) {
    throw InputError(robot.source, "platform.mass", "the equilibrium needs the platform's weight, and it is 0");
  }
  auto shared_robot = std::make_shared<const SpatialRobot>(robot);
  if (!(robot.sensors.encoder_sigma_m > 0.0)) throw InputError(robot.source, "sensors.encoder", "sigma is 0");
  const double inv_encoder = 1.0 / robot.sensors.encoder_sigma_m;
  const SpatialSensorZero reference = SensorZeroAt(robot, robot.home_pose());
  std::map<int, int> pose_of_id;
  for (int k = 0; k < static_cast<int>(readings.size()); ++k) {
    const SpatialMeasurement& r = readings[k];
    const std::string where = r.where.empty() ? "reading " + std::to_string(k + 1) + " (pose " +
                                                    std::to_string(r.pose_id) + ")"
                                              : r.where;
    if (r.dl_m.size() != m) {
      throw InputError(where, "dl", std::to_string(r.dl_m.size()) + " encoder values for a robot of " +
                                        std::to_string(m) + " cables");
    }
    auto [it, added] = pose_of_id.emplace(r.pose_id, static_cast<int>(model.pose_ids.size()));
    if (added) {
      model.pose_ids.push_back(r.pose_id);
      model.pose_where.push_back(where);
      model.pose_terms.emplace_back();
      model.pose_values.push_back(0);
    }
    const int j = it->second;
    const auto add = [&](std::unique_ptr<ceres::CostFunction> cost, std::vector<int> offset, std::vector<int> size,
                         int sensor, int value, std::vector<int> tension_cables = {}) {
      Term t;
      t.cost = std::move(cost);
      t.pose = j;
      t.tension_cables = std::move(tension_cables);
      t.block_offset = std::move(offset);
      t.block_size = std::move(size);
      t.reading = k;
      t.sensor = sensor;
      t.value = value;
      model.pose_terms[j].push_back(static_cast<int>(model.terms.size()));
      model.pose_values[j] += t.size();
      model.num_values += t.size();
      model.terms.push_back(std::move(t));
    };
    if (added && model.nt > 0) {  // one equilibrium per pose, however often it was read
      std::vector<CableData> cables;
      std::vector<int> offset, size, tension_cables;
      for (int i = 0; i < m; ++i) {
        const SpatialCable& c = robot.cables[i];
        cables.push_back(CableData{c.k_F_swivel_axis, c.pulley_radius_m, c.p_P_anchor_m});
        offset.push_back(L.exit(i));
        size.push_back(3);
        tension_cables.push_back(i);
      }
      for (int i = 0; i < m && L.anchors; ++i) {
        offset.push_back(L.anchor(i));
        size.push_back(3);
      }
      offset.push_back(L.platform_block());
      size.push_back(4);
      const EquilibriumCost f{shared_robot, cables, 1.0 / (kEquilibriumForceSigmaRelative * weight_N),
                              1.0 / (kEquilibriumMomentSigma_m * weight_N), L.anchors};
      if (!L.anchors) {
        add(std::make_unique<EquilibriumCostFunction>(f), offset, size, kEquilibriumTerm, 0, tension_cables);
      } else {
        // Free anchors: Ceres' dynamic autodiff over every block (EquilibriumCostFunction's
        // cable-by-cable Jet covers the pose, tension and exit blocks only).
        auto* cost = new ceres::DynamicAutoDiffCostFunction<EquilibriumCost, 4>(new EquilibriumCost(f));
        cost->AddParameterBlock(6);
        for (int i = 0; i < m; ++i) cost->AddParameterBlock(1);
        for (std::size_t b = 0; b < offset.size(); ++b) cost->AddParameterBlock(size[b]);
        cost->SetNumResiduals(6);
        add(std::unique_ptr<ceres::CostFunction>(cost), offset, size, kEquilibriumTerm, 0, tension_cables);
      }
    }
    for (int i = 0; i < m; ++i) {
      const SpatialCable& c = robot.cables[i];
      const CableData cable{c.k_F_swivel_axis, c.pulley_radius_m, c.p_P_anchor_m};
      const auto [offset, size] = cable_blocks(i, {L.exit(i), L.length(i)}, {3, 1});
      if (model.nt > 0 && c.stiffness_N) {
        add(std::make_unique<ElasticEncoderCost>(cable, c.stiffness_N, r.dl_m(i), inv_encoder, L.anchors), offset,
            size, -1, i, {i});
      } else {
        add(std::make_unique<EncoderCost>(cable, r.dl_m(i), inv_encoder, L.anchors), offset, size, -1, i);
      }
    }
    for (const SpatialSensor s : kSpatialSensors) {
      if (!r.has(s)) continue;
      const std::string sname = ToString(s);
      if (r.values(s).size() != SpatialSensorSize(s, m)) {
        throw InputError(where, sname, std::to_string(r.values(s).size()) + " values, expected " +
                                           std::to_string(SpatialSensorSize(s, m)));
      }
      if (s == SpatialSensor::kLoadCell && model.nt == 0) {  // the statics left out (options.statics)
        if (std::find(model.unused_sensors.begin(), model.unused_sensors.end(), sname) == model.unused_sensors.end()) {
          model.unused_sensors.push_back(sname);
        }
        continue;
      }
      const double inv = 1.0 / SigmaOf(robot, s, where);
      const VectorXd& v = r.values(s);
      const int sensor = static_cast<int>(s);
      switch (s) {
        case SpatialSensor::kInclinometer:
          add(Cost<InclinometerCost, 2, 6>(InclinometerCost{v.head<2>(), inv}), {}, {}, sensor, 0);
          break;
        case SpatialSensor::kLaser:
          add(Cost<LaserCost, 1, 6>(LaserCost{robot.p_F_frame_min_m.z(), v(0), inv}), {}, {}, sensor, 0);
          break;
        case SpatialSensor::kPosition:
          add(Cost<PositionCost, 3, 6>(PositionCost{robot.sensors.position->p_P_target_m, v.head<3>(), inv}), {}, {},
              sensor, 0);
          break;
        case SpatialSensor::kSwivel:
          for (int i = 0; i < m; ++i) {
            const SpatialCable& c = robot.cables[i];
            const CableData cable{c.k_F_swivel_axis, c.pulley_radius_m, c.p_P_anchor_m};
            const SwivelCost f{cable, reference.u_F[i], v(i), inv};
            const auto [offset, size] = cable_blocks(i, {L.exit(i), L.swivel_offset(i)}, {3, 1});
            add(L.anchors ? Cost<SwivelCost, 1, 6, 3, 1, 3>(f) : Cost<SwivelCost, 1, 6, 3, 1>(f), offset, size,
                sensor, i);
          }
          break;
        case SpatialSensor::kHeading:
          add(Cost<HeadingCost, 1, 6, 1>(HeadingCost{v(0), inv}), {L.yaw0()}, {1}, sensor, 0);
          break;
        case SpatialSensor::kLoadCell:
          for (int i = 0; i < m; ++i) add(Cost<LoadCellCost, 1, 6, 1>(LoadCellCost{v(i), inv}), {}, {}, sensor, i, {i});
          break;
      }
    }
  }
  if (L.platform) {
    Term t;
    t.cost = Cost<PlatformPriorCost, 4, 4>(
        PlatformPriorCost{robot.platform_values(), SpatialPlatformPriorSigma(robot).cwiseInverse()});
    t.block_offset = {L.platform_block()};
    t.block_size = {4};
    model.prior_terms.push_back(static_cast<int>(model.terms.size()));
    model.num_values += 4;
    model.terms.push_back(std::move(t));
  }
  if (prior) {
    if (!robot.sensors.tracker_sigma_m || !(*robot.sensors.tracker_sigma_m > 0.0)) {
      throw InputError("--gauge", "prior", "the robot file " + robot.source + " gives no sensors.tracker sigma");
    }
    for (int i = 0; i < m; ++i) {
      Term t;
      t.cost = Cost<ExitPriorCost, 3, 3>(ExitPriorCost{robot.cables[i].p_F_exit_m, 1.0 / *robot.sensors.tracker_sigma_m});
      t.block_offset = {L.exit(i)};
      t.block_size = {3};
      t.value = i;
      t.gauge_prior = true;
      model.prior_terms.push_back(static_cast<int>(model.terms.size()));
      model.num_values += 3;
      model.terms.push_back(std::move(t));
    }
  }
  return model;
}

// Each pose's local unknowns: its 6 coordinates, then its tensions (Model::nt, N).
using Locals = std::vector<VectorXd>;

// A term's residuals and (when asked) its Jacobians: d r / d local (size x (6 + nt): the pose's
// coordinates, then its tensions) and d r / d geometry (size x p, only its blocks' columns
// nonzero); `local` is the term's pose's local unknowns (ignored for a term of no pose). The
// blocks not asked for are not computed (nullptr to the cost).
void EvaluateTerm(const Term& t, const VectorXd& g, const double* local, int local_size, double* residuals,
                  MatrixXd* d_local, MatrixXd* d_geometry) {
  constexpr int kMaxBlocks = 64;
  const double* params[kMaxBlocks];
  int np = 0;
  const int tensions = static_cast<int>(t.tension_cables.size());
  CABLECAL_CHECK(2 + tensions + static_cast<int>(t.block_offset.size()) <= kMaxBlocks, "too many parameter blocks");
  if (t.pose >= 0) params[np++] = local;
  for (int i : t.tension_cables) params[np++] = local + 6 + i;
  for (int b : t.block_offset) params[np++] = g.data() + b;
  const int n = t.size();
  using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  // Row-major per block, as Ceres writes them: the pose's n x 6, each tension's n x 1, each
  // geometry block's n x size, one buffer.
  int total = 0;
  if (t.pose >= 0 && d_local) total += n * (6 + tensions);
  if (d_geometry) {
    for (int s : t.block_size) total += n * s;
  }
  double buffer_stack[256];
  std::vector<double> buffer_heap;
  double* buffer = buffer_stack;
  if (total > 256) {
    buffer_heap.resize(total);
    buffer = buffer_heap.data();
  }
  double* jac_ptr[kMaxBlocks];
  int next = 0, offset = 0;
  if (t.pose >= 0) {
    jac_ptr[next++] = d_local ? buffer : nullptr;
    if (d_local) offset += 6 * n;
    for (int k = 0; k < tensions; ++k) {
      jac_ptr[next++] = d_local ? buffer + offset : nullptr;
      if (d_local) offset += n;
    }
  }
  const int first_geometry = next;
  for (int s : t.block_size) {
    jac_ptr[next++] = d_geometry ? buffer + offset : nullptr;
    if (d_geometry) offset += n * s;
  }
  const bool any = d_local || d_geometry;
  const bool ok = t.cost->Evaluate(params, residuals, any ? jac_ptr : nullptr);
  CABLECAL_CHECK(ok, "a spatial residual could not be evaluated");
  if (!any) return;
  if (d_local) {
    if (t.pose >= 0) {
      d_local->setZero(n, local_size);
      d_local->leftCols(6) = Eigen::Map<const RowMajor>(jac_ptr[0], n, 6);
      for (int k = 0; k < tensions; ++k) {
        d_local->col(6 + t.tension_cables[k]) = Eigen::Map<const VectorXd>(jac_ptr[1 + k], n);
      }
    } else {
      d_local->setZero(n, 6);
    }
  }
  if (d_geometry) {
    d_geometry->setZero(n, g.size());
    for (std::size_t b = 0; b < t.block_offset.size(); ++b) {
      d_geometry->middleCols(t.block_offset[b], t.block_size[b]) =
          Eigen::Map<const RowMajor>(jac_ptr[first_geometry + b], n, t.block_size[b]);
    }
  }
}
void EvaluateTerm(const Term& t, const VectorXd& g, const Locals& locals, double* residuals, MatrixXd* d_local,
                  MatrixXd* d_geometry) {
  const VectorXd* local = t.pose >= 0 ? &locals[t.pose] : nullptr;
  EvaluateTerm(t, g, local ? local->data() : nullptr, local ? static_cast<int>(local->size()) : 0, residuals, d_local,
               d_geometry);
}

// The tensions nearest t_N that hold the nominal platform at pose q in exact equilibrium:
// t + W^+ (-w_g - W t), least squares through the complete orthogonal decomposition; from
// t = 0, the least-norm ones.
VectorXd BalancedTensions(const SpatialRobot& nominal, const SpatialPose<double>& q, const VectorXd& t_N) {
  const Eigen::Matrix<double, 6, Eigen::Dynamic> W = WrenchMatrix<double>(nominal, q);
  const Eigen::Matrix<double, 6, 1> w_g = GravityWrench<double>(nominal, q);
  const VectorXd misfit = -w_g - W * t_N;
  return t_N + MatrixXd(W).completeOrthogonalDecomposition().solve(misfit);
}

// The starting local unknowns of pose j: Levenberg-Marquardt on its own readings (and its
// equilibrium) alone, from `start`, with the geometry g (nominal: exits as in the file, l_i0
// the nominal home's lengths). The first `fixed` unknowns stay as `start` has them (the pose,
// while the tensions are fitted to it). SolveBlockArrow refits its candidates' poses with it too.
VectorXd StartingLocal(const Model& model, int j, const VectorXd& g, const VectorXd& start, int fixed = 0,
                       int max_iterations = 200) {
  const int rows = model.pose_values[j];
  const int cols = start.size();
  const int free = cols - fixed;
  MatrixXd jp;
  const auto evaluate = [&](const VectorXd& x, VectorXd* r, MatrixXd* J) {
    r->resize(rows);
    if (J) J->resize(rows, cols);
    int row = 0;
    for (int k : model.pose_terms[j]) {
      const Term& t = model.terms[k];
      EvaluateTerm(t, g, x.data(), cols, r->data() + row, J ? &jp : nullptr, nullptr);
      if (J) J->middleRows(row, t.size()) = jp;
      row += t.size();
    }
  };
  VectorXd x = start;
  VectorXd r, r_new;
  MatrixXd J, J_new;
  evaluate(x, &r, &J);
  double cost = r.squaredNorm(), lambda = 1e-6;
  // A start needs no more than a tenth of a nanometre: a step below 1e-10 (1 + |x|) ends it,
  // taken or not (one refused that small is rounding), as does a cost that no longer falls by
  // 1e-12 of itself. Ceres polishes from here; before this rule a pose that the nominal
  // geometry does not fit exactly spent 10 to 30 evaluations raising the damping to 1e12.
  for (int it = 0; it < max_iterations && cost > 0.0; ++it) {
    const MatrixXd H = J.rightCols(free).transpose() * J.rightCols(free);
    const VectorXd grad = J.rightCols(free).transpose() * r;
    MatrixXd damped = H;
    damped.diagonal() += lambda * (H.diagonal().array() + 1e-12).matrix();
    VectorXd step = damped.ldlt().solve(-grad);
    // A Gauss-Newton step from home can turn the platform by radians into another orientation
    // that fits the cable lengths locally (ipanema1: pitch -2.9 rad for a pose at -0.2): the
    // orientation moves at most kMaxStartTurn_rad a step, which keeps the start on the path
    // from home to the pose.
    constexpr double kMaxStartTurn_rad = 0.25;
    if (fixed == 0) {
      const double turn = step.segment<3>(3).lpNorm<Eigen::Infinity>();
      if (turn > kMaxStartTurn_rad) step *= kMaxStartTurn_rad / turn;
    }
    const bool negligible = step.norm() < 1e-10 * (1.0 + x.norm());
    VectorXd trial = x;
    trial.tail(free) += step;
    evaluate(trial, &r_new, &J_new);
    const double cost_new = r_new.squaredNorm();
    if (std::isfinite(cost_new) && cost_new < cost) {
      const bool stalled = cost - cost_new < 1e-12 * cost;
      x = trial;
      cost = cost_new;
      lambda = std::max(lambda / 10.0, 1e-12);
      r.swap(r_new);
      J.swap(J_new);
      if (negligible || stalled) break;
    } else {
      // Refused, but no worse than rounding: the start is at its minimum to the digits the cost
      // has (a pose at 1e4 N of tensions spent up to 8 more evaluations raising the damping).
      const bool at_rounding = std::abs(cost_new - cost) <= 1e-12 * cost;
      if (negligible || at_rounding) break;
      lambda *= 10.0;
      if (lambda > 1e12) break;
    }
  }
  return x;
}

std::string LocalCoordinateNames(const VectorXd& v) {
  std::string out;
  for (int a = 0; a < v.size(); ++a) {
    if (std::abs(v(a)) > 0.1 * v.cwiseAbs().maxCoeff()) {
      out += (out.empty() ? "" : ", ") +
             (a < 6 ? std::string(SpatialKind::kPoseNames[a]) : "the tension t" + std::to_string(a - 5));
    }
  }
  return out;
}

// Whether the upper-triangular R's singular values satisfy s_min > kSpatialNullThreshold s_max,
// cheaply when the answer is clearly yes: s_min >= 1 / |R^-1|_F and s_max <= |R|_F (each
// within a factor sqrt(size) of the truth), so that a ratio of the bounds above the threshold
// settles it; otherwise (a deficient matrix, or one within that factor of the threshold) the
// singular values decide. `inverse` receives R^-1 when computed.
bool SurelyOfFullRank(const MatrixXd& R, MatrixXd* inverse = nullptr) {
  const int k = R.cols();
  MatrixXd R_inv = R.triangularView<Eigen::Upper>().solve(MatrixXd::Identity(k, k));
  const double bound = 1.0 / R_inv.norm();
  const bool certain = R_inv.allFinite() && bound > kSpatialNullThreshold * R.norm();
  if (inverse) *inverse = std::move(R_inv);
  if (certain) return true;
  const VectorXd s = Eigen::BDCSVD<MatrixXd>(R).singularValues();
  return s(k - 1) > kSpatialNullThreshold * s(0);
}

// Pose j's Jacobians at (g, locals), its terms' rows in order: d r / d local (values x
// Model::local()) and d r / d geometry (values x p).
void PoseJacobians(const Model& model, int j, const VectorXd& g, const Locals& locals, MatrixXd* Jq, MatrixXd* Jg) {
  const int rows = model.pose_values[j];
  Jq->resize(rows, model.local());
  Jg->resize(rows, g.size());
  VectorXd r(rows);
  int row = 0;
  for (int k : model.pose_terms[j]) {
    const Term& t = model.terms[k];
    MatrixXd jp, jg;
    EvaluateTerm(t, g, locals, r.data() + row, &jp, &jg);
    Jq->middleRows(row, t.size()) = jp;
    Jg->middleRows(row, t.size()) = jg;
    row += t.size();
  }
}

// The reduced geometry Jacobian: for each pose, its rows projected onto the orthogonal
// complement of its own pose columns (Householder QR, nothing squared), so that the stacked
// rows see exactly the geometry directions no pose change can compensate; the priors' rows as
// they are (the exits' tracker prior only with_prior: it is a gauge, the platform's is
// knowledge). InputError for a pose its own readings do not determine (when `refuse`).
// What the leverages need of each pose (TermLeverages), kept by ReducedJacobian as it goes: the
// diagonal of the pose's own hat matrix (Q1's rows' squared norms, Jq = Q1 R) and its geometry
// rows less their projection onto the pose's columns (Q2 Q2^T Jg, in the readings' rows, not
// rotated); for a prior's rows, those rows. Empty for a pose ReducedJacobian skipped.
struct LeverageParts {
  VectorXd pose_h;
  MatrixXd m;
};

MatrixXd ReducedJacobian(const Model& model, const VectorXd& g, const Locals& locals, bool refuse, bool with_prior,
                         std::vector<LeverageParts>* parts = nullptr) {
  const int p = g.size();
  const int cols = model.local();
  std::vector<MatrixXd> blocks;
  int total = 0;
  if (parts) parts->assign(model.terms.size(), {});
  for (std::size_t j = 0; j < model.pose_ids.size(); ++j) {
    const int rows = model.pose_values[j];
    MatrixXd Jq, Jg;
    PoseJacobians(model, static_cast<int>(j), g, locals, &Jq, &Jg);
    // The pose's singular values from the QR's triangular factor (the same as Jq's), its full
    // SVD only to name what a refused pose leaves unseen. The rank is judged with every column
    // scaled to unit norm (R D is the factor of Jq D): a tension's column is in 1/N, a
    // coordinate's in 1/m or 1/rad, and with the equilibrium rows whitened by the statics'
    // tolerance a 4-cable pose's largest and smallest singular values were 4e-10 apart while
    // its tensions were well determined (W of full rank).
    Eigen::HouseholderQR<MatrixXd> qr(Jq);
    const VectorXd column_norms = Jq.colwise().norm().transpose();
    bool deficient = rows < cols || !(column_norms.minCoeff() > 0.0);
    if (!deficient) {
      const MatrixXd R = qr.matrixQR().topRows(cols).triangularView<Eigen::Upper>();
      deficient = !SurelyOfFullRank(R * column_norms.cwiseInverse().asDiagonal());
    }
    if (deficient) {
      if (!refuse) continue;
      const Eigen::JacobiSVD<MatrixXd> svd(
          Jq * column_norms.cwiseMax(std::numeric_limits<double>::min()).cwiseInverse().asDiagonal(),
          Eigen::ComputeFullV);
      const std::string unknowns = model.nt > 0 ? "6 coordinates and " + std::to_string(model.nt) + " tensions"
                                                : "6 coordinates";
      throw InputError(model.pose_where[j], "pose " + std::to_string(model.pose_ids[j]),
                       "its own readings (" + std::to_string(rows) + " values" +
                           (model.nt > 0 ? ", the equilibrium's 6 among them" : "") + ") do not determine the pose's " +
                           unknowns + " (unseen: " + LocalCoordinateNames(svd.matrixV().col(cols - 1)) +
                           "): no reading fixes it; add a sensor that sees it, or more cables' encoders");
    }
    Jg.applyOnTheLeft(qr.householderQ().adjoint());  // Q^T Jg without forming Q
    const MatrixXd& projected = Jg;
    blocks.push_back(projected.bottomRows(rows - cols));
    total += rows - cols;
    if (parts) {
      const MatrixXd Q = qr.householderQ() * MatrixXd::Identity(rows, rows);
      const VectorXd pose_h = Q.leftCols(cols).rowwise().squaredNorm();
      const MatrixXd m = Q.rightCols(rows - cols) * projected.bottomRows(rows - cols);
      int row = 0;
      for (int k : model.pose_terms[j]) {
        const int size = model.terms[k].size();
        (*parts)[k] = {pose_h.segment(row, size), m.middleRows(row, size)};
        row += size;
      }
    }
  }
  for (int k : model.prior_terms) {
    const Term& t = model.terms[k];
    if (t.gauge_prior && !with_prior) continue;
    MatrixXd jg;
    VectorXd r(t.size());
    EvaluateTerm(t, g, locals, r.data(), nullptr, &jg);
    if (parts) (*parts)[k] = {VectorXd::Zero(t.size()), jg};
    blocks.push_back(jg);
    total += t.size();
  }
  MatrixXd A(total, p);
  int row = 0;
  for (const MatrixXd& b : blocks) {
    A.middleRows(row, b.rows()) = b;
    row += b.rows();
  }
  return A;
}

// Each term's rows' leverages (SpatialReadingLeverage) from ReducedJacobian's LeverageParts,
// `free` the geometry columns not held and `cov_free` their covariance (the inverse of the
// reduced Jacobian's normal matrix, priors included, as IdentifySpatial computes it). The hat
// matrix of the whole whitened fit splits by pose (Frisch-Waugh): a row's leverage is its
// pose's own part plus the geometry's, m^T C m. A pose ReducedJacobian skipped (its own
// readings do not determine it) gets NaN.
struct TermLeverage {
  VectorXd total, geometry;  // per row: h, and its geometry part m^T C m
};
std::vector<TermLeverage> TermLeverages(const Model& model, const std::vector<LeverageParts>& parts,
                                        const std::vector<int>& free, const MatrixXd& cov_free) {
  // Every term's free columns stacked, for one product with the covariance.
  int total = 0;
  for (std::size_t k = 0; k < model.terms.size(); ++k) total += parts[k].m.rows();
  MatrixXd m_free(total, free.size());
  for (std::size_t k = 0, row = 0; k < model.terms.size(); row += parts[k].m.rows(), ++k) {
    for (std::size_t c = 0; c < free.size(); ++c) m_free.col(c).segment(row, parts[k].m.rows()) = parts[k].m.col(free[c]);
  }
  const VectorXd geometry = (m_free * cov_free).cwiseProduct(m_free).rowwise().sum();
  std::vector<TermLeverage> out(model.terms.size());
  for (std::size_t k = 0, row = 0; k < model.terms.size(); row += parts[k].m.rows(), ++k) {
    const int size = model.terms[k].size();
    if (parts[k].m.rows() != size) {
      out[k].total = out[k].geometry = VectorXd::Constant(size, std::numeric_limits<double>::quiet_NaN());
      continue;
    }
    out[k].geometry = geometry.segment(row, size);
    out[k].total = parts[k].pose_h + out[k].geometry;
  }
  return out;
}

// A's p x p triangular factor R (A = Q R; A may have thousands of rows): R^T R = A^T A.
MatrixXd TriangularFactor(const MatrixXd& A) {
  const int p = A.cols();
  MatrixXd R = MatrixXd::Zero(p, p);
  if (A.rows() >= p) {
    Eigen::HouseholderQR<MatrixXd> qr(A);
    R = qr.matrixQR().topRows(p).triangularView<Eigen::Upper>();
  } else {
    R.topRows(A.rows()) = A;
  }
  return R;
}

// The SVD of A through its triangular factor; Eigen's divide and conquer (BDCSVD): faster than
// JacobiSVD at p = 32 (bench/README.md), as accurate.
Eigen::BDCSVD<MatrixXd> SmallSvd(const MatrixXd& A) {
  return Eigen::BDCSVD<MatrixXd>(TriangularFactor(A), Eigen::ComputeFullV);
}

// ---- The solve without a robust loss: Levenberg-Marquardt on the block-arrow structure ----
//
// identify/least_squares.h's iterations (Ceres' Levenberg-Marquardt: damping mu diag(J^T J),
// mu = 1 / radius, the diagonal clamped to [1e-6, 1e32], the radius from each step's quality,
// the gradient, step and relative-cost tests of LevenbergMarquardtSettings; the step that meets
// the last two is not taken), on the spatial Model's terms: each pose's local unknowns
// eliminated, the geometry's Schur complement (p x p) solved. Ceres' general machinery (its
// Problem, block-sparse bookkeeping and generic Schur eliminator over 2m small geometry
// blocks) was half of every 30-pose identification (bench/README.md).
//
// Two departures from Ceres' iterations, for problems barely determined by their readings
// (irma4u at 4 poses: 4 encoders, 4 swivel encoders, an inclinometer and 6 nearly hard
// equilibrium rows per pose, 21 geometry unknowns; bench/README.md, "Ill-conditioned
// identifications"), where Ceres' own DENSE_SCHUR crawled as ours did (mean 570 iterations, 11
// of 100 simulated experiments not converged in 2000):
// - A step whose normal equations fail (their LDLT, or a predicted decrease that is not
//   positive: the Schur complement has the square of the Jacobian's condition number) is
//   computed again by orthogonal factorizations (BlockArrowStepQr) before the region shrinks.
// - Once a step's quality has fallen below kCurvedQuality (the linear model mispredicted it: a
//   curved valley, such as the equilibrium rows make) and the fit is within kPolishWhitenedRms
//   of the readings, each candidate's poses are refitted to their own readings at the candidate
//   geometry (StartingLocal, at most kPolishIterations steps each) before its cost is taken:
//   the poses follow the valley, as in variable projection, instead of the geometry inching
//   along it (irma4u, 4 poses: mean 33 iterations instead of 470, 100 of 100 converged). The
//   step's quality then counts that refit's decrease too; the minimum is the same. Not from a
//   poor start: there a refit makes long steps acceptable that lead to another minimum (a random
//   4-cable robot from a start 100 sigma off its noise-free readings: a cost of 4553, not 0).
constexpr double kCurvedQuality = 0.5;
constexpr int kPolishIterations = 3;
constexpr double kPolishWhitenedRms = 3.0;

// One pose's share of the normal equations: A (local x local), B (p x local), its gradient.
struct PoseNormal {
  MatrixXd a, b, damped_inverse;
  VectorXd gradient;
};

struct BlockArrowSummary {
  bool converged = false;
  int iterations = 0;
  std::string message;
  double cost = std::numeric_limits<double>::infinity();  // 1/2 sum of squares at the last iterate
};

// Every term of every pose, and the pose-free terms (the prior): the normal equations and the
// cost (1/2 sum of squares; infinite where a residual is not). Only the geometry columns a
// term reads are accumulated.
double BlockArrowNormal(const Model& model, const VectorXd& g, const Locals& locals, std::vector<PoseNormal>& poses,
                        MatrixXd& h, VectorXd& gradient) {
  const int p = g.size();
  const int local = model.local();
  h.setZero(p, p);
  gradient.setZero(p);
  double sum = 0.0;
  MatrixXd jq, jg, jgc, hc, bc;
  VectorXd r, gc;
  std::vector<int> cols;
  const auto add = [&](const Term& t, PoseNormal* pose) {
    r.resize(t.size());
    EvaluateTerm(t, g, locals, r.data(), pose ? &jq : nullptr, &jg);
    sum += r.squaredNorm();
    cols.clear();
    for (std::size_t b = 0; b < t.block_offset.size(); ++b) {
      for (int c = 0; c < t.block_size[b]; ++c) cols.push_back(t.block_offset[b] + c);
    }
    // A term touches a few of the geometry's columns. One value's rank-one update (an encoder's)
    // is done in plain loops, where Eigen's general products cost more in their setup than in
    // the sums; more values' (the equilibrium's six rows over every exit) by products of the
    // term's own columns gathered. Each of the two cut the spatial identification's instructions
    // by a tenth (bench/README.md, "Spatial identification").
    const int c = static_cast<int>(cols.size());
    if (t.size() == 1) {
      for (int x = 0; x < c; ++x) {
        const double jx = jg(0, cols[x]);
        gradient(cols[x]) += jx * r(0);
        double* h_column = h.col(cols[x]).data();
        for (int y = 0; y < c; ++y) h_column[cols[y]] += jx * jg(0, cols[y]);
      }
      if (!pose) return;
      for (int q1 = 0; q1 < local; ++q1) {
        const double jv = jq(0, q1);
        pose->gradient(q1) += jv * r(0);
        double* a_column = pose->a.col(q1).data();
        for (int q2 = 0; q2 < local; ++q2) a_column[q2] += jv * jq(0, q2);
        double* b_column = pose->b.col(q1).data();
        for (int x = 0; x < c; ++x) b_column[cols[x]] += jv * jg(0, cols[x]);
      }
      return;
    }
    jgc.resize(t.size(), c);
    for (int x = 0; x < c; ++x) jgc.col(x) = jg.col(cols[x]);
    hc.noalias() = jgc.transpose() * jgc;
    gc.noalias() = jgc.transpose() * r;
    for (int x = 0; x < c; ++x) {
      gradient(cols[x]) += gc(x);
      for (int y = 0; y < c; ++y) h(cols[y], cols[x]) += hc(y, x);
    }
    if (!pose) return;
    bc.noalias() = jgc.transpose() * jq;
    for (int x = 0; x < c; ++x) pose->b.row(cols[x]) += bc.row(x);
    pose->a.noalias() += jq.transpose() * jq;
    pose->gradient.noalias() += jq.transpose() * r;
  };
  for (std::size_t j = 0; j < model.pose_ids.size(); ++j) {
    PoseNormal& pose = poses[j];
    pose.a.setZero(local, local);
    pose.b.setZero(p, local);
    pose.gradient.setZero(local);
    for (int k : model.pose_terms[j]) add(model.terms[k], &pose);
  }
  for (int k : model.prior_terms) add(model.terms[k], nullptr);
  return std::isfinite(sum) ? 0.5 * sum : std::numeric_limits<double>::infinity();
}

// Levenberg-Marquardt's damping mu D: D the diagonal of the normal equations, clamped to
// [1e-6, 1e32] as Ceres clamps it.
VectorXd ClampedDiagonal(const MatrixXd& normal) { return normal.diagonal().cwiseMax(1e-6).cwiseMin(1e32); }

// The damped step of SolveBlockArrow by orthogonal factorizations, nothing squared: each pose's
// rows [J_q J_g r] with sqrt(mu D_q) below J_q are reduced by the Householder QR of that
// column block, which eliminates the pose's locals and leaves rows on the geometry alone; those
// of every pose, the prior terms' rows and sqrt(mu D_g) are then solved by QR for the geometry's
// step, and each pose's follows from its triangular factor. The same step as the normal
// equations' in exact arithmetic, with the digits of the Jacobian's condition instead of its
// square. `model_decrease`: the linear model's cost decrease, from J times the step (not from
// J^T J). False when the step is not finite.
bool BlockArrowStepQr(const Model& model, const VectorXd& g, const Locals& locals, const std::vector<int>& held,
                      double mu, const std::vector<PoseNormal>& poses, const MatrixXd& h, VectorXd& step_g,
                      std::vector<VectorXd>& step_q, double& model_decrease) {
  const int p = g.size();
  const int local = model.local();
  const int n = static_cast<int>(locals.size());
  std::vector<int> free;  // the geometry columns not held
  for (int c = 0; c < p; ++c) {
    if (std::find(held.begin(), held.end(), c) == held.end()) free.push_back(c);
  }
  const int pf = static_cast<int>(free.size());
  int geometry_rows = pf;
  for (int j = 0; j < n; ++j) geometry_rows += model.pose_values[j];
  for (int k : model.prior_terms) geometry_rows += model.terms[k].size();
  MatrixXd G = MatrixXd::Zero(geometry_rows, pf + 1);  // the geometry's rows, then their residuals
  int next_row = 0;
  // Each pose's and prior term's Jacobian and residuals (free geometry columns), for the model's decrease.
  std::vector<MatrixXd> jq_of(n), jg_of(n + model.prior_terms.size());
  std::vector<VectorXd> r_of(n + model.prior_terms.size());
  std::vector<MatrixXd> pose_factor(n), pose_rest(n);  // R_j and Q_j^T [J_g r]'s first `local` rows
  MatrixXd jq, jg;
  const auto gather = [&](const std::vector<int>& terms, MatrixXd* Jq, MatrixXd& Jg, VectorXd& r) {
    int rows = 0;
    for (int k : terms) rows += model.terms[k].size();
    if (Jq) Jq->resize(rows, local);
    Jg.resize(rows, pf);
    r.resize(rows);
    int row = 0;
    for (int k : terms) {
      const Term& t = model.terms[k];
      EvaluateTerm(t, g, locals, r.data() + row, Jq ? &jq : nullptr, &jg);
      if (Jq) Jq->middleRows(row, t.size()) = jq;
      for (int c = 0; c < pf; ++c) Jg.col(c).segment(row, t.size()) = jg.col(free[c]);
      row += t.size();
    }
  };
  for (int j = 0; j < n; ++j) {
    gather(model.pose_terms[j], &jq_of[j], jg_of[j], r_of[j]);
    const int rows = model.pose_values[j];
    MatrixXd A(rows + local, local);
    A.topRows(rows) = jq_of[j];
    A.bottomRows(local) = (mu * ClampedDiagonal(poses[j].a)).cwiseSqrt().asDiagonal();
    MatrixXd rest = MatrixXd::Zero(rows + local, pf + 1);
    rest.topLeftCorner(rows, pf) = jg_of[j];
    rest.col(pf).head(rows) = r_of[j];
    const Eigen::HouseholderQR<MatrixXd> qr(A);
    rest.applyOnTheLeft(qr.householderQ().transpose());
    pose_factor[j] = qr.matrixQR().topRows(local).triangularView<Eigen::Upper>();
    pose_rest[j] = rest.topRows(local);
    G.middleRows(next_row, rows) = rest.bottomRows(rows);
    next_row += rows;
  }
  for (std::size_t b = 0; b < model.prior_terms.size(); ++b) {
    gather({model.prior_terms[b]}, nullptr, jg_of[n + b], r_of[n + b]);
    const int rows = static_cast<int>(r_of[n + b].size());
    G.block(next_row, 0, rows, pf) = jg_of[n + b];
    G.col(pf).segment(next_row, rows) = r_of[n + b];
    next_row += rows;
  }
  const VectorXd damping = (mu * ClampedDiagonal(h)).cwiseSqrt();
  for (int c = 0; c < pf; ++c) G(next_row + c, c) = damping(free[c]);
  const VectorXd free_step = -G.leftCols(pf).householderQr().solve(G.col(pf));
  step_g = VectorXd::Zero(p);
  for (int c = 0; c < pf; ++c) step_g(free[c]) = free_step(c);
  model_decrease = 0.0;
  bool finite = free_step.allFinite();
  for (std::size_t b = 0; b < r_of.size(); ++b) {
    VectorXd j_step = jg_of[b] * free_step;
    if (static_cast<int>(b) < n) {
      step_q[b] = -pose_factor[b].triangularView<Eigen::Upper>().solve(pose_rest[b].col(pf) +
                                                                        pose_rest[b].leftCols(pf) * free_step);
      finite = finite && step_q[b].allFinite();
      j_step += jq_of[b] * step_q[b];
    }
    model_decrease -= r_of[b].dot(j_step) + 0.5 * j_step.squaredNorm();
  }
  return finite;
}

// Minimises the cost over g (its `held` entries fixed) and the locals, in place.
BlockArrowSummary SolveBlockArrow(const Model& model, VectorXd& g, Locals& locals, const std::vector<int>& held,
                                  int max_iterations) {
  constexpr internal::LevenbergMarquardtSettings kSettings;
  constexpr double kMinRelativeDecrease = 1e-3, kMaxRadius = 1e16, kMinRadius = 1e-32;
  constexpr int kMaxConsecutiveInvalidSteps = 5;
  double radius = kSettings.initial_trust_region_radius, decrease_factor = 2.0;
  const int n = static_cast<int>(locals.size());
  const int p = g.size();
  const int local = model.local();
  BlockArrowSummary summary;
  std::vector<PoseNormal> poses(n);
  MatrixXd h;
  VectorXd gradient;
  double cost = BlockArrowNormal(model, g, locals, poses, h, gradient);
  for (int k : held) gradient(k) = 0.0;
  if (!std::isfinite(cost)) {
    summary.message = "a residual is not finite at the start (an anchor inside its pulley?)";
    return summary;
  }
  const auto stop = [&](bool converged, const std::string& why) {
    summary.converged = converged;
    summary.message = why;
    summary.cost = cost;
    return summary;
  };
  const auto gradient_small = [&]() {
    double largest = gradient.cwiseAbs().maxCoeff();
    for (const PoseNormal& pose : poses) largest = std::max(largest, pose.gradient.cwiseAbs().maxCoeff());
    return largest <= kSettings.gradient_tolerance;
  };
  if (gradient_small()) return stop(true, "Gradient tolerance reached");
  const auto at_limit = [&]() { return summary.iterations >= max_iterations; };
  const std::string limit_reached = "Maximum number of iterations reached";
  Locals candidate_locals = locals;
  std::vector<VectorXd> step_q(n);
  int invalid_steps = 0;
  bool curved = false;
  for (;;) {
    const double mu = 1.0 / radius;
    bool valid = true;
    MatrixXd schur = h;
    schur.diagonal() += mu * ClampedDiagonal(h);
    VectorXd rhs = gradient;
    // Every pose's b A^-1 and b side by side, so that the Schur complement's sum over the poses
    // is one product (30 small ones per iteration cost 8 % of a 30-pose identification).
    MatrixXd bc_all(p, local * n), b_all(p, local * n);
    VectorXd gradient_all(local * n);
    for (int j = 0; j < n && valid; ++j) {
      PoseNormal& pose = poses[j];
      MatrixXd damped = pose.a;
      damped.diagonal() += mu * ClampedDiagonal(pose.a);
      const Eigen::LLT<MatrixXd> llt(damped);
      if (llt.info() != Eigen::Success) {
        valid = false;
        break;
      }
      pose.damped_inverse = llt.solve(MatrixXd::Identity(local, local));
      bc_all.middleCols(local * j, local).noalias() = pose.b * pose.damped_inverse;
      b_all.middleCols(local * j, local) = pose.b;
      gradient_all.segment(local * j, local) = pose.gradient;
    }
    if (valid) {
      // Only the lower half: the LDLT below reads no other.
      schur.triangularView<Eigen::Lower>() -= bc_all * b_all.transpose();
      rhs.noalias() -= bc_all * gradient_all;
    }
    VectorXd step_g = VectorXd::Zero(p);
    if (valid) {
      for (int k : held) {
        schur.row(k).setZero();
        schur.col(k).setZero();
        schur(k, k) = 1.0;
        rhs(k) = 0.0;
      }
      const Eigen::LDLT<MatrixXd> ldlt(schur);
      step_g = -ldlt.solve(rhs);
      valid = ldlt.info() == Eigen::Success && step_g.allFinite();
    }
    double model_decrease = 0.0;
    if (valid) {
      double jstep2 = step_g.dot(h * step_g);
      model_decrease = -gradient.dot(step_g);
      for (int j = 0; j < n; ++j) {
        const PoseNormal& pose = poses[j];
        step_q[j] = -pose.damped_inverse * (pose.gradient + pose.b.transpose() * step_g);
        jstep2 += step_q[j].dot(pose.a * step_q[j]) + 2.0 * step_g.dot(pose.b * step_q[j]);
        model_decrease -= pose.gradient.dot(step_q[j]);
      }
      model_decrease -= 0.5 * jstep2;
      valid = std::isfinite(model_decrease) && model_decrease > 0.0;
    }
    if (!valid) {
      // The normal equations square the Jacobian's condition: where that has used up the
      // digits, the same damped step by orthogonal factorizations (BlockArrowStepQr).
      valid = BlockArrowStepQr(model, g, locals, held, mu, poses, h, step_g, step_q, model_decrease) &&
              std::isfinite(model_decrease) && model_decrease > 0.0;
    }
    if (!valid) {
      if (at_limit()) return stop(false, limit_reached);
      ++summary.iterations;
      if (++invalid_steps >= kMaxConsecutiveInvalidSteps) {
        return stop(false, "the linear solve failed " + std::to_string(kMaxConsecutiveInvalidSteps) + " times in a row");
      }
      radius /= decrease_factor;
      decrease_factor *= 2.0;
      if (radius < kMinRadius) return stop(false, "the trust region became too small");
      continue;
    }
    invalid_steps = 0;
    // The step's and the iterate's size over every unknown (whichever factorization gave it).
    double step_norm2 = step_g.squaredNorm(), x_norm2 = g.squaredNorm();
    for (int j = 0; j < n; ++j) {
      step_norm2 += step_q[j].squaredNorm();
      x_norm2 += locals[j].squaredNorm();
    }
    if (std::sqrt(step_norm2) <= kSettings.parameter_tolerance * (std::sqrt(x_norm2) + kSettings.parameter_tolerance)) {
      return stop(true, "Parameter tolerance reached");
    }
    const VectorXd candidate_g = g + step_g;
    double candidate_cost = 0.0;
    for (int j = 0; j < n; ++j) candidate_locals[j] = locals[j] + step_q[j];
    if (curved && cost <= 0.5 * kPolishWhitenedRms * kPolishWhitenedRms * model.num_values) {
      for (int j = 0; j < n; ++j) {
        candidate_locals[j] = StartingLocal(model, j, candidate_g, candidate_locals[j], 0, kPolishIterations);
      }
    }
    for (const Term& t : model.terms) {
      VectorXd r(t.size());
      EvaluateTerm(t, candidate_g, candidate_locals, r.data(), nullptr, nullptr);
      candidate_cost += 0.5 * r.squaredNorm();
    }
    if (!std::isfinite(candidate_cost)) candidate_cost = std::numeric_limits<double>::infinity();
    const double cost_change = cost - candidate_cost;
    if (std::isfinite(candidate_cost) && std::abs(cost_change) <= kSettings.function_tolerance * cost) {
      return stop(true, "Function tolerance reached");
    }
    const double quality = cost_change / model_decrease;
    if (!(quality >= kCurvedQuality)) curved = true;
    if (at_limit()) return stop(false, limit_reached);
    ++summary.iterations;
    if (!std::isfinite(candidate_cost) || !(quality > kMinRelativeDecrease)) {
      radius /= decrease_factor;
      decrease_factor *= 2.0;
      if (radius < kMinRadius) return stop(false, "the trust region became too small");
      continue;
    }
    g = candidate_g;
    locals.swap(candidate_locals);
    radius = std::min(kMaxRadius, radius / std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * quality - 1.0, 3)));
    decrease_factor = 2.0;
    cost = BlockArrowNormal(model, g, locals, poses, h, gradient);
    for (int k : held) gradient(k) = 0.0;
    if (gradient_small()) return stop(true, "Gradient tolerance reached");
  }
}

// ---- Directions in words ----

const char* kGeneratorNames[6] = {"a translation along x", "a translation along y", "a translation along z",
                                  "a rotation about x",    "a rotation about y",    "a rotation about z"};

// The rows of `rows` of V.
MatrixXd Rows(const MatrixXd& V, const std::vector<int>& rows) {
  MatrixXd out(rows.size(), V.cols());
  for (std::size_t r = 0; r < rows.size(); ++r) out.row(r) = V.row(rows[r]);
  return out;
}

// The rigid motions on the holdable coordinates (Layout::holdable's rows): of the frame on the
// exit points (translations along x, y, z and rotations about the axes through the exits'
// centroid, per radian), then, when the anchors are free, of the anchors in P (translations
// along P's axes, rotations about P's axes through its origin: the point the poses locate, so
// that a rotation of the platform frame about its origin reads as one generator).
MatrixXd RigidGenerators(const VectorXd& g, const Layout& L) {
  const int groups = L.anchors ? 2 : 1;
  MatrixXd G = MatrixXd::Zero(L.exit_coordinates() + L.anchor_coordinates(), 6 * groups);
  for (int group = 0; group < groups; ++group) {
    const auto point = [&](int i) { return group == 0 ? L.exit(i) : L.anchor(i); };
    Vector3d centroid = Vector3d::Zero();
    if (group == 0) {
      for (int i = 0; i < L.m; ++i) centroid += g.segment<3>(point(i));
      centroid /= L.m;
    }
    for (int i = 0; i < L.m; ++i) {
      const Vector3d d = g.segment<3>(point(i)) - centroid;
      const int row = 3 * L.m * group + 3 * i;
      for (int a = 0; a < 3; ++a) {
        G(row + a, 6 * group + a) = 1.0;
        G.block<3, 1>(row, 6 * group + 3 + a) = Vector3d::Unit(a).cross(d);
      }
    }
  }
  return G;
}

std::string LargestComponents(const VectorXd& v, const std::vector<std::string>& names) {
  std::vector<int> order(v.size());
  for (int k = 0; k < v.size(); ++k) order[k] = k;
  std::sort(order.begin(), order.end(), [&](int a, int b) { return std::abs(v(a)) > std::abs(v(b)); });
  std::string out;
  for (int k = 0; k < std::min<int>(4, v.size()); ++k) {
    if (std::abs(v(order[k])) < 0.1 * std::abs(v(order[0]))) break;
    out += (out.empty() ? "" : ", ") + names[order[k]];
  }
  return out;
}

// Describes the span of the columns of V (p x k, orthonormal-ish): when their holdable parts
// are rigid motions (of the frame, and of the anchors in P when free), a basis in reduced
// row-echelon form over the generators (translations x, y, z, rotations x, y, z) so that "a
// translation along x of the frame" comes out as such; otherwise each column by the unknowns
// it moves most.
std::vector<SpatialDirection> Describe(const MatrixXd& V, const VectorXd& g, const Layout& L,
                                       const std::vector<std::string>& names) {
  const int k = V.cols();
  std::vector<SpatialDirection> out;
  if (k == 0) return out;
  const std::vector<int> holdable = L.holdable();
  std::vector<int> rest;
  std::vector<std::string> rest_names;
  for (int c = 0; c < V.rows(); ++c) {
    if (std::find(holdable.begin(), holdable.end(), c) != holdable.end()) continue;
    rest.push_back(c);
    rest_names.push_back(names[c]);
  }
  const MatrixXd G = RigidGenerators(g, L);
  const int generators = G.cols();
  const MatrixXd E = Rows(V, holdable);
  const MatrixXd C = G.colPivHouseholderQr().solve(E);  // generators x k
  bool rigid = true;
  for (int c = 0; c < k; ++c) {
    const double e = E.col(c).norm();
    rigid = rigid && e > 1e-3 * V.col(c).norm() && (G * C.col(c) - E.col(c)).norm() <= 1e-6 * e;
  }
  // Without free anchors every generator is the frame's, said once at the end; with them each
  // says whose it is.
  const auto generator_name = [&](int a) {
    if (!L.anchors) return std::string(kGeneratorNames[a]);
    return std::string(kGeneratorNames[a % 6]) + (a < 6 ? " of the frame" : " of the anchors in P");
  };
  if (rigid) {
    // RREF of [C^T | I]: the rows' right halves say which combination of V each row is.
    MatrixXd M(k, generators + k);
    M << C.transpose(), MatrixXd::Identity(k, k);
    int row = 0;
    for (int col = 0; col < generators && row < k; ++col) {
      int best = row;
      for (int r = row; r < k; ++r) {
        if (std::abs(M(r, col)) > std::abs(M(best, col))) best = r;
      }
      if (std::abs(M(best, col)) < 1e-6 * M.leftCols(generators).cwiseAbs().maxCoeff()) continue;
      M.row(row).swap(M.row(best));
      M.row(row) /= M(row, col);
      for (int r = 0; r < k; ++r) {
        if (r != row) M.row(r) -= M(r, col) * M.row(row);
      }
      ++row;
    }
    for (int r = 0; r < k; ++r) {
      SpatialDirection d;
      d.geometry = (V * M.row(r).rightCols(k).transpose()).normalized();
      std::string words;
      int terms = 0;
      for (int a = 0; a < generators; ++a) {
        if (std::abs(M(r, a)) > 1e-6) {
          char buf[96];
          std::snprintf(buf, sizeof(buf), " (%.3g%s)", M(r, a), a % 6 < 3 ? " m" : " rad");
          words += terms ? " with " + generator_name(a) + buf : generator_name(a);
          ++terms;
        }
      }
      if (terms > 1) words = "a combination: " + words;
      const VectorXd others = Rows(d.geometry, rest);
      const std::string frame = L.anchors ? "" : " of the frame";
      words += others.norm() > 1e-6 ? frame + ", with " + LargestComponents(others, rest_names) : frame;
      d.description = words;
      out.push_back(d);
    }
    return out;
  }
  for (int c = 0; c < k; ++c) {
    SpatialDirection d;
    d.geometry = V.col(c).normalized();
    const double e = Rows(d.geometry, holdable).norm();
    d.description = (e < 1e-3 ? (L.anchors ? "a direction that moves no exit point or anchor, of "
                                           : "a direction that moves no exit point, of ")
                              : "a direction of ") +
                    LargestComponents(d.geometry, names);
    // A weakly seen direction whose exit part is within kSpatialNearlyRigid of a rigid motion (a
    // turn about z that one tilted swivel axis barely sees): named so, its components after.
    const double e_c = E.col(c).norm();
    const double off = (G * C.col(c) - E.col(c)).norm();
    if (e >= 1e-3 && e_c > 0.0 && off <= kSpatialNearlyRigid * e_c) {
      d.nearly_rigid = true;
      std::string words;
      const double largest = C.col(c).cwiseAbs().maxCoeff();
      for (int a = 0; a < generators; ++a) {
        if (std::abs(C(a, c)) < 0.1 * largest) continue;
        words += (words.empty() ? "" : " with ") + generator_name(a);
      }
      char buf[64];
      std::snprintf(buf, sizeof(buf), " (to %.2g %%)", 100.0 * off / e_c);
      d.description = "nearly " + words + (L.anchors ? "" : " of the frame") + buf + ": " + d.description;
    }
    out.push_back(d);
  }
  return out;
}

std::string Join(const std::vector<std::string>& v, const char* sep) {
  std::string s;
  for (const std::string& x : v) s += (s.empty() ? "" : sep) + x;
  return s;
}

std::string DescribeAll(const std::vector<SpatialDirection>& d) {
  std::vector<std::string> w;
  for (const SpatialDirection& x : d) w.push_back(x.description);
  return Join(w, "; ");
}

// The directions of span(N) (N: p x k, orthonormal columns) that move none of the coordinates
// `rows` (p x r): those holding them leaves unfixed.
MatrixXd DirectionsNotMoving(const MatrixXd& N, const std::vector<int>& rows) {
  const int k = N.cols();
  if (rows.empty() || k == 0) return N;
  Eigen::JacobiSVD<MatrixXd> svd(Rows(N, rows), Eigen::ComputeFullV);
  std::vector<int> left;
  for (int c = 0; c < k; ++c) {
    const double sv = c < svd.singularValues().size() ? svd.singularValues()(c) : 0.0;
    if (!(sv > 1e-6)) left.push_back(c);
  }
  MatrixXd U(N.rows(), left.size());
  for (std::size_t c = 0; c < left.size(); ++c) U.col(c) = N * svd.matrixV().col(left[c]);
  return U;
}

// The column-pivoted QR of E^T (E: the null basis's holdable rows, exits then anchors, k
// columns) by modified Gram-Schmidt: k times, the coordinate whose row has the largest norm
// left after removing the rows already chosen, among the exit rows (the first `exit_rows`)
// while any of them has more than 1e-6 left (the threshold of DirectionsNotMoving), else among
// the anchor rows. Row norms and projections do not depend on which orthonormal basis of the
// null space the SVD returned, so neither does the choice; near-ties (within 1e-6 relative,
// e.g. the symmetric exits of a built-in robot) go to the lowest index, so that noise in the
// readings never changes the held set. Indices into E's rows, sorted.
std::vector<int> PivotedHoldCoordinates(const MatrixXd& E, int exit_rows) {
  MatrixXd rows = E;
  std::vector<int> held;
  for (int c = 0; c < E.cols(); ++c) {
    const VectorXd norms = rows.rowwise().norm();
    const bool exits = exit_rows == E.rows() || norms.head(exit_rows).maxCoeff() > 1e-6;
    const int first = exits ? 0 : exit_rows;
    const double largest = exits ? norms.head(exit_rows).maxCoeff() : norms.tail(E.rows() - exit_rows).maxCoeff();
    int best = first;
    while (norms(best) < (1.0 - 1e-6) * largest) ++best;
    held.push_back(best);
    const VectorXd q = rows.row(best).transpose() / norms(best);
    rows -= (rows * q) * q.transpose();
  }
  std::sort(held.begin(), held.end());
  return held;
}

}  // namespace

// How many independent null directions (columns of N) move the holdable coordinates by a rigid
// motion of the frame (or of the anchors in P), or nearly (within kSpatialNearlyRigid of one,
// as SpatialDirection::nearly_rigid): the directions v of N with |off v| <= kSpatialNearlyRigid
// |E v|, E the exit and anchor rows of N and off their part outside the span of
// RigidGenerators, counted by the generalized eigenvalues of (off^T off, E^T E). A nearly rigid
// turn that one tilted swivel axis barely sees is null when the values only just suffice for the
// other unknowns, and design holds it (weakly_seen_held) whatever the poses. 0 when a null
// direction moves no holdable coordinate (refused after the count).
int RigidNullDimension(const MatrixXd& N, const VectorXd& g, const Layout& L) {
  const int k = N.cols();
  if (k == 0) return 0;
  const MatrixXd G = RigidGenerators(g, L);
  const Eigen::ColPivHouseholderQR<MatrixXd> qr(G);
  const MatrixXd Q = qr.householderQ() * MatrixXd::Identity(G.rows(), qr.rank());
  const MatrixXd E = Rows(N, L.holdable());
  const MatrixXd off = E - Q * (Q.transpose() * E);
  const MatrixXd EtE = E.transpose() * E;
  const Eigen::SelfAdjointEigenSolver<MatrixXd> moved(EtE);
  if (!(moved.eigenvalues().minCoeff() > 1e-12)) return 0;
  const Eigen::GeneralizedSelfAdjointEigenSolver<MatrixXd> ratio(off.transpose() * off, EtE);
  int rigid = 0;
  for (int c = 0; c < k; ++c) rigid += ratio.eigenvalues()(c) <= kSpatialNearlyRigid * kSpatialNearlyRigid;
  return std::min(rigid, static_cast<int>(G.cols()));
}

namespace {

// SpatialPlausibilityWarnings against the nominal geometry g0 (names order: only its exits and
// lengths are read), which IdentifySpatial's analysis has already: solving the home
// equilibrium again for it was work in every Monte Carlo trial.
std::vector<std::string> PlausibilityWarnings(const SpatialRobot& nominal, const VectorXd& g, const VectorXd& g0) {
  const Layout L{nominal.num_cables(), false, false};
  CABLECAL_CHECK(g.size() >= L.size() && g0.size() >= L.size(), "a geometry vector shorter than the exits and lengths");
  std::vector<std::string> out;
  const Vector3d lo = nominal.p_F_frame_min_m, hi = nominal.p_F_frame_max_m;
  const double diagonal_m = (hi - lo).norm();
  char buf[160];
  for (int i = 0; i < L.m; ++i) {
    const Vector3d d = g.segment<3>(L.exit(i));
    const double outside_m = (d.cwiseMax(lo).cwiseMin(hi) - d).norm();
    if (outside_m > kPlausibleExitOutsideFrame_m) {
      std::snprintf(buf, sizeof(buf), "exit point %d is %.3g m outside the frame box (more than %.3g m)", i + 1,
                    outside_m, kPlausibleExitOutsideFrame_m);
      out.push_back(std::string(buf) + ": wrong units, another robot's file, or a cable led elsewhere?");
    }
  }
  for (int i = 0; i < L.m; ++i) {
    const double off_m = g(L.length(i)) - g0(L.length(i));
    if (std::abs(off_m) > diagonal_m) {
      std::snprintf(buf, sizeof(buf), "l%d0 is %.4g m off its nominal %.4g m, more than the frame's diagonal %.4g m",
                    i + 1, off_m, g0(L.length(i)), diagonal_m);
      out.push_back(std::string(buf) + ": an encoder zeroed elsewhere, or readings of another cable order?");
    }
  }
  return out;
}

}  // namespace

std::vector<std::string> SpatialPlausibilityWarnings(const SpatialRobot& nominal, const Eigen::VectorXd& g) {
  return PlausibilityWarnings(nominal, g, NominalSpatialGeometry(nominal, false, false));
}

namespace {

// Each pose's start: its commanded pose where `plan` has one (SpatialIdentifyOptions::
// pose_starts), else home; and the tensions its first load-cell reading gives, else the plan's,
// else the least-squares tensions holding the nominal platform at the starting pose.
//
// With the statics, a pose's tensions are a second unknown of its start: from home with the
// home tensions, a pose a metre away can end in a wrong basin (measured on ipanema1, 8 stiff
// cables: 3 of 12 poses started at tensions of 1e5 N, and the whole fit converged at 30 sigma
// from noise-free readings). So a pose without a plan comes first from the readings without
// the statics (the encoders' lengths inextensible, as --equilibrium off), then the tensions
// with that pose held, then both ("staged"); where the staged start stands out (below), a start
// from home competes and is kept when it fits the pose's readings better. Below 6 cables the
// statics, not the cables, hold the platform's pose, and the staged start is tried only when
// `staged_below_six` (IdentifySpatial's second attempt, when the fit from home ends far from
// the readings): there readings that fit a staged start to within their noise (encoders and an
// inclinometer: 6 values for 6 coordinates) may still be at a wrong pose, so the start from
// home always competes. A commanded pose is within the geometry's errors of the true one. From
// 6 cables on it is the start as it is, and the whole fit moves it with the geometry: on
// cogiro's Monte Carlo trials the fit took as many iterations as from fitted starts and ended
// at the same cost to 1e-6, and the per-pose fits were a fifth of the identification's time.
// Below 6 cables it is fitted to its readings and the start from home competes, as for the
// staged start: in irma4u's study trials (30 a cell) the raw commanded poses ended at a higher
// cost than the starts from home in 22 trials and lower in 7; fitted and competing, higher in
// 1 and lower in 7, the rest equal.
Locals PoseStarts(const Model& model, const SpatialRobot& nominal, const std::vector<SpatialMeasurement>& readings,
                  bool anchors, const VectorXd& g0, bool staged_below_six,
                  const std::map<int, SpatialPoseStart>& plan) {
  const Layout& L = model.layout;
  const int n = static_cast<int>(model.pose_ids.size());
  VectorXd start0(model.local());
  start0.head<6>() = nominal.home_pose();
  if (model.nt > 0) start0.tail(model.nt) = BalancedTensions(nominal, nominal.home_pose(), VectorXd::Zero(model.nt));
  std::vector<const SpatialPoseStart*> planned(n, nullptr);
  bool every_pose_planned = true;
  for (int j = 0; j < n; ++j) {
    const auto found = plan.find(model.pose_ids[j]);
    if (found != plan.end()) planned[j] = &found->second;
    every_pose_planned = every_pose_planned && planned[j];
  }
  std::optional<Model> rigid;
  if (model.nt > 0 && (L.m >= 6 || staged_below_six) && !every_pose_planned) {
    rigid = BuildModel(nominal, readings, false, false, anchors);
  }
  const auto pose_cost = [&](int j, const VectorXd& x) {
    double cost = 0.0;
    for (int k : model.pose_terms[j]) {
      const Term& t = model.terms[k];
      VectorXd r(t.size());
      EvaluateTerm(t, g0, x.data(), static_cast<int>(x.size()), r.data(), nullptr, nullptr);
      cost += r.squaredNorm();
    }
    return std::isfinite(cost) ? cost : std::numeric_limits<double>::infinity();
  };
  const auto first_reading = [&](int j) -> const SpatialMeasurement& {
    return readings[model.terms[model.pose_terms[j][0]].reading];
  };
  Locals starts(n);
  std::vector<double> staged_costs(n, -1.0);  // -1: the start from home is the only one
  std::vector<VectorXd> home_starts(n);
  for (int j = 0; j < n; ++j) {
    VectorXd s = start0;
    const SpatialMeasurement& first = first_reading(j);
    const bool load_cells = model.nt > 0 && first.has(SpatialSensor::kLoadCell);
    if (load_cells) s.tail(model.nt) = first.values(SpatialSensor::kLoadCell);
    if (planned[j]) {
      VectorXd commanded = s;
      commanded.head<6>() = planned[j]->q;
      if (model.nt > 0 && !load_cells) {
        const bool given = planned[j]->tensions_N.size() == model.nt;
        commanded.tail(model.nt) =
            given ? planned[j]->tensions_N : BalancedTensions(nominal, planned[j]->q, VectorXd::Zero(model.nt));
      }
      starts[j] = L.m >= 6 ? std::move(commanded) : StartingLocal(model, j, g0, commanded);
    } else if (!rigid) {
      starts[j] = StartingLocal(model, j, g0, s);
      continue;
    } else {
      VectorXd staged = s;
      staged.head<6>() = StartingLocal(*rigid, j, g0, start0.head<6>());
      if (!load_cells) staged.tail(model.nt) = BalancedTensions(nominal, staged.head<6>(), VectorXd::Zero(model.nt));
      starts[j] = StartingLocal(model, j, g0, StartingLocal(model, j, g0, staged, 6));
    }
    staged_costs[j] = pose_cost(j, starts[j]);
    home_starts[j] = std::move(s);
  }
  // From 6 cables on, and for a commanded pose, the start from home competes only where the
  // start looks like a wrong basin: its cost above the readings' noise and, among at least
  // kFewPoses poses, more than kWrongBasinRatio times the median cost per value of the poses
  // started alike (the nominal geometry's misfit raises every pose's cost alike; a wrong basin
  // stands out). Measured on the spatial study's cogiro trials and the spatial tests (3968
  // poses): where the start from home fitted better by more than 10 %, the staged cost was 5.8e3
  // to 3.5e4 times the median, or at rounding (1e-20); elsewhere at most 38 times. Running it
  // for every pose was 20 % of a Monte Carlo trial. A commanded pose that stands out is not
  // where its readings were taken (another pose's row, a pose the robot did not reach): it is
  // fitted first, then competes as a staged one.
  constexpr int kFewPoses = 5;
  constexpr double kWrongBasinRatio = 100.0;
  const auto median_per_value = [&](bool of_planned, int* count) {
    std::vector<double> per_value;
    for (int j = 0; j < n; ++j) {
      if (staged_costs[j] >= 0.0 && (planned[j] != nullptr) == of_planned) {
        per_value.push_back(staged_costs[j] / model.pose_values[j]);
      }
    }
    *count = static_cast<int>(per_value.size());
    if (per_value.empty()) return 0.0;
    std::nth_element(per_value.begin(), per_value.begin() + *count / 2, per_value.end());
    return per_value[*count / 2];
  };
  int compared[2];
  const double median[2] = {median_per_value(false, &compared[0]), median_per_value(true, &compared[1])};
  const auto wrong_basin = [&](int j, double cost) {
    const int group = planned[j] ? 1 : 0;
    const bool within_noise = cost <= model.pose_values[j];
    const bool stands_out =
        compared[group] < kFewPoses || cost > kWrongBasinRatio * median[group] * model.pose_values[j];
    return !within_noise && stands_out;
  };
  // Pose j fitted from `from` competes with its start: the lower cost is kept.
  const auto try_start = [&](int j, const VectorXd& from) {
    VectorXd fitted = StartingLocal(model, j, g0, from);
    const double cost = pose_cost(j, fitted);
    if (cost < staged_costs[j]) {
      starts[j] = std::move(fitted);
      staged_costs[j] = cost;
    }
  };
  for (int j = 0; j < n; ++j) {
    if (staged_costs[j] < 0.0 || !wrong_basin(j, staged_costs[j])) {
      if (L.m >= 6 || staged_costs[j] < 0.0) continue;
    }
    if (planned[j] && L.m >= 6) {
      starts[j] = StartingLocal(model, j, g0, starts[j]);
      staged_costs[j] = pose_cost(j, starts[j]);
    }
    try_start(j, home_starts[j]);
  }
  // A pose whose start still stands out after both (a soft cable's stretch of centimetres can
  // leave the fits from home and from the rigid stage in wrong basins alike: measured on random
  // 6- to 8-cable robots with E*A 30 times the largest tension, 4 of 27 noise-free experiments
  // ended as poor_fit, one pose turned by 120 degrees about z or tilted by 30): it starts from
  // the starts of the kNeighbourStarts poses whose encoder readings are nearest its own, among
  // those that do not stand out (nearby lengths, a nearby pose), and keeps the best fit.
  constexpr int kNeighbourStarts = 3;
  std::vector<int> good;
  for (int j = 0; j < n; ++j) {
    if (staged_costs[j] >= 0.0 && !wrong_basin(j, staged_costs[j])) good.push_back(j);
  }
  for (int j = 0; j < n; ++j) {
    if (staged_costs[j] < 0.0 || !wrong_basin(j, staged_costs[j]) || good.empty()) continue;
    std::vector<std::pair<double, int>> nearest;
    for (const int k : good) nearest.emplace_back((first_reading(k).dl_m - first_reading(j).dl_m).squaredNorm(), k);
    const std::size_t tried = std::min<std::size_t>(kNeighbourStarts, nearest.size());
    std::partial_sort(nearest.begin(), nearest.begin() + tried, nearest.end());
    for (std::size_t c = 0; c < tried; ++c) {
      VectorXd from = starts[nearest[c].second];
      if (model.nt > 0 && first_reading(j).has(SpatialSensor::kLoadCell)) {
        from.tail(model.nt) = home_starts[j].tail(model.nt);  // its own load cells' tensions
      }
      try_start(j, from);
    }
  }
  // A pose that still stands out may be turned far about the vertical from home and from every
  // neighbour: a new user's 8-cable robot with exits in corner pairs, poses yawed 1.8 to 2.1 rad
  // from home, fitted every start into a wrong basin and the whole fit failed (RMS 88 on
  // noise-free readings). Home turned by a quarter, a half and three quarters of a turn about
  // the vertical is tried too, and the best fit kept.
  for (int j = 0; j < n; ++j) {
    if (staged_costs[j] < 0.0 || !wrong_basin(j, staged_costs[j])) continue;
    for (int quarter = 1; quarter <= 3; ++quarter) {
      VectorXd from = home_starts[j];
      from(5) += quarter * 0.5 * M_PI;
      if (model.nt > 0 && !first_reading(j).has(SpatialSensor::kLoadCell)) {
        from.tail(model.nt) = BalancedTensions(nominal, from.head<6>(), VectorXd::Zero(model.nt));
      }
      if (rigid) from.head<6>() = StartingLocal(*rigid, j, g0, from.head<6>());
      try_start(j, from);
    }
  }
  return starts;
}

// The readings' values cannot determine the unknowns: p geometry coordinates less `held` that a
// gauge holds (the words say which), and each pose's coordinates and tensions.
[[noreturn]] void RefuseTooFewValues(const Model& model, int n, int held, const std::string& held_words) {
  const int p = model.layout.size();
  const std::string tensions =
      model.nt > 0 ? " and " + std::to_string(model.nt) +
                         " tensions per pose (the equilibrium's 6 rows per pose are among the values; a "
                         "stretching cable's tension is an unknown that load cells would read)"
                   : "";
  throw InputError("readings", "",
                   std::to_string(model.num_values) + " reading values for " +
                       std::to_string(p - held + model.local() * n) + " unknowns (" + std::to_string(p) +
                       " of the geometry" + (held > 0 ? held_words : "") + ", 6 coordinates per pose for " +
                       std::to_string(n) + " poses" + tensions +
                       "): too few to determine the geometry; measure more poses or add a sensor");
}

// "1, 2, 5, ..." (the first kShown, then how many more): pose ids in a message.
std::string PoseIdList(const std::vector<int>& ids) {
  constexpr std::size_t kShown = 8;
  std::string out;
  for (std::size_t k = 0; k < ids.size() && k < kShown; ++k) out += (k ? ", " : "") + std::to_string(ids[k]);
  if (ids.size() > kShown) out += ", ... (" + std::to_string(ids.size() - kShown) + " more)";
  return out;
}

std::vector<int> PlanIds(const std::map<int, SpatialPoseStart>& plan) {
  std::vector<int> ids;
  for (const auto& [id, start] : plan) ids.push_back(id);
  return ids;
}

struct Analysis {
  Model model;
  VectorXd g0;
  Locals start;
  SpatialGaugeAnalysis gauge;
};

Analysis Analyze(const SpatialRobot& nominal, const std::vector<SpatialMeasurement>& readings,
                 const SpatialIdentifyOptions& options) {
  Analysis a;
  a.model = BuildModel(nominal, readings, options.gauge.kind == SpatialGaugeKind::kPrior, options.statics,
                       options.anchors);
  const Layout& L = a.model.layout;
  a.g0 = NominalSpatialGeometry(nominal, L.swivel, L.heading, L.anchors, L.platform, &options.home_paid_out_m);
  a.gauge.names = SpatialGeometryNames(L.m, L.swivel, L.heading, L.anchors, L.platform);
  const int p = L.size();
  const int n = static_cast<int>(a.model.pose_ids.size());
  const int local = a.model.local();
  // Before the starts, the count with the most a gauge can hold (6 rigid motions of the frame,
  // 6 more of the anchors in P; none with the tracker's prior, whose rows are among the values):
  // readings short of that are refused at once, the exact count follows the gauge analysis.
  const int most_held = options.gauge.kind == SpatialGaugeKind::kPrior ? 0 : L.anchors ? 12 : 6;
  if (a.model.num_values < p - most_held + local * n) {
    RefuseTooFewValues(a.model, n, most_held,
                       " less at most " + std::to_string(most_held) + " rigid motions that a gauge can hold");
  }
  if (!options.pose_starts.empty()) {
    const auto planned = [&](int id) { return options.pose_starts.count(id) > 0; };
    if (std::none_of(a.model.pose_ids.begin(), a.model.pose_ids.end(), planned)) {
      throw InputError("plan", "column 'pose'",
                       "none of the readings' " + std::to_string(n) + " pose ids (" + PoseIdList(a.model.pose_ids) +
                           ") has a row in the plan (pose ids " + PoseIdList(PlanIds(options.pose_starts)) +
                           "): the plan of another experiment?");
    }
  }
  a.start = PoseStarts(a.model, nominal, readings, options.anchors, a.g0, false, options.pose_starts);
  // What the readings alone see, at the starts with each pose's tensions moved to the nearest
  // that hold it in exact equilibrium: at a start that misfits the equilibrium (the nominal l_i0
  // of a stretching cable is its length under load, not unloaded), the equilibrium rows see a
  // turn of the whole robot about the vertical, which no reading of these sensors sees
  // (ipanema1: the turn read as weakly seen at the start, then unseen at the estimate).
  Locals balanced = a.start;
  if (a.model.nt > 0) {
    for (VectorXd& x : balanced) x.tail(a.model.nt) = BalancedTensions(nominal, x.head<6>(), x.tail(a.model.nt));
  }
  const MatrixXd A = ReducedJacobian(a.model, a.g0, balanced, true, false);
  // The platform's mass and centre of mass (the last columns) are known to their priors, which
  // no gauge holds and no reading need see: projected off as each pose's unknowns are, so that
  // the directions below are the geometry's with the platform estimated beside it (their own,
  // in kg and m, would read as "weakly seen" beside the exits' information).
  const int platform = L.platform ? 4 : 0;
  const int g = p - platform;
  MatrixXd Ag = A.leftCols(g);
  if (platform > 0) {
    const Eigen::HouseholderQR<MatrixXd> qr(A.rightCols(platform));
    Ag.applyOnTheLeft(qr.householderQ().adjoint());
    Ag = Ag.bottomRows(A.rows() - platform).eval();
  }
  const Eigen::BDCSVD<MatrixXd> svd = SmallSvd(Ag);
  const VectorXd& s = svd.singularValues();
  const double largest = s(0);
  std::vector<int> null_cols, weak_cols;
  for (int c = 0; c < g; ++c) {
    if (!(s(c) > kSpatialNullThreshold * largest)) {
      null_cols.push_back(c);
    } else if (s(c) < kSpatialWeakThreshold * largest) {
      weak_cols.push_back(c);
    }
  }
  const auto columns = [&](const std::vector<int>& cols) {
    MatrixXd V = MatrixXd::Zero(p, cols.size());
    for (std::size_t c = 0; c < cols.size(); ++c) V.col(c).head(g) = svd.matrixV().col(cols[c]);
    return V;
  };
  const MatrixXd N = columns(null_cols);
  const int k = N.cols();
  a.gauge.null_directions = Describe(N, a.g0, L, a.gauge.names);
  a.gauge.weak_directions = Describe(columns(weak_cols), a.g0, L, a.gauge.names);
  for (std::size_t c = 0; c < weak_cols.size(); ++c) {
    a.gauge.weak_directions[c].relative_singular_value = s(weak_cols[c]) / largest;
  }
  // The default gauge holds the nearly rigid weak directions too (file comment).
  std::vector<int> nearly_rigid_cols;
  for (std::size_t c = 0; c < weak_cols.size(); ++c) {
    if (a.gauge.weak_directions[c].nearly_rigid) nearly_rigid_cols.push_back(weak_cols[c]);
  }
  const bool hold_weak = options.gauge.kind == SpatialGaugeKind::kAuto && !nearly_rigid_cols.empty();
  // Enough values for the unknowns the readings must determine: every geometry coordinate but
  // the rigid motions of the frame that no reading sees (the gauge holds them; with --gauge
  // prior the tracker's rows, counted among the values, fix them) and, for the default gauge,
  // the nearly rigid weak directions it holds, as design's count (MinSpatialDesignPoses). A
  // null direction from too few readings is no rigid motion and is not subtracted.
  // A lab's hold: list leaves its coordinates out of the unknowns, whatever they are (it must fix
  // the null directions, checked below).
  const int rigid = options.gauge.kind == SpatialGaugeKind::kPrior ? 0 : RigidNullDimension(N, a.g0, L);
  const int gauge_held = options.gauge.kind == SpatialGaugeKind::kHold
                             ? static_cast<int>(options.gauge.held.size())
                             : rigid + (hold_weak ? static_cast<int>(nearly_rigid_cols.size()) : 0);
  a.gauge.redundancy = a.model.num_values - (p - gauge_held + local * n);
  if (a.gauge.redundancy < 0) {
    RefuseTooFewValues(a.model, n, gauge_held,
                       options.gauge.kind == SpatialGaugeKind::kHold
                           ? " less the " + std::to_string(gauge_held) + " that --gauge hold: holds"
                           : " less " + std::to_string(gauge_held) +
                                 " rigid motion(s) of the frame, or nearly, that the gauge holds");
  }
  // A lab's hold: list is checked and held even when the readings see everything (holding every
  // exit coordinate identifies the lengths, offsets and poses alone).
  if (k == 0 && options.gauge.kind != SpatialGaugeKind::kHold && !hold_weak) return a;
  // A null direction that moves no holdable coordinate cannot be held: refused whatever the gauge.
  const std::vector<int> holdable = L.holdable();
  const std::string holdable_words = L.anchors ? "exit or anchor coordinates" : "exit coordinates";
  const MatrixXd unheldable = DirectionsNotMoving(N, holdable);
  if (k > 0 && unheldable.cols() > 0) {
    throw InputError("readings", "",
                     "no reading fixes " + DescribeAll(Describe(unheldable, a.g0, L, a.gauge.names)) + ", and holding " +
                         holdable_words +
                         " cannot fix it: add a sensor that sees it (swivel offsets need swivel readings at several "
                         "poses, yaw0 heading readings)");
  }
  const std::vector<std::string>& names = a.gauge.names;
  switch (options.gauge.kind) {
    case SpatialGaugeKind::kAuto: {
      MatrixXd gauge(p, k + nearly_rigid_cols.size());
      gauge << N, columns(nearly_rigid_cols);
      for (int h : PivotedHoldCoordinates(Rows(gauge, holdable), L.exit_coordinates())) {
        a.gauge.held.push_back(holdable[h]);
      }
      break;
    }
    case SpatialGaugeKind::kHold: {
      const std::string flag = "hold:" + Join(options.gauge.held, ",");
      const std::string m = std::to_string(L.m);
      for (const std::string& h : options.gauge.held) {
        const auto it = std::find_if(holdable.begin(), holdable.end(), [&](int c) { return names[c] == h; });
        if (it == holdable.end()) {
          const std::vector<std::string> with_anchors = SpatialGeometryNames(L.m, false, false, true);
          const bool anchor = !L.anchors && h[0] == 'b' &&
                              std::find(with_anchors.begin(), with_anchors.end(), h) != with_anchors.end();
          throw InputError("--gauge", flag,
                           anchor ? "'" + h + "' is a platform anchor coordinate: an unknown, that a gauge may hold, "
                                                "only with --identify anchors"
                                  : "'" + h + "' is not an " + (L.anchors ? "exit or anchor" : "exit") +
                                        " coordinate of this " + m + "-cable robot (a1x .. a" + m + "z" +
                                        (L.anchors ? ", b1x .. b" + m + "z)" : ")"));
        }
        if (std::find(a.gauge.held.begin(), a.gauge.held.end(), *it) != a.gauge.held.end()) {
          throw InputError("--gauge", flag, "'" + h + "' is named twice");
        }
        a.gauge.held.push_back(*it);
      }
      std::sort(a.gauge.held.begin(), a.gauge.held.end());
      const MatrixXd left = DirectionsNotMoving(N, a.gauge.held);
      if (k == 0 || left.cols() == 0) break;
      // The holdable coordinate the first remaining direction moves most: holding it too helps.
      int best = 0;
      Rows(left.col(0), holdable).col(0).cwiseAbs().maxCoeff(&best);
      throw InputError("--gauge", flag,
                       "does not fix the gauge: no reading fixes " + DescribeAll(Describe(left, a.g0, L, names)) +
                           " (" + std::to_string(left.cols()) + " of the " + std::to_string(k) +
                           " null directions left); hold " + names[holdable[best]] +
                           " too, or add a sensor that sees it");
    }
    case SpatialGaugeKind::kPrior: {
      // The tracker's survey is of the exit points: a direction of the anchors alone stays unseen.
      std::vector<int> exits(holdable.begin(), holdable.begin() + L.exit_coordinates());
      const MatrixXd left = DirectionsNotMoving(N, exits);
      if (left.cols() > 0) {
        throw InputError("--gauge", "prior",
                         "the tracker's prior is on the exit points, and no reading fixes " +
                             DescribeAll(Describe(left, a.g0, L, names)) +
                             ": use --gauge auto or hold: anchor coordinates, or add a sensor that sees it");
      }
      break;
    }
    case SpatialGaugeKind::kNone: break;
  }
  return a;
}

// One fit from the given starts, `held` fixed at g0: the block-arrow LM for plain least squares,
// Ceres for a robust loss. `objective` is what it minimised (Ceres' robust cost with a loss).
struct Fit {
  VectorXd g;
  Locals locals;
  bool converged = false;
  int iterations = 0;
  double objective = std::numeric_limits<double>::infinity();
  std::string message;
};
Fit FitFrom(const Model& model, const VectorXd& g0, const std::vector<int>& held, const SpatialIdentifyOptions& options,
            Locals starts) {
  const Layout& L = model.layout;
  const int n = static_cast<int>(model.pose_ids.size());
  Fit fit;
  fit.g = g0;
  fit.locals = std::move(starts);
  VectorXd& g = fit.g;
  Locals& locals = fit.locals;
  if (options.loss.kind == LossKind::kNone) {
    const BlockArrowSummary solved = SolveBlockArrow(model, g, locals, held, options.max_iterations);
    fit.converged = solved.converged;
    fit.iterations = solved.iterations + 1;  // with the start, as Ceres counts them
    fit.message = solved.message;
    fit.objective = std::isfinite(solved.cost) ? solved.cost : std::numeric_limits<double>::infinity();
    return fit;
  }
  // A robust loss: Ceres, which reweights each residual block by it.
  const int local = model.local();
  std::vector<std::unique_ptr<ceres::CostFunction>> adapters;
  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  // Every pose's block in one buffer, in pose order: Ceres keeps a group's blocks in a set
  // ordered by address, so blocks allocated one by one would be eliminated in an order that
  // changes from run to run, and the result's last bits with it (a Monte Carlo's trials must
  // give the same bytes every time).
  std::vector<double> local_buffer(static_cast<std::size_t>(n) * local);
  const auto block = [&](int j) { return local_buffer.data() + static_cast<std::size_t>(j) * local; };
  auto* ordering = new ceres::ParameterBlockOrdering;
  for (int j = 0; j < n; ++j) {
    Eigen::Map<VectorXd>(block(j), local) = locals[j];
    problem.AddParameterBlock(block(j), local);
    ordering->AddElementToGroup(block(j), 0);
  }
  for (int i = 0; i < L.m; ++i) {
    problem.AddParameterBlock(g.data() + L.exit(i), 3);
    problem.AddParameterBlock(g.data() + L.length(i), 1);
    ordering->AddElementToGroup(g.data() + L.exit(i), 1);
    ordering->AddElementToGroup(g.data() + L.length(i), 1);
    if (L.anchors) {
      problem.AddParameterBlock(g.data() + L.anchor(i), 3);
      ordering->AddElementToGroup(g.data() + L.anchor(i), 1);
    }
    if (L.swivel) {
      problem.AddParameterBlock(g.data() + L.swivel_offset(i), 1);
      ordering->AddElementToGroup(g.data() + L.swivel_offset(i), 1);
    }
  }
  if (L.heading) {
    problem.AddParameterBlock(g.data() + L.yaw0(), 1);
    ordering->AddElementToGroup(g.data() + L.yaw0(), 1);
  }
  if (L.platform) {
    problem.AddParameterBlock(g.data() + L.platform_block(), 4);
    ordering->AddElementToGroup(g.data() + L.platform_block(), 1);
  }
  for (const Term& t : model.terms) {
    std::vector<double*> params;
    if (t.pose >= 0) params.push_back(block(t.pose));
    for (int b : t.block_offset) params.push_back(g.data() + b);
    // The robust loss on the sensors' readings; the equilibrium is the model's, not a reading.
    const bool reading = t.reading >= 0 && t.sensor != kEquilibriumTerm;
    ceres::LossFunction* loss = nullptr;
    if (reading && options.loss.kind == LossKind::kHuber) loss = new ceres::HuberLoss(options.loss.scale_sigmas);
    if (reading && options.loss.kind == LossKind::kCauchy) loss = new ceres::CauchyLoss(options.loss.scale_sigmas);
    ceres::CostFunction* cost = t.cost.get();
    if (t.pose >= 0 && local > 6) {
      adapters.push_back(std::make_unique<LocalBlockCost>(t, local));
      cost = adapters.back().get();
    }
    problem.AddResidualBlock(cost, loss, params);
  }
  // The held coordinates: of the exit points' blocks, then the free anchors'.
  for (int point = 0; point < (L.exit_coordinates() + L.anchor_coordinates()) / 3; ++point) {
    const int offset = point < L.m ? L.exit(point) : L.anchor(point - L.m);
    std::vector<int> axes;
    for (int axis = 0; axis < 3; ++axis) {
      if (std::count(held.begin(), held.end(), offset + axis)) axes.push_back(axis);
    }
    if (axes.size() == 3) {
      problem.SetParameterBlockConstant(g.data() + offset);
    } else if (!axes.empty()) {
      problem.SetManifold(g.data() + offset, new ceres::SubsetManifold(3, axes));
    }
  }
  ceres::Solver::Options solver;
  constexpr internal::LevenbergMarquardtSettings kSettings;
  solver.minimizer_type = ceres::TRUST_REGION;
  solver.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  solver.function_tolerance = kSettings.function_tolerance;
  solver.gradient_tolerance = kSettings.gradient_tolerance;
  solver.parameter_tolerance = kSettings.parameter_tolerance;
  solver.initial_trust_region_radius = kSettings.initial_trust_region_radius;
  solver.linear_solver_type = ceres::DENSE_SCHUR;  // the poses eliminated first
  solver.linear_solver_ordering.reset(ordering);
  solver.max_num_iterations = options.max_iterations;
  solver.num_threads = 1;
  solver.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(solver, &problem, &summary);
  for (int j = 0; j < n; ++j) locals[j] = Eigen::Map<const VectorXd>(block(j), local);
  fit.converged = summary.termination_type == ceres::CONVERGENCE;
  fit.iterations = static_cast<int>(summary.iterations.size());
  fit.message = summary.message;
  fit.objective = std::isfinite(summary.final_cost) ? summary.final_cost : std::numeric_limits<double>::infinity();
  return fit;
}

}  // namespace

std::vector<std::string> SpatialGeometryNames(int num_cables, bool swivel, bool heading, bool anchors, bool platform) {
  std::vector<std::string> names = SpatialLayout(num_cables).names();
  for (int i = 1; i <= num_cables && anchors; ++i) {
    for (const char axis : {'x', 'y', 'z'}) names.push_back("b" + std::to_string(i) + axis);
  }
  if (swivel) {
    for (int i = 1; i <= num_cables; ++i) names.push_back("sw" + std::to_string(i) + "0");
  }
  if (heading) names.push_back("yaw0");
  if (platform) names.insert(names.end(), std::begin(kSpatialPlatformNames), std::end(kSpatialPlatformNames));
  return names;
}

Eigen::VectorXd NominalSpatialGeometry(const SpatialRobot& nominal, bool swivel, bool heading, bool anchors,
                                       bool platform, const Eigen::VectorXd* home_paid_out_m) {
  Layout L{nominal.num_cables(), swivel, heading, anchors, platform};
  VectorXd g = VectorXd::Zero(L.size());
  // l_i0 is what the encoder counts from: the cable paid out at the home equilibrium (its
  // unstretched length; the Monte Carlo's truth and the plans' zero, experiment/spatial_plan.h
  // SpatialHome). Taking the geometric length at the file's home pose instead put a soft
  // cable's start its stretch away (centimetres at E*A 3e4 N), and fits from home then ended
  // in wrong minima; an underactuated robot's home equilibrium also turns from home_rpy. Where
  // home is no equilibrium (a robot the caller checks elsewhere), the geometric length.
  VectorXd home_lengths;
  if (home_paid_out_m != nullptr && home_paid_out_m->size() == L.m) {
    home_lengths = *home_paid_out_m;
  } else {
    const SpatialPoseEvaluation home = EvaluateSpatialHome(nominal);
    home_lengths = home.has_equilibrium ? PaidOutLengths(nominal, home.equilibrium)
                                        : CableLengths<double>(nominal, nominal.home_pose());
  }
  for (int i = 0; i < L.m; ++i) {
    g.segment<3>(L.exit(i)) = nominal.cables[i].p_F_exit_m;
    g(L.length(i)) = nominal.cables[i].initial_length_m.value_or(home_lengths(i));
    if (anchors) g.segment<3>(L.anchor(i)) = nominal.cables[i].p_P_anchor_m;
  }
  if (heading) g(L.yaw0()) = nominal.home_rpy_rad.z();
  if (platform) g.segment<4>(L.platform_block()) = nominal.platform_values();
  return g;
}

SpatialGauge ParseSpatialGauge(const std::string& text) {
  SpatialGauge gauge;
  if (text == "auto") return gauge;
  if (text == "none") {
    gauge.kind = SpatialGaugeKind::kNone;
    return gauge;
  }
  if (text == "prior") {
    gauge.kind = SpatialGaugeKind::kPrior;
    return gauge;
  }
  if (text.rfind("hold:", 0) == 0) {
    gauge.kind = SpatialGaugeKind::kHold;
    std::stringstream list(text.substr(5));
    std::string name;
    while (std::getline(list, name, ',')) {
      if (name.empty()) throw InputError("--gauge", text, "an empty name in the hold list");
      if (name.find_first_of(" \t") != std::string::npos) {
        throw InputError("--gauge", text, "'" + name + "': a space in the hold list (names are separated by commas alone)");
      }
      gauge.held.push_back(name);
    }
    // getline gives no empty name after a trailing comma: refused as any other empty name.
    if (text.back() == ',') throw InputError("--gauge", text, "an empty name in the hold list");
    if (gauge.held.empty()) throw InputError("--gauge", text, "hold: names no coordinate (e.g. hold:a1x,a1y,a1z)");
    return gauge;
  }
  throw InputError("--gauge", text, "expected auto, none, prior or hold:a1x,a1y,...");
}

std::string ToString(const SpatialGauge& gauge) {
  switch (gauge.kind) {
    case SpatialGaugeKind::kAuto: return "auto";
    case SpatialGaugeKind::kNone: return "none";
    case SpatialGaugeKind::kPrior: return "prior";
    case SpatialGaugeKind::kHold: return "hold:" + Join(gauge.held, ",");
  }
  return "?";
}

bool ParseSpatialIdentify(const std::string& text) {
  if (text == "exits") return false;
  if (text == "anchors") return true;
  throw InputError("--identify", text,
                   "expected exits (the exit points and initial lengths: the default) or anchors (the platform "
                   "anchors too)");
}

const char* SpatialIdentifyName(bool anchors) { return anchors ? "anchors" : "exits"; }

const char* ToString(SpatialIdentifyStatus s) {
  switch (s) {
    case SpatialIdentifyStatus::kConverged: return "converged";
    case SpatialIdentifyStatus::kNotConverged: return "not_converged";
    case SpatialIdentifyStatus::kRankDeficient: return "rank_deficient";
    case SpatialIdentifyStatus::kPoorFit: return "poor_fit";
  }
  return "?";
}

SpatialGaugeAnalysis AnalyzeSpatialGauge(const SpatialRobot& nominal, const std::vector<SpatialMeasurement>& readings,
                                         const SpatialIdentifyOptions& options) {
  return Analyze(nominal, readings, options).gauge;
}

namespace {

// The leverages into result->fits (TermLeverages), and a warning naming the values no other
// reading checks (kUncheckedLeverage) whose error would go mostly into the geometry (its part
// of the leverage at least half), in a fit with redundancy (without, every value is unchecked,
// as the warning before says). A value whose error its own pose's unknowns take (an encoder of
// a stretching cable, whose tension follows it) leaves the geometry alone and is not named.
void AddReadingLeverages(const Model& model, const std::vector<LeverageParts>& parts, const std::vector<int>& free,
                         const MatrixXd& cov_free, int redundancy, SpatialIdentifyResult* result) {
  const Layout& L = model.layout;
  const std::vector<TermLeverage> leverages = TermLeverages(model, parts, free, cov_free);
  for (std::size_t k = 0; k < model.terms.size(); ++k) {
    const Term& t = model.terms[k];
    if (t.reading < 0) {
      result->prior_leverage += leverages[k].total.sum();
      continue;
    }
    SpatialReadingFit& fit = result->fits[t.reading];
    VectorXd& v = ValuesOf(fit.leverage, t);
    const Eigen::Index size = ValuesOf(fit, t).size();  // as its residuals
    if (v.size() != size) v = VectorXd::Constant(size, std::numeric_limits<double>::quiet_NaN());
    v.segment(t.value, t.size()) = leverages[k].total;
  }
  if (redundancy <= 0) return;
  struct Unchecked {
    double leverage;
    int term, row;
  };
  std::vector<Unchecked> unchecked;
  for (std::size_t k = 0; k < model.terms.size(); ++k) {
    const Term& t = model.terms[k];
    if (t.reading < 0 || t.sensor == kEquilibriumTerm) continue;
    for (int v = 0; v < t.size(); ++v) {
      const double h = leverages[k].total(v);
      if (h >= kUncheckedLeverage && leverages[k].geometry(v) >= 0.5 * h) {
        unchecked.push_back({h, static_cast<int>(k), v});
      }
    }
  }
  if (unchecked.empty()) return;
  std::stable_sort(unchecked.begin(), unchecked.end(),
                   [](const Unchecked& a, const Unchecked& b) { return a.leverage > b.leverage; });
  std::string named;
  constexpr std::size_t kNamed = 3;
  for (std::size_t u = 0; u < std::min(kNamed, unchecked.size()); ++u) {
    const Term& t = model.terms[unchecked[u].term];
    char buf[200];
    std::snprintf(buf, sizeof(buf), "%s of pose %d (leverage %.3f)", ValueName(t, unchecked[u].row, L.m).c_str(),
                  model.pose_ids[t.pose], unchecked[u].leverage);
    named += (named.empty() ? "" : "; ") + std::string(buf);
  }
  result->warnings.push_back(
      std::to_string(unchecked.size()) + " reading value" + (unchecked.size() == 1 ? "" : "s") +
      " that no other reading checks (leverage at least 0.99, most of it the geometry's: " + named +
      (unchecked.size() > kNamed ? "; ..." : "") +
      "): the fit follows such a value, so an error in it shows at most a tenth of itself in its residual and "
      "moves the calibrated geometry instead; read it again, or add poses or a sensor whose readings see the "
      "same directions");
}

}  // namespace

SpatialIdentifyResult IdentifySpatial(const SpatialRobot& nominal, const std::vector<SpatialMeasurement>& readings,
                                      const SpatialIdentifyOptions& options) {
  if (options.max_iterations < 1) throw InputError("--max-iterations", "", "must be at least 1");
  Analysis a = Analyze(nominal, readings, options);
  const Model& model = a.model;
  const Layout& L = model.layout;
  const int p = L.size();
  const int n = static_cast<int>(model.pose_ids.size());

  SpatialIdentifyResult result;
  result.names = a.gauge.names;
  result.null_directions = a.gauge.null_directions;
  result.weak_directions = a.gauge.weak_directions;
  result.unused_sensors = model.unused_sensors;
  for (int h : a.gauge.held) result.held.push_back(a.gauge.names[h]);
  result.pose_ids = model.pose_ids;
  for (const VectorXd& x : a.start) result.starting_poses.push_back(x.head<6>());

  Fit fit = FitFrom(model, a.g0, a.gauge.held, options, a.start);
  // A fit of readings at their noise has a whitened RMS near 1 over every value (the
  // equilibrium's rows included); one that did not converge or ended beyond kRetryWhitenedRms
  // is solved again from other starts below, and the lower objective wins.
  constexpr double kRetryWhitenedRms = 2.0;
  const auto astray = [&](const Fit& f) {
    return !f.converged || !(f.objective <= 0.5 * kRetryWhitenedRms * kRetryWhitenedRms * model.num_values);
  };
  const auto keep_better = [&](Fit second, const Locals& starts) {
    const bool better = second.converged == fit.converged ? second.objective < fit.objective : second.converged;
    if (!better) return;
    fit = std::move(second);
    result.starting_poses.clear();
    for (const VectorXd& x : starts) result.starting_poses.push_back(x.head<6>());
  };
  // A plan that is not the readings' (rows of other poses, another experiment's plan) can lead
  // the whole fit astray even where each start that stands out is refitted (a new user's
  // shuffled plans on a 6- and an 8-cable robot: poor_fit and not converged, where the readings
  // alone identify in 11 to 14 iterations): solved again from the starts without the plan.
  if (options.retry_without_plan && !options.pose_starts.empty() && astray(fit)) {
    const Locals own = PoseStarts(model, nominal, readings, options.anchors, a.g0, false, {});
    keep_better(FitFrom(model, a.g0, a.gauge.held, options, own), own);
  }
  // Below 6 cables every pose starts from home (PoseStarts), and a pose far from home can end
  // in another equilibrium: a 4-cable robot with its centre of mass off in x and z, poses 0.7 m
  // from home, had its noise-free readings fitted at 17.5 sigma, the exits 0.3 m off. Starting
  // every such pose staged instead led irma4u's noisy experiments to a higher minimum in 55 of
  // 60 (27 designed poses), so the staged starts are a second attempt only, for a fit that did
  // not converge or ended beyond kRetryWhitenedRms (whitened RMS over every value, the
  // equilibrium's rows included): a fit of readings at their noise has an RMS near 1, so a fit
  // from home that is good keeps its result bit for bit. The lower objective wins.
  if (model.nt > 0 && L.m < 6 && astray(fit)) {
    Locals staged = PoseStarts(model, nominal, readings, options.anchors, a.g0, true, {});
    bool differ = false;
    for (int j = 0; j < n; ++j) differ = differ || staged[j] != a.start[j];
    if (differ) keep_better(FitFrom(model, a.g0, a.gauge.held, options, staged), staged);
  }
  const VectorXd& g = fit.g;
  const Locals& locals = fit.locals;
  const bool converged = fit.converged;
  const int iterations = fit.iterations;
  const std::string& message = fit.message;

  result.geometry = g;
  for (const VectorXd& x : locals) {
    result.poses.push_back(x.head<6>());
    if (model.nt > 0) result.tensions_N.push_back(x.tail(model.nt));
  }
  result.iterations = iterations;
  // Plain whitened residuals (before the loss) per reading.
  result.fits.resize(readings.size());
  for (std::size_t k = 0; k < readings.size(); ++k) {
    result.fits[k].pose_id = readings[k].pose_id;
    result.fits[k].where = readings[k].where;
    result.fits[k].encoders = VectorXd::Zero(L.m);
    for (const SpatialSensor s : kSpatialSensors) {
      if (readings[k].has(s) && (s != SpatialSensor::kLoadCell || model.nt > 0)) {
        result.fits[k].sensors[static_cast<int>(s)] = VectorXd::Zero(SpatialSensorSize(s, L.m));
      }
    }
  }
  double cost = 0.0;
  double reading_squares = 0.0;
  int reading_values = 0, sensor_values = 0, tripped = 0;
  for (const Term& t : model.terms) {
    VectorXd r(t.size());
    EvaluateTerm(t, g, locals, r.data(), nullptr, nullptr);
    cost += 0.5 * r.squaredNorm();
    if (t.reading < 0) continue;
    if (t.sensor != kEquilibriumTerm) {
      for (int v = 0; v < t.size(); ++v) {
        const bool beyond = !(std::abs(r(v)) <= kOutlierSigmas);
        tripped += beyond;
        ++sensor_values;
        if (options.loss.kind != LossKind::kNone && beyond) continue;
        reading_squares += r(v) * r(v);
        ++reading_values;
      }
    }
    SpatialReadingFit& fit = result.fits[t.reading];
    VectorXd& out = ValuesOf(fit, t);
    if (t.sensor == kEquilibriumTerm) out.resize(6);
    out.segment(t.value, t.size()) = r;
    for (int v = 0; v < t.size(); ++v) {
      if (!(std::abs(r(v)) > std::abs(result.worst_residual))) continue;
      result.worst_residual = r(v);
      result.worst_pose_id = readings[t.reading].pose_id;
      result.worst_where = readings[t.reading].where;
      result.worst_sensor = ValueName(t, v, L.m);
    }
  }
  result.final_cost = cost;
  result.whitened_rms = reading_values > 0 ? std::sqrt(reading_squares / reading_values)
                                           : std::numeric_limits<double>::infinity();
  const std::vector<std::string> implausible = PlausibilityWarnings(nominal, g, a.g0);
  result.warnings = implausible;
  std::vector<int> unplanned;
  for (const int id : model.pose_ids) {
    if (!options.pose_starts.empty() && !options.pose_starts.count(id)) unplanned.push_back(id);
  }
  // A commanded pose is within the geometry's errors of where the platform settled: far from it,
  // the plan row is likely another pose's (ids renumbered, another experiment's plan). The fit
  // itself recovers (the rows stand out and are refitted, or the whole fit moves them), but the
  // lab should know its plan and readings disagree.
  std::vector<int> far;
  double farthest_m = 0.0;
  int farthest_id = 0;
  for (std::size_t j = 0; j < model.pose_ids.size(); ++j) {
    const auto planned = options.pose_starts.find(model.pose_ids[j]);
    if (planned == options.pose_starts.end()) continue;
    const double d_m = (locals[j].head<3>() - planned->second.q.head<3>()).norm();
    if (!(d_m > kSpatialPlanFarFromPose_m)) continue;
    far.push_back(model.pose_ids[j]);
    if (d_m > farthest_m) farthest_m = d_m, farthest_id = model.pose_ids[j];
  }
  if (!far.empty()) {
    char buf[160];
    std::snprintf(buf, sizeof(buf), " (the farthest, pose %d, %.3g m)", farthest_id, farthest_m);
    result.warnings.push_back(std::to_string(far.size()) + " of " + std::to_string(n) + " poses (" + PoseIdList(far) +
                              ") settled more than " + FormatDouble(100.0 * kSpatialPlanFarFromPose_m) +
                              " cm from their commanded poses in the plan" + buf +
                              ": are the plan's pose ids the readings'?");
  }
  // The tensions are unknowns without bounds (a bound would bias the covariance): a fit may
  // end with a cable pushing, which no cable does. Not a refusal, since the readings may fit
  // within their noise (too few poses, a geometry far off), but the lab must know its
  // estimate rests on an impossible state (a new user's 8-cable robot, 10 poses: -55 N).
  std::vector<int> pushing;
  double most_negative_N = 0.0;
  int most_negative_id = 0, most_negative_cable = 0;
  for (std::size_t j = 0; j < result.tensions_N.size(); ++j) {
    const VectorXd& t = result.tensions_N[j];
    if (t.size() == 0) continue;
    Eigen::Index i = 0;
    const double lowest_N = t.minCoeff(&i);
    if (!(lowest_N < 0.0)) continue;
    pushing.push_back(model.pose_ids[j]);
    if (lowest_N < most_negative_N) {
      most_negative_N = lowest_N;
      most_negative_id = model.pose_ids[j];
      most_negative_cable = static_cast<int>(i) + 1;
    }
  }
  if (!pushing.empty()) {
    char buf[160];
    std::snprintf(buf, sizeof(buf), " (the most, cable %d of pose %d: %.3g N)", most_negative_cable, most_negative_id,
                  most_negative_N);
    result.warnings.push_back(std::to_string(pushing.size()) + " of " + std::to_string(n) + " poses (" +
                              PoseIdList(pushing) + ") have a cable estimated pushing, a negative tension" + buf +
                              ": no cable can push, so the geometry rests on an impossible state there; measure "
                              "more poses, or check those poses' readings and the robot file's mass");
  }
  if (!unplanned.empty()) {
    result.warnings.push_back("pose" + std::string(unplanned.size() > 1 ? "s " : " ") + PoseIdList(unplanned) +
                              (unplanned.size() > 1 ? " have" : " has") +
                              " no row in the plan: started from home, not from a commanded pose");
  }
  if (a.gauge.redundancy == 0) {
    result.warnings.push_back(
        "no redundancy: " + std::to_string(a.model.num_values) +
        " reading values for as many unknowns, so the fit is exact whatever the readings (noise and gross errors "
        "alike) and no reading checks another; the sigmas are the model's, not confirmed by the data. Measure "
        "more poses (design warns at its fewest)");
  }
  if (std::abs(result.worst_residual) > kOutlierSigmas) {
    char buf[64];
    std::snprintf(buf, sizeof(buf), "%.3g", result.worst_residual);
    result.warnings.push_back("the worst reading, " + result.worst_sensor + " of pose " +
                              std::to_string(result.worst_pose_id) +
                              (result.worst_where.empty() ? "" : " (" + result.worst_where + ")") + ", is " + buf +
                              " sigma off the fit: an outlier, or a model that does not fit the data");
  }

  if (!converged) {
    result.status = SpatialIdentifyStatus::kNotConverged;
    // result.iterations counts the start too (as Ceres' summary does); the message counts steps,
    // so that a cap of --max-iterations N reads "after N".
    result.message = "the solver stopped after " + std::to_string(std::max(0, result.iterations - 1)) +
                     " iterations without converging: " + message;
    // Where it stopped: readings that do not fit this robot (wrong units, another robot, a
    // gross reading) mostly end here, and the last iterate's misfit points at them.
    char buf[240];
    std::snprintf(buf, sizeof(buf),
                  " (at the last iterate the readings' whitened RMS is %.3g; the worst, %s of pose %d, %.3g sigma%s)",
                  result.whitened_rms, result.worst_sensor.c_str(), result.worst_pose_id, result.worst_residual,
                  result.worst_where.empty() ? "" : (", " + result.worst_where).c_str());
    result.message += buf;
    if (result.whitened_rms > kSpatialPoorFitFactor) {
      result.message += ": readings far from any fit; are they in the file's units (m, rad), of this robot, in the "
                        "order of its cables? Else raise --max-iterations, or try --loss cauchy against a gross "
                        "reading";
      // Below 6 cables exact readings can end here too: a pose near the workspace's edge (a
      // helper's 4-cable robot, pitch 0.33 rad of a 0.35 limit) led both starts to another
      // equilibrium, and without it the rest fitted to 1e-15.
      if (model.nt > 0 && L.m < 6) {
        result.message += "; below 6 cables, a pose far from home or near the workspace's edge can also lead the fit "
                          "to another equilibrium from both its starts: identify without the pose named worst";
      }
    }
    return result;
  }
  // Covariance at the estimate with the gauge held (and what the leverages need, when asked).
  const bool leverages = options.reading_leverage && options.loss.kind == LossKind::kNone;
  std::vector<LeverageParts> leverage_parts;
  const MatrixXd A = ReducedJacobian(model, g, locals, false, true, leverages ? &leverage_parts : nullptr);
  std::vector<int> free;
  for (int c = 0; c < p; ++c) {
    if (!std::count(a.gauge.held.begin(), a.gauge.held.end(), c)) free.push_back(c);
  }
  MatrixXd A_free(A.rows(), free.size());
  for (std::size_t c = 0; c < free.size(); ++c) A_free.col(c) = A.col(free[c]);
  // Every direction seen (the usual case): (A^T A)^-1 = R^-1 R^-T from the triangular factor;
  // else the pseudo-inverse from the SVD.
  const MatrixXd R = TriangularFactor(A_free);
  const int f = static_cast<int>(free.size());
  MatrixXd R_inv;
  int unseen = 0;
  MatrixXd cov_free = MatrixXd::Zero(f, f);
  if (SurelyOfFullRank(R, &R_inv)) {
    cov_free = R_inv * R_inv.transpose();
  } else {
    const Eigen::BDCSVD<MatrixXd> svd(R, Eigen::ComputeFullV);
    const VectorXd& s = svd.singularValues();
    for (int c = 0; c < f; ++c) {
      if (!(s(c) > kSpatialNullThreshold * s(0))) {
        ++unseen;
        continue;
      }
      cov_free += svd.matrixV().col(c) * svd.matrixV().col(c).transpose() / (s(c) * s(c));
    }
  }
  result.covariance = MatrixXd::Zero(p, p);
  for (int r = 0; r < f; ++r) {
    for (int c = 0; c < f; ++c) result.covariance(free[r], free[c]) = cov_free(r, c);
  }
  result.sigma = result.covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
  const int expected_unseen = options.gauge.kind == SpatialGaugeKind::kNone ? static_cast<int>(a.gauge.null_directions.size()) : 0;
  if (unseen > expected_unseen) {
    result.status = SpatialIdentifyStatus::kRankDeficient;
    result.message = std::to_string(unseen - expected_unseen) +
                     " direction(s) of the geometry beyond the gauge are unseen at the estimate (the readings "
                     "saw them at the start only): not a result";
    return result;
  }
  if (leverages) {
    AddReadingLeverages(model, leverage_parts, free, cov_free, a.gauge.redundancy, &result);
  }
  // The verdicts of a converged fit (the planar identification's): readings far from it are
  // not noise, and a geometry off the frame is no robot's. Either is a status, never a result.
  if (!(result.whitened_rms <= kSpatialPoorFitFactor)) {
    char buf[200];
    std::snprintf(buf, sizeof(buf),
                  "the readings' whitened residuals have an RMS of %.3g times the sensors' noise (more than %g; "
                  "the worst, %s of pose %d, %.3g sigma)",
                  result.whitened_rms, kSpatialPoorFitFactor, result.worst_sensor.c_str(), result.worst_pose_id,
                  result.worst_residual);
    result.status = SpatialIdentifyStatus::kPoorFit;
    result.message = std::string(buf) +
                     ": the measurements do not fit this robot (are dl1..dl" + std::to_string(L.m) +
                     " in the order of the robot file's cables, the readings of this robot, in m and rad, and the "
                     "sensors' sigmas the robot file's?), or the solver stopped in a wrong minimum; a single gross "
                     "reading spreads over the whole fit, so the worst named may not be it: --loss cauchy finds it; "
                     "not a result";
    return result;
  }
  // Readings beyond kOutlierSigmas: without a robust loss any one refuses the fit (for clean
  // data each value is at most N(0, 1), so 400 values trip it with probability 0.3 %); with one,
  // a few are what it down-weights, and more than kFewOutliers or 5 % of the values point to
  // wrong units or another robot, which no loss mends.
  const int few = std::max(static_cast<int>(kFewOutliers), sensor_values / 20);
  const bool robust = options.loss.kind != LossKind::kNone;
  if (tripped > 0 && (!robust || tripped > few)) {
    char buf[200];
    std::snprintf(buf, sizeof(buf), "%d reading value%s beyond %g sigma, the worst %s of pose %d at %.3g sigma", tripped,
                  tripped == 1 ? "" : "s", kOutlierSigmas, result.worst_sensor.c_str(), result.worst_pose_id,
                  result.worst_residual);
    result.status = SpatialIdentifyStatus::kPoorFit;
    // A few such values are outliers to name; more are a model or file that does not fit.
    const std::string too_many =
        ": too many to be outliers: are the readings in the file's units (m, rad), of this robot, in the order of "
        "its cables, and the model its cables' (stretching cables identified as inextensible, the statics off, "
        "misfit by their stretch)?";
    result.message = "readings that do not fit this robot: " + std::string(buf) +
                     (result.worst_where.empty() ? "" : " (" + result.worst_where + ")") +
                     (tripped > few ? too_many
                                    : ": check that reading, drop its pose, or identify with --loss cauchy, which "
                                      "down-weights it") +
                     "; not a result";
    return result;
  }
  if (options.check_plausible_geometry && !implausible.empty()) {
    result.status = SpatialIdentifyStatus::kPoorFit;
    result.message = "the identified geometry is no robot's of this file: " + Join(implausible, "; ") +
                     "; few or bunched poses may not determine the geometry either (plan them with cablecal "
                     "design); not a result";
    return result;
  }
  result.status = SpatialIdentifyStatus::kConverged;
  return result;
}

}  // namespace cablecal
