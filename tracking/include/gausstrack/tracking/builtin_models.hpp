// The models compiled into the shipped programs, by the name configurations use. One list: the
// offline simulation, gausstrack-plant and gausstrack-controller all dispatch through it.
#pragma once

#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "gausstrack/systems/cart_double_pendulum.hpp"
#include "gausstrack/systems/cart_pole.hpp"
#include "gausstrack/systems/coupled_duffing.hpp"
#include "gausstrack/systems/differential_drive.hpp"
#include "gausstrack/systems/duffing_chain.hpp"
#include "gausstrack/systems/nonholonomic_particle.hpp"
#include "gausstrack/systems/pendulum.hpp"
#include "gausstrack/systems/planar_arm.hpp"

namespace gausstrack::tracking {

/// Eight masses tracked on the relative displacements of the first four pairs.
using DuffingChain8 = systems::DuffingChain<8, 4, double>;

/// Calls f(std::type_identity<M>{}) for the model named `name` and returns true, or returns false
/// for a name that is not compiled in.
template <typename F>
bool visit_builtin_model(std::string_view name, F&& f) {
  if (name == "coupled_duffing")
    return f(std::type_identity<systems::CoupledDuffing<double>>{}), true;
  if (name == "duffing_chain") return f(std::type_identity<DuffingChain8>{}), true;
  if (name == "pendulum") return f(std::type_identity<systems::Pendulum<double>>{}), true;
  if (name == "nonholonomic_particle")
    return f(std::type_identity<systems::NonholonomicParticle<double>>{}), true;
  if (name == "planar_arm") return f(std::type_identity<systems::PlanarArm<double>>{}), true;
  if (name == "planar_arm_passive_wrist")
    return f(std::type_identity<systems::PlanarArmPassiveWrist<double>>{}), true;
  if (name == "cart_double_pendulum")
    return f(std::type_identity<systems::CartDoublePendulum<double>>{}), true;
  if (name == "cart_pole") return f(std::type_identity<systems::CartPole<double>>{}), true;
  if (name == "differential_drive")
    return f(std::type_identity<systems::DifferentialDrive<double>>{}), true;
  return false;
}

/// Every name visit_builtin_model knows, in one list.
inline constexpr const char* kBuiltinModels[] = {
    "coupled_duffing",      "duffing_chain", "pendulum",          "nonholonomic_particle",
    "planar_arm",           "planar_arm_passive_wrist", "cart_double_pendulum", "cart_pole",
    "differential_drive"};

/// Their names, for messages ("coupled_duffing, duffing_chain, ...").
std::string builtin_model_names();

/// The parameter names a compiled-in model's parameters() visitor offers (false for a name that
/// is not compiled in).
bool builtin_parameter_names(std::string_view model, std::vector<std::string>& names);

}  // namespace gausstrack::tracking
