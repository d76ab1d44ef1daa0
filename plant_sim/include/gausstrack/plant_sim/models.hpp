// The one extension point: a model written for the control law (gausstrack::Model: A, f, Q and
// its constraints as phi, psi or hand-written rows) becomes, by name, a scene's tracking
// controller and a scene's plant. The compiled-in models are listed in
// tracking/builtin_models.hpp; a
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
#include "gausstrack/tracking/builtin_models.hpp"
#include "gausstrack/tracking/make_controller.hpp"
#include "gausstrack/tracking_controller.hpp"

namespace gausstrack::plant_sim {

// The law's configuration (parameters by name, the controller a tracking section describes, the
// tracking error) is gausstrack::tracking's; the simulation uses it under the same names.
using tracking::apply_parameters;
using tracking::make_controller;
using tracking::parameter_names;
using tracking::tracking_error;

/// A control law as the simulation holds it: any dimension, behind one virtual call.
class ControlLaw {
 public:
  virtual ~ControlLaw() = default;
  virtual int dof() const noexcept = 0;
  /// Writes the force (dof() entries, zero on failure) and returns the solve's status.
  virtual Status compute(const double* q, const double* qd, double t, double* force) noexcept = 0;
  /// The last compute's warnings (warning:: flags).
  virtual std::uint32_t warnings() const noexcept = 0;
  /// The model's actuators (the entries of u), or 0 for a model without B.
  virtual int actuators() const noexcept { return 0; }
  /// The last compute's control u (actuators() entries, zero on failure); nullptr without B.
  virtual const double* control() const noexcept { return nullptr; }
  virtual double tracking_error(const double* q, const double* qd, double t) const = 0;
};

template <Model M>
class ModelControlLaw final : public ControlLaw {
 public:
  using V = Eigen::Matrix<double, M::kDof, 1>;
  explicit ModelControlLaw(LawFor<M> controller) : controller_(std::move(controller)) {}
  int dof() const noexcept override { return M::kDof; }
  Status compute(const double* q, const double* qd, double t, double* force) noexcept override {
    const Status s = controller_.compute(Eigen::Map<const V>(q), Eigen::Map<const V>(qd), t, out_);
    Eigen::Map<V> u(force);
    u = out_.force;
    return s;
  }
  std::uint32_t warnings() const noexcept override { return out_.diagnostics.warnings; }
  int actuators() const noexcept override {
    if constexpr (ActuatedModel<M>) return kActuatorsOf<M>;
    else return 0;
  }
  const double* control() const noexcept override {
    if constexpr (ActuatedModel<M>) return out_.control.data();
    else return nullptr;
  }
  double tracking_error(const double* q, const double* qd, double t) const override {
    return tracking::tracking_error(controller_.model(), V(Eigen::Map<const V>(q)), V(Eigen::Map<const V>(qd)), t);
  }

 private:
  LawFor<M> controller_;  ///< ActuatedController for a model with actuators
  typename LawFor<M>::Output out_;
};

/// A plant's own dynamics, A(q, q', t) q'' + f = Q + u, at any dimension.
class PlantModel {
 public:
  virtual ~PlantModel() = default;
  virtual int dof() const noexcept = 0;
  /// A (dof x dof, symmetric positive definite), f and Q at (q, q', t).
  virtual void evaluate(const Eigen::VectorXd& q, const Eigen::VectorXd& qd, double t,
                        Eigen::MatrixXd& A, Eigen::VectorXd& f, Eigen::VectorXd& Q) = 0;
  /// The rows the environment holds (the model's physical rows), which the plant enforces.
  virtual int physical_rows() const noexcept { return 0; }
  /// Physical row k is a position-level (holonomic) row: its error e is phi.
  virtual bool physical_holonomic(int) const noexcept { return false; }
  /// The physical rows at (q, q', t): D_p q'' = g_p (rows physical_rows(), written into the
  /// caller's D, g from row `first` on), with their position errors e (phi, 0 for a row from psi)
  /// and velocity errors e' (phi', psi).
  virtual void physical(const Eigen::VectorXd&, const Eigen::VectorXd&, double, int,
                        Eigen::MatrixXd&, Eigen::VectorXd&, Eigen::VectorXd&, Eigen::VectorXd&) {}
};

/// A model's dynamics as a plant, with the rows it declares physical held (its task rows are the
/// controller's, not physics, and are not used).
template <Model M>
class ModelPlant final : public PlantModel {
  static_assert(RowLayout<M>::kFirstAcceleration >= 64 ||
                    (RowLayout<M>::kPhysicalMask >> RowLayout<M>::kFirstAcceleration) == 0,
                "a plant holds physical rows written as phi or psi (it projects onto their errors); a "
                "hand-written acceleration-level row has no error the plant could hold");

 public:
  using V = Eigen::Matrix<double, M::kDof, 1>;
  explicit ModelPlant(M model) : model_(std::move(model)) {}
  int dof() const noexcept override { return M::kDof; }
  int physical_rows() const noexcept override { return RowLayout<M>::kPhysical; }
  bool physical_holonomic(int k) const noexcept override {
    return row(k) < RowLayout<M>::kHolonomic;
  }
  void physical(const Eigen::VectorXd& q, const Eigen::VectorXd& qd, double t, int first,
                Eigen::MatrixXd& D, Eigen::VectorXd& g, Eigen::VectorXd& e,
                Eigen::VectorXd& e_rate) override {
    if constexpr (RowLayout<M>::kPhysical > 0) {
      terms_ = {};
      evaluate_model(model_, V(q), V(qd), t, terms_);
      for (int k = 0; k < RowLayout<M>::kPhysical; ++k) {
        const int r = row(k);
        D.row(first + k) = terms_.constraint_matrix.row(r);
        g(first + k) = terms_.constraint_rhs(r);
        e(first + k) = terms_.constraint_error(r);
        e_rate(first + k) = terms_.constraint_error_rate(r);
      }
    }
  }
  void evaluate(const Eigen::VectorXd& q, const Eigen::VectorXd& qd, double t, Eigen::MatrixXd& A,
                Eigen::VectorXd& f, Eigen::VectorXd& Q) override {
    terms_ = {};
    model_.evaluate(V(q), V(qd), t, terms_);
    A = terms_.mass_matrix;
    f = terms_.nonlinear_force;
    Q = terms_.applied_force;
  }

 private:
  // The model's row of physical row k.
  static int row(int k) noexcept {
    for (int i = 0, seen = 0; i < M::kConstraints; ++i)
      if (RowLayout<M>::physical(i) && seen++ == k) return i;
    return -1;
  }
  M model_;
  TermsOf<M> terms_;
};

/// A model made available to scenes by name: what a scene's tracking section and a scene's
/// plant.model become.
struct ModelFactory {
  std::string name;
  int dof = 0;
  int physical_rows = 0;  ///< rows the plant must hold for the law to track (RowLayout::kPhysical)
  int actuators = 0;      ///< the entries of u for a model with B (kActuatorsOf), 0 without
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
  f.physical_rows = RowLayout<M>::kPhysical;
  if constexpr (ActuatedModel<M>) f.actuators = kActuatorsOf<M>;
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
      return tracking::tracking_error(m, V(Eigen::Map<const V>(q)), V(Eigen::Map<const V>(qd)), t);
    };
  };
  return f;
}

/// The compiled-in models (tracking/builtin_models.hpp), by name; nullptr for an unknown name.
const ModelFactory* find_builtin_model(const std::string& name);
using tracking::builtin_model_names;

}  // namespace gausstrack::plant_sim
