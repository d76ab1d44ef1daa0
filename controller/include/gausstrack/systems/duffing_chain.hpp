// A chain of N Duffing masses with P tracking constraints on neighbouring relative displacements;
// the coupled Duffing oscillator of eq. (35) is the case N = 2, P = 1.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstddef>

#include "gausstrack/model.hpp"
#include "gausstrack/systems/decaying_sine.hpp"

namespace gausstrack::systems {

/// Mass i (i = 0..N-2) is tied to mass i+1 by (k1, kb1, c1); the last mass to ground by
/// (k2, kb2, c2). Masses alternate m1, m2 from the first. Constraint j (j = 0..P-1):
/// phi_j = x_j - x_(j+1) - s_j(t), so D has rows e_j - e_(j+1) (rank P) and g_j = s_j''(t).
template <int N, int P, typename Scalar_ = double>
struct DuffingChain {
  static_assert(N >= 2 && P >= 1 && P <= N - 1, "DuffingChain needs 1 <= P <= N - 1");
  using Scalar = Scalar_;
  static constexpr int kDof = N;
  static constexpr int kConstraints = P;
  static constexpr MassMatrix kMassMatrix = MassMatrix::kDiagonal;
  static constexpr int kHolonomicRows = P;
  using Vector = Eigen::Matrix<Scalar, N, 1>;
  using Terms = ModelTerms<N, P, Scalar>;

  Scalar m1 = Scalar(2), m2 = Scalar(1);
  Scalar k1 = Scalar(10), k2 = Scalar(12);
  Scalar kb1 = Scalar(1), kb2 = Scalar(2);
  Scalar c1 = Scalar(0.1), c2 = Scalar(0.15);
  std::array<DecayingSine<Scalar>, P> trajectories{};

  /// Visits every parameter by name: f(name, reference); row j's trajectory is amplitude_j,
  /// alpha_j, omega_j (j = 1..P).
  template <typename F>
  void parameters(F&& f) {
    f("m1", m1), f("m2", m2), f("k1", k1), f("k2", k2), f("kb1", kb1), f("kb2", kb2), f("c1", c1), f("c2", c2);
    static constexpr const char* kNames[3][8] = {
        {"amplitude_1", "amplitude_2", "amplitude_3", "amplitude_4", "amplitude_5", "amplitude_6", "amplitude_7", "amplitude_8"},
        {"alpha_1", "alpha_2", "alpha_3", "alpha_4", "alpha_5", "alpha_6", "alpha_7", "alpha_8"},
        {"omega_1", "omega_2", "omega_3", "omega_4", "omega_5", "omega_6", "omega_7", "omega_8"}};
    for (int j = 0; j < P && j < 8; ++j) {
      auto& s = trajectories[static_cast<std::size_t>(j)];
      f(kNames[0][j], s.amplitude), f(kNames[1][j], s.alpha), f(kNames[2][j], s.omega);
    }
  }

  void evaluate(const Vector& q, const Vector& qd, Scalar, Terms& terms) const noexcept {
    for (int i = 0; i < N; ++i) terms.mass_matrix(i, i) = (i % 2 == 0) ? m1 : m2;
    Vector& f = terms.nonlinear_force;
    f.setZero();
    for (int i = 0; i + 1 < N; ++i) {
      const Scalar d = q(i) - q(i + 1);
      const Scalar coupling = k1 * d + c1 * (qd(i) - qd(i + 1)) + kb1 * d * d * d;
      f(i) += coupling;
      f(i + 1) -= coupling;
    }
    const Scalar x = q(N - 1);
    f(N - 1) += k2 * x + c2 * qd(N - 1) + kb2 * x * x * x;
  }
  template <typename T>
  Eigen::Matrix<T, P, 1> phi(const Eigen::Matrix<T, N, 1>& q, const T& t) const {
    Eigen::Matrix<T, P, 1> e;
    for (int j = 0; j < P; ++j)
      e(j) = q(j) - q(j + 1) - trajectories[static_cast<std::size_t>(j)].position(t);
    return e;
  }
};

}  // namespace gausstrack::systems
