// MuJoCo as the plant (plant.engine: mujoco): the controller's models against MuJoCo's own
// dynamics at random states (A against mj_fullM, f - Q against qfrc_bias - qfrc_passive), only
// the listed effects acting (the unlisted ones change nothing, bit for bit, and each one listed
// does change the motion), a free swing against plant_sim's own integration of the model, the
// closed loop on the arm and the cart pendulum, a heavier plant link with and without
// stabilization, and a diverging plant that ends the run with its reason.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <mujoco/mujoco.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "gausstrack/model.hpp"
#include "gausstrack/plant_sim/mujoco.hpp"
#include "gausstrack/plant_sim/scene.hpp"
#include "gausstrack/plant_sim/simulation.hpp"
#include "gausstrack/systems/cart_double_pendulum.hpp"
#include "gausstrack/systems/planar_arm.hpp"

namespace gausstrack::plant_sim {
namespace {

const std::string kScenes = GAUSSTRACK_SCENE_DIR;
const std::string kModels = GAUSSTRACK_MODEL_DIR;
const std::string kTestModels = GAUSSTRACK_TEST_MODEL_DIR;

RunOptions with_mujoco() {
  RunOptions o;
  o.engines.push_back(mujoco_engine());
  return o;
}

RunResult run(const std::string& scene, const std::vector<std::string>& sets = {}) {
  return run_scene(load_scene(kScenes + "/" + scene, sets), with_mujoco());
}

EngineSpec spec(const std::string& path, std::vector<std::string> effects) {
  EngineSpec e;
  e.name = "mujoco";
  e.model_path = path;
  e.timestep = 1e-4;
  e.effects = std::move(effects);
  return e;
}

// The controller's model M against MuJoCo's at random states: A against mj_fullM and f - Q
// against qfrc_bias - qfrc_passive, each to 1e-10 relative to its own size.
template <typename M>
void expect_same_dynamics(const M& model, MujocoModel& mj, double velocity_scale) {
  using V = Eigen::Vector3d;
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> angle(-3.0, 3.0), rate(-velocity_scale, velocity_scale);
  for (int trial = 0; trial < 200; ++trial) {
    V q, qd;
    for (int i = 0; i < 3; ++i) q(i) = angle(rng), qd(i) = rate(rng);
    typename M::Terms terms;
    terms.mass_matrix.setZero();
    model.evaluate(q, qd, 0.0, terms);
    mj.set_state(q.data(), qd.data());
    Eigen::Matrix3d A;
    V r;
    mj.mass_matrix(A.data());
    mj.bias_minus_passive(r.data());
    const V f_minus_q = terms.nonlinear_force - terms.applied_force;
    ASSERT_LE((A - terms.mass_matrix).norm(), 1e-10 * terms.mass_matrix.norm())
        << "trial " << trial << "\nmujoco\n" << A << "\nmodel\n" << terms.mass_matrix;
    ASSERT_LE((r - f_minus_q).norm(), 1e-10 * std::max(f_minus_q.norm(), 1e-3))
        << "trial " << trial << ": mujoco " << r.transpose() << ", model " << f_minus_q.transpose();
  }
}

TEST(MujocoCrossCheck, ArmMassMatrixAndForcesEqualMujocos) {
  systems::PlanarArm<double> arm;
  arm.gravity = 0;
  MujocoModel bare(spec(kModels + "/arm3.xml", {}), {"shoulder", "elbow", "wrist"});
  expect_same_dynamics(arm, bare, 3.0);

  arm.gravity = 9.81;
  MujocoModel gravity(spec(kModels + "/arm3.xml", {"gravity"}), {"shoulder", "elbow", "wrist"});
  expect_same_dynamics(arm, gravity, 3.0);

  // Joint damping listed (the model file's 0.5 N m s/rad); its springs, armature and the rest not.
  arm.damping = 0.5;
  MujocoModel damped(spec(kTestModels + "/arm3_extras.xml", {"gravity", "damping"}), {"shoulder", "elbow", "wrist"});
  expect_same_dynamics(arm, damped, 3.0);
}

TEST(MujocoCrossCheck, CartDoublePendulumEqualsMujocos) {
  systems::CartDoublePendulum<double> cart;
  MujocoModel mj(spec(kModels + "/cart_double_pendulum.xml", {"gravity"}), {"cart", "hinge1", "hinge2"});
  expect_same_dynamics(cart, mj, 3.0);
  cart.gravity = 0;
  MujocoModel bare(spec(kModels + "/cart_double_pendulum.xml", {}), {"cart", "hinge1", "hinge2"});
  expect_same_dynamics(cart, bare, 3.0);
}

TEST(MujocoCrossCheck, CoordinatesFollowTheScenesJointOrder) {
  // The same model with its joints named in another order: A and f - Q permute with them.
  MujocoModel in_order(spec(kModels + "/arm3.xml", {"gravity"}), {"shoulder", "elbow", "wrist"});
  MujocoModel permuted(spec(kModels + "/arm3.xml", {"gravity"}), {"wrist", "shoulder", "elbow"});
  const double q[3] = {0.3, -0.7, 1.1}, qd[3] = {0.5, 1.5, -2.0};
  const double qp[3] = {q[2], q[0], q[1]}, qdp[3] = {qd[2], qd[0], qd[1]};
  in_order.set_state(q, qd);
  permuted.set_state(qp, qdp);
  double A[9], Ap[9], r[3], rp[3];
  in_order.mass_matrix(A);
  permuted.mass_matrix(Ap);
  in_order.bias_minus_passive(r);
  permuted.bias_minus_passive(rp);
  const int perm[3] = {2, 0, 1};  // coordinate i of `permuted` is joint perm[i]
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(rp[i], r[perm[i]]);
    for (int j = 0; j < 3; ++j) EXPECT_EQ(Ap[j * 3 + i], A[perm[j] * 3 + perm[i]]);
  }
}

TEST(MujocoCrossCheck, MotorsActuatorMomentsAreTheModelsB) {
  // arm3_motors.xml's two <motor>s against systems::PlanarArmPassiveWrist's B at random states:
  // MuJoCo's actuator_moment times the gain is the generalized force per unit control.
  EngineSpec motors = spec(kModels + "/arm3_motors.xml", {"gravity"});
  motors.actuators = {"shoulder_motor", "elbow_motor"};
  MujocoModel mj(motors, {"shoulder", "elbow", "wrist"});
  ASSERT_EQ(mj.actuators(), 2);
  systems::PlanarArmPassiveWrist<double> arm;
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> angle(-3.0, 3.0), rate(-3.0, 3.0);
  for (int trial = 0; trial < 50; ++trial) {
    Eigen::Vector3d q, qd;
    for (int i = 0; i < 3; ++i) q(i) = angle(rng), qd(i) = rate(rng);
    mj.set_state(q.data(), qd.data());
    Eigen::Matrix<double, 3, 2> b_mujoco, b_model;
    mj.actuation_matrix(b_mujoco.data());
    arm.actuation(q, 0.0, b_model);
    ASSERT_LE((b_mujoco - b_model).norm(), 1e-15) << "trial " << trial << "\nmujoco\n" << b_mujoco;
  }
  // And they act: a step under control u equals a step under the force B u applied to the joints
  // (the arm without motors), and the command's force entries are not applied on top of it.
  MujocoModel joints(spec(kModels + "/arm3.xml", {"gravity"}), {"shoulder", "elbow", "wrist"});
  const double q[3] = {0.3, -0.7, 1.1}, qd[3] = {0.5, 1.5, -2.0};
  mj.set_state(q, qd);
  joints.set_state(q, qd);
  const double command[5] = {100.0, -100.0, 100.0, 2.5, -1.25};  // a force ignored, then u
  const double force[3] = {2.5, -1.25, 0.0};
  double after[6], expected[6];
  for (int k = 0; k < 10; ++k) {
    ASSERT_EQ(mj.step(command), "");
    ASSERT_EQ(joints.step(force), "");
  }
  mj.state(after, after + 3);
  joints.state(expected, expected + 3);
  for (int i = 0; i < 6; ++i) EXPECT_NEAR(after[i], expected[i], 1e-14) << i;
  mj.set_state(q, qd);
  const double idle[5] = {0, 0, 0, 0, 0};
  for (int k = 0; k < 10; ++k) ASSERT_EQ(mj.step(idle), "");
  double still[6];
  mj.state(still, still + 3);
  EXPECT_GT(std::abs(still[3] - after[3]), 1e-6);  // the control did move the arm
}

TEST(MujocoEffects, UnlistedEffectsChangeNothingBitForBit) {
  const std::vector<std::string> shorter = {"duration=1.0"};
  const RunResult plain = run("planar_arm_mujoco.yaml", shorter);
  ASSERT_TRUE(plain.summary.failure.empty()) << plain.summary.failure;
  std::vector<std::string> extras = shorter;
  extras.push_back("plant.model=" + kTestModels + "/arm3_extras.xml");
  const RunResult unlisted = run("planar_arm_mujoco.yaml", extras);
  ASSERT_TRUE(unlisted.summary.failure.empty()) << unlisted.summary.failure;
  ASSERT_EQ(plain.samples.size(), unlisted.samples.size());
  for (std::size_t k = 0; k < plain.samples.size(); ++k) {
    ASSERT_EQ(plain.samples[k].q, unlisted.samples[k].q) << "t = " << plain.samples[k].t;
    ASSERT_EQ(plain.samples[k].qd, unlisted.samples[k].qd) << "t = " << plain.samples[k].t;
  }
  EXPECT_EQ(unlisted.summary.engine_effects, std::vector<std::string>{"gravity"});
  EXPECT_NE(unlisted.summary.engine.find("mujoco 2.2.2, rk4, timestep 0.0001 s"), std::string::npos)
      << unlisted.summary.engine;

  // And each of them, listed, does act: the comparison above can fail.
  for (const char* effect : {"damping", "springs", "armature", "frictionloss", "limits", "contact", "equality"}) {
    std::vector<std::string> listed = extras;
    listed.push_back(std::string("plant.effects=[gravity, ") + effect + "]");
    const RunResult on = run("planar_arm_mujoco.yaml", listed);
    double difference = 0;
    for (std::size_t k = 0; k < std::min(on.samples.size(), plain.samples.size()); ++k)
      for (std::size_t i = 0; i < 3; ++i)
        difference = std::max(difference, std::abs(on.samples[k].q[i] - plain.samples[k].q[i]));
    EXPECT_GT(difference, 1e-6) << effect << " listed changed nothing";
  }
  // Gravity too: unlisted, the arm's model without gravity is what MuJoCo steps.
  std::vector<std::string> weightless = shorter;
  weightless.push_back("plant.effects=[]");
  const RunResult no_gravity = run("planar_arm_mujoco.yaml", weightless);
  EXPECT_GT(std::abs(no_gravity.samples.back().q[0] - plain.samples.back().q[0]), 1e-6);
}

TEST(MujocoClosedLoop, FreeSwingEqualsPlantSimsOwnIntegrationOfTheModel) {
  // No controller: the arm falls under gravity for 1 s. MuJoCo's RK4 at 0.1 ms against the
  // planar_arm model integrated by plant_sim with dopri5 at 1e-12.
  const RunResult mujoco = run("planar_arm_mujoco.yaml", {"tracking=null", "duration=1.0"});
  const RunResult own = run_scene(load_scene(kScenes + "/planar_arm.yaml",
                                             {"tracking=null", "duration=1.0", "integrator.tolerance=1e-12"}));
  ASSERT_TRUE(mujoco.summary.failure.empty()) << mujoco.summary.failure;
  ASSERT_EQ(mujoco.samples.size(), own.samples.size());
  double worst = 0, motion = 0;
  for (std::size_t k = 0; k < own.samples.size(); ++k)
    for (std::size_t i = 0; i < 3; ++i) {
      worst = std::max(worst, std::abs(mujoco.samples[k].q[i] - own.samples[k].q[i]));
      motion = std::max(motion, std::abs(own.samples[k].q[i] - own.samples[0].q[i]));
    }
  EXPECT_GT(motion, 0.5);  // it does swing
  EXPECT_LT(worst, 1e-9);
}

TEST(MujocoClosedLoop, ArmTracksTheCircleAsItsOwnModelDoes) {
  const RunResult r = run("planar_arm_mujoco.yaml");
  ASSERT_TRUE(r.summary.failure.empty()) << r.summary.failure;
  EXPECT_NEAR(r.samples.back().t, 10.0, 1e-12);
  EXPECT_EQ(r.summary.control_failures, 0u);
  EXPECT_EQ(r.summary.steps, 100000u);  // 10 s of 0.1 ms steps
  // The same loop (sampled at 1 kHz, held) closed on plant_sim's own integration of the arm: the
  // two plants agree along the whole run, so the tracking error is the sampling's, not MuJoCo's.
  const RunResult own = run_scene(load_scene(
      kScenes + "/planar_arm.yaml", {"control={mode: sampled, rate: 1000}", "integrator.tolerance=1e-12"}));
  ASSERT_EQ(r.samples.size(), own.samples.size());
  double worst = 0;
  for (std::size_t k = 0; k < own.samples.size(); ++k)
    for (std::size_t i = 0; i < 3; ++i) worst = std::max(worst, std::abs(r.samples[k].q[i] - own.samples[k].q[i]));
  EXPECT_LT(worst, 1e-7);  // RK4 at 0.1 ms over 10 s (1.4e-8 here)
  EXPECT_LT(r.summary.max_tracking_error, 5e-4);  // 0.3 mm: the 1 kHz hold on a circle of 0.3 m
  EXPECT_NEAR(r.summary.max_tracking_error, own.summary.max_tracking_error, 1e-3 * own.summary.max_tracking_error);
}

TEST(MujocoClosedLoop, PassiveWristTracksThroughMujocosOwnMotors) {
  // The controller's u drives MuJoCo's two motors; the wrist has none. The same loop closed on
  // plant_sim's integration of the arm under the force B u gives the same motion.
  const RunResult r = run("planar_arm_passive_wrist_mujoco.yaml");
  ASSERT_TRUE(r.summary.failure.empty()) << r.summary.failure;
  EXPECT_EQ(r.summary.control_failures, 0u);
  EXPECT_EQ(r.summary.steps, 100000u);
  const RunResult own = run_scene(load_scene(kScenes + "/planar_arm_passive_wrist.yaml",
                                             {"control={mode: sampled, rate: 1000}", "integrator.tolerance=1e-12"}));
  ASSERT_TRUE(own.summary.failure.empty()) << own.summary.failure;
  ASSERT_EQ(r.samples.size(), own.samples.size());
  double worst = 0, wrist_force = 0, wrist_swing = 0;
  for (std::size_t k = 0; k < own.samples.size(); ++k) {
    for (std::size_t i = 0; i < 3; ++i) worst = std::max(worst, std::abs(r.samples[k].q[i] - own.samples[k].q[i]));
    wrist_force = std::max(wrist_force, std::abs(r.samples[k].u[2]));
    wrist_swing = std::max(wrist_swing, std::abs(r.samples[k].q[2] - r.samples[0].q[2]));
  }
  EXPECT_LT(worst, 1e-6);
  EXPECT_EQ(wrist_force, 0.0);   // B u has no wrist torque
  EXPECT_GT(wrist_swing, 0.1);   // and the wrist does move, unactuated
  EXPECT_LT(r.summary.max_tracking_error, 1e-3);
  EXPECT_NEAR(r.summary.max_tracking_error, own.summary.max_tracking_error, 1e-2 * own.summary.max_tracking_error);
}

TEST(MujocoClosedLoop, CartDoublePendulumTracks) {
  const RunResult r = run("cart_double_pendulum_mujoco.yaml");
  ASSERT_TRUE(r.summary.failure.empty()) << r.summary.failure;
  EXPECT_EQ(r.summary.control_failures, 0u);
  EXPECT_LT(r.summary.max_tracking_error, 1e-4);
  double swing = 0;
  for (const Sample& s : r.samples) swing = std::max(swing, std::abs(s.q[1]));
  EXPECT_GT(swing, 0.05);  // the rods do swing
}

TEST(MujocoClosedLoop, HeavierLinkIsHeldByStabilizationOnly) {
  const std::string heavy = "plant.model=" + kModels + "/arm3_heavy.xml";
  const RunResult stabilized = run("planar_arm_mujoco.yaml", {heavy});
  const RunResult open = run("planar_arm_mujoco.yaml", {heavy, "tracking.stabilization={zeta: 1.0, omega: 0.0}"});
  ASSERT_TRUE(stabilized.summary.failure.empty()) << stabilized.summary.failure;
  EXPECT_LT(stabilized.summary.max_tracking_error, 1e-2);
  EXPECT_GT(open.summary.max_tracking_error, 10 * stabilized.summary.max_tracking_error);
}

TEST(MujocoFailures, DivergingPlantEndsTheRunWithItsReason) {
  // A controller whose model believes in a gravity of 1e12 m/s^2 commands torques MuJoCo cannot
  // integrate: MuJoCo would reset the state to qpos0 and go on; the run must end instead.
  const RunResult r = run("planar_arm_mujoco.yaml", {"tracking.parameters={gravity: 1.0e12}"});
  ASSERT_FALSE(r.summary.failure.empty());
  EXPECT_NE(r.summary.failure.find("qacc"), std::string::npos) << r.summary.failure;
  EXPECT_LT(r.summary.failed_at, 0.01);
  for (const Sample& s : r.samples)
    for (double v : s.q) ASSERT_TRUE(std::isfinite(v));
}

// MuJoCo's control callback calls mju_error from inside mj_step after 5 ms: unhandled, MuJoCo
// would print and end the process.
void error_after_5ms(const mjModel*, mjData* d) {
  if (d->time > 5e-3) mju_error("injected error");
}

TEST(MujocoFailures, MujocoErrorsEndTheRunNotTheProcess) {
  mjcb_control = error_after_5ms;
  const RunResult r = run("planar_arm_mujoco.yaml", {"duration=1.0"});
  mjcb_control = nullptr;
  ASSERT_FALSE(r.summary.failure.empty());
  EXPECT_NE(r.summary.failure.find("MuJoCo: injected error"), std::string::npos) << r.summary.failure;
  EXPECT_GE(r.summary.failed_at, 4.9e-3);  // the step that met it started at 5 ms or just before
  EXPECT_LT(r.summary.failed_at, 6e-3);
  EXPECT_EQ(r.samples.size(), 1u);  // t = 0 only: the next sample was due at 10 ms
  // The process goes on: the same scene runs to its end afterwards.
  const RunResult again = run("planar_arm_mujoco.yaml", {"duration=1.0"});
  EXPECT_TRUE(again.summary.failure.empty()) << again.summary.failure;
  EXPECT_EQ(again.samples.size(), 101u);
}

// The scene's refusal, or "no error".
std::string scene_error(const std::string& scene, const std::vector<std::string>& sets) {
  try {
    run(scene, sets);
  } catch (const SceneError& e) {
    return e.what();
  }
  return "no error";
}

TEST(MujocoScenes, BadEngineScenesAreRefusedWithTheirReason) {
  auto error_of = [](const std::vector<std::string>& sets) { return scene_error("planar_arm_mujoco.yaml", sets); };
  EXPECT_NE(error_of({"plant.coordinates=[shoulder, elbow, hand]"}).find("no joint named 'hand'"), std::string::npos);
  EXPECT_NE(error_of({"plant.coordinates=[shoulder, elbow]", "plant.initial={}", "tracking=null"}).find("3 degrees of freedom"),
            std::string::npos);
  EXPECT_NE(error_of({"plant.effects=[gravity, wind]"}).find("unknown effect 'wind'"), std::string::npos);
  EXPECT_NE(error_of({"plant.model=missing.xml"}).find("cannot open the model file"), std::string::npos);
  // A timestep the step budget cannot cover is refused when the scene loads, not after 1e8 steps.
  EXPECT_NE(error_of({"plant.timestep=1.0e-12"}).find("plant.timestep: gives"), std::string::npos);
  EXPECT_NE(error_of({"integrator={method: rk4, step: 1.0e-3}"}).find("the engine integrates"), std::string::npos);
  EXPECT_NE(error_of({"control={mode: continuous}"}).find("needs control.mode: sampled"), std::string::npos);
  EXPECT_NE(error_of({"plant.timestep=3.0e-4"}).find("whole number of engine steps"), std::string::npos);
  EXPECT_NE(error_of({"plant.integrator=implicitfast"}).find("unknown integrator"), std::string::npos);
  EXPECT_NE(error_of({"plant.masses=[1, 1, 1]"}).find("unknown key"), std::string::npos);
  EXPECT_NE(error_of({"plant.coordinates=[shoulder, elbow, elbow]"}).find("duplicate coordinate"), std::string::npos);
  // Actuators: each must exist and be a motor, all must be named, and the controller's u must
  // have one entry per actuator.
  auto wrist_error_of = [](const std::vector<std::string>& sets) {
    return scene_error("planar_arm_passive_wrist_mujoco.yaml", sets);
  };
  EXPECT_NE(wrist_error_of({"plant.actuators=[shoulder_motor, wrist_motor]"}).find("no actuator named 'wrist_motor'"),
            std::string::npos);
  EXPECT_NE(wrist_error_of({"plant.actuators=[shoulder_motor]", "tracking=null"}).find("has 2 actuators; the scene names 1"),
            std::string::npos);
  EXPECT_NE(wrist_error_of({"tracking.model=planar_arm"}).find("no actuation matrix B"), std::string::npos);
  EXPECT_NE(wrist_error_of({"plant.model=" + kTestModels + "/arm3_servo.xml"}).find("'elbow_motor' is not a motor"),
            std::string::npos);
  EXPECT_NE(wrist_error_of({"plant.model=" + kTestModels + "/arm3_force_limited.xml"}).find("is force limited"),
            std::string::npos);
  std::string thirty = "plant.actuators=[";
  for (int k = 0; k < 30; ++k) thirty += (k ? ", m" : "m") + std::to_string(k);
  EXPECT_NE(wrist_error_of({thirty + "]"}).find("has at most 32 entries"), std::string::npos);
  EXPECT_NE(wrist_error_of({"plant.actuators=[shoulder_motor, shoulder_motor]"}).find("listed twice"), std::string::npos);
  EXPECT_NE(error_of({"plant.actuators=[shoulder_motor]", "tracking=null"}).find("no actuator named"), std::string::npos);
  // The model class itself refuses a joint named twice (the other would get no force).
  try {
    MujocoModel twice(spec(kModels + "/arm3.xml", {}), {"shoulder", "shoulder", "wrist"});
    ADD_FAILURE() << "a joint named twice was accepted";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("named twice"), std::string::npos) << e.what();
  }
  // A program built without the engine says so.
  try {
    run_scene(load_scene(kScenes + "/planar_arm_mujoco.yaml"));
    ADD_FAILURE() << "ran without an engine";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("built without the 'mujoco' engine"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace gausstrack::plant_sim
