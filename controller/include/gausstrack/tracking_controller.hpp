// Tracking control law: the constraint force of eq. (32) for a measured state, split into a
// closed-loop part, a feedforward part and an optional constraint-stabilizing part.
#pragma once

#include <array>
#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "gausstrack/constraint_solver.hpp"
#include "gausstrack/model.hpp"

namespace gausstrack {

/// Constraint stabilization by Baumgarte's method (Baumgarte, Comput. Methods Appl. Mech. Eng. 1,
/// 1972), per constraint row: g_i is replaced by g_i - 2 zeta omega e'_i - omega^2 e_i, so that
/// a holonomic row's error obeys e'' + 2 zeta omega e' + omega^2 e = 0 instead of e'' = 0 (which
/// keeps any initial error and lets rounding, sampling and model error drift). A nonholonomic row
/// has no position error (e = 0): its velocity-level error obeys e'' + 2 zeta omega e' = 0, i.e.
/// decays at the rate 2 zeta omega. A hand-written row is stabilized through the e and e' its model
/// writes (none: no effect). omega = 0 (the default) reproduces the paper's law exactly.
template <typename Scalar>
struct Stabilization {
  Scalar zeta = Scalar(1);   ///< damping ratio [-]
  Scalar omega = Scalar(0);  ///< natural frequency [rad/s]; 0 disables stabilization
  bool enabled() const noexcept { return omega > Scalar(0); }
};

/// A robust term for a model that is wrong, per row: with a declared bound rho on the model's
/// error at the row's acceleration level (|D_i q''_plant - D_i q''_model| <= rho [row units/s^2]),
/// the row's g gains -rho sat(s / Phi), s = e' + omega e the row's sliding variable (omega the
/// row's Baumgarte frequency; e = 0 for a nonholonomic row), sat(x) = max(-1, min(1, x)): the
/// generalized sliding surface of Udwadia and Wanichanon's control of uncertain multibody
/// systems, with a boundary layer of width Phi [row units/s] so that the force stays continuous.
/// With Baumgarte's gains at zeta = 1, s' = -omega s - rho sat(s / Phi) + delta: outside the layer
/// s shrinks at least like e^(-omega t), inside it |s| <= rho / (omega + rho / Phi), so that a
/// holonomic row's error ends within
///   |e| <= rho / (omega (omega + rho / Phi))                     (robust_error_bound)
/// against rho / omega^2 with stabilization alone: 1 + rho / (omega Phi) times smaller, at the
/// price of a gain rho / Phi inside the layer. bound = 0 (the default): no robust term.
template <typename Scalar>
struct Robust {
  Scalar bound = Scalar(0);  ///< rho [row units/s^2]; 0 disables the term
  Scalar layer = Scalar(1);  ///< Phi [row units/s], > 0
  bool enabled() const noexcept { return bound > Scalar(0); }
  /// nullptr when usable, else what is wrong.
  const char* validate() const noexcept {
    if (!std::isfinite(bound) || !(bound >= Scalar(0))) return "robust.bound must be finite and >= 0";
    if (!std::isfinite(layer) || !(layer > Scalar(0))) return "robust.layer must be finite and > 0";
    return nullptr;
  }
};

/// The ultimate bound the robust term promises on a holonomic row's error (Robust's formula), in
/// continuous time, for a task the law meets without saturation; infinity when either is off or
/// zeta != 1 (then s = e' + omega e does not factor Baumgarte's dynamics and no bound is promised).
template <typename Scalar>
Scalar robust_error_bound(const Stabilization<Scalar>& s, const Robust<Scalar>& r) noexcept {
  if (!s.enabled() || !r.enabled() || s.zeta != Scalar(1)) return std::numeric_limits<Scalar>::infinity();
  return r.bound / (s.omega * (s.omega + r.bound / r.layer));
}

/// The correction to one row's g: Baumgarte's, -2 zeta omega e' - omega^2 e, plus the robust
/// term, -rho sat((e' + omega e) / Phi). Shared by the controllers.
template <typename Scalar>
Scalar row_correction(const Stabilization<Scalar>& s, const Robust<Scalar>& r, Scalar e, Scalar e_rate) noexcept {
  Scalar c = Scalar(0);
  if (s.enabled()) c = -(Scalar(2) * s.zeta * s.omega) * e_rate - (s.omega * s.omega) * e;
  if (r.enabled()) {
    const Scalar x = (e_rate + s.omega * e) / r.layer;
    c -= r.bound * (x > Scalar(1) ? Scalar(1) : (x < Scalar(-1) ? Scalar(-1) : x));
  }
  return c;
}

/// Sampled-data control: the force computed for a state measured at t is applied from t + delay
/// and held for one period (zero-order hold). The law at the measured state, held, meets the
/// constraints to first order in the period; with a hold the controller evaluates the law at the
/// middle of the hold interval instead, t_m = t + delay + period / 2, at the state predicted
/// there through the constrained acceleration q'' it computes at t and the jerk j from the
/// previous sample's q'' (at most two periods earlier; else j = 0):
///   q_m = q + tau q' + tau^2 / 2 q'' + tau^3 / 6 j,  q'_m = q' + tau q'' + tau^2 / 2 j,
///   tau = delay + period / 2,
/// so that the held force is the continuous law's at the interval's midpoint and the constraints
/// are met over the interval to second order in the period (docs/sampled_law.md). Two
/// evaluations of the law per call. period = delay = 0 (the default): the law at the measured
/// state, as for continuous control.
template <typename Scalar>
struct Hold {
  Scalar period = Scalar(0);  ///< the hold's length [s]
  Scalar delay = Scalar(0);   ///< from the measurement to the force's application [s]
  bool enabled() const noexcept { return period > Scalar(0) || delay > Scalar(0); }
  /// From the measurement to the middle of the hold interval [s].
  Scalar lead() const noexcept { return delay + period / Scalar(2); }
};

/// The hold's prediction, shared by the controllers: from the measured state and the constrained
/// acceleration the law computed there, the state at the middle of the hold interval (Hold's
/// formula), with the jerk from the previous sample of the same motion. Keeps the latest two
/// samples' accelerations; a call for the same t again (a repeated call) keeps the previous
/// sample, so that it answers as the first did; an earlier t starts a new motion.
template <int N, typename Scalar>
class HoldPrediction {
 public:
  using VectorN = Eigen::Matrix<Scalar, N, 1>;

  /// Writes (q_m, q'_m) at t + hold.lead() and remembers a for the next call.
  void predict(const Hold<Scalar>& hold, const VectorN& q, const VectorN& qd, Scalar t, const VectorN& a,
               VectorN& q_m, VectorN& qd_m) noexcept {
    if (!has_latest_ || t != t_latest_) {
      has_previous_ = has_latest_ && t > t_latest_;
      a_previous_ = a_latest_;
      t_previous_ = t_latest_;
    }
    a_latest_ = a;
    t_latest_ = t;
    has_latest_ = true;
    // The jerk from the acceleration of the previous sample (at most two periods earlier); else none.
    VectorN jerk = VectorN::Zero();
    const Scalar since = t - t_previous_;
    if (has_previous_ && since > Scalar(0) && since <= Scalar(2) * hold.period) jerk = (a - a_previous_) / since;
    const Scalar tau = hold.lead();
    q_m = q + tau * qd + (tau * tau / Scalar(2)) * a + (tau * tau * tau / Scalar(6)) * jerk;
    qd_m = qd + tau * a + (tau * tau / Scalar(2)) * jerk;
  }
  /// After a failed call: the next one starts a new motion.
  void forget() noexcept { has_latest_ = has_previous_ = false; }

 private:
  VectorN a_latest_ = VectorN::Zero(), a_previous_ = VectorN::Zero();
  Scalar t_latest_ = Scalar(0), t_previous_ = Scalar(0);
  bool has_latest_ = false, has_previous_ = false;
};

template <typename Scalar>
struct ControllerOptions {
  SolverOptions<Scalar> solver{};
  /// Gains for every row; TrackingController::set_stabilization changes one row's.
  Stabilization<Scalar> stabilization{};
  /// Sampled-data hold (none by default); TrackingController::set_hold changes it.
  Hold<Scalar> hold{};
  /// The robust term for every row (off by default); set_robust changes one row's.
  Robust<Scalar> robust{};

  /// nullptr when the options are usable, else what is wrong with them. Never throws.
  const char* validate() const noexcept {
    if (!std::isfinite(stabilization.zeta) || stabilization.zeta < Scalar(0))
      return "stabilization.zeta must be finite and >= 0";
    if (!std::isfinite(stabilization.omega) || stabilization.omega < Scalar(0))
      return "stabilization.omega must be finite and >= 0";
    if (!std::isfinite(hold.period) || hold.period < Scalar(0) || !std::isfinite(hold.delay) || hold.delay < Scalar(0))
      return "hold.period and hold.delay must be finite and >= 0";
    if (const char* problem = robust.validate()) return problem;
    if (!std::isfinite(solver.damping) || solver.damping < Scalar(0))
      return "solver.damping must be finite and >= 0";
    if (!std::isfinite(solver.min_singular_value) || solver.min_singular_value < Scalar(0))
      return "solver.min_singular_value must be finite and >= 0";
    if (!std::isfinite(solver.vanishing_ratio) || solver.vanishing_ratio < Scalar(0))
      return "solver.vanishing_ratio must be finite and >= 0";
    if (!std::isfinite(solver.rank_tolerance) || !std::isfinite(solver.fallback_rcond) ||
        !std::isfinite(solver.residual_tolerance) || !std::isfinite(solver.warn_condition))
      return "solver tolerances must be finite";
    return nullptr;
  }
};

/// Control force for one measured state, Q' = closed_loop + feedforward + stabilizing.
template <int N, int P, typename Scalar>
struct ControlOutput {
  using VectorN = Eigen::Matrix<Scalar, N, 1>;
  using VectorP = Eigen::Matrix<Scalar, P, 1>;
  VectorN force = VectorN::Zero();         ///< Q' to apply, eq. (32)                    [N]
  VectorN closed_loop = VectorN::Zero();   ///< (I - A X A^-1)(f - Q): depends on q, q', t [N]
  /// A (I - X) D^- g for the model's g. Purely feedforward (a function of t alone) when A, D and
  /// g depend on t only, as for the Duffing oscillator (the paper's remark after eq. 32).
  VectorN feedforward = VectorN::Zero();   ///<                                          [N]
  VectorN stabilizing = VectorN::Zero();   ///< force due to -2 zeta omega e' - omega^2 e  [N]
  VectorN acceleration = VectorN::Zero();  ///< q'' the force produces on the model, eq. (30)
  /// 1, or the factor the force and its parts were scaled by to meet the force limit
  /// (warning::kSaturated).
  Scalar saturation_scale = Scalar(1);
  VectorP constraint_error = VectorP::Zero();       ///< e: phi for holonomic rows, else 0 or the model's
  VectorP constraint_error_rate = VectorP::Zero();  ///< e': phi' or psi, or the model's
  SolveDiagnostics<Scalar> diagnostics;
};

/// Evaluates eq. (32) for a Model at a measured state: one evaluation of the model's terms
/// (evaluate_model), Baumgarte's correction per row, one solve. Allocation-free and exception-free
/// after construction.
template <Model M>
class TrackingController {
  static_assert(RowLayout<M>::kPhysical == 0,
                "a model with physical rows is controlled by ActuatedController (LawFor<M>), which "
                "leaves them "
                "to the environment");

 public:
  using Scalar = typename M::Scalar;
  static constexpr int N = M::kDof;
  static constexpr int P = M::kConstraints;
  using VectorN = Eigen::Matrix<Scalar, N, 1>;
  using VectorP = Eigen::Matrix<Scalar, P, 1>;
  using Output = ControlOutput<N, P, Scalar>;
  using Options = ControllerOptions<Scalar>;
  using Terms = TermsOf<M>;

  /// Throws std::invalid_argument (when exceptions are enabled; traps otherwise) if
  /// `options.validate()` reports a problem.
  explicit TrackingController(M model = M{}, const Options& options = Options{})
      : model_(std::move(model)), options_(options), solver_(options.solver) {
    if (const char* problem = options.validate()) config_error(problem);
    row_gains_.fill(options.stabilization);
    row_robust_.fill(options.robust);
  }

  M& model() noexcept { return model_; }
  const M& model() const noexcept { return model_; }
  const Options& options() const noexcept { return options_; }

  /// The robust term of one row (Robust). Returns false, changing nothing, for a row outside
  /// [0, P) or a term that does not validate.
  bool set_robust(int row, const Robust<Scalar>& robust) noexcept {
    if (row < 0 || row >= P || robust.validate() != nullptr) return false;
    row_robust_[static_cast<std::size_t>(row)] = robust;
    return true;
  }
  Robust<Scalar> robust(int row) const noexcept {
    return row < 0 || row >= P ? Robust<Scalar>{} : row_robust_[static_cast<std::size_t>(row)];
  }

  /// Baumgarte gains of one constraint row (rows in the model's order: holonomic, nonholonomic,
  /// hand-written). Returns false, changing nothing, for a row outside [0, P) or gains that are
  /// not finite and >= 0.
  bool set_stabilization(int row, const Stabilization<Scalar>& gains) noexcept {
    if (row < 0 || row >= P || !std::isfinite(gains.zeta) || !(gains.zeta >= Scalar(0)) ||
        !std::isfinite(gains.omega) || !(gains.omega >= Scalar(0)))
      return false;
    row_gains_[static_cast<std::size_t>(row)] = gains;
    return true;
  }
  /// Gains of one row; gains that are off for a row outside [0, P).
  Stabilization<Scalar> stabilization(int row) const noexcept {
    if (row < 0 || row >= P) return Stabilization<Scalar>{Scalar(1), Scalar(0)};
    return row_gains_[static_cast<std::size_t>(row)];
  }
  /// Actuator limits: |force_i| <= limit_i for every published force. A force beyond them is
  /// scaled down as a whole (its direction and the split into parts kept) and the output says so
  /// (warning::kSaturated, saturation_scale); q'' is the model's under the applied force. Returns
  /// false, changing nothing, unless every limit is > 0 (infinity: no limit). Default: no limit.
  bool set_force_limit(const VectorN& limit) noexcept {
    for (int i = 0; i < N; ++i)
      if (!(limit(i) > Scalar(0))) return false;
    force_limit_ = limit;
    return true;
  }
  const VectorN& force_limit() const noexcept { return force_limit_; }

  /// The sampled-data hold. Returns false, changing nothing, unless period and delay are finite
  /// and >= 0. The hold's memory (the latest samples' accelerations) is kept: it is used only for
  /// a call that follows it by at most two periods.
  bool set_hold(const Hold<Scalar>& hold) noexcept {
    if (!std::isfinite(hold.period) || !(hold.period >= Scalar(0)) || !std::isfinite(hold.delay) ||
        !(hold.delay >= Scalar(0)))
      return false;
    options_.hold = hold;
    return true;
  }
  const Hold<Scalar>& hold() const noexcept { return options_.hold; }

  /// The terms of the last evaluation of the law (A, f, Q, D, g, e, e': at the measured state, or
  /// with a hold at the predicted one).
  const Terms& terms() const noexcept { return terms_; }

  /// Control force for state (q [m], qd [m/s], t [s]): eq. (32) at that state, or with a hold
  /// (set_hold) the force to hold over [t + delay, t + delay + period]. The output's
  /// constraint_error and constraint_error_rate are the measured state's in both cases.
  template <typename Dq, typename Dqd>
  Status compute(const Eigen::MatrixBase<Dq>& q, const Eigen::MatrixBase<Dqd>& qd, Scalar t,
                 Output& out) noexcept {
    if (!q.allFinite() || !qd.allFinite() || !std::isfinite(t)) {
      out = Output{};
      out.diagnostics.status = Status::kNonFiniteInput;
      out.diagnostics.non_finite_inputs = input::kState;
      return out.diagnostics.status;
    }
    const VectorN qv = q;
    const VectorN qdv = qd;
    const Status measured = evaluate(qv, qdv, t, out);
    if (!options_.hold.enabled()) return measured;
    if (failed(measured)) {
      prediction_.forget();
      return measured;
    }
    const Scalar tau = options_.hold.lead();
    const VectorP e = out.constraint_error, e_rate = out.constraint_error_rate;
    VectorN q_m, qd_m;
    prediction_.predict(options_.hold, qv, qdv, t, out.acceleration, q_m, qd_m);
    Status status = q_m.allFinite() && qd_m.allFinite() ? evaluate(q_m, qd_m, t + tau, out) : Status::kNonFiniteInput;
    if (failed(status)) {
      status = evaluate(qv, qdv, t, out);
      out.diagnostics.warnings |= warning::kHoldAtMeasuredState;
    }
    out.constraint_error = e;
    out.constraint_error_rate = e_rate;
    return status;
  }

 private:
  // Eq. (32) at (q, q', t) with the stabilization and the force limit, compiled as one body
  // (`flatten`): the model's terms, the solve and the force's split are inlined, as the solver's
  // normal-equations path is, so that no call boundary spills the small matrices. What the solver
  // marks `noinline` (the rank-revealing factorizations, the failure path) stays out of line.
  [[gnu::flatten]] Status evaluate(const VectorN& qv, const VectorN& qdv, Scalar t, Output& out) noexcept {
    evaluate_model(model_, qv, qdv, t, terms_);
    out.constraint_error = terms_.constraint_error;
    out.constraint_error_rate = terms_.constraint_error_rate;

    // Baumgarte's correction to g and the robust term, row by row (zero for rows with neither).
    VectorP correction = VectorP::Zero();
    bool stabilized = false;
    for (int i = 0; i < P; ++i) {
      const auto k = static_cast<std::size_t>(i);
      if (!row_gains_[k].enabled() && !row_robust_[k].enabled()) continue;
      stabilized = true;
      correction(i) = row_correction(row_gains_[k], row_robust_[k], terms_.constraint_error(i),
                                     terms_.constraint_error_rate(i));
    }

    const VectorP g = terms_.constraint_rhs + correction;
    const Status status = solver_.solve(terms_.mass_matrix, terms_.nonlinear_force, terms_.applied_force,
                                        terms_.constraint_matrix, g, solution_);
    out.diagnostics = solution_.diagnostics;
    if (failed(status)) {
      out.force.setZero();
      out.closed_loop.setZero();
      out.feedforward.setZero();
      out.stabilizing.setZero();
      out.acceleration.setZero();
      out.saturation_scale = Scalar(1);
      return status;
    }
    out.force = solution_.constraint_force;
    out.closed_loop = solution_.force_from_impressed;
    out.stabilizing = stabilized ? solver_.force_for_rhs(correction) : VectorN::Zero();
    out.feedforward = solution_.force_from_rhs - out.stabilizing;
    out.acceleration = solution_.acceleration;
    out.saturation_scale = Scalar(1);
    for (int i = 0; i < N; ++i) {
      const Scalar magnitude = std::abs(out.force(i));
      if (magnitude > force_limit_(i)) out.saturation_scale = std::min(out.saturation_scale, force_limit_(i) / magnitude);
    }
    if (out.saturation_scale < Scalar(1)) {
      // q'' = a + A^-1 Q' is affine in Q': scaling the force scales q'' - a alike.
      const Scalar k = out.saturation_scale;
      out.force *= k;
      out.closed_loop *= k;
      out.feedforward *= k;
      out.stabilizing *= k;
      out.acceleration = solution_.unconstrained_acceleration +
                         k * (solution_.acceleration - solution_.unconstrained_acceleration);
      // Rounding of the scale must not leave a component a last bit above its limit.
      out.force = out.force.cwiseMax(-force_limit_).cwiseMin(force_limit_);
      out.diagnostics.warnings |= warning::kSaturated;
    }
    return status;
  }

  [[noreturn]] static void config_error(const char* problem);

  M model_;
  Options options_;
  std::array<Stabilization<Scalar>, static_cast<std::size_t>(P)> row_gains_{};
  std::array<Robust<Scalar>, static_cast<std::size_t>(P)> row_robust_{};
  VectorN force_limit_ = VectorN::Constant(std::numeric_limits<Scalar>::infinity());
  Terms terms_{};
  HoldPrediction<N, Scalar> prediction_;  ///< the hold's memory
  ConstraintSolver<N, P, Scalar, kMassMatrixOf<M>> solver_;
  ConstraintSolution<N, P, Scalar> solution_;
};

}  // namespace gausstrack

#if defined(__cpp_exceptions)
#include <stdexcept>
#include <string>
template <gausstrack::Model M>
void gausstrack::TrackingController<M>::config_error(const char* problem) {
  throw std::invalid_argument(std::string("gausstrack::TrackingController: ") + problem);
}
#else
// Without exceptions a bad configuration traps at construction (no stdio, so that firmware links
// without it); call `options.validate()` first to get the message.
template <gausstrack::Model M>
void gausstrack::TrackingController<M>::config_error(const char*) {
  __builtin_trap();
}
#endif
