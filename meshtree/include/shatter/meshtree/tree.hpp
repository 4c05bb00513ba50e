#pragma once
// The mesh tree (seed thesis ch. 3, Fig 3.1-3.3): the input solid at the root,
// every solid a cut produced as a child of the solid it was cut from, the
// fragments at the leaves. Nodes are stored in depth-first preorder and leaves are
// numbered in that order, so every node's leaves form one contiguous range.

#include <cstdint>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "shatter/kernel/mass.hpp"
#include "shatter/kernel/mesh.hpp"
#include "shatter/kernel/solid.hpp"
#include "shatter/kernel/vec.hpp"

namespace shatter {

/// Index of a node in MeshTree::nodes.
using NodeIndex = std::uint32_t;
/// Index of a leaf (fragment) in depth-first order: MeshTree::leaf_nodes[i].
using LeafIndex = std::uint32_t;
inline constexpr NodeIndex no_node = std::numeric_limits<NodeIndex>::max();

/// How the builder picks the next plane and the next node to cut.
enum class Strategy : std::uint8_t {
  /// A random plane through the node's volume centroid; a node's fragment budget is
  /// shared evenly among its children, whatever their size (the seed's method).
  thesis = 0,
  /// A random plane through the centroid, always cutting the largest-volume leaf
  /// next, which evens out fragment sizes.
  balanced = 1,
  /// Planes across the node's longest bounding-box axis (X, Y or Z) near the
  /// centroid, with offset and angle jitter (as PhysX APEX slices); the budget is
  /// shared among the children in proportion to their volume.
  axis = 2,
};

/// Which kernel cuts (DESIGN.md, "Exact arithmetic"). `plane`: plane-based
/// vertices (kernel/implicit.hpp), exact at any depth and rounded once, certified,
/// for output; the default. `exact`: CGAL Epeck rationals, the reference.
/// `fast`: rounded cut points, exact predicates; kept only for comparison.
enum class KernelKind : std::uint8_t { fast = 0, exact = 1, plane = 2 };

std::string_view strategy_name(Strategy strategy);
std::string_view kernel_name(KernelKind kernel);

/// Everything that decides a tree's contents. Two builds with equal options on
/// equal input give byte-identical trees, whatever `threads` is.
struct BuildOptions {
  std::uint32_t fragments = 2;  ///< stop at the first leaf count >= this (>= 1)
  std::uint64_t seed = 1;
  Strategy strategy = Strategy::thesis;
  KernelKind kernel = KernelKind::plane;
  double interior_uv_scale = 1.0;
  /// Planes drawn for one node before the build fails. A plane is redrawn when it
  /// misses the node. With the fast and exact kernels also when it passes within
  /// 1e-8 of the node's bounding-box diagonal of a vertex (it would leave needles
  /// later planes cannot cut), or when a piece's stored (rounded) mesh would not
  /// be a valid solid; the plane kernel never redraws for numerical reasons.
  std::uint32_t max_plane_tries = 64;
  /// Accept a self-intersecting input (only topology is promised then).
  bool allow_self_intersections = false;
  /// Worker threads; 0 means one per hardware thread. Never changes the output.
  unsigned threads = 0;
  /// The caller has already refused the input unless it is a valid solid, as
  /// require_valid_solid(mesh, name, allow_self_intersections) does (the full
  /// validate_mesh, self-intersections included), so the builder skips that
  /// check instead of repeating it. Set it only after such a check of this very
  /// mesh: on any other mesh the build's guarantees do not hold. Never changes
  /// the output; a built tree's options have it false again.
  bool input_validated = false;
};

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

struct MeshTreeNode {
  /// The closed solid, a valid one (validate_mesh finds no defect; with
  /// allow_self_intersections only topology is promised). Cap triangles of the cut
  /// at node k carry cap_surface_of(k) = k + 1; the input's triangles keep surface 0.
  Mesh mesh;
  MassProperties mass;  ///< of `mesh`, unit density
  /// The convex hull of `mesh` (outward triangles over its own positions; every
  /// surface id 0, no attributes), for colliders.
  Mesh hull;
  /// Plane kernel: the node's exact solid, its vertices defined over
  /// MeshTree::plane_set() (cut plane k is node k's plane). Empty otherwise.
  Solid solid;
  /// Plane kernel: the solid is convex (decided exactly), so `mesh` is its own
  /// hull and `hull` is left empty. Use MeshTree::hull_of.
  bool convex = false;
  NodeIndex parent = no_node;
  std::vector<NodeIndex> children;  ///< empty for a leaf; otherwise two or more
  Plane plane;                      ///< the plane that cut this node (internal nodes only)
  /// Which side of its parent's plane the node lies on (false: n·x + d < 0).
  bool above_parent_plane = false;
  std::uint32_t depth = 0;          ///< root 0
  LeafIndex first_leaf = 0;         ///< this node's leaves are [first_leaf, first_leaf + leaf_count)
  std::uint32_t leaf_count = 0;
  std::uint64_t seed = 0;           ///< the node's own seed, derived from the root seed

  bool is_leaf() const { return children.empty(); }
};

/// What `build_mesh_tree` produces and the .shatter file stores.
struct MeshTree {
  BuildOptions options;
  /// The shatter version that built the tree (shatter::version_string, e.g.
  /// "0.1.0"; build_mesh_tree sets it), kept by the .shatter file. Empty when
  /// unknown: a tree made by hand, or read from a file written before versions
  /// were recorded.
  std::string shatter_version;
  std::vector<MeshTreeNode> nodes;   ///< depth-first preorder; nodes[0] is the root
  std::vector<NodeIndex> leaf_nodes; ///< leaf i is nodes[leaf_nodes[i]]
  std::vector<Bond> bonds;           ///< sorted by (first, second, cut_node)
  /// Plane kernel: the input points and input planes the nodes' solids are
  /// defined over. Empty otherwise.
  InputGeometry geometry;
  /// Plane kernel: every node's plane in node order (zero for leaves), the cut
  /// planes of plane_set(). Empty otherwise.
  std::vector<Plane> cut_planes;

  std::size_t leaf_count() const { return leaf_nodes.size(); }
  const MeshTreeNode& leaf(LeafIndex i) const { return nodes[leaf_nodes[i]]; }
  /// The planes the nodes' exact solids are defined over (plane kernel).
  PlaneSet plane_set() const { return geometry.plane_set(cut_planes); }
  /// A node's convex hull: its own mesh when it is convex, else `hull`.
  const Mesh& hull_of(NodeIndex node) const { return nodes[node].convex ? nodes[node].mesh : nodes[node].hull; }
};

/// The surface id cap triangles of the cut at `node` carry.
inline SurfaceId cap_surface_of(NodeIndex node) { return node + 1; }

}  // namespace shatter
