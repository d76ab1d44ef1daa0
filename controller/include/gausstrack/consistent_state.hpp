// Initial conditions that satisfy a model's constraints (the paper's examples start on them).
#pragma once

#include <Eigen/Core>
#include <cmath>

#include "gausstrack/model.hpp"
#include "gausstrack/small_dense.hpp"

namespace gausstrack {

/// Moves (q, q') onto the constraints at time t, changing them as little as possible:
/// Gauss-Newton steps q <- q - D^T (D D^T)^-1 e until |e| <= tolerance (rows with a position
/// error; the others ask D dq = 0), then one step q' <- q' - D^T (D D^T)^-1 e', exact because e'
/// is affine in q'. Returns false, leaving the best iterate, when D D^T is singular (a rank-deficient
/// configuration) or the iteration does not converge. Allocation-free; not meant for a control loop.
template <Model M>
bool make_consistent(const M& m, Eigen::Matrix<typename M::Scalar, M::kDof, 1>& q,
                     Eigen::Matrix<typename M::Scalar, M::kDof, 1>& qd, typename M::Scalar t,
                     typename M::Scalar tolerance = typename M::Scalar(1e-12), int max_iterations = 50) noexcept {
  using S = typename M::Scalar;
  constexpr int P = M::kConstraints;
  TermsOf<M> terms;
  auto solve = [&](const Eigen::Matrix<S, P, 1>& r, Eigen::Matrix<S, M::kDof, 1>& x) {
    Eigen::Matrix<S, P, P> gram = terms.constraint_matrix * terms.constraint_matrix.transpose();
    if (!small_dense::cholesky_in_place(gram)) return false;  // D D^T = L L^T
    Eigen::Matrix<S, P, 1> w = r;
    small_dense::solve_lower_in_place(gram, w);
    small_dense::solve_lower_transposed_in_place(gram, w);
    const Eigen::Matrix<S, M::kDof, 1> step = terms.constraint_matrix.transpose() * w;
    if (!step.allFinite()) return false;
    x -= step;
    return true;
  };
  bool converged = false;
  for (int it = 0; it < max_iterations; ++it) {
    evaluate_model(m, q, qd, t, terms);
    if (!(terms.constraint_error.template lpNorm<Eigen::Infinity>() > tolerance)) {
      converged = true;
      break;
    }
    if (!solve(terms.constraint_error, q)) return false;
  }
  if (!converged) return false;
  if (!solve(terms.constraint_error_rate, qd)) return false;
  evaluate_model(m, q, qd, t, terms);
  return terms.constraint_error_rate.template lpNorm<Eigen::Infinity>() <= tolerance * (S(1) + qd.norm()) * S(100);
}

}  // namespace gausstrack
