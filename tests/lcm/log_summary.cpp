// log_summary FILE: reads an LCM log and prints, per channel, "channel NAME COUNT", and for each
// gausstrack::loop_stats_t found, "stats PROCESS states_published=.. commands_applied=..
// commands_published=.. messages_rejected=..". Exits 1 if the file cannot be read.
#include <lcm/lcm-cpp.hpp>

#include <cstdio>
#include <map>
#include <string>

#include "gausstrack/nodes/codec.hpp"

int main(int argc, char** argv) {
  if (argc != 2) return std::fprintf(stderr, "usage: %s FILE\n", argv[0]), 2;
  lcm::LogFile log(argv[1], "r");
  if (!log.good()) return std::fprintf(stderr, "error: cannot read %s\n", argv[1]), 1;
  std::map<std::string, long> counts;
  while (const lcm::LogEvent* e = log.readNextEvent()) {
    ++counts[e->channel];
    gausstrack::loop_stats_t stats;
    if (e->channel.size() > 6 && e->channel.compare(e->channel.size() - 6, 6, "_STATS") == 0 &&
        gausstrack::nodes::decode_loop_stats(e->data, static_cast<std::size_t>(e->datalen), stats))
      std::printf("stats %s states_published=%lld commands_applied=%lld commands_published=%lld "
                  "messages_rejected=%lld\n",
                  stats.process.c_str(), static_cast<long long>(stats.states_published),
                  static_cast<long long>(stats.commands_applied), static_cast<long long>(stats.commands_published),
                  static_cast<long long>(stats.messages_rejected));
  }
  for (const auto& [channel, count] : counts) std::printf("channel %s %ld\n", channel.c_str(), count);
  return 0;
}
