#pragma once
// The whole public API of shatter::meshtree, one include, in pipeline order: a
// closed mesh comes in, is cut, built into a mesh tree with hulls and bonds,
// covered, summed up, checked, stored and exported. Each header holds:
//
//   input
//     separate.hpp      separate_solids: a closed triangle set into solids (shells, cavities placed exactly)
//     plane_input.hpp   prepare_plane_input: an input mesh as the plane kernel's first solid
//   cut
//     cut_solid.hpp     cut_solid: one plane cut of a plane-based solid, capped and separated
//     plane_cut.hpp     cut_by_plane, cut_mesh_by_plane: the plane kernel's one cut call, pieces certified
//   build
//     tree_index.hpp    NodeIndex, LeafIndex, no_node: how a tree numbers its nodes and leaves
//     recipe.hpp        TreeRecipe, Strategy, KernelKind: what decides a tree, kept in it
//     tree.hpp          MeshTree, MeshTreeNode: the tree's data, every level of the slicing
//     build.hpp         build_mesh_tree and how one build runs: BuildRunOptions, BuildReport
//   hulls
//     hull.hpp          convex_hull_of, convex_hull_of_points: canonical convex hulls, the colliders
//   bonds
//     bonds.hpp         Bond, find_bonds (true contact), the seed's bounding-box rule and its comparison
//   cover
//     cover.hpp         minimal_cover: the fewest nodes whose leaves are exactly a set of leaves
//   stats
//     stats.hpp         tree_stats: counts, depths, fragment volume spread, bonds
//   check
//     validate_tree.hpp validate_tree: every invariant of a tree, naming the part and index at fault
//   file
//     file.hpp          the .shatter format, byte by byte: encode_shatter, decode_shatter, read and write
//   export
//     export.hpp        mesh files per node selection, and the whole tree as one GLB
//
// Not included: tinygltf.hpp, tinygltf as meshtree compiles it, only for code that
// reads or writes glTF with tinygltf itself (it sets tinygltf's macros).

// The includes follow the pipeline, not the alphabet.
// clang-format off
#include "shatter/meshtree/separate.hpp"
#include "shatter/meshtree/plane_input.hpp"

#include "shatter/meshtree/cut_solid.hpp"
#include "shatter/meshtree/plane_cut.hpp"

#include "shatter/meshtree/tree_index.hpp"
#include "shatter/meshtree/recipe.hpp"
#include "shatter/meshtree/tree.hpp"
#include "shatter/meshtree/build.hpp"

#include "shatter/meshtree/hull.hpp"

#include "shatter/meshtree/bonds.hpp"

#include "shatter/meshtree/cover.hpp"

#include "shatter/meshtree/stats.hpp"

#include "shatter/meshtree/validate_tree.hpp"

#include "shatter/meshtree/file.hpp"

#include "shatter/meshtree/export.hpp"
// clang-format on
