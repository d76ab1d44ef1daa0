#include "gausstrack/nodes/plant_process.hpp"

#include <lcm/lcm-cpp.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "cli.hpp"
#include "gausstrack/nodes/latency_json.hpp"
#include "gausstrack/nodes/message_log.hpp"
#include "gausstrack/nodes/plant_node.hpp"
#include "gausstrack/nodes/process.hpp"
#include "gausstrack/plant_sim/scene.hpp"
#include "gausstrack/plant_sim/simulation.hpp"

namespace gausstrack::nodes {

void PlantNode::add_to_summary(nlohmann::ordered_json& j, long log_dropped) const {
  j["mode"] = o_.lockstep ? "lockstep" : "realtime";
  j["control_rate_hz"] = o_.rate_hz;
  if (!o_.lockstep) {
    j["spin_us"] = o_.spin_us;
    // The time spent spinning, waking to deadline (wall time: a spin that was preempted counts the
    // time it was off the CPU too, so its CPU time is at most this).
    j["spun_ms"] = static_cast<double>(scheduler_.spun_ns()) * 1e-6;
  }
  j["run_id"] = run_id_;
  j["states_published"] = counts_.states_published;
  j["commands_applied"] = counts_.commands_applied;
  j["commands_missing"] = counts_.commands_missing;
  j["commands_late"] = counts_.commands_late;
  j["commands_failed"] = counts_.commands_failed;
  j["deadline_misses"] = scheduler_.misses();
  j["messages_rejected"] = counts_.rejected;
  j["commands_of_other_runs"] = counts_.other_run;
  j["rejected"] = {{"malformed", counts_.malformed},         {"dimension", counts_.wrong_dimension},
                   {"non_finite", counts_.non_finite},       {"stale", counts_.stale},
                   {"other_run", counts_.other_run},         {"unauthenticated", counts_.auth.unauthenticated},
                   {"bad_tag", counts_.auth.bad_tag},        {"replayed", counts_.auth.replayed}};
  j["authenticated"] = auth_ != nullptr;
  j["states_resent"] = counts_.states_resent;
  j["watchdog_trips"] = watchdog_.trips();
  j["log_dropped"] = log_dropped;
  j["round_trip_us"] = percentiles_json(round_trip_us_);
  j["compute_ns"] = percentiles_json(compute_ns_);
  j["wake_late_us"] = o_.lockstep ? nlohmann::ordered_json() : percentiles_json(scheduler_.wake_late_us());
  j["deadline_work_us"] = o_.lockstep ? nlohmann::ordered_json() : percentiles_json(deadline_work_us_);
  j["hold_lag_periods"] = o_.lockstep ? nlohmann::ordered_json() : percentiles_json(hold_lag_periods_);
}

namespace {

struct PlantProcessOptions {
  ProcessOptions process;
  PlantNodeOptions node;
  std::string out_dir = "out/plant";
};

std::optional<int> parse_plant_options(int argc, char** argv, PlantProcessOptions& o) {
  CLI::App app("Simulates a scene's plant in real time (or lock-step): publishes its state each control period "
               "over LCM and applies the controller's answer; writes the run to --out.");
  add_process_options(app, o.process);
  auto* lockstep = app.add_flag("--lockstep", o.node.lockstep, "wait for each command (not real time)");
  app.add_option("--out", o.out_dir, "the run's directory")->capture_default_str();
  app.add_option("--timeout-ms", o.node.timeout_ms, "give up when no controller answers for this long")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--watchdog-ms", o.node.watchdog_ms, "apply the safe action after this long without a command")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--hold-lag", o.node.hold_lag,
                 "real time: answers act this many periods after their state, fixed (0: one more than the 75th "
                 "percentile of the measured round trips)")
      ->check(CLI::Range(0, HoldLag::kMaxLag))
      ->capture_default_str();
  app.add_option("--spin-us", o.node.spin_us,
                 "real time: wake this long before each period's deadline and spin until it (fewer late periods "
                 "at high rates, for up to this much CPU time per period; less than the period)")
      ->check(CLI::Range(0, 1000000))
      ->excludes(lockstep)
      ->capture_default_str();
  std::string safe_action = "zero";
  app.add_option("--safe-action", safe_action, "what the watchdog applies: zero force, or hold the last")
      ->check(CLI::IsMember({"zero", "hold"}))
      ->capture_default_str();
  const std::optional<int> code = parse_command_line(app, argc, argv);
  o.node.safe_hold = safe_action == "hold";
  return code;
}

void write_latency_csv(const PlantNode& node, const std::string& path) {
  std::ofstream csv(path);
  csv << "state_sequence,round_trip_us,compute_ns\n";
  const auto& seq = node.answered_sequences().values();
  for (std::size_t k = 0; k < seq.size(); ++k)
    csv << static_cast<long long>(seq[k]) << ',' << node.round_trip_us().values()[k] << ','
        << node.compute_ns().values()[k] << '\n';
  if (!csv) throw std::runtime_error("cannot write " + path);
}

// Real time: per period, the hold lag and the state whose answer the plant held.
void write_periods_csv(const PlantNode& node, const std::string& path) {
  std::ofstream csv(path);
  csv << "period,hold_lag,applied_state\n";
  const auto& lag = node.hold_lag_periods().values();
  const auto& applied = node.applied_states().values();
  for (std::size_t p = 0; p < lag.size() && p < applied.size(); ++p)
    csv << p << ',' << static_cast<int>(lag[p]) << ',' << static_cast<long long>(applied[p]) << '\n';
  if (!csv) throw std::runtime_error("cannot write " + path);
}

void print_summary(const PlantNode& node, const plant_sim::RunResult& result, const loop_stats_t& stats,
                   const std::string& out_dir) {
  const PlantCounts& c = node.counts();
  std::printf("gausstrack-plant: %zu samples, max tracking error %.3g, %ld states published, %ld commands "
              "applied, %ld missing, %ld late, %ld failed solves, %ld deadline misses, %ld watchdog trips, %ld "
              "messages rejected, round trip p50 %.1f us p99 %.1f us max %.1f us -> %s\n",
              result.samples.size(), result.summary.max_tracking_error, c.states_published, c.commands_applied,
              c.commands_missing, c.commands_late, c.commands_failed, node.scheduler().misses(),
              node.watchdog().trips(), c.rejected, stats.round_trip_us_p50, stats.round_trip_us_p99,
              stats.round_trip_us_max, out_dir.c_str());
  if (const std::string counts = plant_sim::warning_counts(c.warnings); !counts.empty())
    std::printf("  warnings, in control periods: %s\n", counts.c_str());
}

// The scene over LCM: publishes states, applies commands, then writes the run's files and
// statistics. Returns the exit code.
int run_plant(const PlantProcessOptions& o, const plant_sim::Scene& scene, plant_sim::RunOptions run_options) {
  using namespace plant_sim;
  const ProcessOptions& p = o.process;
  PlantNodeOptions node_options = o.node;
  node_options.rate_hz = scene.control_rate;
  node_options.actuators = scene.actuators();
  node_options.periods = static_cast<std::size_t>(std::ceil(scene.duration * scene.control_rate)) + 16;
  // The log's writer before the real-time options, LCM (and its receive thread) after them.
  const auto log = open_message_log(p.log_path);
  stop_on_signals();
  apply_realtime(p, "gausstrack-plant");
  lcm::LCM lcm(p.lcm_url);
  if (!lcm.good()) return std::fprintf(stderr, "error: cannot open LCM (%s)\n", p.lcm_url.c_str()), 1;
  // Lock-step is not real time: its log waits for the disk rather than drop a message.
  PairAuth auth = open_pair_auth(p, "gausstrack-plant");
  Outbox state_out(lcm, p.state_channel, log.get(), node_options.lockstep || p.log_wait,
                   auth.enabled() ? &*auth.states : nullptr);
  Outbox stats_out(lcm, p.stats_channel, log.get(), true);
  PlantNode node(lcm, state_out, p.command_channel, scene.dof(), node_options);
  if (auth.enabled()) node.authenticate(*auth.commands);

  run_options.on_progress = terminal_progress(scene);
  run_options.sampled_control = [&](std::int64_t period, double t, std::span<const double> q,
                                    std::span<const double> qd, std::span<double> u) {
    return node.exchange(period, t, q, qd, u);
  };
  raise_loop_above_receiver(p, "gausstrack-plant");  // the node has subscribed
  RunResult result = run_scene(scene, run_options);
  // The run's warnings are those of the answers the plant held, period by period.
  result.summary.warnings = node.counts().warnings;
  result.summary.rows_not_met = rows_not_met(scene, result.summary.warnings, "control periods");

  const loop_stats_t stats = node.stats();
  stats_out.publish_message(stats);
  const long log_dropped = close_message_log(log.get(), "gausstrack-plant", p.log_path);

  std::filesystem::create_directories(o.out_dir);
  write_trajectory_csv(scene, result, o.out_dir + "/trajectory.csv");
  nlohmann::ordered_json summary = summary_json(scene, result);
  node.add_to_summary(summary, log_dropped);
  write_json(summary, o.out_dir + "/summary.json");
  write_latency_csv(node, o.out_dir + "/latency.csv");
  if (!o.node.lockstep) write_periods_csv(node, o.out_dir + "/periods.csv");
  print_summary(node, result, stats, o.out_dir);
  if (!result.summary.failure.empty()) {
    std::fprintf(stderr, "error: %s (data up to then written to %s)\n", result.summary.failure.c_str(),
                 o.out_dir.c_str());
    return 1;
  }
  if (!result.summary.rows_not_met.empty() && !g_stop_requested) {
    std::fprintf(stderr, "error: the run completed but did not track: %s (data written to %s)\n",
                 result.summary.rows_not_met.c_str(), o.out_dir.c_str());
    return 1;
  }
  // Interrupted by a signal: the data up to then is written and the run counts as done.
  return result.summary.stopped_early && !g_stop_requested ? 1 : 0;
}

}  // namespace

int plant_main(int argc, char** argv, std::vector<plant_sim::ModelFactory> models,
               std::vector<plant_sim::EngineFactory> engines) {
  using namespace plant_sim;
  PlantProcessOptions o;
  if (const std::optional<int> code = parse_plant_options(argc, argv, o)) return *code;
  try {
    const Scene scene = load_scene(o.process.scene_path, o.process.sets);
    if (scene.control_mode != ControlMode::kSampled)
      throw SceneError(o.process.scene_path + ": the plant process needs control.mode: sampled (add --set "
                                              "control.mode=sampled --set control.rate=HZ)");
    if (!o.node.lockstep && !spin_fits_period(o.node.spin_us, period_ns_at(scene.control_rate))) {
      std::fprintf(stderr, "error: --spin-us %d: must be less than the control period (%g us at %g Hz)\n",
                   o.node.spin_us, 1e6 / scene.control_rate, scene.control_rate);
      return 2;
    }
    RunOptions run_options;
    run_options.models = std::move(models);
    run_options.engines = std::move(engines);
    return run_plant(o, scene, std::move(run_options));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}

}  // namespace gausstrack::nodes
