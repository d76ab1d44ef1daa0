// Cost of simulating the coupled Duffing plant as effects are added to its scene, one at a
// time: a fixed number of RK4 steps (so every run does the same number of right-hand-side
// evaluations), reported per evaluation. Baseline: the same plant with no effect listed.
#include <benchmark/benchmark.h>

#include <string>
#include <vector>

#include "gausstrack/plant_sim/scene.hpp"
#include "gausstrack/plant_sim/simulation.hpp"

namespace {

using namespace gausstrack::plant_sim;

const char* const kEffects[] = {
    "{type: spring, between: [x1, x2], stiffness: 10.0}",
    "{type: cubic_spring, between: [x1, x2], stiffness: 1.0}",
    "{type: damper, between: [x1, x2], coefficient: 0.1}",
    "{type: spring, between: [x2, ground], stiffness: 12.0}",
    "{type: cubic_spring, between: [x2, ground], stiffness: 2.0}",
    "{type: damper, between: [x2, ground], coefficient: 0.15}",
    "{type: disturbance, coordinate: x1, amplitude: 0.5, frequency: 3.0}",
    "{type: gravity, coordinate: x2, acceleration: 9.81}",
};

Scene scene_with(int effects) {
  std::string text = R"(name: step_cost
plant:
  coordinates: [x1, x2]
  masses: [2.0, 1.0]
  initial: {q1: 1.0, q2: 1.0, qd1: 8.283185307179586, qd2: 2.0}
  effects: [)";
  for (int i = 0; i < effects; ++i) text += std::string(i ? ", " : "") + kEffects[i];
  text += R"(]
integrator: {method: rk4, step: 1.0e-3}
duration: 1.0
output_period: 1.0
)";
  return parse_scene(text, "step_cost");
}

void BM_PlantStep(benchmark::State& state) {
  const Scene scene = scene_with(static_cast<int>(state.range(0)));
  std::uint64_t rhs = 0;
  for (auto _ : state) {
    const RunResult r = run_scene(scene);
    rhs += r.summary.rhs_evaluations;
    benchmark::DoNotOptimize(r.samples.data());
  }
  // Seconds per right-hand-side evaluation (shown with an SI prefix, e.g. 14n = 14 ns).
  state.counters["s_per_rhs"] =
      benchmark::Counter(static_cast<double>(rhs), benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.SetLabel(std::to_string(state.range(0)) + " effects");
}
BENCHMARK(BM_PlantStep)->DenseRange(0, 8)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
