// The actuated law (ActuatedController, actuation.hpp) against independent formulations (B = I
// against eq. (32) for every shipped model is in actuation_eq32_*_test.cpp); a Lagrange-multiplier
// (KKT) solve of least u^T W u subject to the task rows, for Gauss's weight and for a given one;
// the least-squares answer through a Moore-Penrose inverse when the rows cannot all be actuated.
// Closed forms and refusals: actuation_closed_forms_test.cpp; the hold, limits, reach, the
// cart-pole and allocation: actuation_cart_pole_test.cpp. Split so that no unit compiles them all.
#undef NDEBUG
#define EIGEN_RUNTIME_NO_MALLOC

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <cmath>
#include <limits>

#include "actuation_systems.hpp"
#include "gausstrack/systems/cart_pole.hpp"
#include "oracles.hpp"

namespace gausstrack::test {
namespace {

TEST(Actuation, LeastCostAmongCommandsMeetingTheRowsAsLagrangeMultipliersGiveIt) {
  RandomSource<double> rng(11);
  for (bool gauss : {true, false}) {
    expect_least_cost<4, 2, 3>(rng, gauss);
    expect_least_cost<6, 2, 2>(rng, gauss);
  }
}

}  // namespace
}  // namespace gausstrack::test
