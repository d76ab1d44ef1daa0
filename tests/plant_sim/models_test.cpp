// Models by name, as tracking controllers and as plants, at any dimension: each shipped model
// tracks from its scene; plants built two ways agree (point masses with effects vs the model's
// own dynamics; a physical constraint held by the plant's KKT solve vs the same constraint
// imposed by the control law); a user's own model runs through RunOptions::models alone.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <bit>
#include <cmath>
#include <string>

#include "../../examples/my_first_model/my_model.hpp"
#include "gausstrack/plant_sim/models.hpp"
#include "gausstrack/plant_sim/scene.hpp"
#include "gausstrack/plant_sim/simulation.hpp"

namespace gausstrack::plant_sim {
namespace {

const std::string kScenes = GAUSSTRACK_SCENE_DIR;

double max_difference(const RunResult& a, const RunResult& b) {
  EXPECT_EQ(a.samples.size(), b.samples.size());
  double worst = 0;
  for (std::size_t k = 0; k < std::min(a.samples.size(), b.samples.size()); ++k)
    for (std::size_t i = 0; i < a.samples[k].q.size(); ++i)
      worst = std::max({worst, std::abs(a.samples[k].q[i] - b.samples[k].q[i]),
                        std::abs(a.samples[k].qd[i] - b.samples[k].qd[i])});
  return worst;
}

TEST(Models, ChainOfEightTracksItsFourRelativeDisplacements) {
  const RunResult r = run_scene(load_scene(kScenes + "/duffing_chain8.yaml"));
  ASSERT_TRUE(r.summary.failure.empty()) << r.summary.failure;
  EXPECT_EQ(r.samples.front().q.size(), 8u);
  EXPECT_LT(r.summary.max_tracking_error, 1e-8);
  EXPECT_EQ(r.summary.control_failures, 0u);
  // Q' = D^T lambda (eq. 32 with A positive definite) and every row of D is e_j - e_(j+1): the
  // forces sum to zero, as internal forces do.
  for (const Sample& s : r.samples) {
    double sum = 0, scale = 0;
    for (double u : s.u) sum += u, scale += std::abs(u);
    ASSERT_LE(std::abs(sum), 1e-9 * (1 + scale));
  }
}

// The cart-pole declares one actuator (the cart's motor): the scene's law is the actuated one,
// every force it applies is along the cart alone (exactly zero on the pendulum's angle), and the
// pendulum follows its angle. Sampled at 1 kHz, the held law (midpoint, the default) is far more
// accurate than the law at the measured state, through the same prediction as the plain law's.
TEST(Models, CartPoleSwingsItsPendulumWithTheCartForceAlone) {
  const RunResult r = run_scene(load_scene(kScenes + "/cart_pole.yaml"));
  ASSERT_TRUE(r.summary.failure.empty()) << r.summary.failure;
  EXPECT_LT(r.summary.max_tracking_error, 1e-8);
  EXPECT_EQ(r.summary.control_failures, 0u);
  EXPECT_EQ(r.summary.warnings.rows_not_met, 0u);
  double largest = 0;
  for (const Sample& s : r.samples) {
    ASSERT_EQ(s.u[1], 0.0) << "t = " << s.t;
    largest = std::max(largest, std::abs(s.u[0]));
  }
  EXPECT_GT(largest, 0.1);  // the cart is pushed
  const std::vector<std::string> sampled = {"control.mode=sampled", "control.rate=1000",
                                            "duration=2"};
  std::vector<std::string> sample_law = sampled;
  sample_law.push_back("tracking.hold=sample");
  const RunResult held = run_scene(load_scene(kScenes + "/cart_pole.yaml", sampled));
  const RunResult plain = run_scene(load_scene(kScenes + "/cart_pole.yaml", sample_law));
  EXPECT_GT(plain.summary.max_tracking_error, 50 * held.summary.max_tracking_error)
      << "held " << held.summary.max_tracking_error << ", at the measured state "
      << plain.summary.max_tracking_error;
}

// The arm with its wrist passive: the plant is the full arm, the law pushes the shoulder and the
// elbow alone (exactly zero torque at the wrist), the hand follows the circle, and the wrist link
// swings on its own (the task's zero dynamics: a pendulum hanging from the hand).
TEST(Models, ArmWithAPassiveWristTracksWithTwoMotors) {
  const RunResult r = run_scene(load_scene(kScenes + "/planar_arm_passive_wrist.yaml"));
  ASSERT_TRUE(r.summary.failure.empty()) << r.summary.failure;
  EXPECT_LT(r.summary.max_tracking_error, 1e-8);
  EXPECT_EQ(r.summary.control_failures, 0u);
  EXPECT_EQ(r.summary.warnings.rows_not_met, 0u);
  double wrist_lo = 1e9, wrist_hi = -1e9, largest = 0;
  for (const Sample& s : r.samples) {
    ASSERT_EQ(s.u[2], 0.0) << "t = " << s.t;
    largest = std::max(largest, std::abs(s.u[0]) + std::abs(s.u[1]));
    const double wrist = s.q[0] + s.q[1] + s.q[2];  // link 3's absolute angle
    wrist_lo = std::min(wrist_lo, wrist), wrist_hi = std::max(wrist_hi, wrist);
  }
  EXPECT_GT(largest, 1.0);               // the motors hold the arm against gravity
  EXPECT_GT(wrist_hi - wrist_lo, 1e-3);  // the wrist link moves, unactuated
}

// The differential drive: drive force and yaw torque only, the ground holding its wheels against
// side slip (the model's physical row, held by the plant's KKT solve). The look-ahead point
// converges onto the figure-eight, the wheels never slip, and no command ever pushes sideways.
TEST(Models, DifferentialDriveTracksTheFigureEightWithoutSlipping) {
  const RunResult r = run_scene(load_scene(kScenes + "/differential_drive.yaml"));
  ASSERT_TRUE(r.summary.failure.empty()) << r.summary.failure;
  EXPECT_EQ(r.summary.control_failures, 0u);
  EXPECT_EQ(r.summary.warnings.rows_not_met, 0u);
  EXPECT_GT(r.samples.front().tracking_error * r.samples.front().tracking_error,
            1e-3);  // starts off the path
  EXPECT_LT(r.summary.max_constraint_residual, 1e-9);
  double settled = 0, largest = 0;
  for (const Sample& s : r.samples) {
    const double sideways = -std::sin(s.q[2]) * s.u[0] + std::cos(s.q[2]) * s.u[1];
    ASSERT_LE(std::abs(sideways), 1e-12 * (1 + std::abs(s.u[0]) + std::abs(s.u[1])))
        << "t = " << s.t;
    largest = std::max(largest, std::abs(s.u[0]) + std::abs(s.u[1]));
    if (s.t >= 10) settled = std::max(settled, std::abs(s.tracking_error));
  }
  EXPECT_GT(largest, 1.0);
  EXPECT_LT(settled, 1e-8);
}

// Without a law the plant alone holds the no-slip row: pushed off along its heading and turning,
// the robot's velocity follows its heading (a plant that ignored the row would keep its first
// direction of travel).
TEST(Models, ThePlantHoldsAModelsPhysicalRowsOnItsOwn) {
  const RunResult r = run_scene(
      load_scene(kScenes + "/differential_drive.yaml",
                 {"tracking=null", "plant.initial={q1: 0, q2: 0, q3: 0, qd1: 1, qd2: 0, qd3: 0.5}",
                  "duration=4"}));
  ASSERT_TRUE(r.summary.failure.empty()) << r.summary.failure;
  const Sample& last = r.samples.back();
  EXPECT_GT(std::abs(last.q[2]), 0.5);  // it turned
  const double speed = std::hypot(last.qd[0], last.qd[1]);
  ASSERT_GT(speed, 0.1);
  EXPECT_NEAR(last.qd[0] / speed, std::cos(last.q[2]), 1e-9);
  EXPECT_NEAR(last.qd[1] / speed, std::sin(last.q[2]), 1e-9);
  EXPECT_LT(r.summary.max_constraint_residual, 1e-9);
}

// A law that leaves rows to the environment needs a plant that holds them.
TEST(Models, APlantThatCannotHoldTheModelsPhysicalRowsIsRefused) {
  try {
    run_scene(load_scene(kScenes + "/differential_drive.yaml",
                         {"plant.model=null", "plant.masses=[10, 10, 0.5]"}));
    FAIL() << "a plant without the no-slip row was accepted";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("declares 1 physical row(s), which the plant must hold"),
              std::string::npos)
        << e.what();
  }
}

// Plants that differ from the controller's model (the arm's second link 10 % heavier; the chain
// with friction the model does not know): under the same force limit the robust term's error is
// at least 10x smaller than stabilization's alone, within the bound it promises at every sample
// (both runs start on the path), and its force moves no more than 1.5x as much (total variation:
// no chattering beyond the boundary layer).
// The robust term's promises on one mismatched scene, against the same scene without it.
void expect_robust_beats_stabilization(const Scene& scene, const RunResult& robust,
                                       const RunResult& alone) {
  ASSERT_GT(scene.tracking.robust_bound, 0.0);
  ASSERT_TRUE(robust.summary.failure.empty()) << robust.summary.failure;
  ASSERT_TRUE(alone.summary.failure.empty()) << alone.summary.failure;
  constexpr auto kSaturated = static_cast<std::size_t>(std::countr_zero(warning::kSaturated));
  EXPECT_EQ(robust.summary.warnings.by_kind[kSaturated], 0u);  // the same limit, reached by neither
  EXPECT_EQ(alone.summary.warnings.by_kind[kSaturated], 0u);
  const double bound = robust_error_bound(
      Stabilization<double>{scene.tracking.zeta, scene.tracking.stabilization_omega},
      Robust<double>{scene.tracking.robust_bound, scene.tracking.robust_layer});
  EXPECT_LE(robust.summary.max_tracking_error, bound);
  EXPECT_GE(alone.summary.max_tracking_error, 10 * robust.summary.max_tracking_error)
      << "alone " << alone.summary.max_tracking_error << ", robust "
      << robust.summary.max_tracking_error;
  EXPECT_GT(robust.summary.force_total_variation, 0.0);
  EXPECT_LE(robust.summary.force_total_variation, 1.5 * alone.summary.force_total_variation)
      << robust.summary.force_total_variation << " against " << alone.summary.force_total_variation;
}

TEST(Models, TheRobustTermHoldsAMismatchedPlantWithinItsBound) {
  for (const char* name : {"planar_arm_heavy", "duffing_chain8_friction"}) {
    SCOPED_TRACE(name);
    const Scene scene = load_scene(kScenes + "/" + name + ".yaml");
    expect_robust_beats_stabilization(
        scene, run_scene(scene),
        run_scene(load_scene(kScenes + "/" + name + ".yaml", {"tracking.robust=null"})));
  }
}

// The tethered puck of examples/my_first_model (a user's own model) with its plant 10 % heavier
// than the model and pushed by an unmodelled disturbance: the same 10x, bound and total variation
// as above, under the same force limit.
TEST(Models, TheRobustTermHoldsTheHeavierTetheredPuckWithinItsBound) {
  const std::string path = kScenes + "/../../examples/my_first_model/tethered_puck.yaml";
  RunOptions o;
  o.models.push_back(model_factory<TetheredPuck>("tethered_puck"));
  const std::vector<std::string> limit = {"tracking.force_limit=10.0"};
  std::vector<std::string> with_robust = limit;
  with_robust.push_back("tracking.robust={bound: 1.0, layer: 0.002}");
  const Scene scene = load_scene(path, with_robust);
  ASSERT_EQ(scene.plant_parameters.size(), 1u);  // the plant's mass differs from the model's
  expect_robust_beats_stabilization(scene, run_scene(scene, o),
                                    run_scene(load_scene(path, limit), o));
}

TEST(Models, PointMassChainEqualsTheChainModelAsItsOwnPlant) {
  const std::string scene = kScenes + "/duffing_chain8.yaml";
  const RunResult point_masses = run_scene(load_scene(scene));
  const RunResult model = run_scene(
      load_scene(scene, {"plant.masses=null", "plant.effects=[]", "plant.model=duffing_chain",
                         "plant.parameters={m1: 2.0, m2: 1.0, k1: 10.0, k2: 12.0, kb1: 1.0, kb2: "
                         "2.0, c1: 0.1, c2: 0.15}"}));
  ASSERT_TRUE(model.summary.failure.empty()) << model.summary.failure;
  EXPECT_LT(max_difference(point_masses, model), 1e-8);
}

TEST(Models, ArmTracksTheCircleFromItsScene) {
  const RunResult r = run_scene(load_scene(kScenes + "/planar_arm.yaml"));
  ASSERT_TRUE(r.summary.failure.empty()) << r.summary.failure;
  EXPECT_LT(r.summary.max_tracking_error, 1e-7);
  EXPECT_EQ(r.summary.control_failures, 0u);
}

// A heavier link in the plant than in the controller's model: the law alone drifts, the per-row
// stabilization bounds it.
TEST(Models, ArmMismatchIsBoundedByStabilization) {
  const std::string scene = kScenes + "/planar_arm.yaml";
  const RunResult with = run_scene(load_scene(scene, {"plant.parameters={mass_2: 1.65}"}));
  const RunResult without = run_scene(
      load_scene(scene, {"plant.parameters={mass_2: 1.65}", "tracking.stabilization.omega=0"}));
  ASSERT_TRUE(with.summary.failure.empty() && without.summary.failure.empty());
  EXPECT_GT(without.summary.max_tracking_error, 1e-3);
  EXPECT_LT(with.summary.max_tracking_error, 1e-2);
  EXPECT_LT(with.summary.max_tracking_error, 0.2 * without.summary.max_tracking_error);
}

// Two formulations of the same motion: the rod held by the plant (a Lagrange-multiplier solve
// written in plant_sim) and the rod imposed by the control law on a free bob (eq. 32).
TEST(Models, PendulumHeldByThePlantEqualsPendulumHeldByTheLaw) {
  const RunResult physical = run_scene(load_scene(kScenes + "/pendulum_fig1.yaml"));
  const RunResult controlled = run_scene(load_scene(kScenes + "/pendulum_controlled.yaml"));
  ASSERT_TRUE(controlled.summary.failure.empty()) << controlled.summary.failure;
  EXPECT_LT(controlled.summary.max_tracking_error, 1e-6 * 400);  // phi in m^2, L^2 = 400
  EXPECT_LT(max_difference(physical, controlled), 1e-5);
}

TEST(Models, NonholonomicParticleHeldByThePlantEqualsParticleHeldByTheLaw) {
  const RunResult physical = run_scene(load_scene(kScenes + "/rosenberg.yaml"));
  const RunResult controlled = run_scene(load_scene(kScenes + "/particle_controlled.yaml"));
  ASSERT_TRUE(controlled.summary.failure.empty()) << controlled.summary.failure;
  EXPECT_LT(controlled.summary.max_tracking_error, 1e-8);
  EXPECT_LT(max_difference(physical, controlled), 1e-7);
}

TEST(Models, SeveralPhysicalConstraintsAreHeldTogether) {
  // Two pendulum bobs (x1, y1), (x2, y2) on rods of 20 m and 10 m, with a spring between them.
  const std::string text = R"(
name: two_bobs
plant:
  coordinates: [x1, y1, x2, y2]
  masses: [1.0, 1.0, 2.0, 2.0]
  initial: {q1: 0.0, q2: 20.0, q3: 0.0, q4: 10.0, qd1: 2.0, qd3: -1.0}
  effects:
    - {type: gravity, coordinate: y1, acceleration: 9.81}
    - {type: gravity, coordinate: y2, acceleration: 9.81}
    - {type: spring, between: [x1, x2], stiffness: 3.0}
  constraints:
    - {type: pendulum_length, x: x1, y: y1, length: 20.0}
    - {type: pendulum_length, x: x2, y: y2, length: 10.0}
integrator: {method: dopri5, tolerance: 1.0e-11}
duration: 5.0
output_period: 0.01
)";
  const RunResult r = run_scene(parse_scene(text, "two_bobs"));
  ASSERT_TRUE(r.summary.failure.empty()) << r.summary.failure;
  EXPECT_LT(r.summary.max_constraint_residual, 1e-5);
  double worst = 0;
  for (const Sample& s : r.samples) {
    worst = std::max(worst, std::abs(s.q[0] * s.q[0] + s.q[1] * s.q[1] - 400));
    worst = std::max(worst, std::abs(s.q[2] * s.q[2] + s.q[3] * s.q[3] - 100));
  }
  EXPECT_LT(worst, 1e-5);
  EXPECT_GT(std::abs(r.samples.back().q[2]), 0.1);  // the spring moved the second bob
}

// Acceleration-level integration drifts off a physical constraint (Fig. 2: 3.3e-6 of L^2);
// projecting each accepted step onto the position and velocity manifolds removes the drift,
// and the motion still agrees with the run without projection to its integration accuracy.
TEST(Models, ProjectionRemovesConstraintDrift) {
  for (const char* scene : {"pendulum_fig2", "rosenberg"}) {
    const RunResult drift = run_scene(load_scene(kScenes + "/" + scene + ".yaml"));
    const RunResult projected =
        run_scene(load_scene(kScenes + "/" + scene + ".yaml", {"plant.projection=true"}));
    ASSERT_TRUE(projected.summary.failure.empty()) << projected.summary.failure;
    EXPECT_EQ(drift.summary.projections, 0u);
    EXPECT_GE(projected.summary.projections, projected.summary.steps);
    EXPECT_LT(projected.summary.max_constraint_residual, 1e-9) << scene;
    EXPECT_LT(projected.summary.max_constraint_residual,
              1e-3 * drift.summary.max_constraint_residual)
        << scene;
    EXPECT_LT(max_difference(drift, projected), 1e-4) << scene;
  }
}

// Without interpolation (rk4, rkf78) each accepted step is projected once, before its samples are
// taken: exactly one projection per step, and every sample is a projected state.
TEST(Models, StepsWithoutInterpolationAreProjectedOnceEach) {
  for (const char* method : {"integrator={method: rk4, step: 1.0e-3}",
                             "integrator={method: rkf78, tolerance: 1.0e-8}"}) {
    const RunResult r = run_scene(load_scene(kScenes + "/pendulum_fig2.yaml",
                                             {method, "plant.projection=true", "duration=2"}));
    ASSERT_TRUE(r.summary.failure.empty()) << r.summary.failure;
    EXPECT_EQ(r.summary.projections, r.summary.steps) << method;
    EXPECT_LT(r.summary.max_constraint_residual, 1e-9) << method;
  }
}

// A user's own model: one mass tracking x = sin(t) from the constraint written as phi(q, t).
struct SineTracker {
  using Scalar = double;
  static constexpr int kDof = 1, kConstraints = 1, kHolonomicRows = 1;
  double mass = 2.0;
  void evaluate(const Eigen::Matrix<double, 1, 1>&, const Eigen::Matrix<double, 1, 1>&, double,
                ModelTerms<1, 1, double>& terms) const noexcept {
    terms.mass_matrix(0, 0) = mass;
  }
  template <typename T>
  Eigen::Matrix<T, 1, 1> phi(const Eigen::Matrix<T, 1, 1>& q, const T& t) const {
    using std::sin;
    return Eigen::Matrix<T, 1, 1>(q(0) - sin(t));
  }
  template <typename F>
  void parameters(F&& f) {
    f("mass", mass);
  }
};

const char* kUserScene = R"(
name: user
plant:
  coordinates: [x]
  model: sine_tracker
  parameters: {mass: 3.0}
  initial: {q1: 0.0, qd1: 1.0}
tracking:
  model: sine_tracker
  parameters: {mass: 3.0}
integrator: {method: dopri5, tolerance: 1.0e-11}
duration: 3.0
output_period: 0.01
)";

TEST(Models, AUsersOwnModelRunsThroughRunOptionsAlone) {
  RunOptions o;
  o.models.push_back(model_factory<SineTracker>("sine_tracker"));
  const RunResult r = run_scene(parse_scene(kUserScene, "user"), o);
  ASSERT_TRUE(r.summary.failure.empty()) << r.summary.failure;
  EXPECT_LT(r.summary.max_tracking_error, 1e-8);
  // Closed form: x = sin t needs u = m x'' = -3 sin t.
  for (const Sample& s : r.samples) ASSERT_NEAR(s.u[0], -3.0 * std::sin(s.t), 1e-6);
  try {
    run_scene(parse_scene(kUserScene, "user"));
    FAIL() << "an unknown model ran";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("unknown model 'sine_tracker'"), std::string::npos)
        << e.what();
  }
  try {
    run_scene(parse_scene(kUserScene, "user", {"tracking.parameters.masss=1"}), o);
    FAIL() << "an unknown parameter was accepted";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("has no parameter 'masss' (known: mass)"),
              std::string::npos)
        << e.what();
  }
}

TEST(Models, ScenesNamingModelsAreCheckedWithFileLineAndKey) {
  const std::string arm = kScenes + "/planar_arm.yaml";
  auto error_of = [](const std::string& path, const std::vector<std::string>& sets) -> std::string {
    try {
      load_scene(path, sets);
    } catch (const SceneError& e) {
      return e.what();
    }
    return "accepted";
  };
  EXPECT_NE(error_of(arm, {"plant.parameters={mass_7: 1}"}).find("has no parameter 'mass_7'"),
            std::string::npos);
  EXPECT_NE(
      error_of(arm, {"plant.coordinates=[a, b]"}).find("model 'planar_arm' has 3 coordinates"),
      std::string::npos);
  EXPECT_NE(error_of(arm, {"plant.effects=[{type: gravity, coordinate: q1, acceleration: 9.8}]"})
                .find("a plant model's gravity is its own"),
            std::string::npos);
  EXPECT_NE(error_of(arm, {"plant.masses=[1, 1, 1]"}).find("either point masses or a model"),
            std::string::npos);
  EXPECT_NE(
      error_of(arm, {"tracking.model=coupled_duffing"}).find("has 2 coordinates, the plant has 3"),
      std::string::npos);
  // The controller's own configuration: the tracking section alone, whatever else the file holds.
  const TrackingSpec spec = load_tracking(arm, {"tracking.strategy=svd"});
  EXPECT_EQ(spec.model, "planar_arm");
  EXPECT_EQ(spec.strategy, InverseStrategy::kSvd);
  EXPECT_EQ(spec.stabilization_omega, 20.0);
  const TrackingSpec alone =
      parse_tracking("tracking: {model: pendulum, parameters: {mu: -0.1}}", "own.yaml");
  EXPECT_EQ(alone.parameter("mu", 0), -0.1);
}

}  // namespace
}  // namespace gausstrack::plant_sim
