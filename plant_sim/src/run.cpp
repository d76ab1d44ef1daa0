// The run loop: segments (the whole run, or one control period each), steps within a segment,
// samples at exact output times, and the guards that end a run with its reason.
#include <chrono>
#include <cmath>
#include <limits>
#include <span>
#include <utility>

#include "gausstrack/plant_sim/simulation.hpp"
#include "plant.hpp"
#include "report.hpp"
#include "stepper.hpp"

namespace gausstrack::plant_sim {
namespace detail {
namespace {

std::unique_ptr<PlantEngine> make_engine(const Scene& s, const RunOptions& o) {
  if (s.engine.name.empty()) return nullptr;
  for (const EngineFactory& f : o.engines)
    if (f.name == s.engine.name) return f.make(s);
  throw SceneError(s.engine.where + ": this program was built without the '" + s.engine.name + "' engine");
}

class Run {
 public:
  Run(const Scene& s, const RunOptions& o);
  Run(const Run&) = delete;  // the stepper holds this run's address and its held force
  Run& operator=(const Run&) = delete;
  RunResult execute();

 private:
  bool hold_force(std::int64_t period, double t0);
  bool advance(double t0, double t1);
  void restart_projected();
  void rhs(const State& x, State& dxdt, double t);
  void emit_until(double t, bool project);
  void record(const State& x, double t);
  bool may_go_on(double t, const State& x, double h);
  void fail(double t, std::string why);
  double sample_time(std::size_t k) const { return static_cast<double>(k) * s_.output_period; }

  const Scene& s_;
  const RunOptions& o_;
  const int n_;
  RunResult result_;
  RunSummary& stats_ = result_.summary;
  Plant plant_;
  Control control_;
  std::unique_ptr<PlantEngine> engine_;
  const bool sampled_, project_;
  // Sampled control: the period and the command held over it (the force, then the control of
  // an engine's actuators). Continuous: one segment.
  const double period_;
  V held_;
  // Work vectors sized once: the right-hand side and the sampled measurement allocate nothing
  // per evaluation (a constrained plant's KKT solve still does).
  V rhs_q_, rhs_qd_, rhs_u_, rhs_qdd_, measured_q_, measured_qd_;
  State x_, scratch_;
  std::unique_ptr<Stepper> stepper_;
  const std::size_t sample_count_;
  std::size_t next_sample_ = 0;
};

Run::Run(const Scene& s, const RunOptions& o)
    : s_(s),
      o_(o),
      n_(s.dof()),
      plant_(s, o),
      control_(s, o),
      engine_(make_engine(s, o)),
      sampled_(s.control_mode == ControlMode::kSampled),
      project_(s.projection && plant_.has_constraints()),
      period_(sampled_ ? 1.0 / s.control_rate : s.duration),
      held_(V::Zero(s.command_size())),
      rhs_q_(n_), rhs_qd_(n_), rhs_u_(n_), rhs_qdd_(n_), measured_q_(n_), measured_qd_(n_),
      x_(2 * n_), scratch_(2 * n_),
      sample_count_(static_cast<std::size_t>(std::floor(s.duration / s.output_period + 1e-9)) + 1) {
  for (int i = 0; i < n_; ++i) {
    x_(i) = s.q0[static_cast<std::size_t>(i)];
    x_(n_ + i) = s.qd0[static_cast<std::size_t>(i)];
  }
  if (engine_) {
    stats_.engine = engine_->description();
    stats_.engine_effects = s.engine.effects;
    stepper_ = make_engine_stepper(*engine_, held_, s.step);
  } else {
    const double first_step = s.method == Method::kRk4 ? s.step : std::min(1e-3, period_);
    stepper_ = make_stepper(s, [this](const State& x, State& dxdt, double t) { rhs(x, dxdt, t); }, first_step);
  }
  result_.samples.reserve(sample_count_);
}

RunResult Run::execute() {
  const auto wall_start = std::chrono::steady_clock::now();
  auto last_progress = wall_start;
  const auto segments = static_cast<std::size_t>(std::ceil(s_.duration / period_ - 1e-9));
  for (std::size_t k = 0; k < segments; ++k) {
    const double t0 = static_cast<double>(k) * period_;
    const double t1 = std::min(s_.duration, static_cast<double>(k + 1) * period_);
    if (sampled_ && !hold_force(static_cast<std::int64_t>(k), t0)) break;
    if (next_sample_ == 0) {
      record(x_, 0.0);
      next_sample_ = 1;
    }
    if (!advance(t0, t1)) break;
    if (o_.on_progress) {
      const auto now = std::chrono::steady_clock::now();
      if (now - last_progress > std::chrono::milliseconds(100) || k + 1 == segments) {
        o_.on_progress(t1);
        last_progress = now;
      }
    }
  }
  double sum_squares = 0;
  for (std::size_t k = 0; k < result_.samples.size(); ++k) {
    const Sample& smp = result_.samples[k];
    sum_squares += smp.tracking_error * smp.tracking_error;
    if (k > 0)
      for (std::size_t i = 0; i < smp.u.size(); ++i)
        stats_.force_total_variation += std::abs(smp.u[i] - result_.samples[k - 1].u[i]);
  }
  if (!result_.samples.empty())
    stats_.rms_tracking_error = std::sqrt(sum_squares / static_cast<double>(result_.samples.size()));
  stats_.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  stats_.rows_not_met = rows_not_met(s_, stats_.warnings, "control evaluations");
  return std::move(result_);
}

// Sampled control: the force for the period starting at t0, from the measured state, held over
// the period. False when the external control source ends the run.
bool Run::hold_force(std::int64_t period, double t0) {
  measured_q_ = x_.head(n_);
  measured_qd_ = x_.tail(n_);
  plant_.measure(measured_q_, measured_qd_, stats_);
  if (o_.sampled_control) {
    held_.setZero();
    const auto n = static_cast<std::size_t>(n_);
    if (!o_.sampled_control(period, t0, std::span<const double>(measured_q_.data(), n),
                            std::span<const double>(measured_qd_.data(), n),
                            std::span<double>(held_.data(), static_cast<std::size_t>(held_.size())))) {
      stats_.stopped_early = true;
      return false;
    }
  } else {
    control_.force(measured_q_, measured_qd_, t0, stats_, held_);
  }
  plant_.saturate(held_, stats_);
  return true;
}

// One segment [t0, t1] from x_; x_ is then the state at t1. With projection (plant.projection),
// samples are the projected states at their times and each step starts from the projected state:
// a stepper without interpolation is projected as soon as a step is accepted; one with dense
// output keeps the step's end state until its samples are interpolated, then restarts from the
// projection. False when the run cannot go on (its failure or stop is in the summary).
bool Run::advance(double t0, double t1) {
  const bool project_now = project_ && !stepper_->interpolates();
  const bool project_after = project_ && stepper_->interpolates();
  stepper_->start(x_, t0, t1);
  while (!stepper_->done()) {
    const double next_output =
        next_sample_ < sample_count_ ? sample_time(next_sample_) : std::numeric_limits<double>::infinity();
    StepOutcome outcome = stepper_->step(next_output);
    if (!outcome.failure.empty()) {
      fail(stepper_->time(), std::move(outcome.failure));
      return false;
    }
    if (outcome.accepted) {
      ++stats_.steps;
      if (project_now) restart_projected();
      // Samples up to a finite step are kept even when the run cannot go on after it.
      if (stepper_->state().allFinite()) emit_until(std::min(stepper_->time(), t1), project_after);
    }
    if (!may_go_on(stepper_->time(), stepper_->state(), stepper_->step_size())) return false;
    if (outcome.accepted && project_after && !stepper_->done()) restart_projected();
  }
  stepper_->state_at(t1, x_);
  if (project_after) plant_.project(x_, t1, stats_);
  if (x_.allFinite()) return true;
  fail(t1, "the state left the finite range at t = " + number(t1) + " s: " + describe_state(x_));
  return false;
}

void Run::restart_projected() {
  scratch_ = stepper_->state();
  plant_.project(scratch_, stepper_->time(), stats_);
  stepper_->restart(scratch_);
}

void Run::rhs(const State& x, State& dxdt, double t) {
  ++stats_.rhs_evaluations;
  rhs_q_ = x.head(n_);
  rhs_qd_ = x.tail(n_);
  if (!sampled_) {
    control_.force(rhs_q_, rhs_qd_, t, stats_, rhs_u_);
    plant_.saturate(rhs_u_, stats_);
  }
  plant_.acceleration(rhs_q_, rhs_qd_, t, sampled_ ? held_ : rhs_u_, stats_, rhs_qdd_);
  dxdt.resize(2 * n_);
  dxdt.head(n_) = rhs_qd_;
  dxdt.tail(n_) = rhs_qdd_;
}

// The samples due by t (exact output times k * output_period), from the stepper's states,
// projected when `project` (interpolated states).
void Run::emit_until(double t, bool project) {
  while (next_sample_ < sample_count_ && sample_time(next_sample_) <= t * (1 + 1e-14)) {
    const double ts = sample_time(next_sample_);
    stepper_->state_at(ts, scratch_);
    if (project) plant_.project(scratch_, ts, stats_);
    record(scratch_, ts);
    ++next_sample_;
  }
}

void Run::record(const State& x, double t) {
  Sample smp;
  smp.t = t;
  const V q = x.head(n_), qd = x.tail(n_);
  V u = held_;
  if (!sampled_) {
    RunSummary scratch;  // recording must not count as simulation work
    control_.force(q, qd, t, scratch, u);
    plant_.saturate(u, scratch);
  }
  smp.q.assign(q.data(), q.data() + n_);
  smp.qd.assign(qd.data(), qd.data() + n_);
  smp.u.assign(u.data(), u.data() + n_);
  smp.tracking_error = control_.tracking_error(q, qd, t);
  smp.constraint_residual = plant_.constraint_residual(q, qd, t);
  stats_.max_tracking_error = std::max(stats_.max_tracking_error, std::abs(smp.tracking_error));
  stats_.max_constraint_residual = std::max(stats_.max_constraint_residual, std::abs(smp.constraint_residual));
  result_.samples.push_back(std::move(smp));
}

// Guards: true when the step just attempted (now at time t, state x, step size h) lets the run
// go on; otherwise the run ends with its reason and keeps what it computed.
bool Run::may_go_on(double t, const State& x, double h) {
  if (!x.allFinite()) {
    fail(t, "the state left the finite range at t = " + number(t) + " s: " + describe_state(x));
    return false;
  }
  if (stepper_->adaptive() && h < s_.min_step) {
    fail(t, "steps collapsed to " + number(h) + " s (integrator.min_step " + number(s_.min_step) + ") at t = " +
                number(t) + " s: the plant diverges or is too stiff for the tolerance; " + describe_state(x));
    return false;
  }
  if (static_cast<double>(stats_.steps) > s_.max_steps) {
    fail(t, "the step budget integrator.max_steps (" + std::to_string(static_cast<long long>(s_.max_steps)) +
                ") was spent at t = " + number(t) + " s");
    return false;
  }
  if (o_.stop_requested && o_.stop_requested()) {
    stats_.stopped_early = true;
    return false;
  }
  return true;
}

void Run::fail(double t, std::string why) {
  stats_.failure = std::move(why);
  stats_.failed_at = t;
}

V to_vector(const std::vector<double>& v, const Scene& s) {
  if (static_cast<int>(v.size()) != s.dof())
    throw std::invalid_argument(s.file + ": expected " + std::to_string(s.dof()) + " values, got " +
                                std::to_string(v.size()));
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
}  // namespace detail

RunResult run_scene(const Scene& scene, const RunOptions& options) {
  if (options.sampled_control && scene.control_mode != ControlMode::kSampled)
    throw SceneError(scene.file + ": control from another process needs control.mode: sampled");
  return detail::Run(scene, options).execute();
}

std::vector<double> plant_applied_force(const Scene& scene, const std::vector<double>& q,
                                        const std::vector<double>& qd, double t) {
  return detail::evaluate(scene, q, qd, t, nullptr);
}

std::vector<double> plant_acceleration(const Scene& scene, const std::vector<double>& q,
                                       const std::vector<double>& qd, double t, const std::vector<double>& u) {
  return detail::evaluate(scene, q, qd, t, &u);
}

}  // namespace gausstrack::plant_sim
