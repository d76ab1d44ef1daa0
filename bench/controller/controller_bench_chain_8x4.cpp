// The Duffing chain of 8 masses with P = 4 tracking constraints.
#include "controller_bench.hpp"
#include "gausstrack/systems/duffing_chain.hpp"

namespace gausstrack::bench {
namespace {

const bool registered = [] {
  register_model<systems::DuffingChain<8, 4, double>>("chain");
  register_solve_phases<systems::DuffingChain<8, 4, double>>("chain");
  return true;
}();

}  // namespace
}  // namespace gausstrack::bench
