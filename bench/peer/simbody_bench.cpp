// The law beside Simbody 3.7 on the same constrained motion: the planar arm's hand on its circle
// (bench/peer/simbody_arm.hpp). Before any timing the two are held to the same accelerations at
// every benchmark state (to 1e-9 relative; the program exits 1 otherwise):
//   peer/arm/simbody   Simbody: the state's time, q and u set, realize(Stage::Acceleration) (its
//                      O(n) kinematics, mass properties, constraint Jacobian and multipliers)
//   peer/arm/law       TrackingController<PlanarArm>, stabilization off (as Simbody has none):
//                      the model's terms and eq. (32), with its checks, diagnostics and q''
//   peer/arm/kkt       the model's terms and the dynamic-size KKT LU (bench_dynamic_kkt, as
//   controller_bench's baseline): what a user
//                      writes without either library
#include <benchmark/benchmark.h>

#include <cstdio>

#include "../controller/controller_bench.hpp"
#include "gausstrack/systems/planar_arm.hpp"
#include "simbody_arm.hpp"

namespace gausstrack::bench {
namespace {

using Arm = systems::PlanarArm<double>;

ControllerOptions<double> unstabilized() {
  ControllerOptions<double> o;
  o.stabilization = {0.0, 0.0};
  return o;
}

void bench_simbody(benchmark::State& state) {
  static const States<Arm> s;
  peer::SimbodyArm simbody(peer::arm_parameters(Arm{}));
  Eigen::Vector3d qdd;
  measure(state, [&](std::size_t k) {
    simbody.acceleration(s.q[k].data(), s.qd[k].data(), s.t[k], qdd.data());
    benchmark::DoNotOptimize(qdd.data());
  });
}

void bench_law(benchmark::State& state) {
  static const States<Arm> s;
  TrackingController<Arm> law{Arm{}, unstabilized()};
  TrackingController<Arm>::Output out;
  measure(state, [&](std::size_t k) {
    benchmark::DoNotOptimize(law.compute(s.q[k], s.qd[k], s.t[k], out));
    benchmark::DoNotOptimize(out.acceleration.data());
  });
}

// The accuracy gate: the law's q'' against Simbody's at every benchmark state.
bool same_motion() {
  const States<Arm> s;
  peer::SimbodyArm simbody(peer::arm_parameters(Arm{}));
  TrackingController<Arm> law{Arm{}, unstabilized()};
  TrackingController<Arm>::Output out;
  double worst = 0;
  for (int k = 0; k < States<Arm>::kCount; ++k) {
    Eigen::Vector3d qdd;
    simbody.acceleration(s.q[k].data(), s.qd[k].data(), s.t[k], qdd.data());
    if (failed(law.compute(s.q[k], s.qd[k], s.t[k], out)))
      return std::fprintf(stderr, "the law failed at state %d\n", k), false;
    worst = std::max(worst, (out.acceleration - qdd).norm() / (1.0 + qdd.norm()));
  }
  std::printf("law vs Simbody 3.7: q'' agree to %.3g (relative, %d states; required 1e-9)\n", worst,
              States<Arm>::kCount);
  return worst <= 1e-9;
}

}  // namespace
}  // namespace gausstrack::bench

int main(int argc, char** argv) {
  using namespace gausstrack::bench;
  if (!same_motion()) return 1;
  benchmark::RegisterBenchmark("peer/arm/simbody", bench_simbody);
  benchmark::RegisterBenchmark("peer/arm/law", bench_law);
  benchmark::RegisterBenchmark("peer/arm/kkt", bench_dynamic_kkt<Arm>);
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
