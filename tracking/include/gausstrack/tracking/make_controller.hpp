// From a tracking configuration to a controller for model type M: parameters set by name, the
// strategy, stabilization, singular-value floor and force limit. The same in the offline
// simulation, the controller process and a user's own main. Templates on the model alone: no
// YAML here.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <string>
#include <type_traits>
#include <vector>

#include "gausstrack/model.hpp"
#include "gausstrack/tracking/config.hpp"
#include "gausstrack/actuation.hpp"
#include "gausstrack/tracking_controller.hpp"

namespace gausstrack::tracking {

template <typename M>
concept HasParameters = requires(M& m) {
  m.parameters([](const char*, typename M::Scalar&) {});
};

/// The names a model's parameters() visitor offers (none when it has no visitor).
template <Model M>
std::vector<std::string> parameter_names(M m = {}) {
  std::vector<std::string> names;
  if constexpr (HasParameters<M>)
    m.parameters([&](const char* n, typename M::Scalar&) { names.emplace_back(n); });
  return names;
}

/// Sets each parameter on the model by name. An unknown name is a ConfigError naming where it was
/// written and the names the model knows.
template <Model M>
void apply_parameters(M& m, const std::vector<ModelParameter>& parameters,
                      const std::string& model_name) {
  for (const ModelParameter& p : parameters) {
    bool found = false;
    if constexpr (HasParameters<M>)
      m.parameters([&](const char* n, typename M::Scalar& v) {
        if (!found && p.name == n) {
          v = static_cast<typename M::Scalar>(p.value);
          found = true;
        }
      });
    if (!found) {
      std::string known;
      for (const std::string& n : parameter_names<M>()) known += (known.empty() ? "" : ", ") + n;
      throw ConfigError(p.where + ": model '" + model_name + "' has no parameter '" + p.name +
                        "' (known: " + (known.empty() ? "none" : known) + ")");
    }
  }
}

/// The controller the tracking section describes for model type M, starting from `model`'s
/// parameters: an ActuatedController when M declares actuators or physical rows (force_limit then
/// limits each actuator), else a TrackingController. Throws ConfigError for options the controller
/// refuses.
template <Model M>
LawFor<M> make_controller(const TrackingSpec& spec, M model = {}) {
  apply_parameters(model, spec.parameters, spec.model);
  ControllerOptions<typename M::Scalar> o;
  o.solver.strategy = spec.strategy;
  o.solver.min_singular_value = static_cast<typename M::Scalar>(spec.min_singular_value);
  o.stabilization = {static_cast<typename M::Scalar>(spec.zeta),
                     static_cast<typename M::Scalar>(spec.stabilization_omega)};
  o.robust = {static_cast<typename M::Scalar>(spec.robust_bound), static_cast<typename M::Scalar>(spec.robust_layer)};
  if (spec.hold == HoldLaw::kMidpoint)
    o.hold = {static_cast<typename M::Scalar>(spec.period), static_cast<typename M::Scalar>(spec.delay)};
  if (const char* error = o.validate()) throw ConfigError(spec.where + ": " + error);
  LawFor<M> controller(model, o);
  const auto limit = static_cast<typename M::Scalar>(spec.force_limit);
  if constexpr (std::is_same_v<LawFor<M>, ActuatedController<M>>)
    controller.set_actuator_limit(LawFor<M>::VectorK::Constant(limit));
  else
    controller.set_force_limit(LawFor<M>::VectorN::Constant(limit));
  return controller;
}

/// The tracking error of model m at (q, q', t): the task row of largest magnitude, at
/// position level for rows derived from phi and at velocity level for rows from psi (0 for
/// hand-written rows, which have neither).
template <Model M>
double tracking_error(const M& m, const Eigen::Matrix<double, M::kDof, 1>& q,
                      const Eigen::Matrix<double, M::kDof, 1>& qd, double t) {
  TermsOf<M> terms;
  evaluate_model(m, q, qd, t, terms);
  double worst = 0;
  constexpr int kH = RowLayout<M>::kHolonomic, kV = RowLayout<M>::kNonholonomic;
  for (int k = 0; k < kH + kV; ++k) {
    if (RowLayout<M>::physical(k)) continue;  // the plant's, not the task's
    const double e = k < kH ? terms.constraint_error(k) : terms.constraint_error_rate(k);
    if (std::abs(e) > std::abs(worst) || !std::isfinite(e)) worst = e;
  }
  return worst;
}

}  // namespace gausstrack::tracking
