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

/// The KKT matrix's LU alone (the phase benchmarks): returns a pointer into the factors so that
/// the work cannot be optimized away.
double kkt_lu(const Eigen::MatrixXd& kkt);

}  // namespace gausstrack::bench
