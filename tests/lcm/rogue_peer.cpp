// A third process on the pair's LCM group, for the fault campaign's attacks (run only inside a
// network namespace the test creates, with ttl=0):
//   rogue_peer answer --lcm-url URL [--forge]    answers every plant state at once with its own
//       command (same run_id and state_sequence, a constant 50 N push, sequence numbers far above
//       the controller's); --forge appends a trailer made with a key of its own.
//   rogue_peer flood --lcm-url URL --kind garbage|command|forged --rate HZ --seconds S
//       publishes on the state and the command channels in turn at RATE messages per second for
//       S seconds (at most 1,000,000 messages): random bytes of a command's size, well-formed
//       commands for the current run without a trailer, or with a forged one.
// Runs until its time is up, or SIGINT/SIGTERM; prints what it sent.
#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <random>
#include <string>
#include <thread>

#include "gausstrack/control_command_t.hpp"
#include "gausstrack/nodes/auth.hpp"
#include "gausstrack/plant_state_t.hpp"
#include "gausstrack/tracking/stop_request.hpp"

namespace {

using gausstrack::control_command_t;
using gausstrack::plant_state_t;
using gausstrack::nodes::ChannelAuth;
using gausstrack::nodes::MessageKey;

MessageKey random_key(std::mt19937_64& rng) {
  std::array<std::uint8_t, gausstrack::nodes::kKeyBytes> bytes{};
  for (auto& b : bytes) b = static_cast<std::uint8_t>(rng());
  return MessageKey(bytes);
}

// Encodes a 50 N push answering (run_id, state_sequence), sealed with `forge` when given.
int encode_push(std::int64_t run_id, std::int64_t state_sequence, int dimension, std::int64_t sequence,
                ChannelAuth* forge, std::array<std::uint8_t, 4096>& buf) {
  control_command_t c{};
  c.run_id = run_id;
  c.state_sequence = state_sequence;
  c.sequence = sequence;
  c.dimension = dimension;
  for (int i = 0; i < dimension; ++i) c.force[i] = 50.0;
  const int size = c.getEncodedSize();
  c.encode(buf.data(), 0, size);
  return forge ? forge->seal(buf.data(), static_cast<std::size_t>(size), buf.size()) : size;
}

// Follows the plant's states; in answer mode replies to each at once.
struct Peer {
  lcm::LCM& lcm;
  std::string command_channel;
  ChannelAuth* forge = nullptr;
  bool answering = false;
  std::int64_t sent = 0, run_id = 0, last_sequence = 0;
  int dimension = 2;
  std::array<std::uint8_t, 4096> buf{};
  void on_state(const lcm::ReceiveBuffer* r, const std::string&) {
    plant_state_t s{};
    if (s.decode(r->data, 0, static_cast<int>(r->data_size)) < 0) return;
    run_id = s.run_id;
    last_sequence = s.sequence;
    dimension = std::clamp(s.dimension, 1, 32);
    if (!answering) return;
    const int n = encode_push(s.run_id, s.sequence, dimension, 1'000'000'000 + sent, forge, buf);
    lcm.publish(command_channel, buf.data(), static_cast<unsigned>(n));
    ++sent;
  }
};

int answer(lcm::LCM& lcm, const std::string& state_channel, const std::string& command_channel, bool forge) {
  std::mt19937_64 rng(std::random_device{}());
  ChannelAuth forged(random_key(rng), command_channel);
  Peer peer{lcm, command_channel, forge ? &forged : nullptr, true};
  lcm.subscribe(state_channel, &Peer::on_state, &peer);
  std::printf("rogue_peer: ready (answering states%s)\n", forge ? " with a forged trailer" : "");
  std::fflush(stdout);
  while (!gausstrack::g_stop_requested) lcm.handleTimeout(50);
  std::printf("rogue_peer: %lld commands sent\n", static_cast<long long>(peer.sent));
  return 0;
}

int flood(lcm::LCM& lcm, const std::string& state_channel, const std::string& command_channel, const std::string& kind,
          double rate, double seconds) {
  std::mt19937_64 rng(std::random_device{}());
  ChannelAuth forged(random_key(rng), command_channel);
  Peer peer{lcm, command_channel};
  lcm.subscribe(state_channel, &Peer::on_state, &peer);
  const auto total = static_cast<std::int64_t>(std::min(1e6, rate * seconds));
  const auto period = std::chrono::nanoseconds(static_cast<std::int64_t>(1e9 / rate));
  std::printf("rogue_peer: ready (flooding %lld %s messages)\n", static_cast<long long>(total), kind.c_str());
  std::fflush(stdout);
  std::array<std::uint8_t, 4096> buf{};
  const int command_size = control_command_t{}.getEncodedSize();
  auto next = std::chrono::steady_clock::now();
  std::int64_t sent = 0;
  for (; sent < total && !gausstrack::g_stop_requested; ++sent) {
    while (lcm.handleTimeout(0) > 0) {
    }
    int n = command_size;
    if (kind == "garbage") {
      for (int i = 0; i < n; ++i) buf[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(rng());
    } else {
      n = encode_push(peer.run_id, peer.last_sequence, peer.dimension, 1'000'000'000 + sent,
                      kind == "forged" ? &forged : nullptr, buf);
    }
    lcm.publish(sent % 2 == 0 ? command_channel : state_channel, buf.data(), static_cast<unsigned>(n));
    next += period;
    if (next > std::chrono::steady_clock::now()) std::this_thread::sleep_until(next);
  }
  std::printf("rogue_peer: %lld messages sent\n", static_cast<long long>(sent));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"rogue_peer: a third process on the pair's LCM group (fault campaign only)"};
  app.require_subcommand(1);
  std::string url, state_channel = "GAUSSTRACK_STATE", command_channel = "GAUSSTRACK_COMMAND", kind = "garbage";
  bool forge = false;
  double rate = 100000, seconds = 1;
  for (CLI::App* sub : {app.add_subcommand("answer", "answer every state first"),
                        app.add_subcommand("flood", "publish messages at a rate")}) {
    sub->add_option("--lcm-url", url)->required();
    sub->add_option("--state-channel", state_channel)->capture_default_str();
    sub->add_option("--command-channel", command_channel)->capture_default_str();
  }
  app.get_subcommand("answer")->add_flag("--forge", forge, "seal with a key of its own");
  CLI::App* f = app.get_subcommand("flood");
  f->add_option("--kind", kind)->check(CLI::IsMember({"garbage", "command", "forged"}))->capture_default_str();
  f->add_option("--rate", rate, "messages per second")->check(CLI::Range(1.0, 1e6))->capture_default_str();
  f->add_option("--seconds", seconds)->check(CLI::Range(0.01, 60.0))->capture_default_str();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  if (url.find("ttl=0") == std::string::npos)
    return std::fprintf(stderr, "rogue_peer: the URL must keep LCM's ttl=0 (%s)\n", url.c_str()), 2;
  lcm::LCM lcm(url);
  if (!lcm.good()) return std::fprintf(stderr, "rogue_peer: cannot open LCM (%s)\n", url.c_str()), 1;
  gausstrack::stop_on_signals();
  return app.got_subcommand("answer") ? answer(lcm, state_channel, command_channel, forge)
                                      : flood(lcm, state_channel, command_channel, kind, rate, seconds);
}
