#include "shatter/triangulate/cap.hpp"

#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_face_base_with_info_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <deque>
#include <optional>
#include <type_traits>

#include "shatter/kernel/error.hpp"
#include "shatter/kernel/index_map.hpp"
#include "shatter/kernel/projection_exact.hpp"

namespace shatter {

std::vector<std::vector<VertexIndex>> link_loops(std::span<const Edge> border) {
  // first_out: vertex -> an edge leaving it; next_out chains the others, so a
  // vertex where loops meet (a pinch) hands out each of its edges once.
  IndexMap first_out(border.size());
  std::vector<std::uint32_t> next_out(border.size(), IndexMap::absent);
  for (std::uint32_t e = 0; e < border.size(); ++e) {
    const std::uint32_t head = first_out.insert(border[e][0], e);
    if (head != e) {
      next_out[e] = next_out[head];
      next_out[head] = e;
    }
  }
  std::vector<bool> used(border.size(), false);
  std::vector<std::vector<VertexIndex>> loops;
  for (std::uint32_t start = 0; start < border.size(); ++start) {
    if (used[start]) continue;
    std::vector<VertexIndex> loop;
    std::uint32_t e = start;
    while (e != IndexMap::absent && !used[e]) {
      used[e] = true;
      loop.push_back(border[e][0]);
      const VertexIndex to = border[e][1];
      if (to == border[start][0]) break;
      std::uint32_t candidate = first_out.find(to);
      while (candidate != IndexMap::absent && used[candidate]) candidate = next_out[candidate];
      e = candidate;
    }
    loops.push_back(std::move(loop));
  }
  return loops;
}

namespace {

template <class Point2>
Sign orientation_2d(const Point2& a, const Point2& b, const Point2& c) {
  const CGAL::Orientation o = CGAL::orientation(a, b, c);
  return o == CGAL::LEFT_TURN ? Sign::positive : o == CGAL::RIGHT_TURN ? Sign::negative : Sign::zero;
}

// The fan from loop[apex] is a triangulation of the loop exactly when every fan
// triangle is strictly counter-clockwise and every fan vertex lies strictly within
// the half-turn from the first fan edge: the triangles then occupy disjoint angular
// sectors around the apex whose union is bounded by the loop.
template <class Point2>
bool fan_is_valid(const std::vector<Point2>& loop, std::size_t apex) {
  const std::size_t n = loop.size();
  const Point2& o = loop[apex];
  const Point2& first = loop[(apex + 1) % n];
  for (std::size_t k = 1; k + 1 < n; ++k) {
    const Point2& p = loop[(apex + k) % n];
    const Point2& q = loop[(apex + k + 1) % n];
    if (orientation_2d(o, p, q) != Sign::positive) return false;
    if (orientation_2d(o, first, q) != Sign::positive) return false;
  }
  return true;
}

// Tries a fan from a few apexes (all of them for small loops, where collinear runs
// from exact constructions make some apexes fail).
template <class Point2>
std::optional<std::vector<Triangle>> try_fan(const std::vector<VertexIndex>& loop,
                                             const std::vector<Point2>& points) {
  constexpr std::size_t apexes_tried = 8;
  const std::size_t n = loop.size();
  if (n < 3) return std::nullopt;
  for (std::size_t apex = 0; apex < std::min(n, apexes_tried); ++apex) {
    if (!fan_is_valid(points, apex)) continue;
    std::vector<Triangle> triangles;
    triangles.reserve(n - 2);
    for (std::size_t k = 1; k + 1 < n; ++k) {
      triangles.push_back({loop[apex], loop[(apex + k) % n], loop[(apex + k + 1) % n]});
    }
    return triangles;
  }
  return std::nullopt;
}

}  // namespace

bool cap_boundary_is_border(std::span<const Triangle> triangles, std::span<const Edge> border) {
  IndexMap cap_edges(3 * triangles.size());
  for (const Triangle& t : triangles) {
    for (int k = 0; k < 3; ++k) {
      const VertexIndex u = t[k], v = t[(k + 1) % 3];
      const std::uint64_t key = directed_edge_key(u, v);
      if (u == v || cap_edges.find(key) != IndexMap::absent) return false;  // degenerate, or an edge used twice
      cap_edges.insert(key, 1);
    }
  }
  IndexMap border_edges(border.size());
  for (const Edge& e : border) {
    if (cap_edges.find(directed_edge_key(e[0], e[1])) == IndexMap::absent) return false;
    if (cap_edges.find(directed_edge_key(e[1], e[0])) != IndexMap::absent) return false;
    border_edges.insert(directed_edge_key(e[0], e[1]), 1);
  }
  for (const Triangle& t : triangles) {
    for (int k = 0; k < 3; ++k) {
      const VertexIndex u = t[k], v = t[(k + 1) % 3];
      if (border_edges.find(directed_edge_key(u, v)) != IndexMap::absent) continue;
      if (cap_edges.find(directed_edge_key(v, u)) == IndexMap::absent) return false;
    }
  }
  return true;
}

bool flip_to_counter_clockwise(std::vector<Triangle>& triangles, std::span<const Edge> border,
                               std::span<const Vec3> positions,
                               const std::function<bool(VertexIndex, VertexIndex, VertexIndex)>& counter_clockwise) {
  std::vector<std::uint32_t> slivers;
  for (std::uint32_t t = 0; t < triangles.size(); ++t) {
    if (!counter_clockwise(triangles[t][0], triangles[t][1], triangles[t][2])) slivers.push_back(t);
  }
  if (slivers.empty()) return true;
  // Slivers are rare (about one cap in fifteen of a fractured curved mesh, one
  // or two triangles each), so each neighbour is found by a scan; a border edge
  // has none, as the region lies on its left only.
  const auto across = [&](VertexIndex u, VertexIndex v) -> std::uint32_t {
    for (std::uint32_t t = 0; t < triangles.size(); ++t) {
      const Triangle& n = triangles[t];
      for (int k = 0; k < 3; ++k) {
        if (n[k] == v && n[(k + 1) % 3] == u) return t;
      }
    }
    return IndexMap::absent;
  };
  // Flips edge k of triangle t, (u, v), shared with the neighbour (v, u, x): the
  // diagonal u-v of quadrilateral u, x, v, w becomes x-w, when both new
  // triangles are counter-clockwise exactly (else nothing changes).
  // `delaunay_only`: and only when the edge is not locally Delaunay on the
  // rounded positions (the angles at w and x sum to more than a half-turn): a
  // choice of shape, which no validity rests on.
  std::uint32_t changed = IndexMap::absent;
  const auto flip = [&](std::uint32_t t, int k, bool delaunay_only) {
    const VertexIndex u = triangles[t][k], v = triangles[t][(k + 1) % 3], w = triangles[t][(k + 2) % 3];
    const std::uint32_t n = across(u, v);
    if (n == IndexMap::absent) return false;
    VertexIndex x = triangles[n][0];
    for (const VertexIndex corner : triangles[n]) {
      if (corner != u && corner != v) x = corner;
    }
    if (x == w) return false;
    if (delaunay_only) {
      const Vec3 a = positions[u] - positions[w], b = positions[v] - positions[w];
      const Vec3 c = positions[v] - positions[x], d = positions[u] - positions[x];
      // sin(alpha + beta) < 0, each factor scaled by the positive |a||b| or |c||d|.
      if (!(norm(cross(a, b)) * dot(c, d) + dot(a, b) * norm(cross(c, d)) < 0)) return false;
    }
    if (!counter_clockwise(u, x, w) || !counter_clockwise(x, v, w)) return false;
    triangles[t] = {u, x, w};
    triangles[n] = {x, v, w};
    changed = n;
    return true;
  };
  std::vector<std::uint8_t> is_sliver(triangles.size(), 0);
  for (const std::uint32_t t : slivers) is_sliver[t] = 1;
  std::vector<std::uint32_t> touched;
  for (const std::uint32_t t : slivers) {
    if (!is_sliver[t]) continue;  // flipped away with a neighbour that was one too
    // Its longest edge first: the chord its middle corner was moved across,
    // whose flip joins that corner to the vertex beyond.
    const auto length = [&](int k) {
      const Vec3 d = positions[triangles[t][(k + 1) % 3]] - positions[triangles[t][k]];
      return dot(d, d);
    };
    std::array<int, 3> order{0, 1, 2};
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return length(a) > length(b); });
    if (!flip(t, order[0], false) && !flip(t, order[1], false) && !flip(t, order[2], false)) return false;
    is_sliver[t] = is_sliver[changed] = 0;
    touched.push_back(t);
    touched.push_back(changed);
  }
  // The vertex beyond may lie nearly on the line too (a run of corners along a
  // flat stretch of the section), leaving thin triangles the exact Delaunay
  // triangulation would not have: Lawson's flips around the flipped ones bring
  // the shape back, a bounded number of them (a cycle on nearly cocircular
  // corners ends there).
  for (std::size_t budget = 8 * touched.size(); !touched.empty() && budget > 0;) {
    const std::uint32_t t = touched.back();
    touched.pop_back();
    for (int k = 0; k < 3; ++k) {
      if (!flip(t, k, true)) continue;
      touched.push_back(t);
      touched.push_back(changed);
      --budget;
      break;
    }
  }
  // A flip can make an edge that another pair of triangles has already: then
  // the triangles are no chain with the border as its boundary.
  return cap_boundary_is_border(triangles, border);
}

namespace {

template <class K>
struct CdtTypes {
  using VertexBase = CGAL::Triangulation_vertex_base_with_info_2<VertexIndex, K>;
  using FaceBase = CGAL::Triangulation_face_base_with_info_2<int, K, CGAL::Constrained_triangulation_face_base_2<K>>;
  using Tds = CGAL::Triangulation_data_structure_2<VertexBase, FaceBase>;
  // Crossing constraints are an error, not a reason to add Steiner points: a cap
  // never adds a vertex on its boundary.
  using Cdt = CGAL::Constrained_Delaunay_triangulation_2<K, Tds, CGAL::No_constraint_intersection_tag>;
};

// Constrained Delaunay triangulation of the border edges; the faces at odd
// constraint-crossing depth from the infinite face form the region. Returns
// nullopt when two border vertices coincide in 2D or constraints cross or touch.
template <class K, class Point2>
std::optional<std::vector<Triangle>> triangulate_with_cdt(std::span<const Edge> border,
                                                          const std::vector<VertexIndex>& vertices,
                                                          const std::vector<Point2>& points) {
  using Cdt = typename CdtTypes<K>::Cdt;
  using VertexHandle = typename Cdt::Vertex_handle;
  using FaceHandle = typename Cdt::Face_handle;
  Cdt cdt;
  IndexMap handle_of_vertex(vertices.size());
  std::vector<VertexHandle> handles;
  handles.reserve(vertices.size());
  try {
    for (std::size_t i = 0; i < vertices.size(); ++i) {
      VertexHandle h = cdt.insert(points[i]);
      if (cdt.number_of_vertices() != i + 1) return std::nullopt;  // two mesh vertices at one 2D point
      h->info() = vertices[i];
      handles.push_back(h);
      handle_of_vertex.insert(vertices[i], static_cast<std::uint32_t>(i));
    }
    for (const Edge& e : border) {
      cdt.insert_constraint(handles[handle_of_vertex.find(e[0])], handles[handle_of_vertex.find(e[1])]);
    }
  } catch (const CGAL::Failure_exception&) {
    return std::nullopt;
  } catch (const typename Cdt::Intersection_of_constraints_exception&) {
    return std::nullopt;
  }

  for (FaceHandle f : cdt.all_face_handles()) f->info() = -1;
  // Breadth-first over faces; crossing a constrained edge goes one level deeper.
  std::deque<FaceHandle> frontier{cdt.infinite_face()};
  cdt.infinite_face()->info() = 0;
  std::deque<FaceHandle> next_level;
  for (int depth = 0; !frontier.empty(); ++depth) {
    while (!frontier.empty()) {
      FaceHandle f = frontier.front();
      frontier.pop_front();
      for (int k = 0; k < 3; ++k) {
        FaceHandle neighbor = f->neighbor(k);
        if (neighbor->info() != -1) continue;
        if (cdt.is_constrained({f, k})) {
          next_level.push_back(neighbor);
        } else {
          neighbor->info() = depth;
          frontier.push_back(neighbor);
        }
      }
    }
    for (FaceHandle f : next_level) {
      if (f->info() == -1) {
        f->info() = depth + 1;
        frontier.push_back(f);
      }
    }
    next_level.clear();
  }
  std::vector<Triangle> triangles;
  for (FaceHandle f : cdt.finite_face_handles()) {
    if (f->info() % 2 == 1) {
      triangles.push_back({f->vertex(0)->info(), f->vertex(1)->info(), f->vertex(2)->info()});
    }
  }
  return triangles;
}

// One new vertex inside each loop, joined to every loop edge. Only topology is
// guaranteed: closed, oriented, boundary = border.
template <class Point>
Cap<Point> steiner_fan(std::span<const Point> positions, const std::vector<std::vector<VertexIndex>>& loops) {
  Cap<Point> cap;
  cap.method = CapMethod::steiner_fan;
  cap.loop_count = loops.size();
  for (const auto& loop : loops) {
    Vec3 sum;
    for (VertexIndex v : loop) sum = sum + to_vec3(positions[v]);
    const Vec3 centre = sum * (1.0 / static_cast<double>(loop.size()));
    const auto apex = static_cast<VertexIndex>(positions.size() + cap.added_points.size());
    if constexpr (std::is_same_v<Point, Vec3>) {
      cap.added_points.push_back(centre);
    } else {
      cap.added_points.emplace_back(centre.x, centre.y, centre.z);
    }
    for (std::size_t k = 0; k < loop.size(); ++k) {
      cap.triangles.push_back({apex, loop[k], loop[(k + 1) % loop.size()]});
    }
  }
  return cap;
}

std::vector<VertexIndex> distinct_vertices(std::span<const Edge> border) {
  std::vector<VertexIndex> vertices;
  vertices.reserve(border.size());
  IndexMap seen(border.size());
  for (const Edge& e : border) {
    if (seen.insert(e[0], 1) == 1 && seen.size() > vertices.size()) vertices.push_back(e[0]);
  }
  return vertices;
}

// The certificate that a triangulation made over approximations of the exact
// points triangulates the polygon the exact points bound: every triangle strictly
// counter-clockwise for the exact points, no two vertices at one exact point, and
// the triangles' boundary is the border (cap_boundary_is_border). The triangles
// then form a chain with that boundary, so the number of triangles covering a
// point not on an edge is the border's winding number around it; the exact
// triangulation accepts a border only where that number is 0 or 1, and there the
// triangles cover the region once and meet only along edges.
bool certifies_for_exact_points(const std::vector<Triangle>& triangles, std::span<const Edge> border,
                                const std::vector<VertexIndex>& vertices,
                                const std::vector<ExactKernel::Point_2>& points) {
  if (!cap_boundary_is_border(triangles, border)) return false;
  IndexMap slot_of_vertex(vertices.size());
  for (std::uint32_t i = 0; i < vertices.size(); ++i) slot_of_vertex.insert(vertices[i], i);
  const auto point = [&](VertexIndex v) -> const ExactKernel::Point_2& { return points[slot_of_vertex.find(v)]; };
  for (const Triangle& t : triangles) {
    if (orientation_2d(point(t[0]), point(t[1]), point(t[2])) != Sign::positive) return false;
  }
  std::vector<std::uint32_t> order(points.size());
  for (std::uint32_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(),
            [&](std::uint32_t a, std::uint32_t b) { return CGAL::compare_xy(points[a], points[b]) == CGAL::SMALLER; });
  for (std::size_t i = 1; i < order.size(); ++i) {
    if (CGAL::compare_xy(points[order[i - 1]], points[order[i]]) == CGAL::EQUAL) return false;
  }
  return true;
}

// Exact points triangulated through their double approximations: the
// triangulation of the doubles is taken when it certifies for the exact points
// (above), and the exact triangulation is built only when it does not. Exact
// incircle tests are what make the exact triangulation slow: a cap's corners lie
// close to a conic (a plane section of a smooth surface), so the filter fails on
// many quadruples; the certificate needs only orientations and distinctness,
// which the filter decides almost always. Where the two differ at all, they
// differ by diagonals of near-cocircular corners, where rounding decided the
// Delaunay choice. Returns only a triangulation whose boundary is the border;
// nullopt where the exact triangulation fails or its boundary is not the border.
std::optional<std::vector<Triangle>> triangulate_exact_points(std::span<const Edge> border,
                                                              const std::vector<VertexIndex>& vertices,
                                                              const std::vector<ExactKernel::Point_2>& points) {
  std::vector<CGAL::Epick::Point_2> approximate;
  approximate.reserve(points.size());
  for (const auto& p : points) approximate.emplace_back(CGAL::to_double(p.x()), CGAL::to_double(p.y()));
  auto candidate = triangulate_with_cdt<CGAL::Epick>(border, vertices, approximate);
  if (candidate && certifies_for_exact_points(*candidate, border, vertices, points)) return candidate;
  auto exact = triangulate_with_cdt<ExactKernel>(border, vertices, points);
  if (exact && !cap_boundary_is_border(*exact, border)) return std::nullopt;
  return exact;
}

template <class Point2, class Project>
std::vector<Point2> project_all(const std::vector<VertexIndex>& vertices, Project&& project) {
  std::vector<Point2> points;
  points.reserve(vertices.size());
  for (VertexIndex v : vertices) points.push_back(project(v));
  return points;
}

// Methods 1 and 2 for either kernel; K is the CGAL kernel for the 2D points.
template <class K, class Point, class Point2, class Project>
std::optional<Cap<Point>> fan_or_cdt(std::span<const Edge> border,
                                     const std::vector<std::vector<VertexIndex>>& loops,
                                     Project&& project, bool allow_fan = true) {
  Cap<Point> cap;
  cap.loop_count = loops.size();
  if (allow_fan && loops.size() == 1) {
    std::vector<Point2> loop_points = project_all<Point2>(loops[0], project);
    if (auto fan = try_fan(loops[0], loop_points)) {
      cap.triangles = std::move(*fan);
      cap.method = CapMethod::fan;
      return cap;
    }
  }
  const std::vector<VertexIndex> vertices = distinct_vertices(border);
  std::optional<std::vector<Triangle>> triangles;
  if constexpr (std::is_same_v<K, ExactKernel>) {
    triangles = triangulate_exact_points(border, vertices, project_all<Point2>(vertices, project));
  } else {
    triangles = triangulate_with_cdt<K>(border, vertices, project_all<Point2>(vertices, project));
    if (triangles && !cap_boundary_is_border(*triangles, border)) triangles.reset();
  }
  if (!triangles) return std::nullopt;
  cap.triangles = std::move(*triangles);
  cap.method = CapMethod::cdt;
  return cap;
}

// Cut points that lie on one line exactly (where the plane crosses a flat face
// split into several triangles) come out of rounding a little off it. A
// triangulation of the rounded points may then join three of them in a sliver
// that fills a dent of a few ulps: a needle, whose two long edges any later plane
// crosses at points that round together. Such a cap is rebuilt from the exact
// points, where those three can never form a triangle.
bool joins_exactly_collinear_points(const std::vector<Triangle>& triangles, const PlaneProjection& projection,
                                    const ExactPositionFn& exact_position) {
  IndexMap slot_of_vertex(3 * triangles.size());
  std::vector<ExactKernel::Point_2> projected;
  const auto exact_projected = [&](VertexIndex v) -> const ExactKernel::Point_2& {
    const auto slot = static_cast<std::uint32_t>(projected.size());
    const std::uint32_t found = slot_of_vertex.insert(v, slot);
    if (found == slot) projected.push_back(project(projection, exact_position(v)));
    return projected[found];
  };
  projected.reserve(3 * triangles.size());
  for (const Triangle& t : triangles) {
    const ExactKernel::Point_2 a = exact_projected(t[0]), b = exact_projected(t[1]), c = exact_projected(t[2]);
    if (CGAL::collinear(a, b, c)) return true;
  }
  return false;
}

}  // namespace

Cap<Vec3> triangulate_cap(std::span<const Vec3> positions, std::span<const Edge> border, const Plane& plane,
                          const ExactPositionFn& exact_position, bool allow_fan) {
  if (border.empty()) return {};
  const PlaneProjection projection = PlaneProjection::of(plane);
  const auto loops = link_loops(border);
  using Point2 = CGAL::Epick::Point_2;
  auto rounded = fan_or_cdt<CGAL::Epick, Vec3, Point2>(
      border, loops,
      [&](VertexIndex v) {
        const Vec2 p = projection(positions[v]);
        return Point2(p.x, p.y);
      },
      allow_fan);
  if (rounded && (!exact_position || !joins_exactly_collinear_points(rounded->triangles, projection, exact_position))) {
    return std::move(*rounded);
  }
  if (exact_position) {
    const std::vector<VertexIndex> vertices = distinct_vertices(border);
    auto triangles = triangulate_exact_points(
        border, vertices, project_all<ExactKernel::Point_2>(vertices, [&](VertexIndex v) {
          return project(projection, exact_position(v));
        }));
    if (triangles) {
      Cap<Vec3> cap;
      cap.triangles = std::move(*triangles);
      cap.loop_count = loops.size();
      cap.method = CapMethod::exact_cdt;
      return cap;
    }
  }
  return steiner_fan<Vec3>(positions, loops);
}

Cap<ExactPoint> triangulate_cap(std::span<const ExactPoint> positions, std::span<const Edge> border,
                                const Plane& plane, bool allow_fan) {
  if (border.empty()) return {};
  const PlaneProjection projection = PlaneProjection::of(plane);
  const auto loops = link_loops(border);
  auto exact = fan_or_cdt<ExactKernel, ExactPoint, ExactKernel::Point_2>(
      border, loops, [&](VertexIndex v) { return project(projection, positions[v]); }, allow_fan);
  if (exact) return std::move(*exact);
  return steiner_fan<ExactPoint>(positions, loops);
}

}  // namespace shatter
