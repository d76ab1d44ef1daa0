// Hard cases, each with its stated expectation: redundant and inconsistent constraints, nearly
// singular D, badly conditioned and badly scaled mass matrices, D = 0, P = N - 1, non-finite and
// extreme input. Across all of them no finite input yields a non-finite output.
#include <Eigen/Cholesky>
#include <array>
#include <limits>
#include <string>

#include "gausstrack/constraint_solver.hpp"
#include "test_support.hpp"

namespace gausstrack::test {
namespace {

constexpr std::array<InverseStrategy, 4> kStrategies = {
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
// ||D q'' - g|| = |g1 - g2| / sqrt(2).
TEST(HardCases, InconsistentRowsAreMetInLeastSquares) {
  RandomSource<double> rng(2);
  for (InverseStrategy s : kStrategies) {
    auto base = solver_for<6, 3>(InverseStrategy::kSvd);
    auto conflicting = solver_for<6, 5>(s);
    ConstraintSolution<6, 3> ref;
    ConstraintSolution<6, 5> sol;
    for (int it = 0; it < 100; ++it) {
      auto sys = rng.system<6, 3>();
      const double g1 = sys.g(0), g2 = g1 + rng.uniform(0.5, 2);
      // Row 0 twice with different right sides, and a consistent copy of row 2.
      Eigen::Matrix<double, 5, 6> D;
      Eigen::Matrix<double, 5, 1> g;
      D << sys.D, sys.D.row(0), sys.D.row(2);
      g << sys.g, g2, sys.g(2);
      sys.g(0) = 0.5 * (g1 + g2);
      ASSERT_EQ(base.solve(sys.A, sys.f, sys.Q, sys.D, sys.g, ref), Status::kOk);
      ASSERT_EQ(conflicting.solve(sys.A, sys.f, sys.Q, D, g, sol), Status::kOk);
      EXPECT_TRUE(near(sol.acceleration, ref.acceleration, 1e-9, inf_norm(ref.acceleration) + 1, to_string(s)));
      EXPECT_TRUE(sol.diagnostics.has(warning::kConstraintsNotMet)) << to_string(s);
      EXPECT_NEAR(sol.diagnostics.residual_norm, std::abs(g2 - g1) / std::sqrt(2.0), 1e-9);
    }
  }
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
  // The finding's numbers, each matrix column by column.
  const double a[] = {0x0.64d0006000000p-1022, 0x0.100ff00000000p-1022, 0x1.effffffffffffp-1008,
                      0x1.d4d4d4d000001p+213,  0x1.d4d4d4d4d4d4dp+213,  0x1.d4d4d4d4d4d4dp+213,
                      0x1.d4d4d4d4d4d4dp+213,  0x1.d4d4d4d4d4d4dp+213,  0x1.d4d4d4d4d4d4dp+213};
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

// float instantiation: the same answers as double within float precision.
TEST(HardCases, FloatMatchesDouble) {
  RandomSource<double> rng(11);
  for (InverseStrategy s : kStrategies) {
    SolverOptions<float> of;
    of.strategy = s;
    ConstraintSolver<6, 3, float> single(of);
    auto twice = solver_for<6, 3>(InverseStrategy::kSvd);
    ConstraintSolution<6, 3, float> sf;
    ConstraintSolution<6, 3> sd;
    for (int it = 0; it < 200; ++it) {
      auto sys = rng.system<6, 3>(10.0);
      const RandomSystem<6, 3, float> sysf{sys.A.cast<float>(), sys.f.cast<float>(), sys.Q.cast<float>(),
                                           sys.D.cast<float>(), sys.g.cast<float>()};
      // Solve the double problem on exactly the float data.
      sys = {sysf.A.cast<double>(), sysf.f.cast<double>(), sysf.Q.cast<double>(), sysf.D.cast<double>(),
             sysf.g.cast<double>()};
      ASSERT_EQ(single.solve(sysf.A, sysf.f, sysf.Q, sysf.D, sysf.g, sf), Status::kOk);
      ASSERT_EQ(twice.solve(sys.A, sys.f, sys.Q, sys.D, sys.g, sd), Status::kOk);
      EXPECT_TRUE(near(sf.constraint_force, sd.constraint_force, Tolerance<float>::kAgree,
                       inf_norm(sd.constraint_force) + inf_norm(sys.Q - sys.f), to_string(s)));
    }
  }
}


// --- Reuse of the factorization, and the declared-diagonal mass matrix. ---

template <int N, int P>
void expect_identical(const ConstraintSolution<N, P>& a, const ConstraintSolution<N, P>& b) {
  EXPECT_EQ(a.acceleration, b.acceleration);
  EXPECT_EQ(a.constraint_force, b.constraint_force);
  EXPECT_EQ(a.force_from_impressed, b.force_from_impressed);
  EXPECT_EQ(a.force_from_rhs, b.force_from_rhs);
  EXPECT_EQ(a.diagnostics.status, b.diagnostics.status);
  EXPECT_EQ(a.diagnostics.warnings, b.diagnostics.warnings);
  EXPECT_EQ(a.diagnostics.rank, b.diagnostics.rank);
  EXPECT_EQ(a.diagnostics.strategy_used, b.diagnostics.strategy_used);
  EXPECT_EQ(a.diagnostics.condition_estimate, b.diagnostics.condition_estimate);
}

// Expectation: a solver that kept its factorization from an earlier call answers bit for bit as a
// fresh solver does, whether A, D or neither changed (by as little as one ulp in one entry), for
// every strategy, and keeps reporting the factorization's diagnostics (here the fallback to the
// SVD for nearly dependent rows).
TEST(Reuse, KeptFactorizationAnswersAsAFreshSolver) {
  RandomSource<double> rng(21);
  for (InverseStrategy s : kStrategies) {
    auto kept = solver_for<6, 3>(s, -1, 1e-6);
    ConstraintSolution<6, 3> a, b;
    for (int it = 0; it < 50; ++it) {
      auto sys = rng.system<6, 3>();
      if (it % 5 == 4) sys.D.row(2) = sys.D.row(1) + 1e-9 * rng.matrix<1, 6>();  // nearly dependent
      for (int change = 0; change < 5; ++change) {
        if (change == 1) sys.A(3, 2) = sys.A(2, 3) = std::nextafter(sys.A(2, 3), 10.0);
        if (change == 2) sys.D(1, 4) = std::nextafter(sys.D(1, 4), -10.0);
        if (change == 3) sys.A(5, 5) = std::nextafter(sys.A(5, 5), 10.0);  // the diagonal
        // change == 4: A and D as before, only f, Q and g new (the factorization is kept).
        sys.f = rng.matrix<6, 1>();
        sys.Q = rng.matrix<6, 1>();
        sys.g = rng.matrix<3, 1>();
        auto fresh = solver_for<6, 3>(s, -1, 1e-6);
        ASSERT_EQ(kept.solve(sys.A, sys.f, sys.Q, sys.D, sys.g, a), Status::kOk);
        ASSERT_EQ(fresh.solve(sys.A, sys.f, sys.Q, sys.D, sys.g, b), Status::kOk);
        expect_identical(a, b);
        if (it % 5 == 4 && s == InverseStrategy::kCholeskyWithFallback) {
          ASSERT_TRUE(a.diagnostics.has(warning::kFellBackToSvd)) << "iteration " << it << " change " << change;
        }
        ASSERT_FALSE(HasFailure()) << to_string(s) << " iteration " << it << " change " << change;
      }
    }
  }
}

// The same with one constraint row (the scalar normal equations), the row shrinking to zero on
// the way (where the Cholesky path hands over to the SVD).
TEST(Reuse, OneRowKeptFactorizationAnswersAsAFreshSolver) {
  RandomSource<double> rng(24);
  for (InverseStrategy s : kStrategies) {
    auto kept = solver_for<3, 1>(s, -1, 1e-6);
    ConstraintSolution<3, 1> a, b;
    for (int it = 0; it < 50; ++it) {
      auto sys = rng.system<3, 1>();
      if (it % 7 == 6) sys.D.setZero();
      for (int change = 0; change < 3; ++change) {
        if (change == 1 && sys.D(0, 1) != 0) sys.D(0, 1) = std::nextafter(sys.D(0, 1), 10.0);
        sys.f = rng.matrix<3, 1>();
        sys.Q = rng.matrix<3, 1>();
        sys.g = rng.matrix<1, 1>();
        auto fresh = solver_for<3, 1>(s, -1, 1e-6);
        ASSERT_EQ(kept.solve(sys.A, sys.f, sys.Q, sys.D, sys.g, a), Status::kOk);
        ASSERT_EQ(fresh.solve(sys.A, sys.f, sys.Q, sys.D, sys.g, b), Status::kOk);
        expect_identical(a, b);
        ASSERT_FALSE(HasFailure()) << to_string(s) << " iteration " << it << " change " << change;
      }
    }
  }
}

// Expectation: a fallback threshold no matrix meets (rcond above 1) sends every call to the SVD,
// with one row (whose normal equations are a scalar, rcond exactly 1) as with several.
template <int N, int P>
void expect_threshold_above_one_falls_back() {
  RandomSource<double> rng(27);
  const auto sys = rng.system<N, P>();
  SolverOptions<double> o;
  o.fallback_rcond = 1.5;
  ConstraintSolver<N, P> strict(o);
  ConstraintSolution<N, P> a, b;
  ASSERT_EQ(strict.solve(sys.A, sys.f, sys.Q, sys.D, sys.g, a), Status::kOk);
  EXPECT_TRUE(a.diagnostics.has(warning::kFellBackToSvd));
  EXPECT_EQ(a.diagnostics.strategy_used, InverseStrategy::kSvd);
  o.fallback_rcond = 1.0;  // met exactly by the scalar: no fallback there
  ConstraintSolver<N, P> lenient(o);
  ASSERT_EQ(lenient.solve(sys.A, sys.f, sys.Q, sys.D, sys.g, b), Status::kOk);
  if (P == 1) {
    EXPECT_FALSE(b.diagnostics.has(warning::kFellBackToSvd));
  }
  EXPECT_TRUE(a.constraint_force.isApprox(b.constraint_force, 1e-9));
}

TEST(HardCases, FallbackThresholdAboveOneAlwaysFallsBack) {
  expect_threshold_above_one_falls_back<3, 1>();
  expect_threshold_above_one_falls_back<6, 3>();
}

// Expectation: the normal equations' condition estimate is a bound, never optimistic: for D
// A^(-1/2) with prescribed singular values (condition 1 to 1e6), the estimate lies between the
// SVD's exact condition number and P^0.75 times it, sigma_max from above and sigma_min from below
// (up to the rounding of a Gram matrix of condition up to 1e12);
// the call falls back to the SVD whenever the exact cond(B)^2 is beyond 1 / fallback_rcond, and
// answers by the normal equations whenever the bound is within it.
template <int N, int P>
void expect_condition_bound() {
  RandomSource<double> rng(31);
  SolverOptions<double> o;
  o.fallback_rcond = 0.0;  // no fallback: the bound is reported at every condition
  auto exact = solver_for<N, P>(InverseStrategy::kSvd);
  ConstraintSolver<N, P> bound(o);
  ConstraintSolver<N, P> fallback;  // default threshold
  ConstraintSolution<N, P> e, b, d;
  for (int it = 0; it < 200; ++it) {
    const double cond = std::pow(10.0, rng.uniform(0.0, 6.0));
    const double tol = 1e-9 + 100 * std::numeric_limits<double>::epsilon() * cond * cond;
    Eigen::Matrix<double, P, 1> sigma;
    for (int i = 0; i < P; ++i) sigma(i) = std::pow(cond, -double(i) / std::max(P - 1, 1));
    auto sys = rng.template system<N, P>();
    const Eigen::LLT<Eigen::MatrixXd> llt{Eigen::MatrixXd(sys.A)};
    // D = S L^T, so B = D L^-T = S has exactly these singular values.
    sys.D = rng.template with_singular_values<P, N>(sigma) * Eigen::Matrix<double, N, N>(llt.matrixU());
    ASSERT_EQ(exact.solve(sys.A, sys.f, sys.Q, sys.D, sys.g, e), Status::kOk);
    ASSERT_EQ(bound.solve(sys.A, sys.f, sys.Q, sys.D, sys.g, b), Status::kOk);
    ASSERT_EQ(fallback.solve(sys.A, sys.f, sys.Q, sys.D, sys.g, d), Status::kOk);
    const double true_cond = e.diagnostics.condition_estimate;
    ASSERT_FALSE(b.diagnostics.has(warning::kFellBackToSvd));
    EXPECT_GE(b.diagnostics.condition_estimate, true_cond * (1 - tol)) << "it " << it;
    EXPECT_LE(b.diagnostics.condition_estimate, true_cond * std::pow(P, 0.75) * (1 + tol)) << "it " << it;
    EXPECT_GE(b.diagnostics.sigma_max, e.diagnostics.sigma_max * (1 - 1e-9));
    EXPECT_LE(b.diagnostics.sigma_min_kept, e.diagnostics.sigma_min_kept * (1 + tol));
    const double threshold = 1 / std::sqrt(SolverOptions<double>{}.fallback_rcond);  // on cond(B)
    if (true_cond > threshold * 1.01) {
      EXPECT_TRUE(d.diagnostics.has(warning::kFellBackToSvd)) << "it " << it;
    }
    if (b.diagnostics.condition_estimate < threshold * (1 - 1e-9)) {
      EXPECT_FALSE(d.diagnostics.has(warning::kFellBackToSvd)) << "it " << it;
    }
  }
}

TEST(HardCases, NormalEquationsConditionIsABound) {
  expect_condition_bound<6, 3>();
  expect_condition_bound<12, 6>();
}

// Expectation: a failed call (NaN in A or D, A not positive definite) leaves nothing behind: the
// next call with the earlier, good A and D answers as a fresh solver; and new options apply at
// once (the kept factorization was the old strategy's).
TEST(Reuse, FailuresAndNewOptionsDropTheKeptFactorization) {
  RandomSource<double> rng(22);
  const auto sys = rng.system<6, 3>();
  ConstraintSolver<6, 3> kept;
  ConstraintSolution<6, 3> a, b;
  ConstraintSolver<6, 3> fresh;
  ASSERT_EQ(fresh.solve(sys.A, sys.f, sys.Q, sys.D, sys.g, b), Status::kOk);
  ASSERT_EQ(kept.solve(sys.A, sys.f, sys.Q, sys.D, sys.g, a), Status::kOk);
  // A NaN in D while the factorization for this A and D is kept: refused, and then kept still.
  auto nan_d = sys.D;
  nan_d(2, 0) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(kept.solve(sys.A, sys.f, sys.Q, nan_d, sys.g, a), Status::kNonFiniteInput);
  EXPECT_EQ(a.diagnostics.non_finite_inputs, input::kConstraintMatrix);
  ASSERT_EQ(kept.solve(sys.A, sys.f, sys.Q, sys.D, sys.g, a), Status::kOk);
  expect_identical(a, b);
  // The same A that is not positive definite, twice: it fails both times (no failed factor kept).
  auto bad_a = sys.A;
  bad_a(1, 1) = -1;
  EXPECT_EQ(kept.solve(bad_a, sys.f, sys.Q, sys.D, sys.g, a), Status::kMassMatrixNotPositiveDefinite);
  EXPECT_EQ(kept.solve(bad_a, sys.f, sys.Q, sys.D, sys.g, a), Status::kMassMatrixNotPositiveDefinite);
  expect_all_zero(a);
  // A NaN in A: refused by name.
  auto nan_a = sys.A;
  nan_a(4, 1) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(kept.solve(nan_a, sys.f, sys.Q, sys.D, sys.g, a), Status::kNonFiniteInput);
  EXPECT_EQ(a.diagnostics.non_finite_inputs, input::kMassMatrix);
  ASSERT_EQ(kept.solve(sys.A, sys.f, sys.Q, sys.D, sys.g, a), Status::kOk);
  expect_identical(a, b);

  SolverOptions<double> svd;
  svd.strategy = InverseStrategy::kSvd;
  kept.set_options(svd);
  ASSERT_EQ(kept.solve(sys.A, sys.f, sys.Q, sys.D, sys.g, a), Status::kOk);
  EXPECT_EQ(a.diagnostics.strategy_used, InverseStrategy::kSvd);
  ConstraintSolver<6, 3> fresh_svd(svd);
  ASSERT_EQ(fresh_svd.solve(sys.A, sys.f, sys.Q, sys.D, sys.g, b), Status::kOk);
  expect_identical(a, b);
}

// Found by fuzz_solver: when B = D A^(-1/2) or its factors overflow, the SVD refused its input
// and left the previous call's singular values in place, so a solver that had solved another
// system reported other warnings than a fresh one. Expectation, in every strategy and mass kind,
// with and without a singular-value floor: a solver that solved a good system first answers bit
// for bit as a fresh one, keeps nothing non-finite for the next call, and
// - B itself overflowing (A = 1e-300 I, D near 1e200) is kNonFiniteResult with zero outputs;
// - B finite with row norms beyond sqrt(DBL_MAX) (D near 1e300, A = I) is answered, since the
//   rank-revealing kernels scale B by a power of two before squaring anything: the motion is that
//   of the rows D / 1e300 = D~ with right side g 1e-300, q'' = a + D~^+ (g 1e-300 - D~ a), from
//   Eigen's SVD of D~; with a floor of 1e300 the directions with sigma(D~) < 1 are dropped;
// - B finite with a Gram matrix that overflows but rows that do not (D = 1e200 [I 0]) is answered:
//   q''_i = g_i 1e-200 on the constrained coordinates and a_i = Q_i - f_i on the others (A = I);
//   with a floor of 1e300 every direction is below it, so q'' = a.
template <typename Solver>
ConstraintSolution<6, 3> expect_answered_as_fresh(const SolverOptions<double>& o, const Eigen::Matrix<double, 6, 6>& A,
                                                  const Eigen::Matrix<double, 3, 6>& D, Status expected) {
  RandomSource<double> rng(25);
  auto good = rng.system<6, 3>();
  good.A = A.diagonal().cwiseAbs().cwiseMax(1.0).asDiagonal();  // diagonal, for both kinds
  Solver kept(o), fresh(o);
  ConstraintSolution<6, 3> a, b, before;
  EXPECT_EQ(kept.solve(good.A, good.f, good.Q, good.D, good.g, before), Status::kOk);
  EXPECT_EQ(kept.solve(A, good.f, good.Q, D, good.g, a), expected);
  EXPECT_EQ(fresh.solve(A, good.f, good.Q, D, good.g, b), expected);
  expect_identical(a, b);
  expect_all_finite(a);
  if (failed(expected)) {
    expect_all_zero(a);
    EXPECT_EQ(a.diagnostics.warnings, 0u);
    EXPECT_EQ(a.diagnostics.rank, 0);
  }
  // Back to the good system: the answer of the first call again.
  EXPECT_EQ(kept.solve(good.A, good.f, good.Q, good.D, good.g, b), Status::kOk);
  expect_identical(b, before);
  return a;
}

TEST(HardCases, OverflowingFactorsAreANonFiniteResultNotStaleState) {
  RandomSource<double> rng(26);
  const Eigen::Matrix<double, 3, 6> D = rng.matrix<3, 6>();
  Eigen::Matrix<double, 3, 6> unit_rows = Eigen::Matrix<double, 3, 6>::Zero();
  unit_rows.leftCols<3>().setIdentity();
  const Eigen::Matrix<double, 6, 6> tiny_a = Eigen::Matrix<double, 6, 1>::Constant(1e-300).asDiagonal();
  const Eigen::Matrix<double, 6, 6> unit_a = Eigen::Matrix<double, 6, 6>::Identity();
  using Dense = ConstraintSolver<6, 3>;
  using Diagonal = ConstraintSolver<6, 3, double, MassMatrix::kDiagonal>;
  const auto good = RandomSource<double>(25).system<6, 3>();  // the f, Q, g the helper uses
  for (InverseStrategy s : kStrategies) {
    for (double floor : {0.0, 1e300}) {  // a singular-value floor sends every strategy to the SVD
      SolverOptions<double> o;
      o.strategy = s;
      o.min_singular_value = floor;
      SCOPED_TRACE(std::string(to_string(s)) + (floor > 0 ? " with a floor" : ""));
      expect_answered_as_fresh<Dense>(o, tiny_a, 1e200 * D, Status::kNonFiniteResult);
      expect_answered_as_fresh<Diagonal>(o, tiny_a, 1e200 * D, Status::kNonFiniteResult);
      // The independent answer for D near 1e300: Eigen's SVD of D~ = D, kept singular values
      // sigma > 0 without a floor and sigma >= 1 (1e300 sigma >= the floor) with one.
      const Eigen::JacobiSVD<Eigen::MatrixXd> svd(Eigen::MatrixXd(D), Eigen::ComputeThinU | Eigen::ComputeThinV);
      const Eigen::Matrix<double, 6, 1> a = good.Q - good.f;
      const Eigen::Vector3d r = 1e-300 * good.g - D * a;
      Eigen::Matrix<double, 6, 1> huge_rows_expected = a;
      int huge_rows_rank = 0;
      for (int i = 0; i < 3; ++i) {
        const double sigma = svd.singularValues()(i);
        if (floor > 0 ? !(sigma >= 1) : !(sigma > 0)) continue;
        ++huge_rows_rank;
        huge_rows_expected += svd.matrixV().col(i) * (svd.matrixU().col(i).dot(r) / sigma);
      }
      for (const auto& sol : {expect_answered_as_fresh<Dense>(o, unit_a, 1e300 * D, Status::kOk),
                              expect_answered_as_fresh<Diagonal>(o, unit_a, 1e300 * D, Status::kOk)}) {
        EXPECT_TRUE(near(sol.acceleration, huge_rows_expected, 1e-9, inf_norm(huge_rows_expected), "1e300 D"));
        EXPECT_EQ(sol.diagnostics.rank, huge_rows_rank);
      }
      for (const auto& sol : {expect_answered_as_fresh<Dense>(o, unit_a, 1e200 * unit_rows, Status::kOk),
                              expect_answered_as_fresh<Diagonal>(o, unit_a, 1e200 * unit_rows, Status::kOk)}) {
        Eigen::Matrix<double, 6, 1> expected = good.Q - good.f;
        if (floor == 0) expected.head<3>() = 1e-200 * good.g;
        EXPECT_TRUE(sol.acceleration.isApprox(expected, 1e-12)) << sol.acceleration.transpose();
        EXPECT_EQ(sol.diagnostics.rank, floor == 0 ? 3 : 0);
      }
    }
  }
}

// Expectation: a solver told the mass matrix is diagonal gives the dense solver's answer (to
// rounding) for a diagonal A, in every strategy; it reads the diagonal alone; a non-positive or
// non-finite diagonal entry fails as it does for the dense solver.
TEST(DiagonalMass, AgreesWithTheDenseSolver) {
  RandomSource<double> rng(23);
  for (InverseStrategy s : kStrategies) {
    SolverOptions<double> o;
    o.strategy = s;
    ConstraintSolver<6, 3> dense(o);
    ConstraintSolver<6, 3, double, MassMatrix::kDiagonal> diagonal(o);
    ConstraintSolution<6, 3> a, b;
    for (int it = 0; it < 100; ++it) {
      auto sys = rng.system<6, 3>();
      Eigen::Matrix<double, 6, 1> m;
      for (int i = 0; i < 6; ++i) m(i) = std::pow(10.0, rng.uniform(-2, 2));
      sys.A = m.asDiagonal();
      ASSERT_EQ(dense.solve(sys.A, sys.f, sys.Q, sys.D, sys.g, a), Status::kOk);
      ASSERT_EQ(diagonal.solve(sys.A, sys.f, sys.Q, sys.D, sys.g, b), Status::kOk);
      const double scale = 1 + a.constraint_force.norm();
      ASSERT_LT((a.constraint_force - b.constraint_force).norm(), 1e-10 * scale) << to_string(s);
      ASSERT_LT((a.force_from_impressed - b.force_from_impressed).norm(), 1e-10 * scale) << to_string(s);
      ASSERT_LT((a.force_from_rhs - b.force_from_rhs).norm(), 1e-10 * scale) << to_string(s);
      ASSERT_LT((a.acceleration - b.acceleration).norm(), 1e-10 * (1 + a.acceleration.norm())) << to_string(s);
      ASSERT_EQ(a.diagnostics.rank, b.diagnostics.rank);
      // Off-diagonal entries are not read.
      Eigen::Matrix<double, 6, 6> with_junk = sys.A;
      with_junk(0, 3) = std::numeric_limits<double>::quiet_NaN();
      ConstraintSolution<6, 3> c;
      ASSERT_EQ(diagonal.solve(with_junk, sys.f, sys.Q, sys.D, sys.g, c), Status::kOk);
      ASSERT_EQ(c.constraint_force, b.constraint_force);
    }
    Eigen::Matrix<double, 6, 6> A = Eigen::Matrix<double, 6, 6>::Identity();
    const auto sys = rng.system<6, 3>();
    A(4, 4) = 0;
    EXPECT_EQ(diagonal.solve(A, sys.f, sys.Q, sys.D, sys.g, b), Status::kMassMatrixNotPositiveDefinite);
    expect_all_zero(b);
    A(4, 4) = std::numeric_limits<double>::infinity();
    EXPECT_EQ(diagonal.solve(A, sys.f, sys.Q, sys.D, sys.g, b), Status::kNonFiniteInput);
    EXPECT_EQ(b.diagnostics.non_finite_inputs, input::kMassMatrix);
  }
}

}  // namespace
}  // namespace gausstrack::test
