#include "gausstrack/plant_sim/scene.hpp"

#include "gausstrack/plant_sim/models.hpp"

#include <yaml-cpp/yaml.h>

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

namespace {

// Walks a YAML mapping with its dotted path, so that every error names file, line and key.
class Reader {
 public:
  Reader(YAML::Node node, std::string path, std::shared_ptr<const std::string> file,
         std::shared_ptr<const std::set<std::string>> overridden)
      : node_(std::move(node)), path_(std::move(path)), file_(std::move(file)),
        overridden_(std::move(overridden)) {}

  [[noreturn]] void fail(const std::string& message) const { fail_at(node_, path_, message); }

  [[noreturn]] void fail_at(const YAML::Node& where, const std::string& path,
                            const std::string& message) const {
    std::ostringstream out;
    out << *file_;
    if (overridden_->count(path)) {
      out << ": --set " << path;
    } else {
      out << ":" << (where.Mark().line + 1);
      if (!path.empty()) out << ": " << path;
    }
    out << ": " << message;
    throw SceneError(out.str());
  }

  /// "file:line: key" of this node, as error messages start.
  std::string where() const {
    std::ostringstream out;
    out << *file_;
    if (overridden_->count(path_)) out << ": --set " << path_;
    else out << ":" << (node_.Mark().line + 1) << ": " << path_;
    return out.str();
  }

  const std::string& file() const { return *file_; }
  /// True when `key` of this node was given by an override (--set) rather than by the file.
  bool overridden(const char* key) const { return overridden_->count(key_path(key)) > 0; }

  std::string key_path(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }

  /// The text of a mapping key of this node; a key that is a list or a mapping is an error.
  std::string key(const YAML::Node& k) const {
    if (!k.IsScalar()) fail_at(k, path_, "a key must be a plain name, not a list or a mapping");
    return k.Scalar();
  }

  void require_map() const {
    if (!node_.IsMap()) fail("must be a mapping of keys to values");
  }

  // Unknown keys are errors: a misspelt key must not be silently ignored.
  void allow_only(std::initializer_list<const char*> keys) const {
    require_map();
    for (const auto& kv : node_) {
      const std::string k = key(kv.first);
      if (std::none_of(keys.begin(), keys.end(), [&](const char* a) { return k == a; })) {
        std::string allowed;
        for (const char* a : keys) allowed += std::string(allowed.empty() ? "" : ", ") + a;
        fail_at(kv.first, key_path(k), "unknown key (allowed here: " + allowed + ")");
      }
    }
  }

  bool has(const char* key) const { return node_.IsMap() && node_[key].IsDefined() && !node_[key].IsNull(); }

  Reader child(const char* key) const {
    if (!has(key)) fail("missing required key '" + std::string(key) + "'");
    return Reader(node_[key], key_path(key), file_, overridden_);
  }

  double number(const char* key) const {
    const Reader c = child(key);
    return c.as_number();
  }
  double number(const char* key, double fallback) const { return has(key) ? number(key) : fallback; }

  double positive(const char* key) const {
    const double v = number(key);
    if (!(v > 0)) child(key).fail("must be > 0 (got " + format(v) + ")");
    return v;
  }
  double positive(const char* key, double fallback) const { return has(key) ? positive(key) : fallback; }
  double non_negative(const char* key, double fallback) const {
    if (!has(key)) return fallback;
    const double v = number(key);
    if (!(v >= 0)) child(key).fail("must be >= 0 (got " + format(v) + ")");
    return v;
  }

  std::string text(const char* key) const {
    const Reader c = child(key);
    if (!c.node_.IsScalar()) c.fail("must be a string");
    return c.node_.Scalar();
  }
  std::string text(const char* key, const std::string& fallback) const { return has(key) ? text(key) : fallback; }

  double as_number() const {
    if (!node_.IsScalar()) fail("must be a number");
    double v = 0;
    if (!YAML::convert<double>::decode(node_, v) || !std::isfinite(v))
      fail("must be a finite number (got '" + node_.Scalar() + "')");
    return v;
  }

  std::vector<Reader> items(const char* key) const {
    const Reader c = child(key);
    if (!c.node_.IsSequence()) c.fail("must be a list");
    std::vector<Reader> out;
    for (std::size_t i = 0; i < c.node_.size(); ++i)
      out.emplace_back(c.node_[i], c.path_ + "[" + std::to_string(i) + "]", file_, overridden_);
    return out;
  }

  const YAML::Node& node() const { return node_; }
  const std::string& path() const { return path_; }

  static std::string format(double v) {
    std::ostringstream o;
    o << v;
    return o.str();
  }

 private:
  YAML::Node node_;
  std::string path_;
  std::shared_ptr<const std::string> file_;
  std::shared_ptr<const std::set<std::string>> overridden_;
};

// "a.b.2.c=value": replaces (or adds) the value at that dotted path, parsed as YAML.
void apply_override(YAML::Node root, const std::string& assignment, const std::string& file,
                    std::set<std::string>& overridden) {
  const auto eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0)
    throw SceneError(file + ": --set " + assignment + ": expected key=value");
  const std::string path = assignment.substr(0, eq);
  YAML::Node value;
  try {
    value = YAML::Load(assignment.substr(eq + 1));
  } catch (const YAML::Exception& e) {
    throw SceneError(file + ": --set " + path + ": value is not valid YAML: " + e.msg);
  }
  std::vector<std::string> keys;
  std::stringstream ss(path);
  for (std::string k; std::getline(ss, k, '.');) keys.push_back(k);
  YAML::Node cur = root;
  std::string shown;
  for (std::size_t i = 0; i < keys.size(); ++i) {
    const std::string& k = keys[i];
    const bool last = i + 1 == keys.size();
    if (cur.IsSequence()) {
      std::size_t idx = 0;
      try {
        idx = std::stoul(k);
      } catch (...) {
        throw SceneError(file + ": --set " + path + ": '" + k + "' must index a list");
      }
      // An index one past the end appends (e.g. adds an effect to the list).
      if (idx > cur.size() || (idx == cur.size() && !last))
        throw SceneError(file + ": --set " + path + ": index " + k + " out of range");
      if (last && idx == cur.size()) {
        cur.push_back(value);
      } else if (last) {
        cur[idx] = value;
      } else {
        YAML::Node next = cur[idx];
        cur.reset(next);
      }
      shown += (shown.empty() ? "" : ".") + k;
      continue;
    }
    if (!cur.IsMap() && cur.IsDefined() && !cur.IsNull())
      throw SceneError(file + ": --set " + path + ": '" + shown + "' is not a mapping");
    if (last) {
      cur[k] = value;
    } else {
      YAML::Node next = cur[k];
      cur.reset(next);
    }
    shown += (shown.empty() ? "" : ".") + k;
  }
  // Record the path as the readers spell it (list indices in brackets).
  std::string spelled;
  for (const std::string& k : keys) {
    const bool index = !k.empty() && std::all_of(k.begin(), k.end(), ::isdigit);
    spelled += index ? "[" + k + "]" : (spelled.empty() ? "" : ".") + k;
  }
  overridden.insert(spelled);
}

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
  const std::string type = r.text("type");
  auto pair = [&](const char* key) {
    const auto ends = r.items(key);
    if (ends.size() != 2) r.child(key).fail("must list two ends: [coordinate, coordinate or ground]");
    e.a = coordinate_index(ends[0], names, false);
    e.b = coordinate_index(ends[1], names, true);
    if (e.a == e.b) r.child(key).fail("the two ends must differ");
  };
  if (type == "gravity") {
    r.allow_only({"type", "coordinate", "acceleration"});
    e.kind = EffectKind::kGravity;
    e.a = coordinate_index(r.child("coordinate"), names, false);
    e.value = r.number("acceleration");
  } else if (type == "spring" || type == "cubic_spring") {
    r.allow_only({"type", "between", "stiffness"});
    e.kind = type == "spring" ? EffectKind::kSpring : EffectKind::kCubicSpring;
    pair("between");
    e.value = r.number("stiffness");
  } else if (type == "damper") {
    r.allow_only({"type", "between", "coefficient"});
    e.kind = EffectKind::kDamper;
    pair("between");
    e.value = r.non_negative("coefficient", 0);
  } else if (type == "disturbance") {
    r.allow_only({"type", "coordinate", "amplitude", "frequency", "phase"});
    e.kind = EffectKind::kDisturbance;
    e.a = coordinate_index(r.child("coordinate"), names, false);
    e.value = r.number("amplitude");
    e.frequency = r.number("frequency", 0);
    e.phase = r.number("phase", 0);
  } else if (type == "actuator_saturation") {
    r.allow_only({"type", "limit"});
    e.kind = EffectKind::kActuatorSaturation;
    e.value = r.positive("limit");
  } else if (type == "sensor_noise") {
    r.allow_only({"type", "std", "seed"});
    e.kind = EffectKind::kSensorNoise;
    e.value = r.non_negative("std", 0);
    e.seed = static_cast<std::uint64_t>(r.non_negative("seed", 1));
  } else {
    r.child("type").fail("unknown effect '" + type +
                         "' (known: gravity, spring, cubic_spring, damper, disturbance, "
                         "actuator_saturation, sensor_noise)");
  }
  return e;
}

ConstraintSpec read_constraint(const Reader& r, const std::vector<std::string>& names) {
  ConstraintSpec c;
  const std::string type = r.text("type");
  if (type == "pendulum_length") {
    r.allow_only({"type", "x", "y", "length", "mu"});
    c.kind = ConstraintKind::kPendulumLength;
    c.coordinates = {coordinate_index(r.child("x"), names, false), coordinate_index(r.child("y"), names, false)};
    c.length = r.positive("length");
    c.mu = r.number("mu", 0);
  } else if (type == "nonholonomic") {
    r.allow_only({"type", "x", "y", "z"});
    c.kind = ConstraintKind::kNonholonomic;
    c.coordinates = {coordinate_index(r.child("x"), names, false), coordinate_index(r.child("y"), names, false),
                     coordinate_index(r.child("z"), names, false)};
  } else {
    r.child("type").fail("unknown constraint '" + type + "' (known: pendulum_length, nonholonomic)");
  }
  return c;
}

std::vector<ModelParameter> read_parameters(const Reader& r) {
  r.require_map();
  std::vector<ModelParameter> out;
  for (const auto& kv : r.node()) {
    const std::string k = r.key(kv.first);
    const Reader v = r.child(k.c_str());
    out.push_back({k, v.as_number(), v.where()});
  }
  return out;
}

// Parameter names of a compiled-in model are checked with the scene (file, line, key).
void check_parameter_names(const Reader& parent, const char* key, const ModelFactory& f) {
  if (!parent.has(key)) return;
  const Reader r = parent.child(key);
  r.require_map();
  for (const auto& kv : r.node()) {
    const std::string k = r.key(kv.first);
    if (std::find(f.parameter_names.begin(), f.parameter_names.end(), k) == f.parameter_names.end()) {
      std::string known;
      for (const auto& p : f.parameter_names) known += (known.empty() ? "" : ", ") + p;
      r.fail_at(kv.first, r.key_path(k), "model '" + f.name + "' has no parameter '" + k + "' (known: " + known + ")");
    }
  }
}

TrackingSpec read_tracking(const Reader& t) {
  t.allow_only({"model", "parameters", "trajectory", "stabilization", "strategy", "force_limit", "min_singular_value"});
  TrackingSpec tr;
  tr.enabled = true;
  tr.model = t.text("model");
  tr.where = t.child("model").where();
  // The trajectory's parameters are the model's too; they are kept apart in scenes for reading.
  for (const char* section : {"parameters", "trajectory"})
    if (t.has(section)) {
      const auto p = read_parameters(t.child(section));
      tr.parameters.insert(tr.parameters.end(), p.begin(), p.end());
    }
  if (const ModelFactory* f = find_builtin_model(tr.model)) {
    check_parameter_names(t, "parameters", *f);
    check_parameter_names(t, "trajectory", *f);
  } else if (tr.model.empty()) {
    t.child("model").fail("must name a model");
  }
  if (t.has("stabilization")) {
    const Reader st = t.child("stabilization");
    st.allow_only({"zeta", "omega"});
    tr.zeta = st.non_negative("zeta", 1.0);
    tr.stabilization_omega = st.non_negative("omega", 0.0);
  }
  tr.force_limit = t.positive("force_limit", tr.force_limit);
  tr.min_singular_value = t.non_negative("min_singular_value", tr.min_singular_value);
  tr.strategy = t.text("strategy", "cholesky");
  if (tr.strategy != "cholesky" && tr.strategy != "svd" && tr.strategy != "cod" && tr.strategy != "damped")
    t.child("strategy").fail("unknown strategy '" + tr.strategy + "' (known: cholesky, svd, cod, damped)");
  return tr;
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
  e.integrator = plant.text("integrator", "rk4");
  if (e.integrator != "euler" && e.integrator != "rk4" && e.integrator != "implicit")
    plant.child("integrator").fail("unknown integrator '" + e.integrator + "' (known: euler, rk4, implicit)");
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
}

Scene read_scene(const Reader& root) {
  Scene s;
  root.allow_only({"name", "plant", "tracking", "control", "integrator", "duration", "output_period"});
  s.name = root.text("name", "");

  const Reader plant = root.child("plant");
  const bool engine = plant.has("engine") && !(plant.child("engine").node().IsScalar() &&
                                                plant.child("engine").node().Scalar() == "gausstrack");
  if (engine)
    plant.allow_only({"engine", "model", "coordinates", "timestep", "integrator", "effects", "initial"});
  else
    plant.allow_only({"engine", "coordinates", "masses", "model", "parameters", "initial", "effects", "constraints", "projection"});
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
    plant.child("coordinates").fail("a plant has 1 to " + std::to_string(kMaxCoordinates) + " coordinates (got " + std::to_string(n) + ")");
  if (engine) {
    read_engine(plant, s);
  } else if (plant.has("model")) {
    // The plant is a model's own dynamics (A, f, Q); the effects listed add to them.
    if (plant.has("masses")) plant.child("masses").fail("a plant is either point masses or a model, not both");
    s.plant_model = plant.text("model");
    s.plant_model_where = plant.child("model").where();
    if (plant.has("parameters")) s.plant_parameters = read_parameters(plant.child("parameters"));
    if (const ModelFactory* f = find_builtin_model(s.plant_model)) {
      if (f->dof != n)
        plant.child("coordinates").fail("model '" + s.plant_model + "' has " + std::to_string(f->dof) + " coordinates, the plant lists " + std::to_string(n));
      check_parameter_names(plant, "parameters", *f);
    }
  } else {
    if (plant.has("parameters")) plant.child("parameters").fail("parameters belong to a plant model (plant.model)");
    const auto masses = plant.items("masses");
    if (static_cast<int>(masses.size()) != n)
      plant.child("masses").fail("needs one mass per coordinate (" + std::to_string(n) + "), got " + std::to_string(masses.size()));
    for (const Reader& m : masses) {
      const double v = m.as_number();
      if (!(v > 0)) m.fail("mass must be > 0 (got " + Reader::format(v) + ")");
      s.masses.push_back(v);
    }
  }
  const Reader initial = plant.child("initial");
  initial.require_map();
  for (const auto& kv : initial.node()) {
    const std::string k = initial.key(kv.first);
    bool ok = false;
    for (int i = 1; i <= n; ++i) ok = ok || k == "q" + std::to_string(i) || k == "qd" + std::to_string(i);
    if (!ok) initial.fail_at(kv.first, initial.key_path(k), "unknown key (expected q1..q" + std::to_string(n) + ", qd1..qd" + std::to_string(n) + ")");
  }
  for (int i = 1; i <= n; ++i) {
    s.q0.push_back(initial.number(("q" + std::to_string(i)).c_str(), 0.0));
    s.qd0.push_back(initial.number(("qd" + std::to_string(i)).c_str(), 0.0));
  }
  if (plant.has("effects") && !engine)
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
  if (static_cast<int>(s.constraints.size()) >= n)
    plant.child("constraints").fail("needs fewer constraints than coordinates");

  if (root.has("tracking")) {
    s.tracking = read_tracking(root.child("tracking"));
    if (const ModelFactory* f = find_builtin_model(s.tracking.model))
      if (f->dof != n)
        root.child("tracking").child("model").fail("model '" + s.tracking.model + "' has " + std::to_string(f->dof) +
                                                   " coordinates, the plant has " + std::to_string(n));
    if (!s.constraints.empty()) root.child("tracking").fail("tracking control of a plant with physical constraints is not supported");
  }

  if (root.has("control")) {
    const Reader c = root.child("control");
    c.allow_only({"mode", "rate"});
    const std::string mode = c.text("mode", "continuous");
    if (mode == "continuous") {
      s.control_mode = ControlMode::kContinuous;
    } else if (mode == "sampled") {
      s.control_mode = ControlMode::kSampled;
      s.control_rate = c.positive("rate");
    } else {
      c.child("mode").fail("unknown control mode '" + mode + "' (known: continuous, sampled)");
    }
  }
  for (std::size_t i = 0; i < s.effects.size(); ++i)
    if (s.effects[i].kind == EffectKind::kSensorNoise && s.control_mode != ControlMode::kSampled)
      plant.items("effects")[i].fail("sensor_noise needs control.mode: sampled (noise inside an adaptive integrator is not defined)");

  if (engine) {
    if (root.has("integrator"))
      root.child("integrator").fail("the engine integrates this plant: set plant.timestep and plant.integrator");
    if (s.control_mode != ControlMode::kSampled)
      plant.child("engine").fail("an engine steps under a held command: needs control.mode: sampled");
  }
  const Reader integ = engine ? root : root.child("integrator");
  if (!engine) integ.allow_only({"method", "tolerance", "step", "min_step", "max_steps"});
  const std::string method = engine ? "rk4" : integ.text("method");
  if (engine) {
    s.method = Method::kRk4;
    s.step = s.engine.timestep;
  } else if (method == "rk4") {
    s.method = Method::kRk4;
    s.step = integ.positive("step");
  } else if (method == "dopri5" || method == "rkf78" || method == "bulirsch_stoer") {
    s.method = method == "dopri5" ? Method::kDopri5 : method == "rkf78" ? Method::kRkf78 : Method::kBulirschStoer;
    s.tolerance = integ.positive("tolerance");
  } else {
    integ.child("method").fail("unknown integrator '" + method + "' (known: rk4, dopri5, rkf78, bulirsch_stoer)");
  }

  s.duration = root.positive("duration");
  s.output_period = root.positive("output_period");
  if (s.output_period > s.duration) root.child("output_period").fail("must not exceed duration");
  // What a run can hold: its samples live in memory, and a step must still advance time.
  constexpr double kMaxSamples = 1e7;
  if (s.duration / s.output_period > kMaxSamples)
    root.child("output_period")
        .fail("gives " + Reader::format(s.duration / s.output_period) + " samples over the duration (at most " +
              Reader::format(kMaxSamples) + "): raise output_period or shorten duration");
  if (s.duration * std::numeric_limits<double>::epsilon() * 1e3 > s.output_period)
    root.child("duration").fail("is too long for its output grid to be resolved in double precision");
  s.min_step = engine ? 1e-12 * s.duration : integ.positive("min_step", 1e-12 * s.duration);
  if (!engine) s.max_steps = integ.positive("max_steps", s.max_steps);
  if (s.method == Method::kRk4 && s.duration / s.step > s.max_steps)
    integ.child("step").fail("gives " + Reader::format(s.duration / s.step) + " steps, above integrator.max_steps (" +
                             Reader::format(s.max_steps) + ")");
  if (s.control_mode == ControlMode::kSampled && s.duration * s.control_rate > s.max_steps)
    root.child("control").fail("gives " + Reader::format(s.duration * s.control_rate) +
                               " control periods, above integrator.max_steps (" + Reader::format(s.max_steps) + ")");
  if (s.method == Method::kRk4) {
    const double ratio = s.output_period / s.step;
    if (std::abs(ratio - std::round(ratio)) > 1e-9 * ratio)
      root.child("output_period").fail(std::string("must be a whole number of ") + (engine ? "engine" : "rk4") +
                                       " steps (step " + Reader::format(s.step) + ")");
  }
  if (s.control_mode == ControlMode::kSampled && s.method == Method::kRk4) {
    const double ratio = 1.0 / (s.control_rate * s.step);
    if (std::abs(ratio - std::round(ratio)) > 1e-9 * ratio)
      root.child("control").fail(std::string("the control period must be a whole number of ") +
                                 (engine ? "engine" : "rk4") + " steps (step " + Reader::format(s.step) + ")");
  }
  return s;
}

}  // namespace

namespace {

// Parses YAML text and applies the overrides; the readers then see one tree.
Reader parse_root(const std::string& yaml_text, const std::string& name, const std::vector<std::string>& overrides) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    throw SceneError(name + ":" + std::to_string(e.mark.line + 1) + ": not valid YAML: " + e.msg);
  }
  if (!root.IsMap()) throw SceneError(name + ":1: must be a mapping of keys to values");
  auto overridden = std::make_shared<std::set<std::string>>();
  for (const std::string& o : overrides) apply_override(root, o, name, *overridden);
  return Reader(root, "", std::make_shared<const std::string>(name), overridden);
}

std::string read_file(const std::string& path, const char* what) {
  std::ifstream in(path);
  if (!in) throw SceneError(path + ": cannot open " + what);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace

// Any yaml-cpp error the readers did not turn into a message of their own (a conversion of a
// node of an unexpected kind) still ends as a SceneError naming the file and the line.
namespace {
template <typename F>
auto reading(const std::string& name, F&& read) {
  try {
    return read();
  } catch (const YAML::Exception& e) {
    throw SceneError(name + ":" + std::to_string(e.mark.line + 1) + ": cannot be read: " + e.msg);
  }
}
}  // namespace

Scene parse_scene(const std::string& yaml_text, const std::string& name, const std::vector<std::string>& overrides) {
  Scene s = reading(name, [&] { return read_scene(parse_root(yaml_text, name, overrides)); });
  s.file = name;
  return s;
}

Scene load_scene(const std::string& path, const std::vector<std::string>& overrides) {
  return parse_scene(read_file(path, "scene file"), path, overrides);
}

TrackingSpec parse_tracking(const std::string& yaml_text, const std::string& name,
                            const std::vector<std::string>& overrides) {
  return reading(name, [&] { return read_tracking(parse_root(yaml_text, name, overrides).child("tracking")); });
}

TrackingSpec load_tracking(const std::string& path, const std::vector<std::string>& overrides) {
  return parse_tracking(read_file(path, "configuration file"), path, overrides);
}

}  // namespace gausstrack::plant_sim
