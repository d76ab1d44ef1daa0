// The planar arm driven through its stretched configuration, where its hand Jacobian (the
// constraint matrix D) loses rank: the circle below passes 2.4 m from the shoulder, the arm's
// full reach. Each strategy of the law is run over the same passage (plant = the arm model,
// offline) and the program prints what the diagnostics said and what force was commanded.
//   planar_arm_stretched [OUT_DIR]
#include <cmath>
#include <cstdio>
#include <string>

#include "gausstrack/tracking/builtin_models.hpp"
#include "gausstrack/plant_sim/models.hpp"
#include "gausstrack/plant_sim/simulation.hpp"

int main(int argc, char** argv) {
  using namespace gausstrack;
  using Arm = systems::PlanarArm<double>;
  const std::string scene_path = std::string(GAUSSTRACK_EXAMPLE_DIR) + "/stretched.yaml";
  bool ok = true;
  std::printf("| strategy | floor [min sigma] | max tracking error | max |force| [N m] | rank-deficient | "
              "near-singular | saturated |\n|---|---|---|---|---|---|---|\n");
  for (const char* strategy : {"cholesky", "svd", "cod", "damped"})
    for (const char* floor : {"0", "0.05"}) {
      const plant_sim::Scene scene = plant_sim::load_scene(
          scene_path, {std::string("tracking.strategy=") + strategy, std::string("tracking.min_singular_value=") + floor});
      // The offline run with the scene's controller ...
      const plant_sim::RunResult r = plant_sim::run_scene(scene);
      if (argc > 1) plant_sim::write_trajectory_csv(scene, r, std::string(argv[1]) + "/" + strategy + "_" + floor + ".csv");
      // ... and the same law replayed on the run's states, to read its diagnostics.
      auto law = plant_sim::make_controller<Arm>(scene.tracking);
      TrackingController<Arm>::Output out;
      long rank_deficient = 0, near_singular = 0, saturated = 0;
      double max_force = 0;
      for (const plant_sim::Sample& s : r.samples) {
        law.compute(Arm::Vector(s.q.data()), Arm::Vector(s.qd.data()), s.t, out);
        rank_deficient += out.diagnostics.has(warning::kRankDeficient);
        near_singular += out.diagnostics.has(warning::kNearSingular);
        saturated += out.diagnostics.has(warning::kSaturated);
        max_force = std::max(max_force, out.force.cwiseAbs().maxCoeff());
      }
      // Whatever the strategy, no command beyond the actuator limit and nothing non-finite.
      ok = ok && std::isfinite(max_force) && max_force <= scene.tracking.force_limit * (1 + 1e-12);
      std::printf("| %s | %s | %.3g | %.3g | %ld | %ld | %ld |%s\n", strategy, floor, r.summary.max_tracking_error,
                  max_force, rank_deficient, near_singular, saturated,
                  r.summary.failure.empty() ? "" : (" failed: " + r.summary.failure).c_str());
    }
  return ok ? 0 : 1;
}
