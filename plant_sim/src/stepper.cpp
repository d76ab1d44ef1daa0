#include "stepper.hpp"

#include <algorithm>
#include <boost/numeric/odeint.hpp>
#include <boost/numeric/odeint/external/eigen/eigen.hpp>
#include <cmath>
#include <exception>
#include <utility>

#include "report.hpp"

namespace gausstrack::plant_sim::detail {
namespace {

namespace odeint = boost::numeric::odeint;
using Algebra = odeint::vector_space_algebra;

bool reached(double t, double t1) { return t >= t1 * (1 - 1e-15); }

std::string step_failure(double t, const std::exception& e, const State& x) {
  return "the integrator could not take a step at t = " + number(t) + " s (" + e.what() +
         "): " + describe_state(x);
}

// A method with dense output (dopri5, Bulirsch-Stoer): steps are chosen by the error control
// alone and may pass the segment's end; states between steps are interpolated.
template <class Dense>
class DenseStepper final : public Stepper {
 public:
  // Dense is built in place from `args` (Bulirsch-Stoer's stepper cannot be copied or moved
  // once built: it keeps pointers into itself).
  template <class... Args>
  DenseStepper(RightHandSide rhs, double first_step, Args&&... args)
      : dense_(std::forward<Args>(args)...), rhs_(std::move(rhs)), dt_(first_step) {}

  void start(const State& x, double t0, double t1) override {
    dense_.initialize(x, t0, dt_);
    t1_ = t1;
  }
  bool done() const override { return reached(dense_.current_time(), t1_); }
  StepOutcome step(double) override {
    try {
      dense_.do_step(rhs_);
    } catch (const std::exception& e) {  // odeint gives up after 500 rejected steps
      return {false, step_failure(dense_.current_time(), e, dense_.current_state())};
    }
    dt_ = dense_.current_time_step();
    return {};
  }
  double time() const override { return dense_.current_time(); }
  const State& state() const override { return dense_.current_state(); }
  double step_size() const override { return dense_.current_time_step(); }
  void state_at(double t, State& x) const override {
    if (t >= time()) {
      x = state();
    } else {
      x.resize(state().size());  // Bulirsch-Stoer's interpolation writes into x as it is
      dense_.calc_state(t, x);
    }
  }
  void restart(const State& x) override { dense_.initialize(x, dense_.current_time(), dense_.current_time_step()); }
  bool adaptive() const override { return true; }
  bool interpolates() const override { return true; }

 private:
  Dense dense_;
  RightHandSide rhs_;
  double dt_, t1_ = 0;
};

// Fehlberg 7(8) with error control: odeint has no dense output for it, so its steps are clipped
// to end exactly on sample and segment times (a clipped step does not shrink the step size used
// afterwards).
class ClippedStepper final : public Stepper {
 public:
  ClippedStepper(double tolerance, RightHandSide rhs, double first_step)
      : controlled_(odeint::make_controlled(tolerance, tolerance, Rkf78())), rhs_(std::move(rhs)), dt_(first_step) {}

  void start(const State& x, double t0, double t1) override {
    x_ = x;
    t_ = t0;
    t1_ = t1;
  }
  bool done() const override { return reached(t_, t1_); }
  StepOutcome step(double next_output) override {
    const double stop = std::min(t1_, next_output);
    const bool clipped = stop - t_ < dt_;
    double h = clipped ? stop - t_ : dt_;
    odeint::controlled_step_result result = odeint::fail;
    try {
      result = controlled_.try_step(rhs_, x_, t_, h);
    } catch (const std::exception& e) {
      return {false, step_failure(t_, e, x_)};
    }
    const bool accepted = result == odeint::success;
    if (accepted && clipped) t_ = stop;
    if (!accepted || !clipped) dt_ = h;
    guard_step_ = clipped ? std::max(h, dt_) : dt_;
    return {accepted, {}};
  }
  double time() const override { return t_; }
  const State& state() const override { return x_; }
  double step_size() const override { return guard_step_; }
  void state_at(double, State& x) const override { x = x_; }
  void restart(const State& x) override { x_ = x; }
  bool adaptive() const override { return true; }
  bool interpolates() const override { return false; }

 private:
  using Rkf78 = odeint::runge_kutta_fehlberg78<State, double, State, double, Algebra>;
  decltype(odeint::make_controlled(0.0, 0.0, Rkf78())) controlled_;
  RightHandSide rhs_;
  State x_;
  double t_ = 0, t1_ = 0, dt_, guard_step_ = 0;
};

// Fixed steps of h: the segment takes round((t1 - t0) / h) of them, at times t0 + i h.
class FixedSteps : public Stepper {
 public:
  explicit FixedSteps(double h) : h_(h) {}
  void start(const State& x, double t0, double t1) override {
    x_ = x;
    t0_ = t0;
    i_ = 0;
    n_ = std::llround((t1 - t0) / h_);
  }
  bool done() const override { return i_ >= n_; }
  double time() const override { return t0_ + static_cast<double>(i_) * h_; }
  const State& state() const override { return x_; }
  double step_size() const override { return h_; }
  void state_at(double, State& x) const override { x = x_; }
  void restart(const State& x) override { x_ = x; }
  bool adaptive() const override { return false; }
  bool interpolates() const override { return false; }

 protected:
  State x_;
  double h_, t0_ = 0;
  long long i_ = 0, n_ = 0;
};

class Rk4Stepper final : public FixedSteps {
 public:
  Rk4Stepper(RightHandSide rhs, double h) : FixedSteps(h), rhs_(std::move(rhs)) {}
  StepOutcome step(double) override {
    rk4_.do_step(rhs_, x_, time(), h_);
    ++i_;
    return {};
  }

 private:
  odeint::runge_kutta4<State, double, State, double, Algebra> rk4_;
  RightHandSide rhs_;
};

// A physics engine's fixed steps under the held force; its state is the plant's. (An engine's
// plant lists no constraints, so nothing restarts it from a projected state.)
class EngineStepper final : public FixedSteps {
 public:
  EngineStepper(PlantEngine& engine, const State& held, double h) : FixedSteps(h), engine_(engine), held_(held) {}
  StepOutcome step(double) override {
    if (std::string why = engine_.step(held_.data()); !why.empty()) return {false, std::move(why)};
    engine_.state(x_.data(), x_.data() + x_.size() / 2);
    ++i_;
    return {};
  }

 private:
  PlantEngine& engine_;
  const State& held_;
};

}  // namespace

std::unique_ptr<Stepper> make_stepper(const Scene& s, RightHandSide rhs, double first_step) {
  using Dopri = odeint::runge_kutta_dopri5<State, double, State, double, Algebra>;
  using DenseDopri = decltype(odeint::make_dense_output(0.0, 0.0, Dopri()));
  using BulirschStoer = odeint::bulirsch_stoer_dense_out<State, double, State, double, Algebra>;
  switch (s.method) {
    case Method::kRk4: return std::make_unique<Rk4Stepper>(std::move(rhs), s.step);
    case Method::kDopri5:
      return std::make_unique<DenseStepper<DenseDopri>>(std::move(rhs), first_step,
                                                        odeint::make_dense_output(s.tolerance, s.tolerance, Dopri()));
    case Method::kBulirschStoer:
      // Richardson extrapolation of modified midpoint steps: a high-accuracy choice for offline
      // runs; it allocates its extrapolation tables as it goes. Its interpolation is
      // error-controlled too: a sampled run restarts from the interpolated state.
      return std::make_unique<DenseStepper<BulirschStoer>>(std::move(rhs), first_step, s.tolerance, s.tolerance, 1.0,
                                                           1.0, 0.0, true);
    case Method::kRkf78: return std::make_unique<ClippedStepper>(s.tolerance, std::move(rhs), first_step);
  }
  return nullptr;
}

std::unique_ptr<Stepper> make_engine_stepper(PlantEngine& engine, const State& held, double step) {
  return std::make_unique<EngineStepper>(engine, held, step);
}

}  // namespace gausstrack::plant_sim::detail
