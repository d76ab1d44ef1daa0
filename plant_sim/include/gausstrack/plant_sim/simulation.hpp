// Runs a scene: integrates the plant's constrained equations of motion (eq. 31) with the
// tracking control law of eq. (32) in the loop, and records samples at exact output times.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <nlohmann/json_fwd.hpp>
#include <span>
#include <string>
#include <vector>

#include "gausstrack/plant_sim/models.hpp"
#include "gausstrack/plant_sim/scene.hpp"

namespace gausstrack::plant_sim {

struct Sample {
  double t = 0;
  std::vector<double> q, qd;
  std::vector<double> u;                ///< control force applied [N]
  double tracking_error = 0;            ///< tracking constraint at position level (0 when none)
  double constraint_residual = 0;       ///< physical constraint residual (0 when none); position
                                        ///< level for the pendulum, velocity level (y' - z x') for
                                        ///< the nonholonomic constraint, which has no other
};

struct RunSummary {
  double max_tracking_error = 0;
  double rms_tracking_error = 0;  ///< over the samples
  double max_constraint_residual = 0;
  /// The applied force's total variation over the samples, sum_k ||u_k - u_(k-1)||_1 [N]: how much
  /// the force moves (a chattering force's grows with the sampling).
  double force_total_variation = 0;
  std::uint64_t steps = 0;            ///< accepted integrator steps
  std::uint64_t rhs_evaluations = 0;  ///< evaluations of the equations of motion
  std::uint64_t control_evaluations = 0;
  std::uint64_t control_failures = 0;  ///< controller calls that returned a failure status
  /// The warnings of the control evaluations (offline) or of the control periods (over LCM: the
  /// applied answer's, each period it was held).
  WarningTally warnings;
  /// Not empty when the run did not track: the share of evaluations (periods) whose answer left
  /// task rows unmet was above tracking.unmet_limit (rows_not_met()). The run still completed.
  std::string rows_not_met;
  std::uint64_t projections = 0;       ///< states projected onto the constraints (plant.projection)
  double wall_time_s = 0;
  bool stopped_early = false;  ///< the external control source, or a stop request, ended the run
  /// Why the run could not go on (empty when it completed): steps collapsing below the scene's
  /// integrator.min_step, the step budget integrator.max_steps spent, or the state leaving the
  /// finite range; with the time it happened and the quantities involved. The samples up to then
  /// are kept.
  std::string failure;
  double failed_at = 0;  ///< simulated time of the failure [s]
  /// Evaluations of each effect kind (indexed by EffectKind): zero for every kind not listed.
  std::array<std::uint64_t, static_cast<std::size_t>(EffectKind::kCount)> effect_evaluations{};
  /// The engine that stepped the plant (plant.engine), e.g. "mujoco 2.2.2, rk4, timestep 0.0001 s";
  /// empty for plant_sim's own integrator.
  std::string engine;
  std::vector<std::string> engine_effects;  ///< the engine's effects that were on
};

/// A plant stepped by a physics engine (plant.engine): fixed steps of the scene's timestep under
/// a generalized force held over each step, in the scene's coordinates.
class PlantEngine {
 public:
  virtual ~PlantEngine() = default;
  /// Advances one step under the held command u: the generalized force (one entry per
  /// coordinate), then, for a plant driven through its own actuators (plant.actuators), their
  /// control (which then acts instead of the force). Returns an empty string, or why the plant
  /// cannot go on (the engine failed, or reset its state); the run then ends with it.
  virtual std::string step(const double* u) = 0;
  /// The state after the last step (at first, the scene's initial state).
  virtual void state(double* q, double* qd) const = 0;
  /// For the summary: the engine, its version, integrator and step.
  virtual std::string description() const = 0;
};

/// An engine made available to scenes by name (plant.engine).
struct EngineFactory {
  std::string name;
  /// Builds the engine for a scene; throws SceneError for a model that does not fit the scene.
  std::function<std::unique_ptr<PlantEngine>(const Scene&)> make;
};

struct RunResult {
  std::vector<Sample> samples;
  RunSummary summary;
};

struct RunOptions {
  /// Called now and then with the simulated time (for a progress display).
  std::function<void(double t)> on_progress;
  /// Sampled control from elsewhere (a controller process): called at the start of control
  /// period `period` with the measured state, writes the command to hold into u (zero on entry:
  /// the N force entries, then the scene's Scene::actuators() control entries) and returns false
  /// to stop the run. Replaces the scene's own controller; needs
  /// sampled control. The spans view fixed-size storage: calling it allocates nothing.
  std::function<bool(std::int64_t period, double t, std::span<const double> q, std::span<const double> qd,
                     std::span<double> u)>
      sampled_control;
  /// Models the scene may name (tracking.model, plant.model) besides the compiled-in ones: how a
  /// user's own model runs, e.g. models = {model_factory<MyModel>("my_model")}.
  std::vector<ModelFactory> models;
  /// The engines scenes may name (plant.engine): the programs pass mujoco_engine() when built with
  /// MuJoCo.
  std::vector<EngineFactory> engines;
  /// Polled between steps: true stops the run where it is (stopped_early), keeping its samples.
  std::function<bool()> stop_requested;
};

RunResult run_scene(const Scene& scene, const RunOptions& options = {});

/// Why a run did not track, or empty: the share of `warnings.calls` (control evaluations, or
/// periods: `unit`) whose answer left task rows unmet is above the scene's tracking.unmet_limit;
/// the message gives the share and the count of each warning kind.
std::string rows_not_met(const Scene& scene, const WarningTally& warnings, const char* unit);
/// "constraints_not_met 12, saturated 3": the count of each warning kind that occurred, and of
/// failures; empty when none.
std::string warning_counts(const WarningTally& warnings);

/// A progress display for on_progress: "name: t = 3.000 / 10.000 s ( 30%)" on stderr, rewritten
/// in place, shown only when stderr is a terminal and the run has lasted a second.
std::function<void(double t)> terminal_progress(const Scene& scene);

/// The plant's generalized impressed force Q(q, q', t) from the scene's force effects.
std::vector<double> plant_applied_force(const Scene& scene, const std::vector<double>& q,
                                        const std::vector<double>& qd, double t);
/// The plant's acceleration (eq. 31 with its physical constraint, if any) under control force u.
std::vector<double> plant_acceleration(const Scene& scene, const std::vector<double>& q,
                                       const std::vector<double>& qd, double t,
                                       const std::vector<double>& u);

/// `t,q1..qN,qd1..qdN,u1..uN,tracking_error,constraint_residual`, one row per sample.
void write_trajectory_csv(const Scene& scene, const RunResult& result, const std::string& path);
/// The run's summary (summary.json's members): whether it completed or why not, tracking and
/// constraint errors, work counts, effects evaluated, engine, wall time. A process adds its own
/// members (e.g. its loop statistics) before writing it.
nlohmann::ordered_json summary_json(const Scene& scene, const RunResult& result);
/// Writes a JSON document, indented, to path. Throws std::runtime_error when it cannot.
void write_json(const nlohmann::ordered_json& document, const std::string& path);
/// write_json(summary_json(scene, result), path).
void write_summary_json(const Scene& scene, const RunResult& result, const std::string& path);

}  // namespace gausstrack::plant_sim
