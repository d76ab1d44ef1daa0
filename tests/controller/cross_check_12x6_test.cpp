#include "cross_check_suite.hpp"

namespace gausstrack::test {
using Size12x6Types = ::testing::Types<Size<12, 6>>;
INSTANTIATE_TYPED_TEST_SUITE_P(Size12x6, CrossCheck, Size12x6Types);
}  // namespace gausstrack::test
