// Explicit constrained accelerations (eq. 30) and constraint force (eq. 32) of Kalaba & Udwadia,
// J. Appl. Mech. 60 (1993), for compile-time sizes, without allocating and without throwing.
//
// Problem, at one instant (q, q', t):
//   A q'' + f = Q + Q'        A: N x N symmetric positive definite (mass matrix)  [kg, kg m^2]
//   D q'' = g                 D: P x N constraint matrix, g: P right side
// Gauss's principle (eq. 14/16): q'' minimises (A q'' + f - Q)^T A^-1 (A q'' + f - Q) subject to
// D q'' = g, equivalently Q' minimises Q'^T A^-1 Q'.
//
// Computation. With A = L L^T (Cholesky), a = A^-1 (Q - f) the unconstrained acceleration and
// B = D L^-T (P x N; it has the singular values of D A^(-1/2)):
//   Q'  = L B^+ (g - D a)                                       (eq. 32, compact form)
//   q'' = a + A^-1 Q' = a + L^-T B^+ (g - D a)                  (eq. 30)
// This is the same force as A^(1/2) (D A^(-1/2))^+ (g - D a): A^(1/2) = L U for an orthogonal U,
// so both are the Moore-Penrose (minimum A^-1-norm) answer. Eq. (32)'s two terms are the parts
// linear in (f - Q) and in g:
//   (I - A X A^-1)(f - Q) = L B^+ D A^-1 (f - Q) = L B^+ (-D a)    "force_from_impressed"
//   A (I - X) D^- g       = L B^+ g                                 "force_from_rhs"
// (They are unique whatever g-inverses eq. 32 uses, since the constrained motion is unique.)
//
// Reuse. The factorization (of A, and of B with the chosen strategy) depends on A and D alone; a
// solve whose A and D equal the previous solve's bit for bit keeps it, and so do its diagnostics
// (rank, singular values, fallback). A constant mass matrix is therefore factored once, and a
// constant A and D (a joint-space trajectory on a chain) leave only products with the factors.
// A mass matrix declared diagonal (MassMatrix::kDiagonal) is read on its diagonal only and
// "factored" by square roots: L = diag(sqrt(A_ii)).
//
// Strategies for y = B^+ r (all allocation-free for fixed sizes):
// - kCholeskyWithFallback (default): normal equations, y = B^T (B B^T)^-1 r with B B^T = D A^-1 D^T
//   factored by Cholesky. Exact Moore-Penrose answer when rank(D) = P. Its rounding error grows
//   like eps * cond(B)^2, so when the Cholesky factorization fails or its reciprocal condition
//   bound 1 / (||G||_1 ||L_G^-1||_F^2) (G = B B^T = L_G L_G^T; never above the true reciprocal
//   condition number) falls below `fallback_rcond` the call answers by kSvd instead and sets
//   warning::kFellBackToSvd.
// - kSvd: Moore-Penrose inverse by SVD: one-sided Jacobi SVD B^T = U S V^T (the singular values
//   of B, small ones to about eps * sigma_max), so B^+ = U S^+ V^T. Singular values
//   sigma_i <= rank_tolerance * sigma_max are treated as zero.
// - kCompleteOrthogonal: complete orthogonal decomposition B Pi = Q [S^T 0; 0 0] Z^T from a
//   column-pivoted Householder QR, rank decided by the same relative tolerance on the QR's
//   diagonal; minimum-norm least-squares solve.
// Both rank-revealing kernels are written with plain loops (rank_revealing.hpp) and scale B by a
// power of two first, so that any finite B is decomposed without overflow.
// - kDampedLeastSquares: y = B^T (B B^T + lambda^2 I)^-1 r. Each singular direction sigma_i of B
//   meets only sigma_i^2 / (sigma_i^2 + lambda^2) of its constraint, so D q'' = g holds with a
//   relative error of about lambda^2 / sigma_min^2 in exchange for a force bounded by
//   |r| / (2 lambda) near singular configurations. The normal equations answer under the same
//   condition test as the default; when B B^T + lambda^2 I fails it, the same filter is applied
//   through the SVD, y = sum_i u_i sigma_i / (sigma_i^2 + lambda^2) (v_i^T r) (warning::
//   kFellBackToSvd). lambda = 0 gives the normal equations, or kSvd's answer when they are
//   singular or ill-conditioned.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <type_traits>

#include "gausstrack/mass_matrix.hpp"
#include "gausstrack/rank_revealing.hpp"
#include "gausstrack/small_dense.hpp"
#include "gausstrack/status.hpp"

namespace gausstrack {

/// Generalized-inverse strategy for B^+ = (D A^(-1/2))^+ (see the file comment).
enum class InverseStrategy : std::uint8_t {
  kCholeskyWithFallback,
  kSvd,
  kCompleteOrthogonal,
  kDampedLeastSquares,
};

constexpr const char* to_string(InverseStrategy s) noexcept {
  switch (s) {
    case InverseStrategy::kCholeskyWithFallback: return "cholesky";
    case InverseStrategy::kSvd: return "svd";
    case InverseStrategy::kCompleteOrthogonal: return "cod";
    case InverseStrategy::kDampedLeastSquares: return "damped";
  }
  return "unknown";
}

template <typename Scalar>
struct SolverOptions {
  static constexpr Scalar kEps = std::numeric_limits<Scalar>::epsilon();

  InverseStrategy strategy = InverseStrategy::kCholeskyWithFallback;
  /// Relative rank tolerance: a singular value sigma_i of D A^(-1/2) counts when
  /// sigma_i > rank_tolerance * sigma_max. A value <= 0 selects max(N, P) * eps, the LAPACK and
  /// MATLAB `rank` convention.
  Scalar rank_tolerance = Scalar(-1);
  /// The normal equations (default and damped) answer only when a lower bound on the reciprocal condition number of
  /// D A^-1 D^T (at most P^1.5 times below it, so the fallback can come from cond(B) about
  /// 1e3 / P^0.75 on) is at least this: cond(D A^(-1/2)) up to about 1e3 for double (normal-equations error
  /// eps * cond^2 below about 2e-10), about 30 for float.
  Scalar fallback_rcond = std::numeric_limits<Scalar>::digits > 24 ? Scalar(1e-6) : Scalar(1e-3);
  /// lambda of kDampedLeastSquares, in the units of the singular values of D A^(-1/2).
  Scalar damping = Scalar(0);
  /// warning::kConstraintsNotMet when
  /// ||D q'' - g|| > residual_tolerance sqrt(||g||^2 + ||D||_F^2 ||q''||^2).
  Scalar residual_tolerance = std::sqrt(kEps);
  /// warning::kIllConditioned when the condition estimate of D A^(-1/2) exceeds this.
  Scalar warn_condition = Scalar(1) / std::sqrt(kEps);
  /// Absolute floor on the singular values of D A^(-1/2), in the model's own units (row units per
  /// unit of A^(-1/2) q'', e.g. m / (m sqrt(kg)^-1) for a position row of a point mass): a direction
  /// whose singular value is below it is treated as lost (warning::kNearSingular) and its share of
  /// the rows is not enforced, which bounds the force by ||L|| ||g - D a|| / min_singular_value.
  /// 0 (the default) relies on the relative rank tolerance alone.
  Scalar min_singular_value = Scalar(0);
  /// warning::kVanishingReach when the largest singular value of D A^(-1/2) falls below this
  /// times the largest one the solver has computed since it was made or its options were set: the
  /// model's own scale, as the run has shown it. sqrt(eps) by default (the same margin as
  /// warn_condition, measured against the run's history instead of the current call); 0 turns it
  /// off. A solver whose first call is already at the vanishing point has no scale to compare
  /// with: min_singular_value, in the model's units, covers that. The reach compared is the
  /// diagnostics' sigma_max: exact for kSvd, an upper bound (within sqrt(P)) for the normal
  /// equations, the largest pivot for kCompleteOrthogonal; with damping it is
  /// sqrt(sigma^2 + lambda^2), which never vanishes, so the damped strategy never flags.
  Scalar vanishing_ratio = std::sqrt(kEps);
  /// Keep the factorization while A and D are unchanged bit for bit (see the file comment). Only
  /// the cost changes: false factors on every call, as a configuration-dependent A and D do.
  bool reuse_factorization = true;
};

/// Diagnostics of one solve. Singular values are those of B = D L^-T, which equal those of
/// D A^(-1/2): exact for kSvd; for the normal equations bounds from their Cholesky factor
/// (sigma_max from above, sigma_min_kept from below, so the condition estimate is never low; with
/// damping they bound sqrt(sigma^2 + lambda^2) instead); for kCompleteOrthogonal the largest and
/// smallest kept pivots of its column-pivoted QR. A call that fell back to the SVD (kFellBackToSvd,
/// the damped strategy's included) reports the SVD's exact singular values, its rank and, from
/// them, kRankDeficient and kIllConditioned.
template <typename Scalar>
struct SolveDiagnostics {
  Status status = Status::kOk;
  std::uint32_t warnings = 0;           ///< warning::* flags
  std::uint32_t non_finite_inputs = 0;  ///< input::* flags (with Status::kNonFiniteInput)
  InverseStrategy strategy_used = InverseStrategy::kCholeskyWithFallback;  ///< the one asked for on failure
  int rank = 0;                         ///< numerical rank of D A^(-1/2)
  Scalar sigma_max = Scalar(0);         ///< largest singular value of D A^(-1/2)
  Scalar sigma_min_kept = Scalar(0);    ///< smallest singular value treated as nonzero
  Scalar condition_estimate = Scalar(0);  ///< sigma_max / sigma_min_kept (0 when rank is 0)
  Scalar residual_norm = Scalar(0);     ///< ||D q'' - g||

  bool has(std::uint32_t warning_flag) const noexcept { return (warnings & warning_flag) != 0; }
};

/// Result of one solve. On failure every vector is zero.
template <int N, int P, typename Scalar = double>
struct ConstraintSolution {
  using VectorN = Eigen::Matrix<Scalar, N, 1>;
  VectorN acceleration = VectorN::Zero();                ///< q'', eq. (30)            [m/s^2]
  VectorN constraint_force = VectorN::Zero();            ///< Q', eq. (32)             [N]
  VectorN force_from_impressed = VectorN::Zero();        ///< (I - A X A^-1)(f - Q)    [N]
  VectorN force_from_rhs = VectorN::Zero();              ///< A (I - X) D^- g          [N]
  VectorN unconstrained_acceleration = VectorN::Zero();  ///< a = A^-1 (Q - f)         [m/s^2]
  Eigen::Matrix<Scalar, P, 1> residual = Eigen::Matrix<Scalar, P, 1>::Zero();  ///< D q'' - g, row by row
  SolveDiagnostics<Scalar> diagnostics;
};

/// Solver for eq. (30) and eq. (32) with N coordinates and P constraint rows. Owns its workspace;
/// `solve` never allocates and never throws.
template <int N, int P, typename Scalar = double, MassMatrix kMass = MassMatrix::kDense>
class ConstraintSolver {
  static_assert(N >= 1 && P >= 1, "ConstraintSolver needs at least one coordinate and one row");
  static_assert(P <= N, "more constraint rows than coordinates are necessarily redundant: "
                        "remove rows until P <= N");

 public:
  using MatrixNN = Eigen::Matrix<Scalar, N, N>;
  using MatrixPN = Eigen::Matrix<Scalar, P, N>;
  using MatrixNP = Eigen::Matrix<Scalar, N, P>;
  using MatrixPP = Eigen::Matrix<Scalar, P, P>;
  using VectorN = Eigen::Matrix<Scalar, N, 1>;
  using VectorP = Eigen::Matrix<Scalar, P, 1>;
  using Solution = ConstraintSolution<N, P, Scalar>;
  using Options = SolverOptions<Scalar>;

  explicit ConstraintSolver(const Options& options = Options{}) noexcept { set_options(options); }

  void set_options(const Options& options) noexcept {
    factored_ = false;
    options_ = options;
    if (!(options_.rank_tolerance > Scalar(0))) {
      options_.rank_tolerance = Scalar(std::max(N, P)) * std::numeric_limits<Scalar>::epsilon();
    }
    if (!(options_.damping >= Scalar(0))) options_.damping = Scalar(0);
    if (!(options_.min_singular_value >= Scalar(0))) options_.min_singular_value = Scalar(0);
    if (!(options_.vanishing_ratio >= Scalar(0))) options_.vanishing_ratio = Scalar(0);
    reach_seen_ = Scalar(0);
  }
  const Options& options() const noexcept { return options_; }

  /// Constrained accelerations (eq. 30), constraint force (eq. 32) and its two terms for
  /// A (N x N), f, Q (N), D (P x N), g (P). Returns the status also stored in
  /// out.diagnostics.status.
  ///
  /// The normal equations' path is compiled as one body (`flatten`: every kernel it calls is
  /// inlined, so that no call boundary spills the small matrices or reloads the member state);
  /// the rank-revealing factorizations, their application and the failure path stay out of line
  /// (`noinline`), each dominated by its own work, so that the body stays small.
  template <typename DA, typename Df, typename DQ, typename DD, typename Dg>
  [[gnu::flatten]] Status solve(const Eigen::MatrixBase<DA>& A, const Eigen::MatrixBase<Df>& f,
                                const Eigen::MatrixBase<DQ>& Q, const Eigen::MatrixBase<DD>& D,
                                const Eigen::MatrixBase<Dg>& g, Solution& out) noexcept {
    // Plain matrices: references to the arguments when they are plain matrices already, else
    // their values. The work below runs on their contiguous storage.
    const MatrixNN& a_plain = A.derived();
    const VectorN& f_plain = f.derived();
    const VectorN& q_plain = Q.derived();
    const MatrixPN& d_plain = D.derived();
    const VectorP& g_plain = g.derived();
    return solve_plain(a_plain, f_plain, q_plain, d_plain, g_plain, out);
  }

  /// Constraint force L B^+ rhs that the last successful solve's factorization gives for another
  /// right side (P): the part of Q' due to a term added to g. Zero if the last solve failed.
  [[gnu::always_inline]] VectorN force_for_rhs(const VectorP& rhs) const noexcept {
    if (!ready_) return VectorN::Zero();
    VectorN force;
    apply_pseudo_inverse(rhs, force, nullptr);
    return force;
  }

 private:
  Status solve_plain(const MatrixNN& A, const VectorN& f, const VectorN& Q, const MatrixPN& D, const VectorP& g,
                     Solution& out) noexcept {
    ready_ = false;
    out.diagnostics = SolveDiagnostics<Scalar>{};
    // u = L^-1 (Q - f), so that a = A^-1 (Q - f) = L^-T u and D a = B u: the right sides of the
    // two eq. (32) terms, -D a and g, solved together, take -D a as a product with B^T (kept
    // with the factors), and a and q'' = a + L^-T y = L^-T (u + y) are one back substitution on
    // two columns side by side. A new dense factorization has solved for u beside D^T (set_bt); a
    // kept one, or a diagonal L, solves for it here.
    if (const Status s = check_and_factor(A, f, Q, D, g, out); failed(s)) return s;
    out.diagnostics = factor_diagnostics_;
    VectorN u;
    bool solved = false;
    if constexpr (kMass != MassMatrix::kDiagonal) {
      solved = fresh_.solved;
      if (solved) u = fresh_.u;
    }
    if (!solved) {
      for (int i = 0; i < N; ++i) u(i) = Q(i) - f(i);
      solve_l_in_place(u);
    }
    Eigen::Matrix<Scalar, P, 2> rhs;
    for (int i = 0; i < P; ++i) {  // -(B u)_i = -(D a)_i over B^T's column's support
      const int from = kSupports ? bt_first_[i] : 0, to = kSupports ? bt_end_[i] : N;
      rhs(i, 0) = -small_dense::dot(bt_.data() + i * N + from, u.data() + from, to - from);
      rhs(i, 1) = g(i);
    }
    Eigen::Matrix<Scalar, N, 2> force;
    VectorN y;  // B^+ (-D a) + B^+ g
    apply_pseudo_inverse(rhs, force, &y);

    Eigen::Matrix<Scalar, N, 2> w;  // [u, u + y], then L^-T of both: [a, q'']
    for (int i = 0; i < N; ++i) {
      w(i, 0) = u(i);
      w(i, 1) = u(i) + y(i);
    }
    for (int i = 0; i < N; ++i) {
      out.force_from_impressed(i) = force(i, 0);
      out.force_from_rhs(i) = force(i, 1);
      out.constraint_force(i) = force(i, 0) + force(i, 1);
    }
    solve_lt_in_place(w);
    for (int i = 0; i < N; ++i) {
      out.unconstrained_acceleration(i) = w(i, 0);
      out.acceleration(i) = w(i, 1);
    }

    // Both parts are finite when their sum is (an Inf or NaN part makes the sum Inf or NaN). a
    // is checked apart: q'' = L^-T (u + y) can be finite where a = L^-T u overflowed (the
    // constraint cancelling an unconstrained acceleration beyond the range).
    if (!small_dense::all_finite(out.acceleration.data(), N) ||
        !small_dense::all_finite(out.constraint_force.data(), N) ||
        !small_dense::all_finite(out.unconstrained_acceleration.data(), N)) {
      return fail(out, Status::kNonFiniteResult);
    }
    set_warnings(D, g, out);
    reach_seen_ = flag_vanishing_reach(options_.vanishing_ratio, reach_seen_, out.diagnostics);
    ready_ = true;
    return out.diagnostics.status;
  }

  // The inputs' checks, then the factorizations of A and of the constraint rows, unless A and D
  // equal the factored ones (which are finite and need no new factorization). A new dense
  // factorization also solves for u = L^-1 (Q - f) (fresh_).
  Status check_and_factor(const MatrixNN& A, const VectorN& f, const VectorN& Q, const MatrixPN& D,
                          const VectorP& g, Solution& out) noexcept {
    using small_dense::all_finite;
    if constexpr (kMass != MassMatrix::kDiagonal) fresh_.solved = false;
    const bool same_mass = factored_ && options_.reuse_factorization && mass_equals(A);
    const bool same_factors = same_mass && small_dense::all_equal(D.data(), d_key_.data(), P * N);
    // A new D is read once: into D^T (kept) with its squared norm, which is finite only when every
    // entry is (an overflowed square sends the test to the entries themselves). The kept
    // factorization is dropped first, since D^T is part of it.
    if (!same_factors) {
      factored_ = false;
      read_constraint_matrix(D);
    }
    std::uint32_t bad = 0;
    if (!same_mass && !load_mass(A)) bad |= input::kMassMatrix;
    if (!all_finite(f.data(), N)) bad |= input::kNonlinearForce;
    if (!all_finite(Q.data(), N)) bad |= input::kAppliedForce;
    if (!same_factors && !std::isfinite(d_norm2_) && !all_finite(D.data(), P * N)) bad |= input::kConstraintMatrix;
    if (!all_finite(g.data(), P)) bad |= input::kConstraintRhs;
    if (bad != 0) {
      out.diagnostics.non_finite_inputs = bad;
      return fail(out, Status::kNonFiniteInput);
    }
    if (same_factors) return Status::kOk;
    if (!same_mass && !factor_mass(A)) return fail(out, Status::kMassMatrixNotPositiveDefinite);
    if (options_.reuse_factorization) d_key_ = D;  // only compared when kept
    set_bt(f, Q);  // B^T = L^-1 D^T, and with a dense L u = L^-1 (Q - f)
    factor_diagnostics_ = SolveDiagnostics<Scalar>{};
    // B or its factors overflowed (entries near the range limit): nothing below could be
    // trusted, and a factorization of non-finite numbers is not kept.
    if (!factorize(factor_diagnostics_)) return fail(out, Status::kNonFiniteResult);
    factored_ = true;
    return Status::kOk;
  }

  // The residual |D q'' - g| against the tolerance, the rank and the condition: the warnings.
  void set_warnings(const MatrixPN& D, const VectorP& g, Solution& out) const noexcept {
    using small_dense::squared_norm;
    SolveDiagnostics<Scalar>& diag = out.diagnostics;
    // Squared norms: one square root (the reported residual), none for the scale.
    VectorP& residual = out.residual;
    if constexpr (kSupports) {
      // Row i of D q'' over the coordinates the row can touch (D^T's column, kept with its support).
      for (int i = 0; i < P; ++i)
        residual(i) = small_dense::dot(dt_.data() + i * N + d_first_[i], out.acceleration.data() + d_first_[i],
                                       d_end_[i] - d_first_[i]) - g(i);
    } else {
      small_dense::multiply(D.data(), P, N, out.acceleration.data(), residual.data());
      for (int i = 0; i < P; ++i) residual(i) -= g(i);
    }
    const Scalar residual2 = squared_norm(residual.data(), P);
    const Scalar scale2 = squared_norm(g.data(), P) + d_norm2_ * squared_norm(out.acceleration.data(), N);
    bool met;
    if (std::isfinite(residual2) && std::isfinite(scale2)) {
      // One row: the norm is the residual's magnitude (no square root).
      if constexpr (P == 1) diag.residual_norm = std::abs(residual(0));
      else diag.residual_norm = std::sqrt(residual2);
      met = !(residual2 > options_.residual_tolerance * options_.residual_tolerance * scale2);
    } else {
      // Squares beyond the range (norms from about 1e154): the same test on norms taken without
      // squaring. A residual that is itself not finite (D q'' overflowed) cannot be verified.
      diag.residual_norm = small_dense::scaled_norm(residual.data(), P);
      met = std::isfinite(diag.residual_norm) &&
            !(diag.residual_norm > options_.residual_tolerance * unsquared_scale(g, out.acceleration));
      if (!std::isfinite(diag.residual_norm)) diag.residual_norm = std::numeric_limits<Scalar>::infinity();
    }
    if (!met) diag.warnings |= warning::kConstraintsNotMet;
    if (diag.rank < P) diag.warnings |= warning::kRankDeficient;
    if (diag.condition_estimate > options_.warn_condition) diag.warnings |= warning::kIllConditioned;
  }

  // --- The mass matrix's factor L (A = L L^T), dense or diagonal. ---
  bool mass_equals(const MatrixNN& A) const noexcept {
    if constexpr (kMass == MassMatrix::kDiagonal) {
      bool same = true;
      for (int i = 0; i < N; ++i) same &= A(i, i) == mass_diagonal_(i);
      return same;
    } else {
      return small_dense::all_equal(A.data(), mass_key_.data(), N * N);
    }
  }
  // A's finiteness; a dense A is copied into mass_l_ on the way (one pass), for factor_mass to
  // factor in place.
  bool load_mass(const MatrixNN& A) noexcept {
    if constexpr (kMass == MassMatrix::kDiagonal) {
      for (int i = 0; i < N; ++i)
        if (!std::isfinite(A(i, i))) return false;
      return true;
    } else {
      return small_dense::all_finite(A.data(), N * N, mass_l_.data());
    }
  }
  // The factor of the finite A load_mass has read.
  bool factor_mass(const MatrixNN& A) noexcept {
    if constexpr (kMass == MassMatrix::kDiagonal) {
      for (int i = 0; i < N; ++i) {
        const Scalar m = A(i, i);
        mass_diagonal_(i) = m;
        if (!(m > Scalar(0))) return false;
        sqrt_mass_(i) = std::sqrt(m);
        inverse_sqrt_mass_(i) = Scalar(1) / sqrt_mass_(i);
      }
      return true;
    } else {
      if (options_.reuse_factorization) mass_key_ = A;  // only compared when kept
      return small_dense::cholesky_in_place(mass_l_, mass_reciprocal_.data());
    }
  }
  // D^T into dt_, ||D||_F^2 into d_norm2_, and where each row of D can be nonzero.
  void read_constraint_matrix(const MatrixPN& D) noexcept {
    dt_ = D.transpose();
    d_norm2_ = small_dense::squared_norm(dt_.data(), N * P);
    if constexpr (kSupports) small_dense::column_supports(dt_, d_first_, d_end_);
  }
  // B^T = L^-1 D^T. Its columns' supports: D's rows' with a diagonal L; from the same first row
  // to the last with a dense one (the substitution fills in below). With a dense L, u = L^-1 (Q -
  // f) is one more column of the same forward substitution (fresh_): its dependent chain, a
  // one-vector solve's whole cost, runs beside D^T's columns instead of after them.
  void set_bt(const VectorN& f, const VectorN& Q) noexcept {
    if constexpr (kSupports) {
      for (int i = 0; i < P; ++i) {
        bt_first_[i] = d_first_[i];
        bt_end_[i] = d_end_[i];
      }
      if constexpr (kMass != MassMatrix::kDiagonal) small_dense::fill_in_below<N>(bt_end_, P);
    }
    if constexpr (kMass == MassMatrix::kDiagonal) {
      bt_.noalias() = inverse_sqrt_mass_.asDiagonal() * dt_;  // Eigen's vectorized product
    } else {
      bt_ = dt_;
      for (int i = 0; i < N; ++i) fresh_.u(i) = Q(i) - f(i);
      small_dense::solve_lower_in_place(mass_l_, mass_reciprocal_.data(), bt_, fresh_.u,
                                        kSupports ? bt_first_ : nullptr);
      fresh_.solved = true;
    }
  }
  // x = L^-1 x for u when set_bt has not solved it (a kept factorization, or a diagonal L): by the
  // path set_bt solves it on beside D^T, so that a kept factorization answers bit for bit as a new
  // one.
  void solve_l_in_place(VectorN& x) const noexcept {
    if constexpr (kMass == MassMatrix::kDiagonal) {
      for (int i = 0; i < N; ++i) x(i) *= inverse_sqrt_mass_(i);
    } else {
      small_dense::solve_lower_columns<1, (P + 1 > 2)>(mass_l_, mass_reciprocal_.data(),
                                                       [&x](int) { return x.data(); });
    }
  }
  template <int K>
  void apply_l_in_place(Eigen::Matrix<Scalar, N, K>& x) const noexcept {  // x = L x
    if constexpr (kMass == MassMatrix::kDiagonal) {
      for (int k = 0; k < K; ++k)
        for (int i = 0; i < N; ++i) x(i, k) *= sqrt_mass_(i);
    } else {
      small_dense::multiply_lower_in_place(mass_l_, x);
    }
  }
  template <int K>
  void solve_lt_in_place(Eigen::Matrix<Scalar, N, K>& x) const noexcept {  // x = L^-T x
    if constexpr (kMass == MassMatrix::kDiagonal) {
      for (int k = 0; k < K; ++k)
        for (int i = 0; i < N; ++i) x(i, k) *= inverse_sqrt_mass_(i);
    } else {
      small_dense::solve_lower_transposed_in_place(mass_l_, mass_reciprocal_.data(), x);
    }
  }

  // |g| + |D| |q''| without squaring (for |D|^2 |q''|^2 beyond the range; rare, so not cached).
  [[gnu::noinline]] Scalar unsquared_scale(const VectorP& g, const VectorN& acceleration) const noexcept {
    return small_dense::scaled_norm(g.data(), P) +
           small_dense::scaled_norm(dt_.data(), P * N) * small_dense::scaled_norm(acceleration.data(), N);
  }

  [[gnu::noinline]] Status fail(Solution& out, Status status) noexcept {
    const VectorN zero = VectorN::Zero();
    out.acceleration = zero;
    out.constraint_force = zero;
    out.force_from_impressed = zero;
    out.force_from_rhs = zero;
    out.unconstrained_acceleration = zero;
    out.residual.setZero();
    // Only the status and the named inputs describe a failed call; the rest is reset.
    const std::uint32_t bad = out.diagnostics.non_finite_inputs;
    out.diagnostics = SolveDiagnostics<Scalar>{};
    out.diagnostics.status = status;
    out.diagnostics.non_finite_inputs = bad;
    out.diagnostics.strategy_used = options_.strategy;
    return status;
  }

  // Factor B (held as bt_) with the selected strategy; fills the rank diagnostics. Returns
  // false when the factors came out non-finite (B finite, but its norms overflowed).
  bool factorize(SolveDiagnostics<Scalar>& diag) noexcept {
    // With a floor on the singular values, every strategy first asks whether B certainly has
    // none below it; if that cannot be shown, the SVD decides exactly which directions to keep
    // (and sets kNearSingular when it drops one the relative tolerance would have kept).
    if (options_.min_singular_value > Scalar(0) && options_.strategy != InverseStrategy::kSvd &&
        !certainly_above_floor()) {
      diag.warnings |= warning::kFellBackToSvd;
      return factorize_svd(diag);
    }
    switch (options_.strategy) {
      case InverseStrategy::kCholeskyWithFallback:
        if (factorize_normal_equations(Scalar(0), diag)) return true;
        diag.warnings |= warning::kFellBackToSvd;
        return factorize_svd(diag);
      case InverseStrategy::kDampedLeastSquares:
        if (factorize_normal_equations(options_.damping * options_.damping, diag)) return true;
        diag.warnings |= warning::kFellBackToSvd;
        return factorize_svd(diag);
      case InverseStrategy::kSvd:
        return factorize_svd(diag);
      case InverseStrategy::kCompleteOrthogonal:
        return factorize_cod(diag);
    }
    return false;
  }

  // True when every singular value of B is shown to be >= min_singular_value: with
  // B B^T = L L^T, sigma_min(B)^2 = lambda_min(B B^T) = 1 / ||L^-1||_2^2 >= 1 / ||L^-1||_F^2.
  // A sufficient test (it may send a solve to the SVD needlessly, never the other way round).
  bool certainly_above_floor() noexcept {
    Scalar norm1, inverse_norm2;
    if (!factor_gram(Scalar(0), norm1, inverse_norm2)) return false;
    const Scalar floor = options_.min_singular_value;
    return std::isfinite(inverse_norm2) && inverse_norm2 * floor * floor <= Scalar(1);
  }

  // G = B B^T + lambda2 I = L L^T: keeps L^-1 (gram_l_inv_) and gives ||G||_1 and ||L^-1||_F^2.
  // False when G is not finite (an overflowed Gram matrix would look well conditioned) or its
  // Cholesky factorization fails.
  bool factor_gram(Scalar lambda2, Scalar& norm1, Scalar& inverse_norm2) noexcept {
    MatrixPP gram;  // B B^T: dot products of B^T's columns
    if constexpr (kSupports) small_dense::gram(bt_, gram, bt_first_, bt_end_);
    else small_dense::gram(bt_, gram);
    for (int i = 0; i < P; ++i) gram(i, i) += lambda2;
    if (!small_dense::all_finite(gram.data(), P * P)) return false;
    norm1 = Scalar(0);  // ||G||_1, the largest column sum of |G|
    for (int j = 0; j < P; ++j) {
      Scalar column(0);
      for (int i = 0; i < P; ++i) column += std::abs(gram(i, j));
      norm1 = std::max(norm1, column);
    }
    Scalar reciprocal[P];
    if (!small_dense::cholesky_in_place(gram, reciprocal)) return false;
    inverse_norm2 = small_dense::invert_lower(gram, reciprocal, gram_l_inv_);
    return true;
  }


  // Cholesky of B B^T + lambda2 I = D A^-1 D^T + lambda2 I. Returns false when it is not usable.
  bool factorize_normal_equations(Scalar lambda2, SolveDiagnostics<Scalar>& diag) noexcept {
    if constexpr (P == 1) {
      // One row: B B^T is the scalar |b|^2, exactly conditioned (rcond 1); only its size can
      // fail, or a fallback threshold above 1 that no matrix meets.
      const Scalar gram = small_dense::squared_norm(bt_.data(), N) + lambda2;
      if (!(gram > Scalar(0)) || !std::isfinite(gram)) return false;
      if (!(Scalar(1) >= options_.fallback_rcond)) return false;
      inverse_gram_ = Scalar(1) / gram;
      used_ = options_.strategy;
      rank_ = 1;
      diag.strategy_used = used_;
      diag.rank = 1;
      diag.sigma_max = diag.sigma_min_kept = std::sqrt(gram);
      diag.condition_estimate = Scalar(1);
      return true;
    } else {
      // Not usable when G overflowed (the SVD then works on B itself) or is not positive definite.
      Scalar norm1, inverse_norm2;
      if (!factor_gram(lambda2, norm1, inverse_norm2)) return false;
      // lambda_max(G) <= ||G||_1 and 1 / lambda_min(G) = ||L^-1||_2^2 <= ||L^-1||_F^2, so this is
      // never above G's true reciprocal condition number (and at most P^1.5 times below it): an
      // ill-conditioned G always falls back.
      const Scalar rcond = Scalar(1) / (norm1 * inverse_norm2);
      if (!(rcond >= options_.fallback_rcond)) return false;
      if (!(rcond > Scalar(0)) || !std::isfinite(rcond)) return false;
      used_ = options_.strategy;
      rank_ = P;
      diag.strategy_used = used_;
      diag.rank = P;
      diag.sigma_max = std::sqrt(norm1);                        // >= sigma_max
      diag.sigma_min_kept = Scalar(1) / std::sqrt(inverse_norm2);  // <= sigma_min
      diag.condition_estimate = diag.sigma_max / diag.sigma_min_kept;
      return true;
    }
  }

  // One-sided Jacobi SVD of B^T = U S V^T (N x P), so B = V S U^T and B^+ = U S^+ V^T.
  // Both rank-revealing kernels refuse a non-finite B (L^-1 D^T overflowed). The normal equations
  // need no test: a non-finite B makes B B^T non-finite, which they refuse.
  [[gnu::noinline]] bool factorize_svd(SolveDiagnostics<Scalar>& diag) noexcept {
    if (!small_dense::all_finite(bt_.data(), N * P)) return false;
    used_ = InverseStrategy::kSvd;
    svd_damping2_ = options_.strategy == InverseStrategy::kDampedLeastSquares ? options_.damping * options_.damping
                                                                               : Scalar(0);
    svd_u_ = bt_;
    if (!small_dense::jacobi_svd_in_place(svd_u_.data(), N, P, svd_sigma_.data(), svd_v_.data())) return false;
    const VectorP& s = svd_sigma_;
    rank_ = 0;
    if (s(0) > Scalar(0)) {
      const Scalar relative = options_.rank_tolerance * s(0);
      const Scalar cutoff = std::max(relative, options_.min_singular_value);
      while (rank_ < P && s(rank_) > cutoff) ++rank_;
      if (rank_ < P && s(rank_) > relative) diag.warnings |= warning::kNearSingular;
    }
    set_rank_diagnostics(diag, s(0), rank_ > 0 ? s(rank_ - 1) : Scalar(0));
    return true;
  }

  [[gnu::noinline]] bool factorize_cod(SolveDiagnostics<Scalar>& diag) noexcept {
    if (!small_dense::all_finite(bt_.data(), N * P)) return false;
    used_ = InverseStrategy::kCompleteOrthogonal;
    MatrixPN b;
    for (int i = 0; i < P; ++i)
      for (int j = 0; j < N; ++j) b(i, j) = bt_(j, i);
    if (!small_dense::factor_complete_orthogonal(b.data(), P, N, options_.rank_tolerance, cod_)) return false;
    rank_ = cod_.rank;
    set_rank_diagnostics(diag, rank_ > 0 ? cod_.largest_pivot : Scalar(0), cod_.smallest_kept_pivot);
    return true;
  }

  void set_rank_diagnostics(SolveDiagnostics<Scalar>& diag, Scalar hi, Scalar lo) const noexcept {
    diag.strategy_used = used_;
    diag.rank = rank_;
    diag.sigma_max = hi;
    diag.sigma_min_kept = lo;
    diag.condition_estimate = rank_ > 0 ? hi / lo : Scalar(0);
  }

  // The constraint force L y, y = B^+ r, for K right sides, with the factorization `factorize`
  // chose, and when asked the sum of the K columns of y (q'' needs only that). On the normal
  // equations B^+ = B^T G^-1, so with w = G^-1 r (the constraints' multipliers) y = B^T w and
  // L y = L L^-1 D^T w = D^T w: a product with D (N P) rather than with a dense L (N^2); a diagonal
  // L is N products. The sum of y's columns is B^T applied to the sum of w's.
  template <int K>
  [[gnu::always_inline]] void apply_pseudo_inverse(const Eigen::Matrix<Scalar, P, K>& r,
                                                   Eigen::Matrix<Scalar, N, K>& force, VectorN* y_sum) const noexcept {
    if (used_ != InverseStrategy::kCholeskyWithFallback && used_ != InverseStrategy::kDampedLeastSquares) {
      apply_rank_revealing(r, force, y_sum);
      return;
    }
    Eigen::Matrix<Scalar, P, K> w = r;  // w = G^-1 r = L^-T L^-1 r
    if constexpr (P == 1) {
      for (int k = 0; k < K; ++k) w(0, k) *= inverse_gram_;
    } else {
      // L^-1 is kept with its upper triangle zero: two products as dense ones, Eigen's
      // coefficient-based kernels vectorized down the columns.
      const Eigen::Matrix<Scalar, P, K> z = gram_l_inv_.lazyProduct(w);
      w.noalias() = gram_l_inv_.transpose().lazyProduct(z);
    }
    // Products down the N x P factors' columns, into locals (the outputs might alias the factors,
    // as far as the compiler knows).
    Scalar column[N];
    if constexpr (kMass == MassMatrix::kDiagonal) {
      // force = sqrt(A) B^T w column by column; y's sum from the columns before scaling.
      Scalar sum[N] = {};
      for (int k = 0; k < K; ++k) {
        times(bt_, bt_first_, bt_end_, w.data() + k * P, column);
        for (int i = 0; i < N; ++i) {
          sum[i] += column[i];
          force(i, k) = sqrt_mass_(i) * column[i];
        }
      }
      if (y_sum != nullptr)
        for (int i = 0; i < N; ++i) (*y_sum)(i) = sum[i];
    } else {
      for (int k = 0; k < K; ++k) {
        times(dt_, d_first_, d_end_, w.data() + k * P, column);
        for (int i = 0; i < N; ++i) force(i, k) = column[i];
      }
      if (y_sum != nullptr) {
        Scalar w_sum[P];
        for (int j = 0; j < P; ++j) {
          w_sum[j] = w(j, 0);
          for (int k = 1; k < K; ++k) w_sum[j] += w(j, k);
        }
        times(bt_, bt_first_, bt_end_, w_sum, column);
        for (int i = 0; i < N; ++i) (*y_sum)(i) = column[i];
      }
    }
  }

  // out = M x for an N x P factor M (supports above kDenseUpTo coordinates).
  static void times(const MatrixNP& m, const int* first, const int* end, const Scalar* x, Scalar* out) noexcept {
    small_dense::multiply_columns<kSupports>(m, x, out, first, end);
  }

  // apply_pseudo_inverse with the SVD or the complete orthogonal decomposition: force = L y.
  template <int K>
  [[gnu::noinline]] void apply_rank_revealing(const Eigen::Matrix<Scalar, P, K>& r,
                                               Eigen::Matrix<Scalar, N, K>& force, VectorN* y_sum) const noexcept {
    Eigen::Matrix<Scalar, N, K> y;
    switch (used_) {
      case InverseStrategy::kCholeskyWithFallback:
      case InverseStrategy::kDampedLeastSquares:
        break;  // apply_pseudo_inverse
      case InverseStrategy::kSvd: {
        // B^+ r = sum_i u_i (v_i^T r) / s_i over the kept values.
        y.setZero();
        for (int k = 0; k < K; ++k) {
          for (int i = 0; i < rank_; ++i) {
            Scalar c(0);
            for (int j = 0; j < P; ++j) c += svd_v_(j, i) * r(j, k);
            // sigma / (sigma^2 + lambda^2): 1 / sigma without damping.
            const Scalar sigma = svd_sigma_(i);
            c = svd_damping2_ > Scalar(0) ? c / (sigma + svd_damping2_ / sigma) : c / sigma;  // no sigma^2
            for (int j = 0; j < N; ++j) y(j, k) += svd_u_(j, i) * c;
          }
        }
        break;
      }
      case InverseStrategy::kCompleteOrthogonal: {
        Scalar column[P], work[P];
        Scalar answer[N];
        for (int k = 0; k < K; ++k) {
          for (int i = 0; i < P; ++i) column[i] = r(i, k);
          small_dense::solve_complete_orthogonal(cod_, column, answer, work);
          for (int i = 0; i < N; ++i) y(i, k) = answer[i];
        }
        break;
      }
    }
    if (y_sum != nullptr) *y_sum = y.rowwise().sum();
    force = y;
    apply_l_in_place(force);
  }

  Options options_;
  // The factorization and what it was computed from (valid while factored_).
  bool factored_ = false;
  MatrixNN mass_key_ = MatrixNN::Zero();   // A (dense)
  VectorN mass_diagonal_ = VectorN::Zero();  // A's diagonal (diagonal)
  VectorN sqrt_mass_ = VectorN::Zero(), inverse_sqrt_mass_ = VectorN::Zero();
  MatrixPN d_key_ = MatrixPN::Zero();       // D (kept only with reuse_factorization)
  Scalar d_norm2_ = Scalar(0);              // ||D||_F^2
  Scalar inverse_gram_ = Scalar(0);         // 1 / (B B^T + lambda^2) when P = 1
  SolveDiagnostics<Scalar> factor_diagnostics_;  // what factorize reported
  Scalar reach_seen_ = Scalar(0);                // the largest sigma_max computed (kVanishingReach)
  MatrixNN mass_l_ = MatrixNN::Identity();       // A = L L^T, lower triangle (dense)
  VectorN mass_reciprocal_ = VectorN::Ones();     // 1 / L_kk (dense)
  MatrixNP bt_ = MatrixNP::Zero();               // B^T = L^-1 D^T
  MatrixNP dt_ = MatrixNP::Zero();               // D^T
  // Where the columns of D^T and of B^T can be nonzero (small_dense::column_supports): above
  // kDenseUpTo coordinates the products, B^T's solve and the Gram matrix skip the rest, which a
  // constraint row touching a few coordinates leaves mostly zero; up to it the loops of fixed
  // length measure faster (as for the jets, jet.hpp).
  static constexpr int kDenseUpTo = 8;
  static constexpr bool kSupports = N > kDenseUpTo;
  int d_first_[P] = {}, d_end_[P] = {}, bt_first_[P] = {}, bt_end_[P] = {};
  MatrixPP gram_l_inv_ = MatrixPP::Identity();   // L^-1 for B B^T + lambda^2 I = L L^T
  MatrixNP svd_u_ = MatrixNP::Zero();            // B^T = U S V^T (kSvd)
  MatrixPP svd_v_ = MatrixPP::Identity();
  VectorP svd_sigma_ = VectorP::Zero();
  Scalar svd_damping2_ = Scalar(0);  // lambda^2 when kDampedLeastSquares fell back to the SVD
  small_dense::CompleteOrthogonal<Scalar, P, N> cod_{};  // B Pi = Q [S^T 0; 0 0] Z^T (kCompleteOrthogonal)
  InverseStrategy used_ = InverseStrategy::kCholeskyWithFallback;
  // u = L^-1 (Q - f) when this call factored a dense A or D anew (set_bt); nothing with a diagonal L.
  struct FreshRightSide {
    VectorN u = VectorN::Zero();
    bool solved = false;
  };
  struct NoRightSide {};
  [[no_unique_address]] std::conditional_t<kMass == MassMatrix::kDiagonal, NoRightSide, FreshRightSide> fresh_{};
  int rank_ = 0;
  bool ready_ = false;
};

}  // namespace gausstrack
