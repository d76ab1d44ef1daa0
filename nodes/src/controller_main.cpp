// gausstrack-controller --config FILE [common options] [--diagnostics] [--stats-out FILE]
// Runs the compiled-in model the configuration's tracking.model names (tracking/builtin_models.hpp).
// Links the law, its configuration and the LCM types: nothing of the simulator.
#include <cstdio>
#include <optional>

#include "gausstrack/nodes/controller_process.hpp"
#include "gausstrack/tracking/builtin_models.hpp"

int main(int argc, char** argv) {
  using namespace gausstrack;
  nodes::ControllerProcessOptions o;
  if (const std::optional<int> code = nodes::parse_controller_options(argc, argv, o)) return *code;
  try {
    const tracking::TrackingSpec spec = tracking::load_tracking(o.process.scene_path, o.process.sets);
    int code = 1;
    if (!tracking::visit_builtin_model(spec.model, [&]<typename M>(std::type_identity<M>) {
          code = nodes::run_controller<M>(o, spec);
        }))
      throw tracking::ConfigError(spec.where + ": unknown model '" + spec.model + "' (compiled in: " +
                                  tracking::builtin_model_names() + ")");
    return code;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
