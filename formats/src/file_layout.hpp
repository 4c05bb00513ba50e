#pragma once
// The .shatter file's building blocks, shared by the container (file.cpp: the
// header, the section table, the version 1 and 2 payloads) and the version 3
// payloads (file_v3.cpp): tags, sizes, the byte writer and the bounds-checked
// payload reader. Internal to the library; the layout is documented in
// shatter/formats/file.hpp.

#include <zlib.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <cstring>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "shatter/kernel/error.hpp"
#include "shatter/kernel/vec.hpp"
#include "shatter/meshtree/tree.hpp"
#include "shatter/meshtree/validate_tree.hpp"

namespace shatter::file_layout {

/// `value` as "0x" and `digits` upper-case hexadecimal digits (the low ones), as
/// messages name flag bytes and checksums.
inline std::string hex(std::uint64_t value, int digits) {
  std::string text(static_cast<std::size_t>(digits) + 2, '0');
  text[1] = 'x';
  for (std::size_t k = text.size(); k-- > 2; value >>= 4) text[k] = "0123456789ABCDEF"[value & 0xF];
  return text;
}

// ---------------------------------------------------------------------------
// Constants of the layout

using Tag = std::array<char, 4>;

inline constexpr std::array<unsigned char, 8> magic = {0x89, 'S', 'H', 'T', 0x0D, 0x0A, 0x1A, 0x0A};
inline constexpr std::size_t file_header_size = 12;     // magic, u32 version
inline constexpr std::size_t section_header_size = 16;  // tag, u64 length, u32 crc

inline constexpr Tag recipe_tag = {'O', 'P', 'T', 'S'};
inline constexpr Tag nodes_tag = {'N', 'O', 'D', 'E'};
inline constexpr Tag meshes_tag = {'M', 'E', 'S', 'H'};
inline constexpr Tag hulls_tag = {'H', 'U', 'L', 'L'};
inline constexpr Tag bonds_tag = {'B', 'O', 'N', 'D'};
inline constexpr Tag geometry_tag = {'G', 'E', 'O', 'M'};  // version 2
inline constexpr Tag solids_tag = {'S', 'O', 'L', 'D'};    // version 2
inline constexpr Tag end_tag = {'E', 'N', 'D', ' '};
// Version 3, only in a tree with cell planes (voronoi.hpp): the planes after the
// nodes' (MeshTree::cut_planes). Upper case: a reader that does not know it
// refuses the file rather than misread its solids.
inline constexpr Tag cell_planes_tag = {'C', 'E', 'L', 'L'};
// Optional by the tag rule (lower-case first letter): readers that predate it skip it.
inline constexpr Tag version_tag = {'v', 'e', 'r', 's'};
inline constexpr Tag repair_tag = {'r', 'p', 'a', 'r'};
inline constexpr Tag pattern_tag = {'p', 'a', 't', 't'};  // TreeRecipe::pattern

// Bytes on disk, the least each record can take: counts are checked against these
// before anything is allocated, which bounds memory by a multiple of the input.
inline constexpr std::size_t recipe_size = 27;
inline constexpr std::size_t node_record_min_size = 165;  // without its children
inline constexpr std::size_t child_size = 4;
inline constexpr std::size_t mesh_record_min_size = 9;
inline constexpr std::size_t vertex_size = 24;
inline constexpr std::size_t triangle_size = 16;  // three indices and the surface id
inline constexpr std::size_t normal_size = 24;
inline constexpr std::size_t uv_size = 16;
inline constexpr std::size_t tangent_size = 32;
inline constexpr std::size_t bond_size = 68;
inline constexpr std::size_t geometry_header_size = 8;  // point count, input plane count
inline constexpr std::size_t point_size = 24;
inline constexpr std::size_t input_plane_size = 12;
inline constexpr std::size_t solid_record_min_size = 17;  // flags and four counts
inline constexpr std::size_t point_def_size = 13;
inline constexpr std::size_t face_size = 17;
inline constexpr std::size_t loop_size = 4;
inline constexpr std::size_t corner_min_size = 9;  // without its segment
inline constexpr std::size_t segment_size = 8;
inline constexpr std::size_t max_version_text_size = 64;
inline constexpr std::size_t max_repair_text_size = 4096;  // `rpar`: one line of a repair report

// SOLD flag bits: per node, and per face.
inline constexpr std::uint8_t node_convex_bit = 1;
inline constexpr std::uint8_t solid_convex_bit = 2;
inline constexpr std::uint8_t face_reversed_bit = 1;
inline constexpr std::uint8_t face_convex_bit = 2;

inline constexpr std::uint8_t normals_bit = 1;
inline constexpr std::uint8_t uvs_bit = 2;
inline constexpr std::uint8_t tangents_bit = 4;
inline constexpr std::uint8_t known_channel_bits = normals_bit | uvs_bit | tangents_bit;

// ---------------------------------------------------------------------------
// Small helpers

/// The CRC-32 of `bytes`; with `so_far`, the CRC-32 of the bytes it was the CRC
/// of followed by `bytes` (so a payload in pieces is checked piece by piece).
inline std::uint32_t crc_of(std::string_view bytes, std::uint32_t so_far = 0) {
  uLong crc = so_far;
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
inline std::optional<std::string> version_text_problem(std::string_view text) {
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

/// What is wrong with a `patt` payload (TreeRecipe::pattern: 1 to 1024 bytes of
/// printable ASCII, spaces allowed), or nullopt.
inline std::optional<std::string> pattern_text_problem(std::string_view text) {
  if (text.empty()) return "the pattern is empty";
  if (text.size() > 1024) return "the pattern is " + std::to_string(text.size()) + " bytes long (at most 1024)";
  for (std::size_t k = 0; k < text.size(); ++k) {
    const auto c = static_cast<unsigned char>(text[k]);
    if (c < 0x20 || c > 0x7E) return "byte " + std::to_string(k) + " of the pattern is " + hex(c, 2) + " (printable ASCII only)";
  }
  return std::nullopt;
}

/// A tag as it can be printed in a one-line message: printable ASCII as is,
/// anything else (damage, usually) as \xNN.
inline std::string tag_text(Tag tag) {
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
inline std::string section_name(Tag tag) { return tag == end_tag ? std::string("END") : tag_text(tag); }

inline std::string str(std::uint64_t value) { return std::to_string(value); }

[[noreturn]] inline void refuse(const std::string& message) { throw CorruptFileError(message); }

// ---------------------------------------------------------------------------
// Encoding

class ByteWriter {
 public:
  ByteWriter() = default;
  /// A writer that hands each full piece to `flush` at end_record instead of
  /// putting it aside, and reuses its buffer: a section streamed to its file
  /// then holds one piece at a time. take_pieces gives what is left.
  explicit ByteWriter(std::function<void(std::string_view)> flush) : flush_(std::move(flush)) {}

  void u8(std::uint8_t value) {
    if (used_ == bytes_.size()) make_room(1);
    bytes_[used_++] = static_cast<char>(value);
  }
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
  /// An unsigned LEB128 varint (file.hpp, version 3): seven bits a byte, the
  /// low group first, the high bit set on every byte but the last; the shortest
  /// form.
  void varint(std::uint64_t value) {
    constexpr std::size_t longest = 10;  // 64 bits, seven a byte
    if (bytes_.size() - used_ < longest) make_room(longest);
    char* at = bytes_.data() + used_;
    while (value >= 0x80) {
      *at++ = static_cast<char>((value & 0x7F) | 0x80);
      value >>= 7;
    }
    *at++ = static_cast<char>(value);
    used_ = static_cast<std::size_t>(at - bytes_.data());
  }
  void tag(Tag tag) { append(std::string_view(tag.data(), tag.size())); }
  std::size_t size() const { return used_; }
  void append(std::string_view bytes) {
    if (bytes_.size() - used_ < bytes.size()) make_room(bytes.size());
    if (!bytes.empty()) std::memcpy(bytes_.data() + used_, bytes.data(), bytes.size());
    used_ += bytes.size();
  }
  /// Appends `bytes`, one or more whole records written elsewhere, and ends
  /// the record (end_record) after them.
  void append_record(std::string_view bytes) {
    append(bytes);
    end_record();
  }

  /// The bytes written, whole. Pieces put aside by end_record are joined first.
  std::string take() {
    bytes_.resize(used_);
    used_ = 0;
    if (pieces_.empty()) return std::move(bytes_);
    std::string whole;
    for (const std::string& piece : pieces_) whole += piece;
    whole += bytes_;
    pieces_.clear();
    bytes_.clear();
    return whole;
  }

  /// Marks the end of a record: once the current piece holds piece_bytes or
  /// more, it is put aside and a new one begun. A section hundreds of megabytes
  /// long (a million fragments) is then never one string grown by doubling,
  /// which holds up to twice its size and touches three times it while copying.
  void end_record() {
    if (used_ < piece_bytes) return;
    if (flush_) {
      flush_(std::string_view(bytes_.data(), used_));
      used_ = 0;  // the buffer is kept for the next piece
      return;
    }
    bytes_.resize(used_);
    pieces_.push_back(std::move(bytes_));
    bytes_ = std::string();
    used_ = 0;
  }
  static constexpr std::size_t piece_bytes = std::size_t{1} << 20;

  /// The bytes written, in the pieces end_record made (the last may be empty).
  std::vector<std::string> take_pieces() {
    bytes_.resize(used_);
    pieces_.push_back(std::move(bytes_));
    bytes_ = std::string();
    used_ = 0;
    return std::move(pieces_);
  }

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
    append(std::string_view(bytes, sizeof bytes));
  }

  // Grows the buffer so that `more` bytes fit after the used ones, by doubling
  // (its size is its capacity: the bytes past used_ are room, written before
  // they are used). Out of line: the writers above test for room inline, and a
  // byte at a time through std::string::push_back was a call each (3 % of the
  // instructions of `fracture` cube -> 8,192, callgrind).
  [[gnu::noinline]] void make_room(std::size_t more) {
    bytes_.resize(std::max({2 * bytes_.size(), used_ + more, std::size_t{256}}));
  }

  std::vector<std::string> pieces_;  ///< full pieces put aside by end_record, in order
  std::function<void(std::string_view)> flush_;  ///< where full pieces go instead, when set

  std::string bytes_;  ///< the current piece's first used_ bytes, then room
  std::size_t used_ = 0;
};

// ---------------------------------------------------------------------------
// Decoding

inline std::uint32_t load_u32(std::string_view bytes, std::size_t at) {
  std::uint32_t value = 0;
  for (std::size_t k = 0; k < 4; ++k) value |= std::uint32_t{static_cast<unsigned char>(bytes[at + k])} << (8 * k);
  return value;
}

inline std::uint64_t load_u64(std::string_view bytes, std::size_t at) {
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
  std::optional<Section> pattern;           // optional, in any version
  std::optional<Section> input_repair;      // optional, in any version
  std::optional<Section> cell_planes;       // version 3, a cell tree's only
};

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
  void set_record(std::string record) {
    record_ = std::move(record);
    record_kind_ = nullptr;
  }
  /// The same as set_record(kind + " " + index), the name made only if a
  /// failure needs it: a file of 600,000 bonds made as many strings to read them.
  /// `kind` must outlive the reading (a string literal).
  void set_record(const char* kind, std::size_t index) {
    record_kind_ = kind;
    record_index_ = index;
  }

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
  /// An unsigned LEB128 varint of at most `bits` bits (32 or 64); a value that
  /// does not fit is refused. Longer forms than needed are read as written.
  std::uint64_t varint(const char* field, int bits = 32) {
    const std::size_t at = offset();
    std::uint64_t value = 0;
    for (int shift = 0;; shift += 7) {
      const std::uint8_t byte = u8(field);
      const std::uint64_t group = byte & 0x7Fu;
      // Refused when this group would set a bit at or above `bits`.
      if (shift >= bits || (bits - shift < 7 && (group >> (bits - shift)) != 0)) {
        fail_at(at, std::string(field) + " does not fit in " + str(bits) + " bits");
      }
      value |= group << shift;
      if ((byte & 0x80u) == 0) return value;
    }
  }
  std::uint32_t varint32(const char* field) { return static_cast<std::uint32_t>(varint(field, 32)); }
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
    const std::string record = record_kind_ != nullptr ? std::string(record_kind_) + " " + str(record_index_) : record_;
    refuse("damaged .shatter file: " + section_name(tag_) + " section, byte " + str(at) + (record.empty() ? "" : ", " + record) + ": " + problem);
  }

 private:
  std::string_view payload_;
  std::size_t payload_offset_;
  std::size_t position_ = 0;
  Tag tag_;
  std::string record_;
  const char* record_kind_ = nullptr;  // with record_index_, the record when set so (set_record)
  std::size_t record_index_ = 0;
};

// ---------------------------------------------------------------------------
// Mesh records' attribute channels, alike in every version

/// The channel flags byte of a mesh record: bit 0 normals, 1 uvs, 2 tangents.
inline std::uint8_t channel_flags(const Mesh& mesh) {
  return static_cast<std::uint8_t>((mesh.corners.has_normals() ? normals_bit : 0) | (mesh.corners.has_uvs() ? uvs_bit : 0) |
                                   (mesh.corners.has_tangents() ? tangents_bit : 0));
}

/// Reads a channel flags byte, refusing unknown bits, and any channel on a mesh
/// without triangles (a channel is present when it holds values, so accepting
/// bits there would decode to a mesh that encodes differently).
inline std::uint8_t read_channel_flags(PayloadReader& in, std::uint64_t triangle_count) {
  const std::size_t at = in.offset();
  const std::uint8_t channels = in.u8("channel flags");
  if ((channels & ~known_channel_bits) != 0) in.fail_at(at, "unknown attribute channel bits " + hex(channels, 2));
  if (triangle_count == 0 && channels != 0) {
    in.fail_at(at, "attribute channel bits " + hex(channels, 2) + " for a mesh without triangles (must be 0)");
  }
  return channels;
}

/// Writes the mesh's present channels, 3T values each (corner c of triangle t
/// at 3t + c): normals f64 x3, uvs f64 x2, tangents f64 x4.
inline void write_corner_channels(ByteWriter& out, const Mesh& mesh) {
  for (const Vec3& normal : mesh.corners.normals) out.vec3(normal);
  for (const Vec2& uv : mesh.corners.uvs) out.vec2(uv);
  for (const Vec4& tangent : mesh.corners.tangents) out.vec4(tangent);
}

/// Reads the channels `channels` names into `mesh`, laid out as
/// write_corner_channels writes them, checking the room before sizing each.
inline void read_corner_channels(PayloadReader& in, std::uint8_t channels, std::uint64_t triangle_count, Mesh& mesh) {
  const std::uint64_t corner_count = 3 * triangle_count;
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
}

// ---------------------------------------------------------------------------
// SOLD records' bytes that every version lays out alike

/// Reads a SOLD record's flags byte into the node's and its solid's convex flags.
inline void read_solid_flags(PayloadReader& in, MeshTreeNode& node) {
  const std::size_t at = in.offset();
  const std::uint8_t flags = in.u8("solid flags");
  if ((flags & ~(node_convex_bit | solid_convex_bit)) != 0) in.fail_at(at, "unknown solid flag bits " + hex(flags, 2));
  node.convex = (flags & node_convex_bit) != 0;
  node.solid->convex = (flags & solid_convex_bit) != 0;
}

/// Reads vertex `vertex`'s kind byte, refusing an unknown kind.
inline PointKind read_point_kind(PayloadReader& in, std::size_t vertex) {
  const std::size_t at = in.offset();
  const std::uint8_t kind = in.u8("vertex kind");
  if (kind > static_cast<std::uint8_t>(last_point_kind)) in.fail_at(at, "vertex " + str(vertex) + " has unknown kind " + str(kind));
  return static_cast<PointKind>(kind);
}

/// Reads a face's flags byte into its reversed and convex flags.
inline void read_face_flags(PayloadReader& in, SolidFace& face) {
  const std::size_t at = in.offset();
  const std::uint8_t flags = in.u8("face flags");
  if ((flags & ~(face_reversed_bit | face_convex_bit)) != 0) in.fail_at(at, "unknown face flag bits " + hex(flags, 2));
  face.reversed = (flags & face_reversed_bit) != 0;
  face.convex = (flags & face_convex_bit) != 0;
}

/// Faces take their loops, and loops their corners, in order: gives the next
/// range of `count` items its `first` (the running sum `next`), refusing a sum
/// beyond the record's `total`. `count_at`: where the count was read.
inline std::uint32_t next_range(PayloadReader& in, std::size_t count_at, std::uint32_t count, std::uint64_t& next,
                                std::uint32_t total, const char* owners, const char* items) {
  const auto first = static_cast<std::uint32_t>(next);
  next += count;
  if (next > total) {
    in.fail_at(count_at, std::string("the ") + owners + " claim " + str(next) + " " + items + " or more, of " + str(total));
  }
  return first;
}

/// Where each record of a decoded tree came from, to place a defect in the file.
struct RecordOffsets {
  std::vector<std::size_t> nodes, meshes, hulls, solids;
  std::vector<std::size_t> bonds;  ///< version 3 (bonds of varying size); earlier versions compute them
  std::size_t point_count = 0;
};

// ---------------------------------------------------------------------------
// The optional `rpar` section, alike in every version (file.cpp)

/// What is wrong with a repair text (file.hpp, `rpar`: a line without control
/// characters), or nullopt.
std::optional<std::string> repair_text_problem(std::string_view text);
/// The `rpar` payload of `report`. Precondition: every text passes
/// repair_text_problem (write_shatter checks).
std::string repair_payload(const RepairReport& report);
/// Reads an `rpar` payload; refuses with CorruptFileError what file.hpp does not allow.
RepairReport read_repair(const Section& section);

// ---------------------------------------------------------------------------
// Version 3 payloads (file_v3.cpp)

/// A section's payload: written into the given writer, which may hand it on in
/// pieces as it goes (ByteWriter's flush) or keep them (take_pieces).
using SectionPayload = std::function<void(ByteWriter&)>;

/// Hands `emit` the version 3 sections of `tree` one at a time, in the order
/// encode_shatter writes them, END last, each as the function that writes its
/// payload, to be called once during `emit`'s call.
/// Precondition: `tree` passes validate_tree with its caches (or none, as
/// encode_shatter allows); with `masses_derived`, every node's mass is also
/// mass_properties of its mesh bit for bit (a certificate that says so holds,
/// TreeCertificate::masses_derived), so the masses are left out without being
/// recomputed. Without it each is recomputed and compared, and all are stored
/// when any differs: the same bytes either way for such a tree.
void write_version3_sections(const MeshTree& tree, bool masses_derived,
                             const std::function<void(Tag, const SectionPayload&)>& emit);

/// What a version 3 file leaves to compute once the tree's structure has passed
/// validate_tree and its caches are filled: per node, per mesh (hull) vertex,
/// the solid vertex (mesh vertex) whose position it takes, no_index where the
/// position was stored; and whether the masses are the meshes' own.
struct Version3Pending {
  std::vector<std::vector<std::uint32_t>> mesh_sources, hull_sources;
  bool masses_derived = true;
};

// The version 3 readers, in the order decode_shatter calls them: NODE (after
// OPTS: seeds derive from the recipe), then GEOM, SOLD, MESH, HULL, and BOND
// (once tree.leaf_nodes is filled). Each refuses with CorruptFileError what it
// cannot decode, and leaves the rest to validate_tree; the structure they build
// from child counts is a tree by construction.
void read_version3_nodes(const Section& section, MeshTree& tree, Version3Pending& pending, RecordOffsets& offsets);
void read_version3_solids(const Section& section, MeshTree& tree, RecordOffsets& offsets);
/// Appends the CELL section's planes to tree.cut_planes (after the nodes' own).
void read_cell_planes(const Section& section, MeshTree& tree);
void read_version3_bonds(const Section& section, MeshTree& tree, RecordOffsets& offsets);
/// SOLD, MESH, HULL and BOND (with tree.leaf_nodes), SOLD beside the other
/// three; refuses what reading them in that order refuses, with the same
/// message (the first failure in section and record order).
void read_version3_shapes(const SectionTable& sections, MeshTree& tree, Version3Pending& pending, RecordOffsets& offsets);
/// Fills the derived positions and masses. Precondition: the tree passed
/// validate_tree without caches and its caches are filled.
void finish_version3(MeshTree& tree, const Version3Pending& pending);

}  // namespace shatter::file_layout
