// The actuated law among rows the environment holds (kPhysicalRowMask): the control never pushes
// along them, the motion is the physically constrained system's, and the commands are the least
// cost ones, each against an independent formulation (a Lagrange-multiplier solve of the whole
// problem, oracles.cpp), on random systems; the same on the differential drive, and a model
// without physical rows, in actuation_physical_models_test. That the physically constrained law
// allocates nothing is in actuation_cart_pole_test.
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <cmath>
#include <cstdint>

#include "actuation_systems.hpp"
#include "oracles.hpp"

namespace gausstrack::test {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

// A given system whose rows in Mask the environment holds, pushed through B (K actuators).
template <int N, int P, int K, std::uint64_t Mask>
struct GivenPhysical : GivenSystem<N, P, K> {
  static constexpr std::uint64_t kPhysicalRowMask = Mask;
  static GivenPhysical random(RandomSource<double>& rng) {
    GivenPhysical s;
    static_cast<GivenSystem<N, P, K>&>(s) = GivenSystem<N, P, K>::random(rng);
    return s;
  }
};

// The same without B: every coordinate actuated (B = I).
template <int N, int P, std::uint64_t Mask>
struct GivenPhysicalUnactuated {
  using Scalar = double;
  static constexpr int kDof = N;
  static constexpr int kConstraints = P;
  static constexpr std::uint64_t kPhysicalRowMask = Mask;
  GivenSystem<N, P, 1> terms;
  void evaluate(const Eigen::Matrix<double, N, 1>& q, const Eigen::Matrix<double, N, 1>& qd,
                double t, ModelTerms<N, P, double>& out) const noexcept {
    terms.evaluate(q, qd, t, out);
  }
};

// Rows of m selected by the mask (physical) or not (task).
MatrixXd rows_of(const MatrixXd& m, std::uint64_t mask, bool physical) {
  auto wanted = [&](Eigen::Index i) { return (((mask >> i) & 1U) != 0) == physical; };
  Eigen::Index count = 0;
  for (Eigen::Index i = 0; i < m.rows(); ++i) count += wanted(i) ? 1 : 0;
  MatrixXd out(count, m.cols());
  for (Eigen::Index i = 0, k = 0; i < m.rows(); ++i)
    if (wanted(i)) out.row(k++) = m.row(i);
  return out;
}

// Holds the law's commands and motion to the oracle's for one system, weight W.
template <typename C, typename Sys>
void expect_matches_oracle(C& c, const Sys& sys, const MatrixXd& B, const MatrixXd& W,
                           std::uint64_t mask) {
  typename C::Output out;
  const Eigen::Matrix<double, Sys::kDof, 1> zero = Eigen::Matrix<double, Sys::kDof, 1>::Zero();
  ASSERT_FALSE(failed(c.compute(zero, zero, 0.0, out)));
  const MatrixXd D = sys.D;
  const VectorXd g = sys.g;
  const auto [u, qdd] = oracle::physical_least_cost_control(
      sys.A, sys.f, sys.Q, rows_of(D, mask, true), rows_of(g, mask, true), rows_of(D, mask, false),
      rows_of(g, mask, false), B, W);
  EXPECT_TRUE(near(out.control, u, 1e-9, 1 + u.norm(), "u"));
  EXPECT_TRUE(near(out.acceleration, qdd, 1e-9, 1 + qdd.norm(), "q''"));
  EXPECT_TRUE(near(out.force, B * out.control, 1e-12, 1 + out.force.norm(), "force = B u"));
  // Every row met: the task by the control, the physical ones by the law's model of the plant.
  EXPECT_TRUE(near(out.row_residual, VectorXd::Zero(Sys::kConstraints), 1e-9,
                   1 + qdd.norm() * D.norm() + g.norm(), "D q'' - g"));
  EXPECT_EQ(out.unmet_rows, 0u);
}

// With B = I and Gauss's weight the control does not act along the physical rows
// (D_p A^-1 u = 0), and the motion is the one of every row held (eq. 30 on the stacked rows).
TEST(PhysicalRows, TheControlNeverPushesAlongThem) {
  RandomSource<double> rng(test_seed());
  constexpr std::uint64_t kMask = 0b1010;  // rows 1 and 3 of 4
  using S = GivenPhysicalUnactuated<6, 4, kMask>;
  for (int k = 0; k < 20; ++k) {
    S sys;
    sys.terms = GivenSystem<6, 4, 1>::random(rng);
    ActuatedController<S> c(sys);
    static_assert(ActuatedController<S>::K == 6 && ActuatedController<S>::kTask == 2 &&
                  ActuatedController<S>::kPhysical == 2);
    ActuatedController<S>::Output out;
    ASSERT_EQ(c.compute(Eigen::Matrix<double, 6, 1>::Zero(), Eigen::Matrix<double, 6, 1>::Zero(),
                        0.0, out),
              Status::kOk);
    const MatrixXd Ainv = sys.terms.A.inverse();
    const MatrixXd Dp = rows_of(sys.terms.D, kMask, true);
    const VectorXd along = Dp * Ainv * out.force;
    EXPECT_TRUE(near(along, VectorXd::Zero(2), 1e-11, Dp.norm() * Ainv.norm() * out.force.norm(),
                     "D_p A^-1 u"));
    const VectorXd qdd =
        oracle::kkt_solution(sys.terms.A, sys.terms.f, sys.terms.Q, sys.terms.D, sys.terms.g).first;
    EXPECT_TRUE(near(out.acceleration, qdd, 1e-9, 1 + qdd.norm(), "q'' against every row held"));
    expect_matches_oracle(c, sys.terms, MatrixXd::Identity(6, 6), Ainv, kMask);
  }
}

// Random B, Gauss's weight B^T A^-1 B and a given weight: the least-cost commands of the whole
// problem (oracle), the force in the range of B, every row met.
TEST(PhysicalRows, ActuatedCommandsAreTheLeastCostOnes) {
  RandomSource<double> rng(test_seed() + 1);
  constexpr std::uint64_t kMask = 0b001;  // row 0 of 3
  using S = GivenPhysical<6, 3, 4, kMask>;
  for (int k = 0; k < 20; ++k) {
    const S sys = S::random(rng);
    ActuatedController<S> gauss(sys);
    const MatrixXd B = sys.B;
    expect_matches_oracle(gauss, sys, B, B.transpose() * sys.A.inverse() * B, kMask);
    ActuatedController<S> weighted(sys);
    const Eigen::Matrix4d W = rng.spd<4>(50.0, 1.0);
    ASSERT_TRUE(weighted.set_weight(W));
    expect_matches_oracle(weighted, sys, B, W, kMask);
  }
}

// A task row the physical rows already hold (parallel to one, consistent with it): after the
// projection only rounding is left of it, which the law gives up (rank deficient) instead of
// answering with commands of size 1 / eps; the answer is the law without that row, and the row is
// met all the same, by the environment.
TEST(PhysicalRows, ATaskRowThePhysicalRowsHoldIsGivenUp) {
  RandomSource<double> rng(test_seed() + 6);
  using S = GivenPhysical<5, 3, 5, 0b001>;
  for (int k = 0; k < 20; ++k) {
    S sys = S::random(rng);
    sys.D.row(1) = 2.5 * sys.D.row(0);
    sys.g(1) = 2.5 * sys.g(0);
    ActuatedController<S> c(sys), without(sys);
    ASSERT_TRUE(without.set_row_active(1, false));
    ActuatedController<S>::Output out, expected;
    const Eigen::Matrix<double, 5, 1> zero = Eigen::Matrix<double, 5, 1>::Zero();
    ASSERT_EQ(c.compute(zero, zero, 0.0, out), Status::kOk);
    ASSERT_EQ(without.compute(zero, zero, 0.0, expected), Status::kOk);
    EXPECT_EQ(out.diagnostics.rank, 1);
    EXPECT_TRUE(out.diagnostics.has(warning::kRankDeficient));
    EXPECT_TRUE(near(out.control, expected.control, 1e-9, 1 + expected.control.norm(), "u"));
    EXPECT_EQ(out.unmet_rows, 0u);
  }
}

}  // namespace
}  // namespace gausstrack::test
