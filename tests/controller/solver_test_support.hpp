// Helpers shared by the solver's hard-case tests (hard_cases_test.cpp, solver_factorization_test.cpp).
#pragma once

#include <array>

#include "gausstrack/constraint_solver.hpp"
#include "test_support.hpp"

namespace gausstrack::test {

inline constexpr std::array<InverseStrategy, 4> kStrategies = {
    InverseStrategy::kCholeskyWithFallback, InverseStrategy::kSvd,
    InverseStrategy::kCompleteOrthogonal, InverseStrategy::kDampedLeastSquares};

template <int N, int P>
ConstraintSolver<N, P> solver_for(InverseStrategy s, double rank_tolerance = -1, double damping = 0) {
  SolverOptions<double> o;
  o.strategy = s;
  o.rank_tolerance = rank_tolerance;
  o.damping = damping;
  return ConstraintSolver<N, P>(o);
}

template <int N, int P>
void expect_all_finite(const ConstraintSolution<N, P>& s) {
  EXPECT_TRUE(s.acceleration.allFinite());
  EXPECT_TRUE(s.constraint_force.allFinite());
  EXPECT_TRUE(s.force_from_impressed.allFinite());
  EXPECT_TRUE(s.force_from_rhs.allFinite());
  EXPECT_TRUE(s.unconstrained_acceleration.allFinite());
}

template <int N, int P>
void expect_all_zero(const ConstraintSolution<N, P>& s) {
  EXPECT_TRUE(s.acceleration.isZero(0));
  EXPECT_TRUE(s.constraint_force.isZero(0));
  EXPECT_TRUE(s.force_from_impressed.isZero(0));
  EXPECT_TRUE(s.force_from_rhs.isZero(0));
  EXPECT_TRUE(s.unconstrained_acceleration.isZero(0));
}

}  // namespace gausstrack::test
