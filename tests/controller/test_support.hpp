// Shared test helpers: reproducible randomness, named tolerances, one comparison helper, random
// constrained systems, and formulations independent of ConstraintSolver.
#pragma once

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <random>
#include <string>

#include "oracles.hpp"

namespace gausstrack::test {

/// Tolerances per scalar type, in one place.
template <typename Scalar>
struct Tolerance;
template <>
struct Tolerance<double> {
  static constexpr double kAgree = 1e-10;     // independent formulations, well-conditioned cases
  static constexpr double kIdentity = 1e-11;  // identities such as A q'' + f = Q + Q'
};
template <>
struct Tolerance<float> {
  static constexpr float kAgree = 2e-3f;
  static constexpr float kIdentity = 1e-4f;
};

/// Seed and repeat count from GAUSSTRACK_SEED / GAUSSTRACK_REPEAT, printed once.
inline std::uint64_t test_seed() {
  static const std::uint64_t seed = [] {
    const char* env = std::getenv("GAUSSTRACK_SEED");
    const std::uint64_t s = env ? std::strtoull(env, nullptr, 10) : 19930901ull;
    std::printf("[gausstrack] GAUSSTRACK_SEED=%llu\n", static_cast<unsigned long long>(s));
    return s;
  }();
  return seed;
}
inline int test_repeat(int fallback = 1000) {
  const char* env = std::getenv("GAUSSTRACK_REPEAT");
  return env ? std::atoi(env) : fallback;
}

/// ||actual - expected||_inf <= tol * scale, reporting the worst entry and where it is.
template <typename DA, typename DB>
::testing::AssertionResult near(const Eigen::MatrixBase<DA>& actual,
                                const Eigen::MatrixBase<DB>& expected, double tol, double scale,
                                const char* what = "") {
  if (actual.rows() != expected.rows() || actual.cols() != expected.cols())
    return ::testing::AssertionFailure() << what << ": size mismatch";
  double worst = -1;
  Eigen::Index wi = 0, wj = 0;
  for (Eigen::Index j = 0; j < actual.cols(); ++j)
    for (Eigen::Index i = 0; i < actual.rows(); ++i) {
      double d = std::abs(static_cast<double>(actual(i, j)) - static_cast<double>(expected(i, j)));
      if (std::isnan(d)) d = std::numeric_limits<double>::infinity();  // a NaN is the worst entry
      if (d > worst) {
        worst = d;
        wi = i;
        wj = j;
      }
    }
  if (worst <= tol * scale) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure()
         << what << ": worst difference " << worst << " at (" << wi << "," << wj << "): actual "
         << actual(wi, wj) << " expected " << expected(wi, wj) << ", allowed " << tol * scale
         << " (tol " << tol << " x scale " << scale << ")";
}

template <typename D>
double inf_norm(const Eigen::MatrixBase<D>& m) {
  return m.size() == 0 ? 0.0 : static_cast<double>(m.cwiseAbs().maxCoeff());
}


/// One random constrained system of fixed sizes.
template <int N, int P, typename Scalar = double>
struct RandomSystem {
  Eigen::Matrix<Scalar, N, N> A;
  Eigen::Matrix<Scalar, N, 1> f, Q;
  Eigen::Matrix<Scalar, P, N> D;
  Eigen::Matrix<Scalar, P, 1> g;
};

template <typename Scalar = double>
class RandomSource {
 public:
  explicit RandomSource(std::uint64_t salt = 0) : rng_(test_seed() ^ (salt * 0x9E3779B97F4A7C15ull)) {}

  Scalar uniform(Scalar lo, Scalar hi) { return std::uniform_real_distribution<Scalar>(lo, hi)(rng_); }

  template <int R, int C>
  Eigen::Matrix<Scalar, R, C> matrix() {
    Eigen::Matrix<Scalar, R, C> m;
    for (Eigen::Index i = 0; i < m.size(); ++i) m(i) = uniform(Scalar(-1), Scalar(1));
    return m;
  }

  template <int N>
  Eigen::Matrix<Scalar, N, N> orthogonal() {
    // The factorization is compiled once (oracles.cpp) for every size the tests draw.
    const Eigen::MatrixXd m = matrix<N, N>().template cast<double>();
    return oracle::orthogonal_factor(m).template cast<Scalar>();
  }

  /// Symmetric positive definite with eigenvalues log-uniform in [scale/cond, scale].
  template <int N>
  Eigen::Matrix<Scalar, N, N> spd(Scalar cond, Scalar scale = Scalar(1)) {
    const Eigen::Matrix<Scalar, N, N> U = orthogonal<N>();
    Eigen::Matrix<Scalar, N, 1> lambda;
    for (int i = 0; i < N; ++i) lambda(i) = scale * std::pow(cond, -uniform(Scalar(0), Scalar(1)));
    lambda(0) = scale;
    if (N > 1) lambda(N - 1) = scale / cond;
    Eigen::Matrix<Scalar, N, N> a = U * lambda.asDiagonal() * U.transpose();
    return Scalar(0.5) * (a + a.transpose());
  }

  /// P x N with prescribed singular values (descending), random singular vectors.
  template <int P, int N>
  Eigen::Matrix<Scalar, P, N> with_singular_values(const Eigen::Matrix<Scalar, P, 1>& sigma) {
    Eigen::Matrix<Scalar, P, N> s = Eigen::Matrix<Scalar, P, N>::Zero();
    for (int i = 0; i < P; ++i) s(i, i) = sigma(i);
    return orthogonal<P>() * s * orthogonal<N>().transpose();
  }

  template <int N, int P>
  RandomSystem<N, P, Scalar> system(Scalar mass_cond = Scalar(100)) {
    RandomSystem<N, P, Scalar> s;
    s.A = spd<N>(mass_cond, uniform(Scalar(0.5), Scalar(5)));
    s.f = matrix<N, 1>();
    s.Q = matrix<N, 1>();
    s.D = matrix<P, N>();
    s.g = matrix<P, 1>();
    return s;
  }

 private:
  std::mt19937_64 rng_;
};

/// The oracles at run-time size (oracles.cpp) on a fixed-size system: its matrices in double.
template <int N, int P, typename Scalar>
struct AsDynamic {
  Eigen::MatrixXd A, D;
  Eigen::VectorXd f, Q, g;
  explicit AsDynamic(const RandomSystem<N, P, Scalar>& s)
      : A(s.A.template cast<double>()), D(s.D.template cast<double>()), f(s.f.template cast<double>()),
        Q(s.Q.template cast<double>()), g(s.g.template cast<double>()) {}
};

/// Compact form Q' = A^(1/2) (D A^(-1/2))^+ (g - D a), a = A^-1 (Q - f), with the symmetric square
/// root (not the Cholesky factor the solver uses).
template <int N, int P, typename Scalar>
Eigen::Matrix<Scalar, N, 1> compact_form_force(const RandomSystem<N, P, Scalar>& s,
                                               Scalar tol = Scalar(1e-10)) {
  const AsDynamic<N, P, Scalar> d(s);
  return oracle::compact_form_force(d.A, d.f, d.Q, d.D, d.g, double(tol)).template cast<Scalar>();
}

/// Lagrange multipliers: [A -D^T; D 0] [q''; mu] = [Q - f; g], Q' = D^T mu (full row rank D).
template <int N, int P, typename Scalar>
std::pair<Eigen::Matrix<Scalar, N, 1>, Eigen::Matrix<Scalar, N, 1>> kkt_solution(
    const RandomSystem<N, P, Scalar>& s) {
  const AsDynamic<N, P, Scalar> d(s);
  const auto [qdd, force] = oracle::kkt_solution(d.A, d.f, d.Q, d.D, d.g);
  return {qdd.template cast<Scalar>(), force.template cast<Scalar>()};
}

/// Gauss's function, eq. (14): (A q'' + f - Q)^T A^-1 (A q'' + f - Q).
template <int N, int P, typename Scalar>
Scalar gauss_function(const RandomSystem<N, P, Scalar>& s, const Eigen::Matrix<Scalar, N, 1>& qdd) {
  const AsDynamic<N, P, Scalar> d(s);
  return Scalar(oracle::gauss_function(d.A, d.f, d.Q, qdd.template cast<double>()));
}

/// A random v with D v = 0 (projection of a random vector on the null space of D).
template <int N, int P, typename Scalar>
Eigen::Matrix<Scalar, N, 1> null_space_vector(const Eigen::Matrix<Scalar, P, N>& D,
                                              RandomSource<Scalar>& rng) {
  const Eigen::Matrix<Scalar, N, 1> w = rng.template matrix<N, 1>();
  const Eigen::MatrixXd pinv = oracle::pseudo_inverse(D.template cast<double>(), 1e-12);
  return w - (pinv * (D * w).template cast<double>()).template cast<Scalar>();
}

}  // namespace gausstrack::test
