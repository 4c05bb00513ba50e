#pragma once
// The compact form a lean build (BuildRunOptions::lean) keeps an internal
// node's mesh and exact solid in once it is cut: a few hundred bytes instead of
// the arrays' kilobyte and more. Nothing below the node needs them again; the
// writer, the validator and fill_tree_caches unpack one node at a time
// (NodeShapes, tree.hpp).

#include <cstdint>
#include <span>
#include <vector>

#include "shatter/kernel/mesh.hpp"
#include "shatter/kernel/solid.hpp"
#include "shatter/meshtree/tree_index.hpp"

namespace shatter {

/// Packs `mesh` and `solid` into bytes: every count and index as a varint,
/// positions and corner attributes bit for bit, plane references and surface
/// ids as given (the builder names a cut plane by its node's depth, a cap by
/// that depth + 1). Solid::approx is not kept (it is recomputed from the
/// definitions). `named_by_node`: the references already name the tree's
/// nodes (a finished tree's leaf, pack_leaves), and unpacking keeps them
/// whatever its path. Deterministic: equal inputs give equal bytes.
/// Guarantees: unpack_node_shape with an empty path gives `mesh` and `solid`
/// back exactly, but for an empty approx, provided the solid's definitions keep
/// the PointDef convention (unused fields zero).
std::vector<std::uint8_t> pack_node_shape(const Mesh& mesh, const Solid& solid, bool named_by_node = false);
/// pack_node_shape into `bytes` (cleared first; its capacity kept), the same
/// bytes: a caller that copies them on (the builder, into its blocks) reuses one
/// buffer instead of growing a fresh array a node.
void pack_node_shape(const Mesh& mesh, const Solid& solid, bool named_by_node, std::vector<std::uint8_t>& bytes);

/// Unpacks what pack_node_shape packed into `mesh` and `solid` (their previous
/// contents replaced; solid.approx left empty). With a non-empty `path`, each
/// cut plane reference PlaneRef::cut(d) becomes PlaneRef::cut(path[d]) and each
/// surface id s > 0, in the mesh and the solid's faces, cap_surface_of(path[s -
/// 1]): the builder's names by depth become the tree's by node, as number_tree
/// renames an unpacked node's (`path[d]`: the node's ancestor at depth d).
/// Throws std::invalid_argument when the bytes are not such a packing (cut
/// short, trailing bytes, a depth outside `path`): a defect, never reached from
/// what the builder packs.
void unpack_node_shape(std::span<const std::uint8_t> bytes, std::span<const NodeIndex> path, Mesh& mesh,
                       Solid& solid);

/// unpack_node_shape's solid alone: the mesh's bytes are read past (and
/// checked as there), not unpacked, for a reader that needs only the exact
/// solid (the bonds). Throws as unpack_node_shape does.
void unpack_node_solid(std::span<const std::uint8_t> bytes, std::span<const NodeIndex> path, Solid& solid);

/// unpack_node_shape's mesh alone: the reading stops where the solid's bytes
/// begin, which are neither read nor checked, for a reader that needs only the
/// mesh (the file writer's mass check and hulls). Throws as unpack_node_shape
/// does for a defect in the mesh's bytes.
void unpack_node_mesh(std::span<const std::uint8_t> bytes, std::span<const NodeIndex> path, Mesh& mesh);

/// unpack_node_shape's mesh and the solid's point definitions alone, into
/// `mesh` and `points.defs` (points' faces, loops and corners emptied, its
/// approx left empty): the reading stops after the definitions, whose bytes are
/// checked as unpack_node_shape checks them; the rest is neither read nor
/// checked. For a reader of the positions a mesh refers to (the file writer's
/// MESH records). Throws as unpack_node_shape does for a defect in what it reads.
void unpack_node_mesh_and_points(std::span<const std::uint8_t> bytes, std::span<const NodeIndex> path, Mesh& mesh,
                                 Solid& points);

/// A packed mesh's sizes: its vertices, its triangles, and those of them on a
/// cut's cap (any surface but the input's).
struct PackedMeshSizes {
  std::size_t vertices = 0;
  std::size_t triangles = 0;
  std::size_t cap_triangles = 0;
};

/// The sizes of the mesh pack_node_shape packed into `bytes`, read from its
/// counts and surface runs, without unpacking it (tree_stats counts a lean
/// tree's leaves so). Equal to the counts of the mesh unpack_node_mesh gives,
/// under any path. Throws std::invalid_argument when the mesh's bytes are not
/// such a packing (cut short, a count beyond the bytes, surface runs beyond the
/// triangles).
PackedMeshSizes packed_mesh_sizes(std::span<const std::uint8_t> bytes);

struct MeshTree;

/// Packs every leaf's mesh and solid of a tree with an exact representation
/// into MeshTree::packed_shapes (named by node), for a caller that only
/// writes the tree, sums it up and reads it through NodeShapes (`shatter
/// fracture`, once the bonds are found and the leaves exported): a lean
/// build's tree then keeps no node's arrays. Nothing else changes: the same
/// file bytes, and fill_tree_caches unpacks them back. A certificate that held
/// (MeshTree::certificate) still holds after: packing is lossless. Does nothing
/// to a tree without an exact representation.
void pack_leaves(MeshTree& tree);

/// Renames a node's cut plane references and cap surface ids from the
/// builder's depths to the tree's nodes, as unpack_node_shape does with a
/// path: cut(d) becomes cut(path[d]), surface s > 0 cap_surface_of(path[s - 1]).
/// Precondition: every depth named is < path.size().
void rename_by_path(std::span<const NodeIndex> path, Mesh& mesh, Solid& solid);

}  // namespace shatter
