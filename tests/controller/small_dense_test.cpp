// The dense kernels (small_dense.hpp) against Eigen's own factorization and triangular solves, at
// every size parity their two-at-a-time steps distinguish (N odd and even, 1 to 9 and 16) and for
// one to three right sides, in double and in float.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <limits>
#include <random>

#include "gausstrack/small_dense.hpp"

namespace gausstrack::test {
namespace {

template <typename Scalar, int N, int K>
void expect_kernels_match_eigen(unsigned seed) {
  using MatrixNN = Eigen::Matrix<Scalar, N, N>;
  using MatrixNK = Eigen::Matrix<Scalar, N, K>;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  Eigen::Matrix<double, N, N> b;
  for (int i = 0; i < N * N; ++i) b.data()[i] = u(rng);
  const Eigen::Matrix<double, N, N> a_exact = b * b.transpose() + Eigen::Matrix<double, N, N>::Identity();
  MatrixNN a = a_exact.template cast<Scalar>();
  MatrixNK x0;
  for (int i = 0; i < N * K; ++i) x0.data()[i] = Scalar(u(rng));
  const Eigen::LLT<MatrixNN> llt(a);
  ASSERT_EQ(llt.info(), Eigen::Success);
  const MatrixNN l_eigen = llt.matrixL();

  MatrixNN l = a;
  for (int j = 1; j < N; ++j)  // the upper triangle is not read: poison it
    for (int i = 0; i < j; ++i) l(i, j) = std::numeric_limits<Scalar>::quiet_NaN();
  Scalar reciprocal[N];
  ASSERT_TRUE(small_dense::cholesky_in_place(l, reciprocal));
  const MatrixNN lower = l.template triangularView<Eigen::Lower>();
  // A few eps of cond(A) <= 1 + max eigenvalue of b b^T, relative.
  const Scalar tol = Scalar(64) * Scalar(N) * std::numeric_limits<Scalar>::epsilon() * Scalar(1 + N);
  EXPECT_LE((lower - l_eigen).norm(), tol * l_eigen.norm());
  for (int k = 0; k < N; ++k) EXPECT_NEAR(reciprocal[k] * l(k, k), Scalar(1), tol) << "k " << k;

  MatrixNK x = x0;
  small_dense::solve_lower_in_place(l, reciprocal, x);
  MatrixNK expected = l_eigen.template triangularView<Eigen::Lower>().solve(x0);
  EXPECT_LE((x - expected).norm(), tol * (Scalar(1) + expected.norm())) << "L^-1";
  x = x0;
  small_dense::solve_lower_in_place(l, x);  // reciprocals of its own
  EXPECT_LE((x - expected).norm(), tol * (Scalar(1) + expected.norm())) << "L^-1 (own reciprocals)";

  x = x0;
  small_dense::solve_lower_transposed_in_place(l, reciprocal, x);
  expected = l_eigen.transpose().template triangularView<Eigen::Upper>().solve(x0);
  EXPECT_LE((x - expected).norm(), tol * (Scalar(1) + expected.norm())) << "L^-T, N " << N << " K " << K;
  x = x0;
  small_dense::solve_lower_transposed_in_place(l, x);
  EXPECT_LE((x - expected).norm(), tol * (Scalar(1) + expected.norm())) << "L^-T (own reciprocals)";

  x = x0;
  small_dense::multiply_lower_in_place(l, x);
  expected = l_eigen * x0;
  EXPECT_LE((x - expected).norm(), tol * (Scalar(1) + expected.norm())) << "L x, N " << N << " K " << K;
}

template <typename Scalar, int K>
void every_size(unsigned seed) {
  expect_kernels_match_eigen<Scalar, 1, K>(seed + 1);
  expect_kernels_match_eigen<Scalar, 2, K>(seed + 2);
  expect_kernels_match_eigen<Scalar, 3, K>(seed + 3);
  expect_kernels_match_eigen<Scalar, 4, K>(seed + 4);
  expect_kernels_match_eigen<Scalar, 5, K>(seed + 5);
  expect_kernels_match_eigen<Scalar, 7, K>(seed + 7);
  expect_kernels_match_eigen<Scalar, 8, K>(seed + 8);
  expect_kernels_match_eigen<Scalar, 9, K>(seed + 9);
  expect_kernels_match_eigen<Scalar, 16, K>(seed + 16);
}

TEST(SmallDense, KernelsMatchEigenDouble) {
  every_size<double, 1>(100);
  every_size<double, 2>(200);
  every_size<double, 3>(300);
}

TEST(SmallDense, KernelsMatchEigenFloat) {
  every_size<float, 1>(400);
  every_size<float, 2>(500);
  every_size<float, 3>(600);
}

TEST(SmallDense, CholeskyRejectsWhatIsNotPositiveDefinite) {
  // Each matrix fails at a different pivot: the first, the second of a pair, the last alone.
  Eigen::Matrix3d first;
  first << -1, 0, 0, 0, 1, 0, 0, 0, 1;
  Eigen::Matrix3d second;
  second << 1, 2, 0, 2, 1, 0, 0, 0, 1;  // 1 - 4 < 0
  Eigen::Matrix3d last;
  last << 1, 0, 1, 0, 1, 0, 1, 0, 1;    // singular: last pivot 0
  double reciprocal[3];
  EXPECT_FALSE(small_dense::cholesky_in_place(first, reciprocal));
  EXPECT_FALSE(small_dense::cholesky_in_place(second, reciprocal));
  EXPECT_FALSE(small_dense::cholesky_in_place(last, reciprocal));
  Eigen::Matrix4d pair;  // fails at pivot 4, the second of the second pair
  pair << 4, 0, 0, 0, 0, 4, 0, 0, 0, 0, 1, 3, 0, 0, 3, 1;
  double r4[4];
  EXPECT_FALSE(small_dense::cholesky_in_place(pair, r4));
}

}  // namespace
}  // namespace gausstrack::test
