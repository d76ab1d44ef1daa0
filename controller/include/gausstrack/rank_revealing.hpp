// Rank-revealing kernels behind the solver's fallbacks: a one-sided Jacobi SVD and a complete
// orthogonal decomposition by column-pivoted Householder QR, written once with plain loops.
//
// Why by hand: Eigen's fixed-size JacobiSVD and CompleteOrthogonalDecomposition unroll into a large
// amount of code at every size they are instantiated with, and every model pays for them because
// the strategy is chosen at run time. The SVD takes run-time sizes and is templated on the scalar
// alone (the solver's is compiled once per scalar type, whatever the models); the actuated law,
// which may take it on every call, compiles it at its own sizes (jacobi_svd_fixed). The complete
// orthogonal decomposition keeps fixed-size storage, plain loops of a few kilobytes of code per
// size.
// Nothing allocates or throws; every loop is bounded.
//
// Scaling. Each kernel first divides its matrix by a power of two near its largest entry (exact),
// so that no square of an entry or norm overflows for any finite input; singular values and
// triangular factors are scaled back at the end. (Entries far below the largest may still
// underflow when squared: they are below the kernels' accuracy of about eps times the largest.)
#pragma once

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <utility>

#include "gausstrack/small_dense.hpp"

namespace gausstrack::small_dense {

/// A power of two s with max_i |x_i| / s in [1, 2) (1 for a zero x): division by s is exact
/// unless an entry falls below the normal range.
template <typename Scalar>
Scalar power_of_two_scale(const Scalar* x, int count) noexcept {
  Scalar largest(0);
  for (int i = 0; i < count; ++i) largest = std::max(largest, std::abs(x[i]));
  if (!(largest > Scalar(0)) || !std::isfinite(largest)) return Scalar(1);
  if constexpr (detail::kHasIeeeBits<Scalar>) {
    // A normal value with its mantissa cleared is the power of two at or below it: no library
    // call (frexp and ldexp are most of this function's cost on a small matrix).
    using Bits = detail::IeeeBits<Scalar>;
    constexpr int kMantissa = std::numeric_limits<Scalar>::digits - 1;
    const Bits bits = std::bit_cast<Bits>(largest);
    if ((bits >> kMantissa) != 0) return std::bit_cast<Scalar>(bits & ~((Bits(1) << kMantissa) - 1));
  }
  int exponent = 0;  // a subnormal largest entry
  (void)std::frexp(largest, &exponent);
  return std::ldexp(Scalar(1), exponent - 1);  // max / s in [1, 2): s is representable even at the top
}

/// ||x||_2 of `count` entries without overflow or underflow of the squares: max |x_i| times the
/// norm of x / max |x_i|. For where a plain sum of squares can leave the range; slower.
template <typename Scalar>
Scalar scaled_norm(const Scalar* x, int count) noexcept {
  Scalar largest(0);
  for (int i = 0; i < count; ++i) {
    if (std::isnan(x[i])) return x[i];
    largest = std::max(largest, std::abs(x[i]));
  }
  if (!(largest > Scalar(0)) || !std::isfinite(largest)) return largest;  // 0, or infinity
  Scalar sum(0);
  for (int i = 0; i < count; ++i) sum += (x[i] / largest) * (x[i] / largest);
  return largest * std::sqrt(sum);
}

/// Most sweeps of the Jacobi SVD. Convergence is quadratic: a few sweeps at the sizes a controller
/// has (rows up to about 32); the bound only guarantees that a call ends.
inline constexpr int kMaxJacobiSweeps = 64;

/// Thin SVD of the rows x cols column-major matrix w (rows >= cols) by one-sided Jacobi rotations
/// (Hestenes' method with Rutishauser's rotation), in place: w V = U S with the columns of w made orthogonal.
/// On return w holds U (rows x cols, unit columns; a column whose singular value is 0 is zero),
/// sigma the singular values in descending order and v (cols x cols, column-major) the orthogonal
/// V, so that the input equals U diag(sigma) V^T. Singular values are accurate to about
/// eps * rows * sigma_max, small ones included (no normal equations are formed). Returns false
/// when the input or a singular value is not finite (outputs then unspecified but finite-safe).
template <typename Scalar>
bool jacobi_svd_in_place(Scalar* w, int rows, int cols, Scalar* sigma, Scalar* v) noexcept {
  const int size = rows * cols;
  for (int i = 0; i < size; ++i)
    if (!std::isfinite(w[i])) return false;
  const Scalar scale = power_of_two_scale(w, size);
  for (int i = 0; i < size; ++i) w[i] /= scale;
  for (int j = 0; j < cols; ++j)
    for (int i = 0; i < cols; ++i) v[j * cols + i] = Scalar(i == j);

  // Two columns count as orthogonal when |w_i . w_j| <= rows * eps |w_i| |w_j| (the dot product's
  // own rounding error); a zero column is orthogonal to every other.
  const Scalar tolerance = Scalar(rows) * std::numeric_limits<Scalar>::epsilon();
  for (int sweep = 0; sweep < kMaxJacobiSweeps; ++sweep) {
    bool rotated = false;
    for (int i = 0; i + 1 < cols; ++i) {
      for (int j = i + 1; j < cols; ++j) {
        Scalar* wi = w + i * rows;
        Scalar* wj = w + j * rows;
        Scalar alpha(0), beta(0), gamma(0);
        for (int k = 0; k < rows; ++k) {
          alpha += wi[k] * wi[k];
          beta += wj[k] * wj[k];
          gamma += wi[k] * wj[k];
        }
        // A column negligible against the other (its norm below eps times the other's: within
        // the accuracy above) is left alone; without this, a column whose squares underflow would
        // make the threshold 0 and keep rounding-level gamma rotating until the sweep cap.
        const Scalar eps = std::numeric_limits<Scalar>::epsilon();
        if (!(std::min(alpha, beta) > eps * eps * std::max(alpha, beta))) continue;
        if (!(std::abs(gamma) > tolerance * std::sqrt(alpha) * std::sqrt(beta))) continue;
        rotated = true;
        // The rotation by angle theta with tan(theta) = t, the smaller root of
        // t^2 + 2 zeta t - 1 = 0, makes the two columns orthogonal.
        const Scalar zeta = (beta - alpha) / (Scalar(2) * gamma);
        const Scalar t =
            std::copysign(Scalar(1), zeta) / (std::abs(zeta) + std::hypot(Scalar(1), zeta));
        const Scalar c = Scalar(1) / std::sqrt(Scalar(1) + t * t);
        const Scalar s = c * t;
        for (int k = 0; k < rows; ++k) {
          const Scalar x = wi[k], y = wj[k];
          wi[k] = c * x - s * y;
          wj[k] = s * x + c * y;
        }
        Scalar* vi = v + i * cols;
        Scalar* vj = v + j * cols;
        for (int k = 0; k < cols; ++k) {
          const Scalar x = vi[k], y = vj[k];
          vi[k] = c * x - s * y;
          vj[k] = s * x + c * y;
        }
      }
    }
    if (!rotated) break;
  }

  for (int j = 0; j < cols; ++j) {
    Scalar* wj = w + j * rows;
    Scalar norm2(0);
    for (int k = 0; k < rows; ++k) norm2 += wj[k] * wj[k];
    const Scalar norm = std::sqrt(norm2);
    sigma[j] = norm;
    for (int k = 0; k < rows; ++k) wj[k] = norm > Scalar(0) ? wj[k] / norm : Scalar(0);
  }
  // Descending order (selection sort: cols is small), columns of U and V alike.
  for (int j = 0; j < cols; ++j) {
    int best = j;
    for (int k = j + 1; k < cols; ++k)
      if (sigma[k] > sigma[best]) best = k;
    if (best == j) continue;
    std::swap(sigma[j], sigma[best]);
    for (int k = 0; k < rows; ++k) std::swap(w[j * rows + k], w[best * rows + k]);
    for (int k = 0; k < cols; ++k) std::swap(v[j * cols + k], v[best * cols + k]);
  }
  for (int j = 0; j < cols; ++j) {
    sigma[j] *= scale;
    if (!std::isfinite(sigma[j])) return false;
  }
  return true;
}

/// jacobi_svd_in_place at compile-time sizes, out of line: one body per size with every kernel
/// inlined (the rotations' loops keep their constant bounds), for a caller that may take the SVD
/// on every call, from a hot body that the SVD, dominated by its own work, would otherwise grow.
/// It costs a copy of the SVD per size; the solver's fallback, rarely taken, keeps run-time sizes.
template <int Rows, int Cols, typename Scalar>
[[gnu::noinline, gnu::flatten]] bool jacobi_svd_fixed(Scalar* w, Scalar* sigma, Scalar* v) noexcept {
  static_assert(Rows >= Cols, "the thin SVD needs rows >= columns");
  return jacobi_svd_in_place(w, Rows, Cols, sigma, v);
}

/// Householder reflector H = I - tau u u^T with u = (1, x[1:]) that maps x (length n, in place) to
/// (beta, 0, ..., 0): x[0] becomes beta and x[1:] the tail of u. tau = 0 (H = I) when x[1:] is 0.
template <typename Scalar>
Scalar make_householder_in_place(Scalar* x, int n) noexcept {
  Scalar tail2(0);
  for (int i = 1; i < n; ++i) tail2 += x[i] * x[i];
  if (!(tail2 > Scalar(0))) return Scalar(0);
  const Scalar alpha = x[0];
  const Scalar beta = -std::copysign(std::sqrt(alpha * alpha + tail2), alpha);
  const Scalar divisor = alpha - beta;
  for (int i = 1; i < n; ++i) x[i] /= divisor;
  x[0] = beta;
  return (beta - alpha) / beta;
}

/// y = H y for y of length n (stride 1), H = I - tau u u^T, u = (1, tail[0 .. n-2]).
template <typename Scalar>
void apply_householder(const Scalar* tail, Scalar tau, Scalar* y, int n) noexcept {
  if (tau == Scalar(0)) return;
  Scalar dot = y[0];
  for (int i = 1; i < n; ++i) dot += tail[i - 1] * y[i];
  dot *= tau;
  y[0] -= dot;
  for (int i = 1; i < n; ++i) y[i] -= dot * tail[i - 1];
}

/// Workspace and factors of a complete orthogonal decomposition of a rows x cols matrix
/// (rows <= cols <= MaxCols), computed by `factor_complete_orthogonal`:
///   B Pi = Q [R11 R12; 0 R22]   column-pivoted Householder QR, R22 taken as 0 (rank r)
///   [R11 R12]^T = Z [S; 0]      Householder QR of the kept rows' transpose (S: r x r, upper)
/// so that B Pi = Q [S^T 0; 0 0] Z^T and the minimum-norm least-squares solution of B y = c is
///   y = Pi Z [S^-T (Q^T c)_(1:r); 0].
template <typename Scalar, int MaxRows, int MaxCols>
struct CompleteOrthogonal {
  Scalar qr[MaxRows * MaxCols];  // R on and above the diagonal, Q's reflectors below (rows x cols)
  Scalar q_tau[MaxRows];
  Scalar z[MaxCols * MaxRows];  // S on and above the diagonal, Z's reflectors below (cols x rank)
  Scalar z_tau[MaxRows];
  int permutation[MaxCols];  // column k of B Pi is column permutation[k] of B
  Scalar scale = Scalar(1);  // B was divided by it (a power of two)
  int rows = 0, cols = 0, rank = 0;
  Scalar largest_pivot = Scalar(0), smallest_kept_pivot = Scalar(0);  // |R_kk| of B (unscaled)
};

/// Factors the column-major rows x cols matrix b (rows <= cols). The rank is the number of pivots
/// |R_kk| > relative_tolerance * max_k |R_kk|. Returns false when an input or factor is not finite.
template <typename Scalar, int MaxRows, int MaxCols>
bool factor_complete_orthogonal(const Scalar* b, int rows, int cols, Scalar relative_tolerance,
                                CompleteOrthogonal<Scalar, MaxRows, MaxCols>& f) noexcept {
  f.rows = rows;
  f.cols = cols;
  f.rank = 0;
  const int size = rows * cols;
  for (int i = 0; i < size; ++i)
    if (!std::isfinite(b[i])) return false;
  f.scale = power_of_two_scale(b, size);
  for (int i = 0; i < size; ++i) f.qr[i] = b[i] / f.scale;
  for (int j = 0; j < cols; ++j) f.permutation[j] = j;

  Scalar* a = f.qr;
  Scalar largest(0);
  for (int k = 0; k < rows; ++k) {
    // Pivot: the remaining column with the largest norm below row k (recomputed, not downdated).
    int best = k;
    Scalar best2(-1);
    for (int j = k; j < cols; ++j) {
      Scalar n2(0);
      for (int i = k; i < rows; ++i) n2 += a[j * rows + i] * a[j * rows + i];
      if (n2 > best2) best2 = n2, best = j;
    }
    if (best != k) {
      for (int i = 0; i < rows; ++i) std::swap(a[k * rows + i], a[best * rows + i]);
      std::swap(f.permutation[k], f.permutation[best]);
    }
    Scalar* ck = a + k * rows + k;
    f.q_tau[k] = make_householder_in_place(ck, rows - k);
    for (int j = k + 1; j < cols; ++j)
      apply_householder(ck + 1, f.q_tau[k], a + j * rows + k, rows - k);
    largest = std::max(largest, std::abs(ck[0]));
  }
  f.largest_pivot = largest * f.scale;
  f.smallest_kept_pivot = Scalar(0);
  if (largest > Scalar(0)) {
    // The kept pivots are the leading ones: counting stops at the first below the tolerance (the
    // pivots decrease up to rounding), so S is built from exactly the kept rows.
    for (int k = 0; k < rows; ++k) {
      const Scalar pivot = std::abs(a[k * rows + k]);
      if (!(pivot > relative_tolerance * largest)) break;
      ++f.rank;
      f.smallest_kept_pivot =
          f.smallest_kept_pivot == Scalar(0) ? pivot : std::min(f.smallest_kept_pivot, pivot);
    }
  }
  f.smallest_kept_pivot *= f.scale;

  // z = [R11 R12]^T (cols x rank): row k of R from its diagonal on, then its QR.
  const int r = f.rank;
  for (int k = 0; k < r; ++k) {
    Scalar* zk = f.z + k * cols;
    for (int j = 0; j < cols; ++j) zk[j] = j < k ? Scalar(0) : a[j * rows + k];
  }
  for (int k = 0; k < r; ++k) {
    Scalar* zk = f.z + k * cols + k;
    f.z_tau[k] = make_householder_in_place(zk, cols - k);
    for (int j = k + 1; j < r; ++j)
      apply_householder(zk + 1, f.z_tau[k], f.z + j * cols + k, cols - k);
  }
  for (int i = 0; i < size; ++i)
    if (!std::isfinite(f.qr[i])) return false;
  for (int i = 0; i < r * cols; ++i)
    if (!std::isfinite(f.z[i])) return false;
  return std::isfinite(f.largest_pivot);
}

/// y = B^+ c in the minimum-norm least-squares sense of the decomposition (rank f.rank): c has
/// f.rows entries, y f.cols; `work` holds f.rows entries.
template <typename Scalar, int MaxRows, int MaxCols>
void solve_complete_orthogonal(const CompleteOrthogonal<Scalar, MaxRows, MaxCols>& f,
                               const Scalar* c, Scalar* y, Scalar* work) noexcept {
  const int rows = f.rows, cols = f.cols, r = f.rank;
  if (r == 0) {
    for (int i = 0; i < cols; ++i) y[i] = Scalar(0);
    return;
  }
  for (int i = 0; i < rows; ++i) work[i] = c[i] / f.scale;  // (s B)^+ = B^+ / s
  // work = Q^T c: only the first r reflectors touch entries 0 .. r-1.
  for (int k = 0; k < r; ++k)
    apply_householder(f.qr + k * rows + k + 1, f.q_tau[k], work + k, rows - k);
  // x = S^-T work(1:r): forward substitution with the lower triangular S^T.
  Scalar x[MaxRows] = {};
  for (int i = 0; i < r; ++i) {
    Scalar s = work[i];
    const Scalar* zi = f.z + i * cols;  // column i of z holds column i of S above its diagonal
    for (int j = 0; j < i; ++j) s -= zi[j] * x[j];
    x[i] = s / zi[i];
  }
  // t = Z [x; 0] (Z = H_0 ... H_(r-1)), then y = Pi t.
  Scalar t[MaxCols] = {};
  for (int i = 0; i < r; ++i) t[i] = x[i];
  for (int k = r - 1; k >= 0; --k)
    apply_householder(f.z + k * cols + k + 1, f.z_tau[k], t + k, cols - k);
  for (int k = 0; k < cols; ++k) y[f.permutation[k]] = t[k];
}

}  // namespace gausstrack::small_dense
