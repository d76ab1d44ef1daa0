// Tracking control law: the constraint force of eq. (32) for a measured state, split into a
// closed-loop part, a feedforward part and an optional constraint-stabilizing part.
#pragma once

#include <cmath>
#include <utility>

#include "gausstrack/constraint_solver.hpp"
#include "gausstrack/model.hpp"

namespace gausstrack {

/// Constraint stabilization: g is replaced by g - 2 zeta omega e' - omega^2 e, so that the
/// constraint error obeys e'' + 2 zeta omega e' + omega^2 e = 0 instead of e'' = 0 (which keeps
/// any initial error and lets rounding, sampling and model error drift). omega = 0 (the default)
/// reproduces the paper's law exactly.
template <typename Scalar>
struct Stabilization {
  Scalar zeta = Scalar(1);   ///< damping ratio [-]
  Scalar omega = Scalar(0);  ///< natural frequency [rad/s]; 0 disables stabilization
  bool enabled() const noexcept { return omega > Scalar(0); }
};

template <typename Scalar>
struct ControllerOptions {
  SolverOptions<Scalar> solver{};
  Stabilization<Scalar> stabilization{};

  /// nullptr when the options are usable, else what is wrong with them. Never throws.
  const char* validate() const noexcept {
    if (!std::isfinite(stabilization.zeta) || stabilization.zeta < Scalar(0))
      return "stabilization.zeta must be finite and >= 0";
    if (!std::isfinite(stabilization.omega) || stabilization.omega < Scalar(0))
      return "stabilization.omega must be finite and >= 0";
    if (!std::isfinite(solver.damping) || solver.damping < Scalar(0))
      return "solver.damping must be finite and >= 0";
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
  VectorP constraint_error = VectorP::Zero();       ///< e(q,t) when the model provides it
  VectorP constraint_error_rate = VectorP::Zero();  ///< e'(q,q',t) when the model provides it
  SolveDiagnostics<Scalar> diagnostics;
};

/// Evaluates eq. (32) for a Model at a measured state. Allocation-free and exception-free
/// after construction.
template <Model M>
class TrackingController {
 public:
  using Scalar = typename M::Scalar;
  static constexpr int N = M::kDof;
  static constexpr int P = M::kConstraints;
  using VectorN = Eigen::Matrix<Scalar, N, 1>;
  using VectorP = Eigen::Matrix<Scalar, P, 1>;
  using Output = ControlOutput<N, P, Scalar>;
  using Options = ControllerOptions<Scalar>;

  /// Throws std::invalid_argument (when exceptions are enabled; aborts otherwise) if
  /// `options.validate()` reports a problem.
  explicit TrackingController(M model = M{}, const Options& options = Options{})
      : model_(std::move(model)), options_(options), solver_(options.solver) {
    if (const char* problem = options.validate()) config_error(problem);
  }

  M& model() noexcept { return model_; }
  const M& model() const noexcept { return model_; }
  const Options& options() const noexcept { return options_; }

  /// Control force for state (q [m], qd [m/s], t [s]).
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

    out.constraint_error.setZero();
    out.constraint_error_rate.setZero();
    if constexpr (HasPositionError<M>) out.constraint_error = model_.constraint_error(qv, t);
    if constexpr (HasVelocityError<M>) out.constraint_error_rate = model_.constraint_error_rate(qv, qdv, t);

    // Stabilizing correction to g (zero when disabled or when the model gives no errors).
    VectorP correction = VectorP::Zero();
    const Stabilization<Scalar>& stab = options_.stabilization;
    if (stab.enabled()) {
      correction = -(Scalar(2) * stab.zeta * stab.omega) * out.constraint_error_rate -
                   (stab.omega * stab.omega) * out.constraint_error;
    }

    const VectorP g = model_.constraint_rhs(qv, qdv, t) + correction;
    const Status status = solver_.solve(model_.mass_matrix(qv, t), model_.nonlinear_force(qv, qdv, t),
                                        model_.applied_force(qv, qdv, t),
                                        model_.constraint_matrix(qv, t), g, solution_);
    out.diagnostics = solution_.diagnostics;
    if (failed(status)) {
      out.force.setZero();
      out.closed_loop.setZero();
      out.feedforward.setZero();
      out.stabilizing.setZero();
      out.acceleration.setZero();
      return status;
    }
    out.force = solution_.constraint_force;
    out.closed_loop = solution_.force_from_impressed;
    out.stabilizing = stab.enabled() ? solver_.force_for_rhs(correction) : VectorN::Zero();
    out.feedforward = solution_.force_from_rhs - out.stabilizing;
    out.acceleration = solution_.acceleration;
    return status;
  }

 private:
  [[noreturn]] static void config_error(const char* problem);

  M model_;
  Options options_;
  ConstraintSolver<N, P, Scalar> solver_;
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
#include <cstdio>
#include <cstdlib>
template <gausstrack::Model M>
void gausstrack::TrackingController<M>::config_error(const char* problem) {
  std::fprintf(stderr, "gausstrack::TrackingController: %s\n", problem);
  std::abort();
}
#endif
