// The solver's factorization, each case with its stated expectation: float against double, reuse
// of a kept factorization, the normal equations' fallback and condition bound, overflowing
// factors, and the declared-diagonal mass matrix.
#include <Eigen/Cholesky>
#include <array>
#include <limits>
#include <string>

#include "gausstrack/constraint_solver.hpp"
#include "solver_test_support.hpp"
#include "test_support.hpp"

namespace gausstrack::test {
namespace {

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
  // kVanishingReach compares with the solver's history by design (a kept solver that saw larger
  // rows flags a vanishing one; a fresh solver cannot): every other flag is the same.
  constexpr std::uint32_t kHistory = warning::kVanishingReach;
  EXPECT_EQ(a.diagnostics.warnings & ~kHistory, b.diagnostics.warnings & ~kHistory);
  EXPECT_EQ(a.diagnostics.rank, b.diagnostics.rank);
  EXPECT_EQ(a.diagnostics.strategy_used, b.diagnostics.strategy_used);
  EXPECT_EQ(a.diagnostics.condition_estimate, b.diagnostics.condition_estimate);
  EXPECT_EQ(a.diagnostics.residual_norm, b.diagnostics.residual_norm);
}

// Expectation: a solver that kept its factorization from an earlier call answers bit for bit as a
// fresh solver does, whether A, D or neither changed (by as little as one ulp in one entry), for
// every strategy, and keeps reporting the factorization's diagnostics (here the fallback to the
// SVD for nearly dependent rows). At 6 and 7 coordinates with dense rows, and at 12 with rows touching
// three coordinates each (the solver then keeps each row's support with D: the residual and the
// products run over it).
template <int N, int P>
void expect_kept_factorization_answers_as_a_fresh_solver(unsigned seed, bool banded) {
  RandomSource<double> rng(seed);
  for (InverseStrategy s : kStrategies) {
    auto kept = solver_for<N, P>(s, -1, 1e-6);
    ConstraintSolution<N, P> a, b;
    for (int it = 0; it < 50; ++it) {
      auto sys = rng.template system<N, P>();
      if (banded)
        for (int i = 0; i < P; ++i)
          for (int j = 0; j < N; ++j)
            if (j < 2 * i || j > 2 * i + 2) sys.D(i, j) = 0.0;
      if (it % 5 == 4) sys.D.row(2) = sys.D.row(1) + 1e-9 * rng.template matrix<1, N>();  // nearly dependent
      for (int change = 0; change < 5; ++change) {
        if (change == 1) sys.A(3, 2) = sys.A(2, 3) = std::nextafter(sys.A(2, 3), 10.0);
        if (change == 2) sys.D(1, 4) = std::nextafter(sys.D(1, 4), -10.0);
        if (change == 3) sys.A(5, 5) = std::nextafter(sys.A(5, 5), 10.0);  // the diagonal
        // change == 4: A and D as before, only f, Q and g new (the factorization is kept).
        sys.f = rng.template matrix<N, 1>();
        sys.Q = rng.template matrix<N, 1>();
        sys.g = rng.template matrix<P, 1>();
        auto fresh = solver_for<N, P>(s, -1, 1e-6);
        ASSERT_EQ(kept.solve(sys.A, sys.f, sys.Q, sys.D, sys.g, a), Status::kOk);
        ASSERT_EQ(fresh.solve(sys.A, sys.f, sys.Q, sys.D, sys.g, b), Status::kOk);
        expect_identical(a, b);
        if (it % 5 == 4 && s == InverseStrategy::kCholeskyWithFallback) {
          ASSERT_TRUE(a.diagnostics.has(warning::kFellBackToSvd)) << "iteration " << it << " change " << change;
        }
        ASSERT_FALSE(::testing::Test::HasFailure())
            << to_string(s) << " N " << N << " iteration " << it << " change " << change;
      }
    }
  }
}

TEST(Reuse, KeptFactorizationAnswersAsAFreshSolver) {
  expect_kept_factorization_answers_as_a_fresh_solver<6, 3>(21, false);
  expect_kept_factorization_answers_as_a_fresh_solver<7, 3>(23, false);  // N odd: the last row alone
  expect_kept_factorization_answers_as_a_fresh_solver<12, 5>(25, true);
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

// Entries at the top of the range (1e308, above 2^1023): B is finite, its Gram matrix is not. The
// rank-revealing kernels scale by a power of two that must itself be finite. Expectation, for the
// SVD, the COD and the damped strategy (lambda = 1, which reaches its SVD filter through the
// overflowed Gram matrix): answered, q'' = (g1, g2, 0) / 1e308 (A = I, f = Q = 0), rank 2.
TEST(HardCases, EntriesAtTheTopOfTheRangeAreDecomposed) {
  Eigen::Matrix<double, 2, 3> D = Eigen::Matrix<double, 2, 3>::Zero();
  D(0, 0) = D(1, 1) = 1e308;
  const Eigen::Vector2d g(1e10, 2e10);
  const Eigen::Vector3d zero = Eigen::Vector3d::Zero(), expected(1e-298, 2e-298, 0);
  for (InverseStrategy s :
       {InverseStrategy::kSvd, InverseStrategy::kCompleteOrthogonal, InverseStrategy::kDampedLeastSquares}) {
    auto solver = solver_for<3, 2>(s, -1, s == InverseStrategy::kDampedLeastSquares ? 1.0 : 0.0);
    ConstraintSolution<3, 2> sol;
    ASSERT_EQ(solver.solve(Eigen::Matrix3d::Identity(), zero, zero, D, g, sol), Status::kOk) << to_string(s);
    EXPECT_TRUE(near(sol.acceleration, expected, 1e-12, 2e-298, to_string(s)));
    EXPECT_EQ(sol.diagnostics.rank, 2) << to_string(s);
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
