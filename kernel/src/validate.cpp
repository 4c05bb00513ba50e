#include "shatter/kernel/validate.hpp"

#include "shatter/kernel/error.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <CGAL/box_intersection_d.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <tuple>
#include <unordered_set>
#include <cstdint>
#include <iterator>
#include <limits>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <utility>

#include "shatter/kernel/certify.hpp"
#include "shatter/kernel/index_map.hpp"
#include "shatter/kernel/mass.hpp"
#include "shatter/kernel/position_key.hpp"
#include "shatter/kernel/predicates.hpp"
#include "shatter/kernel/self_intersections.hpp"
#include "shatter/kernel/shells.hpp"
#include "shatter/kernel/union_find.hpp"
#include "shatter/kernel/star_shaped.hpp"
#include "triangle_boxes.hpp"

namespace shatter {
namespace {

using CgalPoint = CGAL::Epick::Point_3;

// Every undirected edge, in the order it is first met scanning triangles in order
// and each triangle's corners c -> c+1. "First" for edge defects means first in
// this order, so reports are deterministic and point at the earliest triangle.
struct EdgeRecord {
  VertexIndex low = 0, high = 0;     // endpoints, low < high
  std::uint32_t forward = 0;         // triangles traversing low -> high
  std::uint32_t backward = 0;        // triangles traversing high -> low
  // The first two triangles on the edge (as corner ids 3*t + c, where the edge
  // leaves corner c): enough to join the fans at both endpoints of a manifold edge.
  std::array<std::uint32_t, 2> corners{};

  std::uint32_t triangle_count() const { return forward + backward; }
};

std::uint64_t edge_key(VertexIndex a, VertexIndex b) {
  const VertexIndex low = std::min(a, b), high = std::max(a, b);
  return (std::uint64_t{low} << 32) | high;
}

std::string vertex_text(std::size_t v) { return "vertex " + std::to_string(v); }
std::string triangle_text(std::size_t t) { return "triangle " + std::to_string(t); }
std::string edge_text(const EdgeRecord& e) {
  return "edge (" + std::to_string(e.low) + ", " + std::to_string(e.high) + ")";
}

// Collects the defects of one kind: the count and the first element.
struct Tally {
  std::size_t count = 0;
  std::string first;
  // Takes a function making the element's text, so only the first one is built.
  template <class MakeText>
  void add(MakeText&& make_text) {
    if (count++ == 0) first = make_text();
  }
};

void append(ValidationReport& report, DefectKind kind, Tally&& tally) {
  if (tally.count > 0) report.defects.push_back({kind, tally.count, std::move(tally.first)});
}

// The self-intersection defect for `pairs` (sorted), none when there is no pair.
void append_self_intersections(ValidationReport& report, const std::vector<std::pair<std::size_t, std::size_t>>& pairs) {
  if (pairs.empty()) return;
  report.defects.push_back({DefectKind::self_intersection, pairs.size(),
                            "triangles " + std::to_string(pairs.front().first) + " and " +
                                std::to_string(pairs.front().second)});
}

using detail::box_of;
using detail::TriangleBox;

// Whether every index is in range, every vertex used, no triangle repeats an
// index, every directed edge appears once and its reverse once (closed and
// consistently oriented, two triangles per edge), and the triangles around each
// vertex form one fan. Linear time on flat arrays: the out-edges of each vertex
// are gathered by source (counting sort), so twins and fans are found in short,
// sorted per-vertex lists. Meant as the fast path: a mesh that passes has none of
// the topological defects, and one that fails goes to the detailed checks, which
// name them.
bool closed_oriented_manifold(const Mesh& mesh) {
  const std::size_t vertex_count = mesh.positions.size();
  const std::size_t triangle_count = mesh.triangles.size();
  if (triangle_count == 0 || 3 * triangle_count > std::numeric_limits<std::uint32_t>::max()) return false;
  thread_local std::vector<std::uint32_t> first_out;  // CSR offsets by source vertex
  thread_local std::vector<std::uint64_t> out;        // (target << 32 | half-edge 3t + c), sorted per source
  first_out.assign(vertex_count + 1, 0);
  for (const Triangle& tri : mesh.triangles) {
    for (const VertexIndex v : tri) {
      if (v >= vertex_count) return false;
      ++first_out[v + 1];
    }
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) return false;
  }
  for (std::size_t v = 0; v < vertex_count; ++v) {
    if (first_out[v + 1] == 0) return false;  // unused
    first_out[v + 1] += first_out[v];
  }
  out.resize(3 * triangle_count);
  {
    thread_local std::vector<std::uint32_t> fill;
    fill.assign(first_out.begin(), first_out.end() - 1);
    for (std::uint32_t t = 0; t < triangle_count; ++t) {
      const Triangle& tri = mesh.triangles[t];
      for (std::uint32_t c = 0; c < 3; ++c) {
        out[fill[tri[c]]++] = (std::uint64_t{tri[(c + 1) % 3]} << 32) | (3 * t + c);
      }
    }
  }
  // The out-edge v -> w, as its index into `out`, or none. A short list (most
  // vertices have a handful of out-edges) is scanned, a long one searched:
  // the binary search's unpredictable branches were most of this check's time
  // on the pieces of curved meshes. Either finds the one entry (no directed
  // edge is there twice, checked before any lookup).
  constexpr std::uint32_t none = std::numeric_limits<std::uint32_t>::max();
  constexpr std::uint32_t scanned = 16;
  const auto find_out = [&](VertexIndex v, VertexIndex w) {
    const auto begin = out.begin() + first_out[v], end = out.begin() + first_out[v + 1];
    if (end - begin <= scanned) {
      for (auto it = begin; it != end; ++it) {
        if ((*it >> 32) == w) return static_cast<std::uint32_t>(it - out.begin());
      }
      return none;
    }
    const auto it = std::lower_bound(begin, end, std::uint64_t{w} << 32);
    return it != end && (*it >> 32) == w ? static_cast<std::uint32_t>(it - out.begin()) : none;
  };
  for (std::size_t v = 0; v < vertex_count; ++v) {
    const auto begin = out.begin() + first_out[v], end = out.begin() + first_out[v + 1];
    std::sort(begin, end);
    for (auto it = begin; it + 1 < end; ++it) {
      if ((*it >> 32) == (*(it + 1) >> 32)) return false;  // a directed edge twice
    }
  }
  for (std::size_t v = 0; v < vertex_count; ++v) {
    const std::uint32_t degree = first_out[v + 1] - first_out[v];
    // Around v: the triangle (v, w, x) leads to the one holding v -> x. Each
    // out-edge has its twin (x -> v is in the triangle before), so the steps are
    // a permutation of v's out-edges; one fan is one cycle through all of them.
    std::uint32_t slot = first_out[v], steps = 0;
    do {
      const std::uint32_t half_edge = static_cast<std::uint32_t>(out[slot]);
      const VertexIndex w = static_cast<VertexIndex>(out[slot] >> 32);
      if (find_out(w, static_cast<VertexIndex>(v)) == none) return false;  // no twin: open
      const Triangle& tri = mesh.triangles[half_edge / 3];
      slot = find_out(static_cast<VertexIndex>(v), tri[(half_edge % 3 + 2) % 3]);
      if (slot == none) return false;
      ++steps;
    } while (slot != first_out[v] && steps <= degree);
    if (steps != degree) return false;
  }
  return true;
}

std::string plural(std::size_t count, const char* singular, const char* plural_form) {
  return std::to_string(count) + " " + (count == 1 ? singular : plural_form);
}

std::string defect_line(const Defect& d) {
  const std::string first = d.first.empty() ? "" : ", first " + d.first;
  switch (d.kind) {
    case DefectKind::nonfinite_coordinate:
      return "non-finite coordinates: " + plural(d.count, "vertex", "vertices") + " with NaN or infinity" + first;
    case DefectKind::index_out_of_range:
      return "indices out of range: " + plural(d.count, "triangle", "triangles") +
             " with a vertex index past the vertex count" + first;
    case DefectKind::unused_vertex:
      return "unused vertices: " + plural(d.count, "vertex", "vertices") + " no triangle uses" + first;
    case DefectKind::zero_area_triangle:
      return "degenerate mesh: " + plural(d.count, "zero-area triangle", "zero-area triangles") + first;
    case DefectKind::boundary_edge:
      return "open mesh: " + plural(d.count, "boundary edge", "boundary edges") + first;
    case DefectKind::non_manifold_edge:
      return "non-manifold mesh: " + plural(d.count, "edge", "edges") + " shared by three or more triangles" +
             first;
    case DefectKind::non_manifold_vertex:
      return "non-manifold mesh: " + plural(d.count, "vertex", "vertices") +
             " where separate fans of triangles meet" + first;
    case DefectKind::inconsistent_orientation:
      return "inconsistent orientation: " + plural(d.count, "edge", "edges") +
             " traversed the same way by two triangles" + first;
    case DefectKind::inward_orientation:
      return "inward-facing: negative volume (faces point inward)";
    case DefectKind::self_intersection:
      return "self-intersecting: " + plural(d.count, "pair", "pairs") + " of intersecting triangles" + first;
    case DefectKind::misnested_shell:
      return "misnested shells: " + plural(d.count, "shell faces", "shells face") +
             " the same way as the shell around it, so the solid covers its inside twice" + first;
  }
  return std::string(defect_name(d.kind));
}

}  // namespace

std::string_view defect_name(DefectKind kind) {
  switch (kind) {
    case DefectKind::nonfinite_coordinate: return "non-finite coordinates";
    case DefectKind::index_out_of_range: return "indices out of range";
    case DefectKind::unused_vertex: return "unused vertices";
    case DefectKind::zero_area_triangle: return "zero-area triangles";
    case DefectKind::boundary_edge: return "boundary edges";
    case DefectKind::non_manifold_edge: return "non-manifold edges";
    case DefectKind::non_manifold_vertex: return "non-manifold vertices";
    case DefectKind::inconsistent_orientation: return "inconsistent orientation";
    case DefectKind::inward_orientation: return "inward orientation";
    case DefectKind::self_intersection: return "self-intersecting triangle pairs";
    case DefectKind::misnested_shell: return "misnested shells";
  }
  return "unknown defect";
}

const Defect* ValidationReport::find(DefectKind kind) const {
  for (const Defect& d : defects) {
    if (d.kind == kind) return &d;
  }
  return nullptr;
}

std::string ValidationReport::summary() const {
  if (defects.empty()) return "valid";
  std::string line = defect_line(defects.front());
  if (defects.size() > 1) {
    line += "; also";
    for (std::size_t i = 1; i < defects.size(); ++i) {
      const Defect& d = defects[i];
      line += (i == 1 ? " " : ", ");
      line += defect_name(d.kind);
      if (d.kind != DefectKind::inward_orientation) line += " (" + std::to_string(d.count) + ")";
    }
  }
  return line;
}

namespace {

// Whether the corners of triangle t are collinear, decided exactly (Epick's
// predicates are exact on double input: static and interval filters, then exact
// arithmetic).
bool collinear_corners(const Mesh& mesh, std::size_t t) {
  const Triangle& tri = mesh.triangles[t];
  const Vec3 a = mesh.positions[tri[0]], b = mesh.positions[tri[1]], c = mesh.positions[tri[2]];
  return CGAL::collinear(CgalPoint(a.x, a.y, a.z), CgalPoint(b.x, b.y, b.z), CgalPoint(c.x, c.y, c.z));
}

// Shells whose orientation disagrees with their nesting (shells.hpp). When every
// shell disagrees the whole mesh is reversed, which inward_orientation names
// instead. Precondition: as shell_nesting's.
Tally misnested_shells(const Mesh& mesh) {
  Tally misnested;
  // One shell cannot disagree with a nesting of its own (it is the whole mesh,
  // which inward_orientation judges). On a closed manifold the triangles around
  // a vertex are one fan, so triangles joined through vertices are joined
  // through edges: one vertex-connected surface is one shell, found by a
  // union-find over vertices, far cheaper than shell_nesting's half-edges.
  if (connected_surface(mesh)) return misnested;
  const ShellNesting nesting = shell_nesting(mesh);
  std::vector<std::size_t> first_triangle(nesting.shell_count(), mesh.triangles.size());
  for (std::size_t t = mesh.triangles.size(); t-- > 0;) first_triangle[nesting.shell_of_triangle[t]] = t;
  std::size_t disagreeing = 0;
  for (std::size_t s = 0; s < nesting.shell_count(); ++s) disagreeing += nesting.well_nested(s) ? 0 : 1;
  if (disagreeing == nesting.shell_count()) return misnested;
  for (std::size_t s = 0; s < nesting.shell_count(); ++s) {
    if (!nesting.well_nested(s)) misnested.add([&] { return "shell of " + triangle_text(first_triangle[s]); });
  }
  return misnested;
}

// The geometric checks of a mesh closed_oriented_manifold has passed (finite
// coordinates checked by the caller): zero-area triangles (only those `area_mask`
// marks, or all without it), inward orientation, self-intersections. The report
// is the one the detailed checks would make: no topological defect can be in it.
ValidationReport validate_sound_topology(const Mesh& mesh, const ValidationOptions& options,
                                         const std::vector<std::uint8_t>* area_mask) {
  ValidationReport report;
  report.vertex_count = mesh.vertex_count();
  report.triangle_count = mesh.triangle_count();
  Tally zero_area;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    if (area_mask != nullptr && !(*area_mask)[t]) continue;
    if (collinear_corners(mesh, t)) zero_area.add([&] { return triangle_text(t); });
  }
  const bool flat_free = zero_area.count == 0;
  append(report, DefectKind::zero_area_triangle, std::move(zero_area));
  if (signed_volume_sign(mesh) == Sign::negative) report.defects.push_back({DefectKind::inward_orientation, 1, "whole mesh"});
  if (options.check_self_intersections && flat_free) {
    append_self_intersections(report, self_intersecting_pairs(mesh.positions, mesh.triangles));
    report.self_intersections_checked = true;
    if (report.defects.empty()) append(report, DefectKind::misnested_shell, misnested_shells(mesh));
  }
  return report;
}

// validate_mesh, with the zero-area test limited to the triangles `area_mask`
// marks when the topology is sound (the others are known not to be flat).
ValidationReport validate_masked(const Mesh& mesh, const ValidationOptions& options,
                                 const std::vector<std::uint8_t>* area_mask);

}  // namespace

ValidationReport validate_mesh(const Mesh& mesh, const ValidationOptions& options) {
  return validate_masked(mesh, options, nullptr);
}

namespace {

ValidationReport validate_masked(const Mesh& mesh, const ValidationOptions& options,
                                 const std::vector<std::uint8_t>* area_mask) {
  if (std::all_of(mesh.positions.begin(), mesh.positions.end(), [](const Vec3& p) { return is_finite(p); }) &&
      closed_oriented_manifold(mesh)) {
    return validate_sound_topology(mesh, options, area_mask);
  }
  ValidationReport report;
  report.vertex_count = mesh.vertex_count();
  report.triangle_count = mesh.triangle_count();
  const std::size_t vertex_count = mesh.vertex_count();
  const std::size_t triangle_count = mesh.triangle_count();

  // --- Per-vertex and per-triangle checks -------------------------------------
  Tally nonfinite;
  std::vector<bool> finite(vertex_count);
  for (std::size_t v = 0; v < vertex_count; ++v) {
    finite[v] = is_finite(mesh.positions[v]);
    if (!finite[v]) nonfinite.add([&] { return vertex_text(v); });
  }

  Tally out_of_range;
  std::vector<bool> in_range(triangle_count);
  std::vector<bool> used(vertex_count);
  for (std::size_t t = 0; t < triangle_count; ++t) {
    bool all_in_range = true;
    for (VertexIndex v : mesh.triangles[t]) {
      if (v < vertex_count) {
        used[v] = true;  // referenced, even by a triangle that is otherwise broken
      } else {
        all_in_range = false;
      }
    }
    in_range[t] = all_in_range;
    if (!all_in_range) out_of_range.add([&] { return triangle_text(t); });
  }

  Tally unused;
  for (std::size_t v = 0; v < vertex_count; ++v) {
    if (!used[v]) unused.add([&] { return vertex_text(v); });
  }

  // A triangle with a repeated index has no area and no well-defined edges: it is
  // reported here and left out of the edge topology below (its "edges" would be a
  // loop and a doubled edge, which would only produce confusing follow-up defects).
  Tally zero_area;
  std::vector<bool> in_topology(triangle_count);
  for (std::size_t t = 0; t < triangle_count; ++t) {
    if (!in_range[t]) continue;
    const Triangle& tri = mesh.triangles[t];
    const bool repeated = tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2];
    in_topology[t] = !repeated;
    bool degenerate = repeated;
    if (!repeated && finite[tri[0]] && finite[tri[1]] && finite[tri[2]]) degenerate = collinear_corners(mesh, t);
    if (degenerate) zero_area.add([&] { return triangle_text(t); });
  }

  // --- Edge topology (index-based, linear time) -------------------------------
  std::vector<EdgeRecord> edges;
  edges.reserve(3 * triangle_count / 2 + 1);
  std::unordered_map<std::uint64_t, std::uint32_t> edge_ids;
  edge_ids.reserve(3 * triangle_count / 2 + 1);
  for (std::size_t t = 0; t < triangle_count; ++t) {
    if (!in_topology[t]) continue;
    const Triangle& tri = mesh.triangles[t];
    for (std::uint32_t c = 0; c < 3; ++c) {
      const VertexIndex from = tri[c], to = tri[(c + 1) % 3];
      const auto [it, inserted] = edge_ids.try_emplace(edge_key(from, to), static_cast<std::uint32_t>(edges.size()));
      if (inserted) edges.push_back({std::min(from, to), std::max(from, to), 0, 0, {}});
      EdgeRecord& edge = edges[it->second];
      const std::uint32_t seen = edge.triangle_count();
      if (seen < 2) edge.corners[seen] = static_cast<std::uint32_t>(3 * t + c);
      (from < to ? edge.forward : edge.backward) += 1;
    }
  }

  Tally boundary, non_manifold_edges, inconsistent;
  std::vector<bool> on_non_manifold_edge(vertex_count);
  for (const EdgeRecord& edge : edges) {
    const std::uint32_t n = edge.triangle_count();
    if (n == 1) boundary.add([&] { return edge_text(edge); });
    if (n > 2) {
      non_manifold_edges.add([&] { return edge_text(edge); });
      on_non_manifold_edge[edge.low] = on_non_manifold_edge[edge.high] = true;
    }
    // Consistent orientation pairs every traversal with one in the opposite
    // direction. On a manifold edge this is exactly "no directed edge appears
    // twice"; on a non-manifold edge a balanced split (2 + 2, two solids touching
    // along an edge) is still orientable and is reported only as non-manifold.
    const std::uint32_t imbalance = edge.forward > edge.backward ? edge.forward - edge.backward
                                                                 : edge.backward - edge.forward;
    if (imbalance >= 2) inconsistent.add([&] { return edge_text(edge); });
  }

  // Non-manifold vertices: the corners at a vertex are joined across each manifold
  // edge (exactly two triangles); a vertex whose corners fall into more than one
  // group sits where separate fans touch. Vertices on non-manifold edges are left
  // to that defect: their fans are split by definition.
  Tally non_manifold_vertices;
  UnionFind fans(3 * triangle_count);  // corners joined across manifold edges: the fans
  for (const EdgeRecord& edge : edges) {
    if (edge.triangle_count() != 2) continue;
    for (VertexIndex v : {edge.low, edge.high}) {
      std::array<std::uint32_t, 2> corner_at_v{};
      for (int side = 0; side < 2; ++side) {
        const std::uint32_t corner = edge.corners[side];
        const std::uint32_t t = corner / 3, c = corner % 3;
        corner_at_v[side] = mesh.triangles[t][c] == v ? corner : 3 * t + (c + 1) % 3;
      }
      fans.unite(corner_at_v[0], corner_at_v[1]);
    }
  }
  constexpr std::uint32_t no_fan = std::numeric_limits<std::uint32_t>::max();
  std::vector<std::uint32_t> fan_of_vertex(vertex_count, no_fan);  // the first fan met at each vertex
  std::vector<bool> several_fans(vertex_count);
  for (std::size_t t = 0; t < triangle_count; ++t) {
    if (!in_topology[t]) continue;
    for (std::uint32_t c = 0; c < 3; ++c) {
      const VertexIndex v = mesh.triangles[t][c];
      const std::uint32_t fan = fans.find(static_cast<std::uint32_t>(3 * t + c));
      if (fan_of_vertex[v] == no_fan) {
        fan_of_vertex[v] = fan;
      } else if (fan_of_vertex[v] != fan) {
        several_fans[v] = true;
      }
    }
  }
  for (std::size_t v = 0; v < vertex_count; ++v) {
    if (several_fans[v] && !on_non_manifold_edge[v]) non_manifold_vertices.add([&] { return vertex_text(v); });
  }

  // Which later checks are meaningful is decided before the tallies move out.
  const bool coordinates_and_indices_sound = nonfinite.count == 0 && out_of_range.count == 0;
  const bool closed_and_oriented = coordinates_and_indices_sound && boundary.count == 0 &&
                                   non_manifold_edges.count == 0 && inconsistent.count == 0;
  // Unused vertices do not touch the surface, so they do not block the geometric
  // checks; zero-area triangles do block the self-intersection test (CGAL reports
  // a degenerate face as intersecting itself). A non-manifold vertex does not: the
  // test runs on the mesh with one copy of the vertex per fan, and triangles of
  // different fans that meet only there are then reported as intersecting, which
  // they are: the surface touches itself at that point. (This is also exactly the
  // unwelded input when welding created the pinch, as in the corpus cow.)
  const bool closed_manifold_up_to_vertices = closed_and_oriented && zero_area.count == 0;
  const bool has_non_manifold_vertices = non_manifold_vertices.count > 0;

  append(report, DefectKind::nonfinite_coordinate, std::move(nonfinite));
  append(report, DefectKind::index_out_of_range, std::move(out_of_range));
  append(report, DefectKind::unused_vertex, std::move(unused));
  append(report, DefectKind::zero_area_triangle, std::move(zero_area));
  append(report, DefectKind::boundary_edge, std::move(boundary));
  append(report, DefectKind::non_manifold_edge, std::move(non_manifold_edges));
  append(report, DefectKind::non_manifold_vertex, std::move(non_manifold_vertices));
  append(report, DefectKind::inconsistent_orientation, std::move(inconsistent));

  // --- Orientation and self-intersection (geometry, exact) --------------------
  // The signed volume is translation-invariant, and so meaningful, only when every
  // edge is traversed once each way: a closed, consistently oriented mesh.
  if (closed_and_oriented && signed_volume_sign(mesh) == Sign::negative) {
    report.defects.push_back({DefectKind::inward_orientation, 1, "whole mesh"});
  }

  if (options.check_self_intersections && closed_manifold_up_to_vertices) {
    std::vector<Vec3> positions = mesh.positions;
    std::vector<Triangle> triangles = mesh.triangles;
    if (has_non_manifold_vertices) {
      // Every fan but the first at a pinched vertex gets its own copy of it.
      std::unordered_map<std::uint32_t, VertexIndex> copy_of_fan;
      for (std::size_t t = 0; t < triangle_count; ++t) {
        for (std::uint32_t c = 0; c < 3; ++c) {
          const VertexIndex v = mesh.triangles[t][c];
          if (!several_fans[v]) continue;
          const std::uint32_t fan = fans.find(static_cast<std::uint32_t>(3 * t + c));
          if (fan == fan_of_vertex[v]) continue;
          const auto [it, inserted] = copy_of_fan.try_emplace(fan, static_cast<VertexIndex>(positions.size()));
          if (inserted) positions.push_back(mesh.positions[v]);
          triangles[t][c] = it->second;
        }
      }
    }
    append_self_intersections(report, self_intersecting_pairs(positions, triangles));
    report.self_intersections_checked = true;
  }
  return report;
}

}  // namespace

void require_valid_solid(const Mesh& mesh, std::string_view name, bool allow_self_intersections) {
  // No triangle has no defect either, but it is no solid.
  if (mesh.triangles.empty()) throw InvalidMeshError("invalid mesh " + std::string(name) + ": empty (no triangles)");
  // A mesh a piece certificate proves valid needs no search: certify_piece
  // accepts only what validate_mesh finds valid, and declines quickly (at the
  // first triangle facing a centre) on a mesh star-shaped around none.
  if (certify_piece(mesh)) return;
  const ValidationReport report = validate_mesh(mesh);
  const Defect* self_intersection = nullptr;
  for (const Defect& d : report.defects) {
    if (d.kind == DefectKind::self_intersection) {
      self_intersection = &d;
      continue;
    }
    if (d.kind == DefectKind::non_manifold_vertex && allow_self_intersections) continue;
    throw InvalidMeshError("invalid mesh " + std::string(name) + ": " + report.summary());
  }
  if (self_intersection && !allow_self_intersections) {
    const bool one = self_intersection->count == 1;
    throw InvalidMeshError("invalid mesh " + std::string(name) + ": self-intersecting: " +
                           std::to_string(self_intersection->count) + (one ? " pair" : " pairs") +
                           " of intersecting triangles, first " +
                           self_intersection->first + " (--allow-self-intersections cuts it anyway)");
  }
}

namespace {

// A triangle's corner positions, rotated to start at the lexicographically least,
// so the same triangle gives the same key whatever its first corner.
std::array<Vec3, 3> triangle_key(const Mesh& mesh, const Triangle& t) {
  std::array<Vec3, 3> p{mesh.positions[t[0]], mesh.positions[t[1]], mesh.positions[t[2]]};
  const auto less = [](const Vec3& a, const Vec3& b) { return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z); };
  int first = 0;
  for (int i = 1; i < 3; ++i) {
    if (less(p[i], p[first])) first = i;
  }
  return {p[first], p[(first + 1) % 3], p[(first + 2) % 3]};
}

struct TriangleKeyHash {
  std::size_t operator()(const std::array<Vec3, 3>& key) const {
    std::size_t h = 0;
    for (const Vec3& p : key) {
      for (const double x : {p.x, p.y, p.z}) {
        std::uint64_t bits;
        const double y = x == 0 ? 0.0 : x;
        std::memcpy(&bits, &y, sizeof bits);
        h = (h ^ bits) * 0x9E3779B97F4A7C15ull;
      }
    }
    return h;
  }
};
struct TriangleKeyEqual {
  bool operator()(const std::array<Vec3, 3>& a, const std::array<Vec3, 3>& b) const {
    for (int i = 0; i < 3; ++i) {
      if (!(a[i].x == b[i].x && a[i].y == b[i].y && a[i].z == b[i].z)) return false;
    }
    return true;
  }
};

// The vertices whose position another vertex has too (one flag per vertex), or
// empty when every position is one vertex's.
std::vector<std::uint8_t> shared_positions(const Mesh& mesh) {
  std::vector<VertexIndex> order(mesh.positions.size());
  for (VertexIndex v = 0; v < order.size(); ++v) order[v] = v;
  const auto less = [&](VertexIndex a, VertexIndex b) {
    const Vec3& p = mesh.positions[a];
    const Vec3& q = mesh.positions[b];
    return std::tie(p.x, p.y, p.z) < std::tie(q.x, q.y, q.z);
  };
  std::sort(order.begin(), order.end(), less);
  std::vector<std::uint8_t> shared;
  for (std::size_t k = 1; k < order.size(); ++k) {
    if (less(order[k - 1], order[k])) continue;  // sorted: not less means equal (NaNs aside: not finite, refused before)
    if (shared.empty()) shared.assign(mesh.positions.size(), 0);
    shared[order[k - 1]] = shared[order[k]] = 1;
  }
  return shared;
}

// Marks as new (untrusted) every triangle with a corner whose position another
// vertex of the mesh shares (`shared`, from shared_positions). A valid mesh has
// no two vertices at one position (every vertex is used, and triangles around two
// vertices at one point meet there beyond any element they share), so in a mesh's
// trusted triangles and in the valid mesh they were found in, two corners are one
// vertex exactly when they are at one position: a pair of trusted triangles then
// shares the same corners in both, and triangles_intersect answers alike. Without
// this, two coincident copies of a trusted triangle, over different vertices,
// would be skipped as a trusted pair; so marked, they are tested (and found).
void untrust_shared_positions(const Mesh& mesh, std::span<const std::uint8_t> shared, std::vector<std::uint8_t>& is_new) {
  if (shared.empty()) return;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    for (const VertexIndex v : mesh.triangles[t]) {
      if (v < shared.size() && shared[v]) is_new[t] = 1;
    }
  }
}

// Groups of the new triangles whose pairs need no test: edge-connected new
// triangles with nearly parallel normals (a face the cut clipped and triangulated
// anew, a cap), each group kept only when triangles_embed_in_projection certifies,
// exactly, that no two of its triangles meet beyond what they share. The grouping
// is a guess in doubles and may be anything: only the certificate is trusted.
// One entry per triangle, no_embedded_group for a triangle in no certified group;
// empty when there is none.
std::vector<std::uint32_t> embedded_groups(const Mesh& mesh, const std::vector<std::uint8_t>& is_new) {
  constexpr std::size_t smallest_group = 3;  // a group of two saves one pair
  std::vector<Vec3> normal(mesh.triangles.size());
  std::vector<std::uint8_t> grouped(mesh.triangles.size(), 0);  // new, with a usable normal
  struct EdgeUse {
    VertexIndex low, high;
    std::uint32_t triangle;
  };
  std::vector<EdgeUse> uses;
  for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t) {
    if (!is_new[t]) continue;
    const Triangle& tri = mesh.triangles[t];
    const Vec3 n = cross(mesh.positions[tri[1]] - mesh.positions[tri[0]], mesh.positions[tri[2]] - mesh.positions[tri[0]]);
    const double length = std::sqrt(dot(n, n));
    if (!(length > 0) || !std::isfinite(length)) continue;
    normal[t] = n * (1 / length);
    grouped[t] = 1;
    for (int c = 0; c < 3; ++c) {
      const VertexIndex u = tri[c], v = tri[(c + 1) % 3];
      uses.push_back({std::min(u, v), std::max(u, v), t});
    }
  }
  if (uses.size() < 3 * smallest_group) return {};
  std::sort(uses.begin(), uses.end(), [](const EdgeUse& a, const EdgeUse& b) {
    return std::tie(a.low, a.high, a.triangle) < std::tie(b.low, b.high, b.triangle);
  });
  UnionFind sets(mesh.triangles.size());
  for (std::size_t k = 1; k < uses.size(); ++k) {
    const EdgeUse &a = uses[k - 1], &b = uses[k];
    if (a.low == b.low && a.high == b.high && dot(normal[a.triangle], normal[b.triangle]) > 1 - 1e-9) {
      sets.unite(a.triangle, b.triangle);
    }
  }
  // Each group's triangles, by a counting sort on the representative.
  std::vector<std::uint32_t> size(mesh.triangles.size(), 0);
  std::vector<std::uint32_t> root(mesh.triangles.size(), no_embedded_group);
  for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t) {
    if (grouped[t]) ++size[root[t] = sets.find(t)];
  }
  std::vector<std::uint32_t> start(mesh.triangles.size() + 1, 0);
  for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t) {
    start[t + 1] = start[t] + (size[t] >= smallest_group ? size[t] : 0);
  }
  if (start.back() == 0) return {};
  std::vector<std::uint32_t> members(start.back());
  {
    std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
    for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t) {
      if (root[t] != no_embedded_group && size[root[t]] >= smallest_group) members[fill[root[t]]++] = t;
    }
  }
  std::vector<std::uint32_t> embedded(mesh.triangles.size(), no_embedded_group);
  bool any = false;
  for (std::uint32_t r = 0; r < mesh.triangles.size(); ++r) {
    if (start[r + 1] == start[r]) continue;
    const std::span<const std::uint32_t> group(members.data() + start[r], start[r + 1] - start[r]);
    Vec3 sum;
    for (const std::uint32_t t : group) sum = sum + normal[t];
    const double ax = std::fabs(sum.x), ay = std::fabs(sum.y), az = std::fabs(sum.z);
    const int axis = ax >= ay && ax >= az ? 0 : ay >= az ? 1 : 2;
    if (!triangles_embed_in_projection(mesh.positions, mesh.triangles, group, axis)) continue;
    for (const std::uint32_t t : group) embedded[t] = r;
    any = true;
  }
  if (!any) return {};
  return embedded;
}

ValidationReport validate_against(const Mesh& mesh, const TrustedTriangles* trusted, const Plane* near,
                                  std::span<const std::uint8_t> exact_vertices) {
  if (!exact_vertices.empty() && exact_vertices.size() != mesh.positions.size()) {
    throw std::invalid_argument("validate_mesh_against: exact_vertices must hold one flag per vertex");
  }
  // A triangle of the trusted mesh is not flat: only the new ones are tested.
  std::vector<std::uint8_t> is_new(mesh.triangles.size(), 1);
  if (trusted) {
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
      const Triangle& tri = mesh.triangles[t];
      if (tri[0] < mesh.positions.size() && tri[1] < mesh.positions.size() && tri[2] < mesh.positions.size()) {
        is_new[t] = !trusted->contains(mesh, tri);
      }
    }
  }
  ValidationOptions without;
  without.check_self_intersections = false;
  ValidationReport report = validate_masked(mesh, without, &is_new);
  if (!report.valid()) return report;
  const bool use_exact = !exact_vertices.empty();
  const std::vector<std::uint8_t> shared = trusted || use_exact ? shared_positions(mesh) : std::vector<std::uint8_t>{};
  if (trusted) untrust_shared_positions(mesh, shared, is_new);
  // Two triangles whose corners are all exact (flagged, each at a position of
  // its own) are two triangles of an embedded surface (the caller's
  // precondition): they meet only in what they share. A pair is therefore
  // tested only when one triangle is new and one is not all exact ("moved"):
  // the new moved ones against every triangle (`tested`), and the new exact
  // ones against the trusted moved ones (below).
  std::vector<std::uint8_t> moved;
  if (use_exact) {
    moved.assign(mesh.triangles.size(), 0);
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
      for (const VertexIndex v : mesh.triangles[t]) {
        if (!exact_vertices[v] || (!shared.empty() && shared[v])) moved[t] = 1;
      }
    }
  }
  std::vector<std::uint8_t> new_and_moved;
  if (use_exact) {
    new_and_moved = is_new;
    for (std::size_t t = 0; t < new_and_moved.size(); ++t) new_and_moved[t] &= moved[t];
  }
  const std::vector<std::uint8_t>& tested = use_exact ? new_and_moved : is_new;
  std::vector<std::uint32_t> all;  // the triangles searched
  all.reserve(mesh.triangles.size());
  // With a plane the new triangles lie along, only triangles within the slab the
  // new ones span can meet them: each triangle's range of n·p + d, in doubles
  // widened by a bound on their rounding, against the new ones'.
  std::vector<std::array<double, 2>> range;
  double largest_term = 0;  // the largest |n_x x| + |n_y y| + |n_z z| + |d| over the vertices
  if (near) {
    range.resize(mesh.triangles.size());
    double largest = 0;
    for (const Vec3& p : mesh.positions) {
      largest = std::max(largest, std::fabs(near->normal.x * p.x) + std::fabs(near->normal.y * p.y) +
                                      std::fabs(near->normal.z * p.z) + std::fabs(near->offset));
    }
    largest_term = largest;
    const double slack = 8 * 0x1p-53 * largest;
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
      double lo = INFINITY, hi = -INFINITY;
      for (const VertexIndex v : mesh.triangles[t]) {
        const double d = dot(near->normal, mesh.positions[v]) + near->offset;
        lo = std::min(lo, d);
        hi = std::max(hi, d);
      }
      range[t] = {lo - slack, hi + slack};
    }
  }
  report.self_intersections_checked = true;
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  // Tests the triangles of `members` flagged in `tested` against every other
  // member whose box meets theirs, exactly (intersecting_pairs_with: a hashed
  // grid, the same pairs as CGAL's box intersection of the tested boxes against
  // the members').
  const std::vector<std::uint32_t> embedded = embedded_groups(mesh, is_new);
  const auto search = [&](const std::vector<std::uint32_t>& members, const std::vector<std::uint8_t>& these) {
    const std::vector<TrianglePair> found =
        intersecting_pairs_with(mesh.positions, mesh.triangles, members, these, embedded);
    pairs.insert(pairs.end(), found.begin(), found.end());
  };
  if (!near) {
    all.resize(mesh.triangles.size());
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) all[t] = static_cast<std::uint32_t>(t);
    search(all, tested);
  } else {
    // The new triangles split in two: those flat along the plane (the cap, all
    // corners within a rounding's reach of it: their ranges inside [-flat, flat])
    // and the others (the faces the cut clipped, which may reach far from it).
    // The flat ones lie in the slab Z their ranges span, a few ulps thick; a
    // triangle whose range misses Z cannot meet them, so they are tested only
    // against the triangles that reach Z, and the others against the slab their
    // own ranges span. Every pair with a new triangle whose boxes meet is still
    // tested, except pairs of a flat new triangle and a triangle provably off Z.
    const double flat = 0x1p-36 * largest_term;
    std::vector<std::uint8_t> is_flat(mesh.triangles.size(), 0), is_side(mesh.triangles.size(), 0);
    double flat_lo = INFINITY, flat_hi = -INFINITY, side_lo = INFINITY, side_hi = -INFINITY;
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
      if (!tested[t]) continue;
      if (range[t][0] >= -flat && range[t][1] <= flat) {
        is_flat[t] = 1;
        flat_lo = std::min(flat_lo, range[t][0]);
        flat_hi = std::max(flat_hi, range[t][1]);
      } else {
        is_side[t] = 1;
        side_lo = std::min(side_lo, range[t][0]);
        side_hi = std::max(side_hi, range[t][1]);
      }
    }
    const auto meets = [&](std::size_t t, double lo, double hi) { return !(range[t][1] < lo || range[t][0] > hi); };
    std::vector<std::uint32_t> near_flat;
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
      const bool side_reach = meets(t, side_lo, side_hi), flat_reach = meets(t, flat_lo, flat_hi);
      if (!side_reach && !flat_reach && !tested[t]) continue;
      // The side triangles against every triangle in their slab but the flat ones;
      // the flat ones against every triangle reaching Z, the side ones included
      // (most side triangles, those of a clipped face away from the cut, do not).
      if ((side_reach || is_side[t]) && !is_flat[t]) all.push_back(static_cast<std::uint32_t>(t));
      if (flat_reach || is_flat[t]) near_flat.push_back(static_cast<std::uint32_t>(t));
    }
    search(all, is_side);
    search(near_flat, is_flat);
  }
  if (use_exact && trusted) {
    // The new exact triangles against the trusted moved ones, whose pairs with
    // each other the trusted mesh settles (one group).
    std::vector<std::uint32_t> members, group(mesh.triangles.size(), no_embedded_group);
    std::vector<std::uint8_t> trusted_moved(mesh.triangles.size(), 0);
    bool any_new_exact = false;
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
      if (is_new[t] == moved[t]) continue;  // new and moved (tested above), or trusted and exact
      members.push_back(static_cast<std::uint32_t>(t));
      if (moved[t]) {
        trusted_moved[t] = 1;
        group[t] = 0;
      } else {
        any_new_exact = true;
      }
    }
    if (any_new_exact) {
      const std::vector<TrianglePair> found =
          intersecting_pairs_with(mesh.positions, mesh.triangles, members, trusted_moved, group);
      pairs.insert(pairs.end(), found.begin(), found.end());
    }
  }
  std::sort(pairs.begin(), pairs.end());
  append_self_intersections(report, pairs);
  // Rounding can move a thin cavity out of its solid, or turn a thin shell inside
  // out, without any two triangles meeting: only the nesting shows it.
  if (report.valid()) append(report, DefectKind::misnested_shell, misnested_shells(mesh));
  return report;
}

}  // namespace

namespace {

// A triangle key's slot: its corners' position hashes (the kernel's one,
// position_key.hpp, which mixes the low bits doubles often leave zero),
// rotated apart so that the corners' order counts.
std::size_t slot_hash(const std::array<Vec3, 3>& key) {
  const kernel_detail::PositionKeyHash hash;
  return hash(kernel_detail::key_of(key[0])) ^ std::rotl(hash(kernel_detail::key_of(key[1])), 21) ^
         std::rotl(hash(kernel_detail::key_of(key[2])), 42);
}

}  // namespace

TrustedTriangles::TrustedTriangles(const Mesh& mesh) {
  keys_.reserve(mesh.triangles.size());
  // At most half full, so a probe ends within a few slots.
  slots_.assign(std::bit_ceil(std::max<std::size_t>(16, 2 * mesh.triangles.size())), empty_slot);
  const std::size_t mask = slots_.size() - 1;
  for (const Triangle& t : mesh.triangles) {
    std::array<Vec3, 3> key = triangle_key(mesh, t);
    for (std::size_t slot = slot_hash(key) & mask;; slot = (slot + 1) & mask) {
      if (slots_[slot] == empty_slot) {
        slots_[slot] = static_cast<std::uint32_t>(keys_.size());
        keys_.push_back(key);
        break;
      }
      if (TriangleKeyEqual{}(keys_[slots_[slot]], key)) break;  // the same triangle again
    }
  }
}

bool TrustedTriangles::contains(const Mesh& mesh, const Triangle& t) const {
  if (keys_.empty()) return false;
  const std::array<Vec3, 3> key = triangle_key(mesh, t);
  const std::size_t mask = slots_.size() - 1;
  for (std::size_t slot = slot_hash(key) & mask; slots_[slot] != empty_slot; slot = (slot + 1) & mask) {
    if (TriangleKeyEqual{}(keys_[slots_[slot]], key)) return true;
  }
  return false;
}

const TrustedTriangles& TrustedTrianglesOnce::get() const {
  std::call_once(made_, [this] { index_ = TrustedTriangles(*mesh_); });
  return index_;
}

ValidationReport validate_mesh_against(const Mesh& mesh, const Mesh* trusted, const Plane* near,
                                       std::span<const std::uint8_t> exact_vertices) {
  if (!trusted) return validate_against(mesh, nullptr, near, exact_vertices);
  const TrustedTriangles index(*trusted);
  return validate_against(mesh, &index, near, exact_vertices);
}

ValidationReport validate_mesh_against(const Mesh& mesh, const TrustedTriangles& trusted, const Plane* near,
                                       std::span<const std::uint8_t> exact_vertices) {
  return validate_against(mesh, &trusted, near, exact_vertices);
}

namespace {

// The range of a plane's values over a triangle's corners, widened by the
// error bound of evaluating n.x + d in doubles: each corner's value is four
// roundings from the exact one (three products, three sums, at most four on any
// term's path), so |error| <= gamma_4 (|n_x x| + |n_y y| + |n_z z| + |d|) with
// gamma_4 < 2^-50.9; 2^-49 of that sum also covers the roundings of the sum and
// of the widening itself, and 2^-1000 the products that underflow. Inputs are
// below 2^500 (checked by the caller), so nothing overflows. A linear function
// takes every value it has on the triangle within its corners' range, so two
// triangles with disjoint ranges share no point.
struct ValueRange {
  double lo, hi;
};

ValueRange value_range(const Plane& plane, std::span<const Vec3> positions, const Triangle& tri) {
  ValueRange range{INFINITY, -INFINITY};
  for (const VertexIndex v : tri) {
    const Vec3& q = positions[v];
    const double x = plane.normal.x * q.x, y = plane.normal.y * q.y, z = plane.normal.z * q.z;
    const double value = x + y + z + plane.offset;
    const double error = 0x1p-49 * (std::fabs(x) + std::fabs(y) + std::fabs(z) + std::fabs(plane.offset)) + 0x1p-1000;
    range.lo = std::min(range.lo, value - error);
    range.hi = std::max(range.hi, value + error);
  }
  return range;
}

bool ranges_meet(const ValueRange& a, const ValueRange& b) { return !(a.hi < b.lo || b.hi < a.lo); }

bool below_two_to_500(double x) { return std::isless(std::fabs(x), 0x1p500); }

// Calls `test(i, j)` for every pair of triangles across parts whose boxes meet
// and which `regions`' planes do not keep apart (the argument at PartRegions):
// the trusted triangles (part_of[t] their part, region[t] their region or
// no_region) grouped by (part, region); the pairs of groups of different parts
// whose bounding boxes meet; for each, the triangles of each group whose value
// range over the groups' plane meets the other group's, then those pairs whose
// boxes and ranges meet. Without a plane, every pair whose boxes meet.
template <typename Test>
void test_across_regions(const Mesh& mesh, std::span<const TriangleBox> boxes, std::span<const std::uint32_t> part_of,
                         std::span<const std::uint32_t> region, std::uint32_t untrusted, const PartRegions& regions,
                         bool planes_usable, Test&& test) {
  constexpr std::uint32_t no_region = std::numeric_limits<std::uint32_t>::max();
  struct Member {
    std::uint32_t part, region, triangle;
  };
  struct Group {
    std::uint32_t part, region, begin, end;
    CGAL::Bbox_3 box;
  };
  thread_local std::vector<Member> members;
  thread_local std::vector<Group> groups;
  thread_local std::vector<TriangleBox> group_boxes, near_a, near_b;
  thread_local std::vector<ValueRange> range_of;  // per triangle, for the current pair of groups
  members.clear();
  for (std::size_t t = 0; t < part_of.size(); ++t) {
    if (part_of[t] != untrusted) members.push_back({part_of[t], region[t], static_cast<std::uint32_t>(t)});
  }
  std::sort(members.begin(), members.end(), [](const Member& a, const Member& b) {
    return std::tie(a.part, a.region, a.triangle) < std::tie(b.part, b.region, b.triangle);
  });
  groups.clear();
  for (std::uint32_t i = 0; i < members.size();) {
    Group group{members[i].part, members[i].region, i, i, CGAL::Bbox_3()};
    for (; i < members.size() && members[i].part == group.part && members[i].region == group.region; ++i) {
      group.box += boxes[members[i].triangle].bbox();
    }
    group.end = i;
    groups.push_back(group);
  }
  range_of.resize(mesh.triangles.size());
  const auto pair_of_groups = [&](std::size_t ga, std::size_t gb) {
    const Group &a = groups[ga], &b = groups[gb];
    if (a.part == b.part) return;
    std::optional<Plane> plane;
    if (planes_usable && a.region != no_region && b.region != no_region) {
      plane = regions.plane_between(a.region, b.region);
      if (plane && !(below_two_to_500(plane->normal.x) && below_two_to_500(plane->normal.y) &&
                     below_two_to_500(plane->normal.z) && below_two_to_500(plane->offset))) {
        plane.reset();
      }
    }
    near_a.clear();
    near_b.clear();
    if (plane) {
      ValueRange span_a{INFINITY, -INFINITY}, span_b{INFINITY, -INFINITY};
      for (std::uint32_t i = a.begin; i < a.end; ++i) {
        const std::uint32_t t = members[i].triangle;
        range_of[t] = value_range(*plane, mesh.positions, mesh.triangles[t]);
        span_a = {std::min(span_a.lo, range_of[t].lo), std::max(span_a.hi, range_of[t].hi)};
      }
      for (std::uint32_t i = b.begin; i < b.end; ++i) {
        const std::uint32_t t = members[i].triangle;
        range_of[t] = value_range(*plane, mesh.positions, mesh.triangles[t]);
        span_b = {std::min(span_b.lo, range_of[t].lo), std::max(span_b.hi, range_of[t].hi)};
      }
      for (std::uint32_t i = a.begin; i < a.end; ++i) {
        const std::uint32_t t = members[i].triangle;
        if (ranges_meet(range_of[t], span_b)) near_a.push_back(boxes[t]);
      }
      for (std::uint32_t i = b.begin; i < b.end; ++i) {
        const std::uint32_t t = members[i].triangle;
        if (ranges_meet(range_of[t], span_a)) near_b.push_back(boxes[t]);
      }
    } else {
      for (std::uint32_t i = a.begin; i < a.end; ++i) near_a.push_back(boxes[members[i].triangle]);
      for (std::uint32_t i = b.begin; i < b.end; ++i) near_b.push_back(boxes[members[i].triangle]);
    }
    const auto maybe_test = [&](std::size_t i, std::size_t j) {
      if (!plane || ranges_meet(range_of[i], range_of[j])) test(i, j);
    };
    if (near_a.size() * near_b.size() <= 1024) {
      for (const TriangleBox& x : near_a) {
        for (const TriangleBox& y : near_b) {
          if (CGAL::do_overlap(x.bbox(), y.bbox())) maybe_test(x.handle(), y.handle());
        }
      }
    } else {
      CGAL::box_intersection_d(
          near_a.begin(), near_a.end(), near_b.begin(), near_b.end(),
          [&](const TriangleBox& x, const TriangleBox& y) { maybe_test(x.handle(), y.handle()); }, std::ptrdiff_t{10},
          CGAL::Box_intersection_d::CLOSED);
    }
  };
  if (groups.size() <= 64) {
    for (std::size_t ga = 0; ga < groups.size(); ++ga) {
      for (std::size_t gb = ga + 1; gb < groups.size(); ++gb) {
        if (CGAL::do_overlap(groups[ga].box, groups[gb].box)) pair_of_groups(ga, gb);
      }
    }
  } else {
    group_boxes.clear();
    for (std::size_t g = 0; g < groups.size(); ++g) group_boxes.emplace_back(groups[g].box, g);
    CGAL::box_self_intersection_d(
        group_boxes.begin(), group_boxes.end(),
        [&](const TriangleBox& x, const TriangleBox& y) { pair_of_groups(x.handle(), y.handle()); },
        std::ptrdiff_t{10}, CGAL::Box_intersection_d::CLOSED);
  }
  constexpr std::size_t kept = std::size_t{1} << 16;  // released past this, as validate_mesh_of_parts' buffers
  if (range_of.capacity() > kept) range_of = {};
  if (members.capacity() > kept) members = {};
}

}  // namespace

ValidationReport validate_mesh_of_parts(const Mesh& mesh, std::span<const Mesh* const> parts,
                                        const PartRegions* regions, bool topology_sound,
                                        std::span<const std::uint64_t> origins) {
  constexpr std::uint32_t untrusted = std::numeric_limits<std::uint32_t>::max();
  // Reused buffers: a hierarchy certifies thousands of unions, and fresh large
  // allocations each cost their pages' zeroing again. Those grown past a few
  // megabytes (the few largest unions) are released at the end.
  thread_local std::vector<std::uint32_t> part_of;  // per triangle: the part it is found in, or `untrusted`
  thread_local std::vector<std::uint32_t> region;   // per triangle, with `regions`: its region in that part
  thread_local std::vector<std::uint8_t> is_new;
  thread_local std::vector<TriangleBox> boxes, fresh, all, tested, against;
  thread_local std::vector<std::size_t> first, by_part, fill;
  // The parts' triangles by key: an open-addressed table of (part << 32 | triangle),
  // the key recomputed from the part's mesh (a node-based map allocated a node
  // per triangle: most of this function's own time at 10^4 Voronoi sites).
  thread_local std::vector<std::uint64_t> known;
  struct Release {  // at every return
    ~Release() {
      constexpr std::size_t kept = std::size_t{1} << 16;  // triangles
      if (part_of.capacity() > kept) {
        part_of = {};
        region = {};
        is_new = {};
        first = {};
        by_part = {};
        fill = {};
      }
      for (std::vector<TriangleBox>* v : {&boxes, &fresh, &all, &tested, &against}) {
        if (v->capacity() > kept) *v = {};
      }
      if (known.capacity() > 4 * kept) known = {};
    }
  } release;
  // Each triangle's part: the part its origin names if that part has it (same
  // corner positions, turning the same way), else the first part whose mesh
  // has it.
  part_of.assign(mesh.triangles.size(), untrusted);
  region.assign(regions ? mesh.triangles.size() : 0, std::numeric_limits<std::uint32_t>::max());
  const auto take = [&](std::size_t t, std::uint32_t k, std::uint32_t index) {
    part_of[t] = k;
    if (regions) {
      const std::span<const std::uint32_t> given =
          k < regions->region_of.size() ? regions->region_of[k] : std::span<const std::uint32_t>{};
      if (given.size() == parts[k]->triangles.size()) region[t] = given[index];
    }
  };
  const auto in_range = [&](const Mesh& m, const Triangle& tri) {
    return tri[0] < m.positions.size() && tri[1] < m.positions.size() && tri[2] < m.positions.size();
  };
  std::size_t unplaced = mesh.triangles.size();
  if (origins.size() == mesh.triangles.size()) {
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
      const auto k = static_cast<std::uint32_t>(origins[t] >> 32);
      const auto index = static_cast<std::uint32_t>(origins[t] & 0xFFFFFFFFu);
      if (k >= parts.size() || !parts[k] || index >= parts[k]->triangles.size()) continue;
      const Triangle& tri = mesh.triangles[t];
      const Triangle& theirs = parts[k]->triangles[index];
      if (!in_range(mesh, tri) || !in_range(*parts[k], theirs)) continue;
      if (!TriangleKeyEqual{}(triangle_key(mesh, tri), triangle_key(*parts[k], theirs))) continue;
      take(t, k, index);
      --unplaced;
    }
  }
  if (unplaced > 0) {
    std::size_t total = 0;
    for (const Mesh* part : parts) total += part ? part->triangles.size() : 0;
    std::size_t capacity = 16;
    while (capacity < 2 * total) capacity *= 2;  // at most half full
    constexpr std::uint64_t empty = std::numeric_limits<std::uint64_t>::max();
    known.assign(capacity, empty);
    const TriangleKeyHash hash;
    const TriangleKeyEqual equal;
    const auto key_in = [&](std::uint64_t slot) {
      const Mesh& part = *parts[slot >> 32];
      return triangle_key(part, part.triangles[slot & 0xFFFFFFFFu]);
    };
    // The slot holding `key`, or the empty one where it would go.
    const auto find = [&](const std::array<Vec3, 3>& key) {
      std::size_t at = hash(key) & (capacity - 1);
      while (known[at] != empty && !equal(key_in(known[at]), key)) at = (at + 1) & (capacity - 1);
      return at;
    };
    for (std::uint32_t k = 0; k < parts.size(); ++k) {
      if (!parts[k]) continue;
      for (std::uint32_t t = 0; t < parts[k]->triangles.size(); ++t) {
        const std::size_t at = find(triangle_key(*parts[k], parts[k]->triangles[t]));
        if (known[at] == empty) known[at] = (std::uint64_t{k} << 32) | t;  // the first part keeps it
      }
    }
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
      const Triangle& tri = mesh.triangles[t];
      if (part_of[t] != untrusted || !in_range(mesh, tri)) continue;
      const std::size_t at = find(triangle_key(mesh, tri));
      if (known[at] == empty) continue;
      take(t, static_cast<std::uint32_t>(known[at] >> 32), static_cast<std::uint32_t>(known[at] & 0xFFFFFFFFu));
    }
  }
  // A triangle of a valid part is not flat: only the new ones are tested.
  is_new.resize(mesh.triangles.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) is_new[t] = part_of[t] == untrusted;
  ValidationOptions without;
  without.check_self_intersections = false;
  const bool sound = topology_sound && std::all_of(mesh.positions.begin(), mesh.positions.end(),
                                                   [](const Vec3& p) { return is_finite(p); });
  ValidationReport report = sound ? validate_sound_topology(mesh, without, &is_new) : validate_masked(mesh, without, &is_new);
  if (!report.valid()) return report;
  untrust_shared_positions(mesh, shared_positions(mesh), is_new);
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    if (is_new[t]) part_of[t] = untrusted;
  }
  report.self_intersections_checked = true;

  // Which pairs are tested (the argument in validate.hpp): every pair whose boxes
  // meet, except two triangles of one part. The new triangles are tested against
  // every triangle; the triangles of part k against those of the later parts,
  // each side first narrowed to the triangles whose boxes meet the other side's
  // bounding box (a triangle missing that box meets none of its triangles).
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  const auto test = [&](std::size_t i, std::size_t j) {
    if (triangles_intersect(mesh.positions, mesh.triangles[i], mesh.triangles[j])) {
      pairs.emplace_back(std::min(i, j), std::max(i, j));
    }
  };
  boxes.clear();
  fresh.clear();
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    boxes.push_back(box_of(mesh.positions, mesh.triangles[t], t));
    if (is_new[t]) fresh.push_back(boxes.back());
  }
  if (!fresh.empty()) {
    all.assign(boxes.begin(), boxes.end());
    CGAL::box_intersection_d(
        fresh.begin(), fresh.end(), all.begin(), all.end(),
        [&](const TriangleBox& a, const TriangleBox& b) {
          const std::size_t i = a.handle(), j = b.handle();
          if (i == j || (is_new[j] && j < i)) return;  // each pair of new triangles once
          test(i, j);
        },
        std::ptrdiff_t{10}, CGAL::Box_intersection_d::CLOSED);
  }
  if (regions) {
    const bool planes_usable =
        regions->plane_between && std::all_of(mesh.positions.begin(), mesh.positions.end(), [](const Vec3& p) {
          return below_two_to_500(p.x) && below_two_to_500(p.y) && below_two_to_500(p.z);
        });
    test_across_regions(mesh, boxes, part_of, region, untrusted, *regions, planes_usable, test);
    std::sort(pairs.begin(), pairs.end());
    append_self_intersections(report, pairs);
    if (report.valid()) append(report, DefectKind::misnested_shell, misnested_shells(mesh));
    return report;
  }
  // The parts' triangles, grouped by part (in mesh order within a part), and
  // each part's bounding box.
  const std::size_t part_count = parts.size();
  first.assign(part_count + 1, 0);
  for (const std::uint32_t k : part_of) {
    if (k != untrusted) ++first[k + 1];
  }
  for (std::size_t k = 0; k < part_count; ++k) first[k + 1] += first[k];
  by_part.resize(first.back());
  {
    fill.assign(first.begin(), first.end() - 1);
    for (std::size_t t = 0; t < part_of.size(); ++t) {
      if (part_of[t] != untrusted) by_part[fill[part_of[t]]++] = t;
    }
  }
  const auto bound = [&](std::span<const std::size_t> triangles) {
    CGAL::Bbox_3 box;  // empty
    for (const std::size_t t : triangles) box += boxes[t].bbox();
    return box;
  };
  const auto meets = [](const CGAL::Bbox_3& a, const CGAL::Bbox_3& b) {
    for (int axis = 0; axis < 3; ++axis) {
      if (a.max(axis) < b.min(axis) || b.max(axis) < a.min(axis)) return false;
    }
    return true;
  };
  const auto triangles_of = [&](std::size_t k) { return std::span<const std::size_t>(by_part).subspan(first[k], first[k + 1] - first[k]); };
  std::vector<CGAL::Bbox_3> part_box(part_count);
  for (std::size_t k = 0; k < part_count; ++k) part_box[k] = bound(triangles_of(k));
  for (std::size_t k = 0; k + 1 < part_count; ++k) {
    if (first[k + 1] == first[k]) continue;
    against.clear();
    for (std::size_t l = k + 1; l < part_count; ++l) {
      if (first[l + 1] == first[l] || !meets(part_box[k], part_box[l])) continue;
      for (const std::size_t t : triangles_of(l)) {
        if (meets(boxes[t].bbox(), part_box[k])) against.push_back(boxes[t]);
      }
    }
    if (against.empty()) continue;
    CGAL::Bbox_3 reach;
    for (const TriangleBox& b : against) reach += b.bbox();
    tested.clear();
    for (const std::size_t t : triangles_of(k)) {
      if (meets(boxes[t].bbox(), reach)) tested.push_back(boxes[t]);
    }
    if (tested.empty()) continue;
    CGAL::box_intersection_d(
        tested.begin(), tested.end(), against.begin(), against.end(),
        [&](const TriangleBox& a, const TriangleBox& b) { test(a.handle(), b.handle()); }, std::ptrdiff_t{10},
        CGAL::Box_intersection_d::CLOSED);
  }
  std::sort(pairs.begin(), pairs.end());
  append_self_intersections(report, pairs);
  if (report.valid()) append(report, DefectKind::misnested_shell, misnested_shells(mesh));
  return report;
}

bool is_closed_oriented_manifold(const Mesh& mesh) { return closed_oriented_manifold(mesh); }

bool certify_star_shaped(const Mesh& mesh, const Vec3& centre) {
  return kernel_detail::faces_away_from(mesh, centre) && kernel_detail::covers_once(mesh, centre);
}

// Why one ray suffices. Every triangle strictly faces away from the centre c,
// so the radial projection from c maps each onto a spherical triangle,
// preserving orientation; across an edge the two triangles (the edge used once
// each way) land on the two sides of its arc, and around a vertex the ring's
// image winds k >= 1 times (each step turns by an angle in (0, pi)). The
// projection of the closed surface is then a branched covering of the sphere,
// of some degree d >= 1 for each component, branched k-fold at a vertex whose
// ring winds k times. Over a point of the sphere that is no image of an edge
// or a vertex, the triangles whose cones hold it number the sum of the
// components' degrees. When that is 1 there is one component, of degree 1,
// which no vertex can branch (a k-fold branch point has k preimages nearby):
// the projection is one-to-one, the surface embedded and star-shaped around c,
// exactly what every ring winding once (winds_once_around) shows, at 1-3
// orientations a triangle where that walk takes three and an edge lookup.
std::optional<bool> kernel_detail::covered_once_along_a_ray(const Mesh& mesh, const Vec3& centre) {
  using Point = CGAL::Epick::Point_3;
  const auto point = [](const Vec3& p) { return Point(p.x, p.y, p.z); };
  const Point c = point(centre);
  // Whether the ray from c through `target` runs inside triangle t's cone
  // (positive), outside it (negative), or along its boundary (zero): for a
  // triangle facing away, the cone is where the three planes through c and an
  // edge all have the target on their positive side.
  const auto in_cone = [&](const Triangle& t, const Point& target) {
    bool on_boundary = false;
    for (int k = 0; k < 3; ++k) {
      const CGAL::Orientation side =
          CGAL::orientation(c, point(mesh.positions[t[k]]), point(mesh.positions[t[(k + 1) % 3]]), target);
      if (side == CGAL::NEGATIVE) return CGAL::NEGATIVE;
      on_boundary |= side == CGAL::COPLANAR;
    }
    return on_boundary ? CGAL::COPLANAR : CGAL::POSITIVE;
  };
  // The ray: through a triangle's centroid (rounded, then tested exactly),
  // from the first few triangles whose rounded centroid lands inside its cone.
  constexpr std::size_t tries = 4;
  for (std::size_t first = 0; first < std::min(tries, mesh.triangles.size()); ++first) {
    const Triangle& t0 = mesh.triangles[first];
    const Vec3 a = mesh.positions[t0[0]], b = mesh.positions[t0[1]], d = mesh.positions[t0[2]];
    const Point target = point({(a.x + b.x + d.x) / 3, (a.y + b.y + d.y) / 3, (a.z + b.z + d.z) / 3});
    if (in_cone(t0, target) != CGAL::POSITIVE) continue;
    std::size_t covering = 0;
    for (const Triangle& t : mesh.triangles) {
      const CGAL::Orientation side = in_cone(t, target);
      if (side == CGAL::COPLANAR) return std::nullopt;  // along an edge's image: not a regular point
      if (side == CGAL::POSITIVE && ++covering > 1) return false;
    }
    return covering == 1;
  }
  return std::nullopt;
}

bool kernel_detail::covers_once(const Mesh& mesh, const Vec3& centre) {
  // Every vertex used, as the walk around each vertex requires.
  thread_local std::vector<std::uint8_t> used;
  used.assign(mesh.positions.size(), 0);
  for (const Triangle& t : mesh.triangles) {
    for (const VertexIndex v : t) used[v] = 1;
  }
  if (std::find(used.begin(), used.end(), 0) != used.end()) return false;
  if (const std::optional<bool> once = covered_once_along_a_ray(mesh, centre)) return *once;
  return winds_once_around(mesh, centre);
}

bool kernel_detail::faces_away_from(const Mesh& mesh, const Vec3& centre) {
  using Point = CGAL::Epick::Point_3;
  const auto point = [](const Vec3& p) { return Point(p.x, p.y, p.z); };
  const Point c = point(centre);
  for (const Triangle& t : mesh.triangles) {
    if (CGAL::orientation(point(mesh.positions[t[0]]), point(mesh.positions[t[1]]), point(mesh.positions[t[2]]), c) !=
        CGAL::NEGATIVE) {
      return false;
    }
  }
  return true;
}

bool kernel_detail::winds_once_around(const Mesh& mesh, const Vec3& centre) {
  using Point = CGAL::Epick::Point_3;
  const auto point = [](const Vec3& p) { return Point(p.x, p.y, p.z); };
  const Point c = point(centre);
  const std::size_t n = mesh.positions.size();
  // The triangles around each vertex, in order: for triangle (v, a, b) the next is
  // the one holding the directed edge (v, b). Found in v's own out-edges, as
  // (target << 32 | triangle), gathered by a counting sort by source and sorted
  // per vertex: a binary search in a short contiguous list, where a hash map of
  // every directed edge cost a cache miss per insertion and per step (about half
  // of certifying a hemisphere of the 1.3 M-triangle sphere).
  thread_local std::vector<std::uint32_t> first_out, some_triangle;
  thread_local std::vector<std::uint64_t> out;
  if (3 * mesh.triangles.size() > std::numeric_limits<std::uint32_t>::max()) return false;
  first_out.assign(n + 1, 0);
  some_triangle.assign(n, std::numeric_limits<std::uint32_t>::max());
  for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t) {
    for (const VertexIndex v : mesh.triangles[t]) {
      ++first_out[v + 1];
      some_triangle[v] = t;
    }
  }
  for (std::size_t v = 0; v < n; ++v) first_out[v + 1] += first_out[v];
  out.resize(3 * mesh.triangles.size());
  {
    thread_local std::vector<std::uint32_t> fill;
    fill.assign(first_out.begin(), first_out.end() - 1);
    for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t) {
      const Triangle& tri = mesh.triangles[t];
      for (int k = 0; k < 3; ++k) out[fill[tri[k]]++] = (std::uint64_t{tri[(k + 1) % 3]} << 32) | t;
    }
  }
  // Each list is in triangle order (filled so); a long one is sorted for a
  // binary search, a short one (a convex piece's vertices have a handful) is
  // scanned, which finds the same triangle: the first holding the edge.
  constexpr std::uint32_t scanned = 16;
  for (std::size_t v = 0; v < n; ++v) {
    if (first_out[v + 1] - first_out[v] > scanned) std::sort(out.begin() + first_out[v], out.begin() + first_out[v + 1]);
  }
  // The triangle holding the directed edge (v, w), the first if several, or none.
  constexpr std::uint32_t none = std::numeric_limits<std::uint32_t>::max();
  const auto triangle_of_edge = [&](VertexIndex v, VertexIndex w) {
    const auto begin = out.begin() + first_out[v], end = out.begin() + first_out[v + 1];
    if (end - begin <= scanned) {
      for (auto it = begin; it != end; ++it) {
        if ((*it >> 32) == w) return static_cast<std::uint32_t>(*it);
      }
      return none;
    }
    const auto it = std::lower_bound(begin, end, std::uint64_t{w} << 32);
    return it != end && (*it >> 32) == w ? static_cast<std::uint32_t>(*it) : none;
  };
  const auto corner_of = [&](std::uint32_t t, VertexIndex v) {
    const Triangle& tri = mesh.triangles[t];
    return tri[0] == v ? 0 : tri[1] == v ? 1 : 2;
  };
  for (VertexIndex v = 0; v < n; ++v) {
    if (some_triangle[v] == none) return false;
    const Point pv = point(mesh.positions[v]);
    // The ring w_1 .. w_k around v. Each step w_i -> w_{i+1} turns by an angle in
    // (0, pi) about the axis centre -> v (its triangle faces away from the centre).
    // The ring winds once exactly when, with s_i the side of w_i of the plane
    // through the axis and w_1, exactly one step goes from s < 0 to s >= 0 (the
    // last one, back to w_1, included).
    const std::uint32_t first = some_triangle[v];
    const Triangle& t0 = mesh.triangles[first];
    const VertexIndex w1 = t0[(corner_of(first, v) + 1) % 3];
    const Point p1 = point(mesh.positions[w1]);
    std::uint32_t t = first;
    int crossings = 0;
    CGAL::Orientation previous = CGAL::COPLANAR;  // s_1 = 0: w_1 is on the plane
    for (std::size_t steps = 0;; ++steps) {
      if (steps > mesh.triangles.size()) return false;
      const Triangle& tri = mesh.triangles[t];
      const VertexIndex next = tri[(corner_of(t, v) + 2) % 3];
      const CGAL::Orientation s =
          next == w1 ? CGAL::COPLANAR : CGAL::orientation(c, pv, p1, point(mesh.positions[next]));
      if (previous == CGAL::NEGATIVE && s != CGAL::NEGATIVE) ++crossings;
      previous = s;
      const std::uint32_t found = triangle_of_edge(v, next);
      if (found == none) return false;
      t = found;
      if (t == first) break;
    }
    if (crossings != 1) return false;
  }
  return true;
}

}  // namespace shatter
