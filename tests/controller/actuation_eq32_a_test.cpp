// B = I equals eq. (32) through TrackingController (actuation_eq32.hpp): coupled_duffing, pendulum, nonholonomic_particle.
#include "actuation_eq32.hpp"
#include "gausstrack/systems/coupled_duffing.hpp"
#include "gausstrack/systems/pendulum.hpp"
#include "gausstrack/systems/nonholonomic_particle.hpp"

namespace gausstrack::test {
namespace {

TEST(Actuation, EveryCoordinateActuatedIsEq32ForEveryStrategyDuffingPendulumParticle) {
  expect_equal_to_eq32(systems::CoupledDuffing<double>{}, "coupled_duffing");
  expect_equal_to_eq32(systems::Pendulum<double>{}, "pendulum");
  expect_equal_to_eq32(systems::NonholonomicParticle<double>{}, "nonholonomic_particle");
}

}  // namespace
}  // namespace gausstrack::test
