// What a user's mechanical system provides to the tracking controller.
#pragma once

#include <Eigen/Core>
#include <concepts>

namespace gausstrack {

/// A system A(q,t) q'' + f(q,q',t) = Q(q,q',t) + Q' with constraints D(q,t) q'' = g(q,q',t)
/// (eq. 7 and eq. 18). N = M::kDof coordinates, P = M::kConstraints constraint rows.
///   mass_matrix(q, t)          A, N x N symmetric positive definite
///   nonlinear_force(q, qd, t)  f, the left-side terms of eq. (7) besides A q'' (springs,
///                              dampers, Coriolis), N
///   applied_force(q, qd, t)    Q, the impressed forces, N
///   constraint_matrix(q, t)    D, P x N
///   constraint_rhs(q, qd, t)   g, P: the constraints differentiated to acceleration level
/// Results are returned by value as fixed-size Eigen objects (no allocation).
template <typename M>
concept Model = requires(const M& m, const Eigen::Matrix<typename M::Scalar, M::kDof, 1>& q,
                         typename M::Scalar t) {
  requires std::floating_point<typename M::Scalar>;
  requires M::kDof >= 1 && M::kConstraints >= 1;
  { m.mass_matrix(q, t) } -> std::convertible_to<Eigen::Matrix<typename M::Scalar, M::kDof, M::kDof>>;
  { m.nonlinear_force(q, q, t) } -> std::convertible_to<Eigen::Matrix<typename M::Scalar, M::kDof, 1>>;
  { m.applied_force(q, q, t) } -> std::convertible_to<Eigen::Matrix<typename M::Scalar, M::kDof, 1>>;
  { m.constraint_matrix(q, t) }
      -> std::convertible_to<Eigen::Matrix<typename M::Scalar, M::kConstraints, M::kDof>>;
  { m.constraint_rhs(q, q, t) }
      -> std::convertible_to<Eigen::Matrix<typename M::Scalar, M::kConstraints, 1>>;
};

/// A model whose constraints are holonomic, phi(q, t) = 0: constraint_error(q, t) returns phi.
template <typename M>
concept HasPositionError = Model<M> && requires(
    const M& m, const Eigen::Matrix<typename M::Scalar, M::kDof, 1>& q, typename M::Scalar t) {
  { m.constraint_error(q, t) }
      -> std::convertible_to<Eigen::Matrix<typename M::Scalar, M::kConstraints, 1>>;
};

/// A model that can evaluate its constraints at velocity level: constraint_error_rate(q, qd, t)
/// returns phi'(q, q', t) for holonomic constraints, or the Pfaffian form's value for
/// nonholonomic ones (eq. 3 divided by dt).
template <typename M>
concept HasVelocityError = Model<M> && requires(
    const M& m, const Eigen::Matrix<typename M::Scalar, M::kDof, 1>& q, typename M::Scalar t) {
  { m.constraint_error_rate(q, q, t) }
      -> std::convertible_to<Eigen::Matrix<typename M::Scalar, M::kConstraints, 1>>;
};

}  // namespace gausstrack
