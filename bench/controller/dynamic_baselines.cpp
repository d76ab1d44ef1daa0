#include "dynamic_baselines.hpp"

#include <Eigen/Dense>

namespace gausstrack::bench {

Eigen::VectorXd dynamic_user_force(const Eigen::MatrixXd& A, const Eigen::VectorXd& f,
                                   const Eigen::VectorXd& Q, const Eigen::MatrixXd& D,
                                   const Eigen::VectorXd& g) {
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(A);
  const Eigen::MatrixXd a_half = eig.operatorSqrt();
  const Eigen::MatrixXd a_minus_half = eig.operatorInverseSqrt();
  const Eigen::VectorXd a = A.ldlt().solve(Q - f);
  const Eigen::MatrixXd B = D * a_minus_half;
  const Eigen::MatrixXd B_plus = B.completeOrthogonalDecomposition().pseudoInverse();
  return a_half * (B_plus * (g - D * a));
}

Eigen::VectorXd dynamic_kkt_force(const Eigen::MatrixXd& A, const Eigen::VectorXd& f,
                                  const Eigen::VectorXd& Q, const Eigen::MatrixXd& D,
                                  const Eigen::VectorXd& g) {
  const Eigen::Index N = A.rows(), P = D.rows();
  const Eigen::VectorXd impressed = Q - f;
  Eigen::MatrixXd K = Eigen::MatrixXd::Zero(N + P, N + P);
  K.topLeftCorner(N, N) = A;
  K.topRightCorner(N, P) = D.transpose();
  K.bottomLeftCorner(P, N) = D;
  Eigen::VectorXd rhs(N + P);
  rhs << impressed, g;
  const Eigen::VectorXd x = K.partialPivLu().solve(rhs);
  return A * x.head(N) - impressed;
}

double kkt_lu(const Eigen::MatrixXd& kkt) {
  const Eigen::PartialPivLU<Eigen::MatrixXd> lu(kkt);
  return lu.matrixLU()(0, 0);
}

}  // namespace gausstrack::bench
