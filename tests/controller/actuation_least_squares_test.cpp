// The actuated law's least-squares answer when the rows cannot all be actuated.

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <cmath>
#include <limits>

#include "actuation_systems.hpp"
#include "oracles.hpp"

namespace gausstrack::test {
namespace {

// More rows than actuators: the least-squares answer W^(-1/2) (K W^(-1/2))^+ r, the rows flagged,
// and the force still in the range of B.
TEST(Actuation, RowsBeyondTheActuatorsAreMetInTheLeastSquaresSenseAndFlagged) {
  RandomSource<double> rng(13);
  using S = GivenSystem<5, 3, 2>;
  for (int k = 0; k < 20; ++k) {
    const S sys = S::random(rng);
    ActuatedController<S> c(sys);
    S::Scalar t = 0;
    ActuatedController<S>::Output out;
    ASSERT_EQ(c.compute(Eigen::Matrix<double, 5, 1>::Zero(), Eigen::Matrix<double, 5, 1>::Zero(), t, out), Status::kOk);
    const Eigen::MatrixXd Ainv = Eigen::MatrixXd(sys.A).inverse();
    const Eigen::MatrixXd W = sys.B.transpose() * Ainv * sys.B;
    const Eigen::MatrixXd R = W.llt().matrixU();  // W = R^T R
    const Eigen::MatrixXd Rinv = R.inverse();
    const Eigen::VectorXd r = sys.g - sys.D * (Ainv * (sys.Q - sys.f));
    const Eigen::VectorXd u = Rinv * oracle::pseudo_inverse(sys.D * Ainv * sys.B * Rinv, 1e-12) * r;
    EXPECT_LT((out.control - u).norm() / (1 + u.norm()), 1e-9);
    EXPECT_TRUE(out.diagnostics.has(warning::kRankDeficient));
    EXPECT_TRUE(out.diagnostics.has(warning::kConstraintsNotMet));
    EXPECT_NE(out.unmet_rows, 0u);
    EXPECT_EQ(out.diagnostics.rank, 2);
    // B u: its component off B's range, by an independent projection, is rounding.
    const Eigen::Matrix<double, 5, 5> project = sys.B * oracle::pseudo_inverse(sys.B, 1e-12);
    EXPECT_LT((out.force - project * out.force).norm(), 1e-12 * (1 + out.force.norm()));
  }
}

}  // namespace
}  // namespace gausstrack::test
