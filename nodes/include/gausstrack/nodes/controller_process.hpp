// A whole controller process for model type M: options, configuration, LCM, the node, the loop
// and its statistics. gausstrack-controller calls it for the compiled-in model a configuration
// names; a user's own controller main may call it for their model in one line (linking
// gausstrack::nodes: the law, its configuration and the LCM types, nothing of the simulator):
//
//   int main(int argc, char** argv) { return gausstrack::nodes::controller_main<MyModel>(argc, argv, "my_model"); }
//
// gausstrack-controller --config FILE [common options] [--diagnostics] [--stats-out FILE]
// FILE holds a `tracking` section (a whole scene, or a file of that section alone): model,
// parameters, trajectory, stabilization, strategy, limits. Nothing else in it is read.
#pragma once

#include <lcm/lcm-cpp.hpp>

#include <cmath>
#include <cstdio>
#include <optional>
#include <string>

#include "gausstrack/loop_stats_t.hpp"
#include "gausstrack/nodes/controller_node.hpp"
#include "gausstrack/nodes/message_log.hpp"
#include "gausstrack/nodes/process.hpp"
#include "gausstrack/tracking/config.hpp"
#include "gausstrack/tracking/make_controller.hpp"

namespace gausstrack::nodes {

struct ControllerProcessOptions {
  ProcessOptions process;
  std::string stats_out;     ///< --stats-out FILE: the counts as JSON
  bool diagnostics = false;  ///< --diagnostics: publish control_diagnostics_t beside each command
};

/// Parses the controller's command line (the common options, --diagnostics, --stats-out). Nothing
/// to go on; else the exit code (0 after --help, 2 after a usage error, printed).
std::optional<int> parse_controller_options(int argc, char** argv, ControllerProcessOptions& o);

/// Writes the controller's counts and compute-time percentiles to `path` as JSON (--stats-out).
/// Throws std::runtime_error when it cannot.
void write_controller_stats(const std::string& path, const std::string& model, const ControllerCounts& counts,
                            long log_dropped, const LatencyRecorder& compute_ns);

/// Runs the controller for model type M until SIGINT/SIGTERM; returns the exit code. Prints
/// "gausstrack-controller: ready" once subscribed.
template <Model M>
int run_controller(const ControllerProcessOptions& o, const tracking::TrackingSpec& spec, M defaults = {}) {
  const ProcessOptions& p = o.process;
  // The log's writer before the real-time options, LCM (and its receive thread) after them.
  const auto log = open_message_log(p.log_path);
  stop_on_signals();
  apply_realtime(p, "gausstrack-controller");
  lcm::LCM lcm(p.lcm_url);  // empty: LCM_DEFAULT_URL or LCM's own default
  if (!lcm.good()) return std::fprintf(stderr, "error: cannot open LCM (%s)\n", p.lcm_url.c_str()), 1;
  PairAuth auth = open_pair_auth(p, "gausstrack-controller");
  Outbox commands(lcm, p.command_channel, log.get(), p.log_wait, auth.enabled() ? &*auth.commands : nullptr);
  Outbox diagnostics(lcm, p.diagnostics_channel, o.diagnostics ? log.get() : nullptr, p.log_wait);
  Outbox stats_outbox(lcm, p.stats_channel, log.get(), true);
  ControllerNode<M> node(tracking::make_controller<M>(spec, defaults), commands, o.diagnostics ? &diagnostics : nullptr);
  node.use_measured_delay(!spec.delay_configured);
  if (auth.enabled()) node.authenticate(*auth.states);
  lcm.subscribe(p.state_channel, &ControllerNode<M>::on_state, &node);
  std::printf("gausstrack-controller: ready (%s, %d coordinates, %d constraint rows, %s)\n", spec.model.c_str(),
              M::kDof, M::kConstraints, auth.enabled() ? "authenticated" : "unauthenticated");
  std::fflush(stdout);
  while (!g_stop_requested) node.serve(lcm, 100);

  const ControllerCounts& c = node.counts();
  loop_stats_t stats{};
  stats.utime = wall_us();
  stats.process = "controller";
  stats.commands_published = c.served;
  stats.commands_failed = c.failed;
  stats.runs = c.runs;
  stats.messages_rejected = c.rejected;
  stats.compute_ns_p50 = node.compute_ns().quantile(0.5);
  stats.compute_ns_p99 = node.compute_ns().quantile(0.99);
  stats.compute_ns_max = node.compute_ns().max();
  stats_outbox.publish_message(stats);
  const long log_dropped = close_message_log(log.get(), "gausstrack-controller", p.log_path);
  if (!o.stats_out.empty()) {
    try {
      write_controller_stats(o.stats_out, spec.model, c, log_dropped, node.compute_ns());
    } catch (const std::exception& e) {
      return std::fprintf(stderr, "error: %s\n", e.what()), 1;
    }
  }
  std::printf("gausstrack-controller: %ld commands published (%ld failed solves), %ld states superseded by a "
              "newer one, %ld plant runs, %ld messages rejected, compute p50 %.0f ns, p99 %.0f ns, max %.0f ns\n",
              c.served, c.failed, c.superseded, c.runs, c.rejected, stats.compute_ns_p50, stats.compute_ns_p99, stats.compute_ns_max);
  if (c.auth.total() > 0)
    std::printf("gausstrack-controller: %ld states failed authentication (%ld with another key or altered, %ld "
                "without a key, %ld replayed)%s\n", c.auth.total(), c.auth.bad_tag, c.auth.unauthenticated,
                c.auth.replayed, c.served == 0 ? ": no state verified, the plant must run with this key (--key)" : "");
  return 0;
}

/// The whole controller process for a user's model M, known to configurations as `name`.
template <Model M>
int controller_main(int argc, char** argv, const std::string& name, M defaults = {}) {
  ControllerProcessOptions o;
  if (const std::optional<int> code = parse_controller_options(argc, argv, o)) return *code;
  try {
    const tracking::TrackingSpec spec = tracking::load_tracking(o.process.scene_path, o.process.sets);
    if (spec.model != name)
      throw tracking::ConfigError(spec.where + ": this controller runs model '" + name + "', not '" + spec.model + "'");
    return run_controller<M>(o, spec, defaults);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}

}  // namespace gausstrack::nodes
