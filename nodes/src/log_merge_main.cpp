// gausstrack-log-merge OUT IN... : merges LCM log files into one, ordered by event timestamp
// (stable: events with equal timestamps keep their file and in-file order). gausstrack-run uses it
// to join the plant's and the controller's own logs into the run's log. Exits 1 naming the file
// that cannot be read or written.
#include <lcm/lcm-cpp.hpp>

#include <algorithm>
#include <cstdio>
#include <cstdint>
#include <string>
#include <vector>

namespace {

struct Event {
  std::int64_t timestamp;
  std::string channel;
  std::vector<std::uint8_t> data;
};

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) return std::fprintf(stderr, "usage: %s OUT IN...\n", argv[0]), 2;
  std::vector<Event> events;
  for (int i = 2; i < argc; ++i) {
    lcm::LogFile in(argv[i], "r");
    if (!in.good()) return std::fprintf(stderr, "gausstrack-log-merge: cannot read %s\n", argv[i]), 1;
    while (const lcm::LogEvent* e = in.readNextEvent()) {
      const auto* bytes = static_cast<const std::uint8_t*>(e->data);
      events.push_back({e->timestamp, e->channel, std::vector<std::uint8_t>(bytes, bytes + e->datalen)});
    }
  }
  std::stable_sort(events.begin(), events.end(),
                   [](const Event& a, const Event& b) { return a.timestamp < b.timestamp; });
  lcm::LogFile out(argv[1], "w");
  if (!out.good()) return std::fprintf(stderr, "gausstrack-log-merge: cannot write %s\n", argv[1]), 1;
  for (Event& e : events) {
    lcm::LogEvent event{};
    event.timestamp = e.timestamp;
    event.channel = e.channel;
    event.datalen = static_cast<std::int32_t>(e.data.size());
    event.data = e.data.data();
    if (out.writeEvent(&event) != 0)
      return std::fprintf(stderr, "gausstrack-log-merge: cannot write %s\n", argv[1]), 1;
  }
  std::printf("gausstrack-log-merge: %zu events from %d files -> %s\n", events.size(), argc - 2, argv[1]);
  return 0;
}
