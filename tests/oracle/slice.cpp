#include "shatter/oracle/slice.hpp"

#include <algorithm>

#include "shatter/kernel/index_map.hpp"
#include "shatter/kernel/projection_exact.hpp"

namespace shatter::oracle {
namespace {

// Where an output corner's attributes come from: a source corner, or the
// interpolation from source corner `from` to `to` at parameter t.
struct CornerSource {
  std::uint32_t from;
  std::uint32_t to;
  double t;  // 0 for a plain copy
};

Vec3 lerp(Vec3 a, Vec3 b, double t) { return a + (b - a) * t; }

void append_corner(CornerAttributes& out, const CornerAttributes& in, const CornerSource& source) {
  if (in.has_normals()) {
    const Vec3 n = source.t == 0 ? in.normals[source.from]
                                 : normalized(lerp(in.normals[source.from], in.normals[source.to], source.t));
    out.normals.push_back(n);
  }
  if (in.has_uvs()) {
    const Vec2 a = in.uvs[source.from], b = in.uvs[source.to];
    out.uvs.push_back({a.x + (b.x - a.x) * source.t, a.y + (b.y - a.y) * source.t});
  }
  if (in.has_tangents()) {
    const Vec4 a = in.tangents[source.from], b = in.tangents[source.to];
    const Vec3 xyz = source.t == 0 ? Vec3{a.x, a.y, a.z}
                                   : normalized(lerp({a.x, a.y, a.z}, {b.x, b.y, b.z}, source.t));
    // Handedness is a discrete flag: keep the source corner's.
    out.tangents.push_back({xyz.x, xyz.y, xyz.z, a.w});
  }
}

template <class Point>
class Slicer {
 public:
  Slicer(const BasicMesh<Point>& mesh, const Plane& plane)
      : mesh_(mesh), plane_(plane), projection_(PlaneProjection::of(plane)), has_attributes_(mesh.corners.has_normals() || mesh.corners.has_uvs() ||
                                                    mesh.corners.has_tangents()) {}

  SlicedMesh<Point> run() {
    out_.input_vertex_count = mesh_.positions.size();
    out_.positions = mesh_.positions;
    classify_vertices();
    if (!any_below_ || !any_above_) {
      // Nothing to split: the whole mesh lies on one side (vertices on the plane do
      // not vote). A flat mesh with every vertex on the plane goes below.
      OpenHalf& whole = any_above_ ? out_.above : out_.below;
      whole.triangles = mesh_.triangles;
      whole.surfaces = mesh_.surfaces;
      whole.corners = mesh_.corners;
      return std::move(out_);
    }
    crossing_vertex_of_edge_.reset(mesh_.triangles.size() / 4 + 16);
    for (TriangleIndex t = 0; t < mesh_.triangles.size(); ++t) slice_triangle(t);
    if (any_on_plane_) collect_border_edges_along_plane();
    return std::move(out_);
  }

 private:
  void classify_vertices() {
    sides_.resize(mesh_.positions.size());
    for (std::size_t v = 0; v < sides_.size(); ++v) {
      const Sign s = side_of_plane(plane_, mesh_.positions[v]);
      sides_[v] = s;
      any_below_ |= s == Sign::negative;
      any_above_ |= s == Sign::positive;
      any_on_plane_ |= s == Sign::zero;
    }
  }

  OpenHalf& half(Sign side) { return side == Sign::positive ? out_.above : out_.below; }

  void emit(OpenHalf& half, const Triangle& triangle, SurfaceId surface,
            const std::array<CornerSource, 3>& sources) {
    half.triangles.push_back(triangle);
    half.surfaces.push_back(surface);
    if (has_attributes_) {
      for (const CornerSource& source : sources) append_corner(half.corners, mesh_.corners, source);
    }
  }

  void slice_triangle(TriangleIndex t) {
    const Triangle& tri = mesh_.triangles[t];
    const SurfaceId surface = mesh_.surfaces[t];
    const std::array<Sign, 3> s = {sides_[tri[0]], sides_[tri[1]], sides_[tri[2]]};
    const bool has_above = std::find(s.begin(), s.end(), Sign::positive) != s.end();
    const bool has_below = std::find(s.begin(), s.end(), Sign::negative) != s.end();
    const std::uint32_t c0 = 3 * t;
    const std::array<CornerSource, 3> copy = {CornerSource{c0, c0, 0}, {c0 + 1, c0 + 1, 0},
                                              {c0 + 2, c0 + 2, 0}};
    if (!(has_above && has_below)) {
      Sign side = has_above ? Sign::positive : has_below ? Sign::negative : Sign::zero;
      if (side == Sign::zero) {
        // In the plane: the lid of the solid on the side it faces away from.
        const Sign facing = orientation_in_projection(projection_, mesh_.positions[tri[0]],
                                                      mesh_.positions[tri[1]], mesh_.positions[tri[2]]);
        side = facing == Sign::positive ? Sign::negative : Sign::positive;
      }
      OpenHalf& target = half(side);
      if (side == Sign::positive && any_on_plane_) note_edges_along_plane(tri);
      emit(target, tri, surface, copy);
      return;
    }
    // Rotate so that corner 0 is the one that differs: the vertex on the plane if
    // there is one, else the lone vertex on its side.
    int first = 0;
    const auto zero = std::find(s.begin(), s.end(), Sign::zero);
    if (zero != s.end()) {
      first = static_cast<int>(zero - s.begin());
    } else {
      first = s[0] == s[1] ? 2 : s[0] == s[2] ? 1 : 0;
    }
    const int i1 = (first + 1) % 3, i2 = (first + 2) % 3;
    const VertexIndex a = tri[first], b = tri[i1], c = tri[i2];
    const std::uint32_t ca = c0 + first, cb = c0 + i1, cc = c0 + i2;
    const CornerSource keep_a{ca, ca, 0}, keep_b{cb, cb, 0}, keep_c{cc, cc, 0};

    if (s[first] == Sign::zero) {
      // a on the plane, b and c strictly opposite: one new vertex on (b, c).
      const VertexIndex m = crossing_vertex(b, c);
      const CornerSource at_m = corner_at_crossing(m, b, cb, cc);
      emit(half(s[i1]), {a, b, m}, surface, {keep_a, keep_b, at_m});
      emit(half(s[i2]), {a, m, c}, surface, {keep_a, at_m, keep_c});
      out_.border_edges.push_back(s[i1] == Sign::positive ? Edge{m, a} : Edge{a, m});
      return;
    }
    // a alone on its side: new vertices on (a, b) and (c, a); the quad on the other
    // side is convex, so either diagonal gives two non-degenerate triangles.
    const VertexIndex m_ab = crossing_vertex(a, b);
    const VertexIndex m_ca = crossing_vertex(c, a);
    const CornerSource at_ab = corner_at_crossing(m_ab, a, ca, cb);
    const CornerSource at_ca = corner_at_crossing(m_ca, a, ca, cc);
    emit(half(s[first]), {a, m_ab, m_ca}, surface, {keep_a, at_ab, at_ca});
    OpenHalf& other = half(s[i1]);
    emit(other, {m_ab, b, c}, surface, {at_ab, keep_b, keep_c});
    emit(other, {m_ab, c, m_ca}, surface, {at_ab, keep_c, at_ca});
    out_.border_edges.push_back(s[first] == Sign::positive ? Edge{m_ab, m_ca} : Edge{m_ca, m_ab});
  }

  // The one new vertex of crossing edge (p, q), created on first use. Its position
  // is computed from the endpoints in index order, so both triangles of the edge
  // (which traverse it in opposite directions) share one vertex and one point.
  VertexIndex crossing_vertex(VertexIndex p, VertexIndex q) {
    const VertexIndex lo = std::min(p, q), hi = std::max(p, q);
    const auto next = static_cast<VertexIndex>(out_.positions.size());
    const VertexIndex found = crossing_vertex_of_edge_.insert(directed_edge_key(lo, hi), next);
    if (found != next) return found;
    auto crossing = crossing_point(plane_, mesh_.positions[lo], mesh_.positions[hi]);
    out_.positions.push_back(std::move(crossing.point));
    out_.crossing_edges.push_back({lo, hi});
    crossing_parameter_.push_back(crossing.t);
    return next;
  }

  // Attributes of the corner at new vertex m, interpolated between the triangle's
  // corner at vertex `from` (corner index from_corner) and its other corner.
  CornerSource corner_at_crossing(VertexIndex m, VertexIndex from, std::uint32_t from_corner,
                                  std::uint32_t to_corner) const {
    const std::size_t i = m - out_.input_vertex_count;
    const double t = crossing_parameter_[i];  // along crossing_edges[i], low index to high
    if (out_.crossing_edges[i][0] == from) return {from_corner, to_corner, t};
    return {to_corner, from_corner, t};
  }

  // Edges with both ends on the plane can be border edges only when they are
  // original edges of unsplit triangles. Remember those of the above half; the
  // ones whose twin is not above are its boundary.
  void note_edges_along_plane(const Triangle& tri) {
    for (int k = 0; k < 3; ++k) {
      const VertexIndex u = tri[k], v = tri[(k + 1) % 3];
      if (sides_[u] == Sign::zero && sides_[v] == Sign::zero) {
        above_edges_along_plane_.push_back({u, v});
      }
    }
  }

  void collect_border_edges_along_plane() {
    IndexMap present(above_edges_along_plane_.size());
    for (const Edge& e : above_edges_along_plane_) present.insert(directed_edge_key(e[0], e[1]), 1);
    for (const Edge& e : above_edges_along_plane_) {
      if (present.find(directed_edge_key(e[1], e[0])) == IndexMap::absent) out_.border_edges.push_back(e);
    }
  }

  const BasicMesh<Point>& mesh_;
  const Plane plane_;
  const PlaneProjection projection_;
  const bool has_attributes_;
  std::vector<Sign> sides_;
  bool any_below_ = false, any_above_ = false, any_on_plane_ = false;
  IndexMap crossing_vertex_of_edge_;
  std::vector<double> crossing_parameter_;
  std::vector<Edge> above_edges_along_plane_;
  SlicedMesh<Point> out_;
};

}  // namespace

ExactPoint exact_position(const SlicedMesh<Vec3>& sliced, const Plane& plane, VertexIndex v) {
  if (v < sliced.input_vertex_count) {
    const Vec3& p = sliced.positions[v];
    return {p.x, p.y, p.z};
  }
  const Edge& edge = sliced.crossing_edges[v - sliced.input_vertex_count];
  return exact_crossing_point(plane, sliced.positions[edge[0]], sliced.positions[edge[1]]);
}

SlicedMesh<Vec3> slice_mesh(const Mesh& mesh, const Plane& plane) { return Slicer<Vec3>(mesh, plane).run(); }

SlicedMesh<ExactPoint> slice_mesh(const ExactMesh& mesh, const Plane& plane) {
  return Slicer<ExactPoint>(mesh, plane).run();
}

}  // namespace shatter::oracle
