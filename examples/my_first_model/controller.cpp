// The controller process for TetheredPuck: subscribes to plant states and answers the newest with
// the law's force, reading the `tracking` section of the scene (or of a file of its own). Links the
// law, its configuration and the LCM types; nothing of the simulator.
//   my_model_controller --config tethered_puck.yaml [--lcm-url URL] [--diagnostics] [--stats-out FILE]
#include "gausstrack/nodes/controller_process.hpp"
#include "my_model.hpp"

int main(int argc, char** argv) {
  return gausstrack::nodes::controller_main<TetheredPuck>(argc, argv, "tethered_puck");
}
