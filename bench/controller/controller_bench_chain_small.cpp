// Duffing chains of N masses with P = N / 2 tracking constraints (N = 2 4).
#include "controller_bench.hpp"
#include "gausstrack/systems/duffing_chain.hpp"

namespace gausstrack::bench {
namespace {

const bool registered = [] {
  register_model<systems::DuffingChain<2, 1, double>>("chain");
  register_solve_phases<systems::DuffingChain<2, 1, double>>("chain");
  register_model<systems::DuffingChain<4, 2, double>>("chain");
  register_solve_phases<systems::DuffingChain<4, 2, double>>("chain");
  return true;
}();

}  // namespace
}  // namespace gausstrack::bench
