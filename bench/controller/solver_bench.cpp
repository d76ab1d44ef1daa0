// Cost of one ConstraintSolver::solve per generalized-inverse strategy, beside the literal
// formula of the paper (symmetric square root + JacobiSVD pseudo-inverses) measured in the same
// run. Size from GAUSSTRACK_BENCH_N / GAUSSTRACK_BENCH_P.
#include <benchmark/benchmark.h>

#include <random>

#include "gausstrack/constraint_solver.hpp"
#include "gausstrack/reference/literal_formulas.hpp"

namespace {

constexpr int N = GAUSSTRACK_BENCH_N;
constexpr int P = GAUSSTRACK_BENCH_P;

struct Problem {
  Eigen::Matrix<double, N, N> A;
  Eigen::Matrix<double, N, 1> f, Q;
  Eigen::Matrix<double, P, N> D;
  Eigen::Matrix<double, P, 1> g;
};

Problem make_problem() {
  std::mt19937_64 rng(1993);
  std::uniform_real_distribution<double> u(-1, 1);
  auto fill = [&](auto& m) {
    for (Eigen::Index i = 0; i < m.size(); ++i) m(i) = u(rng);
  };
  Problem p;
  Eigen::Matrix<double, N, N> r;
  fill(r);
  p.A = r * r.transpose() + N * Eigen::Matrix<double, N, N>::Identity();
  fill(p.f);
  fill(p.Q);
  fill(p.D);
  fill(p.g);
  return p;
}

template <gausstrack::InverseStrategy S>
void BM_Solve(benchmark::State& state) {
  const Problem p = make_problem();
  gausstrack::SolverOptions<double> o;
  o.strategy = S;
  o.damping = 1e-6;
  gausstrack::ConstraintSolver<N, P> solver(o);
  gausstrack::ConstraintSolution<N, P> sol;
  for (auto _ : state) {
    benchmark::DoNotOptimize(solver.solve(p.A, p.f, p.Q, p.D, p.g, sol));
    benchmark::DoNotOptimize(sol.constraint_force.data());
  }
  state.SetLabel(std::string(gausstrack::to_string(sol.diagnostics.strategy_used)));
}

void BM_LiteralFormulas(benchmark::State& state) {
  const Problem p = make_problem();
  for (auto _ : state) {
    auto out = gausstrack::reference::literal_formulas<N, P, double>(p.A, p.f, p.Q, p.D, p.g);
    benchmark::DoNotOptimize(out.constraint_force.data());
  }
}

BENCHMARK(BM_Solve<gausstrack::InverseStrategy::kCholeskyWithFallback>);
BENCHMARK(BM_Solve<gausstrack::InverseStrategy::kSvd>);
BENCHMARK(BM_Solve<gausstrack::InverseStrategy::kCompleteOrthogonal>);
BENCHMARK(BM_Solve<gausstrack::InverseStrategy::kDampedLeastSquares>);
BENCHMARK(BM_LiteralFormulas);

}  // namespace

BENCHMARK_MAIN();
