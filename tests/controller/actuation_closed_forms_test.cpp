// The actuated law against closed forms, and its refusals (actuation.hpp).
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <cmath>
#include <limits>

#include "actuation_systems.hpp"
#include "oracles.hpp"

namespace gausstrack::test {
namespace {

// Closed form: the Duffing pair's task x1 - x2 = x_d(t) with a force on mass 1 alone needs
// u = m1 (g - (a1 - a2)), and the rows are met.
TEST(Actuation, OneActuatorOnTheFirstMassOfTheDuffingPairIsTheClosedForm) {
  ActuatedController<Duffing1> c;
  TrackingController<systems::CoupledDuffing<double>> plain;  // for the model's terms at the state
  RandomSource<double> rng(17);
  for (int k = 0; k < 10; ++k) {
    const Eigen::Vector2d q = rng.matrix<2, 1>(), qd = rng.matrix<2, 1>();
    const double t = rng.uniform(0, 3);
    ActuatedController<Duffing1>::Output out;
    ASSERT_EQ(c.compute(q, qd, t, out), Status::kOk);
    TrackingController<systems::CoupledDuffing<double>>::Output unused;
    ASSERT_EQ(plain.compute(q, qd, t, unused), Status::kOk);
    const auto& terms = plain.terms();
    const Eigen::Vector2d a = terms.mass_matrix.ldlt().solve(terms.applied_force - terms.nonlinear_force);
    const double expected = terms.mass_matrix(0, 0) * (terms.constraint_rhs(0) - (a(0) - a(1)));
    EXPECT_NEAR(out.control(0), expected, 1e-12 * (1 + std::abs(expected)));
    EXPECT_EQ(out.force(1), 0.0);
    EXPECT_EQ(out.unmet_rows, 0u);
  }
}

// The same unactuated row at a scale whose squares leave the range (g ~ 1e160, |r|^2 = Inf): still
// named, and the met row still met; the residual's norm is the unmet row's.
TEST(Actuation, AnUnactuatedRowIsNamedWhereItsSquaresOverflow) {
  for (const double scale : {1.0, 1e160, 1e300}) {
    GivenSystem<2, 2, 1> two;
    two.D.setIdentity();
    two.g << 0.7 * scale, -0.4 * scale;
    two.B << 1, 0;
    ActuatedController<GivenSystem<2, 2, 1>> c(two);
    ActuatedController<GivenSystem<2, 2, 1>>::Output out;
    ASSERT_EQ(c.compute(Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero(), 0.0, out), Status::kOk) << scale;
    EXPECT_EQ(out.unmet_rows, 0b10u) << scale;
    EXPECT_TRUE(out.diagnostics.has(warning::kConstraintsNotMet)) << scale;
    EXPECT_NEAR(out.control(0), 0.7 * scale, 1e-15 * scale) << scale;
    EXPECT_NEAR(out.diagnostics.residual_norm, 0.4 * scale, 1e-15 * scale) << scale;
  }
}

// Closed forms: two independent unit masses tracked each, one actuator on the first: the second
// row cannot be actuated (flagged alone) and the first is met exactly. Two actuators on one
// coordinate with W = diag(w1, w2) share the force as 1 / w_i (Gauss's weight would be singular).
TEST(Actuation, AnUnactuatedRowIsNamedAndRedundantActuatorsShareByTheWeight) {
  GivenSystem<2, 2, 1> two;
  two.D.setIdentity();
  two.g << 0.7, -0.4;
  two.B << 1, 0;
  ActuatedController<GivenSystem<2, 2, 1>> c(two);
  ActuatedController<GivenSystem<2, 2, 1>>::Output out;
  ASSERT_EQ(c.compute(Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero(), 0.0, out), Status::kOk);
  EXPECT_EQ(out.unmet_rows, 0b10u);
  EXPECT_NEAR(out.control(0), 0.7, 1e-15);
  EXPECT_NEAR(out.row_residual(1), 0.4, 1e-15);

  GivenSystem<1, 1, 2> shared;
  shared.D << 1;
  shared.g << 3.0;
  shared.B << 1, 1;
  ActuatedController<GivenSystem<1, 1, 2>> redundant(shared);
  ActuatedController<GivenSystem<1, 1, 2>>::Output r;
  EXPECT_EQ(redundant.compute(Eigen::Matrix<double, 1, 1>::Zero(), Eigen::Matrix<double, 1, 1>::Zero(), 0.0, r),
            Status::kWeightNotPositiveDefinite);
  EXPECT_EQ(r.control, Eigen::Vector2d::Zero());
  ASSERT_TRUE(redundant.set_weight(Eigen::Vector2d(1.0, 4.0).asDiagonal().toDenseMatrix()));
  ASSERT_EQ(redundant.compute(Eigen::Matrix<double, 1, 1>::Zero(), Eigen::Matrix<double, 1, 1>::Zero(), 0.0, r),
            Status::kOk);
  EXPECT_NEAR(r.control(0), 3.0 * 4.0 / 5.0, 1e-14);
  EXPECT_NEAR(r.control(1), 3.0 * 1.0 / 5.0, 1e-14);
  EXPECT_FALSE(redundant.set_weight(Eigen::Vector2d(1.0, -4.0).asDiagonal().toDenseMatrix()));
}

// The actuated law keeps the same history of its reach as the solver: one row D = s (0.8, 0.6)
// through two actuators, shrinking from s = 1, is flagged once s < sqrt(eps), and its commands,
// still computed, grow like 1 / s.
TEST(Actuation, AVanishingReachIsFlaggedAgainstTheLawsHistory) {
  using S = GivenSystem<2, 1, 2>;
  S sys;
  sys.A = Eigen::Vector2d(2.0, 0.5).asDiagonal();
  sys.Q << 0.0, -9.81;
  sys.g << 0.3;
  sys.B << 1.0, 0.2, -0.3, 1.0;
  ActuatedController<S> c(sys);
  double previous = 0;
  for (double s = 1.0; s >= 1e-12; s /= 10) {
    c.model().D = s * Eigen::RowVector2d(0.8, 0.6);
    ActuatedController<S>::Output out;
    ASSERT_EQ(c.compute(Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero(), 0.0, out), Status::kOk)
        << s;
    EXPECT_EQ(out.diagnostics.has(warning::kVanishingReach), s < 1.49e-8) << s;
    EXPECT_GT(out.control.norm(), previous) << s;
    previous = out.control.norm();
  }
}

// Columns of B that are dependent (the second three times the first) make Gauss's weight
// singular: refused, not answered with a command of 1 / eps along B's null space.
TEST(Actuation, DependentActuatorsAreRefusedUnderGausssWeight) {
  RandomSource<double> rng(19);
  GivenSystem<3, 1, 2> sys = GivenSystem<3, 1, 2>::random(rng);
  sys.B.col(1) = 3.0 * sys.B.col(0);
  ActuatedController<GivenSystem<3, 1, 2>> c(sys);
  ActuatedController<GivenSystem<3, 1, 2>>::Output out;
  EXPECT_EQ(c.compute(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), 0.0, out), Status::kWeightNotPositiveDefinite);
  EXPECT_TRUE(out.control.isZero(0));
}

TEST(Actuation, ANonFiniteActuationIsRefusedWithZeroOutputs) {
  GivenSystem<2, 1, 1> sys;
  sys.D << 1, -1;
  sys.g << 1;
  sys.B << std::numeric_limits<double>::quiet_NaN(), 0;
  ActuatedController<GivenSystem<2, 1, 1>> c(sys);
  ActuatedController<GivenSystem<2, 1, 1>>::Output out;
  EXPECT_EQ(c.compute(Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero(), 0.0, out), Status::kNonFiniteInput);
  EXPECT_EQ(out.diagnostics.non_finite_inputs, input::kActuation);
  EXPECT_TRUE(out.force.isZero(0));
  EXPECT_TRUE(out.control.isZero(0));
}

}  // namespace
}  // namespace gausstrack::test
