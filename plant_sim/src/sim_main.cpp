// gausstrack-sim SCENE.yaml [--out DIR] [--set key=value ...]
// Runs a scene in one process and writes DIR/trajectory.csv and DIR/summary.json.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "gausstrack/plant_sim/scene.hpp"
#include "gausstrack/plant_sim/simulation.hpp"
#include "gausstrack/tracking/stop_request.hpp"
#ifdef GAUSSTRACK_HAVE_MUJOCO
#include "gausstrack/plant_sim/mujoco.hpp"
#endif

int main(int argc, char** argv) {
  using namespace gausstrack::plant_sim;
  std::string scene_path, out_dir = "out/sim";
  std::vector<std::string> sets;
  CLI::App app("Runs a scene in one process: the plant, the effects it lists and the tracking law of eq. (32); "
               "writes DIR/trajectory.csv and DIR/summary.json.");
  app.add_option("scene", scene_path, "the scene file (YAML)")->required();
  app.add_option("--out", out_dir, "the run's directory")->capture_default_str();
  app.add_option("--set", sets, "override a key of the scene: dotted.key=value (repeatable)")
      ->allow_extra_args(false);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;  // --help, or a usage error (printed)
  }

  try {
    const Scene scene = load_scene(scene_path, sets);
    RunOptions options;
    options.on_progress = terminal_progress(scene);
#ifdef GAUSSTRACK_HAVE_MUJOCO
    options.engines.push_back(mujoco_engine());
#endif
    // Ctrl-C (or SIGTERM) stops the run where it is; what it computed is written.
    gausstrack::stop_on_signals();
    options.stop_requested = [] { return gausstrack::g_stop_requested != 0; };
    const RunResult result = run_scene(scene, options);
    std::filesystem::create_directories(out_dir);
    write_trajectory_csv(scene, result, out_dir + "/trajectory.csv");
    write_summary_json(scene, result, out_dir + "/summary.json");
    const RunSummary& s = result.summary;
    std::printf("%s: %zu samples, max tracking error %.3g (rms %.3g), max constraint residual %.3g, %llu steps, "
                "%llu rhs evaluations, %.3f s -> %s\n",
                scene.name.c_str(), result.samples.size(), s.max_tracking_error, s.rms_tracking_error, s.max_constraint_residual,
                static_cast<unsigned long long>(s.steps), static_cast<unsigned long long>(s.rhs_evaluations),
                s.wall_time_s, out_dir.c_str());
    if (s.control_failures > 0)
      std::printf("  warning: %llu control evaluations failed (zero force applied)\n",
                  static_cast<unsigned long long>(s.control_failures));
    if (const std::string counts = warning_counts(s.warnings); !counts.empty())
      std::printf("  warnings, in control evaluations: %s\n", counts.c_str());
    const double reached = result.samples.empty() ? 0.0 : result.samples.back().t;
    if (!s.rows_not_met.empty() && s.failure.empty() && !gausstrack::g_stop_requested) {
      std::fprintf(stderr, "error: %s: the run completed but did not track: %s (data written)\n", scene_path.c_str(),
                   s.rows_not_met.c_str());
      return 1;
    }
    if (!s.failure.empty()) {
      std::fprintf(stderr, "error: %s: %s (samples up to t = %g s written)\n", scene_path.c_str(), s.failure.c_str(),
                   reached);
      return 1;
    }
    if (gausstrack::g_stop_requested) {
      std::fprintf(stderr, "gausstrack-sim: interrupted; samples up to t = %g s written\n", reached);
      return 130;
    }
    return 0;
  } catch (const SceneError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
