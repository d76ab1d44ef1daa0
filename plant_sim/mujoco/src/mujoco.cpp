#include "gausstrack/plant_sim/mujoco.hpp"

#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <stdexcept>

namespace gausstrack::plant_sim {
namespace {

// mju_error would print, wait for Enter and end the process; here it becomes an exception that
// ends the run with MuJoCo's message.
[[noreturn]] void throw_error(const char* message) { throw std::runtime_error(std::string("MuJoCo: ") + message); }
// Warnings are read from mjData's counters after each step; none is written to MUJOCO_LOG.TXT.
void ignore_warning(const char*) {}

void install_handlers() {
  mju_user_error = throw_error;
  mju_user_warning = ignore_warning;
}

bool listed(const EngineSpec& spec, const char* effect) {
  return std::find(spec.effects.begin(), spec.effects.end(), effect) != spec.effects.end();
}

std::string g(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.6g", v);
  return b;
}

// The warnings with which mj_step resets the state to qpos0 (or computes from a singular M).
// And those with which it drops contacts or constraint rows (nconmax, njmax full) and goes on
// with other physics than the scene's.
constexpr struct {
  int index;
  const char* what;
} kResetWarnings[] = {{mjWARN_BADQPOS, "a bad number in qpos"},
                      {mjWARN_BADQVEL, "a bad number in qvel"},
                      {mjWARN_BADQACC, "a bad number or an acceleration above 1e10 in qacc"},
                      {mjWARN_INERTIA, "a (near) singular mass matrix"},
                      {mjWARN_CONTACTFULL, "a full contact list (raise the model's nconmax)"},
                      {mjWARN_CNSTRFULL, "a full constraint list (raise the model's njmax)"}};

}  // namespace

MujocoModel::MujocoModel(const EngineSpec& spec, const std::vector<std::string>& joints) {
  install_handlers();
  char error[1000] = "";
  try {
    m_ = mj_loadXML(spec.model_path.c_str(), nullptr, error, sizeof error);
  } catch (const std::exception& e) {
    throw SceneError(spec.model_path + ": " + e.what());
  }
  if (!m_) throw SceneError(spec.model_path + ": MuJoCo cannot load it: " + error);
  try {
    configure(spec, joints);
  } catch (const std::exception& e) {  // a model that does not fit, or an mju_error while setting up
    release();
    if (dynamic_cast<const SceneError*>(&e) != nullptr) throw;
    throw SceneError(spec.model_path + ": " + e.what());
  }
}

void MujocoModel::release() noexcept {
  if (d_) mj_deleteData(d_);
  if (m_) mj_deleteModel(m_);
  d_ = nullptr;
  m_ = nullptr;
}

void MujocoModel::configure(const EngineSpec& spec, const std::vector<std::string>& joints) {
  auto fail = [&](const std::string& why) { throw SceneError(spec.model_path + ": " + why); };
  // The coordinates: one hinge or slide joint each, covering every degree of freedom once.
  for (const std::string& name : joints) {
    const int j = mj_name2id(m_, mjOBJ_JOINT, name.c_str());
    if (j < 0) fail("has no joint named '" + name + "' (the scene's plant.coordinates are the model's joints)");
    if (m_->jnt_type[j] != mjJNT_HINGE && m_->jnt_type[j] != mjJNT_SLIDE)
      fail("joint '" + name + "' is not a hinge or a slide (a coordinate is one scalar joint)");
    if (std::find(dof_index_.begin(), dof_index_.end(), m_->jnt_dofadr[j]) != dof_index_.end())
      fail("joint '" + name + "' is named twice");
    if (m_->qpos0[m_->jnt_qposadr[j]] != 0)
      fail("joint '" + name + "' has a nonzero reference position (ref): its angle would not be the controller's");
    qpos_index_.push_back(m_->jnt_qposadr[j]);
    dof_index_.push_back(m_->jnt_dofadr[j]);
  }
  if (m_->nv != static_cast<int>(joints.size()))
    fail("has " + std::to_string(m_->nv) + " degrees of freedom; the scene names " + std::to_string(joints.size()) +
         " joints (name every joint, in the controller's order)");

  // Only the listed effects: the disable flags for whole features, the model's own fields where
  // one flag covers two effects (PASSIVE is springs and dampers together) or none exists.
  const int physical = mjDSBL_CONSTRAINT | mjDSBL_EQUALITY | mjDSBL_FRICTIONLOSS | mjDSBL_LIMIT | mjDSBL_CONTACT |
                       mjDSBL_PASSIVE | mjDSBL_GRAVITY | mjDSBL_ACTUATION | mjDSBL_CLAMPCTRL;
  configure_actuators(spec);
  // The command is a generalized force unless the scene names actuators: then they act (and only
  // they), under the command's control, unclamped (the law's u is held as it is).
  int off = actuator_ids_.empty() ? mjDSBL_ACTUATION : mjDSBL_CLAMPCTRL;
  if (!listed(spec, "gravity")) off |= mjDSBL_GRAVITY;
  if (!listed(spec, "contact")) off |= mjDSBL_CONTACT;
  if (!listed(spec, "frictionloss")) off |= mjDSBL_FRICTIONLOSS;
  if (!listed(spec, "limits")) off |= mjDSBL_LIMIT;
  if (!listed(spec, "equality")) off |= mjDSBL_EQUALITY;
  if (!listed(spec, "contact") && !listed(spec, "frictionloss") && !listed(spec, "limits") && !listed(spec, "equality"))
    off |= mjDSBL_CONSTRAINT;
  if (!listed(spec, "damping") && !listed(spec, "springs")) off |= mjDSBL_PASSIVE;
  m_->opt.disableflags = (m_->opt.disableflags & ~physical) | off;
  if (!listed(spec, "damping")) {
    std::fill_n(m_->dof_damping, m_->nv, 0.0);
    std::fill_n(m_->tendon_damping, m_->ntendon, 0.0);
  }
  if (!listed(spec, "springs")) {
    std::fill_n(m_->jnt_stiffness, m_->njnt, 0.0);
    std::fill_n(m_->tendon_stiffness, m_->ntendon, 0.0);
  }
  if (!listed(spec, "armature")) std::fill_n(m_->dof_armature, m_->nv, 0.0);
  // Fluid forces (passive, from the medium) are not offered: always off.
  m_->opt.density = 0;
  m_->opt.viscosity = 0;
  std::fill_n(m_->opt.wind, 3, 0.0);

  m_->opt.timestep = spec.timestep;
  integrator_ = spec.integrator;
  switch (spec.integrator) {
    case EngineIntegrator::kEuler: m_->opt.integrator = mjINT_EULER; break;
    case EngineIntegrator::kRk4: m_->opt.integrator = mjINT_RK4; break;
    case EngineIntegrator::kImplicit: m_->opt.integrator = mjINT_IMPLICIT; break;
  }
  d_ = mj_makeData(m_);
  if (!d_) fail("MuJoCo cannot allocate its data");
  // The constants the compiler derived from the fields zeroed above (the armature enters
  // dof_invweight0 and meaninertia, which scale constraint impedance and solver tolerance).
  mj_setConst(m_, d_);
  std::vector<double> zero(joints.size(), 0.0);
  for (std::size_t i = 0; i < joints.size(); ++i) zero[i] = d_->qpos[qpos_index_[i]];
  set_state(zero.data(), std::vector<double>(joints.size(), 0.0).data());
}

// plant.actuators: each a motor (force = gain * ctrl along its transmission, no activation
// dynamics, no bias), so that the generalized force is B u with B = actuator_moment^T * gain; the
// model's every actuator is named, in the order of the controller's u.
void MujocoModel::configure_actuators(const EngineSpec& spec) {
  auto fail = [&](const std::string& why) { throw SceneError(spec.model_path + ": " + why); };
  if (spec.actuators.empty()) return;
  for (const std::string& name : spec.actuators) {
    const int a = mj_name2id(m_, mjOBJ_ACTUATOR, name.c_str());
    if (a < 0) fail("has no actuator named '" + name + "' (the scene's plant.actuators are the model's actuators)");
    if (m_->actuator_dyntype[a] != mjDYN_NONE || m_->actuator_gaintype[a] != mjGAIN_FIXED ||
        m_->actuator_biastype[a] != mjBIAS_NONE)
      fail("actuator '" + name + "' is not a motor (a <motor>: no activation dynamics, a fixed gain, no bias), so "
           "its force is not B u");
    if (m_->actuator_forcelimited[a])
      fail("actuator '" + name + "' is force limited (forcerange): MuJoCo would saturate it, and its force would "
           "not be B u (limit the controller's u instead: tracking.force_limit)");
    actuator_ids_.push_back(a);
  }
  if (m_->nu != static_cast<int>(spec.actuators.size()))
    fail("has " + std::to_string(m_->nu) + " actuators; the scene names " + std::to_string(spec.actuators.size()) +
         " (name every actuator, in the order of the controller's u)");
}

MujocoModel::~MujocoModel() { release(); }

// MuJoCo 2.x keeps actuator_moment dense, nu x nv (3.x made it sparse).
static_assert(mjVERSION_HEADER < 300, "actuation_matrix reads actuator_moment as MuJoCo 2.x stores it");

void MujocoModel::actuation_matrix(double* B) const {
  const int nv = m_->nv;
  const int k = actuators();
  for (int j = 0; j < k; ++j) {
    const int a = actuator_ids_[static_cast<std::size_t>(j)];
    for (int i = 0; i < dof(); ++i)
      B[j * dof() + i] = d_->actuator_moment[a * nv + dof_index_[static_cast<std::size_t>(i)]] *
                         m_->actuator_gainprm[a * mjNGAIN];
  }
}

void MujocoModel::set_state(const double* q, const double* qd, double t) {
  for (int i = 0; i < dof(); ++i) {
    d_->qpos[qpos_index_[static_cast<std::size_t>(i)]] = q[i];
    d_->qvel[dof_index_[static_cast<std::size_t>(i)]] = qd[i];
  }
  d_->time = t;
  mj_forward(m_, d_);
}

void MujocoModel::state(double* q, double* qd) const {
  for (int i = 0; i < dof(); ++i) {
    q[i] = d_->qpos[qpos_index_[static_cast<std::size_t>(i)]];
    qd[i] = d_->qvel[dof_index_[static_cast<std::size_t>(i)]];
  }
}

void MujocoModel::mass_matrix(double* A) const {
  const int nv = m_->nv;
  std::vector<double> full(static_cast<std::size_t>(nv * nv));
  mj_fullM(m_, full.data(), d_->qM);
  for (int j = 0; j < dof(); ++j)
    for (int i = 0; i < dof(); ++i)
      A[j * dof() + i] = full[static_cast<std::size_t>(dof_index_[static_cast<std::size_t>(i)] * nv +
                                                       dof_index_[static_cast<std::size_t>(j)])];
}

void MujocoModel::bias_minus_passive(double* r) const {
  for (int i = 0; i < dof(); ++i) {
    const int k = dof_index_[static_cast<std::size_t>(i)];
    r[i] = d_->qfrc_bias[k] - d_->qfrc_passive[k];
  }
}

std::string MujocoModel::step(const double* u) {
  if (actuator_ids_.empty()) {
    for (int i = 0; i < dof(); ++i) d_->qfrc_applied[dof_index_[static_cast<std::size_t>(i)]] = u[i];
  } else {
    // The actuators' control acts; the command's force (the controller's B u) is what it gives.
    for (int j = 0; j < actuators(); ++j) d_->ctrl[actuator_ids_[static_cast<std::size_t>(j)]] = u[dof() + j];
  }
  int before[std::size(kResetWarnings)];
  for (std::size_t k = 0; k < std::size(kResetWarnings); ++k) before[k] = d_->warning[kResetWarnings[k].index].number;
  if (!failure_.empty()) return failure_;
  const double t = d_->time;
  const auto stack = d_->pstack;
  try {
    mj_step(m_, d_);
  } catch (const std::exception& e) {
    // The step stopped half-way: its stack mark is restored, and the model steps no more.
    d_->pstack = stack;
    failure_ = std::string(e.what()) + " (in the step from t = " + g(t) + " s)";
    return failure_;
  }
  for (std::size_t k = 0; k < std::size(kResetWarnings); ++k)
    if (d_->warning[kResetWarnings[k].index].number != before[k])
      return "MuJoCo met " + std::string(kResetWarnings[k].what) + " in the step from t = " + g(t) +
             " s (it resets the state or drops constraints and goes on; the run cannot)";
  for (int i = 0; i < m_->nq; ++i)
    if (!std::isfinite(d_->qpos[i])) return "MuJoCo's qpos left the finite range at t = " + g(d_->time) + " s";
  for (int i = 0; i < m_->nv; ++i)
    if (!std::isfinite(d_->qvel[i])) return "MuJoCo's qvel left the finite range at t = " + g(d_->time) + " s";
  return {};
}

std::string MujocoModel::description() const {
  return "mujoco " + mujoco_version() + ", " + to_string(integrator_) + ", timestep " + g(m_->opt.timestep) + " s";
}

std::string mujoco_version() {
  const int v = mj_version();
  return std::to_string(v / 100) + "." + std::to_string(v / 10 % 10) + "." + std::to_string(v % 10);
}

namespace {

class MujocoEngine final : public PlantEngine {
 public:
  explicit MujocoEngine(const Scene& s) : model_(s.engine, s.coordinates) { model_.set_state(s.q0.data(), s.qd0.data(), 0); }
  std::string step(const double* u) override { return model_.step(u); }
  void state(double* q, double* qd) const override { model_.state(q, qd); }
  std::string description() const override { return model_.description(); }

 private:
  MujocoModel model_;
};

}  // namespace

EngineFactory mujoco_engine() {
  return {"mujoco", [](const Scene& s) -> std::unique_ptr<PlantEngine> { return std::make_unique<MujocoEngine>(s); }};
}

}  // namespace gausstrack::plant_sim
