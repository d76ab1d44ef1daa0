// gausstrack-plant --scene S [common options] [--lockstep] [--out DIR] [--timeout-ms T]
//                  [--watchdog-ms W] [--safe-action zero|hold]
// Steps the scene's plant one control period at a time (sampled and held control) and publishes
// its state at the start of each period.
// Lock-step: waits for the command answering that state and applies it (deterministic; for
//   tests and accuracy studies).
// Real time (default): periods start on absolute deadlines (clock_nanosleep); the plant never
//   waits for a command. Between deadlines it services LCM, so each command is timestamped when it
//   arrives. At each period it applies the newest valid command received so far (zero-order
//   hold; the command answering state k is applied from period k + 1), counts deadline misses and
//   periods without a fresh command, and when no command has come for longer than the watchdog
//   time applies the safe action (zero force, or hold the last one) until commands return.
// Writes DIR/trajectory.csv, DIR/summary.json (the run and its loop statistics) and
// DIR/latency.csv (one row per command received), and publishes its loop_stats_t when it stops.
#include <lcm/lcm-cpp.hpp>
#include <poll.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "gausstrack/control_command_t.hpp"
#include "gausstrack/loop_stats_t.hpp"
#include "gausstrack/plant_sim/latency_recorder.hpp"
#include "gausstrack/plant_sim/scene.hpp"
#include "gausstrack/plant_sim/simulation.hpp"
#include "gausstrack/plant_state_t.hpp"
#include "message_log.hpp"
#include "process.hpp"

namespace {

using namespace gausstrack::plant_sim;

// Keeps valid commands: in lock-step the one answering the awaited state, in real time the newest
// one answering a published state not yet answered. Everything else is counted and dropped. Each
// accepted command's round trip (state published to command received, both on this process's
// monotonic clock) and the compute time it reports are recorded.
class CommandInbox {
 public:
  CommandInbox(int dimension, std::size_t periods)
      : dimension_(dimension), round_trip_us_(periods), compute_ns_(periods), sequences_(periods) {}

  void await(std::int64_t sequence) {
    awaited_ = sequence;
    ready_ = false;
  }
  void published(std::int64_t sequence, std::int64_t when_ns) {
    published_at_[static_cast<std::size_t>(sequence) % published_at_.size()] = when_ns;
    last_published_ = sequence;
  }
  bool ready() const { return ready_; }
  const double* force() const { return latest_.force; }
  std::int64_t answered() const { return answered_; }
  long rejected() const { return rejected_; }
  long late() const { return late_; }
  void set_exact(bool exact) { exact_ = exact; }
  const LatencyRecorder& round_trip_us() const { return round_trip_us_; }
  const LatencyRecorder& compute_ns() const { return compute_ns_; }
  const LatencyRecorder& sequences() const { return sequences_; }

  void on_command(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    const std::int64_t received = monotonic_ns();
    if (incoming_.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) < 0 || incoming_.dimension != dimension_ ||
        incoming_.status != 0 || incoming_.state_sequence > last_published_ || incoming_.state_sequence <= answered_ ||
        (exact_ && incoming_.state_sequence != awaited_) ||
        incoming_.state_sequence <= last_published_ - static_cast<std::int64_t>(published_at_.size())) {
      ++rejected_;
      return;
    }
    for (int i = 0; i < dimension_; ++i)
      if (!std::isfinite(incoming_.force[i])) {
        ++rejected_;
        return;
      }
    // In real time the command for state k belongs to period k; one arriving after a newer state
    // went out is late (it is still the newest and is applied).
    if (incoming_.state_sequence < last_published_) ++late_;
    const std::int64_t sent = published_at_[static_cast<std::size_t>(incoming_.state_sequence) % published_at_.size()];
    round_trip_us_.add(static_cast<double>(received - sent) * 1e-3);
    compute_ns_.add(static_cast<double>(incoming_.compute_ns));
    sequences_.add(static_cast<double>(incoming_.state_sequence));
    latest_ = incoming_;
    answered_ = incoming_.state_sequence;
    ready_ = true;
  }

 private:
  int dimension_;
  gausstrack::control_command_t incoming_{}, latest_{};
  std::array<std::int64_t, 4096> published_at_{};
  std::int64_t awaited_ = -1, answered_ = -1, last_published_ = -1;
  bool ready_ = false, exact_ = true;
  long rejected_ = 0, late_ = 0;
  LatencyRecorder round_trip_us_, compute_ns_, sequences_;
};

// Services LCM until `deadline_ns` (monotonic) or until `done()`: waits on LCM's socket and
// dispatches whatever arrives, so that commands are timestamped on arrival rather than at the
// next period.
template <typename Done>
void service_until(lcm::LCM& lcm, std::int64_t deadline_ns, Done&& done) {
  pollfd fd{lcm.getFileno(), POLLIN, 0};
  for (;;) {
    const std::int64_t left = deadline_ns - monotonic_ns();
    if (done()) return;
    if (left <= 0) return;
    const timespec timeout = to_timespec(left);
    const int ready = ppoll(&fd, 1, &timeout, nullptr);
    if (ready > 0) lcm.handle();
    else if (ready == 0 || g_stop_requested) return;
  }
}

int usage(const char* argv0) {
  std::fprintf(stderr,
               "usage: %s %s [--lockstep] [--out DIR] [--timeout-ms T] [--watchdog-ms W] "
               "[--safe-action zero|hold]\n", argv0, kCommonUsage);
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  ProcessOptions options;
  std::string out_dir = "out/plant", error;
  bool lockstep = false, safe_hold = false;
  int timeout_ms = 2000, watchdog_ms = 50;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool has_value = i + 1 < argc;
    if (parse_common_option(argc, argv, i, options, error)) {
      if (!error.empty()) return std::fprintf(stderr, "error: %s\n", error.c_str()), 2;
    } else if (a == "--out" && has_value) {
      out_dir = argv[++i];
    } else if ((a == "--timeout-ms" || a == "--watchdog-ms") && has_value) {
      const int v = std::atoi(argv[++i]);
      if (v <= 0) return std::fprintf(stderr, "error: %s takes a positive number of ms\n", a.c_str()), 2;
      (a == "--timeout-ms" ? timeout_ms : watchdog_ms) = v;
    } else if (a == "--safe-action" && has_value) {
      const std::string v = argv[++i];
      if (v != "zero" && v != "hold") return std::fprintf(stderr, "error: --safe-action is zero or hold\n"), 2;
      safe_hold = v == "hold";
    } else if (a == "--lockstep") {
      lockstep = true;
    } else {
      return usage(argv[0]);
    }
  }
  if (options.scene_path.empty()) return std::fprintf(stderr, "error: --scene is required\n"), usage(argv[0]);
  try {
    const Scene scene = load_scene(options.scene_path, options.sets);
    if (scene.control_mode != ControlMode::kSampled)
      throw SceneError(options.scene_path + ": the plant process needs control.mode: sampled (add --set "
                                            "control.mode=sampled --set control.rate=HZ)");
    lcm::LCM lcm(options.lcm_url);
    if (!lcm.good()) return std::fprintf(stderr, "error: cannot open LCM (%s)\n", options.lcm_url.c_str()), 1;
    const int n = scene.dof();
    const auto periods = static_cast<std::size_t>(std::ceil(scene.duration * scene.control_rate)) + 16;
    CommandInbox inbox(n, periods);
    inbox.set_exact(lockstep);
    lcm.subscribe(options.command_channel, &CommandInbox::on_command, &inbox);
    // Lock-step is not real time: its log waits for the disk rather than drop a message.
    const auto log = open_message_log(options.log_path);
    Outbox state_out(lcm, options.state_channel, log.get(), lockstep || options.log_wait);
    Outbox stats_out(lcm, options.stats_channel, log.get(), true);
    stop_on_signals();
    apply_realtime(options, "gausstrack-plant");

    const auto period_ns = static_cast<std::int64_t>(std::llround(1e9 / scene.control_rate));
    const std::int64_t start = monotonic_ns();
    long deadline_misses = 0, applied = 0, missing = 0, watchdog_trips = 0, published = 0;
    bool in_watchdog = false;
    std::int64_t last_command_ns = start, last_applied = -1;
    std::array<double, gausstrack::plant_state_t::MAX_DIMENSION> hold{};
    LatencyRecorder wake_late_us(periods);
    gausstrack::plant_state_t state{};
    std::array<std::uint8_t, 4096> buffer{};

    RunOptions run_options;
    run_options.on_progress = terminal_progress(scene);
    run_options.sampled_control = [&](std::int64_t period, double t, std::span<const double> q,
                                      std::span<const double> qd, std::span<double> u) {
      if (g_stop_requested) return false;
      state = {};
      state.sequence = period;
      state.t = t;
      state.dimension = n;
      for (int i = 0; i < n; ++i) {
        state.q[i] = q[static_cast<std::size_t>(i)];
        state.qd[i] = qd[static_cast<std::size_t>(i)];
      }
      auto publish_state = [&] {
        state.utime = wall_us();
        const int size = state.getEncodedSize();
        state.encode(buffer.data(), 0, size);
        inbox.published(period, monotonic_ns());
        state_out.publish(buffer.data(), static_cast<std::size_t>(size), state.utime);
        ++published;
      };
      if (!lockstep) {
        // Until this period's absolute deadline take commands as they come; then wake exactly
        // at it, apply the newest command and publish the state.
        const std::int64_t deadline = start + period_ns * period;
        service_until(lcm, deadline, [] { return false; });
        const timespec wake = to_timespec(deadline);
        clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &wake, nullptr);
        const std::int64_t now = monotonic_ns();
        wake_late_us.add(static_cast<double>(now - deadline) * 1e-3);
        if (now - deadline > period_ns / 2) ++deadline_misses;
        while (lcm.handleTimeout(0) > 0) {
        }
        if (inbox.answered() > last_applied) {
          last_applied = inbox.answered();
          last_command_ns = now;
          ++applied;
          in_watchdog = false;
          std::copy(inbox.force(), inbox.force() + n, hold.begin());
        } else {
          ++missing;
          if (!in_watchdog && now - last_command_ns > static_cast<std::int64_t>(watchdog_ms) * 1000000) {
            in_watchdog = true;
            ++watchdog_trips;
          }
          if (in_watchdog && !safe_hold) hold.fill(0.0);
        }
        std::copy(hold.begin(), hold.begin() + n, u.begin());
        inbox.await(period);
        publish_state();
        return true;
      }
      inbox.await(period);
      publish_state();
      const std::int64_t give_up = monotonic_ns() + static_cast<std::int64_t>(timeout_ms) * 1000000;
      service_until(lcm, give_up, [&] { return inbox.ready() || g_stop_requested; });
      if (g_stop_requested) return false;
      if (!inbox.ready()) {
        ++missing;
        std::fprintf(stderr, "error: no command answered state %lld within %d ms\n", static_cast<long long>(period),
                     timeout_ms);
        return false;
      }
      std::copy(inbox.force(), inbox.force() + n, u.begin());
      ++applied;
      return true;
    };
    const RunResult result = run_scene(scene, run_options);

    gausstrack::loop_stats_t stats{};
    stats.utime = wall_us();
    stats.process = "plant";
    stats.states_published = published;
    stats.commands_applied = applied;
    stats.commands_missing = missing;
    stats.commands_late = inbox.late();
    stats.deadline_misses = deadline_misses;
    stats.messages_rejected = inbox.rejected();
    stats.watchdog_trips = static_cast<int32_t>(watchdog_trips);
    stats.round_trip_us_p50 = inbox.round_trip_us().quantile(0.5);
    stats.round_trip_us_p99 = inbox.round_trip_us().quantile(0.99);
    stats.round_trip_us_p999 = inbox.round_trip_us().quantile(0.999);
    stats.round_trip_us_max = inbox.round_trip_us().max();
    stats.compute_ns_p50 = inbox.compute_ns().quantile(0.5);
    stats.compute_ns_p99 = inbox.compute_ns().quantile(0.99);
    stats.compute_ns_max = inbox.compute_ns().max();
    stats.wake_late_us_p99 = wake_late_us.quantile(0.99);
    stats.wake_late_us_max = wake_late_us.max();
    stats_out.publish_message(stats);
    const long log_dropped = close_message_log(log.get(), "gausstrack-plant", options.log_path);

    std::filesystem::create_directories(out_dir);
    write_trajectory_csv(scene, result, out_dir + "/trajectory.csv");
    const std::string loop =
        "\"mode\": \"" + std::string(lockstep ? "lockstep" : "realtime") + "\", \"control_rate_hz\": " +
        std::to_string(scene.control_rate) + ", \"states_published\": " + std::to_string(published) +
        ", \"commands_applied\": " + std::to_string(applied) + ", \"commands_missing\": " + std::to_string(missing) +
        ", \"commands_late\": " + std::to_string(inbox.late()) + ", \"deadline_misses\": " +
        std::to_string(deadline_misses) + ", \"messages_rejected\": " + std::to_string(inbox.rejected()) +
        ", \"watchdog_trips\": " + std::to_string(watchdog_trips) +
        ", \"log_dropped\": " + std::to_string(log_dropped) + ",\n  " + inbox.round_trip_us().json("round_trip_us") +
        ",\n  " + inbox.compute_ns().json("compute_ns") + ",\n  " +
        (lockstep ? std::string("\"wake_late_us\": null") : wake_late_us.json("wake_late_us"));
    write_summary_json(scene, result, out_dir + "/summary.json", loop);
    {
      std::ofstream csv(out_dir + "/latency.csv");
      csv << "state_sequence,round_trip_us,compute_ns\n";
      const auto& seq = inbox.sequences().values();
      for (std::size_t k = 0; k < seq.size(); ++k)
        csv << static_cast<long long>(seq[k]) << ',' << inbox.round_trip_us().values()[k] << ','
            << inbox.compute_ns().values()[k] << '\n';
      if (!csv) throw std::runtime_error("cannot write " + out_dir + "/latency.csv");
    }
    std::printf("gausstrack-plant: %zu samples, max tracking error %.3g, %ld states published, %ld commands "
                "applied, %ld missing, %ld late, %ld deadline misses, %ld watchdog trips, %ld messages rejected, "
                "round trip p50 %.1f us p99 %.1f us max %.1f us -> %s\n",
                result.samples.size(), result.summary.max_tracking_error, published, applied, missing, inbox.late(),
                deadline_misses, watchdog_trips, inbox.rejected(), stats.round_trip_us_p50, stats.round_trip_us_p99,
                stats.round_trip_us_max, out_dir.c_str());
    if (!result.summary.failure.empty()) {
      std::fprintf(stderr, "error: %s (data up to then written to %s)\n", result.summary.failure.c_str(),
                   out_dir.c_str());
      return 1;
    }
    // Interrupted by a signal: the data up to then is written and the run counts as done.
    return result.summary.stopped_early && !g_stop_requested ? 1 : 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
