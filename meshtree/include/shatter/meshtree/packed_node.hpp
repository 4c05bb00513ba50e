#pragma once
// The compact form a lean build (BuildRunOptions::lean) keeps an internal
// node's mesh and exact solid in once it is cut: a few hundred bytes instead of
// the arrays' kilobyte and more. Nothing below the node needs them again; the
// writer, the validator and fill_tree_caches unpack one node at a time
// (NodeShapes, tree.hpp).

#include <cstdint>
#include <span>
#include <vector>

#include "shatter/kernel/implicit.hpp"
#include "shatter/kernel/mesh.hpp"
#include "shatter/kernel/solid.hpp"
#include "shatter/meshtree/tree_index.hpp"

namespace shatter {

/// Codes positions against source positions, as a packed node codes its
/// mesh's against its solid's and the .shatter file its MESH and HULL records'
/// (one coder, so a packed node's codes are the file's): position v's code is
/// 0 when no source has its bits (the position is then kept beside the code),
/// else 1 + zigzag(s - v) for the source s found first among: the one the
/// previous code pointed to (s - v unchanged), s = v, and the lowest index of
/// the sources equal to it bit for bit (a hash table of them, made at the first
/// such search). A function of the positions coded so far and the sources.
class PositionCoder {
 public:
  static constexpr std::uint64_t stored = 0;
  /// `sources` must outlive the coder.
  explicit PositionCoder(std::span<const Vec3> sources) : sources_(sources) {}
  /// The code of vertex `vertex` at `position`; vertices are coded in order.
  std::uint64_t code(std::size_t vertex, Vec3 position);
  /// The source index a code other than `stored` names for `vertex` (it may lie
  /// outside the sources: a reader checks).
  static std::int64_t source_of(std::size_t vertex, std::uint64_t code);

 private:
  std::int64_t search(Vec3 position);
  std::size_t slot_of(Vec3 position) const;

  std::span<const Vec3> sources_;
  std::int64_t offset_ = 0;
  std::vector<std::uint32_t> slots_;  // into sources_; empty_slot where none
  static constexpr std::uint32_t empty_slot = ~std::uint32_t{0};
};

/// Packs `mesh` and `solid` into bytes: every count and index as a varint,
/// positions and corner attributes bit for bit, plane references and surface
/// ids as given (the builder names a cut plane by its node's depth, a cap by
/// that depth + 1). Solid::approx is not kept (it is recomputed from the
/// definitions). `named_by_node`: the references already name the tree's
/// nodes (a finished tree's leaf, pack_leaves), and unpacking keeps them
/// whatever its path. Given `set` (the planes the solid's definitions name)
/// and a solid with its approximations, the mesh's positions are coded
/// against the solid's output positions (PositionCoder; output_position of
/// each definition), a byte or two each where they took 24, and unpacking
/// computes them again (it then needs the tree's plane set). Deterministic:
/// equal inputs give equal bytes. Guarantees: unpack_node_shape with an empty
/// path (and `set`, for coded positions) gives `mesh` and `solid` back exactly,
/// but for an empty approx, provided the solid's definitions keep the PointDef
/// convention (unused fields zero) and its approximations are approximate()'s.
std::vector<std::uint8_t> pack_node_shape(const Mesh& mesh, const Solid& solid, bool named_by_node = false,
                                          const PlaneSet* set = nullptr);
/// pack_node_shape into `bytes` (cleared first; its capacity kept), the same
/// bytes: a caller that copies them on (the builder, into its blocks) reuses one
/// buffer instead of growing a fresh array a node.
void pack_node_shape(const Mesh& mesh, const Solid& solid, bool named_by_node, std::vector<std::uint8_t>& bytes,
                     const PlaneSet* set = nullptr);

/// Whether pack_node_shape coded these bytes' positions (their unpacking then
/// needs a plane set). Throws std::invalid_argument for empty bytes.
bool packed_positions_coded(std::span<const std::uint8_t> bytes);

/// Unpacks what pack_node_shape packed into `mesh` and `solid` (their previous
/// contents replaced; solid.approx left empty). With a non-empty `path`, each
/// cut plane reference PlaneRef::cut(d) becomes PlaneRef::cut(path[d]) and each
/// surface id s > 0, in the mesh and the solid's faces, cap_surface_of(path[s -
/// 1]): the builder's names by depth become the tree's by node, as number_tree
/// renames an unpacked node's (`path[d]`: the node's ancestor at depth d).
/// Coded positions are computed from the definitions so renamed, in `set`
/// (MeshTree::plane_set() for a tree's node; what was packed with an empty
/// path). Throws std::invalid_argument when the bytes are not such a packing
/// (cut short, trailing bytes, a depth outside `path`, a code naming no
/// definition) or its positions are coded and `set` is null: a defect, never
/// reached from what the builder packs.
void unpack_node_shape(std::span<const std::uint8_t> bytes, std::span<const NodeIndex> path, Mesh& mesh,
                       Solid& solid, const PlaneSet* set = nullptr);

/// unpack_node_shape's solid alone: the mesh's bytes are read past (and
/// checked as there), not unpacked, for a reader that needs only the exact
/// solid (the bonds). Throws as unpack_node_shape does.
void unpack_node_solid(std::span<const std::uint8_t> bytes, std::span<const NodeIndex> path, Solid& solid);

/// unpack_node_shape's mesh alone, for a reader that needs only the mesh (the
/// file writer's mass check and hulls): the reading stops where the solid's
/// bytes begin, or, for coded positions, after its point definitions (those
/// bytes checked as unpack_node_shape checks them; the rest neither read nor
/// checked). Throws as unpack_node_shape does for a defect in what it reads.
void unpack_node_mesh(std::span<const std::uint8_t> bytes, std::span<const NodeIndex> path, Mesh& mesh,
                      const PlaneSet* set = nullptr);

/// unpack_node_shape's mesh and the solid's point definitions alone, into
/// `mesh` and `points.defs` (points' faces, loops and corners emptied, its
/// approx left empty): the reading stops after the definitions, whose bytes are
/// checked as unpack_node_shape checks them; the rest is neither read nor
/// checked. For a reader of the positions a mesh refers to (the file writer's
/// MESH records). Throws as unpack_node_shape does for a defect in what it reads.
void unpack_node_mesh_and_points(std::span<const std::uint8_t> bytes, std::span<const NodeIndex> path, Mesh& mesh,
                                 Solid& points, const PlaneSet* set = nullptr);

/// unpack_node_shape's mesh with its positions left as their codes (`mesh`'s
/// positions emptied; `codes` one per vertex, PositionCoder's, against the
/// solid's output positions in definition order; `stored` the positions of the
/// codes PositionCoder::stored, in order), no definition read: the file
/// writer's MESH record of a coded packing, whose codes are the record's.
/// Precondition: packed_positions_coded(bytes). Throws as unpack_node_mesh does
/// for a defect in the mesh's bytes (a code's source is not checked here).
void unpack_node_mesh_codes(std::span<const std::uint8_t> bytes, std::span<const NodeIndex> path, Mesh& mesh,
                            std::vector<std::uint64_t>& codes, std::vector<Vec3>& stored);

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
