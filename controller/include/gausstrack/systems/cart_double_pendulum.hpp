// A double pendulum hanging from a cart: the cart tracks a sinusoid along x while the pendulum's
// tip swings about it by a prescribed horizontal offset. P = 2 constraint rows on N = 3
// coordinates: the elbow's motion that keeps the tip's offset is Gauss's to choose (eq. 32).
#pragma once

#include <Eigen/Core>
#include <cmath>

#include "gausstrack/model.hpp"

namespace gausstrack::systems {

/// q = (x, a1, a2): the cart's position [m], rod 1's angle from the downward vertical and rod 2's
/// angle relative to rod 1 [rad] (theta_1 = a1, theta_2 = a1 + a2, positive toward +x), in the
/// vertical x-y plane with gravity along -y. Rod i has mass m_i, length l_i, its centre of mass at
/// distance r_i from its hinge and moment of inertia I_i about that centre; the cart has mass m_c.
///   A(q) = m_c e_x e_x^T + sum_i m_i Jv_i^T Jv_i + I_i Jw_i^T Jw_i
///   f(q, q') = sum_i m_i Jv_i^T (Jv_i' q')      centrifugal forces [N, N m]
///   Q(q) = sum_i m_i Jv_i^T (0, -gravity)       gravity, an impressed force
/// Constraints: phi_1 = x - a sin(w t), phi_2 = (l_1 sin theta_1 + l_2 sin theta_2) - b sin(w t).
template <typename Scalar_ = double>
struct CartDoublePendulum {
  using Scalar = Scalar_;
  static constexpr int kDof = 3;
  static constexpr int kConstraints = 2;
  static constexpr int kHolonomicRows = 2;
  using Vector = Eigen::Matrix<Scalar, 3, 1>;
  using Terms = ModelTerms<3, 2, Scalar>;

  Scalar cart_mass = Scalar(1);                          ///< m_c [kg]
  Scalar mass_1 = Scalar(0.5), mass_2 = Scalar(0.5);     ///< [kg]
  Scalar length_1 = Scalar(0.6), length_2 = Scalar(0.6); ///< [m]
  Scalar com_1 = Scalar(0.3), com_2 = Scalar(0.3);       ///< r_i [m]
  Scalar inertia_1 = Scalar(0.015), inertia_2 = Scalar(0.015);  ///< about the centre [kg m^2]
  Scalar gravity = Scalar(9.81);                         ///< [m/s^2]
  Scalar cart_amplitude = Scalar(0.2);                   ///< a [m]
  Scalar swing_amplitude = Scalar(0.1);                  ///< b [m]
  Scalar rate = Scalar(2);                               ///< w [rad/s]

  template <typename F>
  void parameters(F&& f) {
    f("cart_mass", cart_mass), f("mass_1", mass_1), f("mass_2", mass_2), f("length_1", length_1);
    f("length_2", length_2), f("com_1", com_1), f("com_2", com_2), f("inertia_1", inertia_1);
    f("inertia_2", inertia_2), f("gravity", gravity), f("cart_amplitude", cart_amplitude);
    f("swing_amplitude", swing_amplitude), f("rate", rate);
  }

  void evaluate(const Vector& q, const Vector& qd, Scalar, Terms& terms) const noexcept {
    const Scalar s1 = std::sin(q(1)), c1 = std::cos(q(1));
    const Scalar s2 = std::sin(q(1) + q(2)), c2 = std::cos(q(1) + q(2));
    const Scalar w1 = qd(1), w2 = qd(1) + qd(2);
    // Centres of mass: p1 = (x + r1 s1, -r1 c1), p2 = (x + l1 s1 + r2 s2, -l1 c1 - r2 c2).
    Eigen::Matrix<Scalar, 2, 3> j1, j2;
    j1 << Scalar(1), com_1 * c1, Scalar(0), Scalar(0), com_1 * s1, Scalar(0);
    j2 << Scalar(1), length_1 * c1 + com_2 * c2, com_2 * c2, Scalar(0), length_1 * s1 + com_2 * s2, com_2 * s2;
    // Their accelerations at q'' = 0.
    const Eigen::Matrix<Scalar, 2, 1> b1(-com_1 * s1 * w1 * w1, com_1 * c1 * w1 * w1);
    const Eigen::Matrix<Scalar, 2, 1> b2(-length_1 * s1 * w1 * w1 - com_2 * s2 * w2 * w2,
                                         length_1 * c1 * w1 * w1 + com_2 * c2 * w2 * w2);
    terms.mass_matrix.noalias() = mass_1 * j1.transpose() * j1 + mass_2 * j2.transpose() * j2;
    terms.mass_matrix(0, 0) += cart_mass;
    terms.mass_matrix.template bottomRightCorner<2, 2>().array() += inertia_2;
    terms.mass_matrix(1, 1) += inertia_1;
    terms.nonlinear_force.noalias() = mass_1 * j1.transpose() * b1 + mass_2 * j2.transpose() * b2;
    terms.applied_force = -gravity * (mass_1 * j1.row(1).transpose() + mass_2 * j2.row(1).transpose());
  }

  template <typename T>
  Eigen::Matrix<T, 2, 1> phi(const Eigen::Matrix<T, 3, 1>& q, const T& t) const {
    using std::sin;
    const T s = sin(rate * t);
    return {q(0) - cart_amplitude * s, length_1 * sin(q(1)) + length_2 * sin(q(1) + q(2)) - swing_amplitude * s};
  }
};

}  // namespace gausstrack::systems
