// The one extension point: a model written for the control law (gausstrack::Model: A, f, Q and
// its constraints as phi, psi or hand-written rows) becomes, by name, a scene's tracking
// controller and a scene's plant. The compiled-in models are listed in builtin_models.hpp; a
// user's own model is added to a run with model_factory<MyModel>("my_model") (RunOptions::models,
// or the nodes' mains), and nothing else in the library changes.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <functional>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

#include "gausstrack/model.hpp"
#include "gausstrack/plant_sim/scene.hpp"
#include "gausstrack/tracking_controller.hpp"

namespace gausstrack::plant_sim {

template <typename M>
concept HasParameters = requires(M& m) { m.parameters([](const char*, typename M::Scalar&) {}); };

/// The names a model's parameters() visitor offers (none when it has no visitor).
template <Model M>
std::vector<std::string> parameter_names(M m = {}) {
  std::vector<std::string> names;
  if constexpr (HasParameters<M>) m.parameters([&](const char* n, typename M::Scalar&) { names.emplace_back(n); });
  return names;
}

/// Sets each parameter on the model by name. An unknown name is a SceneError naming where it was
/// written and the names the model knows.
template <Model M>
void apply_parameters(M& m, const std::vector<ModelParameter>& parameters, const std::string& model_name) {
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
      throw SceneError(p.where + ": model '" + model_name + "' has no parameter '" + p.name + "' (known: " +
                       (known.empty() ? "none" : known) + ")");
    }
  }
}

inline InverseStrategy strategy_from(const std::string& s) {
  if (s == "svd") return InverseStrategy::kSvd;
  if (s == "cod") return InverseStrategy::kCompleteOrthogonal;
  if (s == "damped") return InverseStrategy::kDampedLeastSquares;
  return InverseStrategy::kCholeskyWithFallback;
}

/// The controller a scene's tracking section describes for model type M, starting from
/// `defaults`: the same in the offline simulation, the controller process and a user's main.
template <Model M>
TrackingController<M> make_controller(const TrackingSpec& spec, M model = {}) {
  apply_parameters(model, spec.parameters, spec.model);
  ControllerOptions<typename M::Scalar> o;
  o.solver.strategy = strategy_from(spec.strategy);
  o.solver.min_singular_value = spec.min_singular_value;
  o.stabilization = {spec.zeta, spec.stabilization_omega};
  if (const char* error = o.validate()) throw SceneError(spec.where + ": " + error);
  TrackingController<M> controller(model, o);
  controller.set_force_limit(TrackingController<M>::VectorN::Constant(spec.force_limit));
  return controller;
}

/// The tracking error of model m at (q, q', t): the constraint row of largest magnitude, at
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
    const double e = k < kH ? terms.constraint_error(k) : terms.constraint_error_rate(k);
    if (std::abs(e) > std::abs(worst) || !std::isfinite(e)) worst = e;
  }
  return worst;
}

/// A control law as the simulation holds it: any dimension, behind one virtual call.
class ControlLaw {
 public:
  virtual ~ControlLaw() = default;
  virtual int dof() const noexcept = 0;
  /// Writes the force (dof() entries, zero on failure) and returns the solve's status.
  virtual Status compute(const double* q, const double* qd, double t, double* force) noexcept = 0;
  virtual double tracking_error(const double* q, const double* qd, double t) const = 0;
};

template <Model M>
class ModelControlLaw final : public ControlLaw {
 public:
  using V = Eigen::Matrix<double, M::kDof, 1>;
  explicit ModelControlLaw(TrackingController<M> controller) : controller_(std::move(controller)) {}
  int dof() const noexcept override { return M::kDof; }
  Status compute(const double* q, const double* qd, double t, double* force) noexcept override {
    const Status s = controller_.compute(Eigen::Map<const V>(q), Eigen::Map<const V>(qd), t, out_);
    Eigen::Map<V> u(force);
    u = out_.force;
    return s;
  }
  double tracking_error(const double* q, const double* qd, double t) const override {
    return plant_sim::tracking_error(controller_.model(), V(Eigen::Map<const V>(q)), V(Eigen::Map<const V>(qd)), t);
  }

 private:
  TrackingController<M> controller_;
  typename TrackingController<M>::Output out_;
};

/// A plant's own dynamics, A(q, q', t) q'' + f = Q + u, at any dimension.
class PlantModel {
 public:
  virtual ~PlantModel() = default;
  virtual int dof() const noexcept = 0;
  /// A (dof x dof, symmetric positive definite), f and Q at (q, q', t).
  virtual void evaluate(const Eigen::VectorXd& q, const Eigen::VectorXd& qd, double t, Eigen::MatrixXd& A,
                        Eigen::VectorXd& f, Eigen::VectorXd& Q) = 0;
};

/// A model's unconstrained dynamics as a plant (its constraint rows are the controller's task,
/// not physics, and are not used).
template <Model M>
class ModelPlant final : public PlantModel {
 public:
  using V = Eigen::Matrix<double, M::kDof, 1>;
  explicit ModelPlant(M model) : model_(std::move(model)) {}
  int dof() const noexcept override { return M::kDof; }
  void evaluate(const Eigen::VectorXd& q, const Eigen::VectorXd& qd, double t, Eigen::MatrixXd& A, Eigen::VectorXd& f,
                Eigen::VectorXd& Q) override {
    terms_ = {};
    model_.evaluate(V(q), V(qd), t, terms_);
    A = terms_.mass_matrix;
    f = terms_.nonlinear_force;
    Q = terms_.applied_force;
  }

 private:
  M model_;
  TermsOf<M> terms_;
};

/// A model made available to scenes by name: what a scene's tracking section and a scene's
/// plant.model become.
struct ModelFactory {
  std::string name;
  int dof = 0;
  std::vector<std::string> parameter_names;
  std::function<std::unique_ptr<ControlLaw>(const TrackingSpec&)> control_law;
  std::function<std::unique_ptr<PlantModel>(const std::vector<ModelParameter>&)> plant;
  /// The tracking error alone (the model's phi and psi with the spec's parameters): what a plant
  /// whose forces come from elsewhere (a controller process) records, without a controller.
  std::function<std::function<double(const double* q, const double* qd, double t)>(const TrackingSpec&)> tracking_error;
};

/// The factory for model type M under `name`, starting from the parameters of `defaults`.
template <Model M>
ModelFactory model_factory(std::string name, M defaults = {}) {
  static_assert(std::is_same_v<typename M::Scalar, double>, "scenes run models in double");
  ModelFactory f;
  f.name = name;
  f.dof = M::kDof;
  f.parameter_names = parameter_names<M>(defaults);
  f.control_law = [defaults](const TrackingSpec& spec) -> std::unique_ptr<ControlLaw> {
    return std::make_unique<ModelControlLaw<M>>(make_controller<M>(spec, defaults));
  };
  f.plant = [defaults, name](const std::vector<ModelParameter>& parameters) -> std::unique_ptr<PlantModel> {
    M m = defaults;
    apply_parameters(m, parameters, name);
    return std::make_unique<ModelPlant<M>>(m);
  };
  f.tracking_error = [defaults](const TrackingSpec& spec) {
    M m = defaults;
    apply_parameters(m, spec.parameters, spec.model);
    return [m](const double* q, const double* qd, double t) {
      using V = Eigen::Matrix<double, M::kDof, 1>;
      return plant_sim::tracking_error(m, V(Eigen::Map<const V>(q)), V(Eigen::Map<const V>(qd)), t);
    };
  };
  return f;
}

/// The compiled-in models (builtin_models.hpp), by name; nullptr for an unknown name.
const ModelFactory* find_builtin_model(const std::string& name);
/// Their names, for messages.
std::string builtin_model_names();

}  // namespace gausstrack::plant_sim
