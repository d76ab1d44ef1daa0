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
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <type_traits>

namespace gausstrack::small_dense {

// Element-wise helpers over contiguous storage (a matrix with one row or one column is contiguous
// whatever Eigen's storage order): the solver's whole-matrix checks and products without an Eigen
// expression per use.

namespace detail {
// The unsigned integer of an IEEE float's or double's size, for the bit tests below; void for
// other types, which take the floating-point tests instead.
template <typename Scalar>
using IeeeBits = std::conditional_t<
    !std::numeric_limits<Scalar>::is_iec559, void,
    std::conditional_t<sizeof(Scalar) == 8, std::uint64_t, std::conditional_t<sizeof(Scalar) == 4, std::uint32_t, void>>>;
template <typename Scalar>
inline constexpr bool kHasIeeeBits = !std::is_void_v<IeeeBits<Scalar>>;

// Two adjacent entries (an even row and the odd one below it) as one value: an SSE2 packet for
// double, so that the kernels' pairs of rows run as one load, multiply and add each rather than
// as whatever the compiler's vectorizer makes of a short loop with run-time bounds (for the Gram
// matrix's blocks, nothing: they ran scalar). The same arithmetic entry by entry, so the same
// rounding; plain scalar code where there is no packet of two (float, a CPU without SIMD).
// Written on Eigen's packet functions, not as an Eigen::Array<Scalar, 2, 1>: the array's
// expression templates cost every model's translation unit 0.3 s and 17 MB to compile, for the
// same instructions.
template <typename Scalar, typename Packet = typename Eigen::internal::find_best_packet<Scalar, 2>::type,
          bool = Eigen::internal::unpacket_traits<Packet>::size == 2>
struct Pair {  // two scalars
  Scalar v[2];
  static Pair zero() noexcept { return {{Scalar(0), Scalar(0)}}; }
  static Pair load(const Scalar* x) noexcept { return {{x[0], x[1]}}; }
  void store(Scalar* x) const noexcept { x[0] = v[0], x[1] = v[1]; }
  Pair operator*(const Pair& o) const noexcept { return {{v[0] * o.v[0], v[1] * o.v[1]}}; }
  Pair operator*(Scalar s) const noexcept { return {{v[0] * s, v[1] * s}}; }
  Pair operator+(const Pair& o) const noexcept { return {{v[0] + o.v[0], v[1] + o.v[1]}}; }
  Pair operator-(const Pair& o) const noexcept { return {{v[0] - o.v[0], v[1] - o.v[1]}}; }
};
template <typename Scalar, typename Packet>
struct Pair<Scalar, Packet, true> {  // one SIMD packet
  Packet v;
  static Pair zero() noexcept { return {Eigen::internal::pset1<Packet>(Scalar(0))}; }
  static Pair load(const Scalar* x) noexcept { return {Eigen::internal::ploadu<Packet>(x)}; }
  void store(Scalar* x) const noexcept { Eigen::internal::pstoreu(x, v); }
  Pair operator*(const Pair& o) const noexcept { return {Eigen::internal::pmul(v, o.v)}; }
  Pair operator*(Scalar s) const noexcept { return {Eigen::internal::pmul(v, Eigen::internal::pset1<Packet>(s))}; }
  Pair operator+(const Pair& o) const noexcept { return {Eigen::internal::padd(v, o.v)}; }
  Pair operator-(const Pair& o) const noexcept { return {Eigen::internal::psub(v, o.v)}; }
};
}  // namespace detail

/// Every entry finite, and when `copy` is given, the entries copied into it on the way (one pass
/// over a matrix the caller keeps anyway). Short arrays entry by entry (the first non-finite one
/// ends a test without a copy; on a 32-bit core this is fewer instructions than the bits of a
/// double). Long ones from the bits: an IEEE value is finite unless its exponent field is all
/// ones, and adding the exponent's lowest bit to the field carries into the sign bit exactly then.
/// One AND, one addition and one OR per entry, in integers, so the loop vectorizes (a
/// floating-point sum of x - x runs as a few dependent chains of additions).
namespace detail {
// all_finite with or without its copy, as two instantiations: the copy's test is decided at
// compile time, not in the loop (at -O2 the compiler does not take it out; on the Cortex-M7 the
// test in the loop cost the differential drive's law 11 % more instructions).
template <bool kCopy, typename Scalar>
bool all_finite(const Scalar* x, int count, Scalar* copy) noexcept {
  if (!kHasIeeeBits<Scalar> || count < 16) {
    for (int i = 0; i < count; ++i) {
      if constexpr (kCopy) copy[i] = x[i];
      if (!std::isfinite(x[i])) {
        if constexpr (kCopy)
          for (int j = i + 1; j < count; ++j) copy[j] = x[j];
        return false;
      }
    }
    return true;
  }
  if constexpr (kHasIeeeBits<Scalar>) {
    using Bits = IeeeBits<Scalar>;
    constexpr int kMantissa = std::numeric_limits<Scalar>::digits - 1;  // 52 or 23 bits
    constexpr Bits kExponent = ((Bits(1) << (sizeof(Scalar) * 8 - 1)) - 1) & ~((Bits(1) << kMantissa) - 1);
    constexpr Bits kLowest = Bits(1) << kMantissa;
    constexpr Bits kSign = Bits(1) << (sizeof(Scalar) * 8 - 1);
    Bits carried = 0;
    for (int i = 0; i < count; ++i) {
      Bits b;
      std::memcpy(&b, x + i, sizeof b);
      if constexpr (kCopy) std::memcpy(copy + i, &b, sizeof b);
      carried |= (b & kExponent) + kLowest;
    }
    return (carried & kSign) == 0;
  }
  return true;  // not reached: every other type took the loop above
}
}  // namespace detail

template <typename Scalar>
bool all_finite(const Scalar* x, int count, Scalar* copy = nullptr) noexcept {
  return copy != nullptr ? detail::all_finite<true>(x, count, copy) : detail::all_finite<false>(x, count, copy);
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

/// a == b entry by entry (so 0 == -0, and NaN equals nothing), for arrays whose b is finite
/// (an infinite a then differs, as it does from every finite b). With IEEE bits: every a - b is
/// a zero of either sign exactly when the entries are equal (the difference of two finite
/// values is zero only when they are equal; a NaN or infinite a makes it NaN or infinite), and
/// the magnitudes' bits of the differences are ORed: a subtraction, an AND and an OR per entry,
/// which vectorize (a bool accumulated by compares does not). No early exit: the usual answer
/// is yes.
template <typename Scalar>
bool all_equal(const Scalar* a, const Scalar* b, int count) noexcept {
  if constexpr (detail::kHasIeeeBits<Scalar>) {
    using Bits = detail::IeeeBits<Scalar>;
    constexpr Bits kMagnitude = ~Bits(0) >> 1;
    Bits differ = 0;
    for (int i = 0; i < count; ++i) {
      const Scalar d = a[i] - b[i];
      Bits bits;
      std::memcpy(&bits, &d, sizeof bits);
      differ |= bits & kMagnitude;
    }
    return differ == 0;
  } else {
    bool same = true;
    for (int i = 0; i < count; ++i) same &= a[i] == b[i];
    return same;
  }
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
/// read) becomes L with m = L L^T, and reciprocal[k] = 1 / L_kk. The recurrence is that of
/// m = L_1 P L_1^T (L_1 unit lower triangular, P the pivots), so that the chain from one pivot to
/// the next holds a division but no square root; L = L_1 P^(1/2) is formed at the end, its square
/// roots independent of each other. Right-looking, two columns per step: the 2 x 2 diagonal block,
/// both columns scaled by their pivots' reciprocals, then one rank-2 update of the columns to their
/// right (each entry of a trailing column loaded and stored once per two columns). Returns false,
/// as Eigen's LLT does, when a pivot is <= 0 (not positive definite); a NaN pivot is not detected
/// here (the factor comes out non-finite; the caller checks that).
template <typename Scalar, int N>
bool cholesky_in_place(Eigen::Matrix<Scalar, N, N>& m, Scalar* reciprocal) noexcept {
  Scalar* a = m.data();
  Scalar inverse_pivot[N];
  for (int k = 0; k + 1 < N; k += 2) {
    Scalar* c0 = a + k * N;
    Scalar* c1 = c0 + N;
    const Scalar p0 = c0[k];
    if (!(p0 > Scalar(0))) return false;
    const Scalar r0 = Scalar(1) / p0;
    const Scalar w1 = c0[k + 1];
    const Scalar l10 = w1 * r0;
    const Scalar p1 = c1[k + 1] - l10 * w1;
    if (!(p1 > Scalar(0))) return false;
    const Scalar r1 = Scalar(1) / p1;
    inverse_pivot[k] = r0;
    inverse_pivot[k + 1] = r1;
    c0[k + 1] = l10;
    c1[k + 1] = p1;
    for (int i = k + 2; i < N; ++i) {  // column k + 1 after column k's update, then both scaled
      const Scalar w = c0[i];
      const Scalar u = c1[i] - w * l10;
      c0[i] = w * r0;
      c1[i] = u * r1;
    }
    // m_ij -= (L_1)_ik p0 (L_1)_jk + (L_1)_i,k+1 p1 (L_1)_j,k+1, two columns j, j + 1 at a time
    // (j even, as k is): rows j, j + 1 of column j and row j + 1 of column j + 1, then the pairs
    // of rows below for both columns, each pair of c0 and c1 loaded once for the two.
    using P2 = detail::Pair<Scalar>;
    int j = k + 2;
    for (; j + 1 < N; j += 2) {
      Scalar* cj = a + j * N;
      Scalar* cj1 = cj + N;
      const Scalar wj = c0[j] * p0, uj = c1[j] * p1;
      const Scalar wj1 = c0[j + 1] * p0, uj1 = c1[j + 1] * p1;
      (P2::load(cj + j) - (P2::load(c0 + j) * wj + P2::load(c1 + j) * uj)).store(cj + j);
      cj1[j + 1] -= c0[j + 1] * wj1 + c1[j + 1] * uj1;
      int i = j + 2;
      for (; i + 1 < N; i += 2) {
        const P2 l0 = P2::load(c0 + i), l1 = P2::load(c1 + i);
        (P2::load(cj + i) - (l0 * wj + l1 * uj)).store(cj + i);
        (P2::load(cj1 + i) - (l0 * wj1 + l1 * uj1)).store(cj1 + i);
      }
      if (i < N) {
        cj[i] -= c0[i] * wj + c1[i] * uj;
        cj1[i] -= c0[i] * wj1 + c1[i] * uj1;
      }
    }
    if (j < N) {  // N odd: the last column, its diagonal entry alone
      Scalar* cj = a + j * N;
      cj[j] -= c0[j] * (c0[j] * p0) + c1[j] * (c1[j] * p1);
    }
  }
  if constexpr (N % 2 == 1) {  // the last pivot alone
    const Scalar p = a[(N - 1) * N + (N - 1)];
    if (!(p > Scalar(0))) return false;
    inverse_pivot[N - 1] = Scalar(1) / p;
  }
  for (int j = 0; j < N; ++j) {  // L = L_1 P^(1/2)
    Scalar* cj = a + j * N;
    const Scalar s = std::sqrt(cj[j]);
    cj[j] = s;
    reciprocal[j] = inverse_pivot[j] * s;
    for (int i = j + 1; i < N; ++i) cj[i] *= s;
  }
  return true;
}

template <typename Scalar, int N>
bool cholesky_in_place(Eigen::Matrix<Scalar, N, N>& m) noexcept {
  Scalar reciprocal[N];
  return cholesky_in_place(m, reciprocal);
}

/// reciprocal[k] = 1 / L_kk: what the solves below take (the Cholesky above gives it).
template <typename Scalar, int N>
void reciprocal_diagonal(const Eigen::Matrix<Scalar, N, N>& l, Scalar* reciprocal) noexcept {
  for (int k = 0; k < N; ++k) reciprocal[k] = Scalar(1) / l(k, k);
}


// The column-oriented loops below update the rows under step k's unknown: x_i -= L_ik x_k for
// i > k. Vectorized, that loop stores rows in pairs, and the next step loads the pairs it starts
// from; when step k + 1's pairs straddle step k's (one starts at an odd row, the other at an even
// one), every load waits for the stores before it to reach the cache instead of taking the value
// from the store (a store-forwarding stall, the most of a one-vector solve's time at N = 8).
// `update_from_even` runs row k + 1 alone when it is odd, so that every step's pairs start at an
// even row and each load matches the store that wrote it.
template <typename Update>
void update_from_even(int first, int end, Update update) noexcept {
  int i = first;
  if ((i & 1) != 0 && i < end) update(i++);
  for (; i < end; ++i) update(i);
}

/// Where each column of the N x K x can be nonzero: rows [first[c], end[c]) (first even, so that
/// the kernels below keep their pairs of rows; first = end = 0 for a zero column). Read as is,
/// a NaN counts as nonzero. A constraint row touches only the coordinates it depends on (a chain's
/// link two of them), and the kernels taking supports skip what is exactly zero, with the same
/// answer (up to the sign of a zero): every term they leave out is an exact zero.
template <typename Scalar, int N, int K>
void column_supports(const Eigen::Matrix<Scalar, N, K>& x, int* first, int* end) noexcept {
  for (int c = 0; c < K; ++c) {
    // The first nonzero from the top, the last from the bottom: a banded column is read about
    // once, and each scan is a compare and a branch taken the same way until it stops.
    const Scalar* xc = x.data() + c * N;
    int lo = 0;
    while (lo < N && xc[lo] == Scalar(0)) ++lo;
    int hi = N;
    while (hi > lo && xc[hi - 1] == Scalar(0)) --hi;
    first[c] = hi == lo ? 0 : lo & ~1;
    end[c] = hi == lo ? 0 : hi;
  }
}

/// out = M x for the N x K matrix M, down its columns. With kSupports (column_supports), column j
/// only over its rows [first[j], end[j]).
template <bool kSupports, typename Scalar, int N, int K>
void multiply_columns(const Eigen::Matrix<Scalar, N, K>& m, const Scalar* x, Scalar* out,
                      const int* first = nullptr, const int* end = nullptr) noexcept {
  if constexpr (kSupports) {
    for (int i = 0; i < N; ++i) out[i] = Scalar(0);
    for (int j = 0; j < K; ++j) {
      const Scalar xj = x[j];
      const Scalar* mj = m.data() + j * N;
      for (int i = first[j]; i < end[j]; ++i) out[i] += mj[i] * xj;
    }
  } else {
    for (int i = 0; i < N; ++i) out[i] = m(i, 0) * x[0];
    for (int j = 1; j < K; ++j)
      for (int i = 0; i < N; ++i) out[i] += m(i, j) * x[j];
  }
}

/// The supports of L^-1 x for a dense lower-triangular L from x's (column_supports): a column keeps
/// its first row and, unless it is zero, fills in down to the last row.
template <int N>
void fill_in_below(int* end, int columns) noexcept {
  for (int c = 0; c < columns; ++c) end[c] = end[c] == 0 ? 0 : N;
}

/// x_c = L^-1 x_c for the kColumns columns of N entries at column(c) (forward substitution,
/// column-oriented), reciprocal[k] = 1 / L_kk. With `first` (see column_supports), column c is
/// known to be zero above row first[c], and so is its answer: its steps start there. The columns
/// need not be one matrix's: a right side solved beside a matrix's columns shares their steps,
/// its dependent chain hidden among theirs. kPairs selects the path (by default one step at a time
/// for one or two columns, two at a time for more); each column's arithmetic is the same expressions
/// on either path whatever the other columns, so a column solved alone by the path of a wider call
/// gets that call's answer bit for bit (with the compiler contracting the same expressions alike).
template <int kColumns, bool kPairs = (kColumns > 2), typename Scalar, int N, typename Column>
void solve_lower_columns(const Eigen::Matrix<Scalar, N, N>& l, const Scalar* reciprocal, Column column,
                         const int* first = nullptr) noexcept {
  const Scalar* a = l.data();
  if constexpr (!kPairs) {
    for (int k = 0; k < N; ++k) {  // step k for every column: independent chains side by side
      const Scalar* ck = a + k * N;
      for (int c = 0; c < kColumns; ++c) {
        if (first != nullptr && k < first[c]) continue;
        Scalar* xc = column(c);
        const Scalar v = xc[k] * reciprocal[k];
        xc[k] = v;
        update_from_even(k + 1, N, [&](int i) { xc[i] -= ck[i] * v; });
      }
    }
  } else {
    // Many columns (B^T = L^-1 D^T), or one solved by their path: two steps at a time, the 2 x 2
    // diagonal block and then one rank-2 update of the rows below, so that each entry is loaded
    // and stored once per two steps (one step at a time, the stores bound the loop). The other
    // columns' work hides the store-forwarding stall that update_from_even avoids for one or two
    // columns.
    int k = 0;
    for (; k + 1 < N; k += 2) {
      const Scalar* c0 = a + k * N;
      const Scalar* c1 = c0 + N;
      for (int c = 0; c < kColumns; ++c) {
        if (first != nullptr && k < first[c]) continue;  // first[c] is even
        Scalar* xc = column(c);
        const Scalar v0 = xc[k] * reciprocal[k];
        const Scalar v1 = (xc[k + 1] - c0[k + 1] * v0) * reciprocal[k + 1];
        xc[k] = v0;
        xc[k + 1] = v1;
        for (int i = k + 2; i < N; ++i) xc[i] -= c0[i] * v0 + c1[i] * v1;
      }
    }
    if (k < N)  // N odd: the last row
      for (int c = 0; c < kColumns; ++c) column(c)[k] *= reciprocal[k];
  }
}

/// x = L^-1 x for every column of x (solve_lower_columns).
template <typename Scalar, int N, int K, int Options, int MaxRows, int MaxCols>
void solve_lower_in_place(const Eigen::Matrix<Scalar, N, N>& l, const Scalar* reciprocal,
                          Eigen::Matrix<Scalar, N, K, Options, MaxRows, MaxCols>& x,
                          const int* first = nullptr) noexcept {
  static_assert(N == 1 || K == 1 || !(Options & Eigen::RowMajor), "column-major right sides");
  solve_lower_columns<K>(l, reciprocal, [&x](int c) { return x.data() + c * N; }, first);
}

/// x = L^-1 x and r = L^-1 r in one substitution: r is one more column beside x's, its steps from
/// row 0 (`first` describes x's columns alone). r's dependent chain, a one-vector solve's whole
/// cost, runs beside x's columns instead of after them. solve_lower_columns<1, (K + 1 > 2)> on r
/// alone takes the same path and gives r's answer bit for bit.
template <typename Scalar, int N, int K>
[[gnu::always_inline]] inline void solve_lower_in_place(const Eigen::Matrix<Scalar, N, N>& l, const Scalar* reciprocal,
                                                        Eigen::Matrix<Scalar, N, K>& x, Eigen::Matrix<Scalar, N, 1>& r,
                                                        const int* first = nullptr) noexcept {
  Scalar* columns[K + 1];
  int from[K + 1];
  for (int c = 0; c < K; ++c) {
    columns[c] = x.data() + c * N;
    from[c] = first != nullptr ? first[c] : 0;
  }
  columns[K] = r.data();
  from[K] = 0;
  solve_lower_columns<K + 1>(l, reciprocal, [&columns](int c) { return columns[c]; },
                             first != nullptr ? from : nullptr);
}

template <typename Scalar, int N, int K, int Options, int MaxRows, int MaxCols>
void solve_lower_in_place(const Eigen::Matrix<Scalar, N, N>& l,
                          Eigen::Matrix<Scalar, N, K, Options, MaxRows, MaxCols>& x) noexcept {
  Scalar reciprocal[N];
  reciprocal_diagonal(l, reciprocal);
  solve_lower_in_place(l, reciprocal, x);
}

/// x = L^-T x for every column of x (back substitution: dot products down L's columns),
/// reciprocal[k] = 1 / L_kk. Each
/// unknown's sum runs from the last row up in two partial sums and takes the newest unknown,
/// x_(k+1), last: the terms of the older unknowns are summed while x_(k+1) is still being
/// computed, so the dependent path from one unknown to the next is one multiply-add, a
/// subtraction and a multiplication rather than the whole sum.
template <typename Scalar, int N, int K, int Options, int MaxRows, int MaxCols>
void solve_lower_transposed_in_place(const Eigen::Matrix<Scalar, N, N>& l, const Scalar* reciprocal,
                                     Eigen::Matrix<Scalar, N, K, Options, MaxRows, MaxCols>& x) noexcept {
  static_assert(N == 1 || K == 1 || !(Options & Eigen::RowMajor), "column-major right sides");
  const Scalar* a = l.data();
  for (int k = N - 1; k >= 0; --k) {  // step k for every column: independent chains side by side
    const Scalar* ck = a + k * N;
    for (int c = 0; c < K; ++c) {
      Scalar* xc = x.data() + c * N;
      Scalar s0(0), s1(0);
      int i = N - 1;
      for (; i > k + 2; i -= 2) {
        s0 += ck[i] * xc[i];
        s1 += ck[i - 1] * xc[i - 1];
      }
      if (i == k + 2) s0 += ck[i] * xc[i];
      Scalar s = xc[k] - (s0 + s1);
      if (k + 1 < N) s -= ck[k + 1] * xc[k + 1];
      xc[k] = s * reciprocal[k];
    }
  }
}

template <typename Scalar, int N, int K, int Options, int MaxRows, int MaxCols>
void solve_lower_transposed_in_place(const Eigen::Matrix<Scalar, N, N>& l,
                                     Eigen::Matrix<Scalar, N, K, Options, MaxRows, MaxCols>& x) noexcept {
  Scalar reciprocal[N];
  reciprocal_diagonal(l, reciprocal);
  solve_lower_transposed_in_place(l, reciprocal, x);
}

/// x = L x for every column of x. Step k (from the last) reads x_k before any later step changes
/// it, so the product runs in place down L's columns.
template <typename Scalar, int N, int K, int Options, int MaxRows, int MaxCols>
void multiply_lower_in_place(const Eigen::Matrix<Scalar, N, N>& l,
                             Eigen::Matrix<Scalar, N, K, Options, MaxRows, MaxCols>& x) noexcept {
  static_assert(N == 1 || K == 1 || !(Options & Eigen::RowMajor), "column-major right sides");
  const Scalar* a = l.data();
  for (int k = N - 1; k >= 0; --k) {  // step k for every column side by side
    const Scalar* ck = a + k * N;
    for (int c = 0; c < K; ++c) {
      Scalar* xc = x.data() + c * N;
      const Scalar v = xc[k];
      xc[k] = ck[k] * v;
      update_from_even(k + 1, N, [&](int i) { xc[i] += ck[i] * v; });
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

/// g = x^T x (both triangles) for the N x K x. Its lower triangle in 2 x 2 blocks of columns:
/// four dot products side by side, each in two partial sums (even and odd rows), so that each
/// loaded pair of entries serves two products and the sums vectorize without reordering. With
/// supports (column_supports), a block's sums run only over the rows where both of its pairs of
/// columns can be nonzero.
template <typename Scalar, int N, int K>
void gram(const Eigen::Matrix<Scalar, N, K>& x, Eigen::Matrix<Scalar, K, K>& g, const int* first = nullptr,
          const int* end = nullptr) noexcept {
  const Scalar* d = x.data();
  const auto block = [&](int i, int j, int rows, int cols) {  // g(i.., j..) for rows, cols <= 2
    const int i1 = i + rows - 1, j1 = j + cols - 1;
    int from = 0, to = N;
    if (first != nullptr) {
      from = std::max(std::min(first[i], first[i1]), std::min(first[j], first[j1]));
      to = std::min(std::max(end[i], end[i1]), std::max(end[j], end[j1]));
    }
    const Scalar* xi0 = d + i * N;
    const Scalar* xi1 = d + i1 * N;
    const Scalar* xj0 = d + j * N;
    const Scalar* xj1 = d + j1 * N;
    using P2 = detail::Pair<Scalar>;  // (even rows' sum, odd rows' sum)
    P2 s00 = P2::zero(), s01 = P2::zero(), s10 = P2::zero(), s11 = P2::zero();
    int k = from;  // even
    for (; k + 1 < to; k += 2) {
      const P2 a0 = P2::load(xi0 + k), a1 = P2::load(xi1 + k), b0 = P2::load(xj0 + k), b1 = P2::load(xj1 + k);
      s00 = s00 + a0 * b0;
      s01 = s01 + a0 * b1;
      s10 = s10 + a1 * b0;
      s11 = s11 + a1 * b1;
    }
    Scalar t[4][2];
    s00.store(t[0]), s01.store(t[1]), s10.store(t[2]), s11.store(t[3]);
    if (k < to) {
      t[0][0] += xi0[k] * xj0[k];
      t[1][0] += xi0[k] * xj1[k];
      t[2][0] += xi1[k] * xj0[k];
      t[3][0] += xi1[k] * xj1[k];
    }
    g(i, j) = t[0][0] + t[0][1];
    if (cols == 2) g(i, j + 1) = t[1][0] + t[1][1];
    if (rows == 2) g(i + 1, j) = t[2][0] + t[2][1];
    if (rows == 2 && cols == 2) g(i + 1, j + 1) = t[3][0] + t[3][1];
  };
  for (int j = 0; j < K; j += 2) {
    const int cols = std::min(2, K - j);
    for (int i = j; i < K; i += 2) block(i, j, std::min(2, K - i), cols);
  }
  for (int j = 1; j < K; ++j)
    for (int i = 0; i < j; ++i) g(i, j) = g(j, i);
}

/// The lower triangle of `inverse` becomes L^-1 (its upper triangle zero), given L's diagonal's
/// reciprocals (cholesky_in_place's); returns the sum of squares of L^-1's entries, ||L^-1||_F^2.
/// Column c of L^-1 solves L z = e_c and is zero above row c: solve_lower_in_place on the
/// identity with those supports, two steps at a time (written out up to 2 x 2).
template <typename Scalar, int N>
Scalar invert_lower(const Eigen::Matrix<Scalar, N, N>& l, const Scalar* reciprocal,
                    Eigen::Matrix<Scalar, N, N>& inverse) noexcept {
  if constexpr (N <= 2) {
    inverse.setZero();
    inverse(0, 0) = reciprocal[0];
    if constexpr (N == 2) {
      inverse(1, 1) = reciprocal[1];
      inverse(1, 0) = -(l(1, 0) * reciprocal[0]) * reciprocal[1];
    }
  } else {
    inverse.setIdentity();
    int first[N];
    for (int c = 0; c < N; ++c) first[c] = c & ~1;  // even, as the kernel's pairs of rows need
    solve_lower_in_place(l, reciprocal, inverse, first);
  }
  return squared_norm(inverse.data(), N * N);
}

/// The same, taking the diagonal's reciprocals itself.
template <typename Scalar, int N>
Scalar invert_lower(const Eigen::Matrix<Scalar, N, N>& l, Eigen::Matrix<Scalar, N, N>& inverse) noexcept {
  Scalar reciprocal[N];
  reciprocal_diagonal(l, reciprocal);
  return invert_lower(l, reciprocal, inverse);
}

}  // namespace gausstrack::small_dense
