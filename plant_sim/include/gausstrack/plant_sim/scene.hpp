// A scene: which plant to simulate (coordinates, masses, the physical effects acting on it, its
// physical constraints), the tracking task given to the controller, how control is applied,
// the integrator, and the output. Loaded from YAML; every value is checked before anything runs.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "gausstrack/tracking/config.hpp"

namespace gausstrack::plant_sim {

/// A scene file that cannot be used: the configuration error of gausstrack::tracking (what()
/// names the file, the line and the dotted key).
using SceneError = tracking::ConfigError;
/// The tracking section and its parameters are the law's configuration (gausstrack::tracking).
using tracking::ModelParameter;
using tracking::TrackingSpec;
using tracking::load_tracking;
using tracking::parse_tracking;

inline constexpr int kGround = -1;  ///< coordinate index meaning "attached to ground"
inline constexpr int kMaxCoordinates = 32;  ///< the messages' MAX_DIMENSION

/// The physical effects a scene may name. Only the named ones are built and evaluated.
enum class EffectKind : std::uint8_t {
  kGravity,             ///< constant force m g on one coordinate
  kSpring,              ///< linear spring k d between two coordinates or a coordinate and ground
  kCubicSpring,         ///< cubic spring k d^3
  kDamper,              ///< viscous damper c d'
  kDisturbance,         ///< external force A sin(w t + phase) on one coordinate
  kActuatorSaturation,  ///< clamps each control force component to [-limit, limit]
  kSensorNoise,         ///< Gaussian noise on the state the controller measures (sampled control)
  kCount
};
const char* to_string(EffectKind kind) noexcept;  ///< the scene's name: "gravity", "cubic_spring", ...
inline constexpr EffectKind kEffectKinds[] = {EffectKind::kGravity,   EffectKind::kSpring,
                                              EffectKind::kCubicSpring, EffectKind::kDamper,
                                              EffectKind::kDisturbance, EffectKind::kActuatorSaturation,
                                              EffectKind::kSensorNoise};

struct EffectSpec {
  EffectKind kind = EffectKind::kGravity;
  int a = 0;                 ///< first coordinate
  int b = kGround;           ///< second coordinate or kGround
  double value = 0.0;        ///< stiffness [N/m, N/m^3], coefficient [N s/m], acceleration
                             ///< [m/s^2], amplitude [N], limit [N] or standard deviation
  double frequency = 0.0;    ///< disturbance [rad/s]
  double phase = 0.0;        ///< disturbance [rad]
  std::uint64_t seed = 1;    ///< sensor noise
};

enum class ConstraintKind : std::uint8_t {
  kPendulumLength,  ///< x^2 + y^2 = L^2 (1 - mu sin(x^2)), eq. (34)
  kNonholonomic,    ///< y' = z x', eq. (36)
};
const char* to_string(ConstraintKind kind) noexcept;  ///< "pendulum_length", "nonholonomic"
inline constexpr ConstraintKind kConstraintKinds[] = {ConstraintKind::kPendulumLength, ConstraintKind::kNonholonomic};

struct ConstraintSpec {
  ConstraintKind kind = ConstraintKind::kPendulumLength;
  std::vector<int> coordinates;  ///< (x, y) or (x, y, z)
  double length = 0.0;
  double mu = 0.0;
};

/// The engine's own integrator (plant.integrator).
enum class EngineIntegrator : std::uint8_t { kEuler, kRk4, kImplicit };
const char* to_string(EngineIntegrator integrator) noexcept;  ///< "euler", "rk4", "implicit"
inline constexpr EngineIntegrator kEngineIntegrators[] = {EngineIntegrator::kEuler, EngineIntegrator::kRk4,
                                                          EngineIntegrator::kImplicit};

/// A plant stepped by a physics engine instead of plant_sim's own integrator (plant.engine).
struct EngineSpec {
  std::string name;        ///< "mujoco"; empty: plant_sim's own (point masses or a model)
  std::string model_path;  ///< plant.model: the engine's model file (MJCF), resolved against the scene's directory
  std::string where;       ///< where plant.engine was written
  double timestep = 0;     ///< the engine's fixed step [s]
  EngineIntegrator integrator = EngineIntegrator::kRk4;
  std::vector<std::string> effects;   ///< the engine's effects switched on; all others are off
  /// plant.actuators: the model's own actuators (MJCF <motor>s) that the command's control u
  /// drives, in the order of the controller's u. Empty: the command's generalized force acts on
  /// the joints directly and the model's actuators never act.
  std::vector<std::string> actuators;
};

/// The effects a MuJoCo plant may list; everything unlisted is switched off.
inline constexpr const char* kMujocoEffects[] = {"gravity", "damping", "springs", "armature",
                                                 "frictionloss", "limits", "contact", "equality"};

enum class ControlMode : std::uint8_t { kContinuous, kSampled };
const char* to_string(ControlMode mode) noexcept;  ///< "continuous", "sampled"
inline constexpr ControlMode kControlModes[] = {ControlMode::kContinuous, ControlMode::kSampled};

/// The plant's integrator: fixed-step RK4; Dormand-Prince 5(4) with dense output; Fehlberg 7(8)
/// (steps end on sample times: odeint has no dense output for it); Bulirsch-Stoer with dense
/// output (high accuracy, offline: it allocates as it steps).
enum class Method : std::uint8_t { kRk4, kDopri5, kRkf78, kBulirschStoer };
const char* to_string(Method method) noexcept;  ///< "rk4", "dopri5", "rkf78", "bulirsch_stoer"
inline constexpr Method kMethods[] = {Method::kRk4, Method::kDopri5, Method::kRkf78, Method::kBulirschStoer};

struct Scene {
  std::string file;
  std::string name;
  std::vector<std::string> coordinates;
  /// Point masses (one per coordinate), or empty when the plant is a model (plant.model): then
  /// A, f and Q are that model's and the effects add to them.
  std::vector<double> masses;
  std::string plant_model;                       ///< plant.model: a model's name
  std::string plant_model_where;
  std::vector<ModelParameter> plant_parameters;  ///< plant.parameters (model mismatch)
  /// plant.engine: a physics engine steps the plant (coordinates are then its joints' names,
  /// control is sampled, and the integrator is the engine's: method rk4 with step = timestep
  /// stands for it in the checks of output and control periods).
  EngineSpec engine;
  std::vector<double> q0, qd0;
  std::vector<EffectSpec> effects;
  std::vector<ConstraintSpec> constraints;
  /// plant.projection: after each accepted step, project the state onto the position and
  /// velocity constraint manifolds (against the drift of acceleration-level integration).
  bool projection = false;
  TrackingSpec tracking;
  ControlMode control_mode = ControlMode::kContinuous;
  double control_rate = 0.0;  ///< [Hz], sampled mode
  Method method = Method::kDopri5;
  double tolerance = 1e-10;   ///< absolute and relative local tolerance (adaptive methods)
  double step = 1e-3;         ///< fixed step (rk4) [s]
  /// Adaptive steps below this end the run with an error (steps collapsing: a diverging or
  /// stiff plant) [s]; default 1e-12 of the duration.
  double min_step = 0;
  /// The most integrator steps a run may take before it ends with an error.
  double max_steps = 1e8;
  double duration = 10.0;     ///< [s]
  double output_period = 0.01;  ///< [s]

  int dof() const noexcept { return static_cast<int>(coordinates.size()); }
  /// The engine's actuators driven by the command's control (plant.actuators); 0 otherwise.
  int actuators() const noexcept { return static_cast<int>(engine.actuators.size()); }
  /// The held command's entries: the generalized force (dof()), then the control (actuators()).
  int command_size() const noexcept { return dof() + actuators(); }
};

/// Loads and checks a scene. `overrides` are "dotted.key=value" pairs applied before checking
/// (values are parsed as YAML; a list index one past the end appends). Throws SceneError naming
/// file, line and key.
Scene load_scene(const std::string& path, const std::vector<std::string>& overrides = {});

/// The same from YAML text; `name` stands for the file in messages.
Scene parse_scene(const std::string& yaml_text, const std::string& name,
                  const std::vector<std::string>& overrides = {});

}  // namespace gausstrack::plant_sim
