// The smallest complete model of one's own system: a puck of mass m sliding on a plane with
// viscous drag, kept by control at distance R from an anchor that moves along x at speed v.
// Write A, f and Q in evaluate(); write the constraint as phi(q, t) = 0; the library derives its
// rows D q'' = g by differentiating phi twice. parameters() names what a configuration may set.
#pragma once

#include <Eigen/Core>

#include "gausstrack/model.hpp"

struct TetheredPuck {
  using Scalar = double;
  static constexpr int kDof = 2;             // q = (x, y) [m]
  static constexpr int kConstraints = 1;     // one constraint row
  static constexpr int kHolonomicRows = 1;   // ... written as phi(q, t)
  using Vector = Eigen::Matrix<double, 2, 1>;

  double mass = 0.5;     // [kg]
  double drag = 0.2;     // [N s/m]
  double radius = 1.0;   // R [m]
  double speed = 0.3;    // v [m/s]

  // A q'' + f = Q + u: A = m I, f = drag * q', no impressed force.
  void evaluate(const Vector&, const Vector& qd, double, gausstrack::ModelTerms<2, 1, double>& terms) const noexcept {
    terms.mass_matrix = mass * Eigen::Matrix2d::Identity();
    terms.nonlinear_force = drag * qd;
  }

  // |q - anchor(t)|^2 - R^2 = 0, anchor(t) = (v t, 0). Templated: the library evaluates it on jets.
  template <typename T>
  Eigen::Matrix<T, 1, 1> phi(const Eigen::Matrix<T, 2, 1>& q, const T& t) const {
    const T dx = q(0) - speed * t, dy = q(1);
    return Eigen::Matrix<T, 1, 1>(dx * dx + dy * dy - radius * radius);
  }

  template <typename F>
  void parameters(F&& f) {
    f("mass", mass), f("drag", drag), f("radius", radius), f("speed", speed);
  }
};
