#include "design/objective.h"

#include <ceres/jet.h>

#include <Eigen/Dense>
#include <cmath>
#include <limits>

#include "identify/jacobian.h"

namespace cablecal {
namespace internal {
namespace {

using Jet3 = ceres::Jet<double, 3>;

Pose<Jet3> Seeded(const Eigen::Vector3d& q) { return Pose<Jet3>(Jet3(q(0), 0), Jet3(q(1), 1), Jet3(q(2), 2)); }

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
double ConditionObjective(const Robot& robot, const std::vector<Eigen::Vector3d>& poses, Eigen::VectorXd* gradient,
                          double p) {
  const int n = static_cast<int>(poses.size());
  if (2 * n < 5 + n) return kInf;
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(2 * n, 5 + n);
  std::vector<LengthRows<Jet3>> rows(n);
  for (int j = 0; j < n; ++j) {
    rows[j] = LengthResidualRows<Jet3>(robot, Seeded(poses[j]));
    for (int i = 0; i < 2; ++i) {
      for (int c = 0; c < 5; ++c) J(2 * j + i, c) = rows[j](i, 1 + c).a;
      J(2 * j + i, 5 + j) = rows[j](i, 6).a;
    }
  }
  // Singular values and vectors through the eigen-decomposition of J'J (d x d, d = 5 + n),
  // several times faster than an SVD of J; the smallest sigma keeps a relative accuracy of
  // about eps * kappa^2, 1e-10 for kappa up to 1e3.
  const Eigen::MatrixXd M = J.transpose() * J;
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(M, gradient ? Eigen::ComputeEigenvectors : Eigen::EigenvaluesOnly);
  const int d = static_cast<int>(M.rows());
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
    gradient->setZero(3 * n);
    const Eigen::MatrixXd V = eig.eigenvectors().rowwise().reverse();
    const Eigen::MatrixXd U = (J * V) * s.cwiseInverse().asDiagonal();
    for (int j = 0; j < n; ++j) {
      for (int k = 0; k < 3; ++k) {
        double total = 0.0;
        for (int m = 0; m < d; ++m) {
          if (w(m) == 0.0) continue;
          double d_sigma = 0.0;  // u_m' dJ v_m over pose j's two rows
          for (int i = 0; i < 2; ++i) {
            double row_v = rows[j](i, 6).v(k) * V(5 + j, m);
            for (int c = 0; c < 5; ++c) row_v += rows[j](i, 1 + c).v(k) * V(c, m);
            d_sigma += U(2 * j + i, m) * row_v;
          }
          total += w(m) * d_sigma / s(m);  // d mu / mu / 2 = d sigma / sigma
        }
        (*gradient)(3 * j + k) = total;
      }
    }
  }
  return (lse_plus + lse_minus) / (2.0 * p);
}

// D, A, E objectives of S = sum_j S_j(q_j) and their gradients through dS_j/dq_j.
double InformationObjective(const Robot& robot, Criterion criterion, const std::vector<Eigen::Vector3d>& poses,
                            Eigen::VectorXd* gradient, double e_power, const PriorInformation* prior) {
  const int n = static_cast<int>(poses.size());
  std::vector<Eigen::Matrix<Jet3, 5, 5>> parts(n);
  // A calibration in rounds: the earlier identification's information adds to the new poses'.
  Eigen::Matrix<double, 5, 5> S = prior ? *prior : PriorInformation::Zero();
  for (int j = 0; j < n; ++j) {
    parts[j] = ReducedInformation<Jet3>(MlResidualRows<Jet3>(robot, Seeded(poses[j])));
    for (int a = 0; a < 5; ++a) {
      for (int b = 0; b < 5; ++b) S(a, b) += parts[j](a, b).a;
    }
  }
  S = 0.5 * (S + S.transpose());
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 5, 5>> eig(S);
  const double lambda_min = eig.eigenvalues()(0);
  if (!(lambda_min > 0.0) || !std::isfinite(lambda_min)) return kInf;
  // dF = sum_ab Gbar_ab dS_ab with Gbar = d objective / dS.
  Eigen::Matrix<double, 5, 5> Gbar;
  double value = 0.0;
  const Eigen::Matrix<double, 5, 5> S_inv = eig.eigenvectors() * eig.eigenvalues().cwiseInverse().asDiagonal() *
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
      // surrogate (log sum lambda^-p) / p lies within log(5) / p of it (same argument as
      // for the condition number). p <= 0 asks for the exact value.
      const Eigen::Matrix<double, 5, 1> log_l = eig.eigenvalues().array().log();
      if (e_power <= 0.0) {
        value = -log_l(0);
        Gbar.setZero();
        break;
      }
      const double lse = LogSumPow(log_l, -e_power);
      value = lse / e_power;
      Gbar.setZero();
      for (int k = 0; k < 5; ++k) {
        const Eigen::Matrix<double, 5, 1> v = eig.eigenvectors().col(k);
        const double weight = std::exp(-e_power * log_l(k) - lse) / eig.eigenvalues()(k);
        Gbar -= weight * (v * v.transpose());
      }
      break;
    }
    case Criterion::kCondition:
      return kInf;  // not an information criterion
  }
  if (gradient) {
    gradient->setZero(3 * n);
    for (int j = 0; j < n; ++j) {
      for (int k = 0; k < 3; ++k) {
        double d = 0.0;
        for (int a = 0; a < 5; ++a) {
          for (int b = 0; b < 5; ++b) d += Gbar(a, b) * parts[j](a, b).v(k);
        }
        (*gradient)(3 * j + k) = d;
      }
    }
  }
  return value;
}

}  // namespace

double DesignObjective(const Robot& robot, Criterion criterion, const std::vector<Eigen::Vector3d>& poses,
                       Eigen::VectorXd* gradient, double power, const PriorInformation* prior) {
  if (criterion == Criterion::kCondition) {
    return ConditionObjective(robot, poses, gradient, power > 0.0 ? power : kConditionPower);
  }
  return InformationObjective(robot, criterion, poses, gradient, power > 0.0 ? power : kEigenvaluePower, prior);
}

double ExactObjective(const Robot& robot, Criterion criterion, const std::vector<Eigen::Vector3d>& poses,
                      const PriorInformation* prior) {
  if (criterion == Criterion::kCondition) return ConditionObjective(robot, poses, nullptr, 0.0);
  return InformationObjective(robot, criterion, poses, nullptr, 0.0, prior);
}

}  // namespace internal

CriteriaValues EvaluateCriteria(const Robot& robot, const std::vector<Eigen::Vector3d>& poses,
                                const PriorInformation* prior) {
  CriteriaValues v;
  v.condition_number = std::exp(internal::ExactObjective(robot, Criterion::kCondition, poses));
  v.d_log_det_information = -internal::ExactObjective(robot, Criterion::kD, poses, prior);
  v.a_trace_covariance_m2 = std::exp(internal::ExactObjective(robot, Criterion::kA, poses, prior));
  v.e_min_eigenvalue = std::exp(-internal::ExactObjective(robot, Criterion::kE, poses, prior));
  return v;
}

double Improvement(Criterion c, const CriteriaValues& set, const CriteriaValues& reference) {
  switch (c) {
    case Criterion::kCondition: return reference.condition_number / set.condition_number;
    case Criterion::kD: return std::exp((set.d_log_det_information - reference.d_log_det_information) / 5.0);
    case Criterion::kA: return reference.a_trace_covariance_m2 / set.a_trace_covariance_m2;
    case Criterion::kE: return set.e_min_eigenvalue / reference.e_min_eigenvalue;
  }
  return 0.0;
}

}  // namespace cablecal
