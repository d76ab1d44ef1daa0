#include "gausstrack/plant_sim/scene.hpp"

#include "gausstrack/plant_sim/models.hpp"

#include <yaml-cpp/yaml.h>

#include "gausstrack/tracking/yaml_reader.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <memory>
#include <set>
#include <sstream>

namespace gausstrack::plant_sim {

const char* to_string(EffectKind kind) noexcept {
  switch (kind) {
    case EffectKind::kGravity: return "gravity";
    case EffectKind::kSpring: return "spring";
    case EffectKind::kCubicSpring: return "cubic_spring";
    case EffectKind::kDamper: return "damper";
    case EffectKind::kDisturbance: return "disturbance";
    case EffectKind::kActuatorSaturation: return "actuator_saturation";
    case EffectKind::kSensorNoise: return "sensor_noise";
    case EffectKind::kCount: break;
  }
  return "unknown";
}

const char* to_string(ConstraintKind kind) noexcept {
  switch (kind) {
    case ConstraintKind::kPendulumLength: return "pendulum_length";
    case ConstraintKind::kNonholonomic: return "nonholonomic";
  }
  return "unknown";
}

const char* to_string(EngineIntegrator integrator) noexcept {
  switch (integrator) {
    case EngineIntegrator::kEuler: return "euler";
    case EngineIntegrator::kRk4: return "rk4";
    case EngineIntegrator::kImplicit: return "implicit";
  }
  return "unknown";
}

const char* to_string(ControlMode mode) noexcept {
  switch (mode) {
    case ControlMode::kContinuous: return "continuous";
    case ControlMode::kSampled: return "sampled";
  }
  return "unknown";
}

const char* to_string(Method method) noexcept {
  switch (method) {
    case Method::kRk4: return "rk4";
    case Method::kDopri5: return "dopri5";
    case Method::kRkf78: return "rkf78";
    case Method::kBulirschStoer: return "bulirsch_stoer";
  }
  return "unknown";
}

namespace {

using tracking::check_parameter_names;
using tracking::read_parameters;
using tracking::read_tracking;
using tracking::Reader;

int coordinate_index(const Reader& r, const std::vector<std::string>& names, bool allow_ground) {
  if (!r.node().IsScalar()) r.fail("must name a coordinate");
  const std::string name = r.node().Scalar();
  if (allow_ground && name == "ground") return kGround;
  const auto it = std::find(names.begin(), names.end(), name);
  if (it == names.end()) {
    std::string known;
    for (const auto& n : names) known += (known.empty() ? "" : ", ") + n;
    r.fail("unknown coordinate '" + name + "' (coordinates: " + known + (allow_ground ? ", ground" : "") + ")");
  }
  return static_cast<int>(it - names.begin());
}

EffectSpec read_effect(const Reader& r, const std::vector<std::string>& names) {
  EffectSpec e;
  e.kind = r.choice("type", kEffectKinds, "effect");
  auto pair = [&](const char* key) {
    const auto ends = r.items(key);
    if (ends.size() != 2) r.child(key).fail("must list two ends: [coordinate, coordinate or ground]");
    e.a = coordinate_index(ends[0], names, false);
    e.b = coordinate_index(ends[1], names, true);
    if (e.a == e.b) r.child(key).fail("the two ends must differ");
  };
  switch (e.kind) {
    case EffectKind::kGravity:
      r.allow_only({"type", "coordinate", "acceleration"});
      e.a = coordinate_index(r.child("coordinate"), names, false);
      e.value = r.number("acceleration");
      break;
    case EffectKind::kSpring:
    case EffectKind::kCubicSpring:
      r.allow_only({"type", "between", "stiffness"});
      pair("between");
      e.value = r.number("stiffness");
      break;
    case EffectKind::kDamper:
      r.allow_only({"type", "between", "coefficient"});
      pair("between");
      e.value = r.non_negative("coefficient", 0);
      break;
    case EffectKind::kDisturbance:
      r.allow_only({"type", "coordinate", "amplitude", "frequency", "phase"});
      e.a = coordinate_index(r.child("coordinate"), names, false);
      e.value = r.number("amplitude");
      e.frequency = r.number("frequency", 0);
      e.phase = r.number("phase", 0);
      break;
    case EffectKind::kActuatorSaturation:
      r.allow_only({"type", "limit"});
      e.value = r.positive("limit");
      break;
    case EffectKind::kSensorNoise:
      r.allow_only({"type", "std", "seed"});
      e.value = r.non_negative("std", 0);
      e.seed = static_cast<std::uint64_t>(r.non_negative("seed", 1));
      break;
    case EffectKind::kCount: break;
  }
  return e;
}

ConstraintSpec read_constraint(const Reader& r, const std::vector<std::string>& names) {
  ConstraintSpec c;
  c.kind = r.choice("type", kConstraintKinds, "constraint");
  auto coordinate = [&](const char* key) { return coordinate_index(r.child(key), names, false); };
  switch (c.kind) {
    case ConstraintKind::kPendulumLength:
      r.allow_only({"type", "x", "y", "length", "mu"});
      c.coordinates = {coordinate("x"), coordinate("y")};
      c.length = r.positive("length");
      c.mu = r.number("mu", 0);
      break;
    case ConstraintKind::kNonholonomic:
      r.allow_only({"type", "x", "y", "z"});
      c.coordinates = {coordinate("x"), coordinate("y"), coordinate("z")};
      break;
  }
  return c;
}

// plant.engine (other than gausstrack): which engine, its model file, its step and integrator, and
// the effects it may simulate. The coordinates are the model's joints, by name.
void read_engine(const Reader& plant, Scene& s) {
  EngineSpec& e = s.engine;
  e.name = plant.text("engine");
  e.where = plant.child("engine").where();
  if (e.name != "mujoco") plant.child("engine").fail("unknown engine '" + e.name + "' (known: gausstrack, mujoco)");
  const Reader model = plant.child("model");
  const std::string file = plant.text("model");
  if (file.empty()) model.fail("must name the engine's model file (MJCF)");
  // Relative to the directory of the scene file; given by --set, relative to the working directory.
  std::filesystem::path path(file);
  if (path.is_relative() && !plant.overridden("model")) {
    path = std::filesystem::path(plant.file()).parent_path() / path;
  }
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) model.fail("cannot open the model file " + path.string());
  e.model_path = path.string();
  e.timestep = plant.positive("timestep");
  e.integrator = plant.choice("integrator", kEngineIntegrators, "integrator", EngineIntegrator::kRk4);
  if (plant.has("effects"))
    for (const Reader& r : plant.items("effects")) {
      if (!r.node().IsScalar()) r.fail("must be an effect's name");
      const std::string name = r.node().Scalar();
      if (std::none_of(std::begin(kMujocoEffects), std::end(kMujocoEffects), [&](const char* k) { return name == k; })) {
        std::string known;
        for (const char* k : kMujocoEffects) known += std::string(known.empty() ? "" : ", ") + k;
        r.fail("unknown effect '" + name + "' (known: " + known + ")");
      }
      if (std::find(e.effects.begin(), e.effects.end(), name) != e.effects.end()) r.fail("listed twice");
      e.effects.push_back(name);
    }
  if (plant.has("actuators"))
    for (const Reader& r : plant.items("actuators")) {
      if (!r.node().IsScalar() || r.node().Scalar().empty()) r.fail("must be the name of one of the model's actuators");
      const std::string name = r.node().Scalar();
      if (std::find(e.actuators.begin(), e.actuators.end(), name) != e.actuators.end()) r.fail("listed twice");
      e.actuators.push_back(name);
    }
  // The plant holds the force and the control in one command of the messages' size.
  if (s.dof() + static_cast<int>(e.actuators.size()) > kMaxCoordinates)
    plant.child("actuators").fail("names " + std::to_string(e.actuators.size()) + " actuators for " +
                                  std::to_string(s.dof()) + " coordinates: the held command (a force per coordinate "
                                  "and a control per actuator) has at most " + std::to_string(kMaxCoordinates) +
                                  " entries");
}

bool names_engine(const Reader& plant) {
  if (!plant.has("engine")) return false;
  const Reader engine = plant.child("engine");  // node() refers into the Reader: keep it alive
  const YAML::Node& e = engine.node();
  return !(e.IsScalar() && e.Scalar() == "gausstrack");
}

void read_coordinates(const Reader& plant, Scene& s) {
  for (const Reader& c : plant.items("coordinates")) {
    if (!c.node().IsScalar() || c.node().Scalar().empty()) c.fail("must be a coordinate name");
    const std::string n = c.node().Scalar();
    if (n == "ground") c.fail("'ground' is reserved");
    if (std::find(s.coordinates.begin(), s.coordinates.end(), n) != s.coordinates.end())
      c.fail("duplicate coordinate '" + n + "'");
    s.coordinates.push_back(n);
  }
  const int n = s.dof();
  if (n < 1 || n > kMaxCoordinates)
    plant.child("coordinates").fail("a plant has 1 to " + std::to_string(kMaxCoordinates) + " coordinates (got " +
                                    std::to_string(n) + ")");
}

// The plant's own dynamics: a model's (A, f, Q; the effects listed add to them), or point masses.
void read_dynamics(const Reader& plant, Scene& s) {
  const int n = s.dof();
  if (plant.has("model")) {
    if (plant.has("masses")) plant.child("masses").fail("a plant is either point masses or a model, not both");
    s.plant_model = plant.text("model");
    s.plant_model_where = plant.child("model").where();
    if (plant.has("parameters")) s.plant_parameters = read_parameters(plant.child("parameters"));
    if (const ModelFactory* f = find_builtin_model(s.plant_model)) {
      if (f->dof != n)
        plant.child("coordinates").fail("model '" + s.plant_model + "' has " + std::to_string(f->dof) +
                                        " coordinates, the plant lists " + std::to_string(n));
      check_parameter_names(plant, "parameters", f->name, f->parameter_names);
    }
    return;
  }
  if (plant.has("parameters")) plant.child("parameters").fail("parameters belong to a plant model (plant.model)");
  const auto masses = plant.items("masses");
  if (static_cast<int>(masses.size()) != n)
    plant.child("masses").fail("needs one mass per coordinate (" + std::to_string(n) + "), got " +
                               std::to_string(masses.size()));
  for (const Reader& m : masses) {
    const double v = m.as_number();
    if (!(v > 0)) m.fail("mass must be > 0 (got " + Reader::format(v) + ")");
    s.masses.push_back(v);
  }
}

void read_initial(const Reader& plant, Scene& s) {
  const int n = s.dof();
  const Reader initial = plant.child("initial");
  initial.require_map();
  for (const auto& kv : initial.node()) {
    const std::string k = initial.key(kv.first);
    bool ok = false;
    for (int i = 1; i <= n; ++i) ok = ok || k == "q" + std::to_string(i) || k == "qd" + std::to_string(i);
    if (!ok)
      initial.fail_at(kv.first, initial.key_path(k),
                      "unknown key (expected q1..q" + std::to_string(n) + ", qd1..qd" + std::to_string(n) + ")");
  }
  for (int i = 1; i <= n; ++i) {
    s.q0.push_back(initial.number(("q" + std::to_string(i)).c_str(), 0.0));
    s.qd0.push_back(initial.number(("qd" + std::to_string(i)).c_str(), 0.0));
  }
}

void read_effects_and_constraints(const Reader& plant, Scene& s) {
  if (plant.has("effects"))
    for (const Reader& e : plant.items("effects")) {
      s.effects.push_back(read_effect(e, s.coordinates));
      if (s.effects.back().kind == EffectKind::kGravity && !s.plant_model.empty())
        e.fail("gravity acts on point masses; a plant model's gravity is its own (a model parameter)");
    }
  if (plant.has("constraints"))
    for (const Reader& c : plant.items("constraints")) s.constraints.push_back(read_constraint(c, s.coordinates));
  if (plant.has("projection")) {
    const Reader pr = plant.child("projection");
    if (!pr.node().IsScalar() || !YAML::convert<bool>::decode(pr.node(), s.projection)) pr.fail("must be true or false");
  }
  if (static_cast<int>(s.constraints.size()) >= s.dof())
    plant.child("constraints").fail("needs fewer constraints than coordinates");
}

void read_plant(const Reader& plant, Scene& s) {
  const bool engine = names_engine(plant);
  if (engine)
    plant.allow_only({"engine", "model", "coordinates", "timestep", "integrator", "effects", "actuators", "initial"});
  else
    plant.allow_only(
        {"engine", "coordinates", "masses", "model", "parameters", "initial", "effects", "constraints", "projection"});
  read_coordinates(plant, s);
  if (engine) read_engine(plant, s);
  else read_dynamics(plant, s);
  read_initial(plant, s);
  if (!engine) read_effects_and_constraints(plant, s);
}

void read_control(const Reader& root, Scene& s) {
  if (root.has("control")) {
    const Reader c = root.child("control");
    c.allow_only({"mode", "rate"});
    s.control_mode = c.choice("mode", kControlModes, "control mode", ControlMode::kContinuous);
    if (s.control_mode == ControlMode::kSampled) s.control_rate = c.positive("rate");
  }
  for (std::size_t i = 0; i < s.effects.size(); ++i)
    if (s.effects[i].kind == EffectKind::kSensorNoise && s.control_mode != ControlMode::kSampled)
      root.child("plant").items("effects")[i].fail(
          "sensor_noise needs control.mode: sampled (noise inside an adaptive integrator is not defined)");
}

// The integrator section, or the engine's step standing for it (method rk4, step = timestep).
void read_integrator(const Reader& root, Scene& s) {
  const bool engine = !s.engine.name.empty();
  if (engine) {
    if (root.has("integrator"))
      root.child("integrator").fail("the engine integrates this plant: set plant.timestep and plant.integrator");
    if (s.control_mode != ControlMode::kSampled)
      root.child("plant").child("engine").fail("an engine steps under a held command: needs control.mode: sampled");
    s.method = Method::kRk4;
    s.step = s.engine.timestep;
    s.min_step = 1e-12 * s.duration;
    return;
  }
  const Reader integ = root.child("integrator");
  integ.allow_only({"method", "tolerance", "step", "min_step", "max_steps"});
  s.method = integ.choice("method", kMethods, "integrator");
  if (s.method == Method::kRk4) s.step = integ.positive("step");
  else s.tolerance = integ.positive("tolerance");
  s.min_step = integ.positive("min_step", 1e-12 * s.duration);
  s.max_steps = integ.positive("max_steps", s.max_steps);
}

// Duration and output grid, and the periods that must fit it: samples in memory, time still
// advancing in double precision, output and control periods whole numbers of fixed steps.
void read_time_grid(const Reader& root, Scene& s) {
  s.duration = root.positive("duration");
  s.output_period = root.positive("output_period");
  if (s.output_period > s.duration) root.child("output_period").fail("must not exceed duration");
  constexpr double kMaxSamples = 1e7;
  if (s.duration / s.output_period > kMaxSamples)
    root.child("output_period")
        .fail("gives " + Reader::format(s.duration / s.output_period) + " samples over the duration (at most " +
              Reader::format(kMaxSamples) + "): raise output_period or shorten duration");
  if (s.duration * std::numeric_limits<double>::epsilon() * 1e3 > s.output_period)
    root.child("duration").fail("is too long for its output grid to be resolved in double precision");
}

void check_periods(const Reader& root, const Scene& s) {
  const bool engine = !s.engine.name.empty();
  if (s.method == Method::kRk4 && s.duration / s.step > s.max_steps)
    (engine ? root.child("plant").child("timestep") : root.child("integrator").child("step"))
        .fail("gives " + Reader::format(s.duration / s.step) + " steps, above integrator.max_steps (" +
              Reader::format(s.max_steps) + ")");
  if (s.control_mode == ControlMode::kSampled && s.duration * s.control_rate > s.max_steps)
    root.child("control").fail("gives " + Reader::format(s.duration * s.control_rate) +
                               " control periods, above integrator.max_steps (" + Reader::format(s.max_steps) + ")");
  if (s.method != Method::kRk4) return;
  const std::string steps = std::string(engine ? "engine" : "rk4") + " steps (step " +
                            Reader::format(s.step) + ")";
  auto whole = [](double ratio) { return std::abs(ratio - std::round(ratio)) <= 1e-9 * ratio; };
  if (!whole(s.output_period / s.step)) root.child("output_period").fail("must be a whole number of " + steps);
  if (s.control_mode == ControlMode::kSampled && !whole(1.0 / (s.control_rate * s.step)))
    root.child("control").fail("the control period must be a whole number of " + steps);
}

Scene read_scene(const Reader& root) {
  Scene s;
  root.allow_only({"name", "plant", "tracking", "control", "integrator", "duration", "output_period"});
  s.name = root.text("name", "");
  read_plant(root.child("plant"), s);
  if (root.has("tracking")) {
    s.tracking = read_tracking(root.child("tracking"));
    if (const ModelFactory* f = find_builtin_model(s.tracking.model))
      if (f->dof != s.dof())
        root.child("tracking").child("model").fail("model '" + s.tracking.model + "' has " + std::to_string(f->dof) +
                                                   " coordinates, the plant has " + std::to_string(s.dof()));
    if (s.actuators() > 0)
      if (const ModelFactory* f = find_builtin_model(s.tracking.model); f != nullptr && f->actuators != s.actuators())
        root.child("plant").child("actuators").fail(
            "names " + std::to_string(s.actuators()) + " actuator(s); model '" + s.tracking.model + "' has " +
            (f->actuators == 0 ? std::string("no actuation matrix B (it commands a generalized force)")
                               : std::to_string(f->actuators) + " actuators") +
            ": the controller's u drives them one to one");
    if (!s.constraints.empty())
      root.child("tracking").fail("tracking control of a plant with physical constraints is not supported");
  }
  read_control(root, s);
  read_time_grid(root, s);
  read_integrator(root, s);
  check_periods(root, s);
  return s;
}

}  // namespace

Scene parse_scene(const std::string& yaml_text, const std::string& name, const std::vector<std::string>& overrides) {
  Scene s = tracking::reading(name, [&] { return read_scene(tracking::parse_root(yaml_text, name, overrides)); });
  s.file = name;
  return s;
}

Scene load_scene(const std::string& path, const std::vector<std::string>& overrides) {
  return parse_scene(tracking::read_file(path, "scene file"), path, overrides);
}

}  // namespace gausstrack::plant_sim
