#pragma once
// Bonds between fragments (DESIGN.md, "Bonds and the runtime"). A bond is true
// contact: two leaves on opposite sides of one cut whose caps on that plane overlap
// in positive area, decided exactly. The seed's rule (bounding boxes overlap) is
// kept beside it only to measure how many false bonds it makes.

#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include "shatter/kernel/vec.hpp"
#include "shatter/meshtree/tree_index.hpp"

namespace shatter {

/// A bond joins two leaves that truly touch: they lie on opposite sides of one
/// cut and their caps on that plane overlap in positive area.
struct Bond {
  LeafIndex first = 0;   ///< first < second
  LeafIndex second = 0;
  NodeIndex cut_node = no_node;  ///< the node whose plane both caps lie on
  /// Area of the caps' overlap: > 0 exactly; as a rounded double it is 0 only
  /// when the exact overlap is below the double range's resolution.
  double area = 0;
  Vec3 centroid;                 ///< area-weighted centroid of the overlap
  Vec3 normal;                   ///< unit normal of the plane, from `first` into `second`
};

/// A bond of a plane-kernel tree as a lean build keeps it (BuildRunOptions::lean,
/// MeshTree::packed_bonds): 40 bytes instead of Bond's 72, for the ten million
/// bonds of a million-fragment cube. What it leaves out follows from the cut
/// node's plane (MeshTree::cut_planes[cut_node]): the centroid lies on it,
/// solved from its two other coordinates over `axis` (point_on_plane_over, as
/// find_plane_bonds makes it), and the normal is the plane's unit normal, signed
/// by the side `first` lies on. unpack_bond gives the Bond back bit for bit.
struct PackedBond {
  LeafIndex first = 0;   ///< first < second
  LeafIndex second = 0;
  NodeIndex cut_node = no_node;  ///< a node whose plane both caps lie on (a cell plane's bonds are never packed)
  std::uint8_t axis = 0;         ///< the coordinate of the centroid solved from the plane (0-2)
  bool first_below = false;      ///< first lies below the plane: Bond::normal is +unit, else -unit
  double area = 0;               ///< Bond::area
  double u = 0, v = 0;           ///< the centroid's coordinates (axis + 1) % 3 and (axis + 2) % 3
};

// tree.hpp includes this header (a tree holds its bonds): the functions below
// take the tree by a forward declaration.
struct MeshTree;

/// The Bond a PackedBond stands for in `tree`.
/// Precondition: bond.cut_node < tree.cut_planes.size() and bond.axis < 3 (so it
/// is of every PackedBond find_packed_plane_bonds made for this tree).
/// Guarantees: the Bond find_plane_bonds gives for the same leaves, bit for bit
/// (the same arithmetic on the same values). Never throws.
Bond unpack_bond(const MeshTree& tree, const PackedBond& bond);

/// Every true bond of the tree's leaves: one Bond per (leaf pair, cut node).
///
/// Preconditions: `tree` is well formed (preorder nodes, contiguous leaf ranges,
/// parent/children links, above_parent_plane set on every non-root node, one
/// cut plane per node with a non-zero finite normal on every internal node); cap
/// triangles of the cut at node k carry cap_surface_of(k) and lie (up to their
/// rounding) on cut_planes[k]. A triangle whose surface id names no internal ancestor of its
/// leaf (e.g. an input surface id that is not 0) is ignored.
///
/// Guarantees: leaves a (below node k's plane) and b (above it) are bonded on k iff
/// some cap-k triangle of a and some cap-k triangle of b have intersecting interiors
/// in the plane. That decision is exact: triangles are projected by dropping the
/// coordinate of the normal's largest component (no arithmetic), and every test on
/// the projected doubles (orientations, a point strictly inside a triangle, a line
/// with each face on its own closed side) is decided exactly; triangles with no
/// interior in the projection never bond. Bond::area is the overlap area in the
/// plane, a rounded construction (convex polygon clipping in doubles, rescaled from
/// the projection to the plane); overlaps whose area rounds to zero or below count
/// 0, so an exactly decided but sub-rounding overlap can come out 0 and the bond is
/// still kept: the area weighs a bond, it never makes one. A leaf's cap on a cut
/// that fills its convex hull up to 1e-12 of its area (a convex face, moved by
/// rounding) is measured on that hull, slightly thinned; any other on its
/// triangles. Bond::centroid is the area-weighted centroid of the overlap, lifted
/// onto the plane (when the area rounds to 0, the centre of the two caps' box
/// overlap). Bond::normal is the unit plane normal pointing from `first` into
/// `second`. first < second; sorted by (first, second, cut_node); no duplicates.
/// Deterministic: equal trees give equal bonds.
///
/// Complexity: O(T log t) to gather the T leaf triangles into caps of at most t
/// triangles and take their hulls, then per cut a sort and sweep of its caps'
/// boxes, O(c log c + P) for c caps and P cross-side pairs whose boxes overlap;
/// a pair costs O(t + hull sizes) when its caps overlap clearly or are
/// clearly apart, and O(t^2) only when they touch without overlapping. Single
/// thread; memory O(T + bonds). On a 65,536-fragment cube (9.5 million cap
/// triangles, as the builder slices caps) it takes about 3 s on one core.
/// A tree with an exact representation (MeshTree::has_exact_representation) is
/// handled by find_plane_bonds.
std::vector<Bond> find_bonds(const MeshTree& tree);

/// The bonds of a plane-kernel tree, decided on the nodes' exact solids: leaves a
/// (below node k's plane) and b (above it) are bonded on k iff some cap face of a
/// and some cap face of b on plane k have interior points in common, decided with
/// exact orientation predicates on the faces' defined vertices (non-convex faces
/// through an exact triangulation). Area and centroid are measured on the rounded
/// overlap, as find_bonds does; same ordering and guarantees.
/// Preconditions: a tree built by the plane kernel (or read from a file that
/// stores its exact solids). Complexity: per cut, a sweep of its faces' boxes,
/// then per candidate pair O(corners) exact predicates when they overlap
/// clearly, O(corners^2) when they only touch.
std::vector<Bond> find_plane_bonds(const MeshTree& tree);

/// find_plane_bonds' bonds as PackedBonds (unpack_bond of each gives them bit
/// for bit, in the same order), made packed as they are found, so a lean build
/// never holds them as Bonds (README "Lean memory").
/// Preconditions: as find_plane_bonds, and every cut plane a node's (a tree of
/// build_mesh_tree; a cell tree's planes after the nodes' throw
/// std::invalid_argument).
/// Threads: those of the task arena it is called in (tbb::this_task_arena; a
/// caller outside any arena lends it every core). On one thread the leaves are
/// read once, in order; on more, in runs of subtrees read in parallel (the
/// overload below), and the bonds are the same, bit for bit and in order.
std::vector<PackedBond> find_packed_plane_bonds(const MeshTree& tree);

/// find_packed_plane_bonds with its leaves split into runs of whole subtrees of
/// at most `run_leaves` leaves each (0: not split), read in parallel; the cuts
/// whose range holds more leaves are run after, in parallel, each on its faces
/// joined in leaf order. Guarantees: the bonds find_packed_plane_bonds(tree)
/// gives, bit for bit and in the same order, for every `run_leaves` (the tests
/// compare them). Preconditions and failure: as find_packed_plane_bonds.
std::vector<PackedBond> find_packed_plane_bonds(const MeshTree& tree, std::uint32_t run_leaves);

/// The seed's bond rule: every pair of leaves whose closed axis-aligned bounding
/// boxes (of the leaf meshes' positions) overlap, touching included.
///
/// Preconditions: `tree` as for find_bonds; leaf positions finite. A leaf with an
/// empty mesh has no box and bonds with nothing.
/// Guarantees: pairs (a, b) with a < b, sorted, no duplicates. Exact: the boxes are
/// compared coordinate by coordinate, no arithmetic.
/// Complexity: O(V + n log^3 n + K) for V leaf vertices, n leaves and K reported
/// pairs (CGAL's streamed segment-tree box intersection), never all n² pairs.
std::vector<std::pair<LeafIndex, LeafIndex>> find_bounding_box_bonds(const MeshTree& tree);

/// How the seed's box rule compares with true contact on one tree.
struct BondRuleComparison {
  std::size_t true_bonds = 0;         ///< leaf pairs with a true bond (counted once over all cuts)
  std::size_t box_bonds = 0;          ///< leaf pairs whose boxes overlap
  std::size_t false_box_bonds = 0;    ///< box pairs with no true bond
  std::size_t missed_true_bonds = 0;  ///< true bonded pairs whose boxes do not overlap
};

/// Runs both rules on `tree` and counts where they disagree.
/// Preconditions: as for find_bonds. Guarantees: true_bonds - missed_true_bonds ==
/// box_bonds - false_box_bonds (the pairs both rules find). A true bond's caps
/// overlap inside both leaves, so a miss can only come from rounding of cap
/// vertices off the plane (the retired fast kernel's trees).
/// Complexity: that of find_bonds plus find_bounding_box_bonds, plus a linear merge.
BondRuleComparison compare_bond_rules(const MeshTree& tree);

}  // namespace shatter
