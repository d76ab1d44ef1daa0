// The tracking controller: its force split, the feedforward of the Duffing law, constraint
// stabilization (converges with it, drifts without it, as the closed forms of the error
// dynamics say), bad state and bad configuration.
#include <boost/numeric/odeint.hpp>
#include <boost/numeric/odeint/external/eigen/eigen.hpp>
#include <stdexcept>

#include "gausstrack/systems/coupled_duffing.hpp"
#include "gausstrack/systems/duffing_chain.hpp"
#include "gausstrack/consistent_state.hpp"
#include "gausstrack/systems/pendulum.hpp"
#include "gausstrack/systems/planar_arm.hpp"
#include "gausstrack/tracking_controller.hpp"
#include "hand_written_systems.hpp"
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
    // The hand-written rows, solved directly: the derived rows and the controller must give the
    // same force to the last bit's neighbourhood.
    HandDuffing<double> hand;
    ModelTerms<2, 1, double> terms;
    hand.evaluate(q, qd, t, terms);
    solver.solve(terms.mass_matrix, terms.nonlinear_force, terms.applied_force, terms.constraint_matrix,
                 terms.constraint_rhs, sol);
    EXPECT_TRUE(near(out.force, sol.constraint_force, 1e-13, 1 + inf_norm(sol.constraint_force), "force"));
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
                            errors.emplace_back(t, model.phi(Eigen::Vector2d(s.head<2>()), t)(0));
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

// The planar arm driven by its own law, the model as the plant (q'' = the law's acceleration),
// dopri5 at tolerance 1e-11. Each hand coordinate's error obeys e'' = 0 without stabilization and
// e'' + 2 w e' + w^2 e = 0 with zeta = 1, so from e(0) = e0, e'(0) = 0 the closed form is
// e(t) = e0 (1 + w t) e^(-w t). Returns the hand's error phi at t = 0, 0.25, ..., 10.
using ArmState = Eigen::Matrix<double, 6, 1>;
std::vector<std::pair<double, Eigen::Vector2d>> run_arm(const ControllerOptions<double>& options,
                                                        const Eigen::Vector3d& offset) {
  using Arm = systems::PlanarArm<double>;
  Arm arm;
  Eigen::Vector3d q(0.2, 0.9, 0.6), qd = Eigen::Vector3d::Zero();
  EXPECT_TRUE(make_consistent(arm, q, qd, 0.0));
  TrackingController<Arm> controller(arm, options);
  TrackingController<Arm>::Output out;
  // Move the arm off the circle, keeping the hand's velocity error zero (q' on the tangent).
  q += offset;
  TermsOf<Arm> terms;
  evaluate_model(arm, q, qd, 0.0, terms);
  const Eigen::Matrix<double, 2, 3> jac = terms.constraint_matrix;
  qd -= jac.transpose() * (jac * jac.transpose()).ldlt().solve(terms.constraint_error_rate);
  auto rhs = [&](const ArmState& x, ArmState& dxdt, double t) {
    EXPECT_EQ(controller.compute(x.head<3>(), x.tail<3>(), t, out), Status::kOk);
    dxdt << x.tail<3>(), out.acceleration;
  };
  ArmState x;
  x << q, qd;
  std::vector<double> times;
  for (int i = 0; i <= 40; ++i) times.push_back(0.25 * i);
  std::vector<std::pair<double, Eigen::Vector2d>> errors;
  namespace odeint = boost::numeric::odeint;
  using Stepper = odeint::runge_kutta_dopri5<ArmState, double, ArmState, double, odeint::vector_space_algebra>;
  odeint::integrate_times(odeint::make_dense_output(1e-11, 1e-11, Stepper()), rhs, x, times.begin(), times.end(),
                          1e-3, [&](const ArmState& s, double t) {
                            errors.emplace_back(t, arm.phi(Eigen::Vector3d(s.head<3>()), t));
                          });
  return errors;
}

TEST(PlanarArm, HandStaysOnTheCircleWithoutStabilization) {
  const auto errors = run_arm(ControllerOptions<double>{}, Eigen::Vector3d::Zero());
  ASSERT_EQ(errors.size(), 41u);
  double worst = 0;
  for (const auto& [t, e] : errors) worst = std::max(worst, e.norm());
  std::printf("arm, no stabilization: max |phi| over 10 s = %.3g m\n", worst);
  // The integrator's accuracy: local tolerance 1e-11 over 10 s of a 1-3 rad/s motion.
  EXPECT_LT(worst, 1e-8);
}

TEST(PlanarArm, StabilizationRecoversAsTheGainsPredict) {
  const double w = 5.0;
  const Eigen::Vector3d offset(0.02, -0.03, 0.01);
  const auto errors = run_arm(stabilized(1.0, w), offset);
  const Eigen::Vector2d e0 = errors.front().second;
  ASSERT_GT(e0.norm(), 1e-3);
  for (const auto& [t, e] : errors) {
    const Eigen::Vector2d predicted = e0 * (1 + w * t) * std::exp(-w * t);
    EXPECT_TRUE(near(e, predicted, 1e-7, 1, "Baumgarte error dynamics")) << "t = " << t;
  }
  EXPECT_LT(errors.back().second.norm(), 1e-9);
  // Without stabilization the same start keeps its error (e'' = 0 from e'(0) = 0).
  const auto kept = run_arm(ControllerOptions<double>{}, offset);
  EXPECT_TRUE(near(kept.back().second, e0, 1e-7, 1, "error kept"));
}

// The robust term in closed form on the Duffing pair's one row: it adds
// D^T (D A^-1 D^T)^-1 (-rho sat(s / Phi)), s = e' + omega e, to the stabilizing force, inside the
// boundary layer (linear in s) and outside it (rho itself); off, the force is Baumgarte's alone.
// The states are put on the path (the row is x1 - x2 - x_d(t), so x1 and x1' move e and e' one for
// one) and then given the sliding variable s = 0.02, 0.9 and 3 layers.
TEST(TrackingController, RobustTermIsTheSaturatedSlidingCorrection) {
  ControllerOptions<double> plain_options, robust_options;
  plain_options.stabilization = robust_options.stabilization = {1.0, 20.0};
  robust_options.robust = {50.0, 0.01};
  TrackingController<Duffing> plain(Duffing{}, plain_options), robust(Duffing{}, robust_options);
  for (const double layers : {0.02, -0.9, 3.0}) {
    Eigen::Vector2d q(0.3, 0.1), qd(0.2, -0.1);
    TrackingController<Duffing>::Output a, b;
    ASSERT_EQ(plain.compute(q, qd, 0.4, a), Status::kOk);
    q(0) -= a.constraint_error(0);                                 // e = 0
    qd(0) += layers * 0.01 - a.constraint_error_rate(0);          // e' = s
    ASSERT_EQ(plain.compute(q, qd, 0.4, a), Status::kOk);
    ASSERT_NEAR(a.constraint_error_rate(0) + 20.0 * a.constraint_error(0), layers * 0.01, 1e-12);
    ASSERT_EQ(robust.compute(q, qd, 0.4, b), Status::kOk);
    const auto& t = plain.terms();
    const double sat = layers < 1.0 ? layers : 1.0;  // s / Phi, clipped at one layer
    const Eigen::RowVector2d D = t.constraint_matrix;
    const double gram = (D * t.mass_matrix.inverse() * D.transpose())(0, 0);
    const Eigen::Vector2d expected = D.transpose() * (-50.0 * sat / gram);
    EXPECT_TRUE(near(Eigen::Vector2d(b.stabilizing - a.stabilizing), expected, 1e-10, 1 + expected.norm(), "robust"))
        << "s / Phi = " << layers;
    EXPECT_TRUE(near(Eigen::Vector2d(b.feedforward), Eigen::Vector2d(a.feedforward), 1e-12, 1 + a.force.norm(), "ff"));
  }
  EXPECT_NEAR(robust_error_bound(robust_options.stabilization, robust_options.robust),
              50.0 / (20.0 * (20.0 + 50.0 / 0.01)), 1e-18);
  EXPECT_EQ(robust_error_bound(Stabilization<double>{0.7, 20.0}, robust_options.robust),
            std::numeric_limits<double>::infinity());  // no promise off zeta = 1
  EXPECT_FALSE(robust.set_robust(0, {1.0, 0.0}));  // a layer must be > 0
  EXPECT_FALSE(robust.set_robust(1, {1.0, 1.0}));  // one row only
  robust_options.robust.bound = -1;
  EXPECT_NE(robust_options.validate(), nullptr);
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
