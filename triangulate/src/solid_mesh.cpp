// Faces triangulated over their own vertices, and the public calls of the
// rounding (solid_mesh.hpp). The rounding's parts are in the sources that
// rounding.hpp lists.
#include "shatter/triangulate/solid_mesh.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "shatter/kernel/error.hpp"
#include "shatter/kernel/exact.hpp"
#include "shatter/kernel/face_loops.hpp"
#include "shatter/kernel/index_map.hpp"
#include "shatter/kernel/rationals.hpp"
#include "shatter/triangulate/cap.hpp"
#include "rounding.hpp"
#include "rounding_exact.hpp"

namespace shatter {

namespace {

// The face's plane and points, orientations seen from its outward side.
FaceGeometry outward_geometry(const PlaneSet& set, const SolidFace& face, Projection projection, const Solid& solid) {
  return {set, solid.defs, solid.approx, projection, face.reversed};
}

// A fan of a convex polygon (the face's one loop) from corner `apex` is a
// triangulation exactly when no fan triangle is flat: the polygon is convex, so
// none is clockwise.
bool fan_from(const PlaneSet& set, const SolidFace& face, Projection projection, const Solid& solid,
              const SolidLoop& loop, std::uint32_t apex, std::vector<Triangle>& out) {
  const VertexIndex a = solid.corners[apex].vertex;
  if (loop.corner_count > 3) {
    const FaceGeometry outward = outward_geometry(set, face, projection, solid);
    for (const CornerEdge& edge : fan_edges(solid.corners, loop, apex)) {
      if (outward.orient(a, edge.from, edge.to) != Sign::positive) return false;
    }
  }
  for (const CornerEdge& edge : fan_edges(solid.corners, loop, apex)) out.push_back({a, edge.from, edge.to});
  return true;
}

// The fan apex whose thinnest triangle is the least thin (twice the area over the
// longest edge squared, on the vertices' approximations): a choice among exactly
// valid fans, made only to keep slivers out of what rounding must preserve.
//
// A triangle with no shape to measure is skipped: corners whose approximations
// coincide (a sliver finer than doubles), or a corner whose approximation is no
// finite point (w approximated by zero, or x/w past the double range, as on
// solids an ulp across). Its quality would be NaN, which the minimum ignored
// before the tests trapped NaNs; skipping it keeps every choice as it was.
// Returns the apex's place in the loop (0 for its first corner).
std::size_t roundest_apex(const Solid& solid, const SolidLoop& loop) {
  auto point = [&](VertexIndex v) -> std::optional<Vec3> {
    const ApproxPoint& a = solid.approx[v];
    const double w = std::fabs(a.w.value), largest = std::numeric_limits<double>::max();
    for (const double c : {a.x.value, a.y.value, a.z.value}) {
      if (!(w > 0 && std::fabs(c) / largest <= w)) return std::nullopt;
    }
    return Vec3{a.x.value / a.w.value, a.y.value / a.w.value, a.z.value / a.w.value};
  };
  std::size_t best = 0;
  double best_quality = -1;
  for (std::uint32_t apex = 0; apex < loop.corner_count; ++apex) {
    const std::optional<Vec3> a = point(solid.corners[loop.first_corner + apex].vertex);
    double quality = INFINITY;
    for (const CornerEdge& edge : fan_edges(solid.corners, loop, loop.first_corner + apex)) {
      const std::optional<Vec3> b = point(edge.from), c = point(edge.to);
      if (!a || !b || !c) continue;
      const double longest = std::max({dot(*b - *a, *b - *a), dot(*c - *b, *c - *b), dot(*a - *c, *a - *c)});
      if (longest > 0) quality = std::min(quality, norm(cross(*b - *a, *c - *a)) / longest);
    }
    if (quality > best_quality) best_quality = quality, best = apex;
  }
  return best;
}

// A face's own numbering of the solid vertices it uses, in order of first use,
// as the cap triangulation takes them.
struct LocalVertices {
  std::vector<VertexIndex> vertices;  ///< local -> solid vertex
  IndexMap local_of{16};
  VertexIndex operator()(VertexIndex v) {
    const auto candidate = static_cast<VertexIndex>(vertices.size());
    const VertexIndex found = local_of.insert(v, candidate);
    if (found == candidate) vertices.push_back(v);
    return found;
  }
};

// Any face that is not one convex loop: a constrained Delaunay triangulation of
// its loops (triangulate_cap), on the rounded points, kept when every triangle is
// counter-clockwise in exact arithmetic, else on the exact points.
void triangulate_region(const PlaneSet& set, const SolidFace& face, Projection projection, const Solid& solid,
                        std::span<const Vec3> rounded, std::vector<Triangle>& out, bool exact_delaunay) {
  LocalVertices local;
  std::vector<VertexIndex>& vertices = local.vertices;
  std::vector<Edge> border;
  for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
    for (const CornerEdge& edge : loop_edges(solid.corners, solid.loops[l])) {
      border.push_back({local(edge.from), local(edge.to)});
    }
  }
  // The projection's plane, as a normal along the dropped axis with the sign of the
  // face's outward normal there: triangulate_cap then works seen from outside.
  Plane plane;
  const double sign = (projection.flipped != face.reversed) ? -1.0 : 1.0;
  (projection.axis == 0 ? plane.normal.x : projection.axis == 1 ? plane.normal.y : plane.normal.z) = sign;
  std::vector<Vec3> local_rounded;
  for (VertexIndex v : vertices) local_rounded.push_back(rounded[v]);
  std::vector<ExactPoint> exact_points;
  auto exact_of = [&](VertexIndex v) -> ExactPoint {
    if (exact_points.empty()) {
      for (VertexIndex w : vertices) exact_points.push_back(rounding::exact_point(set, solid.defs[w]));
    }
    return exact_points[v];
  };
  // The rounded attempt needs no exact positions: every triangle is checked
  // exactly below, which also rules out exactly collinear ones.
  Cap<Vec3> cap;
  if (!exact_delaunay) cap = triangulate_cap(local_rounded, border, plane, {});
  const FaceGeometry outward = outward_geometry(set, face, projection, solid);
  const auto counter_clockwise = [&](VertexIndex a, VertexIndex b, VertexIndex c) {
    return outward.orient(vertices[a], vertices[b], vertices[c]) == Sign::positive;
  };
  auto all_positive = [&](const std::vector<Triangle>& triangles) {
    return std::all_of(triangles.begin(), triangles.end(),
                       [&](const Triangle& t) { return counter_clockwise(t[0], t[1], t[2]); });
  };
  // A triangle of the rounded triangulation that is flat or clockwise for the
  // exact points (a corner rounding moved across its neighbours' chord): the
  // constrained Delaunay triangulation of the rounded points, with each such
  // sliver flipped away on the exact orientations. Only where that fails are
  // the exact points computed and triangulated: a tenth of the rounding's time
  // on fractured subdivided meshes when every sliver went that way (one face
  // in fifteen there). Not the fan with its slivers flipped: a fan of a smooth
  // section is thin all around its apex, which the exact triangulation, being
  // Delaunay, is not (test_glb_normals' cap normals).
  const bool rounded_tried = !exact_delaunay && cap.added_points.empty();
  bool rounded_kept = rounded_tried && all_positive(cap.triangles);
  if (rounded_tried && !rounded_kept) {
    if (cap.method == CapMethod::fan) cap = triangulate_cap(local_rounded, border, plane, {}, false);
    rounded_kept = cap.method == CapMethod::cdt &&
                   flip_to_counter_clockwise(cap.triangles, border, local_rounded, counter_clockwise);
  }
  if (!rounded_kept) {
    exact_of(0);
    Cap<ExactPoint> exact = triangulate_cap(std::span<const ExactPoint>(exact_points), border, plane, !exact_delaunay);
    if (!exact.added_points.empty() || !all_positive(exact.triangles)) {
      throw UnsupportedGeometryError("cannot triangulate a face over its own vertices (the solid is not embedded)");
    }
    cap.triangles = std::move(exact.triangles);
  }
  for (const Triangle& t : cap.triangles) out.push_back({vertices[t[0]], vertices[t[1]], vertices[t[2]]});
}

}  // namespace

namespace rounding {

ExactPoint exact_point(const PlaneSet& set, const PointDef& def) {
  const std::array<mpq_class, 3> c = exact_coordinates(set, def);
  return ExactPoint(ExactKernel::FT(c[0]), ExactKernel::FT(c[1]), ExactKernel::FT(c[2]));
}

bool triangulate_merged_face(const PlaneSet& set, const SolidFace& face,
                             std::span<const std::vector<VertexIndex>> loops, std::span<const PointDef> placed,
                             Projection projection, std::vector<Triangle>& out, bool also_other_axes) {
  LocalVertices local;
  std::vector<VertexIndex>& vertices = local.vertices;
  std::vector<Edge> border;
  for (const auto& loop : loops) {
    for (std::size_t i = 0; i < loop.size(); ++i) border.push_back({local(loop[i]), local(loop[(i + 1) % loop.size()])});
  }
  std::vector<ExactPoint> points;
  for (VertexIndex v : vertices) points.push_back(exact_point(set, placed[v]));
  // The face's own projection first. Snapped corners lie off the face's plane,
  // and two of them can project onto one point along its dominant axis (an edge
  // nearly along that axis, made by the snap): then along each other axis the
  // face's normal has a component of certified sign (any such projection maps
  // the plane one to one, keeping or reversing orientation by that sign).
  std::vector<Projection> projections{projection};
  if (also_other_axes) {
    for (int axis = 0; axis < 3; ++axis) {
      if (axis == projection.axis) continue;
      if (const std::optional<Projection> along = projection_along_if_clear(set, face.plane, axis)) {
        projections.push_back(*along);
      }
    }
  }
  for (const Projection& along : projections) {
    Plane plane;
    const double sign = (along.flipped != face.reversed) ? -1.0 : 1.0;
    (along.axis == 0 ? plane.normal.x : along.axis == 1 ? plane.normal.y : plane.normal.z) = sign;
    const Cap<ExactPoint> cap = triangulate_cap(std::span<const ExactPoint>(points), border, plane, false);
    if (!cap.added_points.empty() || cap.triangles.empty()) continue;
    for (const Triangle& t : cap.triangles) out.push_back({vertices[t[0]], vertices[t[1]], vertices[t[2]]});
    return true;
  }
  return false;
}

}  // namespace rounding

void triangulate_face(const PlaneSet& set, const Solid& solid, std::uint32_t face_index,
                      std::span<const Vec3> positions, std::vector<Triangle>& out, std::size_t attempt) {
  const SolidFace& face = solid.faces[face_index];
  const Projection projection = projection_of(set, face.plane);
  const std::size_t first = out.size();
  if (face.loop_count == 1 && face.convex) {
    const SolidLoop& loop = solid.loops[face.first_loop];
    // Attempt 0 takes the first corner whose fan has no flat triangle; later ones
    // start from the roundest fan, then its neighbours.
    const std::size_t start = attempt == 0 ? 0 : roundest_apex(solid, loop) + (attempt - 1);
    for (std::size_t step = 0; step < loop.corner_count; ++step) {
      out.resize(first);
      const auto apex = loop.first_corner + static_cast<std::uint32_t>((start + step) % loop.corner_count);
      if (fan_from(set, face, projection, solid, loop, apex, out)) return;
    }
    out.resize(first);
  }
  triangulate_region(set, face, projection, solid, positions, out, attempt > 0);
}

Mesh triangulate_solid(const PlaneSet& set, const Solid& solid, const SolidMeshOptions& options) {
  Mesh mesh;
  std::size_t merged = 0;
  rounding::triangulate(set, solid, options, 0, mesh, merged);
  return mesh;
}

MassProperties solid_mass_properties(const Solid& solid) {
  thread_local std::vector<Vec3> points;
  thread_local std::vector<Triangle> fans;
  points.clear();
  fans.clear();
  for (const ApproxPoint& a : solid.approx) {
    points.push_back({a.x.value / a.w.value, a.y.value / a.w.value, a.z.value / a.w.value});
  }
  for (const SolidFace& face : solid.faces) {
    const VertexIndex centre = solid.corners[solid.loops[face.first_loop].first_corner].vertex;
    for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
      for (const CornerEdge& edge : loop_edges(solid.corners, solid.loops[l])) {
        if (edge.from != centre && edge.to != centre) fans.push_back({centre, edge.from, edge.to});
      }
    }
  }
  return mass_properties(points, fans);
}

}  // namespace shatter
