// The dense kernels (small_dense.hpp) in double against Eigen's (small_dense_cases.hpp), at every
// size parity their two-at-a-time steps distinguish (N odd and even, 1 to 9 and 16) and for one to
// five right sides; what the Cholesky factorization rejects; the kernels that skip a column's zeros.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "gausstrack/rank_revealing.hpp"
#include "gausstrack/small_dense.hpp"
#include "small_dense_cases.hpp"

namespace gausstrack::test {
namespace {

TEST(SmallDense, KernelsMatchEigenDouble) {
  every_size<double, 1>(100);
  every_size<double, 2>(200);
  every_size<double, 3>(300);
  every_size<double, 4>(700);  // the many-column paths at both parities of K
  every_size<double, 5>(800);
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

// all_finite against std::isfinite: every special value (infinities, NaNs of both signs, the
// largest and the subnormal values, zeros) at every position of every length up to 40; with a
// copy, the same answer and every entry copied bit for bit, those after a non-finite one too.
template <typename Scalar>
void expect_all_finite_matches_isfinite() {
  using limits = std::numeric_limits<Scalar>;
  const Scalar specials[] = {Scalar(0), -Scalar(0), Scalar(1), limits::max(), -limits::max(), limits::min(),
                             limits::denorm_min(), -limits::denorm_min(), limits::infinity(), -limits::infinity(),
                             limits::quiet_NaN(), -limits::quiet_NaN(), limits::signaling_NaN()};
  for (const Scalar v : specials) {
    for (int n = 1; n <= 40; ++n) {
      for (int at = 0; at < n; ++at) {
        Scalar x[40];
        for (int i = 0; i < n; ++i) x[i] = Scalar(i) - Scalar(7.5);
        x[at] = v;
        ASSERT_EQ(small_dense::all_finite(x, n), std::isfinite(v)) << v << " at " << at << " of " << n;
        Scalar copy[40];
        for (Scalar& c : copy) c = Scalar(99);
        ASSERT_EQ(small_dense::all_finite(x, n, copy), std::isfinite(v)) << v << " at " << at << " of " << n;
        ASSERT_EQ(std::memcmp(copy, x, sizeof(Scalar) * static_cast<std::size_t>(n)), 0)
            << "the copy of " << n << " entries with " << v << " at " << at;
        if (n < 40) {
          ASSERT_EQ(copy[n], Scalar(99)) << "written past the copy's end";
        }
      }
    }
  }
  EXPECT_TRUE(small_dense::all_finite(static_cast<const Scalar*>(nullptr), 0));
}

// all_equal against a == b entry by entry, for a finite b: one entry of a changed to each special
// value at every position of every length up to 40 (zeros of either sign are equal; a NaN, an
// infinity, the next representable value and a difference that overflows are not).
template <typename Scalar>
void expect_all_equal_matches_compare() {
  using limits = std::numeric_limits<Scalar>;
  const Scalar specials[] = {Scalar(0), -Scalar(0), Scalar(1), limits::max(), -limits::max(), limits::min(),
                             limits::denorm_min(), limits::infinity(), -limits::infinity(), limits::quiet_NaN(),
                             -limits::quiet_NaN()};
  for (const Scalar v : specials) {
    for (const Scalar w : {Scalar(0), -Scalar(0), Scalar(1), limits::max(), -limits::max(), limits::denorm_min()}) {
      for (int n = 1; n <= 40; ++n) {
        for (int at = 0; at < n; ++at) {
          Scalar a[40], b[40];
          for (int i = 0; i < n; ++i) a[i] = b[i] = Scalar(i) - Scalar(7.5);
          a[at] = v;
          b[at] = w;
          ASSERT_EQ(small_dense::all_equal(a, b, n), v == w) << v << " against " << w << " at " << at << " of " << n;
        }
      }
    }
    Scalar a[3] = {Scalar(1), v, Scalar(2)};  // the next value up differs
    Scalar b[3] = {Scalar(1), v, std::nextafter(Scalar(2), Scalar(3))};
    if (std::isfinite(v)) {
      ASSERT_FALSE(small_dense::all_equal(a, b, 3)) << v;
    }
  }
}

TEST(SmallDense, AllEqualMatchesCompare) {
  expect_all_equal_matches_compare<double>();
  expect_all_equal_matches_compare<float>();
}

TEST(SmallDense, AllFiniteMatchesIsfinite) {
  expect_all_finite_matches_isfinite<double>();
  expect_all_finite_matches_isfinite<float>();
}

// The rank-revealing kernels' scale (rank_revealing.hpp) against its definition, checked with
// frexp: a power of two s with max |x_i| / s in [1, 2), for largest entries across the whole range
// (both ends of the normal range, powers of two and the values just below them, subnormals),
// either sign, at any position; 1 for a zero, infinite or NaN largest entry.
template <typename Scalar>
void expect_power_of_two_scale_meets_its_definition() {
  using limits = std::numeric_limits<Scalar>;
  std::vector<Scalar> largest = {limits::max(), limits::min(), limits::denorm_min(), limits::min() / Scalar(3),
                                 limits::min() - limits::denorm_min(), Scalar(1), Scalar(2), Scalar(0.75)};
  for (int e = limits::min_exponent - 1; e < limits::max_exponent; e += 7) {
    const Scalar p = std::ldexp(Scalar(1), e);
    largest.insert(largest.end(), {p, std::nextafter(p, Scalar(0)), p * Scalar(1.5)});
  }
  for (const Scalar m : largest) {
    for (int at = 0; at < 3; ++at) {
      for (const Scalar sign : {Scalar(1), Scalar(-1)}) {
        Scalar x[3] = {m / Scalar(4), Scalar(0), -m / Scalar(8)};
        x[at] = sign * m;
        const Scalar s = small_dense::power_of_two_scale(x, 3);
        int exponent = 0;
        EXPECT_EQ(std::frexp(s, &exponent), Scalar(0.5)) << m;  // s is a power of two
        EXPECT_GE(m / s, Scalar(1)) << m;
        EXPECT_LT(m / s, Scalar(2)) << m;
      }
    }
  }
  for (const Scalar bad : {Scalar(0), limits::infinity(), -limits::infinity(), limits::quiet_NaN()}) {
    const Scalar x[2] = {bad, bad};
    EXPECT_EQ(small_dense::power_of_two_scale(x, 2), Scalar(1)) << bad;
  }
}

TEST(SmallDense, PowerOfTwoScaleMeetsItsDefinition) {
  expect_power_of_two_scale_meets_its_definition<double>();
  expect_power_of_two_scale_meets_its_definition<float>();
}

// A NaN counts as nonzero in a column's support, wherever it is (alone in it too); a zero column
// has none.
TEST(SmallDense, SupportsCountANaNAndSkipAZeroColumn) {
  for (int at = 0; at < 9; ++at) {
    Eigen::Matrix<double, 9, 2> x = Eigen::Matrix<double, 9, 2>::Zero();
    x(4, 0) = 1.0;
    x(at, 0) = std::numeric_limits<double>::quiet_NaN();  // at 4: the column's only nonzero
    int first[2], end[2];
    small_dense::column_supports(x, first, end);
    EXPECT_EQ(first[0], std::min(at, 4) & ~1) << "NaN at " << at;
    EXPECT_EQ(end[0], std::max(at, 4) + 1) << "NaN at " << at;
    EXPECT_EQ(first[1], 0);
    EXPECT_EQ(end[1], 0);
  }
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

  // The same substitution on columns held apart: x's with their supports and a dense right side
  // beside them (as the solver solves Q - f beside D^T). Each column is the one-matrix solve's
  // to rounding (the path may change with the number of columns), and the right side's is
  // Eigen's triangular solve's.
  Eigen::Matrix<double, N, K> apart = x;
  Eigen::Matrix<double, N, 1> v;
  for (int i = 0; i < N; ++i) v(i) = u(rng);
  Eigen::Matrix<double, N, 1> v_apart = v;
  small_dense::solve_lower_in_place(l, reciprocal, apart, v_apart, first);
  EXPECT_LE((apart - full).norm(), 1e-13 * full.norm()) << "N " << N << " K " << K;
  const Eigen::Matrix<double, N, 1> v_expected = l.template triangularView<Eigen::Lower>().solve(v);
  EXPECT_LE((v_apart - v_expected).norm(), 1e-13 * v_expected.norm()) << "N " << N << " K " << K;
  // Alone by the same path, the right side's answer is the same bit for bit (what lets a kept
  // factorization solve it alone and answer as a new one).
  Eigen::Matrix<double, N, 1> v_alone = v;
  small_dense::solve_lower_columns<1, (K + 1 > 2)>(l, reciprocal, [&v_alone](int) { return v_alone.data(); });
  EXPECT_TRUE(v_alone == v_apart) << "N " << N << " K " << K;
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
  expect_supports_skip_only_zeros<6, 1>(905);  // one column, and two with the right side beside it
}

}  // namespace
}  // namespace gausstrack::test
