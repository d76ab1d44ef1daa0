// The controller process's command line and statistics file, compiled once for every model.
#include "gausstrack/nodes/controller_process.hpp"

#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "cli.hpp"
#include "gausstrack/nodes/latency_json.hpp"

namespace gausstrack::nodes {

std::optional<int> parse_controller_options(int argc, char** argv, ControllerProcessOptions& o) {
  CLI::App app("Runs the tracking control law of eq. (32) for the model a configuration's tracking section "
               "names: answers each plant state with its command over LCM until SIGINT or SIGTERM.");
  add_process_options(app, o.process);
  app.add_flag("--diagnostics", o.diagnostics, "publish each command's solver diagnostics");
  app.add_option("--stats-out", o.stats_out, "write the counts and compute times as JSON to this file");
  return parse_command_line(app, argc, argv);
}

void write_controller_stats(const std::string& path, const std::string& model, const ControllerCounts& c,
                            long log_dropped, const LatencyRecorder& compute_ns) {
  const nlohmann::ordered_json j = {
      {"process", "controller"},        {"model", model},
      {"commands_published", c.served}, {"commands_failed", c.failed},
      {"commands_repeated", c.repeated}, {"states_superseded", c.superseded},
      {"largest_backlog", c.largest_backlog},
      {"states_duplicated", c.duplicates},
      {"runs", c.runs},
      {"messages_rejected", c.rejected}, {"rejected_malformed", c.malformed},
      {"rejected_dimension", c.wrong_dimension}, {"rejected_non_finite", c.non_finite},
      {"rejected_stale", c.stale},      {"rejected_unauthenticated", c.auth.unauthenticated},
      {"rejected_bad_tag", c.auth.bad_tag}, {"rejected_replayed", c.auth.replayed},
      {"log_dropped", log_dropped},
      {"compute_ns", percentiles_json(compute_ns)}};
  std::ofstream out(path);
  out << j.dump(2, ' ', false, nlohmann::ordered_json::error_handler_t::replace) << '\n';
  if (!out) throw std::runtime_error("cannot write " + path);
}

}  // namespace gausstrack::nodes
