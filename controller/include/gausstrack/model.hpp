// What a user's mechanical system provides to the tracking controller, and how the library turns
// constraints written in their natural form into the acceleration-level rows of eq. (18).
//
// A system A(q,t) q'' + f(q,q',t) = Q(q,q',t) + Q' (eq. 7) with P constraint rows, stacked as
//   rows [0, H)          holonomic or rheonomic, phi(q, t) = 0                       (eq. 3 integrable)
//   rows [H, H + V)      nonholonomic Pfaffian, psi(q, q', t) = 0, affine in q'      (eq. 3)
//   rows [H + V, P)      hand-written at acceleration level, D q'' = g               (eq. 18)
// H = M::kHolonomicRows and V = M::kNonholonomicRows (each 0 when the model does not declare it).
//
// A model provides, with Scalar, kDof = N and kConstraints = P:
//   void evaluate(q, qd, t, ModelTerms& terms) const noexcept
//       fills mass_matrix A (N x N, symmetric positive definite), nonlinear_force f and
//       applied_force Q (N), and, for the hand-written rows only, their entries of
//       constraint_matrix D, constraint_rhs g and, optionally, constraint_error_rate e' (and
//       with it constraint_error e, for a row with a position-level error): what check_model
//       checks D and g against, and what stabilization acts on. One call per control step: kinematics shared by A, f, Q and
//       the hand-written rows (an arm's sines and cosines) are computed once.
//   template <typename T> Eigen::Matrix<T, H, 1> phi(const Eigen::Matrix<T, N, 1>& q, const T& t) const
//   template <typename T> Eigen::Matrix<T, V, 1> psi(const Eigen::Matrix<T, N, 1>& q,
//                                                     const Eigen::Matrix<T, N, 1>& qd, const T& t) const
// The library derives the natural-form rows by automatic differentiation (jet.hpp), one pass each:
//   holonomic:    D = phi_q,  g = -(q'^T phi_qq q' + 2 phi_qt q' + phi_tt),  e = phi,
//                 e' = phi_q q' + phi_t
//   nonholonomic: D = psi_q',  g = -(psi_q q' + psi_t),  e' = psi,  e = 0 (there is no position
//                 error for a constraint that is not integrable)
//
// Where forces go, for every shipped system: f holds the terms of the equations of motion besides
// A q'' that the paper writes on the left of eq. (7): Coriolis and centrifugal terms, springs and
// dampers (eq. 35). Q holds the impressed forces from outside the system, gravity included
// (eq. 33: m y'' = m g). The split changes neither Q' nor q'' (only f - Q enters eq. 32), but it
// decides which of eq. (32)'s two terms a force appears in.
//
// Rows held by the environment (a wheel rolling without slip, a closed kinematic loop) rather than
// by control are declared physical, by a mask over the rows above (bit i: row i, rows 0..63):
//   static constexpr std::uint64_t kPhysicalRowMask = ...;
// They are written and derived like any other row. The plant holds them; the law treats the
// physically constrained system as the one it controls and never pushes along them
// (actuation.hpp). The other rows are the task. At least one row must be a task row.
//
// Entries a model's evaluate never writes keep their previous value; ModelTerms starts at zero, so
// a model with a diagonal A may write the diagonal only. Such a model should also declare
//   static constexpr MassMatrix kMassMatrix = MassMatrix::kDiagonal;
// so that the solver reads and factors the diagonal alone (mass_matrix.hpp).
#pragma once

#include <Eigen/Core>
#include <bit>
#include <concepts>
#include <cstdint>

#include "gausstrack/jet.hpp"
#include "gausstrack/mass_matrix.hpp"

namespace gausstrack {

/// What one evaluation of a model at (q, q', t) computes (the Data of Pinocchio's Model/Data split).
template <int N, int P, typename Scalar>
struct ModelTerms {
  Eigen::Matrix<Scalar, N, N> mass_matrix = Eigen::Matrix<Scalar, N, N>::Zero();  ///< A
  Eigen::Matrix<Scalar, N, 1> nonlinear_force = Eigen::Matrix<Scalar, N, 1>::Zero();  ///< f
  Eigen::Matrix<Scalar, N, 1> applied_force = Eigen::Matrix<Scalar, N, 1>::Zero();    ///< Q
  Eigen::Matrix<Scalar, P, N> constraint_matrix = Eigen::Matrix<Scalar, P, N>::Zero();  ///< D
  Eigen::Matrix<Scalar, P, 1> constraint_rhs = Eigen::Matrix<Scalar, P, 1>::Zero();     ///< g
  Eigen::Matrix<Scalar, P, 1> constraint_error = Eigen::Matrix<Scalar, P, 1>::Zero();   ///< e
  Eigen::Matrix<Scalar, P, 1> constraint_error_rate = Eigen::Matrix<Scalar, P, 1>::Zero();  ///< e'
};

namespace detail {
template <typename M>
constexpr int holonomic_rows() {
  if constexpr (requires { M::kHolonomicRows; }) return M::kHolonomicRows;
  else return 0;
}
template <typename M>
constexpr MassMatrix mass_matrix_kind() {
  if constexpr (requires { M::kMassMatrix; }) return M::kMassMatrix;
  else return MassMatrix::kDense;
}
template <typename M>
constexpr int nonholonomic_rows() {
  if constexpr (requires { M::kNonholonomicRows; }) return M::kNonholonomicRows;
  else return 0;
}
template <typename M>
constexpr std::uint64_t physical_row_mask() {
  if constexpr (requires { M::kPhysicalRowMask; })
    return static_cast<std::uint64_t>(M::kPhysicalRowMask);
  else
    return 0;
}
}  // namespace detail

/// Row counts of a model's three kinds of constraint rows.
template <typename M>
struct RowLayout {
  static constexpr int kHolonomic = detail::holonomic_rows<M>();
  static constexpr int kNonholonomic = detail::nonholonomic_rows<M>();
  static constexpr int kAcceleration = M::kConstraints - kHolonomic - kNonholonomic;
  static constexpr int kFirstNonholonomic = kHolonomic;
  static constexpr int kFirstAcceleration = kHolonomic + kNonholonomic;
  /// Rows held by the environment (M::kPhysicalRowMask), and the task rows, the others.
  static constexpr std::uint64_t kPhysicalMask = detail::physical_row_mask<M>();
  static constexpr int kPhysical = std::popcount(kPhysicalMask);
  static constexpr int kTask = M::kConstraints - kPhysical;
  static constexpr bool physical(int row) noexcept {
    return row < 64 && ((kPhysicalMask >> row) & 1U) != 0;
  }
};

/// How model M's mass matrix is stored (its kMassMatrix, or kDense when it declares none).
template <typename M>
inline constexpr MassMatrix kMassMatrixOf = detail::mass_matrix_kind<M>();

template <typename M>
using TermsOf = ModelTerms<M::kDof, M::kConstraints, typename M::Scalar>;

template <typename M>
concept Model = requires(const M& m, const Eigen::Matrix<typename M::Scalar, M::kDof, 1>& q,
                         typename M::Scalar t, TermsOf<M>& terms) {
  requires std::floating_point<typename M::Scalar>;
  requires M::kDof >= 1 && M::kConstraints >= 1;
  requires RowLayout<M>::kHolonomic >= 0 && RowLayout<M>::kNonholonomic >= 0 &&
      RowLayout<M>::kAcceleration >= 0;
  // Physical rows name existing rows, and leave at least one task row and one free direction.
  requires M::kConstraints >= 64 || (RowLayout<M>::kPhysicalMask >> M::kConstraints) == 0;
  requires RowLayout<M>::kTask >= 1 && RowLayout<M>::kPhysical < M::kDof;
  { m.evaluate(q, q, t, terms) }
  noexcept;
  requires RowLayout<M>::kHolonomic == 0 || requires {
    { m.phi(q, t) } -> std::convertible_to<Eigen::Matrix<typename M::Scalar, RowLayout<M>::kHolonomic, 1>>;
  };
  requires RowLayout<M>::kNonholonomic == 0 || requires {
    { m.psi(q, q, t) } -> std::convertible_to<Eigen::Matrix<typename M::Scalar, RowLayout<M>::kNonholonomic, 1>>;
  };
};

namespace detail {
// Rows [first, first + R) of D: the jets' gradients, zero outside their supports (D is stored by
// columns, so the rows are cleared a column at a time).
template <typename S, int N, int P, int R>
void set_rows(const Eigen::Matrix<Jet<S, N>, R, 1>& x, int first, ModelTerms<N, P, S>& terms) noexcept {
  if constexpr (!Jet<S, N>::kSparse) {
    for (int i = 0; i < N; ++i)
      for (int k = 0; k < R; ++k) terms.constraint_matrix(first + k, i) = x(k).d[i];
  } else {
    for (int i = 0; i < N; ++i)
      for (int k = 0; k < R; ++k) terms.constraint_matrix(first + k, i) = S(0);
    for (int k = 0; k < R; ++k)
      for (int i = x(k).lo; i < x(k).hi; ++i) terms.constraint_matrix(first + k, i) = x(k).d[i];
  }
}
}  // namespace detail

/// Holonomic rows of `terms` starting at row `first`, derived from the model's phi by one pass on
/// jets seeded with d q_i = e_i and the direction (q', 1) in (q, t).
template <int First, Model M>
void derive_holonomic_rows(const M& m, const Eigen::Matrix<typename M::Scalar, M::kDof, 1>& q,
                           const Eigen::Matrix<typename M::Scalar, M::kDof, 1>& qd, typename M::Scalar t,
                           TermsOf<M>& terms) noexcept {
  using S = typename M::Scalar;
  constexpr int N = M::kDof;
  constexpr int H = RowLayout<M>::kHolonomic;
  using J = Jet<S, N>;
  Eigen::Matrix<J, N, 1> qj;
  for (int i = 0; i < N; ++i) qj(i).seed(q(i), i, qd(i));
  const J tj(t, S(1), S(0));
  const Eigen::Matrix<J, H, 1> r = m.phi(qj, tj);
  detail::set_rows(r, First, terms);
  for (int k = 0; k < H; ++k) {
    terms.constraint_rhs(First + k) = -r(k).t2;
    terms.constraint_error(First + k) = r(k).v;
    terms.constraint_error_rate(First + k) = r(k).t1;
  }
}

/// Nonholonomic rows from psi, affine in q': jets seeded with d q'_i = e_i and the direction
/// (q', 0, 1) in (q, q', t), so that d = psi_q' and t1 = psi_q q' + psi_t.
template <int First, Model M>
void derive_nonholonomic_rows(const M& m, const Eigen::Matrix<typename M::Scalar, M::kDof, 1>& q,
                              const Eigen::Matrix<typename M::Scalar, M::kDof, 1>& qd, typename M::Scalar t,
                              TermsOf<M>& terms) noexcept {
  using S = typename M::Scalar;
  constexpr int N = M::kDof;
  constexpr int V = RowLayout<M>::kNonholonomic;
  using J = Jet<S, N>;
  Eigen::Matrix<J, N, 1> qj, qdj;
  for (int i = 0; i < N; ++i) {
    qj(i) = J(q(i), qd(i), S(0));
    qdj(i).seed(qd(i), i, S(0));
  }
  const J tj(t, S(1), S(0));
  const Eigen::Matrix<J, V, 1> r = m.psi(qj, qdj, tj);
  detail::set_rows(r, First, terms);
  for (int k = 0; k < V; ++k) {
    terms.constraint_rhs(First + k) = -r(k).t1;
    terms.constraint_error(First + k) = S(0);
    terms.constraint_error_rate(First + k) = r(k).v;
  }
}

/// Every term of model `m` at (q, q', t): the model's own evaluate (A, f, Q, hand-written rows),
/// then the rows derived from phi and psi. Allocation-free and exception-free.
template <Model M>
void evaluate_model(const M& m, const Eigen::Matrix<typename M::Scalar, M::kDof, 1>& q,
                    const Eigen::Matrix<typename M::Scalar, M::kDof, 1>& qd, typename M::Scalar t,
                    TermsOf<M>& terms) noexcept {
  m.evaluate(q, qd, t, terms);
  if constexpr (RowLayout<M>::kHolonomic > 0) derive_holonomic_rows<0>(m, q, qd, t, terms);
  if constexpr (RowLayout<M>::kNonholonomic > 0)
    derive_nonholonomic_rows<RowLayout<M>::kFirstNonholonomic>(m, q, qd, t, terms);
}

}  // namespace gausstrack
