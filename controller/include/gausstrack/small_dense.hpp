// Dense kernels for the solver's compile-time sizes: Cholesky factorization, triangular solves,
// products and inverse, written as plain loops over column-major storage.
//
// Why not Eigen's LLT and triangularView: at the sizes a controller has (2 to about 32) Eigen runs
// these operations on run-time-sized blocks (matrix-vector products and triangular solves with
// dynamic sizes, blocked ones for several right sides), whose overhead is most of the cost, and
// Eigen's LLT::rcond runs an iterative 1-norm estimator (several triangular solves). Each inner
// loop here runs down one contiguous column, and the solves' divisions are taken off the dependent
// chains; nothing allocates or throws. Only the lower triangle of a factor is read.
#pragma once

#include <Eigen/Core>
#include <cmath>

namespace gausstrack::small_dense {

// Element-wise helpers over contiguous storage (a matrix with one row or one column is contiguous
// whatever Eigen's storage order): the solver's whole-matrix checks and products without an Eigen
// expression per use.

/// Every entry finite. Short arrays entry by entry (the first non-finite one ends the test); long
/// ones by x - x, which is 0 for a finite x and NaN otherwise, summed in four independent chains
/// without a branch (a sum of them stays 0 only when every entry is finite).
template <typename Scalar>
bool all_finite(const Scalar* x, int count) noexcept {
  if (count < 16) {
    for (int i = 0; i < count; ++i)
      if (!std::isfinite(x[i])) return false;
    return true;
  }
  Scalar s0(0), s1(0), s2(0), s3(0);
  int i = 0;
  for (; i + 4 <= count; i += 4) {
    s0 += x[i] - x[i];
    s1 += x[i + 1] - x[i + 1];
    s2 += x[i + 2] - x[i + 2];
    s3 += x[i + 3] - x[i + 3];
  }
  for (; i < count; ++i) s0 += x[i] - x[i];
  return (s0 + s1) + (s2 + s3) == Scalar(0);
}

/// x . y; from 8 entries with four partial sums side by side (a dot product's one accumulator is
/// a dependent chain of additions). The order of the additions is the code's (a compiler that
/// contracts into FMA still rounds differently).
template <typename Scalar>
Scalar dot(const Scalar* x, const Scalar* y, int count) noexcept {
  if (count < 8) {
    Scalar s(0);
    for (int i = 0; i < count; ++i) s += x[i] * y[i];
    return s;
  }
  Scalar s0(0), s1(0), s2(0), s3(0);
  int i = 0;
  for (; i + 4 <= count; i += 4) {
    s0 += x[i] * y[i];
    s1 += x[i + 1] * y[i + 1];
    s2 += x[i + 2] * y[i + 2];
    s3 += x[i + 3] * y[i + 3];
  }
  for (; i < count; ++i) s0 += x[i] * y[i];
  return (s0 + s1) + (s2 + s3);
}

/// a == b entry by entry (so 0 == -0, and NaN equals nothing).
template <typename Scalar>
bool all_equal(const Scalar* a, const Scalar* b, int count) noexcept {
  for (int i = 0; i < count; ++i)
    if (!(a[i] == b[i])) return false;
  return true;
}

template <typename Scalar>
Scalar squared_norm(const Scalar* x, int count) noexcept {
  return dot(x, x, count);
}

/// y = M x for the rows x cols column-major M (y must not alias x).
template <typename Scalar>
void multiply(const Scalar* m, int rows, int cols, const Scalar* x, Scalar* y) noexcept {
  for (int i = 0; i < rows; ++i) y[i] = Scalar(0);
  for (int j = 0; j < cols; ++j) {
    const Scalar xj = x[j];
    const Scalar* mj = m + j * rows;
    for (int i = 0; i < rows; ++i) y[i] += mj[i] * xj;
  }
}

/// In place, the lower triangle of the symmetric positive definite `m` (its upper triangle is not
/// read) becomes L with m = L L^T. Right-looking: step k scales column k and updates the columns
/// to its right. Returns false, as Eigen's LLT does, when a pivot is <= 0 (not positive definite);
/// a NaN pivot is not detected here (the factor comes out non-finite; the caller checks that).
template <typename Scalar, int N>
bool cholesky_in_place(Eigen::Matrix<Scalar, N, N>& m) noexcept {
  Scalar* a = m.data();
  for (int k = 0; k < N; ++k) {
    Scalar* ck = a + k * N;
    if (ck[k] <= Scalar(0)) return false;
    const Scalar d = std::sqrt(ck[k]);
    ck[k] = d;
    // Divided by d, as Eigen's LLT does, rather than multiplied by 1 / d (one rounding, not two:
    // a borderline matrix at the range's ends is then judged as Eigen judges it).
    for (int i = k + 1; i < N; ++i) ck[i] /= d;
    for (int j = k + 1; j < N; ++j) {
      Scalar* cj = a + j * N;
      const Scalar ljk = ck[j];
      for (int i = j; i < N; ++i) cj[i] -= ck[i] * ljk;
    }
  }
  return true;
}

/// x = L^-1 x for every column of x (forward substitution, column-oriented).
template <typename Scalar, int N, int K, int Options, int MaxRows, int MaxCols>
void solve_lower_in_place(const Eigen::Matrix<Scalar, N, N>& l,
                          Eigen::Matrix<Scalar, N, K, Options, MaxRows, MaxCols>& x) noexcept {
  static_assert(N == 1 || K == 1 || !(Options & Eigen::RowMajor), "column-major right sides");
  const Scalar* a = l.data();
  Scalar inverse[N];  // independent divisions up front: only multiplications on the dependent path
  for (int k = 0; k < N; ++k) inverse[k] = Scalar(1) / a[k * N + k];
  for (int k = 0; k < N; ++k) {  // step k for every column: independent chains side by side
    const Scalar* ck = a + k * N;
    for (int c = 0; c < K; ++c) {
      Scalar* xc = x.data() + c * N;
      const Scalar v = xc[k] * inverse[k];
      xc[k] = v;
      for (int i = k + 1; i < N; ++i) xc[i] -= ck[i] * v;
    }
  }
}

/// x = L^-T x for every column of x (back substitution: dot products down L's columns). Each
/// unknown's sum runs from the last row up in two partial sums and takes the newest unknown,
/// x_(k+1), last: the terms of the older unknowns are summed while x_(k+1) is still being
/// computed, so the dependent path from one unknown to the next is one multiply-add, a
/// subtraction and a multiplication rather than the whole sum.
template <typename Scalar, int N, int K, int Options, int MaxRows, int MaxCols>
void solve_lower_transposed_in_place(const Eigen::Matrix<Scalar, N, N>& l,
                                     Eigen::Matrix<Scalar, N, K, Options, MaxRows, MaxCols>& x) noexcept {
  static_assert(N == 1 || K == 1 || !(Options & Eigen::RowMajor), "column-major right sides");
  const Scalar* a = l.data();
  Scalar inverse[N];
  for (int k = 0; k < N; ++k) inverse[k] = Scalar(1) / a[k * N + k];
  for (int c = 0; c < K; ++c) {
    Scalar* xc = x.data() + c * N;
    for (int k = N - 1; k >= 0; --k) {
      const Scalar* ck = a + k * N;
      Scalar s0(0), s1(0);
      int i = N - 1;
      for (; i > k + 2; i -= 2) {
        s0 += ck[i] * xc[i];
        s1 += ck[i - 1] * xc[i - 1];
      }
      if (i == k + 2) s0 += ck[i] * xc[i];
      Scalar s = xc[k] - (s0 + s1);
      if (k + 1 < N) s -= ck[k + 1] * xc[k + 1];
      xc[k] = s * inverse[k];
    }
  }
}

/// x = L x for every column of x. Step k (from the last) reads x_k before any later step changes
/// it, so the product runs in place down L's columns.
template <typename Scalar, int N, int K, int Options, int MaxRows, int MaxCols>
void multiply_lower_in_place(const Eigen::Matrix<Scalar, N, N>& l,
                             Eigen::Matrix<Scalar, N, K, Options, MaxRows, MaxCols>& x) noexcept {
  static_assert(N == 1 || K == 1 || !(Options & Eigen::RowMajor), "column-major right sides");
  const Scalar* a = l.data();
  for (int c = 0; c < K; ++c) {
    Scalar* xc = x.data() + c * N;
    for (int k = N - 1; k >= 0; --k) {
      const Scalar* ck = a + k * N;
      const Scalar v = xc[k];
      xc[k] = ck[k] * v;
      for (int i = k + 1; i < N; ++i) xc[i] += ck[i] * v;
    }
  }
}

/// x = L^T x for every column of x (dot products down L's columns, first row first).
template <typename Scalar, int N, int K, int Options, int MaxRows, int MaxCols>
void multiply_lower_transposed_in_place(const Eigen::Matrix<Scalar, N, N>& l,
                                        Eigen::Matrix<Scalar, N, K, Options, MaxRows, MaxCols>& x) noexcept {
  static_assert(N == 1 || K == 1 || !(Options & Eigen::RowMajor), "column-major right sides");
  const Scalar* a = l.data();
  for (int c = 0; c < K; ++c) {
    Scalar* xc = x.data() + c * N;
    for (int k = 0; k < N; ++k) {
      const Scalar* ck = a + k * N;
      Scalar s(0);
      for (int i = k; i < N; ++i) s += ck[i] * xc[i];
      xc[k] = s;
    }
  }
}

/// The lower triangle of `inverse` becomes L^-1 (its upper triangle zero); returns the sum of
/// squares of L^-1's entries, ||L^-1||_F^2.
template <typename Scalar, int N>
Scalar invert_lower(const Eigen::Matrix<Scalar, N, N>& l, Eigen::Matrix<Scalar, N, N>& inverse) noexcept {
  const Scalar* a = l.data();
  Scalar* z = inverse.data();
  Scalar sum(0);
  Scalar reciprocal[N];
  for (int k = 0; k < N; ++k) reciprocal[k] = Scalar(1) / a[k * N + k];
  // Column c of L^-1 solves L z = e_c; its rows above c are zero. Step k runs for every column
  // that has reached it: independent chains side by side.
  for (int i = 0; i < N * N; ++i) z[i] = Scalar(0);
  for (int c = 0; c < N; ++c) z[c * N + c] = Scalar(1);
  for (int k = 0; k < N; ++k) {
    const Scalar* ck = a + k * N;
    for (int c = 0; c <= k; ++c) {
      Scalar* zc = z + c * N;
      const Scalar v = zc[k] * reciprocal[k];
      zc[k] = v;
      sum += v * v;
      for (int i = k + 1; i < N; ++i) zc[i] -= ck[i] * v;
    }
  }
  return sum;
}

}  // namespace gausstrack::small_dense
