// gausstrack-log-merge OUT IN... : merges LCM log files into one, ordered by event timestamp
// (stable: events with equal timestamps keep their file and in-file order). gausstrack-run uses it
// to join the plant's and the controller's own logs into the run's log. Exits 1 naming the file
// that cannot be read or written.
#include <lcm/lcm-cpp.hpp>


#include <algorithm>
#include <cstdio>
#include <cstdint>
#include <string>
#include <optional>
#include <vector>

#include "cli.hpp"

namespace {

struct Event {
  std::int64_t timestamp;
  std::string channel;
  std::vector<std::uint8_t> data;
};

}  // namespace

int main(int argc, char** argv) {
  std::string out_path;
  std::vector<std::string> in_paths;
  CLI::App app("Merges LCM log files into one, ordered by event timestamp (stable).");
  app.add_option("out", out_path, "the merged log")->required();
  app.add_option("in", in_paths, "the logs to merge")->required();
  if (const std::optional<int> code = gausstrack::nodes::parse_command_line(app, argc, argv)) return *code;
  std::vector<Event> events;
  for (const std::string& path : in_paths) {
    lcm::LogFile in(path, "r");
    if (!in.good()) return std::fprintf(stderr, "gausstrack-log-merge: cannot read %s\n", path.c_str()), 1;
    while (const lcm::LogEvent* e = in.readNextEvent()) {
      const auto* bytes = static_cast<const std::uint8_t*>(e->data);
      events.push_back({e->timestamp, e->channel, std::vector<std::uint8_t>(bytes, bytes + e->datalen)});
    }
  }
  std::stable_sort(events.begin(), events.end(),
                   [](const Event& a, const Event& b) { return a.timestamp < b.timestamp; });
  lcm::LogFile out(out_path, "w");
  if (!out.good()) return std::fprintf(stderr, "gausstrack-log-merge: cannot write %s\n", out_path.c_str()), 1;
  for (Event& e : events) {
    lcm::LogEvent event{};
    event.timestamp = e.timestamp;
    event.channel = e.channel;
    event.datalen = static_cast<std::int32_t>(e.data.size());
    event.data = e.data.data();
    if (out.writeEvent(&event) != 0)
      return std::fprintf(stderr, "gausstrack-log-merge: cannot write %s\n", out_path.c_str()), 1;
  }
  std::printf("gausstrack-log-merge: %zu events from %zu files -> %s\n", events.size(), in_paths.size(),
              out_path.c_str());
  return 0;
}
