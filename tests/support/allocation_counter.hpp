// Counts heap allocations (operator new and the malloc family) while counting is on. Linking
// this library replaces the program's global operator new and, outside sanitizer builds, glibc's
// malloc, calloc, realloc, aligned_alloc and posix_memalign, which Eigen uses.
#pragma once

namespace gausstrack::support {

void start_counting_allocations();
/// Stops counting and returns the allocations seen since start_counting_allocations().
long stop_counting_allocations();

/// Allocations made by `call()`.
template <typename F>
long allocations_during(F&& call) {
  start_counting_allocations();
  call();
  return stop_counting_allocations();
}

}  // namespace gausstrack::support
