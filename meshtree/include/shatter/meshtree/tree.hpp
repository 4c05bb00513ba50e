#pragma once
// The mesh tree (seed thesis ch. 3, Fig 3.1-3.3): the input solid at the root,
// every solid a cut produced as a child of the solid it was cut from, the
// fragments at the leaves. Nodes are stored in depth-first preorder and leaves are
// numbered in that order, so every node's leaves form one contiguous range.
// A tree records the recipe that built it (recipe.hpp) and its bonds (bonds.hpp);
// bonds.hpp declares its functions on a forward-declared MeshTree, and the
// builder (build.hpp) includes this header.

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "shatter/kernel/mass.hpp"
#include "shatter/kernel/mesh.hpp"
#include "shatter/kernel/repair.hpp"
#include "shatter/kernel/solid.hpp"
#include "shatter/kernel/vec.hpp"
#include "shatter/meshtree/bonds.hpp"
#include "shatter/meshtree/boxed.hpp"
#include "shatter/meshtree/packed_shapes.hpp"
#include "shatter/meshtree/recipe.hpp"
#include "shatter/meshtree/tree_index.hpp"

namespace shatter {

struct MeshTreeNode {
  /// The closed solid, a valid one (validate_mesh finds no defect; with
  /// allow_self_intersections only topology is promised). Cap triangles of the cut
  /// at node k carry cap_surface_of(k) = k + 1; the input's triangles keep surface 0.
  /// Boxed, as `hull` is (read it as `*node.mesh` or `node.mesh->positions`):
  /// a lean tree packs every node's mesh (MeshTree::packed_shapes) and leaves
  /// this absent, so its two million records of a million-fragment tree carry
  /// a pointer instead of 144 bytes of empty arrays.
  Boxed<Mesh> mesh;
  MassProperties mass;  ///< of `mesh`, unit density
  /// The convex hull of `mesh` (outward triangles over its own positions; every
  /// surface id 0, no attributes), for colliders. Boxed: held on the heap only
  /// when set, since a convex node leaves it empty (read it as `*node.hull` or
  /// `node.hull->positions`, or through MeshTree::hull_of).
  Boxed<Mesh> hull;
  /// Plane kernel: the node's exact solid, its vertices defined over
  /// MeshTree::plane_set() (cut plane k is node k's, MeshTree::cut_planes[k]).
  /// Empty otherwise. Its vertices' cached approximations (Solid::approx) are
  /// there unless the tree was built lean (BuildRunOptions::lean): then every
  /// node's approx is empty, and fill_tree_caches (validate_tree.hpp) computes
  /// them for code that needs them. Boxed, as `mesh` is, and for the same reason
  /// (128 bytes of empty arrays in a lean tree's packed node).
  Boxed<Solid> solid;
  /// Plane kernel: the solid is convex (decided exactly), so `mesh` is its own
  /// hull and `hull` is left empty. Use MeshTree::hull_of.
  bool convex = false;
  NodeIndex parent = no_node;
  std::vector<NodeIndex> children;  ///< empty for a leaf; otherwise two or more
  /// Which side of its parent's plane (MeshTree::cut_planes[parent]) the node
  /// lies on (false: n·x + d < 0).
  bool above_parent_plane = false;
  std::uint32_t depth = 0;          ///< root 0
  LeafIndex first_leaf = 0;         ///< this node's leaves are [first_leaf, first_leaf + leaf_count)
  std::uint32_t leaf_count = 0;
  std::uint64_t seed = 0;           ///< the node's own seed, derived from the root seed

  bool is_leaf() const { return children.empty(); }
};

namespace detail {
struct TreeCertifier;
}

/// What the code that made a tree established of it, bound to the tree's
/// content: a 128-bit digest (validate_tree.hpp, certificate_holds) of
/// everything validate_tree reads, taken when the tree was certified. Only the
/// meshtree library makes one: build_mesh_tree, for the tree it built (its
/// invariants hold by construction: README "Certificates carried, not re-checked"),
/// and certify_tree, after validate_tree passed. It never has to be cleared by
/// hand: a tree changed afterwards no longer matches its digest, and a consumer
/// (encode_shatter) then checks the tree in full, as it does a tree without one.
/// Copying a tree copies its certificate, which holds for the copy as long as
/// the content is equal. Not stored in a file.
class TreeCertificate {
 public:
  /// Whether a certificate was made at all (not whether it still holds).
  bool present() const { return present_; }
  /// What it says beyond validity, while it holds: every node's mass is
  /// mass_properties of the node's mesh, bit for bit. True of the trees
  /// build_mesh_tree and the Voronoi builder make (they compute each mass so),
  /// false of certify_tree's (validate_tree does not compare masses); it lets
  /// the writer leave the masses out of a file without recomputing each.
  bool masses_derived() const { return masses_derived_; }

 private:
  friend struct detail::TreeCertifier;
  bool present_ = false;
  bool masses_derived_ = false;
  std::uint64_t digest_[2] = {0, 0};
};

/// What `build_mesh_tree` produces and the .shatter file stores.
struct MeshTree {
  TreeRecipe recipe;  ///< what decides the tree's contents (how it was built is not kept)
  /// The shatter version that built the tree (shatter::version_string, e.g.
  /// "0.1.0"; build_mesh_tree sets it), kept by the .shatter file. Empty when
  /// unknown: a tree made by hand, or read from a file written before versions
  /// were recorded.
  std::string shatter_version;
  /// How the input was repaired before the build (`fracture --repair`: its
  /// changes, what it left undone, the counts before and after); empty when the
  /// input was built as read. The root's mesh is the repaired input. Kept by the
  /// .shatter file (the optional `rpar` section), so a tree says where its root
  /// departs from the file it was made from.
  RepairReport input_repair;
  std::vector<MeshTreeNode> nodes;   ///< depth-first preorder; nodes[0] is the root
  std::vector<NodeIndex> leaf_nodes; ///< leaf i is nodes[leaf_nodes[i]]
  /// Sorted by (first, second, cut_node). Empty in a lean build's tree, which
  /// keeps them in packed_bonds: read a tree's bonds through bond_count() and
  /// bond(i), which see either.
  std::vector<Bond> bonds;
  /// A lean build's bonds (BuildRunOptions::lean), packed (PackedBond), in the
  /// order `bonds` would have them; empty in every other tree (a tree has its
  /// bonds in one of the two). fill_tree_caches unpacks them into `bonds`.
  std::vector<PackedBond> packed_bonds;
  /// Plane kernel: the input points and input planes the nodes' solids are
  /// defined over. Empty otherwise.
  InputGeometry geometry;
  /// The plane that cut node k is cut_planes[k]: one per node, in every tree
  /// (a leaf's is unused; the builder leaves it zero). The only copy of the cut
  /// planes, kept here rather than in the nodes because the plane kernel's
  /// predicates view it whole (plane_set(): cut plane k is node k's).
  std::vector<Plane> cut_planes;
  /// A lean build's nodes (BuildRunOptions::lean): one entry per node, the
  /// node's mesh and exact solid packed (packed_node.hpp) once it was cut or
  /// finished as a leaf (a surplus cut undone leaves its node packed, a leaf),
  /// with its own `mesh` and `solid` left empty; an empty entry for a node that
  /// keeps them (pack_leaves packs a tree's remaining leaves). Empty in every
  /// other tree. Read a node's mesh and solid through
  /// NodeShapes, which unpacks them; fill_tree_caches (validate_tree.hpp)
  /// unpacks them all into the nodes. The bytes are kept in blocks
  /// (PackedShapes), not one array a node.
  PackedShapes packed_shapes;
  /// What the code that made the tree certified of it (TreeCertificate): the
  /// writer's full check is replaced by a digest comparison while it holds.
  TreeCertificate certificate;

  std::size_t leaf_count() const { return leaf_nodes.size(); }
  /// The number of bonds, packed or not.
  std::size_t bond_count() const { return bonds.size() + packed_bonds.size(); }
  /// Bond i (< bond_count()) of the sorted list, unpacked when the tree keeps
  /// its bonds packed (unpack_bond's precondition holds for what a build packed).
  Bond bond(std::size_t i) const { return i < bonds.size() ? bonds[i] : unpack_bond(*this, packed_bonds[i - bonds.size()]); }
  const MeshTreeNode& leaf(LeafIndex i) const { return nodes[leaf_nodes[i]]; }
  /// The tree keeps the plane kernel's exact representation (geometry and every
  /// node's solid): every tree this version builds; not those of the retired
  /// kernels, read from old files.
  bool has_exact_representation() const { return !geometry.points.empty(); }
  /// The planes the nodes' exact solids are defined over (plane kernel); a view
  /// of `geometry` and `cut_planes`, valid while they are unchanged.
  PlaneSet plane_set() const { return geometry.plane_set(cut_planes); }
  /// A node's convex hull: its own mesh when it is convex, else `hull`. (A
  /// packed node's mesh is empty: read a lean tree's through NodeShapes.)
  const Mesh& hull_of(NodeIndex node) const { return nodes[node].convex ? *nodes[node].mesh : *nodes[node].hull; }
  /// Whether a lean build packed the node's mesh and solid (packed_shapes).
  bool is_packed(NodeIndex node) const { return node < packed_shapes.size() && !packed_shapes[node].empty(); }
};

/// A node's mesh and exact solid, as NodeShapes gives them.
struct NodeShape {
  const Mesh& mesh;
  const Solid& solid;
};

/// A node's mesh and its exact solid's point definitions (with their
/// approximations where the node keeps them; else empty), as
/// NodeShapes::mesh_and_points gives them.
struct NodePoints {
  const Mesh& mesh;
  std::span<const PointDef> defs;
  std::span<const ApproxPoint> approx;
};

/// A node's mesh with its positions left as the codes a lean build packed them
/// as (PositionCoder, against the solid's output positions in definition
/// order): `mesh` has no positions, `codes` one per vertex, `stored` the
/// positions of the codes PositionCoder::stored, in order.
struct NodeMeshCodes {
  const Mesh& mesh;
  std::span<const std::uint64_t> codes;
  std::span<const Vec3> stored;
};

/// Reads the nodes' meshes and solids one at a time, whether a node keeps its
/// own or a lean build packed them (MeshTree::packed_shapes): those are
/// unpacked into buffers reused from call to call, so a returned shape is valid
/// until the next call and while the tree is unchanged. One per thread.
class NodeShapes {
 public:
  explicit NodeShapes(const MeshTree& tree) : tree_(tree) {}
  /// Node `node`'s mesh and solid; a packed node's solid has no approx.
  /// Throws std::invalid_argument when its packed bytes do not unpack (a
  /// defect validate_tree reports; never in what the builder packs).
  NodeShape operator()(NodeIndex node);
  /// Node `node`'s solid alone (a packed node's mesh is not unpacked), valid
  /// as operator()'s shapes are; throws as it does.
  const Solid& solid(NodeIndex node);
  /// Node `node`'s mesh alone (a packed node's solid is not unpacked, nor its
  /// bytes checked), valid as operator()'s shapes are; throws as it does for a
  /// defect in the mesh's bytes.
  const Mesh& mesh(NodeIndex node);
  /// Node `node`'s mesh and its solid's point definitions alone (a packed
  /// node's faces, loops and corners are neither unpacked nor checked), for a
  /// reader of the positions the mesh refers to; valid as operator()'s shapes
  /// are; throws as it does for a defect in what it reads.
  NodePoints mesh_and_points(NodeIndex node);
  /// Node `node`'s mesh with its positions as codes, when it is packed with
  /// them coded (packed_positions_coded), without computing them: the file
  /// writer's MESH record, whose codes they are; std::nullopt for any other
  /// node. Valid until the next call; throws as mesh() does.
  std::optional<NodeMeshCodes> mesh_codes(NodeIndex node);

 private:
  void find_path(NodeIndex node);  // path_[d]: the node's ancestor at depth d

  const MeshTree& tree_;
  Mesh mesh_;
  Solid solid_;
  std::vector<NodeIndex> path_;
  bool path_is_chain_ = true;  // path_ holds a chain of parents (find_path)
  std::vector<std::uint64_t> codes_;
  std::vector<Vec3> stored_;
};

/// The surface id cap triangles of the cut at `node` carry.
inline SurfaceId cap_surface_of(NodeIndex node) { return node + 1; }

}  // namespace shatter
