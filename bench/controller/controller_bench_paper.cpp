// The paper's systems: the coupled Duffing oscillator (eq. 35) with its hand-derived force, the
// pendulum (eqs. 33-34) and the nonholonomic particle (eqs. 36-38).
#include "controller_bench.hpp"
#include "gausstrack/systems/coupled_duffing.hpp"
#include "gausstrack/systems/nonholonomic_particle.hpp"
#include "gausstrack/systems/pendulum.hpp"

namespace gausstrack::bench {
namespace {

using Duffing = systems::CoupledDuffing<double>;

// Q' = (r, -r) / (1/m1 + 1/m2), r = s''(t) - (a1 - a2), a = A^-1 (Q - f): eq. (32) worked out by
// hand for D = [1, -1], A = diag(m1, m2), Q = 0.
void bench_duffing_closed_form(benchmark::State& state) {
  static const States<Duffing> s;
  const Duffing m{};
  measure(state, [&](std::size_t k) {
    const auto& q = s.q[k];
    const auto& qd = s.qd[k];
    const double d = q(0) - q(1), dd = qd(0) - qd(1), x2 = q(1);
    const double coupling = m.k1 * d + m.c1 * dd + m.kb1 * d * d * d;
    const double ground = m.k2 * x2 + m.c2 * qd(1) + m.kb2 * x2 * x2 * x2;
    const double a1 = -coupling / m.m1, a2 = -(ground - coupling) / m.m2;
    const double r = (m.trajectory.acceleration(s.t[k]) - (a1 - a2)) / (1 / m.m1 + 1 / m.m2);
    Eigen::Vector2d force(r, -r);
    benchmark::DoNotOptimize(force.data());
  });
}

const bool registered = [] {
  benchmark::RegisterBenchmark("baseline/timer_overhead", bench_timer_overhead);
  register_model<Duffing>("duffing");
  benchmark::RegisterBenchmark("baseline/duffing_2x1/closed_form", bench_duffing_closed_form);
  register_model<systems::Pendulum<double>>("pendulum");
  register_model<systems::NonholonomicParticle<double>>("particle");
  return true;
}();

}  // namespace
}  // namespace gausstrack::bench
