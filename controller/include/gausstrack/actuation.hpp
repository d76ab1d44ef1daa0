// The tracking law for a machine that pushes only through its actuators, among constraints the
// environment holds.
//
// A model that declares an actuation matrix B(q, t) (N x K: the generalized force of actuator
// commands u in R^K is B u),
//   static constexpr int kActuators = K;
//   void actuation(const Eigen::Matrix<Scalar, N, 1>& q, Scalar t,
//                  Eigen::Matrix<Scalar, N, K>& B) const noexcept;
// is controlled by the u that meets the task rows D q'' = g with the least cost u^T W u:
//   u = W^(-1/2) (D A^-1 B W^(-1/2))^+ (g - D a),   a = A^-1 (Q - f)
// (Udwadia, Proc. R. Soc. A 464 (2008) 2341: every positive definite W gives a member of the
// family; any square root of W gives the same u). The default weight is Gauss's,
// W = B^T A^-1 B: the answer then is the one of least acceleration change in A's metric among the
// forces B can give, and with B = I it is eq. (32)'s force (actuation_test holds the two equal).
// A model without B is controlled through B = I (K = N).
//
// Physical rows (model.hpp, kPhysicalRowMask: D_p q'' = g_p, held by the environment) make the
// system the law controls the physically constrained one: its acceleration and its response to a
// force are, by Gauss's principle applied to the physical rows alone (eq. 30 with D_p),
//   a_p = a + A^(-1/2) (D_p A^(-1/2))^+ (g_p - D_p a),
//   M_p = A^(-1/2) (I - (D_p A^(-1/2))^+ D_p A^(-1/2)) A^(-1/2),
// and the task rows D_c become D_c M_p B u = g_c - D_c a_p. The control then never pushes along
// the physical rows: with B = I and Gauss's weight, D_p A^-1 u = 0. Physical rows are neither
// stabilized nor switched; their residual under the law's acceleration is reported, and a
// physical row even the environment could not hold (inconsistent physical rows) is named in
// unmet_rows like a task row.
//
// When D_c M_p B has rank below its task rows, some rows cannot be actuated: u meets the rows in
// the least-squares sense, warning::kRankDeficient is set, and `unmet_rows` says which rows are
// not met. The force B u is in the range of B by construction. As in TrackingController, u is
// split into a closed-loop part (from -D_c a_p), a feedforward part (from the model's g_c) and a
// stabilizing part (from Baumgarte's correction), each mapped through the same pseudo-inverse.
//
// How it is computed, with A = L L^T (Cholesky) and C = D L^-T (so that D A^-1 B = C L^-1 B;
// any square root of A serves in M_p):
// - Physical rows: the thin SVD C_p^T = U_p S_p V_p^T gives C_p^+ = U_p S_p^+ V_p^T and the
//   projector I - U_p U_p^T (columns of U_p whose singular value is above the rank tolerance).
// - Gauss's weight: L^-1 B = U R (Gram-Schmidt, twice per column) gives W = R^T R, so the scaled
//   task matrix is C_c (I - U_p U_p^T) U and u = R^-1 (...)^+ r. Dependent columns of B (a
//   diagonal of R at or below sqrt(eps) times the largest column) make W singular:
//   Status::kWeightNotPositiveDefinite.
// - A given weight W = Lw Lw^T (set_weight): U is replaced by L^-1 B Lw^-T and R^-1 by Lw^-T.
// - Without B and with Gauss's weight, W^(1/2) = L^-1: the task matrix is C_c itself and
//   u = L x. Without physical rows too, every row active, no more rows than coordinates, under
//   the default or the SVD strategy, that is eq. (32) (the plain case): the plain law's own solver
//   (ConstraintSolver) answers it, and its diagnostics are the plain law's (the reach, the
//   condition estimate and the rank relative to sigma_max of D A^(-1/2)).
// The task's pseudo-inverse: under the default strategy (kCholeskyWithFallback) its normal
// equations T^T (T T^T)^-1 when every task row is active and the Cholesky factor of T T^T shows T
// of full row rank, well conditioned and above the floor, as the plain law answers eq. (32);
// otherwise the one-sided Jacobi SVD of rank_revealing.hpp with the solver options' rank
// tolerance and singular-value floor (SolverOptions::min_singular_value: with
// Gauss's weight the singular values are those of D_c A^(-1/2) restricted to the actuated,
// physically free directions, in the same units). Fixed-size storage: allocation-free and
// exception-free after construction.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <type_traits>

#include "gausstrack/model.hpp"
#include "gausstrack/rank_revealing.hpp"
#include "gausstrack/small_dense.hpp"
#include "gausstrack/status.hpp"
#include "gausstrack/tracking_controller.hpp"

namespace gausstrack {

template <typename M>
concept ActuatedModel = Model<M> &&
    requires(const M& m, const Eigen::Matrix<typename M::Scalar, M::kDof, 1>& q,
             typename M::Scalar t, Eigen::Matrix<typename M::Scalar, M::kDof, M::kActuators>& b) {
  requires M::kActuators >= 1;
  { m.actuation(q, t, b) }
  noexcept;
};

namespace detail {
template <typename M>
constexpr int actuator_count() {
  if constexpr (ActuatedModel<M>)
    return M::kActuators;
  else
    return M::kDof;
}
// Indices of the rows with (Physical) or without the physical bit, in order.
template <typename M, bool Physical, int Count>
constexpr std::array<int, static_cast<std::size_t>(Count)> rows_of_kind() {
  std::array<int, static_cast<std::size_t>(Count)> rows{};
  std::size_t k = 0;
  for (int i = 0; i < M::kConstraints; ++i)
    if (RowLayout<M>::physical(i) == Physical) rows[k++] = i;
  return rows;
}
}  // namespace detail

/// K: the model's actuators, or N for a model without B (every coordinate actuated, B = I).
template <typename M>
inline constexpr int kActuatorsOf = detail::actuator_count<M>();

/// The actuator commands for one measured state, and the generalized force they give.
template <int N, int P, int K, typename Scalar>
struct ActuatedOutput {
  using VectorN = Eigen::Matrix<Scalar, N, 1>;
  using VectorP = Eigen::Matrix<Scalar, P, 1>;
  using VectorK = Eigen::Matrix<Scalar, K, 1>;
  VectorK control = VectorK::Zero();              ///< u, the actuator commands
  VectorK control_closed_loop = VectorK::Zero();  ///< u's part from -D a (depends on q, q', t)
  VectorK control_feedforward = VectorK::Zero();  ///< u's part from the model's g
  VectorK control_stabilizing = VectorK::Zero();  ///< u's part from Baumgarte's correction
  VectorN force = VectorN::Zero();                ///< B u, the generalized force
  VectorN closed_loop = VectorN::Zero();          ///< B times u's closed-loop part
  VectorN feedforward = VectorN::Zero();          ///< B times u's feedforward part
  VectorN stabilizing = VectorN::Zero();          ///< B times u's stabilizing part
  VectorN acceleration = VectorN::Zero();         ///< q'' = a + A^-1 B u on the model
  VectorP row_residual = VectorP::Zero();         ///< D q'' - g, row by row (g stabilized)
  /// Bit i (rows 0..63): row i is not met (it cannot be actuated, or its direction was given up).
  std::uint64_t unmet_rows = 0;
  /// 1, or the factor u and its parts were scaled by to meet the actuator limits.
  Scalar saturation_scale = Scalar(1);
  VectorP constraint_error = VectorP::Zero();       ///< e at the measured state
  VectorP constraint_error_rate = VectorP::Zero();  ///< e' at the measured state
  /// Status, warnings, and rank and singular values of D A^-1 B W^(-1/2).
  SolveDiagnostics<Scalar> diagnostics;
};

/// The actuated law for a model with actuators or physical rows (or any model, through B = I): one
/// evaluation of the model's terms and of B, Baumgarte's correction per task row, one SVD of the
/// physical rows (when there are any), an orthonormal basis of B's scaled directions (Gauss's
/// weight; none without B) and the pseudo-inverse of the scaled task matrix: its normal equations
/// under the default strategy when every task row is active and the task is of full row rank and
/// well conditioned (the fallback_rcond, rank_tolerance and min_singular_value tests), one SVD
/// otherwise and under every other strategy.
template <Model M>
class ActuatedController {
 public:
  using Scalar = typename M::Scalar;
  static constexpr int N = M::kDof;
  static constexpr int P = M::kConstraints;
  static constexpr int K = kActuatorsOf<M>;
  static constexpr int kPhysical = RowLayout<M>::kPhysical;  ///< P_p, rows the environment holds
  static constexpr int kTask = RowLayout<M>::kTask;          ///< P_c, rows the control holds
  using VectorN = Eigen::Matrix<Scalar, N, 1>;
  using VectorP = Eigen::Matrix<Scalar, P, 1>;
  using VectorK = Eigen::Matrix<Scalar, K, 1>;
  using MatrixNK = Eigen::Matrix<Scalar, N, K>;
  using MatrixKK = Eigen::Matrix<Scalar, K, K>;
  using Output = ActuatedOutput<N, P, K, Scalar>;
  using Options = ControllerOptions<Scalar>;

  /// Throws std::invalid_argument (when exceptions are enabled; traps otherwise) if
  /// `options.validate()` reports a problem.
  explicit ActuatedController(M model = M{}, const Options& options = Options{})
      : model_(std::move(model)), options_(options), plain_solver_(plain_solver_options(options.solver)) {
    if (const char* problem = options.validate()) config_error(problem);
    row_gains_.fill(options.stabilization);
    row_robust_.fill(options.robust);
  }

  /// The robust term of one task row, as TrackingController::set_robust (false for a physical
  /// row).
  bool set_robust(int row, const Robust<Scalar>& robust) noexcept {
    if (row < 0 || row >= P || RowLayout<M>::physical(row) || robust.validate() != nullptr)
      return false;
    row_robust_[static_cast<std::size_t>(row)] = robust;
    return true;
  }

  M& model() noexcept { return model_; }
  const M& model() const noexcept { return model_; }
  const Options& options() const noexcept { return options_; }
  /// B at the last computed state.
  const MatrixNK& actuation() const noexcept { return b_; }

  /// Baumgarte gains of one task row, as TrackingController::set_stabilization (false for a
  /// physical row: the law does not act on it).
  bool set_stabilization(int row, const Stabilization<Scalar>& gains) noexcept {
    if (row < 0 || row >= P || RowLayout<M>::physical(row) || !std::isfinite(gains.zeta) ||
        !(gains.zeta >= Scalar(0)) || !std::isfinite(gains.omega) || !(gains.omega >= Scalar(0)))
      return false;
    row_gains_[static_cast<std::size_t>(row)] = gains;
    return true;
  }

  /// Switches task row `row` on or off at run time (a tool touching a surface, a phase of a gait):
  /// an inactive row is neither held nor counted (no rank deficiency, never in unmet_rows; its
  /// row_residual still says how far the motion is from it). Nothing is allocated or rebuilt: the
  /// task matrix keeps its size with the inactive rows zero, which its SVD gives up exactly. A
  /// row that comes back is stabilized from its current error (Baumgarte's correction has no
  /// memory), and the hold's jerk estimate starts again at the switch. Returns false, changing
  /// nothing, for a row out of range or a physical row (the environment holds it regardless).
  bool set_row_active(int row, bool active) noexcept {
    if (row < 0 || row >= P || RowLayout<M>::physical(row)) return false;
    if (active_[static_cast<std::size_t>(row)] != active) {
      prediction_.forget();
      inactive_rows_ += active ? -1 : 1;
    }
    active_[static_cast<std::size_t>(row)] = active;
    return true;
  }
  bool row_active(int row) const noexcept {
    return row >= 0 && row < P && !RowLayout<M>::physical(row) &&
           active_[static_cast<std::size_t>(row)];
  }

  /// The weight W of the cost u^T W u (symmetric positive definite; only its lower triangle is
  /// read). Returns false, changing nothing, otherwise.
  bool set_weight(const MatrixKK& w) noexcept {
    MatrixKK factor = w;
    if (!w.allFinite() || !small_dense::cholesky_in_place(factor) || !factor.allFinite())
      return false;
    weight_factor_ = factor.template triangularView<Eigen::Lower>();
    gauss_weight_ = false;
    return true;
  }
  /// Back to Gauss's weight, B^T A^-1 B (the default).
  void use_gauss_weight() noexcept { gauss_weight_ = true; }
  /// The robust term of one row (off for a row out of range or a physical row).
  Robust<Scalar> robust(int row) const noexcept {
    return row < 0 || row >= P || RowLayout<M>::physical(row)
               ? Robust<Scalar>{}
               : row_robust_[static_cast<std::size_t>(row)];
  }
  bool gauss_weight() const noexcept { return gauss_weight_; }

  /// Actuator limits |u_i| <= limit_i: u beyond them is scaled down as a whole
  /// (warning::kSaturated, saturation_scale). Returns false, changing nothing, unless every limit
  /// is > 0.
  bool set_actuator_limit(const VectorK& limit) noexcept {
    for (int i = 0; i < K; ++i)
      if (!(limit(i) > Scalar(0))) return false;
    limit_ = limit;
    return true;
  }
  const VectorK& actuator_limit() const noexcept { return limit_; }

  /// The sampled-data hold, as TrackingController::set_hold (the same prediction, through the
  /// acceleration the actuated commands give). Returns false, changing nothing, unless period and
  /// delay are finite and >= 0.
  bool set_hold(const Hold<Scalar>& hold) noexcept {
    if (!std::isfinite(hold.period) || !(hold.period >= Scalar(0)) || !std::isfinite(hold.delay) ||
        !(hold.delay >= Scalar(0)))
      return false;
    options_.hold = hold;
    return true;
  }
  const Hold<Scalar>& hold() const noexcept { return options_.hold; }

  /// Actuator commands for state (q, q', t), or with a hold the commands to hold over
  /// [t + delay, t + delay + period] (warning::kHoldAtMeasuredState when the predicted state
  /// cannot be evaluated). On failure every output is zero. The output's constraint_error and
  /// constraint_error_rate are the measured state's.
  template <typename Dq, typename Dqd>
  Status compute(const Eigen::MatrixBase<Dq>& q, const Eigen::MatrixBase<Dqd>& qd, Scalar t,
                 Output& out) noexcept {
    if (!q.allFinite() || !qd.allFinite() || !std::isfinite(t)) {
      out.constraint_error.setZero();
      out.constraint_error_rate.setZero();
      return fail(out, Status::kNonFiniteInput, input::kState);
    }
    const VectorN qv = q;
    const VectorN qdv = qd;
    const Status measured = evaluate(qv, qdv, t, out);
    if (!options_.hold.enabled()) return measured;
    if (failed(measured)) {
      prediction_.forget();
      return measured;
    }
    const VectorP e = out.constraint_error, e_rate = out.constraint_error_rate;
    VectorN q_m, qd_m;
    prediction_.predict(options_.hold, qv, qdv, t, out.acceleration, q_m, qd_m);
    Status status = q_m.allFinite() && qd_m.allFinite()
                        ? evaluate(q_m, qd_m, t + options_.hold.lead(), out)
                        : Status::kNonFiniteInput;
    if (failed(status)) {
      status = evaluate(qv, qdv, t, out);
      out.diagnostics.warnings |= warning::kHoldAtMeasuredState;
    }
    out.constraint_error = e;
    out.constraint_error_rate = e_rate;
    return status;
  }

 private:
  // The actuated law at (q, q', t), compiled as one body (`flatten`, as the plain law's
  // evaluation): its many small steps (the factors, the projections, the row judgement) are
  // inlined instead of called, so that no call boundary spills the small matrices or reloads the
  // member state. The body holds the path the model takes by default: the plain case when the
  // model has one, else the general law. What is rarely taken or dominated by its own work stays
  // out of line (`noinline`): the general law beside a plain case, the SVDs, fail().
  [[gnu::flatten]] Status evaluate(const VectorN& qv, const VectorN& qdv, Scalar t, Output& out) noexcept {
    // Every vector of `out` is written below on success, and fail() resets them all: only what
    // accumulates starts afresh here.
    out.unmet_rows = 0;
    out.saturation_scale = Scalar(1);
    evaluate_model(model_, qv, qdv, t, terms_);
    if constexpr (ActuatedModel<M>) model_.actuation(qv, t, b_);  // else B = I, set once
    out.constraint_error = terms_.constraint_error;
    out.constraint_error_rate = terms_.constraint_error_rate;
    if constexpr (kHasPlainCase) {
      // A non-finite e or e' (which the plain law's solver does not read) goes the general way,
      // which names every non-finite input.
      if (plain_case() && small_dense::all_finite(terms_.constraint_error.data(), P) &&
          small_dense::all_finite(terms_.constraint_error_rate.data(), P))
        return evaluate_plain(out);
      return evaluate_general_out_of_line(out);
    } else {
      return evaluate_general(out);
    }
  }

  // evaluate_general as its own body, for a model with a plain case: the attribute cannot depend
  // on the model, so the call site chooses between this and the inlined evaluate_general.
  [[gnu::noinline, gnu::flatten]] Status evaluate_general_out_of_line(Output& out) noexcept {
    return evaluate_general(out);
  }

  // The general law on the model's terms (terms_, b_): u of least u^T W u whose B u meets the
  // active task rows with the physical rows held.
  Status evaluate_general(Output& out) noexcept {
    out.diagnostics = SolveDiagnostics<Scalar>{};
    using small_dense::all_finite;
    std::uint32_t bad = 0;
    if constexpr (kMassMatrixOf<M> == MassMatrix::kDiagonal) {  // read on its diagonal only
      for (int i = 0; i < N; ++i)
        if (!std::isfinite(terms_.mass_matrix(i, i))) bad |= input::kMassMatrix;
    } else if (!all_finite(terms_.mass_matrix.data(), N * N)) {
      bad |= input::kMassMatrix;
    }
    if (!all_finite(terms_.nonlinear_force.data(), N)) bad |= input::kNonlinearForce;
    if (!all_finite(terms_.applied_force.data(), N)) bad |= input::kAppliedForce;
    if (!all_finite(terms_.constraint_matrix.data(), P * N)) bad |= input::kConstraintMatrix;
    if (!all_finite(terms_.constraint_rhs.data(), P) ||
        !all_finite(terms_.constraint_error.data(), P) ||
        !all_finite(terms_.constraint_error_rate.data(), P))
      bad |= input::kConstraintRhs;
    if constexpr (ActuatedModel<M>)
      if (!all_finite(b_.data(), N * K)) bad |= input::kActuation;
    if (bad != 0) return fail(out, Status::kNonFiniteInput, bad);

    VectorP correction;
    const bool corrected = corrections(correction);

    // A = L L^T; a = A^-1 (Q - f); L^-1 B; C^T = L^-1 D^T.
    if (!factor_mass()) return fail(out, Status::kMassMatrixNotPositiveDefinite, 0);
    VectorN a = terms_.applied_force - terms_.nonlinear_force;
    solve_l(a);
    solve_lt(a);
    // Without B and with Gauss's weight (W = A^-1 = L^-T L^-1) the square root W^(1/2) = L^-1
    // makes the scaled task matrix D L^-T = C itself and u = L C^+ r: eq. (32) with no basis of
    // B to build (kIdentityGauss below). L^-1 B is needed otherwise.
    const bool identity_gauss = !ActuatedModel<M> && gauss_weight_;
    MatrixNK lb;
    if (!identity_gauss) {
      lb = b_;
      solve_l(lb);
    }
    Eigen::Matrix<Scalar, N, P> ct = terms_.constraint_matrix.transpose();
    solve_l(ct);
    const Scalar eps = std::numeric_limits<Scalar>::epsilon();

    // The task rows' C_c^T, and with physical rows: a_p, and C_c^T projected onto the directions
    // the physical rows leave free (the projector is symmetric, so C_c P_n = (P_n C_c^T)^T).
    // An inactive row's column is zero: the SVD below gives its direction up exactly.
    // Without physical rows every row is a task row, in order: C_c^T is C^T itself (kept in place).
    Eigen::Matrix<Scalar, N, kTask> ctc_copy;
    Eigen::Matrix<Scalar, N, kTask>& ctc = [&]() -> Eigen::Matrix<Scalar, N, kTask>& {
      if constexpr (kPhysical == 0)
        return ct;
      else
        return ctc_copy;
    }();
    int active_rows = 0;
    Scalar active_reach2 = Scalar(0);  // ||C_c||_F^2 of the active rows, before any projection
    for (int j = 0; j < kTask; ++j) {
      const int row = kTaskRows[static_cast<std::size_t>(j)];
      if (active_[static_cast<std::size_t>(row)]) {
        if constexpr (kPhysical > 0) ctc.col(j) = ct.col(row);
        active_reach2 += ctc.col(j).squaredNorm();
        ++active_rows;
      } else {
        ctc.col(j).setZero();
      }
    }
    if constexpr (kPhysical > 0) {
      Eigen::Matrix<Scalar, N, kPhysical> up;  // C_p^T, then U_p
      Eigen::Matrix<Scalar, kPhysical, 1> sp, rp;
      Eigen::Matrix<Scalar, kPhysical, kPhysical> vp;
      for (int j = 0; j < kPhysical; ++j) {
        const int row = kPhysicalRows[static_cast<std::size_t>(j)];
        up.col(j) = ct.col(row);
        rp(j) = terms_.constraint_rhs(row) - terms_.constraint_matrix.row(row).dot(a);
      }
      if (!small_dense::jacobi_svd_fixed<N, kPhysical>(up.data(), sp.data(), vp.data()))
        return fail(out, Status::kNonFiniteResult, 0);
      const Scalar tol =
          (options_.solver.rank_tolerance > Scalar(0) ? options_.solver.rank_tolerance
                                                      : Scalar(N) * eps) *
          sp(0);
      free_basis_rank_ = 0;
      for (int j = 0; j < kPhysical; ++j)
        if (sp(j) > tol) ++free_basis_rank_;
      // a_p = a + L^-T C_p^+ (g_p - D_p a), C_p^+ = U_p S_p^+ V_p^T.
      VectorN shift = VectorN::Zero();
      for (int j = 0; j < free_basis_rank_; ++j) shift += up.col(j) * (vp.col(j).dot(rp) / sp(j));
      solve_lt(shift);
      a += shift;
      physical_basis_ = up;
      project_free(ctc);
    }

    // The actuated directions G (N x K) with D A^-1 B W^(-1/2) = C G, and back = the map from the
    // pseudo-inverse's answer to u.
    MatrixNK g_dirs;
    MatrixKK back;
    if (identity_gauss) {
      // G = I, back = L: set below without the products.
    } else if (gauss_weight_) {
      if constexpr (K > N) {
        return fail(out, Status::kWeightNotPositiveDefinite, 0);  // more actuators than coordinates
      } else {
        // L^-1 B = U R by Gram-Schmidt, each column orthogonalized twice (enough for orthogonality
        // to rounding); W = R^T R.
        g_dirs = lb;
        MatrixKK r = MatrixKK::Zero();
        const Scalar largest = lb.colwise().norm().maxCoeff();
        for (int j = 0; j < K; ++j) {
          for (int pass = 0; pass < 2; ++pass)
            for (int i = 0; i < j; ++i) {
              const Scalar c = g_dirs.col(i).dot(g_dirs.col(j));
              r(i, j) += c;
              g_dirs.col(j) -= c * g_dirs.col(i);
            }
          r(j, j) = g_dirs.col(j).norm();
          // Columns dependent to within sqrt(eps) (exactly dependent ones leave rounding here):
          // W's condition would exceed 1 / eps.
          if (!(r(j, j) > std::sqrt(eps) * largest))
            return fail(out, Status::kWeightNotPositiveDefinite, 0);
          g_dirs.col(j) /= r(j, j);
        }
        back = MatrixKK::Identity();  // R^-1 by back substitution: u = R^-1 (C U)^+ r
        for (int c = 0; c < K; ++c)
          for (int i = K - 1; i >= 0; --i) {
            Scalar v = back(i, c);
            for (int k = i + 1; k < K; ++k) v -= r(i, k) * back(k, c);
            back(i, c) = v / r(i, i);
          }
      }
    } else {
      // G = L^-1 B Lw^-T: G^T = Lw^-1 (L^-1 B)^T.
      Eigen::Matrix<Scalar, K, N> gt = lb.transpose();
      small_dense::solve_lower_in_place(weight_factor_, gt);
      g_dirs = gt.transpose();
      back = MatrixKK::Identity();
      small_dense::solve_lower_transposed_in_place(weight_factor_, back);  // Lw^-T
    }
    // T^T (K x kTask), the scaled task matrix transposed: one column per task row. Without B it
    // is C_c^T itself.
    Eigen::Matrix<Scalar, K, kTask> task_t_storage;
    const Eigen::Matrix<Scalar, K, kTask>* task_t_ptr = &task_t_storage;
    bool task_is_ctc = false;
    if constexpr (!ActuatedModel<M>) {
      if (identity_gauss) {
        task_t_ptr = &ctc;
        task_is_ctc = true;
      }
    }
    if (!task_is_ctc) task_t_storage.noalias() = g_dirs.transpose() * ctc;
    const Eigen::Matrix<Scalar, K, kTask>& task_t = *task_t_ptr;

    // With Gauss's weight the task's singular values are those of D A^(-1/2) along the actuated
    // directions: they are measured against D A^(-1/2) itself (its Frobenius norm), so that
    // actuators that barely reach the rows (one row, one actuator, its reach vanishing) show as
    // ill-conditioned instead of a condition of 1.
    // The reach is that of the active task rows before the physical rows' projection: a task row
    // the physical rows already hold (or nearly) then shows as lost, not as a full-rank row of
    // rounding-sized singular values. The default relative tolerance covers the projection's
    // rounding too.
    constexpr int kRows = K >= kTask ? K : kTask;
    constexpr int kCols = K >= kTask ? kTask : K;
    const Scalar unprojected = std::sqrt(active_reach2);
    const Scalar relative_tolerance = options_.solver.rank_tolerance > Scalar(0)
                                          ? options_.solver.rank_tolerance
                                          : Scalar(kPhysical > 0 ? kRows + N : kRows) * eps;

    // The pseudo-inverse of the task matrix T. The default strategy answers a task of full row
    // rank by its normal equations, x = T^T (T T^T)^-1 r (the plain law's own path for eq. 32),
    // when every task row is active and the Cholesky factor's bounds show T well conditioned
    // (reciprocal condition of T T^T at least fallback_rcond) with every singular value above the
    // rank tolerance and the floor; otherwise, and for the other strategies, the one-sided Jacobi
    // SVD decides exactly which directions to keep.
    Eigen::Matrix<Scalar, kTask, kTask> gram_l_inv;  // normal equations: L_G^-1, T T^T = L_G L_G^T
    bool normal = false;
    Scalar sigma_hi = Scalar(0), sigma_lo = Scalar(0), reach = Scalar(0);
    if constexpr (kTask >= 1 && kTask <= K) {
      if (options_.solver.strategy == InverseStrategy::kCholeskyWithFallback &&
          active_rows == kTask) {
        Eigen::Matrix<Scalar, kTask, kTask> gram;
        for (int j = 0; j < kTask; ++j)
          for (int i = j; i < kTask; ++i)
            gram(i, j) = gram(j, i) = task_t.col(i).dot(task_t.col(j));
        Scalar norm1 = Scalar(0);  // ||T T^T||_1 >= sigma_max^2
        for (int j = 0; j < kTask; ++j) norm1 = std::max(norm1, gram.col(j).cwiseAbs().sum());
        if (small_dense::all_finite(gram.data(), kTask * kTask) &&
            small_dense::cholesky_in_place(gram)) {
          const Scalar inverse_norm2 =
              small_dense::invert_lower(gram, gram_l_inv);  // >= 1 / sigma_min^2
          sigma_hi = std::sqrt(norm1);
          sigma_lo = Scalar(1) / std::sqrt(inverse_norm2);
          reach = gauss_weight_ ? std::max(sigma_hi, unprojected) : sigma_hi;
          const Scalar rcond = Scalar(1) / (norm1 * inverse_norm2);
          normal =
              rcond >= options_.solver.fallback_rcond && std::isfinite(rcond) &&
              rcond > Scalar(0) &&
              sigma_lo > std::max(relative_tolerance * reach, options_.solver.min_singular_value);
        }
      }
    }

    // Otherwise the thin SVD of the task matrix (or of its transpose, so that rows >= columns).
    Eigen::Matrix<Scalar, kRows, kCols> w;
    Eigen::Matrix<Scalar, kCols, 1> sigma;
    Eigen::Matrix<Scalar, kCols, kCols> v;
    Eigen::Matrix<Scalar, kCols, 1> inverse = Eigen::Matrix<Scalar, kCols, 1>::Zero();
    int rank = kTask;
    bool near_singular = false;
    if (!normal) {
      if constexpr (K >= kTask)
        w = task_t;
      else
        w = task_t.transpose();
      if (!small_dense::jacobi_svd_fixed<kRows, kCols>(w.data(), sigma.data(), v.data()))
        return fail(out, Status::kNonFiniteResult, 0);
      reach = gauss_weight_ ? std::max(sigma(0), unprojected) : sigma(0);
      const Scalar relative = relative_tolerance * reach;
      const Scalar floor = std::max(relative, options_.solver.min_singular_value);
      rank = 0;
      for (int i = 0; i < kCols; ++i) {
        if (sigma(i) > floor) {
          inverse(i) = Scalar(1) / sigma(i);
          ++rank;
        } else if (sigma(i) > relative) {
          near_singular = true;
        }
      }
      sigma_hi = sigma(0);
      sigma_lo = rank > 0 ? sigma(rank - 1) : Scalar(0);
    }
    // X = T^+ R for the parts of r at once (their task rows: -D_c a_p, g_c, and the correction
    // when a row has one); U = back X (U = L X without B).
    const VectorP drift = -(terms_.constraint_matrix * a);  // a is a_p here
    VectorN unmapped;  // without B: the parts' sum before u = L x (then L^-1 u needs no solve)
    auto solve_parts = [&](auto& rhs, auto& x) {  // rhs: kTask x C, x: K x C
      constexpr int C = std::remove_reference_t<decltype(rhs)>::ColsAtCompileTime;
      for (int j = 0; j < kTask; ++j) {
        const int row = kTaskRows[static_cast<std::size_t>(j)];
        const bool on = active_[static_cast<std::size_t>(row)];
        rhs(j, 0) = on ? drift(row) : Scalar(0);
        rhs(j, 1) = on ? terms_.constraint_rhs(row) : Scalar(0);
        if constexpr (C == 3) rhs(j, 2) = on ? correction(row) : Scalar(0);
      }
      if (normal) {
        if constexpr (kTask >= 1 && kTask <= K) {
          small_dense::multiply_lower_in_place(gram_l_inv, rhs);             // L_G^-1 R
          small_dense::multiply_lower_transposed_in_place(gram_l_inv, rhs);  // (T T^T)^-1 R
          x.noalias() = task_t * rhs;
        }
      } else if constexpr (K >= kTask) {
        x.noalias() = w * (inverse.asDiagonal() * (v.transpose() * rhs));  // task^T = w S v^T
      } else {
        x.noalias() = v * (inverse.asDiagonal() * (w.transpose() * rhs));  // task = w S v^T
      }
      bool mapped = false;
      if constexpr (!ActuatedModel<M>) {
        if (identity_gauss) {
          for (int i = 0; i < N; ++i) unmapped(i) = x.row(i).sum();  // L^-1 u, before scaling
          multiply_l(x);
          mapped = true;
        }
      }
      if (!mapped) x = (back * x).eval();
    };
    Eigen::Matrix<Scalar, K, 3> parts;
    if (corrected) {
      Eigen::Matrix<Scalar, kTask, 3> rhs;
      solve_parts(rhs, parts);
    } else {  // no correction: its column is zero, and not computed
      Eigen::Matrix<Scalar, kTask, 2> rhs;
      Eigen::Matrix<Scalar, K, 2> two;
      solve_parts(rhs, two);
      parts.template leftCols<2>() = two;
      parts.col(2).setZero();
    }
    out.control_closed_loop = parts.col(0);
    out.control_feedforward = parts.col(1);
    out.control_stabilizing = parts.col(2);
    out.control = out.control_closed_loop + out.control_feedforward + out.control_stabilizing;
    if (!small_dense::all_finite(out.control.data(), K))
      return fail(out, Status::kNonFiniteResult, 0);

    SolveDiagnostics<Scalar>& d = out.diagnostics;
    d.strategy_used = normal ? InverseStrategy::kCholeskyWithFallback : InverseStrategy::kSvd;
    // The normal equations were the strategy's first choice and could not answer, as in the plain
    // law.
    if (!normal && options_.solver.strategy == InverseStrategy::kCholeskyWithFallback &&
        active_rows == kTask && kTask <= K)
      d.warnings |= warning::kFellBackToSvd;
    d.rank = rank;
    d.sigma_max = sigma_hi;
    d.sigma_min_kept = sigma_lo;
    d.condition_estimate = rank > 0 ? reach / sigma_lo : Scalar(0);
    if (rank < active_rows) d.warnings |= warning::kRankDeficient;
    if (near_singular) d.warnings |= warning::kNearSingular;
    if (d.condition_estimate > options_.solver.warn_condition)
      d.warnings |= warning::kIllConditioned;
    // The history of kVanishingReach: the active rows' own reach (the weight and the physical
    // rows aside), and nothing to judge with every row switched off.
    if (active_rows > 0) {
      d.sigma_max = unprojected;
      reach_seen_ = flag_vanishing_reach(options_.solver.vanishing_ratio, reach_seen_, d);
    }
    d.sigma_max = sigma_hi;

    saturate(out);
    if constexpr (ActuatedModel<M>) {
      out.force = b_ * out.control;
      out.closed_loop = b_ * out.control_closed_loop;
      out.feedforward = b_ * out.control_feedforward;
      out.stabilizing = b_ * out.control_stabilizing;
    } else {  // B = I
      out.force = out.control;
      out.closed_loop = out.control_closed_loop;
      out.feedforward = out.control_feedforward;
      out.stabilizing = out.control_stabilizing;
    }
    // q'' = a_p + M_p B u = a_p + L^-T P_n (L^-1 B) u.
    VectorN pushed;
    if constexpr (!ActuatedModel<M>) {
      if (identity_gauss) {
        pushed = unmapped;
        if (out.saturation_scale < Scalar(1)) {  // scaled, and clamped to the limits: from u itself
          pushed = out.control;
          solve_l(pushed);
        }
      } else {
        pushed = lb * out.control;
      }
    } else {
      pushed = lb * out.control;
    }
    if constexpr (kPhysical > 0) project_free(pushed);
    solve_lt(pushed);
    out.acceleration = a + pushed;
    if (!small_dense::all_finite(out.force.data(), N) ||
        !small_dense::all_finite(out.acceleration.data(), N))
      return fail(out, Status::kNonFiniteResult, 0);

    judge_rows(terms_.constraint_rhs + correction, out, nullptr);
    return d.status;
  }

  // Every row active, and Gauss's weight under the default or the SVD strategy (the ones whose
  // answer is the Moore-Penrose one with the same tolerances): eq. (32) itself.
  bool plain_case() const noexcept {
    return gauss_weight_ && inactive_rows_ == 0 &&
           (options_.solver.strategy == InverseStrategy::kCholeskyWithFallback ||
            options_.solver.strategy == InverseStrategy::kSvd);
  }

  // A model without B or physical rows, in the plain case: u = Q' of eq. (32) (B = I and Gauss's
  // weight W = A^-1 make the least-cost command the least-constraint force), computed by the plain
  // law's solver, with this controller's limits, rows' judgement and reach history.
  Status evaluate_plain(Output& out) noexcept {
    VectorP correction;
    const bool corrected = corrections(correction);
    const VectorP g = terms_.constraint_rhs + correction;
    auto& solution = plain_solution_;
    const Status status = plain_solver_.solve(terms_.mass_matrix, terms_.nonlinear_force, terms_.applied_force,
                                              terms_.constraint_matrix, g, solution);
    if (failed(status)) return fail(out, status, solution.diagnostics.non_finite_inputs);
    SolveDiagnostics<Scalar>& d = out.diagnostics;
    d = solution.diagnostics;
    d.warnings &= ~warning::kConstraintsNotMet;  // judged row by row below
    reach_seen_ = flag_vanishing_reach(options_.solver.vanishing_ratio, reach_seen_, d);
    out.control = solution.constraint_force;
    out.control_closed_loop = solution.force_from_impressed;
    out.control_stabilizing = corrected ? plain_solver_.force_for_rhs(correction) : VectorN::Zero();
    out.control_feedforward = solution.force_from_rhs - out.control_stabilizing;
    saturate(out);
    out.force = out.control;
    out.closed_loop = out.control_closed_loop;
    out.feedforward = out.control_feedforward;
    out.stabilizing = out.control_stabilizing;
    // q'' = a + A^-1 u is affine in u: scaling u scales q'' - a alike.
    const VectorN& a = solution.unconstrained_acceleration;
    out.acceleration = out.saturation_scale < Scalar(1)
                           ? VectorN(a + out.saturation_scale * (solution.acceleration - a))
                           : solution.acceleration;
    // The solver's residual is the one of its own q'' (a scaled u moves it).
    judge_rows(g, out, out.saturation_scale < Scalar(1) ? nullptr : &solution.residual);
    return d.status;
  }

  // Baumgarte's correction and the robust term of every active task row; true when some row has
  // either (else the correction is zero).
  bool corrections(VectorP& correction) const noexcept {
    correction.setZero();
    bool corrected = false;
    for (int i = 0; i < P; ++i) {
      if (RowLayout<M>::physical(i) || !active_[static_cast<std::size_t>(i)]) continue;
      const auto k = static_cast<std::size_t>(i);
      if (!row_gains_[k].enabled() && !row_robust_[k].enabled()) continue;
      corrected = true;
      correction(i) = row_correction(row_gains_[k], row_robust_[k], terms_.constraint_error(i),
                                     terms_.constraint_error_rate(i));
    }
    return corrected;
  }

  // Actuator limits: u and its parts scaled as a whole.
  void saturate(Output& out) const noexcept {
    for (int i = 0; i < K; ++i) {
      const Scalar magnitude = std::abs(out.control(i));
      if (magnitude > limit_(i))
        out.saturation_scale = std::min(out.saturation_scale, limit_(i) / magnitude);
    }
    if (out.saturation_scale < Scalar(1)) {
      const Scalar k = out.saturation_scale;
      out.control *= k;
      out.control_closed_loop *= k;
      out.control_feedforward *= k;
      out.control_stabilizing *= k;
      out.control = out.control.cwiseMax(-limit_).cwiseMin(limit_);
      out.diagnostics.warnings |= warning::kSaturated;
    }
  }

  // Which rows are met: |D_i q'' - g_i| against the residual tolerance at the row's own scale
  // (g stabilized); unmet_rows, the residual and kConstraintsNotMet. `residual`: D q'' - g and its
  // norm in the diagnostics already, when the plain law's solver gave them for this q''.
  void judge_rows(const VectorP& g, Output& out, const VectorP* residual) const noexcept {
    SolveDiagnostics<Scalar>& d = out.diagnostics;
    if (residual != nullptr)
      out.row_residual = *residual;
    else
      out.row_residual = terms_.constraint_matrix * out.acceleration - g;
    const Scalar tol2 = options_.solver.residual_tolerance * options_.solver.residual_tolerance;
    Scalar residual2 = Scalar(0);
    Scalar acceleration2 = Scalar(-1);  // |q''|^2, once a row needs it
    for (int i = 0; i < P; ++i) {
      // Squared: |r_i|^2 <= tol^2 (g_i^2 + |D_i|^2 |q''|^2), false for NaN; the row's norm only
      // when g_i alone does not settle it. Squares beyond the range (from about 1e154) would pass
      // any residual (Inf <= Inf): then the same test on norms taken without squaring.
      const Scalar r2 = out.row_residual(i) * out.row_residual(i);
      if (residual == nullptr) residual2 += r2;
      const Scalar g2 = g(i) * g(i);
      if (r2 <= tol2 * g2 && g2 <= std::numeric_limits<Scalar>::max()) continue;
      if (acceleration2 < Scalar(0)) acceleration2 = out.acceleration.squaredNorm();
      const Scalar scale2 = g2 + terms_.constraint_matrix.row(i).squaredNorm() * acceleration2;
      // (A residual whose square overflowed beside a finite scale is unmet, rightly.)
      const bool met = scale2 <= std::numeric_limits<Scalar>::max() ? r2 <= tol2 * scale2
                                                                   : met_unsquared(i, g(i), out);
      if (!met && i < 64 && active_[static_cast<std::size_t>(i)])
        out.unmet_rows |= std::uint64_t{1} << i;
    }
    if (residual == nullptr)
      d.residual_norm = std::isfinite(residual2) ? std::sqrt(residual2)
                                                 : small_dense::scaled_norm(out.row_residual.data(), P);
    if (out.unmet_rows != 0) d.warnings |= warning::kConstraintsNotMet;
  }

  // Row i's test |r_i| <= tol (|g_i| + |D_i| |q''|) on norms taken without squaring (rare: kept
  // out of the loop above).
  [[gnu::noinline]] bool met_unsquared(int i, Scalar g_i, const Output& out) const noexcept {
    Scalar row[N];
    for (int j = 0; j < N; ++j) row[j] = terms_.constraint_matrix(i, j);
    const Scalar scale =
        std::abs(g_i) + small_dense::scaled_norm(row, N) * small_dense::scaled_norm(out.acceleration.data(), N);
    return std::abs(out.row_residual(i)) <= options_.solver.residual_tolerance * scale;
  }

  // A = L L^T: Cholesky, or square roots of a declared-diagonal A (read on its diagonal only).
  bool factor_mass() noexcept {
    if constexpr (kMassMatrixOf<M> == MassMatrix::kDiagonal) {
      for (int i = 0; i < N; ++i) {
        const Scalar m = terms_.mass_matrix(i, i);
        if (!(m > Scalar(0))) return false;
        l_diag_(i) = std::sqrt(m);
        l_inv_diag_(i) = Scalar(1) / l_diag_(i);
        l_(i, i) = l_diag_(i);
      }
      return true;
    } else {
      l_ = terms_.mass_matrix;
      return small_dense::cholesky_in_place(l_, l_inv_diag_.data());
    }
  }
  template <int Cols>
  void solve_l(Eigen::Matrix<Scalar, N, Cols>& x) const noexcept {  // x = L^-1 x
    if constexpr (kMassMatrixOf<M> == MassMatrix::kDiagonal)
      scale_rows(l_inv_diag_, x);
    else
      small_dense::solve_lower_in_place(l_, l_inv_diag_.data(), x);
  }
  template <int Cols>
  void solve_lt(Eigen::Matrix<Scalar, N, Cols>& x) const noexcept {  // x = L^-T x
    if constexpr (kMassMatrixOf<M> == MassMatrix::kDiagonal)
      scale_rows(l_inv_diag_, x);
    else
      small_dense::solve_lower_transposed_in_place(l_, l_inv_diag_.data(), x);
  }
  template <int Cols>
  void multiply_l(Eigen::Matrix<Scalar, N, Cols>& x) const noexcept {  // x = L x
    if constexpr (kMassMatrixOf<M> == MassMatrix::kDiagonal)
      scale_rows(l_diag_, x);
    else
      small_dense::multiply_lower_in_place(l_, x);
  }

  // x = diag(d) x, in place (plain loops: inlined where Eigen's unrolled product is not).
  template <int Cols>
  static void scale_rows(const VectorN& d, Eigen::Matrix<Scalar, N, Cols>& x) noexcept {
    for (int c = 0; c < Cols; ++c)
      for (int i = 0; i < N; ++i) x(i, c) *= d(i);
  }

  // x -= U_p (U_p^T x): onto the directions the physical rows leave free.
  template <int Cols>
  void project_free(Eigen::Matrix<Scalar, N, Cols>& x) const noexcept {
    for (int c = 0; c < Cols; ++c)
      for (int j = 0; j < free_basis_rank_; ++j)
        x.col(c) -= physical_basis_.col(j) * physical_basis_.col(j).dot(x.col(c));
  }

  [[gnu::noinline]] static Status fail(Output& out, Status status, std::uint32_t inputs) noexcept {
    const VectorP e = out.constraint_error, e_rate = out.constraint_error_rate;
    out = Output{};
    out.constraint_error = e;
    out.constraint_error_rate = e_rate;
    out.diagnostics.status = status;
    out.diagnostics.non_finite_inputs = inputs;
    return status;
  }

  [[noreturn]] static void config_error(const char* problem) {
#if defined(__cpp_exceptions)
    throw std::invalid_argument(std::string("gausstrack::ActuatedController: ") + problem);
#else
    (void)problem;
    __builtin_trap();
#endif
  }

  // A model without B and without physical rows, and with no more rows than coordinates (more
  // are necessarily redundant: the general path answers them in the least-squares sense), has a
  // plain case (plain_case): its solver, kept only for such a model.
  static constexpr bool kHasPlainCase = !ActuatedModel<M> && kPhysical == 0 && P <= N;
  struct NoPlainCase {
    explicit NoPlainCase(const SolverOptions<Scalar>&) noexcept {}
  };
  using PlainSolver =
      std::conditional_t<kHasPlainCase, ConstraintSolver<N, P, Scalar, kMassMatrixOf<M>>, NoPlainCase>;
  using PlainSolution = std::conditional_t<kHasPlainCase, ConstraintSolution<N, P, Scalar>, NoPlainCase*>;
  // The reach's history is this controller's, over both of its paths.
  static SolverOptions<Scalar> plain_solver_options(SolverOptions<Scalar> options) noexcept {
    options.vanishing_ratio = Scalar(0);
    return options;
  }

  M model_;
  Options options_;
  PlainSolver plain_solver_;
  PlainSolution plain_solution_{};
  std::array<Stabilization<Scalar>, static_cast<std::size_t>(P)> row_gains_{};
  std::array<Robust<Scalar>, static_cast<std::size_t>(P)> row_robust_{};
  VectorK limit_ = VectorK::Constant(std::numeric_limits<Scalar>::infinity());
  bool gauss_weight_ = true;
  MatrixKK weight_factor_ = MatrixKK::Identity();
  TermsOf<M> terms_{};
  MatrixNK b_ = ActuatedModel<M> ? MatrixNK(MatrixNK::Zero()) : MatrixNK(MatrixNK::Identity());
  Eigen::Matrix<Scalar, N, N> l_ =
      Eigen::Matrix<Scalar, N, N>::Zero();  // A = L L^T (lower triangle)
  VectorN l_diag_ = VectorN::Zero(),
          l_inv_diag_ = VectorN::Zero();  // a declared-diagonal A's L and L^-1; 1 / L_kk for a dense A
  HoldPrediction<N, Scalar> prediction_;  ///< the hold's memory
  static constexpr std::array<int, static_cast<std::size_t>(kTask)> kTaskRows =
      detail::rows_of_kind<M, false, kTask>();
  static constexpr std::array<int, static_cast<std::size_t>(kPhysical)> kPhysicalRows =
      detail::rows_of_kind<M, true, kPhysical>();
  // U_p's leading free_basis_rank_ columns span the directions the physical rows constrain.
  Eigen::Matrix<Scalar, N, (kPhysical > 0 ? kPhysical : 1)> physical_basis_ =
      Eigen::Matrix<Scalar, N, (kPhysical > 0 ? kPhysical : 1)>::Zero();
  int free_basis_rank_ = 0;
  Scalar reach_seen_ = Scalar(0);  ///< the largest reach computed (kVanishingReach)
  /// Rows switched on (physical rows stay true: they are always held).
  std::array<bool, static_cast<std::size_t>(P)> active_ = all_active();
  int inactive_rows_ = 0;  ///< task rows switched off
  static constexpr std::array<bool, static_cast<std::size_t>(P)> all_active() noexcept {
    std::array<bool, static_cast<std::size_t>(P)> a{};
    for (bool& b : a) b = true;
    return a;
  }
};

/// The controller for model M: ActuatedController when M declares actuators or physical rows, else
/// TrackingController (every coordinate actuated, every row a task). Both compute(q, qd, t, out)
/// into an output with force, closed_loop, feedforward, stabilizing, saturation_scale and
/// diagnostics, and take set_stabilization and set_hold.
template <Model M>
struct LawForModel {
  using type = TrackingController<M>;
};
template <Model M>
requires(ActuatedModel<M> || RowLayout<M>::kPhysical > 0) struct LawForModel<M> {
  using type = ActuatedController<M>;
};
template <Model M>
using LawFor = typename LawForModel<M>::type;

}  // namespace gausstrack
