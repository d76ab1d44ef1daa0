// What the LCM processes (gausstrack-plant, gausstrack-controller) share: their common command-line
// options (parsed in src/cli.hpp), the optional real-time setup (SCHED_FIFO, CPU pinning,
// mlockall), the stop request and clocks.
#pragma once

#include <sched.h>
#include <sys/mman.h>
#include <time.h>

#include <algorithm>
#include <cerrno>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <string>
#include <vector>

#include "gausstrack/nodes/auth.hpp"
#include "gausstrack/tracking/stop_request.hpp"

namespace gausstrack::nodes {

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
  std::string key_path;       ///< the pair's key file (gausstrack-keygen); empty: unauthenticated
};

/// The authentication of the state and command channels with the pair's key (--key), or none.
struct PairAuth {
  std::optional<ChannelAuth> states, commands;
  bool enabled() const noexcept { return states.has_value(); }
};

/// Reads the key named by --key; without one, says at start-up that anyone who can reach the LCM
/// group can command the plant. Throws std::runtime_error when the key file cannot be used.
inline PairAuth open_pair_auth(const ProcessOptions& o, const char* program) {
  PairAuth auth;
  if (o.key_path.empty()) {
    std::fprintf(stderr, "%s: warning: no key (--key FILE): messages are not authenticated, and anyone who can "
                         "reach this LCM group can command the plant\n", program);
    return auth;
  }
  const MessageKey key = MessageKey::load(o.key_path);
  auth.states.emplace(key, o.state_channel);
  auth.commands.emplace(key, o.command_channel);
  return auth;
}

/// SCHED_FIFO at `priority` for the calling thread; where the system does not permit it, a warning
/// on stderr and the thread keeps its scheduler.
inline void set_fifo_priority(int priority, const char* program) {
  sched_param p{};
  p.sched_priority = priority;
  if (sched_setscheduler(0, SCHED_FIFO, &p) != 0)
    std::fprintf(stderr, "%s: warning: SCHED_FIFO priority %d not permitted (%s); running under the default "
                         "scheduler\n", program, priority, std::strerror(errno));
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
  if (o.rt_priority > 0) set_fifo_priority(o.rt_priority, program);
}

/// Raises the calling thread (a loop woken by a clock: the plant's) one SCHED_FIFO priority above
/// the one apply_realtime gave the process. Called once the LCM subscriptions exist, and so LCM's
/// receive thread (created by the first subscription, inheriting apply_realtime's priority) stays
/// one below: under SCHED_FIFO threads of one priority do not preempt each other, so the loop's
/// timed wake-up would otherwise wait whenever it lands while the receive thread is taking a
/// message off the socket. With the loop above it, the wake-up preempts the receive thread, which
/// only queues messages for the loop. A loop woken by the receive thread's messages (the
/// controller's) stays at its priority: above it, it would preempt the receive thread in the middle
/// of the hand-over and then wait for it. Does nothing without --rt-priority; what is not
/// permitted is a warning, as in apply_realtime.
inline void raise_loop_above_receiver(const ProcessOptions& o, const char* program) {
  if (o.rt_priority <= 0) return;
  set_fifo_priority(std::min(o.rt_priority + 1, sched_get_priority_max(SCHED_FIFO)), program);
}

}  // namespace gausstrack::nodes
