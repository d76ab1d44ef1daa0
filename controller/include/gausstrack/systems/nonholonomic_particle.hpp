// Unit-mass particle with the nonholonomic, catastatic constraint y' = z x' (eq. 36; Rosenberg).
#pragma once

#include <Eigen/Core>

namespace gausstrack::systems {

/// q = (x, y, z), no impressed forces (Q = f = 0), A = m I. D = [-z, 1, 0] and, differentiating
/// y' - z x' = 0, g = z' x'. The motion is eq. (38): q'' = z'x' / (1 + z^2) (-z, 1, 0); the paper
/// prints the factor as "z x" where it means z'x'. The constraint is not integrable, so only its
/// velocity-level error y' - z x' exists.
template <typename Scalar_ = double>
struct NonholonomicParticle {
  using Scalar = Scalar_;
  static constexpr int kDof = 3;
  static constexpr int kConstraints = 1;
  using Vector = Eigen::Matrix<Scalar, 3, 1>;
  using Rhs = Eigen::Matrix<Scalar, 1, 1>;

  Scalar mass = Scalar(1);  ///< [kg]

  Eigen::Matrix<Scalar, 3, 3> mass_matrix(const Vector&, Scalar) const noexcept {
    return mass * Eigen::Matrix<Scalar, 3, 3>::Identity();
  }
  Vector nonlinear_force(const Vector&, const Vector&, Scalar) const noexcept {
    return Vector::Zero();
  }
  Vector applied_force(const Vector&, const Vector&, Scalar) const noexcept {
    return Vector::Zero();
  }
  Eigen::Matrix<Scalar, 1, 3> constraint_matrix(const Vector& q, Scalar) const noexcept {
    return Eigen::Matrix<Scalar, 1, 3>(-q(2), Scalar(1), Scalar(0));
  }
  Rhs constraint_rhs(const Vector&, const Vector& qd, Scalar) const noexcept {
    return Rhs(qd(2) * qd(0));
  }
  Rhs constraint_error_rate(const Vector& q, const Vector& qd, Scalar) const noexcept {
    return Rhs(qd(1) - q(2) * qd(0));
  }
};

}  // namespace gausstrack::systems
