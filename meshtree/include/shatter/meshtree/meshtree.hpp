#pragma once
// The whole public API of shatter::meshtree, one include, in pipeline order, with
// the cut it builds on (shatter/cut/cut.hpp): a closed mesh is built into a mesh
// tree with hulls and bonds, covered, summed up and checked. Storing and
// exporting a tree is the next floor up (shatter/formats/formats.hpp). Each
// header holds:
//
//   build
//     tree_index.hpp    NodeIndex, LeafIndex, no_node: how a tree numbers its nodes and leaves
//     recipe.hpp        TreeRecipe, Strategy, KernelKind: what decides a tree, kept in it
//     tree.hpp          MeshTree, MeshTreeNode: the tree's data, every level of the slicing
//     build.hpp         build_mesh_tree and how one build runs: BuildRunOptions, BuildReport
//   bonds
//     bonds.hpp         Bond, find_bonds (true contact), the seed's bounding-box rule and its comparison
//   cover
//     cover.hpp         minimal_cover: the fewest nodes whose leaves are exactly a set of leaves
//   stats
//     stats.hpp         tree_stats: counts, depths, fragment volume spread, bonds
//   check
//     validate_tree.hpp validate_tree: every invariant of a tree, naming the part and index at fault

// The includes follow the pipeline, not the alphabet.
// clang-format off
#include "shatter/cut/cut.hpp"

#include "shatter/meshtree/tree_index.hpp"
#include "shatter/meshtree/recipe.hpp"
#include "shatter/meshtree/tree.hpp"
#include "shatter/meshtree/build.hpp"
#include "shatter/meshtree/sites.hpp"
#include "shatter/meshtree/voronoi.hpp"

#include "shatter/meshtree/bonds.hpp"

#include "shatter/meshtree/cover.hpp"

#include "shatter/meshtree/stats.hpp"

#include "shatter/meshtree/validate_tree.hpp"
// clang-format on
