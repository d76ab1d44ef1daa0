// Zero heap allocations per solve and per controller evaluation, proved two ways: Eigen's
// EIGEN_RUNTIME_NO_MALLOC check (eigen_assert active) and global operator new / malloc counters.
// Each mechanism is first shown to catch an allocation, so the zero counts mean something.
#undef NDEBUG
#define EIGEN_RUNTIME_NO_MALLOC

#include <vector>

#include "gausstrack/systems/coupled_duffing.hpp"
#include "gausstrack/systems/duffing_chain.hpp"
#include "gausstrack/systems/nonholonomic_particle.hpp"
#include "gausstrack/systems/pendulum.hpp"
#include "gausstrack/systems/planar_arm.hpp"
#include "gausstrack/tracking_controller.hpp"
#include "allocation_counter.hpp"
#include "test_support.hpp"

namespace gausstrack::test {
namespace {

// Runs `call` with both checks armed and returns the number of allocations seen.
template <typename F>
long allocations_during(F&& call) {
  Eigen::internal::set_is_malloc_allowed(false);
  const long n = support::allocations_during(call);
  Eigen::internal::set_is_malloc_allowed(true);
  return n;
}

TEST(Allocation, CounterCatchesAnAllocation) {
  const long n = allocations_during([] {
    std::vector<double> v(100, 1.0);
    ASSERT_EQ(v.size(), 100u);
  });
  EXPECT_GE(n, 1);
}

TEST(AllocationDeathTest, EigenNoMallocCatchesADynamicMatrix) {
  EXPECT_DEATH(allocations_during([] {
                 Eigen::MatrixXd m(8, 8);
                 m.setOnes();
               }),
               "");
}

template <int N, int P>
void expect_solver_allocation_free(const RandomSystem<N, P>& sys, InverseStrategy s, double damping = 0) {
  SolverOptions<double> o;
  o.strategy = s;
  o.damping = damping;
  ConstraintSolver<N, P> solver(o);
  ConstraintSolution<N, P> sol;
  const long n = allocations_during([&] {
    for (int i = 0; i < 10; ++i) {
      ASSERT_EQ(solver.solve(sys.A, sys.f, sys.Q, sys.D, sys.g, sol), Status::kOk);
      const Eigen::Matrix<double, N, 1> extra = solver.force_for_rhs(sys.g);
      ASSERT_TRUE(extra.allFinite());
    }
  });
  EXPECT_EQ(n, 0) << to_string(s) << " N=" << N << " P=" << P;
}

TEST(Allocation, SolverEveryStrategyAndSize) {
  RandomSource<double> rng(2);
  for (InverseStrategy s : {InverseStrategy::kCholeskyWithFallback, InverseStrategy::kSvd,
                            InverseStrategy::kCompleteOrthogonal, InverseStrategy::kDampedLeastSquares}) {
    expect_solver_allocation_free(rng.system<2, 1>(), s, 1e-3);
    expect_solver_allocation_free(rng.system<12, 6>(), s);
    // Rank-deficient: duplicated rows force the fallback and the truncated paths.
    auto sys = rng.system<12, 6>();
    sys.D.row(2) = sys.D.row(1);
    sys.g(2) = sys.g(1);
    expect_solver_allocation_free(sys, s);
  }
}

TEST(Allocation, SolverFailurePaths) {
  RandomSource<double> rng(3);
  auto sys = rng.system<2, 1>();
  sys.A(0, 0) = std::numeric_limits<double>::quiet_NaN();
  ConstraintSolver<2, 1> solver;
  ConstraintSolution<2, 1> sol;
  EXPECT_EQ(allocations_during([&] { solver.solve(sys.A, sys.f, sys.Q, sys.D, sys.g, sol); }), 0);
  sys.A = -Eigen::Matrix2d::Identity();
  EXPECT_EQ(allocations_during([&] { solver.solve(sys.A, sys.f, sys.Q, sys.D, sys.g, sol); }), 0);
}

// Natural-form models: the jets that derive D, g, e and e' live on the stack.
template <typename M>
void expect_controller_allocation_free(const M& model) {
  using S = typename M::Scalar;
  ControllerOptions<S> o;
  o.stabilization.omega = S(10);
  o.solver.min_singular_value = S(1e-3);  // the near-singularity floor and the force limit too
  TrackingController<M> controller(model, o);
  controller.set_force_limit(Eigen::Matrix<S, M::kDof, 1>::Constant(S(5)));
  typename TrackingController<M>::Output out;
  RandomSource<S> rng(4);
  const Eigen::Matrix<S, M::kDof, 1> q = rng.template matrix<M::kDof, 1>(), qd = rng.template matrix<M::kDof, 1>();
  const long n = allocations_during([&] {
    for (int i = 0; i < 10; ++i) ASSERT_EQ(controller.compute(q, qd, S(0.1) * S(i), out), Status::kOk);
  });
  EXPECT_EQ(n, 0);
}

TEST(Allocation, ControllerOnEveryShippedSystem) {
  expect_controller_allocation_free(systems::CoupledDuffing<double>{});
  expect_controller_allocation_free(systems::Pendulum<double>{});
  expect_controller_allocation_free(systems::NonholonomicParticle<double>{});
  expect_controller_allocation_free(systems::DuffingChain<12, 6>{});
  expect_controller_allocation_free(systems::PlanarArm<double>{});
  expect_controller_allocation_free(systems::CoupledDuffing<float>{});
  expect_controller_allocation_free(systems::PlanarArm<float>{});
  expect_controller_allocation_free(systems::NonholonomicParticle<float>{});
}

}  // namespace
}  // namespace gausstrack::test
