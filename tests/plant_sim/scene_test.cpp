// Scene loading: good scenes load with their values; bad scenes fail before anything runs with
// an error naming the file, the line and the key; --set overrides by dotted path.
#include <gtest/gtest.h>

#include <string>

#include "gausstrack/plant_sim/scene.hpp"
#include "gausstrack/plant_sim/models.hpp"
#include "gausstrack/systems/coupled_duffing.hpp"

namespace gausstrack::plant_sim {
namespace {

const std::string kScenes = GAUSSTRACK_SCENE_DIR;
const std::string kBad = GAUSSTRACK_BAD_SCENE_DIR;

struct BadScene {
  const char* file;
  const char* where;    // "file:line: key" prefix expected in the message
  const char* message;  // what is wrong
};

// Lines and keys read off the files by hand.
const BadScene kBadScenes[] = {
    {"unknown_top_key.yaml", ":9: durration", "unknown key"},
    {"negative_mass.yaml", ":4: plant.masses[1]", "must be > 0"},
    {"masses_size_mismatch.yaml", ":4: plant.masses", "one mass per coordinate"},
    {"unknown_effect.yaml", ":7: plant.effects[0].type", "unknown effect 'magnet'"},
    {"wrong_type.yaml", ":7: plant.effects[0].stiffness", "finite number"},
    {"missing_output_period.yaml", ":1", "missing required key 'output_period'"},
    {"unknown_coordinate.yaml", ":7: plant.effects[0].between[0]", "unknown coordinate 'x3'"},
    {"unknown_integrator.yaml", ":8: integrator.method", "unknown integrator 'euler'"},
    {"zero_tolerance.yaml", ":8: integrator.tolerance", "must be > 0"},
    {"unknown_initial_key.yaml", ":5: plant.initial.q3", "unknown key"},
    {"unknown_model_parameter.yaml", ":13: tracking.trajectory.omgea", "model 'coupled_duffing' has no parameter 'omgea'"},
    {"malformed_yaml.yaml", ":8", "not valid YAML"},
    {"sampled_without_rate.yaml", ":11: control", "missing required key 'rate'"},
    {"noise_without_sampling.yaml", ":7: plant.effects[0]", "sensor_noise needs control.mode: sampled"},
    // Found by fuzz_scene: a list written where a key goes escaped as a yaml-cpp conversion error.
    {"list_as_key.yaml", ":7: plant.effects[0]", "a key must be a plain name"},
};

TEST(Scene, BadScenesFailWithFileLineAndKey) {
  for (const BadScene& b : kBadScenes) {
    const std::string path = kBad + "/" + b.file;
    try {
      load_scene(path);
      ADD_FAILURE() << b.file << " was accepted";
    } catch (const SceneError& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.find(path + b.where), 0u) << b.file << ": " << what;
      EXPECT_NE(what.find(b.message), std::string::npos) << b.file << ": " << what;
    }
  }
}

TEST(Scene, MissingFileIsAnError) {
  EXPECT_THROW(load_scene(kBad + "/no_such_scene.yaml"), SceneError);
}

TEST(Scene, ShippedDuffingSceneHasThePaperValues) {
  const Scene s = load_scene(kScenes + "/duffing_alpha4.yaml");
  EXPECT_EQ(s.dof(), 2);
  EXPECT_EQ(s.masses, (std::vector<double>{2.0, 1.0}));
  EXPECT_EQ(s.effects.size(), 6u);
  EXPECT_TRUE(s.tracking.enabled);
  EXPECT_EQ(s.tracking.parameter("alpha", 0.0), 4.0);
  // x1'(0) = d + A omega makes the initial state consistent with the trajectory.
  EXPECT_NEAR(s.qd0[0], 2.0 + 2.0 * 3.141592653589793, 1e-15);
}

TEST(Scene, SetOverridesByDottedPath) {
  const Scene s = load_scene(kScenes + "/pendulum_fig2.yaml",
                             {"plant.initial.qd1=0.5", "integrator.tolerance=1e-8", "plant.effects.0.acceleration=9.81"});
  EXPECT_EQ(s.qd0[0], 0.5);
  EXPECT_EQ(s.tolerance, 1e-8);
  EXPECT_EQ(s.effects[0].value, 9.81);
}

TEST(Scene, BadSetNamesTheOverride) {
  const std::string path = kScenes + "/pendulum_fig2.yaml";
  try {
    load_scene(path, {"plant.masses.1=-3"});
    FAIL();
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("--set plant.masses[1]: mass must be > 0"), std::string::npos) << e.what();
  }
  EXPECT_THROW(load_scene(path, {"noequals"}), SceneError);
  EXPECT_THROW(load_scene(path, {"integrator.tolerance=[1, 2"}), SceneError);
  EXPECT_THROW(load_scene(path, {"plant.masses.7=1"}), SceneError);
  try {
    load_scene(path, {"integrator.tolerence=1e-8"});
    FAIL();
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("unknown key"), std::string::npos) << e.what();
  }
}

// tracking.force_limit and tracking.min_singular_value reach the controller the scene builds (the
// one the offline simulation and the controller process both use): no force beyond the limit,
// saturation reported in the warnings the command carries.
TEST(Scene, ActuatorLimitReachesTheController) {
  const Scene s = load_scene(kScenes + "/duffing_alpha4.yaml",
                             {"tracking.force_limit=3", "tracking.min_singular_value=1e-3"});
  EXPECT_EQ(s.tracking.force_limit, 3.0);
  EXPECT_EQ(s.tracking.min_singular_value, 1e-3);
  auto c = make_controller<systems::CoupledDuffing<double>>(s.tracking);
  decltype(c)::Output out;
  int saturated = 0;
  for (int i = 0; i < 100; ++i) {
    const double x = -2.0 + 0.04 * i;
    ASSERT_EQ(c.compute(Eigen::Vector2d(x, -x), Eigen::Vector2d(1.0, x), 0.01 * i, out), Status::kOk);
    EXPECT_LE(out.force.cwiseAbs().maxCoeff(), 3.0 * (1 + 1e-12));
    if (out.diagnostics.has(warning::kSaturated)) ++saturated;
  }
  EXPECT_GT(saturated, 10);
  EXPECT_EQ(load_scene(kScenes + "/duffing_alpha4.yaml").tracking.force_limit, std::numeric_limits<double>::infinity());
  try {
    load_scene(kScenes + "/duffing_alpha4.yaml", {"tracking.force_limit=0"});
    FAIL();
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("tracking.force_limit: must be > 0"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace gausstrack::plant_sim
