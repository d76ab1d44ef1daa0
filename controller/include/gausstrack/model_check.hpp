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
#include <utility>

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

// Every output finite; if not, the report names the terms that are not.
template <Model M>
bool check_finite(const TermsOf<M>& at, ModelCheckReport& r) {
  const std::pair<bool, const char*> terms[] = {
      {at.mass_matrix.allFinite(), " A"},           {at.nonlinear_force.allFinite(), " f"},
      {at.applied_force.allFinite(), " Q"},         {at.constraint_matrix.allFinite(), " D"},
      {at.constraint_rhs.allFinite(), " g"},        {at.constraint_error.allFinite(), " e"},
      {at.constraint_error_rate.allFinite(), " e'"}};
  r.all_finite = std::all_of(std::begin(terms), std::end(terms), [](const auto& t) { return t.first; });
  if (r.all_finite) return true;
  ++r.failures;
  r.text += "FAIL  non-finite output:";
  for (const auto& [finite, name] : terms)
    if (!finite) r.text += name;
  r.text += "\n";
  return false;
}

// A symmetric positive definite, and diagonal when the model declares it so (the solver then
// reads its diagonal only: anything else would be ignored).
template <Model M>
void check_mass_matrix(const TermsOf<M>& at, ModelCheckReport& r) {
  using S = typename M::Scalar;
  constexpr int N = M::kDof;
  const S a_max = at.mass_matrix.cwiseAbs().maxCoeff();
  r.asymmetry = a_max > S(0) ? double((at.mass_matrix - at.mass_matrix.transpose()).cwiseAbs().maxCoeff() / a_max)
                             : 0.0;
  Eigen::Matrix<S, N, N> factor = at.mass_matrix;
  r.mass_matrix_positive_definite =
      small_dense::cholesky_in_place(factor) && small_dense::all_finite(factor.data(), N * N);
  const double symmetric_tol = 100 * double(std::numeric_limits<S>::epsilon());
  if (r.asymmetry > symmetric_tol) {
    ++r.failures;
    appendf(r.text, "FAIL  A is not symmetric: max |A - A^T| / max |A| = %.3g\n", r.asymmetry);
  } else if (!r.mass_matrix_positive_definite) {
    ++r.failures;
    r.text += "FAIL  A is not positive definite (Cholesky failed)\n";
  } else {
    r.text += "ok    A symmetric positive definite\n";
  }
  if constexpr (kMassMatrixOf<M> == MassMatrix::kDiagonal) {
    Eigen::Matrix<S, N, N> off = at.mass_matrix;
    off.diagonal().setZero();
    const S off_max = off.cwiseAbs().maxCoeff();
    if (off_max != S(0)) {
      ++r.failures;
      appendf(r.text, "FAIL  A is declared diagonal (kMassMatrix) but max |A_ij|, i != j, = %.3g\n", double(off_max));
    } else {
      r.text += "ok    A diagonal, as declared\n";
    }
  }
}

// Fourth-order central differences at s = 0 along the motion (de/ds, de'/ds) and in each velocity
// direction (de'/dq'), with the terms at s = 0 and one step ahead.
template <Model M>
struct Differences {
  using S = typename M::Scalar;
  using VectorN = Eigen::Matrix<S, M::kDof, 1>;
  using VectorP = Eigen::Matrix<S, M::kConstraints, 1>;
  TermsOf<M> at, ahead;
  VectorP de, drate;
  Eigen::Matrix<S, M::kConstraints, M::kDof> drate_dqd;

  Differences(const M& m, const VectorN& q, const VectorN& qd, const VectorN& qdd, S t, S step) {
    evaluate_model(m, q, qd, t, at);
    const S h = step * (S(1) + q.cwiseAbs().maxCoeff() + qd.cwiseAbs().maxCoeff() + std::abs(t));
    auto along = [&](S s) {
      TermsOf<M> x;
      evaluate_model(m, VectorN(q + qd * s + qdd * (s * s / S(2))), VectorN(qd + qdd * s), t + s, x);
      return x;
    };
    const TermsOf<M> m1 = along(-h), p2 = along(2 * h), m2 = along(-2 * h);
    ahead = along(h);
    de = central(ahead.constraint_error, m1.constraint_error, p2.constraint_error, m2.constraint_error, h);
    drate = central(ahead.constraint_error_rate, m1.constraint_error_rate, p2.constraint_error_rate,
                    m2.constraint_error_rate, h);
    const S hv = step * (S(1) + qd.cwiseAbs().maxCoeff());
    for (int j = 0; j < M::kDof; ++j) {
      auto rate_at = [&](S s) {
        TermsOf<M> x;
        VectorN qds = qd;
        qds(j) += s;
        evaluate_model(m, q, qds, t, x);
        return VectorP(x.constraint_error_rate);
      };
      drate_dqd.col(j) = central(rate_at(hv), rate_at(-hv), rate_at(2 * hv), rate_at(-2 * hv), hv);
    }
  }

  static VectorP central(const VectorP& p1, const VectorP& m1, const VectorP& p2, const VectorP& m2, S h) {
    return (S(8) * (p1 - m1) - (p2 - m2)) / (S(12) * h);
  }
};

// Row i's e', D q'' - g and D against the differences. False when any disagrees (the report says
// which, with both values).
template <Model M>
bool check_row(int i, const char* head, bool has_e, const Differences<M>& d,
               const Eigen::Matrix<typename M::Scalar, M::kDof, 1>& qdd, double tol, ModelCheckReport& r) {
  using S = typename M::Scalar;
  const TermsOf<M>& at = d.at;
  bool row_ok = true;
  auto report = [&](double mismatch, double& worst, const std::string& format, double a, double b) {
    worst = std::max(worst, mismatch);
    if (mismatch <= tol) return;
    row_ok = false;
    appendf(r.text, ("FAIL  " + std::string(head) + format).c_str(), a, b, mismatch);
  };
  if (has_e) {
    const S rate = at.constraint_error_rate(i);
    const double scale = 1 + std::abs(double(rate)) + std::abs(double(d.de(i)));
    report(std::abs(double(d.de(i) - rate)) / scale, r.worst_rate_mismatch,
           ": de/ds = %.10g but e' = %.10g (relative %.2g)\n", double(d.de(i)), double(rate));
  }
  const S expected = (at.constraint_matrix.row(i) * qdd)(0) - at.constraint_rhs(i);
  const double scale = 1 + std::abs(double(expected)) + std::abs(double(d.drate(i))) +
                       double(at.constraint_matrix.row(i).cwiseAbs().sum() * qdd.cwiseAbs().maxCoeff());
  report(std::abs(double(d.drate(i) - expected)) / scale, r.worst_rhs_mismatch,
         ": de'/ds = %.10g but D q'' - g = %.10g (relative %.2g): g or D is wrong\n", double(d.drate(i)),
         double(expected));
  for (int j = 0; j < M::kDof; ++j) {
    const S entry = at.constraint_matrix(i, j);
    const std::string column = ": de'/dq'_" + std::to_string(j) + " = %.10g but D = %.10g (relative %.2g)\n";
    report(std::abs(double(d.drate_dqd(i, j) - entry)) / (1 + std::abs(double(entry))), r.worst_matrix_mismatch, column,
           double(d.drate_dqd(i, j)), double(entry));
  }
  return row_ok;
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
  using Layout = RowLayout<M>;
  ModelCheckReport r;
  const detail::Differences<M> d(m, q, qd, qdd, t, options.step);
  if (!detail::check_finite<M>(d.at, r)) return r;
  detail::check_mass_matrix<M>(d.at, r);
  for (int i = 0; i < M::kConstraints; ++i) {
    const bool hand = i >= Layout::kFirstAcceleration;
    const bool has_e = i < Layout::kHolonomic ||
                       (hand && (d.at.constraint_error(i) != S(0) || d.ahead.constraint_error(i) != S(0)));
    const bool has_rate = !hand || has_e || d.at.constraint_error_rate(i) != S(0) ||
                          d.ahead.constraint_error_rate(i) != S(0);
    const char* kind = i < Layout::kHolonomic ? "holonomic" : hand ? "hand-written" : "nonholonomic";
    char head[96];
    std::snprintf(head, sizeof head, "row %d (%s)", i, kind);
    if (!has_rate) {
      ++r.unchecked_rows;
      r.text += std::string("skip  ") + head + ": gives neither e nor e', D and g not checked\n";
    } else if (detail::check_row<M>(i, head, has_e, d, qdd, double(options.tolerance), r)) {
      r.text += std::string("ok    ") + head + ": D, g" + (has_e ? ", e'" : "") + " agree with differences\n";
    } else {
      ++r.failures;
    }
  }
  r.text += r.failures == 0 ? "PASS " : "FAIL ";
  detail::appendf(r.text, "%.0f failure(s); worst relative mismatch: e' %.2g, D q'' - g %.2g", double(r.failures),
                  r.worst_rate_mismatch, r.worst_rhs_mismatch);
  detail::appendf(r.text, ", D %.2g\n", r.worst_matrix_mismatch);
  return r;
}

}  // namespace gausstrack
