// A whole plant process: steps a scene's plant (point masses or any model, with the effects and
// physical constraints the scene lists) one control period at a time through a PlantNode, and
// writes the run. gausstrack-plant is this with the compiled-in models; a user's plant main
// passes their own model as well:
//
//   int main(int argc, char** argv) {
//     return gausstrack::nodes::plant_main(argc, argv, {gausstrack::plant_sim::model_factory<MyModel>("my_model")});
//   }
//
// Writes DIR/trajectory.csv, DIR/summary.json (the run and its loop statistics) and
// DIR/latency.csv (one row per command received), and publishes its loop_stats_t when it stops.
#pragma once

#include <vector>

#include "gausstrack/plant_sim/models.hpp"
#include "gausstrack/plant_sim/simulation.hpp"

namespace gausstrack::nodes {

/// `engines`: the physics engines a scene may name (plant.engine), e.g. plant_sim::mujoco_engine().
int plant_main(int argc, char** argv, std::vector<plant_sim::ModelFactory> models = {},
               std::vector<plant_sim::EngineFactory> engines = {});

}  // namespace gausstrack::nodes
