// The Duffing chain of 32 masses with P = 16 tracking constraints.
#include "controller_bench.hpp"
#include "gausstrack/systems/duffing_chain.hpp"

namespace gausstrack::bench {
namespace {

const bool registered = [] {
  register_model<systems::DuffingChain<32, 16, double>>("chain");
  register_solve_phases<systems::DuffingChain<32, 16, double>>("chain");
  return true;
}();

}  // namespace
}  // namespace gausstrack::bench
