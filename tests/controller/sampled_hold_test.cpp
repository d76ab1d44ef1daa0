// The sampled-data hold (TrackingController::set_hold, docs/sampled_law.md) against the plain
// law evaluated by hand at the state it must predict: the same force from an independent
// composition of public calls, the jerk from the previous sample, the limit of a vanishing hold,
// the fallback when the prediction cannot be evaluated, no allocation.
#undef NDEBUG
#define EIGEN_RUNTIME_NO_MALLOC

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "allocation_counter.hpp"
#include "gausstrack/systems/coupled_duffing.hpp"
#include "gausstrack/systems/planar_arm.hpp"
#include "gausstrack/tracking_controller.hpp"

namespace gausstrack {
namespace {

using Duffing = systems::CoupledDuffing<double>;
using V2 = Eigen::Vector2d;

ControllerOptions<double> stabilized() {
  ControllerOptions<double> o;
  o.stabilization = {1.0, 20.0};
  return o;
}

// The plain law at (q, q', t): force and constrained acceleration.
TrackingController<Duffing>::Output plain_at(const V2& q, const V2& qd, double t) {
  TrackingController<Duffing> c(Duffing{}, stabilized());
  TrackingController<Duffing>::Output out;
  EXPECT_EQ(c.compute(q, qd, t, out), Status::kOk);
  return out;
}

// Off the trajectory on purpose, so that the stabilization acts.
const V2 kQ(1.02, 0.97), kQd(8.1, 2.2);

TEST(SampledHold, FirstCallIsThePlainLawAtTheMidpointPredictedThroughTheAcceleration) {
  const double h = 1e-3, d = 2e-4, t = 0.3;
  TrackingController<Duffing> held(Duffing{}, stabilized());
  ASSERT_TRUE(held.set_hold({h, d}));
  TrackingController<Duffing>::Output out;
  ASSERT_EQ(held.compute(kQ, kQd, t, out), Status::kOk);

  const auto at_t = plain_at(kQ, kQd, t);
  const double tau = d + h / 2;
  const V2 q_m = kQ + tau * kQd + 0.5 * tau * tau * at_t.acceleration;
  const V2 qd_m = kQd + tau * at_t.acceleration;
  const auto at_m = plain_at(q_m, qd_m, t + tau);
  for (int i = 0; i < 2; ++i) EXPECT_NEAR(out.force(i), at_m.force(i), 1e-12 * (1 + std::abs(at_m.force(i))));
  // The hold moves the force (the test could fail): by more than rounding.
  EXPECT_GT((out.force - at_t.force).norm(), 1e-6 * at_t.force.norm());
  // The constraint error reported is the measured state's.
  EXPECT_EQ(out.constraint_error, at_t.constraint_error);
  EXPECT_EQ(out.constraint_error_rate, at_t.constraint_error_rate);
  EXPECT_FALSE(out.diagnostics.has(warning::kHoldAtMeasuredState));
}

TEST(SampledHold, NextSampleAddsTheJerkFromThePreviousAcceleration) {
  const double h = 1e-3, t0 = 0.3, t1 = t0 + h;
  const V2 q1 = kQ + h * kQd, qd1 = kQd + V2(0.01, -0.02);
  TrackingController<Duffing> held(Duffing{}, stabilized());
  ASSERT_TRUE(held.set_hold({h, 0.0}));
  TrackingController<Duffing>::Output out;
  ASSERT_EQ(held.compute(kQ, kQd, t0, out), Status::kOk);
  ASSERT_EQ(held.compute(q1, qd1, t1, out), Status::kOk);

  const V2 a0 = plain_at(kQ, kQd, t0).acceleration, a1 = plain_at(q1, qd1, t1).acceleration;
  const V2 j = (a1 - a0) / h;
  const double tau = h / 2;
  const V2 q_m = q1 + tau * qd1 + tau * tau / 2 * a1 + tau * tau * tau / 6 * j;
  const V2 qd_m = qd1 + tau * a1 + tau * tau / 2 * j;
  const auto at_m = plain_at(q_m, qd_m, t1 + tau);
  for (int i = 0; i < 2; ++i) EXPECT_NEAR(out.force(i), at_m.force(i), 1e-11 * (1 + std::abs(at_m.force(i))));

  // A sample that does not follow the previous one within two periods (a new run from t = 0, a
  // gap) predicts without the jerk.
  TrackingController<Duffing> restarted = held;
  ASSERT_EQ(restarted.compute(kQ, kQd, t1 + 10 * h, out), Status::kOk);
  const auto at_t = plain_at(kQ, kQd, t1 + 10 * h);
  const auto no_jerk = plain_at(kQ + tau * kQd + tau * tau / 2 * at_t.acceleration, kQd + tau * at_t.acceleration,
                                t1 + 10 * h + tau);
  for (int i = 0; i < 2; ++i)
    EXPECT_NEAR(out.force(i), no_jerk.force(i), 1e-12 * (1 + std::abs(no_jerk.force(i))));
}

// A call repeated for the same sample (a firmware loop that repeats a call a clock jump cut
// short) answers as the first did: the memory keeps the sample before it.
TEST(SampledHold, ARepeatedCallAnswersAsTheFirst) {
  const double h = 1e-3;
  TrackingController<Duffing> held(Duffing{}, stabilized());
  ASSERT_TRUE(held.set_hold({h, 0.0}));
  TrackingController<Duffing>::Output first, again;
  ASSERT_EQ(held.compute(kQ, kQd, 0.3, first), Status::kOk);
  const V2 q1 = kQ + h * kQd;
  ASSERT_EQ(held.compute(q1, kQd, 0.3 + h, first), Status::kOk);
  ASSERT_EQ(held.compute(q1, kQd, 0.3 + h, again), Status::kOk);
  EXPECT_EQ(first.force, again.force);
  // The next sample still sees the jerk from the one before it (not from a repeat): as a fresh
  // controller fed the same two samples.
  TrackingController<Duffing> fresh(Duffing{}, stabilized());
  ASSERT_TRUE(fresh.set_hold({h, 0.0}));
  TrackingController<Duffing>::Output a, b;
  const V2 q2 = q1 + h * kQd;
  ASSERT_EQ(held.compute(q2, kQd, 0.3 + 2 * h, a), Status::kOk);
  ASSERT_EQ(fresh.compute(q1, kQd, 0.3 + h, b), Status::kOk);
  ASSERT_EQ(fresh.compute(q2, kQd, 0.3 + 2 * h, b), Status::kOk);
  EXPECT_EQ(a.force, b.force);
}

TEST(SampledHold, AVanishingHoldGivesThePlainLawAtFirstOrder) {
  const auto plain = plain_at(kQ, kQd, 0.3);
  double previous = 0;
  for (double h : {1e-2, 1e-3, 1e-4}) {
    TrackingController<Duffing> held(Duffing{}, stabilized());
    ASSERT_TRUE(held.set_hold({h, 0.0}));
    TrackingController<Duffing>::Output out;
    ASSERT_EQ(held.compute(kQ, kQd, 0.3, out), Status::kOk);
    const double gap = (out.force - plain.force).norm();
    if (previous > 0) {
      EXPECT_NEAR(previous / gap, 10.0, 1.0) << "period " << h;  // the lead is h / 2
    }
    previous = gap;
  }
  // No hold: the plain law, bit for bit.
  TrackingController<Duffing> none(Duffing{}, stabilized());
  ASSERT_TRUE(none.set_hold({0.0, 0.0}));
  TrackingController<Duffing>::Output out;
  ASSERT_EQ(none.compute(kQ, kQd, 0.3, out), Status::kOk);
  EXPECT_EQ(out.force, plain.force);
}

TEST(SampledHold, APredictionThatCannotBeEvaluatedHoldsTheMeasuredStatesForce) {
  // A hold so long that the predicted state overflows.
  TrackingController<Duffing> held(Duffing{}, stabilized());
  ASSERT_TRUE(held.set_hold({1e300, 0.0}));
  TrackingController<Duffing>::Output out;
  EXPECT_EQ(held.compute(kQ, kQd, 0.3, out), Status::kOk);
  EXPECT_TRUE(out.diagnostics.has(warning::kHoldAtMeasuredState));
  EXPECT_EQ(out.force, plain_at(kQ, kQd, 0.3).force);
  EXPECT_TRUE(out.force.allFinite());
}

TEST(SampledHold, RefusesAHoldThatIsNotFiniteAndNonNegative) {
  TrackingController<Duffing> c(Duffing{}, stabilized());
  ASSERT_TRUE(c.set_hold({1e-3, 1e-4}));
  constexpr double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  for (Hold<double> bad : {Hold<double>{-1e-3, 0}, Hold<double>{1e-3, -1e-4}, Hold<double>{nan, 0},
                           Hold<double>{1e-3, inf}}) {
    EXPECT_FALSE(c.set_hold(bad));
    EXPECT_EQ(c.hold().period, 1e-3);
    EXPECT_EQ(c.hold().delay, 1e-4);
    ControllerOptions<double> o;
    o.hold = bad;
    EXPECT_NE(o.validate(), nullptr);
  }
}

TEST(SampledHold, AllocatesNothing) {
  using Arm = systems::PlanarArm<double>;
  TrackingController<Arm> arm{Arm{}, {}};
  ASSERT_TRUE(arm.set_hold({1e-3, 1e-3}));
  TrackingController<Arm>::Output out;
  const Eigen::Vector3d q(0.3, 0.5, -0.4), qd(0.1, -0.2, 0.3);
  Eigen::internal::set_is_malloc_allowed(false);
  const long n = support::allocations_during([&] {
    for (int k = 0; k < 10; ++k) arm.compute(q, qd, 1e-3 * k, out);
  });
  Eigen::internal::set_is_malloc_allowed(true);
  EXPECT_EQ(n, 0);
  EXPECT_TRUE(out.force.allFinite());
}

}  // namespace
}  // namespace gausstrack
