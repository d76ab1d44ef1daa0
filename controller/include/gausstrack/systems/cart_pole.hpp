// A pendulum hanging from a cart, pushed by a motor on the cart alone: an underactuated machine
// (N = 2 coordinates, K = 1 actuator). The task swings the pendulum through a prescribed angle;
// the law finds the cart force that does it (actuation.hpp).
#pragma once

#include <Eigen/Core>
#include <cmath>

#include "gausstrack/model.hpp"

namespace gausstrack::systems {

/// q = (x, theta): the cart's position [m] and the pendulum's angle from the downward vertical
/// [rad], positive toward +x; a point mass m at distance l from the hinge, the cart of mass M.
///   A(q) = [M + m, m l cos theta; m l cos theta, m l^2]
///   f(q, q') = (-m l sin theta theta'^2, 0)      centrifugal
///   Q(q) = (0, -m g l sin theta)                 gravity, an impressed force
///   B = (1, 0)                                   the motor pushes the cart
/// Constraint: phi = theta - a sin(w t). D A^-1 B = -m l cos theta / det A: the cart's force
/// reaches the angle unless the pendulum is horizontal.
template <typename Scalar_ = double>
struct CartPole {
  using Scalar = Scalar_;
  static constexpr int kDof = 2;
  static constexpr int kConstraints = 1;
  static constexpr int kHolonomicRows = 1;
  static constexpr int kActuators = 1;
  using Vector = Eigen::Matrix<Scalar, 2, 1>;
  using Terms = ModelTerms<2, 1, Scalar>;

  Scalar cart_mass = Scalar(1);    ///< M [kg]
  Scalar mass = Scalar(0.2);       ///< m [kg]
  Scalar length = Scalar(0.5);     ///< l [m]
  Scalar gravity = Scalar(9.81);   ///< [m/s^2]
  Scalar amplitude = Scalar(0.4);  ///< a [rad]
  Scalar rate = Scalar(3);         ///< w [rad/s]

  /// Visits every parameter by name: f(name, reference).
  template <typename F>
  void parameters(F&& f) {
    f("cart_mass", cart_mass), f("mass", mass), f("length", length), f("gravity", gravity);
    f("amplitude", amplitude), f("rate", rate);
  }

  void evaluate(const Vector& q, const Vector& qd, Scalar, Terms& terms) const noexcept {
    using std::cos;
    using std::sin;
    const Scalar c = cos(q(1)), s = sin(q(1));
    terms.mass_matrix << cart_mass + mass, mass * length * c, mass * length * c, mass * length * length;
    terms.nonlinear_force << -mass * length * s * qd(1) * qd(1), Scalar(0);
    terms.applied_force << Scalar(0), -mass * gravity * length * s;
  }
  void actuation(const Vector&, Scalar, Eigen::Matrix<Scalar, 2, 1>& b) const noexcept { b << Scalar(1), Scalar(0); }
  template <typename T>
  Eigen::Matrix<T, 1, 1> phi(const Eigen::Matrix<T, 2, 1>& q, const T& t) const {
    using std::sin;
    return Eigen::Matrix<T, 1, 1>(q(1) - amplitude * sin(rate * t));
  }
};

}  // namespace gausstrack::systems
