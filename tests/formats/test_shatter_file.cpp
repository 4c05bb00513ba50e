// Properties of the .shatter file: the bytes are exactly the layout file.hpp
// documents; trees round-trip field by field and bit for bit (hand-built ones with
// every kind of special double, and built ones of every kernel, the plane
// kernel's exact representation and recomputed caches included); version 1 files
// still read; and every truncation, every single-byte change and a catalogue of
// hostile files are refused with CorruptFileError naming the defect, never a
// crash or an allocation beyond a small multiple of the input (checked by
// counting every operator new).

#include <catch2/catch.hpp>
#include <tbb/task_arena.h>

#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cfenv>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <map>
#include <new>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "shatter/generators/corpus.hpp"
#include "shatter/generators/random.hpp"
#include "shatter/generators/solids.hpp"
#include "shatter/kernel/error.hpp"
#include "shatter/kernel/io.hpp"
#include "shatter/kernel/mass.hpp"
#include "shatter/meshtree/bonds.hpp"
#include "shatter/meshtree/build.hpp"
#include "shatter/meshtree/packed_node.hpp"
#include "shatter/formats/file.hpp"
#include "shatter/meshtree/recipe.hpp"
#include "shatter/meshtree/sites.hpp"
#include "shatter/meshtree/stats.hpp"
#include "shatter/meshtree/validate_tree.hpp"
#include "shatter/meshtree/voronoi.hpp"
#include "shatter/version.hpp"
#include "support/checks.hpp"

using namespace shatter;

// ---------------------------------------------------------------------------
// Allocation budget: while a budget is active, every allocation counts against
// it, and exceeding it throws bad_alloc, which fails the test (decode_shatter
// may only throw CorruptFileError) instead of exhausting the machine.

namespace {
std::atomic<bool> budget_active{false};
std::atomic<std::size_t> budget_left{0};

void* counted_allocation(std::size_t size) noexcept {
  if (budget_active.load(std::memory_order_relaxed)) {
    const std::size_t left = budget_left.load(std::memory_order_relaxed);
    if (size > left) return nullptr;
    budget_left.store(left - size, std::memory_order_relaxed);
  }
  return std::malloc(size == 0 ? 1 : size);
}
void* counted_allocation_or_throw(std::size_t size) {
  if (void* memory = counted_allocation(size)) return memory;
  throw std::bad_alloc();
}
}  // namespace

// Every non-aligned form is replaced, so that all of them pair malloc with free
// (a sanitizer's own operator new[] would not match a free()). Deletes are not
// inlined: GCC would otherwise pair the free() with the `new` expressions it
// sees and warn of a mismatch (-Wmismatched-new-delete) that is not one.
void* operator new(std::size_t size) { return counted_allocation_or_throw(size); }
void* operator new[](std::size_t size) { return counted_allocation_or_throw(size); }
void* operator new(std::size_t size, const std::nothrow_t&) noexcept { return counted_allocation(size); }
void* operator new[](std::size_t size, const std::nothrow_t&) noexcept { return counted_allocation(size); }
[[gnu::noinline]] void operator delete(void* memory) noexcept { std::free(memory); }
[[gnu::noinline]] void operator delete[](void* memory) noexcept { std::free(memory); }
[[gnu::noinline]] void operator delete(void* memory, std::size_t) noexcept { std::free(memory); }
[[gnu::noinline]] void operator delete[](void* memory, std::size_t) noexcept { std::free(memory); }
[[gnu::noinline]] void operator delete(void* memory, const std::nothrow_t&) noexcept { std::free(memory); }
[[gnu::noinline]] void operator delete[](void* memory, const std::nothrow_t&) noexcept { std::free(memory); }

namespace {

class AllocationBudget {
 public:
  explicit AllocationBudget(std::size_t bytes) {
    budget_left = bytes;
    budget_active = true;
  }
  ~AllocationBudget() { budget_active = false; }
  AllocationBudget(const AllocationBudget&) = delete;
  AllocationBudget& operator=(const AllocationBudget&) = delete;
};

/// What decode_shatter may allocate in total for an input of `size` bytes.
std::size_t allowed_allocation(std::size_t size) { return 16 * size + (std::size_t{1} << 16); }

/// The message decode_shatter refuses `bytes` with, or nullopt if it accepts them.
std::optional<std::string> refusal(std::string_view bytes) {
  const AllocationBudget budget(allowed_allocation(bytes.size()));
  try {
    decode_shatter(bytes);
  } catch (const CorruptFileError& error) {
    return std::string(error.what());
  }
  return std::nullopt;
}

/// decode_shatter under the allocation budget.
MeshTree decode_within_budget(std::string_view bytes) {
  const AllocationBudget budget(allowed_allocation(bytes.size()));
  return decode_shatter(bytes);
}

// ---------------------------------------------------------------------------
// Field-by-field comparison, doubles by their bits

std::uint64_t bits(double value) { return std::bit_cast<std::uint64_t>(value); }
bool same(double a, double b) { return bits(a) == bits(b); }
bool same(Vec2 a, Vec2 b) { return same(a.x, b.x) && same(a.y, b.y); }
bool same(Vec3 a, Vec3 b) { return same(a.x, b.x) && same(a.y, b.y) && same(a.z, b.z); }
bool same(Vec4 a, Vec4 b) { return same(a.x, b.x) && same(a.y, b.y) && same(a.z, b.z) && same(a.w, b.w); }
bool same(const Plane& a, const Plane& b) { return same(a.normal, b.normal) && same(a.offset, b.offset); }
bool same(Estimate a, Estimate b) { return same(a.value, b.value) && same(a.error, b.error); }
bool same(const ApproxPoint& a, const ApproxPoint& b) { return same(a.x, b.x) && same(a.y, b.y) && same(a.z, b.z) && same(a.w, b.w); }
bool same(const ApproxPlane& a, const ApproxPlane& b) { return same(a.a, b.a) && same(a.b, b.b) && same(a.c, b.c) && same(a.d, b.d); }
bool same(const SolidFace& a, const SolidFace& b) {
  return a.plane == b.plane && a.reversed == b.reversed && a.convex == b.convex && a.surface == b.surface && a.source == b.source &&
         a.first_loop == b.first_loop && a.loop_count == b.loop_count;
}
bool same(const SolidLoop& a, const SolidLoop& b) { return a.first_corner == b.first_corner && a.corner_count == b.corner_count; }
bool same(const SolidCorner& a, const SolidCorner& b) { return a.vertex == b.vertex && a.line == b.line; }

template <class T>
bool same_all(const std::vector<T>& a, const std::vector<T>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (!same(a[i], b[i])) return false;
  }
  return true;
}

std::string mesh_difference(const Mesh& a, const Mesh& b) {
  if (!same_all(a.positions, b.positions)) return "positions";
  if (a.triangles != b.triangles) return "triangles";
  if (a.surfaces != b.surfaces) return "surfaces";
  if (!same_all(a.corners.normals, b.corners.normals)) return "normals";
  if (!same_all(a.corners.uvs, b.corners.uvs)) return "uvs";
  if (!same_all(a.corners.tangents, b.corners.tangents)) return "tangents";
  return {};
}

std::string solid_difference(const Solid& a, const Solid& b) {
  if (a.defs != b.defs) return "defs";
  if (!same_all(a.approx, b.approx)) return "approx";
  if (!same_all(a.faces, b.faces)) return "faces";
  if (!same_all(a.loops, b.loops)) return "loops";
  if (!same_all(a.corners, b.corners)) return "corners";
  if (a.convex != b.convex) return "convex";
  return {};
}

/// The first field in which the repair reports differ, or an empty string.
std::string repair_difference(const RepairReport& a, const RepairReport& b) {
  if (a.vertices_before != b.vertices_before || a.triangles_before != b.triangles_before ||
      a.vertices_after != b.vertices_after || a.triangles_after != b.triangles_after) {
    return "counts";
  }
  if (a.changes.size() != b.changes.size()) return "change count";
  for (std::size_t k = 0; k < a.changes.size(); ++k) {
    const RepairChange &ca = a.changes[k], &cb = b.changes[k];
    if (ca.kind != cb.kind || ca.count != cb.count || ca.text != cb.text) return "change " + std::to_string(k);
  }
  if (a.notes.size() != b.notes.size()) return "note count";
  for (std::size_t k = 0; k < a.notes.size(); ++k) {
    if (a.notes[k].text != b.notes[k].text) return "note " + std::to_string(k);
  }
  return {};
}

/// The first field in which the trees differ, or an empty string.
std::string tree_difference(const MeshTree& a, const MeshTree& b) {
  const TreeRecipe &oa = a.recipe, &ob = b.recipe;
  if (oa.fragments != ob.fragments || oa.seed != ob.seed || oa.strategy != ob.strategy || oa.kernel != ob.kernel ||
      !same(oa.interior_uv_scale, ob.interior_uv_scale) || oa.max_plane_tries != ob.max_plane_tries ||
      oa.allow_self_intersections != ob.allow_self_intersections) {
    return "recipe";
  }
  if (a.shatter_version != b.shatter_version) return "shatter_version";
  if (const std::string d = repair_difference(a.input_repair, b.input_repair); !d.empty()) return "input_repair " + d;
  if (a.nodes.size() != b.nodes.size()) return "node count";
  for (std::size_t k = 0; k < a.nodes.size(); ++k) {
    const MeshTreeNode &na = a.nodes[k], &nb = b.nodes[k];
    const std::string node = "node " + std::to_string(k) + " ";
    if (const std::string d = mesh_difference(na.mesh, nb.mesh); !d.empty()) return node + "mesh " + d;
    if (const std::string d = mesh_difference(na.hull, nb.hull); !d.empty()) return node + "hull " + d;
    if (!same(na.mass.volume, nb.mass.volume) || !same(na.mass.centroid, nb.mass.centroid)) return node + "mass";
    for (std::size_t e = 0; e < 9; ++e) {
      if (!same(na.mass.inertia[e], nb.mass.inertia[e])) return node + "inertia";
    }
    if (na.parent != nb.parent || na.children != nb.children) return node + "links";
    if (na.above_parent_plane != nb.above_parent_plane || na.depth != nb.depth || na.first_leaf != nb.first_leaf ||
        na.leaf_count != nb.leaf_count || na.seed != nb.seed) {
      return node + "scalars";
    }
    if (na.convex != nb.convex) return node + "convex";
    if (const std::string d = solid_difference(na.solid, nb.solid); !d.empty()) return node + "solid " + d;
  }
  if (!same_all(a.geometry.points, b.geometry.points)) return "geometry points";
  if (a.geometry.planes != b.geometry.planes) return "geometry planes";
  if (!same_all(a.geometry.plane_approx, b.geometry.plane_approx)) return "geometry plane_approx";
  if (!same_all(a.cut_planes, b.cut_planes)) return "cut_planes";
  if (a.leaf_nodes != b.leaf_nodes) return "leaf_nodes";
  if (a.bonds.size() != b.bonds.size()) return "bond count";
  for (std::size_t i = 0; i < a.bonds.size(); ++i) {
    const Bond &ba = a.bonds[i], &bb = b.bonds[i];
    if (ba.first != bb.first || ba.second != bb.second || ba.cut_node != bb.cut_node || !same(ba.area, bb.area) ||
        !same(ba.centroid, bb.centroid) || !same(ba.normal, bb.normal)) {
      return "bond " + std::to_string(i);
    }
  }
  return {};
}

/// "equal", or where two files first differ (printing the files themselves
/// would flood the report with binary).
std::string byte_difference(std::string_view a, std::string_view b) {
  const auto [in_a, in_b] = std::mismatch(a.begin(), a.end(), b.begin(), b.end());
  if (in_a == a.end() && in_b == b.end()) return "equal";
  return "first difference at byte " + std::to_string(in_a - a.begin()) + " (sizes " + std::to_string(a.size()) + " and " +
         std::to_string(b.size()) + ")";
}

/// decode(encode(tree)) equals tree and encodes to the same bytes.
void check_round_trip(const MeshTree& tree) {
  const std::string bytes = encode_shatter(tree);
  const MeshTree decoded = decode_within_budget(bytes);
  CHECK(tree_difference(tree, decoded).empty());
  CHECK(encode_shatter(decoded) == bytes);
}

// ---------------------------------------------------------------------------
// Hand-built trees

/// Doubles whose bits a careless reader or writer would change.
const std::array<double, 8> special_doubles = {
    std::bit_cast<double>(std::uint64_t{0x7FF0000000000001}),  // signalling NaN
    std::bit_cast<double>(std::uint64_t{0xFFF80000DEADBEEF}),  // negative quiet NaN with a payload
    -0.0,
    0x1p-1074,  // smallest subnormal
    std::numeric_limits<double>::infinity(),
    -std::numeric_limits<double>::infinity(),
    std::numeric_limits<double>::max(),
    0.1,
};

MeshTreeNode node_of(Mesh mesh) {
  MeshTreeNode node;
  node.mass = mass_properties(mesh);
  node.hull = mesh;  // the format stores any mesh as a hull; these boxes are convex anyway
  node.mesh = std::move(mesh);
  return node;
}

/// A box [0,2]x[0,1]x[0,1] cut at x = 1 into two leaf boxes, with one bond.
MeshTree two_leaf_tree() {
  MeshTree tree;
  tree.recipe.fragments = 2;
  tree.recipe.seed = 0xFEEDFACECAFEBEEFull;
  tree.recipe.strategy = Strategy::balanced;
  tree.recipe.kernel = KernelKind::exact;
  tree.recipe.interior_uv_scale = 0.5;
  tree.recipe.max_plane_tries = 7;
  tree.recipe.allow_self_intersections = true;

  MeshTreeNode root = node_of(test::box({0, 0, 0}, {2, 1, 1}));
  root.children = {1, 2};
  root.leaf_count = 2;
  root.seed = 11;
  MeshTreeNode left = node_of(test::box({0, 0, 0}, {1, 1, 1}));
  MeshTreeNode right = node_of(test::box({1, 0, 0}, {2, 1, 1}));
  left.parent = right.parent = 0;
  left.depth = right.depth = 1;
  left.leaf_count = right.leaf_count = 1;
  right.first_leaf = 1;
  right.above_parent_plane = true;
  left.seed = 12;
  right.seed = 13;
  // The faces on x = 1 are the cap of the root's cut.
  for (MeshTreeNode* leaf : {&left, &right}) {
    for (std::size_t t = 0; t < leaf->mesh->triangle_count(); ++t) {
      bool on_cap = true;
      for (const VertexIndex v : leaf->mesh->triangles[t]) on_cap = on_cap && leaf->mesh->positions[v].x == 1;
      if (on_cap) leaf->mesh->surfaces[t] = cap_surface_of(0);
    }
  }
  tree.nodes = {root, left, right};
  tree.cut_planes = {Plane{{1, 0, 0}, -1}, Plane{}, Plane{}};
  tree.leaf_nodes = {1, 2};
  tree.bonds = {Bond{0, 1, 0, 1.0, {1, 0.5, 0.5}, {1, 0, 0}}};
  return tree;
}

/// Fills the attribute channels `which` (bit 0 normals, 1 uvs, 2 tangents) of a
/// mesh with values cycling through the special doubles.
void add_attributes(Mesh& mesh, unsigned which, std::size_t& cursor) {
  const auto next = [&] { return special_doubles[cursor++ % special_doubles.size()]; };
  const std::size_t corners = 3 * mesh.triangle_count();
  for (std::size_t c = 0; c < corners; ++c) {
    if (which & 1) mesh.corners.normals.push_back({next(), next(), next()});
    if (which & 2) mesh.corners.uvs.push_back({next(), next()});
    if (which & 4) mesh.corners.tangents.push_back({next(), next(), next(), next()});
  }
}

/// Four leaves two levels deep (root with three children, the first cut again),
/// meshes from the generators, attribute channels in every combination, and
/// special doubles in positions, planes, masses and bonds.
MeshTree deep_tree() {
  MeshTree tree;
  tree.recipe.fragments = 4;
  tree.recipe.seed = 99;
  tree.recipe.strategy = Strategy::axis;
  tree.recipe.kernel = KernelKind::fast;
  tree.recipe.interior_uv_scale = special_doubles[1];
  tree.recipe.max_plane_tries = 0xFFFFFFFFu;

  tree.nodes = {node_of(test::torus(2, 0.5, 12, 8)), node_of(test::ellipsoid({0, 0, 0}, {1, 2, 3}, 8, 6)),
                node_of(test::box({0, 0, 0}, {1, 1, 1})), node_of(test::box({-1, -1, -1}, {0, 0, 0})),
                node_of(test::ellipsoid({0, 0, 1}, {1, 1, 1}, 6, 4)), node_of(test::box({5, 5, 5}, {6, 7, 8}))};
  tree.nodes[0].children = {1, 4, 5};
  tree.nodes[1].children = {2, 3};
  const std::array<NodeIndex, 6> parents = {no_node, 0, 1, 1, 0, 0};
  const std::array<std::uint32_t, 6> depths = {0, 1, 2, 2, 1, 1};
  const std::array<LeafIndex, 6> first_leaves = {0, 0, 0, 1, 2, 3};
  const std::array<std::uint32_t, 6> leaf_counts = {4, 2, 1, 1, 1, 1};
  std::size_t cursor = 0;
  tree.cut_planes.resize(tree.nodes.size());
  for (std::size_t k = 0; k < tree.nodes.size(); ++k) {
    MeshTreeNode& node = tree.nodes[k];
    node.parent = parents[k];
    node.depth = depths[k];
    node.first_leaf = first_leaves[k];
    node.leaf_count = leaf_counts[k];
    node.seed = 0x8000000000000000ull + k;
    node.above_parent_plane = k % 2 == 1;
    if (!node.is_leaf()) tree.cut_planes[k] = {{special_doubles[k], 1, -0.0}, special_doubles[k + 1]};
    node.mass.inertia[k] = special_doubles[k];
    add_attributes(*node.mesh, static_cast<unsigned>(k + 2) % 8, cursor);
    add_attributes(*node.hull, static_cast<unsigned>(k) % 8, cursor);
  }
  tree.nodes[2].mesh->positions[0] = {special_doubles[0], special_doubles[2], special_doubles[3]};
  tree.nodes[3].mesh->surfaces[0] = 0xFFFFFFFFu;
  tree.nodes[5].mesh = Mesh{};  // an empty mesh is stored as it is
  tree.leaf_nodes = {2, 3, 4, 5};
  tree.bonds = {Bond{0, 1, 1, special_doubles[0], {1, 2, 3}, {0, 0, 1}}, Bond{0, 2, 0, 0.25, {}, {}},
                Bond{0, 2, 0, 0.5, {}, {}}, Bond{1, 2, 0, special_doubles[3], {special_doubles[4], 0, 0}, {}},
                Bond{2, 3, 0, 1e300, {}, {-0.0, 0, 0}}};
  return tree;
}

/// A plane-kernel tree (the default kernel): the unit cube in 4 fragments. Its
/// exact representation fills GEOM and SOLD; built once.
const MeshTree& small_plane_tree() {
  static const MeshTree tree = [] {
    TreeRecipe recipe;
    recipe.fragments = 4;
    recipe.seed = 7;
    return build_mesh_tree(test::unit_cube(), recipe, {.threads = 1});
  }();
  return tree;
}

// ---------------------------------------------------------------------------
// The layout as file.hpp documents it, written independently of the library:
// the test of the documentation, and the way to craft files with correct
// checksums around invalid content.

std::uint32_t reference_crc32(std::string_view bytes) {
  std::uint32_t crc = 0xFFFFFFFFu;
  for (const char c : bytes) {
    crc ^= static_cast<unsigned char>(c);
    for (int bit = 0; bit < 8; ++bit) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
  }
  return ~crc;
}

struct Bytes {
  std::string data;
  Bytes& u8(std::uint8_t v) {
    data.push_back(static_cast<char>(v));
    return *this;
  }
  Bytes& u32(std::uint32_t v) {
    for (int k = 0; k < 4; ++k) u8(static_cast<std::uint8_t>(v >> (8 * k)));
    return *this;
  }
  Bytes& u64(std::uint64_t v) {
    for (int k = 0; k < 8; ++k) u8(static_cast<std::uint8_t>(v >> (8 * k)));
    return *this;
  }
  Bytes& f64(double v) { return u64(bits(v)); }
  Bytes& vec3(Vec3 v) { return f64(v.x).f64(v.y).f64(v.z); }
  Bytes& text(std::string_view s) {
    data += s;
    return *this;
  }
  Bytes& vu(std::uint64_t v) {
    for (; v >= 0x80; v >>= 7) u8(static_cast<std::uint8_t>(0x80 | (v & 0x7F)));
    return u8(static_cast<std::uint8_t>(v));
  }
};

const std::string magic_bytes("\x89SHT\r\n\x1a\n", 8);

std::string file_header(std::uint32_t version = 2) { return Bytes{}.text(magic_bytes).u32(version).data; }

std::string section(std::string_view tag, std::string_view payload) {
  return Bytes{}.text(tag).u64(payload.size()).u32(reference_crc32(payload)).text(payload).data;
}

std::string recipe_payload(const TreeRecipe& o) {
  return Bytes{}
      .u32(o.fragments)
      .u64(o.seed)
      .u8(static_cast<std::uint8_t>(o.strategy))
      .u8(static_cast<std::uint8_t>(o.kernel))
      .f64(o.interior_uv_scale)
      .u32(o.max_plane_tries)
      .u8(o.allow_self_intersections ? 1 : 0)
      .data;
}

std::string nodes_payload(const MeshTree& tree) {
  Bytes out;
  out.u32(static_cast<std::uint32_t>(tree.nodes.size()));
  for (std::size_t k = 0; k < tree.nodes.size(); ++k) {
    const MeshTreeNode& n = tree.nodes[k];
    const Plane& plane = tree.cut_planes[k];
    out.u32(n.parent).u32(n.depth).u32(n.first_leaf).u32(n.leaf_count).u64(n.seed).u8(n.above_parent_plane ? 1 : 0);
    out.vec3(plane.normal).f64(plane.offset).f64(n.mass.volume).vec3(n.mass.centroid);
    for (const double e : n.mass.inertia) out.f64(e);
    out.u32(static_cast<std::uint32_t>(n.children.size()));
    for (const NodeIndex c : n.children) out.u32(c);
  }
  return out.data;
}

std::string mesh_record(const Mesh& m) {
  Bytes out;
  out.u32(static_cast<std::uint32_t>(m.positions.size())).u32(static_cast<std::uint32_t>(m.triangles.size()));
  out.u8(static_cast<std::uint8_t>((m.corners.has_normals() ? 1 : 0) | (m.corners.has_uvs() ? 2 : 0) | (m.corners.has_tangents() ? 4 : 0)));
  for (const Vec3& p : m.positions) out.vec3(p);
  for (const Triangle& t : m.triangles) out.u32(t[0]).u32(t[1]).u32(t[2]);
  for (const SurfaceId s : m.surfaces) out.u32(s);
  for (const Vec3& n : m.corners.normals) out.vec3(n);
  for (const Vec2& uv : m.corners.uvs) out.f64(uv.x).f64(uv.y);
  for (const Vec4& t : m.corners.tangents) out.f64(t.x).f64(t.y).f64(t.z).f64(t.w);
  return out.data;
}

std::string meshes_payload(const std::vector<MeshTreeNode>& nodes, bool hulls) {
  std::string out = Bytes{}.u32(static_cast<std::uint32_t>(nodes.size())).data;
  for (const MeshTreeNode& n : nodes) out += mesh_record(hulls ? *n.hull : *n.mesh);
  return out;
}

std::string bonds_payload(const std::vector<Bond>& bonds) {
  Bytes out;
  out.u64(bonds.size());
  for (const Bond& b : bonds) out.u32(b.first).u32(b.second).u32(b.cut_node).f64(b.area).vec3(b.centroid).vec3(b.normal);
  return out.data;
}

std::string geometry_payload(const InputGeometry& g) {
  Bytes out;
  out.u32(static_cast<std::uint32_t>(g.points.size())).u32(static_cast<std::uint32_t>(g.planes.size()));
  for (const Vec3& p : g.points) out.vec3(p);
  for (const auto& plane : g.planes) out.u32(plane[0]).u32(plane[1]).u32(plane[2]);
  return out.data;
}

/// One SOLD record. The fields a vertex's kind does not use are written as they
/// are (zero in a valid tree), so that invalid trees reach the reader.
std::string solid_record(const MeshTreeNode& node) {
  const Solid& s = node.solid;
  Bytes out;
  out.u8(static_cast<std::uint8_t>((node.convex ? 1 : 0) | (s.convex ? 2 : 0)));
  out.u32(static_cast<std::uint32_t>(s.defs.size())).u32(static_cast<std::uint32_t>(s.faces.size()));
  out.u32(static_cast<std::uint32_t>(s.loops.size())).u32(static_cast<std::uint32_t>(s.corners.size()));
  for (const PointDef& d : s.defs) {
    out.u8(static_cast<std::uint8_t>(d.kind));
    if (d.kind == PointKind::three_planes) {
      out.u32(d.planes[0].bits).u32(d.planes[1].bits).u32(d.planes[2].bits);
    } else {
      out.u32(d.a).u32(d.b).u32(d.planes[0].bits);
    }
  }
  for (const SolidFace& f : s.faces) {
    out.u32(f.plane.bits).u8(static_cast<std::uint8_t>((f.reversed ? 1 : 0) | (f.convex ? 2 : 0))).u32(f.surface).u32(f.source).u32(f.loop_count);
  }
  for (const SolidLoop& l : s.loops) out.u32(l.corner_count);
  // A segment is written when p is a point; (none, q) drops q, which the
  // invalid-tree cases below rely on only through the encoder.
  for (const SolidCorner& c : s.corners) {
    out.u32(c.vertex).u32(c.line.other.bits).u8(c.line.p != no_index ? 1 : 0);
    if (c.line.p != no_index) out.u32(c.line.p).u32(c.line.q);
  }
  return out.data;
}

std::string solids_payload(const MeshTree& tree) {
  if (tree.geometry.points.empty()) return Bytes{}.u32(0).data;
  std::string out = Bytes{}.u32(static_cast<std::uint32_t>(tree.nodes.size())).data;
  for (const MeshTreeNode& n : tree.nodes) out += solid_record(n);
  return out;
}

/// The payloads of `tree`'s sections by tag, in the order encode_shatter writes
/// them (version 2), each replaceable.
struct Payloads {
  std::vector<std::pair<std::string, std::string>> parts;

  explicit Payloads(const MeshTree& tree)
      : parts{{"OPTS", recipe_payload(tree.recipe)},      {"NODE", nodes_payload(tree)},
              {"MESH", meshes_payload(tree.nodes, false)}, {"HULL", meshes_payload(tree.nodes, true)},
              {"BOND", bonds_payload(tree.bonds)},         {"GEOM", geometry_payload(tree.geometry)},
              {"SOLD", solids_payload(tree)}} {
    // Optional, and written first when the tree knows its version (built trees do).
    if (!tree.shatter_version.empty()) parts.insert(parts.begin(), {"vers", tree.shatter_version});
  }
  Payloads& with(std::string_view tag, std::string payload) {
    for (auto& [t, p] : parts) {
      if (t == tag) p = std::move(payload);
    }
    return *this;
  }
  std::string& operator[](std::string_view tag) {
    for (auto& [t, p] : parts) {
      if (t == tag) return p;
    }
    throw std::logic_error("no such section");
  }
  /// The file; version 1 leaves out GEOM and SOLD.
  std::string file(std::uint32_t version = 2) const {
    std::string bytes = file_header(version);
    for (const auto& [tag, payload] : parts) {
      if (version == 1 && (tag == "GEOM" || tag == "SOLD")) continue;
      bytes += section(tag, payload);
    }
    return bytes + section("END ", "");
  }
};

/// The documented file of `tree`, whatever its content: no validation.
std::string reference_file(const MeshTree& tree, std::uint32_t version = 2) { return Payloads(tree).file(version); }

/// A file with the given NODE payload and otherwise the sections of `tree`.
std::string file_with_nodes_payload(const MeshTree& tree, const std::string& nodes) { return Payloads(tree).with("NODE", nodes).file(); }

// ---------------------------------------------------------------------------
// Version 3, as file.hpp documents it: the derivations are the library's
// documented functions (output_position, mass_properties, the node seeds,
// point_on_plane_over, normalized); everything else is written here.

std::uint64_t zigzag_of(std::int64_t v) { return v < 0 ? 2 * static_cast<std::uint64_t>(-(v + 1)) + 1 : 2 * static_cast<std::uint64_t>(v); }

/// Root to node, as preorder reaches it.
std::vector<NodeIndex> path_to(const MeshTree& tree, NodeIndex node) {
  std::vector<NodeIndex> path;
  for (NodeIndex k = node; k != no_node; k = tree.nodes[k].parent) path.insert(path.begin(), k);
  return path;
}

std::uint64_t levels_up(const std::vector<NodeIndex>& path, NodeIndex ancestor) {
  for (std::size_t d = 1; d < path.size(); ++d) {
    if (path[path.size() - 1 - d] == ancestor) return d;
  }
  return 0;
}

std::uint64_t plane_code_v3(PlaneRef plane, const std::vector<NodeIndex>& path) {
  if (plane.bits == no_index) return 0;
  if (!plane.is_cut()) return 2 * std::uint64_t{plane.index()} + 1;
  const std::uint64_t up = levels_up(path, plane.index());
  if (up == 0) throw std::logic_error("a cut plane not of an ancestor has no version 3 code");
  return 2 * up;
}

std::uint64_t surface_code_v3(SurfaceId surface, const std::vector<NodeIndex>& path) {
  if (surface == 0) return 0;
  if (const std::uint64_t up = levels_up(path, surface - 1); up != 0) return up;
  return path.size() - 1 + std::uint64_t{surface};
}

void mesh_record_v3(Bytes& out, const Mesh& m, const std::vector<Vec3>& sources, const std::vector<NodeIndex>& path) {
  out.vu(m.positions.size()).vu(m.triangles.size());
  out.u8(static_cast<std::uint8_t>((m.corners.has_normals() ? 1 : 0) | (m.corners.has_uvs() ? 2 : 0) | (m.corners.has_tangents() ? 4 : 0)));
  std::int64_t offset = 0;
  for (std::size_t i = 0; i < m.positions.size(); ++i) {
    const auto matches = [&](std::int64_t s) { return s >= 0 && s < std::ssize(sources) && same(sources[static_cast<std::size_t>(s)], m.positions[i]); };
    const auto at = static_cast<std::int64_t>(i);
    std::int64_t source = matches(at + offset) ? at + offset : matches(at) ? at : -1;
    for (std::int64_t s = 0; source < 0 && s < std::ssize(sources); ++s) {
      if (matches(s)) source = s;
    }
    if (source < 0) {
      out.vu(0).vec3(m.positions[i]);
    } else {
      offset = source - at;
      out.vu(1 + zigzag_of(offset));
    }
  }
  const std::size_t width = m.positions.size() <= 256 ? 1 : m.positions.size() <= 65536 ? 2 : 4;
  for (const Triangle& triangle : m.triangles) {
    for (const VertexIndex v : triangle) {
      for (std::size_t b = 0; b < width; ++b) out.u8(static_cast<std::uint8_t>(v >> (8 * b)));
    }
  }
  std::vector<std::pair<std::uint64_t, std::uint64_t>> runs;
  for (const SurfaceId s : m.surfaces) {
    const std::uint64_t code = surface_code_v3(s, path);
    if (runs.empty() || runs.back().first != code) runs.emplace_back(code, 0);
    ++runs.back().second;
  }
  out.vu(runs.size());
  for (const auto& [code, length] : runs) out.vu(code).vu(length);
  for (const Vec3& n : m.corners.normals) out.vec3(n);
  for (const Vec2& uv : m.corners.uvs) out.f64(uv.x).f64(uv.y);
  for (const Vec4& tangent : m.corners.tangents) out.f64(tangent.x).f64(tangent.y).f64(tangent.z).f64(tangent.w);
}

std::uint64_t seed_derived_v3(const MeshTree& tree, NodeIndex k) {
  if (k == 0) return root_node_seed(tree.recipe.seed);
  const MeshTreeNode& parent = tree.nodes[tree.nodes[k].parent];
  const auto index = static_cast<std::size_t>(std::find(parent.children.begin(), parent.children.end(), k) - parent.children.begin());
  return child_node_seed(parent.seed, index);
}

bool same_mass(const MassProperties& a, const MassProperties& b) {
  return same(a.volume, b.volume) && same(a.centroid, b.centroid) &&
         std::equal(a.inertia.begin(), a.inertia.end(), b.inertia.begin(), [](double x, double y) { return same(x, y); });
}

std::string nodes_payload_v3(const MeshTree& tree) {
  std::uint8_t flags = 0;
  for (NodeIndex k = 0; k < tree.nodes.size(); ++k) {
    const MeshTreeNode& n = tree.nodes[k];
    if (n.seed != seed_derived_v3(tree, k)) flags |= 1;
    if (!same_mass(n.mass, mass_properties(n.mesh))) flags |= 2;
    const Plane& plane = tree.cut_planes[k];
    if (n.is_leaf() && (bits(plane.normal.x) | bits(plane.normal.y) | bits(plane.normal.z) | bits(plane.offset)) != 0) flags |= 4;
  }
  Bytes out;
  out.u32(static_cast<std::uint32_t>(tree.nodes.size())).u8(flags);
  for (NodeIndex k = 0; k < tree.nodes.size(); ++k) {
    const MeshTreeNode& n = tree.nodes[k];
    out.vu(2 * n.children.size() + (n.above_parent_plane ? 1 : 0));
    if (!n.is_leaf() || (flags & 4) != 0) out.vec3(tree.cut_planes[k].normal).f64(tree.cut_planes[k].offset);
    if ((flags & 1) != 0) out.u64(n.seed);
    if ((flags & 2) != 0) {
      out.f64(n.mass.volume).vec3(n.mass.centroid);
      for (const double e : n.mass.inertia) out.f64(e);
    }
  }
  return out.data;
}

std::string solids_payload_v3(const MeshTree& tree) {
  if (tree.geometry.points.empty()) return Bytes{}.u32(0).data;
  Bytes out;
  out.u32(static_cast<std::uint32_t>(tree.nodes.size()));
  for (NodeIndex k = 0; k < tree.nodes.size(); ++k) {
    const std::vector<NodeIndex> path = path_to(tree, k);
    const Solid& s = tree.nodes[k].solid;
    out.u8(static_cast<std::uint8_t>((tree.nodes[k].convex ? 1 : 0) | (s.convex ? 2 : 0)));
    out.vu(s.defs.size()).vu(s.faces.size()).vu(s.loops.size()).vu(s.corners.size());
    for (const PointDef& d : s.defs) {
      out.u8(static_cast<std::uint8_t>(d.kind));
      if (d.kind == PointKind::input) out.vu(d.a);
      if (d.kind == PointKind::segment_plane) out.vu(d.a).vu(d.b).vu(plane_code_v3(d.planes[0], path));
      if (d.kind == PointKind::three_planes) {
        for (const PlaneRef plane : d.planes) out.vu(plane_code_v3(plane, path));
      }
    }
    for (const SolidFace& f : s.faces) {
      out.vu(plane_code_v3(f.plane, path)).u8(static_cast<std::uint8_t>((f.reversed ? 1 : 0) | (f.convex ? 2 : 0)));
      out.vu(surface_code_v3(f.surface, path)).vu(f.source).vu(f.loop_count);
    }
    for (const SolidLoop& l : s.loops) out.vu(l.corner_count);
    // The face of each directed edge, to find the face across a corner's edge.
    std::map<std::pair<VertexIndex, VertexIndex>, std::uint32_t> face_of;
    const auto next_of = [&](std::uint32_t corner, const SolidLoop& loop) {
      return s.corners[loop.first_corner + (corner - loop.first_corner + 1) % loop.corner_count].vertex;
    };
    for (std::uint32_t f = 0; f < s.faces.size(); ++f) {
      for (std::uint32_t l = s.faces[f].first_loop; l < s.faces[f].first_loop + s.faces[f].loop_count; ++l) {
        for (std::uint32_t c = s.loops[l].first_corner; c < s.loops[l].first_corner + s.loops[l].corner_count; ++c) {
          face_of[{s.corners[c].vertex, next_of(c, s.loops[l])}] = f;
        }
      }
    }
    for (const SolidLoop& loop : s.loops) {
      for (std::uint32_t c = loop.first_corner; c < loop.first_corner + loop.corner_count; ++c) {
        const SolidCorner& corner = s.corners[c];
        const auto across = face_of.find({next_of(c, loop), corner.vertex});
        const bool segment = corner.line.p != no_index;
        if (!segment && across != face_of.end() && s.faces[across->second].plane == corner.line.other) {
          out.vu(std::uint64_t{corner.vertex} << 2);
        } else {
          out.vu((std::uint64_t{corner.vertex} << 2) | (segment ? 2 : 1)).vu(plane_code_v3(corner.line.other, path));
          if (segment) out.vu(corner.line.p).vu(corner.line.q);
        }
      }
    }
  }
  return out.data;
}

std::string meshes_payload_v3(const MeshTree& tree, bool hulls) {
  Bytes out;
  out.u32(static_cast<std::uint32_t>(tree.nodes.size()));
  const PlaneSet set = tree.plane_set();
  for (NodeIndex k = 0; k < tree.nodes.size(); ++k) {
    const MeshTreeNode& n = tree.nodes[k];
    std::vector<Vec3> sources = n.mesh->positions;
    if (!hulls) {
      sources.clear();
      for (std::size_t v = 0; v < n.solid->defs.size(); ++v) sources.push_back(output_position(set, n.solid->defs[v], n.solid->approx[v]));
    }
    mesh_record_v3(out, hulls ? *n.hull : *n.mesh, sources, path_to(tree, k));
  }
  return out.data;
}

/// The child of the bond's cut node that holds its first leaf.
NodeIndex first_side(const MeshTree& tree, const Bond& b) {
  NodeIndex side = tree.leaf_nodes[b.first];
  while (tree.nodes[side].parent != b.cut_node) side = tree.nodes[side].parent;
  return side;
}

std::string bonds_payload_v3(const MeshTree& tree) {
  const auto derived_normal = [&](const Bond& b) {
    const Vec3 unit = normalized(tree.cut_planes[b.cut_node].normal);
    return tree.nodes[first_side(tree, b)].above_parent_plane ? -unit : unit;
  };
  const bool normals = std::any_of(tree.bonds.begin(), tree.bonds.end(), [&](const Bond& b) { return !same(b.normal, derived_normal(b)); });
  Bytes out;
  out.u64(tree.bonds.size()).u8(normals ? 1 : 0);
  LeafIndex previous = 0;
  for (const Bond& b : tree.bonds) {
    const Plane& plane = tree.cut_planes[b.cut_node];
    const double n[3] = {std::fabs(plane.normal.x), std::fabs(plane.normal.y), std::fabs(plane.normal.z)};
    const double c[3] = {b.centroid.x, b.centroid.y, b.centroid.z};
    std::vector<int> axes = {0, 1, 2};
    std::stable_sort(axes.begin(), axes.end(), [&](int x, int y) { return n[x] > n[y]; });
    int axis = 3;
    for (const int a : axes) {
      if (same(point_on_plane_over(plane, a, c[(a + 1) % 3], c[(a + 2) % 3]), b.centroid)) {
        axis = a;
        break;
      }
    }
    out.vu(b.first - previous).vu((std::uint64_t{b.second - b.first - 1} << 2) | static_cast<std::uint64_t>(axis)).f64(b.area);
    previous = b.first;
    if (axis == 3) {
      out.vec3(b.centroid);
    } else {
      out.f64(c[(axis + 1) % 3]).f64(c[(axis + 2) % 3]);
    }
    if (normals) out.vec3(b.normal);
  }
  return out.data;
}

/// The `rpar` payload file.hpp documents for `report`.
std::string repair_payload_reference(const RepairReport& report) {
  Bytes out;
  out.u64(report.vertices_before).u64(report.triangles_before).u64(report.vertices_after).u64(report.triangles_after);
  out.u32(static_cast<std::uint32_t>(report.changes.size()));
  for (const RepairChange& change : report.changes) {
    const auto kind = std::find(all_repair_kinds.begin(), all_repair_kinds.end(), change.kind) - all_repair_kinds.begin();
    out.u8(static_cast<std::uint8_t>(kind)).u64(change.count).u32(static_cast<std::uint32_t>(change.text.size()));
    out.data += change.text;
  }
  out.u32(static_cast<std::uint32_t>(report.notes.size()));
  for (const RepairNote& note : report.notes) {
    out.u32(static_cast<std::uint32_t>(note.text.size()));
    out.data += note.text;
  }
  return out.data;
}

/// Version 3 payloads of `tree`, as Payloads holds version 2's, in the order
/// encode_shatter writes them.
std::vector<std::pair<std::string, std::string>> payloads_v3(const MeshTree& tree) {
  // Derivations are attempts: a hand-made tree's special doubles must not trap.
  std::fenv_t saved;
  std::feholdexcept(&saved);
  std::vector<std::pair<std::string, std::string>> parts = {
      {"OPTS", recipe_payload(tree.recipe)},  {"NODE", nodes_payload_v3(tree)},       {"GEOM", geometry_payload(tree.geometry)},
      {"SOLD", solids_payload_v3(tree)},      {"MESH", meshes_payload_v3(tree, false)}, {"HULL", meshes_payload_v3(tree, true)},
      {"BOND", bonds_payload_v3(tree)}};
  std::fesetenv(&saved);
  if (!tree.input_repair.empty()) parts.insert(parts.begin(), {"rpar", repair_payload_reference(tree.input_repair)});
  if (!tree.shatter_version.empty()) parts.insert(parts.begin(), {"vers", tree.shatter_version});
  return parts;
}

std::string file_of_parts(const std::vector<std::pair<std::string, std::string>>& parts, std::uint32_t version) {
  std::string bytes = file_header(version);
  for (const auto& [tag, payload] : parts) bytes += section(tag, payload);
  return bytes + section("END ", "");
}

/// The documented version 3 file of `tree`.
std::string reference_file_v3(const MeshTree& tree) { return file_of_parts(payloads_v3(tree), 3); }

/// Whether `damaged`, `bytes` with the byte at `position` changed, is the one
/// single-byte change the reading rules let through (file.hpp): the tag of the
/// optional `vers` section (written first) turned into another lower-case tag,
/// which is skipped as unknown optional data, so that the file reads as the same
/// tree without its version.
bool reads_as_without_version(const std::string& bytes, std::size_t position, const std::string& damaged) {
  if (bytes.compare(12, 4, "vers") != 0 || position < 12 || position >= 16) return false;
  if (damaged[12] < 'a' || damaged[12] > 'z') return false;
  MeshTree expected = decode_within_budget(bytes);
  expected.shatter_version.clear();
  return tree_difference(decode_within_budget(damaged), expected).empty();
}

/// Refused, with a message holding `expected`.
void check_refused(const std::string& bytes, const std::string& expected) {
  const std::optional<std::string> message = refusal(bytes);
  INFO("expected a refusal mentioning: " << expected);
  REQUIRE(message.has_value());
  INFO("message: " << *message);
  CHECK(message->find(expected) != std::string::npos);
  CHECK(message->find('\n') == std::string::npos);
}

Mesh with_attributes(Mesh mesh) {
  // Unit-ish normals, planar uvs and tangents per corner, as a real input would carry.
  for (const Triangle& t : mesh.triangles) {
    for (const VertexIndex v : t) {
      const Vec3 p = mesh.positions[v];
      mesh.corners.normals.push_back(normalized(p));
      mesh.corners.uvs.push_back({p.x, p.y});
      mesh.corners.tangents.push_back({1, 0, 0, -1});
    }
  }
  return mesh;
}

}  // namespace

// ---------------------------------------------------------------------------

TEST_CASE("encode_shatter writes exactly the layout file.hpp documents", "[shatter_file]") {
  for (const MeshTree& tree : {two_leaf_tree(), deep_tree(), small_plane_tree()}) {
    const std::string bytes = encode_shatter(tree);
    CHECK(byte_difference(bytes, reference_file_v3(tree)) == "equal");
    CHECK(bytes.substr(0, 12) == file_header(3));
    CHECK(bytes.substr(bytes.size() - 16) == std::string("END \0\0\0\0\0\0\0\0\0\0\0\0", 16));
  }
}

TEST_CASE("hand-built trees round-trip field by field and bit for bit", "[shatter_file]") {
  SECTION("two leaves") { check_round_trip(two_leaf_tree()); }
  SECTION("two levels, every attribute combination, special doubles") {
    const MeshTree tree = deep_tree();
    check_round_trip(tree);
    const MeshTree decoded = decode_shatter(encode_shatter(tree));
    // Spot checks that the comparison itself sees the special bit patterns.
    CHECK(bits(decoded.nodes[2].mesh->positions[0].x) == 0x7FF0000000000001u);
    CHECK(bits(decoded.recipe.interior_uv_scale) == 0xFFF80000DEADBEEFu);
    CHECK(bits(decoded.nodes[2].mesh->positions[0].y) == bits(-0.0));
    CHECK(decoded.leaf_nodes == std::vector<NodeIndex>{2, 3, 4, 5});
  }
}

TEST_CASE("built trees round-trip exactly", "[shatter_file][build]") {
  const std::vector<test::NamedMesh> meshes = {{"box", test::box({0, 0, 0}, {2, 1, 1})},
                                               {"torus", test::torus(2, 0.6, 16, 10)},
                                               {"hollow egg", test::hollow_egg()},
                                               {"ellipsoid with attributes", with_attributes(test::ellipsoid({0, 0, 0}, {1, 1.5, 2}, 12, 8))}};
  for (const test::NamedMesh& input : meshes) {
    for (const Strategy strategy : {Strategy::thesis, Strategy::balanced, Strategy::axis}) {
      for (const std::uint32_t fragments : {2u, 3u, 64u}) {
        // Keep the suite fast (building dominates): N = 64 on the box with every
        // strategy, on the other meshes with one.
        if (fragments == 64 && input.name != "box" && strategy != Strategy::axis) continue;
        TreeRecipe recipe;
        recipe.fragments = fragments;
        recipe.seed = 7 + fragments;
        recipe.strategy = strategy;
        INFO(input.name << ", " << strategy_name(strategy) << ", N = " << fragments);
        const MeshTree tree = build_mesh_tree(input.mesh, recipe);
        REQUIRE(tree.leaf_count() >= fragments);
        CHECK(test::tree_problem(tree) == "");
        check_round_trip(tree);
        if (input.name == "ellipsoid with attributes") {
          CHECK(tree.nodes.back().mesh->corners.has_normals());
          CHECK(tree.nodes.back().mesh->corners.has_uvs());
          CHECK(tree.nodes.back().mesh->corners.has_tangents());
        }
      }
    }
  }
}

TEST_CASE("files the retired kernels wrote still read, hold and write back as version 3",
          "[shatter_file][compatibility]") {
  for (const std::filesystem::path& file : test::retired_kernel_trees()) {
    INFO(file.filename());
    std::ifstream in(file, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    REQUIRE(!bytes.empty());
    const MeshTree tree = decode_within_budget(bytes);
    CHECK(tree.recipe.kernel != KernelKind::plane);
    CHECK(!tree.has_exact_representation());
    CHECK(tree.cut_planes.size() == tree.nodes.size());  // the planes of every kernel's tree
    CHECK(test::tree_problem(tree) == "");
    // Version 2 on disk; written again, version 3 of the same tree.
    REQUIRE(bytes.substr(8, 4) == Bytes{}.u32(2).data);
    const std::string again = encode_shatter(tree);
    CHECK(byte_difference(again, reference_file_v3(tree)) == "equal");
    CHECK(tree_difference(decode_within_budget(again), tree).empty());
  }
}

TEST_CASE("every truncation of a file is refused as truncated", "[shatter_file][damage]") {
  for (const std::string& bytes : {encode_shatter(two_leaf_tree()), encode_shatter(small_plane_tree())}) {
    for (std::size_t length = 0; length < bytes.size(); ++length) {
      const std::optional<std::string> message = refusal(std::string_view(bytes).substr(0, length));
      INFO("prefix of " << length << " of " << bytes.size() << " bytes");
      REQUIRE(message.has_value());
      CHECK(message->find("truncated") != std::string::npos);
    }
  }
}

TEST_CASE("every single-byte change is refused", "[shatter_file][damage]") {
  const auto every_byte_three_ways = [](const std::string& bytes) {
    std::vector<std::string> accepted;  // collected rather than asserted one by one, to stay fast
    for (std::size_t position = 0; position < bytes.size(); ++position) {
      for (const int change : {0x01, 0x20, 0xFF}) {
        std::string damaged = bytes;
        damaged[position] = static_cast<char>(static_cast<unsigned char>(damaged[position]) ^ change);
        if (!refusal(damaged) && !reads_as_without_version(bytes, position, damaged)) {
          accepted.push_back("byte " + std::to_string(position) + " xor " + std::to_string(change));
        }
      }
    }
    INFO(bytes.size() << "-byte file: " << accepted.size() << " changes accepted, the first: "
                      << (accepted.empty() ? std::string("none") : accepted.front()));
    CHECK(accepted.empty());
  };
  SECTION("every byte of a small file, three ways") { every_byte_three_ways(encode_shatter(two_leaf_tree())); }
  SECTION("every byte of a small plane-kernel file, three ways") { every_byte_three_ways(encode_shatter(small_plane_tree())); }
  SECTION("2000 random positions in built trees' files") {
    std::vector<std::string> files = {encode_shatter(deep_tree())};
    for (const auto& [mesh, strategy] : {std::pair{test::torus(2, 0.6, 16, 10), Strategy::thesis},
                                         std::pair{test::hollow_egg(), Strategy::axis},
                                         std::pair{test::box({0, 0, 0}, {1, 2, 3}), Strategy::balanced}}) {
      TreeRecipe recipe;
      recipe.fragments = 8;
      recipe.strategy = strategy;
      files.push_back(encode_shatter(build_mesh_tree(mesh, recipe)));
    }
    test::Random random(2024);
    for (int sample = 0; sample < 2000; ++sample) {
      std::string damaged = files[random.index(files.size())];
      const std::size_t position = random.index(damaged.size());
      const auto change = static_cast<unsigned char>(1 + random.index(255));
      const std::string original = damaged;
      damaged[position] = static_cast<char>(static_cast<unsigned char>(damaged[position]) ^ change);
      if (refusal(damaged) || reads_as_without_version(original, position, damaged)) continue;
      FAIL("byte " << position << " of " << damaged.size() << " xor " << int{change} << " accepted");
    }
  }
}

TEST_CASE("random damage behind correct checksums is refused or decodes to a valid tree", "[shatter_file][hostile]") {
  // Checksums stop accidental damage; this is the deliberate kind. Bytes of one
  // payload are changed and its CRC recomputed, so only the structure checks
  // stand between the reader and the damage. Whatever decodes must be a tree the
  // encoder accepts (the two agree on validity) and must re-encode to the input.
  struct Part {
    std::string tag, payload;
  };
  test::Random random(77);
  for (const auto& [tree, version] : {std::pair(two_leaf_tree(), 2u), std::pair(deep_tree(), 2u), std::pair(small_plane_tree(), 2u),
                                      std::pair(two_leaf_tree(), 3u), std::pair(deep_tree(), 3u), std::pair(small_plane_tree(), 3u)}) {
    std::vector<Part> parts;
    for (const auto& [tag, payload] : version == 2 ? Payloads(tree).parts : payloads_v3(tree)) parts.push_back({tag, payload});
    int refused = 0, accepted = 0;
    for (int sample = 0; sample < 1500; ++sample) {
      std::vector<Part> damaged = parts;
      Part& victim = damaged[random.index(damaged.size())];
      const std::string victim_tag = victim.tag;
      const std::size_t changes = 1 + random.index(4);
      for (std::size_t c = 0; c < changes; ++c) {
        // Small values are the interesting ones in counts and indices.
        const std::size_t at = random.index(victim.payload.size());
        victim.payload[at] = static_cast<char>(random.index(2) == 0 ? random.index(4) : random.index(256));
      }
      std::string bytes = file_header(version);
      for (const Part& part : damaged) bytes += section(part.tag, part.payload);
      bytes += section("END ", "");
      std::optional<MeshTree> decoded;
      {
        const AllocationBudget budget(allowed_allocation(bytes.size()));
        try {
          decoded = decode_shatter(bytes);
        } catch (const CorruptFileError&) {
        }
      }
      if (!decoded) {
        ++refused;
        continue;
      }
      ++accepted;
      std::string again;
      REQUIRE_NOTHROW(again = encode_shatter(*decoded));
      INFO("damaged " << victim_tag << " of version " << version);
      // A varint may be written longer than needed, and a position may name
      // another source of the same bits: the tree, not the bytes, comes back.
      REQUIRE(tree_difference(decode_within_budget(again), *decoded).empty());
    }
    CHECK(refused > 0);
    CHECK(accepted > 0);  // changes to doubles and seeds are not damage a reader can see
  }
}

TEST_CASE("the header is checked: magic, version, with distinct messages", "[shatter_file][hostile]") {
  const std::string bytes = encode_shatter(two_leaf_tree());
  std::string wrong_magic = bytes;
  wrong_magic[1] = 'X';
  check_refused(wrong_magic, "not a .shatter file");
  check_refused("ply\nformat ascii 1.0\n", "not a .shatter file");
  // Text-mode transfer turns the CR LF guard into LF: refused as not this format.
  std::string newline_translated = bytes;
  newline_translated.erase(4, 1);
  check_refused(newline_translated, "not a .shatter file");

  std::string future = bytes;
  future.replace(8, 4, Bytes{}.u32(999).data);
  check_refused(future, "unsupported .shatter format version 999");
  check_refused(future, "newer shatter");
  std::string version_zero = bytes;
  version_zero.replace(8, 4, Bytes{}.u32(0).data);
  check_refused(version_zero, "unsupported .shatter format version 0");
  CHECK(*refusal(wrong_magic) != *refusal(future));
}

TEST_CASE("hostile section tables are refused", "[shatter_file][hostile]") {
  const MeshTree tree = two_leaf_tree();
  const std::string opts = section("OPTS", recipe_payload(tree.recipe)), nodes = section("NODE", nodes_payload(tree)),
                    meshes = section("MESH", meshes_payload(tree.nodes, false)), hulls = section("HULL", meshes_payload(tree.nodes, true)),
                    bonds = section("BOND", bonds_payload(tree.bonds)), end = section("END ", "");
  // GEOM and SOLD (version 2): what a tree without an exact representation stores.
  const std::string exact = section("GEOM", geometry_payload(tree.geometry)) + section("SOLD", solids_payload(tree));

  SECTION("a section length of 2^63") {
    const std::string huge = Bytes{}.text("NODE").u64(std::uint64_t{1} << 63).u32(0).data;
    check_refused(file_header() + opts + huge + "tiny", "declares 9223372036854775808 payload bytes");
  }
  SECTION("a section length of 2^64 - 1") {
    const std::string huge = Bytes{}.text("MESH").u64(~std::uint64_t{0}).u32(0).data;
    check_refused(file_header() + huge, "truncated");
  }
  SECTION("a damaged checksum") {
    std::string bad = nodes;
    bad[12] = static_cast<char>(bad[12] ^ 1);
    check_refused(file_header() + opts + bad + meshes + hulls + bonds + exact + end, "NODE section at byte 55 fails its checksum");
  }
  SECTION("missing, repeated, unknown and trailing sections") {
    check_refused(file_header() + opts + nodes + meshes + bonds + exact + end, "no HULL section");
    check_refused(file_header() + opts + nodes + nodes + meshes + hulls + bonds + exact + end, "repeats the one at byte");
    check_refused(file_header() + opts + nodes + meshes + hulls + bonds + exact + section("FUTR", "x") + end, "unknown section 'FUTR'");
    check_refused(file_header() + opts + nodes + meshes + hulls + bonds + exact + section("\x01\xFFzz", "") + end, "unknown section '\\x01\\xFFzz'");
    check_refused(file_header() + opts + nodes + meshes + hulls + bonds + exact + end + "x", "1 bytes follow the END section");
    check_refused(file_header() + opts + nodes + meshes + hulls + bonds + exact + section("END ", "x"), "must be empty");
    check_refused(file_header() + opts + nodes + meshes + hulls + bonds + exact, "without the END section");
    // Version 2 needs GEOM and SOLD; version 1 does not know them.
    check_refused(file_header() + opts + nodes + meshes + hulls + bonds + end, "no GEOM section");
    check_refused(file_header() + opts + nodes + meshes + hulls + bonds + section("GEOM", geometry_payload(tree.geometry)) + end, "no SOLD section");
    check_refused(file_header(1) + opts + nodes + meshes + hulls + bonds + exact + end, "unknown section 'GEOM'");
  }
  SECTION("optional sections are skipped and the order of sections is free") {
    const std::string reordered = file_header() + section("xtra", "later data") + bonds + section("SOLD", solids_payload(tree)) + hulls +
                                  section("note", "") + meshes + section("GEOM", geometry_payload(tree.geometry)) + nodes + opts + end;
    const MeshTree decoded = decode_within_budget(reordered);
    CHECK(tree_difference(tree, decoded).empty());
    CHECK(encode_shatter(decoded) == encode_shatter(tree));
  }
}

TEST_CASE("the version that built a tree is kept in the optional vers section", "[shatter_file][version]") {
  const MeshTree& built = small_plane_tree();
  REQUIRE(built.shatter_version == version_string);
  const std::string bytes = encode_shatter(built);
  // Right after the header: tag, u64 length, CRC, then the text itself.
  CHECK(bytes.substr(12, 4) == "vers");
  CHECK(bytes.substr(16, 8) == Bytes{}.u64(version_string.size()).data);
  CHECK(bytes.substr(28, version_string.size()) == version_string);
  CHECK(bytes.substr(28 + version_string.size(), 4) == "OPTS");
  CHECK(decode_within_budget(bytes).shatter_version == version_string);

  const MeshTree unversioned = two_leaf_tree();
  REQUIRE(unversioned.shatter_version.empty());
  MeshTree versioned = unversioned;
  versioned.shatter_version = "1.22.333-rc.1+build.7";

  SECTION("a tree without a version writes no vers section and reads back without one") {
    const std::string plain = encode_shatter(unversioned);
    CHECK(plain.substr(12, 4) == "OPTS");
    CHECK(decode_within_budget(plain).shatter_version.empty());
    check_round_trip(versioned);
  }
  SECTION("a reader that does not know vers skips it, as version 2 readers before it do") {
    // The reading rules at work: the same section under a tag this reader does
    // not know, lower-case first, is skipped and the tree read without a version.
    std::string renamed = encode_shatter(versioned);
    renamed.replace(12, 4, "vxyz");
    CHECK(tree_difference(decode_within_budget(renamed), unversioned).empty());
  }
  SECTION("it may stand anywhere before END, in either format version") {
    const std::string body = Payloads(unversioned).file(1);
    const std::string before_end = body.substr(0, body.size() - 16) + section("vers", "0.0.1") + section("END ", "");
    CHECK(decode_within_budget(before_end).shatter_version == "0.0.1");
  }
  SECTION("a repeated or malformed vers section is refused") {
    const std::string body = Payloads(unversioned).file();
    const auto with_first = [&](const std::string& sections) { return file_header() + sections + body.substr(12); };
    check_refused(with_first(section("vers", "0.1.0") + section("vers", "0.1.0")), "vers section at byte 33 repeats the one at byte 12");
    check_refused(with_first(section("vers", "")), "vers section at byte 12: the version is empty");
    check_refused(with_first(section("vers", std::string(65, '1'))), "the version is 65 bytes long (at most 64)");
    check_refused(with_first(section("vers", "0.1 beta")), "byte 3 of the version is 0x20");
    check_refused(with_first(section("vers", "0.1\x80")), "byte 3 of the version is 0x80");
    CHECK(decode_within_budget(with_first(section("vers", std::string(64, '~')))).shatter_version == std::string(64, '~'));
  }
  SECTION("encode_shatter refuses a version a reader would refuse") {
    for (const std::string& bad : {std::string(65, '1'), std::string("0.1 beta"), std::string("0.1\n")}) {
      versioned.shatter_version = bad;
      CHECK_THROWS_AS(encode_shatter(versioned), std::invalid_argument);
    }
  }
}

/// A repair report with one change of every kind (counts and texts varying with
/// `seed`) and `notes` notes, as `fracture --repair` could record it.
RepairReport repair_report_of(std::uint64_t seed, std::size_t notes) {
  RepairReport report;
  report.vertices_before = 1000 + seed;
  report.triangles_before = 2000 + 3 * seed;
  report.vertices_after = 990 + seed;
  report.triangles_after = (std::uint64_t{1} << 40) + seed;  // counts are 64-bit in the file
  for (std::size_t k = 0; k < all_repair_kinds.size(); ++k) {
    const RepairKind kind = all_repair_kinds[(k + seed) % all_repair_kinds.size()];
    report.changes.push_back({kind, seed * 7 + k, std::string(repair_kind_name(kind)) + ": " + std::string(k + seed % 5, 'x')});
  }
  for (std::size_t k = 0; k < notes; ++k) report.notes.push_back({"hole " + std::to_string(k) + " left open \xc3\xa9"});
  return report;
}

TEST_CASE("how the input was repaired is kept in the optional rpar section", "[shatter_file][repair]") {
  const MeshTree plain = two_leaf_tree();
  REQUIRE(plain.input_repair.empty());
  CHECK(encode_shatter(plain).find("rpar") == std::string::npos);

  SECTION("every kind, with and without notes, round-trips and is laid out as documented") {
    for (std::uint64_t seed = 0; seed < 12; ++seed) {
      MeshTree repaired = plain;
      repaired.input_repair = repair_report_of(seed, seed % 3);
      const std::string bytes = encode_shatter(repaired);
      CHECK(byte_difference(bytes, reference_file_v3(repaired)) == "equal");
      CHECK(tree_difference(decode_within_budget(bytes), repaired).empty());
    }
    MeshTree notes_only = plain;
    notes_only.input_repair.notes.push_back({"a hole of 3 edges was left"});
    check_round_trip(notes_only);
  }
  MeshTree repaired = plain;
  repaired.input_repair = repair_report_of(5, 1);
  const std::string bytes = encode_shatter(repaired);
  const std::size_t at = bytes.find("rpar");
  REQUIRE(at == 12);  // first: the hand-built tree has no version

  SECTION("a reader that does not know rpar skips it and reads the same tree without it") {
    std::string renamed = bytes;
    renamed.replace(at, 4, "rxyz");
    CHECK(tree_difference(decode_within_budget(renamed), plain).empty());
  }
  SECTION("a repeated, empty or malformed rpar section is refused with one line") {
    const std::string body = bytes.substr(12);  // the sections, rpar first
    const std::string payload = repair_payload_reference(repaired.input_repair);
    const auto with_rpar = [&](const std::string& rpar_payload) {
      return file_header(3) + section("rpar", rpar_payload) + body.substr(16 + payload.size());
    };
    REQUIRE(tree_difference(decode_within_budget(with_rpar(payload)), repaired).empty());
    check_refused(file_header(3) + section("rpar", payload) + body, "rpar section at byte");
    check_refused(with_rpar(repair_payload_reference(RepairReport{})), "no change and no note");
    // Byte 36 is the first change's kind (four u64 counts, then the u32 change count).
    std::string bad_kind = payload;
    bad_kind[36] = static_cast<char>(all_repair_kinds.size());
    check_refused(with_rpar(bad_kind), "unknown repair kind " + std::to_string(all_repair_kinds.size()));
    std::string control = payload;
    control[36 + 1 + 8 + 4] = '\n';  // the first byte of the first change's text
    check_refused(with_rpar(control), "(a control character)");
    std::string huge_count = payload;
    huge_count.replace(32, 4, Bytes{}.u32(0xFFFFFFFF).data);
    check_refused(with_rpar(huge_count), "4294967295 changes need at least 13 bytes each");
    std::string huge_text = payload;
    huge_text.replace(36 + 1 + 8, 4, Bytes{}.u32(0xFFFFFFF0).data);
    check_refused(with_rpar(huge_text), "4294967280 text bytes need at least 1 bytes each");
    check_refused(with_rpar(payload + "x"), "1 unexpected bytes after the last record");
    for (std::size_t cut = 0; cut < payload.size(); cut += 7) {
      CHECK(refusal(with_rpar(payload.substr(0, cut))).has_value());
    }
  }
  SECTION("encode_shatter refuses a text a reader would refuse") {
    for (const std::string& bad : {std::string(), std::string("two\nlines"), std::string(4097, 'a'), std::string("tab\there")}) {
      MeshTree tree = plain;
      tree.input_repair.changes.push_back({RepairKind::filled_holes, 1, bad});
      CHECK_THROWS_AS(encode_shatter(tree), std::invalid_argument);
      tree.input_repair.changes.clear();
      tree.input_repair.notes.push_back({bad});
      CHECK_THROWS_AS(encode_shatter(tree), std::invalid_argument);
    }
  }
}

TEST_CASE("hostile counts are refused before anything is allocated", "[shatter_file][hostile]") {
  const MeshTree tree = two_leaf_tree();
  const auto with_section = [&](std::string_view tag, const std::string& payload) { return Payloads(tree).with(tag, payload).file(); };
  check_refused(with_section("NODE", Bytes{}.u32(0xFFFFFFFFu).u64(0).data), "4294967295 nodes need at least 165 bytes each");
  check_refused(with_section("NODE", Bytes{}.u32(0).data), "node count 0");
  // A node whose child count claims 2^32 - 1 children.
  std::string nodes = nodes_payload(tree);
  nodes.replace(4 + 161, 4, Bytes{}.u32(0xFFFFFFFFu).data);
  check_refused(with_section("NODE", nodes), "4294967295 children need at least 4 bytes each");
  // Two empty meshes after the hostile one, so the mesh count itself fits.
  const std::string two_empty_meshes = Bytes{}.u32(0).u32(0).u8(0).u32(0).u32(0).u8(0).data;
  check_refused(with_section("MESH", Bytes{}.u32(3).u32(0xFFFFFFFFu).u32(0).u8(0).data + two_empty_meshes),
                "4294967295 vertices need at least 24 bytes each");
  check_refused(with_section("HULL", Bytes{}.u32(3).u32(0).u32(0xFFFFFFFFu).u8(0).data + two_empty_meshes),
                "4294967295 triangles need at least 16 bytes each");
  check_refused(with_section("MESH", Bytes{}.u32(0xFFFFFFFFu).data), "4294967295 meshes for 3 nodes");
  check_refused(with_section("BOND", Bytes{}.u64(~std::uint64_t{0}).data), "18446744073709551615 bonds need at least 68 bytes each");
  check_refused(with_section("BOND", Bytes{}.u64(1).u32(0).data), "1 bonds need at least 68 bytes each, but only 4 bytes remain");
  check_refused(with_section("NODE", nodes_payload(tree).substr(0, nodes_payload(tree).size() - 1)),
                "node 2: the payload ends inside child count");
  check_refused(with_section("BOND", bonds_payload(tree.bonds) + "!"), "1 unexpected bytes after the last record");
  check_refused(with_section("OPTS", recipe_payload(tree.recipe).substr(0, 24)), "the payload ends inside max_plane_tries");

  // Attribute channels claiming 3T values with none present.
  Mesh mesh = test::box({0, 0, 0}, {1, 1, 1});
  std::string record = mesh_record(mesh);
  record[8] = 7;
  const std::string one_mesh_three_times = Bytes{}.u32(3).data + record + mesh_record(mesh) + mesh_record(mesh);
  check_refused(with_section("MESH", one_mesh_three_times), "36 corner normals need at least 24 bytes each");
  record[8] = 8;
  check_refused(with_section("MESH", Bytes{}.u32(3).data + record + mesh_record(mesh) + mesh_record(mesh)), "unknown attribute channel bits 0x08");
}

TEST_CASE("enum and bool bytes out of range are refused", "[shatter_file][hostile]") {
  const MeshTree tree = two_leaf_tree();
  const std::string good = encode_shatter(tree);
  const std::size_t opts_payload = 12 + 16;
  const auto with_byte = [&](std::size_t at, std::uint8_t value) {
    std::string payload = recipe_payload(tree.recipe);
    payload[at] = static_cast<char>(value);
    return good.substr(0, 12) + section("OPTS", payload) + good.substr(opts_payload + 27);
  };
  check_refused(with_byte(12, 4), "OPTS section, byte 40: strategy 4 is unknown");
  check_refused(with_byte(13, 3), "kernel 3 is unknown");
  check_refused(with_byte(26, 2), "allow_self_intersections is 2 (must be 0 or 1)");
  std::string nodes = nodes_payload(tree);
  nodes[4 + 24] = 5;  // above_parent_plane of the root
  check_refused(file_with_nodes_payload(tree, nodes), "node 0: above_parent_plane is 5");
  MeshTree zero_fragments = tree;
  zero_fragments.recipe.fragments = 0;
  check_refused(reference_file(zero_fragments), "recipe.fragments is 0");
}

TEST_CASE("invalid trees with correct checksums are refused", "[shatter_file][hostile]") {
  // Each case breaks one invariant of a valid tree, writes it with the reference
  // writer (correct checksums), and expects the reader to name the defect; the
  // library's own encoder refuses the same tree.
  struct Case {
    const char* name;
    MeshTree tree;
    const char* expected;
  };
  std::vector<Case> cases;
  const auto add = [&](const char* name, const MeshTree& base, auto&& change, const char* expected) {
    MeshTree tree = base;
    change(tree);
    cases.push_back({name, std::move(tree), expected});
  };
  const MeshTree small = two_leaf_tree(), deep = deep_tree();

  add("triangle index out of range", small, [](MeshTree& t) { t.nodes[1].mesh->triangles[3][2] = 8; },
      "MESH section, byte 991: the mesh of node 1 triangle 3 corner 2 has vertex index 8, but there are only 8 vertices");
  add("hull triangle index out of range", deep, [](MeshTree& t) { t.nodes[4].hull->triangles.back()[0] = 0xFFFFFFFFu; },
      "the hull of node 4 triangle");
  add("root with a parent", small, [](MeshTree& t) { t.nodes[0].parent = 2; }, "node 0 (the root) has parent 2");
  add("root with depth", small, [](MeshTree& t) { t.nodes[0].depth = 1; }, "node 0 (the root) has depth 1");
  add("cycle in parent links", small,
      [](MeshTree& t) {
        t.nodes[1].parent = 2;
        t.nodes[2].parent = 1;
      },
      "node 1 has parent 2, but node 0 lists it as a child");
  add("cycle in children", deep, [](MeshTree& t) { t.nodes[1].children = {0, 2}; }, "node 1 lists child 0, which already has its place");
  add("self as child", deep, [](MeshTree& t) { t.nodes[1].children = {1, 2}; }, "node 1 lists child 1, which already has its place");
  add("child listed by two parents (overlapping children)", deep, [](MeshTree& t) { t.nodes[0].children = {1, 3, 5}; },
      "node 0 lists child 3, which already has its place");
  add("children out of preorder", deep, [](MeshTree& t) { t.nodes[0].children = {1, 5, 4}; },
      "node 0 lists child 5, but depth-first preorder puts node 4 there");
  add("child beyond the nodes", small, [](MeshTree& t) { t.nodes[0].children = {1, 2, 7}; }, "node 0 lists child 7, but there are only 3 nodes");
  add("child index no_node", small, [](MeshTree& t) { t.nodes[0].children = {1, no_node}; }, "node 0 lists child 4294967295");
  add("single child", small, [](MeshTree& t) { t.nodes[0].children = {1}; }, "node 0 has one child");
  add("unreachable node", small,
      [](MeshTree& t) {
        t.nodes[0].children = {1, 2};
        t.nodes.push_back(t.nodes[2]);
        t.cut_planes.push_back(t.cut_planes[2]);  // one plane per node, as every tree holds them
      },
      "node 3 is not reachable from the root");
  add("wrong depth", deep, [](MeshTree& t) { t.nodes[3].depth = 1; }, "node 3 has depth 1, but its parent's depth is 1");
  add("overlapping leaf ranges", deep, [](MeshTree& t) { t.nodes[4].first_leaf = 1; }, "node 4 claims leaves [1, +1), but its subtree holds [2, +1)");
  add("leaf count not the sum of the children's", deep, [](MeshTree& t) { t.nodes[1].leaf_count = 3; }, "node 1 claims leaves [0, +3)");
  add("bond with first == second", small, [](MeshTree& t) { t.bonds[0].second = 0; }, "BOND section, byte");
  add("bond with first > second", small, [](MeshTree& t) { std::swap(t.bonds[0].first, t.bonds[0].second); }, "does not have first < second");
  add("bond beyond the leaves", small, [](MeshTree& t) { t.bonds[0].second = 2; }, "names a leaf beyond the 2 leaves");
  add("bond cut at a leaf", small, [](MeshTree& t) { t.bonds[0].cut_node = 1; }, "does not name an internal node");
  add("bond cut beyond the nodes", small, [](MeshTree& t) { t.bonds[0].cut_node = no_node; }, "cut node none) does not name an internal node");
  add("bond across a cut that does not separate it", deep, [](MeshTree& t) { t.bonds[0].cut_node = 0; }, "the cut of its cut node does not separate");
  add("bonds out of order", deep, [](MeshTree& t) { std::swap(t.bonds[1], t.bonds[3]); }, "is out of order");

  for (const Case& c : cases) {
    INFO(c.name);
    check_refused(reference_file(c.tree), c.expected);
    CHECK_THROWS_AS(encode_shatter(c.tree), std::invalid_argument);
  }
}

TEST_CASE("encode_shatter refuses trees a reader could not trust", "[shatter_file]") {
  MeshTree tree = two_leaf_tree();
  tree.leaf_nodes = {2, 1};
  CHECK_THROWS_WITH(encode_shatter(tree), Catch::Contains("leaf_nodes[0] is node 2, but leaf 0 is node 1"));
  tree = two_leaf_tree();
  tree.nodes[2].mesh->surfaces.pop_back();
  CHECK_THROWS_WITH(encode_shatter(tree), Catch::Contains("the mesh of node 2 has 11 surface ids for 12 triangles"));
  tree = two_leaf_tree();
  tree.nodes[1].hull->corners.uvs.resize(5);
  CHECK_THROWS_WITH(encode_shatter(tree), Catch::Contains("has 5 uvs for 12 triangles"));
  CHECK_THROWS_AS(encode_shatter(MeshTree{}), std::invalid_argument);
  tree = two_leaf_tree();
  tree.recipe.strategy = static_cast<Strategy>(9);
  CHECK_THROWS_WITH(encode_shatter(tree), Catch::Contains("recipe.strategy 9"));
}

TEST_CASE("write_shatter_file and read_shatter_file", "[shatter_file][io]") {
  const std::filesystem::path directory = std::filesystem::temp_directory_path() / ("shatter-file-test-" + std::to_string(::getpid()));
  std::filesystem::remove_all(directory);
  std::filesystem::create_directories(directory);
  const MeshTree tree = deep_tree();
  const std::filesystem::path path = directory / "tree.shatter";

  write_shatter_file(path, tree);
  CHECK(tree_difference(tree, read_shatter_file(path)).empty());
  // Overwriting replaces the file whole, leaving no temporary beside it.
  write_shatter_file(path, two_leaf_tree());
  CHECK(tree_difference(two_leaf_tree(), read_shatter_file(path)).empty());
  CHECK(std::distance(std::filesystem::directory_iterator(directory), std::filesystem::directory_iterator{}) == 1);

  CHECK_THROWS_AS(write_shatter_file(directory / "no such directory" / "tree.shatter", tree), IoError);
  CHECK_THROWS_AS(write_shatter_file(directory, tree), IoError);  // a directory
  CHECK_THROWS_AS(read_shatter_file(directory / "missing.shatter"), IoError);
  CHECK_THROWS_AS(read_shatter_file(directory), IoError);

  {
    std::string damaged = encode_shatter(tree);
    damaged[damaged.size() / 2] = static_cast<char>(damaged[damaged.size() / 2] ^ 0x10);
    std::ofstream(directory / "damaged.shatter", std::ios::binary) << damaged;
  }
  CHECK_THROWS_AS(read_shatter_file(directory / "damaged.shatter"), CorruptFileError);
  CHECK_THROWS_WITH(read_shatter_file(directory / "damaged.shatter"), Catch::StartsWith((directory / "damaged.shatter").string() + ": damaged"));
  std::filesystem::remove_all(directory);
}

// ---------------------------------------------------------------------------
// Version 2: the plane kernel's exact representation (GEOM, SOLD), and version 1

namespace {

/// The file offset of `tag`'s payload in Payloads::file() (version 2).
std::size_t payload_offset(const Payloads& payloads, std::string_view tag) {
  std::size_t at = 12;
  for (const auto& [t, payload] : payloads.parts) {
    if (t == tag) return at + 16;
    at += 16 + payload.size();
  }
  throw std::logic_error("no such section");
}

/// What encode_shatter writes for a tree read from a version 1 file laid out as
/// version 1's encoder laid it out: the same bytes with version 2, and an empty
/// GEOM (8 zero bytes) and SOLD (4) before END.
std::string converted_from_version_1(std::string_view v1) {
  return std::string(v1.substr(0, 8)) + Bytes{}.u32(2).data + std::string(v1.substr(12, v1.size() - 12 - 16)) +
         section("GEOM", std::string(8, '\0')) + section("SOLD", std::string(4, '\0')) + section("END ", "");
}

std::string read_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

/// The committed fuzz corpus of the .shatter reader (tests/formats/CMakeLists.txt names it).
std::filesystem::path shatter_corpus() { return SHATTER_SHATTER_CORPUS; }

/// The index of the first node (from the back, so a leaf) whose solid has a face
/// on a cut plane and a vertex of kind three_planes.
std::size_t deep_node(const MeshTree& tree) {
  for (std::size_t k = tree.nodes.size(); k-- > 1;) {
    const Solid& s = tree.nodes[k].solid;
    const bool cut_face = std::any_of(s.faces.begin(), s.faces.end(), [](const SolidFace& f) { return f.plane.is_cut(); });
    const bool three = std::any_of(s.defs.begin(), s.defs.end(), [](const PointDef& d) { return d.kind == PointKind::three_planes; });
    if (cut_face && three) return k;
  }
  throw std::logic_error("no node with a cut face and a three_planes vertex");
}

}  // namespace

TEST_CASE("version 1 files still read, as trees without an exact representation", "[shatter_file][v1]") {
  SECTION("built by the reference writer") {
    for (const MeshTree& tree : {two_leaf_tree(), deep_tree()}) {
      const std::string v1 = reference_file(tree, 1);
      REQUIRE(v1.substr(8, 4) == Bytes{}.u32(1).data);
      const MeshTree decoded = decode_within_budget(v1);
      CHECK(tree_difference(tree, decoded).empty());
      CHECK(!decoded.has_exact_representation());
      CHECK(decoded.cut_planes.size() == decoded.nodes.size());
      // Version 1 is version 2 without the exact representation's sections.
      CHECK(tree_difference(decode_within_budget(converted_from_version_1(v1)), decoded).empty());
      CHECK(byte_difference(encode_shatter(decoded), reference_file_v3(tree)) == "equal");
    }
  }
  SECTION("the committed corpus files written by version 1's encoder") {
    for (const char* name : {"cube-4-fragments.shatter", "cube-2-fragments-exact.shatter", "optional-section-before-end.shatter"}) {
      INFO(name);
      const std::string v1 = read_bytes(shatter_corpus() / name);
      REQUIRE(v1.size() > 12);
      REQUIRE(v1.substr(8, 4) == Bytes{}.u32(1).data);
      const MeshTree decoded = decode_within_budget(v1);
      CHECK(decoded.recipe.kernel != KernelKind::plane);
      CHECK(decoded.geometry.points.empty());
      CHECK(decoded.leaf_count() >= 2);
      for (const MeshTreeNode& node : decoded.nodes) CHECK((node.solid->defs.empty() && !node.convex && !node.hull->positions.empty()));
      check_round_trip(decoded);
      if (std::string_view(name) != "optional-section-before-end.shatter") {
        CHECK(tree_difference(decode_within_budget(converted_from_version_1(v1)), decoded).empty());
      }
    }
  }
  SECTION("every truncation and single-byte change of a version 1 file is refused") {
    const std::string v1 = reference_file(two_leaf_tree(), 1);
    for (std::size_t length = 0; length < v1.size(); ++length) REQUIRE(refusal(std::string_view(v1).substr(0, length)));
    std::size_t accepted = 0;
    for (std::size_t position = 0; position < v1.size(); ++position) {
      for (const int change : {0x01, 0x20, 0xFF}) {
        std::string damaged = v1;
        damaged[position] = static_cast<char>(static_cast<unsigned char>(damaged[position]) ^ change);
        if (!refusal(damaged)) ++accepted;
      }
    }
    CHECK(accepted == 0);
  }
  SECTION("other versions are refused, naming the versions read") {
    std::string v4 = encode_shatter(small_plane_tree());
    v4.replace(8, 4, Bytes{}.u32(4).data);
    check_refused(v4, "unsupported .shatter format version 4 at byte 8 (this build reads versions 1 to 3: the file is from a newer shatter");
  }
}

TEST_CASE("plane-kernel trees round-trip exactly, exact representation and caches included", "[shatter_file][build]") {
  // build_mesh_tree's default kernel is the plane kernel. Every generated mesh,
  // every strategy, a few fragment counts; decode must give back every solid,
  // the input geometry, the cut planes and the recomputed caches bit for bit.
  std::size_t convex = 0, non_convex = 0, trees = 0;
  for (const test::NamedMesh& input : test::generated_meshes()) {
    for (const Strategy strategy : {Strategy::thesis, Strategy::balanced, Strategy::axis}) {
      for (const std::uint32_t fragments : {1u, 3u, 12u, 48u}) {
        TreeRecipe recipe;
        recipe.fragments = fragments;
        recipe.seed = 100 + fragments;
        recipe.strategy = strategy;
        INFO(input.name << ", " << strategy_name(strategy) << ", N = " << fragments);
        const MeshTree tree = build_mesh_tree(input.mesh, recipe);
        CHECK(test::tree_problem(tree) == "");
        REQUIRE(tree.recipe.kernel == KernelKind::plane);
        REQUIRE(tree.leaf_count() >= fragments);
        REQUIRE(!tree.geometry.points.empty());
        REQUIRE(tree.cut_planes.size() == tree.nodes.size());
        for (const MeshTreeNode& node : tree.nodes) {
          REQUIRE(!node.solid->defs.empty());
          (node.convex ? convex : non_convex) += 1;
          if (node.convex) REQUIRE(node.hull->positions.empty());
        }
        check_round_trip(tree);
        ++trees;
      }
    }
  }
  CHECK(trees == 120);
  CHECK(convex > 0);
  CHECK(non_convex > 0);
}

TEST_CASE("hostile counts in GEOM and SOLD are refused before anything is allocated", "[shatter_file][hostile]") {
  const MeshTree& tree = small_plane_tree();
  const Solid& root = tree.nodes[0].solid;
  const auto with = [&](std::string_view tag, const std::string& payload) { return Payloads(tree).with(tag, payload).file(); };
  const std::string geometry = geometry_payload(tree.geometry), solids = solids_payload(tree);
  const auto patched = [](std::string payload, std::size_t at, std::uint32_t value) {
    payload.replace(at, 4, Bytes{}.u32(value).data);
    return payload;
  };
  const auto patched_byte = [](std::string payload, std::size_t at, std::uint8_t value) {
    payload[at] = static_cast<char>(value);
    return payload;
  };
  const std::size_t points = tree.geometry.points.size(), nodes = tree.nodes.size();

  check_refused(with("GEOM", patched(geometry, 0, 0xFFFFFFFFu)), "4294967295 input points need at least 24 bytes each");
  check_refused(with("GEOM", patched(geometry, 4, 0xFFFFFFFFu)), "4294967295 input planes need at least 12 bytes each");
  check_refused(with("GEOM", Bytes{}.u32(0).u32(1).data), "1 input planes need at least 12 bytes each, but only 0 bytes remain");
  check_refused(with("GEOM", geometry + "!"), "GEOM section, byte");
  check_refused(with("GEOM", geometry + "!"), "1 unexpected bytes after the last record");
  check_refused(with("GEOM", geometry.substr(0, 8 + 24 * points - 1)),
                std::to_string(points) + " input points need at least 24 bytes each, but only " + std::to_string(24 * points - 1) + " bytes remain");

  // Records for every node when GEOM holds points, none otherwise.
  check_refused(with("SOLD", patched(solids, 0, 0xFFFFFFFFu)), "4294967295 solids for " + std::to_string(nodes) + " nodes");
  check_refused(with("SOLD", patched(solids, 0, 0)), "0 solids for " + std::to_string(nodes) + " nodes");
  MeshTree fast = two_leaf_tree();
  check_refused(Payloads(fast).with("SOLD", Bytes{}.u32(3).data).file(), "3 solids, but GEOM holds no input points");

  // The root's record starts at payload byte 4: u8 flags, then V, F, L, C.
  const std::size_t V = root.defs.size(), F = root.faces.size();
  check_refused(with("SOLD", patched(solids, 5, 0xFFFFFFFFu)), "node 0: 4294967295 vertex definitions need at least 13 bytes each");
  check_refused(with("SOLD", patched(solids, 9, 0xFFFFFFFFu)), "node 0: 4294967295 faces need at least 17 bytes each");
  check_refused(with("SOLD", patched(solids, 13, 0xFFFFFFFFu)), "node 0: 4294967295 loops need at least 4 bytes each");
  check_refused(with("SOLD", patched(solids, 17, 0xFFFFFFFFu)), "node 0: 4294967295 corners need at least 9 bytes each");
  const std::size_t faces_at = 21 + 13 * V, loops_at = faces_at + 17 * F;
  check_refused(with("SOLD", patched(solids, faces_at + 13, 0xFFFFFFFFu)), "node 0: the faces claim 4294967295 loops or more");
  check_refused(with("SOLD", patched(solids, loops_at, 0xFFFFFFFFu)), "node 0: the loops claim 4294967295 corners or more");
  check_refused(with("SOLD", patched_byte(solids, 4, 4)), "node 0: unknown solid flag bits 0x04");
  check_refused(with("SOLD", patched_byte(solids, faces_at + 4, 0x82)), "node 0: unknown face flag bits 0x82");
  check_refused(with("SOLD", patched_byte(solids, 21, 3)), "node 0: vertex 0 has unknown kind 3");
  // The last record ends with its corners: 9 bytes each, 8 more with a segment.
  const Solid& last = tree.nodes.back().solid;
  const std::size_t last_corners = last.corners.size();
  if (std::none_of(last.corners.begin(), last.corners.end(), [](const SolidCorner& c) { return c.line.is_segment(); })) {
    check_refused(with("SOLD", solids.substr(0, solids.size() - 1)), "node " + std::to_string(nodes - 1) + ": " + std::to_string(last_corners) +
                                                                          " corners need at least 9 bytes each, but only " +
                                                                          std::to_string(9 * last_corners - 1) + " bytes remain");
  } else {
    check_refused(with("SOLD", solids.substr(0, solids.size() - 1)), "node " + std::to_string(nodes - 1) + ": the payload ends inside corner");
  }
  // Corner segments: the flag is 0 or 1, and a flagged segment is two points.
  const std::size_t corners_at = loops_at + 4 * root.loops.size();
  REQUIRE(root.corners[0].line.is_segment());  // the input's edges are input segments
  check_refused(with("SOLD", patched_byte(solids, corners_at + 8, 2)), "node 0: corner segment flag is 2 (must be 0 or 1)");
  check_refused(with("SOLD", patched(solids, corners_at + 9, no_index)), "node 0: corner 0 has a segment flag, but its segment is none");
  check_refused(with("SOLD", solids + "!"), "1 unexpected bytes after the last record");
  // One more loop than the faces hold (a loop of no corners, so the loops still
  // fit the corners): a loop no face owns.
  const std::size_t L = root.loops.size();
  std::string extra_loop = patched(solids, 13, static_cast<std::uint32_t>(L + 1));
  extra_loop.insert(loops_at + 4 * L, Bytes{}.u32(0).data);
  check_refused(with("SOLD", extra_loop), "the solid of node 0 has " + std::to_string(L + 1) + " loops, but its faces hold " + std::to_string(L));
}

TEST_CASE("invalid exact representations with correct checksums are refused", "[shatter_file][hostile]") {
  // As "invalid trees with correct checksums": each case breaks one structural
  // invariant of the exact representation, is written by the reference writer,
  // and the reader names the defect and its section; the encoder refuses the
  // same tree with the same words.
  struct Case {
    std::string name;
    MeshTree tree;
    std::string expected;  ///< in both messages
    std::string where;     ///< in the reader's message
  };
  std::vector<Case> cases;
  const MeshTree& base = small_plane_tree();
  const std::size_t P = base.geometry.points.size(), Q = base.geometry.planes.size();
  const auto add = [&](std::string name, auto&& change, std::string expected, std::string where) {
    MeshTree tree = base;
    change(tree);
    cases.push_back({std::move(name), std::move(tree), std::move(expected), std::move(where)});
  };
  const Payloads payloads(base);
  const std::size_t geometry_at = payload_offset(payloads, "GEOM"), solids_at = payload_offset(payloads, "SOLD");
  const std::size_t k = deep_node(base);  // a node below at least one cut
  const Solid& deep = base.nodes[k].solid;
  const std::string node_k = "the solid of node " + std::to_string(k) + " ";
  const std::size_t cut_face =
      std::find_if(deep.faces.begin(), deep.faces.end(), [](const SolidFace& f) { return f.plane.is_cut(); }) - deep.faces.begin();
  const std::size_t three =
      std::find_if(deep.defs.begin(), deep.defs.end(), [](const PointDef& d) { return d.kind == PointKind::three_planes; }) - deep.defs.begin();
  const auto sibling = static_cast<NodeIndex>(k + 1 < base.nodes.size() && base.nodes[k + 1].parent == base.nodes[k].parent ? k + 1 : k - 1);

  add("input point NaN", [](MeshTree& t) { t.geometry.points[3].y = std::numeric_limits<double>::quiet_NaN(); },
      "input point 3 has a coordinate that is NaN or infinite", "GEOM section, byte " + std::to_string(geometry_at + 8 + 3 * 24) + ": ");
  add("input point infinite", [](MeshTree& t) { t.geometry.points[0].z = -std::numeric_limits<double>::infinity(); },
      "input point 0 has a coordinate that is NaN or infinite", "GEOM section");
  add("input plane beyond the points", [&](MeshTree& t) { t.geometry.planes[1][2] = static_cast<VertexIndex>(P); },
      "input plane 1 names input point " + std::to_string(P) + ", but there are only " + std::to_string(P) + " input points",
      "GEOM section, byte " + std::to_string(geometry_at + 8 + 24 * P + 12) + ": ");
  add("cut plane of an internal node infinite",
      [](MeshTree& t) { t.cut_planes[0].offset = std::numeric_limits<double>::infinity(); },
      "node 0 has a plane with a NaN or infinite coefficient", "NODE section");
  add("input vertex beyond the points", [&](MeshTree& t) { t.nodes[0].solid->defs[2].a = static_cast<std::uint32_t>(P); },
      "the solid of node 0 vertex 2 (input) names input point " + std::to_string(P) + ", but there are only", "SOLD section, byte " + std::to_string(solids_at + 4) + ": ");
  add("input vertex with a field its kind does not use", [](MeshTree& t) { t.nodes[0].solid->defs[0].b = 5; },
      "the solid of node 0 vertex 0 (input) has b = 5, a field its kind does not use (must be 0)", "SOLD section");
  add("input vertex with a plane", [](MeshTree& t) { t.nodes[0].solid->defs[0].planes[0] = PlaneRef::input(1); },
      "vertex 0 (input) has plane 0 = 0x00000001, a field its kind does not use", "SOLD section");
  add("vertex of an unknown kind", [](MeshTree& t) { t.nodes[0].solid->defs[1].kind = static_cast<PointKind>(7); },
      "vertex 1 has unknown kind 7", "SOLD section");
  add("face on its own node's cut plane", [&](MeshTree& t) { t.nodes[k].solid->faces[cut_face].plane = PlaneRef::cut(static_cast<std::uint32_t>(k)); },
      node_k + "face " + std::to_string(cut_face) + " names cut plane " + std::to_string(k), "SOLD section");
  add("face on a sibling's cut plane", [&](MeshTree& t) { t.nodes[k].solid->faces[cut_face].plane = PlaneRef::cut(sibling); },
      "but node " + std::to_string(sibling) + " is not an ancestor of node " + std::to_string(k), "SOLD section");
  add("root on a cut plane", [](MeshTree& t) { t.nodes[0].solid->faces[0].plane = PlaneRef::cut(0); },
      "the solid of node 0 face 0 names cut plane 0 (0x80000000), but node 0 is not an ancestor of node 0", "SOLD section");
  add("face on an input plane beyond the planes", [&](MeshTree& t) { t.nodes[k].solid->faces[0].plane = PlaneRef::input(static_cast<std::uint32_t>(Q)); },
      node_k + "face 0 names input plane " + std::to_string(Q) + ", but there are only " + std::to_string(Q) + " input planes", "SOLD section");
  add("three_planes vertex on a node beyond the tree", [&](MeshTree& t) { t.nodes[k].solid->defs[three].planes[2] = PlaneRef::cut(1000); },
      node_k + "vertex " + std::to_string(three) + " (three_planes) plane 2 names cut plane 1000 (0x800003E8), but node 1000 is not an ancestor",
      "SOLD section");
  add("three_planes vertex with the none sentinel", [&](MeshTree& t) { t.nodes[k].solid->defs[three].planes[0] = PlaneRef{no_index}; },
      "plane 0 names cut plane 2147483647 (0xFFFFFFFF)", "SOLD section");
  add("corner line on an input plane beyond the planes",
      [&](MeshTree& t) { t.nodes[k].solid->corners[1].line.other = PlaneRef::input(static_cast<std::uint32_t>(Q + 5)); },
      node_k + "corner 1 line names input plane " + std::to_string(Q + 5), "SOLD section");
  add("corner segment not p < q", [&](MeshTree& t) { t.nodes[k].solid->corners[2].line = {PlaneRef{no_index}, 5, 3}; },
      node_k + "corner 2 has segment (5, 3), not two input points p < q < " + std::to_string(P), "SOLD section");
  add("corner segment beyond the points", [&](MeshTree& t) { t.nodes[k].solid->corners[0].line.p = 0; t.nodes[k].solid->corners[0].line.q = static_cast<std::uint32_t>(P); },
      node_k + "corner 0 has segment (0, " + std::to_string(P) + ")", "SOLD section");
  add("face without a loop",
      [&](MeshTree& t) {
        Solid& s = *t.nodes[k].solid;
        s.faces[1].loop_count += s.faces[0].loop_count;
        s.faces[1].first_loop = 0;
        s.faces[0].loop_count = 0;
      },
      node_k + "face 0 has no loop", "SOLD section");
  add("loop of two corners",
      [&](MeshTree& t) {
        Solid& s = *t.nodes[k].solid;
        s.loops[1].corner_count += s.loops[0].corner_count - 2;
        s.loops[1].first_corner = 2;
        s.loops[0].corner_count = 2;
      },
      node_k + "loop 0 has 2 corners (a loop has at least 3)", "SOLD section");
  add("corner vertex beyond the vertices", [&](MeshTree& t) { t.nodes[k].solid->corners[3].vertex = static_cast<VertexIndex>(deep.defs.size()); },
      node_k + "corner 3 has vertex " + std::to_string(deep.defs.size()) + ", but there are only " + std::to_string(deep.defs.size()) + " vertices",
      "SOLD section");
  add("corner repeating the next corner's vertex",
      [&](MeshTree& t) { t.nodes[k].solid->corners[0].vertex = t.nodes[k].solid->corners[1].vertex; },
      node_k + "corner 0 repeats vertex " + std::to_string(deep.corners[1].vertex) + " of the corner after it", "SOLD section");
  add("a loop reversed: its edges used twice",
      [&](MeshTree& t) {
        Solid& s = *t.nodes[k].solid;
        std::reverse(s.corners.begin(), s.corners.begin() + s.loops[0].corner_count);
      },
      "is used twice", "SOLD section");
  add("a vertex no corner uses",
      [&](MeshTree& t) {
        Solid& s = *t.nodes[k].solid;
        s.defs.push_back(PointDef::input(0));
        s.approx.push_back(approximate(t.plane_set(), s.defs.back()));
      },
      node_k + "vertex " + std::to_string(deep.defs.size()) + " is used by no corner", "SOLD section");
  add("a convex node with a hull",
      [&](MeshTree& t) {
        t.nodes[k].convex = true;
        t.nodes[k].hull = test::unit_cube();
      },
      "node " + std::to_string(k) + " is convex, so its hull must be empty (its mesh is its hull), but the hull has 8 vertices and 12 triangles",
      "HULL section");
  add("a degenerate vertex (the same plane twice)",
      [&](MeshTree& t) {
        PointDef& d = t.nodes[k].solid->defs[three];
        d.planes[1] = d.planes[0];
      },
      node_k + "vertex " + std::to_string(three) + " (three_planes): degenerate point definition", "SOLD section");
  {
    // A corner moved to a vertex adjacent to neither of its loop neighbours:
    // the old edges lose their reverses, and no edge is duplicated.
    const Solid& s = deep;
    std::vector<std::pair<VertexIndex, VertexIndex>> edges;
    for (const SolidLoop& loop : s.loops) {
      for (std::uint32_t i = 0; i < loop.corner_count; ++i) {
        edges.emplace_back(s.corners[loop.first_corner + i].vertex, s.corners[loop.first_corner + (i + 1) % loop.corner_count].vertex);
      }
    }
    const auto adjacent = [&](VertexIndex a, VertexIndex b) {
      return std::find(edges.begin(), edges.end(), std::pair{a, b}) != edges.end() || std::find(edges.begin(), edges.end(), std::pair{b, a}) != edges.end();
    };
    const std::uint32_t n = s.loops[0].corner_count;
    const VertexIndex before = s.corners[n - 1].vertex, after = s.corners[1].vertex;
    std::optional<VertexIndex> moved;
    for (VertexIndex w = 0; w < s.defs.size() && !moved; ++w) {
      if (w != before && w != after && w != s.corners[0].vertex && !adjacent(w, before) && !adjacent(w, after)) moved = w;
    }
    // The deep solid always has such a vertex; without one this case would test nothing.
    REQUIRE(moved);
    add("an open solid", [&](MeshTree& t) { t.nodes[k].solid->corners[0].vertex = *moved; }, "has no reverse: the solid is open", "SOLD section");
  }

  for (const Case& c : cases) {
    INFO(c.name);
    check_refused(reference_file(c.tree), c.where);
    check_refused(reference_file(c.tree), c.expected);
    CHECK_THROWS_AS(encode_shatter(c.tree), std::invalid_argument);
    CHECK_THROWS_WITH(encode_shatter(c.tree), Catch::Contains(c.expected));
  }
}

TEST_CASE("encode_shatter refuses exact representations a reader could not rebuild", "[shatter_file]") {
  // Defects the layout cannot even express (the reader derives these fields), or
  // caches that would not come back as they are: the encoder's precondition.
  const MeshTree& base = small_plane_tree();
  const std::size_t k = deep_node(base);
  const std::size_t three = std::find_if(base.nodes[k].solid->defs.begin(), base.nodes[k].solid->defs.end(),
                                         [](const PointDef& d) { return d.kind == PointKind::three_planes; }) -
                            base.nodes[k].solid->defs.begin();
  const auto refused = [&](auto&& change, const std::string& expected) {
    MeshTree tree = base;
    change(tree);
    INFO("expected: " << expected);
    CHECK_THROWS_WITH(encode_shatter(tree), Catch::Contains(expected));
  };
  refused([&](MeshTree& t) { t.nodes[k].solid->approx[three].x.value += 1; },
          "the solid of node " + std::to_string(k) + " vertex " + std::to_string(three) + " (three_planes): approx is not approximate()");
  refused([&](MeshTree& t) { t.nodes[k].solid->approx[three].w.error = t.nodes[k].solid->approx[three].w.error * 2 + 1; },
          "approx is not approximate() of its definition (a stale cache)");
  refused([&](MeshTree& t) { t.nodes[k].solid->approx.pop_back(); }, "approx entries for");
  refused([](MeshTree& t) { t.geometry.plane_approx[2].d.value = -t.geometry.plane_approx[2].d.value - 1; },
          "geometry.plane_approx[2] is not approximate_input_plane of input plane 2 (a stale cache)");
  refused([](MeshTree& t) { t.geometry.plane_approx.pop_back(); }, "plane_approx entries for");
  refused([](MeshTree& t) { t.cut_planes.pop_back(); }, "cut_planes has");
  refused([&](MeshTree& t) { t.nodes[k].solid->faces[1].first_loop += 1; }, "face 1 starts at loop");
  refused([&](MeshTree& t) { t.nodes[k].solid->loops[1].first_corner -= 1; }, "loop 1 starts at corner");
  refused([&](MeshTree& t) { t.nodes[k].solid->defs[three].a = 4; }, "(three_planes) has a = 4, a field its kind does not use");
  refused(
      [&](MeshTree& t) {
        t.nodes[k].solid->corners[0].line.p = no_index;
        t.nodes[k].solid->corners[0].line.q = 1;
      },
      "corner 0 has segment (4294967295, 1), not two input points p < q");
  refused(
      [&](MeshTree& t) {
        for (PointDef& d : t.nodes[k].solid->defs) {
          if (d.kind == PointKind::three_planes) {
            d = PointDef::segment_plane(0, 1, d.planes[0]);
            d.planes[2] = PlaneRef::input(1);
            break;
          }
        }
      },
      "(segment_plane) has plane 2 = 0x00000001, a field its kind does not use");

  // A tree without input points carries nothing of the exact representation.
  MeshTree fast = two_leaf_tree();
  fast.nodes[1].convex = true;
  fast.nodes[1].hull = Mesh{};
  CHECK_THROWS_WITH(encode_shatter(fast), Catch::Contains("node 1 is marked convex, but the tree has no exact representation"));
  fast = two_leaf_tree();
  fast.nodes[2].solid = base.nodes[0].solid;
  CHECK_THROWS_WITH(encode_shatter(fast), Catch::Contains("node 2 has a solid, but the tree has no geometry"));
  fast = two_leaf_tree();
  fast.cut_planes.resize(2);
  CHECK_THROWS_WITH(encode_shatter(fast), Catch::Contains("cut_planes has 2 planes for 3 nodes"));
  fast = two_leaf_tree();
  fast.cut_planes.resize(4);  // a cell plane past the nodes' (voronoi.hpp) must have a normal
  CHECK_THROWS_WITH(encode_shatter(fast), Catch::Contains("cell plane 3 has a NaN or infinite coefficient or a zero normal"));
  fast = two_leaf_tree();
  fast.geometry.planes.push_back({0, 0, 0});
  fast.geometry.plane_approx.resize(1);
  CHECK_THROWS_WITH(encode_shatter(fast), Catch::Contains("geometry has 1 input planes but no input points"));
  check_refused(reference_file(fast), "GEOM section, byte");
  check_refused(reference_file(fast), "geometry has 1 input planes but no input points");
}

TEST_CASE("sections longer than a writer's piece are written byte for byte as documented", "[shatter_file]") {
  // The writer makes a section in pieces of a mebibyte, cut between records,
  // and sums the header's length and CRC-32 over them. A fine torus cut once
  // has a GEOM section of several pieces (a record per point) and SOLD and MESH
  // sections of a few records each larger than a piece.
  TreeRecipe recipe;
  recipe.fragments = 2;
  const MeshTree tree = build_mesh_tree(test::torus(1.0, 0.35, 300, 300), recipe, {.threads = 1});
  REQUIRE(24 * tree.geometry.points.size() > 2 * (std::size_t{1} << 20));
  const std::string bytes = encode_shatter(tree);
  CHECK(byte_difference(bytes, reference_file_v3(tree)) == "equal");
  std::string pieces;
  write_shatter(tree, [&](std::string_view piece) { pieces.append(piece); });
  CHECK(pieces == bytes);
  CHECK(tree_difference(decode_within_budget(bytes), tree).empty());

  // Streamed (a sink that can go back): every section's header is written
  // ahead and replaced once, and no piece handed on is much over a mebibyte,
  // though SOLD and MESH each hold a record larger than that.
  std::string streamed;
  std::size_t largest_append = 0, overwrites = 0;
  write_shatter(tree, RewritableSink{[&](std::string_view piece) {
                                       largest_append = std::max(largest_append, piece.size());
                                       streamed.append(piece);
                                     },
                                     [&](std::uint64_t offset, std::string_view piece) {
                                       ++overwrites;
                                       REQUIRE(offset + piece.size() <= streamed.size());
                                       streamed.replace(static_cast<std::size_t>(offset), piece.size(), piece);
                                     }});
  CHECK(streamed == bytes);
  CHECK(largest_append < bytes.size() / 2);
  CHECK(overwrites == 9);  // vers, OPTS, NODE, GEOM, SOLD, MESH, HULL, BOND and END
  // write_shatter_file streams to its file the same bytes.
  const std::filesystem::path directory = std::filesystem::temp_directory_path() / ("shatter-stream-test-" + std::to_string(::getpid()));
  std::filesystem::remove_all(directory);
  std::filesystem::create_directories(directory);
  write_shatter_file(directory / "torus.shatter", tree);
  std::ifstream in(directory / "torus.shatter", std::ios::binary);
  CHECK(std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()) == bytes);
  std::filesystem::remove_all(directory);
}

TEST_CASE("solids without their approximations write the same bytes", "[shatter_file]") {
  // A lean build (BuildRunOptions::lean) drops every Solid::approx; the writer
  // computes them as the reader will. Any mix of solids with and without them
  // writes the full tree's bytes, which read back to the full tree.
  const MeshTree& base = small_plane_tree();
  REQUIRE(base.nodes.size() >= 3);
  const std::string bytes = encode_shatter(base);
  const auto keep_none = [](std::size_t) { return false; };
  const auto keep_leaves = [&](std::size_t k) { return base.nodes[k].is_leaf(); };
  const auto keep_odd = [](std::size_t k) { return k % 2 == 1; };
  for (const std::function<bool(std::size_t)>& keep : {std::function<bool(std::size_t)>(keep_none), std::function<bool(std::size_t)>(keep_leaves), std::function<bool(std::size_t)>(keep_odd)}) {
    MeshTree tree = base;
    std::size_t dropped = 0;
    for (std::size_t k = 0; k < tree.nodes.size(); ++k) {
      REQUIRE(!tree.nodes[k].solid->approx.empty());
      if (keep(k)) continue;
      tree.nodes[k].solid->approx.clear();
      ++dropped;
    }
    REQUIRE(dropped > 0);
    CHECK(validate_tree(tree).summary() == "valid");
    CHECK(encode_shatter(tree) == bytes);
    CHECK(tree_difference(decode_within_budget(bytes), base).empty());
  }
  // Without a cache to compare, a definition is still approximated: a
  // degenerate one is refused as the reader would refuse it.
  MeshTree degenerate = base;
  const std::size_t k = deep_node(base);
  Solid& solid = *degenerate.nodes[k].solid;
  solid.approx.clear();
  const auto three = std::find_if(solid.defs.begin(), solid.defs.end(),
                                  [](const PointDef& d) { return d.kind == PointKind::three_planes; });
  REQUIRE(three != solid.defs.end());
  three->planes[1] = three->planes[0];
  CHECK_THROWS_WITH(encode_shatter(degenerate), Catch::Contains("degenerate point definition"));
}

TEST_CASE("a leaf's plane is unused but kept bit for bit", "[shatter_file][compatibility]") {
  // The cut planes have one home, MeshTree::cut_planes, filled from the NODE
  // records. Readers before it kept a leaf's NODE plane in the node and a zero
  // in cut_planes; what they read, the one copy now holds as the file has it,
  // so such a file still re-encodes to its own bytes.
  MeshTree tree = small_plane_tree();
  const NodeIndex leaf = tree.leaf_nodes.back();
  tree.cut_planes[leaf] = {{special_doubles[0], 2, -0.0}, special_doubles[3]};
  const std::string bytes = encode_shatter(tree);
  const MeshTree decoded = decode_within_budget(bytes);
  CHECK(tree_difference(tree, decoded).empty());
  CHECK(encode_shatter(decoded) == bytes);
}

// ---------------------------------------------------------------------------
// Version 3: what it leaves out, and what its reader refuses

namespace {

/// The payload of section `tag` of a file (the first one).
std::string payload_of(std::string_view file, std::string_view tag) {
  for (std::size_t at = 12; at + 16 <= file.size();) {
    std::uint64_t length = 0;
    for (int k = 7; k >= 0; --k) length = (length << 8) | static_cast<unsigned char>(file[at + 4 + static_cast<std::size_t>(k)]);
    if (file.substr(at, 4) == tag) return std::string(file.substr(at + 16, static_cast<std::size_t>(length)));
    at += 16 + static_cast<std::size_t>(length);
  }
  throw std::logic_error("no such section");
}

std::uint64_t read_vu(std::string_view bytes, std::size_t& at) {
  std::uint64_t value = 0;
  for (int shift = 0;; shift += 7) {
    const auto byte = static_cast<unsigned char>(bytes.at(at++));
    value |= std::uint64_t{byte & 0x7Fu} << shift;
    if ((byte & 0x80u) == 0) return value;
  }
}

/// Where the corners of the version 3 SOLD record at `at` start; `at` moves to the
/// record's end, and `corners` gets their count.
std::size_t corners_of_record(std::string_view sold, std::size_t& at, std::uint64_t& corners) {
  ++at;  // flags
  const std::uint64_t vertices = read_vu(sold, at), faces = read_vu(sold, at), loops = read_vu(sold, at);
  corners = read_vu(sold, at);
  for (std::uint64_t v = 0; v < vertices; ++v) {
    const auto kind = static_cast<unsigned char>(sold.at(at++));
    for (int field = 0; field < (kind == 0 ? 1 : 3); ++field) read_vu(sold, at);
  }
  for (std::uint64_t f = 0; f < faces; ++f) {
    read_vu(sold, at);  // plane
    ++at;               // flags
    for (int field = 0; field < 3; ++field) read_vu(sold, at);
  }
  for (std::uint64_t l = 0; l < loops; ++l) read_vu(sold, at);
  const std::size_t first = at;
  for (std::uint64_t c = 0; c < corners; ++c) {
    const std::uint64_t mode = read_vu(sold, at) & 3;
    if (mode != 0) read_vu(sold, at);
    if (mode == 2) {
      read_vu(sold, at);
      read_vu(sold, at);
    }
  }
  return first;
}

/// The version 3 file of `tree` with one payload replaced.
std::string v3_with(const MeshTree& tree, std::string_view tag, const std::string& payload) {
  auto parts = payloads_v3(tree);
  for (auto& [t, p] : parts) {
    if (t == tag) p = payload;
  }
  return file_of_parts(parts, 3);
}

}  // namespace

TEST_CASE("version 3 derives what follows from the tree, and stores what does not", "[shatter_file][v3]") {
  const MeshTree& built = small_plane_tree();
  const std::string bytes = encode_shatter(built);
  // A built tree's seeds, masses, leaf planes and bond normals all follow.
  CHECK(payload_of(bytes, "NODE")[4] == 0);
  CHECK(payload_of(bytes, "BOND")[8] == 0);
  // Changed by hand, each is stored and comes back bit for bit.
  const auto changed = [&](auto&& change) {
    MeshTree tree = built;
    change(tree);
    check_round_trip(tree);
    return encode_shatter(tree);
  };
  CHECK(payload_of(changed([](MeshTree& t) { t.nodes[1].seed ^= 1; }), "NODE")[4] == 1);
  CHECK(payload_of(changed([](MeshTree& t) { t.nodes[2].mass.volume = std::nextafter(t.nodes[2].mass.volume, 1.0); }), "NODE")[4] == 2);
  CHECK(payload_of(changed([](MeshTree& t) { t.cut_planes[t.leaf_nodes[0]].offset = 0.25; }), "NODE")[4] == 4);
  CHECK(payload_of(changed([](MeshTree& t) { t.bonds[0].normal = -t.bonds[0].normal; }), "BOND")[8] == 1);
  // A centroid off its plane keeps its three coordinates; a moved position its own.
  CHECK(changed([](MeshTree& t) { t.bonds.back().centroid.x += 1; }).size() == bytes.size() + 8);
  CHECK(changed([](MeshTree& t) {
          t.nodes[3].mesh->positions[1].y = std::nextafter(t.nodes[3].mesh->positions[1].y, 2.0);
          t.nodes[3].mass = mass_properties(t.nodes[3].mesh);  // still the mesh's own
        }).size() == bytes.size() + 24);
}

TEST_CASE("version 3 is a fraction of version 2 for built trees", "[shatter_file][v3][build]") {
  // The gain grows with depth: plane references, positions and cut nodes are
  // relative or derived, and masses, seeds and normals follow.
  for (const std::uint32_t fragments : {16u, 256u}) {
    TreeRecipe recipe;
    recipe.fragments = fragments;
    const MeshTree tree = build_mesh_tree(test::box({0, 0, 0}, {1, 1, 1}), recipe);
    const std::size_t v2 = reference_file(tree).size(), v3 = encode_shatter(tree).size();
    INFO(fragments << " fragments: version 2 " << v2 << " bytes, version 3 " << v3);
    CHECK(v3 * 3 < v2);
    check_round_trip(tree);
  }
}

TEST_CASE("version 3's relative codes and child counts are checked", "[shatter_file][v3][hostile]") {
  const MeshTree& plane_tree = small_plane_tree();
  const MeshTree hand = two_leaf_tree();
  SECTION("child counts that do not make one tree of the node count") {
    // NODE with every value stored: flags 7, then per node its code, plane, seed and mass.
    const auto nodes = [](std::initializer_list<std::uint64_t> child_counts) {
      Bytes out;
      out.u32(static_cast<std::uint32_t>(child_counts.size())).u8(7);
      for (const std::uint64_t count : child_counts) {
        out.vu(count << 1).vec3({1, 0, 0}).f64(0).u64(5).f64(1).vec3({0, 0, 0});
        for (int e = 0; e < 9; ++e) out.f64(0);
      }
      return out.data;
    };
    check_refused(v3_with(hand, "NODE", nodes({3, 0, 0})), "claims 3 children, but only 2 nodes follow");
    check_refused(v3_with(hand, "NODE", nodes({1, 0, 0})), "the child counts before it describe a whole tree of 2 nodes");
    check_refused(v3_with(hand, "NODE", nodes({2, 1, 0})), "node 0 lacks 1 of its children");
    std::string flags = payload_of(encode_shatter(hand), "NODE");
    flags[4] = 8;
    check_refused(v3_with(hand, "NODE", flags), "unknown node flag bits 0x08");
  }
  SECTION("varints wider than their field") {
    std::string nodes = payload_of(encode_shatter(hand), "NODE");
    nodes.insert(5, std::string(10, '\xFF'));  // before the root's child count: 70 bits
    check_refused(v3_with(hand, "NODE", nodes), "child count does not fit in 64 bits");
    // A mesh's vertex count of 2^32.
    std::string meshes = payload_of(encode_shatter(hand), "MESH");
    meshes.replace(4, 1, Bytes{}.vu(std::uint64_t{1} << 32).data.substr(0, 5) + meshes.substr(5, 0));
    check_refused(v3_with(hand, "MESH", meshes), "vertex count does not fit in 32 bits");
  }
  SECTION("positions, surfaces and bonds that name nothing") {
    // two_leaf_tree has no solids: a position may only be stored.
    Bytes root;
    root.vu(1).vu(0).u8(0).vu(1);  // one vertex, no triangle, from source 0
    std::string meshes = Bytes{}.u32(3).data + root.data + Bytes{}.vu(0).vu(0).u8(0).vu(0).data + Bytes{}.vu(0).vu(0).u8(0).vu(0).data;
    check_refused(v3_with(hand, "MESH", meshes), "vertex 0 takes the position of source vertex 0, of 0");
    Bytes runs;  // one triangle over three stored positions, its surface run two long
    runs.vu(3).vu(1).u8(0);
    for (int v = 0; v < 3; ++v) runs.vu(0).vec3({double(v), double(v == 1), 0});
    runs.u8(0).u8(1).u8(2).vu(1).vu(0).vu(2);
    meshes = Bytes{}.u32(3).data + runs.data + Bytes{}.vu(0).vu(0).u8(0).vu(0).data + Bytes{}.vu(0).vu(0).u8(0).vu(0).data;
    check_refused(v3_with(hand, "MESH", meshes), "surface run 0 of 2 triangles, with 1 left");
    Bytes bonds;
    bonds.u64(1).u8(0).vu(0).vu(std::uint64_t{1} << 2).f64(1).f64(0.5).f64(0.5);  // leaves 0 and 2 of 2
    check_refused(v3_with(hand, "BOND", bonds.data), "bond 0 joins leaves 0 and 2, of 2");
  }
  SECTION("planes above the root, unknown corner lines, lines across no edge") {
    const std::string sold = payload_of(encode_shatter(plane_tree), "SOLD");
    std::size_t at = 4 + 1;
    for (int count = 0; count < 4; ++count) read_vu(sold, at);
    // The root's first vertex made the meet of three planes, one a cut plane a level up.
    std::size_t after = at + 1;
    for (int field = 0; field < (sold[at] == 0 ? 1 : 3); ++field) read_vu(sold, after);
    const std::string above_root = sold.substr(0, at) + Bytes{}.u8(2).vu(2).vu(1).vu(3).data + sold.substr(after);
    check_refused(v3_with(plane_tree, "SOLD", above_root), "names the cut plane of the node 1 levels up, but the node has depth 0");

    // Node 1's first corner whose line is the plane across its edge (a cap's edge).
    std::size_t record = 4;
    std::uint64_t corner_count = 0;
    corners_of_record(sold, record, corner_count);  // the root's
    std::size_t corner = corners_of_record(sold, record, corner_count), corner_end = corner;
    std::uint64_t code = read_vu(sold, corner_end);
    for (std::uint64_t c = 1; c < corner_count && (code & 3) != 0; ++c) {
      corner = corner_end;
      if ((code & 3) != 0) read_vu(sold, corner);
      if ((code & 3) == 2) {
        read_vu(sold, corner);
        read_vu(sold, corner);
      }
      corner_end = corner;
      code = read_vu(sold, corner_end);
    }
    REQUIRE((code & 3) == 0);
    const auto with_corner = [&](std::uint64_t new_code) { return sold.substr(0, corner) + Bytes{}.vu(new_code).data + sold.substr(corner_end); };
    check_refused(v3_with(plane_tree, "SOLD", with_corner(code | 3)), "has line mode 3 (unknown)");
    // The same vertex as the next corner: no face runs the edge back.
    std::size_t next = corner_end;
    const std::uint64_t next_code = read_vu(sold, next);
    check_refused(v3_with(plane_tree, "SOLD", with_corner(next_code & ~std::uint64_t{3})), "SOLD section");
  }
}

// The sections' records are encoded in runs on the caller's threads (the
// arena's) and joined in order: the file must be the one-thread file byte for
// byte, streamed (encode_shatter) or held (write_shatter to a plain sink), for
// trees of more nodes and bonds than a run holds, lean or not, plane and cell.
TEST_CASE("the file encoded on 2 and 4 threads is the one-thread file byte for byte and its summary the same", "[file][property][threads]") {
  struct Case {
    std::string name;
    MeshTree tree;
  };
  std::vector<Case> cases;
  const auto plane_tree = [&](const std::string& name, const Mesh& mesh, Strategy strategy, std::uint32_t fragments,
                              std::uint64_t seed, bool lean) {
    TreeRecipe recipe;
    recipe.fragments = fragments;
    recipe.seed = seed;
    recipe.strategy = strategy;
    cases.push_back({name + " " + std::string(strategy_name(strategy)) + " -> " + std::to_string(fragments) + " seed " +
                         std::to_string(seed) + (lean ? " lean" : ""),
                     build_mesh_tree(mesh, recipe, {.threads = 1, .lean = lean})});
  };
  plane_tree("cube", test::unit_cube(), Strategy::thesis, 1100, 3, true);
  plane_tree("cube", test::unit_cube(), Strategy::thesis, 700, 4, false);
  plane_tree("torus", test::torus(2, 0.6, 24, 16), Strategy::axis, 700, 5, true);
  plane_tree("hollow egg", test::hollow_egg(), Strategy::balanced, 600, 6, true);
  plane_tree("elephant.off", read_mesh(test::mesh_dir() / "elephant.off"), Strategy::thesis, 600, 7, true);
  for (const bool lean : {false, true}) {
    const Mesh cube = test::unit_cube();
    TreeRecipe recipe;
    recipe.strategy = Strategy::voronoi;
    recipe.seed = 8;
    recipe.fragments = 1000;
    cases.push_back({std::string("cube voronoi 1000 sites") + (lean ? " lean" : ""),
                     build_voronoi_tree(cube, uniform_sites(cube, recipe.fragments, recipe.seed), recipe,
                                        {.threads = 1, .lean = lean})});
  }
  for (const Case& c : cases) {
    INFO(c.name << ": " << c.tree.nodes.size() << " nodes, " << c.tree.bond_count() << " bonds");
    REQUIRE(c.tree.nodes.size() > 1024);  // more than two runs of records
    const auto encoded = [&](int threads) {
      tbb::task_arena arena(threads);
      std::pair<std::string, std::string> bytes;
      arena.execute([&] {
        bytes.first = encode_shatter(c.tree);
        write_shatter(c.tree, ByteSink([&](std::string_view piece) { bytes.second.append(piece); }));
      });
      return bytes;
    };
    const auto stats_of = [](const MeshTree& tree, int threads) {
      tbb::task_arena arena(threads);
      return arena.execute([&] { return tree_stats(tree); });
    };
    const TreeStats stats_one = stats_of(c.tree, 1);
    // Packed leaves are counted from their bytes, not unpacked: the same sums.
    MeshTree packed = c.tree;
    pack_leaves(packed);
    REQUIRE(std::all_of(packed.leaf_nodes.begin(), packed.leaf_nodes.end(), [&](NodeIndex k) { return packed.is_packed(k); }));
    const TreeStats stats_packed = stats_of(packed, 2);
    CHECK(stats_packed.leaf_triangles == stats_one.leaf_triangles);
    CHECK(stats_packed.leaf_vertices == stats_one.leaf_vertices);
    CHECK(stats_packed.leaf_cap_triangles == stats_one.leaf_cap_triangles);
    const auto one = encoded(1);
    REQUIRE(one.first == one.second);
    CHECK(decode_shatter(one.first).nodes.size() == c.tree.nodes.size());
    for (const int threads : {2, 4}) {
      INFO(threads << " threads");
      const auto several = encoded(threads);
      CHECK(several.first == one.first);
      CHECK(several.second == one.first);
      // The summary fracture prints, counted on as many threads.
      const TreeStats stats = stats_of(c.tree, threads);
      CHECK(stats.leaf_triangles == stats_one.leaf_triangles);
      CHECK(stats.leaf_vertices == stats_one.leaf_vertices);
      CHECK(stats.leaf_cap_triangles == stats_one.leaf_cap_triangles);
      CHECK(std::bit_cast<std::uint64_t>(stats.total_leaf_volume) == std::bit_cast<std::uint64_t>(stats_one.total_leaf_volume));
    }
  }
  CHECK(cases.size() == 7);
}

namespace {

// Where one MESH record starts in its payload, its channel byte, and its first
// position code that names a source (npos when every position is stored).
// Meshes without attribute channels only (built trees' meshes).
struct MeshRecordAt {
  std::size_t start = 0, channels = 0, code = std::string::npos, code_end = 0, triangles = 0;
  std::uint64_t vertex = 0;
};

std::vector<MeshRecordAt> mesh_records(std::string_view payload) {
  std::vector<MeshRecordAt> records;
  std::size_t at = 4;  // after the mesh count
  while (at < payload.size()) {
    MeshRecordAt record;
    record.start = at;
    const std::uint64_t vertices = read_vu(payload, at), triangles = read_vu(payload, at);
    record.channels = at;
    REQUIRE(payload.at(at++) == 0);
    for (std::uint64_t v = 0; v < vertices; ++v) {
      const std::size_t code_at = at;
      if (read_vu(payload, at) == 0) {
        at += 24;  // a stored position
      } else if (record.code == std::string::npos) {
        record.code = code_at, record.code_end = at, record.vertex = v;
      }
    }
    record.triangles = at;
    at += 3 * (vertices <= 0x100 ? 1 : vertices <= 0x10000 ? 2 : 4) * triangles;
    const std::uint64_t runs = read_vu(payload, at);
    for (std::uint64_t r = 0; r < 2 * runs; ++r) read_vu(payload, at);
    records.push_back(record);
  }
  return records;
}

}  // namespace

// decode_shatter reads SOLD beside MESH, HULL and BOND (MESH's sources checked
// against the solids' vertex counts after both): what it refuses, and the
// message, must be what reading them in turn gives. Every node's first coded
// position is made to name the source one past its solid's last vertex, alone
// and with a later failure in MESH, in HULL, or in SOLD.
TEST_CASE("SOLD, MESH, HULL and BOND read side by side refuse as reading them in turn does", "[shatter_file][v3][hostile]") {
  TreeRecipe recipe;
  recipe.fragments = 16;
  const MeshTree box = build_mesh_tree(test::box({0, 0, 0}, {1, 2, 3}), recipe, {.threads = 1});
  std::size_t cases = 0;
  for (const MeshTree* tree : {&small_plane_tree(), &box}) {
    const std::vector<std::pair<std::string, std::string>> parts = payloads_v3(*tree);
    const auto file_with = [&](std::initializer_list<std::pair<std::string_view, std::string>> changes) {
      auto changed = parts;
      for (auto& [tag, payload] : changed) {
        for (const auto& [changed_tag, changed_payload] : changes) {
          if (tag == changed_tag) payload = changed_payload;
        }
      }
      return file_of_parts(changed, 3);
    };
    const auto payload = [&](std::string_view tag) {
      for (const auto& [t, p] : parts) {
        if (t == tag) return p;
      }
      FAIL("no " << tag << " section");
      return std::string();
    };
    const std::string meshes = payload("MESH"), hulls = payload("HULL"), solids = payload("SOLD");
    const std::vector<MeshRecordAt> records = mesh_records(meshes);
    REQUIRE(records.size() == tree->nodes.size());
    for (std::size_t k = 0; k < records.size(); ++k) {
      const MeshRecordAt& record = records[k];
      if (record.code == std::string::npos) continue;
      const std::uint64_t n = tree->nodes[k].solid->defs.size(), v = record.vertex;
      std::string bad = meshes;
      bad.replace(record.code, record.code_end - record.code, Bytes{}.vu(1 + 2 * (n - v)).data);
      const std::string expected = "vertex " + std::to_string(v) + " takes the position of source vertex " +
                                   std::to_string(n) + ", of " + std::to_string(n);
      const auto check = [&](const std::string& bytes, const std::string& message, const char* what) {
        INFO(what << ", node " << k);
        check_refused(bytes, message);
        if (message == expected) check_refused(bytes, "node " + std::to_string(k));
        ++cases;
      };
      check(file_with({{"MESH", bad}}), expected, "alone");
      check(file_with({{"MESH", bad}, {"HULL", hulls.substr(0, hulls.size() - 1)}}), expected, "HULL cut short");
      if (k + 1 < records.size()) {
        std::string later = bad;
        later[records[k + 1].channels + (later.size() - meshes.size())] = '\x80';
        check(file_with({{"MESH", later}}), expected, "a later record's unknown channel bits");
      }
      // Cut short inside the record's triangles, after its codes: reading in
      // turn meets the source first.
      const std::size_t triangles = record.triangles + (bad.size() - meshes.size());
      check(file_with({{"MESH", bad.substr(0, triangles + 1)}}), expected, "MESH cut short in the triangles");
      std::string bad_solids = solids;
      bad_solids[4] = '\x80';  // the root's solid flags
      check(file_with({{"MESH", bad}, {"SOLD", bad_solids}}), "unknown solid flag bits 0x80", "SOLD's flags");
    }
  }
  CHECK(cases > 100);
}
