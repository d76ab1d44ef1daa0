// The law's configuration: the `tracking` section of a YAML file (a whole scene, or a file holding
// that section alone) says which model the controller runs, with which parameters, how its
// constraints are stabilized and how eq. (32) is computed. What a controller process needs and
// nothing of the plant: this component depends on the law and yaml-cpp alone.
#pragma once

#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "gausstrack/constraint_solver.hpp"

namespace gausstrack::tracking {

/// A configuration (or scene) that cannot be used. what() names the file, the line and the
/// dotted key, or the --set override.
class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// One named model parameter, with where it was written (for error messages).
struct ModelParameter {
  std::string name;
  double value = 0;
  std::string where;  ///< "file:line: dotted.key"
};

/// How a sampled controller chooses the force it holds over a period (TrackingController's Hold).
enum class HoldLaw {
  kMidpoint,  ///< the law at the middle of the hold interval, at the state predicted there
  kSample,    ///< the law at the measured state (first order in the period)
};
constexpr const char* to_string(HoldLaw h) noexcept { return h == HoldLaw::kMidpoint ? "midpoint" : "sample"; }
inline constexpr HoldLaw kHoldLaws[] = {HoldLaw::kMidpoint, HoldLaw::kSample};

/// The tracking task: the controller's own model of the plant (which may differ from the plant
/// on purpose), its parameters (the trajectory's included) and how the law is computed.
struct TrackingSpec {
  bool enabled = false;
  std::string model;                       ///< a compiled-in model's name, or a user's
  std::string where;                       ///< where `model` was written
  std::vector<ModelParameter> parameters;  ///< tracking.parameters, then tracking.trajectory
  double zeta = 1, stabilization_omega = 0;
  /// The robust term (tracking.robust: bound [row units/s^2] and layer [row units/s], both > 0) for
  /// every row; robust_bound 0 (no tracking.robust): none.
  double robust_bound = 0, robust_layer = 1;
  InverseStrategy strategy = InverseStrategy::kCholeskyWithFallback;
  /// Actuator limit on every coordinate [N]: no command exceeds it (saturation is reported).
  double force_limit = std::numeric_limits<double>::infinity();
  /// SolverOptions::min_singular_value: the physical-scale near-singularity floor (0: off).
  double min_singular_value = 0;
  /// Sampled control: the control period [s] (1 / control.rate of a scene whose control.mode is
  /// sampled; 0: continuous control, no hold), the hold law (tracking.hold) and the delay from the
  /// measurement to the force's application the controller assumes (tracking.delay) [s].
  double period = 0;
  HoldLaw hold = HoldLaw::kMidpoint;
  double delay = 0;
  /// tracking.delay was given: a controller process keeps it instead of the delay the plant
  /// reports with each state.
  bool delay_configured = false;
  /// The largest share of control evaluations (periods) whose answer may leave task rows unmet
  /// (warning::kRowsNotMet) before a run reports that it did not track (tracking.unmet_limit).
  double unmet_limit = 0.01;

  /// The value of a parameter the configuration sets, or `fallback`.
  double parameter(const std::string& name, double fallback) const {
    for (const ModelParameter& p : parameters)
      if (p.name == name) return p.value;
    return fallback;
  }
};

/// One name table per enum: its to_string. The value among `values` whose name is `name`, or
/// nothing.
template <class E, std::size_t K>
std::optional<E> from_name(const E (&values)[K], std::string_view name) {
  for (E v : values)
    if (name == to_string(v)) return v;
  return std::nullopt;
}

/// "a, b, c": the names of `values`, for messages.
template <class E, std::size_t K>
std::string names_of(const E (&values)[K]) {
  std::string names;
  for (E v : values) names += (names.empty() ? "" : ", ") + std::string(to_string(v));
  return names;
}

/// Every strategy, in the order the names are listed in messages.
inline constexpr InverseStrategy kStrategies[] = {
    InverseStrategy::kCholeskyWithFallback, InverseStrategy::kSvd,
    InverseStrategy::kCompleteOrthogonal, InverseStrategy::kDampedLeastSquares};

/// The strategy whose name (to_string, the one name table) is `name`; nothing for another name.
std::optional<InverseStrategy> strategy_from_name(std::string_view name);
/// "cholesky, svd, cod, damped", for messages.
std::string strategy_names();

/// Reads the `tracking` section of the file at `path` (nothing else in it is read). `overrides`
/// are "dotted.key=value" pairs applied first (values parsed as YAML). Throws ConfigError naming
/// file, line and key.
TrackingSpec load_tracking(const std::string& path, const std::vector<std::string>& overrides = {});
/// The same from YAML text; `name` stands for the file in messages.
TrackingSpec parse_tracking(const std::string& yaml_text, const std::string& name,
                            const std::vector<std::string>& overrides = {});

}  // namespace gausstrack::tracking
