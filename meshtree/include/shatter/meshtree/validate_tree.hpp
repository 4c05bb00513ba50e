#pragma once
// The tree checker: the invariants of a MeshTree, checked on the tree alone, and
// the part and index of the first one broken (STYLE.md: the validator is a public
// function). Three users, three depths: the .shatter reader runs the structural
// checks on every file it decodes, so the rest of the library can trust what it
// reads; the tests run them, caches included, after every build; and
// `shatter info --check` adds the geometry of every node.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "shatter/meshtree/tree.hpp"

namespace shatter {

/// Where in a tree a defect is. TreeDefect::index says which one of that part.
enum class TreePart : std::uint8_t {
  recipe,       ///< MeshTree::recipe (index 0)
  node,         ///< a node's parent, children, depth, cut plane or mass (index: the node)
  leaf_range,   ///< a node's first_leaf and leaf_count (index: the node)
  leaf_list,    ///< MeshTree::leaf_nodes (index: the leaf)
  mesh,         ///< a node's mesh (index: the node)
  hull,         ///< a node's hull (index: the node)
  bond,         ///< one of MeshTree::bonds (index: the bond)
  input_point,  ///< a point of MeshTree::geometry, the GEOM section (index: the point)
  input_plane,  ///< an input plane of MeshTree::geometry or its cached approximation (index: the plane)
  cut_planes,   ///< MeshTree::cut_planes not one per node (index 0); a plane's own defects are `node`'s
  solid,        ///< a node's exact solid, the SOLD section: vertex definitions, faces, loops, corners,
                ///< cached approximations, convex flag (index: the node)
};

/// The part as messages name it: "recipe", "node", "leaf range", "leaf list",
/// "mesh", "hull", "bond", "input point", "input plane", "cut planes" or "solid";
/// "unknown" for a value outside the enum.
std::string_view tree_part_name(TreePart part);

/// The first defect validate_tree finds.
struct TreeDefect {
  TreePart part = TreePart::node;
  std::size_t index = 0;  ///< which node, leaf, bond, point or plane of `part`
  /// One line naming the defect and the elements at fault in words, e.g.
  /// "node 3 has depth 1, but its parent's depth is 1".
  std::string message;
};

/// What validate_tree checks beyond the structure.
struct TreeValidationOptions {
  /// The floating-point caches a .shatter file does not store (every
  /// InputGeometry::plane_approx and Solid::approx) are sized and equal, bit for
  /// bit, to their recomputation; recomputing them also finds vertex definitions
  /// whose planes meet in no single point. A solid may come without its approx
  /// (empty: a lean build's, BuildRunOptions::lean); its definitions are still
  /// approximated, to find degenerate ones. On for a tree in memory. The reader
  /// turns it off: it recomputes the caches itself, after the structure passed.
  bool caches = true;
  /// What the builder promises of the geometry, too: every internal node's plane
  /// has a finite, non-zero normal and a finite offset, with children on both of
  /// its sides, but a cell node's (a cell tree's: recipe.strategy voronoi or cell
  /// planes kept), which is all zero; every node's mass has a positive volume
  /// and finite moments; every node's mesh is a valid solid, not empty
  /// (validate_mesh, self-intersections included; a tree built with
  /// allow_self_intersections is held to the topology only: closed, consistently
  /// oriented, manifold along every edge (separate fans may meet at a vertex, as
  /// the input check allows with the flag), finite, every vertex used); every
  /// node not marked convex stores a hull that is a closed, outward solid with
  /// positive volume and no zero-area triangle (validate_mesh without the
  /// self-intersection test). Costs the self-intersection test of every
  /// node's mesh, O(T log T) for T triangles on typical meshes, run on the nodes
  /// in parallel: seconds for thousands of fragments, which is why the reader
  /// never asks for it.
  bool geometry = false;
  /// With `geometry`: a node's mesh that certify_piece certifies (a linear-time
  /// exact proof that validate_mesh finds it valid; README, "Certificates") is
  /// not searched for self-intersections; any other is checked in full, so the
  /// verdict and the defect named are the same either way, only the time
  /// differs. `shatter info --check` turns it on; the tests leave it off, so
  /// that the full validator checks every node they build.
  bool certificates = false;
};

/// The answer of validate_tree.
struct TreeValidationReport {
  /// The first defect in the order of the checks, empty when the tree holds: the
  /// structure (recipe, links and leaf ranges, the leaf list, the cut planes'
  /// count, meshes and hulls, bonds, the exact representation), then the
  /// caches, then the geometry (the lowest node at fault).
  std::optional<TreeDefect> defect;
  /// The geometry was checked: asked for, and the structure allowed it.
  bool geometry_checked = false;

  bool valid() const { return !defect.has_value(); }
  /// "valid", or the defect as "<part> <index>: <message>", e.g.
  /// "leaf range 4: node 4 claims leaves [1, +1), but its subtree holds [2, +1)".
  std::string summary() const;
};

/// Checks `tree` against every invariant of a mesh tree, stopping at the first
/// defect, since a broken structure makes the later checks meaningless (or
/// unsafe to index). The structural checks, always made, are those
/// decode_shatter lists (file.hpp): the recipe's enums in range and fragments
/// >= 1; the root, parent and children links, depth-first preorder, depths and
/// child counts; leaf ranges contiguous and consistent with the children, and
/// leaf_nodes the leaves in node order; one cut plane per node; every mesh and hull indexing its own
/// vertices with surfaces and attribute channels sized to its triangles; bonds
/// in range, sorted, each between leaves its cut node's cut separates; and the
/// exact representation (geometry, internal nodes' cut planes finite, convex
/// flags, solids) complete and consistent as a structure, or wholly absent. `options` adds the caches and the
/// geometry (TreeValidationOptions).
/// Preconditions: none; any MeshTree, however malformed, is checked without
/// reading outside its vectors.
/// Guarantees: deterministic (the same tree gives the same report on any thread
/// count); a tree that passes the structural checks is safe to index as
/// MeshTree's comments describe, and one that passes with caches is one
/// encode_shatter accepts. Not checked even with geometry: that the bonds are
/// those find_bonds would find, that children partition their parent, that the
/// exact solids match the meshes, and that hulls are convex (each costs a
/// computation the tests make on their own).
/// Throws only std::bad_alloc.
/// Complexity: the structure O(size of the tree) time, O(nodes + the largest
/// solid) memory; the caches one approximate() per solid vertex; the geometry as
/// TreeValidationOptions::geometry says.
TreeValidationReport validate_tree(const MeshTree& tree, const TreeValidationOptions& options = {});

/// Whether `tree` carries a certificate that still holds (MeshTree::certificate,
/// TreeCertificate): one was made, by build_mesh_tree for the tree it built or
/// by certify_tree, and the digest of the tree's content is still the one taken
/// then. When it holds, validate_tree(tree) (caches on) passes, so a consumer
/// may stand on that instead of repeating the check; encode_shatter does.
/// validate_tree itself never consults a certificate, so `shatter info --check`
/// and the reader check everything whatever a tree carries.
/// Cost: one pass over the tree's memory, no unpacking and no arithmetic on
/// the geometry (far less than validate_tree). Never throws.
bool certificate_holds(const MeshTree& tree);

/// Runs validate_tree(tree) (structure and caches) and, when it passes,
/// certifies the tree (MeshTree::certificate), so that encode_shatter need not
/// repeat the check while the tree is unchanged; otherwise clears any
/// certificate. For a tree assembled or changed by hand that will be written
/// more than once. Returns validate_tree's report. Throws only std::bad_alloc.
TreeValidationReport certify_tree(MeshTree& tree);

/// The leaves among `nodes` in node order: what MeshTree::leaf_nodes must be.
/// Never throws but std::bad_alloc.
std::vector<NodeIndex> leaves_in_order(const std::vector<MeshTreeNode>& nodes);

/// Computes the floating-point caches a tree may come without (every
/// InputGeometry::plane_approx and Solid::approx, as TreeValidationOptions::caches
/// describes them) and stores them in `tree`: what a reader of a stored tree calls.
/// A lean build's packed nodes (MeshTree::packed_shapes) are unpacked into
/// their nodes first, so the tree is the one a full build makes.
/// Precondition: `tree` passed validate_tree with caches off.
/// Returns the first vertex whose definition is degenerate (its planes meet in no
/// single point) as a TreePart::solid defect; the caches are then incomplete.
/// Never throws but std::bad_alloc.
std::optional<TreeDefect> fill_tree_caches(MeshTree& tree);

}  // namespace shatter
