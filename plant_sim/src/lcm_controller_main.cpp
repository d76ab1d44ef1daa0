// gausstrack-controller --scene S [common options] [--stats-out FILE]
// Subscribes to plant states, evaluates the scene's tracking controller for each valid one and
// publishes the command at once. Messages that do not decode, have the wrong dimension,
// non-finite values or an old sequence number are counted and ignored. Prints
// "gausstrack-controller: ready" once subscribed; on SIGINT/SIGTERM publishes its loop_stats_t,
// writes FILE (JSON) if asked and prints its counts.
//
// The compute path (decode into a preallocated message, the allocation-free control law, encode
// into a fixed buffer, publish the bytes) allocates nothing: LCM's typed publish would.
#include <lcm/lcm-cpp.hpp>

#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

#include "gausstrack/control_command_t.hpp"
#include "gausstrack/loop_stats_t.hpp"
#include "gausstrack/plant_sim/latency_recorder.hpp"
#include "gausstrack/plant_sim/scene.hpp"
#include "gausstrack/plant_sim/scene_controller.hpp"
#include "gausstrack/plant_state_t.hpp"
#include "message_log.hpp"
#include "process.hpp"

namespace {

using namespace gausstrack::plant_sim;

class ControllerNode {
 public:
  /// `periods`: how many compute times to keep for the percentiles (later ones are counted only).
  ControllerNode(Outbox& commands, SceneController controller, std::size_t periods)
      : commands_(commands), controller_(std::move(controller)), compute_ns_(periods) {}

  void on_state(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    if (state_.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) < 0 || !valid(state_)) {
      ++rejected_;
      return;
    }
    last_sequence_ = state_.sequence;
    const std::int64_t start = monotonic_ns();
    const auto status = controller_.compute(Eigen::Map<const Eigen::Vector2d>(state_.q),
                                            Eigen::Map<const Eigen::Vector2d>(state_.qd), state_.t, out_);
    const std::int64_t compute_ns = monotonic_ns() - start;
    compute_ns_.add(static_cast<double>(compute_ns));
    command_ = {};
    command_.utime = wall_us();
    command_.sequence = ++published_;
    command_.state_sequence = state_.sequence;
    command_.dimension = 2;
    for (int i = 0; i < 2; ++i) {
      command_.force[i] = out_.force(i);
      command_.closed_loop[i] = out_.closed_loop(i);
      command_.feedforward[i] = out_.feedforward(i);
      command_.stabilizing[i] = out_.stabilizing(i);
    }
    command_.status = static_cast<int32_t>(status);
    command_.warnings = static_cast<int32_t>(out_.diagnostics.warnings);
    command_.compute_ns = compute_ns;
    const int size = command_.getEncodedSize();
    if (size > static_cast<int>(buffer_.size()) || command_.encode(buffer_.data(), 0, size) != size) return;
    commands_.publish(buffer_.data(), static_cast<std::size_t>(size), command_.utime);
  }

  long rejected() const { return rejected_; }
  long published() const { return published_; }
  const LatencyRecorder& compute_ns() const { return compute_ns_; }

 private:
  bool valid(const gausstrack::plant_state_t& s) const {
    if (s.dimension != 2 || s.sequence <= last_sequence_ || !std::isfinite(s.t)) return false;
    for (int i = 0; i < 2; ++i)
      if (!std::isfinite(s.q[i]) || !std::isfinite(s.qd[i])) return false;
    return true;
  }

  Outbox& commands_;
  SceneController controller_;
  SceneController::Output out_;
  gausstrack::plant_state_t state_{};
  gausstrack::control_command_t command_{};
  std::array<std::uint8_t, 4096> buffer_{};
  std::int64_t last_sequence_ = -1;
  long rejected_ = 0;
  long published_ = 0;
  LatencyRecorder compute_ns_;
};

int usage(const char* argv0) {
  std::fprintf(stderr, "usage: %s %s [--stats-out FILE]\n", argv0, kCommonUsage);
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  ProcessOptions options;
  std::string stats_out, error;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (parse_common_option(argc, argv, i, options, error)) {
      if (!error.empty()) return std::fprintf(stderr, "error: %s\n", error.c_str()), 2;
    } else if (a == "--stats-out" && i + 1 < argc) {
      stats_out = argv[++i];
    } else {
      return usage(argv[0]);
    }
  }
  if (options.scene_path.empty()) return std::fprintf(stderr, "error: --scene is required\n"), usage(argv[0]);
  try {
    const Scene scene = load_scene(options.scene_path, options.sets);
    if (!scene.tracking.enabled)
      throw SceneError(options.scene_path + ": the scene has no tracking section to control");
    lcm::LCM lcm(options.lcm_url);  // empty: LCM_DEFAULT_URL or LCM's own default
    if (!lcm.good()) return std::fprintf(stderr, "error: cannot open LCM (%s)\n", options.lcm_url.c_str()), 1;
    // One compute time per control period of the scene's run (and some to spare for restarts).
    const std::size_t periods = scene.control_mode == ControlMode::kSampled
                                    ? static_cast<std::size_t>(std::ceil(scene.duration * scene.control_rate)) + 1024
                                    : std::size_t{1} << 16;
    const auto log = open_message_log(options.log_path);
    Outbox command_out(lcm, options.command_channel, log.get(), options.log_wait);
    Outbox stats_outbox(lcm, options.stats_channel, log.get(), true);
    ControllerNode node(command_out, make_scene_controller(scene.tracking), periods);
    lcm.subscribe(options.state_channel, &ControllerNode::on_state, &node);
    stop_on_signals();
    apply_realtime(options, "gausstrack-controller");
    std::printf("gausstrack-controller: ready\n");
    std::fflush(stdout);
    while (!g_stop_requested) lcm.handleTimeout(100);

    gausstrack::loop_stats_t stats{};
    stats.utime = wall_us();
    stats.process = "controller";
    stats.commands_published = node.published();
    stats.messages_rejected = node.rejected();
    stats.compute_ns_p50 = node.compute_ns().quantile(0.5);
    stats.compute_ns_p99 = node.compute_ns().quantile(0.99);
    stats.compute_ns_max = node.compute_ns().max();
    stats_outbox.publish_message(stats);
    const long log_dropped = close_message_log(log.get(), "gausstrack-controller", options.log_path);
    if (!stats_out.empty()) {
      std::ofstream out(stats_out);
      out << "{\"process\": \"controller\", \"commands_published\": " << node.published()
          << ", \"messages_rejected\": " << node.rejected() << ", \"log_dropped\": " << log_dropped << ", " << node.compute_ns().json("compute_ns") << "}\n";
      if (!out) return std::fprintf(stderr, "error: cannot write %s\n", stats_out.c_str()), 1;
    }
    std::printf("gausstrack-controller: %ld commands published, %ld messages rejected, compute p50 %.0f ns, "
                "p99 %.0f ns, max %.0f ns\n",
                node.published(), node.rejected(), stats.compute_ns_p50, stats.compute_ns_p99, stats.compute_ns_max);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
