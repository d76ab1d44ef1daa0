// The actuated law among rows the environment holds (kPhysicalRowMask): the control never pushes
// along them, the motion is the physically constrained system's, and the commands are the least
// cost ones, each against an independent formulation (a Lagrange-multiplier solve of the whole
// problem, oracles.cpp); a model without physical rows or actuators gets eq. (32)'s force. That
// the physically constrained law allocates nothing is in actuation_cart_pole_test.
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <cmath>
#include <cstdint>

#include "actuation_systems.hpp"
#include "gausstrack/systems/coupled_duffing.hpp"
#include "gausstrack/systems/differential_drive.hpp"
#include "gausstrack/systems/duffing_chain.hpp"
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

// The differential drive at random states, stabilization on: the commands are the least-cost ones
// for the stabilized task, the no-slip row holds under the law's acceleration, and B = (drive,
// yaw) gives no sideways force.
TEST(PhysicalRows, DifferentialDriveAgainstTheOracle) {
  using Robot = systems::DifferentialDrive<double>;
  RandomSource<double> rng(test_seed() + 2);
  ControllerOptions<double> o;
  o.stabilization = {1.0, 4.0};
  for (int k = 0; k < 50; ++k) {
    Robot robot;
    ActuatedController<Robot> c(robot, o);
    const Eigen::Vector3d q = 2.0 * rng.template matrix<3, 1>(), qd = rng.template matrix<3, 1>();
    const double t = 10.0 * std::abs(rng.uniform(0.0, 1.0));
    ActuatedController<Robot>::Output out;
    ASSERT_EQ(c.compute(q, qd, t, out), Status::kOk);
    TermsOf<Robot> terms;
    evaluate_model(robot, q, qd, t, terms);
    Eigen::Matrix<double, 3, 2> B;
    robot.actuation(q, t, B);
    const MatrixXd A = terms.mass_matrix;
    const MatrixXd D = terms.constraint_matrix;
    VectorXd r(2);  // the task rows' stabilized right side
    for (int i = 0; i < 2; ++i)
      r(i) = terms.constraint_rhs(i) - 2 * 1.0 * 4.0 * terms.constraint_error_rate(i) -
             16.0 * terms.constraint_error(i);
    const auto [u, qdd] = oracle::physical_least_cost_control(
        A, terms.nonlinear_force, terms.applied_force, D.bottomRows(1),
        terms.constraint_rhs.tail(1), D.topRows(2), r, B,
        MatrixXd(B.transpose() * A.inverse() * B));
    EXPECT_TRUE(near(out.control, u, 1e-9, 1 + u.norm(), "u"));
    EXPECT_TRUE(near(out.acceleration, qdd, 1e-9, 1 + qdd.norm(), "q''"));
    const double sideways = -std::sin(q(2)) * out.force(0) + std::cos(q(2)) * out.force(1);
    EXPECT_LE(std::abs(sideways), 1e-12 * (1 + out.force.norm()));
    EXPECT_LE(std::abs(out.row_residual(2)), 1e-10 * (1 + qdd.norm()));
  }
}

// The axle centre itself cannot be steered sideways: with no look-ahead the two task rows and the
// no-slip row leave one direction the actuators cannot reach at an instant. The law says so
// (rank 1 of 2, the row it gives up named), instead of a status of ok.
TEST(PhysicalRows, TrackingTheAxleCentreIsFlaggedAsNotActuable) {
  using Robot = systems::DifferentialDrive<double>;
  Robot robot;
  robot.look_ahead = 0.0;
  ActuatedController<Robot> c(robot);
  ActuatedController<Robot>::Output out;
  const Eigen::Vector3d q(0.1, -0.2, 0.3), qd(0.5 * std::cos(0.3), 0.5 * std::sin(0.3), 0.2);
  c.compute(q, qd, 1.0, out);
  EXPECT_EQ(out.diagnostics.rank, 1);
  EXPECT_TRUE(out.diagnostics.has(warning::kRankDeficient));
  EXPECT_TRUE(out.diagnostics.has(warning::kConstraintsNotMet));
  EXPECT_NE(out.unmet_rows & 0b011u, 0u);
  EXPECT_EQ(out.unmet_rows & 0b100u, 0u);  // the ground's row is held regardless
}

// A model without physical rows or actuators, through the actuated law (B = I, Gauss's weight),
// gets TrackingController's eq. (32) force, stabilization and robust term included.
TEST(PhysicalRows, NoneDeclaredGivesTodaysLaw) {
  using Duffing = systems::CoupledDuffing<double>;
  ControllerOptions<double> o;
  o.stabilization = {0.7, 15.0};
  o.robust = {30.0, 0.05};  // the robust term, shared by both
  ActuatedController<Duffing> actuated(Duffing{}, o);
  TrackingController<Duffing> plain(Duffing{}, o);
  RandomSource<double> rng(test_seed() + 3);
  for (int k = 0; k < 50; ++k) {
    const Eigen::Vector2d q = rng.template matrix<2, 1>(), qd = 5.0 * rng.template matrix<2, 1>();
    const double t = std::abs(rng.uniform(0.0, 3.0));
    ActuatedController<Duffing>::Output a;
    TrackingController<Duffing>::Output p;
    ASSERT_EQ(actuated.compute(q, qd, t, a), Status::kOk);
    ASSERT_EQ(plain.compute(q, qd, t, p), Status::kOk);
    EXPECT_TRUE(near(a.force, p.force, 1e-10, 1 + p.force.norm(), "force"));
    EXPECT_TRUE(near(a.feedforward, p.feedforward, 1e-10, 1 + p.force.norm(), "feedforward"));
    EXPECT_TRUE(near(a.stabilizing, p.stabilizing, 1e-10, 1 + p.force.norm(), "stabilizing"));
  }
}

TEST(PhysicalRows, APhysicalRowTakesNoStabilization) {
  ActuatedController<systems::DifferentialDrive<double>> c;
  EXPECT_TRUE(c.set_stabilization(0, {1.0, 5.0}));
  EXPECT_FALSE(c.set_stabilization(2, {1.0, 5.0}));
}

// Task rows switched at run time: with row 1 off the law is the one of the model without that
// row (no rank deficiency, the row never named unmet), and on again the full law.
TEST(SwitchedRows, AnInactiveRowIsAbsent) {
  RandomSource<double> rng(test_seed() + 4);
  using Full = GivenSystem<5, 3, 4>;
  using Part = GivenSystem<5, 2, 4>;
  for (int k = 0; k < 20; ++k) {
    const Full full = Full::random(rng);
    Part part;
    part.A = full.A, part.f = full.f, part.Q = full.Q, part.B = full.B;
    part.D << full.D.row(0), full.D.row(2);
    part.g << full.g(0), full.g(2);
    ActuatedController<Full> c(full), fresh(full);
    ActuatedController<Part> without(part);
    ASSERT_TRUE(c.set_row_active(1, false));
    EXPECT_FALSE(c.row_active(1));
    EXPECT_TRUE(c.row_active(0));
    ActuatedController<Full>::Output out, all;
    ActuatedController<Part>::Output expected;
    const Eigen::Matrix<double, 5, 1> zero = Eigen::Matrix<double, 5, 1>::Zero();
    ASSERT_EQ(c.compute(zero, zero, 0.0, out), Status::kOk);
    ASSERT_EQ(without.compute(zero, zero, 0.0, expected), Status::kOk);
    EXPECT_TRUE(near(out.control, expected.control, 1e-10, 1 + expected.control.norm(), "u, row 1 off"));
    EXPECT_EQ(out.diagnostics.rank, 2);
    EXPECT_FALSE(out.diagnostics.has(warning::kRankDeficient));
    EXPECT_EQ(out.unmet_rows, 0u);
    EXPECT_GT(std::abs(out.row_residual(1)), 1e-6);  // not held, and reported as such
    ASSERT_TRUE(c.set_row_active(1, true));
    ASSERT_EQ(c.compute(zero, zero, 0.0, out), Status::kOk);
    ASSERT_EQ(fresh.compute(zero, zero, 0.0, all), Status::kOk);
    EXPECT_TRUE(near(out.control, all.control, 1e-12, 1 + all.control.norm(), "u, row 1 on again"));
  }
}

// A row that comes back is stabilized from its current error, hold included: after running with
// the row off, the first answer with it on equals a fresh controller's at that state.
TEST(SwitchedRows, ARowThatComesBackStartsFromItsCurrentError) {
  using Chain = systems::DuffingChain<8, 4, double>;
  ControllerOptions<double> o;
  o.stabilization = {1.0, 20.0};
  o.hold = {1e-3, 0.0};
  ActuatedController<Chain> c(Chain{}, o), fresh(Chain{}, o);
  ActuatedController<Chain>::Output out, expected;
  RandomSource<double> rng(test_seed() + 5);
  ASSERT_TRUE(c.set_row_active(2, false));
  Eigen::Matrix<double, 8, 1> q, qd;
  for (int k = 0; k < 5; ++k) {
    q = 0.1 * rng.matrix<8, 1>(), qd = rng.matrix<8, 1>();
    ASSERT_EQ(c.compute(q, qd, 1e-3 * k, out), Status::kOk);
  }
  ASSERT_TRUE(c.set_row_active(2, true));
  ASSERT_EQ(c.compute(q, qd, 5e-3, out), Status::kOk);
  ASSERT_EQ(fresh.compute(q, qd, 5e-3, expected), Status::kOk);
  EXPECT_TRUE(near(out.control, expected.control, 1e-12, 1 + expected.control.norm(), "u"));
  EXPECT_GT(std::abs(out.constraint_error(2)), 1e-3);  // it does come back with an error
  EXPECT_GT(out.control_stabilizing.norm(), 1e-3 * out.control.norm());
}

TEST(SwitchedRows, PhysicalRowsCannotBeSwitchedOff) {
  ActuatedController<systems::DifferentialDrive<double>> c;
  EXPECT_FALSE(c.set_row_active(2, false));
  EXPECT_FALSE(c.set_row_active(3, false));
  EXPECT_FALSE(c.set_row_active(-1, true));
  EXPECT_TRUE(c.set_row_active(0, false));
  EXPECT_FALSE(c.row_active(2));  // not a task row at all
}

}  // namespace
}  // namespace gausstrack::test
