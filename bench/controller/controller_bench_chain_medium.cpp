// Duffing chains of N masses with P = N / 2 tracking constraints (N = 8 16).
#include "controller_bench.hpp"
#include "gausstrack/systems/duffing_chain.hpp"

namespace gausstrack::bench {
namespace {

const bool registered = [] {
  register_model<systems::DuffingChain<8, 4, double>>("chain");
  register_solve_phases<systems::DuffingChain<8, 4, double>>("chain");
  register_model<systems::DuffingChain<16, 8, double>>("chain");
  register_solve_phases<systems::DuffingChain<16, 8, double>>("chain");
  return true;
}();

}  // namespace
}  // namespace gausstrack::bench
