#include "fuzz_input.hpp"

#include <cstdio>
#include <cstdlib>

namespace gausstrack::fuzz {

void property_failed(const char* what) noexcept {
  std::fprintf(stderr, "property failed: %s\n", what);
  std::abort();
}

}  // namespace gausstrack::fuzz
