// Unit-mass particle with the nonholonomic, catastatic constraint y' = z x' (eq. 36; Rosenberg).
#pragma once

#include <Eigen/Core>

#include "gausstrack/model.hpp"

namespace gausstrack::systems {

/// q = (x, y, z), no impressed forces (Q = f = 0), A = m I. The constraint in its Pfaffian form
/// (eq. 3), psi = y' - z x' = 0; the library derives D = [-z, 1, 0] and g = z' x'. The motion is
/// eq. (38): q'' = z'x' / (1 + z^2) (-z, 1, 0); the paper prints the factor as "z x" where it
/// means z'x'. The constraint is not integrable, so only its velocity-level error psi exists.
template <typename Scalar_ = double>
struct NonholonomicParticle {
  using Scalar = Scalar_;
  static constexpr int kDof = 3;
  static constexpr int kConstraints = 1;
  static constexpr MassMatrix kMassMatrix = MassMatrix::kDiagonal;
  static constexpr int kNonholonomicRows = 1;
  using Vector = Eigen::Matrix<Scalar, 3, 1>;
  using Terms = ModelTerms<3, 1, Scalar>;

  Scalar mass = Scalar(1);  ///< [kg]

  /// Visits every parameter by name: f(name, reference).
  template <typename F>
  void parameters(F&& f) {
    f("mass", mass);
  }

  void evaluate(const Vector&, const Vector&, Scalar, Terms& terms) const noexcept {
    terms.mass_matrix.diagonal().setConstant(mass);
  }
  template <typename T>
  Eigen::Matrix<T, 1, 1> psi(const Eigen::Matrix<T, 3, 1>& q, const Eigen::Matrix<T, 3, 1>& qd, const T&) const {
    return Eigen::Matrix<T, 1, 1>(qd(1) - q(2) * qd(0));
  }
};

}  // namespace gausstrack::systems
