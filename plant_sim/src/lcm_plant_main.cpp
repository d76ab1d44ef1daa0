// gausstrack-plant --scene S [--lockstep] [--out DIR] [--set key=value ...] [--lcm-url URL]
//                  [--state-channel C] [--command-channel C] [--timeout-ms T]
//                  [--watchdog-ms W] [--safe-action zero|hold]
// Steps the scene's plant one control period at a time (sampled and held control) and publishes
// its state at the start of each period.
// Lock-step: waits for the command answering that state and applies it (deterministic; for
//   tests and accuracy studies).
// Real time (default): periods start on absolute deadlines (clock_nanosleep); the plant never
//   waits. At each period it applies the newest valid command received so far (zero-order hold;
//   the command answering state k is applied from period k + 1), counts deadline misses and
//   periods without a fresh command, and when no command has come for longer than the watchdog
//   time applies the safe action (zero force, or hold the last one) until commands return.
#include <lcm/lcm-cpp.hpp>

#include <time.h>

#include <array>
#include <csignal>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "gausstrack/control_command_t.hpp"
#include "gausstrack/plant_sim/scene.hpp"
#include "gausstrack/plant_sim/simulation.hpp"
#include "gausstrack/plant_state_t.hpp"

namespace {

using namespace gausstrack::plant_sim;

// Keeps valid commands: in lock-step the one answering the awaited state, in real time the newest
// one answering any state not newer than the last published. Everything else is counted and dropped.
class CommandInbox {
 public:
  explicit CommandInbox(int dimension) : dimension_(dimension) {}

  void await(std::int64_t sequence) {
    awaited_ = sequence;
    ready_ = false;
  }
  bool ready() const { return ready_; }
  const double* force() const { return latest_.force; }
  std::int64_t answered() const { return answered_; }
  long rejected() const { return rejected_; }
  void set_exact(bool exact) { exact_ = exact; }

  void on_command(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    if (incoming_.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) < 0 || incoming_.dimension != dimension_ ||
        incoming_.status != 0 || (exact_ ? incoming_.state_sequence != awaited_
                                         : incoming_.state_sequence > awaited_ || incoming_.state_sequence <= answered_)) {
      ++rejected_;
      return;
    }
    for (int i = 0; i < dimension_; ++i)
      if (!std::isfinite(incoming_.force[i])) {
        ++rejected_;
        return;
      }
    latest_ = incoming_;
    answered_ = incoming_.state_sequence;
    ready_ = true;
  }

 private:
  int dimension_;
  gausstrack::control_command_t incoming_{}, latest_{};
  std::int64_t awaited_ = -1, answered_ = -1;
  bool ready_ = false, exact_ = true;
  long rejected_ = 0;
};

volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }

timespec add_ns(timespec t, long ns) {
  t.tv_nsec += ns;
  while (t.tv_nsec >= 1000000000L) {
    t.tv_nsec -= 1000000000L;
    ++t.tv_sec;
  }
  return t;
}
long diff_ns(const timespec& a, const timespec& b) {
  return (a.tv_sec - b.tv_sec) * 1000000000L + (a.tv_nsec - b.tv_nsec);
}

}  // namespace

int main(int argc, char** argv) {
  std::string scene_path, url, out_dir = "out/plant", state_channel = "GAUSSTRACK_STATE",
                               command_channel = "GAUSSTRACK_COMMAND";
  std::vector<std::string> sets;
  bool lockstep = false, safe_hold = false;
  int timeout_ms = 2000, watchdog_ms = 50;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool has_value = i + 1 < argc;
    if (a == "--scene" && has_value) scene_path = argv[++i];
    else if (a == "--set" && has_value) sets.emplace_back(argv[++i]);
    else if (a == "--out" && has_value) out_dir = argv[++i];
    else if (a == "--lcm-url" && has_value) url = argv[++i];
    else if (a == "--state-channel" && has_value) state_channel = argv[++i];
    else if (a == "--command-channel" && has_value) command_channel = argv[++i];
    else if (a == "--timeout-ms" && has_value) timeout_ms = std::atoi(argv[++i]);
    else if (a == "--watchdog-ms" && has_value) watchdog_ms = std::atoi(argv[++i]);
    else if (a == "--safe-action" && has_value) {
      const std::string v = argv[++i];
      if (v != "zero" && v != "hold") return std::fprintf(stderr, "error: --safe-action is zero or hold\n"), 2;
      safe_hold = v == "hold";
    }
    else if (a == "--lockstep") lockstep = true;
    else {
      std::fprintf(stderr, "usage: %s --scene S --lockstep [--out DIR] [--set key=value ...] [--lcm-url URL] "
                           "[--state-channel C] [--command-channel C] [--timeout-ms T]\n", argv[0]);
      return 2;
    }
  }
  if (scene_path.empty()) return std::fprintf(stderr, "error: --scene is required\n"), 2;
  try {
    const Scene scene = load_scene(scene_path, sets);
    lcm::LCM lcm(url);
    if (!lcm.good()) return std::fprintf(stderr, "error: cannot open LCM (%s)\n", url.c_str()), 1;
    CommandInbox inbox(scene.dof());
    inbox.set_exact(lockstep);
    std::signal(SIGINT, on_signal);
    std::signal(SIGTERM, on_signal);
    const long period_ns = scene.control_mode == ControlMode::kSampled
                               ? static_cast<long>(std::llround(1e9 / scene.control_rate)) : 0;
    timespec start{}, deadline{};
    clock_gettime(CLOCK_MONOTONIC, &start);
    long deadline_misses = 0, applied = 0, watchdog_trips = 0, published = 0;
    bool in_watchdog = false;
    std::vector<double> hold;
    timespec last_command = start;
    std::int64_t last_answered = -1;
    lcm.subscribe(command_channel, &CommandInbox::on_command, &inbox);
    gausstrack::plant_state_t state{};
    std::array<std::uint8_t, 4096> buffer{};
    long missing = 0;

    RunOptions options;
    options.sampled_control = [&](std::int64_t period, double t, const std::vector<double>& q,
                                  const std::vector<double>& qd, std::vector<double>& u) {
      state = {};
      state.utime = std::chrono::duration_cast<std::chrono::microseconds>(
                        std::chrono::system_clock::now().time_since_epoch())
                        .count();
      state.sequence = period;
      state.t = t;
      state.dimension = scene.dof();
      for (int i = 0; i < scene.dof(); ++i) {
        state.q[i] = q[static_cast<std::size_t>(i)];
        state.qd[i] = qd[static_cast<std::size_t>(i)];
      }
      if (g_stop) return false;
      const int size = state.getEncodedSize();
      state.encode(buffer.data(), 0, size);
      if (!lockstep) {
        // Wake at the period's absolute deadline, take the newest command, publish the state.
        deadline = add_ns(start, period_ns * static_cast<long>(period));
        clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &deadline, nullptr);
        timespec now{};
        clock_gettime(CLOCK_MONOTONIC, &now);
        if (diff_ns(now, deadline) > period_ns / 2) ++deadline_misses;
        inbox.await(period - 1);
        while (lcm.handleTimeout(0) > 0) {
        }
        if (hold.empty()) hold.assign(u.size(), 0.0);
        if (inbox.answered() > last_answered) {
          last_answered = inbox.answered();
          last_command = now;
          ++applied;
          in_watchdog = false;
          for (std::size_t i = 0; i < u.size(); ++i) hold[i] = inbox.force()[i];
        } else {
          ++missing;
          if (!in_watchdog && diff_ns(now, last_command) > watchdog_ms * 1000000L) {
            in_watchdog = true;
            ++watchdog_trips;
          }
          if (in_watchdog && !safe_hold) std::fill(hold.begin(), hold.end(), 0.0);
        }
        u = hold;
        lcm.publish(state_channel, buffer.data(), static_cast<unsigned>(size));
        ++published;
        return true;
      }
      inbox.await(period);
      lcm.publish(state_channel, buffer.data(), static_cast<unsigned>(size));
      ++published;
      const auto deadline_wait = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
      while (!inbox.ready()) {
        if (g_stop) return false;
        const auto left =
            std::chrono::duration_cast<std::chrono::milliseconds>(deadline_wait - std::chrono::steady_clock::now());
        if (left.count() <= 0) {
          ++missing;
          std::fprintf(stderr, "error: no command answered state %lld within %d ms\n",
                       static_cast<long long>(period), timeout_ms);
          return false;
        }
        lcm.handleTimeout(static_cast<int>(left.count()));
      }
      for (int i = 0; i < scene.dof(); ++i) u[static_cast<std::size_t>(i)] = inbox.force()[i];
      ++applied;
      return true;
    };
    const RunResult result = run_scene(scene, options);
    std::filesystem::create_directories(out_dir);
    write_trajectory_csv(scene, result, out_dir + "/trajectory.csv");
    write_summary_json(scene, result, out_dir + "/summary.json");
    std::printf("gausstrack-plant: %zu samples, max tracking error %.3g, %ld states published, %ld commands "
                "applied, %ld missing, %ld deadline misses, %ld watchdog trips, %ld messages rejected -> %s\n",
                result.samples.size(), result.summary.max_tracking_error, published, applied, missing,
                deadline_misses, watchdog_trips, inbox.rejected(), out_dir.c_str());
    // Interrupted by a signal: the data up to then is written and the run counts as done.
    return result.summary.stopped_early && !g_stop ? 1 : 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
