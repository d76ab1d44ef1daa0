// The actuated law (ActuatedController, actuation.hpp) against independent formulations (B = I
// against eq. (32) for every shipped model is in actuation_eq32_*_test.cpp); a Lagrange-multiplier
// (KKT) solve of least u^T W u subject to the task rows, for Gauss's weight and for a given one;
// the least-squares answer through a Moore-Penrose inverse when the rows cannot all be actuated.
// Closed forms and refusals: actuation_closed_forms_test.cpp; the hold, limits, reach, the
// cart-pole and allocation: actuation_cart_pole_test.cpp. Split so that no unit compiles them all.
#undef NDEBUG
#define EIGEN_RUNTIME_NO_MALLOC

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <cmath>
#include <limits>

#include "actuation_systems.hpp"
#include "gausstrack/systems/cart_pole.hpp"
#include "oracles.hpp"

namespace gausstrack::test {
namespace {

TEST(Actuation, LeastCostAmongCommandsMeetingTheRowsAsLagrangeMultipliersGiveIt) {
  RandomSource<double> rng(11);
  for (bool gauss : {true, false}) {
    expect_least_cost<4, 2, 3>(rng, gauss);
    expect_least_cost<6, 2, 2>(rng, gauss);
  }
}

// The default strategy answers a full-rank, well-conditioned task by its normal equations and
// says so; the SVD gives the same commands. Rows nearly parallel (cond(T) about 1e5, beyond the
// normal equations' fallback_rcond) fall back to the SVD with kFellBackToSvd, as the plain law
// does.
TEST(Actuation, TheNormalEquationsAnswerAWellConditionedTaskAsTheSvdDoes) {
  using S = GivenSystem<5, 2, 3>;
  RandomSource<double> rng(23);
  ControllerOptions<double> svd_options;
  svd_options.solver.strategy = InverseStrategy::kSvd;
  for (int k = 0; k < 20; ++k) {
    S sys = S::random(rng);
    const bool nearly_parallel = k % 4 == 3;
    if (nearly_parallel) sys.D.row(1) = sys.D.row(0) + 1e-5 * rng.matrix<1, 5>();
    ActuatedController<S> normal(sys), svd(sys, svd_options);
    ActuatedController<S>::Output a, b;
    ASSERT_EQ(normal.compute(Eigen::Matrix<double, 5, 1>::Zero(),
                             Eigen::Matrix<double, 5, 1>::Zero(), 0.0, a),
              Status::kOk);
    ASSERT_EQ(svd.compute(Eigen::Matrix<double, 5, 1>::Zero(), Eigen::Matrix<double, 5, 1>::Zero(),
                          0.0, b),
              Status::kOk);
    EXPECT_EQ(b.diagnostics.strategy_used, InverseStrategy::kSvd);
    EXPECT_FALSE(b.diagnostics.has(warning::kFellBackToSvd));
    if (nearly_parallel) {
      EXPECT_EQ(a.diagnostics.strategy_used, InverseStrategy::kSvd) << k;
      EXPECT_TRUE(a.diagnostics.has(warning::kFellBackToSvd)) << k;
      EXPECT_EQ(a.control, b.control) << k;  // the same SVD
    } else {
      EXPECT_EQ(a.diagnostics.strategy_used, InverseStrategy::kCholeskyWithFallback) << k;
      EXPECT_FALSE(a.diagnostics.has(warning::kFellBackToSvd)) << k;
      EXPECT_LT((a.control - b.control).norm(), 1e-10 * (1.0 + b.control.norm())) << k;
      EXPECT_LT((a.acceleration - b.acceleration).norm(), 1e-10 * (1.0 + b.acceleration.norm()))
          << k;
    }
    EXPECT_EQ(a.diagnostics.rank, 2);
    EXPECT_EQ(a.unmet_rows, 0u);
  }
}

}  // namespace
}  // namespace gausstrack::test
