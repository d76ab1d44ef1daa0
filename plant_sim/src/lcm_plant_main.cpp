// gausstrack-plant --scene S --lockstep [--out DIR] [--set key=value ...] [--lcm-url URL]
//                  [--state-channel C] [--command-channel C] [--timeout-ms T]
// Steps the scene's plant one control period at a time (sampled and held control), publishing
// the state at the start of each period and applying the command that answers it. Lock-step:
// the plant waits for that command (deterministic; for tests and accuracy studies).
#include <lcm/lcm-cpp.hpp>

#include <array>
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

// Keeps the command answering the awaited state; everything else is counted and dropped.
class CommandInbox {
 public:
  explicit CommandInbox(int dimension) : dimension_(dimension) {}

  void await(std::int64_t sequence) {
    awaited_ = sequence;
    ready_ = false;
  }
  bool ready() const { return ready_; }
  const double* force() const { return command_.force; }
  long rejected() const { return rejected_; }

  void on_command(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    if (command_.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) < 0 || command_.dimension != dimension_ ||
        command_.state_sequence != awaited_ || command_.status != 0) {
      ++rejected_;
      return;
    }
    for (int i = 0; i < dimension_; ++i)
      if (!std::isfinite(command_.force[i])) {
        ++rejected_;
        return;
      }
    ready_ = true;
  }

 private:
  int dimension_;
  gausstrack::control_command_t command_{};
  std::int64_t awaited_ = -1;
  bool ready_ = false;
  long rejected_ = 0;
};

}  // namespace

int main(int argc, char** argv) {
  std::string scene_path, url, out_dir = "out/plant", state_channel = "GAUSSTRACK_STATE",
                               command_channel = "GAUSSTRACK_COMMAND";
  std::vector<std::string> sets;
  bool lockstep = false;
  int timeout_ms = 2000;
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
    else if (a == "--lockstep") lockstep = true;
    else {
      std::fprintf(stderr, "usage: %s --scene S --lockstep [--out DIR] [--set key=value ...] [--lcm-url URL] "
                           "[--state-channel C] [--command-channel C] [--timeout-ms T]\n", argv[0]);
      return 2;
    }
  }
  if (scene_path.empty()) return std::fprintf(stderr, "error: --scene is required\n"), 2;
  if (!lockstep) return std::fprintf(stderr, "error: only --lockstep is available in this version\n"), 2;
  try {
    const Scene scene = load_scene(scene_path, sets);
    lcm::LCM lcm(url);
    if (!lcm.good()) return std::fprintf(stderr, "error: cannot open LCM (%s)\n", url.c_str()), 1;
    CommandInbox inbox(scene.dof());
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
      const int size = state.getEncodedSize();
      state.encode(buffer.data(), 0, size);
      inbox.await(period);
      lcm.publish(state_channel, buffer.data(), static_cast<unsigned>(size));
      const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
      while (!inbox.ready()) {
        const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
        if (left.count() <= 0) {
          ++missing;
          std::fprintf(stderr, "error: no command answered state %lld within %d ms\n",
                       static_cast<long long>(period), timeout_ms);
          return false;
        }
        lcm.handleTimeout(static_cast<int>(left.count()));
      }
      for (int i = 0; i < scene.dof(); ++i) u[static_cast<std::size_t>(i)] = inbox.force()[i];
      return true;
    };
    const RunResult result = run_scene(scene, options);
    std::filesystem::create_directories(out_dir);
    write_trajectory_csv(scene, result, out_dir + "/trajectory.csv");
    write_summary_json(scene, result, out_dir + "/summary.json");
    std::printf("gausstrack-plant: %zu samples, max tracking error %.3g, %ld commands missing, "
                "%ld messages rejected -> %s\n",
                result.samples.size(), result.summary.max_tracking_error, missing, inbox.rejected(), out_dir.c_str());
    return result.summary.stopped_early ? 1 : 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
