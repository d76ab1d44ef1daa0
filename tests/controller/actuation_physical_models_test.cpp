// Rows the environment holds on a model of a machine: the differential drive's no-slip row
// against the whole problem's Lagrange-multiplier solve (oracles.cpp), the axle centre flagged as
// not actuable, no stabilization on a physical row; and a model without physical rows or
// actuators, through the actuated law, gets eq. (32)'s force.
#include <gtest/gtest.h>

#include <Eigen/LU>
#include <cmath>

#include "actuation_systems.hpp"
#include "gausstrack/systems/coupled_duffing.hpp"
#include "gausstrack/systems/differential_drive.hpp"
#include "oracles.hpp"

namespace gausstrack::test {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

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

}  // namespace
}  // namespace gausstrack::test
