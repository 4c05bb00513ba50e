#pragma once
// Exports of a mesh tree for other tools: one mesh file per chosen node (OFF, OBJ,
// PLY, STL through kernel/io.hpp), or the whole tree as one binary glTF (GLB) for
// viewers and game engines. Which nodes are written is a NodeSelection: the
// fragments, every level, or the cut of the tree at one depth.

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "shatter/kernel/io.hpp"
#include "shatter/meshtree/tree.hpp"

namespace shatter {

// --- node selection ------------------------------------------------------------

enum class NodeSelectionKind : std::uint8_t {
  /// The fragments: every leaf, in leaf order.
  leaves,
  /// Every node of the tree, in preorder (the levels overlap: not a partition).
  all,
  /// The tree cut at depth K: the nodes at depth K plus the leaves shallower than
  /// K. Their leaf ranges partition the leaves, so together they are the whole
  /// solid once: depth 0 is the root alone, a K beyond the deepest leaf gives the
  /// leaves.
  depth,
};

/// Which nodes an export writes: "leaves", "all" or "depth:K".
struct NodeSelection {
  NodeSelectionKind kind = NodeSelectionKind::leaves;
  std::uint32_t depth = 0;  ///< K; meaningful for NodeSelectionKind::depth only

  friend bool operator==(const NodeSelection&, const NodeSelection&) = default;
};

/// Parses "leaves", "all" or "depth:K" (K a decimal integer 0 ... 2^32 - 1, no
/// sign or spaces; lower case only). Throws std::invalid_argument naming the
/// accepted forms otherwise.
NodeSelection parse_node_selection(std::string_view text);

/// The text parse_node_selection reads back: "leaves", "all" or "depth:K".
std::string node_selection_name(const NodeSelection& selection);

/// The selected nodes in preorder (which for leaves is leaf order), each once.
/// For leaves and depth:K the leaf ranges of the result are disjoint and cover
/// [0, leaf_count). An empty tree gives an empty list.
std::vector<NodeIndex> select_nodes(const MeshTree& tree, const NodeSelection& selection);

// --- mesh files ----------------------------------------------------------------

/// How written mesh files are named.
enum class FileNaming : std::uint8_t {
  /// `leaf-0007.off`: the leaf index, zero-padded to at least 4 digits (more
  /// when the tree has 10,000 leaves or more, the same width for every file of
  /// the tree, so names sort in leaf order). Every named node must be a leaf.
  by_leaf,
  /// `node-00012.off`: the node index, zero-padded to at least 5 digits (more
  /// for larger trees, the same width for every file of the tree).
  by_node,
};

/// by_leaf for the leaves selection, by_node otherwise (the nodes of depth:K or
/// all are not all leaves, and node indices tell the levels apart).
FileNaming file_naming_for(const NodeSelection& selection);

/// The file name (no folder) of `node` under `naming`, with the format's
/// extension. Throws std::invalid_argument for a node index out of range, or
/// a node that is not a leaf under by_leaf.
std::string mesh_file_name(const MeshTree& tree, NodeIndex node, FileNaming naming, MeshFormat format);

/// Writes the mesh of every node in `selection` into `folder` (created if
/// missing) as `format`, named by mesh_file_name, and returns the paths in
/// selection order. Each file is written atomically (write_mesh); if one fails,
/// the files this call wrote are removed before the error propagates, so the
/// folder holds all of them or none (a file of the same name that existed before
/// has been replaced, though, and is gone then too). Throws IoError on a write
/// failure, std::invalid_argument as mesh_file_name does (before writing anything).
std::vector<std::filesystem::path> write_mesh_files(const MeshTree& tree, std::span<const NodeIndex> selection,
                                                    const std::filesystem::path& folder, MeshFormat format,
                                                    FileNaming naming);

// --- glTF binary ---------------------------------------------------------------

/// The material names of the GLB: material 0 for the original surface, 1 for caps.
inline constexpr std::string_view glb_exterior_material = "exterior";
inline constexpr std::string_view glb_interior_material = "interior";

/// Encodes the tree as a glTF 2.0 binary (GLB) file's bytes.
///
/// Layout: one scene whose single root is glTF node 0; glTF node i is tree node i,
/// its children those of the tree node, named "leaf L" for leaf L and "node i"
/// otherwise, with identity transforms (meshes are in world coordinates). Each
/// node's `extras` holds {"tree_node", "depth", "first_leaf", "leaf_count",
/// "volume", "centroid" [x, y, z] (of volume), "triangles", "cap_triangles"},
/// plus "leaf" for a leaf or "plane" [nx, ny, nz, d] (the cut n·x + d = 0) for an
/// internal node. The scene's `extras` holds {"shatter_version", "leaves",
/// "bonds"}, each bond {"first", "second" (leaf indices), "cut_node", "area",
/// "centroid" [x, y, z], "normal" [x, y, z]} as MeshTree::bonds has them. The
/// nodes in `selection` get a mesh of up to two triangle primitives: the original
/// surface (surface id 0) with material 0 "exterior", and the caps (surface id >
/// 0) with material 1 "interior"; an empty primitive is left out (the root has no
/// caps), and a node without triangles gets no mesh.
///
/// glTF stores vertices as 32-bit floats, so positions are rounded to float here:
/// a GLB is for looking at, never for getting exact geometry back (use the
/// .shatter file or mesh files for that). Every vertex has a NORMAL, so every
/// viewer shades it: on the original surface the mesh's per-corner normals where
/// it has them, else each triangle's own (flat shading); on caps the cut plane's
/// unit normal pointing out of the node, so a cap is flat and its crease with the
/// surface stays sharp. UVs (as (u, 1 - v): glTF's v axis points down the image,
/// OBJ's and PLY's up) and tangents are exported where the mesh has them. Each
/// welded vertex is split into one glTF vertex per distinct combination of normal
/// and attributes. Indices are UNSIGNED_INT; POSITION accessors carry min and max.
///
/// Deterministic: the same tree and selection give the same bytes. Throws
/// std::invalid_argument for a selected or child node index out of range,
/// InvalidMeshError for a mesh whose indices or attribute channels are out of
/// range, std::length_error when the result would exceed GLB's 4 GiB limit.
std::string encode_glb(const MeshTree& tree, std::span<const NodeIndex> selection);

/// Writes encode_glb(tree, selection) to `path` atomically (temporary file, then
/// rename), creating its folder if missing. Throws IoError on a write failure,
/// and what encode_glb throws (before touching the file system).
void write_glb(const std::filesystem::path& path, const MeshTree& tree, std::span<const NodeIndex> selection);

}  // namespace shatter
