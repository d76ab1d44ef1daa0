// The control law a scene's `tracking` section describes, built the same way by the offline
// simulation and by the controller process, so that both compute the same forces.
#pragma once

#include "gausstrack/plant_sim/scene.hpp"
#include "gausstrack/systems/coupled_duffing.hpp"
#include "gausstrack/tracking_controller.hpp"

namespace gausstrack::plant_sim {

using SceneModel = systems::CoupledDuffing<double>;
using SceneController = TrackingController<SceneModel>;

inline InverseStrategy strategy_from(const std::string& s) {
  if (s == "svd") return InverseStrategy::kSvd;
  if (s == "cod") return InverseStrategy::kCompleteOrthogonal;
  if (s == "damped") return InverseStrategy::kDampedLeastSquares;
  return InverseStrategy::kCholeskyWithFallback;
}

/// The controller for a checked scene's tracking spec (tracking.enabled must be true).
inline SceneController make_scene_controller(const TrackingSpec& t) {
  SceneModel m;
  m.m1 = t.m1, m.m2 = t.m2, m.k1 = t.k1, m.k2 = t.k2, m.kb1 = t.kb1, m.kb2 = t.kb2, m.c1 = t.c1, m.c2 = t.c2;
  m.trajectory = {t.amplitude, t.alpha, t.omega};
  ControllerOptions<double> o;
  o.solver.strategy = strategy_from(t.strategy);
  o.stabilization = {t.zeta, t.stabilization_omega};
  o.solver.min_singular_value = t.min_singular_value;
  SceneController controller(m, o);
  controller.set_force_limit(SceneModel::Vector::Constant(t.force_limit));
  return controller;
}

}  // namespace gausstrack::plant_sim
