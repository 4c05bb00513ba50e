#pragma once
// Every node's convex hull, for both builders (build.cpp, voronoi.cpp).

#include <tbb/task_arena.h>

#include "shatter/meshtree/tree.hpp"

namespace shatter::detail {

/// Fills the hull of every node of `tree` that is not convex (a convex node,
/// decided exactly, is its own hull and keeps none), from the leaves up, on
/// `arena`'s threads: a leaf's hull is that of its mesh's vertices (one it
/// has already is kept), an internal node's that of its children's hull
/// vertices (a convex child's mesh vertices), which hold the node's own
/// vertices (each is a child's vertex, rounded alike unless one of the two
/// took a later rounding attempt) and are far fewer. Such a hull may exceed
/// the hull of the node's own vertices by the rounding of points inside it.
/// Each depth is done in parallel, deepest first; every hull is a pure
/// function of meshes, so the bytes do not depend on the threads.
/// Precondition: every node's mesh present (packed nodes are read through
/// NodeShapes). Throws what convex_hull_of throws (std::bad_alloc).
void tree_hulls(tbb::task_arena& arena, MeshTree& tree);

}  // namespace shatter::detail
