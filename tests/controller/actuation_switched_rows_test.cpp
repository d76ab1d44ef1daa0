// Task rows switched off and on at run time (set_row_active): an inactive row is absent from the
// law, one that comes back is stabilized from its current error, and rows the environment holds
// cannot be switched.
#include <gtest/gtest.h>

#include <cmath>

#include "actuation_systems.hpp"
#include "gausstrack/systems/differential_drive.hpp"
#include "gausstrack/systems/duffing_chain.hpp"

namespace gausstrack::test {
namespace {

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
