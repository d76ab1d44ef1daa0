// Reading YAML configurations so that every error names file, line and key: the readers of the
// `tracking` section (config.cpp) and of whole scenes (plant_sim) walk the same tree this way.
#pragma once

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "gausstrack/tracking/config.hpp"

namespace gausstrack::tracking {

// Walks a YAML mapping with its dotted path, so that every error names file, line and key.
class Reader {
 public:
  Reader(YAML::Node node, std::string path, std::shared_ptr<const std::string> file,
         std::shared_ptr<const std::set<std::string>> overridden)
      : node_(std::move(node)),
        path_(std::move(path)),
        file_(std::move(file)),
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
    throw ConfigError(out.str());
  }

  /// "file:line: key" of this node, as error messages start.
  std::string where() const {
    std::ostringstream out;
    out << *file_;
    if (overridden_->count(path_))
      out << ": --set " << path_;
    else
      out << ":" << (node_.Mark().line + 1) << ": " << path_;
    return out.str();
  }

  const std::string& file() const { return *file_; }
  /// True when `key` of this node was given by an override (--set) rather than by the file.
  bool overridden(const char* key) const { return overridden_->count(key_path(key)) > 0; }

  std::string key_path(const std::string& key) const {
    return path_.empty() ? key : path_ + "." + key;
  }

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

  bool has(const char* key) const {
    return node_.IsMap() && node_[key].IsDefined() && !node_[key].IsNull();
  }

  Reader child(const char* key) const {
    if (!has(key)) fail("missing required key '" + std::string(key) + "'");
    return Reader(node_[key], key_path(key), file_, overridden_);
  }

  double number(const char* key) const {
    const Reader c = child(key);
    return c.as_number();
  }
  double number(const char* key, double fallback) const {
    return has(key) ? number(key) : fallback;
  }

  double positive(const char* key) const {
    const double v = number(key);
    if (!(v > 0)) child(key).fail("must be > 0 (got " + format(v) + ")");
    return v;
  }
  double positive(const char* key, double fallback) const {
    return has(key) ? positive(key) : fallback;
  }
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
  std::string text(const char* key, const std::string& fallback) const {
    return has(key) ? text(key) : fallback;
  }

  /// The value among `values` named by this key (by the enum's to_string); an unknown name fails
  /// with "unknown <what> 'name' (known: ...)".
  template <class E, std::size_t K>
  E choice(const char* key, const E (&values)[K], const char* what) const {
    const std::string name = text(key);
    if (const std::optional<E> v = from_name(values, name)) return *v;
    child(key).fail("unknown " + std::string(what) + " '" + name + "' (known: " + names_of(values) + ")");
  }
  template <class E, std::size_t K>
  E choice(const char* key, const E (&values)[K], const char* what, E fallback) const {
    return has(key) ? choice(key, values, what) : fallback;
  }

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

/// Parses YAML text and applies the "dotted.key=value" overrides; the readers then see one tree
/// whose overridden keys are reported as "--set key". Throws ConfigError.
Reader parse_root(const std::string& yaml_text, const std::string& name,
                  const std::vector<std::string>& overrides);

/// The whole text of a file; ConfigError "PATH: cannot open WHAT" when it cannot be read.
std::string read_file(const std::string& path, const char* what);

/// Runs read(); a yaml-cpp error the readers did not turn into a message of their own (a
/// conversion of a node of an unexpected kind) still ends as a ConfigError naming file and line.
template <typename F>
auto reading(const std::string& name, F&& read) {
  try {
    return read();
  } catch (const YAML::Exception& e) {
    throw ConfigError(name + ":" + std::to_string(e.mark.line + 1) + ": cannot be read: " + e.msg);
  }
}

/// A mapping of parameter names to numbers.
std::vector<ModelParameter> read_parameters(const Reader& r);

/// Checks the keys of the mapping parent.key (when present) against a model's parameter names;
/// an unknown one fails at its own line, naming the known ones.
void check_parameter_names(const Reader& parent, const char* key, const std::string& model,
                           const std::vector<std::string>& names);

/// The `tracking` section (its node): model, parameters, trajectory, stabilization, strategy,
/// limits. A compiled-in model's parameter names are checked here.
TrackingSpec read_tracking(const Reader& section);

}  // namespace gausstrack::tracking
