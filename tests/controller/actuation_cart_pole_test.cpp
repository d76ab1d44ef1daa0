// The actuated law on the cart-pole and the Duffing pair with one actuator: the hold, actuator
// limits, a vanishing reach, the cart-pole's terms against its Lagrangian, no allocation.
#undef NDEBUG
#define EIGEN_RUNTIME_NO_MALLOC

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <cmath>
#include <limits>

#include "actuation_systems.hpp"
#include "allocation_counter.hpp"
#include "gausstrack/systems/cart_pole.hpp"
#include "gausstrack/systems/differential_drive.hpp"
#include "oracles.hpp"

namespace gausstrack::test {
namespace {

// With a hold the commands are the actuated law's at the middle of the hold interval, at the state
// predicted through the acceleration the measured state's commands give (as TrackingController).
TEST(Actuation, TheHeldCommandsAreTheLawAtThePredictedMidpoint) {
  ControllerOptions<double> o;
  o.stabilization = {1.0, 20.0};
  const double h = 1e-3, d = 2e-4, t = 0.3, tau = d + h / 2;
  const Eigen::Vector2d q(1.02, 0.97), qd(8.1, 2.2);
  ActuatedController<Duffing1> held(Duffing1{}, o), plain(Duffing1{}, o);
  ASSERT_TRUE(held.set_hold({h, d}));
  ActuatedController<Duffing1>::Output out, at_t, at_m;
  ASSERT_EQ(held.compute(q, qd, t, out), Status::kOk);
  ASSERT_EQ(plain.compute(q, qd, t, at_t), Status::kOk);
  const Eigen::Vector2d q_m = q + tau * qd + 0.5 * tau * tau * at_t.acceleration;
  const Eigen::Vector2d qd_m = qd + tau * at_t.acceleration;
  ASSERT_EQ(plain.compute(q_m, qd_m, t + tau, at_m), Status::kOk);
  EXPECT_NEAR(out.control(0), at_m.control(0), 1e-12 * (1 + std::abs(at_m.control(0))));
  EXPECT_GT(std::abs(out.control(0) - at_t.control(0)), 1e-6 * std::abs(at_t.control(0)));  // the hold moved it
  EXPECT_EQ(out.constraint_error, at_t.constraint_error);
  EXPECT_FALSE(out.diagnostics.has(warning::kHoldAtMeasuredState));
}

// Actuator limits scale the commands as a whole and say so; the force is B times the scaled u.
TEST(Actuation, ActuatorLimitsScaleTheCommands) {
  ActuatedController<Duffing1> free_law, limited;
  ActuatedController<Duffing1>::Output f, l;
  const Eigen::Vector2d q(1.3, 0.2), qd(3.0, -1.0);
  ASSERT_EQ(free_law.compute(q, qd, 0.4, f), Status::kOk);
  ASSERT_GT(std::abs(f.control(0)), 1.0);
  ASSERT_TRUE(limited.set_actuator_limit(Eigen::Matrix<double, 1, 1>(0.5)));
  ASSERT_EQ(limited.compute(q, qd, 0.4, l), Status::kOk);
  EXPECT_TRUE(l.diagnostics.has(warning::kSaturated));
  EXPECT_NEAR(std::abs(l.control(0)), 0.5, 1e-15);
  EXPECT_NEAR(l.saturation_scale, 0.5 / std::abs(f.control(0)), 1e-15);
  EXPECT_EQ(l.force(0), l.control(0));
  // Every part by the same factor, still adding up to u; the force's parts are B times them.
  const double k = l.saturation_scale, scale = 1 + std::abs(f.control(0));
  EXPECT_NEAR(l.control_closed_loop(0), k * f.control_closed_loop(0), 1e-14 * scale);
  EXPECT_NEAR(l.control_feedforward(0), k * f.control_feedforward(0), 1e-14 * scale);
  EXPECT_NEAR(l.control_stabilizing(0), k * f.control_stabilizing(0), 1e-14 * scale);
  EXPECT_NEAR(l.control_closed_loop(0) + l.control_feedforward(0) + l.control_stabilizing(0), l.control(0),
              1e-14 * scale);
  EXPECT_EQ(l.closed_loop(0), l.control_closed_loop(0));
  EXPECT_EQ(l.feedforward(0), l.control_feedforward(0));
  EXPECT_FALSE(limited.set_actuator_limit(Eigen::Matrix<double, 1, 1>(0.0)));
}

// The cart-pole's pendulum nearly horizontal: the cart's force barely reaches the angle
// (D A^-1 B = -m l cos theta / det A). With one row and one actuator the task's own condition is
// 1; measured against D A^(-1/2) the loss of reach is flagged.
TEST(Actuation, ActuatorsThatBarelyReachTheRowAreFlagged) {
  ActuatedController<systems::CartPole<double>> c;
  ActuatedController<systems::CartPole<double>>::Output out;
  ASSERT_EQ(c.compute(Eigen::Vector2d(0.0, 0.3), Eigen::Vector2d(0.0, 1.0), 0.0, out), Status::kOk);
  EXPECT_FALSE(out.diagnostics.has(warning::kIllConditioned));
  ASSERT_EQ(c.compute(Eigen::Vector2d(0.0, std::acos(1e-12)), Eigen::Vector2d(0.0, 1.0), 0.0, out), Status::kOk);
  EXPECT_TRUE(out.diagnostics.has(warning::kIllConditioned)) << out.diagnostics.condition_estimate;
}

// The cart-pole's A, f and Q against its Lagrangian, differentiated numerically: T from the bob's
// velocity (x' + l cos theta theta', l sin theta theta'), V = -m g l cos theta;
// A = d2T/dqd2, f = (d/dq dT/dqd) qd - dT/dq, Q = -dV/dq.
TEST(Actuation, CartPoleTermsAreItsLagrangians) {
  const systems::CartPole<double> m;
  auto kinetic = [&](const Eigen::Vector2d& q, const Eigen::Vector2d& qd) {
    const double vx = qd(0) + m.length * std::cos(q(1)) * qd(1), vy = m.length * std::sin(q(1)) * qd(1);
    return 0.5 * m.cart_mass * qd(0) * qd(0) + 0.5 * m.mass * (vx * vx + vy * vy);
  };
  auto potential = [&](const Eigen::Vector2d& q) { return -m.mass * m.gravity * m.length * std::cos(q(1)); };
  auto momentum = [&](const Eigen::Vector2d& q, const Eigen::Vector2d& qd) {  // dT/dqd, exact for a quadratic
    Eigen::Vector2d p;
    for (int i = 0; i < 2; ++i) {
      const Eigen::Vector2d e = Eigen::Vector2d::Unit(i);
      p(i) = (kinetic(q, qd + e) - kinetic(q, qd - e)) / 2;
    }
    return p;
  };
  RandomSource<double> rng(23);
  for (int k = 0; k < 10; ++k) {
    const Eigen::Vector2d q = 2 * rng.matrix<2, 1>(), qd = 2 * rng.matrix<2, 1>();
    ModelTerms<2, 1, double> terms;
    m.evaluate(q, qd, 0.0, terms);
    const double h = 1e-5;
    Eigen::Matrix2d a, dp_dq;
    Eigen::Vector2d dt_dq, dv_dq;
    for (int j = 0; j < 2; ++j) {
      const Eigen::Vector2d e = Eigen::Vector2d::Unit(j);
      a.col(j) = (momentum(q, qd + e) - momentum(q, qd - e)) / 2;
      dp_dq.col(j) = (momentum(q + h * e, qd) - momentum(q - h * e, qd)) / (2 * h);
      dt_dq(j) = (kinetic(q + h * e, qd) - kinetic(q - h * e, qd)) / (2 * h);
      dv_dq(j) = (potential(q + h * e) - potential(q - h * e)) / (2 * h);
    }
    EXPECT_LT((terms.mass_matrix - a).norm(), 1e-9);
    EXPECT_LT((terms.nonlinear_force - (dp_dq * qd - dt_dq)).norm(), 1e-7);
    EXPECT_LT((terms.applied_force + dv_dq).norm(), 1e-7);
  }
}

TEST(Actuation, AllocationFree) {
  ActuatedController<Duffing1> c;
  ActuatedController<systems::CartPole<double>> arm;
  ActuatedController<Duffing1>::Output out;
  ActuatedController<systems::CartPole<double>>::Output arm_out;
  Eigen::internal::set_is_malloc_allowed(false);
  const long n = support::allocations_during([&] {
    for (int i = 0; i < 10; ++i) {
      ASSERT_EQ(c.compute(Eigen::Vector2d(0.1 * i, 0.2), Eigen::Vector2d(1, 2), 0.01 * i, out), Status::kOk);
      ASSERT_EQ(arm.compute(Eigen::Vector2d(0.3, 0.2 * i), Eigen::Vector2d(0, 1), 0.01 * i, arm_out), Status::kOk);
    }
  });
  Eigen::internal::set_is_malloc_allowed(true);
  EXPECT_EQ(n, 0);
}

// With physical rows too (the differential drive: one SVD of the rows the ground holds).
TEST(Actuation, AllocationFreeAmongPhysicalRows) {
  ControllerOptions<double> o;
  o.stabilization = {1.0, 4.0};
  ActuatedController<systems::DifferentialDrive<double>> c(systems::DifferentialDrive<double>{}, o);
  ActuatedController<systems::DifferentialDrive<double>>::Output out;
  const Eigen::Vector3d q(0.1, -0.2, 0.3), qd(0.4, 0.1, 0.2);
  Eigen::internal::set_is_malloc_allowed(false);
  const long n = support::allocations_during([&] {
    for (int i = 0; i < 10; ++i) {
      c.set_row_active(1, i % 2 == 0);  // rows switched at run time
      c.compute(q, qd, 0.01 * i, out);
    }
  });
  Eigen::internal::set_is_malloc_allowed(true);
  EXPECT_EQ(n, 0);
  EXPECT_EQ(out.diagnostics.status, Status::kOk);
}

}  // namespace
}  // namespace gausstrack::test
