// The dense kernels (small_dense.hpp) against Eigen's own factorization and triangular solves, at
// every size parity their two-at-a-time steps distinguish (N odd and even, 1 to 9 and 16) and for
// one to five right sides (double; one to three in float).
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

  Eigen::Matrix<Scalar, K, K> g;
  small_dense::gram(x0, g);
  const Eigen::Matrix<Scalar, K, K> g_eigen = x0.transpose() * x0;
  EXPECT_LE((g - g_eigen).norm(), tol * g_eigen.norm()) << "x^T x, N " << N << " K " << K;
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

TEST(SmallDense, KernelsMatchEigenDouble) {
  every_size<double, 1>(100);
  every_size<double, 2>(200);
  every_size<double, 3>(300);
  every_size<double, 4>(700);  // the many-column paths at both parities of K
  every_size<double, 5>(800);
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

// Columns that are zero outside a band (a constraint row touching a few coordinates): the
// supports found, and the solve and Gram matrix that skip the zeros give what the full kernels give.
template <int N, int K>
void expect_supports_skip_only_zeros(unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  Eigen::Matrix<double, N, N> b;
  for (int i = 0; i < N * N; ++i) b.data()[i] = u(rng);
  Eigen::Matrix<double, N, N> l = b * b.transpose() + Eigen::Matrix<double, N, N>::Identity();
  double reciprocal[N];
  ASSERT_TRUE(small_dense::cholesky_in_place(l, reciprocal));
  Eigen::Matrix<double, N, K> x = Eigen::Matrix<double, N, K>::Zero();
  int lo[K], hi[K];
  for (int c = 0; c < K; ++c) {
    // Column c: rows [lo, hi), every parity, one column all zero and one ending at row N.
    lo[c] = (3 * c + 1) % N;
    hi[c] = c == 1 ? lo[c] : (c == 2 ? N : std::min(N, lo[c] + 1 + c % 3));
    for (int i = lo[c]; i < hi[c]; ++i) x(i, c) = u(rng);
    if (c == 0 && hi[c] - lo[c] > 1) x(lo[c] + 1, c) = -0.0;  // a zero inside the band is kept
  }
  int first[K], end[K];
  small_dense::column_supports(x, first, end);
  for (int c = 0; c < K; ++c) {
    if (hi[c] == lo[c]) {
      EXPECT_EQ(first[c], 0) << "column " << c;
      EXPECT_EQ(end[c], 0) << "column " << c;
      continue;
    }
    EXPECT_EQ(first[c], lo[c] & ~1) << "column " << c;
    EXPECT_EQ(end[c], hi[c]) << "column " << c;
  }
  Eigen::Matrix<double, K, K> g_full, g_band;
  small_dense::gram(x, g_full);
  small_dense::gram(x, g_band, first, end);
  EXPECT_TRUE(g_band == g_full) << "N " << N << " K " << K << "\n" << g_band << "\n" << g_full;

  Eigen::Matrix<double, N, K> full = x, band = x;
  small_dense::solve_lower_in_place(l, reciprocal, full);
  small_dense::solve_lower_in_place(l, reciprocal, band, first);
  EXPECT_TRUE(band == full) << "N " << N << " K " << K;
  // The answer fills in below the band: its supports start where x's do and end at N.
  for (int c = 0; c < K; ++c) end[c] = end[c] == 0 ? 0 : N;
  small_dense::gram(full, g_full);
  small_dense::gram(band, g_band, first, end);
  EXPECT_TRUE(g_band == g_full) << "N " << N << " K " << K;
}

TEST(SmallDense, SupportsSkipOnlyZeros) {
  expect_supports_skip_only_zeros<7, 3>(900);
  expect_supports_skip_only_zeros<8, 4>(901);
  expect_supports_skip_only_zeros<9, 5>(902);
  expect_supports_skip_only_zeros<16, 8>(903);
  expect_supports_skip_only_zeros<5, 2>(904);  // the one- and two-column path
}

}  // namespace
}  // namespace gausstrack::test
