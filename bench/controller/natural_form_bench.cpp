// Constraints in their natural form, measured beside their hand-written versions in the same run:
//   natural/<system>/derived       one controller call, rows derived from phi or psi by jets
//   natural/<system>/hand_written  the same call with D, g, e, e' written out by hand
// and the automatic differentiation itself, one constraint evaluation producing D, e, e' and g:
//   jet/<system>/ours              our Jet (gradient + second directional derivative, one pass)
//   jet/<system>/eigen_autodiff    Eigen's unsupported AutoDiffScalar, fixed-size derivatives:
//                                  one pass with derivatives in (q, t) for D, e, e', and a nested
//                                  pass (AutoDiffScalar of AutoDiffScalar along (q', 1)) for g.
#include <Eigen/Core>
#include <unsupported/Eigen/AutoDiff>

#include "../../tests/controller/hand_written_systems.hpp"
#include "controller_bench.hpp"
#include "gausstrack/systems/coupled_duffing.hpp"
#include "gausstrack/systems/pendulum.hpp"
#include "gausstrack/systems/planar_arm.hpp"

namespace gausstrack::bench {
namespace {

template <typename M>
void bench_call(benchmark::State& state) {
  static const States<M> s;
  TrackingController<M> controller{M{}};
  typename TrackingController<M>::Output out;
  measure(state, [&](std::size_t k) {
    benchmark::DoNotOptimize(controller.compute(s.q[k], s.qd[k], s.t[k], out));
    benchmark::DoNotOptimize(out.force.data());
  });
}

template <typename M>
void bench_jet(benchmark::State& state) {
  static const States<M> s;
  const M model{};
  TermsOf<M> terms;
  measure(state, [&](std::size_t k) {
    derive_holonomic_rows<0>(model, s.q[k], s.qd[k], s.t[k], terms);
    benchmark::DoNotOptimize(terms.constraint_rhs.data());
    benchmark::DoNotOptimize(terms.constraint_matrix.data());
  });
}

template <typename M>
void bench_eigen_autodiff(benchmark::State& state) {
  static const States<M> s;
  const M model{};
  constexpr int N = M::kDof, H = M::kConstraints;
  using Grad = Eigen::AutoDiffScalar<Eigen::Matrix<double, N + 1, 1>>;
  using Inner = Eigen::AutoDiffScalar<Eigen::Matrix<double, 1, 1>>;
  using Outer = Eigen::AutoDiffScalar<Eigen::Matrix<Inner, 1, 1>>;
  TermsOf<M> terms;
  auto rows = [&](std::size_t k) {
    const auto& q = s.q[k];
    const auto& qd = s.qd[k];
    const double t = s.t[k];
    // Pass 1: derivatives in (q, t): D = phi_q, e' = phi_q q' + phi_t.
    Eigen::Matrix<Grad, N, 1> qg;
    for (int i = 0; i < N; ++i) qg(i) = Grad(q(i), N + 1, i);
    const Eigen::Matrix<Grad, H, 1> r1 = model.phi(qg, Grad(t, N + 1, N));
    // Pass 2: second derivative along (q', 1), nested.
    Eigen::Matrix<Outer, N, 1> qo;
    for (int i = 0; i < N; ++i) {
      qo(i).value() = Inner(q(i), Eigen::Matrix<double, 1, 1>(qd(i)));
      qo(i).derivatives()(0) = Inner(qd(i), Eigen::Matrix<double, 1, 1>(0.0));
    }
    Outer to;
    to.value() = Inner(t, Eigen::Matrix<double, 1, 1>(1.0));
    to.derivatives()(0) = Inner(1.0, Eigen::Matrix<double, 1, 1>(0.0));
    const Eigen::Matrix<Outer, H, 1> r2 = model.phi(qo, to);
    for (int j = 0; j < H; ++j) {
      terms.constraint_matrix.row(j) = r1(j).derivatives().template head<N>().transpose();
      terms.constraint_error(j) = r1(j).value();
      terms.constraint_error_rate(j) = r1(j).derivatives().template head<N>().dot(qd) + r1(j).derivatives()(N);
      terms.constraint_rhs(j) = -r2(j).derivatives()(0).derivatives()(0);
    }
  };
  measure(state, [&](std::size_t k) {
    rows(k);
    benchmark::DoNotOptimize(terms.constraint_rhs.data());
    benchmark::DoNotOptimize(terms.constraint_matrix.data());
  });
  // Both computed the same rows (else the comparison would be of different work).
  rows(63);
  TermsOf<M> ours;
  derive_holonomic_rows<0>(model, s.q[63], s.qd[63], s.t[63], ours);
  const double scale = 1 + ours.constraint_rhs.cwiseAbs().maxCoeff() + ours.constraint_matrix.cwiseAbs().maxCoeff();
  if ((ours.constraint_rhs - terms.constraint_rhs).cwiseAbs().maxCoeff() > 1e-12 * scale ||
      (ours.constraint_matrix - terms.constraint_matrix).cwiseAbs().maxCoeff() > 1e-12 * scale ||
      (ours.constraint_error_rate - terms.constraint_error_rate).cwiseAbs().maxCoeff() > 1e-12 * scale)
    state.SkipWithError("Eigen AutoDiff and our jets disagree");
}

const bool registered = [] {
  benchmark::RegisterBenchmark("natural/duffing_2x1/derived", bench_call<systems::CoupledDuffing<double>>);
  benchmark::RegisterBenchmark("natural/duffing_2x1/hand_written", bench_call<test::HandDuffing<double>>);
  benchmark::RegisterBenchmark("natural/pendulum_2x1/derived", bench_call<systems::Pendulum<double>>);
  benchmark::RegisterBenchmark("natural/pendulum_2x1/hand_written", bench_call<test::HandPendulum<double>>);
  benchmark::RegisterBenchmark("natural/arm_3x2/derived", bench_call<systems::PlanarArm<double>>);
  benchmark::RegisterBenchmark("natural/arm_3x2/hand_written", bench_call<test::HandArm<double>>);
  benchmark::RegisterBenchmark("jet/pendulum_2x1/ours", bench_jet<systems::Pendulum<double>>);
  benchmark::RegisterBenchmark("jet/pendulum_2x1/eigen_autodiff", bench_eigen_autodiff<systems::Pendulum<double>>);
  benchmark::RegisterBenchmark("jet/arm_3x2/ours", bench_jet<systems::PlanarArm<double>>);
  benchmark::RegisterBenchmark("jet/arm_3x2/eigen_autodiff", bench_eigen_autodiff<systems::PlanarArm<double>>);
  return true;
}();

}  // namespace
}  // namespace gausstrack::bench
