// The Duffing chain of 16 masses with P = 8 tracking constraints.
#include "controller_bench.hpp"
#include "gausstrack/systems/duffing_chain.hpp"

namespace gausstrack::bench {
namespace {

const bool registered = [] {
  register_model<systems::DuffingChain<16, 8, double>>("chain");
  register_solve_phases<systems::DuffingChain<16, 8, double>>("chain");
  return true;
}();

}  // namespace
}  // namespace gausstrack::bench
