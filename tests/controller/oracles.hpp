// The tests' independent formulations at run-time size and in double precision, compiled once
// (oracles.cpp) for every test file and every size: the paper's literal formulas, the compact
// form, a Lagrange-multiplier (KKT) solve, Gauss's function, a Moore-Penrose inverse and a random
// orthogonal factor. Eigen's SVD, eigen-solver and LU are instantiated there only.
#pragma once

#include <Eigen/Core>
#include <utility>

namespace gausstrack::test::oracle {

using Eigen::MatrixXd;
using Eigen::VectorXd;

/// Eqs. (30a) and (32), the two terms of (32) apart (reference::literal_formulas).
struct Literal {
  VectorXd acceleration, constraint_force, force_from_impressed, force_from_rhs;
};
Literal literal_formulas(const MatrixXd& A, const VectorXd& f, const VectorXd& Q, const MatrixXd& D,
                         const VectorXd& g, double relative_tolerance = 1e-10);

/// Q' = A^(1/2) (D A^(-1/2))^+ (g - D a), a = A^-1 (Q - f), with the symmetric square root.
VectorXd compact_form_force(const MatrixXd& A, const VectorXd& f, const VectorXd& Q, const MatrixXd& D,
                            const VectorXd& g, double tol = 1e-10);

/// [A -D^T; D 0] [q''; mu] = [Q - f; g] by full-pivoting LU: (q'', Q' = D^T mu).
std::pair<VectorXd, VectorXd> kkt_solution(const MatrixXd& A, const VectorXd& f, const VectorXd& Q,
                                           const MatrixXd& D, const VectorXd& g);

/// The least u^T W u whose force B u, applied to the system that the environment holds on
/// D_p q'' = g_p, meets the task rows D_c q'' = r_c: one equality-constrained quadratic program in
/// (u, q'', mu_p), solved by its Lagrange-multiplier system with full-pivoting LU. Returns (u,
/// q''). Needs D_p of full row rank and a task the actuators can meet.
std::pair<VectorXd, VectorXd> physical_least_cost_control(const MatrixXd& A, const VectorXd& f,
                                                          const VectorXd& Q, const MatrixXd& Dp,
                                                          const VectorXd& gp, const MatrixXd& Dc,
                                                          const VectorXd& rc, const MatrixXd& B,
                                                          const MatrixXd& W);

/// Eq. (14): (A q'' + f - Q)^T A^-1 (A q'' + f - Q).
double gauss_function(const MatrixXd& A, const VectorXd& f, const VectorXd& Q, const VectorXd& qdd);

/// Moore-Penrose inverse (reference::pseudo_inverse).
MatrixXd pseudo_inverse(const MatrixXd& m, double relative_tolerance);

/// The orthogonal factor Q of m = Q R (Householder).
MatrixXd orthogonal_factor(const MatrixXd& m);

}  // namespace gausstrack::test::oracle
