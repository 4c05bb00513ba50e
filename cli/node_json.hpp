#pragma once
// One node of a mesh tree as `info --nodes` prints it and the viewer shows it
// when a fragment is clicked (viewer/src/main.js reads the same numbers from
// the GLB's extras), so the two can be compared number for number.

#include <nlohmann/json.hpp>

#include <span>
#include <vector>

#include "shatter/meshtree/tree.hpp"

namespace shatter::cli {

/// For every node of `tree`, the bonds that cross its boundary (one leaf inside
/// its leaf range, the other outside), as indices into tree.bonds in their
/// order. A leaf's are all its bonds; the root has none.
/// Complexity: O(bonds x depth), walking each bond's leaves up to their common
/// ancestor.
std::vector<std::vector<std::size_t>> crossing_bonds_of_nodes(const MeshTree& tree);

/// The description of each node in `nodes`, in that order: {"node", "depth",
/// "leaf" (leaves only), "first_leaf", "leaf_count", "volume", "centroid"
/// [x, y, z], "triangles", "cap_triangles", "bonds": [{"leaf" (inside),
/// "other" (outside), "area"}]} (the bonds crossing the node's boundary, in
/// tree.bonds order). Precondition: every index is a node of `tree`.
nlohmann::ordered_json nodes_json(const MeshTree& tree, std::span<const NodeIndex> nodes);

}  // namespace shatter::cli
