// The .shatter file (layout in file.hpp). The encoder writes every field byte by
// byte; the decoder checks every count against the bytes left before it
// allocates; and one validator, validate_tree, serves both, so whatever the
// encoder accepts the decoder accepts, and a decoded tree keeps every MeshTree
// invariant.

#include "shatter/meshtree/file.hpp"

#include <zlib.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <utility>
#include <vector>

#include "shatter/kernel/error.hpp"
#include "shatter/kernel/implicit.hpp"
#include "shatter/kernel/io.hpp"
#include "shatter/kernel/solid.hpp"
#include "shatter/meshtree/bonds.hpp"
#include "shatter/meshtree/tree.hpp"
#include "shatter/meshtree/validate_tree.hpp"
#include "tree_checks.hpp"

namespace shatter {

namespace {

using detail::hex;
using detail::last_kernel;
using detail::last_point_kind;
using detail::last_strategy;
using detail::leaves_in_order;

// ---------------------------------------------------------------------------
// Constants of the layout

using Tag = std::array<char, 4>;

constexpr std::array<unsigned char, 8> magic = {0x89, 'S', 'H', 'T', 0x0D, 0x0A, 0x1A, 0x0A};
constexpr std::size_t file_header_size = 12;     // magic, u32 version
constexpr std::size_t section_header_size = 16;  // tag, u64 length, u32 crc

constexpr Tag recipe_tag = {'O', 'P', 'T', 'S'};
constexpr Tag nodes_tag = {'N', 'O', 'D', 'E'};
constexpr Tag meshes_tag = {'M', 'E', 'S', 'H'};
constexpr Tag hulls_tag = {'H', 'U', 'L', 'L'};
constexpr Tag bonds_tag = {'B', 'O', 'N', 'D'};
constexpr Tag geometry_tag = {'G', 'E', 'O', 'M'};  // version 2
constexpr Tag solids_tag = {'S', 'O', 'L', 'D'};    // version 2
constexpr Tag end_tag = {'E', 'N', 'D', ' '};
// Optional by the tag rule (lower-case first letter): readers that predate it skip it.
constexpr Tag version_tag = {'v', 'e', 'r', 's'};

// Bytes on disk, the least each record can take: counts are checked against these
// before anything is allocated, which bounds memory by a multiple of the input.
constexpr std::size_t recipe_size = 27;
constexpr std::size_t node_record_min_size = 165;  // without its children
constexpr std::size_t child_size = 4;
constexpr std::size_t mesh_record_min_size = 9;
constexpr std::size_t vertex_size = 24;
constexpr std::size_t triangle_size = 16;  // three indices and the surface id
constexpr std::size_t normal_size = 24;
constexpr std::size_t uv_size = 16;
constexpr std::size_t tangent_size = 32;
constexpr std::size_t bond_size = 68;
constexpr std::size_t geometry_header_size = 8;  // point count, input plane count
constexpr std::size_t point_size = 24;
constexpr std::size_t input_plane_size = 12;
constexpr std::size_t solid_record_min_size = 17;  // flags and four counts
constexpr std::size_t point_def_size = 13;
constexpr std::size_t face_size = 17;
constexpr std::size_t loop_size = 4;
constexpr std::size_t corner_min_size = 9;  // without its segment
constexpr std::size_t segment_size = 8;
constexpr std::size_t max_version_text_size = 64;

// SOLD flag bits: per node, and per face.
constexpr std::uint8_t node_convex_bit = 1;
constexpr std::uint8_t solid_convex_bit = 2;
constexpr std::uint8_t face_reversed_bit = 1;
constexpr std::uint8_t face_convex_bit = 2;

constexpr std::uint8_t normals_bit = 1;
constexpr std::uint8_t uvs_bit = 2;
constexpr std::uint8_t tangents_bit = 4;
constexpr std::uint8_t known_channel_bits = normals_bit | uvs_bit | tangents_bit;

// ---------------------------------------------------------------------------
// Small helpers

std::uint32_t crc_of(std::string_view bytes) {
  uLong crc = crc32(0L, Z_NULL, 0);
  // zlib takes a 32-bit length; feed larger payloads in pieces.
  constexpr std::size_t piece = std::size_t{1} << 30;
  while (!bytes.empty()) {
    const std::size_t length = std::min(bytes.size(), piece);
    crc = crc32(crc, reinterpret_cast<const Bytef*>(bytes.data()), static_cast<uInt>(length));
    bytes.remove_prefix(length);
  }
  return static_cast<std::uint32_t>(crc);
}

/// What is wrong with a `vers` payload (file.hpp: 1 to 64 bytes of printable
/// ASCII, no space), or nullopt. Kept that narrow so it prints as one clean word.
std::optional<std::string> version_text_problem(std::string_view text) {
  if (text.empty()) return "the version is empty";
  if (text.size() > max_version_text_size) {
    return "the version is " + std::to_string(text.size()) + " bytes long (at most " + std::to_string(max_version_text_size) + ")";
  }
  for (std::size_t k = 0; k < text.size(); ++k) {
    const auto c = static_cast<unsigned char>(text[k]);
    if (c < 0x21 || c > 0x7E) return "byte " + std::to_string(k) + " of the version is " + hex(c, 2) + " (printable ASCII without spaces only)";
  }
  return std::nullopt;
}

/// A tag as it can be printed in a one-line message: printable ASCII as is,
/// anything else (damage, usually) as \xNN.
std::string tag_text(Tag tag) {
  std::string text;
  for (const char c : tag) {
    const auto byte = static_cast<unsigned char>(c);
    if (byte >= 0x20 && byte < 0x7F && byte != '\\') {
      text += c;
    } else {
      text += "\\x" + hex(byte, 2).substr(2);
    }
  }
  return text;
}

/// The name of a section in messages: "END" rather than "END ".
std::string section_name(Tag tag) { return tag == end_tag ? std::string("END") : tag_text(tag); }

std::string str(std::uint64_t value) { return std::to_string(value); }

[[noreturn]] void refuse(const std::string& message) { throw CorruptFileError(message); }

// ---------------------------------------------------------------------------
// Encoding

class ByteWriter {
 public:
  void u8(std::uint8_t value) { bytes_.push_back(static_cast<char>(value)); }
  void u32(std::uint32_t value) { little_endian(value); }
  void u64(std::uint64_t value) { little_endian(value); }
  /// A count the validator has already checked to fit 32 bits.
  void count32(std::size_t value) { u32(static_cast<std::uint32_t>(value)); }
  void f64(double value) { u64(std::bit_cast<std::uint64_t>(value)); }
  void vec2(Vec2 v) {
    f64(v.x);
    f64(v.y);
  }
  void vec3(Vec3 v) {
    f64(v.x);
    f64(v.y);
    f64(v.z);
  }
  void vec4(Vec4 v) {
    f64(v.x);
    f64(v.y);
    f64(v.z);
    f64(v.w);
  }
  void tag(Tag tag) {
    for (const char c : tag) bytes_.push_back(c);
  }
  void append(std::string_view bytes) { bytes_.append(bytes); }
  void reserve(std::size_t size) { bytes_.reserve(size); }

  std::string take() { return std::move(bytes_); }

 private:
  // The file is little-endian; on a little-endian machine a value's bytes are
  // copied as they are (one append, not one push_back per byte: the meshes of a
  // large tree are hundreds of megabytes of these).
  template <class Unsigned>
  void little_endian(Unsigned value) {
    char bytes[sizeof(Unsigned)];
    if constexpr (std::endian::native == std::endian::little) {
      std::memcpy(bytes, &value, sizeof bytes);
    } else {
      for (std::size_t k = 0; k < sizeof bytes; ++k) bytes[k] = static_cast<char>(value >> (8 * k));
    }
    bytes_.append(bytes, sizeof bytes);
  }

  std::string bytes_;
};

std::string recipe_payload(const TreeRecipe& recipe) {
  ByteWriter out;
  out.u32(recipe.fragments);
  out.u64(recipe.seed);
  out.u8(static_cast<std::uint8_t>(recipe.strategy));
  out.u8(static_cast<std::uint8_t>(recipe.kernel));
  out.f64(recipe.interior_uv_scale);
  out.u32(recipe.max_plane_tries);
  out.u8(recipe.allow_self_intersections ? 1 : 0);
  return out.take();
}

/// Each node's record holds its cut plane (MeshTree::cut_planes[k]): the file
/// has stored it there since version 1, for every kernel.
std::string nodes_payload(const MeshTree& tree) {
  ByteWriter out;
  out.count32(tree.nodes.size());
  for (std::size_t k = 0; k < tree.nodes.size(); ++k) {
    const MeshTreeNode& node = tree.nodes[k];
    out.u32(node.parent);
    out.u32(node.depth);
    out.u32(node.first_leaf);
    out.u32(node.leaf_count);
    out.u64(node.seed);
    out.u8(node.above_parent_plane ? 1 : 0);
    out.vec3(tree.cut_planes[k].normal);
    out.f64(tree.cut_planes[k].offset);
    out.f64(node.mass.volume);
    out.vec3(node.mass.centroid);
    for (const double entry : node.mass.inertia) out.f64(entry);
    out.count32(node.children.size());
    for (const NodeIndex child : node.children) out.u32(child);
  }
  return out.take();
}

void write_mesh_record(ByteWriter& out, const Mesh& mesh) {
  out.count32(mesh.positions.size());
  out.count32(mesh.triangles.size());
  out.u8(static_cast<std::uint8_t>((mesh.corners.has_normals() ? normals_bit : 0) | (mesh.corners.has_uvs() ? uvs_bit : 0) |
                                   (mesh.corners.has_tangents() ? tangents_bit : 0)));
  for (const Vec3& position : mesh.positions) out.vec3(position);
  for (const Triangle& triangle : mesh.triangles) {
    for (const VertexIndex vertex : triangle) out.u32(vertex);
  }
  for (const SurfaceId surface : mesh.surfaces) out.u32(surface);
  for (const Vec3& normal : mesh.corners.normals) out.vec3(normal);
  for (const Vec2& uv : mesh.corners.uvs) out.vec2(uv);
  for (const Vec4& tangent : mesh.corners.tangents) out.vec4(tangent);
}

std::string meshes_payload(const std::vector<MeshTreeNode>& nodes, Mesh MeshTreeNode::*which) {
  ByteWriter out;
  out.count32(nodes.size());
  for (const MeshTreeNode& node : nodes) write_mesh_record(out, node.*which);
  return out.take();
}

std::string bonds_payload(const std::vector<Bond>& bonds) {
  ByteWriter out;
  out.u64(bonds.size());
  for (const Bond& bond : bonds) {
    out.u32(bond.first);
    out.u32(bond.second);
    out.u32(bond.cut_node);
    out.f64(bond.area);
    out.vec3(bond.centroid);
    out.vec3(bond.normal);
  }
  return out.take();
}

std::string geometry_payload(const InputGeometry& geometry) {
  ByteWriter out;
  out.count32(geometry.points.size());
  out.count32(geometry.planes.size());
  for (const Vec3& point : geometry.points) out.vec3(point);
  for (const auto& plane : geometry.planes) {
    for (const VertexIndex point : plane) out.u32(point);
  }
  return out.take();
}

/// One record per node when the tree has an exact representation, else none.
std::string solids_payload(const MeshTree& tree) {
  ByteWriter out;
  const bool exact = !tree.geometry.points.empty();
  out.count32(exact ? tree.nodes.size() : 0);
  if (!exact) return out.take();
  for (const MeshTreeNode& node : tree.nodes) {
    const Solid& solid = node.solid;
    out.u8(static_cast<std::uint8_t>((node.convex ? node_convex_bit : 0) | (solid.convex ? solid_convex_bit : 0)));
    out.count32(solid.defs.size());
    out.count32(solid.faces.size());
    out.count32(solid.loops.size());
    out.count32(solid.corners.size());
    for (const PointDef& def : solid.defs) {
      out.u8(static_cast<std::uint8_t>(def.kind));
      // The validator has checked that the fields a kind does not use are zero.
      if (def.kind == PointKind::three_planes) {
        for (const PlaneRef plane : def.planes) out.u32(plane.bits);
      } else {
        out.u32(def.a);
        out.u32(def.b);
        out.u32(def.planes[0].bits);
      }
    }
    for (const SolidFace& face : solid.faces) {
      out.u32(face.plane.bits);
      out.u8(static_cast<std::uint8_t>((face.reversed ? face_reversed_bit : 0) | (face.convex ? face_convex_bit : 0)));
      out.u32(face.surface);
      out.u32(face.source);
      out.u32(face.loop_count);
    }
    for (const SolidLoop& loop : solid.loops) out.u32(loop.corner_count);
    for (const SolidCorner& corner : solid.corners) {
      out.u32(corner.vertex);
      out.u32(corner.line.other.bits);
      // The validator has checked that p and q are both none or both points.
      out.u8(corner.line.is_segment() ? 1 : 0);
      if (corner.line.is_segment()) {
        out.u32(corner.line.p);
        out.u32(corner.line.q);
      }
    }
  }
  return out.take();
}

void append_section(ByteWriter& file, Tag tag, std::string_view payload) {
  file.tag(tag);
  file.u64(payload.size());
  file.u32(crc_of(payload));
  file.append(payload);
}

// ---------------------------------------------------------------------------
// Decoding: the section table

std::uint32_t load_u32(std::string_view bytes, std::size_t at) {
  std::uint32_t value = 0;
  for (std::size_t k = 0; k < 4; ++k) value |= std::uint32_t{static_cast<unsigned char>(bytes[at + k])} << (8 * k);
  return value;
}

std::uint64_t load_u64(std::string_view bytes, std::size_t at) {
  std::uint64_t value = 0;
  for (std::size_t k = 0; k < 8; ++k) value |= std::uint64_t{static_cast<unsigned char>(bytes[at + k])} << (8 * k);
  return value;
}

struct Section {
  Tag tag{};
  std::size_t offset = 0;          ///< of the section header in the file
  std::size_t payload_offset = 0;  ///< of the payload in the file
  std::string_view payload;
};

struct SectionTable {
  std::uint32_t version = 0;
  std::optional<Section> recipe, nodes, meshes, hulls, bonds;
  std::optional<Section> geometry, solids;  // version 2
  std::optional<Section> shatter_version;   // optional, in any version
};

/// Checks the magic and returns the version, one this reader knows.
std::uint32_t check_file_header(std::string_view bytes) {
  const std::size_t magic_bytes_present = std::min(bytes.size(), magic.size());
  for (std::size_t k = 0; k < magic_bytes_present; ++k) {
    if (static_cast<unsigned char>(bytes[k]) != magic[k]) {
      refuse("not a .shatter file: byte " + str(k) + " differs from the magic 89 53 48 54 0D 0A 1A 0A (\"\\x89SHT\\r\\n\\x1a\\n\")");
    }
  }
  if (bytes.size() < file_header_size) {
    refuse("truncated .shatter file: " + str(bytes.size()) + " bytes, shorter than the " + str(file_header_size) + "-byte header");
  }
  const std::uint32_t version = load_u32(bytes, magic.size());
  if (version < shatter_oldest_format_version || version > shatter_format_version) {
    refuse("unsupported .shatter format version " + str(version) + " at byte " + str(magic.size()) + " (this build reads versions " +
           str(shatter_oldest_format_version) + " to " + str(shatter_format_version) +
           (version > shatter_format_version ? ": the file is from a newer shatter, or damaged)" : ")"));
  }
  return version;
}

/// Splits the file into its sections, checking every checksum, and keeps the
/// ones this version reads (see the reading rules in file.hpp).
SectionTable read_section_table(std::string_view bytes) {
  SectionTable table;
  table.version = check_file_header(bytes);
  // Version 1 knows the first five; GEOM and SOLD are unknown tags there.
  const std::array<std::pair<Tag, std::optional<Section>*>, 7> all_known = {{{recipe_tag, &table.recipe},
                                                                             {nodes_tag, &table.nodes},
                                                                             {meshes_tag, &table.meshes},
                                                                             {hulls_tag, &table.hulls},
                                                                             {bonds_tag, &table.bonds},
                                                                             {geometry_tag, &table.geometry},
                                                                             {solids_tag, &table.solids}}};
  const std::span<const std::pair<Tag, std::optional<Section>*>> known(all_known.data(), table.version == 1 ? 5 : 7);
  std::size_t position = file_header_size;
  while (true) {
    if (position == bytes.size()) refuse("truncated .shatter file: ends at byte " + str(position) + " without the END section");
    if (bytes.size() - position < section_header_size) {
      refuse("truncated .shatter file: ends at byte " + str(bytes.size()) + " inside the 16-byte section header at byte " + str(position));
    }
    Section section;
    std::copy_n(bytes.data() + position, section.tag.size(), section.tag.begin());
    section.offset = position;
    section.payload_offset = position + section_header_size;
    const std::uint64_t length = load_u64(bytes, position + 4);
    const std::uint32_t stored_crc = load_u32(bytes, position + 12);
    const std::size_t available = bytes.size() - section.payload_offset;
    if (length > available) {
      refuse("truncated .shatter file: " + section_name(section.tag) + " section at byte " + str(position) + " declares " + str(length) +
             " payload bytes, but only " + str(available) + " remain");
    }
    section.payload = bytes.substr(section.payload_offset, static_cast<std::size_t>(length));
    if (const std::uint32_t crc = crc_of(section.payload); crc != stored_crc) {
      refuse("damaged .shatter file: " + section_name(section.tag) + " section at byte " + str(position) + " fails its checksum (stored " +
             hex(stored_crc, 8) + ", computed " + hex(crc, 8) + ")");
    }
    const std::size_t section_end = section.payload_offset + section.payload.size();

    if (section.tag == end_tag) {
      if (!section.payload.empty()) {
        refuse("damaged .shatter file: END section at byte " + str(position) + " has a " + str(length) + "-byte payload (must be empty)");
      }
      if (section_end != bytes.size()) {
        refuse("damaged .shatter file: " + str(bytes.size() - section_end) + " bytes follow the END section at byte " + str(position));
      }
      break;
    }
    const auto slot = std::find_if(known.begin(), known.end(), [&](const auto& entry) { return entry.first == section.tag; });
    if (section.tag == version_tag) {
      if (table.shatter_version) {
        refuse("damaged .shatter file: " + section_name(section.tag) + " section at byte " + str(position) + " repeats the one at byte " +
               str(table.shatter_version->offset));
      }
      table.shatter_version = section;
    } else if (slot != known.end()) {
      if (*slot->second) {
        refuse("damaged .shatter file: " + section_name(section.tag) + " section at byte " + str(position) + " repeats the one at byte " +
               str((*slot->second)->offset));
      }
      *slot->second = section;
    } else if (!(section.tag[0] >= 'a' && section.tag[0] <= 'z')) {
      // Optional sections start with a lower-case letter; any other unknown tag
      // holds data this reader would misunderstand, or is damage.
      refuse("unsupported or damaged .shatter file: unknown section '" + tag_text(section.tag) + "' at byte " + str(position) +
             " (only tags starting with a lower-case letter may be skipped)");
    }
    position = section_end;
  }
  for (const auto& [tag, slot] : known) {
    if (!*slot) refuse("damaged .shatter file: no " + section_name(tag) + " section");
  }
  return table;
}

// ---------------------------------------------------------------------------
// Decoding: payloads

/// Reads one section's payload front to back. Every read is bounds-checked, and
/// every count is checked against the bytes left before anything is sized by it.
/// Failures name the section, the file offset and the record being read.
class PayloadReader {
 public:
  explicit PayloadReader(const Section& section) : payload_(section.payload), payload_offset_(section.payload_offset), tag_(section.tag) {}

  /// The file offset of the next byte.
  std::size_t offset() const { return payload_offset_ + position_; }
  std::size_t remaining() const { return payload_.size() - position_; }

  /// Names the record being read in failure messages ("node 3", ...).
  void set_record(std::string record) { record_ = std::move(record); }

  std::uint8_t u8(const char* field) {
    need(1, field);
    return static_cast<std::uint8_t>(payload_[position_++]);
  }
  std::uint32_t u32(const char* field) {
    need(4, field);
    const std::uint32_t value = load_u32(payload_, position_);
    position_ += 4;
    return value;
  }
  std::uint64_t u64(const char* field) {
    need(8, field);
    const std::uint64_t value = load_u64(payload_, position_);
    position_ += 8;
    return value;
  }
  double f64(const char* field) { return std::bit_cast<double>(u64(field)); }
  Vec2 vec2(const char* field) {
    need(16, field);
    Vec2 v;
    v.x = f64(field);
    v.y = f64(field);
    return v;
  }
  Vec3 vec3(const char* field) {
    need(24, field);
    Vec3 v;
    v.x = f64(field);
    v.y = f64(field);
    v.z = f64(field);
    return v;
  }
  Vec4 vec4(const char* field) {
    need(32, field);
    Vec4 v;
    v.x = f64(field);
    v.y = f64(field);
    v.z = f64(field);
    v.w = f64(field);
    return v;
  }
  bool boolean(const char* field) {
    const std::size_t at = offset();
    const std::uint8_t value = u8(field);
    if (value > 1) fail_at(at, std::string(field) + " is " + str(value) + " (must be 0 or 1)");
    return value == 1;
  }

  /// Refuses a field of `size` bytes if the payload ends before it.
  void need(std::size_t size, const char* field) const {
    if (remaining() < size) fail("the payload ends inside " + std::string(field));
  }

  /// Refuses `count` records of at least `record_size` bytes each if they
  /// cannot fit in what is left, before the caller allocates for them.
  void check_room(std::uint64_t count, std::size_t record_size, const char* what) const {
    if (count > remaining() / record_size) {
      fail(str(count) + " " + what + " need at least " + str(record_size) + " bytes each, but only " + str(remaining()) + " bytes remain");
    }
  }

  void expect_end() const {
    if (remaining() != 0) fail(str(remaining()) + " unexpected bytes after the last record");
  }

  [[noreturn]] void fail(const std::string& problem) const { fail_at(offset(), problem); }
  [[noreturn]] void fail_at(std::size_t at, const std::string& problem) const {
    refuse("damaged .shatter file: " + section_name(tag_) + " section, byte " + str(at) + (record_.empty() ? "" : ", " + record_) + ": " + problem);
  }

 private:
  std::string_view payload_;
  std::size_t payload_offset_;
  std::size_t position_ = 0;
  Tag tag_;
  std::string record_;
};

TreeRecipe read_recipe(const Section& section) {
  PayloadReader in(section);
  TreeRecipe recipe;
  recipe.fragments = in.u32("fragments");
  recipe.seed = in.u64("seed");
  const std::size_t strategy_at = in.offset();
  const std::uint8_t strategy = in.u8("strategy");
  if (strategy > last_strategy) in.fail_at(strategy_at, "strategy " + str(strategy) + " is unknown");
  recipe.strategy = static_cast<Strategy>(strategy);
  const std::size_t kernel_at = in.offset();
  const std::uint8_t kernel = in.u8("kernel");
  if (kernel > last_kernel) in.fail_at(kernel_at, "kernel " + str(kernel) + " is unknown");
  recipe.kernel = static_cast<KernelKind>(kernel);
  recipe.interior_uv_scale = in.f64("interior_uv_scale");
  recipe.max_plane_tries = in.u32("max_plane_tries");
  recipe.allow_self_intersections = in.boolean("allow_self_intersections");
  in.expect_end();
  static_assert(recipe_size == 27);
  return recipe;
}

/// Reads the nodes without their meshes, and their cut planes into
/// tree.cut_planes; `record_offsets` gets each record's offset.
void read_nodes(const Section& section, MeshTree& tree, std::vector<std::size_t>& record_offsets) {
  PayloadReader in(section);
  const std::uint32_t node_count = in.u32("the node count");
  if (node_count == 0) in.fail("node count 0 (a tree has at least its root)");
  in.check_room(node_count, node_record_min_size, "nodes");
  std::vector<MeshTreeNode>& nodes = tree.nodes;
  nodes.resize(node_count);
  tree.cut_planes.resize(node_count);
  record_offsets.resize(node_count);
  for (std::size_t k = 0; k < nodes.size(); ++k) {
    MeshTreeNode& node = nodes[k];
    record_offsets[k] = in.offset();
    in.set_record("node " + str(k));
    node.parent = in.u32("parent");
    node.depth = in.u32("depth");
    node.first_leaf = in.u32("first_leaf");
    node.leaf_count = in.u32("leaf_count");
    node.seed = in.u64("seed");
    node.above_parent_plane = in.boolean("above_parent_plane");
    tree.cut_planes[k].normal = in.vec3("plane normal");
    tree.cut_planes[k].offset = in.f64("plane offset");
    node.mass.volume = in.f64("volume");
    node.mass.centroid = in.vec3("centroid");
    for (double& entry : node.mass.inertia) entry = in.f64("inertia");
    const std::uint32_t child_count = in.u32("child count");
    in.check_room(child_count, child_size, "children");
    node.children.resize(child_count);
    for (NodeIndex& child : node.children) child = in.u32("child");
  }
  in.set_record("");
  in.expect_end();
}

Mesh read_mesh_record(PayloadReader& in) {
  Mesh mesh;
  const std::uint32_t vertex_count = in.u32("vertex count");
  const std::uint32_t triangle_count = in.u32("triangle count");
  const std::size_t channels_at = in.offset();
  const std::uint8_t channels = in.u8("channel flags");
  if ((channels & ~known_channel_bits) != 0) in.fail_at(channels_at, "unknown attribute channel bits " + hex(channels, 2));
  // A channel is present when it holds values, so a mesh without triangles has
  // none; accepting bits here would decode to a mesh that encodes differently.
  if (triangle_count == 0 && channels != 0) {
    in.fail_at(channels_at, "attribute channel bits " + hex(channels, 2) + " for a mesh without triangles (must be 0)");
  }

  in.check_room(vertex_count, vertex_size, "vertices");
  mesh.positions.resize(vertex_count);
  for (Vec3& position : mesh.positions) position = in.vec3("position");

  in.check_room(triangle_count, triangle_size, "triangles");
  mesh.triangles.resize(triangle_count);
  for (Triangle& triangle : mesh.triangles) {
    for (VertexIndex& vertex : triangle) vertex = in.u32("triangle");
  }
  mesh.surfaces.resize(triangle_count);
  for (SurfaceId& surface : mesh.surfaces) surface = in.u32("surface id");

  const std::uint64_t corner_count = 3 * std::uint64_t{triangle_count};
  if ((channels & normals_bit) != 0) {
    in.check_room(corner_count, normal_size, "corner normals");
    mesh.corners.normals.resize(static_cast<std::size_t>(corner_count));
    for (Vec3& normal : mesh.corners.normals) normal = in.vec3("normal");
  }
  if ((channels & uvs_bit) != 0) {
    in.check_room(corner_count, uv_size, "corner uvs");
    mesh.corners.uvs.resize(static_cast<std::size_t>(corner_count));
    for (Vec2& uv : mesh.corners.uvs) uv = in.vec2("uv");
  }
  if ((channels & tangents_bit) != 0) {
    in.check_room(corner_count, tangent_size, "corner tangents");
    mesh.corners.tangents.resize(static_cast<std::size_t>(corner_count));
    for (Vec4& tangent : mesh.corners.tangents) tangent = in.vec4("tangent");
  }
  return mesh;
}

/// Reads one mesh per node into `which` of each node.
void read_meshes(const Section& section, std::vector<MeshTreeNode>& nodes, Mesh MeshTreeNode::*which, std::vector<std::size_t>& record_offsets) {
  PayloadReader in(section);
  const std::uint32_t mesh_count = in.u32("the mesh count");
  if (mesh_count != nodes.size()) in.fail(str(mesh_count) + " meshes for " + str(nodes.size()) + " nodes");
  in.check_room(mesh_count, mesh_record_min_size, "meshes");
  record_offsets.resize(nodes.size());
  for (std::size_t k = 0; k < nodes.size(); ++k) {
    record_offsets[k] = in.offset();
    in.set_record("node " + str(k));
    nodes[k].*which = read_mesh_record(in);
  }
  in.set_record("");
  in.expect_end();
}

std::vector<Bond> read_bonds(const Section& section) {
  PayloadReader in(section);
  const std::uint64_t bond_count = in.u64("the bond count");
  in.check_room(bond_count, bond_size, "bonds");
  std::vector<Bond> bonds(static_cast<std::size_t>(bond_count));
  for (std::size_t i = 0; i < bonds.size(); ++i) {
    Bond& bond = bonds[i];
    in.set_record("bond " + str(i));
    bond.first = in.u32("first");
    bond.second = in.u32("second");
    bond.cut_node = in.u32("cut_node");
    bond.area = in.f64("area");
    bond.centroid = in.vec3("centroid");
    bond.normal = in.vec3("normal");
  }
  in.set_record("");
  in.expect_end();
  return bonds;
}

InputGeometry read_geometry(const Section& section) {
  PayloadReader in(section);
  InputGeometry geometry;
  const std::uint32_t point_count = in.u32("the point count");
  const std::uint32_t plane_count = in.u32("the input plane count");
  in.check_room(point_count, point_size, "input points");
  geometry.points.resize(point_count);
  for (Vec3& point : geometry.points) point = in.vec3("input point");
  in.check_room(plane_count, input_plane_size, "input planes");
  geometry.planes.resize(plane_count);
  for (auto& plane : geometry.planes) {
    for (VertexIndex& point : plane) point = in.u32("input plane");
  }
  in.expect_end();
  return geometry;
}

/// Reads each node's exact solid and convex flag; `exact`: GEOM holds input
/// points, so there is one record per node (else none). Faces' first loops and
/// loops' first corners are the running sums of the counts before them.
void read_solids(const Section& section, std::vector<MeshTreeNode>& nodes, bool exact, std::vector<std::size_t>& record_offsets) {
  PayloadReader in(section);
  const std::uint32_t record_count = in.u32("the solid count");
  if (!exact && record_count != 0) {
    in.fail(str(record_count) + " solids, but GEOM holds no input points (a tree without an exact representation stores none)");
  }
  if (exact && record_count != nodes.size()) in.fail(str(record_count) + " solids for " + str(nodes.size()) + " nodes");
  in.check_room(record_count, solid_record_min_size, "solids");
  record_offsets.resize(record_count);
  for (std::size_t k = 0; k < record_count; ++k) {
    record_offsets[k] = in.offset();
    in.set_record("node " + str(k));
    MeshTreeNode& node = nodes[k];
    Solid& solid = node.solid;
    const std::size_t flags_at = in.offset();
    const std::uint8_t flags = in.u8("solid flags");
    if ((flags & ~(node_convex_bit | solid_convex_bit)) != 0) in.fail_at(flags_at, "unknown solid flag bits " + hex(flags, 2));
    node.convex = (flags & node_convex_bit) != 0;
    solid.convex = (flags & solid_convex_bit) != 0;
    const std::uint32_t vertex_count = in.u32("vertex count");
    const std::uint32_t face_count = in.u32("face count");
    const std::uint32_t loop_count = in.u32("loop count");
    const std::uint32_t corner_count = in.u32("corner count");

    in.check_room(vertex_count, point_def_size, "vertex definitions");
    solid.defs.resize(vertex_count);
    for (std::size_t v = 0; v < vertex_count; ++v) {
      PointDef& def = solid.defs[v];
      const std::size_t kind_at = in.offset();
      const std::uint8_t kind = in.u8("vertex kind");
      if (kind > last_point_kind) in.fail_at(kind_at, "vertex " + str(v) + " has unknown kind " + str(kind));
      def.kind = static_cast<PointKind>(kind);
      // Fields a kind does not use land where the validator refuses non-zero ones.
      if (def.kind == PointKind::three_planes) {
        for (PlaneRef& plane : def.planes) plane.bits = in.u32("vertex plane");
      } else {
        def.a = in.u32("vertex point");
        def.b = in.u32("vertex point");
        def.planes[0].bits = in.u32("vertex plane");
      }
    }

    in.check_room(face_count, face_size, "faces");
    solid.faces.resize(face_count);
    std::uint64_t next_loop = 0;
    for (SolidFace& face : solid.faces) {
      face.plane.bits = in.u32("face plane");
      const std::size_t face_flags_at = in.offset();
      const std::uint8_t face_flags = in.u8("face flags");
      if ((face_flags & ~(face_reversed_bit | face_convex_bit)) != 0) in.fail_at(face_flags_at, "unknown face flag bits " + hex(face_flags, 2));
      face.reversed = (face_flags & face_reversed_bit) != 0;
      face.convex = (face_flags & face_convex_bit) != 0;
      face.surface = in.u32("face surface");
      face.source = in.u32("face source");
      const std::size_t count_at = in.offset();
      face.loop_count = in.u32("face loop count");
      face.first_loop = static_cast<std::uint32_t>(next_loop);
      next_loop += face.loop_count;
      if (next_loop > loop_count) in.fail_at(count_at, "the faces claim " + str(next_loop) + " loops or more, of " + str(loop_count));
    }

    in.check_room(loop_count, loop_size, "loops");
    solid.loops.resize(loop_count);
    std::uint64_t next_corner = 0;
    for (SolidLoop& loop : solid.loops) {
      const std::size_t count_at = in.offset();
      loop.corner_count = in.u32("loop corner count");
      loop.first_corner = static_cast<std::uint32_t>(next_corner);
      next_corner += loop.corner_count;
      if (next_corner > corner_count) in.fail_at(count_at, "the loops claim " + str(next_corner) + " corners or more, of " + str(corner_count));
    }

    in.check_room(corner_count, corner_min_size, "corners");
    solid.corners.resize(corner_count);
    for (std::size_t c = 0; c < corner_count; ++c) {
      SolidCorner& corner = solid.corners[c];
      corner.vertex = in.u32("corner vertex");
      corner.line.other.bits = in.u32("corner line plane");
      const std::size_t segment_at = in.offset();
      const bool segment = in.boolean("corner segment flag");
      if (segment) {
        in.need(segment_size, "corner segment");
        corner.line.p = in.u32("corner segment");
        corner.line.q = in.u32("corner segment");
        // A segment of two "none" points would come back as no segment (flag 0).
        if (corner.line.p == no_index) in.fail_at(segment_at, "corner " + str(c) + " has a segment flag, but its segment is none");
      }
    }
  }
  in.set_record("");
  in.expect_end();
}

/// Where each record of a decoded tree came from, to place a defect in the file.
struct RecordOffsets {
  std::vector<std::size_t> nodes, meshes, hulls, solids;
  std::size_t point_count = 0;
};

std::string located(const TreeDefect& defect, const SectionTable& sections, const RecordOffsets& offsets) {
  Tag tag = nodes_tag;
  std::size_t at = sections.nodes->payload_offset;
  switch (defect.part) {
    case TreePart::recipe:
      tag = recipe_tag;
      at = sections.recipe->payload_offset;
      break;
    case TreePart::node:
    case TreePart::leaf_range:
    case TreePart::cut_planes:  // each node's record holds its plane
      if (defect.index < offsets.nodes.size()) at = offsets.nodes[defect.index];
      break;
    case TreePart::leaf_list: break;  // recomputed by the reader, so never at fault
    case TreePart::mesh:
      tag = meshes_tag;
      at = offsets.meshes[defect.index];
      break;
    case TreePart::hull:
      tag = hulls_tag;
      at = offsets.hulls[defect.index];
      break;
    case TreePart::bond:
      tag = bonds_tag;
      at = sections.bonds->payload_offset + 8 + bond_size * defect.index;
      break;
    // The exact representation's parts exist only in version 2 files.
    case TreePart::input_point:
    case TreePart::input_plane:
      if (sections.geometry) {
        tag = geometry_tag;
        at = sections.geometry->payload_offset;
        if (defect.part == TreePart::input_point) at += geometry_header_size + point_size * defect.index;
        if (defect.part == TreePart::input_plane) {
          at += geometry_header_size + point_size * offsets.point_count + input_plane_size * defect.index;
        }
      }
      break;
    case TreePart::solid:
      if (sections.solids) {
        tag = solids_tag;
        at = defect.index < offsets.solids.size() ? offsets.solids[defect.index] : sections.solids->payload_offset;
      }
      break;
  }
  return "invalid tree in .shatter file: " + section_name(tag) + " section, byte " + str(at) + ": " + defect.message;
}

std::string read_whole_file(const std::filesystem::path& path) {
  const std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!file) throw IoError("cannot open " + path.string() + ": " + std::strerror(errno));
  std::string bytes;
  std::array<char, 1 << 16> buffer;
  while (true) {
    const std::size_t read = std::fread(buffer.data(), 1, buffer.size(), file.get());
    bytes.append(buffer.data(), read);
    if (read < buffer.size()) break;
  }
  // A directory opens but fails to read (EISDIR).
  if (std::ferror(file.get())) throw IoError("cannot read " + path.string() + ": " + std::strerror(errno));
  return bytes;
}

}  // namespace

std::string encode_shatter(const MeshTree& tree) {
  if (const TreeValidationReport report = validate_tree(tree); !report.valid()) {
    throw std::invalid_argument("encode_shatter: invalid tree: " + report.defect->message);
  }
  if (!tree.shatter_version.empty()) {
    if (const std::optional<std::string> problem = version_text_problem(tree.shatter_version)) {
      throw std::invalid_argument("encode_shatter: invalid tree: shatter_version: " + *problem);
    }
  }
  // Every payload first, so the file is allocated once at its final size.
  std::vector<std::pair<Tag, std::string>> sections;
  if (!tree.shatter_version.empty()) sections.emplace_back(version_tag, tree.shatter_version);
  sections.emplace_back(recipe_tag, recipe_payload(tree.recipe));
  sections.emplace_back(nodes_tag, nodes_payload(tree));
  sections.emplace_back(meshes_tag, meshes_payload(tree.nodes, &MeshTreeNode::mesh));
  sections.emplace_back(hulls_tag, meshes_payload(tree.nodes, &MeshTreeNode::hull));
  sections.emplace_back(bonds_tag, bonds_payload(tree.bonds));
  sections.emplace_back(geometry_tag, geometry_payload(tree.geometry));
  sections.emplace_back(solids_tag, solids_payload(tree));
  sections.emplace_back(end_tag, std::string());
  std::size_t size = file_header_size;
  for (const auto& [tag, payload] : sections) size += section_header_size + payload.size();
  ByteWriter file;
  file.reserve(size);
  for (const unsigned char byte : magic) file.u8(byte);
  file.u32(shatter_format_version);
  for (auto& [tag, payload] : sections) {
    append_section(file, tag, payload);
    std::string().swap(payload);  // freed as soon as it is copied
  }
  return file.take();
}

MeshTree decode_shatter(std::string_view bytes) {
  const SectionTable sections = read_section_table(bytes);
  MeshTree tree;
  RecordOffsets offsets;
  if (const std::optional<Section>& version = sections.shatter_version) {
    if (const std::optional<std::string> problem = version_text_problem(version->payload)) {
      refuse("damaged .shatter file: " + section_name(version_tag) + " section at byte " + str(version->offset) + ": " + *problem);
    }
    tree.shatter_version = version->payload;
  }
  tree.recipe = read_recipe(*sections.recipe);
  read_nodes(*sections.nodes, tree, offsets.nodes);
  read_meshes(*sections.meshes, tree.nodes, &MeshTreeNode::mesh, offsets.meshes);
  read_meshes(*sections.hulls, tree.nodes, &MeshTreeNode::hull, offsets.hulls);
  tree.bonds = read_bonds(*sections.bonds);
  if (sections.version >= 2) {
    tree.geometry = read_geometry(*sections.geometry);
    offsets.point_count = tree.geometry.points.size();
    read_solids(*sections.solids, tree.nodes, !tree.geometry.points.empty(), offsets.solids);
  }
  tree.leaf_nodes = leaves_in_order(tree.nodes);
  // The caches are not stored: the structure is checked without them, then they are computed.
  if (const std::optional<TreeDefect> defect = validate_tree(tree, {.caches = false}).defect) {
    refuse(located(*defect, sections, offsets));
  }
  if (const std::optional<TreeDefect> defect = detail::fill_caches(tree)) refuse(located(*defect, sections, offsets));
  return tree;
}

void write_shatter_file(const std::filesystem::path& path, const MeshTree& tree) { write_file_atomically(path, encode_shatter(tree)); }

MeshTree read_shatter_file(const std::filesystem::path& path) {
  const std::string bytes = read_whole_file(path);
  try {
    return decode_shatter(bytes);
  } catch (const CorruptFileError& error) {
    throw CorruptFileError(path.string() + ": " + error.what());
  }
}

}  // namespace shatter
