// Forward-mode automatic differentiation for constraints written in their natural form.
//
// A Jet<S, N> carries, for one intermediate quantity x of a user's constraint function:
//   v    its value,
//   d    its gradient with respect to N seeded variables (fixed size, no allocation), stored
//        on its support [lo, hi) only (see Jet),
//   t1   its first derivative along one direction s,
//   t2   its second derivative along that direction,
// so one evaluation of phi(q, t) on jets seeded with d q_i = e_i and the direction (q', 1) in
// (q, t) gives, in a single pass and without a Hessian:
//   D = phi_q (the rows' d),  e' = phi_q q' + phi_t (t1),
//   g = -(q'^T phi_qq q' + 2 phi_qt q' + phi_tt) = -t2.
// The gradient part follows the first-order chain rule; (v, t1, t2) is truncated Taylor
// arithmetic in s (x(s) = v + t1 s + t2 s^2 / 2).
//
// Why our own type and not Eigen's unsupported AutoDiffScalar: AutoDiffScalar gives first
// derivatives only, so g needs a second, nested pass (an AutoDiffScalar along (q', 1) whose value
// and derivative are themselves AutoDiffScalars) beside the pass for D, e and e'; every operation
// of the nested pass also carries AutoDiffScalar's expression machinery. Ours gets all four in one
// pass of plain arithmetic. bench/controller/natural_form_bench.cpp measures both on the same
// constraints (the pendulum's length, the arm's hand) and checks they give the same rows: both
// are allocation-free for fixed sizes; their times are in docs/performance.md ("Constraints in
// their natural form"). AutoDiffScalar's gradients are dense; ours carry their support, which is
// what keeps the cost of a constraint of a long chain, or of a trajectory in t, independent of N.
//
// Functions a constraint may use: + - * / with jets and scalars, and sin, cos, tan, exp, log,
// sqrt, pow (scalar exponent), abs, atan, atan2, asin, acos, sinh, cosh, tanh, found by
// argument-dependent lookup. Write constraints as templates on the scalar type T and call these
// unqualified after `using std::sin;` (and so on), so that the same code runs on S and on jets.
#pragma once

#include <Eigen/Core>
#include <cmath>

namespace gausstrack {

/// The gradient is stored on its support only: d[i] may be nonzero for lo <= i < hi, and entries
/// outside [lo, hi) are zero and never read (nor written: they hold no value). Seeds have one entry
/// (d q_i = e_i), a function of t alone has none, and an operation's support is the union (the
/// smallest interval holding both), so that a constraint on a few coordinates of a long chain
/// costs a few entries per operation, not N, and a trajectory s(t) costs none. Up to kDenseUpTo
/// variables the support is always all of [0, N): loops of a fixed length, which the compiler
/// unrolls, cost less there than keeping the bounds (bench/controller: the arm's jet and the
/// 8-mass chain's terms).
template <typename S, int N>
struct Jet {
  static constexpr int kDenseUpTo = 8;
  static constexpr bool kSparse = N > kDenseUpTo;
  using Gradient = Eigen::Matrix<S, N, 1>;
  S v = S(0);
  S t1 = S(0);
  S t2 = S(0);
  int lo = 0, hi = kSparse ? 0 : N;  ///< the gradient's support [lo, hi)
  S d[N];                            ///< the gradient, on [lo, hi) only

  Jet() noexcept { clear_dense(); }
  Jet(S value) noexcept : v(value) { clear_dense(); }  // NOLINT(google-explicit-constructor): constants mix with jets
  /// No gradient, with the derivatives along the direction.
  Jet(S value, S first, S second) noexcept : v(value), t1(first), t2(second) { clear_dense(); }
  /// Makes this jet the seed of variable i: value, gradient e_i, derivatives (first, 0).
  void seed(S value, int i, S first) noexcept {
    v = value, t1 = first, t2 = S(0);
    if constexpr (kSparse) {
      lo = i;
      hi = i + 1;
    } else {
      clear_dense();
    }
    d[i] = S(1);
  }
  Jet(const Jet& o) noexcept : v(o.v), t1(o.t1), t2(o.t2), lo(o.lo), hi(o.hi) { copy_gradient(o); }
  Jet& operator=(const Jet& o) noexcept {
    v = o.v, t1 = o.t1, t2 = o.t2, lo = o.lo, hi = o.hi;
    copy_gradient(o);
    return *this;
  }

  /// d x / d q_i (zero outside the support).
  S partial(int i) const noexcept { return i >= lo && i < hi ? d[i] : S(0); }
  /// The whole gradient.
  Gradient gradient() const noexcept {
    Gradient g = Gradient::Zero();
    for (int i = lo; i < hi; ++i) g(i) = d[i];
    return g;
  }

  Jet& operator+=(const Jet& b) { return *this = *this + b; }
  Jet& operator-=(const Jet& b) { return *this = *this - b; }
  Jet& operator*=(const Jet& b) { return *this = *this * b; }
  Jet& operator/=(const Jet& b) { return *this = *this / b; }

 private:
  void clear_dense() noexcept {
    if constexpr (!kSparse)
      for (int i = 0; i < N; ++i) d[i] = S(0);
  }
  void copy_gradient(const Jet& o) noexcept {
    if constexpr (kSparse) {
      // Short supports entry by entry: a loop would become a call to memcpy, which costs more
      // than the copy of one or two entries.
      if (hi - lo <= 2) {
        if (hi > lo) d[lo] = o.d[lo];
        if (hi > lo + 1) d[lo + 1] = o.d[lo + 1];
        return;
      }
      for (int i = lo; i < hi; ++i) d[i] = o.d[i];
    } else {
      for (int i = 0; i < N; ++i) d[i] = o.d[i];
    }
  }
};

namespace detail {
// r's gradient = a x's (r is not x).
template <typename S, int N>
inline void set_scaled(Jet<S, N>& r, S a, const Jet<S, N>& x) {
  if constexpr (!Jet<S, N>::kSparse) {
    for (int i = 0; i < N; ++i) r.d[i] = a * x.d[i];
  } else {
    r.lo = x.lo;
    r.hi = x.hi;
    for (int i = x.lo; i < x.hi; ++i) r.d[i] = a * x.d[i];
  }
}
// r's gradient = a x's + b y's over the union of their supports (r is neither).
template <typename S, int N>
inline void set_combined(Jet<S, N>& r, S a, const Jet<S, N>& x, S b, const Jet<S, N>& y) {
  if constexpr (!Jet<S, N>::kSparse) {
    for (int i = 0; i < N; ++i) r.d[i] = a * x.d[i] + b * y.d[i];
  } else {
    if (y.lo == y.hi) return set_scaled(r, a, x);
    if (x.lo == x.hi) return set_scaled(r, b, y);
    if (x.lo == y.lo && x.hi == y.hi) {
      r.lo = x.lo;
      r.hi = x.hi;
      for (int i = x.lo; i < x.hi; ++i) r.d[i] = a * x.d[i] + b * y.d[i];
      return;
    }
    r.lo = x.lo < y.lo ? x.lo : y.lo;
    r.hi = x.hi > y.hi ? x.hi : y.hi;
    for (int i = r.lo; i < r.hi; ++i) {
      S sum(0);
      if (i >= x.lo && i < x.hi) sum += a * x.d[i];
      if (i >= y.lo && i < y.hi) sum += b * y.d[i];
      r.d[i] = sum;
    }
  }
}
}  // namespace detail

// Chain rule for y = f(x) given f(v), f'(v), f''(v).
template <typename S, int N>
inline Jet<S, N> chain(const Jet<S, N>& x, S f, S df, S ddf) {
  Jet<S, N> r(f, df * x.t1, ddf * x.t1 * x.t1 + df * x.t2);
  detail::set_scaled(r, df, x);
  return r;
}

template <typename S, int N>
inline Jet<S, N> operator+(const Jet<S, N>& a) { return a; }
template <typename S, int N>
inline Jet<S, N> operator-(const Jet<S, N>& a) {
  Jet<S, N> r(-a.v, -a.t1, -a.t2);
  detail::set_scaled(r, S(-1), a);
  return r;
}
template <typename S, int N>
inline Jet<S, N> operator+(const Jet<S, N>& a, const Jet<S, N>& b) {
  Jet<S, N> r(a.v + b.v, a.t1 + b.t1, a.t2 + b.t2);
  detail::set_combined(r, S(1), a, S(1), b);
  return r;
}
template <typename S, int N>
inline Jet<S, N> operator-(const Jet<S, N>& a, const Jet<S, N>& b) {
  Jet<S, N> r(a.v - b.v, a.t1 - b.t1, a.t2 - b.t2);
  detail::set_combined(r, S(1), a, S(-1), b);
  return r;
}
template <typename S, int N>
inline Jet<S, N> operator*(const Jet<S, N>& a, const Jet<S, N>& b) {
  Jet<S, N> r(a.v * b.v, a.v * b.t1 + a.t1 * b.v, a.v * b.t2 + S(2) * a.t1 * b.t1 + a.t2 * b.v);
  detail::set_combined(r, b.v, a, a.v, b);
  return r;
}
template <typename S, int N>
inline Jet<S, N> operator/(const Jet<S, N>& a, const Jet<S, N>& b) {
  const S inv = S(1) / b.v;
  const S c = a.v * inv;
  const S c1 = (a.t1 - c * b.t1) * inv;
  Jet<S, N> r(c, c1, (a.t2 - S(2) * c1 * b.t1 - c * b.t2) * inv);
  detail::set_combined(r, inv, a, -c * inv, b);
  return r;
}

// Mixed with plain scalars (parameters such as a length).
template <typename S, int N>
inline Jet<S, N> operator+(const Jet<S, N>& a, S b) {
  Jet<S, N> r(a);
  r.v += b;
  return r;
}
template <typename S, int N>
inline Jet<S, N> operator+(S a, const Jet<S, N>& b) { return b + a; }
template <typename S, int N>
inline Jet<S, N> operator-(const Jet<S, N>& a, S b) { return a + (-b); }
template <typename S, int N>
inline Jet<S, N> operator-(S a, const Jet<S, N>& b) {
  Jet<S, N> r(a - b.v, -b.t1, -b.t2);
  detail::set_scaled(r, S(-1), b);
  return r;
}
template <typename S, int N>
inline Jet<S, N> operator*(const Jet<S, N>& a, S b) {
  Jet<S, N> r(a.v * b, a.t1 * b, a.t2 * b);
  detail::set_scaled(r, b, a);
  return r;
}
template <typename S, int N>
inline Jet<S, N> operator*(S a, const Jet<S, N>& b) { return b * a; }
template <typename S, int N>
inline Jet<S, N> operator/(const Jet<S, N>& a, S b) { return a * (S(1) / b); }
template <typename S, int N>
inline Jet<S, N> operator/(S a, const Jet<S, N>& b) { return Jet<S, N>(a) / b; }

// Comparisons look at values (for branches in user code; derivatives follow the branch taken).
template <typename S, int N>
inline bool operator<(const Jet<S, N>& a, const Jet<S, N>& b) { return a.v < b.v; }
template <typename S, int N>
inline bool operator>(const Jet<S, N>& a, const Jet<S, N>& b) { return a.v > b.v; }
template <typename S, int N>
inline bool operator<=(const Jet<S, N>& a, const Jet<S, N>& b) { return a.v <= b.v; }
template <typename S, int N>
inline bool operator>=(const Jet<S, N>& a, const Jet<S, N>& b) { return a.v >= b.v; }
template <typename S, int N>
inline bool operator==(const Jet<S, N>& a, const Jet<S, N>& b) { return a.v == b.v; }
template <typename S, int N>
inline bool operator!=(const Jet<S, N>& a, const Jet<S, N>& b) { return a.v != b.v; }

template <typename S, int N>
inline Jet<S, N> sin(const Jet<S, N>& x) {
  const S s = std::sin(x.v), c = std::cos(x.v);
  return chain(x, s, c, -s);
}
template <typename S, int N>
inline Jet<S, N> cos(const Jet<S, N>& x) {
  const S s = std::sin(x.v), c = std::cos(x.v);
  return chain(x, c, -s, -c);
}
template <typename S, int N>
inline Jet<S, N> tan(const Jet<S, N>& x) {
  const S t = std::tan(x.v), sec2 = S(1) + t * t;
  return chain(x, t, sec2, S(2) * t * sec2);
}
template <typename S, int N>
inline Jet<S, N> exp(const Jet<S, N>& x) {
  const S e = std::exp(x.v);
  return chain(x, e, e, e);
}
template <typename S, int N>
inline Jet<S, N> log(const Jet<S, N>& x) {
  const S inv = S(1) / x.v;
  return chain(x, std::log(x.v), inv, -inv * inv);
}
template <typename S, int N>
inline Jet<S, N> sqrt(const Jet<S, N>& x) {
  const S r = std::sqrt(x.v), dr = S(0.5) / r;
  return chain(x, r, dr, -dr / (S(2) * x.v));
}
template <typename S, int N>
inline Jet<S, N> pow(const Jet<S, N>& x, S p) {
  // Integer powers by products: exact, and defined at x = 0 (p (p - 1) x^(p - 2) is 0 * inf there).
  if (p == S(0)) return Jet<S, N>(S(1));
  if (p == S(1)) return x;
  if (p == S(2)) return x * x;
  if (p == S(3)) return x * x * x;
  const S f = std::pow(x.v, p);
  const S df = p * std::pow(x.v, p - S(1));
  const S ddf = p * (p - S(1)) * std::pow(x.v, p - S(2));
  return chain(x, f, df, ddf);
}
template <typename S, int N>
inline Jet<S, N> abs(const Jet<S, N>& x) { return x.v < S(0) ? -x : x; }
template <typename S, int N>
inline Jet<S, N> atan(const Jet<S, N>& x) {
  const S inv = S(1) / (S(1) + x.v * x.v);
  return chain(x, std::atan(x.v), inv, -S(2) * x.v * inv * inv);
}
template <typename S, int N>
inline Jet<S, N> asin(const Jet<S, N>& x) {
  const S inv = S(1) / std::sqrt(S(1) - x.v * x.v);
  return chain(x, std::asin(x.v), inv, x.v * inv * inv * inv);
}
template <typename S, int N>
inline Jet<S, N> acos(const Jet<S, N>& x) {
  const S inv = S(1) / std::sqrt(S(1) - x.v * x.v);
  return chain(x, std::acos(x.v), -inv, -x.v * inv * inv * inv);
}
template <typename S, int N>
inline Jet<S, N> sinh(const Jet<S, N>& x) {
  const S s = std::sinh(x.v), c = std::cosh(x.v);
  return chain(x, s, c, s);
}
template <typename S, int N>
inline Jet<S, N> cosh(const Jet<S, N>& x) {
  const S s = std::sinh(x.v), c = std::cosh(x.v);
  return chain(x, c, s, c);
}
template <typename S, int N>
inline Jet<S, N> tanh(const Jet<S, N>& x) {
  const S t = std::tanh(x.v), sech2 = S(1) - t * t;
  return chain(x, t, sech2, -S(2) * t * sech2);
}
/// atan2(y, x) with its gradient and second directional derivative (both arguments may vary).
template <typename S, int N>
inline Jet<S, N> atan2(const Jet<S, N>& y, const Jet<S, N>& x) {
  const S r2 = x.v * x.v + y.v * y.v, inv = S(1) / r2, inv2 = inv * inv;
  const S hy = x.v * inv, hx = -y.v * inv;
  const S hxx = S(2) * x.v * y.v * inv2, hyy = -hxx, hxy = (y.v * y.v - x.v * x.v) * inv2;
  Jet<S, N> r(std::atan2(y.v, x.v), hx * x.t1 + hy * y.t1,
              hx * x.t2 + hy * y.t2 + hxx * x.t1 * x.t1 + S(2) * hxy * x.t1 * y.t1 + hyy * y.t1 * y.t1);
  detail::set_combined(r, hx, x, hy, y);
  return r;
}

}  // namespace gausstrack

namespace Eigen {
template <typename S, int N>
struct NumTraits<gausstrack::Jet<S, N>> : NumTraits<S> {
  using Real = gausstrack::Jet<S, N>;
  using NonInteger = Real;
  using Nested = Real;
  using Literal = Real;
  enum {
    IsComplex = 0,
    IsInteger = 0,
    IsSigned = 1,
    RequireInitialization = 1,
    ReadCost = (N + 3) * NumTraits<S>::ReadCost,
    AddCost = (N + 3) * NumTraits<S>::AddCost,
    MulCost = (2 * N + 6) * NumTraits<S>::MulCost,
  };
  static Real epsilon() { return Real(NumTraits<S>::epsilon()); }
  static Real dummy_precision() { return Real(NumTraits<S>::dummy_precision()); }
  static Real highest() { return Real(NumTraits<S>::highest()); }
  static Real lowest() { return Real(NumTraits<S>::lowest()); }
};
template <typename S, int N, typename BinaryOp>
struct ScalarBinaryOpTraits<gausstrack::Jet<S, N>, S, BinaryOp> {
  using ReturnType = gausstrack::Jet<S, N>;
};
template <typename S, int N, typename BinaryOp>
struct ScalarBinaryOpTraits<S, gausstrack::Jet<S, N>, BinaryOp> {
  using ReturnType = gausstrack::Jet<S, N>;
};
}  // namespace Eigen
