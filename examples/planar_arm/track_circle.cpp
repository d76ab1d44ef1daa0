// The arm's hand tracks its circle offline: the shipped scene, the compiled-in model.
//   planar_arm_track SCENE.yaml
#include <cstdio>

#include "gausstrack/plant_sim/simulation.hpp"

int main(int argc, char** argv) {
  using namespace gausstrack::plant_sim;
  if (argc != 2) return std::fprintf(stderr, "usage: %s SCENE.yaml\n", argv[0]), 2;
  try {
    const Scene scene = load_scene(argv[1]);
    const RunResult r = run_scene(scene);
    std::printf("%s: hand off its circle by at most %.3g m over %.0f s (%zu samples)\n", scene.name.c_str(),
                r.summary.max_tracking_error, scene.duration, r.samples.size());
    return r.summary.failure.empty() && r.summary.max_tracking_error < 1e-6 ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
