#include <array>
#include <string>

#include "gausstrack/plant_sim/models.hpp"

namespace gausstrack::plant_sim {
namespace {

const std::vector<ModelFactory>& builtin_factories() {
  static const std::vector<ModelFactory> factories = [] {
    std::vector<ModelFactory> all;
    for (const char* name : tracking::kBuiltinModels)
      tracking::visit_builtin_model(name,
                                    [&]<typename M>(std::type_identity<M>) { all.push_back(model_factory<M>(name)); });
    return all;
  }();
  return factories;
}

}  // namespace

const ModelFactory* find_builtin_model(const std::string& name) {
  for (const ModelFactory& f : builtin_factories())
    if (f.name == name) return &f;
  return nullptr;
}

}  // namespace gausstrack::plant_sim
