// Planar pendulum bob in Cartesian coordinates with a constrained length, eqs. (33)-(34).
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <numbers>

namespace gausstrack::systems {

/// q = (x, y), y downwards. m x'' = Q'_x, m y'' = m g + Q'_y (eq. 33), subject to
///   phi(q) = x^2 + y^2 - L^2 (1 - mu sin(x^2)) = 0      (eq. 34; mu = 0 is a constant length).
/// Differentiating twice: D = [2x (1 + mu L^2 cos(x^2)), 2y],
///   g = -(2 x'^2 (1 + mu L^2 cos(x^2)) - 4 mu L^2 x^2 x'^2 sin(x^2) + 2 y'^2).
/// D depends on q, so neither term of eq. (32) is a pure feedforward here.
template <typename Scalar_ = double>
struct Pendulum {
  using Scalar = Scalar_;
  static constexpr int kDof = 2;
  static constexpr int kConstraints = 1;
  using Vector = Eigen::Matrix<Scalar, 2, 1>;
  using Rhs = Eigen::Matrix<Scalar, 1, 1>;

  Scalar mass = Scalar(1);                                 ///< m [kg]
  Scalar length = Scalar(20);                              ///< L [m]
  Scalar gravity = Scalar(4) * std::numbers::pi_v<Scalar>;  ///< g [m/s^2]
  Scalar mu = Scalar(0);                                   ///< length nonlinearity [-]

  Eigen::Matrix<Scalar, 2, 2> mass_matrix(const Vector&, Scalar) const noexcept {
    return Eigen::Matrix<Scalar, 2, 2>{{mass, Scalar(0)}, {Scalar(0), mass}};
  }
  Vector nonlinear_force(const Vector&, const Vector&, Scalar) const noexcept {
    return Vector::Zero();
  }
  Vector applied_force(const Vector&, const Vector&, Scalar) const noexcept {
    return Vector(Scalar(0), mass * gravity);
  }
  Eigen::Matrix<Scalar, 1, 2> constraint_matrix(const Vector& q, Scalar) const noexcept {
    const Scalar l2 = length * length;
    return Eigen::Matrix<Scalar, 1, 2>(
        Scalar(2) * q(0) * (Scalar(1) + mu * l2 * std::cos(q(0) * q(0))), Scalar(2) * q(1));
  }
  Rhs constraint_rhs(const Vector& q, const Vector& qd, Scalar) const noexcept {
    const Scalar l2 = length * length;
    const Scalar x2 = q(0) * q(0);
    const Scalar xd2 = qd(0) * qd(0);
    return Rhs(-(Scalar(2) * xd2 * (Scalar(1) + mu * l2 * std::cos(x2)) -
                 Scalar(4) * mu * l2 * x2 * xd2 * std::sin(x2) + Scalar(2) * qd(1) * qd(1)));
  }
  Rhs constraint_error(const Vector& q, Scalar) const noexcept {
    return Rhs(q(0) * q(0) + q(1) * q(1) -
               length * length * (Scalar(1) - mu * std::sin(q(0) * q(0))));
  }
  Rhs constraint_error_rate(const Vector& q, const Vector& qd, Scalar t) const noexcept {
    return constraint_matrix(q, t) * qd;
  }
};

}  // namespace gausstrack::systems
