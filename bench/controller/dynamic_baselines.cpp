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

Eigen::VectorXd dynamic_kkt_control(const Eigen::MatrixXd& A, const Eigen::VectorXd& f,
                                    const Eigen::VectorXd& Q, const Eigen::MatrixXd& Dc,
                                    const Eigen::VectorXd& gc, const Eigen::MatrixXd& Dp,
                                    const Eigen::VectorXd& gp, const Eigen::MatrixXd& B) {
  const Eigen::Index N = A.rows(), K = B.cols(), Pc = Dc.rows(), Pp = Dp.rows();
  const Eigen::MatrixXd W = B.transpose() * A.llt().solve(B);
  // Unknowns (q'', u, lambda_p, nu, mu_c, mu_p); nu, mu_c, mu_p the multipliers of the dynamics,
  // the task rows and the physical rows.
  const Eigen::Index n = 2 * N + K + Pc + 2 * Pp;
  const Eigen::Index u0 = N, l0 = N + K, nu0 = N + K + Pp, mc0 = 2 * N + K + Pp,
                     mp0 = 2 * N + K + Pp + Pc;
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(n, n);
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(n);
  // d/dq'': A nu + D_c^T mu_c + D_p^T mu_p = 0
  M.block(0, nu0, N, N) = A;
  M.block(0, mc0, N, Pc) = Dc.transpose();
  M.block(0, mp0, N, Pp) = Dp.transpose();
  // d/du: W u - B^T nu = 0
  M.block(u0, u0, K, K) = W;
  M.block(u0, nu0, K, N) = -B.transpose();
  // d/dlambda_p: -D_p nu = 0
  M.block(l0, nu0, Pp, N) = -Dp;
  // A q'' - B u - D_p^T lambda_p = Q - f; D_c q'' = g_c; D_p q'' = g_p
  M.block(nu0, 0, N, N) = A;
  M.block(nu0, u0, N, K) = -B;
  M.block(nu0, l0, N, Pp) = -Dp.transpose();
  rhs.segment(nu0, N) = Q - f;
  M.block(mc0, 0, Pc, N) = Dc;
  rhs.segment(mc0, Pc) = gc;
  M.block(mp0, 0, Pp, N) = Dp;
  rhs.segment(mp0, Pp) = gp;
  return M.partialPivLu().solve(rhs).segment(u0, K);
}

double kkt_lu(const Eigen::MatrixXd& kkt) {
  const Eigen::PartialPivLU<Eigen::MatrixXd> lu(kkt);
  return lu.matrixLU()(0, 0);
}

}  // namespace gausstrack::bench
