// The dense kernels in single precision (small_dense_cases.hpp): every size, one to three right
// sides.
#include "small_dense_cases.hpp"

namespace gausstrack::test {
namespace {

TEST(SmallDense, KernelsMatchEigenFloat) {
  every_size<float, 1>(400);
  every_size<float, 2>(500);
  every_size<float, 3>(600);
}

}  // namespace
}  // namespace gausstrack::test
