// firmware_loop [--iterations N] [--period-us P] [--out FILE.json]
// A firmware-style fixed-period loop: wait for the period's deadline (spinning on the clock, as a
// bare-metal loop would on a timer), read a simulated sensor, evaluate the control law, write an
// actuator value. The plant (the Duffing oscillator of eq. 35) is stepped between periods,
// outside the timed region. The same loop runs twice in one process: with the hand-derived
// closed-form force (the floor) and with the library's TrackingController, and prints each
// one's latency histogram (sensor read to actuator write), percentiles, wake-up jitter and the
// tracking error reached (so a loop that computes nonsense cannot look fast).
#include <time.h>

#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>

#include "allocation_counter.hpp"
#include "duffing_closed_form.hpp"
#include "gausstrack/nodes/latency_json.hpp"
#include "gausstrack/systems/coupled_duffing.hpp"
#include "gausstrack/tracking_controller.hpp"

namespace {

using Duffing = gausstrack::systems::CoupledDuffing<double>;
using gausstrack::nodes::LatencyRecorder;

std::int64_t now_ns() {
  timespec t{};
  clock_gettime(CLOCK_MONOTONIC, &t);
  return static_cast<std::int64_t>(t.tv_sec) * 1000000000LL + t.tv_nsec;
}

struct LoopResult {
  LatencyRecorder latency_ns, jitter_ns;
  long allocations = 0;
  double max_tracking_error = 0;
  explicit LoopResult(std::size_t n) : latency_ns(n), jitter_ns(n) {}
};

// The memory-mapped I/O of a firmware loop: a sensor register block and an actuator register.
struct Registers {
  volatile double sensor[5];  // x1, x2, x1', x2', t
  volatile double actuator[2];
};

template <typename Law>
void run_loop(long iterations, std::int64_t period_ns, Law&& law, LoopResult& r) {
  const Duffing plant{};
  Eigen::Vector2d q(1.0, 1.0), qd(plant.consistent_x1_velocity(2.0), 2.0), u = Eigen::Vector2d::Zero();
  const double dt = static_cast<double>(period_ns) * 1e-9;
  Registers io{};
  std::int64_t deadline = now_ns() + period_ns;
  gausstrack::support::start_counting_allocations();
  for (long k = 0; k < iterations; ++k) {
    const double t = static_cast<double>(k) * dt;
    io.sensor[0] = q(0);
    io.sensor[1] = q(1);
    io.sensor[2] = qd(0);
    io.sensor[3] = qd(1);
    io.sensor[4] = t;
    while (now_ns() < deadline) {
    }
    const std::int64_t start = now_ns();
    const Eigen::Vector2d qs(io.sensor[0], io.sensor[1]), qds(io.sensor[2], io.sensor[3]);
    const Eigen::Vector2d force = law(qs, qds, io.sensor[4]);
    io.actuator[0] = force(0);
    io.actuator[1] = force(1);
    const std::int64_t end = now_ns();
    r.latency_ns.add(static_cast<double>(end - start));
    r.jitter_ns.add(static_cast<double>(start - deadline));
    deadline += period_ns;
    if (end > deadline) deadline = end + period_ns;  // overran: start the next period afresh

    // The plant over one period under the held force (semi-implicit Euler), outside the timing.
    u(0) = io.actuator[0];
    u(1) = io.actuator[1];
    const Eigen::Vector2d a = (u - plant.spring_damper_force(q, qd)).cwiseQuotient(Eigen::Vector2d(plant.m1, plant.m2));
    qd += dt * a;
    q += dt * qd;
    r.max_tracking_error = std::max(r.max_tracking_error, std::abs(plant.phi(q, t + dt)(0)));
  }
  r.allocations = gausstrack::support::stop_counting_allocations();
}

void print(const char* name, const LoopResult& r) {
  const auto& l = r.latency_ns;
  std::printf("%-14s latency p50 %7.0f ns  p99 %7.0f  p99.9 %7.0f  max %8.0f | jitter p99 %6.0f ns  max %8.0f | "
              "allocations %ld | max tracking error %.2e\n",
              name, l.quantile(0.5), l.quantile(0.99), l.quantile(0.999), l.max(), r.jitter_ns.quantile(0.99),
              r.jitter_ns.max(), r.allocations, r.max_tracking_error);
  // Histogram on a log2 scale of nanoseconds.
  long bins[32] = {};
  for (double v : l.values()) {
    int b = 0;
    while (b < 31 && v >= static_cast<double>(1L << (b + 1))) ++b;
    ++bins[b];
  }
  for (int b = 0; b < 32; ++b)
    if (bins[b] > 0)
      std::printf("    [%8ld, %8ld) ns %9ld  %s\n", 1L << b, 1L << (b + 1), bins[b],
                  std::string(static_cast<std::size_t>(std::ceil(40.0 * static_cast<double>(bins[b]) /
                                                                  static_cast<double>(l.count()))),
                              '#').c_str());
}

nlohmann::ordered_json json(const LoopResult& r) {
  return {{"latency_ns", gausstrack::nodes::percentiles_json(r.latency_ns)},
          {"jitter_ns", gausstrack::nodes::percentiles_json(r.jitter_ns)},
          {"allocations", r.allocations},
          {"max_tracking_error", r.max_tracking_error}};
}

}  // namespace

int main(int argc, char** argv) {
  long iterations = 1000000;
  double period_us = 10;
  std::string out;
  CLI::App app("The Duffing law (eq. 35) against its closed form in a paced loop, as firmware would run it.");
  app.add_option("--iterations", iterations, "loop iterations")->check(CLI::PositiveNumber)->capture_default_str();
  app.add_option("--period-us", period_us, "loop period [us]")->check(CLI::PositiveNumber)->capture_default_str();
  app.add_option("--out", out, "write the percentiles as JSON to this file");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;  // --help, or a usage error (printed)
  }
  if (!std::isfinite(period_us)) return std::fprintf(stderr, "error: --period-us must be finite\n"), 2;
  const auto period_ns = static_cast<std::int64_t>(std::llround(period_us * 1e3));
  const auto n = static_cast<std::size_t>(iterations);

  const Duffing m{};
  LoopResult closed(n), library(n);
  run_loop(iterations, period_ns, [&](const Eigen::Vector2d& q, const Eigen::Vector2d& qd, double t) {
    return gausstrack::bench::duffing_closed_form_force(m, q, qd, t);
  }, closed);

  gausstrack::TrackingController<Duffing> controller;
  gausstrack::TrackingController<Duffing>::Output output;
  run_loop(iterations, period_ns, [&](const Eigen::Vector2d& q, const Eigen::Vector2d& qd, double t) {
    controller.compute(q, qd, t, output);
    return Eigen::Vector2d(output.force);
  }, library);

  std::printf("firmware loop: %ld iterations at %.1f us, Duffing oscillator (eq. 35), same run\n", iterations,
              period_us);
  print("closed form", closed);
  print("gausstrack", library);
  std::printf("ratio of medians (gausstrack / closed form): %.2f\n",
              library.latency_ns.quantile(0.5) / closed.latency_ns.quantile(0.5));
  if (!out.empty()) {
    const nlohmann::ordered_json j = {{"iterations", iterations},
                                      {"period_us", period_us},
                                      {"closed_form", json(closed)},
                                      {"gausstrack", json(library)}};
    std::ofstream f(out);
    f << j.dump(2) << '\n';
    if (!f) return std::fprintf(stderr, "error: cannot write %s\n", out.c_str()), 1;
  }
  return library.allocations == 0 ? 0 : 1;
}
