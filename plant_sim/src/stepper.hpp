// How the plant's state moves in time (internal to plant_sim): one interface that odeint's
// methods and a physics engine implement, so that the run loop is one loop for all of them.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <memory>
#include <string>

#include "gausstrack/plant_sim/scene.hpp"
#include "gausstrack/plant_sim/simulation.hpp"

namespace gausstrack::plant_sim::detail {

using State = Eigen::VectorXd;  ///< x = (q, q')
/// The equations of motion in first-order form: dxdt = (q', q'') at (x, t).
using RightHandSide = std::function<void(const State& x, State& dxdt, double t)>;

/// What one attempt at a step did.
struct StepOutcome {
  bool accepted = true;  ///< false: the step was rejected and will be retried with a smaller one
  std::string failure;   ///< why no step can be taken (the run ends with it); empty otherwise
};

/// Advances the state over segments [t0, t1]: the whole run under continuous control, or one
/// control period each when the force is sampled and held.
class Stepper {
 public:
  virtual ~Stepper() = default;
  /// Starts a segment from state x at t0; the segment ends at t1.
  virtual void start(const State& x, double t0, double t1) = 0;
  /// True when the segment's end has been reached.
  virtual bool done() const = 0;
  /// One attempt at a step. `next_output` is the next sample time: a method without
  /// interpolation ends its step there; one with dense output ignores it.
  virtual StepOutcome step(double next_output) = 0;
  virtual double time() const = 0;
  virtual const State& state() const = 0;
  /// The step size in use (for the guard against collapsing steps).
  virtual double step_size() const = 0;
  /// The state at t within the last accepted step (interpolated, or the step's end state).
  virtual void state_at(double t, State& x) const = 0;
  /// Continues from x at time() (after a projection onto the constraints).
  virtual void restart(const State& x) = 0;
  /// Whether step sizes adapt (then collapsing steps end the run).
  virtual bool adaptive() const = 0;
  /// Whether states between steps are interpolated (dense output): then a step's end state must
  /// stay as it is until its samples are taken, and the projection comes after them.
  virtual bool interpolates() const = 0;
};

/// The scene's method (integrator.method) on the right-hand side, or the engine when the scene
/// names one (the engine's state is the plant's; the held force is read from `held`).
std::unique_ptr<Stepper> make_stepper(const Scene& s, RightHandSide rhs, double first_step);
std::unique_ptr<Stepper> make_engine_stepper(PlantEngine& engine, const State& held, double step);

}  // namespace gausstrack::plant_sim::detail
