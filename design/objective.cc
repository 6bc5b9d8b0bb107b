#include "design/objective.h"

#include <ceres/jet.h>

#include <Eigen/Dense>
#include <cmath>
#include <limits>

#include "common/error.h"
#include "identify/jacobian.h"
#include "identify/nested_jet.h"
#include "model/kind.h"

namespace cablecal {
namespace internal {

// The geometry columns the default gauge leaves free (3m - 1: a1x held).
std::vector<int> FreeColumns(const Robot& robot) { return PlanarKind::FreeByDefault(LayoutOf(robot)); }

namespace {

// The pose's own coordinates as Jets (identify/nested_jet.h): the rows of identify/jacobian.h
// then carry their exact derivatives with respect to x, z, theta.
constexpr int kPose = PlanarKind::kPoseDim;
using PoseJet = nested_jet::InnerJet<kPose>;

Pose<PoseJet> Seeded(const PlanarPose& q) {
  Pose<PoseJet> seeded;
  for (int k = 0; k < kPose; ++k) seeded(k) = PoseJet(q(k), k);
  return seeded;
}



constexpr double kInf = std::numeric_limits<double>::infinity();

// log-sum-exp of p * log(mu_k): log sum mu_k^p without overflow.
double LogSumPow(const Eigen::VectorXd& log_mu, double p) {
  const double m = (p * log_mu).maxCoeff();
  return m + std::log((p * log_mu.array() - m).exp().sum());
}

// The condition number is not differentiable where its extreme singular values are
// repeated, which is where its minimisers tend to sit, so Ipopt minimises the smooth
// spectral surrogate  log kappa_p = (log sum mu^p + log sum mu^-p) / (2p),  mu = sigma^2,
// the eigenvalues of J'J. With d the number of columns, kappa <= kappa_p <= d^(1/p) kappa,
// hence the surrogate's minimiser has kappa within d^(1/p) of the optimum (README).
// The gradient follows from d mu_k = 2 sigma_k u_k' dJ v_k, exact for a spectral function.
// J: per pose the m length rows, columns a1z .. lm0 (3m - 1, a1x held) and every pose's x.
double ConditionObjective(const Robot& robot, const std::vector<PlanarPose>& poses, Eigen::VectorXd* gradient,
                          double p) {
  const int num_cables = robot.num_cables();
  const std::vector<int> free = FreeColumns(robot);
  const int G = static_cast<int>(free.size());  // geometry columns
  const int x_column = PlanarLayout(num_cables).size();  // the x column of identify/jacobian.h's rows
  const int n = static_cast<int>(poses.size());
  if (num_cables * n < G + n) return kInf;
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(num_cables * n, G + n);
  // With a gradient the rows carry their pose derivatives (nested Jets); without, plain
  // doubles: the same values, to the last bit, at a fraction of the cost.
  std::vector<Rows<PoseJet>> rows(gradient ? n : 0);
  for (int j = 0; j < n; ++j) {
    Rows<double> values(num_cables, RowColumns(num_cables));
    if (gradient) {
      rows[j] = LengthResidualRows<PoseJet>(robot, Seeded(poses[j]));
      for (int i = 0; i < num_cables; ++i) {
        for (int c = 0; c < RowColumns(num_cables); ++c) values(i, c) = rows[j](i, c).a;
      }
    } else {
      values = LengthResidualRows<double>(robot, poses[j]);
    }
    for (int i = 0; i < num_cables; ++i) {
      for (int c = 0; c < G; ++c) J(num_cables * j + i, c) = values(i, free[c]);
      J(num_cables * j + i, G + j) = values(i, x_column);
    }
  }
  // Singular values and vectors through the eigen-decomposition of J'J (d x d, d = G + n),
  // several times faster than an SVD of J; the smallest sigma keeps a relative accuracy of
  // about eps * kappa^2, 1e-10 for kappa up to 1e3.
  const Eigen::MatrixXd Mt = J.transpose() * J;
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(Mt, gradient ? Eigen::ComputeEigenvectors : Eigen::EigenvaluesOnly);
  const int d = static_cast<int>(Mt.rows());
  // Descending order, as an SVD would give.
  const Eigen::VectorXd s = eig.eigenvalues().reverse().cwiseMax(0.0).cwiseSqrt();
  if (!(s(d - 1) > 0.0)) return kInf;
  if (p <= 0.0) return std::log(s(0) / s(d - 1));  // the exact condition number
  const Eigen::VectorXd log_mu = 2.0 * s.array().log();
  const double lse_plus = LogSumPow(log_mu, p), lse_minus = LogSumPow(log_mu, -p);
  if (gradient) {
    // d value = sum_k w_k d mu_k / mu_k / 2 with w_k = (mu^p / sum mu^p - mu^-p / sum mu^-p).
    Eigen::VectorXd w(d);
    for (int k = 0; k < d; ++k) {
      w(k) = std::exp(p * log_mu(k) - lse_plus) - std::exp(-p * log_mu(k) - lse_minus);
    }
    gradient->setZero(kPose * n);
    const Eigen::MatrixXd V = eig.eigenvectors().rowwise().reverse();
    const Eigen::MatrixXd U = (J * V) * s.cwiseInverse().asDiagonal();
    for (int j = 0; j < n; ++j) {
      for (int k = 0; k < kPose; ++k) {
        double total = 0.0;
        for (int m = 0; m < d; ++m) {
          if (w(m) == 0.0) continue;
          double d_sigma = 0.0;  // u_m' dJ v_m over pose j's num_cables rows
          for (int i = 0; i < num_cables; ++i) {
            double row_v = rows[j](i, x_column).v(k) * V(G + j, m);
            for (int c = 0; c < G; ++c) row_v += rows[j](i, free[c]).v(k) * V(c, m);
            d_sigma += U(num_cables * j + i, m) * row_v;
          }
          total += w(m) * d_sigma / s(m);  // d mu / mu / 2 = d sigma / sigma
        }
        (*gradient)(kPose * j + k) = total;
      }
    }
  }
  return (lse_plus + lse_minus) / (2.0 * p);
}

// D, A, E objectives of S = sum_j S_j(q_j) (3m - 1 square) and their gradients through dS_j/dq_j.
double InformationObjective(const Robot& robot, Criterion criterion, const std::vector<PlanarPose>& poses,
                            Eigen::VectorXd* gradient, double e_power, const PriorInformation* prior) {
  const int G = static_cast<int>(FreeColumns(robot).size());
  using Information = Eigen::MatrixXd;
  const int n = static_cast<int>(poses.size());
  std::vector<Rows<PoseJet>> parts(gradient ? n : 0);  // as in ConditionObjective
  // A calibration in rounds: the earlier identification's information adds to the new poses'.
  CABLECAL_CHECK(!prior || (prior->rows() == G && prior->cols() == G),
                 "the prior information covers the 3m - 1 gauge-fixed geometric parameters");
  Information S = prior ? Information(*prior) : Information::Zero(G, G);
  for (int j = 0; j < n; ++j) {
    if (gradient) {
      parts[j] = ReducedInformation<PoseJet>(MlResidualRows<PoseJet>(robot, Seeded(poses[j])));
      for (int a = 0; a < G; ++a) {
        for (int b = 0; b < G; ++b) S(a, b) += parts[j](a, b).a;
      }
    } else {
      const Information part = ReducedInformation<double>(MlResidualRows<double>(robot, poses[j]));
      for (int a = 0; a < G; ++a) {
        for (int b = 0; b < G; ++b) S(a, b) += part(a, b);
      }
    }
  }
  S = 0.5 * (S + S.transpose());
  Eigen::SelfAdjointEigenSolver<Information> eig(S);
  const double lambda_min = eig.eigenvalues()(0);
  if (!(lambda_min > 0.0) || !std::isfinite(lambda_min)) return kInf;
  // dF = sum_ab Gbar_ab dS_ab with Gbar = d objective / dS.
  Information Gbar;
  double value = 0.0;
  const Information S_inv = eig.eigenvectors() * eig.eigenvalues().cwiseInverse().asDiagonal() *
                            eig.eigenvectors().transpose();
  switch (criterion) {
    case Criterion::kD:
      value = -eig.eigenvalues().array().log().sum();
      Gbar = -S_inv;
      break;
    case Criterion::kA: {
      const double trace = S_inv.trace();
      value = std::log(trace);
      Gbar = -(S_inv * S_inv) / trace;
      break;
    }
    case Criterion::kE: {
      // -log lambda_min is not differentiable where the smallest eigenvalues coincide; the
      // surrogate (log sum lambda^-p) / p lies within log(3m - 1) / p of it (same argument as
      // for the condition number). p <= 0 asks for the exact value.
      const Eigen::VectorXd log_l = eig.eigenvalues().array().log();
      if (e_power <= 0.0) {
        value = -log_l(0);
        Gbar.setZero(G, G);
        break;
      }
      const double lse = LogSumPow(log_l, -e_power);
      value = lse / e_power;
      Gbar.setZero(G, G);
      for (int k = 0; k < G; ++k) {
        const Eigen::VectorXd v = eig.eigenvectors().col(k);
        const double weight = std::exp(-e_power * log_l(k) - lse) / eig.eigenvalues()(k);
        Gbar -= weight * (v * v.transpose());
      }
      break;
    }
    case Criterion::kCondition:
      return kInf;  // not an information criterion
  }
  if (gradient) {
    gradient->setZero(kPose * n);
    for (int j = 0; j < n; ++j) {
      for (int k = 0; k < kPose; ++k) {
        double d = 0.0;
        for (int a = 0; a < G; ++a) {
          for (int b = 0; b < G; ++b) d += Gbar(a, b) * parts[j](a, b).v(k);
        }
        (*gradient)(kPose * j + k) = d;
      }
    }
  }
  return value;
}

}  // namespace

double DesignObjective(const Robot& robot, Criterion criterion, const std::vector<PlanarPose>& poses,
                       Eigen::VectorXd* gradient, double power, const PriorInformation* prior) {
  if (criterion == Criterion::kCondition) {
    return ConditionObjective(robot, poses, gradient, power > 0.0 ? power : kConditionPower);
  }
  return InformationObjective(robot, criterion, poses, gradient, power > 0.0 ? power : kEigenvaluePower, prior);
}

double ExactObjective(const Robot& robot, Criterion criterion, const std::vector<PlanarPose>& poses,
                      const PriorInformation* prior) {
  if (criterion == Criterion::kCondition) return ConditionObjective(robot, poses, nullptr, 0.0);
  return InformationObjective(robot, criterion, poses, nullptr, 0.0, prior);
}

}  // namespace internal

CriteriaValues EvaluateCriteria(const Robot& robot, const std::vector<PlanarPose>& poses,
                                const PriorInformation* prior) {
  CriteriaValues v;
  v.condition_number = std::exp(internal::ExactObjective(robot, Criterion::kCondition, poses));
  v.d_log_det_information = -internal::ExactObjective(robot, Criterion::kD, poses, prior);
  v.a_trace_covariance_m2 = std::exp(internal::ExactObjective(robot, Criterion::kA, poses, prior));
  v.e_min_eigenvalue = std::exp(-internal::ExactObjective(robot, Criterion::kE, poses, prior));
  v.information_size = static_cast<int>(internal::FreeColumns(robot).size());
  return v;
}

double Improvement(Criterion c, const CriteriaValues& set, const CriteriaValues& reference) {
  switch (c) {
    case Criterion::kCondition: return reference.condition_number / set.condition_number;
    case Criterion::kD: {
      // The geometric mean per eigenvalue of S: (det S / det S_ref)^(1 / (3m - 1)).
      const int size = set.information_size > 0 ? set.information_size : reference.information_size;
      CABLECAL_CHECK(size > 0 && (reference.information_size == 0 || reference.information_size == size),
                     "criteria of the same robot, from EvaluateCriteria");
      return std::exp((set.d_log_det_information - reference.d_log_det_information) / size);
    }
    case Criterion::kA: return reference.a_trace_covariance_m2 / set.a_trace_covariance_m2;
    case Criterion::kE: return set.e_min_eigenvalue / reference.e_min_eigenvalue;
  }
  return 0.0;
}

}  // namespace cablecal
