#include "shatter/triangulate/solid_mesh.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <stdexcept>
#include <unordered_map>

#include "shatter/kernel/certify.hpp"
#include "shatter/kernel/error.hpp"
#include "shatter/kernel/exact.hpp"
#include "shatter/kernel/face_loops.hpp"
#include "shatter/kernel/index_map.hpp"
#include "shatter/kernel/non_manifold.hpp"
#include "shatter/kernel/predicates.hpp"
#include "shatter/kernel/projection.hpp"
#include "shatter/kernel/rationals.hpp"
#include "shatter/kernel/union_find.hpp"
#include "shatter/kernel/self_intersections.hpp"
#include "shatter/kernel/snap_predicates.hpp"
#include "shatter/kernel/validate.hpp"
#include "shatter/triangulate/cap.hpp"

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

ExactPoint exact_point(const PlaneSet& set, const PointDef& def) {
  const std::array<mpq_class, 3> c = exact_coordinates(set, def);
  return ExactPoint(ExactKernel::FT(c[0]), ExactKernel::FT(c[1]), ExactKernel::FT(c[2]));
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
      for (VertexIndex w : vertices) exact_points.push_back(exact_point(set, solid.defs[w]));
    }
    return exact_points[v];
  };
  // The rounded attempt needs no exact positions: every triangle is checked
  // exactly below, which also rules out exactly collinear ones.
  Cap<Vec3> cap;
  if (!exact_delaunay) cap = triangulate_cap(local_rounded, border, plane, {});
  const FaceGeometry outward = outward_geometry(set, face, projection, solid);
  auto all_positive = [&](const std::vector<Triangle>& triangles) {
    return std::all_of(triangles.begin(), triangles.end(), [&](const Triangle& t) {
      return outward.orient(vertices[t[0]], vertices[t[1]], vertices[t[2]]) == Sign::positive;
    });
  };
  if (exact_delaunay || !cap.added_points.empty() || !all_positive(cap.triangles)) {
    exact_of(0);
    Cap<ExactPoint> exact = triangulate_cap(std::span<const ExactPoint>(exact_points), border, plane, !exact_delaunay);
    if (!exact.added_points.empty() || !all_positive(exact.triangles)) {
      throw UnsupportedGeometryError("cannot triangulate a face over its own vertices (the solid is not embedded)");
    }
    cap.triangles = std::move(exact.triangles);
  }
  for (const Triangle& t : cap.triangles) out.push_back({vertices[t[0]], vertices[t[1]], vertices[t[2]]});
}

// Per-corner attributes at a point of input triangle `source`: the corner's own
// value at one of its vertices, else interpolated with barycentric coordinates
// of the rounded point projected into the triangle (attributes never decide
// geometry, so rounded arithmetic serves).
struct AttributeSource {
  const Mesh& input;
  bool normals, uvs, tangents;

  void append(TriangleIndex source, const PointDef& def, const Vec3& p, CornerAttributes& out) const {
    const Triangle& t = input.triangles[source];
    double w[3] = {0, 0, 0};
    int corner = -1;
    if (def.kind == PointKind::input) {
      for (int c = 0; c < 3; ++c) {
        if (t[c] == def.a) corner = c;
      }
    }
    if (corner >= 0) {
      w[corner] = 1;
    } else {
      const Vec3 a = input.positions[t[0]], b = input.positions[t[1]], c = input.positions[t[2]];
      const Vec3 n = cross(b - a, c - a);
      const double area = dot(n, n);
      if (area > 0) {
        w[0] = dot(cross(b - p, c - p), n) / area;
        w[1] = dot(cross(c - p, a - p), n) / area;
        w[2] = dot(cross(a - p, b - p), n) / area;
      }
      double total = 0;
      for (double& x : w) {
        x = std::clamp(x, 0.0, 1.0);
        total += x;
      }
      if (!(total > 0)) w[0] = total = 1;
      for (double& x : w) x /= total;
    }
    const std::size_t base = 3 * std::size_t{source};
    if (normals) {
      Vec3 n;
      for (int c = 0; c < 3; ++c) n = n + input.corners.normals[base + c] * w[c];
      out.normals.push_back(corner >= 0 ? input.corners.normals[base + corner] : normalized(n));
    }
    if (uvs) {
      Vec2 uv;
      for (int c = 0; c < 3; ++c) {
        uv.x += input.corners.uvs[base + c].x * w[c];
        uv.y += input.corners.uvs[base + c].y * w[c];
      }
      out.uvs.push_back(corner >= 0 ? input.corners.uvs[base + corner] : uv);
    }
    if (tangents) {
      if (corner >= 0) {
        out.tangents.push_back(input.corners.tangents[base + corner]);
      } else {
        Vec3 d;
        for (int c = 0; c < 3; ++c) {
          const Vec4& g = input.corners.tangents[base + c];
          d = d + Vec3{g.x, g.y, g.z} * w[c];
        }
        d = normalized(d);
        out.tangents.push_back({d.x, d.y, d.z, input.corners.tangents[base].w});
      }
    }
  }
};

struct PositionHash {
  std::size_t operator()(const Vec3& p) const {
    auto bits = [](double x) {
      std::uint64_t b;
      x = x == 0 ? 0.0 : x;  // -0.0 and +0.0 are one position
      std::memcpy(&b, &x, sizeof b);
      return b;
    };
    return bits(p.x) * 0x9E3779B97F4A7C15ull ^ bits(p.y) * 0xC2B2AE3D27D4EB4Full ^ bits(p.z);
  }
};
struct PositionEqual {
  bool operator()(const Vec3& a, const Vec3& b) const { return a.x == b.x && a.y == b.y && a.z == b.z; }
};

// A face whose boundary lost corners to merging: its loops over the merged
// vertices (each standing for the point it was placed at: the input point it
// snapped to, or its own), triangulated by the exact constrained Delaunay
// triangulation of their projection. Snapped points are off the face's plane by
// a hair, so the result is a triangulation of the projected polygon only; the
// certification that follows vouches for it in 3D. Returns false, adding
// nothing, when the placed corners bound no polygon the triangulation can cover
// without new points (a face rounded onto the edges around it, or whose loops
// now coincide).
// `also_other_axes`: when the face's own projection fails, try the others (see
// below; round_solid's repairs ask for it).
bool triangulate_merged_face(const PlaneSet& set, const SolidFace& face,
                             std::span<const std::vector<VertexIndex>> loops, std::span<const PointDef> placed,
                             Projection projection, std::vector<Triangle>& out, bool also_other_axes = false) {
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

// --- Loops over merged vertices ---------------------------------------------------
// When vertices merge (rounded onto one point), the faces' loops over the
// representatives can stop being simple polygons, as in snap rounding in the
// plane (Hobby 1999; Halperin & Packer 2002's iterated form), and they are
// repaired the way snap rounding repairs segments, all decided on the rounded
// doubles by exact predicates:
// 1. A vertex lying exactly inside an edge (collinear and strictly between its
//    ends) is inserted into the edge, in every loop that has the edge: the edge
//    passes through that "hot pixel". A face that rounded onto the edges around
//    it then runs forth and back along them, and its neighbours on both sides
//    share vertices again.
// 2. Spikes x -> y -> x (an edge run forth and back) are removed, repeatedly:
//    they enclose nothing. A loop left with fewer than 3 corners vanishes. Two
//    loops of a face that run one edge both ways (a hole rounded against the
//    outer loop) are joined across it: the edge bounds the face on neither side.
// 3. A loop through one vertex twice (two parts that rounding made touch) is
//    split there into simple loops, each triangulated on its own; the vertex is
//    then pinched, which the separation below handles.
// Each step only removes corners, or inserts a vertex into an edge that passes
// through it, so it ends; it changes no position.

// (Step 1's test is the kernel's strictly_inside_segment.)

// Step 2's spikes: x -> y -> x (an edge run forth and back) and repeated
// corners, removed until none is left.
void remove_spikes(std::vector<VertexIndex>& loop) {
  bool changed = true;
  while (changed && loop.size() >= 3) {
    changed = false;
    for (std::size_t i = 0; i < loop.size() && loop.size() >= 3; ++i) {
      const std::size_t k = loop.size();
      if (loop[i] == loop[(i + 2) % k]) {
        // x y x: drop y and the second x.
        const std::size_t y = (i + 1) % k, x2 = (i + 2) % k;
        loop.erase(loop.begin() + static_cast<std::ptrdiff_t>(std::max(y, x2)));
        loop.erase(loop.begin() + static_cast<std::ptrdiff_t>(std::min(y, x2)));
        changed = true;
      } else if (loop[i] == loop[(i + 1) % k]) {
        loop.erase(loop.begin() + static_cast<std::ptrdiff_t>((i + 1) % k));
        changed = true;
      }
    }
  }
}

// Step 2's edges run both ways: when one loop of a face runs a -> b and another
// runs b -> a (a hole that rounding laid against the outer loop, or two holes
// against each other), the two edges bound the face's region on no side, as a
// spike does, and cancel: the loops are joined into one across them (the face's
// region, as the sum of its oriented loops, is unchanged). Joins the first such
// pair; returns whether it found one.
bool join_at_antiparallel_edge(std::vector<std::vector<VertexIndex>>& face) {
  for (std::size_t p = 0; p < face.size(); ++p) {
    const std::vector<VertexIndex>& first = face[p];
    for (std::size_t i = 0; i < first.size(); ++i) {
      const VertexIndex a = first[i], b = first[(i + 1) % first.size()];
      for (std::size_t q = 0; q < face.size(); ++q) {
        if (q == p) continue;
        const std::vector<VertexIndex>& second = face[q];
        for (std::size_t j = 0; j < second.size(); ++j) {
          if (second[j] != b || second[(j + 1) % second.size()] != a) continue;
          // first from b round to a, then second from a round to just before b.
          std::vector<VertexIndex> joined;
          for (std::size_t k = 0; k < first.size(); ++k) joined.push_back(first[(i + 1 + k) % first.size()]);
          for (std::size_t k = 1; k + 1 < second.size(); ++k) joined.push_back(second[(j + 1 + k) % second.size()]);
          face[p] = std::move(joined);
          face.erase(face.begin() + static_cast<std::ptrdiff_t>(q));
          return true;
        }
      }
    }
  }
  return false;
}

// The same within one loop: a loop that runs an edge a -> b and later b -> a
// (a face of a merged group that lies between two others along the edge, so
// that the group's sum crosses it twice) bounds the sum's region on neither side
// there; the two edges cancel and the loop falls into the two loops on either
// side of them. Splits the first such loop; returns whether it found one.
bool split_at_antiparallel_edge(std::vector<std::vector<VertexIndex>>& face) {
  for (std::size_t p = 0; p < face.size(); ++p) {
    const std::vector<VertexIndex>& loop = face[p];
    const std::size_t k = loop.size();
    for (std::size_t i = 0; i < k; ++i) {
      const VertexIndex a = loop[i], b = loop[(i + 1) % k];
      for (std::size_t j = i + 1; j < k; ++j) {
        if (loop[j] != b || loop[(j + 1) % k] != a) continue;
        // loop[i + 1 .. j - 1] (from b round to just before b) and loop[j + 1 .. i - 1]
        // (from a round to just before a), cyclically.
        std::vector<VertexIndex> inner(loop.begin() + static_cast<std::ptrdiff_t>(i + 1),
                                       loop.begin() + static_cast<std::ptrdiff_t>(j));
        std::vector<VertexIndex> outer;
        for (std::size_t m = (j + 1) % k; m != i; m = (m + 1) % k) outer.push_back(loop[m]);
        face[p] = std::move(inner);
        face.push_back(std::move(outer));
        return true;
      }
    }
  }
  return false;
}

// Rewrites every loop of every face, putting after each corner a the vertices
// `inserted(a, b)` names for its edge to the next corner b, in their order.
template <class InsertedFn>
void insert_along_loop_edges(std::vector<std::vector<std::vector<VertexIndex>>>& loops, InsertedFn&& inserted) {
  for (auto& face : loops) {
    for (auto& loop : face) {
      std::vector<VertexIndex> out;
      for (std::size_t i = 0; i < loop.size(); ++i) {
        const VertexIndex a = loop[i], b = loop[(i + 1) % loop.size()];
        out.push_back(a);
        const std::vector<VertexIndex> inside = inserted(a, b);
        out.insert(out.end(), inside.begin(), inside.end());
      }
      loop = std::move(out);
    }
  }
}

// Steps 1 to 3 on every face's loops (over representatives, consecutive repeats
// removed). `loops[f]`: face f's loops; `candidates`: the vertices that may lie
// inside an edge (the merged representatives, and the corners of loops that
// changed), tested against every edge with a bounding-box filter (exact: the
// positions are doubles).
// `near`: when given, a candidate within that distance of an edge's line (the
// Euclidean distance, SegmentReach) whose projection onto the line falls
// strictly between the edge's ends is inserted too: the last
// round's hot pixels in edges (snap_clusters), an edge passing within a pixel of
// a vertex routed through it.
void repair_merged_loops(std::span<const Vec3> positions, std::vector<std::vector<std::vector<VertexIndex>>>& loops,
                         std::span<const VertexIndex> candidates, const mpq_class* near = nullptr) {
  // Within `near` of the line of a -> b and strictly between a and b along it.
  const std::optional<SegmentReach> near_segment =
      near != nullptr ? std::optional<SegmentReach>(SegmentReach(*near)) : std::nullopt;
  const double margin = near != nullptr ? 2 * near->get_d() : 0;
  // The candidates by x, so that each edge visits only those within its box's x range.
  std::vector<VertexIndex> by_x(candidates.begin(), candidates.end());
  std::sort(by_x.begin(), by_x.end(), [&](VertexIndex u, VertexIndex w) {
    return positions[u].x != positions[w].x ? positions[u].x < positions[w].x : u < w;
  });
  // 1. Vertices inside edges.
  insert_along_loop_edges(loops, [&](VertexIndex a, VertexIndex b) {
    const Vec3 &pa = positions[a], &pb = positions[b];
    const Vec3 lo{std::min(pa.x, pb.x) - margin, std::min(pa.y, pb.y) - margin, std::min(pa.z, pb.z) - margin};
    const Vec3 hi{std::max(pa.x, pb.x) + margin, std::max(pa.y, pb.y) + margin, std::max(pa.z, pb.z) + margin};
    std::vector<VertexIndex> inside;
    const auto first = std::lower_bound(by_x.begin(), by_x.end(), lo.x,
                                        [&](VertexIndex v, double x) { return positions[v].x < x; });
    for (auto it = first; it != by_x.end() && positions[*it].x <= hi.x; ++it) {
      const VertexIndex v = *it;
      const Vec3& p = positions[v];
      if (v == a || v == b || p.x < lo.x || p.x > hi.x || p.y < lo.y || p.y > hi.y || p.z < lo.z || p.z > hi.z) {
        continue;
      }
      if (strictly_inside_segment(pa, pb, p) || (near_segment && near_segment->within(pa, pb, p))) inside.push_back(v);
    }
    // In order from a to b, along the first coordinate where they differ
    // (exact comparisons of the doubles themselves); near the edge but off its
    // line, by the projection onto it (exactly), ties by index, so that both
    // ways of an edge take the same vertices in reverse order.
    const auto get = pa.x != pb.x ? &Vec3::x : pa.y != pb.y ? &Vec3::y : &Vec3::z;
    const bool rising = pa.*get < pb.*get;
    if (near == nullptr) {
      std::sort(inside.begin(), inside.end(), [&](VertexIndex u, VertexIndex w) {
        return rising ? positions[u].*get < positions[w].*get : positions[u].*get > positions[w].*get;
      });
    } else {
      // The projection from the edge's smaller end, so that both ways agree.
      const Vec3& from = a < b ? pa : pb;
      const Vec3& to = a < b ? pb : pa;
      std::sort(inside.begin(), inside.end(), [&](VertexIndex u, VertexIndex w) {
        const Sign order = compare_along_direction(from, to, positions[u], positions[w]);
        return order != Sign::zero ? order == Sign::negative : u < w;
      });
      if (b < a) std::reverse(inside.begin(), inside.end());
    }
    inside.erase(std::unique(inside.begin(), inside.end()), inside.end());
    return inside;
  });
  // 2. Spikes, edges run both ways by two loops, and 3. loops through a vertex twice.
  for (auto& face : loops) {
    for (bool again = true; again;) {
      for (auto& loop : face) remove_spikes(loop);
      std::erase_if(face, [](const std::vector<VertexIndex>& loop) { return loop.size() < 3; });
      again = join_at_antiparallel_edge(face);
    }
    std::vector<std::vector<VertexIndex>> simple;
    for (auto& loop : face) {
      if (loop.size() < 3) continue;
      // Split at the first repeated vertex until none is left.
      std::vector<std::vector<VertexIndex>> pending{std::move(loop)};
      while (!pending.empty()) {
        std::vector<VertexIndex> current = std::move(pending.back());
        pending.pop_back();
        bool split = false;
        for (std::size_t i = 0; i < current.size() && !split; ++i) {
          for (std::size_t j = i + 1; j < current.size(); ++j) {
            if (current[i] != current[j]) continue;
            std::vector<VertexIndex> inner(current.begin() + static_cast<std::ptrdiff_t>(i),
                                           current.begin() + static_cast<std::ptrdiff_t>(j));
            current.erase(current.begin() + static_cast<std::ptrdiff_t>(i),
                          current.begin() + static_cast<std::ptrdiff_t>(j));
            if (inner.size() >= 3) pending.push_back(std::move(inner));
            if (current.size() >= 3) pending.push_back(std::move(current));
            split = true;
            break;
          }
        }
        if (!split && current.size() >= 3) simple.push_back(std::move(current));
      }
    }
    face = std::move(simple);
  }
}

// Step 1 for a vertex that rounding carried across an edge of its own face:
// snap rounding routes a segment through every hot pixel it passes (Hobby 1999;
// Guibas & Marimont 1998, "Rounding arrangements dynamically"), so that no
// vertex ends up on the wrong side of a segment; here, in the plane of each face
// (its exact projection), a corner v of the face lies strictly on one side of
// the line of an edge (a, b) of the face in exact arithmetic (placed points) and
// strictly on the other on the rounded doubles, and lies between a and b along
// the edge (exactly, on the doubles): the edge is routed through v, in every
// loop that has it (the face across the edge too), and step 2 then removes the
// spike or splits the loop where it passes v twice. Positions do not change;
// certification vouches for the result. Only corners within 2^-30 of the
// coordinates' magnitude of the edge's box are tested: rounding moves a point by
// at most 2^-40 of its magnitude or 64 ulps when snapped (output_position), so
// no farther corner can have changed side. Returns whether any edge changed.
bool route_edges_through_crossed_corners(const PlaneSet& set, const Solid& solid, std::span<const PointDef> placed,
                                         std::span<const Vec3> positions,
                                         std::vector<std::vector<std::vector<VertexIndex>>>& loops) {
  std::vector<std::optional<ExactPoint>> exact(positions.size());
  const auto exact_of = [&](VertexIndex v) -> const ExactPoint& {
    if (!exact[v]) exact[v] = exact_point(set, placed[v]);
    return *exact[v];
  };
  // Edge (a, b) as a directed key -> the corners to route it through.
  std::unordered_map<std::uint64_t, std::vector<VertexIndex>> through;
  const auto key = [](VertexIndex a, VertexIndex b) { return (std::uint64_t{a} << 32) | b; };
  for (std::uint32_t f = 0; f < loops.size(); ++f) {
    const Projection projection = projection_of(set, solid.faces[f].plane);
    const int u = (projection.axis + 1) % 3, w = (projection.axis + 2) % 3;
    const PlaneProjection kept{u, w};
    std::vector<VertexIndex> corners;
    for (const auto& loop : loops[f]) corners.insert(corners.end(), loop.begin(), loop.end());
    for (const auto& loop : loops[f]) {
      for (std::size_t i = 0; i < loop.size(); ++i) {
        const VertexIndex a = loop[i], b = loop[(i + 1) % loop.size()];
        const Vec3 &pa = positions[a], &pb = positions[b];
        double magnitude = 0;
        for (int k = 0; k < 3; ++k) magnitude = std::max({magnitude, std::fabs(pa[k]), std::fabs(pb[k])});
        const double margin = std::ldexp(magnitude, -30);
        for (const VertexIndex v : corners) {
          if (v == a || v == b) continue;
          const Vec3& pv = positions[v];
          bool near = true;
          for (int k = 0; k < 3; ++k) {
            near = near && pv[k] >= std::min(pa[k], pb[k]) - margin && pv[k] <= std::max(pa[k], pb[k]) + margin;
          }
          if (!near) continue;
          const Sign rounded = orient2d(kept(pa), kept(pb), kept(pv));
          if (rounded == Sign::zero) continue;  // on the line: step 1's case
          const Sign before = orientation_in_projection(kept, exact_of(a), exact_of(b), exact_of(v));
          if (before == Sign::zero || before == rounded) continue;
          // Strictly between a and b along the edge, exactly.
          if (projects_strictly_inside_segment(pa, pb, pv)) through[key(a, b)].push_back(v);
        }
      }
    }
  }
  if (through.empty()) return false;
  // Both directions of an edge take the same corners, in order along it (by the
  // square of the distance from its start, exactly on the doubles).
  insert_along_loop_edges(loops, [&](VertexIndex a, VertexIndex b) {
    std::vector<VertexIndex> inside;
    for (const std::uint64_t k : {key(a, b), key(b, a)}) {
      if (const auto it = through.find(k); it != through.end()) inside.insert(inside.end(), it->second.begin(), it->second.end());
    }
    if (inside.empty()) return inside;
    std::sort(inside.begin(), inside.end());
    inside.erase(std::unique(inside.begin(), inside.end()), inside.end());
    const Vec3& pa = positions[a];
    std::stable_sort(inside.begin(), inside.end(), [&](VertexIndex x, VertexIndex y) {
      return compare_distance_to(pa, positions[x], positions[y]) == Sign::negative;
    });
    return inside;
  });
  return true;
}

// The faces of `group` (indices into `loops`, each written as the face
// `emit_as` names) merged into one face: as 2-chains on a common plane they add
// up to the sum of their loops as traversed, in which an edge run both ways
// cancels (join_at_antiparallel_edge, spikes). The merged face faces the way of
// the member whose outward side its loops turn counter-clockwise about (the
// exact signed area of the loops on the doubles, in that member's projection),
// is held by the group's first face and written as that member; when nothing
// is left (or nothing turns one way) the group vanishes whole. `home[f]`: the
// face holding f's loops afterwards (the group's first, or no_index when it
// vanished). `caps_first`: a member on a cut plane that sees the loops
// counter-clockwise is preferred to the group's order. Changes no position.
void merge_face_group(const PlaneSet& set, const Solid& solid, std::span<const Vec3> positions,
                      std::span<const std::uint32_t> group, std::vector<std::vector<std::vector<VertexIndex>>>& loops,
                      std::vector<std::uint8_t>& changed, std::vector<std::uint32_t>& emit_as,
                      std::vector<std::uint32_t>& home, bool caps_first = false) {
  std::vector<std::vector<VertexIndex>> sum;
  for (const std::uint32_t f : group) sum.insert(sum.end(), loops[f].begin(), loops[f].end());
  for (bool again = true; again;) {
    for (auto& loop : sum) remove_spikes(loop);
    std::erase_if(sum, [](const std::vector<VertexIndex>& loop) { return loop.size() < 3; });
    again = join_at_antiparallel_edge(sum) || split_at_antiparallel_edge(sum);
  }
  // Which way the loops turn in face f's projection, seen from its outside.
  const auto turn_seen_from = [&](std::uint32_t f) {
    const Sign s = loops_orientation(positions, sum, projection_of(set, solid.faces[f].plane));
    return solid.faces[f].reversed ? flip(s) : s;
  };
  // The first member (of those on a cut plane when `caps_only`) that sees the
  // loops counter-clockwise, or no_index.
  const auto first_seeing = [&](bool caps_only) {
    for (const std::uint32_t f : group) {
      if ((!caps_only || solid.faces[emit_as[f]].plane.is_cut()) && turn_seen_from(emit_as[f]) == Sign::positive) {
        return emit_as[f];
      }
    }
    return no_index;
  };
  std::uint32_t as = caps_first ? first_seeing(true) : no_index;
  if (as == no_index) as = first_seeing(false);
  const std::uint32_t first = group.front();
  for (const std::uint32_t f : group) {
    emit_as[f] = no_index;
    loops[f].clear();
  }
  for (std::uint32_t& h : home) {
    if (h != no_index && std::find(group.begin(), group.end(), h) != group.end()) h = as == no_index ? no_index : first;
  }
  if (as == no_index) return;  // nothing left, or nothing facing one way: the group vanishes
  emit_as[first] = as;
  loops[first] = std::move(sum);
  changed[first] = 1;
}

// Step 2 for faces that rounding laid onto each other: a part thinner than the
// rounding between two faces that face opposite ways (a slab between a cap and
// an input face ulps from it) rounds onto one plane, and if the two faces' loops
// then share their vertices they overlap as a two-sided sheet, but are
// triangulated differently, so no two triangles cancel. As 2-chains on the common
// plane the faces add up to their difference, whose boundary is the sum of their
// loops as traversed, in which an edge run both ways cancels: so faces that share
// an edge run both ways, all of whose rounded corners lie exactly on one plane
// (orient3d zero) and of which two face opposite ways, are merged into one face
// over the loops left once those edges cancel (join_at_antiparallel_edge, spikes,
// splits; merge_face_group). `emit_as[f]`: the face whose description face f's
// triangles take, or no_index when f is merged into another; `home[f]`: the
// face holding f's loops (itself unless merged). Returns whether any faces
// were merged.
bool merge_coplanar_sheets(const PlaneSet& set, const Solid& solid, std::span<const Vec3> positions,
                           std::vector<std::vector<std::vector<VertexIndex>>>& loops,
                           std::vector<std::uint8_t>& changed, std::vector<std::uint32_t>& emit_as,
                           std::vector<std::uint32_t>& home) {
  const auto count = static_cast<std::uint32_t>(loops.size());
  emit_as.resize(count);
  home.resize(count);
  for (std::uint32_t f = 0; f < count; ++f) emit_as[f] = home[f] = f;
  std::unordered_map<std::uint64_t, std::uint32_t> face_of_edge;
  const auto key = [](VertexIndex a, VertexIndex b) { return (std::uint64_t{a} << 32) | b; };
  for (std::uint32_t f = 0; f < count; ++f) {
    for (const auto& loop : loops[f]) {
      for (std::size_t i = 0; i < loop.size(); ++i) face_of_edge[key(loop[i], loop[(i + 1) % loop.size()])] = f;
    }
  }
  // Three corners of a face's loops that are not collinear on the doubles.
  const auto frame = [&](std::uint32_t f) -> std::optional<std::array<VertexIndex, 3>> {
    std::vector<VertexIndex> corners;
    for (const auto& loop : loops[f]) corners.insert(corners.end(), loop.begin(), loop.end());
    if (corners.size() < 3) return std::nullopt;
    const Vec3 &a = positions[corners[0]];
    for (std::size_t j = 1; j < corners.size(); ++j) {
      for (std::size_t k = j + 1; k < corners.size(); ++k) {
        if (!collinear(a, positions[corners[j]], positions[corners[k]])) {
          return std::array<VertexIndex, 3>{corners[0], corners[j], corners[k]};
        }
      }
    }
    return std::nullopt;
  };
  const auto on_plane_of = [&](const std::array<VertexIndex, 3>& t, std::uint32_t g) {
    for (const auto& loop : loops[g]) {
      for (const VertexIndex v : loop) {
        if (orient3d(positions[t[0]], positions[t[1]], positions[t[2]], positions[v]) != Sign::zero) return false;
      }
    }
    return true;
  };
  // Outward normals of two faces point the same way (exactly).
  const auto same_facing = [&](std::uint32_t f, std::uint32_t g) {
    const bool same_plane = compare_normals(set, solid.faces[f].plane, solid.faces[g].plane) == Sign::positive;
    return same_plane == (solid.faces[f].reversed == solid.faces[g].reversed);
  };
  UnionFind groups;
  groups.reset(count);
  std::vector<std::optional<std::array<VertexIndex, 3>>> frames(count);
  std::vector<std::uint8_t> framed(count, 0), opposite(count, 0);
  bool any = false;
  for (std::uint32_t f = 0; f < count; ++f) {
    for (const auto& loop : loops[f]) {
      for (std::size_t i = 0; i < loop.size(); ++i) {
        const auto it = face_of_edge.find(key(loop[(i + 1) % loop.size()], loop[i]));
        if (it == face_of_edge.end()) continue;
        const std::uint32_t g = it->second;
        if (g == f || groups.find(f) == groups.find(g)) continue;
        if (!framed[f]) frames[f] = frame(f), framed[f] = 1;
        if (!frames[f] || !on_plane_of(*frames[f], g)) continue;
        const std::uint32_t rf = groups.find(f), rg = groups.find(g);
        const bool flips = !same_facing(f, g);
        groups.unite(f, g);
        opposite[groups.find(f)] = opposite[rf] || opposite[rg] || flips;
        any = true;
      }
    }
  }
  if (!any) return false;
  bool merged_any = false;
  std::vector<std::vector<std::uint32_t>> members(count);
  for (std::uint32_t f = 0; f < count; ++f) members[groups.find(f)].push_back(f);
  for (std::uint32_t root = 0; root < count; ++root) {
    const std::vector<std::uint32_t>& group = members[root];
    if (group.size() < 2 || !opposite[root]) continue;
    merge_face_group(set, solid, positions, group, loops, changed, emit_as, home);
    merged_any = true;
  }
  return merged_any;
}

// How far rounding moved the piece's vertices, and which corners lie within
// that reach of a plane, exactly. `rho`: the largest move of a vertex from its
// exact position to its output position, in the L1 norm (rationals). A corner
// lies within reach of plane n.x + d = 0 when its exact L1 distance to it,
// |n.x + d| / max |n_i|, is at most 2 rho: rounding the piece could have put it
// on the plane's other side. A face all of whose corners lie within reach of the
// plane of a face it shares an edge with bounds, with it, a wedge no thicker than
// that: merging the two moves at most 2 rho times its area.
struct RoundingReach {
  const PlaneSet& set;
  const Solid& solid;
  std::vector<std::optional<std::array<mpq_class, 3>>> exact;
  mpq_class rho = 0;

  RoundingReach(const PlaneSet& s, const Solid& piece, std::span<const Vec3> positions)
      : set(s), solid(piece), exact(piece.defs.size()) {
    for (VertexIndex v = 0; v < piece.defs.size(); ++v) {
      const auto& x = point(v);
      mpq_class moved = 0;
      for (int k = 0; k < 3; ++k) moved += abs(mpq_class(positions[v][k]) - x[k]);
      if (moved > rho) rho = moved;
    }
  }
  const std::array<mpq_class, 3>& point(VertexIndex v) {
    if (!exact[v]) exact[v] = exact_coordinates(set, solid.defs[v]);
    return *exact[v];
  }
  // The points within reach of `plane` (PlaneReach, exact).
  PlaneReach near(PlaneRef plane) const { return PlaneReach(set, plane, 2 * rho); }
  // A rounded position within reach of `plane`.
  bool within(const Vec3& p, PlaneRef plane) const { return near(plane).locate(p).within; }
  // Every corner of `loops` within reach of `plane`.
  bool within(const std::vector<std::vector<VertexIndex>>& loops, PlaneRef plane) {
    const PlaneReach reach = near(plane);
    for (const auto& loop : loops) {
      for (const VertexIndex v : loop) {
        if (!reach.locate(point(v)).within) return false;
      }
    }
    return true;
  }
  // Every corner of the solid's face `f` within reach of `plane`.
  bool within(std::uint32_t f, PlaneRef plane) {
    const SolidFace& face = solid.faces[f];
    std::vector<std::vector<VertexIndex>> loops;
    for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
      std::vector<VertexIndex>& loop = loops.emplace_back();
      for (const CornerEdge& edge : loop_edges(solid.corners, solid.loops[l])) loop.push_back(edge.from);
    }
    return within(loops, plane);
  }
};

// How merge_folded_faces joins the pairs of folded faces it is given: `pairs`,
// each pair on its own merits (every round of round_solid); `groups`, a pair
// joins when any face of one side's group so far may merge with any face of the
// other's, repeated until no pair joins, so that what a fold merges does not
// depend on the order the pairs come in, and the merged face is written on a
// cap's plane when a cap of the group sees its loops counter-clockwise (a
// refined wedge's strips, merged into the cap through a sliver that reaches the
// cap first, stay on the cap's plane instead of taking the sliver's);
// `groups_one_way`, the same, and two faces facing one way merge as well when
// one's corners all lie within rounding's reach of the other's plane (the
// sliver of space between them that the merge fills is thinner than the
// rounding, as a wedge that vanishes is). Only the last repair's refined solids
// take the latter two (see round_solid_rounds).
enum class FoldMerge { pairs, groups, groups_one_way };

// Faces that rounding folded against each other (see round_solid): a pair of
// faces whose rounded triangles certification found crossing, or sharing an
// edge with other triangles (a fold: the wedge between them is thinner than
// the rounding, and rounding turned it inside out), and whose loops share an
// edge run both ways. The wedge between such faces is a part thinner than the
// rounding, as a two-sided sheet is, though its faces do not lie on one plane;
// it vanishes the same way: the faces are merged into the face their sum leaves
// (merge_face_group), triangulated on the placed corners in projection, and
// certification and the volume the merge moved (held to what rounding can
// move) vouch for the result. `folds`: pairs of faces (indices of the loops
// before any merge, mapped through `home`). Decided by index; changes no
// position. `thin_only`: merge only pairs whose wedge is thin by its corners
// (within_rounding_reach), so that no fold that needs a wider merge drags a
// thick wedge along. `apart_too` (with `thin_only`): pairs whose loops share no
// edge are merged as well when thin: a slab thinner than the rounding between a
// cap and a face inside it (a cavity's face ulps from the cap's plane) rounds
// into a fold that touches no edge of the cap; as 2-chains on the cap's plane
// the face's loops, run the other way, add a hole to the cap, through which the
// cavity opens (the slab vanishes). `mode`: see FoldMerge. Returns how many
// faces were merged (each group counts its members).
std::size_t merge_folded_faces(const PlaneSet& set, const Solid& solid, std::span<const Vec3> positions,
                        std::vector<std::vector<std::vector<VertexIndex>>>& loops, std::vector<std::uint8_t>& changed,
                        std::vector<std::uint32_t>& emit_as, std::vector<std::uint32_t>& home,
                        std::span<const std::pair<std::uint32_t, std::uint32_t>> folds, bool thin_only,
                        bool apart_too = false, FoldMerge mode = FoldMerge::pairs) {
  const bool by_members = mode != FoldMerge::pairs;
  const auto count = static_cast<std::uint32_t>(loops.size());
  std::unordered_map<std::uint64_t, std::uint32_t> face_of_edge;
  const auto key = [](VertexIndex a, VertexIndex b) { return (std::uint64_t{a} << 32) | b; };
  for (std::uint32_t f = 0; f < count; ++f) {
    for (const auto& loop : loops[f]) {
      for (std::size_t i = 0; i < loop.size(); ++i) face_of_edge[key(loop[i], loop[(i + 1) % loop.size()])] = f;
    }
  }
  const auto share_edge = [&](std::uint32_t f, std::uint32_t g) {
    for (const auto& loop : loops[f]) {
      for (std::size_t i = 0; i < loop.size(); ++i) {
        const auto it = face_of_edge.find(key(loop[(i + 1) % loop.size()], loop[i]));
        if (it != face_of_edge.end() && it->second == g) return true;
      }
    }
    return false;
  };
  UnionFind groups;
  groups.reset(count);
  bool any = false;
  std::optional<RoundingReach> reach;
  if (by_members) {
    // Whether faces x and y (holding loops) may merge: as below, pair by pair,
    // but for faces facing one way (groups_one_way, thin only).
    const auto mergeable = [&](std::uint32_t x, std::uint32_t y) {
      if (!(apart_too && thin_only) && !share_edge(x, y)) return false;
      const SolidFace &a = solid.faces[emit_as[x]], &b = solid.faces[emit_as[y]];
      const Sign facing = compare_outward_normals(set, a, b);
      if (facing == Sign::zero) return false;
      const bool one_way = facing == Sign::positive;
      if (one_way && mode != FoldMerge::groups_one_way) return false;
      if (!thin_only && !one_way) return true;
      if (!reach) reach.emplace(set, solid, positions);
      return reach->within(loops[y], a.plane) || reach->within(loops[x], b.plane);
    };
    // The faces holding loops in each group, kept by the group's representative
    // (the union-find's smallest index), so a pair looks only at its two groups.
    std::vector<std::vector<std::uint32_t>> holding(count);
    for (std::uint32_t x = 0; x < count; ++x) {
      if (!loops[x].empty()) holding[x].push_back(x);
    }
    for (bool progress = true; progress;) {
      progress = false;
      for (const auto& [f, g] : folds) {
        if (f >= count || g >= count) continue;
        const std::uint32_t hf = home[f], hg = home[g];
        if (hf == no_index || hg == no_index || hf == hg) continue;
        const std::uint32_t rf = groups.find(hf), rg = groups.find(hg);
        if (rf == rg) continue;
        bool joined = false;
        for (std::size_t i = 0; i < holding[rf].size() && !joined; ++i) {
          for (std::size_t j = 0; j < holding[rg].size() && !joined; ++j) {
            joined = mergeable(holding[rf][i], holding[rg][j]);
          }
        }
        if (!joined) continue;
        groups.unite(rf, rg);
        const std::uint32_t kept = std::min(rf, rg), gone = std::max(rf, rg);
        holding[kept].insert(holding[kept].end(), holding[gone].begin(), holding[gone].end());
        holding[gone].clear();
        any = progress = true;
      }
    }
  }
  for (const auto& [f, g] : by_members ? std::span<const std::pair<std::uint32_t, std::uint32_t>>() : folds) {
    if (f >= count || g >= count) continue;
    const std::uint32_t hf = home[f], hg = home[g];
    if (hf == no_index || hg == no_index || hf == hg || groups.find(hf) == groups.find(hg)) continue;
    if (!(apart_too && thin_only) && !share_edge(hf, hg)) continue;
    // Facing opposite ways (their outward normals' dot product negative,
    // exactly): the solid lies between them, in the wedge. Two faces facing one
    // way crowd an edge only beside such a wedge; merging them would fill
    // what lies outside the solid between them.
    const SolidFace &a = solid.faces[emit_as[hf]], &b = solid.faces[emit_as[hg]];
    if (compare_outward_normals(set, a, b) != Sign::negative) continue;
    if (thin_only) {
      if (!reach) reach.emplace(set, solid, positions);
      if (!reach->within(loops[hg], a.plane) && !reach->within(loops[hf], b.plane)) continue;
    }
    groups.unite(hf, hg);
    any = true;
  }
  if (!any) return 0;
  std::vector<std::vector<std::uint32_t>> members(count);
  for (std::uint32_t f = 0; f < count; ++f) {
    if (!loops[f].empty()) members[groups.find(f)].push_back(f);
  }
  std::size_t merged = 0;
  for (const std::vector<std::uint32_t>& group : members) {
    if (group.size() < 2) continue;
    merge_face_group(set, solid, positions, group, loops, changed, emit_as, home, by_members);
    merged += group.size();
  }
  return merged;
}

// Steps 1 and 2 (see solid_mesh.hpp): positions, vertices merged where they
// rounded onto one point, faces triangulated.
// `repair_loops`: repair the loops of faces over merged vertices
// (repair_merged_loops) before triangulating them; round_solid asks for it once
// the plain merge has failed certification, so that a piece valid without it is
// written as before. `route_crossed`: the last round's repairs as well (edges
// routed through crossed corners, faces rounded onto one plane merged).
// `folds`: pairs of faces rounding folded against each other, merged
// (merge_folded_faces, only with `route_crossed`; `thin_folds_only` as there);
// `folded` receives how many faces that merged; `folds_apart_too`: as
// merge_folded_faces' `apart_too`. `face_of_triangle`: when given,
// the face (loop index) each triangle of `mesh` came from, in order.
void triangulate(const PlaneSet& set, const Solid& solid, const SolidMeshOptions& options, std::size_t attempt,
                 Mesh& mesh, std::size_t& merged, std::vector<VertexIndex>* mesh_vertex_of = nullptr,
                 bool repair_loops = false, bool route_crossed = false,
                 std::span<const std::pair<std::uint32_t, std::uint32_t>> folds = {},
                 std::vector<std::uint32_t>* face_of_triangle = nullptr, std::size_t* folded = nullptr,
                 bool thin_folds_only = false, std::span<const VertexIndex> snapped_to = {},
                 const mpq_class* snap_within = nullptr, bool folds_apart_too = false,
                 FoldMerge fold_merge = FoldMerge::pairs) {
  const std::size_t n = solid.defs.size();
  thread_local std::vector<Vec3> positions;
  thread_local std::vector<PointDef> placed;
  positions.resize(n);
  placed.resize(n);
  for (std::size_t v = 0; v < n; ++v) {
    const OutputPoint point = output_point(set, solid.defs[v], solid.approx[v]);
    positions[v] = point.position;
    placed[v] = point.placed;
  }
  // The last round's hot pixels (snap_clusters): every vertex takes its
  // cluster's representative's place, and so merges with it below.
  if (!snapped_to.empty()) {
    for (std::size_t v = 0; v < n; ++v) {
      if (snapped_to[v] != v) positions[v] = positions[snapped_to[v]], placed[v] = placed[snapped_to[v]];
    }
  }
  // One representative per position: an open-addressing table keyed by a hash of
  // the position, collisions resolved by comparing positions.
  thread_local std::vector<VertexIndex> representative;
  representative.resize(n);
  merged = 0;
  {
    thread_local std::vector<VertexIndex> slots;
    std::size_t capacity = 16;
    while (capacity < 2 * n) capacity *= 2;
    slots.assign(capacity, no_index);
    for (VertexIndex v = 0; v < n; ++v) {
      std::size_t i = PositionHash{}(positions[v]) & (capacity - 1);
      while (slots[i] != no_index && !PositionEqual{}(positions[slots[i]], positions[v])) i = (i + 1) & (capacity - 1);
      if (slots[i] == no_index) {
        slots[i] = v;
        representative[v] = v;
      } else {
        representative[v] = slots[i];
        ++merged;
      }
    }
  }
  const Mesh* input = options.attributes;
  const bool normals = input && input->corners.has_normals();
  const bool uvs = input && input->corners.has_uvs();
  const bool tangents = input && input->corners.has_tangents();
  thread_local std::vector<Triangle> face_triangles;
  thread_local std::vector<std::vector<VertexIndex>> loops;
  thread_local std::vector<VertexIndex> out_index;
  out_index.assign(n, no_index);
  mesh = Mesh{};
  mesh.positions.reserve(n);
  mesh.triangles.reserve(solid.corners.size());
  mesh.surfaces.reserve(solid.corners.size());
  // The repair of loops over merged vertices (repair_merged_loops), when asked
  // for: every face's loops at once, since an edge of one face may pass through a
  // vertex of another.
  thread_local std::vector<std::vector<std::vector<VertexIndex>>> repaired;
  thread_local std::vector<std::uint8_t> repaired_changed;
  thread_local std::vector<std::uint32_t> emit_as, home;  // merge_coplanar_sheets, merge_folded_faces
  emit_as.clear();
  if (face_of_triangle != nullptr) face_of_triangle->clear();
  if (folded != nullptr) *folded = 0;
  // Folds are merged on the loops over representatives, which the repair
  // builds, merged vertices or not.
  const bool repairing = repair_loops && (merged > 0 || (route_crossed && !folds.empty()) || snap_within != nullptr);
  if (repairing) {
    repaired.assign(solid.faces.size(), {});
    repaired_changed.assign(solid.faces.size(), 0);
    std::vector<std::uint8_t> candidate(n, 0);
    for (VertexIndex v = 0; v < n; ++v) {
      if (representative[v] != v) candidate[representative[v]] = 1;
    }
    for (std::uint32_t f = 0; f < solid.faces.size(); ++f) {
      const SolidFace& face = solid.faces[f];
      for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
        const SolidLoop& loop = solid.loops[l];
        std::vector<VertexIndex> corners;
        for (std::uint32_t i = 0; i < loop.corner_count; ++i) {
          const VertexIndex v = representative[solid.corners[loop.first_corner + i].vertex];
          // A corner snapped onto an input point lies off the face's plane: the
          // face is triangulated over the placed points too, whose collinear
          // runs (a snapped corner on the line of an edge) it keeps out of its
          // triangles.
          const VertexIndex own = solid.corners[loop.first_corner + i].vertex;
          repaired_changed[f] |= v != own || !(placed[own] == solid.defs[own]);
          if (corners.empty() || corners.back() != v) corners.push_back(v);
        }
        while (corners.size() > 1 && corners.back() == corners.front()) corners.pop_back();
        repaired[f].push_back(std::move(corners));
      }
      if (repaired_changed[f]) {
        for (const auto& loop : repaired[f]) {
          for (const VertexIndex v : loop) candidate[v] = 1;
        }
      }
    }
    std::vector<VertexIndex> candidates;
    for (VertexIndex v = 0; v < n; ++v) {
      if ((candidate[v] || snap_within != nullptr) && representative[v] == v) candidates.push_back(v);
    }
    // Only loops through a candidate, or along an edge it may lie in, can
    // change; a loop that changes marks its face.
    const auto before = repaired;
    if (route_crossed) route_edges_through_crossed_corners(set, solid, placed, positions, repaired);
    repair_merged_loops(positions, repaired, candidates, snap_within);
    for (std::uint32_t f = 0; f < solid.faces.size(); ++f) repaired_changed[f] |= repaired[f] != before[f];
    if (route_crossed) {
      merge_coplanar_sheets(set, solid, positions, repaired, repaired_changed, emit_as, home);
      if (!folds.empty()) {
        const std::size_t count =
            merge_folded_faces(set, solid, positions, repaired, repaired_changed, emit_as, home, folds, thin_folds_only,
                               folds_apart_too, fold_merge);
        if (folded != nullptr) *folded = count;
      }
    }
  }
  for (std::uint32_t f = 0; f < solid.faces.size(); ++f) {
    if (repairing && route_crossed && emit_as[f] == no_index) continue;
    const SolidFace& face = solid.faces[repairing && route_crossed ? emit_as[f] : f];
    face_triangles.clear();
    bool changed = false;
    if (repairing) {
      changed = repaired_changed[f];
      loops = repaired[f];
    } else if (merged > 0) {
      loops.clear();
      for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
        const SolidLoop& loop = solid.loops[l];
        std::vector<VertexIndex> corners;
        for (std::uint32_t i = 0; i < loop.corner_count; ++i) {
          const VertexIndex v = representative[solid.corners[loop.first_corner + i].vertex];
          changed |= v != solid.corners[loop.first_corner + i].vertex;
          if (corners.empty() || corners.back() != v) corners.push_back(v);
        }
        while (corners.size() > 1 && corners.back() == corners.front()) corners.pop_back();
        if (corners.size() >= 3) loops.push_back(std::move(corners));
      }
    }
    if (!changed) {
      const std::size_t face_attempt =
          attempt == 0 && !options.face_attempts.empty() ? options.face_attempts[f] : attempt;
      triangulate_face(set, solid, f, positions, face_triangles, face_attempt);
    } else if (!loops.empty()) {
      // A face that cannot be triangulated over its placed corners is left out.
      // If it had vanished in the rounding (seen: a thin annulus cap whose two
      // loops snapped onto the same ridge of vertices) the rest closes up without
      // it; if not, certification finds the mesh open and refuses it.
      face_triangles.clear();
      const Projection projection = projection_of(set, face.plane);
      // Folded in every projection (a snapped corner went past its neighbour's
      // edge): a fan over the rounded corners, from the apex the attempt names,
      // skipping apexes with a triangle collinear in 3D (decided exactly).
      // Certification vouches for the result or refuses it.
      const auto fan_over_rounded = [&](const std::vector<VertexIndex>& corners) {
        const std::size_t k = corners.size();
        for (std::size_t step = 0; step < k; ++step) {
          const std::size_t apex = (attempt - 1 + step) % k;
          bool flat = false;
          for (std::size_t i = 1; i + 1 < k && !flat; ++i) {
            const Vec3 &a = positions[corners[apex]], &b = positions[corners[(apex + i) % k]],
                       &c = positions[corners[(apex + i + 1) % k]];
            // Distinct representatives have distinct positions: three of them
            // are collinear exactly when one lies strictly between the others.
            flat = strictly_inside_segment(a, b, c) || strictly_inside_segment(b, c, a) ||
                   strictly_inside_segment(c, a, b);
          }
          if (flat) continue;
          for (std::size_t i = 1; i + 1 < k; ++i) {
            face_triangles.push_back({corners[apex], corners[(apex + i) % k], corners[(apex + i + 1) % k]});
          }
          return;
        }
      };
      if (!triangulate_merged_face(set, face, loops, placed, projection, face_triangles, repairing) && repairing) {
        // Loops split where they touched lie side by side: each on its own.
        for (const auto& loop : loops) {
          if (loops.size() > 1 &&
              triangulate_merged_face(set, face, std::span<const std::vector<VertexIndex>>(&loop, 1), placed,
                                      projection, face_triangles, true)) {
            continue;
          }
          // A face with holes is left out rather than fanned over its outer loop.
          if (face.loop_count == 1) fan_over_rounded(loop);
        }
      }
    }
    const bool cap = face.surface != original_surface;
    PlaneBasis basis(Plane{});
    Vec3 cap_normal;
    if (cap && (normals || uvs || tangents)) {
      const ApproxPlane a = set.approx(face.plane);
      basis = PlaneBasis(Plane{{a.a.value, a.b.value, a.c.value}, a.d.value});
      cap_normal = face.reversed ? -basis.normal : basis.normal;
    }
    for (Triangle t : face_triangles) {
      if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0]) continue;
      for (VertexIndex& v : t) {
        if (out_index[v] == no_index) {
          out_index[v] = static_cast<VertexIndex>(mesh.positions.size());
          mesh.positions.push_back(positions[v]);
        }
      }
      mesh.triangles.push_back({out_index[t[0]], out_index[t[1]], out_index[t[2]]});
      if (face_of_triangle != nullptr) face_of_triangle->push_back(f);
      mesh.surfaces.push_back(face.surface);
      for (VertexIndex v : t) {
        if (!cap) {
          if (input && (normals || uvs || tangents)) {
            AttributeSource{*input, normals, uvs, tangents}.append(face.source, solid.defs[v], positions[v],
                                                                   mesh.corners);
          }
          continue;
        }
        const Vec3 p = positions[v];
        if (normals) mesh.corners.normals.push_back(cap_normal);
        if (uvs) {
          mesh.corners.uvs.push_back(
              {dot(p, basis.u) * options.interior_uv_scale, dot(p, basis.v) * options.interior_uv_scale});
        }
        if (tangents) mesh.corners.tangents.push_back({basis.u.x, basis.u.y, basis.u.z, face.reversed ? -1.0 : 1.0});
      }
    }
  }
  if (mesh_vertex_of != nullptr) {
    mesh_vertex_of->resize(n);
    for (VertexIndex v = 0; v < n; ++v) (*mesh_vertex_of)[v] = out_index[representative[v]];
  }
}


// --- Parts thinner than the rounding --------------------------------------------
// Rounding can flatten a part of a piece that is thinner than the rounding of its
// coordinates: its two sides round onto the same vertices, and the mesh holds the
// same triangle twice, once each way (a two-sided sheet: non-manifold edges where
// it meets the rest, or the whole piece). Such a pair bounds no volume and removing
// it keeps every directed edge matched by its reverse, so the part vanishes into
// its neighbour (the piece across the cut, or the rest of the piece) and what is
// left is certified like any rounding. This is the collapse step of iterated snap
// rounding (Halperin & Packer 2002; in 3D, Lazard & Valque 2025, behind CGAL 6's
// autorefine_triangle_soup): elements that rounding made degenerate are
// eliminated, by index, not by distance.

// Removes every pair of triangles over the same three vertices turning opposite
// ways (matched by index; the first unmatched one in mesh order pairs with the
// first of its reverse), with their surfaces and corner attributes, then the
// vertices no triangle uses any more. Returns how many triangles went.
// `renumbered`: each old vertex's new index (no_index when it went).
// `quads`: also remove two-sided sheets over four corners triangulated with the
// two different diagonals, (a, b, c) + (a, c, d) one way and (a, d, b) + (b, d,
// c) the other (a cap whose corners snapped onto those of two input triangles,
// triangulated across the other diagonal): the four bound only the thin
// tetrahedron between the two triangulations, and removing them keeps every
// directed edge matched (their boundaries are a -> b -> c -> d and its reverse).
// Four such triangles always bound a tetrahedron: one that no other triangle
// meets along an edge, its corners off one plane (exact), is a part of its own
// (a union's tiny part touching the rest at a vertex), not a sheet, and stays.
// `kept`: when given, the old index of each triangle left, in order.
std::size_t cancel_two_sided_sheets(Mesh& mesh, std::vector<VertexIndex>& renumbered, bool quads = false,
                                    std::vector<std::uint32_t>* kept_triangles = nullptr) {
  const std::size_t count = mesh.triangles.size();
  // Key: the triangle rotated to start at its smallest index; its reverse is then
  // (a, c, b) for (a, b, c).
  auto rotated = [](Triangle t) {
    const auto smallest = std::min_element(t.begin(), t.end());
    std::rotate(t.begin(), smallest, t.end());
    return t;
  };
  std::vector<std::uint32_t> order(count);
  for (std::uint32_t t = 0; t < count; ++t) order[t] = t;
  std::vector<Triangle> keys(count);
  for (std::size_t t = 0; t < count; ++t) keys[t] = rotated(mesh.triangles[t]);
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    return keys[a] != keys[b] ? keys[a] < keys[b] : a < b;
  });
  auto find = [&](const Triangle& key) {
    return std::lower_bound(order.begin(), order.end(), key,
                            [&](std::uint32_t t, const Triangle& k) { return keys[t] < k; });
  };
  std::vector<std::uint8_t> removed(count, 0);
  std::size_t gone = 0;
  for (std::uint32_t t = 0; t < count; ++t) {
    if (removed[t]) continue;
    const Triangle& key = keys[t];
    const Triangle reverse{key[0], key[2], key[1]};
    if (reverse == key) continue;  // a repeated index: not a sheet
    for (auto it = find(reverse); it != order.end() && keys[*it] == reverse; ++it) {
      if (!removed[*it]) {
        removed[t] = removed[*it] = 1;
        gone += 2;
        break;
      }
    }
  }
  if (quads) {
    // Directed edge -> the triangles running it, among those left.
    std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> running;
    const auto edge = [](VertexIndex a, VertexIndex b) { return (std::uint64_t{a} << 32) | b; };
    for (std::uint32_t t = 0; t < count; ++t) {
      if (removed[t]) continue;
      for (int c = 0; c < 3; ++c) running[edge(mesh.triangles[t][c], mesh.triangles[t][(c + 1) % 3])].push_back(t);
    }
    const auto unremoved = [&](const Triangle& key) -> std::uint32_t {
      for (auto it = find(rotated(key)); it != order.end() && keys[*it] == rotated(key); ++it) {
        if (!removed[*it]) return *it;
      }
      return no_index;
    };
    for (std::uint32_t t = 0; t < count; ++t) {
      for (int c = 0; c < 3 && !removed[t]; ++c) {
        // t = (a, b, c) with the diagonal c -> a; its partner runs a -> c.
        const VertexIndex a = mesh.triangles[t][c], b = mesh.triangles[t][(c + 1) % 3], cc = mesh.triangles[t][(c + 2) % 3];
        const auto it = running.find(edge(a, cc));
        if (it == running.end()) continue;
        for (const std::uint32_t u : it->second) {
          if (u == t || removed[u]) continue;
          const Triangle& tu = mesh.triangles[u];
          VertexIndex d = no_index;
          for (int k = 0; k < 3; ++k) {
            if (tu[k] != a && tu[k] != cc) d = tu[k];
          }
          if (d == no_index || d == b) continue;
          const std::uint32_t q1 = unremoved({a, d, b});
          const std::uint32_t q2 = unremoved({b, d, cc});
          if (q1 == no_index || q2 == no_index || q1 == q2 || q1 == t || q1 == u || q2 == t || q2 == u) continue;
          // A tetrahedron of its own stays (see above; diplodocus.off).
          const auto alone = [&](VertexIndex x, VertexIndex y) {
            const auto there = running.find(edge(x, y)), back = running.find(edge(y, x));
            return there != running.end() && there->second.size() == 1 && back != running.end() &&
                   back->second.size() == 1;
          };
          if (alone(a, b) && alone(b, cc) && alone(cc, d) && alone(d, a) && alone(a, cc) && alone(b, d) &&
              orient3d(mesh.positions[a], mesh.positions[b], mesh.positions[cc], mesh.positions[d]) != Sign::zero) {
            continue;
          }
          removed[t] = removed[u] = removed[q1] = removed[q2] = 1;
          gone += 4;
          break;
        }
      }
    }
  }
  if (gone == 0) return 0;
  Mesh kept;
  std::vector<VertexIndex> index(mesh.positions.size(), no_index);
  for (std::uint32_t t = 0; t < count; ++t) {
    if (removed[t]) continue;
    Triangle out;
    for (int c = 0; c < 3; ++c) {
      VertexIndex& v = index[mesh.triangles[t][c]];
      if (v == no_index) {
        v = static_cast<VertexIndex>(kept.positions.size());
        kept.positions.push_back(mesh.positions[mesh.triangles[t][c]]);
      }
      out[c] = v;
    }
    kept.triangles.push_back(out);
    if (kept_triangles != nullptr) kept_triangles->push_back(t);
    kept.surfaces.push_back(mesh.surfaces[t]);
    for (int c = 0; c < 3; ++c) {
      if (mesh.corners.has_normals()) kept.corners.normals.push_back(mesh.corners.normals[3 * t + c]);
      if (mesh.corners.has_uvs()) kept.corners.uvs.push_back(mesh.corners.uvs[3 * t + c]);
      if (mesh.corners.has_tangents()) kept.corners.tangents.push_back(mesh.corners.tangents[3 * t + c]);
    }
  }
  mesh = std::move(kept);
  renumbered = std::move(index);
  return gone;
}

// How much volume rounding the solid's vertices to their output positions can
// move, exactly (rationals), as a bound: every point of a fan triangle of a face
// moves no further than the furthest of its corners, delta, so the region swept
// between the exact triangle and its rounded image lies within delta of the
// exact triangle, whose volume is at most 2 delta A + pi delta^2 P + 4/3 pi
// delta^3 (Steiner's formula for a convex plane set: area A, perimeter P). Here
// A, P and delta are taken in the L1 norm (upper bounds of the Euclidean
// ones), pi as 4 and 4/3 pi as 5. The written volume of the piece then differs
// from the exact one by at most the sum over the fan triangles; a piece whose
// rounding leaves no volume at all (it collapsed onto sheets or points) has
// its whole volume within it.
// That holds for the fan around `centre` only. With `any_triangulation`, delta
// is the furthest move over the whole face and the area term is doubled, which
// also covers a face triangulated otherwise over its rounded corners (the repairs'
// roundest fans, Delaunay, loops routed through a vertex on their edges): all
// such corners lie within delta of the exact plane, so two surfaces over the
// same loops, each covering the face once in projection, enclose at most 2 delta
// times its area between them. (fuzz_slice corpus: cube-off-cap-routed-through-
// vertex.bin, a cap fan whose wide triangle has exact corners while the
// retriangulated cap moved 0.33 eps x its area.)
mpq_class rounding_sweep_bound(const PlaneSet& set, const Solid& solid, bool any_triangulation = false) {
  const std::size_t n = solid.defs.size();
  std::vector<std::array<mpq_class, 3>> exact(n);
  std::vector<mpq_class> moved(n);
  for (std::size_t v = 0; v < n; ++v) {
    exact[v] = exact_coordinates(set, solid.defs[v]);
    const Vec3 p = output_position(set, solid.defs[v], solid.approx[v]);
    const double coordinates[3] = {p.x, p.y, p.z};
    for (int k = 0; k < 3; ++k) moved[v] += abs(mpq_class(coordinates[k]) - exact[v][k]);
  }
  auto length1 = [&](VertexIndex a, VertexIndex b) {
    return mpq_class(abs(exact[a][0] - exact[b][0]) + abs(exact[a][1] - exact[b][1]) + abs(exact[a][2] - exact[b][2]));
  };
  mpq_class bound = 0;
  for (const SolidFace& face : solid.faces) {
    const VertexIndex centre = solid.corners[solid.loops[face.first_loop].first_corner].vertex;
    mpq_class face_delta = 0;
    if (any_triangulation) {
      for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
        for (const CornerEdge& edge : loop_edges(solid.corners, solid.loops[l])) {
          if (moved[edge.from] > face_delta) face_delta = moved[edge.from];
        }
      }
    }
    for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
      for (const CornerEdge& edge : loop_edges(solid.corners, solid.loops[l])) {
        if (edge.from == centre || edge.to == centre) continue;
        const auto& a = exact[centre];
        const auto& b = exact[edge.from];
        const auto& c = exact[edge.to];
        const mpq_class u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
        const mpq_class w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        const mpq_class area = (abs(u[1] * w[2] - u[2] * w[1]) + abs(u[2] * w[0] - u[0] * w[2]) +
                                abs(u[0] * w[1] - u[1] * w[0])) / 2;
        const mpq_class perimeter = length1(centre, edge.from) + length1(edge.from, edge.to) + length1(edge.to, centre);
        const mpq_class delta =
            any_triangulation ? face_delta : std::max({moved[centre], moved[edge.from], moved[edge.to]});
        bound += delta * ((any_triangulation ? 4 : 2) * area + delta * (4 * perimeter + 5 * delta));
      }
    }
  }
  return bound;
}

// --- Where a piece touches itself -----------------------------------------------
// A cut can leave a piece that touches itself at a point, exactly: the plane
// passes through a saddle vertex of the surface whose two lobes on one side are
// one piece (several fans of faces meet at the vertex), or through the corner of
// a cavity or a dent that reaches the plane inside the cap (the corner touches
// the cap). No mesh of such a piece is valid, however it is rounded. The part
// thinner than the rounding, a point, gives way instead: each fan gets its own
// copy of the vertex, and every copy, and every corner touching a cap, moves a
// hair into its own fan's cone (along the mean direction to its neighbours).
// Certification then vouches for the result, as for any other rounding.

// The solid's vertices that lie on the plane of one of its cut faces (a cap)
// inside that face or on its boundary without being a corner of it. Exact.
std::vector<VertexIndex> corners_touching_caps(const PlaneSet& set, const Solid& solid) {
  std::vector<VertexIndex> touching;
  std::vector<PlaneRef> planes;
  for (const SolidFace& face : solid.faces) {
    if (face.plane.is_cut() && std::find(planes.begin(), planes.end(), face.plane) == planes.end()) {
      planes.push_back(face.plane);
    }
  }
  std::vector<std::uint8_t> corner_of_plane;
  std::vector<LoopEdge> loop;
  for (const PlaneRef plane : planes) {
    corner_of_plane.assign(solid.defs.size(), 0);
    for (const SolidFace& face : solid.faces) {
      if (face.plane != plane) continue;
      for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
        for (const CornerEdge& edge : loop_edges(solid.corners, solid.loops[l])) corner_of_plane[edge.from] = 1;
      }
    }
    const FaceGeometry geometry{set, solid.defs, solid.approx, projection_of(set, plane), false};
    for (VertexIndex v = 0; v < solid.defs.size(); ++v) {
      if (corner_of_plane[v] || side(set, plane, solid.defs[v], solid.approx[v]) != Sign::zero) continue;
      for (const SolidFace& face : solid.faces) {
        if (face.plane != plane) continue;
        // On a loop (at the place of a corner: a copy of a vertex of a piece
        // that meets itself along a chord) touches the cap as well.
        bool inside = false, on = false;
        for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count && !on; ++l) {
          loop.clear();
          for (const CornerEdge& edge : loop_edges(solid.corners, solid.loops[l])) loop.push_back({edge.from, edge.to, {}});
          const Sign where = locate_in_loop(geometry, v, loop);
          on = where == Sign::zero;
          if (where == Sign::positive) inside = !inside;
        }
        if (inside || on) {
          touching.push_back(v);
          break;
        }
      }
    }
  }
  return touching;
}

// What separate_touching did.
struct Separation {
  std::size_t moved = 0;        ///< vertex copies moved (a pinched vertex counts once per fan)
  mpq_class volume_change = 0;  ///< |signed volume after - before|, exactly
  /// Sum over moved copies of the distance moved x twice the area of their
  /// triangles, both in the L1 norm (upper bounds of the Euclidean), exactly.
  mpq_class volume_bound = 0;
};

// --- Edges that rounding made non-manifold ---------------------------------------
// A part of a piece thinner than the rounding can round onto an edge without
// flattening into a sheet: a neck squeezed to a segment, or two walls of a
// thin slot rounded onto one edge. The edge then has 2k triangles, k running it
// each way. As where a piece touches itself at a point, the part thinner than
// the rounding gives way: the triangles around the edge are paired in exact
// angular order, each pair bounding one wedge of the solid, and each pair gets
// its own copies of the edge's vertices (separate_touching), which then move a
// hair into their own wedges. This is how exact boolean operations on
// non-manifold input untangle an edge (CGAL's corefinement orders the faces
// around an edge with sorted_around_edge and pairs each face with the next one
// across the volume: Loriot, Tournois & Jamin, "Polygon Mesh Processing", CGAL
// 5.5 manual, section "Corefinement and Boolean Operations"; Granados et al.
// 2003, "Boolean operations on 3D selective Nef complexes", for the general
// radial order).

// pair_around_non_manifold_edges (shatter/kernel/non_manifold.hpp) pairs them.

// Splits every vertex of `mesh` where several edge-connected fans of triangles
// meet into one vertex per fan, then moves each copy, and each vertex of
// `touching` (one fan, touching a cap), toward its fan's neighbours by `scale`
// times its nearest neighbour's distance. Returns nothing moved when there is
// nothing to separate. `partner`: empty, or for each directed edge slot on a
// non-manifold edge the triangle it is paired with (pair_around_non_manifold_edges):
// triangles meet across such an edge only in their pairs, so the edge's
// vertices fall into one fan per pair where nothing else joins them.
// `held`: empty, or per vertex of the split mesh (split_vertex_fans numbers
// the copies the same way for the same mesh) whether the fan that keeps that
// vertex stays where it is, only the other fans' copies moving (see
// round_solid_rounds: a nearly flat fan's mean edge can point into another
// fan's wedge).
// Preconditions: closed and consistently oriented (each edge run as often each
// way), and every non-manifold edge paired in `partner`.
Separation separate_touching(Mesh& mesh, std::span<const VertexIndex> touching, double scale,
                             std::span<const std::uint32_t> partner = {}, std::span<const std::uint8_t> held = {}) {
  const std::size_t n = mesh.positions.size();
  const auto vertex_of = [&](std::uint32_t corner, std::uint32_t step) {
    return mesh.triangles[corner / 3][(corner % 3 + step) % 3];
  };
  // The fans of every vertex where several meet, each vertex's first keeping it
  // (split_vertex_fans), and every vertex of `touching` that has one fan: all
  // move, in vertex order, each vertex's fans in the order of their first corner.
  std::vector<VertexFan> split = split_vertex_fans(mesh, partner);
  std::vector<std::uint8_t> wanted(n, 0);
  for (const VertexIndex v : touching) wanted[v] = 1;
  for (const VertexFan& fan : split) wanted[fan.split_from] = 0;
  std::vector<std::vector<std::uint32_t>> lone_corners(n);  // of the wanted vertices left whole, in triangle order
  for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t) {
    for (std::uint32_t c = 0; c < 3; ++c) {
      const VertexIndex v = mesh.triangles[t][c];
      if (v < n && wanted[v]) lone_corners[v].push_back(3 * t + c);
    }
  }
  std::vector<VertexFan> to_move;
  to_move.reserve(split.size() + touching.size());
  std::size_t next_split = 0;
  for (VertexIndex v = 0; v < n; ++v) {
    if (!lone_corners[v].empty()) to_move.push_back({v, v, std::move(lone_corners[v])});
    while (next_split < split.size() && split[next_split].split_from == v) to_move.push_back(std::move(split[next_split++]));
  }
  // Moving p to p' changes the volume by dot(p' - p, sum of (b - p) x (c - p))/6
  // over its fan's triangles (p, b, c): each fan is a closed ring, so this equals
  // the change of the divergence sum, and it is computed on differences near p,
  // not on coordinates near the origin. Each triangle's part is a tetrahedron no
  // thicker than the move over the triangle: at most distance x area / 3.
  // In doubles first, as the moves are made; where coordinates near the top of
  // the double range overflow the products (fuzz_slice regressions:
  // cube-ply-huge-coordinates-pinch.bin gave NaN for both), again exactly, on
  // rationals over the moved doubles, the bound in the L1 norm (an upper bound
  // of the Euclidean one): twice the area x the distance, a third of which
  // bounds the change.
  Separation result;
  double volume_change = 0, volume_bound = 0;
  struct Move {
    VertexIndex vertex;
    const std::vector<std::uint32_t>* corners;
    Vec3 from, to;
  };
  std::vector<Move> moves;
  for (const VertexFan& fan : to_move) {
    if (fan.vertex == fan.split_from && fan.vertex < held.size() && held[fan.vertex]) continue;
    const Vec3 p = mesh.positions[fan.vertex];
    Vec3 direction, normal_sum;
    double nearest = INFINITY, area = 0;
    for (const std::uint32_t corner : fan.corners) {
      const Vec3 b = mesh.positions[vertex_of(corner, 1)] - p, c = mesh.positions[vertex_of(corner, 2)] - p;
      for (const Vec3& d : {b, c}) {
        const double length = norm(d);
        if (length > 0) direction = direction + d * (1 / length), nearest = std::min(nearest, length);
      }
      normal_sum = normal_sum + cross(b, c);
      area += 0.5 * norm(cross(b, c));
    }
    const double length = norm(direction);
    if (!(length > 0) || !std::isfinite(nearest)) continue;
    const double distance = scale * nearest;
    const Vec3 move = direction * (distance / length);
    mesh.positions[fan.vertex] = p + move;
    volume_change += dot(move, normal_sum) / 6;
    volume_bound += distance * area;
    moves.push_back({fan.vertex, &fan.corners, p, mesh.positions[fan.vertex]});
    ++result.moved;
  }
  if (std::isfinite(volume_change) && std::isfinite(volume_bound)) {
    result.volume_change = std::fabs(volume_change);
    result.volume_bound = volume_bound;
    return result;
  }
  // Exactly: the moves replayed in order, each against the positions its
  // neighbours had when it was made, so that the changes add up to the whole.
  for (auto m = moves.rbegin(); m != moves.rend(); ++m) mesh.positions[m->vertex] = m->from;
  mpq_class volume_change6 = 0, bound = 0;
  for (const Move& m : moves) {
    const std::array<mpq_class, 3> from{mpq_class(m.from.x), mpq_class(m.from.y), mpq_class(m.from.z)};
    const std::array<mpq_class, 3> step{mpq_class(m.to.x) - from[0], mpq_class(m.to.y) - from[1], mpq_class(m.to.z) - from[2]};
    mpq_class twice_area1 = 0;
    for (const std::uint32_t corner : *m.corners) {
      const Vec3 &bp = mesh.positions[vertex_of(corner, 1)], &cp = mesh.positions[vertex_of(corner, 2)];
      const std::array<mpq_class, 3> b{mpq_class(bp.x) - from[0], mpq_class(bp.y) - from[1], mpq_class(bp.z) - from[2]};
      const std::array<mpq_class, 3> c{mpq_class(cp.x) - from[0], mpq_class(cp.y) - from[1], mpq_class(cp.z) - from[2]};
      const std::array<mpq_class, 3> normal{b[1] * c[2] - b[2] * c[1], b[2] * c[0] - b[0] * c[2], b[0] * c[1] - b[1] * c[0]};
      volume_change6 += step[0] * normal[0] + step[1] * normal[1] + step[2] * normal[2];
      twice_area1 += abs(normal[0]) + abs(normal[1]) + abs(normal[2]);
    }
    bound += (abs(step[0]) + abs(step[1]) + abs(step[2])) * twice_area1;
    mesh.positions[m.vertex] = m.to;
  }
  result.volume_change = abs(volume_change6) / 6;
  result.volume_bound = bound;
  return result;
}

}  // namespace

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

namespace {

Vec3 vertex_average(const Mesh& mesh) {
  Vec3 sum;
  for (const Vec3& p : mesh.positions) sum = sum + p;
  return sum * (1.0 / static_cast<double>(mesh.positions.size()));
}

}  // namespace

Mesh triangulate_solid(const PlaneSet& set, const Solid& solid, const SolidMeshOptions& options) {
  Mesh mesh;
  std::size_t merged = 0;
  triangulate(set, solid, options, 0, mesh, merged);
  return mesh;
}

namespace {

// The volume a repair moved: the written mesh's volume against the exact piece's
// (both sides exact: the mesh's doubles and the solid's rationals), and what
// rounding the piece's vertices can move, whatever the triangulation over them
// (rounding_sweep_bound with any_triangulation), which the repaired mesh is held
// to: its triangles are the exact piece's, moved by the rounding and triangulated
// again, less sheets of no volume.
struct MovedVolume {
  mpq_class change = 0, bound = 0;
};

// The piece's exact six-fold volume and its rounding bounds (rounding_sweep_bound,
// per fan and for any triangulation), each computed at its first need and kept:
// they depend on the piece alone, while the rounds measure mesh after mesh
// against them (diplodocus.off's repair: the whole piece's exact volume, again
// at every attempt, was an eighth of its time). `set` and `solid` must outlive it.
class PieceVolumes {
 public:
  PieceVolumes(const PlaneSet& set, const Solid& solid) : set_(set), solid_(solid) {}
  const mpq_class& six() {
    if (!six_) six_ = exact_six_volume(set_, solid_);
    return *six_;
  }
  const mpq_class& sweep(bool any_triangulation) {
    std::optional<mpq_class>& kept = any_triangulation ? sweep_any_ : sweep_fan_;
    if (!kept) kept = rounding_sweep_bound(set_, solid_, any_triangulation);
    return *kept;
  }

 private:
  const PlaneSet& set_;
  const Solid& solid_;
  std::optional<mpq_class> six_, sweep_fan_, sweep_any_;
};

MovedVolume measured_moved_volume(PieceVolumes& piece, const Mesh& mesh) {
  mpq_class mesh_six = 0;
  for (const Triangle& t : mesh.triangles) {
    const Vec3 &a = mesh.positions[t[0]], &b = mesh.positions[t[1]], &c = mesh.positions[t[2]];
    const mpq_class ax(a.x), ay(a.y), az(a.z), bx(b.x), by(b.y), bz(b.z), cx(c.x), cy(c.y), cz(c.z);
    mesh_six += ax * (by * cz - bz * cy) + ay * (bz * cx - bx * cz) + az * (bx * cy - by * cx);
  }
  return {abs(mesh_six - piece.six()) / 6, piece.sweep(/*any_triangulation=*/true)};
}

// Reports `moved` in `result` (as doubles, each rounded toward zero, so the
// order the exact values have is kept) and says whether it is within its bound.
bool report_moved_volume(const MovedVolume& moved, RoundedSolid& result) {
  result.moved_volume = moved.change.get_d();
  result.moved_volume_bound = moved.bound.get_d();
  return moved.change <= moved.bound;
}

// The triangles of `mesh` with a shape (self_intersecting_pairs' precondition):
// three distinct corners not on one line (collinear, exact on the doubles).
// `index[i]` is shaped[i]'s place in mesh.triangles.
void shaped_triangles(const Mesh& mesh, std::vector<Triangle>& shaped, std::vector<std::uint32_t>& index) {
  for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t) {
    const Triangle& tri = mesh.triangles[t];
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[2] == tri[0]) continue;
    if (collinear(mesh.positions[tri[0]], mesh.positions[tri[1]], mesh.positions[tri[2]])) continue;
    shaped.push_back(tri);
    index.push_back(t);
  }
}

// The hot pixels of 3D snap rounding (Hobby 1999's hot pixels; in 3D, as CGAL
// 6's autorefine_triangle_soup snaps): a rounded vertex v that landed within
// rounding's reach of the plane of a face it does not belong to, and inside one
// of that face's triangles that crosses a triangle at v, is inserted into it: the
// triangle (a, b, c) becomes (a, b, v), (b, c, v), (c, a, v). The face then
// passes through v, as its exact surface passes within reach of it, and the
// piece touches itself at v (two fans), which separate_touching then takes
// apart. Decided exactly: the crossing pairs by self_intersecting_pairs, reach
// by RoundingReach on the face's exact plane, "inside" by exact orientations of
// the doubles in the face's projection (strictly inside, so no triangle made is
// flat in projection). Each triangle takes one vertex per pass; the new corner's
// attributes are the mean of the triangle's. `face_of[t]`: triangle t's face,
// extended for the triangles made. Returns how many vertices were inserted.
std::size_t insert_vertices_into_crossed_triangles(const PlaneSet& set, const Solid& solid, RoundingReach& reach,
                                                   Mesh& mesh, std::vector<std::uint32_t>& face_of) {
  std::vector<Triangle> shaped;
  std::vector<std::uint32_t> shaped_index;
  shaped_triangles(mesh, shaped, shaped_index);
  const std::size_t count = mesh.triangles.size();
  std::vector<VertexIndex> insert(count, no_index);
  const auto try_insert = [&](std::uint32_t t, std::uint32_t u) {
    if (insert[t] != no_index) return;
    const Triangle& tri = mesh.triangles[t];
    const PlaneRef plane = solid.faces[face_of[t]].plane;
    const Projection projection = projection_of(set, plane);
    const int i = (projection.axis + 1) % 3, j = (projection.axis + 2) % 3;
    const auto kept = [&](const Vec3& p) { return Vec2{p[i], p[j]}; };
    for (const VertexIndex v : mesh.triangles[u]) {
      if (v == tri[0] || v == tri[1] || v == tri[2]) continue;
      const Vec3& p = mesh.positions[v];
      if (!strictly_inside_triangle(kept(mesh.positions[tri[0]]), kept(mesh.positions[tri[1]]),
                                    kept(mesh.positions[tri[2]]), kept(p))) {
        continue;
      }
      if (!reach.within(p, plane)) continue;
      insert[t] = v;
      return;
    }
  };
  for (const TrianglePair& pair : self_intersecting_pairs(mesh.positions, shaped)) {
    const std::uint32_t t = shaped_index[pair.first], u = shaped_index[pair.second];
    if (face_of[t] == face_of[u]) continue;
    try_insert(t, u);
    try_insert(u, t);
  }
  std::size_t inserted = 0;
  for (std::uint32_t t = 0; t < count; ++t) {
    const VertexIndex v = insert[t];
    if (v == no_index) continue;
    const Triangle tri = mesh.triangles[t];
    const std::array<Triangle, 3> parts{Triangle{tri[0], tri[1], v}, Triangle{tri[1], tri[2], v}, Triangle{tri[2], tri[0], v}};
    mesh.triangles[t] = parts[0];
    for (int k = 1; k < 3; ++k) {
      mesh.triangles.push_back(parts[k]);
      mesh.surfaces.push_back(mesh.surfaces[t]);
      face_of.push_back(face_of[t]);
    }
    // Corner attributes: corners c and c + 1 of the triangle, then the mean.
    const auto spread = [&](auto& values) {
      if (values.empty()) return;
      using Value = std::decay_t<decltype(values[0])>;
      const Value a = values[3 * t], b = values[3 * t + 1], c = values[3 * t + 2];
      Value mean = a;
      if constexpr (std::is_same_v<Value, Vec2>) {
        mean = Vec2{(a.x + b.x + c.x) / 3, (a.y + b.y + c.y) / 3};
      } else if constexpr (std::is_same_v<Value, Vec3>) {
        mean = normalized(a + b + c);
      } else {
        const Vec3 d = normalized(Vec3{a.x + b.x + c.x, a.y + b.y + c.y, a.z + b.z + c.z});
        mean = Value{d.x, d.y, d.z, a.w};
      }
      values[3 * t + 2] = mean;
      for (const auto& [x, y] : {std::pair{b, c}, std::pair{c, a}}) {
        values.push_back(x);
        values.push_back(y);
        values.push_back(mean);
      }
    };
    spread(mesh.corners.normals);
    spread(mesh.corners.uvs);
    spread(mesh.corners.tangents);
    ++inserted;
  }
  return inserted;
}

// The last round's hot pixels (3D snap rounding, Halperin & Packer 2002's
// iterated form, Lazard & Valque 2025 behind CGAL 6's autorefine_triangle_soup:
// features closer than the rounding unit are snapped together). Rounding each
// vertex on its own to doubles can scramble vertices that lie closer together
// than the rounding moves them: the tip of a wedge between near-parallel planes
// holds corners of both of its faces ulps apart, and a face a few ulps off
// another holds its corners that close to the other's; rounded separately they
// change order and the faces fold. Vertices whose output positions lie within
// `within` of each other (the L-infinity norm, decided exactly on the doubles)
// are put into one cluster, transitively, and each vertex of a cluster is
// placed at its representative's output position: an input point of the
// cluster when it has one (doubles hold it exactly), else its smallest index.
// The part between the vertices of a cluster, thinner than the pixel, then
// vanishes, as parts that rounded onto one point do. `snapped_to[v]`: v's
// representative (v itself when alone). Returns whether any cluster has two
// vertices.
bool snap_clusters(const Solid& solid, std::span<const Vec3> positions, const mpq_class& within,
                   std::vector<VertexIndex>& snapped_to) {
  const auto n = static_cast<VertexIndex>(positions.size());
  std::vector<VertexIndex> order(n);
  for (VertexIndex v = 0; v < n; ++v) order[v] = v;
  std::sort(order.begin(), order.end(), [&](VertexIndex a, VertexIndex b) {
    return positions[a].x != positions[b].x ? positions[a].x < positions[b].x : a < b;
  });
  // Exactly (CoordinateReach: in doubles where they decide).
  const CoordinateReach pixel(within);
  const auto close = [&](VertexIndex a, VertexIndex b, int axis) {
    return pixel.within(positions[a][axis], positions[b][axis]);
  };
  UnionFind clusters;
  clusters.reset(n);
  bool any = false;
  for (std::size_t i = 0; i < order.size(); ++i) {
    for (std::size_t j = i + 1; j < order.size() && close(order[i], order[j], 0); ++j) {
      if (close(order[i], order[j], 1) && close(order[i], order[j], 2)) {
        clusters.unite(order[i], order[j]);
        any = true;
      }
    }
  }
  snapped_to.resize(n);
  for (VertexIndex v = 0; v < n; ++v) snapped_to[v] = v;
  if (!any) return false;
  std::vector<VertexIndex> best(n, no_index);
  const auto better = [&](VertexIndex a, VertexIndex b) {  // a preferred to b
    const bool ia = solid.defs[a].kind == PointKind::input, ib = solid.defs[b].kind == PointKind::input;
    return ia != ib ? ia : a < b;
  };
  for (VertexIndex v = 0; v < n; ++v) {
    VertexIndex& b = best[clusters.find(v)];
    if (b == no_index || better(v, b)) b = v;
  }
  for (VertexIndex v = 0; v < n; ++v) snapped_to[v] = best[clusters.find(v)];
  return true;
}

// Adds to `pairs` (kept sorted and unique, the smaller face first) the pairs
// of faces whose triangles in `mesh` fold against each other: triangles of
// different faces around an edge that more than two triangles share, or run one
// way by both, and pairs of triangles of different faces that intersect
// (self_intersecting_pairs, exact, over the triangles with three distinct
// non-collinear corners). `face_of[t]`: the face (loop index) triangle t came from.
void add_folded_face_pairs(const Mesh& mesh, std::span<const std::uint32_t> face_of,
                           std::vector<std::pair<std::uint32_t, std::uint32_t>>& pairs) {
  const auto add = [&](std::uint32_t f, std::uint32_t g) {
    if (f != g) pairs.emplace_back(std::min(f, g), std::max(f, g));
  };
  struct Use {
    std::uint64_t key;
    std::uint32_t triangle;
    bool forward;
  };
  std::vector<Use> uses;
  for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t) {
    for (int c = 0; c < 3; ++c) {
      const VertexIndex a = mesh.triangles[t][c], b = mesh.triangles[t][(c + 1) % 3];
      uses.push_back({(std::uint64_t{std::min(a, b)} << 32) | std::max(a, b), t, a < b});
    }
  }
  std::sort(uses.begin(), uses.end(), [](const Use& x, const Use& y) {
    return x.key != y.key ? x.key < y.key : x.triangle < y.triangle;
  });
  for (std::size_t i = 0; i < uses.size();) {
    std::size_t j = i;
    while (j < uses.size() && uses[j].key == uses[i].key) ++j;
    const bool folded = j - i > 2 || (j - i == 2 && uses[i].forward == uses[i + 1].forward);
    if (folded) {
      for (std::size_t k = i; k < j; ++k) {
        for (std::size_t l = k + 1; l < j; ++l) add(face_of[uses[k].triangle], face_of[uses[l].triangle]);
      }
    }
    i = j;
  }
  std::vector<Triangle> shaped;
  std::vector<std::uint32_t> shaped_index;
  shaped_triangles(mesh, shaped, shaped_index);
  for (const TrianglePair& p : self_intersecting_pairs(mesh.positions, shaped)) {
    add(face_of[shaped_index[p.first]], face_of[shaped_index[p.second]]);
  }
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
}

// `result` but for its mesh, which the caller replaces (copying it would cost a
// mesh per certified piece).
RoundedSolid copy_without_mesh(RoundedSolid& result) {
  Mesh mesh = std::move(result.mesh);
  RoundedSolid copy = result;
  result.mesh = std::move(mesh);
  return copy;
}

// The full check, self-intersections included, narrowed by what is known to be
// valid already: the parts of a union (their pairs within one part skipped), or
// else the trusted mesh the piece was cut from. Both accept exactly the meshes
// validate_mesh accepts (validate.hpp says why).
ValidationReport validate_knowing(const Mesh& mesh, const SolidMeshOptions& options) {
  if (!options.parts.empty()) return validate_mesh_of_parts(mesh, options.parts);
  if (options.trusted != nullptr && options.trusted_triangles != nullptr) {
    return validate_mesh_against(mesh, *options.trusted_triangles, options.cut);
  }
  return validate_mesh_against(mesh, options.trusted, options.cut);
}

// Certifies a rounded mesh as round_solid promises: the linear certificate of
// certify_piece when it applies (it accepts only valid meshes, and the full check
// accepts every valid one, so the mesh written is the same either way), else
// validate_knowing; or the topology alone (with vertices where the surface
// touches itself allowed) for a solid accepted with self-intersections.
ValidationReport certify_rounded(const Mesh& mesh, const SolidMeshOptions& options) {
  if (!options.allow_self_intersections) {
    if (certify_piece(mesh)) {
      ValidationReport certified;
      certified.vertex_count = mesh.vertex_count();
      certified.triangle_count = mesh.triangle_count();
      certified.self_intersections_checked = true;
      return certified;
    }
    return validate_knowing(mesh, options);
  }
  ValidationOptions topology_only;
  topology_only.check_self_intersections = false;
  ValidationReport report = validate_mesh(mesh, topology_only);
  // A surface allowed to cross itself may touch itself at a vertex.
  std::erase_if(report.defects, [](const Defect& d) { return d.kind == DefectKind::non_manifold_vertex; });
  return report;
}

// --- Wedges beyond rounding's reach ------------------------------------------------
// The last repair, tried only when every round above has failed and the piece
// could not vanish whole: a cap folded against faces that share an edge with it
// and lie nearly in its plane, though not all of their corners lie within
// rounding's reach of it (a chain of near-parallel cuts: the earlier cap's
// clipped faces run from the wedge's tip, on the cap, to corners far off its
// plane), so the thin round cannot merge them and merging them whole moves more
// than rounding may. Such faces are split where they leave rounding's reach:
// along their line with a new plane parallel to the cap's, offset into the
// piece by a few times the rounding move (the cap's doubles with another
// offset, a plane of the set like any cut, so every new vertex is defined
// exactly, as split_solid defines one). The solid is the same point set, with
// more faces: the strips between the cap and the new plane are thin by their
// corners, and the rounds above, run again on the refined solid, merge them
// into the cap (the thin part of the wedge vanishes) and certify the result.
// The volume moved is held to the original piece's bound, measured against its
// exact volume, which the refinement does not change.

// The solid with each face of `split` (convex, one loop, with corners strictly on
// both sides of `plane`) split along its line with `plane`, the crossing vertices
// inserted into the edges of the faces across. `set` must hold `plane`. Returns
// false, leaving `out` undefined, when no face was split.
bool split_faces_along(const PlaneSet& set, const Solid& solid, PlaneRef plane, std::span<const std::uint32_t> split,
                       Solid& out) {
  out = Solid{};
  out.defs = solid.defs;
  out.approx = solid.approx;
  out.convex = solid.convex;
  std::vector<std::uint8_t> splitting(solid.faces.size(), 0);
  std::vector<Sign> sides(solid.defs.size(), Sign::zero);
  std::vector<std::uint8_t> sided(solid.defs.size(), 0);
  const auto side_of = [&](VertexIndex v) {
    if (!sided[v]) sides[v] = side(set, plane, solid.defs[v], solid.approx[v]), sided[v] = 1;
    return sides[v];
  };
  for (const std::uint32_t f : split) {
    const SolidFace& face = solid.faces[f];
    if (!face.convex || face.loop_count != 1) continue;
    bool below = false, above = false;
    for (const CornerEdge& edge : loop_edges(solid.corners, solid.loops[face.first_loop])) {
      below |= side_of(edge.from) == Sign::negative;
      above |= side_of(edge.from) == Sign::positive;
    }
    splitting[f] = below && above;
  }
  // The crossing vertex of each crossed edge of a face split, once per edge.
  IndexMap crossing(64);
  bool any = false;
  for (std::uint32_t f = 0; f < solid.faces.size(); ++f) {
    if (!splitting[f]) continue;
    any = true;
    const SolidFace& face = solid.faces[f];
    for (const CornerEdge& edge : loop_edges(solid.corners, solid.loops[face.first_loop])) {
      const Sign a = side_of(edge.from), b = side_of(edge.to);
      if (a == Sign::zero || b == Sign::zero || a == b) continue;
      const auto candidate = static_cast<VertexIndex>(out.defs.size());
      if (crossing.insert(undirected_edge_key(edge.from, edge.to), candidate) != candidate) continue;
      const PointDef def = edge_crossing_def(face, solid.corners[edge.corner].line, plane);
      out.defs.push_back(def);
      out.approx.push_back(approximate(set, def));
    }
  }
  if (!any) return false;
  std::vector<SolidCorner> augmented;
  for (std::uint32_t f = 0; f < solid.faces.size(); ++f) {
    const SolidFace& face = solid.faces[f];
    SolidFace copy = face;
    copy.first_loop = static_cast<std::uint32_t>(out.loops.size());
    for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
      augmented.clear();
      for (const CornerEdge& edge : loop_edges(solid.corners, solid.loops[l])) {
        const EdgeLine& line = solid.corners[edge.corner].line;
        augmented.push_back({edge.from, line});
        const VertexIndex x = crossing.find(undirected_edge_key(edge.from, edge.to));
        if (x != no_index) augmented.push_back({x, line});
      }
      if (!splitting[f]) {
        out.loops.push_back({static_cast<std::uint32_t>(out.corners.size()), static_cast<std::uint32_t>(augmented.size())});
        out.corners.insert(out.corners.end(), augmented.begin(), augmented.end());
        continue;
      }
      // A convex loop with corners strictly on both sides meets the plane at
      // exactly two of its (augmented) corners: the chord between them.
      std::vector<std::size_t> on;
      for (std::size_t i = 0; i < augmented.size(); ++i) {
        const VertexIndex v = augmented[i].vertex;
        if (v >= solid.defs.size() || side_of(v) == Sign::zero) on.push_back(i);
      }
      if (on.size() != 2) return false;
      EdgeLine chord;
      chord.other = plane;
      for (const auto& [from, to] : {std::pair{on[0], on[1]}, std::pair{on[1], on[0]}}) {
        if (from != on[0]) copy.first_loop = static_cast<std::uint32_t>(out.loops.size());
        const auto first = static_cast<std::uint32_t>(out.corners.size());
        for (std::size_t i = from; i != to; i = (i + 1) % augmented.size()) out.corners.push_back(augmented[i]);
        out.corners.push_back({augmented[to].vertex, chord});
        out.loops.push_back({first, static_cast<std::uint32_t>(out.corners.size()) - first});
        copy.loop_count = 1;
        out.faces.push_back(copy);
      }
    }
    if (!splitting[f]) {
      copy.loop_count = face.loop_count;
      out.faces.push_back(copy);
    }
  }
  return true;
}

// --- Strips thin by their corners --------------------------------------------------
// After the wedge split, tried only when it has failed too (so that every piece
// written before is written as before): a corner strictly inside the piece a
// fraction of an ulp from a cap's plane (an earlier cap's vertex, the new plane
// through it up to rounding: smoke corpus seed 7 case 28) takes the position of
// its own crossings with the cap (output_point snaps a crossing within 64 ulps
// of its segment's end onto it), and the faces between it and the cap, thin by
// their corners, then lie on the cap over triangles of the cap's own, laid
// over them or crossing them. The folding rounds merge only the pairs
// certification names, and it never names these: their triangles cancel as
// sheets, or cross the cap's only where thicker folds cross it too, which it
// names first. Such faces are found here from the exact solid instead.

// For each cap (a face on a cut plane), the faces reached from it across shared
// edges, face by face, whose corners all lie within rounding's reach of the
// cap's plane (RoundingReach: exactly, in the L1 norm), not on its plane: the
// strips between the cap and the corners by it, as pairs (cap, face), by cap,
// then in the order they were reached. The wedge each bounds with the cap is
// no thicker than the reach, so merging it moves at most the reach times its
// area, as a fold's merge does.
std::vector<std::pair<std::uint32_t, std::uint32_t>> strips_thin_by_corners(const Solid& solid, RoundingReach& reach) {
  const auto count = static_cast<std::uint32_t>(solid.faces.size());
  std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> faces_of_edge;
  const auto key = [](VertexIndex a, VertexIndex b) {
    return (std::uint64_t{std::min(a, b)} << 32) | std::max(a, b);
  };
  for (std::uint32_t f = 0; f < count; ++f) {
    const SolidFace& face = solid.faces[f];
    for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
      for (const CornerEdge& edge : loop_edges(solid.corners, solid.loops[l])) {
        faces_of_edge[key(edge.from, edge.to)].push_back(f);
      }
    }
  }
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
  std::vector<std::uint8_t> visited(count);
  std::vector<std::uint32_t> reached;
  for (std::uint32_t c = 0; c < count; ++c) {
    const SolidFace& cap = solid.faces[c];
    if (!cap.plane.is_cut()) continue;
    std::fill(visited.begin(), visited.end(), 0);
    visited[c] = 1;
    reached.assign(1, c);
    for (std::size_t next = 0; next < reached.size(); ++next) {
      const SolidFace& from = solid.faces[reached[next]];
      for (std::uint32_t l = from.first_loop; l < from.first_loop + from.loop_count; ++l) {
        for (const CornerEdge& edge : loop_edges(solid.corners, solid.loops[l])) {
          for (const std::uint32_t g : faces_of_edge[key(edge.from, edge.to)]) {
            if (visited[g]) continue;
            visited[g] = 1;
            if (solid.faces[g].plane == cap.plane || !reach.within(g, cap.plane)) continue;
            pairs.emplace_back(c, g);
            reached.push_back(g);
          }
        }
      }
    }
  }
  return pairs;
}

// Every cap's strips thin by their corners (strips_thin_by_corners) merged into
// it as folds (merge_folded_faces, thin pairs: each face's group joins the cap's
// only through faces within reach), with no snapping, then with snap rounding's
// pixels (snap_levels, as the snapping round: a fold of the thicker faces along
// an edge shorter than the rounding vanishes into a vertex), each by pairs, then
// by groups (FoldMerge), over attempts 1 to 3, sheets cancelled; the first mesh
// certified whose exact volume moved is within the piece's rounding bound
// (measured_moved_volume). A finite pass: a fixed list of pairs, seven pixels,
// two modes, three attempts, each one triangulation and certification.
// `positions`: the output positions of the solid's vertices; `reach` over them;
// `piece` the solid's volumes.
std::optional<RoundedSolid> round_merging_thin_strips(const PlaneSet& set, const Solid& solid,
                                                      const SolidMeshOptions& options,
                                                      std::span<const Vec3> positions, RoundingReach& reach,
                                                      std::span<const int> snap_levels, PieceVolumes& piece) {
  const std::vector<std::pair<std::uint32_t, std::uint32_t>> strips = strips_thin_by_corners(solid, reach);
  if (strips.empty()) return std::nullopt;
  std::vector<VertexIndex> snapped_to, mesh_vertex_of, renumbered;
  std::vector<std::uint32_t> face_of_triangle, kept;
  mpq_class pixel;
  for (std::size_t level = 0; level <= snap_levels.size(); ++level) {
    const bool snapping = level > 0;
    std::size_t snapped = 0;
    if (snapping) {
      pixel = reach.rho * mpq_class(mpz_class(1) << snap_levels[level - 1]);
      snap_clusters(solid, positions, pixel, snapped_to);
      for (VertexIndex v = 0; v < solid.defs.size(); ++v) snapped += snapped_to[v] != v;
    }
    for (const FoldMerge mode : {FoldMerge::pairs, FoldMerge::groups}) {
      for (std::size_t attempt = 1; attempt < 4; ++attempt) {
        Mesh mesh;
        std::size_t merged = 0, folded = 0;
        triangulate(set, solid, options, attempt, mesh, merged, &mesh_vertex_of, true, true, strips, &face_of_triangle,
                    &folded, true, snapping ? std::span<const VertexIndex>(snapped_to) : std::span<const VertexIndex>(),
                    snapping ? &pixel : nullptr, false, mode);
        if (mesh.triangles.empty()) continue;
        ValidationReport report = certify_rounded(mesh, options);
        std::size_t gone = 0;
        if (!report.valid()) {
          Mesh sheetless = mesh;
          gone = cancel_two_sided_sheets(sheetless, renumbered, true, &kept);
          if (gone == 0 || sheetless.triangles.empty()) continue;
          mesh = std::move(sheetless);
          if (!certify_rounded(mesh, options).valid()) continue;
        }
        RoundedSolid written;
        if (!report_moved_volume(measured_moved_volume(piece, mesh), written)) continue;
        written.mesh = std::move(mesh);
        written.valid = true;
        written.merged_vertices = merged;
        written.retriangulated_faces = solid.faces.size();
        written.vanished_triangles = gone;
        written.folded_faces = folded;
        written.snapped_vertices = snapped;
        written.attempt = -1;
        return written;
      }
    }
  }
  return std::nullopt;
}

// round_solid; `collapse_wedges`: also the last repair above (not when rounding a
// solid it refined); `fold_merge`: how the folding rounds merge (FoldMerge; a
// refined solid of the widened split takes `groups` or `groups_one_way`).
RoundedSolid round_solid_rounds(const PlaneSet& set, const Solid& solid, const SolidMeshOptions& options,
                                bool collapse_wedges, FoldMerge fold_merge = FoldMerge::pairs) {
  if (!options.face_attempts.empty() && options.face_attempts.size() != solid.faces.size()) {
    throw std::invalid_argument("round_solid: face_attempts must hold one attempt per face");
  }
  RoundedSolid result;
  PieceVolumes piece(set, solid);
  ValidationReport first_report;
  bool flattened_whole = false;    // every triangle was in a two-sided sheet
  std::size_t sheets_cancelled = 0;  // triangles of two-sided sheets removed at this attempt
  std::optional<std::vector<VertexIndex>> touching_caps;  // solid vertices; found at the first need
  std::vector<VertexIndex> mesh_vertex_of, touching;
  // Attempt 0 is the cheapest triangulation. A fold that rounding made comes from
  // a sliver triangle (a corner nearly on the line of its neighbours, where two
  // input faces are nearly coplanar); later attempts take the roundest fans and
  // the exact Delaunay triangulation, which keep such corners out of slivers.
  // The second round of attempts (untangle_edges) also untangles edges that
  // rounding made non-manifold (pair_around_non_manifold_edges): a repair tried
  // only once the others have failed, so that every piece they write is written
  // as before it existed.
  // The third round (folding), tried only when the first two have failed,
  // merges faces that rounding folded against each other (merge_folded_faces):
  // attempts 1 to 3 again, each with the pairs of faces whose triangles the
  // second round's certification found folded, then with those its own
  // failures add, until a retry finds no new pair (at most fold_retries times).
  // It merges first only the pairs whose wedge is thin by its corners (the
  // faces' corners within reach of each other's planes, RoundingReach), then,
  // if that fails, every pair found (thin only where it folded).
  constexpr std::size_t attempts = 4, fold_retries = 6, fold_steps = (attempts - 1) * fold_retries;
  // A third phase merges the thin pairs again and also inserts rounded
  // vertices into the triangles they crossed within rounding's reach
  // (insert_vertices_into_crossed_triangles, 3D snap rounding's hot pixels).
  constexpr std::size_t plain_steps = 2 * attempts, steps = plain_steps + 3 * fold_steps;
  // The last round (snapping), tried only when all of the above has failed, so
  // that no piece written before it existed is written differently, is 3D snap
  // rounding at coarser pixels: for each pixel of 2^k times the largest
  // rounding move rho (k in snap_levels), vertices within a pixel of each other
  // are placed at one of them (snap_clusters) and edges passing within a pixel
  // of a vertex are routed through it (repair_merged_loops' `near`); then
  // attempts 1 to 3, each retried with the faces its failures find folded
  // merged (merge_folded_faces, every pair), until a retry finds no new pair.
  // Why it ends: six pixels x three attempts x at most snap_retries tries,
  // each one pass of triangulate and certify, every part of which is finite
  // (clusters by one union-find; insertions only of existing vertices into
  // edges, each edge taking each vertex once; spike removal and splitting only
  // shorten loops; merges only remove faces). Why what it writes is valid:
  // nothing of it is trusted, the mesh is taken only when certify_rounded
  // passes (closed, oriented, manifold, no self-intersection, positive volume)
  // and when the volume it moved, measured exactly against the exact piece, is
  // within what rounding the piece's vertices alone can move (rounding_sweep_bound,
  // as for folds merged), however large the pixel: what vanishes is a part
  // thinner than the rounding of its coordinates, between vertices a pixel apart:
  // the tip of a wedge between near-parallel planes, thinner than the rounding
  // near their shared edge, which folded when its corners were rounded one by
  // one.
  // (Pixels to 2^10 rho repair the fuzz's wedges; the pieces of a chain cut
  // again as written, themselves wedges 2^-20 to 2^-40 thick, need 2^16 and
  // 2^24: measured on the robustness corpus, 2026-12-03.)
  constexpr std::array<int, 6> snap_levels{1, 3, 6, 10, 16, 24};
  constexpr std::size_t snap_retries = 2, snap_steps = (attempts - 1) * snap_retries;
  // After it, tried only when every round above has failed (so that no piece
  // written before it existed is written differently; a piece that vanished
  // whole may now be written instead, when this certifies it), the folding round's
  // thin phase again with pairs of faces whose loops share no edge merged too
  // (merge_folded_faces' `apart_too`): a slab thinner than the rounding between
  // a cap and a face it passes ulps from (a cavity's face in a plane that holds
  // it up to rounding: issue 17's hollow-egg, corpus case 933) folds where no
  // edge of the cap is near; the face's loops become a hole of the cap and the
  // slab vanishes. Why it ends and why what it writes is valid: as the folding
  // round (a fixed number of retries, each a finite pass; certified, and the
  // volume moved held to the rounding's bound).
  constexpr std::size_t snap_end = steps + snap_levels.size() * snap_steps;
  constexpr std::size_t all_steps = snap_end + fold_steps;
  std::array<std::vector<std::pair<std::uint32_t, std::uint32_t>>, attempts> snap_folds;
  std::array<bool, attempts> snap_stalled{};
  std::vector<VertexIndex> snapped_to;
  mpq_class snap_pixel;
  // Per phase of the folding round (0 to 2) and the round of pairs apart (3).
  std::array<std::array<std::vector<std::pair<std::uint32_t, std::uint32_t>>, attempts>, 4> fold_pairs;
  std::array<std::array<bool, attempts>, 4> fold_stalled{};
  std::optional<RoundingReach> reach;
  std::vector<Vec3> output_positions;
  std::vector<std::uint32_t> face_of_triangle;
  // The first separation certified with some fans held still (see below), the
  // last resort.
  std::optional<RoundedSolid> held_fallback;
  // Whether the piece's exact volume is within what rounding its vertices can
  // move (rounding_sweep_bound): then it may vanish whole (see below).
  std::optional<bool> thin_whole;
  const auto within_its_rounding = [&] {
    if (!thin_whole) thin_whole = piece.six() <= 6 * piece.sweep(false);
    return *thin_whole;
  };
  for (std::size_t step = 0; step < all_steps; ++step) {
    const bool apart = step >= snap_end;
    const bool snapping = step >= steps && !apart;
    const bool folding = (step >= plain_steps && !snapping) || apart;
    const std::size_t phase = apart ? 3 : folding ? (step - plain_steps) / fold_steps : 0;
    const bool thin_only = phase != 1 && !snapping;
    const bool inserting = folding && phase == 2;
    const std::size_t snap_retry = snapping ? (step - steps) % snap_retries : 0;
    const std::size_t attempt = snapping ? 1 + (step - steps) % snap_steps / snap_retries
                                : apart  ? 1 + (step - snap_end) / fold_retries
                                : folding ? 1 + (step - plain_steps) % fold_steps / fold_retries
                                          : step % attempts;
    if (snapping && attempt == 1 && snap_retry == 0) {
      // A new pixel size: the clusters it makes, and where they place the vertices.
      if (!reach) {
        for (VertexIndex v = 0; v < solid.defs.size(); ++v) {
          output_positions.push_back(output_position(set, solid.defs[v], solid.approx[v]));
        }
        reach.emplace(set, solid, output_positions);
      }
      const int level = snap_levels[(step - steps) / snap_steps];
      for (auto& pairs : snap_folds) pairs.clear();
      snap_stalled = {};
      snap_pixel = reach->rho * mpq_class(mpz_class(1) << level);
      snap_clusters(solid, output_positions, snap_pixel, snapped_to);
    }
    std::size_t snapped = 0;
    if (snapping) {
      for (VertexIndex v = 0; v < solid.defs.size(); ++v) snapped += snapped_to[v] != v;
    }
    if (snapping && ((snap_retry > 0 && (snap_folds[attempt].empty() || snap_stalled[attempt])))) {
      continue;
    }
    const bool untangle_edges = step >= attempts;
    // The second round's pairs start every phase; each phase adds its own.
    auto& folds = fold_pairs[phase];
    auto& folds_stalled = fold_stalled[phase];
    if (folding && (folds[attempt].empty() || folds_stalled[attempt])) continue;
    Mesh mesh;
    std::size_t merged = 0, folded_faces = 0;
    ValidationReport report;
    triangulate(set, solid, options, attempt, mesh, merged, &mesh_vertex_of, attempt > 0, untangle_edges,
                folding    ? std::span<const std::pair<std::uint32_t, std::uint32_t>>(folds[attempt])
                : snapping ? std::span<const std::pair<std::uint32_t, std::uint32_t>>(snap_folds[attempt])
                           : std::span<const std::pair<std::uint32_t, std::uint32_t>>(),
                untangle_edges ? &face_of_triangle : nullptr, &folded_faces, thin_only,
                snapping ? std::span<const VertexIndex>(snapped_to) : std::span<const VertexIndex>(),
                snapping ? &snap_pixel : nullptr, apart, fold_merge);
    std::size_t inserted = 0;
    if (inserting) {
      if (!reach) {
        for (VertexIndex v = 0; v < solid.defs.size(); ++v) {
          output_positions.push_back(output_position(set, solid.defs[v], solid.approx[v]));
        }
        reach.emplace(set, solid, output_positions);
      }
      inserted = insert_vertices_into_crossed_triangles(set, solid, *reach, mesh, face_of_triangle);

    }
    // (Not when folds were merged: their volume is held to its bound below.)
    if (solid.convex && merged == 0 && !folding && certify_star_shaped(mesh, vertex_average(mesh))) {
      // A convex solid's rounding certified in O(T) exact orientations.
      result.mesh = std::move(mesh);
      result.merged_vertices = 0;
      result.retriangulated_faces = attempt == 0 ? 0 : solid.faces.size();
      result.attempt = snapping ? -1 : static_cast<int>(attempt);
      result.valid = true;
      return result;
    } else {
      report = certify_rounded(mesh, options);
      if (mesh.triangles.empty()) {
        // Every vertex rounded onto a few points and the whole piece flattened
        // away: no defect is left to name, but nothing is left either.
        report.defects.push_back({DefectKind::zero_area_triangle, solid.faces.size(),
                                  "the whole piece (it is thinner than the rounding of its coordinates)"});
      }
    }
    if (step == 0) {
      first_report = report;
      // The first attempt's mesh is what a piece that cannot be certified
      // reports; one certified now is returned below without reading it.
      if (!report.valid()) result.mesh = mesh;
      result.merged_vertices = merged;
    }
    // Parts that rounded flat (two-sided sheets) vanish; if that is all of the
    // piece, the piece vanishes (below). The report is then the sheetless mesh's.
    if (!report.valid() && !mesh.triangles.empty()) {
      Mesh sheetless = mesh;
      std::vector<VertexIndex> renumbered;
      std::vector<std::uint32_t> kept;
      if (const std::size_t gone = cancel_two_sided_sheets(sheetless, renumbered, untangle_edges,
                                                           untangle_edges ? &kept : nullptr);
          gone > 0) {
        if (sheetless.triangles.empty()) {
          // A repair that merged folds or snapped vertices can flatten a piece
          // that is not thin (it merged across a thick part): when the piece
          // cannot vanish whole (below), the later repairs are tried instead.
          if ((folding || snapping) && !within_its_rounding()) continue;
          flattened_whole = true;
          break;
        }
        sheets_cancelled = gone;
        mesh = std::move(sheetless);
        // The separation below names vertices by their new numbers.
        for (VertexIndex& v : mesh_vertex_of) {
          if (v != no_index) v = renumbered[v];
        }
        if (untangle_edges) {
          for (std::uint32_t& t : kept) t = face_of_triangle[t];
          face_of_triangle = std::move(kept);
        }
        report = certify_rounded(mesh, options);
      } else {
        sheets_cancelled = 0;
      }
    }
    // The faces this attempt folded (what is left once sheets vanished), for
    // the folding round: only a repair attempt (1 to 3) of the second round or
    // the folding round collects them.
    if (snapping && !report.valid() && !mesh.triangles.empty()) {
      const std::size_t before = snap_folds[attempt].size();
      add_folded_face_pairs(mesh, face_of_triangle, snap_folds[attempt]);
      if (snap_folds[attempt].size() == before) snap_stalled[attempt] = true;
    }
    if (untangle_edges && attempt > 0 && !snapping && !report.valid() && !mesh.triangles.empty()) {
      const std::size_t before = folds[attempt].size();
      add_folded_face_pairs(mesh, face_of_triangle, folds[attempt]);
      if (!folding) fold_pairs[1][attempt] = fold_pairs[2][attempt] = fold_pairs[3][attempt] = folds[attempt];
      if (folding && folds[attempt].size() == before) folds_stalled[attempt] = true;
    }
    if (report.valid()) {
      RoundedSolid written = copy_without_mesh(result);
      written.mesh = std::move(mesh);
      written.merged_vertices = merged;
      written.retriangulated_faces = attempt == 0 ? 0 : solid.faces.size();
      written.vanished_triangles = sheets_cancelled;
      written.folded_faces = folded_faces;
      written.inserted_vertices = inserted;
      written.snapped_vertices = snapped;
      // The volume the repairs moved is held to the bound of what rounding can
      // move, or the mesh is not taken (fuzz_slice corpus: cube-off-cap-routed-
      // through-vertex.bin, taken at the first round beyond the bound it reported).
      const bool within = !(sheets_cancelled > 0 || folding || snapping) ||
                          report_moved_volume(measured_moved_volume(piece, written.mesh), written);
      if (within) {
        const bool plain = merged == 0 && sheets_cancelled == 0 && inserted == 0 && !folding && !snapping;
        written.attempt = plain ? static_cast<int>(attempt) : -1;
        written.valid = true;
        return written;
      }
      // A fold merged over more than rounding can move: retrying with the
      // same pairs would only do it again.
      if (folding) folds_stalled[attempt] = true;
      if (snapping) snap_stalled[attempt] = true;
      continue;
    }
    // The piece may touch itself, exactly (see separate_touching): only then is
    // what is left a pinched vertex or an intersection, on a closed oriented mesh.
    const bool may_touch = !options.allow_self_intersections &&
                           std::all_of(report.defects.begin(), report.defects.end(), [&](const Defect& d) {
                             return d.kind == DefectKind::non_manifold_vertex ||
                                    d.kind == DefectKind::self_intersection ||
                                    (untangle_edges && d.kind == DefectKind::non_manifold_edge);
                           });
    if (!may_touch) continue;
    // The second round repeats the first but for the edges: nothing else to try.
    // (The folding round meets new meshes: a fold merged can leave a pinch.)
    if (untangle_edges && !folding && !snapping && report.find(DefectKind::non_manifold_edge) == nullptr) continue;
    std::vector<std::uint32_t> partner;
    if (report.find(DefectKind::non_manifold_edge) != nullptr) {
      std::optional<std::vector<std::uint32_t>> paired = pair_around_non_manifold_edges(mesh);
      if (!paired) continue;
      partner = std::move(*paired);
    }
    if (!touching_caps) touching_caps = corners_touching_caps(set, solid);
    touching.clear();
    for (const VertexIndex v : *touching_caps) {
      if (mesh_vertex_of[v] != no_index) touching.push_back(mesh_vertex_of[v]);
    }
    // The smallest move that certifies: a few bits below the neighbours' distance
    // first, then further. Returns the mesh separated with the fans `held` keep
    // still when it certifies within the volume bound; else leaves in `crossed`
    // the last separated mesh that failed validation (empty when none did).
    const auto separate = [&](std::span<const std::uint8_t> held, Mesh& crossed) -> std::optional<RoundedSolid> {
      crossed = Mesh{};
      for (const int bits : {40, 30, 20}) {
        Mesh separated = mesh;
        const Separation separation = separate_touching(separated, touching, std::ldexp(1.0, -bits), partner, held);
        if (separation.moved == 0) break;
        if (!validate_knowing(separated, options).valid()) {
          crossed = std::move(separated);
          continue;
        }
        RoundedSolid written = copy_without_mesh(result);
        written.mesh = std::move(separated);
        written.merged_vertices = merged;
        written.retriangulated_faces = attempt == 0 ? 0 : solid.faces.size();
        written.separated_vertices = separation.moved;
        written.vanished_triangles = sheets_cancelled;
        written.folded_faces = folded_faces;
        written.inserted_vertices = inserted;
        written.snapped_vertices = snapped;
        MovedVolume moved{separation.volume_change, separation.volume_bound};
        if (sheets_cancelled > 0 || folding || snapping) {
          // The sheets' or the folds' volume as well: measured against the exact piece.
          moved = measured_moved_volume(piece, written.mesh);
          moved.bound += separation.volume_bound;
        }
        // Held to the bound, as above (a fold's wedge is thinner than the
        // rounding, so its volume is within it).
        if (!report_moved_volume(moved, written)) break;
        written.valid = true;
        return written;
      }
      return std::nullopt;
    };
    Mesh crossed;
    if (std::optional<RoundedSolid> written = separate({}, crossed)) return std::move(*written);
    // Every fan moving along its mean edge can push a fan into another's wedge:
    // a nearly flat fan (b9_mesh's union: the top of a solid whose conical
    // cavity touches it from below at a vertex) has a mean edge of no clear
    // direction, here into the solid, where the cavity's copy moves too. The
    // fans of the vertices of the triangles that crossed then keep their first
    // fan still and move only the others' copies (as step 9 of the repair
    // separates touching parts, repair_touching.hpp). Kept aside, and taken only
    // when every round here and below has failed, so that no piece certified
    // before it existed is written differently (not in the rounds of a refined
    // solid, whose failure lets the wedge split try its next plane).
    if (collapse_wedges && !held_fallback && !crossed.triangles.empty()) {
      std::vector<Triangle> shaped;
      std::vector<std::uint32_t> shaped_index;
      shaped_triangles(crossed, shaped, shaped_index);
      const std::vector<TrianglePair> pairs = self_intersecting_pairs(crossed.positions, shaped);
      if (!pairs.empty()) {
        std::vector<std::uint8_t> held(crossed.positions.size(), 0);
        for (const TrianglePair& pair : pairs) {
          for (const std::size_t t : {pair.first, pair.second}) {
            for (const VertexIndex v : shaped[t]) held[v] = 1;
          }
        }
        held_fallback = separate(held, crossed);
      }
    }
  }
  // A piece that cannot be certified and whose whole volume is within what the
  // rounding of its vertices can move (rounding_sweep_bound) is thinner than the
  // rounding of its coordinates: it vanishes whole, its volume moving to its
  // neighbours across the cut. A piece that rounded onto two-sided sheets or onto
  // a few points has no volume left, so it always qualifies, by the bound's
  // argument; the test is made all the same, exactly.
  const mpq_class six = piece.six();
  const mpq_class sweep = piece.sweep(false);
  if (six <= 6 * sweep) {
    const bool was_empty = result.mesh.triangles.empty();
    result.mesh = Mesh{};
    result.collapsed = true;
    result.moved_volume = mpq_class(six / 6).get_d();
    result.moved_volume_bound = sweep.get_d();
    // The first attempt's defect, or the collapse itself when no triangle was left to
    // have one.
    result.defect = flattened_whole ? "the whole piece (it rounds onto two-sided sheets: it is thinner than the "
                                      "rounding of its coordinates)"
                    : was_empty ? first_report.summary()
                                : "the whole piece (its volume is within what the rounding of its coordinates "
                                  "moves): " + first_report.summary();
    return result;
  }
  // The wedges beyond rounding's reach (see split_faces_along): the faces folded
  // against a cap, per cap plane, split along a plane offset from it into the
  // piece by 2, 1 and 4 times the rounding move, each refined solid rounded
  // again by every round above. Not for a union of parts (its caller keeps the
  // parts when it fails) nor for a solid allowed to cross itself.
  if (collapse_wedges && options.parts.empty() && !options.allow_self_intersections) {
    std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
    for (const auto& phase : fold_pairs) {
      for (const auto& found : phase) pairs.insert(pairs.end(), found.begin(), found.end());
    }
    for (const auto& found : snap_folds) pairs.insert(pairs.end(), found.begin(), found.end());
    // (cap face, face folded against it), the cap on a cut plane and the other
    // face on another plane; in order of the cap plane, then the face.
    std::vector<std::pair<std::uint32_t, std::uint32_t>> against;
    for (const auto& [f, g] : pairs) {
      for (const auto& [c, o] : {std::pair{f, g}, std::pair{g, f}}) {
        if (c < solid.faces.size() && o < solid.faces.size() && solid.faces[c].plane.is_cut() &&
            solid.faces[c].plane != solid.faces[o].plane) {
          against.emplace_back(c, o);
        }
      }
    }
    const auto plane_bits = [&](std::uint32_t f) { return solid.faces[f].plane.bits; };
    std::sort(against.begin(), against.end(), [&](const auto& x, const auto& y) {
      return plane_bits(x.first) != plane_bits(y.first) ? plane_bits(x.first) < plane_bits(y.first) : x < y;
    });
    if (!reach) {
      for (VertexIndex v = 0; v < solid.defs.size(); ++v) {
        output_positions.push_back(output_position(set, solid.defs[v], solid.approx[v]));
      }
      reach.emplace(set, solid, output_positions);
    }
    // Three passes: the wedge split as it was, then, when every plane has failed,
    // the strips thin by their corners merged into the caps
    // (round_merging_thin_strips), first on the piece itself, then on each
    // refined solid of the first pass instead of the rounds above; last, the
    // split widened to every face that meets the cap's plane as well
    // (`to_the_cap`, see widen_to_near_faces), rounded by the rounds above.
    for (const int pass : {0, 1, 2}) {
      const bool strips = pass == 1;
      const bool to_the_cap = pass == 2;
      if (strips) {
        if (std::optional<RoundedSolid> written =
                round_merging_thin_strips(set, solid, options, output_positions, *reach, snap_levels, piece)) {
          return std::move(*written);
        }
      }
      for (std::size_t i = 0; i < against.size();) {
        std::size_t j = i;
        std::vector<std::uint32_t> faces;
        while (j < against.size() && plane_bits(against[j].first) == plane_bits(against[i].first)) {
          faces.push_back(against[j++].second);
        }
        std::sort(faces.begin(), faces.end());
        faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
        const SolidFace& cap = solid.faces[against[i].first];
        i = j;
        const Plane& cut = set.cuts[cap.plane.index()];
        const double largest = std::max({std::fabs(cut.normal.x), std::fabs(cut.normal.y), std::fabs(cut.normal.z)});
        // When every plane has failed on the faces found folded (corpus cases 364
        // and 988: the cap passes a fraction of the rounding move over the tip of
        // a wedge between two earlier caps, or along a fan of an earlier cap
        // whose corners lie ulps from it, and faces the certification never
        // reached fold once the first ones merged), the split takes every face
        // with a corner strictly inside the piece within reach of the cap's plane
        // (exactly), so that all the strips by the cap are thin by their
        // corners, and the refined solid is rounded with its folds merged by
        // groups (FoldMerge::groups), then by groups with faces facing one way
        // too (groups_one_way). Adds the faces to `split` (kept sorted).
        // The last pass (`to_the_cap`) also takes every convex face with a corner
        // on the cap's plane: along the tip of a wedge between the cap and an
        // earlier cap nearly parallel to it (smoke corpus seed 7 case 28's other
        // piece: the earlier cap's triangles cross the new plane at 1e-9 rad, their
        // far corners 1e5 rounding moves off it), every face crossing the cap is
        // thin near its crossing line and may fold there once the first folds
        // merge, though none has a corner strictly inside within reach; split all
        // along the offset plane, the whole band by the cap is strips thin by
        // their corners, which the groups merge into the cap.
        FoldMerge refined_merge = FoldMerge::pairs;
        const auto widen_to_near_faces = [&](const SolidFace& c, std::vector<std::uint32_t>& split) {
          const PlaneReach near = reach->near(c.plane);
          const Sign inside = c.reversed ? Sign::positive : Sign::negative;
          const std::size_t before = split.size();
          for (std::uint32_t f = 0; f < solid.faces.size(); ++f) {
            const SolidFace& face = solid.faces[f];
            if (face.plane == c.plane || !face.convex || face.loop_count != 1) continue;
            if (std::binary_search(split.begin(), split.begin() + static_cast<std::ptrdiff_t>(before), f)) continue;
            for (const CornerEdge& edge : loop_edges(solid.corners, solid.loops[face.first_loop])) {
              const PlaneReach::Where where = near.locate(reach->point(edge.from));
              if ((where.side == inside || (to_the_cap && where.side == Sign::zero)) && where.within) {
                split.push_back(f);
                break;
              }
            }
          }
          std::sort(split.begin(), split.end());
        };
        // The piece refined along `split_plane` and rounded by every round above;
        // `within`: only if every crossing vertex lies strictly inside the piece and
        // at most that far from the cap's plane (an L1 distance; PlaneReach). A refinement
        // that cannot be made or rounded (a definition found degenerate, a face that
        // cannot be triangulated) leaves the refusal as it was.
        const auto refine = [&](const Plane& split_plane, const mpq_class* within,
                                bool* rounded = nullptr) -> std::optional<RoundedSolid> {
          std::vector<Plane> cuts(set.cuts.begin(), set.cuts.end());
          cuts.push_back(split_plane);
          const PlaneSet refined_set{set.points, set.inputs, set.input_approx, cuts};
          Solid refined;
          RoundedSolid written;
          try {
            const PlaneRef split_ref = PlaneRef::cut(static_cast<std::uint32_t>(cuts.size() - 1));
            if (!split_faces_along(refined_set, solid, split_ref, faces, refined)) {
              return std::nullopt;
            }
            if (within != nullptr) {
              const PlaneReach near(cut, *within);
              const Sign inside = cap.reversed ? Sign::positive : Sign::negative;
              for (VertexIndex v = static_cast<VertexIndex>(solid.defs.size()); v < refined.defs.size(); ++v) {
                const PlaneReach::Where where = near.locate(exact_coordinates(refined_set, refined.defs[v]));
                if (where.side != inside || !where.within) return std::nullopt;
              }
            }
            if (!check_solid(refined_set, refined).empty()) return std::nullopt;
            SolidMeshOptions refined_options = options;
            refined_options.face_attempts = {};
            if (rounded != nullptr) *rounded = true;
            if (strips) {
              std::vector<Vec3> positions;
              for (VertexIndex v = 0; v < refined.defs.size(); ++v) {
                positions.push_back(output_position(refined_set, refined.defs[v], refined.approx[v]));
              }
              RoundingReach refined_reach(refined_set, refined, positions);
              PieceVolumes refined_piece(refined_set, refined);
              std::optional<RoundedSolid> merged = round_merging_thin_strips(
                  refined_set, refined, refined_options, positions, refined_reach, snap_levels, refined_piece);
              if (!merged) return std::nullopt;
              written = std::move(*merged);
            } else {
              written = round_solid_rounds(refined_set, refined, refined_options, false, refined_merge);
            }
          } catch (const UnsupportedGeometryError&) {
            return std::nullopt;
          } catch (const std::domain_error&) {
            return std::nullopt;
          }
          if (!written.valid) return std::nullopt;
          // Held to the piece's own bound, against its exact volume (the refined
          // solid's, the same point set).
          if (!report_moved_volume(measured_moved_volume(piece, written.mesh), written)) return std::nullopt;
          written.attempt = -1;
          written.wedge_faces_split = refined.faces.size() - solid.faces.size();
          return written;
        };
        for (const FoldMerge merge : {FoldMerge::pairs, FoldMerge::groups, FoldMerge::groups_one_way}) {
          // (The strips' pass merges its own way: the faces widened once are enough.)
          if (strips && merge == FoldMerge::groups_one_way) break;
          // (The last pass widens at once: its pairs were the first pass's.)
          if (to_the_cap && merge == FoldMerge::pairs) continue;
          if (merge == FoldMerge::groups) widen_to_near_faces(cap, faces);
          refined_merge = merge;
          std::array<bool, 5> unrepresentable{};
          for (const int times : {2, 1, 4}) {
            // The piece lies behind the cap's outward normal: n.x + d < 0 when the cap
            // faces along +n, so the new plane n.x + d' = 0 with d' = d + h lies in
            // it; the doubles d' and h are whatever they round to, the plane exact.
            // The offset is held to the reach exactly (|d' - d| <= times rho max |n_i|),
            // stepping d' toward d while the rounding of d + h put it beyond: the
            // strips' corners on the new plane must lie within the thin rounds' reach.
            const mpq_class reach_offset = times * reach->rho * largest;
            const double h = reach_offset.get_d();
            double offset = cap.reversed ? cut.offset - h : cut.offset + h;
            const CoordinateReach offset_reach(reach_offset);
            while (offset != cut.offset && !offset_reach.within(offset, cut.offset)) {
              offset = std::nextafter(offset, cut.offset);
            }
            if (!(offset != cut.offset)) {
              unrepresentable[times] = true;
              continue;
            }
            if (std::optional<RoundedSolid> written = refine(Plane{cut.normal, offset}, nullptr)) {
              return std::move(*written);
            }
          }
          // No double offset within reach (the cap's offset d is large beside the
          // rounding of the corners: ulp(d) > times rho max |n_i|, corpus case 908):
          // the same plane scaled by lambda = 9/8 to 15/8, its coefficients rounded
          // to doubles and the offset stepped by 1 to 4 ulps into the piece, is tilted
          // from the cap's by the rounding of lambda n and moved by that of lambda d,
          // at a finer step than ulp(d). The first such plane whose crossing vertices
          // all lie strictly inside the piece and within the reach of the cap's plane
          // (decided exactly: the strips are thin by their corners, as above) is
          // rounded, once per reach that had no parallel plane, so a piece this
          // cannot repair costs at most two more rounds.
          for (const int times : {2, 1}) {
            if (!unrepresentable[times]) continue;
            const mpq_class within = times * reach->rho;
            bool rounded = false;
            for (int eighths = 9; eighths < 16 && !rounded; ++eighths) {
              const double lambda = eighths / 8.0;
              const Vec3 normal{lambda * cut.normal.x, lambda * cut.normal.y, lambda * cut.normal.z};
              double offset = lambda * cut.offset;
              for (int step = 0; step < 4 && !rounded; ++step) {
                offset = std::nextafter(offset, cap.reversed ? -HUGE_VAL : HUGE_VAL);
                if (std::optional<RoundedSolid> written = refine(Plane{normal, offset}, &within, &rounded)) {
                  return std::move(*written);
                }
              }
            }
          }
        }
      }
    }
  }
  if (held_fallback) return std::move(*held_fallback);
  result.defect = first_report.summary();
  result.collapsed = false;
  return result;
}

}  // namespace

RoundedSolid round_solid(const PlaneSet& set, const Solid& solid, const SolidMeshOptions& options) {
  return round_solid_rounds(set, solid, options, true);
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
