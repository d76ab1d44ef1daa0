#include "gausstrack/tracking/yaml_reader.hpp"

#include <fstream>

namespace gausstrack::tracking {
namespace {

// "a.b.2.c=value": replaces (or adds) the value at that dotted path, parsed as YAML.
void apply_override(YAML::Node root, const std::string& assignment, const std::string& file,
                    std::set<std::string>& overridden) {
  const auto eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0)
    throw ConfigError(file + ": --set " + assignment + ": expected key=value");
  const std::string path = assignment.substr(0, eq);
  YAML::Node value;
  try {
    value = YAML::Load(assignment.substr(eq + 1));
  } catch (const YAML::Exception& e) {
    throw ConfigError(file + ": --set " + path + ": value is not valid YAML: " + e.msg);
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
        throw ConfigError(file + ": --set " + path + ": '" + k + "' must index a list");
      }
      // An index one past the end appends (e.g. adds an effect to the list).
      if (idx > cur.size() || (idx == cur.size() && !last))
        throw ConfigError(file + ": --set " + path + ": index " + k + " out of range");
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
      throw ConfigError(file + ": --set " + path + ": '" + shown + "' is not a mapping");
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

}  // namespace

Reader parse_root(const std::string& yaml_text, const std::string& name,
                  const std::vector<std::string>& overrides) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    throw ConfigError(name + ":" + std::to_string(e.mark.line + 1) + ": not valid YAML: " + e.msg);
  }
  if (!root.IsMap()) throw ConfigError(name + ":1: must be a mapping of keys to values");
  auto overridden = std::make_shared<std::set<std::string>>();
  for (const std::string& o : overrides) apply_override(root, o, name, *overridden);
  return Reader(root, "", std::make_shared<const std::string>(name), overridden);
}

std::string read_file(const std::string& path, const char* what) {
  std::ifstream in(path);
  if (!in) throw ConfigError(path + ": cannot open " + what);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
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

}  // namespace gausstrack::tracking
