// MuJoCo (Debian's libmujoco-dev, 2.2.2) as a plant engine: a scene's `plant: {engine: mujoco,
// model: arm3.xml, timestep: ..., integrator: rk4, effects: [...]}` is stepped by mj_step under
// the held command, applied as qfrc_applied on the scene's joints, or with plant.actuators as the
// control of the model's own motors. Only the effects the scene lists act: the others are off
// through MuJoCo's disable flags and the model's own fields, and the model's actuators act only
// when the scene names them. Design: docs/mujoco_plant.md.
#pragma once

#include <string>
#include <vector>

#include "gausstrack/plant_sim/scene.hpp"
#include "gausstrack/plant_sim/simulation.hpp"

struct mjModel_;
struct mjData_;

namespace gausstrack::plant_sim {

/// An MJCF model whose coordinates are the named joints (hinge or slide joints that together hold
/// all its degrees of freedom), with only the listed effects on. What the engine steps, and what
/// the tests hold the controller's models against.
class MujocoModel {
 public:
  /// Loads spec.model_path and sets spec's timestep, integrator and effects; the state is the
  /// model's qpos0 at rest. Throws SceneError (a file MuJoCo cannot load, a joint it does not have).
  MujocoModel(const EngineSpec& spec, const std::vector<std::string>& joints);
  ~MujocoModel();
  MujocoModel(const MujocoModel&) = delete;
  MujocoModel& operator=(const MujocoModel&) = delete;

  int dof() const noexcept { return static_cast<int>(qpos_index_.size()); }
  /// The actuators the command's control drives (spec.actuators), 0 when it is a force.
  int actuators() const noexcept { return static_cast<int>(actuator_ids_.size()); }

  /// Sets the state (q, q' in the scene's coordinates, at time t) and runs mj_forward.
  void set_state(const double* q, const double* qd, double t = 0);
  void state(double* q, double* qd) const;
  /// After set_state: MuJoCo's mass matrix (mj_fullM, armature included) in the coordinates'
  /// order, column-major dof x dof; and qfrc_bias - qfrc_passive, which is the controller's
  /// f - Q for A q'' + f = Q + u.
  void mass_matrix(double* A) const;
  void bias_minus_passive(double* r) const;
  /// After set_state: the generalized force per unit control of each named actuator, B (column-
  /// major dof x actuators): MuJoCo's actuator_moment (gear and transmission) times its gain.
  void actuation_matrix(double* B) const;

  /// One mj_step under the command u (the generalized force; or, with actuators, the force's
  /// dof() entries followed by the actuators' control, which alone acts): an empty string, or why the state cannot be trusted
  /// (MuJoCo warned of a bad qpos, qvel or qacc and reset its state, dropped contacts or
  /// constraint rows, or called mju_error; after an mju_error the model steps no more).
  std::string step(const double* u);

  std::string description() const;
  const mjModel_* model() const noexcept { return m_; }
  mjData_* data() noexcept { return d_; }

 private:
  void configure(const EngineSpec& spec, const std::vector<std::string>& joints);
  void configure_actuators(const EngineSpec& spec);
  void release() noexcept;

  mjModel_* m_ = nullptr;
  mjData_* d_ = nullptr;
  std::vector<int> qpos_index_, dof_index_, actuator_ids_;
  EngineIntegrator integrator_ = EngineIntegrator::kRk4;
  std::string failure_;
};

/// The factory for plant.engine: mujoco (RunOptions::engines, plant_main's engines).
EngineFactory mujoco_engine();

/// "2.2.2": the library's version, as it reports it.
std::string mujoco_version();

}  // namespace gausstrack::plant_sim
