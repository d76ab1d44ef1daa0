// The paper's systems: the coupled Duffing oscillator (eq. 35) with its hand-derived force, the
// pendulum (eqs. 33-34) and the nonholonomic particle (eqs. 36-38).
#include "controller_bench.hpp"
#include "duffing_closed_form.hpp"
#include "gausstrack/systems/coupled_duffing.hpp"
#include "gausstrack/systems/nonholonomic_particle.hpp"
#include "gausstrack/systems/pendulum.hpp"

namespace gausstrack::bench {
namespace {

using Duffing = systems::CoupledDuffing<double>;

void bench_duffing_closed_form(benchmark::State& state) {
  static const States<Duffing> s;
  const Duffing m{};
  measure(state, [&](std::size_t k) {
    const Eigen::Vector2d force = duffing_closed_form_force(m, s.q[k], s.qd[k], s.t[k]);
    benchmark::DoNotOptimize(force.data());
  });
}

const bool registered = [] {
  benchmark::AddCustomContext("build_for_host_cpu", GAUSSTRACK_NATIVE_BUILD ? "yes (-march=native)" : "no (GAUSSTRACK_NATIVE=OFF)");
  benchmark::RegisterBenchmark("baseline/timer_overhead", bench_timer_overhead);
  register_model<Duffing>("duffing");
  benchmark::RegisterBenchmark("baseline/duffing_2x1/closed_form", bench_duffing_closed_form);
  register_model<systems::Pendulum<double>>("pendulum");
  register_model<systems::NonholonomicParticle<double>>("particle");
  return true;
}();

}  // namespace
}  // namespace gausstrack::bench
