// The actuated law's plain case: a model without B or physical rows is eq. (32), answered by the
// plain law's solver; against the general path under Gauss's weight given by hand (actuation.hpp).
// Apart from actuation_closed_forms_test.cpp so that neither unit's compile passes 1.5 GB.
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <cmath>
#include <limits>

#include "actuation_systems.hpp"
#include "oracles.hpp"

namespace gausstrack::test {
namespace {

// A model without B or physical rows, under Gauss's weight with every row active, is eq. (32): the
// controller answers it with the plain law's solver. The general path answers the same problem
// when Gauss's weight is given by hand (W = A^-1, set_weight): the two must agree on every output
// and flag, and on the rows they leave unmet.
template <int N, int P>
void expect_plain_case_as_the_general_path(ActuatedController<GivenUnactuated<N, P>>& plain, const char* what) {
  using S = GivenUnactuated<N, P>;
  ActuatedController<S> general(plain.model());
  ASSERT_TRUE(general.set_weight(plain.model().A.inverse())) << what;
  ASSERT_TRUE(general.set_actuator_limit(plain.actuator_limit())) << what;
  typename ActuatedController<S>::Output p, g;
  const Eigen::Matrix<double, N, 1> zero = Eigen::Matrix<double, N, 1>::Zero();
  ASSERT_EQ(plain.compute(zero, zero, 0.0, p), Status::kOk) << what;
  ASSERT_EQ(general.compute(zero, zero, 0.0, g), Status::kOk) << what;
  const double scale = 1.0 + g.control.norm();
  EXPECT_TRUE(near(p.control, g.control, 1e-9, scale, "control")) << what;
  EXPECT_TRUE(near(p.closed_loop, g.closed_loop, 1e-9, scale, "closed loop")) << what;
  EXPECT_TRUE(near(p.feedforward, g.feedforward, 1e-9, scale, "feedforward")) << what;
  EXPECT_TRUE(near(p.acceleration, g.acceleration, 1e-9, 1.0 + g.acceleration.norm(), "q''")) << what;
  EXPECT_TRUE(near(p.row_residual, g.row_residual, 1e-9, 1.0 + g.acceleration.norm(), "residual")) << what;
  EXPECT_EQ(p.force, p.control) << what;
  EXPECT_EQ(p.unmet_rows, g.unmet_rows) << what;
  EXPECT_EQ(p.diagnostics.rank, g.diagnostics.rank) << what;
  EXPECT_NEAR(p.saturation_scale, g.saturation_scale, 1e-12) << what;
  constexpr std::uint32_t kCompared = warning::kRankDeficient | warning::kConstraintsNotMet | warning::kSaturated;
  EXPECT_EQ(p.diagnostics.warnings & kCompared, g.diagnostics.warnings & kCompared) << what;
}

TEST(Actuation, WithoutBThePlainCaseIsTheGeneralPathUnderGausssWeight) {
  RandomSource<double> rng(23);
  for (int k = 0; k < 10; ++k) {  // rows of full rank, met
    ActuatedController<GivenUnactuated<4, 2>> c(GivenUnactuated<4, 2>::random(rng));
    expect_plain_case_as_the_general_path(c, "random 4 x 2");
    ActuatedController<GivenUnactuated<4, 2>>::Output out;
    ASSERT_EQ(c.compute(Eigen::Vector4d::Zero(), Eigen::Vector4d::Zero(), 0.0, out), Status::kOk);
    EXPECT_EQ(out.unmet_rows, 0u);
  }
  {  // the same row twice with two right sides: rank 1, both rows missed by the least-squares answer
    GivenUnactuated<3, 2> sys = GivenUnactuated<3, 2>::random(rng);
    sys.D.row(1) = sys.D.row(0);
    sys.g << 1.0, 2.0;
    ActuatedController<GivenUnactuated<3, 2>> c(sys);
    expect_plain_case_as_the_general_path(c, "redundant rows");
    ActuatedController<GivenUnactuated<3, 2>>::Output out;
    ASSERT_EQ(c.compute(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), 0.0, out), Status::kOk);
    EXPECT_EQ(out.unmet_rows, 0b11u);
    EXPECT_TRUE(out.diagnostics.has(warning::kRankDeficient));
    EXPECT_NEAR(out.row_residual(0), 0.5, 1e-12);  // D q'' = 1.5 for both rows
    EXPECT_NEAR(out.row_residual(1), -0.5, 1e-12);
  }
  for (int k = 0; k < 5; ++k) {  // limits a tenth of the free command: u scaled, q'' with it, rows unmet
    ActuatedController<GivenUnactuated<4, 2>> c(GivenUnactuated<4, 2>::random(rng));
    ActuatedController<GivenUnactuated<4, 2>>::Output free;
    ASSERT_EQ(c.compute(Eigen::Vector4d::Zero(), Eigen::Vector4d::Zero(), 0.0, free), Status::kOk);
    ASSERT_TRUE(c.set_actuator_limit(Eigen::Vector4d::Constant(0.1 * free.control.cwiseAbs().maxCoeff())));
    expect_plain_case_as_the_general_path(c, "limited");
    ActuatedController<GivenUnactuated<4, 2>>::Output out;
    ASSERT_EQ(c.compute(Eigen::Vector4d::Zero(), Eigen::Vector4d::Zero(), 0.0, out), Status::kOk);
    EXPECT_TRUE(out.diagnostics.has(warning::kSaturated));
    const Eigen::Vector4d a = c.model().A.ldlt().solve(c.model().Q - c.model().f);
    EXPECT_TRUE(near(out.acceleration, a + c.model().A.ldlt().solve(out.force), 1e-10, 1.0 + a.norm(), "q''"));
    EXPECT_NE(out.unmet_rows, 0u);
  }
}

// The plain case's diagnostics are the plain law's, where the general path measures the reach by
// the rows' Frobenius norm: two unit rows on unit masses have singular values 1 and 1, so that the
// SVD gives the plain law a condition estimate of 1 and the general path sqrt(2) (the Frobenius
// reach over the smallest; the general path answers under the complete-orthogonal strategy by
// its SVD). A row switched off and on again in between changes nothing.
TEST(Actuation, WithoutBThePlainCaseReportsThePlainLawsDiagnostics) {
  using S = GivenUnactuated<3, 2>;
  S sys;
  sys.D << 1, 0, 0, 0, 1, 0;
  sys.g << 1, -1;
  sys.f << 0.5, 0.25, 2;
  ControllerOptions<double> svd, cod;
  svd.solver.strategy = InverseStrategy::kSvd;
  cod.solver.strategy = InverseStrategy::kCompleteOrthogonal;
  ActuatedController<S> c(sys, svd), general(sys, cod);
  TrackingController<S> plain_law(sys, svd);
  ActuatedController<S>::Output out, by_general;
  TrackingController<S>::Output law;
  const Eigen::Vector3d zero = Eigen::Vector3d::Zero();
  ASSERT_TRUE(c.set_row_active(1, false));
  ASSERT_TRUE(c.set_row_active(1, true));
  ASSERT_EQ(c.compute(zero, zero, 0.0, out), Status::kOk);
  ASSERT_EQ(general.compute(zero, zero, 0.0, by_general), Status::kOk);
  ASSERT_EQ(plain_law.compute(zero, zero, 0.0, law), Status::kOk);
  EXPECT_EQ(out.force, law.force);
  EXPECT_EQ(out.acceleration, law.acceleration);
  EXPECT_EQ(out.diagnostics.sigma_max, law.diagnostics.sigma_max);
  EXPECT_EQ(out.diagnostics.condition_estimate, law.diagnostics.condition_estimate);
  EXPECT_NEAR(out.diagnostics.condition_estimate, 1.0, 1e-12);
  EXPECT_NEAR(by_general.diagnostics.condition_estimate, std::sqrt(2.0), 1e-12);
  EXPECT_TRUE(near(by_general.force, law.force, 1e-12, 1.0, "force"));
}

// A non-finite row error (which eq. (32)'s solver does not read) is refused as the general path
// refuses it, with every non-finite input named.
TEST(Actuation, WithoutBANonFiniteRowErrorIsRefusedWithEveryBadInputNamed) {
  RandomSource<double> rng(31);
  GivenUnactuated<3, 1> sys = GivenUnactuated<3, 1>::random(rng);
  sys.e(0) = std::numeric_limits<double>::quiet_NaN();
  sys.f(1) = std::numeric_limits<double>::infinity();
  ActuatedController<GivenUnactuated<3, 1>> c(sys);
  ActuatedController<GivenUnactuated<3, 1>>::Output out;
  EXPECT_EQ(c.compute(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), 0.0, out), Status::kNonFiniteInput);
  EXPECT_EQ(out.diagnostics.non_finite_inputs, input::kConstraintRhs | input::kNonlinearForce);
  EXPECT_TRUE(out.control.isZero(0));
}

// The plain case keeps the controller's own history of the rows' reach (kVanishingReach), so
// that a reach a billion times below the largest seen is flagged.
TEST(Actuation, WithoutBThePlainCaseFlagsAVanishingReach) {
  RandomSource<double> rng(29);
  ActuatedController<GivenUnactuated<3, 1>> c(GivenUnactuated<3, 1>::random(rng));
  ActuatedController<GivenUnactuated<3, 1>>::Output out;
  ASSERT_EQ(c.compute(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), 0.0, out), Status::kOk);
  EXPECT_FALSE(out.diagnostics.has(warning::kVanishingReach));
  c.model().D *= 1e-9;
  ASSERT_EQ(c.compute(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), 0.0, out), Status::kOk);
  EXPECT_TRUE(out.diagnostics.has(warning::kVanishingReach));
}

// More rows than coordinates without B: no plain case (eq. 32's solver needs P <= N); the general
// path answers in the least-squares sense and names the rows it misses.
TEST(Actuation, WithoutBMoreRowsThanCoordinatesTakeTheGeneralPath) {
  GivenUnactuated<2, 3> sys;
  sys.D << 1, 0, 0, 1, 1, 1;
  sys.g << 1, 1, 1;  // x'' = y'' = 1 leaves x'' + y'' = 2, not 1
  ActuatedController<GivenUnactuated<2, 3>> c(sys);
  ActuatedController<GivenUnactuated<2, 3>>::Output out;
  ASSERT_EQ(c.compute(Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero(), 0.0, out), Status::kOk);
  EXPECT_EQ(out.diagnostics.rank, 2);
  EXPECT_TRUE(out.diagnostics.has(warning::kConstraintsNotMet));
  EXPECT_NE(out.unmet_rows, 0u);
  EXPECT_TRUE(near(out.acceleration, Eigen::Vector2d(out.force), 1e-12, 1.0, "q'' = u with A = I, f = Q = 0"));
}

}  // namespace
}  // namespace gausstrack::test
