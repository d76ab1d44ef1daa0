// gausstrack-controller --scene S [--set key=value ...] [--lcm-url URL]
//                       [--state-channel C] [--command-channel C]
// Subscribes to plant states, evaluates the scene's tracking controller for each valid one and
// publishes the command at once. Messages that do not decode, have the wrong dimension,
// non-finite values or an old sequence number are counted and ignored.
#include <lcm/lcm-cpp.hpp>

#include <array>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <string>
#include <vector>

#include "gausstrack/control_command_t.hpp"
#include "gausstrack/plant_sim/scene.hpp"
#include "gausstrack/plant_sim/scene_controller.hpp"
#include "gausstrack/plant_state_t.hpp"

namespace {

volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }

using namespace gausstrack::plant_sim;

class ControllerNode {
 public:
  ControllerNode(lcm::LCM& lcm, SceneController controller, std::string command_channel)
      : lcm_(lcm), controller_(std::move(controller)), command_channel_(std::move(command_channel)) {}

  void on_state(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    if (state_.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) < 0 || !valid(state_)) {
      ++rejected_;
      return;
    }
    last_sequence_ = state_.sequence;
    const auto start = std::chrono::steady_clock::now();
    const auto status = controller_.compute(Eigen::Map<const Eigen::Vector2d>(state_.q),
                                            Eigen::Map<const Eigen::Vector2d>(state_.qd), state_.t, out_);
    const auto compute_ns =
        std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - start).count();
    command_ = {};
    command_.utime = std::chrono::duration_cast<std::chrono::microseconds>(
                         std::chrono::system_clock::now().time_since_epoch())
                         .count();
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
    lcm_.publish(command_channel_, buffer_.data(), static_cast<unsigned>(size));
  }

  long rejected() const { return rejected_; }
  long published() const { return published_; }

 private:
  bool valid(const gausstrack::plant_state_t& s) const {
    if (s.dimension != 2 || s.sequence <= last_sequence_ || !std::isfinite(s.t)) return false;
    for (int i = 0; i < 2; ++i)
      if (!std::isfinite(s.q[i]) || !std::isfinite(s.qd[i])) return false;
    return true;
  }

  lcm::LCM& lcm_;
  SceneController controller_;
  SceneController::Output out_;
  std::string command_channel_;
  gausstrack::plant_state_t state_{};
  gausstrack::control_command_t command_{};
  std::array<std::uint8_t, 4096> buffer_{};
  std::int64_t last_sequence_ = -1;
  long rejected_ = 0;
  long published_ = 0;
};

}  // namespace

int main(int argc, char** argv) {
  std::string scene_path, url, state_channel = "GAUSSTRACK_STATE", command_channel = "GAUSSTRACK_COMMAND";
  std::vector<std::string> sets;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool has_value = i + 1 < argc;
    if (a == "--scene" && has_value) scene_path = argv[++i];
    else if (a == "--set" && has_value) sets.emplace_back(argv[++i]);
    else if (a == "--lcm-url" && has_value) url = argv[++i];
    else if (a == "--state-channel" && has_value) state_channel = argv[++i];
    else if (a == "--command-channel" && has_value) command_channel = argv[++i];
    else {
      std::fprintf(stderr, "usage: %s --scene S [--set key=value ...] [--lcm-url URL] "
                           "[--state-channel C] [--command-channel C]\n", argv[0]);
      return 2;
    }
  }
  if (scene_path.empty()) return std::fprintf(stderr, "error: --scene is required\n"), 2;
  try {
    const Scene scene = load_scene(scene_path, sets);
    if (!scene.tracking.enabled) throw SceneError(scene_path + ": the scene has no tracking section to control");
    lcm::LCM lcm(url);  // empty: LCM_DEFAULT_URL or LCM's own default
    if (!lcm.good()) return std::fprintf(stderr, "error: cannot open LCM (%s)\n", url.c_str()), 1;
    ControllerNode node(lcm, make_scene_controller(scene.tracking), command_channel);
    lcm.subscribe(state_channel, &ControllerNode::on_state, &node);
    std::signal(SIGINT, on_signal);
    std::signal(SIGTERM, on_signal);
    while (!g_stop) lcm.handleTimeout(100);
    std::printf("gausstrack-controller: %ld commands published, %ld messages rejected\n", node.published(),
                node.rejected());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
