// The scene reader on hostile text: the YAML of a scene, and `--set` overrides. The input is the
// YAML, optionally followed by a line "#--set" and one override ("dotted.key=value") per line.
//
// Properties (any violation aborts, so libFuzzer keeps the input):
// - the reader either accepts the scene or throws SceneError (nothing else escapes, nothing
//   crashes or hangs);
// - an accepted scene is one the simulator can start: 1..32 coordinates, finite initial state of
//   that size, positive finite masses, a finite positive duration and output period; its
//   controller (when tracking is on and the model is built in) computes a finite force at the
//   initial state, and the plant's acceleration there can be evaluated.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "fuzz_input.hpp"
#include "gausstrack/tracking/builtin_models.hpp"
#include "gausstrack/plant_sim/models.hpp"
#include "gausstrack/plant_sim/scene.hpp"
#include "gausstrack/plant_sim/simulation.hpp"

namespace {

namespace ps = gausstrack::plant_sim;

bool all_finite(const std::vector<double>& v) {
  for (double x : v)
    if (!std::isfinite(x)) return false;
  return true;
}

void check_accepted(const ps::Scene& s) {
  const int n = s.dof();
  GAUSSTRACK_FUZZ_CHECK(n >= 1 && n <= ps::kMaxCoordinates);
  GAUSSTRACK_FUZZ_CHECK(static_cast<int>(s.q0.size()) == n && static_cast<int>(s.qd0.size()) == n);
  GAUSSTRACK_FUZZ_CHECK(all_finite(s.q0) && all_finite(s.qd0));
  GAUSSTRACK_FUZZ_CHECK(s.masses.empty() || static_cast<int>(s.masses.size()) == n);
  for (double m : s.masses) GAUSSTRACK_FUZZ_CHECK(std::isfinite(m) && m > 0);
  GAUSSTRACK_FUZZ_CHECK(std::isfinite(s.duration) && s.duration > 0);
  GAUSSTRACK_FUZZ_CHECK(std::isfinite(s.output_period) && s.output_period > 0);

  if (s.tracking.enabled) {
    if (const ps::ModelFactory* factory = ps::find_builtin_model(s.tracking.model)) {
      GAUSSTRACK_FUZZ_CHECK(factory->dof == n);
      const auto law = factory->control_law(s.tracking);
      std::vector<double> force(static_cast<std::size_t>(n));
      law->compute(s.q0.data(), s.qd0.data(), 0.0, force.data());
      GAUSSTRACK_FUZZ_CHECK(all_finite(force));
    }
  }
  if (!s.engine.name.empty()) return;  // an engine's physics are not plant_sim's
  const std::vector<double> u(static_cast<std::size_t>(n), 0.0);
  const std::vector<double> a = ps::plant_acceleration(s, s.q0, s.qd0, 0.0, u);
  GAUSSTRACK_FUZZ_CHECK(static_cast<int>(a.size()) == n);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  static const std::string kMarker = "\n#--set\n";
  const std::size_t split = text.find(kMarker);
  const std::string yaml = text.substr(0, split);
  std::vector<std::string> overrides;
  if (split != std::string::npos) {
    std::size_t begin = split + kMarker.size();
    while (begin < text.size()) {
      std::size_t end = text.find('\n', begin);
      if (end == std::string::npos) end = text.size();
      overrides.push_back(text.substr(begin, end - begin));
      begin = end + 1;
    }
  }
  try {
    check_accepted(ps::parse_scene(yaml, "fuzz.yaml", overrides));
  } catch (const ps::SceneError&) {
  }
  try {
    const ps::TrackingSpec spec = ps::parse_tracking(yaml, "fuzz.yaml", overrides);
    if (spec.enabled) {
      if (const ps::ModelFactory* factory = ps::find_builtin_model(spec.model)) (void)factory->control_law(spec);
    }
  } catch (const ps::SceneError&) {
  }
  return 0;
}
