#include "cross_check_suite.hpp"

namespace gausstrack::test {
using Size2x1Types = ::testing::Types<Size<2, 1>>;
INSTANTIATE_TYPED_TEST_SUITE_P(Size2x1, CrossCheck, Size2x1Types);
}  // namespace gausstrack::test
