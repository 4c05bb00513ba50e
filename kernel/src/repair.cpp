#include "shatter/kernel/repair.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/border.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/repair_degeneracies.h>
#include <CGAL/Polygon_mesh_processing/stitch_borders.h>
#include <CGAL/Polygon_mesh_processing/triangulate_hole.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/boost/graph/Euler_operations.h>
#include <CGAL/boost/graph/helpers.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <iterator>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <span>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "shatter/kernel/index_map.hpp"
#include "shatter/kernel/position_key.hpp"
#include "shatter/kernel/predicates.hpp"
#include "repair_touching.hpp"
#include "shatter/kernel/arrangement.hpp"
#include "shatter/kernel/union_find.hpp"
#include "shatter/kernel/mass.hpp"
#include "shatter/kernel/self_intersections.hpp"
#include "shatter/kernel/shells.hpp"
#include "shatter/kernel/validate.hpp"

namespace shatter {
namespace {

namespace PMP = CGAL::Polygon_mesh_processing;
using CgalPoint = CGAL::Epick::Point_3;
using SurfaceMesh = CGAL::Surface_mesh<CgalPoint>;
using FaceIndex = SurfaceMesh::Face_index;
using HalfedgeIndex = SurfaceMesh::Halfedge_index;
using SmVertex = SurfaceMesh::Vertex_index;

constexpr std::int64_t no_origin = -1;

std::string plural(std::size_t count, const char* singular, const char* plural_form) {
  return std::to_string(count) + " " + (count == 1 ? singular : plural_form);
}

// --- Exact position keys (as the readers weld: -0.0 equals +0.0) ------------------

using kernel_detail::PositionKey;
using kernel_detail::PositionKeyHash;
using kernel_detail::key_of;

// A number in a report line: six significant digits.
std::string number_text(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", value);
  return text;
}

// A share as 2^k when it is a power of two (the default 2^-20), else as %g.
std::string share_text(double share) {
  int exponent = 0;
  if (share > 0 && std::frexp(share, &exponent) == 0.5) return "2^" + std::to_string(exponent - 1);
  return number_text(share);
}

// Step 9's line in the report (separate_touching_parts, at `share` of the
// nearest neighbour's distance).
RepairChange touching_change(const kernel_detail::TouchingSeparation& separation, double share) {
  std::string text = "separated parts touching at " + plural(separation.vertices, "vertex", "vertices");
  if (separation.edges > 0) {
    text += " (on " + plural(separation.edges, "edge", "edges") +
            " with more than two triangles, paired into wedges in exact angular order)";
  }
  text += ": " + plural(separation.copies, "vertex copy", "vertex copies") + " moved into their own parts by at most " +
          number_text(separation.largest_move) + " (" + share_text(share) +
          " of the nearest neighbour's distance), volume change " + number_text(separation.volume_change) +
          " (bound " + number_text(separation.volume_bound) + ")";
  return {RepairKind::separated_touching_parts, separation.vertices, std::move(text)};
}

// Attributes of a point inside input triangle t, barycentric in t's corners
// (computed in doubles: attributes are data, no decision depends on them).
void interpolate_corner_attributes(const Mesh& input, std::size_t t, Vec3 p, CornerAttributes& out) {
  const Triangle& tri = input.triangles[t];
  const Vec3 a = input.positions[tri[0]], b = input.positions[tri[1]], c = input.positions[tri[2]];
  const Vec3 n = cross(b - a, c - a);
  const double area2 = dot(n, n);
  double wa = 1.0 / 3, wb = 1.0 / 3, wc = 1.0 / 3;
  if (area2 > 0) {
    wa = dot(cross(b - p, c - p), n) / area2;
    wb = dot(cross(c - p, a - p), n) / area2;
    wc = 1.0 - wa - wb;
  }
  const CornerAttributes& in = input.corners;
  const std::size_t k = 3 * t;
  if (in.has_normals()) {
    Vec3 v = in.normals[k] * wa + in.normals[k + 1] * wb + in.normals[k + 2] * wc;
    const double length = std::sqrt(dot(v, v));
    if (length > 0) v = v * (1.0 / length);
    out.normals.push_back(v);
  }
  if (in.has_uvs()) {
    const Vec2 &ua = in.uvs[k], &ub = in.uvs[k + 1], &uc = in.uvs[k + 2];
    out.uvs.push_back(Vec2{ua.x * wa + ub.x * wb + uc.x * wc, ua.y * wa + ub.y * wb + uc.y * wc});
  }
  if (in.has_tangents()) {
    const Vec4 &ta = in.tangents[k], &tb = in.tangents[k + 1], &tc = in.tangents[k + 2];
    Vec3 v{ta.x * wa + tb.x * wb + tc.x * wc, ta.y * wa + tb.y * wb + tc.y * wc, ta.z * wa + tb.z * wb + tc.z * wc};
    const double length = std::sqrt(dot(v, v));
    if (length > 0) v = v * (1.0 / length);
    out.tangents.push_back(Vec4{v.x, v.y, v.z, ta.w});
  }
}

// Step 1's line in the report.
std::string merged_vertices_text(std::size_t merged) {
  return "merged " + plural(merged, "duplicate vertex", "duplicate vertices") + " (exactly equal positions)";
}

PositionKey key_of(const CgalPoint& p) { return key_of(Vec3{p.x(), p.y(), p.z()}); }

CgalPoint to_cgal(Vec3 p) { return CgalPoint(p.x, p.y, p.z); }

bool exactly_collinear(const SurfaceMesh& sm, FaceIndex f) {
  const HalfedgeIndex h = sm.halfedge(f);
  return CGAL::collinear(sm.point(sm.source(h)), sm.point(sm.target(h)), sm.point(sm.target(sm.next(h))));
}

std::size_t count_collinear_faces(const SurfaceMesh& sm) {
  std::size_t count = 0;
  for (FaceIndex f : sm.faces()) count += exactly_collinear(sm, f) ? 1 : 0;
  return count;
}

// The three vertex ids of a triangle in the rotation that starts at its smallest.
Triangle canonical_rotation(const Triangle& t) {
  const int first = t[0] < t[1] ? (t[0] < t[2] ? 0 : 2) : (t[1] < t[2] ? 1 : 2);
  return {t[first], t[(first + 1) % 3], t[(first + 2) % 3]};
}

bool same_cyclic_order(const Triangle& a, const Triangle& b) { return canonical_rotation(a) == canonical_rotation(b); }

// The lid of one hole over its own corners: the triangulation of the polygon
// `ids` (welded vertex ids, all distinct, in the hole's order) of least total
// area among those that draw no diagonal `joined` already joins, make no
// triangle `exists` already has, and make none over three exactly collinear
// corners. Dynamic programming over sub-polygons: the minimum-weight
// triangulation of a polygon (Klincsek 1980), over a hole's vertices as in
// Barequet & Sharir 1995 and Liepa 2003 (here without their dihedral weights). The area only chooses among lids; whether the repaired mesh
// is a valid solid is decided exactly afterwards, by validation. Triangles as
// positions in `ids`, in the polygon's orientation, each after one it shares an
// edge with; std::nullopt when every triangulation is excluded. O(n^3) time,
// O(n^2) memory.
template <class Joined, class Exists>
std::optional<std::vector<std::array<std::size_t, 3>>> least_area_lid(const std::vector<VertexIndex>& ids,
                                                                      const std::vector<Vec3>& points,
                                                                      const Joined& joined, const Exists& exists) {
  const std::size_t n = ids.size();
  if (n < 3) return std::nullopt;
  const auto area = [&](std::size_t i, std::size_t k, std::size_t j) {
    const Vec3 u = points[k] - points[i], v = points[j] - points[i];
    const Vec3 c{u.y * v.z - u.z * v.y, u.z * v.x - u.x * v.z, u.x * v.y - u.y * v.x};
    return std::sqrt(c.x * c.x + c.y * c.y + c.z * c.z);
  };
  constexpr double none = std::numeric_limits<double>::infinity();
  std::vector<double> best(n * n, none);
  std::vector<std::uint32_t> apex(n * n, 0);
  for (std::size_t i = 0; i + 1 < n; ++i) best[i * n + i + 1] = 0;
  for (std::size_t span = 2; span < n; ++span) {
    for (std::size_t i = 0; i + span < n; ++i) {
      const std::size_t j = i + span;
      // (0, n - 1) is a side of the polygon, the hole's own border edge.
      if (!(i == 0 && j == n - 1) && joined(ids[i], ids[j])) continue;
      for (std::size_t k = i + 1; k < j; ++k) {
        const double left = best[i * n + k], right = best[k * n + j];
        if (left == none || right == none || exists(ids[i], ids[k], ids[j])) continue;
        // A triangle over three collinear corners (a straight stretch of the
        // border) has no area: exactly excluded, as validation would refuse it.
        if (CGAL::collinear(to_cgal(points[i]), to_cgal(points[k]), to_cgal(points[j]))) continue;
        const double total = left + right + area(i, k, j);
        if (total < best[i * n + j]) {
          best[i * n + j] = total;
          apex[i * n + j] = static_cast<std::uint32_t>(k);
        }
      }
    }
  }
  if (best[n - 1] == none) return std::nullopt;
  std::vector<std::array<std::size_t, 3>> triangles;
  std::vector<std::pair<std::size_t, std::size_t>> stack{{0, n - 1}};
  while (!stack.empty()) {
    const auto [i, j] = stack.back();
    stack.pop_back();
    if (j < i + 2) continue;
    const std::size_t k = apex[i * n + j];
    triangles.push_back({i, k, j});
    stack.push_back({i, k});
    stack.push_back({k, j});
  }
  return triangles;
}

// A hole's boundary as simple polygons: split wherever it passes through one
// vertex twice (holes touching there), each part closed at that vertex. Empty
// when a part has fewer than three corners (a slit: two edges between the same
// two vertices, which no triangle over them closes).
std::vector<std::vector<std::size_t>> simple_loops(const std::vector<VertexIndex>& ids) {
  std::vector<std::vector<std::size_t>> loops, pending(1);
  for (std::size_t i = 0; i < ids.size(); ++i) pending[0].push_back(i);
  while (!pending.empty()) {
    std::vector<std::size_t> loop = std::move(pending.back());
    pending.pop_back();
    std::unordered_map<VertexIndex, std::size_t> seen;
    std::size_t first = 0, second = 0;
    for (std::size_t q = 0; q < loop.size() && second == 0; ++q) {
      const auto [at, fresh] = seen.try_emplace(ids[loop[q]], q);
      if (!fresh) first = at->second, second = q;
    }
    if (second == 0) {
      if (loop.size() < 3) return {};
      loops.push_back(std::move(loop));
      continue;
    }
    const auto at = [&](std::size_t q) { return loop.begin() + static_cast<std::ptrdiff_t>(q); };
    std::vector<std::size_t> inner(at(first), at(second)), outer(at(second), loop.end());
    outer.insert(outer.end(), loop.begin(), at(first));
    pending.push_back(std::move(inner));
    pending.push_back(std::move(outer));
  }
  return loops;
}

// The holes of the welded surface, from the border cycles CGAL left (each a
// walk over welded vertex ids: cycle[q] -> cycle[q + 1] is a border edge).
// orient_polygon_soup split every vertex where several fans of triangles meet
// into one copy per fan, so each of CGAL's cycles turns, at such a vertex, from
// one fan's incoming border edge to the same fan's outgoing one: around the fan,
// not across the gap beside it. Where exactly two border visits meet at a
// welded vertex, two fans meet there with two gaps between them, and each gap
// runs from one fan's incoming border edge to the other fan's outgoing one:
// the walks are paired again that way. That joins holes that touch at the
// vertex into the gaps they are: a patch cut off all round by holes that touch
// it at its corners gets lids between it and the surface around it, not a lid
// of its own over its own border, which would close it into a separate shell
// (repair fuzz case 7fdb8afdd0fc228b of seed 2: two triangles left between four
// removed ones were closed into a tetrahedron outside the torus, and turned
// inside out to bound it). Pairing by topology alone: two fans leave one way
// to pair them. Where more visits meet, the order of the gaps around the vertex
// is not known from the topology, and CGAL's pairing is kept (simple_loops then
// splits what still passes a vertex twice, as before). Walks in the order of
// their first edge; deterministic.
std::vector<std::vector<VertexIndex>> holes_between_fans(const std::vector<std::vector<VertexIndex>>& cycles) {
  // Border edges numbered cycle by cycle; next[e] is the edge a walk takes
  // after e, at e's end vertex.
  std::vector<VertexIndex> source;
  std::vector<std::size_t> next;
  for (const std::vector<VertexIndex>& cycle : cycles) {
    const std::size_t base = source.size();
    for (std::size_t q = 0; q < cycle.size(); ++q) {
      source.push_back(cycle[q]);
      next.push_back(base + (q + 1) % cycle.size());
    }
  }
  std::vector<std::pair<VertexIndex, std::size_t>> arrivals;  // (vertex, edge arriving there)
  arrivals.reserve(next.size());
  for (std::size_t e = 0; e < next.size(); ++e) arrivals.push_back({source[next[e]], e});
  std::sort(arrivals.begin(), arrivals.end());
  for (std::size_t i = 0; i < arrivals.size();) {
    std::size_t j = i;
    while (j < arrivals.size() && arrivals[j].first == arrivals[i].first) ++j;
    if (j - i == 2) std::swap(next[arrivals[i].second], next[arrivals[i + 1].second]);
    i = j;
  }
  std::vector<std::vector<VertexIndex>> holes;
  std::vector<std::uint8_t> walked(next.size(), 0);
  for (std::size_t start = 0; start < next.size(); ++start) {
    if (walked[start]) continue;
    std::vector<VertexIndex> hole;
    for (std::size_t e = start; !walked[e]; e = next[e]) {
      walked[e] = 1;
      hole.push_back(source[e]);
    }
    holes.push_back(std::move(hole));
  }
  return holes;
}

// The whole repair works on this copy of the input plus CGAL's surface mesh.
class Repairer {
 public:
  Repairer(const Mesh& input, const RepairOptions& options, RepairReport& report)
      : input_(input), options_(options), report_(report) {}

  Mesh run() {
    merge_duplicate_vertices();
    clean_triangles();
    remove_flat_pieces();
    if (working_.empty()) {
      report_.notes.push_back({"no triangle left after removing degenerate, duplicate and flat ones; nothing to repair"});
      return output_from_working_only();
    }
    build_surface_mesh();
    stitch();
    fill_holes();
    remove_zero_area_triangles();
    orient_to_bound_volume();
    return to_mesh(sm_, /*record=*/true);
  }

 private:
  void change(RepairKind kind, std::size_t count, std::string text) {
    report_.changes.push_back({kind, count, std::move(text)});
  }

  // Step 1: one representative (the first) per exact position.
  void merge_duplicate_vertices() {
    representative_.resize(input_.vertex_count());
    std::unordered_map<PositionKey, VertexIndex, PositionKeyHash> first_at;
    first_at.reserve(input_.vertex_count());
    std::size_t merged = 0;
    for (std::size_t v = 0; v < input_.vertex_count(); ++v) {
      const auto [it, inserted] = first_at.try_emplace(key_of(input_.positions[v]), static_cast<VertexIndex>(v));
      representative_[v] = it->second;
      merged += inserted ? 0 : 1;
    }
    if (merged > 0) change(RepairKind::merged_duplicate_vertices, merged, merged_vertices_text(merged));
  }

  Triangle mapped(std::size_t t) const {
    const Triangle& tri = input_.triangles[t];
    return {representative_[tri[0]], representative_[tri[1]], representative_[tri[2]]};
  }

  // Step 2: triangles with a repeated vertex, duplicate copies, opposite pairs.
  void clean_triangles() {
    std::vector<std::size_t> kept;
    std::size_t repeated = 0;
    for (std::size_t t = 0; t < input_.triangle_count(); ++t) {
      const Triangle tri = mapped(t);
      if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) {
        ++repeated;
      } else {
        kept.push_back(t);
      }
    }
    // Group by vertex set; within a group, a canonical rotation tells the two
    // orientations apart.
    std::map<Triangle, std::vector<std::size_t>> by_vertex_set;
    for (std::size_t t : kept) {
      Triangle sorted = mapped(t);
      std::sort(sorted.begin(), sorted.end());
      by_vertex_set[sorted].push_back(t);
    }
    std::vector<bool> drop(input_.triangle_count());
    std::size_t duplicates = 0, in_opposite_pairs = 0;
    for (const auto& [vertex_set, group] : by_vertex_set) {
      if (group.size() < 2) continue;
      const Triangle first = mapped(group.front());
      const bool both_orientations = std::any_of(group.begin(), group.end(), [&](std::size_t t) {
        return !same_cyclic_order(mapped(t), first);
      });
      if (both_orientations) {
        // A triangle and its reverse enclose nothing; which of them the surface
        // needs cannot be told, so both go and hole filling closes what is left.
        for (std::size_t t : group) drop[t] = true;
        in_opposite_pairs += group.size();
      } else {
        for (std::size_t i = 1; i < group.size(); ++i) drop[group[i]] = true;
        duplicates += group.size() - 1;
      }
    }
    for (std::size_t t : kept) {
      if (!drop[t]) working_.push_back(t);
    }
    if (repeated > 0) {
      change(RepairKind::removed_repeated_index_triangles, repeated,
             "removed " + plural(repeated, "zero-area triangle", "zero-area triangles") + " that use one vertex twice");
    }
    if (duplicates > 0) {
      change(RepairKind::removed_duplicate_triangles, duplicates,
             "removed " + plural(duplicates, "duplicate triangle", "duplicate triangles"));
    }
    if (in_opposite_pairs > 0) {
      change(RepairKind::removed_opposite_triangle_pairs, in_opposite_pairs,
             "removed " + plural(in_opposite_pairs, "triangle", "triangles") +
                 " lying back to back with a reversed copy of themselves");
    }
  }

  // Step 2, last: pieces (triangles joined through shared welded vertices) whose
  // corners all lie in one plane, decided exactly. Closed by any lid over their
  // own vertices or in their plane, such a piece bounds no volume: dropping it
  // changes no winding number off its plane, so the solid the rest encloses
  // stays the same. Kept, it blocks the rest: its holes have no lid but its own
  // reverse, and it crosses what it pokes through (CGAL's
  // tetra_intersected_by_triangle.off: a stray triangle through a tetrahedron;
  // b9_mesh.off: 14 lone triangles). Pieces by vertex, not by edge: flat
  // triangles that hang on to the rest by a corner (a planar quad of a torus
  // whose neighbours were removed) are part of its surface, and hole filling
  // joins them back.
  void remove_flat_pieces() {
    if (working_.empty()) return;
    UnionFind pieces(working_.size());
    std::unordered_map<VertexIndex, std::uint32_t> first_at_vertex;
    for (std::size_t i = 0; i < working_.size(); ++i) {
      for (const VertexIndex v : mapped(working_[i])) {
        const auto [it, fresh] = first_at_vertex.try_emplace(v, static_cast<std::uint32_t>(i));
        if (!fresh) pieces.unite(it->second, static_cast<std::uint32_t>(i));
      }
    }
    // Per piece (by its root): a triangle of it with area, whose plane every
    // corner of the piece must lie on; none when all its triangles are collinear.
    constexpr std::size_t no_plane = std::numeric_limits<std::size_t>::max();
    std::vector<std::size_t> plane_of(working_.size(), no_plane);
    const auto point = [&](VertexIndex v) { return to_cgal(input_.positions[v]); };
    for (std::size_t i = 0; i < working_.size(); ++i) {
      const Triangle tri = mapped(working_[i]);
      std::size_t& plane = plane_of[pieces.find(static_cast<std::uint32_t>(i))];
      if (plane == no_plane && !CGAL::collinear(point(tri[0]), point(tri[1]), point(tri[2]))) plane = i;
    }
    std::vector<std::uint8_t> flat(working_.size(), 1);  // by root: every corner so far on its plane
    for (std::size_t i = 0; i < working_.size(); ++i) {
      const std::uint32_t root = pieces.find(static_cast<std::uint32_t>(i));
      if (!flat[root] || plane_of[root] == no_plane) continue;
      const Triangle base = mapped(working_[plane_of[root]]), tri = mapped(working_[i]);
      for (int c = 0; c < 3 && flat[root]; ++c) {
        flat[root] = CGAL::orientation(point(base[0]), point(base[1]), point(base[2]), point(tri[c])) == CGAL::COPLANAR;
      }
    }
    std::vector<std::size_t> kept;
    std::size_t removed = 0, removed_pieces = 0;
    for (std::size_t i = 0; i < working_.size(); ++i) {
      const std::uint32_t root = pieces.find(static_cast<std::uint32_t>(i));
      if (!flat[root]) {
        kept.push_back(working_[i]);
        continue;
      }
      ++removed;
      if (root == i) ++removed_pieces;
    }
    if (removed == 0) return;
    if (kept.empty()) {
      report_.no_volume_reason = "every piece of it is flat (all its corners in one plane)";
    }
    working_ = std::move(kept);
    change(RepairKind::removed_flat_pieces, removed,
           "removed " + plural(removed, "triangle", "triangles") + " in " +
               plural(removed_pieces, "flat piece", "flat pieces") +
               " (all corners in one plane: closed in any way, they enclose no volume)");
  }

  // Step 3: the soup, oriented by CGAL, as a halfedge mesh. Each face remembers
  // the input triangle it holds.
  void build_surface_mesh() {
    std::vector<CgalPoint> points;
    std::unordered_map<VertexIndex, std::size_t> point_of;
    std::vector<std::vector<std::size_t>> polygons;
    polygons.reserve(working_.size());
    for (std::size_t t : working_) {
      std::vector<std::size_t> polygon;
      for (VertexIndex v : mapped(t)) {
        const auto [it, inserted] = point_of.try_emplace(v, points.size());
        if (inserted) points.push_back(to_cgal(input_.positions[v]));
        polygon.push_back(it->second);
      }
      polygons.push_back(std::move(polygon));
    }
    const std::size_t points_before = points.size();
    // Returns false when it had to split vertices to make the soup an oriented
    // manifold. The copies sit at the same positions, so the output (welded by
    // position) joins them again and validation names them; nothing is hidden.
    // Noted at the end only if the output still has such a vertex: filling the
    // holes that touch at a vertex usually joins its fans into one.
    if (!PMP::orient_polygon_soup(points, polygons)) split_vertices_ = points.size() - points_before;
    PMP::polygon_soup_to_polygon_mesh(points, polygons, sm_);
    auto [origin, created] = sm_.add_property_map<FaceIndex, std::int64_t>("f:origin", no_origin);
    origin_ = origin;
    // A fresh Surface_mesh gets its faces in polygon order; checked, since the
    // attribute bookkeeping depends on it.
    if (sm_.number_of_faces() != polygons.size()) {
      throw std::logic_error("repair: CGAL built " + std::to_string(sm_.number_of_faces()) + " faces from " +
                             std::to_string(polygons.size()) + " triangles");
    }
    for (FaceIndex f : sm_.faces()) origin_[f] = static_cast<std::int64_t>(working_[f.idx()]);
  }

  // Step 4.
  void stitch() {
    const std::size_t stitched = PMP::stitch_borders(sm_);
    if (stitched > 0) {
      change(RepairKind::stitched_border_edges, stitched,
             "stitched " + plural(stitched, "pair", "pairs") + " of boundary edges with equal endpoints");
    }
  }

  // Vertices of the surface mesh as the output will number them: by exact
  // position, so copies made by orient_polygon_soup count as one.
  std::uint32_t welded_id(SmVertex v) {
    return welded_ids_.try_emplace(key_of(sm_.point(v)), static_cast<std::uint32_t>(welded_ids_.size())).first->second;
  }
  std::uint64_t welded_edge_key(SmVertex a, SmVertex b) {
    const std::uint32_t i = welded_id(a), j = welded_id(b);
    return (std::uint64_t{std::min(i, j)} << 32) | std::max(i, j);
  }

  // A patch is kept only if, once copies are joined again on output, it adds no
  // edge the mesh already has (that would make the edge non-manifold: holes that
  // touch at a pinched vertex) and no triangle over the vertices of an existing
  // one (the lid of a lone open triangle is its reverse). Both decided by index.
  bool patch_is_manifold_when_welded(const std::vector<FaceIndex>& patch, std::unordered_map<std::uint64_t, int>& edges,
                                     std::map<std::array<std::uint32_t, 3>, int>& faces) {
    std::vector<FaceIndex> sorted_patch = patch;
    std::sort(sorted_patch.begin(), sorted_patch.end());
    auto in_patch = [&](FaceIndex f) { return std::binary_search(sorted_patch.begin(), sorted_patch.end(), f); };
    std::vector<std::uint64_t> new_edges;
    std::vector<std::array<std::uint32_t, 3>> new_faces;
    for (FaceIndex f : patch) {
      std::array<std::uint32_t, 3> corners{};
      int k = 0;
      for (HalfedgeIndex h : CGAL::halfedges_around_face(sm_.halfedge(f), sm_)) {
        corners[k++] = welded_id(sm_.target(h));
        const FaceIndex other = sm_.face(sm_.opposite(h));
        // A diagonal inside the patch is met from both sides: count it once.
        if (other != SurfaceMesh::null_face() && in_patch(other) && other < f) continue;
        if (other == SurfaceMesh::null_face() || in_patch(other)) {
          new_edges.push_back(welded_edge_key(sm_.source(h), sm_.target(h)));
        }
      }
      std::sort(corners.begin(), corners.end());
      new_faces.push_back(corners);
    }
    // A lid over a hole that passes through one vertex twice can draw the same
    // welded edge from both of CGAL's copies of it: as bad as repeating one the
    // mesh has.
    std::sort(new_edges.begin(), new_edges.end());
    if (std::adjacent_find(new_edges.begin(), new_edges.end()) != new_edges.end()) return false;
    for (std::uint64_t e : new_edges) {
      if (edges.count(e)) return false;
    }
    for (const auto& f : new_faces) {
      if (faces.count(f)) return false;
    }
    for (std::uint64_t e : new_edges) edges[e] = 1;
    for (const auto& f : new_faces) faces[f] = 1;
    return true;
  }

  // Whether a lid just added to the surface meets it, or itself, beyond the
  // vertices and edges they share: each lid triangle is tested exactly
  // (triangles_intersect) against every other triangle whose box meets its own,
  // with vertices named by position (welded_id), so that CGAL's copies of one
  // vertex count as one. Triangles with exactly collinear corners are left out
  // (step 5 removes them; the predicate's precondition excludes them). Only a
  // choice between lids rests on it: the repaired mesh is validated in full.
  // Cost: a pass over the surface's boxes, plus the pairs whose boxes meet.
  bool lid_crosses_surface(const std::vector<FaceIndex>& patch) {
    std::vector<Vec3> positions;
    std::unordered_map<std::uint32_t, VertexIndex> local;
    const auto index_of = [&](SmVertex v) {
      const auto [it, fresh] = local.try_emplace(welded_id(v), static_cast<VertexIndex>(positions.size()));
      if (fresh) positions.push_back({sm_.point(v).x(), sm_.point(v).y(), sm_.point(v).z()});
      return it->second;
    };
    const auto corners_of = [&](FaceIndex f) {
      const HalfedgeIndex h = sm_.halfedge(f);
      return std::array<SmVertex, 3>{sm_.source(h), sm_.target(h), sm_.target(sm_.next(h))};
    };
    const auto box_of = [&](const std::array<SmVertex, 3>& c) {
      return sm_.point(c[0]).bbox() + sm_.point(c[1]).bbox() + sm_.point(c[2]).bbox();
    };
    const auto flat = [&](const std::array<SmVertex, 3>& c) {
      return CGAL::collinear(sm_.point(c[0]), sm_.point(c[1]), sm_.point(c[2]));
    };
    std::vector<FaceIndex> sorted_patch = patch;
    std::sort(sorted_patch.begin(), sorted_patch.end());
    std::vector<Triangle> lid;
    std::vector<CGAL::Bbox_3> lid_boxes;
    CGAL::Bbox_3 lid_box;
    for (FaceIndex f : patch) {
      const auto c = corners_of(f);
      if (flat(c)) continue;
      lid.push_back({index_of(c[0]), index_of(c[1]), index_of(c[2])});
      lid_boxes.push_back(box_of(c));
      lid_box += lid_boxes.back();
    }
    for (std::size_t i = 0; i < lid.size(); ++i) {
      for (std::size_t j = i + 1; j < lid.size(); ++j) {
        if (CGAL::do_overlap(lid_boxes[i], lid_boxes[j]) && triangles_intersect(positions, lid[i], lid[j])) return true;
      }
    }
    for (FaceIndex f : sm_.faces()) {
      if (std::binary_search(sorted_patch.begin(), sorted_patch.end(), f)) continue;
      const auto c = corners_of(f);
      const CGAL::Bbox_3 box = box_of(c);
      if (!CGAL::do_overlap(box, lid_box) || flat(c)) continue;
      const Triangle other{index_of(c[0]), index_of(c[1]), index_of(c[2])};
      for (std::size_t i = 0; i < lid.size(); ++i) {
        if (CGAL::do_overlap(lid_boxes[i], box) && triangles_intersect(positions, lid[i], other)) return true;
      }
    }
    return false;
  }

  // Step 6 (before the zero-area step, so that flips can work on a closed surface).
  void fill_holes() {
    std::vector<HalfedgeIndex> cycles;
    PMP::extract_boundary_cycles(sm_, std::back_inserter(cycles));
    if (cycles.empty()) return;
    std::unordered_map<std::uint64_t, int> welded_edges;
    std::map<std::array<std::uint32_t, 3>, int> welded_faces;
    for (HalfedgeIndex h : sm_.halfedges()) {
      if (!sm_.is_border(h)) welded_edges[welded_edge_key(sm_.source(h), sm_.target(h))] = 1;
    }
    for (FaceIndex f : sm_.faces()) {
      const HalfedgeIndex h = sm_.halfedge(f);
      std::array<std::uint32_t, 3> corners{welded_id(sm_.source(h)), welded_id(sm_.target(h)),
                                           welded_id(sm_.target(sm_.next(h)))};
      std::sort(corners.begin(), corners.end());
      welded_faces[corners] = 1;
    }
    std::size_t filled = 0, filled_edges = 0, new_triangles = 0;
    std::vector<std::size_t> too_large;
    // Each border's vertices, walked once (filling one hole leaves the others'
    // border halfedges as they are), and how often the borders of the holes to
    // fill pass through each welded vertex.
    std::vector<std::vector<SmVertex>> borders(cycles.size());
    std::map<std::uint32_t, std::size_t> visits;
    for (std::size_t k = 0; k < cycles.size(); ++k) {
      HalfedgeIndex walk = cycles[k];
      do {
        borders[k].push_back(sm_.source(walk));
        walk = sm_.next(walk);
      } while (walk != cycles[k]);
      if (borders[k].size() > options_.max_hole_edges) continue;
      for (const SmVertex v : borders[k]) ++visits[welded_id(v)];
    }
    for (std::size_t k = 0; k < cycles.size(); ++k) {
      const HalfedgeIndex h = cycles[k];
      std::vector<SmVertex> cycle = std::move(borders[k]);
      const std::size_t edges = cycle.size();
      if (edges > options_.max_hole_edges) {
        too_large.push_back(edges);
        continue;
      }
      // A border that passes through two of CGAL's copies of one vertex is two
      // holes touching there, opened into one at the vertex: a lid over the copies
      // would cover the fan between them twice once they are joined. A border
      // that meets one other border at a vertex, and nothing else does, is one
      // side of two holes touching there that CGAL's copies opened the other way
      // (holes_between_fans). Such holes, and those whose CGAL lid repeats an edge
      // once copies are joined, get their lids over the welded vertices when the
      // mesh is written (to_mesh).
      std::set<std::uint32_t> welded_seen;
      bool passes_twice = false, touches_one_other = false;
      for (const SmVertex v : cycle) {
        const std::uint32_t id = welded_id(v);
        passes_twice = passes_twice || !welded_seen.insert(id).second;
        touches_one_other = touches_one_other || visits[id] == 2;
      }
      if (passes_twice || touches_one_other) {
        welded_lid_cycles_.push_back(std::move(cycle));
        continue;
      }
      std::vector<FaceIndex> patch;
      // Up to kFullSearchHoleEdges edges, the whole space of triangulations over
      // the hole's vertices, not CGAL's default of searching a 3D Delaunay
      // triangulation of them first: that search is not deterministic. CGAL
      // 5.5's TDS_3 edge iterator reports each edge from its incident cell of
      // least address, so the order it tries triangles in follows where malloc
      // put the cells; where two lids weigh exactly the same (a symmetric hole,
      // repair fuzz case c3e86611603229a3 of seed 2) the one found first wins,
      // and two repairs of one mesh in one process differed. The full search
      // breaks ties by vertex index, and its minimum is over a superset of the
      // Delaunay search's lids, but it is cubic in the hole's edges (0.07 s on
      // main against 1.0 s at 400 edges, 0.22 against 7.1 s at 800): a larger
      // hole keeps the Delaunay search, deterministic unless two of its lids
      // weigh exactly the same (README, "Repair": a known limitation).
      // The full search's lid is the least weight (worst dihedral angle, then
      // area) over every triangulation, including lids that pass through the
      // surface (a hole in a saddle, CGAL's demo meshes negative.off and
      // fold.off, 5 of its 143 meshes refused for it); the Delaunay search keeps
      // to triangles of the hole's 3D Delaunay triangulation, which rarely
      // cross. So a lid that crosses the surface is replaced by the Delaunay
      // search's when that one does not (its ties are then the limitation
      // above), and kept otherwise (validation names the crossing).
      constexpr std::size_t kFullSearchHoleEdges = 200;
      const bool full_search = cycle.size() <= kFullSearchHoleEdges;
      PMP::triangulate_hole(sm_, h, std::back_inserter(patch), CGAL::parameters::use_delaunay_triangulation(!full_search));
      if (full_search && !patch.empty() && lid_crosses_surface(patch)) {
        for (FaceIndex f : patch) CGAL::Euler::remove_face(sm_.halfedge(f), sm_);
        patch.clear();
        PMP::triangulate_hole(sm_, h, std::back_inserter(patch), CGAL::parameters::use_delaunay_triangulation(true));
        if (patch.empty() || lid_crosses_surface(patch)) {
          for (FaceIndex f : patch) CGAL::Euler::remove_face(sm_.halfedge(f), sm_);
          patch.clear();
          PMP::triangulate_hole(sm_, h, std::back_inserter(patch), CGAL::parameters::use_delaunay_triangulation(false));
        }
      }
      if (patch.empty()) {
        // CGAL found no lid (its search keeps to triangles it deems valid, e.g.
        // on a flat or folded border): the least-area lid tries all of them.
        welded_lid_cycles_.push_back(std::move(cycle));
        continue;
      }
      if (!patch_is_manifold_when_welded(patch, welded_edges, welded_faces)) {
        for (FaceIndex f : patch) CGAL::Euler::remove_face(sm_.halfedge(f), sm_);
        welded_lid_cycles_.push_back(std::move(cycle));
        continue;
      }
      ++filled;
      filled_edges += edges;
      new_triangles += patch.size();
    }
    // Announced with the welded lids, at the place of this step in the report.
    holes_filled_ = {filled, filled_edges, new_triangles};
    holes_change_at_ = report_.changes.size();
    if (!too_large.empty()) {
      report_.notes.push_back({"left " + plural(too_large.size(), "hole", "holes") + " larger than " +
                               std::to_string(options_.max_hole_edges) + " edges unfilled (" + hole_sizes(too_large) +
                               " edges)"});
    }
  }

  static std::string hole_sizes(const std::vector<std::size_t>& v) {
    std::string text;
    for (std::size_t i = 0; i < v.size() && i < 8; ++i) text += (i ? ", " : "") + std::to_string(v[i]);
    if (v.size() > 8) text += ", ...";
    return text;
  }

  // Step 5: CGAL flips the longest edge of a triangle whose third corner lies on
  // it, and collapses edges of length zero; both only rewire existing vertices.
  void remove_zero_area_triangles() {
    const std::size_t before = count_collinear_faces(sm_);
    if (before == 0) return;
    PMP::remove_degenerate_faces(sm_);
    const std::size_t after = count_collinear_faces(sm_);
    if (after < before) {
      change(RepairKind::fixed_zero_area_triangles, before - after,
             "removed " + plural(before - after, "zero-area triangle", "zero-area triangles") +
                 " by flipping or collapsing their edges");
    }
    if (after > 0) {
      report_.notes.push_back({"could not remove " + plural(after, "zero-area triangle", "zero-area triangles")});
    }
  }

  // Step 7: reversal is counted at the end, against the input.
  void orient_to_bound_volume() {
    if (!CGAL::is_closed(sm_) || sm_.number_of_faces() == 0) return;
    PMP::orient_to_bound_a_volume(sm_);
  }

  // Step 8.
  Mesh output_from_working_only() {
    // Only reached when every triangle was removed: nothing is left to output.
    Mesh out;
    finish_report(out, 0, 0);
    return out;
  }

  // The first corner (3*t + c) at each vertex, overall and per surface: the
  // attributes a corner of a new triangle borrows.
  std::optional<std::size_t> borrowed_corner(VertexIndex v, SurfaceId surface) {
    if (corner_at_.empty()) {
      for (std::size_t t : working_) {
        const Triangle tri = mapped(t);
        for (std::size_t c = 0; c < 3; ++c) {
          corner_at_.try_emplace(tri[c], 3 * t + c);
          corner_at_surface_.try_emplace((std::uint64_t{tri[c]} << 32) | input_.surfaces[t], 3 * t + c);
        }
      }
    }
    if (auto it = corner_at_surface_.find((std::uint64_t{v} << 32) | surface); it != corner_at_surface_.end()) {
      return it->second;
    }
    if (auto it = corner_at_.find(v); it != corner_at_.end()) return it->second;
    return std::nullopt;
  }

  // Converts a repaired surface back to shatter's mesh. `record` adds the
  // reversal, self-intersection and unused-vertex changes to the report.
  Mesh to_mesh(const SurfaceMesh& sm, bool record) {
    const auto origin = sm.property_map<FaceIndex, std::int64_t>("f:origin").first;

    // Vertices: existing positions keep their input (representative) index; new
    // positions (a filled hole's fan hub) get new ones. Welded by position, as always.
    std::unordered_map<PositionKey, VertexIndex, PositionKeyHash> input_vertex_at;
    for (std::size_t v = 0; v < input_.vertex_count(); ++v) {
      if (representative_[v] == v) input_vertex_at.emplace(key_of(input_.positions[v]), static_cast<VertexIndex>(v));
    }
    constexpr VertexIndex new_base = std::numeric_limits<VertexIndex>::max() / 2;  // marks new vertices until renumbering
    std::vector<Vec3> new_positions;
    std::unordered_map<PositionKey, VertexIndex, PositionKeyHash> new_vertex_at;
    auto vertex_id = [&](SmVertex v) -> VertexIndex {
      const PositionKey key = key_of(sm.point(v));
      if (auto it = input_vertex_at.find(key); it != input_vertex_at.end()) return it->second;
      const auto [it, inserted] = new_vertex_at.try_emplace(key, static_cast<VertexIndex>(new_base + new_positions.size()));
      if (inserted) new_positions.push_back({sm.point(v).x(), sm.point(v).y(), sm.point(v).z()});
      return it->second;
    };

    struct Face {
      Triangle vertices;
      std::int64_t origin;
      std::optional<SurfaceId> surface;
      FaceIndex handle;
      int against_input = 0;  // the input triangle itself: +1 as read, -1 reversed; 0 otherwise
    };
    std::vector<Face> faces;
    faces.reserve(sm.number_of_faces());
    std::size_t reversed = 0;
    for (FaceIndex f : sm.faces()) {
      const HalfedgeIndex h = sm.halfedge(f);
      Triangle tri{vertex_id(sm.source(h)), vertex_id(sm.target(h)), vertex_id(sm.target(sm.next(h)))};
      Face face{tri, origin[f], std::nullopt, f};
      if (face.origin != no_origin) {
        const std::size_t t = static_cast<std::size_t>(face.origin);
        const Triangle in = mapped(t);
        Triangle sorted_in = in, sorted_out = tri;
        std::sort(sorted_in.begin(), sorted_in.end());
        std::sort(sorted_out.begin(), sorted_out.end());
        if (sorted_in == sorted_out) {
          // The input triangle itself: written as it was read, or reversed
          // keeping its first corner, so an untouched triangle stays bit-identical.
          if (same_cyclic_order(tri, in)) {
            face.vertices = in;
            face.against_input = 1;
          } else {
            face.vertices = {in[0], in[2], in[1]};
            face.against_input = -1;
            ++reversed;
          }
        }
        face.surface = input_.surfaces[t];
      }
      faces.push_back(face);
    }

    // New triangles (hole filling) take the surface of a neighbour that has one,
    // spreading inward across the patch.
    std::unordered_map<std::uint32_t, std::size_t> face_slot;
    for (std::size_t i = 0; i < faces.size(); ++i) face_slot[faces[i].handle.idx()] = i;
    for (bool progress = true; progress;) {
      progress = false;
      for (Face& face : faces) {
        if (face.surface) continue;
        for (HalfedgeIndex h : CGAL::halfedges_around_face(sm.halfedge(face.handle), sm)) {
          const FaceIndex neighbour = sm.face(sm.opposite(h));
          if (neighbour == SurfaceMesh::null_face()) continue;
          const Face& other = faces[face_slot.at(neighbour.idx())];
          if (other.surface) {
            face.surface = other.surface;
            progress = true;
            break;
          }
        }
      }
    }

    if (record) {
      // Step 6, finished: the holes whose lid CGAL could not draw over its copies of
      // a vertex (holes touching there), each split into simple loops at a vertex
      // it passes twice and closed by least_area_lid over the welded vertices,
      // avoiding every edge and triangle already there (lids included), so that
      // no edge gets a third triangle. A new triangle's surface is that of a
      // triangle across one of its edges.
      std::unordered_map<std::uint64_t, std::size_t> face_of_edge;  // directed (a, b) -> faces index
      std::set<std::uint64_t> joined_pairs;
      std::set<std::array<VertexIndex, 3>> triples;
      const auto pair_key = [](VertexIndex a, VertexIndex b) {
        return (std::uint64_t{std::min(a, b)} << 32) | std::max(a, b);
      };
      const auto sorted = [](VertexIndex a, VertexIndex b, VertexIndex c) {
        std::array<VertexIndex, 3> t{a, b, c};
        std::sort(t.begin(), t.end());
        return t;
      };
      const auto enter = [&](std::size_t f) {
        const Triangle& t = faces[f].vertices;
        for (int c = 0; c < 3; ++c) {
          face_of_edge[(std::uint64_t{t[c]} << 32) | t[(c + 1) % 3]] = f;
          joined_pairs.insert(pair_key(t[c], t[(c + 1) % 3]));
        }
        triples.insert(sorted(t[0], t[1], t[2]));
      };
      if (!welded_lid_cycles_.empty()) {
        for (std::size_t f = 0; f < faces.size(); ++f) enter(f);
      }
      const auto position = [&](VertexIndex v) { return v >= new_base ? new_positions[v - new_base] : input_.positions[v]; };
      std::size_t lids = 0, lid_edges = 0, lid_triangles = 0, fan_lids = 0;
      std::vector<std::size_t> unclosed;
      std::vector<std::vector<VertexIndex>> cycles;
      for (const std::vector<SmVertex>& cycle : welded_lid_cycles_) {
        std::vector<VertexIndex>& ids = cycles.emplace_back();
        for (const SmVertex v : cycle) ids.push_back(vertex_id(v));
      }
      for (const std::vector<VertexIndex>& ids : holes_between_fans(cycles)) {
        const std::vector<std::vector<std::size_t>> loops = simple_loops(ids);
        std::vector<Triangle> lid;
        bool closed = !loops.empty();
        std::set<std::uint64_t> drawn;  // this lid's diagonals, which later loops avoid too
        for (std::size_t l = 0; l < loops.size() && closed; ++l) {
          std::vector<VertexIndex> loop_ids;
          std::vector<Vec3> points;
          for (const std::size_t q : loops[l]) {
            loop_ids.push_back(ids[q]);
            points.push_back(position(ids[q]));
          }
          const auto joined = [&](VertexIndex a, VertexIndex b) {
            return joined_pairs.count(pair_key(a, b)) > 0 || drawn.count(pair_key(a, b)) > 0;
          };
          const auto exists = [&](VertexIndex a, VertexIndex b, VertexIndex c) { return triples.count(sorted(a, b, c)) > 0; };
          const auto triangles = least_area_lid(loop_ids, points, joined, exists);
          if (triangles) {
            for (const auto& [i, k, j] : *triangles) {
              lid.push_back({loop_ids[i], loop_ids[k], loop_ids[j]});
              for (const auto& [a, b] : {std::pair{i, k}, std::pair{k, j}, std::pair{i, j}}) {
                drawn.insert(pair_key(loop_ids[a], loop_ids[b]));
              }
            }
            continue;
          }
          // No triangulation over the hole's own corners is allowed: each one
          // draws a diagonal the mesh has, or a triangle over three corners on
          // one line. CGAL's patch-23.off: a flat rectangular border with its
          // sides in many collinear corners, three of whose corners are ears of
          // the patch (the ear's diagonal taken), leaves none. Then a fan from
          // one new vertex at the mean of the corners: its edges are all new and
          // its triangles are new, so it repeats nothing; taken when no fan
          // triangle is exactly collinear and the new position is no vertex's.
          // Whether the lid crosses the surface is left to step 11 and validation.
          Vec3 sum{0, 0, 0};
          for (const Vec3& q : points) sum = sum + q;
          const Vec3 centre = sum * (1.0 / static_cast<double>(points.size()));
          const PositionKey key = key_of(centre);
          bool fan = std::isfinite(centre.x) && std::isfinite(centre.y) && std::isfinite(centre.z) &&
                     !input_vertex_at.count(key) && !new_vertex_at.count(key);
          for (std::size_t q = 0; q < points.size() && fan; ++q) {
            fan = !CGAL::collinear(to_cgal(points[q]), to_cgal(points[(q + 1) % points.size()]), to_cgal(centre));
          }
          if (!fan) {
            closed = false;
            break;
          }
          const VertexIndex hub = static_cast<VertexIndex>(new_base + new_positions.size());
          new_vertex_at.emplace(key, hub);
          new_positions.push_back(centre);
          fan_corner_from_[hub] = loop_ids.front();
          for (std::size_t q = 0; q < loop_ids.size(); ++q) {
            lid.push_back({loop_ids[q], loop_ids[(q + 1) % loop_ids.size()], hub});
          }
          ++fan_lids;
        }
        if (!closed) {
          unclosed.push_back(ids.size());
          continue;
        }
        for (const Triangle& t : lid) {
          Face face{t, no_origin, std::nullopt, SurfaceMesh::null_face()};
          for (int c = 0; c < 3 && !face.surface; ++c) {
            const auto across = face_of_edge.find((std::uint64_t{t[(c + 1) % 3]} << 32) | t[c]);
            if (across != face_of_edge.end()) face.surface = faces[across->second].surface;
          }
          faces.push_back(face);
          enter(faces.size() - 1);
        }
        ++lids;
        lid_edges += ids.size();
        lid_triangles += lid.size();
      }
      auto [filled, filled_edges, new_triangles] = holes_filled_;
      if (filled + lids > 0) {
        const RepairChange fill{RepairKind::filled_holes, filled + lids,
                                "filled " + plural(filled + lids, "hole", "holes") + " (" +
                                    plural(filled_edges + lid_edges, "border edge", "border edges") + ") with " +
                                    plural(new_triangles + lid_triangles, "new triangle", "new triangles") +
                                    (lids > 0 ? " (" + std::to_string(lids) +
                                                    " of them by the least-area lid over the welded vertices: holes "
                                                    "touching at a vertex, or where CGAL's lid failed)"
                                              : std::string()) +
                                    (fan_lids > 0 ? " (" + plural(fan_lids, "part", "parts") +
                                                        " of a hole no lid over its own corners closes by a fan from "
                                                        "a new vertex at their mean)"
                                                  : std::string())};
        report_.changes.insert(report_.changes.begin() + static_cast<std::ptrdiff_t>(holes_change_at_), fill);
      }
      if (!unclosed.empty()) {
        report_.notes.push_back({"did not fill " + plural(unclosed.size(), "hole", "holes") + " (" +
                                 hole_sizes(unclosed) +
                                 " edges): every lid over its vertices would repeat an edge or triangle the mesh has"});
      }
    }

    // Renumber: surviving input vertices in input order, then new ones.
    std::vector<bool> input_used(input_.vertex_count());
    std::vector<bool> new_used(new_positions.size());
    for (const Face& face : faces) {
      for (VertexIndex v : face.vertices) {
        if (v >= new_base) new_used[v - new_base] = true; else input_used[v] = true;
      }
    }
    Mesh out;
    std::vector<VertexIndex> input_number(input_.vertex_count()), new_number(new_positions.size());
    for (std::size_t v = 0; v < input_.vertex_count(); ++v) {
      if (!input_used[v]) continue;
      input_number[v] = static_cast<VertexIndex>(out.positions.size());
      out.positions.push_back(input_.positions[v]);
    }
    std::size_t created_vertices = 0;
    for (std::size_t v = 0; v < new_positions.size(); ++v) {
      if (!new_used[v]) continue;
      new_number[v] = static_cast<VertexIndex>(out.positions.size());
      out.positions.push_back(new_positions[v]);
      ++created_vertices;
    }

    const CornerAttributes& in_corners = input_.corners;
    const bool normals = in_corners.has_normals(), uvs = in_corners.has_uvs(), tangents = in_corners.has_tangents();
    for (const Face& face : faces) {
      Triangle tri;
      for (int c = 0; c < 3; ++c) {
        const VertexIndex v = face.vertices[c];
        tri[c] = v >= new_base ? new_number[v - new_base] : input_number[v];
      }
      out.triangles.push_back(tri);
      const SurfaceId surface = face.surface.value_or(original_surface);
      out.surfaces.push_back(surface);
      if (!normals && !uvs && !tangents) continue;
      for (int c = 0; c < 3; ++c) {
        const VertexIndex v = face.vertices[c];
        std::optional<std::size_t> corner;
        if (face.origin != no_origin) {
          const std::size_t t = static_cast<std::size_t>(face.origin);
          const Triangle in = mapped(t);
          for (std::size_t k = 0; k < 3; ++k) {
            if (in[k] == v) corner = 3 * t + k;
          }
        }
        if (!corner && v < new_base) corner = borrowed_corner(v, surface);
        // A fan's hub borrows the attributes of a corner of its hole.
        if (auto hub = fan_corner_from_.find(v); !corner && hub != fan_corner_from_.end()) {
          corner = borrowed_corner(hub->second, surface);
        }
        if (corner) {
          if (normals) out.corners.normals.push_back(in_corners.normals[*corner]);
          if (uvs) out.corners.uvs.push_back(in_corners.uvs[*corner]);
          if (tangents) out.corners.tangents.push_back(in_corners.tangents[*corner]);
        } else {
          // Unreachable for vertices that came from the input (each has a
          // corner); kept total so the channels always stay 3 per triangle.
          interpolate_corner(out, face.origin == no_origin ? working_.front() : static_cast<std::size_t>(face.origin),
                             out.positions[tri[c]]);
        }
      }
    }

    // Step 9: parts touching at a vertex or along an edge, taken apart now that the
    // surface is closed and its copies of a vertex joined again.
    const bool separated = record && separate_touching(out);

    // Step 7 for the lids drawn above: orient_to_bound_volume ran on CGAL's mesh,
    // still open where these holes were, so it did nothing or oriented only the
    // shells closed then. Now the output is closed, each shell is turned whole
    // the way its nesting asks (outward at even depth, a cavity at odd: shells.hpp).
    // The same once step 9 has separated touching parts: CGAL oriented its split
    // copies, in which the parts sharing an edge may have been glued otherwise.
    if (record && (!welded_lid_cycles_.empty() || separated) && is_closed_oriented_manifold(out)) {
      const ShellNesting nesting = shell_nesting(out);
      for (std::size_t t = 0; t < out.triangles.size(); ++t) {
        if (nesting.well_nested(nesting.shell_of_triangle[t])) continue;
        std::swap(out.triangles[t][1], out.triangles[t][2]);
        if (normals) std::swap(out.corners.normals[3 * t + 1], out.corners.normals[3 * t + 2]);
        if (uvs) std::swap(out.corners.uvs[3 * t + 1], out.corners.uvs[3 * t + 2]);
        if (tangents) std::swap(out.corners.tangents[3 * t + 1], out.corners.tangents[3 * t + 2]);
        if (faces[t].against_input == 1) ++reversed;
        if (faces[t].against_input == -1) --reversed;
      }
    }

    if (record) {
      if (reversed > 0) {
        change(RepairKind::reversed_triangles, reversed,
               "reversed " + plural(reversed, "triangle", "triangles") +
                   " to orient the surface consistently and outward");
      }
      if (separation_change_) report_.changes.push_back(std::move(*separation_change_));
      // Step 9's copies are new vertices too, not input vertices kept.
      std::size_t kept_input_vertices = out.positions.size() - created_vertices - separation_copies_;
      finish_report(out, kept_input_vertices, created_vertices);
    }
    return out;
  }

  // Step 9 (repair_touching.hpp): when the output is closed and consistently
  // oriented but touches itself at non-manifold vertices or edges, their parts
  // are split apart and moved a hair into their own wedges. Only vertex indices
  // and the moved copies' positions change: triangles, surfaces and corner
  // attributes keep their places. Returns whether it changed `out`.
  bool separate_touching(Mesh& out) {
    if (out.triangles.empty() || is_closed_oriented_manifold(out)) return false;
    ValidationOptions topology_only;
    topology_only.check_self_intersections = false;
    const ValidationReport topology = validate_mesh(out, topology_only);
    const Defect* pinched = topology.find(DefectKind::non_manifold_vertex);
    const Defect* crowded = topology.find(DefectKind::non_manifold_edge);
    if (!pinched && !crowded) return false;
    for (const DefectKind blocking : {DefectKind::nonfinite_coordinate, DefectKind::index_out_of_range,
                                      DefectKind::zero_area_triangle, DefectKind::boundary_edge,
                                      DefectKind::inconsistent_orientation}) {
      if (const Defect* defect = topology.find(blocking)) {
        report_.notes.push_back({"did not separate parts touching at non-manifold vertices or edges: the surface "
                                 "still has " + std::string(defect_name(blocking)) + " (" +
                                 std::to_string(defect->count) + ")"});
        return false;
      }
    }
    const kernel_detail::TouchingSeparation separation =
        kernel_detail::separate_touching_parts(out, options_.touching_separation);
    if (!separation.separated) {
      if (!separation.failure.empty()) report_.notes.push_back({separation.failure});
      return false;
    }
    // Named after the reversal and self-intersection steps, which are counted later.
    separation_copies_ = separation.copies;
    separation_change_ = touching_change(separation, options_.touching_separation);
    return true;
  }

  void interpolate_corner(Mesh& out, std::size_t t, Vec3 p) const {
    interpolate_corner_attributes(input_, t, p, out.corners);
  }

  void finish_report(const Mesh& out, std::size_t kept_input_vertices, std::size_t /*created_vertices*/) {
    std::size_t distinct_input = 0;
    for (std::size_t v = 0; v < input_.vertex_count(); ++v) distinct_input += representative_[v] == v ? 1 : 0;
    const std::size_t unused = distinct_input - kept_input_vertices;
    if (unused > 0) {
      change(RepairKind::removed_unused_vertices, unused,
             "removed " + plural(unused, "vertex", "vertices") + " no triangle uses");
    }
    report_.vertices_after = out.vertex_count();
    report_.triangles_after = out.triangle_count();
    if (split_vertices_ > 0) {
      ValidationOptions topology_only;
      topology_only.check_self_intersections = false;
      const ValidationReport topology = validate_mesh(out, topology_only);
      if (const Defect* pinched = topology.find(DefectKind::non_manifold_vertex)) {
        report_.notes.push_back({"the surface is not an orientable manifold at " +
                                 plural(split_vertices_, "vertex", "vertices") +
                                 " (worked on split copies, joined again on output; " +
                                 plural(pinched->count, "vertex", "vertices") + " still pinched)"});
      }
    }
  }

  const Mesh& input_;
  const RepairOptions& options_;
  RepairReport& report_;
  std::vector<VertexIndex> representative_;
  std::vector<std::size_t> working_;  // input triangles kept after step 2, in input order
  SurfaceMesh sm_;
  SurfaceMesh::Property_map<FaceIndex, std::int64_t> origin_;
  std::optional<RepairChange> separation_change_;  // step 9's, once it is done
  std::size_t separation_copies_ = 0;               // the vertex copies step 9 made
  // Vertices orient_polygon_soup split to make the soup an oriented manifold.
  std::size_t split_vertices_ = 0;
  std::unordered_map<PositionKey, std::uint32_t, PositionKeyHash> welded_ids_;
  // The new vertex at the centre of each fan lid (a to_mesh id, new_base + k) ->
  // the hole corner whose attributes its corners borrow.
  std::unordered_map<VertexIndex, VertexIndex> fan_corner_from_;
  // Holes CGAL's lid could not close without repeating an edge (holes touching at
  // a vertex), closed over the welded vertices when the mesh is written.
  std::vector<std::vector<SmVertex>> welded_lid_cycles_;
  // The hole step's counts (holes, their edges, new triangles) and where in the
  // report its change goes, once the welded lids are added to them.
  std::array<std::size_t, 3> holes_filled_{};
  std::size_t holes_change_at_ = 0;
  std::unordered_map<VertexIndex, std::size_t> corner_at_;
  std::unordered_map<std::uint64_t, std::size_t> corner_at_surface_;
};

// Step 11's orientation: winding numbers count each shell with its turn, so a
// shell that crosses another (or itself) must face the way it is meant to.
// Steps 3 and 7 cannot tell that way where shells cross: orient_to_bound_a_volume
// decides by nesting, which crossing shells do not have (it turned whole
// overlapping spheres into cavities of each other). So a crossing shell whose
// triangles the input held all one way round (every one of them found in the
// input as it is, or every one reversed; `input` as repair_mesh received it)
// faces the way the input had it: a cavity of a solid that crosses a copy of it
// stays a cavity. Any other crossing shell, or every one when
// `own_volume_only`, is taken as a solid of its own and turned to bound a
// positive volume (exact sign), and so is every one of a mesh of one shell
// (no shell for it to be a cavity of). A shell that crosses nothing keeps the
// orientation its nesting gave it. Returns the triangles reversed.
std::size_t orient_crossing_shells(Mesh& mesh, std::span<const TrianglePair> pairs, const Mesh& input,
                                   bool own_volume_only) {
  const std::size_t n = mesh.triangles.size();
  UnionFind shells(n);
  std::unordered_map<std::uint64_t, std::uint32_t> first_at_edge;
  for (std::uint32_t t = 0; t < n; ++t) {
    for (int c = 0; c < 3; ++c) {
      const VertexIndex u = mesh.triangles[t][c], v = mesh.triangles[t][(c + 1) % 3];
      const auto [it, inserted] = first_at_edge.try_emplace((std::uint64_t{std::min(u, v)} << 32) | std::max(u, v), t);
      if (!inserted) shells.unite(it->second, t);
    }
  }
  // A shell can be a cavity only inside another: a mesh of one shell faces out
  // of its own volume whatever the input's turn (one turned inside out as a
  // whole, whose lid over a hole crosses it, wound around only the lid's
  // sliver: a spool came out of volume 2e-5).
  std::size_t shell_count = 0;
  for (std::uint32_t t = 0; t < n; ++t) shell_count += shells.find(t) == t;
  own_volume_only = own_volume_only || shell_count == 1;
  std::vector<std::uint8_t> crossing(n, 0);
  for (const TrianglePair& pair : pairs) {
    crossing[shells.find(static_cast<std::uint32_t>(pair.first))] = 1;
    crossing[shells.find(static_cast<std::uint32_t>(pair.second))] = 1;
  }
  std::vector<std::vector<std::uint32_t>> members(n);
  for (std::uint32_t t = 0; t < n; ++t) {
    if (crossing[shells.find(t)]) members[shells.find(t)].push_back(t);
  }
  // The input's triangles over its positions welded (first index per exact
  // position), each rotated to start at its least vertex.
  std::unordered_map<PositionKey, VertexIndex, PositionKeyHash> welded;
  const auto id_of = [&](const Vec3& p) {
    return welded.try_emplace(key_of(p), static_cast<VertexIndex>(welded.size())).first->second;
  };
  std::set<Triangle> input_triangles;
  if (!own_volume_only) {
    for (const Triangle& t : input.triangles) {
      if (t[0] >= input.positions.size() || t[1] >= input.positions.size() || t[2] >= input.positions.size()) continue;
      input_triangles.insert(canonical_rotation({id_of(input.positions[t[0]]), id_of(input.positions[t[1]]),
                                                 id_of(input.positions[t[2]])}));
    }
  }
  Mesh shell;
  shell.positions = mesh.positions;
  std::size_t reversed = 0;
  const bool normals = mesh.corners.has_normals(), uvs = mesh.corners.has_uvs(), tangents = mesh.corners.has_tangents();
  for (const std::vector<std::uint32_t>& triangles : members) {
    if (triangles.empty()) continue;
    std::size_t as_read = 0, against = 0;
    for (const std::uint32_t t : triangles) {
      if (own_volume_only) break;
      const Triangle& tri = mesh.triangles[t];
      const Triangle ids{id_of(mesh.positions[tri[0]]), id_of(mesh.positions[tri[1]]), id_of(mesh.positions[tri[2]])};
      as_read += input_triangles.count(canonical_rotation(ids));
      against += input_triangles.count(canonical_rotation({ids[0], ids[2], ids[1]}));
    }
    bool turn = false;
    if (as_read > 0 && against == 0) {
      turn = false;
    } else if (against > 0 && as_read == 0) {
      turn = true;
    } else {
      shell.triangles.clear();
      for (const std::uint32_t t : triangles) shell.triangles.push_back(mesh.triangles[t]);
      turn = signed_volume_sign(shell) == Sign::negative;
    }
    if (!turn) continue;
    for (const std::uint32_t t : triangles) {
      std::swap(mesh.triangles[t][1], mesh.triangles[t][2]);
      if (normals) std::swap(mesh.corners.normals[3 * t + 1], mesh.corners.normals[3 * t + 2]);
      if (uvs) std::swap(mesh.corners.uvs[3 * t + 1], mesh.corners.uvs[3 * t + 2]);
      if (tangents) std::swap(mesh.corners.tangents[3 * t + 1], mesh.corners.tangents[3 * t + 2]);
    }
    reversed += triangles.size();
  }
  return reversed;
}

// Step 11 (RepairOptions::round_solid): a mesh the other steps left closed but
// self-intersecting, resolved exactly: its arrangement, the boundary of what it
// winds around at least once, that boundary as a plane-based solid, rounded and
// certified by the hook. Taken only when the rounded mesh is valid (then
// true); otherwise the mesh stays as it was and a note says why (false).
// `touching_too`: also when no two triangles cross (a closed chain whose
// shells only touch, along edges or at vertices: the rounding takes them apart).
bool resolve_self_intersections_exactly(Mesh& mesh, const Mesh& input, const RepairOptions& options,
                                        RepairReport& report, bool touching_too = false) {
  if (!options.round_solid || mesh.triangles.empty()) return false;
  // Validation names self-intersections only on a surface whose topology passes,
  // so the pairs are found here; their finder needs finite, in-range, non-flat
  // triangles.
  ValidationOptions topology_only;
  topology_only.check_self_intersections = false;
  const ValidationReport check = validate_mesh(mesh, topology_only);
  const auto not_done = [&](const std::string& why) {
    report.notes.push_back({"did not resolve self-intersections exactly: " + why});
  };
  for (const DefectKind blocking :
       {DefectKind::nonfinite_coordinate, DefectKind::index_out_of_range, DefectKind::zero_area_triangle}) {
    if (const Defect* defect = check.find(blocking)) {
      not_done("the surface still has " + std::string(defect_name(blocking)) + " (" + std::to_string(defect->count) + ")");
      return false;
    }
  }
  const std::vector<TrianglePair> pairs = self_intersecting_pairs(mesh.positions, mesh.triangles);
  if (pairs.empty() && !touching_too) return false;
  // The input's orientation where it is one, else each shell's own volume; when
  // that leaves nothing wound around (an input turned inside out as a whole),
  // every crossing shell by its own volume.
  Mesh oriented = mesh;
  std::size_t turned = orient_crossing_shells(oriented, pairs, input, false);
  MeshArrangement arrangement = arrange_triangles(oriented.positions, oriented.triangles);
  WindingBoundary boundary = winding_boundary(arrangement);
  if (boundary.status == WindingBoundary::Status::ok && boundary.triangles.empty()) {
    oriented = mesh;
    turned = orient_crossing_shells(oriented, pairs, input, true);
    arrangement = arrange_triangles(oriented.positions, oriented.triangles);
    boundary = winding_boundary(arrangement);
  }
  if (boundary.status == WindingBoundary::Status::open) {
    not_done("the surface is open (its pieces do not close up), so it winds around no solid");
    return false;
  }
  if (boundary.status != WindingBoundary::Status::ok) {
    not_done("the winding numbers of its cells could not be decided");
    return false;
  }
  if (boundary.triangles.empty()) {
    report.no_volume_reason = "every cell of its exact arrangement has winding number <= 0";
    not_done("the surface winds around no volume (every cell has winding number <= 0)");
    return false;
  }
  const ArrangementSolid made = solid_from_winding_boundary(arrangement, boundary, oriented.surfaces);
  switch (made.status) {
    case ArrangementSolid::Status::ok: break;
    case ArrangementSolid::Status::not_selected: not_done("nothing selected"); return false;
    case ArrangementSolid::Status::crowded_edge:
      not_done("the solid it winds around touches itself along an edge whose faces cannot be paired into wedges");
      return false;
    case ArrangementSolid::Status::pinched_face:
      not_done("a face of the solid it winds around does not close into simple loops");
      return false;
    case ArrangementSolid::Status::no_edge_line: not_done("an edge of the result lies on no known line"); return false;
  }
  RepairRounding rounded;
  try {
    rounded = options.round_solid(arrangement.plane_set(), made.solid, oriented);
  } catch (const std::bad_alloc&) {
    throw;
  } catch (const std::exception& e) {
    // The rounding refused the solid (e.g. UnsupportedGeometryError): the mesh
    // stays as it was, as for a rounding that is not valid.
    rounded.valid = false;
    rounded.defect = e.what();
  }
  if (!rounded.valid) {
    not_done("the solid it winds around did not round to a valid mesh (" + rounded.defect + ")");
    return false;
  }
  const double before = signed_volume(mesh), after = signed_volume(rounded.mesh);
  char volume[160];
  std::snprintf(volume, sizeof volume, "volume %.9g -> %.9g (change %.3g, overlaps counted once; rounding moved %.3g, bound %.3g)",
                before, after, after - before, rounded.moved_volume, rounded.moved_volume_bound);
  // With no crossing (`touching_too`), what the step did is take apart where
  // the solid touches itself.
  const bool crossed = !arrangement.pairs.empty();
  std::string text = (crossed ? "resolved " + plural(arrangement.pairs.size(), "self-intersecting triangle pair",
                                                     "self-intersecting triangle pairs") +
                                    " exactly ("
                              : std::string("made the solid the surface winds around, exactly, where its shells touch "
                                            "along edges or at vertices (")) +
                     (turned > 0 ? plural(turned, "triangle", "triangles") +
                                       " of crossing shells turned to face as in the input or out of their own volume; "
                                 : std::string()) +
                     "mesh arrangement: " + plural(arrangement.split_triangles, "triangle", "triangles") +
                     " split, " + plural(arrangement.triangles.size(), "piece", "pieces") + "; kept " +
                     plural(boundary.triangles.size(), "face", "faces") + " of " + std::to_string(boundary.faces) +
                     " bounding winding number >= 1 (at most " + std::to_string(boundary.max_winding) + "), merged into " +
                     plural(made.solid.faces.size(), "polygon face", "polygon faces") + ", rounded to " +
                     plural(rounded.mesh.triangles.size(), "triangle", "triangles") +
                     (rounded.separated_vertices > 0
                          ? " with " + plural(rounded.separated_vertices, "vertex copy", "vertex copies") +
                                " moved apart where the solid touches itself"
                          : std::string()) +
                     "); " + volume;
  if (crossed || rounded.separated_vertices == 0) {
    report.changes.push_back({RepairKind::resolved_self_intersections_exactly, arrangement.pairs.size(), std::move(text)});
  } else {
    report.changes.push_back({RepairKind::separated_touching_parts, rounded.separated_vertices, std::move(text)});
  }
  mesh = std::move(rounded.mesh);
  report.vertices_after = mesh.vertex_count();
  report.triangles_after = mesh.triangle_count();
  return true;
}

// A surface that, welded by exact position, is closed as a chain: every
// segment is crossed as often one way as the other, once the triangles that
// enclose nothing are gone (one over a repeated or collinear corner; one and its
// reverse), copies of a triangle are what its neighbours need (when the chain is
// not closed with them) and edges are counted through the vertices that lie
// inside them.
// Its winding numbers are then defined everywhere off it, and the solid it
// encloses is the region they count at least once (step 11). Closed shells that
// touch or overlap (boxes sharing a face triangulated along other diagonals, an
// L of boxes, a copy of a solid moved by an ulp, tetrahedra around one edge)
// and closed surfaces with stray zero-area triangles, fins or T-junctions are
// such chains. The other steps would take them apart at their shared or crowded
// edges (orient_polygon_soup splits them, leaving borders that hole filling
// then closes with lids that are no part of any shell: an L of three unit boxes
// came out of volume 2.5, a box with stray zero-area triangles along its edges
// lost a sixth of its volume).
struct ClosedChain {
  Mesh mesh;  ///< welded, those triangles removed, every edge split at the vertices inside it, unused vertices dropped
  std::size_t merged = 0;       ///< vertices welded into an earlier one at the same position
  std::size_t repeated = 0;     ///< triangles over a repeated vertex (after welding)
  std::size_t collinear = 0;    ///< triangles over three distinct, exactly collinear corners
  std::size_t opposite = 0;     ///< triangles removed from groups over the same corners both ways round
  std::size_t duplicates = 0;   ///< extra copies of a triangle the same way round (no reverse among them)
  std::size_t fins = 0;         ///< triangles hanging from an edge of the surface, their other edges free
  std::size_t split_edges = 0;  ///< edges split at vertices inside them (T-junctions)
  std::size_t split_at = 0;     ///< the vertices they were split at, counted once per edge
  std::size_t unused = 0;       ///< vertices no triangle left uses
};

// A piece of an input triangle: its corners, and the input triangle's index
// (its surface, and its corners' attributes interpolated at the piece's).
struct TrianglePiece {
  Triangle corners;
  std::uint32_t source;
};

// Splits every piece at each vertex of `inside` (undirected edge, low << 32 |
// high -> the vertices strictly inside it) that lies inside one of its edges:
// the piece (a, b, c) with p inside a -> b becomes (a, p, c) and (p, b, c),
// both non-degenerate (c is off the line of a and b, and p is strictly between
// them).
void split_at_inside_vertices(const std::vector<Vec3>& positions,
                                     const std::unordered_map<std::uint64_t, std::vector<VertexIndex>>& inside,
                                     std::vector<TrianglePiece>& pieces) {
  const std::size_t original = pieces.size();
  std::vector<std::size_t> of_triangle;
  for (std::size_t t = 0; t < original; ++t) {
    const Triangle corners = pieces[t].corners;
    of_triangle.assign(1, t);
    for (int c = 0; c < 3; ++c) {
      const VertexIndex u = corners[c], v = corners[(c + 1) % 3];
      const auto found = inside.find(undirected_edge_key(u, v));
      if (found == inside.end()) continue;
      for (const VertexIndex p : found->second) {
        for (const std::size_t at : of_triangle) {
          TrianglePiece& piece = pieces[at];
          int e = 0;
          while (e < 3 && !strictly_inside_segment(positions[piece.corners[e]], positions[piece.corners[(e + 1) % 3]],
                                                   positions[p])) {
            ++e;
          }
          if (e == 3) continue;
          const VertexIndex a = piece.corners[e], b = piece.corners[(e + 1) % 3], c = piece.corners[(e + 2) % 3];
          piece.corners = {a, p, c};
          pieces.push_back({{p, b, c}, piece.source});
          of_triangle.push_back(pieces.size() - 1);
          break;
        }
      }
    }
  }
}

// Per undirected edge (low << 32 | high): its uses low -> high minus high -> low.
std::unordered_map<std::uint64_t, std::int64_t> edge_balance(const std::vector<TrianglePiece>& pieces) {
  std::unordered_map<std::uint64_t, std::int64_t> balance;
  balance.reserve(3 * pieces.size() / 2 + 3);
  for (const TrianglePiece& piece : pieces) {
    for (int c = 0; c < 3; ++c) {
      const VertexIndex u = piece.corners[c], v = piece.corners[(c + 1) % 3];
      balance[undirected_edge_key(u, v)] += u < v ? 1 : -1;
    }
  }
  return balance;
}

// `mesh` as a closed chain (above), or nothing when some segment is crossed
// more often one way than the other (a hole, duplicated triangles, a triangle
// turned against its neighbours, cracks: the other steps' work) or an index is
// out of range.
std::optional<ClosedChain> closed_welded_chain(const Mesh& mesh) {
  const std::size_t vertices = mesh.positions.size();
  ClosedChain chain;
  std::vector<Vec3> positions;
  std::unordered_map<PositionKey, VertexIndex, PositionKeyHash> index_of;
  index_of.reserve(vertices);
  std::vector<VertexIndex> welded_of(vertices);
  for (std::size_t v = 0; v < vertices; ++v) {
    const auto [it, inserted] = index_of.try_emplace(key_of(mesh.positions[v]), static_cast<VertexIndex>(positions.size()));
    if (inserted) positions.push_back(mesh.positions[v]);
    welded_of[v] = it->second;
  }
  chain.merged = vertices - positions.size();
  std::vector<TrianglePiece> pieces;
  pieces.reserve(mesh.triangles.size());
  for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t) {
    const Triangle& tri = mesh.triangles[t];
    if (tri[0] >= vertices || tri[1] >= vertices || tri[2] >= vertices) return std::nullopt;
    const Triangle w{welded_of[tri[0]], welded_of[tri[1]], welded_of[tri[2]]};
    if (w[0] == w[1] || w[1] == w[2] || w[2] == w[0]) {
      ++chain.repeated;
    } else if (collinear(positions[w[0]], positions[w[1]], positions[w[2]])) {
      ++chain.collinear;
    } else {
      pieces.push_back({w, t});
    }
  }
  std::unordered_map<std::uint64_t, std::int64_t> balance = edge_balance(pieces);
  // Fins: a triangle on an edge of the surface (one that three or more
  // triangles use), its other edges its own or also such (a sliver stuck on an
  // edge: a zero-area triangle whose third corner rounded off the edge's line).
  // Its free edges are a border, so it bounds nothing; removed, the surface may
  // close. Peeled until none is left, before the copies below are settled: a
  // fin on an edge of copied triangles would count against what the edge needs.
  if (std::any_of(balance.begin(), balance.end(), [](const auto& entry) { return entry.second != 0; })) {
    const auto edge_of = [&](const TrianglePiece& piece, int c) {
      return undirected_edge_key(piece.corners[c], piece.corners[(c + 1) % 3]);
    };
    // A fin's free edges are crossed one way only: the candidates are the
    // triangles on such edges, and only their edges' uses are counted (peeling
    // never frees an edge of another triangle: it takes one use from an edge
    // with three or more, or the last from a free one).
    std::vector<std::uint32_t> candidates;
    std::unordered_map<std::uint64_t, std::uint32_t> uses;
    for (std::uint32_t i = 0; i < pieces.size(); ++i) {
      bool on_unbalanced = false;
      for (int c = 0; c < 3 && !on_unbalanced; ++c) on_unbalanced = balance.find(edge_of(pieces[i], c))->second != 0;
      if (!on_unbalanced) continue;
      candidates.push_back(i);
      for (int c = 0; c < 3; ++c) uses.emplace(edge_of(pieces[i], c), 0);
    }
    for (const TrianglePiece& piece : pieces) {
      for (int c = 0; c < 3; ++c) {
        if (const auto it = uses.find(edge_of(piece, c)); it != uses.end()) ++it->second;
      }
    }
    std::vector<std::uint8_t> peeled(pieces.size(), 0);
    for (bool changed = true; changed;) {
      changed = false;
      for (const std::uint32_t i : candidates) {
        if (peeled[i]) continue;
        int free = 0, crowded = 0;
        for (int c = 0; c < 3; ++c) {
          const std::uint32_t count = uses[edge_of(pieces[i], c)];
          free += count == 1;
          crowded += count >= 3;
        }
        if (free == 0 || crowded == 0 || free + crowded != 3) continue;
        peeled[i] = 1;
        ++chain.fins;
        changed = true;
        for (int c = 0; c < 3; ++c) {
          const std::uint64_t edge = edge_of(pieces[i], c);
          --uses[edge];
          balance[edge] -= pieces[i].corners[c] < pieces[i].corners[(c + 1) % 3] ? 1 : -1;
        }
      }
    }
    if (chain.fins > 0) {
      std::size_t at = 0;
      for (std::size_t i = 0; i < pieces.size(); ++i) {
        if (!peeled[i]) pieces[at++] = pieces[i];
      }
      pieces.resize(at);
    }
  }
  // Triangles over the same three vertices: a triangle and its reverse enclose
  // nothing, so each group first keeps only what its copies add up to (its
  // uses one way minus the other, as copies of the first of that way round),
  // which crosses every edge as before. When the chain is still not closed
  // there, a group's copies are a copying error rather than shells (a reversed
  // or repeated copy of a triangle of a closed surface): the group becomes what
  // its edges need, one copy either way round or none, as the rest of the chain
  // crosses those edges (ignoring edges it shares with another such group,
  // whose need depends on that group; groups are settled until none changes).
  balance.clear();
  {
    // (sorted corners, piece) in order: a group's pieces together, in input order.
    std::vector<std::pair<Triangle, std::uint32_t>> by_corners(pieces.size());
    for (std::uint32_t i = 0; i < pieces.size(); ++i) {
      Triangle sorted = pieces[i].corners;
      std::sort(sorted.begin(), sorted.end());
      by_corners[i] = {sorted, i};
    }
    std::sort(by_corners.begin(), by_corners.end());
    struct Group {
      Triangle sorted;              // runs each edge as `sign` of the copies kept
      std::vector<std::uint32_t> pieces;
      std::int64_t net;             // copies kept, signed: + as `sorted` runs, - reversed
      bool mixed;                   // copies both ways round
    };
    std::vector<Group> multiple;
    std::vector<std::uint8_t> kept(pieces.size(), 1);
    const auto way = [&](std::uint32_t piece, const Triangle& sorted) {
      return canonical_rotation(pieces[piece].corners) == sorted ? 1 : -1;  // sorted is its own canonical rotation
    };
    for (std::size_t first = 0, end = 0; first < by_corners.size(); first = end) {
      end = first + 1;
      while (end < by_corners.size() && by_corners[end].first == by_corners[first].first) ++end;
      if (end - first < 2) continue;
      const Triangle& sorted = by_corners[first].first;
      Group group{sorted, {}, 0, false};
      for (std::size_t k = first; k < end; ++k) group.pieces.push_back(by_corners[k].second);
      for (const std::uint32_t piece : group.pieces) {
        group.net += way(piece, sorted);
        group.mixed = group.mixed || way(piece, sorted) != way(group.pieces.front(), sorted);
      }
      multiple.push_back(std::move(group));
    }
    // Keeps `net` copies of a group (those first in input order of that way round).
    const auto keep = [&](Group& group, std::int64_t net) {
      std::int64_t left = net < 0 ? -net : net;
      for (const std::uint32_t piece : group.pieces) {
        const bool take = left > 0 && way(piece, group.sorted) == (net < 0 ? -1 : 1);
        kept[piece] = take ? 1 : 0;
        if (take) --left;
      }
      group.net = net;
    };
    for (Group& group : multiple) keep(group, group.net);
    for (std::uint32_t i = 0; i < pieces.size(); ++i) {
      if (!kept[i]) continue;
      for (int c = 0; c < 3; ++c) {
        const VertexIndex u = pieces[i].corners[c], v = pieces[i].corners[(c + 1) % 3];
        balance[undirected_edge_key(u, v)] += u < v ? 1 : -1;
      }
    }
    const auto closed = [&] {
      return std::all_of(balance.begin(), balance.end(), [](const auto& entry) { return entry.second == 0; });
    };
    if (!closed()) {
      std::unordered_map<std::uint64_t, std::uint32_t> groups_at_edge;
      for (const Group& group : multiple) {
        for (int c = 0; c < 3; ++c) ++groups_at_edge[undirected_edge_key(group.sorted[c], group.sorted[(c + 1) % 3])];
      }
      std::vector<std::uint8_t> settled(multiple.size(), 0);
      for (bool changed = true; changed;) {
        changed = false;
        for (std::size_t g = 0; g < multiple.size(); ++g) {
          if (settled[g]) continue;
          Group& group = multiple[g];
          std::optional<std::int64_t> need;
          bool agree = true;
          for (int c = 0; c < 3 && agree; ++c) {
            const VertexIndex u = group.sorted[c], v = group.sorted[(c + 1) % 3];
            const std::uint64_t edge = undirected_edge_key(u, v);
            if (groups_at_edge[edge] > 1) continue;
            const std::int64_t runs = u < v ? 1 : -1;  // how `sorted` crosses the edge
            const std::int64_t rest = balance[edge] - group.net * runs;
            const std::int64_t here = -rest * runs;
            agree = !need || *need == here;
            need = here;
          }
          if (!agree || !need) continue;  // waits for its neighbours, or stays as it is
          // Settled now, also when its need cannot be met (it then stays).
          settled[g] = 1;
          changed = true;
          for (int c = 0; c < 3; ++c) --groups_at_edge[undirected_edge_key(group.sorted[c], group.sorted[(c + 1) % 3])];
          const bool available = *need == 0 || std::any_of(group.pieces.begin(), group.pieces.end(), [&](std::uint32_t piece) {
            return way(piece, group.sorted) == *need;
          });
          if (*need == group.net || *need < -1 || *need > 1 || !available) continue;
          for (int c = 0; c < 3; ++c) {
            const VertexIndex u = group.sorted[c], v = group.sorted[(c + 1) % 3];
            balance[undirected_edge_key(u, v)] += (*need - group.net) * (u < v ? 1 : -1);
          }
          keep(group, *need);
        }
      }
    }
    for (const Group& group : multiple) {
      const std::size_t removed = group.pieces.size() - static_cast<std::size_t>(group.net < 0 ? -group.net : group.net);
      (group.mixed ? chain.opposite : chain.duplicates) += removed;
    }
    std::size_t at = 0;
    for (std::uint32_t i = 0; i < pieces.size(); ++i) {
      if (kept[i]) pieces[at++] = pieces[i];
    }
    pieces.resize(at);
  }
  std::vector<std::uint64_t> unbalanced;
  for (const auto& [edge, count] : balance) {
    if (count != 0) unbalanced.push_back(edge);
  }
  // Edges crossed more often one way: closed all the same when vertices inside
  // them split them into segments that are not (T-junctions, a zero-area
  // triangle's long edge). The vertices to look for are those of such edges.
  if (!unbalanced.empty()) {
    std::sort(unbalanced.begin(), unbalanced.end());
    std::vector<VertexIndex> candidates;
    for (const std::uint64_t edge : unbalanced) {
      candidates.push_back(static_cast<VertexIndex>(edge >> 32));
      candidates.push_back(static_cast<VertexIndex>(edge));
    }
    std::sort(candidates.begin(), candidates.end());
    candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
    // The candidates sorted along each axis; an edge scans those within its
    // extent along the axis where that range holds the fewest.
    std::array<std::vector<VertexIndex>, 3> along;
    for (int axis = 0; axis < 3; ++axis) {
      along[axis] = candidates;
      std::sort(along[axis].begin(), along[axis].end(), [&](VertexIndex a, VertexIndex b) {
        return positions[a][axis] != positions[b][axis] ? positions[a][axis] < positions[b][axis] : a < b;
      });
    }
    std::unordered_map<std::uint64_t, std::vector<VertexIndex>> inside;
    for (const std::uint64_t edge : unbalanced) {
      const auto u = static_cast<VertexIndex>(edge >> 32), v = static_cast<VertexIndex>(edge);
      using Range = std::pair<std::vector<VertexIndex>::const_iterator, std::vector<VertexIndex>::const_iterator>;
      std::optional<Range> fewest;
      for (int axis = 0; axis < 3; ++axis) {
        const double low = std::min(positions[u][axis], positions[v][axis]);
        const double high = std::max(positions[u][axis], positions[v][axis]);
        const auto first = std::partition_point(along[axis].cbegin(), along[axis].cend(),
                                                [&](VertexIndex w) { return positions[w][axis] < low; });
        const auto last = std::partition_point(first, along[axis].cend(),
                                               [&](VertexIndex w) { return positions[w][axis] <= high; });
        if (!fewest || last - first < fewest->second - fewest->first) fewest = Range{first, last};
      }
      std::vector<VertexIndex> on;
      for (auto it = fewest->first; it != fewest->second; ++it) {
        if (strictly_inside_segment(positions[u], positions[v], positions[*it])) on.push_back(*it);
      }
      if (on.empty()) continue;
      // From u to v: along the first coordinate where they differ (exact).
      int axis = 0;
      while (positions[u][axis] == positions[v][axis]) ++axis;
      const bool rising = positions[u][axis] < positions[v][axis];
      std::sort(on.begin(), on.end(), [&](VertexIndex a, VertexIndex b) {
        return rising ? positions[a][axis] < positions[b][axis] : positions[a][axis] > positions[b][axis];
      });
      chain.split_at += on.size();
      inside.emplace(edge, std::move(on));
    }
    if (inside.empty()) return std::nullopt;
    chain.split_edges = inside.size();
    split_at_inside_vertices(positions, inside, pieces);
    balance = edge_balance(pieces);
    for (const auto& [edge, count] : balance) {
      if (count != 0) return std::nullopt;
    }
  }
  // The chain's mesh over the vertices it uses, in their first order.
  std::vector<VertexIndex> renumbered(positions.size(), no_index);
  for (const TrianglePiece& piece : pieces) {
    for (const VertexIndex v : piece.corners) renumbered[v] = 0;
  }
  for (VertexIndex v = 0; v < positions.size(); ++v) {
    if (renumbered[v] == no_index) {
      ++chain.unused;
      continue;
    }
    renumbered[v] = static_cast<VertexIndex>(chain.mesh.positions.size());
    chain.mesh.positions.push_back(positions[v]);
  }
  for (const TrianglePiece& piece : pieces) {
    chain.mesh.triangles.push_back(
        {renumbered[piece.corners[0]], renumbered[piece.corners[1]], renumbered[piece.corners[2]]});
    chain.mesh.surfaces.push_back(mesh.surfaces[piece.source]);
    for (const VertexIndex v : piece.corners) interpolate_corner_attributes(mesh, piece.source, positions[v], chain.mesh.corners);
  }
  return chain;
}

// The chain's steps as report lines (in step order, the kinds the other steps
// report the same changes with).
void report_chain(const ClosedChain& chain, RepairReport& report) {
  const auto add = [&](std::size_t count, RepairKind kind, std::string text) {
    if (count > 0) report.changes.push_back({kind, count, std::move(text)});
  };
  add(chain.merged, RepairKind::merged_duplicate_vertices, merged_vertices_text(chain.merged));
  add(chain.repeated, RepairKind::removed_repeated_index_triangles,
      "removed " + plural(chain.repeated, "zero-area triangle", "zero-area triangles") + " that use one vertex twice");
  add(chain.duplicates, RepairKind::removed_duplicate_triangles,
      "removed " + plural(chain.duplicates, "duplicate triangle", "duplicate triangles"));
  add(chain.opposite, RepairKind::removed_opposite_triangle_pairs,
      "removed " +
          plural(chain.opposite, "triangle lying back to back with a copy of itself",
                 "triangles lying back to back with copies of themselves") +
          " (the copies over three vertices kept as their neighbours need them)");
  add(chain.collinear, RepairKind::fixed_zero_area_triangles,
      "removed " + plural(chain.collinear, "zero-area triangle", "zero-area triangles") +
          " (corners exactly collinear: they enclose nothing)");
  add(chain.fins, RepairKind::removed_hanging_triangles,
      "removed " + plural(chain.fins, "triangle", "triangles") +
          " hanging from an edge of the surface (fins: their other edges free, they bound nothing)");
  add(chain.split_edges, RepairKind::split_edges_at_vertices,
      "split " + plural(chain.split_edges, "edge", "edges") + " at the " + plural(chain.split_at, "vertex", "vertices") +
          " lying inside them (T-junctions), closing the surface");
  add(chain.unused, RepairKind::removed_unused_vertices,
      "removed " + plural(chain.unused, "vertex", "vertices") + " no triangle uses");
  report.vertices_after = chain.mesh.vertex_count();
  report.triangles_after = chain.mesh.triangle_count();
}

}  // namespace

RepairReport repair_mesh(Mesh& mesh, const RepairOptions& options) {
  RepairReport report;
  report.vertices_before = report.vertices_after = mesh.vertex_count();
  report.triangles_before = report.triangles_after = mesh.triangle_count();
  if (mesh.triangles.empty()) {
    report.notes.push_back({"the mesh has no triangle; nothing to repair"});
    return report;
  }
  const ValidationReport validation = validate_mesh(mesh);
  if (validation.valid()) return report;
  if (validation.find(DefectKind::nonfinite_coordinate) || validation.find(DefectKind::index_out_of_range)) {
    report.notes.push_back({"not repaired: " + validation.summary()});
    return report;
  }
  if (std::optional<ClosedChain> chain = closed_welded_chain(mesh)) {
    RepairReport attempt = report;
    report_chain(*chain, attempt);
    if (getenv("DBG_CHAIN")) fprintf(stderr, "chain: %s\n", attempt.summary().c_str());
    // Taken only as a whole: valid as it is, or the hook's mesh is valid
    // (RepairRounding::valid). Shells that only touch go to the arrangement
    // too; shells nested the wrong way round (no crossing, no touching) stay
    // for step 7, which orients them by their nesting (an inner shell a cavity).
    // Shells that touch are taken apart as step 9 does, keeping their
    // triangles, when that leaves a valid mesh.
    const ValidationReport check = validate_mesh(chain->mesh);
    const bool touching = check.find(DefectKind::non_manifold_edge) || check.find(DefectKind::non_manifold_vertex);
    if (touching && !check.find(DefectKind::inconsistent_orientation)) {
      Mesh separated = chain->mesh;
      const kernel_detail::TouchingSeparation separation =
          kernel_detail::separate_touching_parts(separated, options.touching_separation);
      if (separation.separated && validate_mesh(separated).valid()) {
        attempt.changes.push_back(touching_change(separation, options.touching_separation));
        mesh = std::move(separated);
        attempt.vertices_after = mesh.vertex_count();
        return attempt;
      }
    }
    if (check.valid() || resolve_self_intersections_exactly(chain->mesh, mesh, options, attempt, touching)) {
      mesh = std::move(chain->mesh);
      return attempt;
    }
  }
  Mesh repaired = Repairer(mesh, options, report).run();
  resolve_self_intersections_exactly(repaired, mesh, options, report);
  mesh = std::move(repaired);
  return report;
}

}  // namespace shatter
