// The actuated law against a KKT solve at two more sizes (actuation_test.cpp has the others).
#include <gtest/gtest.h>

#include "actuation_systems.hpp"

namespace gausstrack::test {
namespace {

TEST(Actuation, LeastCostAtMoreSizes) {
  RandomSource<double> rng(29);
  for (bool gauss : {true, false}) {
    expect_least_cost<5, 1, 5>(rng, gauss);
    expect_least_cost<8, 3, 6>(rng, gauss);
  }
}

}  // namespace
}  // namespace gausstrack::test
