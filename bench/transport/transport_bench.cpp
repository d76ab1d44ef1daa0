// transport_bench [--round-trips N] [--rate HZ [--seconds S] [--realtime [--cpus A,B]] [--spin-us S]]
//                 [--lcm-url URL] [--out FILE.json]
// Round trip between two processes on this machine, in one run:
//   lcm  a plant_state_t published over LCM, answered by a child process that decodes it and
//        publishes a control_command_t (both encoded into fixed buffers, as the real processes do);
//   udp  raw UDP datagrams on loopback of the same sizes (the floor).
// Back to back by default. With --rate, each round trip starts at its own period's deadline, as
// the plant's do (absolute deadlines on CLOCK_MONOTONIC, the plant's PeriodScheduler), and a
// third path measures the machine's own floor in the manner of cyclictest:
//   sleep  the same paced loop with nothing in it: how late the wake-ups are, and how many are
//          later than half a period (the loop's deadline misses). The scheduler sets the timer
//          slack to 1 ns, as it does in the plant. It always sleeps: --spin-us (the plant's option)
//          applies to the paced round trips only.
// --realtime applies what `gausstrack-run --realtime` applies: SCHED_FIFO (80 for every thread here;
// gausstrack-run raises the plant's loop to 83 and its receive thread to 82), mlockall, the pacing
// process pinned to the last CPU and the answering one to the one before (--cpus A,B: the pacing
// process on A, the answering one on B; A = B puts both on one CPU).
// Prints p50/p99/p99.9/max of each and writes them as JSON.
#include <arpa/inet.h>
#include <lcm/lcm-cpp.hpp>
#include <CLI/CLI.hpp>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <array>
#include <memory>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include "gausstrack/control_command_t.hpp"
#include "gausstrack/nodes/latency_json.hpp"
#include "gausstrack/nodes/plant_node.hpp"
#include "gausstrack/plant_state_t.hpp"

namespace {

using gausstrack::nodes::LatencyRecorder;
using gausstrack::nodes::PeriodScheduler;

// Pacing of one path: none (back to back) or one round trip per period.
struct Pacing {
  double rate_hz = 0;
  bool realtime = false;
  int cpus = 1;
  int pacing_cpu = -1, answering_cpu = -1;  // -1: the last CPU and the one before
  int spin_us = 0;  // the round trips' pacing spins this long before each deadline (not the floor's)
  std::unique_ptr<PeriodScheduler> scheduler;
  void start(std::size_t periods, bool spin = true) {
    if (rate_hz > 0)
      scheduler = std::make_unique<PeriodScheduler>(gausstrack::nodes::period_ns_at(rate_hz),
                                                    gausstrack::nodes::monotonic_ns() + 1000000, periods,
                                                    spin ? std::int64_t{spin_us} * 1000 : 0);
  }
  void wait(long k) {
    if (scheduler) scheduler->wait_for(k);
  }
  // The process that paces (the plant's role) and the one that answers (the controller's).
  void apply(bool pacing_side) const {
    if (!realtime) return;
    gausstrack::nodes::ProcessOptions o;
    o.rt_priority = 80;
    o.lock_memory = true;
    if (pacing_side) o.cpu = pacing_cpu >= 0 ? pacing_cpu : cpus - 1;
    else o.cpu = answering_cpu >= 0 ? answering_cpu : std::max(0, cpus - 2);
    gausstrack::nodes::apply_realtime(o, "transport_bench");
  }
};

std::int64_t now_ns() {
  timespec t{};
  clock_gettime(CLOCK_MONOTONIC, &t);
  return static_cast<std::int64_t>(t.tv_sec) * 1000000000LL + t.tv_nsec;
}

const std::string kPing = "TRANSPORT_BENCH_STATE_" + std::to_string(getpid());
const std::string kPong = "TRANSPORT_BENCH_COMMAND_" + std::to_string(getpid());

// Child: answers every state with a command until told to stop (sequence < 0).
struct Echo {
  lcm::LCM* lcm;
  gausstrack::plant_state_t state{};
  gausstrack::control_command_t command{};
  std::array<std::uint8_t, 4096> buffer{};
  bool stop = false;
  void on_state(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    if (state.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) < 0) return;
    if (state.sequence < 0) {
      stop = true;
      return;
    }
    command.state_sequence = state.sequence;
    command.dimension = state.dimension;
    for (int i = 0; i < state.dimension; ++i) command.force[i] = -state.q[i];
    const int size = command.getEncodedSize();
    command.encode(buffer.data(), 0, size);
    lcm->publish(kPong, buffer.data(), static_cast<unsigned>(size));
  }
};

int lcm_echo(const std::string& url, const Pacing& pacing) {
  pacing.apply(false);
  lcm::LCM lcm(url);
  if (!lcm.good()) return 1;
  Echo echo{&lcm};
  lcm.subscribe(kPing, &Echo::on_state, &echo);
  const std::int64_t give_up = now_ns() + 120LL * 1000000000LL;
  while (!echo.stop && now_ns() < give_up) lcm.handleTimeout(100);
  return 0;
}

struct Pong {
  std::int64_t answered = -1;
  gausstrack::control_command_t command{};
  void on_command(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    if (command.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) >= 0) answered = command.state_sequence;
  }
};

bool lcm_round_trips(const std::string& url, long n, Pacing& pacing, LatencyRecorder& rt_us, int& state_bytes,
                     int& command_bytes) {
  lcm::LCM lcm(url);
  if (!lcm.good()) return false;
  Pong pong;
  lcm.subscribe(kPong, &Pong::on_command, &pong);
  gausstrack::plant_state_t state{};
  state.dimension = 2;
  std::array<std::uint8_t, 4096> buffer{};
  command_bytes = gausstrack::control_command_t{}.getEncodedSize();
  auto send = [&](std::int64_t seq) {
    state.sequence = seq;
    state.q[0] = static_cast<double>(seq);
    const int size = state.getEncodedSize();
    state_bytes = size;
    state.encode(buffer.data(), 0, size);
    lcm.publish(kPing, buffer.data(), static_cast<unsigned>(size));
  };
  // Handshake: until the child answers (it may not have subscribed yet).
  for (int tries = 0; pong.answered != 0; ++tries) {
    if (tries > 100) return false;
    send(0);
    lcm.handleTimeout(50);
  }
  const long warmup = pacing.rate_hz > 0 ? 0 : 1000;
  pacing.start(static_cast<std::size_t>(n));
  for (long k = 1; k <= n + warmup; ++k) {
    pacing.wait(k - 1);
    const std::int64_t t0 = now_ns();
    send(k);
    while (pong.answered != k)
      if (lcm.handleTimeout(1000) <= 0) return false;
    if (k > warmup) rt_us.add(static_cast<double>(now_ns() - t0) * 1e-3);
  }
  send(-1);
  return true;
}

int udp_echo(int fd, int state_bytes, int command_bytes) {
  std::vector<char> in(static_cast<std::size_t>(state_bytes) + 16), out(static_cast<std::size_t>(command_bytes));
  for (;;) {
    sockaddr_in from{};
    socklen_t len = sizeof from;
    const ssize_t got = recvfrom(fd, in.data(), in.size(), 0, reinterpret_cast<sockaddr*>(&from), &len);
    if (got <= 0) return 1;
    if (got == 1) return 0;  // stop
    sendto(fd, out.data(), out.size(), 0, reinterpret_cast<sockaddr*>(&from), len);
  }
}

bool udp_round_trips(long n, int state_bytes, int command_bytes, Pacing& pacing, LatencyRecorder& rt_us) {
  const int server = socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t len = sizeof addr;
  if (server < 0 || bind(server, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0 ||
      getsockname(server, reinterpret_cast<sockaddr*>(&addr), &len) != 0)
    return false;
  const pid_t child = fork();
  if (child == 0) {
    pacing.apply(false);
    _exit(udp_echo(server, state_bytes, command_bytes));
  }
  close(server);
  const int client = socket(AF_INET, SOCK_DGRAM, 0);
  std::vector<char> out(static_cast<std::size_t>(state_bytes)), in(static_cast<std::size_t>(command_bytes) + 16);
  pollfd p{client, POLLIN, 0};
  bool ok = true;
  const long warmup = pacing.rate_hz > 0 ? 0 : 1000;
  pacing.start(static_cast<std::size_t>(n));
  for (long k = 0; k < n + warmup && ok; ++k) {
    pacing.wait(k);
    const std::int64_t t0 = now_ns();
    sendto(client, out.data(), out.size(), 0, reinterpret_cast<sockaddr*>(&addr), sizeof addr);
    ok = poll(&p, 1, 1000) == 1 && recv(client, in.data(), in.size(), 0) == command_bytes;
    if (k >= warmup) rt_us.add(static_cast<double>(now_ns() - t0) * 1e-3);
  }
  sendto(client, out.data(), 1, 0, reinterpret_cast<sockaddr*>(&addr), sizeof addr);
  close(client);
  int status = 0;
  waitpid(child, &status, 0);
  return ok;
}

void print(const char* name, const LatencyRecorder& r, const char* what = "round trips") {
  std::printf("%-22s p50 %7.1f us  p99 %7.1f  p99.9 %7.1f  max %8.1f  (%zu %s)\n", name, r.quantile(0.5),
              r.quantile(0.99), r.quantile(0.999), r.max(), r.count(), what);
}

// The paced path's wake-ups: lateness and misses, printed and added to the JSON document.
void wake_json(const char* name, const Pacing& pacing, nlohmann::ordered_json& j) {
  if (!pacing.scheduler) return;
  char head[128];
  std::snprintf(head, sizeof head, "%s wake-ups", name);
  print(head, pacing.scheduler->wake_late_us(), "periods");
  std::printf("%-22s %ld deadline misses (woke more than half a period late)\n", "", pacing.scheduler->misses());
  j[std::string(name) + "_wake_late_us"] = gausstrack::nodes::percentiles_json(pacing.scheduler->wake_late_us());
  j[std::string(name) + "_deadline_misses"] = pacing.scheduler->misses();
}

// The cyclictest-style floor: the paced loop with nothing in it.
void sleep_only(long n, Pacing& pacing) {
  pacing.start(static_cast<std::size_t>(n), false);
  for (long k = 0; k < n; ++k) pacing.wait(k);
}

}  // namespace

int main(int argc, char** argv) {
  long n = 20000;
  double seconds = 5;
  Pacing pacing;
  pacing.cpus = static_cast<int>(std::max(1L, sysconf(_SC_NPROCESSORS_ONLN)));
  std::string url = "udpm://239.255.76.67:7671?ttl=0", out;
  std::vector<int> cpus;
  CLI::App app("LCM round trips between two processes beside raw UDP of the same sizes, back to back or paced.");
  app.add_option("--round-trips", n, "round trips back to back")->check(CLI::PositiveNumber)->capture_default_str();
  auto* rate = app.add_option("--rate", pacing.rate_hz, "pace one round trip per period at this rate [Hz]")
                   ->check(CLI::Range(0.0, 1e6));
  app.add_option("--seconds", seconds, "paced: for this long")->check(CLI::PositiveNumber)->capture_default_str()->needs(rate);
  auto* realtime = app.add_flag("--realtime", pacing.realtime, "paced: SCHED_FIFO, pinned")->needs(rate);
  app.add_option("--cpus", cpus, "realtime: the pacing and the answering process's CPUs, A,B")
      ->delimiter(',')
      ->expected(2)
      ->check(CLI::NonNegativeNumber)
      ->needs(realtime);
  app.add_option("--spin-us", pacing.spin_us,
                 "paced round trips: wake this long before each deadline and spin until it, as the plant's "
                 "--spin-us (the floor always sleeps)")
      ->check(CLI::NonNegativeNumber)
      ->needs(rate);
  app.add_option("--lcm-url", url)->capture_default_str();
  app.add_option("--out", out, "write the percentiles as JSON to this file");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;  // --help, or a usage error (printed)
  }
  if (!std::isfinite(pacing.rate_hz) || !std::isfinite(seconds))
    return std::fprintf(stderr, "error: --rate and --seconds must be finite\n"), 2;
  if (pacing.spin_us > 0 && !(pacing.rate_hz > 0))
    return std::fprintf(stderr, "error: --spin-us paces round trips: it needs a --rate above 0\n"), 2;
  if (pacing.spin_us > 0 && !gausstrack::nodes::spin_fits_period(pacing.spin_us, gausstrack::nodes::period_ns_at(pacing.rate_hz)))
    return std::fprintf(stderr, "error: --spin-us %d: must be less than the period (%g us at %g Hz)\n",
                        pacing.spin_us, 1e6 / pacing.rate_hz, pacing.rate_hz),
           2;
  if (cpus.size() == 2) {
    pacing.pacing_cpu = cpus[0];
    pacing.answering_cpu = cpus[1];
  }
  if (pacing.rate_hz > 0) n = std::max(1L, static_cast<long>(seconds * pacing.rate_hz));
  const auto capacity = static_cast<std::size_t>(n);
  LatencyRecorder lcm_us(capacity), udp_us(capacity);
  int state_bytes = 0, command_bytes = 0;
  nlohmann::ordered_json j = nlohmann::ordered_json::object();

  // The floor first, in the pacing process's own setting (the parent applies it after forking the
  // children, which apply theirs).
  const pid_t child = fork();
  if (child == 0) _exit(lcm_echo(url, pacing));
  pacing.apply(true);
  if (pacing.rate_hz > 0) {
    sleep_only(n, pacing);
    wake_json("sleep", pacing, j);
  }
  const bool lcm_ok = lcm_round_trips(url, n, pacing, lcm_us, state_bytes, command_bytes);
  if (!lcm_ok) kill(child, SIGTERM);
  int status = 0;
  waitpid(child, &status, 0);
  if (!lcm_ok) return std::fprintf(stderr, "error: LCM round trips failed on %s\n", url.c_str()), 1;
  if (pacing.rate_hz > 0) wake_json("lcm", pacing, j);
  if (!udp_round_trips(n, state_bytes, command_bytes, pacing, udp_us))
    return std::fprintf(stderr, "error: UDP loopback round trips failed\n"), 1;
  if (pacing.rate_hz > 0) wake_json("udp", pacing, j);

  std::printf("round trip between two processes on loopback: state %d bytes out, command %d bytes back%s\n",
              state_bytes, command_bytes, pacing.rate_hz > 0 ? ", one per period" : ", back to back");
  print("lcm (plant_state_t)", lcm_us);
  print("raw udp (same sizes)", udp_us);
  std::printf("lcm / udp at p50: %.2f\n", lcm_us.quantile(0.5) / udp_us.quantile(0.5));
  if (!out.empty()) {
    nlohmann::ordered_json doc = {{"round_trips", n},
                                  {"rate_hz", pacing.rate_hz},
                                  {"realtime", pacing.realtime},
                                  {"spin_us", pacing.spin_us},
                                  {"state_bytes", state_bytes},
                                  {"command_bytes", command_bytes},
                                  {"lcm_url", url},
                                  {"lcm_us", gausstrack::nodes::percentiles_json(lcm_us)},
                                  {"udp_us", gausstrack::nodes::percentiles_json(udp_us)}};
    doc.update(j);
    std::ofstream f(out);
    f << doc.dump(2) << '\n';
    if (!f) return std::fprintf(stderr, "error: cannot write %s\n", out.c_str()), 1;
  }
  return 0;
}
