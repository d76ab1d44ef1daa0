// The sampled-data law closed around the simulated plant (control.mode: sampled, the force held
// over each period): its order of accuracy read off the error when the period halves (two for
// the held midpoint law, one for the law at the measured state, as derived in
// docs/sampled_law.md), and the accuracy it buys on the Duffing scene, the 3-link arm and the
// 8-mass chain.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <vector>

#include "gausstrack/plant_sim/scene.hpp"
#include "gausstrack/plant_sim/simulation.hpp"

namespace gausstrack::plant_sim {
namespace {

const std::string kScenes = GAUSSTRACK_SCENE_DIR;

// The largest tracking error of `scene` sampled at `rate` with hold law `hold` (and `more`
// overrides).
double max_error(const std::string& scene, const char* hold, double rate, double duration,
                 std::vector<std::string> more = {}) {
  std::vector<std::string> sets = {"control.mode=sampled", "control.rate=" + std::to_string(rate),
                                   std::string("tracking.hold=") + hold, "duration=" + std::to_string(duration),
                                   "tracking.stabilization={zeta: 1.0, omega: 20.0}"};
  sets.insert(sets.end(), more.begin(), more.end());
  const Scene s = load_scene(kScenes + "/" + scene + ".yaml", sets);
  const RunResult r = run_scene(s);
  EXPECT_TRUE(r.summary.failure.empty()) << scene << " " << hold << " " << rate << ": " << r.summary.failure;
  EXPECT_EQ(r.summary.control_failures, 0u);
  return r.summary.max_tracking_error;
}

TEST(SampledLaw, MidpointHoldIsSecondOrderAndTheMeasuredStateLawFirst) {
  // Duffing, alpha = 4: the error peaks in the first second, while the trajectory moves fastest.
  const double mid_1k = max_error("duffing_alpha4", "midpoint", 1000, 2.0);
  const double mid_2k = max_error("duffing_alpha4", "midpoint", 2000, 2.0);
  const double sample_1k = max_error("duffing_alpha4", "sample", 1000, 2.0);
  const double sample_2k = max_error("duffing_alpha4", "sample", 2000, 2.0);
  std::printf("duffing_alpha4: midpoint %.3g at 1 kHz, %.3g at 2 kHz; sample %.3g, %.3g\n", mid_1k, mid_2k,
              sample_1k, sample_2k);
  EXPECT_NEAR(mid_1k / mid_2k, 4.0, 0.5);
  EXPECT_NEAR(sample_1k / sample_2k, 2.0, 0.25);
}

TEST(SampledLaw, AHundredTimesMoreAccurateAtOneKilohertzAndAtAHundredHertzAsAccurateAsTheOldLawAtOne) {
  struct Case {
    const char* scene;
    double duration;
  };
  for (const Case& c : {Case{"duffing_alpha4", 2.0}, Case{"planar_arm", 4.0}, Case{"duffing_chain8", 2.0}}) {
    const double sample_1k = max_error(c.scene, "sample", 1000, c.duration);
    const double mid_1k = max_error(c.scene, "midpoint", 1000, c.duration);
    const double mid_100 = max_error(c.scene, "midpoint", 100, c.duration);
    std::printf("%s: sample %.3g at 1 kHz; midpoint %.3g at 1 kHz, %.3g at 100 Hz\n", c.scene, sample_1k, mid_1k,
                mid_100);
    EXPECT_LE(mid_1k, sample_1k / 100) << c.scene;
    EXPECT_LE(mid_100, sample_1k) << c.scene;
  }
}

// A wrong model (the controller's first mass and spring 10 % off the plant's): the prediction
// runs through that model, and the held law degrades to the accuracy of the law at the measured
// state (both set by the model's error), not below it.
TEST(SampledLaw, AWrongModelDegradesToTheMeasuredStateLawsAccuracy) {
  for (const char* m1 : {"1.8", "2.2"}) {
    const std::vector<std::string> wrong = {std::string("tracking.parameters.m1=") + m1, "tracking.parameters.k1=11.0"};
    const double sample = max_error("duffing_alpha4", "sample", 1000, 2.0, wrong);
    const double mid = max_error("duffing_alpha4", "midpoint", 1000, 2.0, wrong);
    std::printf("duffing_alpha4, m1 = %s in the model: sample %.3g, midpoint %.3g\n", m1, sample, mid);
    EXPECT_GT(sample, 1e-3);  // the model's error dominates (the test could fail)
    EXPECT_LE(mid, 1.1 * sample) << m1;
  }
}

}  // namespace
}  // namespace gausstrack::plant_sim
