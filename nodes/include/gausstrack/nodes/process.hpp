// What the LCM processes (gausstrack-plant, gausstrack-controller) share: their common command-line
// options, the optional real-time setup (SCHED_FIFO, CPU pinning, mlockall) and clocks.
#pragma once

#include <sched.h>
#include <sys/mman.h>
#include <time.h>

#include <cerrno>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

namespace gausstrack::nodes {

inline volatile std::sig_atomic_t g_stop_requested = 0;

/// SIGINT and SIGTERM ask the loop to stop; the process then writes its statistics and exits.
inline void stop_on_signals() {
  auto handler = [](int) { g_stop_requested = 1; };
  std::signal(SIGINT, handler);
  std::signal(SIGTERM, handler);
}

/// CLOCK_MONOTONIC [ns].
inline std::int64_t monotonic_ns() {
  timespec t{};
  clock_gettime(CLOCK_MONOTONIC, &t);
  return static_cast<std::int64_t>(t.tv_sec) * 1000000000LL + t.tv_nsec;
}

/// Wall clock [us since the Unix epoch], for the messages' utime.
inline std::int64_t wall_us() {
  timespec t{};
  clock_gettime(CLOCK_REALTIME, &t);
  return static_cast<std::int64_t>(t.tv_sec) * 1000000LL + t.tv_nsec / 1000;
}

inline timespec to_timespec(std::int64_t ns) {
  return {static_cast<time_t>(ns / 1000000000LL), static_cast<long>(ns % 1000000000LL)};
}

struct ProcessOptions {
  std::string scene_path;           ///< --scene (the plant's scene; the controller's --config)
  std::vector<std::string> sets;  ///< scene overrides, key=value
  std::string lcm_url;            ///< empty: LCM_DEFAULT_URL, else LCM's own default
  std::string state_channel = "GAUSSTRACK_STATE";
  std::string command_channel = "GAUSSTRACK_COMMAND";
  std::string stats_channel = "GAUSSTRACK_STATS";
  std::string diagnostics_channel = "GAUSSTRACK_DIAGNOSTICS";
  int rt_priority = 0;        ///< SCHED_FIFO priority; 0 keeps the default scheduler
  int cpu = -1;               ///< pin to this CPU; -1 leaves affinity alone
  bool lock_memory = false;   ///< mlockall(MCL_CURRENT | MCL_FUTURE)
  std::string log_path;       ///< record every message this process publishes (MessageLog)
  bool log_wait = false;      ///< when the log's buffer is full, wait rather than drop (lock-step)
};

inline constexpr const char* kCommonUsage =
    "--scene S [--set key=value ...] [--lcm-url URL] [--state-channel C] [--command-channel C] "
    "[--stats-channel C] [--diagnostics-channel C] [--rt-priority P] [--cpu K] [--lock-memory] [--log FILE [--log-wait]]";

/// Consumes argv[i] (and its value) if it is a common option. Returns false if it is not one;
/// a common option with a missing or malformed value sets `error`.
inline bool parse_common_option(int argc, char** argv, int& i, ProcessOptions& o, std::string& error) {
  const std::string a = argv[i];
  if (a == "--lock-memory") return o.lock_memory = true;
  if (a == "--log-wait") return o.log_wait = true;
  const bool takes_value = a == "--scene" || a == "--config" || a == "--diagnostics-channel" || a == "--set" || a == "--lcm-url" || a == "--state-channel" ||
                           a == "--command-channel" || a == "--stats-channel" || a == "--rt-priority" ||
                           a == "--cpu" || a == "--log";
  if (!takes_value) return false;
  if (i + 1 >= argc) {
    error = a + " needs a value";
    return true;
  }
  const std::string v = argv[++i];
  auto integer = [&](int lo, int hi, int& out) {
    char* end = nullptr;
    errno = 0;
    const long x = std::strtol(v.c_str(), &end, 10);
    if (errno != 0 || end == v.c_str() || *end != '\0' || x < lo || x > hi)
      error = a + " takes an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got '" + v + "'";
    else
      out = static_cast<int>(x);
  };
  if (a == "--scene" || a == "--config") o.scene_path = v;
  else if (a == "--diagnostics-channel") o.diagnostics_channel = v;
  else if (a == "--set") o.sets.push_back(v);
  else if (a == "--lcm-url") o.lcm_url = v;
  else if (a == "--state-channel") o.state_channel = v;
  else if (a == "--command-channel") o.command_channel = v;
  else if (a == "--stats-channel") o.stats_channel = v;
  else if (a == "--log") o.log_path = v;
  else if (a == "--rt-priority") integer(1, 99, o.rt_priority);
  else integer(0, 1023, o.cpu);
  return true;
}

/// Applies the real-time options asked for to the calling thread and to the threads it creates
/// afterwards (they inherit the policy and the CPU). The processes call it after opening their
/// message log (its writer stays an ordinary thread: it may be late, the log then drops and counts)
/// and before creating the lcm::LCM, whose receive thread hands every incoming message to the loop
/// and so must not wait behind ordinary threads for a CPU. What the system does not permit (no
/// CAP_SYS_NICE, RLIMIT_MEMLOCK, a missing CPU) is a warning on stderr, not a failure: the loop
/// still runs, only with worse wake-up latency.
inline void apply_realtime(const ProcessOptions& o, const char* program) {
  if (o.lock_memory && mlockall(MCL_CURRENT | MCL_FUTURE) != 0)
    std::fprintf(stderr, "%s: warning: mlockall not permitted (%s); memory may page\n", program,
                 std::strerror(errno));
  if (o.cpu >= 0) {
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(o.cpu, &set);
    if (sched_setaffinity(0, sizeof set, &set) != 0)
      std::fprintf(stderr, "%s: warning: cannot pin to CPU %d (%s)\n", program, o.cpu, std::strerror(errno));
  }
  if (o.rt_priority > 0) {
    sched_param p{};
    p.sched_priority = o.rt_priority;
    if (sched_setscheduler(0, SCHED_FIFO, &p) != 0)
      std::fprintf(stderr, "%s: warning: SCHED_FIFO priority %d not permitted (%s); running under the default "
                           "scheduler\n", program, o.rt_priority, std::strerror(errno));
  }
}

}  // namespace gausstrack::nodes
