// Cross-checks run per size (N, P) on reproducible random systems: the solver's every strategy,
// the paper's literal formulas, the compact form and a Lagrange-multiplier (KKT) solve must
// agree, and the defining properties of the constrained motion must hold. Each size is
// instantiated in its own translation unit; the oracles run at dynamic size.
#pragma once

#include <array>
#include <limits>

#include "gausstrack/constraint_solver.hpp"
#include "test_support.hpp"

namespace gausstrack::test {

template <int N_, int P_>
struct Size {
  static constexpr int N = N_;
  static constexpr int P = P_;
};

inline constexpr std::array<InverseStrategy, 4> kAllStrategies = {
    InverseStrategy::kCholeskyWithFallback, InverseStrategy::kSvd,
    InverseStrategy::kCompleteOrthogonal, InverseStrategy::kDampedLeastSquares /* lambda = 0 */};

template <typename S>
class CrossCheck : public ::testing::Test {};
TYPED_TEST_SUITE_P(CrossCheck);

TYPED_TEST_P(CrossCheck, AllFormulationsAgree) {
  constexpr int N = TypeParam::N, P = TypeParam::P;
  constexpr double tol = Tolerance<double>::kAgree;
  RandomSource<double> rng(N * 100 + P);
  std::array<ConstraintSolver<N, P>, kAllStrategies.size()> solvers;
  for (std::size_t k = 0; k < solvers.size(); ++k) {
    SolverOptions<double> o;
    o.strategy = kAllStrategies[k];
    solvers[k].set_options(o);
  }
  ConstraintSolution<N, P> sol;
  const int repeat = test_repeat();
  for (int it = 0; it < repeat; ++it) {
    const auto s = rng.template system<N, P>();
    // The literal formulas at run-time size (compiled once, oracles.cpp, for every size).
    const oracle::Literal dynamic = oracle::literal_formulas(s.A, s.f, s.Q, s.D, s.g);
    struct {
      Eigen::Matrix<double, N, 1> acceleration, constraint_force, force_from_impressed, force_from_rhs;
    } lit{dynamic.acceleration, dynamic.constraint_force, dynamic.force_from_impressed, dynamic.force_from_rhs};
    const Eigen::Matrix<double, N, 1> a = s.A.llt().solve(s.Q - s.f);
    const double force_scale = inf_norm(lit.constraint_force) + inf_norm(s.Q - s.f);
    const double acc_scale = inf_norm(lit.acceleration) + inf_norm(a);

    ASSERT_TRUE(near(compact_form_force(s), lit.constraint_force, tol, force_scale,
                     "compact form vs literal eq. 32"))
        << "system " << it;
    const auto [kkt_qdd, kkt_force] = kkt_solution(s);
    ASSERT_TRUE(near(kkt_force, lit.constraint_force, tol, force_scale, "KKT vs literal eq. 32"))
        << "system " << it;
    ASSERT_TRUE(near(kkt_qdd, lit.acceleration, tol, acc_scale, "KKT vs literal eq. 30"))
        << "system " << it;

    for (std::size_t k = 0; k < solvers.size(); ++k) {
      const char* name = to_string(kAllStrategies[k]);
      ASSERT_EQ(solvers[k].solve(s.A, s.f, s.Q, s.D, s.g, sol), Status::kOk) << name;
      ASSERT_EQ(sol.diagnostics.rank, P) << name << " system " << it;
      ASSERT_FALSE(sol.diagnostics.has(warning::kConstraintsNotMet)) << name;
      ASSERT_TRUE(near(sol.acceleration, lit.acceleration, tol, acc_scale, name)) << "q'' system " << it;
      ASSERT_TRUE(near(sol.constraint_force, lit.constraint_force, tol, force_scale, name))
          << "Q' system " << it;
      ASSERT_TRUE(near(sol.force_from_impressed, lit.force_from_impressed, tol, force_scale, name))
          << "first term of eq. 32, system " << it;
      ASSERT_TRUE(near(sol.force_from_rhs, lit.force_from_rhs, tol, force_scale, name))
          << "second term of eq. 32, system " << it;
    }
  }
}

TYPED_TEST_P(CrossCheck, EquationsOfMotionAndConstraintsHold) {
  constexpr int N = TypeParam::N, P = TypeParam::P;
  constexpr double tol = Tolerance<double>::kIdentity;
  RandomSource<double> rng(N * 100 + P + 1);
  ConstraintSolver<N, P> solver;
  ConstraintSolution<N, P> sol;
  const int repeat = test_repeat();
  for (int it = 0; it < repeat; ++it) {
    const auto s = rng.template system<N, P>();
    ASSERT_EQ(solver.solve(s.A, s.f, s.Q, s.D, s.g, sol), Status::kOk);
    const Eigen::Matrix<double, N, 1> lhs = s.A * sol.acceleration + s.f;
    const Eigen::Matrix<double, N, 1> rhs = s.Q + sol.constraint_force;
    ASSERT_TRUE(near(lhs, rhs, tol, inf_norm(s.A) * inf_norm(sol.acceleration) + inf_norm(s.f) +
                                        inf_norm(s.Q) + inf_norm(sol.constraint_force),
                     "A q'' + f = Q + Q'"))
        << "system " << it;
    const Eigen::Matrix<double, P, 1> dq = s.D * sol.acceleration;
    ASSERT_TRUE(near(dq, s.g, tol, inf_norm(s.g) + inf_norm(s.D) * inf_norm(sol.acceleration),
                     "D q'' = g"))
        << "system " << it;
    // The reported residual is ||D q'' - g||. Both are rounding, so they agree only to the
    // rounding of D q'' - g summed in another order (the solver's dot products keep partial sums
    // side by side): n eps times the largest a row's sum can be, N |D|max |q''|max + |g|max.
    const double rounding = 4.0 * N * std::numeric_limits<double>::epsilon() *
                            (inf_norm(s.g) + N * inf_norm(s.D) * inf_norm(sol.acceleration));
    ASSERT_NEAR(sol.diagnostics.residual_norm, (dq - s.g).norm(), rounding);
  }
}

TYPED_TEST_P(CrossCheck, ForceDoesNoWorkOnAdmissibleMotions) {
  constexpr int N = TypeParam::N, P = TypeParam::P;
  RandomSource<double> rng(N * 100 + P + 2);
  ConstraintSolver<N, P> solver;
  ConstraintSolution<N, P> sol;
  const int repeat = test_repeat();
  for (int it = 0; it < repeat; ++it) {
    const auto s = rng.template system<N, P>();
    ASSERT_EQ(solver.solve(s.A, s.f, s.Q, s.D, s.g, sol), Status::kOk);
    const Eigen::Matrix<double, N, 1> v = null_space_vector<N, P>(s.D, rng);
    ASSERT_LT((s.D * v).norm(), 1e-12);
    // Q'^T v = 0 for every virtual displacement v with D v = 0 (eq. 11).
    ASSERT_LE(std::abs(sol.constraint_force.dot(v)),
              Tolerance<double>::kIdentity * sol.constraint_force.norm() * v.norm() + 1e-15)
        << "system " << it;
  }
}

TYPED_TEST_P(CrossCheck, GaussFunctionIsMinimal) {
  constexpr int N = TypeParam::N, P = TypeParam::P;
  RandomSource<double> rng(N * 100 + P + 3);
  ConstraintSolver<N, P> solver;
  ConstraintSolution<N, P> sol;
  const int repeat = test_repeat();
  for (int it = 0; it < repeat; ++it) {
    const auto s = rng.template system<N, P>();
    ASSERT_EQ(solver.solve(s.A, s.f, s.Q, s.D, s.g, sol), Status::kOk);
    const double g0 = gauss_function(s, sol.acceleration);
    for (double step : {1e-3, 1e-1, 1.0}) {
      const Eigen::Matrix<double, N, 1> v = step * null_space_vector<N, P>(s.D, rng);
      // G(q'' + v) - G(q'') = v^T A v >= 0 exactly (eq. 13); allow rounding of G's size.
      const double g1 = gauss_function(s, Eigen::Matrix<double, N, 1>(sol.acceleration + v));
      ASSERT_GE(g1 - g0, -1e-12 * (1 + g0)) << "system " << it << " step " << step;
      ASSERT_NEAR(g1 - g0, v.dot(s.A * v), 1e-9 * (1 + g0)) << "system " << it;
    }
  }
}

REGISTER_TYPED_TEST_SUITE_P(CrossCheck, AllFormulationsAgree, EquationsOfMotionAndConstraintsHold,
                            ForceDoesNoWorkOnAdmissibleMotions, GaussFunctionIsMinimal);

}  // namespace gausstrack::test
