// The law against Simbody 3.7, an independent multibody library, on the same constrained motion:
// the planar arm's hand on its circle (bench/peer/simbody_arm.hpp builds it in Simbody from the
// model's parameters). Without stabilization the law's q'' (eq. 30) is the exact constrained
// acceleration Simbody's realize(Acceleration) solves for, and its force (eq. 32) is Simbody's
// constraint force D^T lambda; with stabilization on, the two must differ where the state is off
// the circle (so the comparison can fail).
#include <gtest/gtest.h>

#include <random>

#include "gausstrack/systems/planar_arm.hpp"
#include "gausstrack/tracking_controller.hpp"
#include "simbody_arm.hpp"

namespace gausstrack {
namespace {

using Arm = systems::PlanarArm<double>;

ControllerOptions<double> unstabilized() {
  ControllerOptions<double> o;
  o.stabilization = {0.0, 0.0};
  return o;
}

// q'' and Q' against Simbody's at random states, to 1e-9 relative.
void expect_same_motion(const Arm& arm) {
  peer::SimbodyArm simbody(peer::arm_parameters(arm));
  TrackingController<Arm> law(arm, unstabilized());
  TrackingController<Arm>::Output out;
  std::mt19937_64 rng(2008);
  std::uniform_real_distribution<double> angle(-3.0, 3.0), rate(-3.0, 3.0), time(0.0, 10.0);
  int compared = 0;
  for (int trial = 0; trial < 500; ++trial) {
    Eigen::Vector3d q, qd, qdd;
    for (int i = 0; i < 3; ++i) q(i) = angle(rng), qd(i) = rate(rng);
    const double t = time(rng);
    simbody.acceleration(q.data(), qd.data(), t, qdd.data());
    ASSERT_EQ(law.compute(q, qd, t, out), Status::kOk) << "trial " << trial;
    if (out.diagnostics.condition_estimate > 1e4)
      continue;  // near a singular arm: both lose digits
    ASSERT_LE((out.acceleration - qdd).norm(), 1e-9 * (1.0 + qdd.norm()))
        << "trial " << trial << ": law " << out.acceleration.transpose() << ", simbody "
        << qdd.transpose();
    TermsOf<Arm> terms;
    evaluate_model(arm, q, qd, t, terms);
    Eigen::Vector2d lambda;
    simbody.multipliers(lambda.data());
    const Eigen::Vector3d constraint_force = terms.constraint_matrix.transpose() * lambda;
    ASSERT_LE((out.force - constraint_force).norm(), 1e-9 * (1.0 + constraint_force.norm()))
        << "trial " << trial << ": law " << out.force.transpose() << ", simbody "
        << constraint_force.transpose();
    ++compared;
  }
  EXPECT_GE(compared, 475);  // the near-singular arms left out are few
}

TEST(SimbodyPeer, ArmAccelerationsAndConstraintForceEqualSimbodys) { expect_same_motion(Arm{}); }

TEST(SimbodyPeer, AnotherArmOnAnotherCircleToo) {
  Arm arm;
  arm.mass << 3.0, 0.7, 1.9;
  arm.com << 0.3, 0.5, 0.1;
  arm.inertia << 0.2, 0.05, 0.01;
  arm.gravity = 3.7;
  arm.damping = 0.4;
  arm.center_x = 0.4, arm.center_y = -0.9, arm.radius = 0.6, arm.rate = 2.3, arm.phase = 0.7;
  expect_same_motion(arm);
}

TEST(SimbodyPeer, StabilizationMakesTheLawDifferOffTheCircle) {
  // Off the circle, Baumgarte's correction adds acceleration that Simbody's exact solve has not.
  peer::SimbodyArm simbody(peer::arm_parameters(Arm{}));
  ControllerOptions<double> o;
  o.stabilization = {1.0, 20.0};
  TrackingController<Arm> law{Arm{}, o};
  TrackingController<Arm>::Output out;
  const Eigen::Vector3d q(0.3, 0.9, 0.6), qd(0.2, -0.4, 0.5);
  Eigen::Vector3d qdd;
  simbody.acceleration(q.data(), qd.data(), 0.0, qdd.data());
  ASSERT_EQ(law.compute(q, qd, 0.0, out), Status::kOk);
  ASSERT_GT(out.constraint_error.norm(), 1e-2);
  EXPECT_GT((out.acceleration - qdd).norm(), 1e-3);
}

}  // namespace
}  // namespace gausstrack
