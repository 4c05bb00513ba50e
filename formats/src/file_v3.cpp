// Version 3 of the .shatter file (layout in file.hpp): the tree's structure as
// child counts in preorder, the exact solids with their planes named relative
// to the node, varints for every index, and no value that follows from what is
// stored: seeds, masses, the meshes' rounded positions, the hulls' positions,
// the bonds' cut nodes and normals and one coordinate of their centroids are
// left out wherever they equal their derivation bit for bit. The encoder checks
// each equality and stores the value where one fails, so every tree that
// validates round-trips exactly, hand-made ones included.

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_pipeline.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cfenv>
#include <cstdint>
#include <exception>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "file_layout.hpp"
#include "shatter/kernel/implicit.hpp"
#include "shatter/kernel/mass.hpp"
#include "shatter/kernel/solid.hpp"
#include "shatter/meshtree/packed_node.hpp"
#include "shatter/meshtree/recipe.hpp"
#include "shatter/meshtree/tree.hpp"

namespace shatter::file_layout {

namespace {

// NODE flags: which derivable values are stored anyway.
constexpr std::uint8_t seeds_stored_bit = 1;
constexpr std::uint8_t masses_stored_bit = 2;
constexpr std::uint8_t leaf_planes_stored_bit = 4;
constexpr std::uint8_t known_node_flags = seeds_stored_bit | masses_stored_bit | leaf_planes_stored_bit;
// BOND flags.
constexpr std::uint8_t bond_normals_stored_bit = 1;
// A bond centroid's axis code: 0-2 the coordinate solved from the cut plane, 3 none.
constexpr std::uint64_t centroid_stored = 3;
// A corner's line, in the low two bits of its code.
constexpr std::uint64_t line_across = 0;   // the plane of the face across the edge, no segment
constexpr std::uint64_t line_stored = 1;   // a plane code follows, no segment
constexpr std::uint64_t line_segment = 2;  // a plane code and the segment's points follow
// A position code: 0 stored, else 1 + zigzag(source - vertex) (PositionCoder, packed_node.hpp).
constexpr std::uint64_t position_stored = PositionCoder::stored;

std::int64_t unzigzag(std::uint64_t code) { return static_cast<std::int64_t>(code >> 1) ^ -static_cast<std::int64_t>(code & 1); }

std::uint64_t bits(double value) { return std::bit_cast<std::uint64_t>(value); }
bool same_bits(Vec3 a, Vec3 b) { return bits(a.x) == bits(b.x) && bits(a.y) == bits(b.y) && bits(a.z) == bits(b.z); }
bool same_bits(const MassProperties& a, const MassProperties& b) {
  if (bits(a.volume) != bits(b.volume) || !same_bits(a.centroid, b.centroid)) return false;
  for (std::size_t k = 0; k < a.inertia.size(); ++k) {
    if (bits(a.inertia[k]) != bits(b.inertia[k])) return false;
  }
  return true;
}
bool all_zero_bits(const Plane& plane) {
  return bits(plane.normal.x) == 0 && bits(plane.normal.y) == 0 && bits(plane.normal.z) == 0 && bits(plane.offset) == 0;
}
/// Floating-point exceptions held for its lifetime, and the caller's
/// environment (flags and traps) restored after: deriving a value is an attempt
/// whose result is compared bit for bit or was so compared by the writer, and a
/// hand-made tree's infinities and NaNs must neither trap there nor leave flags
/// behind.
class HeldFloatingPointExceptions {
 public:
  HeldFloatingPointExceptions() { std::feholdexcept(&saved_); }
  ~HeldFloatingPointExceptions() { std::fesetenv(&saved_); }
  HeldFloatingPointExceptions(const HeldFloatingPointExceptions&) = delete;
  HeldFloatingPointExceptions& operator=(const HeldFloatingPointExceptions&) = delete;

 private:
  std::fenv_t saved_;
};

// --- records encoded in parallel ------------------------------------------------
// A section's records (a node's, a bond's) are each a function of the tree and
// of the record's place alone, so runs of them can be encoded on any thread and
// joined in order: the same bytes as one thread writing them one after the
// other. The joining streams (ByteWriter's flush) as the runs finish, a few at
// a time in flight, so a section is never held whole.

/// Records per run: small enough for a few in flight to stay some megabytes
/// (a node of a large tree writes about a kilobyte), large enough that a run's
/// set-up (its ancestor path, its buffers) does not show.
constexpr std::size_t records_per_run = 512;

/// Whether the caller's task arena has more than one thread to lend.
bool on_several_threads() { return tbb::this_task_arena::max_concurrency() > 1; }

/// `run` shortened so that `count` records make about four runs per thread of
/// the caller's arena, but not below a 32nd of `run` (a run's set-up still does
/// not show). A tree of 256 fragments has 511 nodes: as one run of 512 its
/// records were encoded on one thread while the other waited, a sixth of
/// `fracture blobby x4 -> 256` on 2 threads.
std::size_t shared_run(std::size_t count, std::size_t run) {
  const auto runs = 4 * static_cast<std::size_t>(tbb::this_task_arena::max_concurrency());
  return std::clamp((count + runs - 1) / runs, std::max<std::size_t>(1, run / 32), run);
}

/// Writes records [0, count) to `out`: `encode(first, end, writer)` writes
/// records first..end-1 to `writer`. On one thread `out` is handed over whole;
/// on more, runs of at most `run` records (shared_run) are encoded in parallel
/// and joined in order.
/// Every run holds the floating-point exceptions on its own thread, as
/// write_version3_sections does on the caller's.
template <class Encode>
void encode_records(std::size_t count, std::size_t run, ByteWriter& out, const Encode& encode) {
  if (on_several_threads()) run = shared_run(count, run);
  if (!on_several_threads() || count <= run) {
    encode(std::size_t{0}, count, out);
    return;
  }
  std::size_t next = 0;
  const auto in_flight = static_cast<std::size_t>(4 * tbb::this_task_arena::max_concurrency());
  tbb::parallel_pipeline(
      in_flight,
      tbb::make_filter<void, std::pair<std::size_t, std::size_t>>(
          tbb::filter_mode::serial_in_order,
          [&](tbb::flow_control& control) -> std::pair<std::size_t, std::size_t> {
            if (next >= count) {
              control.stop();
              return {0, 0};
            }
            const std::size_t first = next;
            next = std::min(count, next + run);
            return {first, next};
          }) &
          tbb::make_filter<std::pair<std::size_t, std::size_t>, std::vector<std::string>>(
              tbb::filter_mode::parallel,
              [&](const std::pair<std::size_t, std::size_t>& records) {
                const HeldFloatingPointExceptions held;
                ByteWriter writer;
                encode(records.first, records.second, writer);
                return writer.take_pieces();
              }) &
          tbb::make_filter<std::vector<std::string>, void>(tbb::filter_mode::serial_in_order,
                                                           [&](const std::vector<std::string>& pieces) {
                                                             for (const std::string& piece : pieces) out.append_record(piece);
                                                           }));
}

/// Calls `visit(first, end)` on runs of [0, count) covering it, in parallel
/// when the caller's arena lends several threads, each run holding the
/// floating-point exceptions on its thread. For passes whose results are
/// joined by an order-free rule (or of flags).
template <class Visit>
void visit_runs(std::size_t count, std::size_t run, const Visit& visit) {
  if (on_several_threads()) run = shared_run(count, run);
  if (!on_several_threads() || count <= run) {
    visit(std::size_t{0}, count);
    return;
  }
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, run), [&](const tbb::blocked_range<std::size_t>& range) {
    const HeldFloatingPointExceptions held;
    visit(range.begin(), range.end());
  });
}

double coordinate(Vec3 v, int axis) { return axis == 0 ? v.x : axis == 1 ? v.y : v.z; }

/// The nodes from the root to the node being written or read (preorder visits a
/// node's ancestors first), so a plane or surface names an ancestor by how far
/// up it is.
class AncestorPath {
 public:
  /// The path to `node` found by its parents, as entering every node before it
  /// in preorder leaves it (a chunk of records can then start at any node).
  void start_at(NodeIndex node, const std::vector<MeshTreeNode>& nodes) {
    path_.assign(std::size_t{nodes[node].depth} + 1, 0);
    for (NodeIndex a = node; a != no_node; a = nodes[a].parent) path_[nodes[a].depth] = a;
  }
  void enter(NodeIndex node, std::uint32_t depth) {
    path_.resize(std::size_t{depth} + 1);
    path_[depth] = node;
  }
  std::uint32_t depth() const { return static_cast<std::uint32_t>(path_.size() - 1); }
  /// The ancestor `up` levels above; 1 <= up <= depth().
  NodeIndex above(std::uint64_t up) const { return path_[path_.size() - 1 - up]; }
  /// How far above the node `node` is, or 0 if it is not a strict ancestor.
  std::uint32_t distance_to(NodeIndex node, std::uint32_t node_depth) const {
    return node_depth < depth() && path_[node_depth] == node ? depth() - node_depth : 0;
  }

 private:
  std::vector<NodeIndex> path_;
};

// ---------------------------------------------------------------------------
// Encoding

/// A plane as the node whose solid uses it names it: 0 none, 2i + 1 input plane
/// i, 2d the cut plane of the ancestor d levels up (the validator has checked
/// that every cut plane a solid uses is a strict ancestor's).
/// A cell plane (index nodes.size() + c, voronoi.hpp) is 2(depth + 1 + c): past
/// every ancestor, where older readers refuse the code.
std::uint64_t plane_code(PlaneRef plane, const AncestorPath& path, const std::vector<MeshTreeNode>& nodes) {
  if (plane.bits == no_index) return 0;
  if (!plane.is_cut()) return 2 * std::uint64_t{plane.index()} + 1;
  if (plane.index() >= nodes.size()) return 2 * (std::uint64_t{path.depth()} + 1 + (plane.index() - nodes.size()));
  return 2 * std::uint64_t{path.distance_to(plane.index(), nodes[plane.index()].depth)};
}

/// A surface id as a node names it: 0 the input's surface, 1..depth the cap of
/// the ancestor that many levels up, depth + s any other id s.
std::uint64_t surface_code(SurfaceId surface, const AncestorPath& path, const std::vector<MeshTreeNode>& nodes) {
  if (surface == original_surface) return 0;
  const std::uint64_t cutter = surface - 1;  // the node whose cut made it, if any
  if (cutter < nodes.size()) {
    if (const std::uint32_t up = path.distance_to(static_cast<NodeIndex>(cutter), nodes[cutter].depth); up != 0) return up;
  }
  return std::uint64_t{path.depth()} + surface;
}


void write_mesh_after_positions(ByteWriter& out, const Mesh& mesh, std::size_t vertex_count, const AncestorPath& path,
                                const std::vector<MeshTreeNode>& nodes);

/// A mesh record, each position coded against `sources` (PositionCoder).
void write_mesh(ByteWriter& out, const Mesh& mesh, std::span<const Vec3> sources, const AncestorPath& path,
                const std::vector<MeshTreeNode>& nodes) {
  out.varint(mesh.positions.size());
  out.varint(mesh.triangles.size());
  out.u8(channel_flags(mesh));
  PositionCoder coder(sources);
  for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
    const std::uint64_t code = coder.code(v, mesh.positions[v]);
    out.varint(code);
    if (code == position_stored) out.vec3(mesh.positions[v]);
  }
  write_mesh_after_positions(out, mesh, mesh.positions.size(), path, nodes);
}

/// The same record from a packed mesh's codes (NodeShapes::mesh_codes), which
/// the packing made with the same coder against the same sources.
void write_mesh(ByteWriter& out, const NodeMeshCodes& coded, const AncestorPath& path,
                const std::vector<MeshTreeNode>& nodes) {
  out.varint(coded.codes.size());
  out.varint(coded.mesh.triangles.size());
  out.u8(channel_flags(coded.mesh));
  std::size_t next_stored = 0;
  for (const std::uint64_t code : coded.codes) {
    out.varint(code);
    if (code == position_stored) out.vec3(coded.stored[next_stored++]);
  }
  write_mesh_after_positions(out, coded.mesh, coded.codes.size(), path, nodes);
}

/// A mesh record's triangles, surfaces and corner channels.
void write_mesh_after_positions(ByteWriter& out, const Mesh& mesh, std::size_t vertex_count, const AncestorPath& path,
                                const std::vector<MeshTreeNode>& nodes) {
  const std::size_t width = vertex_count <= 0x100 ? 1 : vertex_count <= 0x10000 ? 2 : 4;
  for (const Triangle& triangle : mesh.triangles) {
    for (const VertexIndex vertex : triangle) {
      if (width == 1) out.u8(static_cast<std::uint8_t>(vertex));
      if (width == 2) {
        out.u8(static_cast<std::uint8_t>(vertex));
        out.u8(static_cast<std::uint8_t>(vertex >> 8));
      }
      if (width == 4) out.u32(vertex);
    }
  }
  // Surfaces in runs: a face's triangles are consecutive.
  std::vector<std::pair<std::uint64_t, std::uint64_t>> runs;
  for (const SurfaceId surface : mesh.surfaces) {
    const std::uint64_t code = surface_code(surface, path, nodes);
    if (!runs.empty() && runs.back().first == code) {
      ++runs.back().second;
    } else {
      runs.emplace_back(code, 1);
    }
  }
  out.varint(runs.size());
  for (const auto& [code, length] : runs) {
    out.varint(code);
    out.varint(length);
  }
  write_corner_channels(out, mesh);
}

void nodes_payload(const MeshTree& tree, bool masses_derived, ByteWriter& out) {
  const std::vector<MeshTreeNode>& nodes = tree.nodes;
  // Which derivations fail anywhere: an or over the nodes, in any order.
  std::atomic<std::uint8_t> any_flags{0};
  visit_runs(nodes.size(), records_per_run, [&](std::size_t first, std::size_t end) {
    std::uint8_t found = 0;
    NodeShapes shapes(tree);  // a mass compared unpacks its node's mesh alone
    for (std::size_t k = first; k < end; ++k) {
      const MeshTreeNode& node = nodes[k];
      const std::uint64_t derived_seed =
          k == 0 ? root_node_seed(tree.recipe.seed)
                 : child_node_seed(nodes[node.parent].seed, static_cast<std::size_t>(
                                                                std::find(nodes[node.parent].children.begin(), nodes[node.parent].children.end(), k) -
                                                                nodes[node.parent].children.begin()));
      if (node.seed != derived_seed) found |= seeds_stored_bit;
      if (!masses_derived && !same_bits(node.mass, mass_properties(shapes.mesh(static_cast<NodeIndex>(k))))) {
        found |= masses_stored_bit;
      }
      if (node.is_leaf() && !all_zero_bits(tree.cut_planes[k])) found |= leaf_planes_stored_bit;
    }
    any_flags.fetch_or(found, std::memory_order_relaxed);
  });
  const std::uint8_t flags = any_flags.load();
  out.count32(nodes.size());
  out.u8(flags);
  for (std::size_t k = 0; k < nodes.size(); ++k) {
    const MeshTreeNode& node = nodes[k];
    out.varint((std::uint64_t{node.children.size()} << 1) | (node.above_parent_plane ? 1 : 0));
    if (!node.is_leaf() || (flags & leaf_planes_stored_bit) != 0) {
      out.vec3(tree.cut_planes[k].normal);
      out.f64(tree.cut_planes[k].offset);
    }
    if ((flags & seeds_stored_bit) != 0) out.u64(node.seed);
    if ((flags & masses_stored_bit) != 0) {
      out.f64(node.mass.volume);
      out.vec3(node.mass.centroid);
      for (const double entry : node.mass.inertia) out.f64(entry);
    }
    out.end_record();
  }
}

/// Which face of a solid runs an edge: each vertex's out-edges (to, face) in
/// face order, by a counting sort on `from`, so an edge's lowest face is found
/// among its tail's few out-edges. The SOLD writer asks it whether a corner's
/// line is the face across its edge, the reader which face that is. Buffers
/// are kept from solid to solid.
class EdgeFaces {
 public:
  /// Indexes the edges of the loops of `solid`'s faces. Precondition: every
  /// corner's vertex is below `vertex_count` (the reader checks it first).
  void index(const Solid& solid, std::size_t vertex_count) {
    first_out_.assign(vertex_count + 1, 0);
    const auto for_each_edge = [&](const auto& visit) {
      for (std::uint32_t f = 0; f < solid.faces.size(); ++f) {
        const SolidFace& face = solid.faces[f];
        for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
          for (const CornerEdge& edge : loop_edges(solid.corners, solid.loops[l])) visit(edge, f);
        }
      }
    };
    for_each_edge([&](const CornerEdge& edge, std::uint32_t) { ++first_out_[edge.from + 1]; });
    for (std::size_t v = 0; v < vertex_count; ++v) first_out_[v + 1] += first_out_[v];
    out_edges_.resize(first_out_.back());
    for_each_edge([&](const CornerEdge& edge, std::uint32_t f) { out_edges_[first_out_[edge.from]++] = {edge.to, f}; });
    // The fill moved each start to the next vertex's: shift them back.
    for (std::size_t v = vertex_count; v > 0; --v) first_out_[v] = first_out_[v - 1];
    first_out_[0] = 0;
  }
  /// The lowest face whose loops run the edge from -> to, or none.
  std::optional<std::uint32_t> face_of_edge(VertexIndex from, VertexIndex to) const {
    for (std::uint32_t i = first_out_[from]; i < first_out_[from + 1]; ++i) {
      if (out_edges_[i].first == to) return out_edges_[i].second;
    }
    return std::nullopt;
  }

 private:
  std::vector<std::uint32_t> first_out_;
  std::vector<std::pair<VertexIndex, std::uint32_t>> out_edges_;
};

void solid_records(const MeshTree& tree, std::size_t first, std::size_t end, ByteWriter& out);

void solids_payload(const MeshTree& tree, ByteWriter& out) {
  const bool exact = tree.has_exact_representation();
  out.count32(exact ? tree.nodes.size() : 0);
  if (!exact) return;
  const std::vector<MeshTreeNode>& nodes = tree.nodes;
  encode_records(nodes.size(), records_per_run, out, [&](std::size_t first, std::size_t end, ByteWriter& writer) {
    solid_records(tree, first, end, writer);
  });
}

/// The SOLD records of nodes first..end-1.
void solid_records(const MeshTree& tree, std::size_t first, std::size_t end, ByteWriter& out) {
  const std::vector<MeshTreeNode>& nodes = tree.nodes;
  AncestorPath path;
  if (first < end) path.start_at(static_cast<NodeIndex>(first), nodes);
  EdgeFaces edge_faces;  // the face across a corner's edge
  NodeShapes shapes(tree);
  for (std::size_t k = first; k < end; ++k) {
    const MeshTreeNode& node = nodes[k];
    const Solid& solid = shapes.solid(static_cast<NodeIndex>(k));
    path.enter(static_cast<NodeIndex>(k), node.depth);
    const auto plane = [&](PlaneRef ref) { out.varint(plane_code(ref, path, nodes)); };
    out.u8(static_cast<std::uint8_t>((node.convex ? node_convex_bit : 0) | (solid.convex ? solid_convex_bit : 0)));
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
          plane(def.planes[0]);
          break;
        case PointKind::three_planes:
          for (const PlaneRef p : def.planes) plane(p);
          break;
      }
    }
    for (const SolidFace& face : solid.faces) {
      plane(face.plane);
      out.u8(static_cast<std::uint8_t>((face.reversed ? face_reversed_bit : 0) | (face.convex ? face_convex_bit : 0)));
      out.varint(surface_code(face.surface, path, nodes));
      out.varint(face.source);
      out.varint(face.loop_count);
    }
    for (const SolidLoop& loop : solid.loops) out.varint(loop.corner_count);

    edge_faces.index(solid, solid.defs.size());
    // The validator has checked that the loops cover the corners in order.
    for (const SolidLoop& loop : solid.loops) {
      for (const CornerEdge& edge : loop_edges(solid.corners, loop)) {
        std::uint64_t mode = edge.line.is_segment() ? line_segment : line_stored;
        if (!edge.line.is_segment()) {
          const std::optional<std::uint32_t> across = edge_faces.face_of_edge(edge.to, edge.from);
          if (across && solid.faces[*across].plane == edge.line.other) mode = line_across;
        }
        out.varint((std::uint64_t{edge.from} << 2) | mode);
        if (mode != line_across) plane(edge.line.other);
        if (mode == line_segment) {
          out.varint(edge.line.p);
          out.varint(edge.line.q);
        }
      }
    }
    out.end_record();
  }
}

/// Each mesh's positions coded against its solid's output positions (MESH) or
/// each hull's against its node's mesh (HULL).
void mesh_records(const MeshTree& tree, bool hulls, std::size_t first, std::size_t end, ByteWriter& out);

void meshes_payload(const MeshTree& tree, bool hulls, ByteWriter& out) {
  out.count32(tree.nodes.size());
  encode_records(tree.nodes.size(), records_per_run, out, [&](std::size_t first, std::size_t end, ByteWriter& writer) {
    mesh_records(tree, hulls, first, end, writer);
  });
}

/// The MESH (or HULL) records of nodes first..end-1.
void mesh_records(const MeshTree& tree, bool hulls, std::size_t first, std::size_t end, ByteWriter& out) {
  const std::vector<MeshTreeNode>& nodes = tree.nodes;
  const PlaneSet set = tree.plane_set();
  AncestorPath path;
  if (first < end) path.start_at(static_cast<NodeIndex>(first), nodes);
  std::vector<Vec3> solid_positions;
  NodeShapes shapes(tree);
  for (std::size_t k = first; k < end; ++k) {
    const MeshTreeNode& node = nodes[k];
    path.enter(static_cast<NodeIndex>(k), node.depth);
    if (hulls) {
      // A convex node's hull is empty: it looks up no position (a packed node stays packed).
      std::span<const Vec3> sources;
      if (!node.hull->positions.empty()) sources = shapes.mesh(static_cast<NodeIndex>(k)).positions;
      write_mesh(out, node.hull, sources, path, nodes);
      out.end_record();
      continue;
    }
    // A lean build packed its nodes' positions coded as this record codes them.
    if (const std::optional<NodeMeshCodes> coded = shapes.mesh_codes(static_cast<NodeIndex>(k))) {
      write_mesh(out, *coded, path, nodes);
      out.end_record();
      continue;
    }
    // Another packed node's positions need the solid's point definitions, not its faces.
    const NodePoints shape = shapes.mesh_and_points(static_cast<NodeIndex>(k));
    solid_positions.resize(shape.defs.size());
    // A lean tree keeps no approximations (the validator has checked that a
    // solid has all or none): they are computed here, as the reader will.
    const bool cached = !shape.approx.empty();
    for (std::size_t v = 0; v < solid_positions.size(); ++v) {
      const PointDef& def = shape.defs[v];
      solid_positions[v] = output_position(set, def, cached ? shape.approx[v] : approximate(set, def));
    }
    write_mesh(out, shape.mesh, solid_positions, path, nodes);
    out.end_record();
  }
}

/// The child of `ancestor` on the way down to `node` (a strict descendant).
NodeIndex child_toward(const std::vector<MeshTreeNode>& nodes, NodeIndex ancestor, NodeIndex node) {
  while (nodes[node].parent != ancestor) node = nodes[node].parent;
  return node;
}

/// The bond normal a built tree has: the cut plane's unit normal, pointing from
/// `first` into `second`.
/// A plane with a zero normal (a cell node's, voronoi.hpp) derives none.
bool zero_normal(const Plane& plane) { return plane.normal.x == 0 && plane.normal.y == 0 && plane.normal.z == 0; }

Vec3 derived_normal(const MeshTree& tree, const Bond& bond) {
  const NodeIndex side = child_toward(tree.nodes, bond.cut_node, tree.leaf_nodes[bond.first]);
  const Vec3 unit = normalized(tree.cut_planes[bond.cut_node].normal);
  return tree.nodes[side].above_parent_plane ? -unit : unit;
}

void bond_records(const MeshTree& tree, std::uint8_t flags, std::size_t first, std::size_t end, ByteWriter& out);

void bonds_payload(const MeshTree& tree, ByteWriter& out) {
  constexpr std::size_t bonds_per_run = 8 * records_per_run;  // a bond's record is some 20 bytes
  std::atomic<std::uint8_t> any_flags{0};
  visit_runs(tree.bond_count(), bonds_per_run, [&](std::size_t first, std::size_t end) {
    for (std::size_t i = first; i < end && any_flags.load(std::memory_order_relaxed) == 0; ++i) {
      const Bond bond = tree.bond(i);
      if (zero_normal(tree.cut_planes[bond.cut_node]) || !same_bits(bond.normal, derived_normal(tree, bond))) {
        any_flags.fetch_or(bond_normals_stored_bit, std::memory_order_relaxed);
      }
    }
  });
  const std::uint8_t flags = any_flags.load();
  out.u64(tree.bond_count());
  out.u8(flags);
  encode_records(tree.bond_count(), bonds_per_run, out, [&](std::size_t first, std::size_t end, ByteWriter& writer) {
    bond_records(tree, flags, first, end, writer);
  });
}

/// The BOND records of bonds first..end-1 (each first leaf coded against the
/// bond before it).
void bond_records(const MeshTree& tree, std::uint8_t flags, std::size_t first, std::size_t end, ByteWriter& out) {
  LeafIndex previous_first = first == 0 ? 0 : tree.bond(first - 1).first;
  for (std::size_t i = first; i < end; ++i) {
    const Bond bond = tree.bond(i);
    const Plane& plane = tree.cut_planes[bond.cut_node];
    // The largest normal component first: the projection the bonds were measured in.
    std::array<int, 3> axes = {0, 1, 2};
    std::stable_sort(axes.begin(), axes.end(),
                     [&](int a, int b) { return std::fabs(coordinate(plane.normal, a)) > std::fabs(coordinate(plane.normal, b)); });
    std::uint64_t axis_code = centroid_stored;
    for (const int axis : axes) {
      if (zero_normal(plane)) break;
      const Vec3 solved = point_on_plane_over(plane, axis, coordinate(bond.centroid, (axis + 1) % 3), coordinate(bond.centroid, (axis + 2) % 3));
      if (same_bits(solved, bond.centroid)) {
        axis_code = static_cast<std::uint64_t>(axis);
        break;
      }
    }
    out.varint(bond.first - previous_first);
    out.varint((std::uint64_t{bond.second - bond.first - 1} << 2) | axis_code);
    previous_first = bond.first;
    out.f64(bond.area);
    if (axis_code == centroid_stored) {
      out.vec3(bond.centroid);
    } else {
      const int axis = static_cast<int>(axis_code);
      out.f64(coordinate(bond.centroid, (axis + 1) % 3));
      out.f64(coordinate(bond.centroid, (axis + 2) % 3));
    }
    if ((flags & bond_normals_stored_bit) != 0) out.vec3(bond.normal);
    out.end_record();
  }
}

void cell_planes_payload(const MeshTree& tree, ByteWriter& out) {
  out.count32(tree.cut_planes.size() - tree.nodes.size());
  for (std::size_t k = tree.nodes.size(); k < tree.cut_planes.size(); ++k) {
    out.vec3(tree.cut_planes[k].normal);
    out.f64(tree.cut_planes[k].offset);
    out.end_record();
  }
}

void geometry_payload(const InputGeometry& geometry, ByteWriter& out) {
  out.count32(geometry.points.size());
  out.count32(geometry.planes.size());
  for (const Vec3& point : geometry.points) {
    out.vec3(point);
    out.end_record();
  }
  for (const auto& plane : geometry.planes) {
    for (const VertexIndex point : plane) out.u32(point);
  }
}

void recipe_payload(const TreeRecipe& recipe, ByteWriter& out) {
  out.u32(recipe.fragments);
  out.u64(recipe.seed);
  out.u8(static_cast<std::uint8_t>(recipe.strategy));
  out.u8(static_cast<std::uint8_t>(recipe.kernel));
  out.f64(recipe.interior_uv_scale);
  out.u32(recipe.max_plane_tries);
  out.u8(recipe.allow_self_intersections ? 1 : 0);
}

// ---------------------------------------------------------------------------
// Decoding

/// Reads a plane code of the node at the end of `path`.
PlaneRef read_plane(PayloadReader& in, const AncestorPath& path, const MeshTree& tree, const char* field) {
  const std::size_t at = in.offset();
  const std::uint64_t code = in.varint(field, 64);
  if (code == 0) return PlaneRef{no_index};
  if ((code & 1) != 0) {
    const std::uint64_t input = code >> 1;
    if (input >= PlaneRef::cut_bit) in.fail_at(at, std::string(field) + " names input plane " + str(input) + ", beyond any index");
    return PlaneRef::input(static_cast<std::uint32_t>(input));
  }
  const std::uint64_t up = code >> 1;
  if (up > path.depth()) {
    const std::uint64_t cell = up - path.depth() - 1;
    if (cell < tree.cut_planes.size() - tree.nodes.size()) return PlaneRef::cut(static_cast<std::uint32_t>(tree.nodes.size() + cell));
    in.fail_at(at, std::string(field) + " names the cut plane of the node " + str(up) + " levels up, but the node has depth " + str(path.depth()));
  }
  return PlaneRef::cut(path.above(up));
}

SurfaceId read_surface(PayloadReader& in, const AncestorPath& path, const char* field) {
  const std::size_t at = in.offset();
  const std::uint64_t code = in.varint(field, 64);
  if (code == 0) return original_surface;
  if (code <= path.depth()) return cap_surface_of(path.above(code));
  const std::uint64_t surface = code - path.depth();
  if (surface > 0xFFFFFFFFull) in.fail_at(at, std::string(field) + " is beyond 32 bits");
  return static_cast<SurfaceId>(surface);
}

/// Reads one mesh record; `sources` gets, per vertex, the index of the source its
/// position comes from (no_index when stored), `source_count` the sources there are.
Mesh read_mesh(PayloadReader& in, std::size_t source_count, std::vector<std::uint32_t>& sources, const AncestorPath& path) {
  Mesh mesh;
  const std::uint32_t vertex_count = in.varint32("vertex count");
  const std::uint32_t triangle_count = in.varint32("triangle count");
  const std::uint8_t channels = read_channel_flags(in, triangle_count);
  in.check_room(vertex_count, 1, "vertices");
  mesh.positions.resize(vertex_count);
  sources.assign(vertex_count, no_index);
  for (std::size_t v = 0; v < vertex_count; ++v) {
    const std::size_t at = in.offset();
    const std::uint64_t code = in.varint("position code", 64);
    if (code == position_stored) {
      mesh.positions[v] = in.vec3("position");
      continue;
    }
    const std::int64_t source = static_cast<std::int64_t>(v) + unzigzag(code - 1);
    if (source < 0 || static_cast<std::uint64_t>(source) >= source_count) {
      in.fail_at(at, "vertex " + str(v) + " takes the position of source vertex " + std::to_string(source) + ", of " + str(source_count));
    }
    sources[v] = static_cast<std::uint32_t>(source);
  }
  const std::size_t width = vertex_count <= 0x100 ? 1 : vertex_count <= 0x10000 ? 2 : 4;
  in.check_room(triangle_count, 3 * width, "triangles");
  mesh.triangles.resize(triangle_count);
  for (Triangle& triangle : mesh.triangles) {
    for (VertexIndex& vertex : triangle) {
      if (width == 1) vertex = in.u8("triangle");
      if (width == 2) {
        vertex = in.u8("triangle");
        vertex |= VertexIndex{in.u8("triangle")} << 8;
      }
      if (width == 4) vertex = in.u32("triangle");
    }
  }
  const std::uint32_t run_count = in.varint32("surface run count");
  in.check_room(run_count, 2, "surface runs");
  mesh.surfaces.reserve(triangle_count);
  for (std::uint32_t r = 0; r < run_count; ++r) {
    const SurfaceId surface = read_surface(in, path, "surface");
    const std::size_t at = in.offset();
    const std::uint32_t length = in.varint32("surface run length");
    if (length == 0 || length > triangle_count - mesh.surfaces.size()) {
      in.fail_at(at, "surface run " + str(r) + " of " + str(length) + " triangles, with " + str(triangle_count - mesh.surfaces.size()) + " left");
    }
    mesh.surfaces.insert(mesh.surfaces.end(), length, surface);
  }
  if (mesh.surfaces.size() != triangle_count) in.fail("the surface runs cover " + str(mesh.surfaces.size()) + " of " + str(triangle_count) + " triangles");

  read_corner_channels(in, channels, triangle_count, mesh);
  return mesh;
}

}  // namespace

void write_version3_sections(const MeshTree& tree, bool masses_derived,
                             const std::function<void(Tag, const SectionPayload&)>& emit) {
  const HeldFloatingPointExceptions held;
  const auto bytes = [](const std::string& text) { return [&text](ByteWriter& out) { out.append(text); }; };
  if (!tree.shatter_version.empty()) emit(version_tag, bytes(tree.shatter_version));
  if (!tree.input_repair.empty()) emit(repair_tag, [&](ByteWriter& out) { out.append(repair_payload(tree.input_repair)); });
  emit(recipe_tag, [&](ByteWriter& out) { recipe_payload(tree.recipe, out); });
  if (!tree.recipe.pattern.empty()) emit(pattern_tag, bytes(tree.recipe.pattern));
  emit(nodes_tag, [&](ByteWriter& out) { nodes_payload(tree, masses_derived, out); });
  if (tree.cut_planes.size() > tree.nodes.size()) emit(cell_planes_tag, [&](ByteWriter& out) { cell_planes_payload(tree, out); });
  emit(geometry_tag, [&](ByteWriter& out) { geometry_payload(tree.geometry, out); });
  emit(solids_tag, [&](ByteWriter& out) { solids_payload(tree, out); });
  emit(meshes_tag, [&](ByteWriter& out) { meshes_payload(tree, false, out); });
  emit(hulls_tag, [&](ByteWriter& out) { meshes_payload(tree, true, out); });
  emit(bonds_tag, [&](ByteWriter& out) { bonds_payload(tree, out); });
  emit(end_tag, [](ByteWriter&) {});
}

void read_version3_nodes(const Section& section, MeshTree& tree, Version3Pending& pending, RecordOffsets& offsets) {
  PayloadReader in(section);
  const std::uint32_t node_count = in.u32("the node count");
  if (node_count == 0) in.fail("node count 0 (a tree has at least its root)");
  const std::size_t flags_at = in.offset();
  const std::uint8_t flags = in.u8("node flags");
  if ((flags & ~known_node_flags) != 0) in.fail_at(flags_at, "unknown node flag bits " + hex(flags, 2));
  pending.masses_derived = (flags & masses_stored_bit) == 0;
  in.check_room(node_count, 1, "nodes");
  std::vector<MeshTreeNode>& nodes = tree.nodes;
  nodes.resize(node_count);
  tree.cut_planes.resize(node_count);
  offsets.nodes.resize(node_count);
  // The nodes still owed children, innermost last: preorder hands each node to
  // the innermost one.
  std::vector<std::pair<NodeIndex, std::uint32_t>> open;  // node, children it still lacks
  for (std::size_t k = 0; k < node_count; ++k) {
    MeshTreeNode& node = nodes[k];
    offsets.nodes[k] = in.offset();
    in.set_record("node", k);
    const std::uint64_t code = in.varint("child count", 64);
    const std::uint64_t child_count = code >> 1;
    node.above_parent_plane = (code & 1) != 0;
    if (k > 0) {
      if (open.empty()) in.fail_at(offsets.nodes[k], "the child counts before it describe a whole tree of " + str(k) + " nodes");
      node.parent = open.back().first;
      node.depth = nodes[node.parent].depth + 1;
      nodes[node.parent].children.push_back(static_cast<NodeIndex>(k));
      if (--open.back().second == 0) open.pop_back();
    }
    if (child_count > node_count - 1 - k) {
      in.fail_at(offsets.nodes[k], "node " + str(k) + " claims " + str(child_count) + " children, but only " + str(node_count - 1 - k) + " nodes follow");
    }
    if (child_count > 0) {
      open.emplace_back(static_cast<NodeIndex>(k), static_cast<std::uint32_t>(child_count));
      nodes[k].children.reserve(static_cast<std::size_t>(child_count));
    }
    if (child_count > 0 || (flags & leaf_planes_stored_bit) != 0) {
      tree.cut_planes[k].normal = in.vec3("plane normal");
      tree.cut_planes[k].offset = in.f64("plane offset");
    }
    if ((flags & seeds_stored_bit) != 0) {
      node.seed = in.u64("seed");
    } else {
      const MeshTreeNode* parent = k == 0 ? nullptr : &nodes[node.parent];
      node.seed = parent == nullptr ? root_node_seed(tree.recipe.seed) : child_node_seed(parent->seed, parent->children.size() - 1);
    }
    if ((flags & masses_stored_bit) != 0) {
      node.mass.volume = in.f64("volume");
      node.mass.centroid = in.vec3("centroid");
      for (double& entry : node.mass.inertia) entry = in.f64("inertia");
    }
  }
  in.set_record("");
  if (!open.empty()) in.fail("node " + str(open.back().first) + " lacks " + str(open.back().second) + " of its children: the node count ends the tree early");
  in.expect_end();
  // Leaves are numbered in preorder, and every node's leaves follow it.
  LeafIndex next_leaf = 0;
  for (MeshTreeNode& node : nodes) {
    node.first_leaf = next_leaf;
    if (node.is_leaf()) ++next_leaf;
  }
  for (std::size_t k = node_count; k-- > 0;) {
    MeshTreeNode& node = nodes[k];
    node.leaf_count = node.is_leaf() ? 1 : 0;
    for (const NodeIndex child : node.children) node.leaf_count += nodes[child].leaf_count;
  }
}

void read_version3_solids(const Section& section, MeshTree& tree, RecordOffsets& offsets) {
  PayloadReader in(section);
  std::vector<MeshTreeNode>& nodes = tree.nodes;
  const bool exact = tree.has_exact_representation();
  const std::uint32_t record_count = in.u32("the solid count");
  if (!exact && record_count != 0) {
    in.fail(str(record_count) + " solids, but GEOM holds no input points (a tree without an exact representation stores none)");
  }
  if (exact && record_count != nodes.size()) in.fail(str(record_count) + " solids for " + str(nodes.size()) + " nodes");
  offsets.solids.resize(record_count);
  AncestorPath path;
  std::vector<std::uint32_t> across;  // corners whose line is the plane across their edge
  EdgeFaces edge_faces;                   // the face across a corner's edge
  std::vector<std::uint32_t> next_vertex;  // per corner: the next vertex of its loop
  for (std::size_t k = 0; k < record_count; ++k) {
    offsets.solids[k] = in.offset();
    in.set_record("node", k);
    MeshTreeNode& node = nodes[k];
    path.enter(static_cast<NodeIndex>(k), node.depth);
    Solid& solid = *node.solid;
    read_solid_flags(in, node);
    const std::uint32_t vertex_count = in.varint32("vertex count");
    const std::uint32_t face_count = in.varint32("face count");
    const std::uint32_t loop_count = in.varint32("loop count");
    const std::uint32_t corner_count = in.varint32("corner count");

    in.check_room(vertex_count, 2, "vertex definitions");
    solid.defs.resize(vertex_count);
    for (std::size_t v = 0; v < vertex_count; ++v) {
      PointDef& def = solid.defs[v];
      def.kind = read_point_kind(in, v);
      switch (def.kind) {
        case PointKind::input: def.a = in.varint32("vertex point"); break;
        case PointKind::segment_plane:
          def.a = in.varint32("vertex point");
          def.b = in.varint32("vertex point");
          def.planes[0] = read_plane(in, path, tree, "vertex plane");
          break;
        case PointKind::three_planes:
          for (PlaneRef& plane : def.planes) plane = read_plane(in, path, tree, "vertex plane");
          break;
      }
    }

    in.check_room(face_count, 5, "faces");
    solid.faces.resize(face_count);
    std::uint64_t next_loop = 0;
    for (SolidFace& face : solid.faces) {
      face.plane = read_plane(in, path, tree, "face plane");
      read_face_flags(in, face);
      face.surface = read_surface(in, path, "face surface");
      face.source = in.varint32("face source");
      const std::size_t count_at = in.offset();
      face.loop_count = in.varint32("face loop count");
      face.first_loop = next_range(in, count_at, face.loop_count, next_loop, loop_count, "faces", "loops");
    }

    in.check_room(loop_count, 1, "loops");
    solid.loops.resize(loop_count);
    std::uint64_t next_corner = 0;
    for (SolidLoop& loop : solid.loops) {
      const std::size_t count_at = in.offset();
      loop.corner_count = in.varint32("loop corner count");
      loop.first_corner = next_range(in, count_at, loop.corner_count, next_corner, corner_count, "loops", "corners");
    }
    // Corners not in any loop are refused by the validator; they still need a line.
    in.check_room(corner_count, 1, "corners");
    solid.corners.resize(corner_count);
    across.clear();
    for (std::size_t c = 0; c < corner_count; ++c) {
      SolidCorner& corner = solid.corners[c];
      const std::size_t at = in.offset();
      const std::uint64_t code = in.varint("corner", 64);
      const std::uint64_t mode = code & 3;
      const std::uint64_t vertex = code >> 2;
      if (vertex >= vertex_count) in.fail_at(at, "corner " + str(c) + " has vertex " + str(vertex) + ", of " + str(vertex_count));
      corner.vertex = static_cast<VertexIndex>(vertex);
      if (mode == line_across) {
        across.push_back(static_cast<std::uint32_t>(c));
        continue;
      }
      if (mode != line_stored && mode != line_segment) in.fail_at(at, "corner " + str(c) + " has line mode 3 (unknown)");
      corner.line.other = read_plane(in, path, tree, "corner line plane");
      if (mode == line_segment) {
        corner.line.p = in.varint32("corner segment");
        corner.line.q = in.varint32("corner segment");
        // A segment of two "none" points would come back as no segment.
        if (corner.line.p == no_index) in.fail_at(at, "corner " + str(c) + " has a segment, but its segment is none");
      }
    }
    if (across.empty()) continue;
    // The line across an edge is the plane of the lowest face that runs it the
    // other way, found as the writer found it (EdgeFaces; a sort of all edges
    // and a binary search a corner was a tenth of reading).
    edge_faces.index(solid, vertex_count);
    next_vertex.assign(corner_count, no_index);
    for (const SolidFace& face : solid.faces) {  // the faces' loops only, as the index
      for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
        for (const CornerEdge& edge : loop_edges(solid.corners, solid.loops[l])) next_vertex[edge.corner] = edge.to;
      }
    }
    for (const std::uint32_t c : across) {
      const VertexIndex from = next_vertex[c];
      const std::optional<std::uint32_t> found =
          from == no_index ? std::nullopt : edge_faces.face_of_edge(from, solid.corners[c].vertex);
      if (!found) {
        in.fail_at(offsets.solids[k], "corner " + str(c) + " takes the plane of the face across its edge, but no face runs that edge the other way");
      }
      solid.corners[c].line.other = solid.faces[*found].plane;
    }
  }
  in.set_record("");
  in.expect_end();
}

namespace {

// What the MESH section's reading beside SOLD's leaves to check once the
// solids are read (read_version3_shapes): `read` records were read, and the
// next one (if any) failed to.
struct DeferredSources {
  std::size_t read = 0;
};

void read_meshes(const Section& section, MeshTree& tree, bool hulls, Version3Pending& pending, RecordOffsets& offsets,
                 DeferredSources* deferred) {
  PayloadReader in(section);
  std::vector<MeshTreeNode>& nodes = tree.nodes;
  const std::uint32_t mesh_count = in.u32("the mesh count");
  if (mesh_count != nodes.size()) in.fail(str(mesh_count) + " meshes for " + str(nodes.size()) + " nodes");
  std::vector<std::size_t>& record_offsets = hulls ? offsets.hulls : offsets.meshes;
  std::vector<std::vector<std::uint32_t>>& sources = hulls ? pending.hull_sources : pending.mesh_sources;
  record_offsets.resize(mesh_count);
  sources.resize(mesh_count);
  AncestorPath path;
  for (std::size_t k = 0; k < mesh_count; ++k) {
    record_offsets[k] = in.offset();
    in.set_record("node", k);
    path.enter(static_cast<NodeIndex>(k), nodes[k].depth);
    // Deferred: any source a 32-bit index holds passes here (no_index, the
    // stored mark, does not), and is checked against the solid's vertex count
    // once it is known.
    const std::size_t source_count = deferred != nullptr ? std::size_t{no_index}
                                     : hulls               ? nodes[k].mesh->positions.size()
                                                           : nodes[k].solid->defs.size();
    Mesh mesh = read_mesh(in, source_count, sources[k], path);
    if (deferred != nullptr) deferred->read = k + 1;
    if (!hulls) {
      nodes[k].mesh = std::move(mesh);
    } else if (!mesh.positions.empty() || !mesh.triangles.empty()) {
      nodes[k].hull = std::move(mesh);  // a convex node's stays absent (Boxed)
    }
  }
  in.set_record("");
  in.expect_end();
}

// Reads MESH record `k` again, now that the solids are read, with its solid's
// vertex count: it throws just what reading it in turn would have.
void reread_mesh_record(const Section& section, const MeshTree& tree, const RecordOffsets& offsets, std::size_t k) {
  const std::size_t from = offsets.meshes[k] - section.payload_offset;
  Section rest = section;
  rest.payload = section.payload.substr(from);
  rest.payload_offset = section.payload_offset + from;
  PayloadReader in(rest);
  in.set_record("node", k);
  AncestorPath path;
  path.start_at(static_cast<NodeIndex>(k), tree.nodes);
  std::vector<std::uint32_t> sources;
  read_mesh(in, tree.nodes[k].solid->defs.size(), sources, path);
}

}  // namespace

void read_version3_shapes(const SectionTable& sections, MeshTree& tree, Version3Pending& pending, RecordOffsets& offsets) {
  // SOLD on one side; MESH, HULL and BOND on the other, which need of the
  // solids only their vertex counts (the sources of MESH's positions), checked
  // after both. Failures are then reported as reading in turn would: SOLD's
  // first, then a deferred source of a MESH record before the one MESH failed
  // at (read again, so the message is the same), then the other side's own.
  std::exception_ptr solids_failure, others_failure;
  DeferredSources deferred;
  tbb::parallel_invoke(
      [&] {
        try {
          read_version3_solids(*sections.solids, tree, offsets);
        } catch (...) {
          solids_failure = std::current_exception();
        }
      },
      [&] {
        try {
          read_meshes(*sections.meshes, tree, false, pending, offsets, &deferred);
          read_meshes(*sections.hulls, tree, true, pending, offsets, nullptr);
          tree.leaf_nodes = leaves_in_order(tree.nodes);
          read_version3_bonds(*sections.bonds, tree, offsets);
        } catch (...) {
          others_failure = std::current_exception();
        }
      });
  if (solids_failure) std::rethrow_exception(solids_failure);
  for (std::size_t k = 0; k < deferred.read; ++k) {
    const std::size_t vertices = tree.nodes[k].solid->defs.size();
    for (const std::uint32_t source : pending.mesh_sources[k]) {
      if (source != no_index && source >= vertices) reread_mesh_record(*sections.meshes, tree, offsets, k);
    }
  }
  // MESH failed at a record (fewer read than it holds): with the solid's count
  // it may fail sooner in it.
  if (others_failure && deferred.read < offsets.meshes.size()) {
    reread_mesh_record(*sections.meshes, tree, offsets, deferred.read);
  }
  if (others_failure) std::rethrow_exception(others_failure);
}

void read_version3_bonds(const Section& section, MeshTree& tree, RecordOffsets& offsets) {
  const HeldFloatingPointExceptions held;
  PayloadReader in(section);
  const std::vector<MeshTreeNode>& nodes = tree.nodes;
  const std::uint64_t bond_count = in.u64("the bond count");
  const std::size_t flags_at = in.offset();
  const std::uint8_t flags = in.u8("bond flags");
  if ((flags & ~bond_normals_stored_bit) != 0) in.fail_at(flags_at, "unknown bond flag bits " + hex(flags, 2));
  in.check_room(bond_count, 2 + 3 * 8, "bonds");
  tree.bonds.resize(static_cast<std::size_t>(bond_count));
  offsets.bonds.resize(tree.bonds.size());
  const std::uint64_t leaf_count = tree.leaf_nodes.size();
  std::uint64_t first = 0;
  for (std::size_t i = 0; i < tree.bonds.size(); ++i) {
    Bond& bond = tree.bonds[i];
    offsets.bonds[i] = in.offset();
    in.set_record("bond", i);
    first += in.varint("first", 64);
    const std::uint64_t code = in.varint("second", 64);
    const std::uint64_t second = first + 1 + (code >> 2);
    if (first >= leaf_count || second >= leaf_count || second <= first) {
      in.fail_at(offsets.bonds[i], "bond " + str(i) + " joins leaves " + str(first) + " and " + str(second) + ", of " + str(leaf_count));
    }
    bond.first = static_cast<LeafIndex>(first);
    bond.second = static_cast<LeafIndex>(second);
    // The cut node is where the two leaves' paths meet; `side` the child on first's side.
    NodeIndex side = tree.leaf_nodes[bond.first];
    NodeIndex cut = nodes[side].parent;
    while (!(nodes[cut].first_leaf <= bond.second && bond.second < nodes[cut].first_leaf + nodes[cut].leaf_count)) {
      side = cut;
      cut = nodes[cut].parent;
    }
    bond.cut_node = cut;
    const Plane& plane = tree.cut_planes[cut];
    bond.area = in.f64("area");
    const std::uint64_t axis_code = code & 3;
    if (axis_code == centroid_stored) {
      bond.centroid = in.vec3("centroid");
    } else {
      const int axis = static_cast<int>(axis_code);
      const double u = in.f64("centroid");
      const double v = in.f64("centroid");
      bond.centroid = point_on_plane_over(plane, axis, u, v);
    }
    if ((flags & bond_normals_stored_bit) != 0) {
      bond.normal = in.vec3("normal");
    } else {
      const Vec3 unit = normalized(plane.normal);
      bond.normal = nodes[side].above_parent_plane ? -unit : unit;
    }
  }
  in.set_record("");
  in.expect_end();
}

void read_cell_planes(const Section& section, MeshTree& tree) {
  PayloadReader in(section);
  const std::uint32_t count = in.u32("the cell plane count");
  in.check_room(count, 32, "cell planes");
  tree.cut_planes.reserve(tree.cut_planes.size() + count);
  for (std::uint32_t k = 0; k < count; ++k) {
    in.set_record("cell plane " + str(k));
    Plane plane;
    plane.normal = in.vec3("plane normal");
    plane.offset = in.f64("plane offset");
    tree.cut_planes.push_back(plane);
  }
  in.set_record("");
  in.expect_end();
}

void finish_version3(MeshTree& tree, const Version3Pending& pending) {
  const PlaneSet set = tree.plane_set();
  // Node by node in parallel: each node's positions and mass are its own, so
  // the bits do not depend on the schedule. On one thread it was a tenth of
  // `info` (cube -> 65,536), run while the other thread waited.
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, tree.nodes.size(), 256), [&](const tbb::blocked_range<std::size_t>& range) {
    const HeldFloatingPointExceptions held;  // the environment is each thread's own
    for (std::size_t k = range.begin(); k != range.end(); ++k) {
      MeshTreeNode& node = tree.nodes[k];
      const std::vector<std::uint32_t>& mesh_sources = pending.mesh_sources[k];
      for (std::size_t v = 0; v < mesh_sources.size(); ++v) {
        if (const std::uint32_t s = mesh_sources[v]; s != no_index) node.mesh->positions[v] = output_position(set, node.solid->defs[s], node.solid->approx[s]);
      }
      const std::vector<std::uint32_t>& hull_sources = pending.hull_sources[k];
      for (std::size_t v = 0; v < hull_sources.size(); ++v) {
        if (const std::uint32_t s = hull_sources[v]; s != no_index) node.hull->positions[v] = node.mesh->positions[s];
      }
      if (pending.masses_derived) node.mass = mass_properties(node.mesh);
    }
  });
}

}  // namespace shatter::file_layout
