// The processes' command lines (internal to the node library): the options every process takes,
// and parsing with CLI11 so that a bad command line is a usage error (exit 2) and --help exits 0.
#pragma once

#include <CLI/CLI.hpp>

#include <optional>

#include "gausstrack/nodes/process.hpp"

namespace gausstrack::nodes {

/// The options of ProcessOptions: --scene (or --config), --set, LCM's URL and channels, the
/// real-time options and the message log.
inline void add_process_options(CLI::App& app, ProcessOptions& o) {
  app.add_option("--scene,--config", o.scene_path, "the scene (plant) or the file holding the tracking section")
      ->required();
  app.add_option("--set", o.sets, "override a key of the file: dotted.key=value (repeatable)")
      ->allow_extra_args(false);
  app.add_option("--lcm-url", o.lcm_url, "LCM's URL (default: LCM_DEFAULT_URL, else LCM's own)");
  app.add_option("--state-channel", o.state_channel)->capture_default_str();
  app.add_option("--command-channel", o.command_channel)->capture_default_str();
  app.add_option("--stats-channel", o.stats_channel)->capture_default_str();
  app.add_option("--diagnostics-channel", o.diagnostics_channel)->capture_default_str();
  app.add_option("--rt-priority", o.rt_priority, "run the loop under SCHED_FIFO at this priority")
      ->check(CLI::Range(1, 99));
  app.add_option("--cpu", o.cpu, "pin the process to this CPU")->check(CLI::Range(0, 1023));
  app.add_flag("--lock-memory", o.lock_memory, "mlockall: keep the process's memory resident");
  app.add_option("--key", o.key_path, "the pair's key file (gausstrack-keygen): sign what this process sends, "
                                      "accept only what the other signed")
      ->check(CLI::ExistingFile);
  auto* log = app.add_option("--log", o.log_path, "record every message this process publishes (LCM log)");
  app.add_flag("--log-wait", o.log_wait, "when the log's buffer is full, wait rather than drop")->needs(log);
}

/// Parses argv into the options added to app. Nothing to go on; else the exit code: 0 after
/// --help, 2 after a usage error (printed with the usage).
inline std::optional<int> parse_command_line(CLI::App& app, int argc, char** argv) {
  try {
    app.parse(argc, argv);
    return std::nullopt;
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
}

}  // namespace gausstrack::nodes
