#include "gausstrack/tracking/config.hpp"

#include <algorithm>

#include "gausstrack/tracking/builtin_models.hpp"
#include "gausstrack/tracking/make_controller.hpp"
#include "gausstrack/tracking/yaml_reader.hpp"

namespace gausstrack::tracking {

std::optional<InverseStrategy> strategy_from_name(std::string_view name) { return from_name(kStrategies, name); }

std::string strategy_names() { return names_of(kStrategies); }

std::string builtin_model_names() {
  std::string names;
  for (const char* name : kBuiltinModels) names += (names.empty() ? "" : ", ") + std::string(name);
  return names;
}

bool builtin_parameter_names(std::string_view model, std::vector<std::string>& names) {
  return visit_builtin_model(
      model, [&]<typename M>(std::type_identity<M>) { names = parameter_names<M>(); });
}

void check_parameter_names(const Reader& parent, const char* key, const std::string& model,
                           const std::vector<std::string>& names) {
  if (!parent.has(key)) return;
  const Reader r = parent.child(key);
  r.require_map();
  for (const auto& kv : r.node()) {
    const std::string k = r.key(kv.first);
    if (std::find(names.begin(), names.end(), k) == names.end()) {
      std::string known;
      for (const auto& p : names) known += (known.empty() ? "" : ", ") + p;
      r.fail_at(kv.first, r.key_path(k),
                "model '" + model + "' has no parameter '" + k + "' (known: " + known + ")");
    }
  }
}

TrackingSpec read_tracking(const Reader& t) {
  t.allow_only({"model", "parameters", "trajectory", "stabilization", "robust", "strategy", "force_limit",
                "min_singular_value", "hold", "delay", "unmet_limit"});
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
  if (std::vector<std::string> names; builtin_parameter_names(tr.model, names)) {
    check_parameter_names(t, "parameters", tr.model, names);
    check_parameter_names(t, "trajectory", tr.model, names);
  } else if (tr.model.empty()) {
    t.child("model").fail("must name a model");
  }
  if (t.has("stabilization")) {
    const Reader st = t.child("stabilization");
    st.allow_only({"zeta", "omega"});
    tr.zeta = st.non_negative("zeta", 1.0);
    tr.stabilization_omega = st.non_negative("omega", 0.0);
  }
  if (t.has("robust")) {
    const Reader r = t.child("robust");
    r.allow_only({"bound", "layer"});
    tr.robust_bound = r.positive("bound");
    tr.robust_layer = r.positive("layer");
  }
  tr.force_limit = t.positive("force_limit", tr.force_limit);
  tr.min_singular_value = t.non_negative("min_singular_value", tr.min_singular_value);
  if (t.has("strategy")) {
    tr.strategy = t.choice("strategy", kStrategies, "strategy");
  }
  tr.hold = t.choice("hold", kHoldLaws, "hold law", HoldLaw::kMidpoint);
  tr.delay = t.non_negative("delay", 0.0);
  tr.delay_configured = t.has("delay");
  tr.unmet_limit = t.non_negative("unmet_limit", tr.unmet_limit);
  if (tr.unmet_limit > 1) t.child("unmet_limit").fail("must be a share between 0 and 1");
  return tr;
}

TrackingSpec parse_tracking(const std::string& yaml_text, const std::string& name,
                            const std::vector<std::string>& overrides) {
  return reading(name, [&] {
    const Reader root = parse_root(yaml_text, name, overrides);
    TrackingSpec tr = read_tracking(root.child("tracking"));
    // The period, where the file says the control is sampled (the scene reader checks the rest
    // of the control section).
    if (root.has("control")) {
      const Reader c = root.child("control");
      if (c.text("mode", "continuous") == "sampled") tr.period = 1.0 / c.positive("rate");
    }
    return tr;
  });
}

TrackingSpec load_tracking(const std::string& path, const std::vector<std::string>& overrides) {
  return parse_tracking(read_file(path, "configuration file"), path, overrides);
}

}  // namespace gausstrack::tracking
