// The dense kernels (small_dense.hpp) against Eigen's factorization, triangular solves and
// products: one case per size (N, K), shared by small_dense_test.cpp (double) and
// small_dense_float_test.cpp (float), two files so that each builds in well under a minute.
#pragma once

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <limits>
#include <random>

#include "gausstrack/small_dense.hpp"

namespace gausstrack::test {

// Eigen's answers at run-time size and in double precision, computed once per case outside the
// size templates (a fixed-size LLT and triangular solve per size made this file minutes to build).
struct Expected {
  Eigen::MatrixXd l, l_inverse, lower_solve, lower_transposed_solve, lower_product, gram;
};

inline void eigen_answers(const Eigen::MatrixXd& a, const Eigen::MatrixXd& x0, Expected& e) {
  const Eigen::LLT<Eigen::MatrixXd> llt(a);
  ASSERT_EQ(llt.info(), Eigen::Success);
  e.l = llt.matrixL();
  e.l_inverse = e.l.triangularView<Eigen::Lower>().solve(Eigen::MatrixXd::Identity(a.rows(), a.cols()));
  e.lower_solve = e.l.triangularView<Eigen::Lower>().solve(x0);
  e.lower_transposed_solve = e.l.transpose().triangularView<Eigen::Upper>().solve(x0);
  e.lower_product = e.l * x0;
  e.gram = x0.transpose() * x0;
}

// |got - expected| <= tol (1 + |expected|), in double whatever the kernel's scalar.
inline ::testing::AssertionResult near(const Eigen::MatrixXd& got, const Eigen::MatrixXd& expected, double tol) {
  const double error = (got - expected).norm();
  if (error <= tol * (1 + expected.norm())) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "error " << error << " above " << tol << " (1 + " << expected.norm()
                                       << ")";
}

template <typename Scalar, int N, int K>
void expect_kernels_match_eigen(unsigned seed) {
  using MatrixNN = Eigen::Matrix<Scalar, N, N>;
  using MatrixNK = Eigen::Matrix<Scalar, N, K>;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  Eigen::MatrixXd b(N, N);
  for (int i = 0; i < N * N; ++i) b.data()[i] = u(rng);
  Eigen::MatrixXd a_exact = b * b.transpose();
  a_exact.diagonal().array() += 1;
  const MatrixNN a = a_exact.cast<Scalar>();
  MatrixNK x0;
  for (int i = 0; i < N * K; ++i) x0.data()[i] = Scalar(u(rng));
  // The oracle factors the matrix the kernel sees (rounded to Scalar), in double.
  Expected e;
  ASSERT_NO_FATAL_FAILURE(eigen_answers(a.template cast<double>(), x0.template cast<double>(), e));
  const auto wide = [](const auto& m) -> Eigen::MatrixXd { return m.template cast<double>(); };

  MatrixNN l = a;
  for (int j = 1; j < N; ++j)  // the upper triangle is not read: poison it
    for (int i = 0; i < j; ++i) l(i, j) = std::numeric_limits<Scalar>::quiet_NaN();
  Scalar reciprocal[N];
  ASSERT_TRUE(small_dense::cholesky_in_place(l, reciprocal));
  const MatrixNN lower = l.template triangularView<Eigen::Lower>();
  // A few eps of cond(A) <= 1 + max eigenvalue of b b^T, relative.
  const double tol = 64.0 * N * std::numeric_limits<Scalar>::epsilon() * (1 + N);
  EXPECT_LE((wide(lower) - e.l).norm(), tol * e.l.norm()) << "L, N " << N << " K " << K;
  for (int k = 0; k < N; ++k) EXPECT_NEAR(double(reciprocal[k] * l(k, k)), 1.0, tol) << "k " << k;

  MatrixNK x = x0;
  small_dense::solve_lower_in_place(l, reciprocal, x);
  EXPECT_TRUE(near(wide(x), e.lower_solve, tol)) << "L^-1, N " << N << " K " << K;
  x = x0;
  small_dense::solve_lower_in_place(l, x);  // reciprocals of its own
  EXPECT_TRUE(near(wide(x), e.lower_solve, tol)) << "L^-1 (own reciprocals), N " << N << " K " << K;

  x = x0;
  small_dense::solve_lower_transposed_in_place(l, reciprocal, x);
  EXPECT_TRUE(near(wide(x), e.lower_transposed_solve, tol)) << "L^-T, N " << N << " K " << K;
  x = x0;
  small_dense::solve_lower_transposed_in_place(l, x);
  EXPECT_TRUE(near(wide(x), e.lower_transposed_solve, tol)) << "L^-T (own reciprocals), N " << N << " K " << K;

  x = x0;
  small_dense::multiply_lower_in_place(l, x);
  EXPECT_TRUE(near(wide(x), e.lower_product, tol)) << "L x, N " << N << " K " << K;

  // L^-1 (lower triangle; the upper one exactly zero) and its squared Frobenius norm, with the
  // factor's reciprocals and with its own.
  MatrixNN z;
  const Scalar norm2 = small_dense::invert_lower(l, reciprocal, z);
  const double expected_norm2 = e.l_inverse.squaredNorm();
  EXPECT_LE((wide(z) - e.l_inverse).norm(), tol * e.l_inverse.norm()) << "L^-1 (inverse), N " << N;
  EXPECT_NEAR(double(norm2), expected_norm2, tol * expected_norm2) << "||L^-1||_F^2, N " << N;
  for (int j = 1; j < N; ++j)
    for (int i = 0; i < j; ++i) EXPECT_EQ(z(i, j), Scalar(0)) << "L^-1 upper (" << i << ", " << j << "), N " << N;
  MatrixNN z_own;
  EXPECT_NEAR(double(small_dense::invert_lower(l, z_own)), expected_norm2, tol * expected_norm2)
      << "||L^-1||_F^2 (own reciprocals), N " << N;
  EXPECT_LE((wide(z_own) - e.l_inverse).norm(), tol * e.l_inverse.norm()) << "L^-1 (own reciprocals), N " << N;

  Eigen::Matrix<Scalar, K, K> g;
  small_dense::gram(x0, g);
  EXPECT_LE((wide(g) - e.gram).norm(), tol * e.gram.norm()) << "x^T x, N " << N << " K " << K;
  EXPECT_EQ(g, g.transpose()) << "x^T x symmetric, N " << N << " K " << K;
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

}  // namespace gausstrack::test
