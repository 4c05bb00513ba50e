#include "shatter/meshtree/recipe.hpp"

#include "shatter/kernel/enum_names.hpp"

namespace shatter {

std::string_view strategy_name(Strategy strategy) {
  switch (strategy) {
    case Strategy::thesis: return "thesis";
    case Strategy::balanced: return "balanced";
    case Strategy::axis: return "axis";
    case Strategy::voronoi: return "voronoi";
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
  return enum_named(name, {Strategy::thesis, Strategy::balanced, Strategy::axis, Strategy::voronoi},
                    &strategy_name);
}

std::uint64_t splitmix64(std::uint64_t& state) {
  std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

std::uint64_t root_node_seed(std::uint64_t recipe_seed) {
  std::uint64_t state = recipe_seed;
  return splitmix64(state);
}

std::uint64_t child_node_seed(std::uint64_t parent_seed, std::size_t index) {
  std::uint64_t state = parent_seed ^ (0xD1B54A32D192ED03ull * (index + 1));
  return splitmix64(state);
}

}  // namespace shatter
