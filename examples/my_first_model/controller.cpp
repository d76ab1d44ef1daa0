// The controller process for TetheredPuck: subscribe to plant states, answer each with the law's
// force. Reads the `tracking` section of the scene (or of a file of its own). Written out to show
// the node; nodes::controller_main<TetheredPuck>(argc, argv, "tethered_puck") is the same process
// with message logs, diagnostics and statistics in one line.
//   my_model_controller --config tethered_puck.yaml [--lcm-url URL]
#include <lcm/lcm-cpp.hpp>

#include <cstdio>

#include "gausstrack/nodes/controller_node.hpp"
#include "gausstrack/nodes/process.hpp"
#include "gausstrack/plant_sim/models.hpp"
#include "my_model.hpp"

int main(int argc, char** argv) {
  using namespace gausstrack;
  nodes::ProcessOptions o;
  std::string error;
  for (int i = 1; i < argc; ++i)
    if (!nodes::parse_common_option(argc, argv, i, o, error) || !error.empty())
      return std::fprintf(stderr, "usage: %s %s\n", argv[0], nodes::kCommonUsage), 2;
  try {
    const plant_sim::TrackingSpec spec = plant_sim::load_tracking(o.scene_path, o.sets);
    if (spec.model != "tethered_puck") return std::fprintf(stderr, "error: %s names another model\n", spec.where.c_str()), 1;
    lcm::LCM lcm(o.lcm_url);
    if (!lcm.good()) return std::fprintf(stderr, "error: cannot open LCM\n"), 1;
    nodes::Outbox commands(lcm, o.command_channel, nullptr, false);
    nodes::ControllerNode<TetheredPuck> node(plant_sim::make_controller<TetheredPuck>(spec), commands);
    lcm.subscribe(o.state_channel, &nodes::ControllerNode<TetheredPuck>::on_state, &node);
    nodes::stop_on_signals();
    nodes::apply_realtime(o, "my_model_controller");  // --rt-priority, --cpu, --lock-memory
    std::printf("my_model_controller: ready\n");
    std::fflush(stdout);
    while (!nodes::g_stop_requested) lcm.handleTimeout(100);
    std::printf("my_model_controller: %ld commands, %ld rejected, compute p50 %.0f ns\n", node.counts().served,
                node.counts().rejected, node.compute_ns().quantile(0.5));
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
