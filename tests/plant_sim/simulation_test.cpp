// Runs the paper's scenes and holds them to what the paper reports, against closed forms and
// independent formulations that could fail: the angle-coordinate pendulum, the minimal-coordinate
// Duffing oscillator, eq. (38)'s invariants, and the controller's own hand-written models.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <boost/numeric/odeint.hpp>
#include <boost/numeric/odeint/external/eigen/eigen.hpp>
#include <cmath>
#include <fstream>
#include <numbers>
#include <random>

#include "gausstrack/plant_sim/scene.hpp"
#include "pendulum_angle_model.hpp"
#include "gausstrack/plant_sim/simulation.hpp"
#include "gausstrack/systems/coupled_duffing.hpp"
#include "gausstrack/systems/pendulum.hpp"
#include "gausstrack/tracking_controller.hpp"

namespace gausstrack::plant_sim {
namespace {

const std::string kScenes = GAUSSTRACK_SCENE_DIR;
namespace odeint = boost::numeric::odeint;

std::size_t kind(EffectKind k) { return static_cast<std::size_t>(k); }

// Every control evaluation's warnings are tallied. A run whose answers gave task rows up in more
// than tracking.unmet_limit of its evaluations completes and says that it did not track, with the
// kinds; a tracking error far above the law's confirms it independently.
TEST(Simulation, WarningsAreCountedAndARunThatDidNotTrackSaysSo) {
  const std::string path = kScenes + "/duffing_alpha4.yaml";
  const RunResult ok = run_scene(load_scene(path, {"duration=0.5"}));
  EXPECT_EQ(ok.summary.warnings.calls, ok.summary.control_evaluations);
  EXPECT_EQ(ok.summary.warnings.rows_not_met, 0u);
  EXPECT_TRUE(ok.summary.rows_not_met.empty());
  // A singular-value floor far above that of D A^(-1/2) (about 1.4): each answer gives the row up.
  const RunResult given_up = run_scene(load_scene(path, {"duration=0.5", "tracking.min_singular_value=1e6"}));
  const RunSummary& s = given_up.summary;
  EXPECT_TRUE(s.failure.empty());
  EXPECT_EQ(s.warnings.calls, s.control_evaluations);
  EXPECT_EQ(s.warnings.by_kind[4], s.control_evaluations);  // warning::kNearSingular is bit 4
  EXPECT_EQ(s.warnings.rows_not_met, s.control_evaluations);
  EXPECT_NE(s.rows_not_met.find("100.0 % of the control evaluations"), std::string::npos) << s.rows_not_met;
  EXPECT_NE(s.rows_not_met.find("near_singular"), std::string::npos) << s.rows_not_met;
  EXPECT_GT(s.max_tracking_error, 1e3 * ok.summary.max_tracking_error);
  // A limit that allows every evaluation to miss accepts the same run.
  const RunResult allowed = run_scene(
      load_scene(path, {"duration=0.5", "tracking.min_singular_value=1e6", "tracking.unmet_limit=1"}));
  EXPECT_TRUE(allowed.summary.rows_not_met.empty());
  EXPECT_THROW(load_scene(path, {"tracking.unmet_limit=2"}), SceneError);
}

TEST(Simulation, DuffingTracksToThePaperAccuracyForBothAlphas) {
  for (const char* name : {"duffing_alpha4", "duffing_alpha0.4"}) {
    const Scene s = load_scene(kScenes + "/" + name + ".yaml");
    const RunResult r = run_scene(s);
    EXPECT_EQ(r.samples.size(), 1001u);
    EXPECT_LE(r.summary.max_tracking_error, 1e-9) << name;  // the paper: 1e-9 at tolerance 1e-10
    EXPECT_EQ(r.summary.control_failures, 0u);
    // The force of eq. (32) is equal and opposite on the two masses.
    for (const Sample& smp : r.samples) ASSERT_NEAR(smp.u[0], -smp.u[1], 1e-9 * (1 + std::abs(smp.u[0])));
  }
}

// Independent formulation: with x1 = x2 + s(t), summing eq. (35a) and (35b) eliminates the
// control force: (m1 + m2) x2'' = -(f1 + f2) - m1 s''. Integrated in x2 alone.
TEST(Simulation, DuffingMatchesTheMinimalCoordinateModel) {
  const Scene s = load_scene(kScenes + "/duffing_alpha0.4.yaml");
  const RunResult r = run_scene(s);
  systems::CoupledDuffing<double> m;
  m.trajectory.alpha = 0.4;
  using S2 = Eigen::Matrix<double, 2, 1>;
  auto rhs = [&](const S2& z, S2& dz, double t) {
    const double x2 = z(0), v2 = z(1);
    const double x1 = x2 + m.trajectory.position(t), v1 = v2 + m.trajectory.velocity(t);
    const double d = x1 - x2, dd = v1 - v2;
    const double f1 = m.k1 * d + m.c1 * dd + m.kb1 * d * d * d;
    const double f2 = m.k2 * x2 - m.k1 * d + m.c2 * v2 - m.c1 * dd + m.kb2 * x2 * x2 * x2 - m.kb1 * d * d * d;
    dz << v2, (-(f1 + f2) - m.m1 * m.trajectory.acceleration(t)) / (m.m1 + m.m2);
  };
  S2 z(1.0, 2.0);
  using D2 = odeint::runge_kutta_dopri5<S2, double, S2, double, odeint::vector_space_algebra>;
  auto ds = odeint::make_dense_output(1e-13, 1e-13, D2());
  ds.initialize(z, 0.0, 1e-3);
  double worst = 0;
  for (const Sample& smp : r.samples) {
    while (ds.current_time() < smp.t) ds.do_step(rhs);
    S2 zs = z;
    if (smp.t > 0) ds.calc_state(smp.t, zs);
    worst = std::max(worst, std::abs(smp.q[1] - zs(0)));
    worst = std::max(worst, std::abs(smp.q[0] - zs(0) - m.trajectory.position(smp.t)));
  }
  EXPECT_LT(worst, 1e-7);
  std::printf("duffing vs minimal-coordinate model: max |dx| = %.3g\n", worst);
}

TEST(Simulation, ConstantLengthPendulumEqualsTheAngleModel) {
  const Scene s = load_scene(kScenes + "/pendulum_fig1.yaml");
  const RunResult r = run_scene(s);
  const testing::AngleModelComparison a = testing::compare_with_angle_model(s, r);
  EXPECT_LT(a.max_difference, 1e-6);  // 20 m rod: 5e-8 relative
  EXPECT_GT(a.max_angle_deg, 76.0);   // the paper: "about 80 degrees"
  EXPECT_LT(a.max_angle_deg, 80.0);
  EXPECT_LT(r.summary.max_constraint_residual, 1e-6);      // of x^2 + y^2 - L^2 = 400
}

TEST(Simulation, NonlinearLengthPendulumKeepsItsConstraint) {
  for (const char* a : {"0.5", "1", "2", "4"}) {
    const Scene s = load_scene(kScenes + "/pendulum_fig2.yaml", {std::string("plant.initial.qd1=") + a});
    const RunResult r = run_scene(s);
    EXPECT_LT(r.summary.max_constraint_residual, 1e-4) << "a = " << a;  // of L^2 = 400
    for (const Sample& smp : r.samples) ASSERT_TRUE(std::isfinite(smp.q[0]) && std::isfinite(smp.q[1]));
  }
}

// Eq. (38): no force does work on the particle, so kinetic energy is constant, and z'' = 0.
TEST(Simulation, RosenbergParticleKeepsEq38Invariants) {
  const Scene s = load_scene(kScenes + "/rosenberg.yaml");
  const RunResult r = run_scene(s);
  EXPECT_LT(r.summary.max_constraint_residual, 1e-8);
  const double e0 = 0.5 * (1.0 + 0.0 + 1.0);
  for (const Sample& smp : r.samples) {
    const double e = 0.5 * (smp.qd[0] * smp.qd[0] + smp.qd[1] * smp.qd[1] + smp.qd[2] * smp.qd[2]);
    ASSERT_NEAR(e, e0, 1e-8) << "t = " << smp.t;
    ASSERT_NEAR(smp.qd[2], 1.0, 1e-12) << "z'' = 0";
    ASSERT_NEAR(smp.q[2], smp.t, 1e-10) << "z = z0 + z0' t";
  }
}

TEST(Simulation, EveryIntegratorReachesTheTrackingAccuracy) {
  struct Case {
    std::vector<std::string> sets;
    double bound;
  };
  const Case cases[] = {{{"integrator.method=rkf78", "integrator.tolerance=1e-10"}, 1e-9},
                        {{"integrator.method=bulirsch_stoer", "integrator.tolerance=1e-10"}, 1e-9},
                        {{"integrator.method=rk4", "integrator.step=1e-3"}, 1e-9}};
  for (const Case& c : cases) {
    const Scene s = load_scene(kScenes + "/duffing_alpha4.yaml", c.sets);
    const RunResult r = run_scene(s);
    EXPECT_EQ(r.samples.size(), 1001u);
    EXPECT_LE(r.summary.max_tracking_error, c.bound) << c.sets[0];
    EXPECT_NEAR(r.samples.back().t, 10.0, 1e-12);
  }
}

// With sparse output no step is cut by the output grid: each adaptive method's cost follows its
// tolerance, and the tighter run is the more accurate one against the minimal-coordinate model.
TEST(Simulation, AdaptiveCostFollowsTheTolerance) {
  for (const char* method : {"dopri5", "rkf78", "bulirsch_stoer"}) {
    auto run_at = [&](const char* tolerance) {
      return run_scene(load_scene(kScenes + "/duffing_alpha4.yaml",
                                  {std::string("integrator.method=") + method,
                                   std::string("integrator.tolerance=") + tolerance, "output_period=1.0"}));
    };
    const RunResult loose = run_at("1e-6"), tight = run_at("1e-12");
    EXPECT_LT(loose.summary.rhs_evaluations, tight.summary.rhs_evaluations) << method;
    EXPECT_LT(tight.summary.max_tracking_error, loose.summary.max_tracking_error) << method;
    EXPECT_LT(tight.summary.max_tracking_error, 1e-9) << method;
  }
}

// Sampled and held control drifts off the trajectory; stabilization pulls it back.
TEST(Simulation, SampledControlNeedsStabilization) {
  const std::vector<std::string> sampled = {"control.mode=sampled", "control.rate=100"};
  const RunResult plain = run_scene(load_scene(kScenes + "/duffing_alpha4.yaml", sampled));
  auto with = sampled;
  with.push_back("tracking.stabilization={zeta: 1.0, omega: 20.0}");
  const RunResult stabilized = run_scene(load_scene(kScenes + "/duffing_alpha4.yaml", with));
  EXPECT_GT(plain.summary.max_tracking_error, 1e-3);
  EXPECT_LT(stabilized.summary.max_tracking_error, 0.5 * plain.summary.max_tracking_error);
  EXPECT_LT(std::abs(stabilized.samples.back().tracking_error), 1e-3);
  EXPECT_EQ(stabilized.summary.control_evaluations, 1000u);
}

// A controller whose model is wrong (k1 10% high) no longer keeps the trajectory: the model error
// acts as an unmodelled force and e'' != 0. Stabilization turns the drift into a small bounded error.
TEST(Simulation, ModelMismatchDriftsAndStabilizationBoundsIt) {
  const std::string scene = kScenes + "/duffing_alpha0.4.yaml";
  const RunResult exact = run_scene(load_scene(scene));
  const RunResult wrong = run_scene(load_scene(scene, {"tracking.parameters.k1=11.0"}));
  const RunResult held = run_scene(load_scene(
      scene, {"tracking.parameters.k1=11.0", "tracking.stabilization={zeta: 1.0, omega: 10.0}"}));
  EXPECT_GT(wrong.summary.max_tracking_error, 1e3 * exact.summary.max_tracking_error);
  EXPECT_LT(held.summary.max_tracking_error, 0.1 * wrong.summary.max_tracking_error);
}

TEST(Simulation, UnlistedEffectsAreNeverEvaluated) {
  const RunResult pend = run_scene(load_scene(kScenes + "/pendulum_fig1.yaml"));
  for (std::size_t k = 0; k < pend.summary.effect_evaluations.size(); ++k) {
    if (k == kind(EffectKind::kGravity)) {
      EXPECT_EQ(pend.summary.effect_evaluations[k], pend.summary.rhs_evaluations);
    } else {
      EXPECT_EQ(pend.summary.effect_evaluations[k], 0u) << to_string(static_cast<EffectKind>(k));
    }
  }
  const RunResult duff = run_scene(load_scene(kScenes + "/duffing_alpha4.yaml"));
  EXPECT_EQ(duff.summary.effect_evaluations[kind(EffectKind::kGravity)], 0u);
  EXPECT_EQ(duff.summary.effect_evaluations[kind(EffectKind::kSpring)], 2 * duff.summary.rhs_evaluations);
  EXPECT_EQ(duff.summary.effect_evaluations[kind(EffectKind::kSensorNoise)], 0u);
  EXPECT_EQ(duff.summary.effect_evaluations[kind(EffectKind::kActuatorSaturation)], 0u);
}

TEST(Simulation, SaturationClampsTheAppliedForce) {
  const RunResult r = run_scene(load_scene(kScenes + "/duffing_alpha4.yaml",
                                           {"plant.effects.6={type: actuator_saturation, limit: 20.0}"}));
  double peak = 0;
  for (const Sample& smp : r.samples) peak = std::max({peak, std::abs(smp.u[0]), std::abs(smp.u[1])});
  EXPECT_LE(peak, 20.0);
  EXPECT_GT(r.summary.max_tracking_error, 1e-6);  // the unsaturated law needs 42 N at t = 0
}

// The plant's forces come from its effects; the controller's CoupledDuffing is a separate,
// hand-written model of the same physics: Q_plant = -f_model at any state.
TEST(Simulation, PlantEffectsAgreeWithTheControllerModels) {
  const Scene s = load_scene(kScenes + "/duffing_alpha4.yaml");
  systems::CoupledDuffing<double> m;
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-3, 3);
  for (int it = 0; it < 200; ++it) {
    const std::vector<double> q = {u(rng), u(rng)}, qd = {u(rng), u(rng)};
    const auto Q = plant_applied_force(s, q, qd, 0.0);
    const Eigen::Vector2d f = m.spring_damper_force(Eigen::Vector2d(q[0], q[1]), Eigen::Vector2d(qd[0], qd[1]));
    ASSERT_NEAR(Q[0], -f(0), 1e-12 * (1 + std::abs(f(0))));
    ASSERT_NEAR(Q[1], -f(1), 1e-12 * (1 + std::abs(f(1))));
  }
  // The pendulum plant's constrained acceleration against the controller's Pendulum model.
  for (double mu : {0.0, -0.1}) {
    const Scene p = load_scene(kScenes + "/pendulum_fig2.yaml", {"plant.constraints.0.mu=" + std::to_string(mu)});
    systems::Pendulum<double> model;
    model.mu = mu;
    TrackingController<systems::Pendulum<double>> c(model);
    TrackingController<systems::Pendulum<double>>::Output out;
    for (int it = 0; it < 200; ++it) {
      const std::vector<double> q = {u(rng), 20 + u(rng)}, qd = {u(rng), u(rng)};
      const auto acc = plant_acceleration(p, q, qd, 0.0, {0.0, 0.0});
      ASSERT_EQ(c.compute(Eigen::Vector2d(q[0], q[1]), Eigen::Vector2d(qd[0], qd[1]), 0.0, out), Status::kOk);
      ASSERT_NEAR(acc[0], out.acceleration(0), 1e-9 * (1 + std::abs(acc[0])));
      ASSERT_NEAR(acc[1], out.acceleration(1), 1e-9 * (1 + std::abs(acc[1])));
    }
  }
}

TEST(Simulation, OutputFilesHaveTheDocumentedColumns) {
  const Scene s = load_scene(kScenes + "/rosenberg.yaml", {"duration=0.1"});
  const RunResult r = run_scene(s);
  const std::string dir = ::testing::TempDir();
  write_trajectory_csv(s, r, dir + "/trajectory.csv");
  write_summary_json(s, r, dir + "/summary.json");
  std::ifstream csv(dir + "/trajectory.csv");
  std::string header;
  std::getline(csv, header);
  EXPECT_EQ(header, "t,q1,q2,q3,qd1,qd2,qd3,u1,u2,u3,tracking_error,constraint_residual");
  int rows = 0;
  for (std::string line; std::getline(csv, line);) ++rows;
  EXPECT_EQ(rows, 11);
  std::ifstream json(dir + "/summary.json");
  const std::string text((std::istreambuf_iterator<char>(json)), std::istreambuf_iterator<char>());
  for (const char* key : {"max_tracking_error", "max_constraint_residual", "steps", "rhs_evaluations", "wall_time_s"})
    EXPECT_NE(text.find(std::string("\"") + key + "\":"), std::string::npos) << key;
}

// Runs that cannot finish stop with a clear error naming the time and the quantities involved,
// and keep what they computed: no hang, no NaN written, no silent success.
bool samples_finite(const RunResult& r) {
  for (const Sample& smp : r.samples)
    for (const auto* v : {&smp.q, &smp.qd, &smp.u})
      for (double x : *v)
        if (!std::isfinite(x)) return false;
  return true;
}

TEST(RunGuards, DivergingPlantStopsWithItsReason) {
  // The plant's ground spring softens (cubic stiffness -50) while the controller's model keeps
  // +2: x2'' ~ 50 x2^3 blows up in finite time, and the adaptive steps collapse.
  const Scene s = load_scene(kScenes + "/duffing_alpha4.yaml", {"plant.effects.4.stiffness=-50"});
  const RunResult r = run_scene(s);
  ASSERT_FALSE(r.summary.failure.empty());
  std::printf("%s\n", r.summary.failure.c_str());
  EXPECT_TRUE(r.summary.failure.find("steps collapsed") != std::string::npos ||
              r.summary.failure.find("finite range") != std::string::npos ||
              r.summary.failure.find("could not take a step") != std::string::npos)
      << r.summary.failure;
  EXPECT_NE(r.summary.failure.find("t = "), std::string::npos);
  EXPECT_GT(r.summary.failed_at, 0.0);
  EXPECT_LT(r.summary.failed_at, 10.0);
  EXPECT_FALSE(r.samples.empty());
  EXPECT_LT(r.samples.size(), 1001u);
  EXPECT_TRUE(samples_finite(r));
}

TEST(RunGuards, OverflowingForcesStopInsteadOfWritingNaN) {
  for (const char* method : {"dopri5", "rkf78", "bulirsch_stoer", "rk4"}) {
    const Scene s = load_scene(kScenes + "/duffing_alpha4.yaml",
                               {"plant.effects.0.stiffness=1e307", std::string("integrator.method=") + method,
                                "integrator.step=1e-3"});
    const RunResult r = run_scene(s);
    EXPECT_FALSE(r.summary.failure.empty()) << method;
    EXPECT_TRUE(samples_finite(r)) << method;
  }
}

TEST(RunGuards, GridsThatCannotBeHeldAreRejectedUpFront) {
  for (const char* set : {"duration=1e30", "output_period=1e-9"}) {
    try {
      load_scene(kScenes + "/duffing_alpha4.yaml", {set});
      FAIL() << set;
    } catch (const SceneError& e) {
      EXPECT_NE(std::string(e.what()).find("output_period"), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(load_scene(kScenes + "/duffing_alpha4.yaml",
                          {"integrator.method=rk4", "integrator.step=1e-9", "integrator.max_steps=1e6"}),
               SceneError);
}

TEST(RunGuards, AStopRequestKeepsTheSamplesSoFar) {
  const Scene s = load_scene(kScenes + "/duffing_alpha4.yaml");
  RunOptions o;
  int polls = 0;
  o.stop_requested = [&] { return ++polls > 200; };
  const RunResult r = run_scene(s, o);
  EXPECT_TRUE(r.summary.stopped_early);
  EXPECT_TRUE(r.summary.failure.empty());
  EXPECT_GT(r.samples.size(), 1u);
  EXPECT_LT(r.samples.size(), 1001u);
}

}  // namespace
}  // namespace gausstrack::plant_sim
