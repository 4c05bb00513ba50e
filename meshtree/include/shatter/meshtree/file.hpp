#pragma once
// The .shatter file: a MeshTree stored exactly (every double as its IEEE-754 bit
// pattern), in a versioned little-endian binary layout with a CRC-32 per section,
// and a reader that refuses damaged, truncated or hostile files with
// CorruptFileError instead of crashing or allocating what the file claims.
//
// Layout, format version 1. Every integer is little-endian; f64 is the binary64
// bit pattern stored as a u64 (so NaN payloads and -0.0 survive); values are
// written byte by byte, so the bytes are the same on every host.
//
//   header, 12 bytes
//     0   8  magic 89 53 48 54 0D 0A 1A 0A ("\x89SHT\r\n\x1a\n", as PNG: the
//            high byte catches 7-bit transfers, CR LF and LF catch newline
//            translation, 1A stops DOS `type`)
//     8   4  u32 format version = 1
//   then sections, each 16 + L bytes
//     0   4  tag, four ASCII bytes
//     4   8  u64 L, the payload length
//     12  4  u32 CRC-32 of the payload (zlib's crc32, polynomial 0xEDB88320)
//     16  L  payload
//
// Sections, written in this order:
//   OPTS  BuildOptions, 27 bytes: u32 fragments, u64 seed, u8 strategy
//         (0 thesis, 1 balanced, 2 axis), u8 kernel (0 fast, 1 exact),
//         f64 interior_uv_scale, u32 max_plane_tries, u8 allow_self_intersections
//         (0 or 1). `threads` is not stored: it never changes a tree, and leaving
//         it out keeps files of one build byte-identical on every thread count; a
//         decoded tree has threads = 0.
//   NODE  u32 node count n (1 <= n <= 2^32 - 1), then per node in index order:
//         u32 parent (FFFFFFFF for the root), u32 depth, u32 first_leaf,
//         u32 leaf_count, u64 seed, u8 above_parent_plane (0 or 1),
//         f64 x4 plane (normal x, y, z, offset), f64 volume, f64 x3 centroid,
//         f64 x9 inertia (row-major), u32 child count c, u32 x c children;
//         165 + 4c bytes.
//   MESH  u32 n, then per node in index order its mesh:
//         u32 vertex count V, u32 triangle count T, u8 channels (bit 0 normals,
//         bit 1 uvs, bit 2 tangents; other bits 0), V x f64 x3 positions,
//         T x u32 x3 triangles, T x u32 surfaces, then the present channels in
//         that order, 3T values each (corner c of triangle t at 3t + c): normals
//         f64 x3, uvs f64 x2, tangents f64 x4.
//   HULL  the hulls, laid out as MESH.
//   BOND  u64 bond count B, then per bond: u32 first, u32 second, u32 cut_node,
//         f64 area, f64 x3 centroid, f64 x3 normal; 68 bytes.
//   END   empty payload; the last section, nothing may follow it.
// leaf_nodes is not stored: it is the leaves in node order, recomputed on reading
// and checked against every node's first_leaf and leaf_count.
//
// Reading rules. OPTS, NODE, MESH, HULL, BOND must each occur exactly once, in any
// order, before END. An unknown tag whose first byte is a lower-case ASCII letter
// marks optional data a later version may add: its checksum is verified and it is
// skipped. Any other unknown tag is refused, so data a reader would misunderstand
// is never silently dropped. A version other than 1 is refused; a later version
// that only adds optional sections keeps version 1.

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

#include "shatter/meshtree/tree.hpp"

namespace shatter {

/// The version encode_shatter writes and the only one decode_shatter reads.
inline constexpr std::uint32_t shatter_format_version = 1;

/// The bytes of the .shatter file of `tree` (layout above).
/// Precondition: `tree` is valid, i.e. passes every check decode_shatter makes
/// (as every tree build_mesh_tree returns does); otherwise throws
/// std::invalid_argument naming the first defect, so no file is ever written
/// that could not be read back.
/// Guarantees: deterministic (equal trees give equal bytes; `threads` is
/// ignored), and decode_shatter returns a tree equal to `tree` field by field,
/// every double bit for bit, except options.threads, which comes back 0.
std::string encode_shatter(const MeshTree& tree);

/// The tree stored in `bytes`.
/// Throws CorruptFileError, with a one-line message naming the defect and its
/// place (section and byte offset), when the bytes are not a .shatter file, are
/// of another version, truncated, fail a checksum, or decode to a tree that breaks
/// any MeshTree invariant: node 0 the root without a parent; parent and children
/// links consistent, nodes in depth-first preorder, internal nodes with two or
/// more children, depth = parent's depth + 1; leaf ranges contiguous and
/// consistent with the children; every triangle index < its mesh's vertex count
/// (surfaces and attribute channels sized by construction); bonds with
/// first < second < leaf count, sorted by (first, second, cut_node), cut_node the
/// internal node whose cut separates the two leaves; enum and bool bytes in range.
/// Never reads outside `bytes`, and never allocates more than a small multiple of
/// bytes.size(), whatever the counts in the file claim.
/// Guarantees: the result can be trusted by the rest of the library, and
/// encode_shatter of it gives `bytes` back for any file encode_shatter wrote.
MeshTree decode_shatter(std::string_view bytes);

/// Writes encode_shatter(tree) to `path` atomically (write_file_atomically):
/// `path` is either untouched or complete. Throws IoError when it cannot be
/// written, std::invalid_argument as encode_shatter.
void write_shatter_file(const std::filesystem::path& path, const MeshTree& tree);

/// Reads and decodes the .shatter file at `path`. Throws IoError when it cannot
/// be opened or read, CorruptFileError (message prefixed by the path) when its
/// content is refused by decode_shatter.
MeshTree read_shatter_file(const std::filesystem::path& path);

}  // namespace shatter
