// Coupled damped Duffing oscillator of eq. (35), forced to track x1 - x2 = s(t) (eq. 35c).
#pragma once

#include <Eigen/Core>

#include "gausstrack/model.hpp"
#include "gausstrack/systems/decaying_sine.hpp"

namespace gausstrack::systems {

/// q = (x1, x2). Mass 1 is tied to mass 2 by a linear spring k1, a cubic spring kb1 and a damper
/// c1; mass 2 to ground by k2, kb2, c2:
///   m1 x1'' + k1 d + c1 d' + kb1 d^3 = Q'_1,                       d = x1 - x2      (35a)
///   m2 x2'' + k2 x2 - k1 d + c2 x2' - c1 d' + kb2 x2^3 - kb1 d^3 = Q'_2             (35b)
/// The printed eq. (35b) carries k2 and k1 on the cubic terms; they are kb2 and kb1 (the cubic
/// spring of eq. 35a acts on both masses), corrected here. Springs and dampers are in f, Q = 0.
/// Constraint phi = x1 - x2 - s(t) = 0 (eq. 35c): the library derives D = [1, -1], g = s''(t).
/// A, D and g depend on t alone, so the force_from_rhs term of eq. (32) is a pure feedforward
/// and the other term carries the feedback.
template <typename Scalar_ = double>
struct CoupledDuffing {
  using Scalar = Scalar_;
  static constexpr int kDof = 2;
  static constexpr int kConstraints = 1;
  static constexpr MassMatrix kMassMatrix = MassMatrix::kDiagonal;
  static constexpr int kHolonomicRows = 1;
  using Vector = Eigen::Matrix<Scalar, 2, 1>;
  using Terms = ModelTerms<2, 1, Scalar>;

  Scalar m1 = Scalar(2), m2 = Scalar(1);         ///< [kg]
  Scalar k1 = Scalar(10), k2 = Scalar(12);       ///< [N/m]
  Scalar kb1 = Scalar(1), kb2 = Scalar(2);       ///< [N/m^3]
  Scalar c1 = Scalar(0.1), c2 = Scalar(0.15);    ///< [N s/m]
  DecayingSine<Scalar> trajectory{};

  /// Visits every parameter by name (for configuration files): f(name, reference).
  template <typename F>
  void parameters(F&& f) {
    f("m1", m1), f("m2", m2), f("k1", k1), f("k2", k2), f("kb1", kb1), f("kb2", kb2), f("c1", c1), f("c2", c2);
    f("amplitude", trajectory.amplitude), f("alpha", trajectory.alpha), f("omega", trajectory.omega);
  }

  void evaluate(const Vector& q, const Vector& qd, Scalar, Terms& terms) const noexcept {
    terms.mass_matrix(0, 0) = m1;
    terms.mass_matrix(1, 1) = m2;
    terms.nonlinear_force = spring_damper_force(q, qd);
  }
  /// f of eq. (35): the springs and dampers [N].
  Vector spring_damper_force(const Vector& q, const Vector& qd) const noexcept {
    const Scalar d = q(0) - q(1);
    const Scalar dd = qd(0) - qd(1);
    const Scalar coupling = k1 * d + c1 * dd + kb1 * d * d * d;
    const Scalar ground = k2 * q(1) + c2 * qd(1) + kb2 * q(1) * q(1) * q(1);
    return Vector(coupling, ground - coupling);
  }
  template <typename T>
  Eigen::Matrix<T, 1, 1> phi(const Eigen::Matrix<T, 2, 1>& q, const T& t) const {
    return Eigen::Matrix<T, 1, 1>(q(0) - q(1) - trajectory.position(t));
  }
  /// x1'(0) that makes (x1(0), x2(0), x1'(0), x2'(0) = d) satisfy the constraint: c = d + s'(0).
  Scalar consistent_x1_velocity(Scalar x2_velocity) const noexcept {
    return x2_velocity + trajectory.velocity(Scalar(0));
  }
};

}  // namespace gausstrack::systems
