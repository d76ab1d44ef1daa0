// The dynamic-size baselines of controller_bench, compiled once (dynamic_baselines.cpp) rather than
// in every translation unit that registers a model: what a typical user writes with MatrixXd.
#pragma once

#include <Eigen/Core>

namespace gausstrack::bench {

/// Q' = A^(1/2) (D A^(-1/2))^+ (g - D a), a = A^-1 (Q - f): the symmetric square root from
/// SelfAdjointEigenSolver, the pseudo-inverse from completeOrthogonalDecomposition().
Eigen::VectorXd dynamic_user_force(const Eigen::MatrixXd& A, const Eigen::VectorXd& f,
                                   const Eigen::VectorXd& Q, const Eigen::MatrixXd& D,
                                   const Eigen::VectorXd& g);

/// The KKT system [A D^T; D 0] [q''; -lambda] = [Q - f; g] by a dynamic-size LU; Q' = A q'' + f -
/// Q.
Eigen::VectorXd dynamic_kkt_force(const Eigen::MatrixXd& A, const Eigen::VectorXd& f,
                                  const Eigen::VectorXd& Q, const Eigen::MatrixXd& D,
                                  const Eigen::VectorXd& g);

/// The actuated law's problem as one Lagrange-multiplier system, what a user would write with
/// dynamic-size Eigen: least u^T W u, W = B^T A^-1 B (Gauss's weight, A^-1 B by Cholesky), over
/// (q'', u, lambda_p) subject to A q'' + f = Q + B u + D_p^T lambda_p, D_c q'' = g_c and
/// D_p q'' = g_p, its stationarity conditions and constraints solved by one dynamic-size LU of
/// size 2N + K + P_c + 2 P_p. Returns u.
Eigen::VectorXd dynamic_kkt_control(const Eigen::MatrixXd& A, const Eigen::VectorXd& f,
                                    const Eigen::VectorXd& Q, const Eigen::MatrixXd& Dc,
                                    const Eigen::VectorXd& gc, const Eigen::MatrixXd& Dp,
                                    const Eigen::VectorXd& gp, const Eigen::MatrixXd& B);

/// The KKT matrix's LU alone (the phase benchmarks): returns a pointer into the factors so that
/// the work cannot be optimized away.
double kkt_lu(const Eigen::MatrixXd& kkt);

}  // namespace gausstrack::bench
