// Checks a user's model before it drives anything: its constraint rows (hand-written or derived)
// against finite differences of the constraint along the motion, its mass matrix, and the
// finiteness of everything it returns. Not for the real-time path: it builds a readable report.
//
// Along the motion q(s) = q + q' s + q'' s^2 / 2, q'(s) = q' + q'' s, t(s) = t + s, for any q'':
//   d e / ds   = e'              (rows with a position error: holonomic, or hand-written with e)
//   d e' / ds  = D q'' - g       (every row with a velocity-level error e')
//   d e' / dq' = D               (e' is affine in q' for every Pfaffian constraint)
// The derivatives are taken by fourth-order central differences at s = 0, so a wrong D, g, e' or
// a sign error shows as a mismatch far above the differencing error. Hand-written rows that give
// neither e nor e' cannot be checked this way; the report says so.
// Then A must be symmetric and positive definite (Cholesky succeeds), and A, f, Q, D, g, e, e'
// must be finite.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "gausstrack/model.hpp"
#include "gausstrack/small_dense.hpp"

namespace gausstrack {

template <typename Scalar>
struct ModelCheckOptions {
  /// Differencing step, relative to 1 + |q| + |q'| + |t|.
  Scalar step = std::numeric_limits<Scalar>::digits > 24 ? Scalar(1e-3) : Scalar(3e-2);
  /// A derivative mismatch passes when below tolerance * (1 + the size of the quantities).
  Scalar tolerance = std::numeric_limits<Scalar>::digits > 24 ? Scalar(1e-6) : Scalar(2e-2);
};

/// Outcome of check_model at one state. `ok()` when every check passed; `text` says what was
/// checked and, for each failure, the row, the quantity and the two values that disagree.
struct ModelCheckReport {
  int failures = 0;
  int unchecked_rows = 0;              ///< hand-written rows with neither e nor e'
  double worst_rate_mismatch = 0;      ///< |d e/ds - e'|, relative
  double worst_rhs_mismatch = 0;       ///< |d e'/ds - (D q'' - g)|, relative
  double worst_matrix_mismatch = 0;    ///< |d e'/dq' - D|, relative
  double asymmetry = 0;                ///< max |A - A^T| / max |A|
  bool mass_matrix_positive_definite = false;
  bool all_finite = false;
  std::string text;

  bool ok() const noexcept { return failures == 0; }
};

namespace detail {
inline void appendf(std::string& s, const char* format, double a, double b = 0, double c = 0, double d = 0) {
  char line[256];
  std::snprintf(line, sizeof line, format, a, b, c, d);
  s += line;
}
}  // namespace detail

/// Checks model `m` at (q, q', t), moving along the motion with acceleration `qdd` (any
/// acceleration: a generic one such as a random vector exercises every entry of D).
template <Model M>
ModelCheckReport check_model(const M& m, const Eigen::Matrix<typename M::Scalar, M::kDof, 1>& q,
                             const Eigen::Matrix<typename M::Scalar, M::kDof, 1>& qd,
                             const Eigen::Matrix<typename M::Scalar, M::kDof, 1>& qdd, typename M::Scalar t,
                             const ModelCheckOptions<typename M::Scalar>& options = {}) {
  using S = typename M::Scalar;
  constexpr int N = M::kDof;
  constexpr int P = M::kConstraints;
  using Layout = RowLayout<M>;
  using VectorN = Eigen::Matrix<S, N, 1>;
  using VectorP = Eigen::Matrix<S, P, 1>;
  ModelCheckReport r;
  std::string& out = r.text;

  TermsOf<M> at;
  evaluate_model(m, q, qd, t, at);
  r.all_finite = at.mass_matrix.allFinite() && at.nonlinear_force.allFinite() && at.applied_force.allFinite() &&
                 at.constraint_matrix.allFinite() && at.constraint_rhs.allFinite() &&
                 at.constraint_error.allFinite() && at.constraint_error_rate.allFinite();
  if (!r.all_finite) {
    ++r.failures;
    out += "FAIL  non-finite output:";
    if (!at.mass_matrix.allFinite()) out += " A";
    if (!at.nonlinear_force.allFinite()) out += " f";
    if (!at.applied_force.allFinite()) out += " Q";
    if (!at.constraint_matrix.allFinite()) out += " D";
    if (!at.constraint_rhs.allFinite()) out += " g";
    if (!at.constraint_error.allFinite()) out += " e";
    if (!at.constraint_error_rate.allFinite()) out += " e'";
    out += "\n";
    return r;
  }

  const S a_max = at.mass_matrix.cwiseAbs().maxCoeff();
  r.asymmetry = a_max > S(0) ? double((at.mass_matrix - at.mass_matrix.transpose()).cwiseAbs().maxCoeff() / a_max)
                             : 0.0;
  Eigen::Matrix<S, N, N> factor = at.mass_matrix;
  r.mass_matrix_positive_definite =
      small_dense::cholesky_in_place(factor) && small_dense::all_finite(factor.data(), N * N);
  const double symmetric_tol = 100 * double(std::numeric_limits<S>::epsilon());
  if (r.asymmetry > symmetric_tol) {
    ++r.failures;
    detail::appendf(out, "FAIL  A is not symmetric: max |A - A^T| / max |A| = %.3g\n", r.asymmetry);
  } else if (!r.mass_matrix_positive_definite) {
    ++r.failures;
    out += "FAIL  A is not positive definite (Cholesky failed)\n";
  } else {
    out += "ok    A symmetric positive definite\n";
  }
  if constexpr (kMassMatrixOf<M> == MassMatrix::kDiagonal) {
    // The solver reads a declared-diagonal A on its diagonal only: anything else would be ignored.
    Eigen::Matrix<S, N, N> off = at.mass_matrix;
    off.diagonal().setZero();
    const S off_max = off.cwiseAbs().maxCoeff();
    if (off_max != S(0)) {
      ++r.failures;
      detail::appendf(out, "FAIL  A is declared diagonal (kMassMatrix) but max |A_ij|, i != j, = %.3g\n", double(off_max));
    } else {
      out += "ok    A diagonal, as declared\n";
    }
  }

  // Terms along the motion.
  const S h = options.step * (S(1) + q.cwiseAbs().maxCoeff() + qd.cwiseAbs().maxCoeff() + std::abs(t));
  auto along = [&](S s) {
    TermsOf<M> x;
    const VectorN qs = q + qd * s + qdd * (s * s / S(2));
    const VectorN qds = qd + qdd * s;
    evaluate_model(m, qs, qds, t + s, x);
    return x;
  };
  const TermsOf<M> p1 = along(h), m1 = along(-h), p2 = along(2 * h), m2 = along(-2 * h);
  auto derivative = [&](const VectorP& fp1, const VectorP& fm1, const VectorP& fp2, const VectorP& fm2) -> VectorP {
    return (S(8) * (fp1 - fm1) - (fp2 - fm2)) / (S(12) * h);
  };
  const VectorP de = derivative(p1.constraint_error, m1.constraint_error, p2.constraint_error, m2.constraint_error);
  const VectorP drate = derivative(p1.constraint_error_rate, m1.constraint_error_rate, p2.constraint_error_rate,
                                   m2.constraint_error_rate);
  const VectorP rhs_expected = at.constraint_matrix * qdd - at.constraint_rhs;

  // d e'/dq' by differences in each velocity direction.
  Eigen::Matrix<S, P, N> d_fd;
  const S hv = options.step * (S(1) + qd.cwiseAbs().maxCoeff());
  for (int j = 0; j < N; ++j) {
    auto rate_at = [&](S s) {
      TermsOf<M> x;
      VectorN qds = qd;
      qds(j) += s;
      evaluate_model(m, q, qds, t, x);
      return VectorP(x.constraint_error_rate);
    };
    d_fd.col(j) = (S(8) * (rate_at(hv) - rate_at(-hv)) - (rate_at(2 * hv) - rate_at(-2 * hv))) / (S(12) * hv);
  }

  auto kind = [](int i) {
    if (i < Layout::kHolonomic) return "holonomic";
    if (i < Layout::kFirstAcceleration) return "nonholonomic";
    return "hand-written";
  };
  const double tol = double(options.tolerance);
  for (int i = 0; i < P; ++i) {
    const bool hand = i >= Layout::kFirstAcceleration;
    const bool has_e = i < Layout::kHolonomic ||
                       (hand && (at.constraint_error(i) != S(0) || p1.constraint_error(i) != S(0)));
    const bool has_rate = !hand || at.constraint_error_rate(i) != S(0) || p1.constraint_error_rate(i) != S(0) ||
                          has_e;
    char head[96];
    std::snprintf(head, sizeof head, "row %d (%s)", i, kind(i));
    if (!has_rate) {
      ++r.unchecked_rows;
      out += std::string("skip  ") + head + ": gives neither e nor e', D and g not checked\n";
      continue;
    }
    bool row_ok = true;
    if (has_e) {
      const double scale = 1 + std::abs(double(at.constraint_error_rate(i))) + std::abs(double(de(i)));
      const double mismatch = std::abs(double(de(i) - at.constraint_error_rate(i))) / scale;
      r.worst_rate_mismatch = std::max(r.worst_rate_mismatch, mismatch);
      if (!(mismatch <= tol)) {
        row_ok = false;
        detail::appendf(out, ("FAIL  " + std::string(head) + ": de/ds = %.10g but e' = %.10g (relative %.2g)\n").c_str(),
                        double(de(i)), double(at.constraint_error_rate(i)), mismatch);
      }
    }
    {
      const double scale = 1 + std::abs(double(rhs_expected(i))) + std::abs(double(drate(i))) +
                           double(at.constraint_matrix.row(i).cwiseAbs().sum() * qdd.cwiseAbs().maxCoeff());
      const double mismatch = std::abs(double(drate(i) - rhs_expected(i))) / scale;
      r.worst_rhs_mismatch = std::max(r.worst_rhs_mismatch, mismatch);
      if (!(mismatch <= tol)) {
        row_ok = false;
        detail::appendf(out,
                        ("FAIL  " + std::string(head) + ": de'/ds = %.10g but D q'' - g = %.10g (relative %.2g): "
                                                        "g or D is wrong\n").c_str(),
                        double(drate(i)), double(rhs_expected(i)), mismatch);
      }
    }
    for (int j = 0; j < N; ++j) {
      const double scale = 1 + std::abs(double(at.constraint_matrix(i, j)));
      const double mismatch = std::abs(double(d_fd(i, j) - at.constraint_matrix(i, j))) / scale;
      r.worst_matrix_mismatch = std::max(r.worst_matrix_mismatch, mismatch);
      if (!(mismatch <= tol)) {
        row_ok = false;
        char what[64];
        std::snprintf(what, sizeof what, ": de'/dq'_%d = ", j);
        detail::appendf(out, ("FAIL  " + std::string(head) + what + "%.10g but D = %.10g (relative %.2g)\n").c_str(),
                        double(d_fd(i, j)), double(at.constraint_matrix(i, j)), mismatch);
      }
    }
    if (row_ok) out += std::string("ok    ") + head + ": D, g" + (has_e ? ", e'" : "") + " agree with differences\n";
    else ++r.failures;
  }
  out += r.failures == 0 ? "PASS " : "FAIL ";
  detail::appendf(out, "%.0f failure(s); worst relative mismatch: e' %.2g, D q'' - g %.2g",
                  double(r.failures), r.worst_rate_mismatch, r.worst_rhs_mismatch);
  detail::appendf(out, ", D %.2g\n", r.worst_matrix_mismatch);
  return r;
}

}  // namespace gausstrack
