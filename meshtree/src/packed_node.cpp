#include "shatter/meshtree/packed_node.hpp"

#include <algorithm>
#include <bit>
#include <cstring>
#include <stdexcept>
#include <string>

#include "shatter/kernel/position_key.hpp"
#include "shatter/meshtree/tree.hpp"
#include "validate_tree_certificate.hpp"

namespace shatter {

namespace {

// Little-endian base-128 varints (LEB128). A plane reference is coded 0 for
// none, 2i + 1 for input plane i and 2d + 2 for cut plane d (the builder's
// depth, or a node where the names are the tree's), so the common ones take a
// byte; an optional index (no_index: none) is coded + 1.

constexpr std::uint8_t solid_convex_bit = 1;
constexpr std::uint8_t named_by_node_bit = 2;
constexpr std::uint8_t positions_coded_bit = 4;
constexpr std::uint8_t face_reversed_bit = 1;
constexpr std::uint8_t face_convex_bit = 2;

bool same_bits(Vec3 a, Vec3 b) {
  return std::bit_cast<std::uint64_t>(a.x) == std::bit_cast<std::uint64_t>(b.x) &&
         std::bit_cast<std::uint64_t>(a.y) == std::bit_cast<std::uint64_t>(b.y) &&
         std::bit_cast<std::uint64_t>(a.z) == std::bit_cast<std::uint64_t>(b.z);
}

class Packer {
 public:
  /// Appends to `bytes`.
  explicit Packer(std::vector<std::uint8_t>& bytes) : bytes_(bytes) {}
  void varint(std::uint64_t value) {
    while (value >= 0x80) {
      bytes_.push_back(static_cast<std::uint8_t>(value | 0x80));
      value >>= 7;
    }
    bytes_.push_back(static_cast<std::uint8_t>(value));
  }
  void u8(std::uint8_t value) { bytes_.push_back(value); }
  template <class T>
  void raw(std::span<const T> values) {
    const auto* at = reinterpret_cast<const std::uint8_t*>(values.data());
    bytes_.insert(bytes_.end(), at, at + values.size() * sizeof(T));
  }
  template <class T>
  void raw(const std::vector<T>& values) {
    raw(std::span<const T>(values));
  }
  void plane(PlaneRef plane) {
    if (plane.bits == no_index) {
      varint(0);
    } else {
      varint(2 * std::uint64_t{plane.index()} + (plane.is_cut() ? 2 : 1));
    }
  }
  void optional_index(std::uint32_t index) { varint(index == no_index ? 0 : std::uint64_t{index} + 1); }

 private:
  std::vector<std::uint8_t>& bytes_;
};

// The unpacker's failures, out of line: the reads they guard are the writer's
// and the bonds' inner loops (every node is unpacked again for each), and an
// inline throw that builds its message kept the compiler from inlining them.
[[noreturn, gnu::cold, gnu::noinline]] void fail_unpacking(const char* what) { throw std::invalid_argument(what); }
[[noreturn, gnu::cold, gnu::noinline]] void fail_unpacking(const char* what, std::uint64_t value, const char* after = "") {
  throw std::invalid_argument(what + std::to_string(value) + after);
}

class Unpacker {
 public:
  Unpacker(std::span<const std::uint8_t> bytes, std::span<const NodeIndex> path) : bytes_(bytes), path_(path) {}

  std::uint64_t varint() {
    // Most values take one byte (indices of a small piece, plane codes), most
    // others two (indices of a piece of up to 16,384 vertices).
    if (at_ + 1 < bytes_.size()) {
      const std::uint8_t low = bytes_[at_];
      if (low < 0x80) {
        ++at_;
        return low;
      }
      const std::uint8_t high = bytes_[at_ + 1];
      if (high < 0x80) {
        at_ += 2;
        return (low & 0x7fu) | (std::uint64_t{high} << 7);
      }
    } else if (at_ < bytes_.size() && bytes_[at_] < 0x80) {
      return bytes_[at_++];
    }
    return long_varint();
  }
  std::uint32_t u32() {
    const std::uint64_t value = varint();
    if (value > 0xffffffffu) fail_unpacking("packed node: a 32-bit value of ", value);
    return static_cast<std::uint32_t>(value);
  }
  /// Steps over `count` values that u32() would read, checked as it checks
  /// them, without decoding them: a value of at most four bytes (the first
  /// under 0x80 ends it) always fits; a longer one is read by u32() itself.
  /// Reading the solid alone stepped over a mesh's corner indices one u32()
  /// at a time.
  void skip_u32s(std::size_t count) {
    const std::uint8_t* const data = bytes_.data();
    const std::size_t end = bytes_.size();
    for (std::size_t i = 0; i < count; ++i) {
      std::size_t at = at_;
      while (at < end && at - at_ < 3 && data[at] >= 0x80) ++at;
      if (at < end && data[at] < 0x80) {
        at_ = at + 1;
      } else {
        u32();
      }
    }
  }
  std::uint8_t u8() {
    if (at_ >= bytes_.size()) fail_unpacking("packed node: cut short");
    return bytes_[at_++];
  }
  /// A count of elements of `size` bytes each that the bytes left could hold.
  std::size_t count(std::size_t size) {
    const std::uint64_t value = varint();
    if (value > (bytes_.size() - at_) / size) fail_unpacking("packed node: a count beyond its bytes");
    return static_cast<std::size_t>(value);
  }
  /// A length in bytes, then that many bytes.
  std::span<const std::uint8_t> block() {
    const std::uint64_t length = varint();
    if (length > bytes_.size() - at_) fail_unpacking("packed node: cut short");
    const std::span<const std::uint8_t> bytes = bytes_.subspan(at_, static_cast<std::size_t>(length));
    at_ += bytes.size();
    return bytes;
  }
  Vec3 vec3() {
    if (sizeof(Vec3) > bytes_.size() - at_) fail_unpacking("packed node: cut short");
    Vec3 value;
    std::memcpy(&value, bytes_.data() + at_, sizeof(Vec3));
    at_ += sizeof(Vec3);
    return value;
  }
  template <class T>
  void raw(std::vector<T>& values, std::size_t count) {
    if (count > (bytes_.size() - at_) / sizeof(T)) fail_unpacking("packed node: cut short");
    values.resize(count);
    if (count != 0) std::memcpy(values.data(), bytes_.data() + at_, count * sizeof(T));
    at_ += count * sizeof(T);
  }
  /// Steps over `count` elements of `size` bytes.
  void skip(std::size_t count, std::size_t size) {
    if (count > (bytes_.size() - at_) / size) fail_unpacking("packed node: cut short");
    at_ += count * size;
  }
  PlaneRef plane() {
    const std::uint64_t code = varint();
    if (code == 0) return PlaneRef{no_index};
    const std::uint64_t index = (code - 1) / 2;
    if ((code & 1) != 0) {
      if (index >= PlaneRef::cut_bit) fail_unpacking("packed node: input plane out of range");
      return PlaneRef::input(static_cast<std::uint32_t>(index));
    }
    return PlaneRef::cut(depth_to_node(index));
  }
  SurfaceId surface() {
    const std::uint32_t surface = u32();
    if (surface == original_surface || path_.empty()) return surface;
    return cap_surface_of(depth_to_node(surface - 1));
  }
  std::uint32_t optional_index() {
    const std::uint64_t code = varint();
    if (code > 0xffffffffu) fail_unpacking("packed node: an index of ", code);
    return code == 0 ? no_index : static_cast<std::uint32_t>(code - 1);
  }
  void expect_end() const {
    if (at_ != bytes_.size()) fail_unpacking("packed node: bytes after its end");
  }

 private:
  [[gnu::noinline]] std::uint64_t long_varint() {
    std::uint64_t value = 0;
    for (int shift = 0; shift < 64; shift += 7) {
      const std::uint8_t byte = u8();
      value |= std::uint64_t{byte & 0x7fu} << shift;
      if ((byte & 0x80) == 0) return value;
    }
    fail_unpacking("packed node: a varint longer than 64 bits");
  }

  std::uint32_t depth_to_node(std::uint64_t depth) const {
    if (path_.empty()) {
      if (depth >= PlaneRef::cut_bit) fail_unpacking("packed node: cut plane out of range");
      return static_cast<std::uint32_t>(depth);
    }
    if (depth >= path_.size()) fail_unpacking("packed node: depth ", depth, " below the node's own");
    return path_[depth];
  }

  std::span<const std::uint8_t> bytes_;
  std::span<const NodeIndex> path_;
  std::size_t at_ = 0;
};

}  // namespace

std::uint64_t PositionCoder::code(std::size_t vertex, Vec3 position) {
  const auto matches = [&](std::int64_t source) {
    return source >= 0 && static_cast<std::size_t>(source) < sources_.size() &&
           same_bits(sources_[static_cast<std::size_t>(source)], position);
  };
  const auto at = static_cast<std::int64_t>(vertex);
  std::int64_t source = -1;
  if (matches(at + offset_)) {
    source = at + offset_;
  } else if (matches(at)) {
    source = at;
  } else {
    source = search(position);
  }
  if (source < 0) return stored;
  offset_ = source - at;
  return 1 + ((static_cast<std::uint64_t>(offset_) << 1) ^ static_cast<std::uint64_t>(offset_ >> 63));
}

std::int64_t PositionCoder::source_of(std::size_t vertex, std::uint64_t code) {
  const std::uint64_t zigzag = code - 1;
  const auto offset = static_cast<std::int64_t>(zigzag >> 1) ^ -static_cast<std::int64_t>(zigzag & 1);
  return static_cast<std::int64_t>(vertex) + offset;
}

std::int64_t PositionCoder::search(Vec3 position) {
  if (slots_.empty()) {
    // At most half full, so a probe ends within a few slots.
    slots_.assign(std::bit_ceil(std::max<std::size_t>(16, 2 * sources_.size())), empty_slot);
    for (std::size_t s = 0; s < sources_.size(); ++s) {
      for (std::size_t slot = slot_of(sources_[s]);; slot = (slot + 1) & (slots_.size() - 1)) {
        if (slots_[slot] == empty_slot) {
          slots_[slot] = static_cast<std::uint32_t>(s);
          break;
        }
        if (same_bits(sources_[slots_[slot]], sources_[s])) break;  // keep the lowest index
      }
    }
  }
  for (std::size_t slot = slot_of(position); slots_[slot] != empty_slot; slot = (slot + 1) & (slots_.size() - 1)) {
    if (same_bits(sources_[slots_[slot]], position)) return slots_[slot];
  }
  return -1;
}

// The kernel's position hash (position_key.hpp; it takes -0 for +0, which only
// makes the two share a slot: same_bits decides), masked to the table.
std::size_t PositionCoder::slot_of(Vec3 position) const {
  return kernel_detail::PositionKeyHash{}(kernel_detail::key_of(position)) & (slots_.size() - 1);
}

std::vector<std::uint8_t> pack_node_shape(const Mesh& mesh, const Solid& solid, bool named_by_node,
                                          const PlaneSet* set) {
  std::vector<std::uint8_t> bytes;
  pack_node_shape(mesh, solid, named_by_node, bytes, set);
  return bytes;
}

void pack_node_shape(const Mesh& mesh, const Solid& solid, bool named_by_node, std::vector<std::uint8_t>& bytes,
                     const PlaneSet* set) {
  bytes.clear();
  Packer out(bytes);
  const bool coded = set != nullptr && solid.approx.size() == solid.defs.size();
  out.u8(static_cast<std::uint8_t>((solid.convex ? solid_convex_bit : 0) | (named_by_node ? named_by_node_bit : 0) |
                                   (coded ? positions_coded_bit : 0)));
  out.varint(mesh.positions.size());
  out.varint(mesh.triangles.size());
  out.varint(mesh.corners.normals.size());
  out.varint(mesh.corners.uvs.size());
  out.varint(mesh.corners.tangents.size());
  if (coded) {
    // The codes' length first, so a reader of the solid alone steps over them.
    thread_local std::vector<Vec3> sources;
    thread_local std::vector<std::uint8_t> codes;
    sources.resize(solid.defs.size());
    for (std::size_t v = 0; v < sources.size(); ++v) sources[v] = output_position(*set, solid.defs[v], solid.approx[v]);
    codes.clear();
    Packer code_out(codes);
    PositionCoder coder(sources);
    for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
      const std::uint64_t code = coder.code(v, mesh.positions[v]);
      code_out.varint(code);
      if (code == PositionCoder::stored) code_out.raw(std::span<const Vec3>(&mesh.positions[v], 1));
    }
    out.varint(codes.size());
    out.raw(codes);
  } else {
    out.raw(mesh.positions);
  }
  for (const Triangle& triangle : mesh.triangles) {
    for (const VertexIndex vertex : triangle) out.varint(vertex);
  }
  // Surfaces in runs (a face's triangles are consecutive); their count first.
  std::size_t runs = 0;
  for (std::size_t t = 0; t < mesh.surfaces.size(); ++t) runs += t == 0 || mesh.surfaces[t] != mesh.surfaces[t - 1] ? 1 : 0;
  out.varint(runs);
  for (std::size_t t = 0; t < mesh.surfaces.size();) {
    std::size_t end = t + 1;
    while (end < mesh.surfaces.size() && mesh.surfaces[end] == mesh.surfaces[t]) ++end;
    out.varint(mesh.surfaces[t]);
    out.varint(end - t);
    t = end;
  }
  out.raw(mesh.corners.normals);
  out.raw(mesh.corners.uvs);
  out.raw(mesh.corners.tangents);

  out.varint(solid.defs.size());
  out.varint(solid.faces.size());
  out.varint(solid.loops.size());
  out.varint(solid.corners.size());
  for (const PointDef& def : solid.defs) {
    out.u8(static_cast<std::uint8_t>(def.kind));
    switch (def.kind) {
      case PointKind::input: out.varint(def.a); break;
      case PointKind::segment_plane:
        out.varint(def.a);
        out.varint(def.b);
        out.plane(def.planes[0]);
        break;
      case PointKind::three_planes:
        for (const PlaneRef plane : def.planes) out.plane(plane);
        break;
    }
  }
  // Ranges as the difference from where the previous one ended (0 when contiguous, as the cut makes them).
  const auto zigzag = [](std::uint64_t value, std::uint64_t expected) {
    const auto difference = static_cast<std::int64_t>(value - expected);
    return (static_cast<std::uint64_t>(difference) << 1) ^ static_cast<std::uint64_t>(difference >> 63);
  };
  std::uint64_t next = 0;
  for (const SolidFace& face : solid.faces) {
    out.plane(face.plane);
    out.u8(static_cast<std::uint8_t>((face.reversed ? face_reversed_bit : 0) | (face.convex ? face_convex_bit : 0)));
    out.varint(face.surface);
    out.varint(face.source);
    out.varint(zigzag(face.first_loop, next));
    out.varint(face.loop_count);
    next = std::uint64_t{face.first_loop} + face.loop_count;
  }
  next = 0;
  for (const SolidLoop& loop : solid.loops) {
    out.varint(zigzag(loop.first_corner, next));
    out.varint(loop.corner_count);
    next = std::uint64_t{loop.first_corner} + loop.corner_count;
  }
  for (const SolidCorner& corner : solid.corners) {
    out.varint(corner.vertex);
    out.plane(corner.line.other);
    out.optional_index(corner.line.p);
    out.optional_index(corner.line.q);
  }
}

namespace {

// A packed mesh's counts, as its header gives them (each checked against the
// bytes left, as unpacking checks them).
struct PackedMeshHeader {
  std::size_t positions, triangles, normals, uvs, tangents;
};

PackedMeshHeader read_mesh_header(Unpacker& in, bool coded) {
  PackedMeshHeader header{};
  header.positions = in.count(coded ? 1 : sizeof(Vec3));  // a code takes a byte at least
  header.triangles = in.count(3);
  header.normals = in.count(sizeof(Vec3));
  header.uvs = in.count(sizeof(Vec2));
  header.tangents = in.count(sizeof(Vec4));
  return header;
}

// Reads past the mesh whose header `header` is, checking its bytes as unpacking
// does; returns how many of its triangles lie on a cut's cap (a surface other
// than the input's, whatever the naming).
std::size_t read_past_mesh(Unpacker& in, const PackedMeshHeader& header, bool coded) {
  if (coded) {
    in.block();
  } else {
    in.skip(header.positions, sizeof(Vec3));
  }
  in.skip_u32s(3 * header.triangles);
  const std::size_t runs = in.count(2);
  std::uint64_t covered = 0, on_caps = 0;
  for (std::size_t r = 0; r < runs; ++r) {
    const SurfaceId surface = in.surface();
    const std::uint64_t length = in.varint();
    if (length > header.triangles - covered) throw std::invalid_argument("packed node: surface runs beyond the triangles");
    covered += length;
    if (surface != original_surface) on_caps += length;
  }
  in.skip(header.normals, sizeof(Vec3));
  in.skip(header.uvs, sizeof(Vec2));
  in.skip(header.tangents, sizeof(Vec4));
  return static_cast<std::size_t>(on_caps);
}

// The flags byte that opens a packing, checked.
std::uint8_t read_flags(Unpacker& in) {
  const std::uint8_t flags = in.u8();
  if ((flags & ~(solid_convex_bit | named_by_node_bit | positions_coded_bit)) != 0) {
    throw std::invalid_argument("packed node: unknown flags");
  }
  return flags;
}

// What a reading of a packing leaves out or keeps as it is (unpack).
struct Reading {
  bool points_only = false;  // the solid's faces, loops and corners neither read nor checked
  // Coded positions left as codes, here (unpack_node_mesh_codes), not computed.
  std::vector<std::uint64_t>* codes = nullptr;
  std::vector<Vec3>* stored = nullptr;
};

// The positions coded in `block` (a packing's, for `count` vertices), each
// computed from the definition its code names, in `set`.
void decode_positions(std::span<const std::uint8_t> block, std::size_t count, std::span<const PointDef> defs,
                      const PlaneSet* set, std::vector<Vec3>& positions) {
  if (set == nullptr) fail_unpacking("packed node: its positions are coded, and no plane set was given");
  Unpacker in(block, {});
  positions.resize(count);
  for (std::size_t v = 0; v < count; ++v) {
    const std::uint64_t code = in.varint();
    if (code == PositionCoder::stored) {
      positions[v] = in.vec3();
      continue;
    }
    const std::int64_t source = PositionCoder::source_of(v, code);
    if (source < 0 || static_cast<std::uint64_t>(source) >= defs.size()) {
      fail_unpacking("packed node: a position code names no definition, at vertex ", v);
    }
    const PointDef& def = defs[static_cast<std::size_t>(source)];
    positions[v] = output_position(*set, def, approximate(*set, def));
  }
  in.expect_end();
}

// The codes in `block` as they are, and the positions stored among them.
void read_position_codes(std::span<const std::uint8_t> block, std::size_t count, std::vector<std::uint64_t>& codes,
                         std::vector<Vec3>& stored) {
  Unpacker in(block, {});
  codes.resize(count);
  stored.clear();
  for (std::uint64_t& code : codes) {
    code = in.varint();
    if (code == PositionCoder::stored) stored.push_back(in.vec3());
  }
  in.expect_end();
}

// Unpacks into `mesh` and `solid`; a null `mesh` is read past (its bytes
// checked as they are when unpacked) and left out; with a null `solid` the
// reading stops after the mesh (the solid's bytes are neither read nor checked)
// or, when its positions are coded and computed, after the solid's point
// definitions they are computed from; `reading` says what else is left out.
void unpack(std::span<const std::uint8_t> bytes, std::span<const NodeIndex> path, Mesh* mesh, Solid* solid_out,
            const PlaneSet* set, const Reading& reading = {}) {
  if (bytes.empty()) throw std::invalid_argument("packed node: cut short");
  // Names that are already the tree's are kept whatever the path.
  const bool named_by_node = (bytes[0] & named_by_node_bit) != 0;
  Unpacker in(bytes, named_by_node ? std::span<const NodeIndex>() : path);
  const std::uint8_t flags = read_flags(in);
  const bool coded = (flags & positions_coded_bit) != 0;
  const PackedMeshHeader header = read_mesh_header(in, coded);
  const std::size_t position_count = header.positions, triangle_count = header.triangles;
  std::span<const std::uint8_t> code_block;
  if (mesh == nullptr) {
    read_past_mesh(in, header, coded);
  } else {
    if (coded) {
      code_block = in.block();
      mesh->positions.clear();
    } else {
      in.raw(mesh->positions, position_count);
    }
    mesh->triangles.resize(triangle_count);
    for (Triangle& triangle : mesh->triangles) {
      for (VertexIndex& vertex : triangle) vertex = in.u32();
    }
    const std::size_t runs = in.count(2);
    mesh->surfaces.clear();
    mesh->surfaces.reserve(triangle_count);
    for (std::size_t r = 0; r < runs; ++r) {
      const SurfaceId surface = in.surface();
      const std::uint64_t length = in.varint();
      if (length > triangle_count - mesh->surfaces.size()) throw std::invalid_argument("packed node: surface runs beyond the triangles");
      mesh->surfaces.insert(mesh->surfaces.end(), static_cast<std::size_t>(length), surface);
    }
    in.raw(mesh->corners.normals, header.normals);
    in.raw(mesh->corners.uvs, header.uvs);
    in.raw(mesh->corners.tangents, header.tangents);
  }
  if (reading.codes != nullptr) {
    if (!coded) fail_unpacking("packed node: its positions are not coded");
    read_position_codes(code_block, position_count, *reading.codes, *reading.stored);
    return;
  }
  const bool compute_positions = mesh != nullptr && coded;
  if (solid_out == nullptr && !compute_positions) return;

  // The definitions go to a scratch solid when only the positions need them.
  thread_local Solid scratch;
  Solid& solid = solid_out != nullptr ? *solid_out : scratch;
  solid.convex = (flags & solid_convex_bit) != 0;
  const std::size_t def_count = in.count(2);
  const std::size_t face_count = in.count(6);
  const std::size_t loop_count = in.count(2);
  const std::size_t corner_count = in.count(4);
  solid.approx.clear();
  solid.defs.resize(def_count);
  for (PointDef& def : solid.defs) {
    def = PointDef{};
    const std::uint8_t kind = in.u8();
    if (kind > static_cast<std::uint8_t>(last_point_kind)) throw std::invalid_argument("packed node: unknown point kind");
    def.kind = static_cast<PointKind>(kind);
    switch (def.kind) {
      case PointKind::input: def.a = in.u32(); break;
      case PointKind::segment_plane:
        def.a = in.u32();
        def.b = in.u32();
        def.planes[0] = in.plane();
        break;
      case PointKind::three_planes:
        for (PlaneRef& plane : def.planes) plane = in.plane();
        break;
    }
  }
  if (compute_positions) decode_positions(code_block, position_count, solid.defs, set, mesh->positions);
  if (solid_out == nullptr || reading.points_only) {
    solid.faces.clear();
    solid.loops.clear();
    solid.corners.clear();
    return;
  }
  const auto unzigzag = [](std::uint64_t code, std::uint64_t expected) {
    const auto difference = static_cast<std::int64_t>(code >> 1) ^ -static_cast<std::int64_t>(code & 1);
    return static_cast<std::uint32_t>(expected + static_cast<std::uint64_t>(difference));
  };
  std::uint64_t next = 0;
  solid.faces.resize(face_count);
  for (SolidFace& face : solid.faces) {
    face.plane = in.plane();
    const std::uint8_t face_flags = in.u8();
    if ((face_flags & ~(face_reversed_bit | face_convex_bit)) != 0) throw std::invalid_argument("packed node: unknown face flags");
    face.reversed = (face_flags & face_reversed_bit) != 0;
    face.convex = (face_flags & face_convex_bit) != 0;
    face.surface = in.surface();
    face.source = in.u32();
    face.first_loop = unzigzag(in.varint(), next);
    face.loop_count = in.u32();
    next = std::uint64_t{face.first_loop} + face.loop_count;
  }
  next = 0;
  solid.loops.resize(loop_count);
  for (SolidLoop& loop : solid.loops) {
    loop.first_corner = unzigzag(in.varint(), next);
    loop.corner_count = in.u32();
    next = std::uint64_t{loop.first_corner} + loop.corner_count;
  }
  solid.corners.resize(corner_count);
  for (SolidCorner& corner : solid.corners) {
    corner.vertex = in.u32();
    corner.line.other = in.plane();
    corner.line.p = in.optional_index();
    corner.line.q = in.optional_index();
  }
  in.expect_end();
}

}  // namespace

bool packed_positions_coded(std::span<const std::uint8_t> bytes) {
  if (bytes.empty()) throw std::invalid_argument("packed node: cut short");
  return (bytes[0] & positions_coded_bit) != 0;
}

void unpack_node_shape(std::span<const std::uint8_t> bytes, std::span<const NodeIndex> path, Mesh& mesh,
                       Solid& solid, const PlaneSet* set) {
  unpack(bytes, path, &mesh, &solid, set);
}

void unpack_node_solid(std::span<const std::uint8_t> bytes, std::span<const NodeIndex> path, Solid& solid) {
  unpack(bytes, path, nullptr, &solid, nullptr);
}

void unpack_node_mesh(std::span<const std::uint8_t> bytes, std::span<const NodeIndex> path, Mesh& mesh,
                      const PlaneSet* set) {
  unpack(bytes, path, &mesh, nullptr, set);
}

void unpack_node_mesh_and_points(std::span<const std::uint8_t> bytes, std::span<const NodeIndex> path, Mesh& mesh,
                                 Solid& points, const PlaneSet* set) {
  unpack(bytes, path, &mesh, &points, set, Reading{true});
}

void unpack_node_mesh_codes(std::span<const std::uint8_t> bytes, std::span<const NodeIndex> path, Mesh& mesh,
                            std::vector<std::uint64_t>& codes, std::vector<Vec3>& stored) {
  unpack(bytes, path, &mesh, nullptr, nullptr, Reading{false, &codes, &stored});
}

PackedMeshSizes packed_mesh_sizes(std::span<const std::uint8_t> bytes) {
  if (bytes.empty()) throw std::invalid_argument("packed node: cut short");
  // No path: the surface ids are compared with the input's alone, which no
  // renaming changes.
  Unpacker in(bytes, {});
  const bool coded = (read_flags(in) & positions_coded_bit) != 0;
  const PackedMeshHeader header = read_mesh_header(in, coded);
  PackedMeshSizes sizes;
  sizes.vertices = header.positions;
  sizes.triangles = header.triangles;
  sizes.cap_triangles = read_past_mesh(in, header, coded);
  return sizes;
}

void rename_by_path(std::span<const NodeIndex> path, Mesh& mesh, Solid& solid) {
  for (SurfaceId& surface : mesh.surfaces) {
    if (surface != original_surface) surface = cap_surface_of(path[surface - 1]);
  }
  for (SolidFace& face : solid.faces) {
    if (face.surface != original_surface) face.surface = cap_surface_of(path[face.surface - 1]);
    if (face.plane.is_cut()) face.plane = PlaneRef::cut(path[face.plane.index()]);
  }
  for (SolidCorner& corner : solid.corners) {
    if (corner.line.other.bits != no_index && corner.line.other.is_cut()) {
      corner.line.other = PlaneRef::cut(path[corner.line.other.index()]);
    }
  }
  for (PointDef& def : solid.defs) {
    const int planes = def.kind == PointKind::segment_plane ? 1 : def.kind == PointKind::three_planes ? 3 : 0;
    for (int k = 0; k < planes; ++k) {
      if (def.planes[k].is_cut()) def.planes[k] = PlaneRef::cut(path[def.planes[k].index()]);
    }
  }
}

void pack_leaves(MeshTree& tree) {
  if (!tree.has_exact_representation()) return;
  // A lean build packs every leaf itself: then nothing changes, and the
  // certificate is left as it is rather than re-taken (two digests of the tree).
  if (std::all_of(tree.leaf_nodes.begin(), tree.leaf_nodes.end(), [&](NodeIndex k) { return tree.is_packed(k); })) return;
  // Packing changes the representation, not the tree (NodeShapes gives back
  // the same meshes and solids, bit for bit; a packed leaf has no approx, which
  // validate_tree allows): a certificate that held before holds after, and is
  // carried across by taking the digest again. One that did not hold is dropped.
  const bool certified = detail::TreeCertifier::holds(tree);
  const bool masses_derived = tree.certificate.masses_derived();
  detail::TreeCertifier::clear(tree);
  if (tree.packed_shapes.empty()) tree.packed_shapes.resize(tree.nodes.size());
  const PlaneSet set = tree.plane_set();
  for (const NodeIndex k : tree.leaf_nodes) {
    MeshTreeNode& leaf = tree.nodes[k];
    if (tree.is_packed(k)) continue;
    tree.packed_shapes.assign(k, pack_node_shape(leaf.mesh, leaf.solid, true, &set));
    leaf.mesh = Mesh();
    leaf.solid = Solid();
  }
  if (certified) detail::TreeCertifier::certify(tree, masses_derived);
}

// Callers go through nodes in order (preorder, or leaf order), so the previous
// node's path mostly holds this one's: the walk up stops at the first ancestor
// already in place, whose own ancestors fill the entries before it (each walk
// writes a chain of parents, so the entries kept are one). Walking to the root
// each time was 3 % of `fracture` cube -> 65,536, a cache miss a level. A node
// whose parent's depth is not one less (a malformed tree, which validate_tree
// reports) is walked in full, as before, and so is every node after it.
void NodeShapes::find_path(NodeIndex node) {
  const std::size_t size = std::size_t{tree_.nodes[node].depth} + 1;
  if (path_is_chain_) {
    path_.resize(size, no_node);
    for (NodeIndex a = node; a != no_node; a = tree_.nodes[a].parent) {
      const MeshTreeNode& at = tree_.nodes[a];
      const NodeIndex parent = at.parent;
      const bool consistent = at.depth < size && (parent == no_node ? at.depth == 0 : tree_.nodes[parent].depth + 1 == at.depth);
      if (!consistent) break;
      if (path_[at.depth] == a) return;
      path_[at.depth] = a;
      if (parent == no_node) return;
    }
  }
  // A malformed chain: every ancestor whose depth fits, as validate_tree's
  // reports expect; nothing of it is kept for the next walk.
  path_.assign(size, no_node);
  for (NodeIndex a = node; a != no_node && tree_.nodes[a].depth < path_.size(); a = tree_.nodes[a].parent) {
    path_[tree_.nodes[a].depth] = a;
  }
  path_is_chain_ = false;
}

NodeShape NodeShapes::operator()(NodeIndex node) {
  const MeshTreeNode& own = tree_.nodes[node];
  if (!tree_.is_packed(node)) return {own.mesh, own.solid};
  find_path(node);
  const PlaneSet set = tree_.plane_set();
  unpack_node_shape(tree_.packed_shapes[node], path_, mesh_, solid_, &set);
  return {mesh_, solid_};
}

const Mesh& NodeShapes::mesh(NodeIndex node) {
  const MeshTreeNode& own = tree_.nodes[node];
  if (!tree_.is_packed(node)) return own.mesh;
  find_path(node);
  const PlaneSet set = tree_.plane_set();
  unpack_node_mesh(tree_.packed_shapes[node], path_, mesh_, &set);
  return mesh_;
}

NodePoints NodeShapes::mesh_and_points(NodeIndex node) {
  const MeshTreeNode& own = tree_.nodes[node];
  if (!tree_.is_packed(node)) return {own.mesh, own.solid->defs, own.solid->approx};
  find_path(node);
  const PlaneSet set = tree_.plane_set();
  unpack_node_mesh_and_points(tree_.packed_shapes[node], path_, mesh_, solid_, &set);
  return {mesh_, solid_.defs, solid_.approx};
}

std::optional<NodeMeshCodes> NodeShapes::mesh_codes(NodeIndex node) {
  if (!tree_.is_packed(node) || !packed_positions_coded(tree_.packed_shapes[node])) return std::nullopt;
  find_path(node);
  unpack_node_mesh_codes(tree_.packed_shapes[node], path_, mesh_, codes_, stored_);
  return NodeMeshCodes{mesh_, codes_, stored_};
}

const Solid& NodeShapes::solid(NodeIndex node) {
  const MeshTreeNode& own = tree_.nodes[node];
  if (!tree_.is_packed(node)) return own.solid;
  find_path(node);
  unpack_node_solid(tree_.packed_shapes[node], path_, solid_);
  return solid_;
}

}  // namespace shatter
