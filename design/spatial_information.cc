#include "design/spatial_information.h"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "common/csv.h"  // JoinCsv
#include "common/error.h"
#include "common/random.h"
#include "experiment/spatial_simulation.h"
#include "identify/nested_jet.h"
#include "identify/spatial_identify.h"
#include "model/spatial_sensor_model.h"
#include "model/swivel.h"

namespace cablecal {

namespace {

using Eigen::MatrixXd;
using Eigen::Vector3d;
using Eigen::VectorXd;

// Where each row of a pose's whitened Jacobian sits (-1: not read).
struct Rows {
  int equilibrium = -1, encoder = 0, swivel = -1, inclinometer = -1, laser = -1, position = -1, heading = -1,
      load_cell = -1, total = 0;
};

Rows RowsOf(const SpatialRobot& robot, const SpatialInformationLayout& L) {
  const int m = L.num_cables;
  Rows r;
  int next = 0;
  if (L.tensions) {
    r.equilibrium = next;
    next += 6;
  }
  r.encoder = next;
  next += m;
  const auto place = [&](SpatialSensor s, int* where) {
    if (!HasSpatialSensor(robot, s)) return;
    if (s == SpatialSensor::kLoadCell && !L.tensions) return;  // unused without the statics
    *where = next;
    next += SpatialSensorSize(s, m);
  };
  place(SpatialSensor::kInclinometer, &r.inclinometer);
  place(SpatialSensor::kLaser, &r.laser);
  place(SpatialSensor::kPosition, &r.position);
  place(SpatialSensor::kSwivel, &r.swivel);
  place(SpatialSensor::kHeading, &r.heading);
  place(SpatialSensor::kLoadCell, &r.load_cell);
  r.total = next;
  return r;
}

double InverseSigma(const SpatialRobot& robot, SpatialSensor s) {
  return 1.0 / SpatialSensorNoise(robot.sensors, s)->sigma();
}

// One cable's readings and its share of the equilibrium, from z = (x, y, z, roll, pitch, yaw,
// t, Dx, Dy, Dz, l0, sw0): out = (encoder, swivel, t W_i (6)), unwhitened. The identification's
// residuals (identify/spatial_identify.cc) less their readings.
constexpr int kCableZ = 12, kCableX = 7, kCableOut = 8;
template <typename T>
bool CableModel(const SpatialCable& c, bool elastic, const Vector3d& u_F_reference, const T* z, T* out) {
  SpatialPose<T> q;
  for (int a = 0; a < 6; ++a) q(a) = z[a];
  const Eigen::Matrix<T, 3, 3> R = Rotation<T>(q);
  const Vec3<T> D(z[7], z[8], z[9]);
  const SwivelCableState<T> s =
      SwivelCable<T>(D, c.k_F_swivel_axis.cast<T>(), T(c.pulley_radius_m), AnchorInF<T>(q, R, c.p_P_anchor_m.cast<T>()));
  if (!s.valid()) return false;
  out[0] = (elastic ? UnstretchedLength<T>(c, s.length_m, z[6]) : s.length_m) - z[10];
  out[1] = SwivelReading<T>(s, c.k_F_swivel_axis.cast<T>(), u_F_reference.cast<T>()) - z[11];
  const Eigen::Matrix<T, 6, 1> w = z[6] * WrenchColumn<T>(R * c.p_P_anchor_m.cast<T>(), s);
  for (int a = 0; a < 6; ++a) out[2 + a] = w(a);
  return true;
}

// The pose's own rows from z = (x, y, z, roll, pitch, yaw, yaw0, mass, cx, cy, cz): out =
// (gravity wrench (6), roll, pitch, laser, px, py, pz, heading), unwhitened.
constexpr int kPoseZ = 11, kPoseX = 6, kPoseOut = 13;
template <typename T>
bool PoseModel(const SpatialRobot& robot, const T* z, T* out) {
  SpatialPose<T> q;
  for (int a = 0; a < 6; ++a) q(a) = z[a];
  const Eigen::Matrix<T, 6, 1> g = GravityWrench<T>(q, z[7], Vec3<T>(z[8], z[9], z[10]), robot.gravity_mps2);
  for (int a = 0; a < 6; ++a) out[a] = g(a);
  const Vec2<T> tilt = InclinometerReading<T>(q);
  out[6] = tilt(0);
  out[7] = tilt(1);
  out[8] = LaserReading<T>(q, robot.p_F_frame_min_m.z());
  const Vector3d target = robot.sensors.position ? robot.sensors.position->p_P_target_m : Vector3d::Zero();
  const Vec3<T> p = PositionReading<T>(q, Rotation<T>(q), target.cast<T>());
  for (int a = 0; a < 3; ++a) out[9 + a] = p(a);
  out[12] = HeadingReading<T>(q, z[6]);
  return true;
}

// f's outputs, their Jacobian d out / d z (J, out x NZ) and, if dJ is given, that Jacobian's
// derivatives with respect to the first NX entries of z (dJ[k], out x NZ): nested Jets, the
// outer over z, the inner over z's first NX entries. Without dJ, plain Jets over z: the same
// arithmetic on the same values (J identical to the last bit), without the inner layer's cost.
template <int NZ, int NX, int NOUT, typename F>
bool Differentiate(const double* z, const F& f, Eigen::Matrix<double, NOUT, NZ>* J,
                   std::array<Eigen::Matrix<double, NOUT, NZ>, NX>* dJ) {
  if (!dJ) {
    using T = ceres::Jet<double, NZ>;
    std::array<T, NZ> zj;
    for (int c = 0; c < NZ; ++c) zj[c] = T(z[c], c);
    std::array<T, NOUT> out;
    if (!f(zj.data(), out.data())) return false;
    for (int r = 0; r < NOUT; ++r) J->row(r) = out[r].v.transpose();
    return true;
  }
  using Inner = nested_jet::InnerJet<NX>;
  using T = nested_jet::Outer<NX, NZ>;
  std::array<T, NZ> zj;
  for (int c = 0; c < NZ; ++c) {
    Inner value(z[c]);
    if (c < NX) value.v[c] = 1.0;
    zj[c] = T(value);
    zj[c].v[c] = Inner(1.0);
  }
  std::array<T, NOUT> out;
  if (!f(zj.data(), out.data())) return false;
  for (int r = 0; r < NOUT; ++r) {
    for (int c = 0; c < NZ; ++c) {
      (*J)(r, c) = out[r].v[c].a;
      for (int k = 0; k < NX; ++k) (*dJ)[k](r, c) = out[r].v[c].v[k];
    }
  }
  return true;
}

// One pose's whitened Jacobian and, if `dJ` is given, its derivatives with respect to the
// pose's 6 + m design variables (coordinates, tensions). False where a cable's geometry is
// invalid (no reading model there).
bool PoseJacobian(const SpatialRobot& robot, const SpatialInformationLayout& L, const SpatialPose<double>& q,
                  const VectorXd& t, MatrixXd* J, std::vector<MatrixXd>* dJ) {
  const int m = L.num_cables;
  const Rows rows = RowsOf(robot, L);
  const int local = L.local();
  const int cols = local + L.geometry_size();
  const int exits = local, lengths = local + 3 * m, offsets = local + 4 * m;
  const int yaw0 = local + 4 * m + (L.swivel ? m : 0);
  J->setZero(rows.total, cols);
  if (dJ) dJ->assign(6 + m, MatrixXd::Zero(rows.total, cols));
  const double weight_N = robot.platform_mass_kg * robot.gravity_mps2;
  const double inv_force = 1.0 / (kEquilibriumForceSigmaRelative * weight_N);
  const double inv_moment = 1.0 / (kEquilibriumMomentSigma_m * weight_N);
  const double inv_encoder = 1.0 / robot.sensors.encoder_sigma_m;
  const double inv_swivel = L.swivel ? InverseSigma(robot, SpatialSensor::kSwivel) : 0.0;
  const auto equilibrium_weight = [&](int a) { return a < 3 ? inv_force : inv_moment; };
  const SpatialSensorZero reference = SensorZeroAt(robot, robot.home_pose());

  for (int i = 0; i < m; ++i) {
    const SpatialCable& c = robot.cables[i];
    const bool elastic = L.tensions && c.stiffness_N.has_value();
    std::array<double, kCableZ> z{};
    for (int a = 0; a < 6; ++a) z[a] = q(a);
    z[6] = t(i);
    for (int a = 0; a < 3; ++a) z[7 + a] = c.p_F_exit_m(a);
    Eigen::Matrix<double, kCableOut, kCableZ> Jc;
    std::array<Eigen::Matrix<double, kCableOut, kCableZ>, kCableX> dJc;
    const auto f = [&](const auto* zz, auto* out) { return CableModel(c, elastic, reference.u_F[i], zz, out); };
    if (!Differentiate<kCableZ, kCableX, kCableOut>(z.data(), f, &Jc, dJ ? &dJc : nullptr)) return false;
    // z's columns in the pose's Jacobian (-1: not an unknown), and its rows' weights.
    std::array<int, kCableZ> col;
    for (int a = 0; a < 6; ++a) col[a] = a;
    col[6] = L.tensions ? 6 + i : -1;
    for (int a = 0; a < 3; ++a) col[7 + a] = exits + 3 * i + a;
    col[10] = lengths + i;
    col[11] = L.swivel ? offsets + i : -1;
    std::array<int, kCableOut> row;
    std::array<double, kCableOut> weight;
    row[0] = rows.encoder + i;
    weight[0] = inv_encoder;
    row[1] = L.swivel ? rows.swivel + i : -1;
    weight[1] = inv_swivel;
    for (int a = 0; a < 6; ++a) {
      row[2 + a] = L.tensions ? rows.equilibrium + a : -1;
      weight[2 + a] = equilibrium_weight(a);
    }
    for (int r = 0; r < kCableOut; ++r) {
      if (row[r] < 0) continue;
      for (int cz = 0; cz < kCableZ; ++cz) {
        if (col[cz] < 0) continue;
        (*J)(row[r], col[cz]) += weight[r] * Jc(r, cz);
        if (!dJ) continue;
        for (int k = 0; k < kCableX; ++k) (*dJ)[k < 6 ? k : 6 + i](row[r], col[cz]) += weight[r] * dJc[k](r, cz);
      }
    }
  }

  std::array<double, kPoseZ> z{};
  for (int a = 0; a < 6; ++a) z[a] = q(a);
  z[6] = robot.home_rpy_rad.z();
  z[7] = robot.platform_mass_kg;
  for (int a = 0; a < 3; ++a) z[8 + a] = robot.p_P_com_m(a);
  Eigen::Matrix<double, kPoseOut, kPoseZ> Jp;
  std::array<Eigen::Matrix<double, kPoseOut, kPoseZ>, kPoseX> dJp;
  const auto f = [&](const auto* zz, auto* out) { return PoseModel(robot, zz, out); };
  Differentiate<kPoseZ, kPoseX, kPoseOut>(z.data(), f, &Jp, dJ ? &dJp : nullptr);
  std::array<int, kPoseZ> col;
  for (int a = 0; a < 6; ++a) col[a] = a;
  col[6] = L.heading ? yaw0 : -1;
  for (int a = 0; a < 4; ++a) col[7 + a] = L.platform ? local + L.geometry_size() - 4 + a : -1;
  std::array<int, kPoseOut> row;
  std::array<double, kPoseOut> weight{};
  for (int a = 0; a < 6; ++a) {
    row[a] = L.tensions ? rows.equilibrium + a : -1;
    weight[a] = equilibrium_weight(a);
  }
  const auto sensor_rows = [&](SpatialSensor s, int first_out, int count, int first_row) {
    for (int k = 0; k < count; ++k) {
      row[first_out + k] = first_row < 0 ? -1 : first_row + k;
      weight[first_out + k] = first_row < 0 ? 0.0 : InverseSigma(robot, s);
    }
  };
  sensor_rows(SpatialSensor::kInclinometer, 6, 2, rows.inclinometer);
  sensor_rows(SpatialSensor::kLaser, 8, 1, rows.laser);
  sensor_rows(SpatialSensor::kPosition, 9, 3, rows.position);
  sensor_rows(SpatialSensor::kHeading, 12, 1, rows.heading);
  for (int r = 0; r < kPoseOut; ++r) {
    if (row[r] < 0) continue;
    for (int cz = 0; cz < kPoseZ; ++cz) {
      if (col[cz] < 0) continue;
      (*J)(row[r], col[cz]) += weight[r] * Jp(r, cz);
      if (!dJ) continue;
      for (int k = 0; k < kPoseX; ++k) (*dJ)[k](row[r], col[cz]) += weight[r] * dJp[k](r, cz);
    }
  }
  if (rows.load_cell >= 0) {
    const double inv = InverseSigma(robot, SpatialSensor::kLoadCell);
    for (int i = 0; i < m; ++i) (*J)(rows.load_cell + i, 6 + i) = inv;
  }
  return true;
}

// A pose's share of S: its geometry columns (the free ones) projected off its own unknowns'.
struct PoseShare {
  MatrixXd projected;  // (I - Jq Jq^+) Jf
  MatrixXd solved;     // Jq^+ Jf
};
PoseShare ShareOf(const SpatialInformationLayout& L, const MatrixXd& J) {
  const int local = L.local();
  MatrixXd Jf(J.rows(), L.free.size());
  for (std::size_t c = 0; c < L.free.size(); ++c) Jf.col(c) = J.col(local + L.free[c]);
  const MatrixXd Jq = J.leftCols(local);
  PoseShare s;
  s.solved = Jq.householderQr().solve(Jf);
  s.projected = Jf - Jq * s.solved;
  return s;
}

constexpr double kSingularRelative = 1e-14;

// The information of the free unknowns before any pose: an earlier identification's (design
// --prior, which holds the platform's prior already), else the platform's prior when its
// unknowns are among them.
MatrixXd InformationBeforePoses(const SpatialRobot& robot, const SpatialInformationLayout& L) {
  const int f = static_cast<int>(L.free.size());
  if (L.prior_information.size() > 0) return L.prior_information;
  MatrixXd F = MatrixXd::Zero(f, f);
  if (L.platform) F.bottomRightCorner<4, 4>().diagonal() = SpatialPlatformPriorSigma(robot).array().square().inverse().matrix();
  return F;
}

// The geometry's information from F (free x free): the platform's unknowns (F's last 4 rows and
// columns) eliminated, S = A - B C^-1 B^T. K (if given) receives [I; -C^-1 B^T], so that
// S = K^T F K and, F K being zero in the platform's rows, d S = K^T d F K for any change of F.
MatrixXd Eliminated(const SpatialInformationLayout& L, const MatrixXd& F, MatrixXd* K) {
  if (!L.platform) {
    if (K) *K = MatrixXd::Identity(F.rows(), F.cols());
    return F;
  }
  const int g = L.information_size();
  const Eigen::LDLT<Eigen::Matrix4d> C(F.bottomRightCorner<4, 4>());
  const MatrixXd CinvBt = C.solve(F.bottomLeftCorner(4, g));
  if (K) {
    K->resize(g + 4, g);
    K->topRows(g).setIdentity();
    K->bottomRows(4) = -CinvBt;
  }
  MatrixXd S = F.topLeftCorner(g, g) - F.topRightCorner(g, 4) * CinvBt;
  return 0.5 * (S + S.transpose());
}

// The criterion's value on S's eigenvalues and, if G is given, d value / d S.
double CriterionOf(Criterion criterion, const MatrixXd& S, double power, MatrixXd* G) {
  const Eigen::SelfAdjointEigenSolver<MatrixXd> eig(S);
  const VectorXd& l = eig.eigenvalues();
  const MatrixXd& V = eig.eigenvectors();
  const double inf = std::numeric_limits<double>::infinity();
  if (l.size() == 0 || !(l(0) > kSingularRelative * l(l.size() - 1)) || !l.allFinite()) return inf;
  const double lmin = l(0), lmax = l(l.size() - 1);
  VectorXd d(l.size());  // d value / d lambda_i
  double value = 0.0;
  switch (criterion) {
    case Criterion::kD:
      value = -l.array().log().sum();
      d = -l.cwiseInverse();
      break;
    case Criterion::kA: {
      const double trace = l.cwiseInverse().sum();
      value = std::log(trace);
      d = -l.array().square().inverse().matrix() / trace;
      break;
    }
    case Criterion::kE:
    case Criterion::kCondition: {
      VectorXd low = VectorXd::Zero(l.size()), high = VectorXd::Zero(l.size());
      double low_value = -std::log(lmin), high_value = std::log(lmax);
      if (power > 0.0) {
        const VectorXd wl = (lmin * l.cwiseInverse()).array().pow(power).matrix();
        const VectorXd wh = (l / lmax).array().pow(power).matrix();
        low_value += std::log(wl.sum()) / power;
        high_value += std::log(wh.sum()) / power;
        low = -(wl / wl.sum()).cwiseQuotient(l);
        high = (wh / wh.sum()).cwiseQuotient(l);
      } else {
        low(0) = -1.0 / lmin;
        high(l.size() - 1) = 1.0 / lmax;
      }
      if (criterion == Criterion::kE) {
        value = low_value;
        d = low;
      } else {  // log sqrt(lambda_max / lambda_min): S = A^T A
        value = 0.5 * (high_value + low_value);
        d = 0.5 * (high + low);
      }
      break;
    }
  }
  if (G) *G = V * d.asDiagonal() * V.transpose();
  return value;
}

bool StaticsModelled(const SpatialRobot& robot) {
  // The identification's rule (identify/spatial_identify.h, "Statics"): the tensions join when
  // load cells read them, a cable stretches, or the platform is underactuated.
  const int m = robot.num_cables();
  bool stretch = false;
  for (const SpatialCable& c : robot.cables) stretch = stretch || c.stiffness_N.has_value();
  return HasSpatialSensor(robot, SpatialSensor::kLoadCell) || stretch || m < 6;
}

}  // namespace

SpatialInformationLayout SpatialSensorLayout(const SpatialRobot& robot) {
  SpatialInformationLayout L;
  L.num_cables = robot.num_cables();
  L.swivel = HasSpatialSensor(robot, SpatialSensor::kSwivel);
  L.heading = HasSpatialSensor(robot, SpatialSensor::kHeading);
  L.load_cells = HasSpatialSensor(robot, SpatialSensor::kLoadCell);
  L.tensions = StaticsModelled(robot);
  L.platform = L.tensions;
  L.names = SpatialGeometryNames(L.num_cables, L.swivel, L.heading, false, L.platform);
  for (int c = 0; c < L.geometry_size(); ++c) L.free.push_back(c);
  return L;
}

int SpatialValuesPerPose(const SpatialRobot& robot, const SpatialInformationLayout& layout) {
  return RowsOf(robot, layout).total;
}

SpatialInformationLayout SpatialDesignLayout(const SpatialRobot& robot, const std::vector<SpatialPlanPose>& reference) {
  SpatialInformationLayout L = SpatialSensorLayout(robot);
  L.free.clear();
  // The identification's own gauge analysis on the readings these poses would give (read at the
  // poses themselves: a robot of more than 6 inextensible cables cannot be simulated, and the
  // study's encoders-alone design is made on one).
  const SpatialGaugeAnalysis gauge =
      AnalyzeSpatialGauge(robot, PlannedSpatialReadings(robot, reference), SpatialIdentifyOptions{});
  L.held = gauge.held;
  std::vector<const SpatialDirection*> fixed;
  for (const SpatialDirection& d : gauge.null_directions) fixed.push_back(&d);
  for (const SpatialDirection& d : gauge.weak_directions) {
    if (!d.nearly_rigid) continue;
    L.weakly_seen_held.push_back(d.description);
    fixed.push_back(&d);
  }
  L.null_directions = static_cast<int>(gauge.null_directions.size());
  L.gauge_directions.resize(L.geometry_size(), fixed.size());
  for (std::size_t c = 0; c < fixed.size(); ++c) L.gauge_directions.col(c) = fixed[c]->geometry;
  for (int c = 0; c < L.geometry_size(); ++c) {
    if (!std::count(L.held.begin(), L.held.end(), c)) L.free.push_back(c);
  }
  return L;
}

namespace {

// How many of `directions`' independent combinations the coordinates `rows` pin (the rank of
// those rows, relative to 1e-6 as the identification's DirectionsNotMoving).
int Pinned(const MatrixXd& directions, const std::vector<int>& rows) {
  if (directions.cols() == 0 || rows.empty()) return 0;
  MatrixXd R(rows.size(), directions.cols());
  for (std::size_t r = 0; r < rows.size(); ++r) R.row(r) = directions.row(rows[r]);
  const Eigen::JacobiSVD<MatrixXd> svd(R);
  int rank = 0;
  for (Eigen::Index k = 0; k < svd.singularValues().size(); ++k) rank += svd.singularValues()(k) > 1e-6 ? 1 : 0;
  return rank;
}

}  // namespace

void HoldAsThePrior(SpatialInformationLayout* layout, const std::vector<std::string>& held, const std::string& path) {
  if (held.empty()) return;
  SpatialInformationLayout& L = *layout;
  std::vector<int> rows;
  for (const std::string& h : held) {
    const auto it = std::find(L.names.begin(), L.names.end(), h);
    if (it == L.names.end()) throw InputError(path, "held", "'" + h + "' is not an unknown of this design");
    rows.push_back(static_cast<int>(it - L.names.begin()));
  }
  std::sort(rows.begin(), rows.end());
  const MatrixXd null = L.gauge_directions.leftCols(L.null_directions);
  const int pinned = Pinned(null, rows);
  if (pinned < L.null_directions) {
    throw InputError(path, "held",
                     "holds " + JoinCsv(held) + ", which leaves " + std::to_string(L.null_directions - pinned) + " of the " +
                         std::to_string(L.null_directions) +
                         " directions no reading of this robot file's sensors sees free: identify with the robot "
                         "file's sensors and --gauge auto (or a hold: that fixes them)");
  }
  if (Pinned(L.gauge_directions, rows) < L.gauge_directions.cols()) L.weakly_seen_held.clear();
  L.held = rows;
  L.free.clear();
  for (int c = 0; c < L.geometry_size(); ++c) {
    if (!std::binary_search(rows.begin(), rows.end(), c)) L.free.push_back(c);
  }
}

Eigen::MatrixXd SpatialPriorInformation(const SpatialInformationLayout& layout, const std::vector<std::string>& names,
                                        const std::vector<std::string>& held, const Eigen::MatrixXd& covariance,
                                        const std::string& path) {
  if (names != layout.names) {
    throw InputError(path, "parameters",
                     "estimates " + JoinCsv(names) + ", but a design for this robot file's sensors estimates " +
                         JoinCsv(layout.names) +
                         ": identify from readings of every sensor the robot file has (swivel offsets come with swivel "
                         "readings, yaw0 with heading readings) and the exits, not --identify anchors");
  }
  // HoldAsThePrior made the design hold what the result held (a result that held nothing keeps
  // the design's own gauge): the information below is of the design's free unknowns.
  for (const std::string& h : held) {
    CABLECAL_CHECK(std::count(layout.held.begin(), layout.held.end(),
                              static_cast<int>(std::find(names.begin(), names.end(), h) - names.begin())) == 1,
                   "the design holds what the prior held (HoldAsThePrior first)");
  }
  const int p = static_cast<int>(names.size());
  CABLECAL_CHECK(covariance.rows() == p && covariance.cols() == p, "a covariance by the result's names");
  std::vector<int> estimated;  // the result's free unknowns
  for (int c = 0; c < p; ++c) {
    if (std::find(held.begin(), held.end(), names[c]) == held.end()) estimated.push_back(c);
  }
  const int e = static_cast<int>(estimated.size());
  MatrixXd cov(e, e);
  for (int a = 0; a < e; ++a) {
    for (int b = 0; b < e; ++b) cov(a, b) = 0.5 * (covariance(estimated[a], estimated[b]) + covariance(estimated[b], estimated[a]));
  }
  const Eigen::SelfAdjointEigenSolver<MatrixXd> eig(cov);
  if (!cov.allFinite() || !(eig.eigenvalues()(0) > 0.0)) {
    throw InputError(path, "covariance", "the covariance of the unknowns it did not hold is not positive definite");
  }
  const MatrixXd information =
      eig.eigenvectors() * eig.eigenvalues().cwiseInverse().asDiagonal() * eig.eigenvectors().transpose();
  const int f = static_cast<int>(layout.free.size());
  MatrixXd out(f, f);
  for (int a = 0; a < f; ++a) {
    const int ia = static_cast<int>(std::find(estimated.begin(), estimated.end(), layout.free[a]) - estimated.begin());
    for (int b = 0; b < f; ++b) {
      const int ib = static_cast<int>(std::find(estimated.begin(), estimated.end(), layout.free[b]) - estimated.begin());
      out(a, b) = information(ia, ib);
    }
  }
  return out;
}

Eigen::MatrixXd SpatialPoseJacobian(const SpatialRobot& robot, const SpatialInformationLayout& layout,
                                    const SpatialPose<double>& q, const Eigen::VectorXd& tensions_N) {
  MatrixXd J;
  if (!PoseJacobian(robot, layout, q, tensions_N, &J, nullptr)) {
    throw SolverFailure("the readings' model is undefined at a pose with invalid cable geometry");
  }
  return J;
}

Eigen::MatrixXd SpatialFullInformation(const SpatialRobot& robot, const SpatialInformationLayout& layout,
                                       const std::vector<SpatialPlanPose>& poses) {
  MatrixXd F = InformationBeforePoses(robot, layout);
  for (const SpatialPlanPose& p : poses) {
    const PoseShare share = ShareOf(layout, SpatialPoseJacobian(robot, layout, p.q, p.tensions_N));
    F.noalias() += share.projected.transpose() * share.projected;
  }
  return F;
}

Eigen::MatrixXd SpatialGeometryInformation(const SpatialInformationLayout& layout, const Eigen::MatrixXd& full) {
  return Eliminated(layout, full, nullptr);
}

Eigen::MatrixXd SpatialInformation(const SpatialRobot& robot, const SpatialInformationLayout& layout,
                                   const std::vector<SpatialPlanPose>& poses) {
  return SpatialGeometryInformation(layout, SpatialFullInformation(robot, layout, poses));
}

CriteriaValues SpatialCriteria(const Eigen::MatrixXd& S) {
  CriteriaValues v;
  v.information_size = static_cast<int>(S.rows());
  const double inf = std::numeric_limits<double>::infinity();
  const double c = CriterionOf(Criterion::kCondition, S, 0.0, nullptr);
  const double d = CriterionOf(Criterion::kD, S, 0.0, nullptr);
  const double a = CriterionOf(Criterion::kA, S, 0.0, nullptr);
  const double e = CriterionOf(Criterion::kE, S, 0.0, nullptr);
  v.condition_number = std::isfinite(c) ? std::exp(c) : inf;
  v.d_log_det_information = std::isfinite(d) ? -d : -inf;
  v.a_trace_covariance_m2 = std::isfinite(a) ? std::exp(a) : inf;
  v.e_min_eigenvalue = std::isfinite(e) ? std::exp(-e) : 0.0;
  return v;
}

double SpatialDesignObjective(const SpatialRobot& robot, const SpatialInformationLayout& layout, Criterion criterion,
                              const std::vector<SpatialPlanPose>& poses, Eigen::VectorXd* gradient, double power) {
  const int n = static_cast<int>(poses.size());
  const int m = layout.num_cables;
  const int f = static_cast<int>(layout.free.size());
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<MatrixXd> J(n);
  std::vector<std::vector<MatrixXd>> dJ(n);
  std::vector<PoseShare> share(n);
  MatrixXd F = InformationBeforePoses(robot, layout);
  for (int j = 0; j < n; ++j) {
    if (!PoseJacobian(robot, layout, poses[j].q, poses[j].tensions_N, &J[j], gradient ? &dJ[j] : nullptr)) return inf;
    share[j] = ShareOf(layout, J[j]);
    F.noalias() += share[j].projected.transpose() * share[j].projected;
  }
  MatrixXd K, G_S;
  const MatrixXd S = Eliminated(layout, F, gradient ? &K : nullptr);
  const double value = CriterionOf(criterion, S, power, gradient ? &G_S : nullptr);
  if (!gradient || !std::isfinite(value)) return value;
  // d value = <G_S, d S> = <G, d F> with G = K G_S K^T (Eliminated); d F = sum_j d (Jf^T P Jf):
  // with J = [Jq | Jf], its derivative along any pose variable is <Lambda_j, d J_j>,
  // Lambda_f = 2 P Jf G, Lambda_q = -Lambda_f (Jq^+ Jf)^T.
  const MatrixXd G = K * G_S * K.transpose();
  const int local = layout.local();
  gradient->setZero(n * (6 + m));
  for (int j = 0; j < n; ++j) {
    const MatrixXd lambda_f = 2.0 * share[j].projected * G;
    MatrixXd lambda = MatrixXd::Zero(J[j].rows(), J[j].cols());
    lambda.leftCols(local) = -lambda_f * share[j].solved.transpose();
    for (int c = 0; c < f; ++c) lambda.col(local + layout.free[c]) = lambda_f.col(c);
    for (int k = 0; k < 6 + m; ++k) (*gradient)((6 + m) * j + k) = lambda.cwiseProduct(dJ[j][k]).sum();
  }
  return value;
}

}  // namespace cablecal
