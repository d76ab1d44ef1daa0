#include "oracles.hpp"

#include <Eigen/Dense>

#include "gausstrack/reference/literal_formulas.hpp"

namespace gausstrack::test::oracle {

Literal literal_formulas(const MatrixXd& A, const VectorXd& f, const VectorXd& Q, const MatrixXd& D,
                         const VectorXd& g, double relative_tolerance) {
  const auto r = reference::literal_formulas<Eigen::Dynamic, Eigen::Dynamic, double>(A, f, Q, D, g,
                                                                                    relative_tolerance);
  return {r.acceleration, r.constraint_force, r.force_from_impressed, r.force_from_rhs};
}

VectorXd compact_form_force(const MatrixXd& A, const VectorXd& f, const VectorXd& Q, const MatrixXd& D,
                            const VectorXd& g, double tol) {
  const Eigen::SelfAdjointEigenSolver<MatrixXd> eig(A);
  const VectorXd a = A.llt().solve(Q - f);
  const MatrixXd b = D * eig.operatorInverseSqrt();
  return eig.operatorSqrt() * reference::pseudo_inverse(b, tol) * (g - D * a);
}

std::pair<VectorXd, VectorXd> kkt_solution(const MatrixXd& A, const VectorXd& f, const VectorXd& Q,
                                           const MatrixXd& D, const VectorXd& g) {
  const Eigen::Index n = A.rows(), p = D.rows();
  MatrixXd k = MatrixXd::Zero(n + p, n + p);
  k.topLeftCorner(n, n) = A;
  k.topRightCorner(n, p) = -D.transpose();
  k.bottomLeftCorner(p, n) = D;
  VectorXd rhs(n + p);
  rhs << Q - f, g;
  const VectorXd x = k.fullPivLu().solve(rhs);
  return {x.head(n), D.transpose() * x.tail(p)};
}

std::pair<VectorXd, VectorXd> physical_least_cost_control(const MatrixXd& A, const VectorXd& f,
                                                          const VectorXd& Q, const MatrixXd& Dp,
                                                          const VectorXd& gp, const MatrixXd& Dc,
                                                          const VectorXd& rc, const MatrixXd& B,
                                                          const MatrixXd& W) {
  // x = (u, q'', mu_p); minimize u^T W u subject to
  //   A q'' - D_p^T mu_p - B u = Q - f,   D_p q'' = g_p,   D_c q'' = r_c.
  const Eigen::Index n = A.rows(), k = B.cols(), pp = Dp.rows(), pc = Dc.rows();
  const Eigen::Index nx = k + n + pp, ne = n + pp + pc;
  MatrixXd E = MatrixXd::Zero(ne, nx);
  E.block(0, 0, n, k) = -B;
  E.block(0, k, n, n) = A;
  E.block(0, k + n, n, pp) = -Dp.transpose();
  E.block(n, k, pp, n) = Dp;
  E.block(n + pp, k, pc, n) = Dc;
  VectorXd h(ne);
  h << Q - f, gp, rc;
  MatrixXd kkt = MatrixXd::Zero(nx + ne, nx + ne);
  kkt.topLeftCorner(k, k) = 2 * W;
  kkt.topRightCorner(nx, ne) = E.transpose();
  kkt.bottomLeftCorner(ne, nx) = E;
  VectorXd rhs = VectorXd::Zero(nx + ne);
  rhs.tail(ne) = h;
  const VectorXd x = kkt.fullPivLu().solve(rhs);
  return {x.head(k), x.segment(k, n)};
}

double gauss_function(const MatrixXd& A, const VectorXd& f, const VectorXd& Q,
                      const VectorXd& qdd) {
  const VectorXd r = A * qdd + f - Q;
  return r.dot(A.llt().solve(r));
}

MatrixXd pseudo_inverse(const MatrixXd& m, double relative_tolerance) {
  return reference::pseudo_inverse(m, relative_tolerance);
}

MatrixXd orthogonal_factor(const MatrixXd& m) {
  const Eigen::HouseholderQR<MatrixXd> qr(m);
  return qr.householderQ();
}

}  // namespace gausstrack::test::oracle
