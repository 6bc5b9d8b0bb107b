// Second derivatives by nested forward-mode automatic differentiation: a ceres::Jet whose
// scalar is itself a Jet (identify/jacobian.h differentiates the identification's residuals
// with respect to the geometry and the pose, and the design needs those rows' derivatives with
// respect to the pose as well).
//
// A plain ceres::Jet<ceres::Jet<double, K>, N> cannot run the model's templates: they write
// constants as T(M_PI) and scale by doubles (signs.side * r), and neither a double nor a
// double-times-Jet converts to a Jet of Jets. InnerJet<K> is ceres::Jet<double, K> with an
// implicit constructor from double, so T(M_PI) builds the outer Jet; the operators below take
// a double on either side of an outer Jet. Both live in this namespace, which argument-
// dependent lookup searches for any Jet over an InnerJet, so the model's templates find them.
#pragma once

#include <ceres/jet.h>

#include <Eigen/Core>

namespace cablecal::nested_jet {

template <int K>
struct InnerJet : ceres::Jet<double, K> {
  using Base = ceres::Jet<double, K>;
  InnerJet() = default;
  InnerJet(double value) : Base(value) {}  // NOLINT: implicit on purpose (see above)
  InnerJet(double value, int k) : Base(value, k) {}
  InnerJet(const Base& jet) : Base(jet) {}  // NOLINT: results of Jet arithmetic come back
};

// Comparisons by value, as ceres' own for Jets (which do not take the derived type).
#define CABLECAL_INNER_JET_COMPARISON(op)                                  \
  template <int K>                                                         \
  bool operator op(const InnerJet<K>& f, const InnerJet<K>& g) {           \
    return f.a op g.a;                                                     \
  }                                                                        \
  template <int K>                                                         \
  bool operator op(const InnerJet<K>& f, double s) {                       \
    return f.a op s;                                                       \
  }                                                                        \
  template <int K>                                                         \
  bool operator op(double s, const InnerJet<K>& g) {                       \
    return s op g.a;                                                       \
  }
CABLECAL_INNER_JET_COMPARISON(==)
CABLECAL_INNER_JET_COMPARISON(!=)
CABLECAL_INNER_JET_COMPARISON(<)
CABLECAL_INNER_JET_COMPARISON(>)
CABLECAL_INNER_JET_COMPARISON(<=)
CABLECAL_INNER_JET_COMPARISON(>=)
#undef CABLECAL_INNER_JET_COMPARISON

template <int K, int N>
using Outer = ceres::Jet<InnerJet<K>, N>;

template <int K, int N>
Outer<K, N> operator+(const Outer<K, N>& f, double s) {
  return f + InnerJet<K>(s);
}
template <int K, int N>
Outer<K, N> operator+(double s, const Outer<K, N>& f) {
  return InnerJet<K>(s) + f;
}
template <int K, int N>
Outer<K, N> operator-(const Outer<K, N>& f, double s) {
  return f - InnerJet<K>(s);
}
template <int K, int N>
Outer<K, N> operator-(double s, const Outer<K, N>& f) {
  return InnerJet<K>(s) - f;
}
template <int K, int N>
Outer<K, N> operator*(const Outer<K, N>& f, double s) {
  return f * InnerJet<K>(s);
}
template <int K, int N>
Outer<K, N> operator*(double s, const Outer<K, N>& f) {
  return InnerJet<K>(s) * f;
}
template <int K, int N>
Outer<K, N> operator/(const Outer<K, N>& f, double s) {
  return f / InnerJet<K>(s);
}
template <int K, int N>
Outer<K, N> operator/(double s, const Outer<K, N>& f) {
  return InnerJet<K>(s) / f;
}

}  // namespace cablecal::nested_jet

namespace Eigen {
template <int K>
struct NumTraits<cablecal::nested_jet::InnerJet<K>> : NumTraits<ceres::Jet<double, K>> {
  using Real = cablecal::nested_jet::InnerJet<K>;
  using NonInteger = Real;
  using Nested = Real;
  using Literal = Real;
};
}  // namespace Eigen
