#include "shatter/meshtree/packed_node.hpp"

#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <string>

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
constexpr std::uint8_t face_reversed_bit = 1;
constexpr std::uint8_t face_convex_bit = 2;

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
  void raw(const std::vector<T>& values) {
    const auto* at = reinterpret_cast<const std::uint8_t*>(values.data());
    bytes_.insert(bytes_.end(), at, at + values.size() * sizeof(T));
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

std::vector<std::uint8_t> pack_node_shape(const Mesh& mesh, const Solid& solid, bool named_by_node) {
  std::vector<std::uint8_t> bytes;
  pack_node_shape(mesh, solid, named_by_node, bytes);
  return bytes;
}

void pack_node_shape(const Mesh& mesh, const Solid& solid, bool named_by_node, std::vector<std::uint8_t>& bytes) {
  bytes.clear();
  Packer out(bytes);
  out.u8(static_cast<std::uint8_t>((solid.convex ? solid_convex_bit : 0) | (named_by_node ? named_by_node_bit : 0)));
  out.varint(mesh.positions.size());
  out.varint(mesh.triangles.size());
  out.varint(mesh.corners.normals.size());
  out.varint(mesh.corners.uvs.size());
  out.varint(mesh.corners.tangents.size());
  out.raw(mesh.positions);
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

PackedMeshHeader read_mesh_header(Unpacker& in) {
  PackedMeshHeader header{};
  header.positions = in.count(sizeof(Vec3));
  header.triangles = in.count(3);
  header.normals = in.count(sizeof(Vec3));
  header.uvs = in.count(sizeof(Vec2));
  header.tangents = in.count(sizeof(Vec4));
  return header;
}

// Reads past the mesh whose header `header` is, checking its bytes as unpacking
// does; returns how many of its triangles lie on a cut's cap (a surface other
// than the input's, whatever the naming).
std::size_t read_past_mesh(Unpacker& in, const PackedMeshHeader& header) {
  in.skip(header.positions, sizeof(Vec3));
  for (std::size_t i = 0; i < 3 * header.triangles; ++i) in.u32();
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
  if ((flags & ~(solid_convex_bit | named_by_node_bit)) != 0) throw std::invalid_argument("packed node: unknown flags");
  return flags;
}

// Unpacks into `mesh` and `solid`; a null `mesh` is read past (its bytes
// checked as they are when unpacked) and left out; with a null `solid` the
// reading stops after the mesh (the solid's bytes are neither read nor checked);
// with `points_only` it stops after the solid's point definitions (its faces,
// loops and corners are left empty, their bytes neither read nor checked).
void unpack(std::span<const std::uint8_t> bytes, std::span<const NodeIndex> path, Mesh* mesh, Solid* solid_out,
            bool points_only = false) {
  if (bytes.empty()) throw std::invalid_argument("packed node: cut short");
  // Names that are already the tree's are kept whatever the path.
  const bool named_by_node = (bytes[0] & named_by_node_bit) != 0;
  Unpacker in(bytes, named_by_node ? std::span<const NodeIndex>() : path);
  const std::uint8_t flags = read_flags(in);
  const PackedMeshHeader header = read_mesh_header(in);
  const std::size_t position_count = header.positions, triangle_count = header.triangles;
  if (mesh == nullptr) {
    read_past_mesh(in, header);
  } else {
    in.raw(mesh->positions, position_count);
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
  if (solid_out == nullptr) return;

  Solid& solid = *solid_out;
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
  if (points_only) {
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

void unpack_node_shape(std::span<const std::uint8_t> bytes, std::span<const NodeIndex> path, Mesh& mesh,
                       Solid& solid) {
  unpack(bytes, path, &mesh, &solid);
}

void unpack_node_solid(std::span<const std::uint8_t> bytes, std::span<const NodeIndex> path, Solid& solid) {
  unpack(bytes, path, nullptr, &solid);
}

void unpack_node_mesh(std::span<const std::uint8_t> bytes, std::span<const NodeIndex> path, Mesh& mesh) {
  unpack(bytes, path, &mesh, nullptr);
}

void unpack_node_mesh_and_points(std::span<const std::uint8_t> bytes, std::span<const NodeIndex> path, Mesh& mesh,
                                 Solid& points) {
  unpack(bytes, path, &mesh, &points, true);
}

PackedMeshSizes packed_mesh_sizes(std::span<const std::uint8_t> bytes) {
  if (bytes.empty()) throw std::invalid_argument("packed node: cut short");
  // No path: the surface ids are compared with the input's alone, which no
  // renaming changes.
  Unpacker in(bytes, {});
  read_flags(in);
  const PackedMeshHeader header = read_mesh_header(in);
  PackedMeshSizes sizes;
  sizes.vertices = header.positions;
  sizes.triangles = header.triangles;
  sizes.cap_triangles = read_past_mesh(in, header);
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
  for (const NodeIndex k : tree.leaf_nodes) {
    MeshTreeNode& leaf = tree.nodes[k];
    if (tree.is_packed(k)) continue;
    tree.packed_shapes.assign(k, pack_node_shape(leaf.mesh, leaf.solid, true));
    leaf.mesh = Mesh();
    leaf.solid = Solid();
  }
  if (certified) detail::TreeCertifier::certify(tree, masses_derived);
}

void NodeShapes::find_path(NodeIndex node) {
  path_.assign(std::size_t{tree_.nodes[node].depth} + 1, no_node);
  for (NodeIndex a = node; a != no_node && tree_.nodes[a].depth < path_.size(); a = tree_.nodes[a].parent) {
    path_[tree_.nodes[a].depth] = a;
  }
}

NodeShape NodeShapes::operator()(NodeIndex node) {
  const MeshTreeNode& own = tree_.nodes[node];
  if (!tree_.is_packed(node)) return {own.mesh, own.solid};
  find_path(node);
  unpack_node_shape(tree_.packed_shapes[node], path_, mesh_, solid_);
  return {mesh_, solid_};
}

const Mesh& NodeShapes::mesh(NodeIndex node) {
  const MeshTreeNode& own = tree_.nodes[node];
  if (!tree_.is_packed(node)) return own.mesh;
  find_path(node);
  unpack_node_mesh(tree_.packed_shapes[node], path_, mesh_);
  return mesh_;
}

NodePoints NodeShapes::mesh_and_points(NodeIndex node) {
  const MeshTreeNode& own = tree_.nodes[node];
  if (!tree_.is_packed(node)) return {own.mesh, own.solid->defs, own.solid->approx};
  find_path(node);
  unpack_node_mesh_and_points(tree_.packed_shapes[node], path_, mesh_, solid_);
  return {mesh_, solid_.defs, solid_.approx};
}

const Solid& NodeShapes::solid(NodeIndex node) {
  const MeshTreeNode& own = tree_.nodes[node];
  if (!tree_.is_packed(node)) return own.solid;
  find_path(node);
  unpack_node_solid(tree_.packed_shapes[node], path_, solid_);
  return solid_;
}

}  // namespace shatter
