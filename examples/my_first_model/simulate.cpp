// Offline: the scene's plant and the control law in one process.
//   my_model_sim tethered_puck.yaml OUT_DIR
#include <cstdio>

#include "gausstrack/plant_sim/simulation.hpp"
#include "my_model.hpp"

int main(int argc, char** argv) {
  using namespace gausstrack::plant_sim;
  if (argc != 3) return std::fprintf(stderr, "usage: %s SCENE.yaml OUT_DIR\n", argv[0]), 2;
  try {
    const Scene scene = load_scene(argv[1]);
    RunOptions options;
    options.models.push_back(model_factory<TetheredPuck>("tethered_puck"));  // the one extension point
    const RunResult result = run_scene(scene, options);
    write_trajectory_csv(scene, result, std::string(argv[2]) + "/trajectory.csv");
    write_summary_json(scene, result, std::string(argv[2]) + "/summary.json");
    std::printf("%s: max tracking error %.3g over %zu samples\n", scene.name.c_str(),
                result.summary.max_tracking_error, result.samples.size());
    return result.summary.failure.empty() ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
