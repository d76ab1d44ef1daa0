// The shipped systems with their constraints differentiated by hand to acceleration level
// (D q'' = g, with e and e' written out): the independent cross-check of the rows the library
// derives from phi and psi. Dynamics (A, f, Q) are the shipped models'; only the rows differ.
#pragma once

#include <cmath>
#include <cstddef>

#include "gausstrack/systems/coupled_duffing.hpp"
#include "gausstrack/systems/duffing_chain.hpp"
#include "gausstrack/systems/nonholonomic_particle.hpp"
#include "gausstrack/systems/pendulum.hpp"
#include "gausstrack/systems/planar_arm.hpp"

namespace gausstrack::test {

/// x1 - x2 = s(t): D = [1, -1], g = s''(t), e = x1 - x2 - s, e' = x1' - x2' - s'.
template <typename S>
struct HandDuffing : systems::CoupledDuffing<S> {
  static constexpr int kHolonomicRows = 0;
  using V = Eigen::Matrix<S, 2, 1>;
  void evaluate(const V& q, const V& qd, S t, typename systems::CoupledDuffing<S>::Terms& terms) const noexcept {
    systems::CoupledDuffing<S>::evaluate(q, qd, t, terms);
    terms.constraint_matrix << S(1), S(-1);
    terms.constraint_rhs(0) = this->trajectory.acceleration(t);
    terms.constraint_error(0) = q(0) - q(1) - this->trajectory.position(t);
    terms.constraint_error_rate(0) = qd(0) - qd(1) - this->trajectory.velocity(t);
  }
};

template <int N, int P, typename S = double>
struct HandDuffingChain : systems::DuffingChain<N, P, S> {
  static constexpr int kHolonomicRows = 0;
  using V = Eigen::Matrix<S, N, 1>;
  void evaluate(const V& q, const V& qd, S t, typename systems::DuffingChain<N, P, S>::Terms& terms) const noexcept {
    systems::DuffingChain<N, P, S>::evaluate(q, qd, t, terms);
    for (int j = 0; j < P; ++j) {
      const auto& s = this->trajectories[static_cast<std::size_t>(j)];
      terms.constraint_matrix(j, j) = S(1);
      terms.constraint_matrix(j, j + 1) = S(-1);
      terms.constraint_rhs(j) = s.acceleration(t);
      terms.constraint_error(j) = q(j) - q(j + 1) - s.position(t);
      terms.constraint_error_rate(j) = qd(j) - qd(j + 1) - s.velocity(t);
    }
  }
};

/// Eq. (34) differentiated twice: D = [2x (1 + mu L^2 cos(x^2)), 2y],
/// g = -(2 x'^2 (1 + mu L^2 cos(x^2)) - 4 mu L^2 x^2 x'^2 sin(x^2) + 2 y'^2).
template <typename S>
struct HandPendulum : systems::Pendulum<S> {
  static constexpr int kHolonomicRows = 0;
  using V = Eigen::Matrix<S, 2, 1>;
  void evaluate(const V& q, const V& qd, S t, typename systems::Pendulum<S>::Terms& terms) const noexcept {
    systems::Pendulum<S>::evaluate(q, qd, t, terms);
    const S l2 = this->length * this->length, m = this->mu;
    const S x2 = q(0) * q(0), xd2 = qd(0) * qd(0);
    terms.constraint_matrix << S(2) * q(0) * (S(1) + m * l2 * std::cos(x2)), S(2) * q(1);
    terms.constraint_rhs(0) =
        -(S(2) * xd2 * (S(1) + m * l2 * std::cos(x2)) - S(4) * m * l2 * x2 * xd2 * std::sin(x2) +
          S(2) * qd(1) * qd(1));
    terms.constraint_error(0) = x2 + q(1) * q(1) - l2 * (S(1) - m * std::sin(x2));
    terms.constraint_error_rate(0) = terms.constraint_matrix.row(0).dot(qd);
  }
};

/// y' - z x' = 0 differentiated once: D = [-z, 1, 0], g = z' x', e' = y' - z x'.
template <typename S>
struct HandParticle : systems::NonholonomicParticle<S> {
  static constexpr int kNonholonomicRows = 0;
  using V = Eigen::Matrix<S, 3, 1>;
  void evaluate(const V& q, const V& qd, S t, typename systems::NonholonomicParticle<S>::Terms& terms) const noexcept {
    systems::NonholonomicParticle<S>::evaluate(q, qd, t, terms);
    terms.constraint_matrix << -q(2), S(1), S(0);
    terms.constraint_rhs(0) = qd(2) * qd(0);
    terms.constraint_error_rate(0) = qd(1) - q(2) * qd(0);
  }
};

/// The arm's hand on the circle: D = J(q) (the hand's Jacobian), g = c''(t) - J'(q, q') q',
/// with J' q' = -sum_i l_i w_i^2 (cos theta_i, sin theta_i), w_i = q1' + ... + qi'.
template <typename S>
struct HandArm : systems::PlanarArm<S> {
  static constexpr int kHolonomicRows = 0;
  using V = Eigen::Matrix<S, 3, 1>;
  void evaluate(const V& q, const V& qd, S t, typename systems::PlanarArm<S>::Terms& terms) const noexcept {
    systems::PlanarArm<S>::evaluate(q, qd, t, terms);
    S c[3], s[3], w[3], theta = 0, omega = 0;
    for (int i = 0; i < 3; ++i) {
      theta += q(i);
      omega += qd(i);
      c[i] = std::cos(theta);
      s[i] = std::sin(theta);
      w[i] = omega;
    }
    Eigen::Matrix<S, 2, 1> drift = Eigen::Matrix<S, 2, 1>::Zero(), p = drift;
    Eigen::Matrix<S, 2, 3> jac = Eigen::Matrix<S, 2, 3>::Zero();
    for (int i = 0; i < 3; ++i) {
      const S l = this->length(i);
      p += l * Eigen::Matrix<S, 2, 1>(c[i], s[i]);
      drift -= l * w[i] * w[i] * Eigen::Matrix<S, 2, 1>(c[i], s[i]);
      for (int k = 0; k <= i; ++k) jac.col(k) += l * Eigen::Matrix<S, 2, 1>(-s[i], c[i]);
    }
    const S a = this->rate * t + this->phase, r = this->radius, w2 = this->rate * this->rate;
    const Eigen::Matrix<S, 2, 1> circle(this->center_x + r * std::cos(a), this->center_y + r * std::sin(a));
    const Eigen::Matrix<S, 2, 1> circle_rate(-r * this->rate * std::sin(a), r * this->rate * std::cos(a));
    const Eigen::Matrix<S, 2, 1> circle_acc(-r * w2 * std::cos(a), -r * w2 * std::sin(a));
    terms.constraint_matrix = jac;
    terms.constraint_rhs = circle_acc - drift;
    terms.constraint_error = p - circle;
    terms.constraint_error_rate = jac * qd - circle_rate;
  }
};

}  // namespace gausstrack::test
