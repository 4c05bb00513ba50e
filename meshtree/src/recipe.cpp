#include "shatter/meshtree/recipe.hpp"

#include "shatter/kernel/enum_names.hpp"

namespace shatter {

std::string_view strategy_name(Strategy strategy) {
  switch (strategy) {
    case Strategy::thesis: return "thesis";
    case Strategy::balanced: return "balanced";
    case Strategy::axis: return "axis";
  }
  return "unknown";
}

std::string_view kernel_name(KernelKind kernel) {
  switch (kernel) {
    case KernelKind::fast: return "fast";
    case KernelKind::exact: return "exact";
    case KernelKind::plane: return "plane";
  }
  return "unknown";
}

std::optional<Strategy> strategy_named(std::string_view name) {
  return enum_named(name, {Strategy::thesis, Strategy::balanced, Strategy::axis}, &strategy_name);
}

}  // namespace shatter
