// A third process on the pair's LCM group, for the fault campaign's attacks (run only inside a
// network namespace the test creates, with ttl=0):
//   rogue_peer answer --lcm-url URL [--forge]    answers every plant state at once with its own
//       command (same run_id and state_sequence, a constant 50 N push, sequence numbers far above
//       the controller's); --forge appends a trailer made with a key of its own.
//   rogue_peer flood --lcm-url URL --kind garbage|command|forged --rate HZ --seconds S
//       publishes on the state and the command channels in turn at RATE messages per second for
//       S seconds (at most 1,000,000 messages): random bytes of a command's size, well-formed
//       commands for the current run without a trailer, or with a forged one.
// Runs until its time is up, or SIGINT/SIGTERM; prints what it sent. The flood writes LCM's
// datagrams itself on a plain UDP socket: through lcm::LCM::publish (a lock and bookkeeping per
// message) one process reaches about 25,000 messages per second on this 2-core machine, a
// quarter of the rate an attacker's raw socket reaches.
#include <CLI/CLI.hpp>
#include <arpa/inet.h>
#include <lcm/lcm-cpp.hpp>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstring>
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

// Sends datagrams as LCM's UDP multicast transport frames a message that fits in one: the magic
// "LC02" and a sequence number (32-bit, big-endian), the channel's name and a NUL, the payload.
class RawPublisher {
 public:
  // url: udpm://GROUP:PORT?... (ttl=0 checked by main).
  explicit RawPublisher(const std::string& url) {
    const auto at = url.find("://"), colon = url.rfind(':'), query = url.find('?');
    if (at == std::string::npos || colon == std::string::npos || colon < at + 3) return;
    addr_.sin_family = AF_INET;
    addr_.sin_port = htons(static_cast<std::uint16_t>(std::stoi(url.substr(colon + 1, query - colon - 1))));
    if (inet_pton(AF_INET, url.substr(at + 3, colon - at - 3).c_str(), &addr_.sin_addr) != 1) return;
    fd_ = socket(AF_INET, SOCK_DGRAM, 0);
    const int ttl = 0, loop = 1;
    setsockopt(fd_, IPPROTO_IP, IP_MULTICAST_TTL, &ttl, sizeof ttl);
    setsockopt(fd_, IPPROTO_IP, IP_MULTICAST_LOOP, &loop, sizeof loop);
  }
  ~RawPublisher() {
    if (fd_ >= 0) close(fd_);
  }
  RawPublisher(const RawPublisher&) = delete;
  RawPublisher& operator=(const RawPublisher&) = delete;
  bool good() const { return fd_ >= 0; }

  void publish(const std::string& channel, const std::uint8_t* data, int size) {
    if (8 + channel.size() + 1 + static_cast<std::size_t>(size) > datagram_.size()) return;
    const std::uint32_t magic = htonl(0x4c433032), seq = htonl(sequence_++);
    std::memcpy(datagram_.data(), &magic, 4);
    std::memcpy(datagram_.data() + 4, &seq, 4);
    std::memcpy(datagram_.data() + 8, channel.c_str(), channel.size() + 1);
    const std::size_t head = 8 + channel.size() + 1;
    std::memcpy(datagram_.data() + head, data, static_cast<std::size_t>(size));
    sendto(fd_, datagram_.data(), head + static_cast<std::size_t>(size), 0, reinterpret_cast<const sockaddr*>(&addr_),
           sizeof addr_);
  }

 private:
  int fd_ = -1;
  sockaddr_in addr_{};
  std::uint32_t sequence_ = 0;
  std::array<std::uint8_t, 8192> datagram_{};
};

// Follows the plant's states; in answer mode replies to each at once.
struct Peer {
  lcm::LCM* lcm;  // answers through it (answer mode)
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
    lcm->publish(command_channel, buf.data(), static_cast<unsigned>(n));
    ++sent;
  }
};

int answer(lcm::LCM& lcm, const std::string& state_channel, const std::string& command_channel, bool forge) {
  std::mt19937_64 rng(std::random_device{}());
  ChannelAuth forged(random_key(rng), command_channel);
  Peer peer{&lcm, command_channel, forge ? &forged : nullptr, true};
  lcm.subscribe(state_channel, &Peer::on_state, &peer);
  std::printf("rogue_peer: ready (answering states%s)\n", forge ? " with a forged trailer" : "");
  std::fflush(stdout);
  while (!gausstrack::g_stop_requested) lcm.handleTimeout(50);
  std::printf("rogue_peer: %lld commands sent\n", static_cast<long long>(peer.sent));
  return 0;
}

int flood(const std::string& url, const std::string& state_channel, const std::string& command_channel,
          const std::string& kind, double rate, double seconds) {
  std::mt19937_64 rng(std::random_device{}());
  ChannelAuth forged(random_key(rng), command_channel);
  // The current run, from one state (well-formed commands only). The listener is closed before
  // the flood starts: a process on the group receives every message on it, its own included,
  // and reading back its own flood would halve the rate it can send.
  Peer peer{nullptr, command_channel};
  if (kind != "garbage") {
    lcm::LCM rx(url);
    lcm::Subscription* sub = rx.subscribe(state_channel, &Peer::on_state, &peer);
    for (int i = 0; i < 40 && peer.run_id == 0 && !gausstrack::g_stop_requested; ++i) rx.handleTimeout(50);
    rx.unsubscribe(sub);
    if (peer.run_id == 0) std::printf("rogue_peer: no state seen; commands name run 0\n");
  }
  RawPublisher out(url);  // sends only: never joins the group's receivers
  if (!out.good()) return std::fprintf(stderr, "rogue_peer: cannot open a socket for %s\n", url.c_str()), 1;
  const auto total = static_cast<std::int64_t>(std::min(1e6, rate * seconds));
  std::printf("rogue_peer: ready (flooding %lld %s messages)\n", static_cast<long long>(total), kind.c_str());
  std::fflush(stdout);
  std::array<std::uint8_t, 4096> buf{};
  const int command_size = control_command_t{}.getEncodedSize();
  // Paced in 1 ms slices: each slice sends the messages due by its end, so that the rate holds
  // where one sleep per message could not (a sleep costs tens of microseconds).
  const auto start = std::chrono::steady_clock::now();
  std::int64_t sent = 0;
  for (int slice = 1; sent < total && !gausstrack::g_stop_requested; ++slice) {
    const auto due = std::min(total, static_cast<std::int64_t>(rate * 1e-3 * slice));
    for (; sent < due; ++sent) {
      int n = command_size;
      if (kind == "garbage") {
        for (int i = 0; i < n; i += 8) {
          const std::uint64_t r = rng();
          std::memcpy(buf.data() + i, &r, 8);
        }
      } else {
        n = encode_push(peer.run_id, peer.last_sequence, peer.dimension, 1'000'000'000 + sent,
                        kind == "forged" ? &forged : nullptr, buf);
      }
      out.publish(sent % 2 == 0 ? command_channel : state_channel, buf.data(), n);
    }
    std::this_thread::sleep_until(start + std::chrono::milliseconds(slice));
  }
  const double took = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("rogue_peer: %lld messages sent in %.2f s\n", static_cast<long long>(sent), took);
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
  gausstrack::stop_on_signals();
  if (app.got_subcommand("flood")) return flood(url, state_channel, command_channel, kind, rate, seconds);
  lcm::LCM lcm(url);
  if (!lcm.good()) return std::fprintf(stderr, "rogue_peer: cannot open LCM (%s)\n", url.c_str()), 1;
  return answer(lcm, state_channel, command_channel, forge);
}
