// The paper's formulas written out literally, with Moore-Penrose inverses from an SVD and the
// symmetric square root of A from an eigendecomposition. Slow and plain on purpose: this is the
// yardstick tests and benchmarks compare ConstraintSolver against, not a real-time path.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <Eigen/SVD>

namespace gausstrack::reference {

/// Moore-Penrose inverse of m: singular values <= relative_tolerance * sigma_max count as zero.
/// Fixed or dynamic sizes (a dynamic size gives a dynamic-size answer).
template <typename Derived>
Eigen::Matrix<typename Derived::Scalar, Derived::ColsAtCompileTime, Derived::RowsAtCompileTime>
pseudo_inverse(const Eigen::MatrixBase<Derived>& m, typename Derived::Scalar relative_tolerance) {
  using Scalar = typename Derived::Scalar;
  constexpr int R = Derived::RowsAtCompileTime, C = Derived::ColsAtCompileTime;
  constexpr int S = (R == Eigen::Dynamic || C == Eigen::Dynamic) ? Eigen::Dynamic : (R > C ? R : C);
  using Square = Eigen::Matrix<Scalar, S, S>;
  const Eigen::Index r = m.rows(), c = m.cols(), s = r > c ? r : c;
  // m padded with zero rows or columns to a square s x s matrix has m's singular values (and
  // zeros); its pseudo-inverse holds m^+ in the matching block.
  Square square = Square::Zero(s, s);
  square.topLeftCorner(r, c) = m;
  Eigen::JacobiSVD<Square, Eigen::NoQRPreconditioner> svd(square, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const auto& sv = svd.singularValues();
  Square inv = Square::Zero(s, s);
  if (sv(0) > Scalar(0)) {
    for (Eigen::Index i = 0; i < s; ++i) {
      if (sv(i) > relative_tolerance * sv(0)) inv += svd.matrixV().col(i) * svd.matrixU().col(i).transpose() / sv(i);
    }
  }
  return inv.topLeftCorner(c, r);
}

template <int N, typename Scalar>
struct LiteralSolution {
  Eigen::Matrix<Scalar, N, 1> acceleration;          // eq. (30a)
  Eigen::Matrix<Scalar, N, 1> constraint_force;      // eq. (32)
  Eigen::Matrix<Scalar, N, 1> force_from_impressed;  // (I - A X A^-1)(f - Q)
  Eigen::Matrix<Scalar, N, 1> force_from_rhs;        // A (I - X) D^- g
};

/// Eqs. (22), (23), (30a), (32) with D^- = D^+ and H^-_ls = H^+. N and P may be Eigen::Dynamic
/// (the tests use dynamic sizes: one instantiation serves every size).
template <int N, int P, typename Scalar>
LiteralSolution<N, Scalar> literal_formulas(const Eigen::Matrix<Scalar, N, N>& A,
                                            const Eigen::Matrix<Scalar, N, 1>& f,
                                            const Eigen::Matrix<Scalar, N, 1>& Q,
                                            const Eigen::Matrix<Scalar, P, N>& D,
                                            const Eigen::Matrix<Scalar, P, 1>& g,
                                            Scalar relative_tolerance = Scalar(1e-10)) {
  using MatrixNN = Eigen::Matrix<Scalar, N, N>;
  const MatrixNN I = MatrixNN::Identity(A.rows(), A.cols());
  Eigen::SelfAdjointEigenSolver<MatrixNN> eig(A);
  const MatrixNN a_half = eig.operatorSqrt();              // A^(1/2)
  const MatrixNN a_minus_half = eig.operatorInverseSqrt(); // A^(-1/2)
  const Eigen::Matrix<Scalar, N, P> d_minus = pseudo_inverse(D, relative_tolerance);
  const MatrixNN h_hat = I - d_minus * D;                   // I - D^- D
  const MatrixNN H = a_half * h_hat;                        // eq. (22)
  const Eigen::Matrix<Scalar, N, 1> z = -(a_half * d_minus * g + a_minus_half * (f - Q));  // (23)
  const MatrixNN h_ls = pseudo_inverse(H, relative_tolerance);
  const MatrixNN X = h_hat * h_ls * a_half;
  const MatrixNN a_inv = A.llt().solve(I);

  LiteralSolution<N, Scalar> out;
  out.acceleration = d_minus * g + h_hat * h_ls * z;                    // eq. (30a)
  out.force_from_impressed = (I - A * X * a_inv) * (f - Q);             // eq. (32), first term
  out.force_from_rhs = A * (I - X) * d_minus * g;                       // eq. (32), second term
  out.constraint_force = out.force_from_impressed + out.force_from_rhs;
  return out;
}

}  // namespace gausstrack::reference
