// The plant process: steps the scene's plant (here the model's own dynamics, with the scene's
// mismatch and disturbance) one control period at a time and exchanges states and commands.
//   my_model_plant --scene tethered_puck.yaml --set control.mode=sampled --set control.rate=500 [--lockstep]
#include "gausstrack/nodes/plant_process.hpp"
#include "my_model.hpp"

int main(int argc, char** argv) {
  return gausstrack::nodes::plant_main(argc, argv, {gausstrack::plant_sim::model_factory<TetheredPuck>("tethered_puck")});
}
