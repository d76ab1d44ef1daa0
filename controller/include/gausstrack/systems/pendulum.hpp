// Planar pendulum bob in Cartesian coordinates with a constrained length, eqs. (33)-(34).
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <numbers>

#include "gausstrack/model.hpp"

namespace gausstrack::systems {

/// q = (x, y), y downwards. m x'' = Q'_x, m y'' = m g + Q'_y (eq. 33): gravity is the impressed
/// force Q = (0, m g), f = 0. Constraint (eq. 34; mu = 0 is a constant length):
///   phi(q) = x^2 + y^2 - L^2 (1 - mu sin(x^2)) = 0.
/// D depends on q, so neither term of eq. (32) is a pure feedforward here.
template <typename Scalar_ = double>
struct Pendulum {
  using Scalar = Scalar_;
  static constexpr int kDof = 2;
  static constexpr int kConstraints = 1;
  static constexpr MassMatrix kMassMatrix = MassMatrix::kDiagonal;
  static constexpr int kHolonomicRows = 1;
  using Vector = Eigen::Matrix<Scalar, 2, 1>;
  using Terms = ModelTerms<2, 1, Scalar>;

  Scalar mass = Scalar(1);                                 ///< m [kg]
  Scalar length = Scalar(20);                              ///< L [m]
  Scalar gravity = Scalar(4) * std::numbers::pi_v<Scalar>;  ///< g [m/s^2]
  Scalar mu = Scalar(0);                                   ///< length nonlinearity [-]

  /// Visits every parameter by name: f(name, reference).
  template <typename F>
  void parameters(F&& f) {
    f("mass", mass), f("length", length), f("gravity", gravity), f("mu", mu);
  }

  void evaluate(const Vector&, const Vector&, Scalar, Terms& terms) const noexcept {
    terms.mass_matrix.diagonal().setConstant(mass);
    terms.applied_force(1) = mass * gravity;
  }
  template <typename T>
  Eigen::Matrix<T, 1, 1> phi(const Eigen::Matrix<T, 2, 1>& q, const T&) const {
    using std::sin;
    return Eigen::Matrix<T, 1, 1>(q(0) * q(0) + q(1) * q(1) -
                                  (length * length) * (Scalar(1) - mu * sin(q(0) * q(0))));
  }
};

}  // namespace gausstrack::systems
