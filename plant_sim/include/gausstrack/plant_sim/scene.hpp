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

namespace gausstrack::plant_sim {

/// A scene file that cannot be used. what() names the file, the line and the dotted key.
class SceneError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

inline constexpr int kGround = -1;  ///< coordinate index meaning "attached to ground"

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
const char* to_string(EffectKind kind) noexcept;

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

struct ConstraintSpec {
  ConstraintKind kind = ConstraintKind::kPendulumLength;
  std::vector<int> coordinates;  ///< (x, y) or (x, y, z)
  double length = 0.0;
  double mu = 0.0;
};

/// The tracking task: the controller's own model of the plant (which may differ from the plant
/// on purpose) and the trajectory it imposes.
struct TrackingSpec {
  bool enabled = false;
  std::string model;  ///< "coupled_duffing"
  double m1 = 2, m2 = 1, k1 = 10, k2 = 12, kb1 = 1, kb2 = 2, c1 = 0.1, c2 = 0.15;
  double amplitude = 1, alpha = 4, omega = 6.283185307179586;
  double zeta = 1, stabilization_omega = 0;
  std::string strategy = "cholesky";
  /// Actuator limit on every coordinate [N]: no command exceeds it (saturation is reported).
  double force_limit = std::numeric_limits<double>::infinity();
  /// SolverOptions::min_singular_value: the physical-scale near-singularity floor (0: off).
  double min_singular_value = 0;
};

enum class ControlMode : std::uint8_t { kContinuous, kSampled };
enum class Method : std::uint8_t { kRk4, kDopri5, kRkf78 };

struct Scene {
  std::string file;
  std::string name;
  std::vector<std::string> coordinates;
  std::vector<double> masses;
  std::vector<double> q0, qd0;
  std::vector<EffectSpec> effects;
  std::vector<ConstraintSpec> constraints;
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
  bool compare_angle_model = false;  ///< pendulum: also integrate the angle-coordinate model

  int dof() const noexcept { return static_cast<int>(coordinates.size()); }
};

/// Loads and checks a scene. `overrides` are "dotted.key=value" pairs applied before checking
/// (values are parsed as YAML; a list index one past the end appends). Throws SceneError naming
/// file, line and key.
Scene load_scene(const std::string& path, const std::vector<std::string>& overrides = {});

/// The same from YAML text; `name` stands for the file in messages.
Scene parse_scene(const std::string& yaml_text, const std::string& name,
                  const std::vector<std::string>& overrides = {});

}  // namespace gausstrack::plant_sim
