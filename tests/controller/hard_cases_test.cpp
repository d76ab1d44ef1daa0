// Hard cases, each with its stated expectation: redundant and inconsistent constraints, nearly
// singular D, badly conditioned and badly scaled mass matrices, D = 0, P = N - 1, non-finite and
// extreme input. Across all of them no finite input yields a non-finite output.
#include <array>
#include <limits>
#include <string>

#include "gausstrack/constraint_solver.hpp"
#include "solver_test_support.hpp"
#include "test_support.hpp"

namespace gausstrack::test {
namespace {

// Expectation: adding a duplicate or a linear combination of rows (with the matching g) changes
// nothing: same q'' and Q' as the 3 independent rows, rank 3 reported, kRankDeficient set,
// the constraints still met.
TEST(HardCases, RedundantRowsGiveTheSameMotion) {
  RandomSource<double> rng(1);
  for (InverseStrategy s : kStrategies) {
    auto base = solver_for<6, 3>(InverseStrategy::kSvd);
    auto redundant = solver_for<6, 5>(s);
    ConstraintSolution<6, 3> ref;
    ConstraintSolution<6, 5> sol;
    for (int it = 0; it < 100; ++it) {
      const auto sys = rng.system<6, 3>();
      Eigen::Matrix<double, 5, 6> D;
      Eigen::Matrix<double, 5, 1> g;
      D << sys.D, sys.D.row(1), 0.3 * sys.D.row(0) - 2.0 * sys.D.row(2);
      g << sys.g, sys.g(1), 0.3 * sys.g(0) - 2.0 * sys.g(2);
      ASSERT_EQ(base.solve(sys.A, sys.f, sys.Q, sys.D, sys.g, ref), Status::kOk);
      ASSERT_EQ(redundant.solve(sys.A, sys.f, sys.Q, D, g, sol), Status::kOk) << to_string(s);
      const double scale = inf_norm(ref.constraint_force) + inf_norm(sys.Q - sys.f);
      EXPECT_TRUE(near(sol.constraint_force, ref.constraint_force, 1e-9, scale, to_string(s)));
      EXPECT_TRUE(near(sol.acceleration, ref.acceleration, 1e-9, inf_norm(ref.acceleration) + 1, to_string(s)));
      EXPECT_EQ(sol.diagnostics.rank, 3) << to_string(s);
      EXPECT_TRUE(sol.diagnostics.has(warning::kRankDeficient)) << to_string(s);
      EXPECT_FALSE(sol.diagnostics.has(warning::kConstraintsNotMet)) << to_string(s);
      if (s == InverseStrategy::kCholeskyWithFallback || s == InverseStrategy::kDampedLeastSquares) {
        EXPECT_TRUE(sol.diagnostics.has(warning::kFellBackToSvd));
      }
    }
  }
}

// Expectation: two copies of a row asking for different g are met in the least-squares sense:
// the same motion as one copy with the mean right side, kConstraintsNotMet set, and the residual
// ||D q'' - g|| = |g1 - g2| / sqrt(2). At 6 coordinates with dense rows, and at 12 with each row
// touching 3 coordinates (the solver then sums only over each row's support, residual included).
template <int N>
void expect_inconsistent_rows_met_in_least_squares(unsigned seed, bool banded) {
  RandomSource<double> rng(seed);
  for (InverseStrategy s : kStrategies) {
    auto base = solver_for<N, 3>(InverseStrategy::kSvd);
    auto conflicting = solver_for<N, 5>(s);
    ConstraintSolution<N, 3> ref;
    ConstraintSolution<N, 5> sol;
    for (int it = 0; it < 100; ++it) {
      auto sys = rng.template system<N, 3>();
      if (banded)
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < N; ++j)
            if (j < 3 * i + 1 || j > 3 * i + 3) sys.D(i, j) = 0.0;
      const double g1 = sys.g(0), g2 = g1 + rng.uniform(0.5, 2);
      // Row 0 twice with different right sides, and a consistent copy of row 2.
      Eigen::Matrix<double, 5, N> D;
      Eigen::Matrix<double, 5, 1> g;
      D << sys.D, sys.D.row(0), sys.D.row(2);
      g << sys.g, g2, sys.g(2);
      sys.g(0) = 0.5 * (g1 + g2);
      ASSERT_EQ(base.solve(sys.A, sys.f, sys.Q, sys.D, sys.g, ref), Status::kOk);
      ASSERT_EQ(conflicting.solve(sys.A, sys.f, sys.Q, D, g, sol), Status::kOk);
      EXPECT_TRUE(near(sol.acceleration, ref.acceleration, 1e-9, inf_norm(ref.acceleration) + 1, to_string(s)));
      EXPECT_TRUE(sol.diagnostics.has(warning::kConstraintsNotMet)) << to_string(s);
      EXPECT_NEAR(sol.diagnostics.residual_norm, std::abs(g2 - g1) / std::sqrt(2.0), 1e-9) << to_string(s);
    }
  }
}

TEST(HardCases, InconsistentRowsAreMetInLeastSquares) {
  expect_inconsistent_rows_met_in_least_squares<6>(2, false);
  expect_inconsistent_rows_met_in_least_squares<12>(3, true);
}

// D A^(-1/2) with singular values (1, 1e-7, 1e-14). Expectation: the rank is what the tolerance
// says; with the default (6 eps ~ 1.3e-15) all three count and the 1e-14 direction is met with a
// large but finite force, flagged ill-conditioned; with tolerance 1e-10 the rank is 2, the force
// stays of the size |g| / 1e-7 and only the dropped direction is unmet.
TEST(HardCases, NearlySingularConstraintsFollowTheRankTolerance) {
  RandomSource<double> rng(3);
  for (InverseStrategy s : kStrategies) {
    if (s == InverseStrategy::kDampedLeastSquares) continue;  // has its own test below
    for (int it = 0; it < 50; ++it) {
      const Eigen::Matrix<double, 6, 6> A = Eigen::Matrix<double, 6, 6>::Identity();
      const Eigen::Matrix<double, 3, 6> D =
          rng.with_singular_values<3, 6>(Eigen::Vector3d(1.0, 1e-7, 1e-14));
      const Eigen::Matrix<double, 6, 1> f = rng.matrix<6, 1>(), Q = rng.matrix<6, 1>();
      const Eigen::Vector3d g = rng.matrix<3, 1>();
      ConstraintSolution<6, 3> sol;

      auto full = solver_for<6, 3>(s);
      ASSERT_EQ(full.solve(A, f, Q, D, g, sol), Status::kOk);
      expect_all_finite(sol);
      EXPECT_EQ(sol.diagnostics.rank, 3) << to_string(s);
      EXPECT_TRUE(sol.diagnostics.has(warning::kIllConditioned));
      EXPECT_GT(sol.diagnostics.condition_estimate, 1e12);
      EXPECT_FALSE(sol.diagnostics.has(warning::kConstraintsNotMet)) << to_string(s);

      auto truncated = solver_for<6, 3>(s, 1e-10);
      ASSERT_EQ(truncated.solve(A, f, Q, D, g, sol), Status::kOk);
      expect_all_finite(sol);
      EXPECT_EQ(sol.diagnostics.rank, 2) << to_string(s);
      EXPECT_TRUE(sol.diagnostics.has(warning::kRankDeficient));
      const double bound = 2.0 * (g.norm() + (D * (Q - f)).norm()) / 1e-7;
      EXPECT_LT(sol.constraint_force.norm(), bound) << to_string(s);
      // The kept directions are met: project the residual on the leading left singular vectors.
      const Eigen::JacobiSVD<Eigen::MatrixXd> svd{Eigen::MatrixXd(D), Eigen::ComputeFullU};
      const Eigen::Vector3d r = svd.matrixU().transpose() * (D * sol.acceleration - g);
      EXPECT_LT(r.head<2>().norm(), 1e-6 * (1 + g.norm())) << to_string(s);
    }
  }
}

// Expectation: damping bounds the force near a singular configuration: |B^+ r| <= |r| / (2 lambda)
// per direction, so |Q'| <= |L| |r| / (2 lambda); the weak constraint is given up (flagged) while
// strong ones are met to lambda^2 / sigma^2.
TEST(HardCases, DampingBoundsTheForceNearSingularity) {
  RandomSource<double> rng(4);
  const double lambda = 1e-3;
  auto damped = solver_for<6, 3>(InverseStrategy::kDampedLeastSquares, -1, lambda);
  ConstraintSolution<6, 3> sol;
  for (int it = 0; it < 100; ++it) {
    const Eigen::Matrix<double, 6, 6> A = Eigen::Matrix<double, 6, 6>::Identity();
    const Eigen::Matrix<double, 3, 6> D = rng.with_singular_values<3, 6>(Eigen::Vector3d(1.0, 0.5, 1e-9));
    const Eigen::Matrix<double, 6, 1> f = rng.matrix<6, 1>(), Q = rng.matrix<6, 1>();
    const Eigen::Vector3d g = rng.matrix<3, 1>();
    ASSERT_EQ(damped.solve(A, f, Q, D, g, sol), Status::kOk);
    expect_all_finite(sol);
    const double r = (g - D * (Q - f)).norm();
    EXPECT_LE(sol.constraint_force.norm(), r / (2 * lambda) * (1 + 1e-12));
    EXPECT_TRUE(sol.diagnostics.has(warning::kConstraintsNotMet));
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd{Eigen::MatrixXd(D), Eigen::ComputeFullU};
    const Eigen::Vector3d res = svd.matrixU().transpose() * (D * sol.acceleration - g);
    EXPECT_LT(std::abs(res(0)), 2 * lambda * lambda * r);
    EXPECT_LT(std::abs(res(1)), 2 * lambda * lambda / 0.25 * r);
  }
}

// Mass matrices with condition numbers from 1e6 to 1e10. Expectation: status ok, every output
// finite, A q'' + f = Q + Q' with a backward error below 1e-9 of ||A|| (||q''|| + ||a||) + ||f|| +
// ||Q|| + ||Q'|| (q'' = a + L^-T y passes the force through the Cholesky factor, whose condition
// sqrt(cond A) = 1e5 multiplies the rounding: ~1e-10 seen), D q'' = g to 1e-6 relative, and the
// rank-revealing, default and damped (lambda = 0) strategies agree with SVD to 1e-6 relative.
TEST(HardCases, IllConditionedMassMatrices) {
  RandomSource<double> rng(5);
  std::array<ConstraintSolver<6, 3>, 4> solvers;
  for (std::size_t k = 0; k < solvers.size(); ++k) solvers[k] = solver_for<6, 3>(kStrategies[k]);
  ConstraintSolution<6, 3> ref, sol;
  for (int it = 0; it < 100; ++it) {
    auto sys = rng.system<6, 3>();
    sys.A = rng.spd<6>(std::pow(10.0, rng.uniform(6, 10)));
    ASSERT_EQ(solvers[1].solve(sys.A, sys.f, sys.Q, sys.D, sys.g, ref), Status::kOk);
    for (std::size_t k = 0; k < solvers.size(); ++k) {
      const char* name = to_string(kStrategies[k]);
      ASSERT_EQ(solvers[k].solve(sys.A, sys.f, sys.Q, sys.D, sys.g, sol), Status::kOk) << name;
      expect_all_finite(sol);
      const Eigen::Matrix<double, 6, 1> lhs = sys.A * sol.acceleration + sys.f;
      const Eigen::Matrix<double, 6, 1> rhs = sys.Q + sol.constraint_force;
      // q'' = a + L^-T y may be small where a and L^-T y are large and cancel: the errors
      // scale with |a| = |A^-1 (Q - f)|, which reaches cond(A) |Q - f|.
      const double acc = inf_norm(sol.acceleration) + inf_norm(sol.unconstrained_acceleration);
      EXPECT_TRUE(near(lhs, rhs, 1e-9, inf_norm(sys.A) * acc + inf_norm(sys.f) + inf_norm(sys.Q) +
                                            inf_norm(sol.constraint_force), name));
      EXPECT_TRUE(near(sys.D * sol.acceleration, sys.g, 1e-6, inf_norm(sys.g) + inf_norm(sys.D) * acc, name));
      EXPECT_TRUE(near(sol.constraint_force, ref.constraint_force, 1e-6,
                       inf_norm(ref.constraint_force) + inf_norm(sys.Q - sys.f), name));
    }
  }
}

// Entries scaled from 1e-6 to 1e6: the same well-conditioned system in other units,
// q = S^-1 q~ with S = diag(10^[-3, 3]): A = S A~ S, f = S f~, Q = S Q~, D = D~ S, g = g~.
// Expectation: the physics does not change with units: S^-1 Q' = Q'~ and S q'' = q''~ to 1e-9
// relative for every strategy (cond(A) reaches 1e13 here, yet nothing is lost).
TEST(HardCases, BadlyScaledMassMatrices) {
  RandomSource<double> rng(12);
  for (InverseStrategy s : kStrategies) {
    auto solver = solver_for<6, 3>(s);
    ConstraintSolution<6, 3> unit, scaled;
    for (int it = 0; it < 100; ++it) {
      const auto base = rng.system<6, 3>(10.0);
      Eigen::Matrix<double, 6, 1> S;
      for (int i = 0; i < 6; ++i) S(i) = std::pow(10.0, rng.uniform(-3, 3));
      const Eigen::Matrix<double, 6, 6> A = S.asDiagonal() * base.A * S.asDiagonal();
      const Eigen::Matrix<double, 6, 1> f = S.asDiagonal() * base.f, Q = S.asDiagonal() * base.Q;
      const Eigen::Matrix<double, 3, 6> D = base.D * S.asDiagonal();
      ASSERT_EQ(solver.solve(base.A, base.f, base.Q, base.D, base.g, unit), Status::kOk);
      ASSERT_EQ(solver.solve(A, f, Q, D, base.g, scaled), Status::kOk) << to_string(s);
      expect_all_finite(scaled);
      const Eigen::Matrix<double, 6, 1> force = scaled.constraint_force.cwiseQuotient(S);
      const Eigen::Matrix<double, 6, 1> acc = scaled.acceleration.cwiseProduct(S);
      EXPECT_TRUE(near(force, unit.constraint_force, 1e-9,
                       inf_norm(unit.constraint_force) + inf_norm(base.Q - base.f), to_string(s)));
      EXPECT_TRUE(near(acc, unit.acceleration, 1e-9, inf_norm(unit.acceleration) + 1, to_string(s)));
    }
  }
}

// Expectation: D = 0 constrains nothing: rank 0, Q' = 0, q'' = A^-1 (Q - f); a nonzero g cannot
// be met and is flagged.
TEST(HardCases, ZeroConstraintMatrix) {
  RandomSource<double> rng(6);
  for (InverseStrategy s : kStrategies) {
    auto solver = solver_for<6, 3>(s);
    ConstraintSolution<6, 3> sol;
    const auto sys = rng.system<6, 3>();
    const Eigen::Matrix<double, 3, 6> D = Eigen::Matrix<double, 3, 6>::Zero();
    const Eigen::Matrix<double, 6, 1> a = sys.A.llt().solve(sys.Q - sys.f);
    ASSERT_EQ(solver.solve(sys.A, sys.f, sys.Q, D, Eigen::Vector3d::Zero(), sol), Status::kOk);
    EXPECT_EQ(sol.diagnostics.rank, 0) << to_string(s);
    EXPECT_TRUE(sol.constraint_force.isZero(0)) << to_string(s);
    EXPECT_TRUE(near(sol.acceleration, a, 1e-14, inf_norm(a), to_string(s)));
    EXPECT_FALSE(sol.diagnostics.has(warning::kConstraintsNotMet));
    ASSERT_EQ(solver.solve(sys.A, sys.f, sys.Q, D, sys.g, sol), Status::kOk);
    EXPECT_TRUE(sol.diagnostics.has(warning::kConstraintsNotMet)) << to_string(s);
    EXPECT_TRUE(sol.diagnostics.has(warning::kRankDeficient)) << to_string(s);
    EXPECT_NEAR(sol.diagnostics.residual_norm, sys.g.norm(), 1e-14);
    expect_all_finite(sol);
  }
}

// Expectation: P = N - 1 leaves one degree of freedom; every strategy matches a KKT solve.
TEST(HardCases, OneDegreeOfFreedomLeft) {
  RandomSource<double> rng(7);
  for (InverseStrategy s : kStrategies) {
    auto solver = solver_for<6, 5>(s);
    ConstraintSolution<6, 5> sol;
    for (int it = 0; it < 200; ++it) {
      const auto sys = rng.system<6, 5>();
      ASSERT_EQ(solver.solve(sys.A, sys.f, sys.Q, sys.D, sys.g, sol), Status::kOk);
      const auto [qdd, force] = kkt_solution(sys);
      // cond(D A^-1/2) of a random 5 x 6 D can reach 1e3, so allow 1e-9.
      EXPECT_TRUE(near(sol.constraint_force, force, 1e-9, inf_norm(force) + inf_norm(sys.Q - sys.f), to_string(s)));
      EXPECT_TRUE(near(sol.acceleration, qdd, 1e-9, inf_norm(qdd) + 1, to_string(s)));
    }
  }
}

// Expectation: NaN or Inf in any entry of any input fails with kNonFiniteInput, names the input,
// and leaves every output exactly zero.
TEST(HardCases, NonFiniteInputAnywhere) {
  RandomSource<double> rng(8);
  const auto sys = rng.system<6, 3>();
  for (InverseStrategy s : kStrategies) {
    auto solver = solver_for<6, 3>(s);
    ConstraintSolution<6, 3> sol;
    for (double bad : {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(),
                       -std::numeric_limits<double>::infinity()}) {
      auto check = [&](auto mutate, std::uint32_t flag, int count) {
        for (int i = 0; i < count; ++i) {
          auto copy = sys;
          mutate(copy, i);
          ASSERT_EQ(solver.solve(copy.A, copy.f, copy.Q, copy.D, copy.g, sol), Status::kNonFiniteInput);
          EXPECT_EQ(sol.diagnostics.non_finite_inputs, flag);
          expect_all_zero(sol);
          EXPECT_TRUE(solver.force_for_rhs(Eigen::Vector3d::Ones()).isZero(0));
        }
      };
      check([&](auto& c, int i) { c.A(i) = bad; }, input::kMassMatrix, 36);
      check([&](auto& c, int i) { c.f(i) = bad; }, input::kNonlinearForce, 6);
      check([&](auto& c, int i) { c.Q(i) = bad; }, input::kAppliedForce, 6);
      check([&](auto& c, int i) { c.D(i) = bad; }, input::kConstraintMatrix, 18);
      check([&](auto& c, int i) { c.g(i) = bad; }, input::kConstraintRhs, 3);
    }
  }
}

// Expectation: an indefinite, semidefinite or zero mass matrix fails with
// kMassMatrixNotPositiveDefinite and zero outputs.
TEST(HardCases, MassMatrixNotPositiveDefinite) {
  RandomSource<double> rng(9);
  const auto sys = rng.system<6, 3>();
  ConstraintSolver<6, 3> solver;
  ConstraintSolution<6, 3> sol;
  using M6 = Eigen::Matrix<double, 6, 6>;
  Eigen::Matrix<double, 6, 1> d;
  d << 1, -1, 2, 3, 1, 1;
  const M6 indefinite = d.asDiagonal();
  d(1) = 0;
  const M6 semidefinite = d.asDiagonal();
  for (const M6& A : {indefinite, semidefinite, M6::Zero().eval(), M6(-M6::Identity())}) {
    ASSERT_EQ(solver.solve(A, sys.f, sys.Q, sys.D, sys.g, sol), Status::kMassMatrixNotPositiveDefinite);
    expect_all_zero(sol);
  }
}

// Expectation: finite input at the edges of the double range never yields a non-finite output;
// it either solves (finite) or fails with a status and zero outputs.
TEST(HardCases, ExtremeMagnitudesNeverProduceNonFiniteOutput) {
  RandomSource<double> rng(10);
  for (InverseStrategy s : kStrategies) {
    auto solver = solver_for<6, 3>(s);
    ConstraintSolution<6, 3> sol;
    int failures = 0;
    for (int it = 0; it < 500; ++it) {
      auto sys = rng.system<6, 3>();
      const double sa = std::pow(10.0, rng.uniform(-300, 300));
      sys.A *= sa;
      sys.f *= std::pow(10.0, rng.uniform(-300, 300));
      sys.Q *= std::pow(10.0, rng.uniform(-300, 300));
      sys.D *= std::pow(10.0, rng.uniform(-300, 300));
      sys.g *= std::pow(10.0, rng.uniform(-300, 300));
      const Status st = solver.solve(sys.A, sys.f, sys.Q, sys.D, sys.g, sol);
      expect_all_finite(sol);
      if (failed(st)) {
        ++failures;
        EXPECT_NE(st, Status::kNonFiniteInput);
        expect_all_zero(sol);
      }
    }
    std::printf("[%s] extreme magnitudes: %d of 500 calls reported failure\n", to_string(s), failures);
  }
}

// Expectation: a finite answer whose residual D q'' - g overflows (nearly dependent rows near
// 1e150, g near 1e300: q'' near 1e162, each product D_ij q''_j beyond the range) cannot be
// verified, so it says so (constraints not met, residual infinite) instead of a NaN residual that
// no tolerance test catches.
TEST(HardCases, UnverifiableResidualIsReported) {
  Eigen::Matrix<double, 2, 3> D;
  D << 1, 1, 0, 1, 1 + 1e-12, 0;
  D *= 1e150;
  const Eigen::Vector2d g(0, 1e300);
  const Eigen::Vector3d zero = Eigen::Vector3d::Zero();
  for (InverseStrategy s : {InverseStrategy::kCholeskyWithFallback, InverseStrategy::kSvd}) {
    auto solver = solver_for<3, 2>(s);
    ConstraintSolution<3, 2> sol;
    const Status st = solver.solve(Eigen::Matrix3d::Identity(), zero, zero, D, g, sol);
    ASSERT_EQ(st, Status::kOk) << to_string(s);
    expect_all_finite(sol);
    // The case is what it claims: a finite answer whose residual overflows.
    ASSERT_FALSE(std::isfinite((D * sol.acceleration - g).norm()));
    EXPECT_GT(sol.acceleration.norm(), 1e161);
    EXPECT_TRUE(sol.diagnostics.has(warning::kConstraintsNotMet));
    EXPECT_EQ(sol.diagnostics.residual_norm, std::numeric_limits<double>::infinity());
  }
}

// Expectation: inconsistent rows are reported as not met when |D|^2 |q''|^2 overflows but the
// answer does not (A = 1e300 I keeps B = D L^-T near 1e10 for D near 1e160): the test falls back
// to norms taken without squaring instead of comparing against an infinite scale.
TEST(HardCases, InconsistentRowsAreReportedWhenTheScaleOverflows) {
  Eigen::Matrix<double, 2, 3> D;
  D << 1, 2, 0, 1, 2, 0;  // the same row twice
  D *= 1e160;
  const Eigen::Vector2d g(1, 3);  // asking for two values of one quantity
  const Eigen::Vector3d zero = Eigen::Vector3d::Zero();
  const Eigen::Matrix3d A = 1e300 * Eigen::Matrix3d::Identity();
  ASSERT_FALSE(std::isfinite(D.squaredNorm()));
  for (InverseStrategy s : kStrategies) {
    auto solver = solver_for<3, 2>(s);
    ConstraintSolution<3, 2> sol;
    ASSERT_EQ(solver.solve(A, zero, zero, D, g, sol), Status::kOk) << to_string(s);
    expect_all_finite(sol);
    EXPECT_TRUE(sol.diagnostics.has(warning::kConstraintsNotMet)) << to_string(s);
    // Least squares meets the mean of the two: D q'' = (2, 2), residual |(1, -1)| = sqrt(2)
    // (undamped normal equations of two equal rows fail the condition test and fall back).
    EXPECT_NEAR((D.row(0) * sol.acceleration)(0), 2.0, 1e-9) << to_string(s);
    EXPECT_NEAR(sol.diagnostics.residual_norm, std::sqrt(2.0), 1e-9) << to_string(s);
  }
}

// Found by fuzz_solver (it then reported a rank-0 answer, ok with an overflowing residual):
// entries near the range limit for which B = D L^-T is finite but its complete orthogonal
// decomposition is not. Expectation: kNonFiniteResult with zero outputs, not an answer.
TEST(HardCases, OverflowingDecompositionIsANonFiniteResult) {
  // The finding's numbers, each matrix column by column, but for A_33: the finding's A (equal
  // A_22, A_32, A_33) is indefinite, det A = -A_22 (A_21 - A_31)^2 / A_11 < 0, and a factorization
  // may reject it or not by rounding; doubling A_33 makes it positive definite.
  const double a[] = {0x0.64d0006000000p-1022, 0x0.100ff00000000p-1022, 0x1.effffffffffffp-1008,
                      0x1.d4d4d4d000001p+213,  0x1.d4d4d4d4d4d4dp+213,  0x1.d4d4d4d4d4d4dp+213,
                      0x1.d4d4d4d4d4d4dp+213,  0x1.d4d4d4d4d4d4dp+213,  0x1.d4d4d4d4d4d4dp+214};
  const double d[] = {0x1.d4d4d00000100p+213, 0x1.d4d4d4d4d4d4dp+213, 0x1.a2a2a2a2a2a2ap-349,
                      0x1.a2a2a2a2a2a2ap-1021, 0x0.0000200550000p-1022, 0x1.d4d4d2a2a2a00p+213};
  const Eigen::Matrix3d A = Eigen::Map<const Eigen::Matrix3d>(a);
  const Eigen::Matrix<double, 2, 3> D = Eigen::Map<const Eigen::Matrix<double, 2, 3>>(d);
  const Eigen::Vector3d f(0x1.a2a2a2a2a4d4dp-349, 0x1.a2a2a2a2a2a2ap-349, 0x1.a2a2a342a2a2ap-349);
  const Eigen::Vector3d Q(0x1.a2a0100feff2ap-349, 0x1.a2a2a2a2a2a2ap-349, -0x1.f2a2a2a2a2a34p+1008);
  const Eigen::Vector2d g(0x0.04d4d4d4d4d4dp-1022, 0x1.d00000080fe00p+213);
  // The case is what it claims: B = D L^-T finite (L from an independent Cholesky of A), with a
  // row whose squared norm overflows.
  const Eigen::LLT<Eigen::MatrixXd> llt{Eigen::MatrixXd(A)};
  ASSERT_EQ(llt.info(), Eigen::Success);
  Eigen::Matrix<double, 3, 2> bt = D.transpose();
  llt.matrixL().solveInPlace(bt);
  ASSERT_TRUE(bt.allFinite());
  ASSERT_FALSE(std::isfinite(bt.col(0).squaredNorm()));
  auto solver = solver_for<3, 2>(InverseStrategy::kCompleteOrthogonal, -1, 0x0.00000004d0033p-1022);
  ConstraintSolution<3, 2> sol;
  EXPECT_EQ(solver.solve(A, f, Q, D, g, sol), Status::kNonFiniteResult);
  expect_all_zero(sol);
}

}  // namespace
}  // namespace gausstrack::test
