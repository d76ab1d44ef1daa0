// The actuated law (actuation.hpp) beside the plain law of eq. (32) on the same model, in the same
// run, both factoring A on every call (the actuated law always does):
//   actuation/<case>/actuated   ActuatedController: the commands of K actuators (Gauss's weight)
//   actuation/<case>/law        TrackingController on the same model, every coordinate actuated,
//                               reuse_factorization off
#include "controller_bench.hpp"
#include "gausstrack/actuation.hpp"
#include "gausstrack/systems/coupled_duffing.hpp"
#include "gausstrack/systems/duffing_chain.hpp"
#include "gausstrack/systems/planar_arm.hpp"

namespace gausstrack::bench {
namespace {

// A model with the actuators `Columns` name: B's column j pushes coordinate Columns[j].
template <typename M, int... Columns>
struct Actuated : M {
  static constexpr int kActuators = sizeof...(Columns);
  void actuation(const Eigen::Matrix<double, M::kDof, 1>&, double,
                 Eigen::Matrix<double, M::kDof, kActuators>& b) const noexcept {
    b.setZero();
    int j = 0;
    ((b(Columns, j++) = 1.0), ...);
  }
};

template <typename A>
void bench_actuated(benchmark::State& state) {
  static const States<A> s;
  ActuatedController<A> controller{A{}};
  typename ActuatedController<A>::Output out;
  measure(state, [&](std::size_t k) {
    benchmark::DoNotOptimize(controller.compute(s.q[k], s.qd[k], s.t[k], out));
    benchmark::DoNotOptimize(out.control.data());
  });
}

template <typename M>
void bench_plain(benchmark::State& state) {
  static const States<M> s;
  ControllerOptions<double> o;
  o.solver.reuse_factorization = false;
  TrackingController<M> controller{M{}, o};
  typename TrackingController<M>::Output out;
  measure(state, [&](std::size_t k) {
    benchmark::DoNotOptimize(controller.compute(s.q[k], s.qd[k], s.t[k], out));
    benchmark::DoNotOptimize(out.force.data());
  });
}

using Duffing = systems::CoupledDuffing<double>;
using Arm = systems::PlanarArm<double>;
using Chain = systems::DuffingChain<8, 4, double>;

const bool registered = [] {
  benchmark::RegisterBenchmark("actuation/duffing_1_of_2/actuated", bench_actuated<Actuated<Duffing, 0>>);
  benchmark::RegisterBenchmark("actuation/duffing_1_of_2/law", bench_plain<Duffing>);
  benchmark::RegisterBenchmark("actuation/arm_3_of_3/actuated", bench_actuated<Actuated<Arm, 0, 1, 2>>);
  benchmark::RegisterBenchmark("actuation/arm_2_of_3/actuated", bench_actuated<Actuated<Arm, 0, 1>>);
  benchmark::RegisterBenchmark("actuation/arm_3_of_3/law", bench_plain<Arm>);
  benchmark::RegisterBenchmark("actuation/chain8_4_of_8/actuated", bench_actuated<Actuated<Chain, 0, 2, 4, 6>>);
  benchmark::RegisterBenchmark("actuation/chain8_8_of_8/actuated",
                               bench_actuated<Actuated<Chain, 0, 1, 2, 3, 4, 5, 6, 7>>);
  benchmark::RegisterBenchmark("actuation/chain8_8_of_8/law", bench_plain<Chain>);
  return true;
}();

}  // namespace
}  // namespace gausstrack::bench
