// B = I equals eq. (32) through TrackingController (actuation_eq32.hpp): planar_arm, duffing_chain, cart_double_pendulum.
#include "actuation_eq32.hpp"
#include "gausstrack/systems/planar_arm.hpp"
#include "gausstrack/systems/duffing_chain.hpp"
#include "gausstrack/systems/cart_double_pendulum.hpp"

namespace gausstrack::test {
namespace {

TEST(Actuation, EveryCoordinateActuatedIsEq32ForEveryStrategyArmChainCart) {
  expect_equal_to_eq32(systems::PlanarArm<double>{}, "planar_arm");
  expect_equal_to_eq32(systems::DuffingChain<8, 4>{}, "duffing_chain");
  expect_equal_to_eq32(systems::CartDoublePendulum<double>{}, "cart_double_pendulum");
}

}  // namespace
}  // namespace gausstrack::test
