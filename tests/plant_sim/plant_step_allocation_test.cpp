// The plant's right-hand side allocates nothing: a run of twice the steps makes exactly as many
// heap allocations as the shorter one (setup, the steppers' state and the two output samples are
// the same in both). Counted for point masses with effects, a model's own dynamics and a tracking
// controller evaluated inside the step. (A physical constraint's KKT system is solved by Eigen's
// rank-revealing CompleteOrthogonalDecomposition, whose solve allocates: not covered here.)
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <string>
#include <vector>

#include "allocation_counter.hpp"
#include "gausstrack/plant_sim/scene.hpp"
#include "gausstrack/plant_sim/simulation.hpp"

namespace gausstrack::plant_sim {
namespace {

const std::string kScenes = GAUSSTRACK_SCENE_DIR;

struct Counted {
  long allocations = 0;
  std::uint64_t rhs = 0;
};

// A run of `duration` seconds with fixed RK4 steps of 1 ms, samples at its start and end only.
Counted run(const std::string& scene, const std::string& duration, std::vector<std::string> more = {}) {
  std::vector<std::string> sets = {"duration=" + duration, "output_period=" + duration, "integrator.method=rk4",
                                   "integrator.step=1.0e-3"};
  sets.insert(sets.end(), more.begin(), more.end());
  const Scene s = load_scene(kScenes + "/" + scene + ".yaml", sets);
  Counted c;
  RunResult r;
  c.allocations = support::allocations_during([&] { r = run_scene(s); });
  c.rhs = r.summary.rhs_evaluations;
  EXPECT_TRUE(r.summary.failure.empty()) << scene << ": " << r.summary.failure;
  EXPECT_EQ(r.samples.size(), 2u) << scene;
  return c;
}

// False where the counter cannot see Eigen's allocations (sanitizer builds do not replace malloc).
bool counter_sees_eigen() {
  return support::allocations_during([] {
           const Eigen::VectorXd v = Eigen::VectorXd::Constant(64, 1.0);
           volatile double sum = v.sum();
           (void)sum;
         }) >= 1;
}

void expect_no_allocation_per_step(const std::string& scene, std::vector<std::string> more = {}) {
  if (!counter_sees_eigen()) GTEST_SKIP() << "this build's allocation counter does not see malloc";
  const Counted shorter = run(scene, "0.25", more), longer = run(scene, "0.5", more);
  ASSERT_EQ(longer.rhs, 2 * shorter.rhs) << scene;  // the steps did double
  EXPECT_EQ(longer.allocations, shorter.allocations)
      << scene << ": " << (longer.allocations - shorter.allocations) << " allocations in "
      << (longer.rhs - shorter.rhs) << " more right-hand-side evaluations";
}

TEST(PlantStepAllocation, PointMassesWithEffectsAndATrackingController) {
  expect_no_allocation_per_step("duffing_alpha4");
}

TEST(PlantStepAllocation, PointMassesWithSaturation) {
  expect_no_allocation_per_step(
      "duffing_alpha4",
      {"plant.effects=[{type: spring, between: [x1, x2], stiffness: 10.0}, {type: damper, between: [x2, ground], "
       "coefficient: 0.1}, {type: disturbance, coordinate: x1, amplitude: 0.5, frequency: 3.0}, "
       "{type: actuator_saturation, limit: 1.0e3}]"});
}

TEST(PlantStepAllocation, AModelsOwnDynamics) { expect_no_allocation_per_step("planar_arm"); }

TEST(PlantStepAllocation, ALongerChainWithItsController) { expect_no_allocation_per_step("duffing_chain8"); }

}  // namespace
}  // namespace gausstrack::plant_sim
