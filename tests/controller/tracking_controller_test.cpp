// The tracking controller: its force split, the feedforward of the Duffing law, constraint
// stabilization (converges with it, drifts without it, as the closed forms of the error
// dynamics say), bad state and bad configuration.
#include <boost/numeric/odeint.hpp>
#include <boost/numeric/odeint/external/eigen/eigen.hpp>
#include <stdexcept>

#include "gausstrack/systems/coupled_duffing.hpp"
#include "gausstrack/systems/duffing_chain.hpp"
#include "gausstrack/systems/pendulum.hpp"
#include "gausstrack/tracking_controller.hpp"
#include "test_support.hpp"

namespace gausstrack::test {
namespace {

using systems::CoupledDuffing;
using Duffing = CoupledDuffing<double>;

ControllerOptions<double> stabilized(double zeta, double omega) {
  ControllerOptions<double> o;
  o.stabilization.zeta = zeta;
  o.stabilization.omega = omega;
  return o;
}

TEST(TrackingController, PartsAddUpToTheForce) {
  RandomSource<double> rng(1);
  TrackingController<systems::DuffingChain<12, 6>> controller({}, stabilized(0.7, 8));
  decltype(controller)::Output out;
  for (int it = 0; it < test_repeat(); ++it) {
    const auto q = rng.matrix<12, 1>(), qd = rng.matrix<12, 1>();
    ASSERT_EQ(controller.compute(q, qd, rng.uniform(0, 10), out), Status::kOk);
    const Eigen::Matrix<double, 12, 1> sum = out.closed_loop + out.feedforward + out.stabilizing;
    ASSERT_TRUE(near(sum, out.force, 1e-13, 1 + inf_norm(out.force), "parts"));
    ASSERT_FALSE(out.stabilizing.isZero(0));
  }
}

TEST(TrackingController, DefaultReproducesThePaperLawExactly) {
  RandomSource<double> rng(2);
  Duffing model;
  TrackingController<Duffing> controller(model);
  ConstraintSolver<2, 1> solver;
  ConstraintSolution<2, 1> sol;
  TrackingController<Duffing>::Output out;
  for (int it = 0; it < 100; ++it) {
    const Eigen::Vector2d q = rng.matrix<2, 1>(), qd = rng.matrix<2, 1>();
    const double t = rng.uniform(0, 10);
    ASSERT_EQ(controller.compute(q, qd, t, out), Status::kOk);
    solver.solve(model.mass_matrix(q, t), model.nonlinear_force(q, qd, t), model.applied_force(q, qd, t),
                 model.constraint_matrix(q, t), model.constraint_rhs(q, qd, t), sol);
    EXPECT_TRUE(out.force == sol.constraint_force);
    EXPECT_TRUE(out.stabilizing.isZero(0));
  }
}

// A, D and g of the Duffing problem depend on t alone: the feedforward part must not change
// with the state, while the closed-loop part does.
TEST(TrackingController, DuffingFeedforwardDependsOnTimeAlone) {
  RandomSource<double> rng(3);
  TrackingController<Duffing> controller;
  TrackingController<Duffing>::Output a, b;
  for (int it = 0; it < 100; ++it) {
    const double t = rng.uniform(0, 10);
    ASSERT_EQ(controller.compute(rng.matrix<2, 1>(), rng.matrix<2, 1>(), t, a), Status::kOk);
    ASSERT_EQ(controller.compute(rng.matrix<2, 1>(), rng.matrix<2, 1>(), t, b), Status::kOk);
    EXPECT_TRUE(near(a.feedforward, b.feedforward, 1e-14, 1 + inf_norm(a.feedforward), "feedforward"));
    EXPECT_GT((a.closed_loop - b.closed_loop).norm(), 1e-6);
  }
}

using State = Eigen::Matrix<double, 4, 1>;

// Integrates the Duffing oscillator under the controller from a state off the trajectory and
// records the tracking error e = x1 - x2 - s(t) at t = 0, 0.5, ..., 10.
std::vector<std::pair<double, double>> run_duffing(const ControllerOptions<double>& options, double e0,
                                                   double e0_rate) {
  Duffing model;
  TrackingController<Duffing> controller(model, options);
  TrackingController<Duffing>::Output out;
  auto rhs = [&](const State& x, State& dxdt, double t) {
    controller.compute(x.head<2>(), x.tail<2>(), t, out);
    dxdt << x.tail<2>(), out.acceleration;
  };
  const double d = 2.0;
  State x(1.0 + e0, 1.0, model.consistent_x1_velocity(d) + e0_rate, d);
  std::vector<double> times;
  for (int i = 0; i <= 20; ++i) times.push_back(0.5 * i);
  std::vector<std::pair<double, double>> errors;
  namespace odeint = boost::numeric::odeint;
  using Stepper = odeint::runge_kutta_dopri5<State, double, State, double, odeint::vector_space_algebra>;
  odeint::integrate_times(odeint::make_dense_output(1e-11, 1e-11, Stepper()), rhs, x, times.begin(),
                          times.end(), 1e-3, [&](const State& s, double t) {
                            errors.emplace_back(t, model.constraint_error(s.head<2>(), t)(0));
                          });
  return errors;
}

// Without stabilization the paper's law enforces e'' = 0, so an initial error persists and grows:
// e(t) = e0 + e0' t. With zeta = 1, omega = w: e(t) = (e0 + (e0' + w e0) t) e^(-w t).
TEST(TrackingController, StabilizationMakesAnOffTrajectoryStartConverge) {
  const double e0 = 0.1, e0_rate = -0.3, w = 5.0;
  const auto drift = run_duffing(ControllerOptions<double>{}, e0, e0_rate);
  for (const auto& [t, e] : drift) EXPECT_NEAR(e, e0 + e0_rate * t, 1e-7) << "t = " << t;
  EXPECT_GT(std::abs(drift.back().second), 2.0);

  const auto converge = run_duffing(stabilized(1.0, w), e0, e0_rate);
  for (const auto& [t, e] : converge)
    EXPECT_NEAR(e, (e0 + (e0_rate + w * e0) * t) * std::exp(-w * t), 1e-7) << "t = " << t;
  EXPECT_LT(std::abs(converge.back().second), 1e-9);
}

TEST(TrackingController, NonFiniteStateFailsWithZeroOutput) {
  TrackingController<Duffing> controller({}, stabilized(1, 5));
  TrackingController<Duffing>::Output out;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(controller.compute(Eigen::Vector2d(nan, 0), Eigen::Vector2d::Zero(), 0.0, out),
            Status::kNonFiniteInput);
  EXPECT_EQ(out.diagnostics.non_finite_inputs, input::kState);
  EXPECT_TRUE(out.force.isZero(0));
  EXPECT_EQ(controller.compute(Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero(),
                               std::numeric_limits<double>::infinity(), out),
            Status::kNonFiniteInput);
  EXPECT_TRUE(out.force.isZero(0) && out.feedforward.isZero(0) && out.acceleration.isZero(0));
  // A model whose output is non-finite (a bob at the pivot with mu making D singular is fine;
  // a NaN parameter is not) is reported through the solver's input flags.
  systems::Pendulum<double> broken;
  broken.gravity = nan;
  TrackingController<systems::Pendulum<double>> pc(broken);
  decltype(pc)::Output po;
  EXPECT_EQ(pc.compute(Eigen::Vector2d(1, 1), Eigen::Vector2d(0, 0), 0.0, po), Status::kNonFiniteInput);
  EXPECT_EQ(po.diagnostics.non_finite_inputs, input::kAppliedForce);
  EXPECT_TRUE(po.force.isZero(0));
}

TEST(TrackingController, BadConfigurationIsRejectedWithItsName) {
  ControllerOptions<double> o = stabilized(1, -2);
  ASSERT_NE(o.validate(), nullptr);
  EXPECT_NE(std::string(o.validate()).find("omega"), std::string::npos);
  try {
    TrackingController<Duffing> c({}, o);
    FAIL() << "negative omega accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("omega"), std::string::npos);
  }
  o = stabilized(1, 2);
  o.solver.damping = -1;
  EXPECT_NE(o.validate(), nullptr);
  EXPECT_EQ(stabilized(0.5, 3).validate(), nullptr);
}

TEST(TrackingController, FloatMatchesDouble) {
  RandomSource<double> rng(5);
  TrackingController<CoupledDuffing<float>> single({}, ControllerOptions<float>{});
  TrackingController<Duffing> twice;
  decltype(single)::Output sf;
  TrackingController<Duffing>::Output sd;
  for (int it = 0; it < 100; ++it) {
    const Eigen::Vector2f q = rng.matrix<2, 1>().cast<float>(), qd = rng.matrix<2, 1>().cast<float>();
    const float t = static_cast<float>(rng.uniform(0, 2));
    ASSERT_EQ(single.compute(q, qd, t, sf), Status::kOk);
    ASSERT_EQ(twice.compute(q.cast<double>(), qd.cast<double>(), static_cast<double>(t), sd), Status::kOk);
    EXPECT_TRUE(near(sf.force, sd.force, 1e-4, 1 + inf_norm(sd.force), "float force"));
  }
}

}  // namespace
}  // namespace gausstrack::test
