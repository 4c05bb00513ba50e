#pragma once
// The description of a mesh tree that `fracture` and `info` both print, so
// their JSON uses the same keys for the same things.

#include <nlohmann/json.hpp>

#include "shatter/meshtree/recipe.hpp"
#include "shatter/meshtree/stats.hpp"
#include "shatter/meshtree/tree.hpp"

namespace shatter::cli {

/// The tree's recipe under the keys both commands print (as "options", the name
/// their JSON has always used): fragments, seed, strategy, kernel,
/// interior_uv_scale, max_plane_tries, allow_self_intersections.
nlohmann::ordered_json recipe_json(const TreeRecipe& recipe);

/// (total leaf volume - root volume) / |root volume|, 0 for a root of volume 0:
/// how far rounding moved the partition from exact.
double leaf_volume_relative_error(const TreeStats& stats);

/// Appends to `out`, in this order: nodes, leaves, internal_nodes, max_depth,
/// min_leaf_depth, "options" (as given), volume, fragment_volume, bonds,
/// leaf_triangles, leaf_vertices; so the JSON reads shape, how built, then how well.
void append_stats_json(nlohmann::ordered_json& out, const nlohmann::ordered_json& options, const TreeStats& stats);

}  // namespace shatter::cli
