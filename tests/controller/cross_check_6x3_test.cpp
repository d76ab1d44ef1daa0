#include "cross_check_suite.hpp"

namespace gausstrack::test {
using Size6x3Types = ::testing::Types<Size<6, 3>>;
INSTANTIATE_TYPED_TEST_SUITE_P(Size6x3, CrossCheck, Size6x3Types);
}  // namespace gausstrack::test
