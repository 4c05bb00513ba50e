#pragma once
// Minimal cover (seed thesis ch. 3.2 and 5.2.2, Fig 3.3): a cluster of fragments
// is drawn and simulated with the fewest mesh tree nodes that make up exactly that
// cluster, e.g. the parent's mesh instead of both its children once neither has
// broken off.

#include <span>
#include <vector>

#include "shatter/meshtree/tree.hpp"

namespace shatter {

/// The fewest nodes of `tree` whose leaves together are exactly the set `leaves`.
///
/// Preconditions: `tree` is well formed (nodes in depth-first preorder, leaves
/// numbered in that order, every node's first_leaf/leaf_count its contiguous leaf
/// range, parent links set, every internal node with two or more children).
/// `leaves` may come in any order and may repeat a leaf: it is read as a set, so
/// a duplicate changes nothing.
/// Guarantees: the result is the unique minimal cover, i.e. every node whose leaves
/// all lie in the set while its parent's do not (or which is the root); the nodes'
/// leaf ranges are disjoint, their union is the set, and they come in increasing
/// order of first_leaf. An empty set gives an empty result; the set of all leaves
/// gives {0} (the root).
/// Throws std::invalid_argument when a leaf index is >= tree.leaf_count().
/// Complexity: O(|leaves|) time and memory (a radix sort, then one climb per run of
/// consecutive leaves, at most 2|leaves| node visits, as every internal node has two
/// or more children), independent of the tree's size.
std::vector<NodeIndex> minimal_cover(const MeshTree& tree, std::span<const LeafIndex> leaves);

}  // namespace shatter
