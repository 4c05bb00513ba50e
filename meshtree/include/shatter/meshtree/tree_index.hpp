#pragma once
// How a mesh tree numbers its nodes and leaves. Apart from tree.hpp because the
// headers tree.hpp needs for its own members (bonds.hpp: a Bond names two leaves
// and a node) must name them too.

#include <cstdint>
#include <limits>

namespace shatter {

/// Index of a node in MeshTree::nodes (depth-first preorder; the root is 0).
using NodeIndex = std::uint32_t;
/// Index of a leaf (fragment) in depth-first order: MeshTree::leaf_nodes[i].
using LeafIndex = std::uint32_t;
/// No node: the parent of the root.
inline constexpr NodeIndex no_node = std::numeric_limits<NodeIndex>::max();

}  // namespace shatter
