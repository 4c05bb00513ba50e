// The solid a winding boundary bounds, as polygon faces with known edge lines
// (arrangement.hpp, solid_from_winding_boundary).
#include <algorithm>
#include <array>
#include <cstdint>
#include <optional>
#include <unordered_map>
#include <utility>
#include <vector>

#include "shatter/kernel/arrangement.hpp"
#include "shatter/kernel/predicates.hpp"
#include "shatter/kernel/union_find.hpp"

namespace shatter {
namespace {

std::uint64_t directed_key(VertexIndex u, VertexIndex v) { return (std::uint64_t{u} << 32) | v; }
std::uint64_t undirected_key(VertexIndex u, VertexIndex v) { return directed_key(std::min(u, v), std::max(u, v)); }

class SolidBuilder {
 public:
  SolidBuilder(const MeshArrangement& arrangement, const WindingBoundary& boundary, std::span<const SurfaceId> surfaces)
      : arrangement_(arrangement), boundary_(boundary), surfaces_(surfaces), set_(arrangement.plane_set()),
        projection_(arrangement.geometry.planes.size()) {}

  ArrangementSolid run() {
    ArrangementSolid out;
    const std::vector<Triangle>& tris = boundary_.triangles;
    const auto fail = [](ArrangementSolid::Status status) {
      ArrangementSolid failed;
      failed.status = status;
      return failed;
    };
    if (boundary_.status != WindingBoundary::Status::ok || tris.empty()) {
      out.status = ArrangementSolid::Status::not_selected;
      return out;
    }
    const auto n = static_cast<std::uint32_t>(tris.size());
    tris_ = tris;
    origin_.resize(arrangement_.defs.size());
    for (VertexIndex v = 0; v < origin_.size(); ++v) origin_[v] = v;
    // Half-edge 3t + c runs from corner c of triangle t to corner c + 1. The
    // boundary is closed and oriented: every edge is passed as often each way.
    // An edge with two triangles joins them; one with more (solids touching
    // along it) pairs each triangle passing it against the turn with the next
    // one around it (exact angular order): the two bound one wedge of the solid.
    std::vector<std::pair<std::uint64_t, std::uint32_t>> by_edge;
    by_edge.reserve(3 * n);
    for (std::uint32_t h = 0; h < 3 * n; ++h) by_edge.emplace_back(undirected_key(from(h), to(h)), h);
    std::sort(by_edge.begin(), by_edge.end());
    std::vector<std::uint32_t> twin(3 * n, no_index);
    std::vector<VertexIndex> crowded_vertices;
    std::vector<PointDef> around;
    for (std::size_t i = 0; i < by_edge.size();) {
      std::size_t j = i;
      while (j < by_edge.size() && by_edge[j].first == by_edge[i].first) ++j;
      const auto a = static_cast<VertexIndex>(by_edge[i].first >> 32);
      const auto b = static_cast<VertexIndex>(by_edge[i].first & 0xffffffffu);
      const std::size_t k = j - i;
      std::vector<std::size_t> order;
      if (k == 2) {
        order = {0, 1};
      } else if (k > 2 && k % 2 == 0) {
        around.clear();
        for (std::size_t m = i; m < j; ++m) {
          const Triangle& t = tris_[by_edge[m].second / 3];
          for (const VertexIndex v : t) {
            if (v != a && v != b) around.push_back(arrangement_.defs[v]);
          }
        }
        std::optional<std::vector<std::size_t>> sorted =
            order_around_edge(set_, arrangement_.defs[a], arrangement_.defs[b], around);
        if (!sorted) return fail(ArrangementSolid::Status::crowded_edge);
        order = std::move(*sorted);
        crowded_vertices.push_back(a);
        crowded_vertices.push_back(b);
      } else {
        return fail(ArrangementSolid::Status::crowded_edge);
      }
      for (std::size_t m = 0; m < k; ++m) {
        const std::uint32_t h = by_edge[i + order[m]].second;
        if (from(h) == a) continue;  // passes a -> b: the outside of the solid lies ahead
        const std::uint32_t g = by_edge[i + order[(m + 1) % k]].second;
        if (from(g) != a || twin[h] != no_index || twin[g] != no_index) return fail(ArrangementSolid::Status::crowded_edge);
        twin[h] = g;
        twin[g] = h;
      }
      i = j;
    }
    for (std::uint32_t h = 0; h < 3 * n; ++h) {
      if (twin[h] == no_index) return fail(ArrangementSolid::Status::crowded_edge);
    }
    split_fans(crowded_vertices, twin);

    // Which way each triangle faces its source's plane (exact).
    std::vector<std::uint8_t> front(n);
    for (std::uint32_t t = 0; t < n; ++t) {
      const Triangle& tri = boundary_.triangles[t];  // the arrangement's vertices
      const PointDef *a = &arrangement_.defs[tri[0]], *b = &arrangement_.defs[tri[1]], *c = &arrangement_.defs[tri[2]];
      front[t] = orient_in_plane(set_, projection(boundary_.source[t]), *a, arrangement_.approx[tri[0]], *b,
                                 arrangement_.approx[tri[1]], *c, arrangement_.approx[tri[2]]) == Sign::positive;
    }
    UnionFind groups(n);
    for (std::uint32_t h = 0; h < 3 * n; ++h) {
      const std::uint32_t t = h / 3, u = twin[h] / 3;
      if (u > t && boundary_.source[t] == boundary_.source[u] && front[t] == front[u]) groups.unite(t, u);
    }
    std::vector<std::uint32_t> group_of(n), first_of_group;
    {
      std::vector<std::uint32_t> index_of_root(n, no_index);
      for (std::uint32_t t = 0; t < n; ++t) {
        const std::uint32_t root = groups.find(t);
        if (index_of_root[root] == no_index) {
          index_of_root[root] = static_cast<std::uint32_t>(first_of_group.size());
          first_of_group.push_back(t);
        }
        group_of[t] = index_of_root[root];
      }
    }
    const auto group_count = static_cast<std::uint32_t>(first_of_group.size());
    std::vector<std::vector<std::uint32_t>> boundary_of(group_count);  // half-edges, in triangle order
    std::vector<std::uint32_t> size_of(group_count);
    for (std::uint32_t t = 0; t < n; ++t) {
      ++size_of[group_of[t]];
      for (std::uint32_t c = 0; c < 3; ++c) {
        const std::uint32_t h = 3 * t + c;
        if (group_of[twin[h] / 3] != group_of[t]) boundary_of[group_of[t]].push_back(h);
      }
    }
    for (std::uint32_t g = 0; g < group_count; ++g) out.merged_triangles += size_of[g] > 1 ? size_of[g] : 0;
    // A face whose boundary passes a vertex twice: where the solid is pinched
    // there (its fans meet at one point, as where a saddle of one part dips into
    // another), each fan gets its own copy of the vertex, as where solids touch
    // along an edge; where the two passes lie in one fan (a hole of the face
    // touching its outer loop), the loops are split there below.
    split_fans(pinched_vertices(boundary_of), twin);
    out.vertex_copies = origin_.size() - arrangement_.defs.size();
    collect_edge_sources(boundary_of);

    // The boundary half-edge of group g that leaves the end of boundary
    // half-edge h: turn about that vertex through g's triangles (across the
    // edges `twin` pairs them by) until an edge leaves g. By index alone, so
    // the loops follow the face's own corners wherever they touch.
    const auto next_in_group = [&](std::uint32_t h, std::uint32_t g) {
      std::uint32_t k = 3 * (h / 3) + (h % 3 + 1) % 3;
      while (group_of[twin[k] / 3] == g) k = 3 * (twin[k] / 3) + (twin[k] % 3 + 1) % 3;
      return k;
    };
    Solid& solid = out.solid;
    std::vector<VertexIndex> local(origin_.size(), no_index);
    std::unordered_map<std::uint32_t, std::uint32_t> position_of;  // half-edge -> position in the group's boundary
    std::unordered_map<VertexIndex, std::uint32_t> on_path;        // start vertex -> position in `path`
    std::vector<std::uint8_t> used;
    std::vector<std::uint32_t> cycle, path;
    for (std::uint32_t g = 0; g < group_count; ++g) {
      const std::vector<std::uint32_t>& edges = boundary_of[g];
      position_of.clear();
      for (std::uint32_t e = 0; e < edges.size(); ++e) position_of.emplace(edges[e], e);
      const std::uint32_t t0 = first_of_group[g];
      const std::uint32_t source = boundary_.source[t0];
      SolidFace face;
      face.plane = PlaneRef::input(source);
      face.reversed = !front[t0];
      face.surface = surfaces_[source];
      face.source = source;
      face.first_loop = static_cast<std::uint32_t>(solid.loops.size());
      // One loop: the group's boundary half-edges path[first..], in order.
      const auto add_loop = [&](std::size_t first) -> std::optional<ArrangementSolid::Status> {
        if (path.size() - first < 3) return ArrangementSolid::Status::pinched_face;
        SolidLoop loop{static_cast<std::uint32_t>(solid.corners.size()), 0};
        for (std::size_t k = first; k < path.size(); ++k) {
          const std::uint32_t h = edges[path[k]];
          const std::optional<EdgeLine> line = edge_line(h, twin[h]);
          if (!line) return ArrangementSolid::Status::no_edge_line;
          const VertexIndex v = from(h);
          if (local[v] == no_index) {
            local[v] = static_cast<VertexIndex>(solid.defs.size());
            solid.defs.push_back(arrangement_.defs[origin_[v]]);
            solid.approx.push_back(arrangement_.approx[origin_[v]]);
          }
          solid.corners.push_back({local[v], *line});
          ++loop.corner_count;
        }
        solid.loops.push_back(loop);
        ++face.loop_count;
        return std::nullopt;
      };
      used.assign(edges.size(), 0);
      for (std::uint32_t e = 0; e < edges.size(); ++e) {
        if (used[e]) continue;
        cycle.clear();
        std::uint32_t f = e;
        do {
          used[f] = 1;
          cycle.push_back(f);
          f = position_of.at(next_in_group(edges[f], g));
        } while (!used[f]);
        if (f != e) return fail(ArrangementSolid::Status::pinched_face);  // not expected: turning is a permutation
        // A cycle that passes a vertex twice is cut there into loops that each
        // pass it once (a face's loops are simple; the same edges bound the
        // same region).
        path.clear();
        on_path.clear();
        for (const std::uint32_t c : cycle) {
          const VertexIndex v = from(edges[c]);
          if (const auto again = on_path.find(v); again != on_path.end()) {
            const std::size_t first = again->second;
            for (std::size_t k = first; k < path.size(); ++k) on_path.erase(from(edges[path[k]]));
            if (const auto failed = add_loop(first)) return fail(*failed);
            path.resize(first);
          }
          on_path.emplace(v, static_cast<std::uint32_t>(path.size()));
          path.push_back(c);
        }
        if (const auto failed = add_loop(0)) return fail(*failed);
      }
      face.convex = convex(solid, face);
      solid.faces.push_back(face);
    }
    solid.convex = false;  // not decided here; false claims nothing
    return out;
  }

 private:
  // Over the vertices as split (tris_); origin_ maps them to the arrangement's.
  VertexIndex from(std::uint32_t h) const { return tris_[h / 3][h % 3]; }
  VertexIndex to(std::uint32_t h) const { return tris_[h / 3][(h % 3 + 1) % 3]; }

  // The vertices (as split) that some group's boundary passes more than once,
  // ascending.
  std::vector<VertexIndex> pinched_vertices(const std::vector<std::vector<std::uint32_t>>& boundary_of) const {
    std::vector<VertexIndex> pinched, starts;
    for (const std::vector<std::uint32_t>& edges : boundary_of) {
      starts.clear();
      for (const std::uint32_t h : edges) starts.push_back(from(h));
      std::sort(starts.begin(), starts.end());
      for (std::size_t k = 1; k < starts.size(); ++k) {
        if (starts[k] == starts[k - 1]) pinched.push_back(starts[k]);
      }
    }
    std::sort(pinched.begin(), pinched.end());
    pinched.erase(std::unique(pinched.begin(), pinched.end()), pinched.end());
    return pinched;
  }

  // Each of `vertices` (ends of edges where solids touch, vertices a face
  // passes twice) gets one copy per fan of triangles around it (triangles
  // joined across their edges at the vertex as `twin` pairs them), where it has
  // more than one: the copies are the same point, kept apart by index, as a cut
  // keeps the two sides of a pinch; round_solid moves them apart when it writes
  // the solid. The first fan keeps the vertex.
  void split_fans(std::vector<VertexIndex> vertices, const std::vector<std::uint32_t>& twin) {
    if (vertices.empty()) return;
    std::sort(vertices.begin(), vertices.end());
    vertices.erase(std::unique(vertices.begin(), vertices.end()), vertices.end());
    std::unordered_map<VertexIndex, std::vector<std::uint32_t>> corners;  // vertex -> its corners 3t + c
    for (const VertexIndex v : vertices) corners.try_emplace(v);
    for (std::uint32_t t = 0; t < tris_.size(); ++t) {
      for (std::uint32_t c = 0; c < 3; ++c) {
        const auto found = corners.find(tris_[t][c]);
        if (found != corners.end()) found->second.push_back(3 * t + c);
      }
    }
    for (const VertexIndex v : vertices) {
      const std::vector<std::uint32_t>& at = corners.at(v);
      std::unordered_map<std::uint32_t, std::uint32_t> slot;  // triangle -> its position in `at`
      for (std::uint32_t k = 0; k < at.size(); ++k) slot.emplace(at[k] / 3, k);
      UnionFind fans(at.size());
      for (std::uint32_t k = 0; k < at.size(); ++k) {
        const std::uint32_t t = at[k] / 3, c = at[k] % 3;
        // The two half-edges of t at v: from v, and into v.
        for (const std::uint32_t h : {3 * t + c, 3 * t + (c + 2) % 3}) fans.unite(k, slot.at(twin[h] / 3));
      }
      std::unordered_map<std::uint32_t, VertexIndex> copy_of;  // fan root -> vertex
      for (std::uint32_t k = 0; k < at.size(); ++k) {
        const std::uint32_t root = fans.find(k);
        auto [it, inserted] = copy_of.try_emplace(root, v);
        if (inserted && copy_of.size() > 1) {
          it->second = static_cast<VertexIndex>(origin_.size());
          origin_.push_back(v);
        }
        tris_[at[k] / 3][at[k] % 3] = it->second;
      }
    }
  }

  Projection projection(std::uint32_t source) {
    std::optional<Projection>& p = projection_[source];
    if (!p) p = projection_of(set_, PlaneRef::input(source));
    return *p;
  }

  const ApproxPoint& input_approx(VertexIndex p) {
    const auto [it, inserted] = input_approx_.try_emplace(p);
    if (inserted) it->second = approximate(set_, PointDef::input(p));
    return it->second;
  }

  // Whether input triangles s and u lie on one plane (exact, on the input points).
  bool coplanar(std::uint32_t s, std::uint32_t u) const {
    const std::array<VertexIndex, 3>& a = arrangement_.geometry.planes[s];
    const std::array<VertexIndex, 3>& b = arrangement_.geometry.planes[u];
    const std::vector<Vec3>& points = arrangement_.geometry.points;
    for (const VertexIndex v : b) {
      if (orient3d(points[a[0]], points[a[1]], points[a[2]], points[v]) != Sign::zero) return false;
    }
    return true;
  }

  // For every boundary edge, the input triangles of the arrangement's pieces
  // that have it, ascending: the planes and segments it may be said to lie on.
  void collect_edge_sources(const std::vector<std::vector<std::uint32_t>>& boundary_of) {
    for (const std::vector<std::uint32_t>& edges : boundary_of) {
      for (const std::uint32_t h : edges) edge_sources_.try_emplace(undirected_key(origin_[from(h)], origin_[to(h)]));
    }
    for (std::size_t k = 0; k < arrangement_.triangles.size(); ++k) {
      const Triangle& t = arrangement_.triangles[k];
      for (int c = 0; c < 3; ++c) {
        const auto found = edge_sources_.find(undirected_key(t[c], t[(c + 1) % 3]));
        if (found != edge_sources_.end()) found->second.push_back(arrangement_.source[k]);
      }
    }
    for (auto& [key, sources] : edge_sources_) {
      std::sort(sources.begin(), sources.end());
      sources.erase(std::unique(sources.begin(), sources.end()), sources.end());
    }
  }

  // The line of the edge of half-edge h (twin: the same edge in the face across),
  // the same from either side: see solid_from_winding_boundary.
  std::optional<EdgeLine> edge_line(std::uint32_t h, std::uint32_t twin) {
    const VertexIndex a = origin_[from(h)], b = origin_[to(h)];
    const std::uint32_t source = boundary_.source[h / 3], across = boundary_.source[twin / 3];
    const std::vector<std::uint32_t>& candidates = edge_sources_.at(undirected_key(a, b));
    EdgeLine line;
    for (const std::uint32_t s : candidates) {
      const std::array<VertexIndex, 3>& corners = arrangement_.geometry.planes[s];
      const Projection proj = projection(s);
      for (int k = 0; k < 3 && !line.is_segment(); ++k) {
        const VertexIndex p = corners[k], q = corners[(k + 1) % 3];
        const auto on = [&](VertexIndex x) {
          return orient_in_plane(set_, proj, PointDef::input(p), input_approx(p), PointDef::input(q), input_approx(q),
                                 arrangement_.defs[x], arrangement_.approx[x]) == Sign::zero;
        };
        if (on(a) && on(b)) {
          line.p = std::min(p, q);
          line.q = std::max(p, q);
        }
      }
      if (line.is_segment()) break;
    }
    if (!coplanar(source, across)) {
      line.other = PlaneRef::input(across);
    } else if (!line.is_segment()) {
      for (const std::uint32_t s : candidates) {
        if (!coplanar(source, s)) {
          line.other = PlaneRef::input(s);
          break;
        }
      }
      if (line.other.bits == no_index) return std::nullopt;
    }
    return line;
  }

  // One loop with no turn against the face's own (decided exactly).
  bool convex(const Solid& solid, const SolidFace& face) {
    if (face.loop_count != 1) return false;
    const SolidLoop& loop = solid.loops[face.first_loop];
    if (loop.corner_count == 3) return true;
    const Projection proj = projection(face.source);
    const Sign against = face.reversed ? Sign::positive : Sign::negative;
    VertexIndex before = solid.corners[loop.first_corner + loop.corner_count - 1].vertex;
    for (const CornerEdge& edge : loop_edges(solid.corners, loop)) {
      if (orient_in_plane(set_, proj, solid.defs[before], solid.approx[before], solid.defs[edge.from],
                          solid.approx[edge.from], solid.defs[edge.to], solid.approx[edge.to]) == against) {
        return false;
      }
      before = edge.from;
    }
    return true;
  }

  const MeshArrangement& arrangement_;
  const WindingBoundary& boundary_;
  std::span<const SurfaceId> surfaces_;
  PlaneSet set_;
  std::vector<std::optional<Projection>> projection_;
  std::unordered_map<VertexIndex, ApproxPoint> input_approx_;
  std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> edge_sources_;
  std::vector<Triangle> tris_;       // the boundary's triangles over the split vertices
  std::vector<VertexIndex> origin_;  // per split vertex, the arrangement's vertex it is
};

}  // namespace

ArrangementSolid solid_from_winding_boundary(const MeshArrangement& arrangement, const WindingBoundary& boundary,
                                             std::span<const SurfaceId> surfaces) {
  return SolidBuilder(arrangement, boundary, surfaces).run();
}

}  // namespace shatter
