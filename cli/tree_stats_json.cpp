#include "tree_stats_json.hpp"

#include <cmath>

namespace shatter::cli {

using json = nlohmann::ordered_json;

json recipe_json(const TreeRecipe& recipe) {
  return json{{"fragments", recipe.fragments},
              {"seed", recipe.seed},
              {"strategy", strategy_name(recipe.strategy)},
              {"kernel", kernel_name(recipe.kernel)},
              {"interior_uv_scale", recipe.interior_uv_scale},
              {"max_plane_tries", recipe.max_plane_tries},
              {"allow_self_intersections", recipe.allow_self_intersections}};
}

double leaf_volume_relative_error(const TreeStats& stats) {
  if (stats.root_volume == 0) return 0;
  return (stats.total_leaf_volume - stats.root_volume) / std::abs(stats.root_volume);
}

void append_stats_json(json& out, const json& options, const TreeStats& stats) {
  const VolumeSpread& volume = stats.fragment_volume;
  out["nodes"] = stats.node_count;
  out["leaves"] = stats.leaf_count;
  out["internal_nodes"] = stats.internal_count;
  out["max_depth"] = stats.max_depth;
  out["min_leaf_depth"] = stats.min_leaf_depth;
  out["options"] = options;
  out["volume"] = {{"root", stats.root_volume},
                   {"leaves_total", stats.total_leaf_volume},
                   {"leaves_relative_error", leaf_volume_relative_error(stats)}};
  out["fragment_volume"] = {{"min", volume.min},
                            {"median", volume.median},
                            {"max", volume.max},
                            {"mean", volume.mean},
                            {"coefficient_of_variation", volume.coefficient_of_variation}};
  out["bonds"] = {{"count", stats.bond_count}, {"total_area", stats.total_bond_area}};
  out["leaf_triangles"] = {{"total", stats.leaf_triangles}, {"cap", stats.leaf_cap_triangles}};
  out["leaf_vertices"] = stats.leaf_vertices;
}

}  // namespace shatter::cli
