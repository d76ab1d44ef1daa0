#include "gausstrack/nodes/plant_process.hpp"

#include <lcm/lcm-cpp.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "gausstrack/nodes/message_log.hpp"
#include "gausstrack/nodes/plant_node.hpp"
#include "gausstrack/nodes/process.hpp"
#include "gausstrack/plant_sim/scene.hpp"
#include "gausstrack/plant_sim/simulation.hpp"

namespace gausstrack::nodes {
namespace {

int usage(const char* argv0) {
  std::fprintf(stderr,
               "usage: %s %s [--lockstep] [--out DIR] [--timeout-ms T] [--watchdog-ms W] "
               "[--safe-action zero|hold]\n",
               argv0, kCommonUsage);
  return 2;
}

}  // namespace

int plant_main(int argc, char** argv, std::vector<plant_sim::ModelFactory> models,
               std::vector<plant_sim::EngineFactory> engines) {
  using namespace plant_sim;
  ProcessOptions options;
  PlantNodeOptions node_options;
  std::string out_dir = "out/plant", error;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool has_value = i + 1 < argc;
    if (parse_common_option(argc, argv, i, options, error)) {
      if (!error.empty()) return std::fprintf(stderr, "error: %s\n", error.c_str()), 2;
    } else if (a == "--out" && has_value) {
      out_dir = argv[++i];
    } else if ((a == "--timeout-ms" || a == "--watchdog-ms") && has_value) {
      const int v = std::atoi(argv[++i]);
      if (v <= 0) return std::fprintf(stderr, "error: %s takes a positive number of ms\n", a.c_str()), 2;
      (a == "--timeout-ms" ? node_options.timeout_ms : node_options.watchdog_ms) = v;
    } else if (a == "--safe-action" && has_value) {
      const std::string v = argv[++i];
      if (v != "zero" && v != "hold") return std::fprintf(stderr, "error: --safe-action is zero or hold\n"), 2;
      node_options.safe_hold = v == "hold";
    } else if (a == "--lockstep") {
      node_options.lockstep = true;
    } else {
      return usage(argv[0]);
    }
  }
  if (options.scene_path.empty()) return std::fprintf(stderr, "error: --scene is required\n"), usage(argv[0]);
  try {
    const Scene scene = load_scene(options.scene_path, options.sets);
    if (scene.control_mode != ControlMode::kSampled)
      throw SceneError(options.scene_path + ": the plant process needs control.mode: sampled (add --set "
                                            "control.mode=sampled --set control.rate=HZ)");
    node_options.rate_hz = scene.control_rate;
    node_options.periods = static_cast<std::size_t>(std::ceil(scene.duration * scene.control_rate)) + 16;
    // The log's writer before the real-time options, LCM (and its receive thread) after them.
    const auto log = open_message_log(options.log_path);
    stop_on_signals();
    apply_realtime(options, "gausstrack-plant");
    lcm::LCM lcm(options.lcm_url);
    if (!lcm.good()) return std::fprintf(stderr, "error: cannot open LCM (%s)\n", options.lcm_url.c_str()), 1;
    // Lock-step is not real time: its log waits for the disk rather than drop a message.
    Outbox state_out(lcm, options.state_channel, log.get(), node_options.lockstep || options.log_wait);
    Outbox stats_out(lcm, options.stats_channel, log.get(), true);
    PlantNode node(lcm, state_out, options.command_channel, scene.dof(), node_options);

    RunOptions run_options;
    run_options.models = std::move(models);
    run_options.engines = std::move(engines);
    run_options.on_progress = terminal_progress(scene);
    run_options.sampled_control = [&](std::int64_t period, double t, std::span<const double> q,
                                      std::span<const double> qd, std::span<double> u) {
      return node.exchange(period, t, q, qd, u);
    };
    const RunResult result = run_scene(scene, run_options);

    const loop_stats_t stats = node.stats();
    stats_out.publish_message(stats);
    const long log_dropped = close_message_log(log.get(), "gausstrack-plant", options.log_path);

    std::filesystem::create_directories(out_dir);
    write_trajectory_csv(scene, result, out_dir + "/trajectory.csv");
    write_summary_json(scene, result, out_dir + "/summary.json", node.summary_members(log_dropped));
    {
      std::ofstream csv(out_dir + "/latency.csv");
      csv << "state_sequence,round_trip_us,compute_ns\n";
      const auto& seq = node.answered_sequences().values();
      for (std::size_t k = 0; k < seq.size(); ++k)
        csv << static_cast<long long>(seq[k]) << ',' << node.round_trip_us().values()[k] << ','
            << node.compute_ns().values()[k] << '\n';
      if (!csv) throw std::runtime_error("cannot write " + out_dir + "/latency.csv");
    }
    const PlantCounts& c = node.counts();
    std::printf("gausstrack-plant: %zu samples, max tracking error %.3g, %ld states published, %ld commands "
                "applied, %ld missing, %ld late, %ld failed solves, %ld deadline misses, %ld watchdog trips, %ld "
                "messages rejected, round trip p50 %.1f us p99 %.1f us max %.1f us -> %s\n",
                result.samples.size(), result.summary.max_tracking_error, c.states_published, c.commands_applied,
                c.commands_missing, c.commands_late, c.commands_failed, node.scheduler().misses(),
                node.watchdog().trips(), c.rejected, stats.round_trip_us_p50, stats.round_trip_us_p99,
                stats.round_trip_us_max, out_dir.c_str());
    if (!result.summary.failure.empty()) {
      std::fprintf(stderr, "error: %s (data up to then written to %s)\n", result.summary.failure.c_str(),
                   out_dir.c_str());
      return 1;
    }
    // Interrupted by a signal: the data up to then is written and the run counts as done.
    return result.summary.stopped_early && !g_stop_requested ? 1 : 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}

}  // namespace gausstrack::nodes
