#include "shatter/kernel/arrangement.hpp"

#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <algorithm>
#include <array>
#include <map>
#include <optional>
#include <utility>

#include "order_around.hpp"
#include "shatter/kernel/exact.hpp"
#include "shatter/kernel/predicates.hpp"
#include "shatter/kernel/rationals.hpp"
#include "shatter/kernel/union_find.hpp"

namespace shatter {
namespace {

using ExactCoordinates = std::array<mpq_class, 3>;

struct LessCoordinates {
  bool operator()(const ExactCoordinates& a, const ExactCoordinates& b) const {
    for (int k = 0; k < 3; ++k) {
      const int c = cmp(a[k], b[k]);
      if (c != 0) return c < 0;
    }
    return false;
  }
};

// One intersection inside a triangle: the segment (or point, a == b) where it
// meets another triangle, on the line where its plane meets `other`.
struct Trace {
  VertexIndex a = 0, b = 0;
  PlaneRef other;
};

using VertexBase = CGAL::Triangulation_vertex_base_with_info_2<VertexIndex, ExactKernel>;
using FaceBase = CGAL::Constrained_triangulation_face_base_2<ExactKernel>;
using Tds = CGAL::Triangulation_data_structure_2<VertexBase, FaceBase>;
// Constraints are cut beforehand wherever they meet, so none crosses another:
// the triangulation never constructs a point.
using Cdt = CGAL::Constrained_Delaunay_triangulation_2<ExactKernel, Tds, CGAL::No_constraint_intersection_tag>;

class Arranger {
 public:
  Arranger(std::span<const Vec3> positions, std::span<const Triangle> triangles)
      : positions_(positions), triangles_(triangles) {
    MeshArrangement& out = result_;
    out.geometry.points.assign(positions.begin(), positions.end());
    out.geometry.planes.reserve(triangles.size());
    out.geometry.plane_approx.reserve(triangles.size());
    for (const Triangle& t : triangles) {
      out.geometry.planes.push_back(t);
      out.geometry.plane_approx.push_back(approximate_input_plane(positions[t[0]], positions[t[1]], positions[t[2]]));
    }
    out.defs.reserve(positions.size());
    out.approx.reserve(positions.size());
    for (VertexIndex v = 0; v < positions.size(); ++v) {
      out.defs.push_back(PointDef::input(v));
      // An input point's approximation is exact: no plane is involved.
      out.approx.push_back({{positions[v].x, 0}, {positions[v].y, 0}, {positions[v].z, 0}, {1, 0}});
    }
    set_ = out.geometry.plane_set({});
  }

  MeshArrangement run() {
    MeshArrangement& out = result_;
    out.pairs = self_intersecting_pairs(positions_, triangles_);
    traces_.resize(triangles_.size());
    // The corners of the triangles involved are known points before any new
    // one is made, so a new point that is an input vertex exactly is that
    // vertex (the lowest index of its position), never a copy of it.
    std::vector<VertexIndex> corners;
    for (const TrianglePair& pair : out.pairs) {
      for (const std::size_t t : {pair.first, pair.second})
        corners.insert(corners.end(), triangles_[t].begin(), triangles_[t].end());
    }
    std::sort(corners.begin(), corners.end());
    corners.erase(std::unique(corners.begin(), corners.end()), corners.end());
    for (VertexIndex v : corners) intern(PointDef::input(v));
    // Triangles overlapping on one plane are triangulated together (one group
    // per set of them joined by such overlaps), so that where they overlap
    // their pieces are the same triangles, vertex for vertex.
    UnionFind groups(triangles_.size());
    for (const TrianglePair& pair : out.pairs) {
      const auto t = static_cast<std::uint32_t>(pair.first), u = static_cast<std::uint32_t>(pair.second);
      if (on_one_plane(t, u)) {
        out.coplanar_pairs.push_back(pair);
        groups.unite(t, u);
        continue;
      }
      intersect(t, u);
    }
    std::vector<std::vector<std::uint32_t>> members(triangles_.size());
    for (std::uint32_t t = 0; t < triangles_.size(); ++t) members[groups.find(t)].push_back(t);
    std::vector<std::vector<Triangle>> pieces(triangles_.size());
    for (std::uint32_t t = 0; t < triangles_.size(); ++t) {
      if (members[t].size() > 1 || (members[t].size() == 1 && !traces_[t].empty())) split(members[t], pieces);
    }
    for (std::uint32_t t = 0; t < triangles_.size(); ++t) {
      if (pieces[t].empty()) {
        out.triangles.push_back(triangles_[t]);
        out.source.push_back(t);
        continue;
      }
      for (const Triangle& piece : pieces[t]) {
        out.triangles.push_back(piece);
        out.source.push_back(t);
      }
      out.split_triangles += pieces[t].size() > 1;
    }
    return std::move(result_);
  }

 private:
  PlaneRef plane(std::uint32_t t) const { return PlaneRef::input(t); }

  Sign side_of(std::uint32_t t, VertexIndex v) const {
    const Triangle& tri = triangles_[t];
    return orient3d(positions_[tri[0]], positions_[tri[1]], positions_[tri[2]], positions_[v]);
  }

  bool on_one_plane(std::uint32_t t, std::uint32_t u) const {
    for (VertexIndex v : triangles_[u]) {
      if (side_of(t, v) != Sign::zero) return false;
    }
    return true;
  }

  // The vertex at `def`'s point: an existing one when some vertex is that point
  // exactly (an input vertex included), else a new one.
  VertexIndex intern(const PointDef& def) {
    ExactCoordinates key = exact_coordinates(set_, def);
    const auto candidate = static_cast<VertexIndex>(result_.defs.size());
    const auto [it, inserted] = vertex_at_.emplace(std::move(key), def.kind == PointKind::input ? def.a : candidate);
    if (inserted && def.kind != PointKind::input) {
      result_.defs.push_back(def);
      result_.approx.push_back(approximate(set_, def));
    }
    return it->second;
  }

  // A plane through input points p and q across the plane of triangle t (which
  // holds them both): through p, q and p moved off that plane along the axis
  // t's projection drops (its normal is not zero there). An input plane past
  // the triangles' own, made once per edge: the carrier that defines where
  // another segment of t's plane crosses the edge p q.
  // The plane depends on the axis, not on t: one made for an edge of a
  // triangle on another plane (an edge two planes share) serves t if it moved
  // off along the same axis, which t's normal does not lie across.
  PlaneRef edge_plane(VertexIndex p, VertexIndex q, std::uint32_t t) {
    if (q < p) std::swap(p, q);
    const int axis = projection_of(set_, plane(t)).axis;
    const std::array<VertexIndex, 3> key{p, q, static_cast<VertexIndex>(axis)};
    const auto found = edge_planes_.find(key);
    if (found != edge_planes_.end()) return found->second;
    InputGeometry& geometry = result_.geometry;
    Vec3 off = positions_[p];
    double& c = axis == 0 ? off.x : axis == 1 ? off.y : off.z;
    // Any other value moves the point off the plane; + 1 keeps it near the
    // mesh where it can (not past 2^53, where it rounds back to c).
    c = c + 1 != c ? c + 1 : c * 0.5;
    const auto w = static_cast<VertexIndex>(geometry.points.size());
    geometry.points.push_back(off);
    const auto index = static_cast<std::uint32_t>(geometry.planes.size());
    geometry.planes.push_back({p, q, w});
    geometry.plane_approx.push_back(approximate_input_plane(positions_[p], positions_[q], off));
    set_ = geometry.plane_set({});  // the arrays may have moved
    const PlaneRef made = PlaneRef::input(index);
    edge_planes_.emplace(key, made);
    return made;
  }

  // The points where triangle t meets the plane of u (t not on it): its corners
  // on that plane and the crossings of its edges with it; none, one or two, as a
  // triangle meets a plane in nothing, a point or a segment.
  std::vector<PointDef> section(std::uint32_t t, std::uint32_t u) const {
    const Triangle& tri = triangles_[t];
    std::array<Sign, 3> s{};
    for (int k = 0; k < 3; ++k) s[k] = side_of(u, tri[k]);
    std::vector<PointDef> points;
    for (int k = 0; k < 3; ++k) {
      const VertexIndex p = tri[k], q = tri[(k + 1) % 3];
      if (s[k] == Sign::zero) points.push_back(PointDef::input(p));
      const Sign next = s[(k + 1) % 3];
      if (s[k] != Sign::zero && next != Sign::zero && s[k] != next) {
        points.push_back(PointDef::segment_plane(std::min(p, q), std::max(p, q), plane(u)));
      }
    }
    return points;
  }

  // Order along the line where the planes of t and u meet.
  Sign along(std::uint32_t t, std::uint32_t u, const PointDef& p, const PointDef& q) const {
    return compare_along(set_, plane(t), plane(u), p, approximate(set_, p), q, approximate(set_, q));
  }

  void intersect(std::uint32_t t, std::uint32_t u) {
    std::vector<PointDef> in_t = section(t, u), in_u = section(u, t);
    if (in_t.empty() || in_u.empty()) return;
    const auto sort_pair = [&](std::vector<PointDef>& points) {
      // points.front() the later end, points.back() the earlier.
      if (points.size() == 2 && along(t, u, points[0], points[1]) == Sign::positive) std::swap(points[0], points[1]);
    };
    sort_pair(in_t);
    sort_pair(in_u);
    // The two sections lie on one line: their overlap runs from the later of
    // their earlier ends to the earlier of their later ends.
    const PointDef& low = along(t, u, in_t.back(), in_u.back()) == Sign::positive ? in_u.back() : in_t.back();
    const PointDef& high = along(t, u, in_t.front(), in_u.front()) == Sign::negative ? in_u.front() : in_t.front();
    if (along(t, u, low, high) == Sign::negative) return;  // they miss each other on the line
    const VertexIndex a = intern(low), b = intern(high);
    traces_[t].push_back({a, b, plane(u)});
    traces_[u].push_back({a, b, plane(t)});
  }

  // A segment to triangulate along: an edge of a member of the group (a, b its
  // interned corners, `edge` true, `owner` the member), or a trace in `owner`
  // on the plane `other`.
  struct Segment {
    VertexIndex a = 0, b = 0;
    std::uint32_t owner = 0;
    bool edge = false;
    PlaneRef other;
  };

  // The triangles of `group` (on one plane; one triangle, or triangles joined
  // by overlaps on that plane) cut by their edges and traces and triangulated
  // together; each member's pieces, the faces inside it, into pieces[member].
  void split(const std::vector<std::uint32_t>& group, std::vector<std::vector<Triangle>>& pieces) {
    const std::uint32_t first = group.front();
    const Projection projection = projection_of(set_, plane(first));
    const auto orient = [&](VertexIndex p, VertexIndex q, VertexIndex r) {
      return orient_in_plane(set_, projection, result_.defs[p], result_.approx[p], result_.defs[q], result_.approx[q],
                             result_.defs[r], result_.approx[r]);
    };
    std::vector<VertexIndex> vertices;
    const auto add = [&](VertexIndex v) {
      if (std::find(vertices.begin(), vertices.end(), v) == vertices.end()) vertices.push_back(v);
    };
    // A corner repeated elsewhere as the same position (an unwelded input) is
    // the vertex the traces use for that point.
    std::vector<std::array<VertexIndex, 3>> corners;
    std::vector<Segment> segments;
    for (const std::uint32_t t : group) {
      const Triangle& tri = triangles_[t];
      std::array<VertexIndex, 3> corner{};
      for (int k = 0; k < 3; ++k) corner[k] = intern(PointDef::input(tri[k]));
      for (VertexIndex v : corner) add(v);
      corners.push_back(corner);
      for (int k = 0; k < 3; ++k) segments.push_back({corner[k], corner[(k + 1) % 3], t, true, {}});
    }
    for (const std::uint32_t t : group) {
      for (const Trace& trace : traces_[t]) {
        add(trace.a);
        add(trace.b);
        if (trace.a != trace.b) segments.push_back({trace.a, trace.b, t, false, trace.other});
      }
    }
    // Two segments that cross each other strictly inside both: an edge's
    // meet with the other's carrier plane (a trace's other plane, or a plane
    // across the group's through another member's edge), or, for two traces,
    // their planes' meet with this one. A member's own edges meet each other
    // and its traces only at their ends.
    for (std::size_t i = 0; i < segments.size(); ++i) {
      const Segment& x = segments[i];
      for (std::size_t j = i + 1; j < segments.size(); ++j) {
        const Segment& y = segments[j];
        if (x.owner == y.owner && (x.edge || y.edge)) continue;
        const Sign ya = orient(x.a, x.b, y.a), yb = orient(x.a, x.b, y.b);
        if (ya == Sign::zero || yb == Sign::zero || ya == yb) continue;
        const Sign xa = orient(y.a, y.b, x.a), xb = orient(y.a, y.b, x.b);
        if (xa == Sign::zero || xb == Sign::zero || xa == xb) continue;
        if (!x.edge && !y.edge) {
          std::array<PlaneRef, 3> planes{plane(x.owner), x.other, y.other};
          std::sort(planes.begin(), planes.end(), [](PlaneRef p, PlaneRef q) { return p.bits < q.bits; });
          add(intern(PointDef::three_planes(planes[0], planes[1], planes[2])));
          continue;
        }
        const Segment& e = x.edge ? x : y;
        const Segment& o = x.edge ? y : x;
        const PlaneRef carrier = o.edge ? edge_plane(o.a, o.b, o.owner) : o.other;
        add(intern(PointDef::segment_plane(std::min(e.a, e.b), std::max(e.a, e.b), carrier)));
      }
    }

    // Every segment cut at the vertices that lie inside it, in order along it.
    const int kept[2] = {(projection.axis + 1) % 3, (projection.axis + 2) % 3};
    std::vector<std::pair<VertexIndex, VertexIndex>> constraints;
    std::vector<VertexIndex> inside;
    for (const Segment& segment : segments) {
      const VertexIndex a = segment.a, b = segment.b;
      // An axis of the projection along which a and b differ orders the segment.
      int axis = kept[0];
      Sign ab = compare_coordinate(set_, axis, result_.defs[a], result_.approx[a], result_.defs[b], result_.approx[b]);
      if (ab == Sign::zero) {
        axis = kept[1];
        ab = compare_coordinate(set_, axis, result_.defs[a], result_.approx[a], result_.defs[b], result_.approx[b]);
      }
      const auto before = [&](VertexIndex p, VertexIndex q) {  // p before q going from a to b
        const Sign s =
            compare_coordinate(set_, axis, result_.defs[p], result_.approx[p], result_.defs[q], result_.approx[q]);
        return s == ab;
      };
      inside.clear();
      for (VertexIndex v : vertices) {
        if (v == a || v == b || orient(a, b, v) != Sign::zero) continue;
        if (before(a, v) && before(v, b)) inside.push_back(v);
      }
      std::sort(inside.begin(), inside.end(), before);
      VertexIndex from = a;
      for (VertexIndex v : inside) {
        constraints.emplace_back(from, v);
        from = v;
      }
      constraints.emplace_back(from, b);
    }

    // A trace along an edge or along another trace gives the same pieces again,
    // and CGAL 5.5's constrained triangulation refuses a constraint inserted
    // twice ("Unauthorized intersections of constraints" under
    // No_constraint_intersection_tag): each piece once.
    for (auto& [a, b] : constraints) {
      if (b < a) std::swap(a, b);
    }
    std::sort(constraints.begin(), constraints.end());
    constraints.erase(std::unique(constraints.begin(), constraints.end()), constraints.end());
    Cdt cdt;
    std::vector<Cdt::Vertex_handle> handles;
    handles.reserve(vertices.size());
    for (VertexIndex v : vertices) {
      const ExactCoordinates c = exact_coordinates(set_, result_.defs[v]);
      const Cdt::Vertex_handle h =
          cdt.insert(ExactKernel::Point_2(ExactKernel::FT(c[kept[0]]), ExactKernel::FT(c[kept[1]])));
      h->info() = v;
      handles.push_back(h);
    }
    const auto position = [&](VertexIndex v) {
      return static_cast<std::size_t>(std::find(vertices.begin(), vertices.end(), v) - vertices.begin());
    };
    for (const auto& [a, b] : constraints) cdt.insert_constraint(handles[position(a)], handles[position(b)]);

    // The triangulation covers the convex hull of the points, which is the
    // union of the members' hulls; every member's edges are constraints, so
    // each face lies inside a member or outside it, and inside exactly when its
    // three corners lie in the closed member (a convex set). Faces turn
    // counter-clockwise in the projection, which is the first member's turn
    // unless the projection flips it, and a member's own unless it faces the
    // other way.
    std::vector<std::vector<char>> in(group.size());  // [member][position of vertex]
    for (std::size_t m = 0; m < group.size(); ++m) {
      in[m].assign(vertices.size(), 1);
      if (group.size() == 1) continue;
      const std::array<VertexIndex, 3>& c = corners[m];
      const Sign turn = orient(c[0], c[1], c[2]);
      for (std::size_t k = 0; k < vertices.size(); ++k) {
        const VertexIndex v = vertices[k];
        for (int e = 0; e < 3 && in[m][k]; ++e) {
          const Sign s = orient(c[e], c[(e + 1) % 3], v);
          if (s != Sign::zero && s != turn) in[m][k] = 0;
        }
      }
    }
    std::vector<bool> reversed(group.size());
    for (std::size_t m = 0; m < group.size(); ++m) {
      reversed[m] = projection.flipped != (m > 0 && compare_normals(set_, plane(group[m]), plane(first)) == Sign::negative);
    }
    for (auto f = cdt.finite_faces_begin(); f != cdt.finite_faces_end(); ++f) {
      const std::array<std::size_t, 3> at{position(f->vertex(0)->info()), position(f->vertex(1)->info()),
                                          position(f->vertex(2)->info())};
      for (std::size_t m = 0; m < group.size(); ++m) {
        if (!in[m][at[0]] || !in[m][at[1]] || !in[m][at[2]]) continue;
        Triangle piece{vertices[at[0]], vertices[at[1]], vertices[at[2]]};
        if (reversed[m]) std::swap(piece[1], piece[2]);
        // A fixed order of the pieces (the face list's order is the
        // triangulation's own): each rotated to start at its least vertex.
        std::rotate(piece.begin(), std::min_element(piece.begin(), piece.end()), piece.end());
        pieces[group[m]].push_back(piece);
      }
    }
    for (const std::uint32_t t : group) std::sort(pieces[t].begin(), pieces[t].end());
  }

  std::span<const Vec3> positions_;
  std::span<const Triangle> triangles_;
  MeshArrangement result_;
  PlaneSet set_;
  std::vector<std::vector<Trace>> traces_;
  std::map<ExactCoordinates, VertexIndex, LessCoordinates> vertex_at_;
  std::map<std::array<VertexIndex, 3>, PlaneRef> edge_planes_;  // by (p, q, axis)
};

}  // namespace

MeshArrangement arrange_triangles(std::span<const Vec3> positions, std::span<const Triangle> triangles) {
  return Arranger(positions, triangles).run();
}

std::optional<std::vector<std::size_t>> order_around_edge(const PlaneSet& set, const PointDef& p, const PointDef& q,
                                                          std::span<const PointDef> around) {
  std::vector<ExactCoordinates> points;
  points.reserve(around.size());
  for (const PointDef& def : around) points.push_back(exact_coordinates(set, def));
  return kernel_detail::order_around_exact(exact_coordinates(set, p), exact_coordinates(set, q), points);
}

}  // namespace shatter
