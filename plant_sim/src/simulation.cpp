#include "gausstrack/plant_sim/simulation.hpp"

#include <unistd.h>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/QR>
#include <boost/numeric/odeint.hpp>
#include <boost/numeric/odeint/external/eigen/eigen.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <numbers>
#include <optional>
#include <random>
#include <span>
#include <stdexcept>

#include "gausstrack/constraint_solver.hpp"
#include "gausstrack/plant_sim/models.hpp"

namespace gausstrack::plant_sim {
namespace {

namespace odeint = boost::numeric::odeint;

using V = Eigen::VectorXd;
using M = Eigen::MatrixXd;

// The model of that name: one the run was given (RunOptions::models), else a compiled-in one.
const ModelFactory& find_model(const RunOptions& o, const std::string& name, const std::string& where) {
  for (const ModelFactory& f : o.models)
    if (f.name == name) return f;
  if (const ModelFactory* f = find_builtin_model(name)) return *f;
  throw SceneError(where + ": unknown model '" + name + "' (compiled in: " + builtin_model_names() +
                   (o.models.empty() ? std::string() : "; given to this run: " + [&] {
                     std::string n;
                     for (const ModelFactory& f : o.models) n += (n.empty() ? "" : ", ") + f.name;
                     return n;
                   }()) + ")");
}

// The plant assembled from exactly the scene's description: point masses or a model's own
// dynamics, the effects listed and the physical constraints listed. Its constraint rows are
// written here and solved as a Lagrange-multiplier (KKT) system, independently of the
// controller's ConstraintSolver, so that plant and controller check each other.
class Plant {
 public:
  Plant(const Scene& s, const RunOptions& o) : n_(s.dof()) {
    if (!s.plant_model.empty()) {
      model_ = find_model(o, s.plant_model, s.plant_model_where).plant(s.plant_parameters);
      if (model_->dof() != n_)
        throw SceneError(s.plant_model_where + ": model '" + s.plant_model + "' has " +
                         std::to_string(model_->dof()) + " coordinates, the plant lists " + std::to_string(n_));
    } else if (!s.masses.empty()) {
      mass_ = Eigen::Map<const V>(s.masses.data(), n_);
    }  // else an engine's plant: its physics are the engine's
    for (const EffectSpec& e : s.effects) {
      switch (e.kind) {
        case EffectKind::kActuatorSaturation: saturation_ = e; break;
        case EffectKind::kSensorNoise:
          noise_ = e;
          rng_.seed(e.seed);
          break;
        default: forces_.push_back(e);
      }
    }
    constraints_ = s.constraints;
    A_.setZero(n_, n_);
    f_.setZero(n_);
    Q_.setZero(n_);
  }

  int dof() const { return n_; }

  // Generalized impressed force Q(q, q', t) from the force effects listed, and nothing else.
  // Every output here is written into a vector the caller keeps: no allocation per evaluation,
  // except in a constrained plant's KKT solve (Eigen's CompleteOrthogonalDecomposition::solve).
  void applied_force(const V& q, const V& qd, double t, RunSummary& stats, V& Q) const {
    Q.setZero(n_);
    for (const EffectSpec& e : forces_) {
      ++stats.effect_evaluations[static_cast<std::size_t>(e.kind)];
      const double xb = e.b == kGround ? 0.0 : q(e.b), vb = e.b == kGround ? 0.0 : qd(e.b);
      const double d = q(e.a) - xb, dd = qd(e.a) - vb;
      double force_on_a = 0;  // force on coordinate a; b receives the opposite
      switch (e.kind) {
        case EffectKind::kGravity: Q(e.a) += mass_(e.a) * e.value; continue;
        case EffectKind::kDisturbance: Q(e.a) += e.value * std::sin(e.frequency * t + e.phase); continue;
        case EffectKind::kSpring: force_on_a = -e.value * d; break;
        case EffectKind::kCubicSpring: force_on_a = -e.value * d * d * d; break;
        case EffectKind::kDamper: force_on_a = -e.value * dd; break;
        default: continue;
      }
      Q(e.a) += force_on_a;
      if (e.b != kGround) Q(e.b) -= force_on_a;
    }
  }

  void saturate(V& u, RunSummary& stats) const {
    if (!saturation_) return;
    ++stats.effect_evaluations[static_cast<std::size_t>(EffectKind::kActuatorSaturation)];
    u = u.cwiseMax(-saturation_->value).cwiseMin(saturation_->value);
  }

  // The state the controller measures: exact, or with the listed sensor noise.
  void measure(V& q, V& qd, RunSummary& stats) {
    if (!noise_) return;
    ++stats.effect_evaluations[static_cast<std::size_t>(EffectKind::kSensorNoise)];
    std::normal_distribution<double> nd(0.0, noise_->value);
    for (int i = 0; i < n_; ++i) {
      q(i) += nd(rng_);
      qd(i) += nd(rng_);
    }
  }

  // Constraint k's row: D_k q'' = g_k, with D_k = grad phi_k (or the Pfaffian row) and g_k the
  // rest of phi_k'' (or psi_k') moved to the right.
  void constraint_row(const ConstraintSpec& c, const Eigen::Ref<const V>& q, const Eigen::Ref<const V>& qd,
                      Eigen::RowVectorXd& D, double& g) const {
    D.setZero(n_);
    const auto& k = c.coordinates;
    if (c.kind == ConstraintKind::kPendulumLength) {
      // phi = x^2 + y^2 - L^2 + mu L^2 sin(x^2); D = grad phi; g = -q'^T Hess(phi) q'.
      const double x = q(k[0]), y = q(k[1]), xd = qd(k[0]), yd = qd(k[1]);
      const double l2mu = c.length * c.length * c.mu;
      D(k[0]) = 2 * x + 2 * l2mu * x * std::cos(x * x);
      D(k[1]) = 2 * y;
      const double hxx = 2 + 2 * l2mu * (std::cos(x * x) - 2 * x * x * std::sin(x * x));
      g = -(hxx * xd * xd + 2 * yd * yd);
    } else {
      // y' - z x' = 0 differentiated: y'' - z x'' = z' x'.
      D(k[0]) = -q(k[2]);
      D(k[1]) = 1;
      g = qd(k[2]) * qd(k[0]);
    }
  }

  // Eq. (31) by Lagrange multipliers: [A D^T; D 0] (q'', -lambda) = (Q + u - f, g).
  void acceleration(const V& q, const V& qd, double t, const V& u, RunSummary& stats, V& qdd) {
    V& rhs = force_;
    applied_force(q, qd, t, stats, rhs);
    rhs += u;
    if (model_) {
      model_->evaluate(q, qd, t, A_, f_, Q_);
      rhs += Q_ - f_;
    }
    const int p = static_cast<int>(constraints_.size());
    if (p == 0) {
      if (!model_) {
        qdd = rhs.cwiseQuotient(mass_);
        return;
      }
      llt_.compute(A_);
      if (llt_.info() != Eigen::Success) qdd.setConstant(n_, std::numeric_limits<double>::quiet_NaN());
      else qdd = llt_.solve(rhs);
      return;
    }
    kkt_.setZero(n_ + p, n_ + p);
    if (model_) kkt_.topLeftCorner(n_, n_) = A_;
    else kkt_.topLeftCorner(n_, n_).diagonal() = mass_;
    V& b = kkt_rhs_;
    b.resize(n_ + p);
    b.head(n_) = rhs;
    for (int k = 0; k < p; ++k) {
      double g = 0;
      constraint_row(constraints_[static_cast<std::size_t>(k)], q, qd, row_, g);
      kkt_.block(n_ + k, 0, 1, n_) = row_;
      kkt_.block(0, n_ + k, n_, 1) = row_.transpose();
      b(n_ + k) = g;
    }
    // Rank-revealing, so that a configuration where the rows lose rank still gives the
    // least-squares multipliers rather than a division by zero.
    kkt_solver_.compute(kkt_);
    kkt_solution_ = kkt_solver_.solve(b);
    qdd = kkt_solution_.head(n_);
  }

  bool has_constraints() const { return !constraints_.empty(); }

  // Projects a state x = (q, q') onto the constraint manifolds, by the least change in the
  // metric of A (the mass-weighted projection): positions onto phi = 0 for the holonomic
  // constraints (Gauss-Newton, at most 3 steps), then velocities onto D q' = 0 for all of them
  // (each constraint here has phi_t = 0 and psi = D q'). Returns false if the state is not finite.
  bool project(Eigen::VectorXd& x, double t, RunSummary& stats) {
    if (constraints_.empty() || !x.allFinite()) return x.allFinite();
    ++stats.projections;
    Eigen::Ref<V> q = x.head(n_), qd = x.tail(n_);
    const int p = static_cast<int>(constraints_.size());
    M D(p, n_);
    V r(p);
    auto rows = [&](bool holonomic_only) {
      double g = 0;
      for (int k = 0; k < p; ++k) {
        const ConstraintSpec& c = constraints_[static_cast<std::size_t>(k)];
        constraint_row(c, q, qd, row_, g);
        const bool holonomic = c.kind == ConstraintKind::kPendulumLength;
        D.row(k) = holonomic_only && !holonomic ? Eigen::RowVectorXd::Zero(n_) : row_;
        r(k) = holonomic_only ? (holonomic ? position_residual(c, q) : 0.0) : row_.dot(qd);
      }
    };
    // W = A^-1 at the current q.
    M W;
    if (model_) {
      model_->evaluate(q, qd, t, A_, f_, Q_);
      llt_.compute(A_);
      if (llt_.info() != Eigen::Success) {
        x.setConstant(std::numeric_limits<double>::quiet_NaN());  // the run stops with its reason
        return false;
      }
      W = llt_.solve(M::Identity(n_, n_));
    } else {
      W = mass_.cwiseInverse().asDiagonal();
    }
    auto correction = [&]() -> V {
      const M DWDt = D * W * D.transpose();
      return W * D.transpose() * DWDt.completeOrthogonalDecomposition().solve(r);
    };
    for (int it = 0; it < 3; ++it) {
      rows(true);
      if (r.cwiseAbs().maxCoeff() == 0) break;
      q -= correction();
    }
    rows(false);
    qd -= correction();
    return x.allFinite();
  }

  static double position_residual(const ConstraintSpec& c, const Eigen::Ref<const V>& q) {
    const auto& k = c.coordinates;
    const double x = q(k[0]), y = q(k[1]), L = c.length;
    return x * x + y * y - L * L * (1 - c.mu * std::sin(x * x));
  }

  double constraint_residual(const V& q, const V& qd) const {
    double worst = 0;
    for (const ConstraintSpec& c : constraints_) {
      const auto& k = c.coordinates;
      const double r = c.kind == ConstraintKind::kPendulumLength ? position_residual(c, q)
                                                                 : qd(k[1]) - q(k[2]) * qd(k[0]);
      if (std::abs(r) > std::abs(worst)) worst = r;
    }
    return worst;
  }

 private:
  int n_;
  V mass_;
  std::unique_ptr<PlantModel> model_;
  M A_;
  V f_, Q_;
  std::vector<EffectSpec> forces_;
  std::optional<EffectSpec> saturation_, noise_;
  std::vector<ConstraintSpec> constraints_;
  std::mt19937_64 rng_;
  Eigen::LLT<M> llt_;
  M kkt_;
  Eigen::RowVectorXd row_;
  Eigen::CompleteOrthogonalDecomposition<M> kkt_solver_;
  V force_, kkt_rhs_, kkt_solution_;  // acceleration()'s work vectors, sized on first use
};

// The scene's tracking controller (none without a tracking section), or, when the forces come
// from elsewhere (a controller process), only the tracking error of the scene's model.
struct Control {
  std::unique_ptr<ControlLaw> law;
  std::function<double(const double*, const double*, double)> error;

  Control(const Scene& s, const RunOptions& o) {
    if (!s.tracking.enabled) return;
    const ModelFactory& model = find_model(o, s.tracking.model, s.tracking.where);
    if (model.dof != s.dof())
      throw SceneError(s.tracking.where + ": model '" + s.tracking.model + "' has " + std::to_string(model.dof) +
                       " coordinates, the plant has " + std::to_string(s.dof()));
    if (o.sampled_control) error = model.tracking_error(s.tracking);
    else law = model.control_law(s.tracking);
  }

  // u = the law's force at (q, q', t); zero without a law or on failure.
  void force(const V& q, const V& qd, double t, RunSummary& stats, V& u) {
    u.setZero(q.size());
    if (law) {
      ++stats.control_evaluations;
      if (failed(law->compute(q.data(), qd.data(), t, u.data()))) {
        ++stats.control_failures;
        u.setZero();
      }
    }
  }

  double tracking_error(const V& q, const V& qd, double t) const {
    if (error) return error(q.data(), qd.data(), t);
    return law ? law->tracking_error(q.data(), qd.data(), t) : 0.0;
  }
};

RunResult run(const Scene& s, const RunOptions& options) {
  using State = Eigen::VectorXd;
  const int N = s.dof();
  if (options.sampled_control && s.control_mode != ControlMode::kSampled)
    throw SceneError(s.file + ": control from another process needs control.mode: sampled");
  const auto wall_start = std::chrono::steady_clock::now();

  RunResult result;
  RunSummary& stats = result.summary;
  const auto sample_count = static_cast<std::size_t>(std::floor(s.duration / s.output_period + 1e-9)) + 1;
  result.samples.reserve(sample_count);
  Plant plant(s, options);
  Control control(s, options);
  std::unique_ptr<PlantEngine> engine;
  if (!s.engine.name.empty()) {
    for (const EngineFactory& f : options.engines)
      if (f.name == s.engine.name) engine = f.make(s);
    if (!engine) throw SceneError(s.engine.where + ": this program was built without the '" + s.engine.name + "' engine");
    stats.engine = engine->description();
    stats.engine_effects = s.engine.effects;
  }
  const bool project = s.projection && plant.has_constraints();

  const bool sampled = s.control_mode == ControlMode::kSampled;
  V held = V::Zero(N);  // the control force held over the current control period
  // The right-hand side writes into vectors sized once here: no allocation per evaluation but a
  // constrained plant's KKT solve. (A sampled run still allocates its measured state and force
  // once per control period, below.)
  V rhs_q(N), rhs_qd(N), rhs_u(N), rhs_qdd(N);
  auto rhs = [&](const State& x, State& dxdt, double t) {
    ++stats.rhs_evaluations;
    rhs_q = x.head(N);
    rhs_qd = x.tail(N);
    if (!sampled) {
      control.force(rhs_q, rhs_qd, t, stats, rhs_u);
      plant.saturate(rhs_u, stats);
    }
    plant.acceleration(rhs_q, rhs_qd, t, sampled ? held : rhs_u, stats, rhs_qdd);
    dxdt.resize(2 * N);
    dxdt.head(N) = rhs_qd;
    dxdt.tail(N) = rhs_qdd;
  };

  State x(2 * N);
  for (int i = 0; i < N; ++i) {
    x(i) = s.q0[static_cast<std::size_t>(i)];
    x(N + i) = s.qd0[static_cast<std::size_t>(i)];
  }

  // Exact output times k * output_period.
  std::size_t next_sample = 0;
  auto record = [&](const State& state, double t) {
    Sample smp;
    smp.t = t;
    const V q = state.head(N), qd = state.tail(N);
    V u = held;
    if (!sampled) {
      RunSummary scratch;  // recording must not count as simulation work
      control.force(q, qd, t, scratch, u);
      plant.saturate(u, scratch);
    }
    smp.q.assign(q.data(), q.data() + N);
    smp.qd.assign(qd.data(), qd.data() + N);
    smp.u.assign(u.data(), u.data() + N);
    smp.tracking_error = control.tracking_error(q, qd, t);
    smp.constraint_residual = plant.constraint_residual(q, qd);
    stats.max_tracking_error = std::max(stats.max_tracking_error, std::abs(smp.tracking_error));
    stats.max_constraint_residual = std::max(stats.max_constraint_residual, std::abs(smp.constraint_residual));
    result.samples.push_back(std::move(smp));
  };
  auto sample_time = [&](std::size_t k) { return static_cast<double>(k) * s.output_period; };

  // Segments: the whole run (continuous control) or one control period each (sampled and held).
  const double period = sampled ? 1.0 / s.control_rate : s.duration;
  const auto segments = static_cast<std::size_t>(std::ceil(s.duration / period - 1e-9));
  auto last_progress = std::chrono::steady_clock::now();

  using Dopri = odeint::runge_kutta_dopri5<State, double, State, double, odeint::vector_space_algebra>;
  using Rkf78 = odeint::runge_kutta_fehlberg78<State, double, State, double, odeint::vector_space_algebra>;
  using Rk4 = odeint::runge_kutta4<State, double, State, double, odeint::vector_space_algebra>;
  auto dopri5 = odeint::make_dense_output(s.tolerance, s.tolerance, Dopri());
  // Bulirsch-Stoer (Richardson extrapolation of modified midpoint steps, dense output): a
  // high-accuracy choice for offline runs; it allocates its extrapolation tables as it goes.
  // Its interpolation is error-controlled too: a sampled run restarts from the interpolated state.
  odeint::bulirsch_stoer_dense_out<State, double, State, double, odeint::vector_space_algebra> bulirsch_stoer(
      s.tolerance, s.tolerance, 1.0, 1.0, 0.0, true);
  auto controlled = odeint::make_controlled(s.tolerance, s.tolerance, Rkf78());
  Rk4 rk4;
  double dt = s.method == Method::kRk4 ? s.step : std::min(1e-3, period);

  // Guards: a run that cannot go on ends with its reason and keeps what it computed.
  auto g = [](double v) {
    char b[32];
    std::snprintf(b, sizeof b, "%.6g", v);
    return std::string(b);
  };
  auto describe = [&](const State& state) {
    std::string v = "q = (";
    for (int i = 0; i < 2 * N; ++i) {
      if (i == N) v += "), q' = (";
      else if (i > 0) v += ", ";
      v += g(state(i));
    }
    return v + ")";
  };
  auto fail = [&](double t, const std::string& why) {
    stats.failure = why;
    stats.failed_at = t;
  };
  // true when the step just taken (to time t, new step size h) lets the run go on.
  auto step_ok = [&](double t, const State& state, double h) {
    if (!state.allFinite()) {
      fail(t, "the state left the finite range at t = " + g(t) + " s: " + describe(state));
      return false;
    }
    if (s.method != Method::kRk4 && h < s.min_step) {
      fail(t, "steps collapsed to " + g(h) + " s (integrator.min_step " + g(s.min_step) +
                  ") at t = " + g(t) + " s: the plant diverges or is too stiff for the tolerance; " +
                  describe(state));
      return false;
    }
    if (static_cast<double>(stats.steps) > s.max_steps) {
      fail(t, "the step budget integrator.max_steps (" + std::to_string(static_cast<long long>(s.max_steps)) +
                  ") was spent at t = " + g(t) + " s");
      return false;
    }
    if (options.stop_requested && options.stop_requested()) {
      stats.stopped_early = true;
      return false;
    }
    return true;
  };
  bool going = true;
  // Samples due by t_reached, from state_at(t).
  auto emit_until = [&](double t_reached, auto&& state_at) {
    while (next_sample < sample_count && sample_time(next_sample) <= t_reached * (1 + 1e-14)) {
      record(state_at(sample_time(next_sample)), sample_time(next_sample));
      ++next_sample;
    }
  };
  // One control period (or the whole run) with a dense-output stepper (dopri5, Bulirsch-Stoer):
  // steps are chosen by the error control alone; samples are interpolated. False when the run
  // cannot go on.
  auto dense_segment = [&](auto& dense, double t0, double t1) -> bool {
    dense.initialize(x, t0, dt);
    while (dense.current_time() < t1 * (1 - 1e-15)) {
      try {
        dense.do_step(rhs);
      } catch (const std::exception& e) {  // odeint gives up after 500 rejected steps
        fail(dense.current_time(), std::string("the integrator could not take a step at t = ") +
                                       g(dense.current_time()) + " s (" + e.what() + "): " +
                                       describe(dense.current_state()));
        going = false;
        break;
      }
      ++stats.steps;
      // Samples up to a finite step are kept even when the run cannot go on after it.
      if (dense.current_state().allFinite()) {
        const double reached = std::min(dense.current_time(), t1);
        emit_until(reached, [&](double ts) {
          State xs(2 * N);
          dense.calc_state(ts, xs);
          if (project) plant.project(xs, ts, stats);  // the plant's state is the projected one
          return xs;
        });
      }
      if (!step_ok(dense.current_time(), dense.current_state(), dense.current_time_step())) {
        going = false;
        break;
      }
      if (project && dense.current_time() < t1 * (1 - 1e-15)) {
        // The next step starts from the projected state (dense output restarts there).
        State xp = dense.current_state();
        plant.project(xp, dense.current_time(), stats);
        dense.initialize(xp, dense.current_time(), dense.current_time_step());
      }
    }
    if (!going) return false;
    dt = dense.current_time_step();
    if (dense.current_time() > t1) {
      dense.calc_state(t1, x);
    } else {
      x = dense.current_state();
    }
    if (project) plant.project(x, t1, stats);
    return true;
  };

  for (std::size_t k = 0; k < segments && going; ++k) {
    const double t0 = static_cast<double>(k) * period;
    const double t1 = std::min(s.duration, static_cast<double>(k + 1) * period);
    if (sampled) {
      V q = x.head(N), qd = x.tail(N);
      plant.measure(q, qd, stats);
      if (options.sampled_control) {
        // The force comes from elsewhere (a controller process); the run stops when it says so.
        V u = V::Zero(N);
        if (!options.sampled_control(static_cast<std::int64_t>(k), t0, std::span<const double>(q.data(), q.size()),
                                     std::span<const double>(qd.data(), qd.size()), std::span<double>(u.data(), u.size()))) {
          stats.stopped_early = true;
          break;
        }
        held = u;
      } else {
        control.force(q, qd, t0, stats, held);
      }
      plant.saturate(held, stats);
    }
    if (next_sample == 0) {
      record(x, 0.0);
      next_sample = 1;
    }

    if (engine) {
      // The engine's fixed steps under the held force; its state is the plant's.
      const auto n_steps = static_cast<long>(std::llround((t1 - t0) / s.step));
      for (long i = 0; i < n_steps; ++i) {
        const double t = t0 + static_cast<double>(i + 1) * s.step;
        if (const std::string why = engine->step(held.data()); !why.empty()) {
          fail(t - s.step, why);
          going = false;
          break;
        }
        engine->state(x.data(), x.data() + N);
        ++stats.steps;
        if (x.allFinite()) emit_until(t, [&](double) { return x; });
        if (!step_ok(t, x, s.step)) {
          going = false;
          break;
        }
      }
    } else if (s.method == Method::kDopri5) {
      if (!dense_segment(dopri5, t0, t1)) break;
    } else if (s.method == Method::kBulirschStoer) {
      if (!dense_segment(bulirsch_stoer, t0, t1)) break;
    } else if (s.method == Method::kRkf78) {
      // No dense output in odeint for this method: steps are clipped to end exactly on sample
      // and segment times (a clipped step does not shrink the step size used afterwards).
      double t = t0;
      for (;;) {
        emit_until(t, [&](double) { return x; });
        if (t >= t1 * (1 - 1e-15)) break;
        double stop = t1;
        if (next_sample < sample_count) stop = std::min(stop, sample_time(next_sample));
        const bool clipped = stop - t < dt;
        double h = clipped ? stop - t : dt;
        odeint::controlled_step_result step_result = odeint::fail;
        try {
          step_result = controlled.try_step(rhs, x, t, h);
        } catch (const std::exception& e) {
          fail(t, std::string("the integrator could not take a step at t = ") + g(t) + " s (" +
                      e.what() + "): " + describe(x));
          going = false;
          break;
        }
        if (step_result == odeint::success) {
          ++stats.steps;
          if (clipped) {
            t = stop;
          } else {
            dt = h;
          }
          if (project) plant.project(x, t, stats);
        } else {
          dt = h;
        }
        if (!step_ok(t, x, clipped ? std::max(h, dt) : dt)) {
          if (x.allFinite()) emit_until(t, [&](double) { return x; });
          going = false;
          break;
        }
      }
      if (!going) break;
    } else {
      const auto n_steps = static_cast<long>(std::llround((t1 - t0) / s.step));
      for (long i = 0; i < n_steps; ++i) {
        rk4.do_step(rhs, x, t0 + static_cast<double>(i) * s.step, s.step);
        ++stats.steps;
        if (project) plant.project(x, t0 + static_cast<double>(i + 1) * s.step, stats);
        if (x.allFinite()) emit_until(t0 + static_cast<double>(i + 1) * s.step, [&](double) { return x; });
        if (!step_ok(t0 + static_cast<double>(i + 1) * s.step, x, s.step)) {
          going = false;
          break;
        }
      }
    }
    if (options.on_progress) {
      const auto now = std::chrono::steady_clock::now();
      if (now - last_progress > std::chrono::milliseconds(100) || k + 1 == segments) {
        options.on_progress(t1);
        last_progress = now;
      }
    }
  }

  double sum_squares = 0;
  for (const Sample& smp : result.samples) sum_squares += smp.tracking_error * smp.tracking_error;
  if (!result.samples.empty()) stats.rms_tracking_error = std::sqrt(sum_squares / static_cast<double>(result.samples.size()));
  stats.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  return result;
}

V to_vector(const std::vector<double>& v, const Scene& s) {
  if (static_cast<int>(v.size()) != s.dof())
    throw std::invalid_argument(s.file + ": expected " + std::to_string(s.dof()) + " values, got " + std::to_string(v.size()));
  return Eigen::Map<const V>(v.data(), s.dof());
}

std::vector<double> evaluate(const Scene& s, const std::vector<double>& q, const std::vector<double>& qd, double t,
                             const std::vector<double>* u) {
  if (!s.engine.name.empty())
    throw SceneError(s.engine.where + ": this plant's physics are the '" + s.engine.name + "' engine's, not plant_sim's");
  Plant plant(s, RunOptions{});
  RunSummary stats;
  V r;
  if (u) plant.acceleration(to_vector(q, s), to_vector(qd, s), t, to_vector(*u, s), stats, r);
  else plant.applied_force(to_vector(q, s), to_vector(qd, s), t, stats, r);
  return {r.data(), r.data() + r.size()};
}

}  // namespace

std::vector<double> plant_applied_force(const Scene& scene, const std::vector<double>& q,
                                        const std::vector<double>& qd, double t) {
  return evaluate(scene, q, qd, t, nullptr);
}

std::vector<double> plant_acceleration(const Scene& scene, const std::vector<double>& q,
                                       const std::vector<double>& qd, double t, const std::vector<double>& u) {
  return evaluate(scene, q, qd, t, &u);
}

RunResult run_scene(const Scene& scene, const RunOptions& options) {
  return run(scene, options);
}

void write_trajectory_csv(const Scene& scene, const RunResult& result, const std::string& path) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write " + path);
  const int n = scene.dof();
  out << "t";
  for (const char* p : {"q", "qd", "u"})
    for (int i = 1; i <= n; ++i) out << "," << p << i;
  out << ",tracking_error,constraint_residual\n";
  char buf[64];
  auto put = [&](double v) {
    std::snprintf(buf, sizeof buf, ",%.17g", v);
    out << buf;
  };
  for (const Sample& s : result.samples) {
    std::snprintf(buf, sizeof buf, "%.17g", s.t);
    out << buf;
    for (double v : s.q) put(v);
    for (double v : s.qd) put(v);
    for (double v : s.u) put(v);
    put(s.tracking_error);
    put(s.constraint_residual);
    out << "\n";
  }
  if (!out) throw std::runtime_error("error writing " + path);
}

std::function<void(double t)> terminal_progress(const Scene& scene) {
  if (isatty(fileno(stderr)) == 0) return {};
  const auto start = std::chrono::steady_clock::now();
  return [start, name = scene.name, duration = scene.duration](double t) {
    if (std::chrono::steady_clock::now() - start < std::chrono::seconds(1)) return;
    std::fprintf(stderr, "\r%s: t = %.3f / %.3f s (%3.0f%%)%s", name.c_str(), t, duration, 100.0 * t / duration,
                 t >= duration ? "\n" : "");
  };
}

void write_summary_json(const Scene& scene, const RunResult& result, const std::string& path,
                        const std::string& extra_members) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write " + path);
  const RunSummary& s = result.summary;
  char buf[128];
  auto num = [&](const char* key, double v, bool comma = true) {
    std::snprintf(buf, sizeof buf, "  \"%s\": %.17g%s\n", key, v, comma ? "," : "");
    out << buf;
  };
  out << "{\n  \"scene\": \"" << scene.name << "\",\n";
  // Whether the run reached its duration; if not, why (a failure) or that it was stopped.
  std::string failure;
  for (char c : s.failure) {
    if (c == '"' || c == '\\') failure += '\\';
    failure += c;
  }
  out << "  \"completed\": " << (s.failure.empty() && !s.stopped_early ? "true" : "false") << ",\n";
  out << "  \"failure\": " << (s.failure.empty() ? std::string("null") : "\"" + failure + "\"") << ",\n";
  if (!s.failure.empty()) num("failed_at", s.failed_at);
  num("max_tracking_error", s.max_tracking_error);
  num("rms_tracking_error", s.rms_tracking_error);
  num("max_constraint_residual", s.max_constraint_residual);
  num("steps", static_cast<double>(s.steps));
  num("rhs_evaluations", static_cast<double>(s.rhs_evaluations));
  num("control_evaluations", static_cast<double>(s.control_evaluations));
  num("control_failures", static_cast<double>(s.control_failures));
  num("projections", static_cast<double>(s.projections));
  out << "  \"effect_evaluations\": {";
  for (std::size_t k = 0; k < s.effect_evaluations.size(); ++k)
    out << (k ? ", " : "") << "\"" << to_string(static_cast<EffectKind>(k)) << "\": " << s.effect_evaluations[k];
  out << "},\n";
  // Which engine stepped the plant, and which of its effects were on (all others were off).
  out << "  \"engine\": " << (s.engine.empty() ? std::string("null") : "\"" + s.engine + "\"") << ",\n";
  if (!s.engine.empty()) {
    out << "  \"engine_effects\": [";
    for (std::size_t k = 0; k < s.engine_effects.size(); ++k) out << (k ? ", " : "") << "\"" << s.engine_effects[k] << "\"";
    out << "],\n";
  }
  if (!extra_members.empty()) out << "  " << extra_members << ",\n";
  num("wall_time_s", s.wall_time_s, false);
  out << "}\n";
  if (!out) throw std::runtime_error("error writing " + path);
}

}  // namespace gausstrack::plant_sim
