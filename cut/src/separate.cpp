#include "shatter/cut/separate.hpp"
#include "shatter/cut/separate_exact.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <numeric>
#include <stdexcept>
#include <string>

#include "shatter/kernel/error.hpp"
#include "shatter/kernel/index_map.hpp"
#include "shatter/kernel/mass.hpp"
#include "shatter/kernel/union_find.hpp"

namespace shatter {
namespace {

// The CGAL kernel whose exact predicates decide containment for a point type.
template <class Point>
struct PredicateKernel;
template <>
struct PredicateKernel<Vec3> {
  using K = CGAL::Epick;
  static K::Point_3 point(const Vec3& p) { return {p.x, p.y, p.z}; }
};
template <>
struct PredicateKernel<ExactPoint> {
  using K = ExactKernel;
  static const K::Point_3& point(const ExactPoint& p) { return p; }
};

Sign volume_sign(const Mesh& shell) { return signed_volume_sign(shell); }

// Six times the volume, sum of det(a, b, c), in interval arithmetic on the points'
// approximations: no lazy nodes are built.
CGAL::Interval_nt<false> approximate_six_volume(const ExactMesh& shell) {
  CGAL::Protect_FPU_rounding<true> rounding_upward;  // Interval_nt<false> needs it; restored on return
  CGAL::Interval_nt<false> six_volume = 0;
  for (const Triangle& t : shell.triangles) {
    const auto& a = shell.positions[t[0]].approx();
    const auto& b = shell.positions[t[1]].approx();
    const auto& c = shell.positions[t[2]].approx();
    six_volume += CGAL::determinant(a.x(), a.y(), a.z(), b.x(), b.y(), b.z(), c.x(), c.y(), c.z());
  }
  return six_volume;
}

Sign volume_sign(const ExactMesh& shell) {
  // Only when the interval holds zero is the sum taken again in exact rationals.
  const CGAL::Interval_nt<false> six_volume = approximate_six_volume(shell);
  if (six_volume.inf() > 0) return Sign::positive;
  if (six_volume.sup() < 0) return Sign::negative;
  ExactKernel::FT::ET exact_six_volume = 0;
  for (const Triangle& t : shell.triangles) {
    const auto& a = CGAL::exact(shell.positions[t[0]]);
    const auto& b = CGAL::exact(shell.positions[t[1]]);
    const auto& c = CGAL::exact(shell.positions[t[2]]);
    exact_six_volume += CGAL::determinant(a.x(), a.y(), a.z(), b.x(), b.y(), b.z(), c.x(), c.y(), c.z());
  }
  const CGAL::Sign s = CGAL::sign(exact_six_volume);
  return s == CGAL::NEGATIVE ? Sign::negative : s == CGAL::POSITIVE ? Sign::positive : Sign::zero;
}

enum class Containment { inside, outside, undecided };

// Whether point q lies inside the closed shell, by the parity of the crossings of a
// segment from q to a point far outside the shell. Every test is an exact
// orientation; a segment that touches an edge or a vertex, or a q on the shell,
// is never resolved by a tolerance: the caller tries another direction or point.
template <class Point>
Containment locate(const Point& q_in, const BasicMesh<Point>& shell, const CGAL::Bbox_3& shell_box,
                   int direction_index) {
  using PK = PredicateKernel<Point>;
  using K = typename PK::K;
  const typename K::Point_3 q = PK::point(q_in);
  const CGAL::Bbox_3 box = shell_box + q.bbox();
  // Deterministic, irregular directions: degenerate ones for one shell are rare,
  // and each degeneracy is detected exactly.
  const double golden = 0.6180339887498949;
  const double phi = 2 * 3.141592653589793 * std::fmod(golden * (direction_index + 1), 1.0);
  const double z = 1 - 2 * std::fmod(0.7548776662466927 * (direction_index + 1), 1.0);
  const double r = std::sqrt(std::max(0.0, 1 - z * z));
  const double reach = 4 * (box.xmax() - box.xmin() + box.ymax() - box.ymin() + box.zmax() - box.zmin()) + 1;
  const typename K::Point_3 far(box.xmin() + (box.xmax() - box.xmin()) / 2 + reach * r * std::cos(phi),
                                box.ymin() + (box.ymax() - box.ymin()) / 2 + reach * r * std::sin(phi),
                                box.zmin() + (box.zmax() - box.zmin()) / 2 + reach * z);
  int crossings = 0;
  for (const Triangle& t : shell.triangles) {
    const auto& a = PK::point(shell.positions[t[0]]);
    const auto& b = PK::point(shell.positions[t[1]]);
    const auto& c = PK::point(shell.positions[t[2]]);
    const CGAL::Orientation side_q = CGAL::orientation(a, b, c, q);
    const CGAL::Orientation side_far = CGAL::orientation(a, b, c, far);
    if (side_q == side_far && side_q != CGAL::COPLANAR) continue;  // both on one side: no crossing
    const CGAL::Orientation ab = CGAL::orientation(q, far, a, b);
    const CGAL::Orientation bc = CGAL::orientation(q, far, b, c);
    const CGAL::Orientation ca = CGAL::orientation(q, far, c, a);
    const bool misses = (ab == CGAL::POSITIVE || bc == CGAL::POSITIVE || ca == CGAL::POSITIVE) &&
                        (ab == CGAL::NEGATIVE || bc == CGAL::NEGATIVE || ca == CGAL::NEGATIVE);
    if (misses) continue;  // the segment's line passes beside the triangle
    if (side_q == CGAL::COPLANAR || side_far == CGAL::COPLANAR || ab == CGAL::COPLANAR ||
        bc == CGAL::COPLANAR || ca == CGAL::COPLANAR) {
      return Containment::undecided;  // touches an edge or vertex, or q is on the plane of a face it may touch
    }
    ++crossings;
  }
  return crossings % 2 == 1 ? Containment::inside : Containment::outside;
}

// Whether shell `inner` lies inside closed shell `outer`; the shells do not cross,
// so any vertex of `inner` not on `outer` decides.
template <class Point>
Containment shell_inside(const BasicMesh<Point>& inner, const BasicMesh<Point>& outer) {
  constexpr int directions_per_point = 8;
  constexpr std::size_t points_tried = 16;
  CGAL::Bbox_3 outer_box;
  for (const Point& p : outer.positions) outer_box += PredicateKernel<Point>::point(p).bbox();
  for (std::size_t v = 0; v < std::min(points_tried, inner.positions.size()); ++v) {
    for (int d = 0; d < directions_per_point; ++d) {
      const Containment c = locate(inner.positions[v], outer, outer_box, d);
      if (c != Containment::undecided) return c;
    }
  }
  return Containment::undecided;  // every probe touches `outer`: only a degenerate embedding does that
}

template <class Point>
void append_shell(BasicMesh<Point>& solid, const BasicMesh<Point>& shell) {
  const auto offset = static_cast<VertexIndex>(solid.positions.size());
  solid.positions.insert(solid.positions.end(), shell.positions.begin(), shell.positions.end());
  for (Triangle t : shell.triangles) solid.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  solid.surfaces.insert(solid.surfaces.end(), shell.surfaces.begin(), shell.surfaces.end());
  auto append = [](auto& to, const auto& from) { to.insert(to.end(), from.begin(), from.end()); };
  append(solid.corners.normals, shell.corners.normals);
  append(solid.corners.uvs, shell.corners.uvs);
  append(solid.corners.tangents, shell.corners.tangents);
}

template <class Point>
std::vector<BasicMesh<Point>> split_into_shells(const BasicMesh<Point>& surface, const HalfEdgeTwins& twins) {
  const auto& tris = surface.triangles;
  const std::size_t corner_count = 3 * tris.size();
  // Corner c of triangle t is also the half-edge leaving it. Each directed edge
  // may appear once: twice is a non-manifold edge.
  if (twins.repeated) {
    throw UnsupportedGeometryError("the cut makes a non-manifold edge (" + std::to_string((*twins.repeated)[0]) + ", " +
                                   std::to_string((*twins.repeated)[1]) +
                                   "): a face of the mesh meets the plane along a cap chord");
  }
  if (twins.first_unmatched != HalfEdgeTwins::none) {
    const std::uint32_t c = twins.first_unmatched;
    throw std::logic_error("separate_solids: open surface at edge (" + std::to_string(tris[c / 3][c % 3]) + ", " +
                           std::to_string(tris[c / 3][(c + 1) % 3]) + ")");
  }
  // Corners around one vertex that are joined across an edge belong to one fan: a
  // fan becomes one output vertex. Triangles joined across an edge share a shell.
  UnionFind fans(corner_count);
  UnionFind shells(tris.size());
  for (std::uint32_t c = 0; c < corner_count; ++c) {
    const std::uint32_t twin = twins.twin[c];
    // Corner c sits at u and leaves for w; the twin corner sits at w; the corner after it in its triangle sits at u.
    const std::uint32_t twin_at_u = (twin / 3) * 3 + (twin % 3 + 1) % 3;
    fans.unite(c, twin_at_u);
    shells.unite(c / 3, twin / 3);
  }
  std::vector<BasicMesh<Point>> result;
  std::vector<std::uint32_t> shell_of_root(tris.size(), IndexMap::absent);
  std::vector<VertexIndex> vertex_of_fan(corner_count, IndexMap::absent);
  const bool normals = surface.corners.has_normals(), uvs = surface.corners.has_uvs(),
             tangents = surface.corners.has_tangents();
  for (std::uint32_t t = 0; t < tris.size(); ++t) {
    const std::uint32_t root = shells.find(t);
    if (shell_of_root[root] == IndexMap::absent) {
      shell_of_root[root] = static_cast<std::uint32_t>(result.size());
      result.emplace_back();
    }
    BasicMesh<Point>& shell = result[shell_of_root[root]];
    Triangle renumbered;
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t corner = 3 * t + k;
      const std::uint32_t fan = fans.find(corner);
      if (vertex_of_fan[fan] == IndexMap::absent) {
        vertex_of_fan[fan] = static_cast<VertexIndex>(shell.positions.size());
        shell.positions.push_back(surface.positions[tris[t][k]]);
      }
      renumbered[k] = vertex_of_fan[fan];
      if (normals) shell.corners.normals.push_back(surface.corners.normals[corner]);
      if (uvs) shell.corners.uvs.push_back(surface.corners.uvs[corner]);
      if (tangents) shell.corners.tangents.push_back(surface.corners.tangents[corner]);
    }
    shell.triangles.push_back(renumbered);
    shell.surfaces.push_back(surface.surfaces[t]);
  }
  return result;
}

template <class Point>
std::vector<BasicMesh<Point>> separate(const BasicMesh<Point>& surface, const HalfEdgeTwins& twins) {
  std::vector<BasicMesh<Point>> shells = split_into_shells(surface, twins);
  if (shells.size() <= 1) return shells;  // a lone closed shell of a valid cut faces outward
  std::vector<Sign> orientation;
  for (const auto& shell : shells) orientation.push_back(volume_sign(shell));

  std::vector<std::size_t> solid_of_shell(shells.size(), SIZE_MAX);
  std::vector<std::size_t> outer;
  for (std::size_t i = 0; i < shells.size(); ++i) {
    if (orientation[i] == Sign::positive) outer.push_back(i);
  }
  std::vector<BasicMesh<Point>> solids;
  std::vector<std::size_t> solid_index_of_outer(shells.size(), SIZE_MAX);
  for (std::size_t i : outer) {
    solid_index_of_outer[i] = solids.size();
    solids.push_back(std::move(shells[i]));
  }
  for (std::size_t i = 0; i < shells.size(); ++i) {
    if (orientation[i] == Sign::positive) continue;
    // A cavity goes with the innermost outward shell containing it: the one that
    // lies inside every other container. A shell that is flat, or that no outward
    // shell contains, can only come from a self-intersecting input or a rounded
    // embedding; it stays a solid of its own, so the output is
    // still closed and oriented, and the caller's validation reports it.
    std::vector<std::size_t> containers;
    if (orientation[i] == Sign::negative) {
      for (std::size_t o : outer) {
        if (shell_inside(shells[i], solids[solid_index_of_outer[o]]) == Containment::inside) {
          containers.push_back(o);
        }
      }
    }
    if (containers.empty()) {
      solids.push_back(std::move(shells[i]));
      continue;
    }
    std::size_t innermost = containers.front();
    for (std::size_t candidate : containers) {
      if (candidate != innermost && shell_inside(solids[solid_index_of_outer[candidate]],
                                                 solids[solid_index_of_outer[innermost]]) == Containment::inside) {
        innermost = candidate;
      }
    }
    solid_of_shell[i] = solid_index_of_outer[innermost];
  }
  for (std::size_t i = 0; i < shells.size(); ++i) {
    if (solid_of_shell[i] != SIZE_MAX) append_shell(solids[solid_of_shell[i]], shells[i]);
  }
  return solids;
}

}  // namespace

std::vector<Mesh> separate_solids(const Mesh& surface) {
  return separate(surface, half_edge_twins(surface.triangles, surface.positions.size()));
}
std::vector<Mesh> separate_solids(const Mesh& surface, const HalfEdgeTwins& twins) { return separate(surface, twins); }
std::vector<ExactMesh> separate_solids(const ExactMesh& surface) {
  return separate(surface, half_edge_twins(surface.triangles, surface.positions.size()));
}

}  // namespace shatter
