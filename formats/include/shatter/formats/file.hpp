#pragma once
// The .shatter file: a MeshTree stored exactly (every double as its IEEE-754 bit
// pattern), in a versioned little-endian binary layout with a CRC-32 per section,
// and a reader that refuses damaged, truncated or hostile files with
// CorruptFileError instead of crashing or allocating what the file claims.
//
// Layout, format version 3 (versions 1 and 2, still read, are described after
// it). Every fixed-size integer is little-endian; f64 is the binary64 bit
// pattern stored as a u64 (so NaN payloads and -0.0 survive); vu is an unsigned
// LEB128 varint: seven bits a byte, the low group first, the high bit set on
// every byte but the last (the writer uses the shortest form; a reader refuses
// a value wider than its field, 32 bits unless said). The bytes are the same on
// every host.
//
//   header, 12 bytes
//     0   8  magic 89 53 48 54 0D 0A 1A 0A ("\x89SHT\r\n\x1a\n", as PNG: the
//            high byte catches 7-bit transfers, CR LF and LF catch newline
//            translation, 1A stops DOS `type`)
//     8   4  u32 format version = 3
//   then sections, each 16 + L bytes
//     0   4  tag, four ASCII bytes
//     4   8  u64 L, the payload length
//     12  4  u32 CRC-32 of the payload (zlib's crc32, polynomial 0xEDB88320)
//     16  L  payload
//
// Values that follow from the rest are not stored where they equal their
// derivation bit for bit (the writer checks; a section's flags say where it
// stores them instead), so every valid tree round-trips exactly. Indices are
// relative to the node being written: a node's solid names a cut plane by how
// many levels up its node is, as preorder visits a node's ancestors first.
//   plane code (vu, 64 bits): 0 none (PlaneRef FFFFFFFF), 2i + 1 input plane
//         i, 2d (1 <= d <= D, the node's depth) the cut plane of the ancestor d
//         levels up, 2(D + 1 + c) cell plane c (CELL; cut plane n + c).
//   surface code (vu, 64 bits) in a node of depth D: 0 the input's surface,
//         1 <= c <= D cap_surface_of(the ancestor c levels up), D + s any
//         other surface id s.
//   position code (vu, 64 bits) of vertex i: 0, then f64 x3, the position;
//         else c: the position of source s = i + unzigzag(c - 1) (unzigzag(z)
//         = (z >> 1) XOR -(z AND 1)); for MESH the sources are the node's solid
//         vertices, placed by output_position (kernel/implicit.hpp), for HULL the
//         node's mesh positions. The writer takes the source at the previous
//         vertex's offset s - i if its position matches, else s = i, else the
//         lowest-numbered match.
//
// Sections, written in this order:
//   vers  optional: the shatter version that built the tree, as text: 1 to 64
//         bytes of printable ASCII without spaces (0x21-0x7E), e.g. "0.1.0".
//         Written only when the tree has one (every built tree does).
//   rpar  optional: how the input was repaired (MeshTree::input_repair; written
//         only when it holds a change or a note, i.e. `fracture --repair` changed
//         the input): u64 x4 vertex and triangle counts before, then after; u32
//         change count C, C x (u8 kind, the position in all_repair_kinds of
//         kernel/repair.hpp; u64 count; text); u32 note count, each a text. A
//         text is u32 length and 1 to 4,096 bytes without control characters
//         (below 0x20, 0x7F). A section with neither change nor note is refused.
//   OPTS  TreeRecipe, 27 bytes: u32 fragments, u64 seed, u8 strategy
//         (0 thesis, 1 balanced, 2 axis), u8 kernel (0 fast, 1 exact, 2 plane),
//         f64 interior_uv_scale, u32 max_plane_tries, u8 allow_self_intersections
//         (0 or 1). How the build ran (threads, ...) is no part of the tree.
//         max_plane_tries reads the same from every file; since issue 17 a
//         plane is no longer redrawn for a piece that vanishes in the rounding
//         (TreeRecipe::max_plane_tries says what it bounds now).
//   patt  optional: TreeRecipe::pattern, how a Voronoi tree's sites were made,
//         as text: 1 to 1024 bytes of printable ASCII (0x20-0x7E). Written only
//         when the recipe has one (`fracture --pattern` other than planes).
//   NODE  u32 node count n (>= 1), u8 flags (bit 0 seeds stored, bit 1 masses
//         stored, bit 2 leaves' planes stored; other bits 0), then per node in
//         preorder: vu (c << 1 | above_parent_plane), 64 bits, c its child count; f64 x4
//         its cut plane (normal x, y, z, offset) when c > 0 or bit 2; u64 seed
//         when bit 0; f64 volume, f64 x3 centroid, f64 x9 inertia (row-major)
//         when bit 1. A node's children are the next c subtrees in preorder, which
//         gives parent, children, depth, first_leaf and leaf_count. Derived: the
//         seeds root_node_seed(OPTS seed) and child_node_seed(parent's, index)
//         (recipe.hpp), the masses mass_properties of the node's mesh
//         (kernel/mass.hpp), a leaf's plane +0.0 x4.
//   CELL  only in a tree with cell planes (meshtree/voronoi.hpp: MeshTree::
//         cut_planes holds more planes than nodes): u32 count C, then C x f64 x4
//         (normal x, y, z, offset), cut planes n to n + C - 1. At most once;
//         upper case, so a reader without it refuses the file.
//   GEOM  as version 2: u32 point count P, u32 input plane count Q, P x f64 x3
//         points, Q x u32 x3 input planes (point indices); P = 0: no exact
//         representation (trees of the retired kernels).
//   SOLD  u32 record count, 0 when P = 0, else n; per node in preorder:
//           u8 flags (bit 0 MeshTreeNode::convex, bit 1 Solid::convex),
//           vu vertex count V, vu face count F, vu loop count L, vu corner count C
//           V x vertex: u8 kind, then kind 0 (input) vu point; kind 1
//              (segment_plane) vu point a, vu point b, plane code; kind 2
//              (three_planes) three plane codes
//           F x face: plane code, u8 flags (bit 0 reversed, bit 1 convex),
//              surface code, vu source, vu loop count
//           L x loop: vu corner count
//           C x corner: vu (vertex << 2 | m), 64 bits; m = 0: its line is the
//              plane of the face holding the reverse edge (from the next corner's
//              vertex in its loop to this one), no segment; m = 1: plane code of
//              line.other, no segment; m = 2: plane code, vu p, vu q (the input
//              segment); m = 3 is refused. The writer uses 0 wherever it holds.
//         Faces take their loops and loops their corners in order, as version 2.
//   MESH  u32 n, then per node in preorder its mesh: vu vertex count V, vu
//         triangle count T, u8 channels (bit 0 normals, bit 1 uvs, bit 2
//         tangents; all 0 when T = 0), V position codes, 3T vertex indices of w
//         bytes each, little-endian (w = 1 when V <= 256, 2 when V <= 65,536,
//         else 4), vu R and R runs of surfaces: surface code, vu run length >= 1,
//         covering the T triangles in order; then the present channels as version
//         2 (3T values each: normals f64 x3, uvs f64 x2, tangents f64 x4).
//   HULL  the hulls, laid out as MESH (position sources: the node's mesh). A
//         convex node has an empty hull.
//   BOND  u64 bond count B, u8 flags (bit 0 normals stored; other bits 0), per
//         bond in order: vu (first - the previous bond's first; the first bond's
//         first), 64 bits, vu ((second - first - 1) << 2 | a), 64 bits, f64 area, then the
//         centroid: a = 3: f64 x3; else f64 u, f64 v, the coordinates (a + 1) % 3
//         and (a + 2) % 3, and coordinate a solved from the cut plane by
//         point_on_plane_over (kernel/vec.hpp); then f64 x3 normal when bit 0.
//         Derived: cut_node, the deepest node holding both leaves; the normal,
//         the cut plane's normal / |normal| (normalized), negated when first lies
//         above the plane. The writer tries a over the axes by decreasing
//         |normal component| (ties: the lower axis first).
//   END   empty payload; the last section, nothing may follow it.
//
// Layout, format version 2 (read only; version 1 is version 2 without the GEOM
// and SOLD sections; see "Versions" below). Every integer is little-endian; f64 is the
// binary64 bit pattern stored as a u64 (so NaN payloads and -0.0 survive); values
// are written byte by byte, so the bytes are the same on every host.
//
//   header, 12 bytes
//     0   8  magic 89 53 48 54 0D 0A 1A 0A ("\x89SHT\r\n\x1a\n", as PNG: the
//            high byte catches 7-bit transfers, CR LF and LF catch newline
//            translation, 1A stops DOS `type`)
//     8   4  u32 format version = 2
//   then sections, each 16 + L bytes
//     0   4  tag, four ASCII bytes
//     4   8  u64 L, the payload length
//     12  4  u32 CRC-32 of the payload (zlib's crc32, polynomial 0xEDB88320)
//     16  L  payload
//
// Sections, written in this order:
//   vers  optional (see the reading rules): the shatter version that built the
//         tree, MeshTree::shatter_version, as text: 1 to 64 bytes of printable
//         ASCII without spaces (0x21-0x7E), e.g. "0.1.0", no terminator. Written
//         only when the tree has one (every built tree does).
//   OPTS  TreeRecipe, 27 bytes: u32 fragments, u64 seed, u8 strategy
//         (0 thesis, 1 balanced, 2 axis), u8 kernel (0 fast, 1 exact, 2 plane),
//         f64 interior_uv_scale, u32 max_plane_tries, u8 allow_self_intersections
//         (0 or 1). How the build ran (BuildRunOptions: threads, ...) is no part
//         of the tree, so files of one recipe are byte-identical on every
//         thread count.
//   NODE  u32 node count n (1 <= n <= 2^32 - 1), then per node in index order:
//         u32 parent (FFFFFFFF for the root), u32 depth, u32 first_leaf,
//         u32 leaf_count, u64 seed, u8 above_parent_plane (0 or 1),
//         f64 x4 plane (MeshTree::cut_planes[k]: normal x, y, z, offset),
//         f64 volume, f64 x3 centroid, f64 x9 inertia (row-major), u32 child
//         count c, u32 x c children; 165 + 4c bytes.
//   MESH  u32 n, then per node in index order its mesh:
//         u32 vertex count V, u32 triangle count T, u8 channels (bit 0 normals,
//         bit 1 uvs, bit 2 tangents; other bits 0; all 0 when T = 0, since a
//         channel is present only with values), V x f64 x3 positions,
//         T x u32 x3 triangles, T x u32 surfaces, then the present channels in
//         that order, 3T values each (corner c of triangle t at 3t + c): normals
//         f64 x3, uvs f64 x2, tangents f64 x4.
//   HULL  the hulls, laid out as MESH. A convex node (SOLD) has an empty hull.
//   BOND  u64 bond count B, then per bond: u32 first, u32 second, u32 cut_node,
//         f64 area, f64 x3 centroid, f64 x3 normal; 68 bytes.
//   GEOM  MeshTree::geometry, the plane kernel's input: u32 point count P,
//         u32 input plane count Q, P x f64 x3 points (x, y, z), Q x u32 x3
//         input planes (three point indices); 8 + 24P + 12Q bytes. P = 0 means
//         the tree has no exact representation (the retired fast and exact
//         kernels' trees): then
//         Q = 0 too, and the payload is 8 zero bytes.
//   SOLD  the nodes' exact solids: u32 record count, 0 when P = 0, else n; then
//         per node in index order (only when there are records):
//           u8 flags: bit 0 MeshTreeNode::convex, bit 1 Solid::convex; other
//              bits 0
//           u32 vertex count V, u32 face count F, u32 loop count L,
//           u32 corner count C
//           V x vertex definition (PointDef), 13 bytes: u8 kind, u32 x3 fields
//              kind 0 input:         point a, 0, 0
//              kind 1 segment_plane: point a, point b, plane
//              kind 2 three_planes:  plane, plane, plane
//           F x face (SolidFace), 17 bytes: u32 plane, u8 flags (bit 0
//              reversed, bit 1 convex; other bits 0), u32 surface, u32 source,
//              u32 loop count
//           L x loop (SolidLoop), 4 bytes: u32 corner count
//           C x corner (SolidCorner), 9 or 17 bytes: u32 vertex, u32
//              line.other (a plane, or FFFFFFFF for none), u8 segment (0 or
//              1), then only when segment is 1: u32 line.p, u32 line.q (input
//              points p < q; with segment 0 both are none, FFFFFFFF)
//         17 + 13V + 17F + 4L + 9C + 8S bytes, S the corners with a segment
//         (input edges: few, once cuts dominate). A plane is a PlaneRef: bit 31 set,
//         cut plane (the plane of the node whose index is in bits 0-30); clear,
//         input plane (an index into GEOM's planes). Faces take their loops and
//         loops their corners in order: face f's first loop is the sum of the
//         loop counts of faces before it, and likewise for loops' first corners.
//   END   empty payload; the last section, nothing may follow it.
// Not stored in any version, recomputed on reading: leaf_nodes (the leaves in node order, checked
// against every node's first_leaf and leaf_count); and the floating-point
// caches InputGeometry::plane_approx (approximate_input_plane of each input
// plane's points) and Solid::approx (approximate() of each vertex over
// MeshTree::plane_set()), which are deterministic functions of what is stored.
//
// Reading rules. OPTS, NODE, MESH, HULL, BOND and (versions 2 and 3) GEOM, SOLD must
// each occur exactly once, in any order, before END. An unknown tag whose first byte is a lower-case
// ASCII letter marks optional data a later version may add: its checksum is
// verified and it is skipped. Any other unknown tag is refused, so data a reader
// would misunderstand is never silently dropped. `vers` is optional data this
// reader knows: it may occur at most once, anywhere before END, in a file of
// any version, and a payload outside its rule is refused; a file without it
// reads with an empty shatter_version. `rpar` follows the same rule: at most once, anywhere before
// END in any version, its payload as above or refused; without it a tree reads
// with an empty input_repair. (A damaged `vers` or `rpar` tag that still
// starts with a lower-case letter is an unknown optional section, so such a file
// reads as the same tree without its version or repair record: the one
// single-byte change a reader cannot see, and it loses nothing else.)
//
// Versions. Version 2 added GEOM and SOLD (the plane kernel's exact
// representation, so a tree can be re-cut exactly) and kernel 2 in OPTS. A
// version 1 file has the first five sections only (GEOM and SOLD are unknown
// tags there, and refused); it reads as a tree without an exact representation,
// and encode_shatter writes that tree as version 2: for a file as version 1's
// encoder laid it out, the same bytes with version 2 and, before END, a GEOM
// section of 8 zero bytes and a SOLD section of 4. Any other version is refused;
// a later version that only adds optional sections keeps its number. So `vers`
// (shatter 0.1.0) did not change it: the version is information, not something
// a reader needs to understand the tree, and as an optional section it is
// skipped by the version 2 readers written before it, which therefore read the
// files written since. (Growing OPTS instead would have made those readers
// refuse every new file: its size is fixed.)
// Version 3 keeps the sections and their tags and recodes five payloads (NODE,
// SOLD, MESH, HULL, BOND) as above: varints, indices relative to the node, and
// no value a reader can derive. The cube cut into 65,536 fragments takes 41.5 MB
// instead of 190.7. Files of versions 1 and 2 read as before; encode_shatter
// writes what they hold as version 3.

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

#include "shatter/kernel/atomic_file.hpp"
#include "shatter/meshtree/tree.hpp"

namespace shatter {

/// The version encode_shatter writes; decode_shatter reads it and every
/// version back to shatter_oldest_format_version.
inline constexpr std::uint32_t shatter_format_version = 3;
/// The oldest version decode_shatter reads.
inline constexpr std::uint32_t shatter_oldest_format_version = 1;

/// The bytes of the .shatter file of `tree` (layout above), always of version
/// shatter_format_version.
/// Precondition: `tree` passes validate_tree (validate_tree.hpp), caches
/// included, as every tree build_mesh_tree returns does: every check
/// decode_shatter makes holds, and the caches are what the reader will
/// recompute: geometry.plane_approx[j] is approximate_input_plane of input plane
/// j's points and every solid's approx[v] is approximate() of its definition
/// over plane_set(), bit for bit (checked, at the cost of recomputing them), or
/// the solid has no approx at all (a lean build's, BuildRunOptions::lean: the
/// writer computes what it needs; the bytes are those of the full tree).
/// Otherwise throws std::invalid_argument with the defect's message, so no file
/// is ever written that could not be read back.
/// A non-empty shatter_version must follow the `vers` rule (std::invalid_argument
/// otherwise); an empty one writes no `vers` section.
/// Guarantees: deterministic (equal trees give equal bytes), and decode_shatter
/// returns a tree equal to `tree` field by field, every double bit for bit,
/// shatter_version included.
std::string encode_shatter(const MeshTree& tree);

/// The tree stored in `bytes` (format version 1, 2 or 3).
/// Throws CorruptFileError, with a one-line message naming the defect and its
/// place (section and byte offset), when the bytes are not a .shatter file, are
/// of another version, truncated, fail a checksum, or decode to a tree that breaks
/// a MeshTree invariant validate_tree checks without the caches (the message then
/// ends with the TreeDefect's): node 0 the root without a parent; parent and
/// children links consistent, nodes in depth-first preorder, internal nodes with two or
/// more children, depth = parent's depth + 1; leaf ranges contiguous and
/// consistent with the children; every triangle index < its mesh's vertex count
/// (surfaces and attribute channels sized by construction); bonds with
/// first < second < leaf count, sorted by (first, second, cut_node), cut_node the
/// internal node whose cut separates the two leaves; enum and bool bytes in range;
/// a `vers` section at most once, within its rule (it fills shatter_version);
/// in version 3, child counts that make one tree of the node count, and every
/// plane, surface and position code naming something that exists (an ancestor,
/// a source vertex, a face across a corner's edge).
/// The exact representation (GEOM, SOLD) is checked for structure, not geometry:
///   - without input points, no input plane, no solid and no convex node;
///   - input points and the planes of internal nodes finite (the exact
///     predicates take them as exact doubles), input planes' point indices in
///     range;
///   - in every node's solid: vertex kinds in range and unused definition fields
///     zero; point indices in range; every plane an input plane in range, a
///     cell plane, or the cut plane of an ancestor of the node (a strict one:
///     the node's own plane cuts it into its children); line.p < line.q < point count, or both none;
///     every face with a loop, every loop with at least 3 corners, faces' loop
///     ranges and loops' corner ranges contiguous and covering all loops and
///     corners; corners' vertices in range, no corner repeating the vertex
///     before it; every directed edge used once and matched by its reverse
///     (closed); every vertex used;
///   - a convex node's hull empty (its mesh is its hull);
///   - every vertex definition non-degenerate (approximate() finds a point),
///     which recomputing the caches decides.
/// Not checked (exact predicates, too costly for a reader): that vertices lie on
/// their faces' planes and edges' lines, faces' orientation and convexity flags,
/// the solids' embedding, nor that a face's `source` names a triangle of the
/// input (the input as the build prepared it is not stored).
/// Never reads outside `bytes`, and never allocates more than a small multiple of
/// bytes.size(), whatever the counts in the file claim.
/// Guarantees: the result can be trusted by the rest of the library as far as
/// the checks above go, and encode_shatter of it gives `bytes` back for any file
/// encode_shatter wrote.
MeshTree decode_shatter(std::string_view bytes);

/// encode_shatter(tree) handed to `sink` in pieces, a section at a time: each
/// payload is made, written and freed in turn, so a large tree's file is never
/// held whole. Preconditions, guarantees and exceptions as encode_shatter's (the
/// tree is checked before the first piece), and whatever `sink` throws.
void write_shatter(const MeshTree& tree, const ByteSink& sink);

/// write_shatter streaming each section as it is made: its header goes out
/// first with a zero length and checksum and is replaced (sink.overwrite) once
/// the payload is written, so no more than a piece of about a mebibyte of the
/// file is held at a time. The same bytes; preconditions, guarantees and
/// exceptions as write_shatter's.
void write_shatter(const MeshTree& tree, const RewritableSink& sink);

/// Writes encode_shatter(tree) to `path` atomically and streamed
/// (write_file_atomically_rewritable, write_shatter): `path` is either untouched
/// or complete. Throws IoError when it cannot be written, std::invalid_argument
/// as encode_shatter.
void write_shatter_file(const std::filesystem::path& path, const MeshTree& tree);

/// Reads and decodes the .shatter file at `path`. Throws IoError when it cannot
/// be opened or read, CorruptFileError (message prefixed by the path) when its
/// content is refused by decode_shatter.
MeshTree read_shatter_file(const std::filesystem::path& path);

}  // namespace shatter
