#include "cross_check_suite.hpp"

namespace gausstrack::test {
using Size3x1Types = ::testing::Types<Size<3, 1>>;
INSTANTIATE_TYPED_TEST_SUITE_P(Size3x1, CrossCheck, Size3x1Types);
}  // namespace gausstrack::test
