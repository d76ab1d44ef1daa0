// A faulty network between plant and controller, in user space: forwards the state channel from
// LCM URL A to URL B and the command channel from B back to A, and on the way delays, jitters,
// drops, duplicates and reorders messages, or takes the link down for a while. Used by the fault
// campaign (scripts/faults) where the kernel offers no netem qdisc.
//   fault_relay --a URL --b URL --state-channel C --command-channel C [--delay-ms D] [--jitter-ms J]
//               [--loss P] [--duplicate P] [--reorder P] [--down-at-s T --down-ms M] [--seed S]
// Runs until SIGINT/SIGTERM and prints what it did.
#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>
#include <poll.h>

#include <cstdint>
#include <cstdio>
#include <ctime>
#include <queue>
#include <random>
#include <string>
#include <vector>

#include "gausstrack/tracking/stop_request.hpp"

namespace {

std::int64_t now_ns() {
  timespec t{};
  clock_gettime(CLOCK_MONOTONIC, &t);
  return static_cast<std::int64_t>(t.tv_sec) * 1000000000LL + t.tv_nsec;
}

struct Pending {
  std::int64_t release_ns;
  std::uint64_t order;  // ties released in arrival order
  bool to_b;
  std::string channel;
  std::vector<std::uint8_t> bytes;
  bool operator>(const Pending& o) const { return release_ns != o.release_ns ? release_ns > o.release_ns : order > o.order; }
};

struct Options {
  std::string a, b, state_channel = "GAUSSTRACK_STATE", command_channel = "GAUSSTRACK_COMMAND";
  double delay_ms = 0, jitter_ms = 0, loss = 0, duplicate = 0, reorder = 0, down_at_s = -1, down_ms = 0;
  unsigned seed = 1;
};

class Relay {
 public:
  Relay(const Options& o, lcm::LCM& a, lcm::LCM& b) : o_(o), a_(a), b_(b), rng_(o.seed), start_(now_ns()) {}

  void from_a(const lcm::ReceiveBuffer* r, const std::string& channel) { take(r, channel, true); }
  void from_b(const lcm::ReceiveBuffer* r, const std::string& channel) { take(r, channel, false); }

  // Sends what is due; returns the time of the next release (or -1).
  std::int64_t release_due() {
    const std::int64_t now = now_ns();
    while (!queue_.empty() && queue_.top().release_ns <= now) {
      const Pending& p = queue_.top();
      (p.to_b ? b_ : a_).publish(p.channel, p.bytes.data(), static_cast<unsigned>(p.bytes.size()));
      ++forwarded_;
      queue_.pop();
    }
    return queue_.empty() ? -1 : queue_.top().release_ns;
  }

  void report() const {
    std::printf("fault_relay: %ld received, %ld forwarded, %ld dropped (%ld while down), %ld duplicated, %ld reordered\n",
                received_, forwarded_, dropped_, dropped_down_, duplicated_, reordered_);
  }

 private:
  void take(const lcm::ReceiveBuffer* r, const std::string& channel, bool to_b) {
    ++received_;
    const std::int64_t now = now_ns();
    const double t = static_cast<double>(now - start_) * 1e-9;
    if (o_.down_at_s >= 0 && t >= o_.down_at_s && t < o_.down_at_s + o_.down_ms * 1e-3) {
      ++dropped_;
      ++dropped_down_;
      return;
    }
    if (uniform_(rng_) < o_.loss) {
      ++dropped_;
      return;
    }
    const auto* data = static_cast<const std::uint8_t*>(r->data);
    Pending p{0, 0, to_b, channel, std::vector<std::uint8_t>(data, data + r->data_size)};
    const int copies = uniform_(rng_) < o_.duplicate ? 2 : 1;
    duplicated_ += copies - 1;
    for (int c = 0; c < copies; ++c) {
      double delay = o_.delay_ms + (o_.jitter_ms > 0 ? o_.jitter_ms * (2 * uniform_(rng_) - 1) : 0.0);
      // Reordering: this message is held back behind the next one (one period at 1 kHz).
      if (uniform_(rng_) < o_.reorder) {
        delay += 1.5;
        ++reordered_;
      }
      p.release_ns = now + static_cast<std::int64_t>(std::max(0.0, delay) * 1e6);
      p.order = order_++;
      queue_.push(p);
    }
  }

  Options o_;
  lcm::LCM& a_;
  lcm::LCM& b_;
  std::mt19937_64 rng_;
  std::uniform_real_distribution<double> uniform_{0.0, 1.0};
  std::priority_queue<Pending, std::vector<Pending>, std::greater<>> queue_;
  std::int64_t start_;
  std::uint64_t order_ = 0;
  long received_ = 0, forwarded_ = 0, dropped_ = 0, dropped_down_ = 0, duplicated_ = 0, reordered_ = 0;
};

}  // namespace

int main(int argc, char** argv) {
  Options o;
  CLI::App app{"fault_relay: a faulty network between plant and controller"};
  app.add_option("--a", o.a, "LCM URL of the plant's side")->required();
  app.add_option("--b", o.b, "LCM URL of the controller's side")->required();
  app.add_option("--state-channel", o.state_channel)->capture_default_str();
  app.add_option("--command-channel", o.command_channel)->capture_default_str();
  app.add_option("--delay-ms", o.delay_ms, "added one-way delay [ms]")->check(CLI::NonNegativeNumber);
  app.add_option("--jitter-ms", o.jitter_ms, "uniform jitter on top of the delay [ms]")->check(CLI::NonNegativeNumber);
  app.add_option("--loss", o.loss, "probability of dropping a message")->check(CLI::Range(0.0, 1.0));
  app.add_option("--duplicate", o.duplicate, "probability of sending a message twice")->check(CLI::Range(0.0, 1.0));
  app.add_option("--reorder", o.reorder, "probability of holding a message back")->check(CLI::Range(0.0, 1.0));
  app.add_option("--down-at-s", o.down_at_s, "take the link down at this time [s]");
  app.add_option("--down-ms", o.down_ms, "for this long [ms]")->check(CLI::NonNegativeNumber);
  app.add_option("--seed", o.seed)->capture_default_str();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  if (o.a == o.b) return std::fprintf(stderr, "fault_relay: --a and --b must differ\n"), 2;
  lcm::LCM a(o.a), b(o.b);
  if (!a.good() || !b.good()) return std::fprintf(stderr, "fault_relay: cannot open LCM\n"), 1;
  Relay relay(o, a, b);
  a.subscribe(o.state_channel, &Relay::from_a, &relay);
  b.subscribe(o.command_channel, &Relay::from_b, &relay);
  gausstrack::stop_on_signals();
  std::printf("fault_relay: ready\n");
  std::fflush(stdout);
  pollfd fds[2] = {{a.getFileno(), POLLIN, 0}, {b.getFileno(), POLLIN, 0}};
  while (!gausstrack::g_stop_requested) {
    const std::int64_t next = relay.release_due();
    const std::int64_t wait = next < 0 ? 10000000 : std::max<std::int64_t>(0, next - now_ns());
    const timespec timeout{static_cast<time_t>(wait / 1000000000), static_cast<long>(wait % 1000000000)};
    if (ppoll(fds, 2, &timeout, nullptr) > 0) {
      if (fds[0].revents & POLLIN) a.handle();
      if (fds[1].revents & POLLIN) b.handle();
    }
  }
  relay.report();
  return 0;
}
