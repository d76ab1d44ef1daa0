// The paper's closed forms: eq. (37), eq. (38), the Duffing force f1 = -f2 and the tension of
// a constant-length pendulum.
#include <array>
#include <numbers>

#include "gausstrack/systems/coupled_duffing.hpp"
#include "gausstrack/systems/nonholonomic_particle.hpp"
#include "gausstrack/systems/pendulum.hpp"
#include "gausstrack/tracking_controller.hpp"
#include "test_support.hpp"

namespace gausstrack::test {
namespace {

using systems::CoupledDuffing;
using systems::NonholonomicParticle;
using systems::Pendulum;

constexpr std::array<InverseStrategy, 4> kStrategies = {
    InverseStrategy::kCholeskyWithFallback, InverseStrategy::kSvd,
    InverseStrategy::kCompleteOrthogonal, InverseStrategy::kDampedLeastSquares};

template <typename M>
TrackingController<M> controller_with(InverseStrategy s, M model = M{}) {
  ControllerOptions<typename M::Scalar> o;
  o.solver.strategy = s;
  return TrackingController<M>(model, o);
}

TEST(ClosedForms, Eq37ProjectorPseudoInverse) {
  RandomSource<double> rng(37);
  for (int it = 0; it < test_repeat(); ++it) {
    const double z = rng.uniform(-10, 10);
    const Eigen::RowVector3d D(-z, 1, 0);
    const Eigen::Vector3d d_minus = Eigen::Vector3d(-z, 1, 0) / (1 + z * z);  // as printed
    ASSERT_TRUE(near(oracle::pseudo_inverse(D, 1e-12), d_minus, 1e-14, 1, "D^- of eq. 37"));
    const Eigen::Matrix3d projector = Eigen::Matrix3d::Identity() - d_minus * D;
    Eigen::Matrix3d expected;
    expected << 1, z, 0, z, z * z, 0, 0, 0, 1 + z * z;
    expected /= 1 + z * z;
    expected(2, 2) = 1;
    ASSERT_TRUE(near(oracle::pseudo_inverse(projector, 1e-12), expected, 1e-12, 1, "eq. 37"))
        << "z = " << z;
  }
}

TEST(ClosedForms, Eq38NonholonomicParticle) {
  RandomSource<double> rng(38);
  for (InverseStrategy s : kStrategies) {
    auto controller = controller_with<NonholonomicParticle<double>>(s);
    TrackingController<NonholonomicParticle<double>>::Output out;
    for (int it = 0; it < test_repeat(); ++it) {
      const Eigen::Vector3d q = 3 * rng.matrix<3, 1>();
      const Eigen::Vector3d qd = 3 * rng.matrix<3, 1>();
      ASSERT_EQ(controller.compute(q, qd, 0.0, out), Status::kOk);
      // eq. (38) with the factor read as z'x': q'' = z'x' / (1 + z^2) (-z, 1, 0).
      const double z = q(2);
      const Eigen::Vector3d expected = qd(2) * qd(0) / (1 + z * z) * Eigen::Vector3d(-z, 1, 0);
      ASSERT_TRUE(near(out.acceleration, expected, 1e-13, 1 + inf_norm(expected), to_string(s)))
          << "state " << q.transpose() << " " << qd.transpose();
      // No impressed forces: the constraint force is the whole force, Q' = m q''.
      ASSERT_TRUE(near(out.force, expected, 1e-13, 1 + inf_norm(expected), "Q' = m q''"));
    }
  }
}

TEST(ClosedForms, DuffingForceIsEqualAndOpposite) {
  RandomSource<double> rng(35);
  for (InverseStrategy s : kStrategies) {
    CoupledDuffing<double> model;
    model.trajectory.alpha = 0.4;
    auto controller = controller_with(s, model);
    TrackingController<CoupledDuffing<double>>::Output out;
    for (int it = 0; it < test_repeat(); ++it) {
      const Eigen::Vector2d q = 2 * rng.matrix<2, 1>();
      const Eigen::Vector2d qd = 5 * rng.matrix<2, 1>();
      const double t = rng.uniform(0, 10);
      ASSERT_EQ(controller.compute(q, qd, t, out), Status::kOk);
      const Eigen::Vector2d a = -model.spring_damper_force(q, qd).cwiseQuotient(Eigen::Vector2d(model.m1, model.m2));
      const double g = model.trajectory.acceleration(t);
      const double f1 = (g - (a(0) - a(1))) / (1 / model.m1 + 1 / model.m2);
      const Eigen::Vector2d expected(f1, -f1);
      ASSERT_TRUE(near(out.force, expected, 1e-12, 1 + std::abs(f1), to_string(s))) << "t = " << t;
      // The feedforward is the force for f = Q = 0: g / (1/m1 + 1/m2), equal and opposite.
      const double ff = g / (1 / model.m1 + 1 / model.m2);
      ASSERT_TRUE(near(out.feedforward, Eigen::Vector2d(ff, -ff), 1e-12, 1 + std::abs(ff), "feedforward"));
    }
  }
}

TEST(ClosedForms, ConstantLengthPendulumTension) {
  RandomSource<double> rng(34);
  Pendulum<double> model;  // mu = 0: constant length L
  auto controller = controller_with<Pendulum<double>>(InverseStrategy::kCholeskyWithFallback, model);
  TrackingController<Pendulum<double>>::Output out;
  for (int it = 0; it < test_repeat(); ++it) {
    // A state on the circle moving tangentially.
    const double theta = rng.uniform(-3, 3), omega = rng.uniform(-3, 3), L = model.length;
    const Eigen::Vector2d q(L * std::sin(theta), L * std::cos(theta));
    const Eigen::Vector2d qd(L * omega * std::cos(theta), -L * omega * std::sin(theta));
    ASSERT_EQ(controller.compute(q, qd, 0.0, out), Status::kOk);
    // Rod tension T = m v^2 / L + m g cos(theta), pulling the bob toward the pivot.
    const double tension = model.mass * (L * omega * omega + model.gravity * std::cos(theta));
    const Eigen::Vector2d expected = -tension * q / L;
    ASSERT_TRUE(near(out.force, expected, 1e-12, 1 + std::abs(tension), "rod tension"));
    // The angle model: theta'' = -(g / L) sin(theta).
    const double theta_dd = -model.gravity / L * std::sin(theta);
    const Eigen::Vector2d acc(L * (theta_dd * std::cos(theta) - omega * omega * std::sin(theta)),
                              -L * (theta_dd * std::sin(theta) + omega * omega * std::cos(theta)));
    ASSERT_TRUE(near(out.acceleration, acc, 1e-12, 1 + inf_norm(acc), "angle model"));
  }
}

}  // namespace
}  // namespace gausstrack::test
