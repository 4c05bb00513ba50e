// Voronoi fracture on the plane kernel (voronoi.hpp says why the cells are exact).
//
// The cells are cut out of the solid without cutting the whole solid once per
// cell: the sites are grouped by a k-d tree (recursive median split along the
// longest axis of the group's sites). Each group has a box that holds every
// point of its cells inside the solid's box, with room to spare: the box of its
// cells' Voronoi vertices (the circumcentres of the Delaunay tetrahedra around
// each site, enclosed in intervals, so rounding only widens the box), grown by a
// margin and clipped to the solid's box, itself grown by the margin. A group's
// container is its parent's container cut by the box's planes (intermediate
// pieces, never kept); a small group cuts its container by each of its cells'
// bisectors in turn. Correctness does not depend on the boxes beyond that they
// hold the cells' parts strictly inside: a fragment is the solid cut by its
// cell's planes and by boxes that contain its part, so it is the solid's part
// of the cell, and no point of it lies on a box plane (then no vertex, face or
// edge of it refers to one: every such reference would name a plane it lies
// on). The assembly checks that last property and throws std::logic_error if a
// box plane is left, so a wrong box could not pass unnoticed.
//
// Cells inside the solid are not cut at all. A cell whose box meets no input
// triangle's box lies wholly inside or wholly outside the solid (place_cells
// decides which, exactly); an inside cell's fragment is the whole cell, a
// convex polyhedron the Delaunay triangulation already describes (its faces
// the dual polygons of the site's Delaunay edges), so it is assembled from the
// site's star (assemble_inner_cell) with the same planes, definitions and
// orientation a cut gives it; an outside cell has no fragment. Only the cells
// that may meet the surface are cut, and a group's box holds only those (a
// group with none needs no container).
//
// Shared vertices, shared bits: a point where the cells of sites a, b, c (and
// d) meet is defined, in each of their fragments, by whichever two (three) of
// their bisectors that cell's cuts met there. Rounding is a function of the
// definition, so each definition is put in one canonical form first: its
// bisectors replaced by those of the smallest site with each of the others
// (B_pq + B_qr = B_pr exactly, so it is the same point), input plane first.
// Neighbouring fragments then write their shared corners bit for bit alike.
//
// The hierarchy reuses the k-d groups: bottom up, each group below the root
// glues the face-connected sets of its parts (voronoi_hierarchy.hpp, and
// voronoi_glue.hpp for a union).

#include "shatter/meshtree/voronoi.hpp"

#include <CGAL/Delaunay_triangulation_3.h>
#include <CGAL/Delaunay_triangulation_cell_base_3.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Interval_nt.h>
#include <CGAL/Triangulation_cell_base_with_info_3.h>
#include <CGAL/Triangulation_vertex_base_with_info_3.h>
#include <CGAL/box_intersection_d.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/info.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <functional>
#include <cmath>
#include <cstdio>
#include <map>
#include <unordered_map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <span>
#include <string>
#include <utility>

#include "shatter/cut/cut_solid.hpp"
#include "shatter/cut/hull.hpp"
#include "shatter/cut/plane_input.hpp"
#include "shatter/kernel/error.hpp"
#include "shatter/kernel/inside.hpp"
#include "shatter/kernel/mass.hpp"
#include "shatter/kernel/predicates.hpp"
#include "shatter/kernel/validate.hpp"
#include "shatter/meshtree/packed_node.hpp"
#include "shatter/triangulate/solid_mesh.hpp"
#include "shatter/version.hpp"
#include "validate_tree_certificate.hpp"
#include "node_mass.hpp"
#include "tree_hulls.hpp"
#include "voronoi_hierarchy.hpp"

namespace shatter {

namespace {

constexpr std::int64_t grid_limit = std::int64_t{1} << 24;  // |k| <= 2^24
constexpr std::uint32_t sentinel_count = 8;
constexpr std::size_t leaf_group_size = 8;

struct Box {
  Vec3 lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
  bool empty() const { return !(lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z); }
  void add(const Vec3& p) {
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  }
  void add(const Box& b) {
    if (b.empty()) return;
    add(b.lo);
    add(b.hi);
  }
};

double& axis_of(Vec3& v, int axis) { return axis == 0 ? v.x : axis == 1 ? v.y : v.z; }
double axis_of(const Vec3& v, int axis) { return axis == 0 ? v.x : axis == 1 ? v.y : v.z; }

Box intersection(const Box& a, const Box& b) {
  Box r;
  r.lo = {std::max(a.lo.x, b.lo.x), std::max(a.lo.y, b.lo.y), std::max(a.lo.z, b.lo.z)};
  r.hi = {std::min(a.hi.x, b.hi.x), std::min(a.hi.y, b.hi.y), std::min(a.hi.z, b.hi.z)};
  return r;
}

// Grown by `margin` on every side and rounded outward, so the result holds the
// box strictly inside.
Box grown(const Box& box, double margin) {
  Box r;
  for (int a = 0; a < 3; ++a) {
    axis_of(r.lo, a) = std::nextafter(axis_of(box.lo, a) - margin, -INFINITY);
    axis_of(r.hi, a) = std::nextafter(axis_of(box.hi, a) + margin, INFINITY);
  }
  return r;
}

// The eight sentinel sites: corners of a cube around `box` whose half-size is
// twice the box's diagonal. Every point x of the box is then strictly nearer to
// any site s inside the box than to a sentinel (|x - s| <= diagonal < 2 sqrt(3)
// diagonal - diagonal / 2 <= |x - sentinel|), and every site inside the box is
// strictly inside the sentinels' hull, so its cell is bounded.
std::array<Vec3, sentinel_count> sentinel_sites(const Box& box) {
  const Vec3 centre = (box.lo + box.hi) * 0.5;
  const double half = 2 * norm(box.hi - box.lo);
  std::array<Vec3, sentinel_count> corners;
  for (std::uint32_t i = 0; i < sentinel_count; ++i) {
    corners[i] = {centre.x + ((i & 1) ? half : -half), centre.y + ((i & 2) ? half : -half),
                  centre.z + ((i & 4) ? half : -half)};
  }
  return corners;
}

std::int64_t grid_index(double coordinate, double step) {
  return static_cast<std::int64_t>(std::nearbyint(coordinate / step));
}

// --- the Delaunay triangulation --------------------------------------------------

using Epick = CGAL::Exact_predicates_inexact_constructions_kernel;
using VertexBase = CGAL::Triangulation_vertex_base_with_info_3<std::uint32_t, Epick>;
// A finite tetrahedron's info is its number in the order finite_cells lists them
// (deterministic: the insertion order is), which orders an inner cell's
// vertices (assemble_inner_cell).
using CellBase =
    CGAL::Triangulation_cell_base_with_info_3<std::uint32_t, Epick, CGAL::Delaunay_triangulation_cell_base_3<Epick>>;
using Tds = CGAL::Triangulation_data_structure_3<VertexBase, CellBase>;
using Delaunay = CGAL::Delaunay_triangulation_3<Epick, Tds>;
// Unprotected intervals, under one switch of the rounding mode for the whole
// loop over the tetrahedra (the protected kind switches it at every operation,
// which was two thirds of the triangulation's time; the bounds are the same bits).
using Interval = CGAL::Interval_nt<false>;

struct Triangulated {
  std::vector<std::array<std::uint32_t, 2>> pairs;  ///< Delaunay edges i < j with a real site, sorted
  std::vector<Box> cell_boxes;                      ///< per real site: its Voronoi vertices' box
  /// The triangulation itself and each point's vertex in it, kept to assemble
  /// the cells that lie inside the solid (assemble_inner_cell).
  std::unique_ptr<Delaunay> dt;
  std::vector<Delaunay::Vertex_handle> vertex_of;
  /// Per finite tetrahedron (by its info), the first numbered tetrahedron with
  /// the same circumcentre (co-spherical neighbours across facets, decided
  /// exactly, joined), and that one's four points in increasing order: one
  /// definition for each Voronoi vertex, whichever cell names it.
  std::vector<std::uint32_t> sphere_of;
  std::vector<std::array<std::uint32_t, 4>> points_of;
};

// Morton order of grid points, compared without forming the code (the axis with
// the highest differing bit decides; Chan 2002): a fixed, spatially coherent
// insertion order, so each insertion's walk is short and the result never
// depends on a random shuffle.
bool morton_less(const std::array<std::uint32_t, 3>& a, const std::array<std::uint32_t, 3>& b) {
  int axis = 0;
  std::uint32_t highest = 0;
  for (int k = 0; k < 3; ++k) {
    const std::uint32_t diff = a[k] ^ b[k];
    if (highest < diff && highest < (highest ^ diff)) {
      axis = k;
      highest = diff;
    }
  }
  return a[axis] < b[axis];
}

Triangulated triangulate(std::span<const Vec3> points, std::uint32_t real_count, double step) {
  std::vector<std::array<std::uint32_t, 3>> keys(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    for (int a = 0; a < 3; ++a) {
      keys[i][a] = static_cast<std::uint32_t>(grid_index(axis_of(points[i], a), step) + 2 * grid_limit);
    }
  }
  std::vector<std::uint32_t> order(points.size());
  for (std::uint32_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    return morton_less(keys[a], keys[b]) || (keys[a] == keys[b] && a < b);
  });
  Triangulated out;
  out.dt = std::make_unique<Delaunay>();
  Delaunay& dt = *out.dt;
  out.vertex_of.assign(points.size(), Delaunay::Vertex_handle());
  Delaunay::Vertex_handle hint;
  for (const std::uint32_t i : order) {
    const Vec3& p = points[i];
    hint = hint == Delaunay::Vertex_handle() ? dt.insert(Epick::Point_3(p.x, p.y, p.z))
                                              : dt.insert(Epick::Point_3(p.x, p.y, p.z), hint);
    hint->info() = i;
    out.vertex_of[i] = hint;
  }
  for (auto e = dt.finite_edges_begin(); e != dt.finite_edges_end(); ++e) {
    std::uint32_t a = e->first->vertex(e->second)->info(), b = e->first->vertex(e->third)->info();
    if (a > b) std::swap(a, b);
    if (a < real_count) out.pairs.push_back({a, b});
  }
  std::sort(out.pairs.begin(), out.pairs.end());
  out.cell_boxes.assign(real_count, Box{});
  if (dt.dimension() < 3) {
    // Only without sentinels; every cell is unbounded.
    for (Box& box : out.cell_boxes) box = {{-INFINITY, -INFINITY, -INFINITY}, {INFINITY, INFINITY, INFINITY}};
    return out;
  }
  std::uint32_t cell_number = 0;
  for (auto c = dt.finite_cells_begin(); c != dt.finite_cells_end(); ++c) {
    c->info() = cell_number++;
    std::array<std::uint32_t, 4> four;
    for (int k = 0; k < 4; ++k) four[k] = c->vertex(k)->info();
    std::sort(four.begin(), four.end());
    out.points_of.push_back(four);
  }
  // Co-spherical neighbours joined (union-find, the root the first numbered): the
  // tetrahedra with one circumcentre triangulate the hull of the sites on its
  // sphere, so they are connected across facets.
  std::vector<std::uint32_t>& sphere = out.sphere_of;
  sphere.resize(cell_number);
  for (std::uint32_t i = 0; i < cell_number; ++i) sphere[i] = i;
  const auto find = [&](std::uint32_t i) {
    while (sphere[i] != i) i = sphere[i] = sphere[sphere[i]];
    return i;
  };
  for (auto c = dt.finite_cells_begin(); c != dt.finite_cells_end(); ++c) {
    for (int k = 0; k < 4; ++k) {
      const Delaunay::Cell_handle n = c->neighbor(k);
      if (dt.is_infinite(n) || n->info() < c->info()) continue;
      const auto& fifth = n->vertex(n->index(c))->point();
      if (CGAL::side_of_oriented_sphere(c->vertex(0)->point(), c->vertex(1)->point(), c->vertex(2)->point(),
                                        c->vertex(3)->point(), fifth) == CGAL::ON_ORIENTED_BOUNDARY) {
        const std::uint32_t a = find(c->info()), b = find(n->info());
        sphere[std::max(a, b)] = std::min(a, b);
      }
    }
  }
  for (std::uint32_t i = 0; i < cell_number; ++i) sphere[i] = find(i);
  const CGAL::Protect_FPU_rounding<true> rounding_upward;  // Interval_nt<false> needs it; restored on return
  for (auto c = dt.finite_cells_begin(); c != dt.finite_cells_end(); ++c) {
    std::array<std::array<Interval, 3>, 4> v;
    for (int k = 0; k < 4; ++k) {
      const auto& p = c->vertex(k)->point();
      v[k] = {Interval(p.x()), Interval(p.y()), Interval(p.z())};
    }
    std::array<std::array<Interval, 3>, 3> e;
    for (int k = 0; k < 3; ++k) {
      for (int a = 0; a < 3; ++a) e[k][a] = v[k + 1][a] - v[0][a];
    }
    const auto cross = [](const std::array<Interval, 3>& x, const std::array<Interval, 3>& y) {
      return std::array<Interval, 3>{x[1] * y[2] - x[2] * y[1], x[2] * y[0] - x[0] * y[2], x[0] * y[1] - x[1] * y[0]};
    };
    const auto square = [](const std::array<Interval, 3>& x) { return x[0] * x[0] + x[1] * x[1] + x[2] * x[2]; };
    const std::array<Interval, 3> cd = cross(e[1], e[2]), db = cross(e[2], e[0]), bc = cross(e[0], e[1]);
    const Interval det = e[0][0] * cd[0] + e[0][1] * cd[1] + e[0][2] * cd[2];
    const Interval sb = square(e[0]), sc = square(e[1]), sd = square(e[2]);
    Box centre;
    for (int a = 0; a < 3; ++a) {
      // Circumcentre = v0 + (|b|^2 c x d + |c|^2 d x b + |d|^2 b x c) / (2 det).
      const Interval value = v[0][a] + (sb * cd[a] + sc * db[a] + sd * bc[a]) / (Interval(2) * det);
      axis_of(centre.lo, a) = value.inf();
      axis_of(centre.hi, a) = value.sup();
    }
    for (int k = 0; k < 4; ++k) {
      const std::uint32_t site = c->vertex(k)->info();
      if (site < real_count) out.cell_boxes[site].add(centre);
    }
  }
  return out;
}

// --- cells inside the solid -------------------------------------------------------

// Where a site's closed cell lies: meeting the solid's surface (or not known not
// to), strictly inside the solid, or strictly outside it.
enum class CellPlace : std::uint8_t { surface, inside, outside };

// Decides, exactly, which cells lie strictly inside or outside the solid. A cell
// is the convex hull of its Voronoi vertices, so its box (cell_boxes, which
// encloses their intervals) holds it, and it is where each of its bisectors is
// on its site's side (<= 0 for B_pq seen from p, the sentinels' included). An
// input triangle misses the closed cell when its closed box misses the cell's
// box, or when its three corners lie strictly beyond one of the cell's
// bisectors (exact side_of_plane on the input doubles: the triangle is their
// convex hull). When every triangle misses it, the surface misses the closed
// cell, which is connected and so lies wholly inside the solid or wholly
// outside it. Two such cells that
// are Delaunay neighbours share a non-empty face, so their union is connected and
// misses the surface too: one point-in-solid query (of a site, which lies in its
// own cell) per connected set of them decides the lot. Every other cell is
// `surface` (cut by the plane kernel as before). Deterministic (the answer is a
// set, whatever order the box search reports pairs in).
std::vector<CellPlace> place_cells(const Mesh& mesh, std::span<const Vec3> sites, std::span<const Box> cell_boxes,
                                   std::span<const std::array<std::uint32_t, 2>> pairs, std::span<const Plane> planes,
                                   std::span<const std::array<std::uint32_t, 2>> plane_pairs,
                                   std::span<const std::vector<std::uint32_t>> bisectors_of) {
  using IndexBox = CGAL::Box_intersection_d::Box_with_handle_d<double, 3, std::size_t, CGAL::Box_intersection_d::ID_EXPLICIT>;
  const auto site_count = static_cast<std::uint32_t>(sites.size());
  std::vector<CellPlace> place(site_count, CellPlace::surface);
  std::vector<IndexBox> cells, triangles;
  for (std::uint32_t s = 0; s < site_count; ++s) {
    const Box& b = cell_boxes[s];
    if (b.empty() || !std::isfinite(b.lo.x) || !std::isfinite(b.lo.y) || !std::isfinite(b.lo.z) ||
        !std::isfinite(b.hi.x) || !std::isfinite(b.hi.y) || !std::isfinite(b.hi.z)) {
      continue;
    }
    cells.emplace_back(CGAL::Bbox_3(b.lo.x, b.lo.y, b.lo.z, b.hi.x, b.hi.y, b.hi.z), s);
  }
  if (cells.empty()) return place;
  triangles.reserve(mesh.triangles.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    Box b;
    for (const VertexIndex v : mesh.triangles[t]) b.add(mesh.positions[v]);
    triangles.emplace_back(CGAL::Bbox_3(b.lo.x, b.lo.y, b.lo.z, b.hi.x, b.hi.y, b.hi.z), site_count + t);
  }
  std::vector<char> clear(site_count, 0);
  for (const IndexBox& c : cells) clear[c.handle()] = 1;
  // Closed boxes (CGAL's default topology): touching counts as meeting.
  std::vector<std::array<std::uint32_t, 2>> near;  // (cell, triangle) whose boxes meet
  CGAL::box_intersection_d(cells.begin(), cells.end(), triangles.begin(), triangles.end(),
                           [&](const IndexBox& a, const IndexBox& b) {
                             const bool first = a.handle() < site_count;
                             const std::size_t cell = first ? a.handle() : b.handle();
                             const std::size_t triangle = (first ? b.handle() : a.handle()) - site_count;
                             near.push_back({static_cast<std::uint32_t>(cell), static_cast<std::uint32_t>(triangle)});
                           });
  std::sort(near.begin(), near.end());
  for (std::size_t k = 0; k < near.size();) {
    const std::uint32_t cell = near[k][0];
    std::size_t end = k;
    while (end < near.size() && near[end][0] == cell) ++end;
    const std::vector<std::uint32_t>& bisectors = bisectors_of[cell];
    std::size_t last = 0;  // the plane that separated the last triangle, tried first
    for (; k < end && clear[cell]; ++k) {
      const Triangle& t = mesh.triangles[near[k][1]];
      const auto beyond = [&](std::size_t b) {
        const std::uint32_t plane = bisectors[b];
        const Sign far = plane_pairs[plane][0] == cell ? Sign::positive : Sign::negative;
        for (const VertexIndex v : t) {
          if (side_of_plane(planes[plane], mesh.positions[v]) != far) return false;
        }
        return true;
      };
      bool separated = !bisectors.empty() && beyond(last);
      for (std::size_t b = 0; b < bisectors.size() && !separated; ++b) {
        if (b != last && beyond(b)) {
          separated = true;
          last = b;
        }
      }
      if (!separated) clear[cell] = 0;
    }
    k = end;
  }
  std::vector<std::vector<std::uint32_t>> neighbours(site_count);
  for (const auto& [a, b] : pairs) {
    if (b < site_count && clear[a] && clear[b]) {
      neighbours[a].push_back(b);
      neighbours[b].push_back(a);
    }
  }
  std::unique_ptr<PointInSolid> inside;
  std::vector<char> seen(site_count, 0);
  std::vector<std::uint32_t> component;
  for (std::uint32_t s = 0; s < site_count; ++s) {
    if (!clear[s] || seen[s]) continue;
    component.assign(1, s);
    seen[s] = 1;
    for (std::size_t k = 0; k < component.size(); ++k) {
      for (const std::uint32_t t : neighbours[component[k]]) {
        if (!seen[t]) {
          seen[t] = 1;
          component.push_back(t);
        }
      }
    }
    if (!inside) inside = std::make_unique<PointInSolid>(mesh);
    const CellPlace where = inside->strictly_inside(sites[s]) ? CellPlace::inside : CellPlace::outside;
    for (const std::uint32_t t : component) place[t] = where;
  }
  return place;
}

// Whether (p0, p1, p2, p3), a permutation of 0..3, is even.
bool even_permutation(int p0, int p1, int p2, int p3) {
  const int p[4] = {p0, p1, p2, p3};
  int inversions = 0;
  for (int i = 0; i < 4; ++i) {
    for (int j = i + 1; j < 4; ++j) inversions += p[i] > p[j];
  }
  return inversions % 2 == 0;
}

// The cell of `site`, one that lies inside the solid (place_cells), as a convex
// solid made straight from the Delaunay triangulation instead of cut out of the
// solid: the Voronoi cell is the dual of the site's star. Its vertices are the
// circumcentres of the tetrahedra around the site, one per class of tetrahedra
// with one circumcentre (Triangulated::sphere_of: co-spherical sites, decided
// exactly); its face on the bisector with a Delaunay neighbour t is the
// circumcentres of the tetrahedra around the edge (site, t) in their order
// around it, repeats in a row dropped; a face left with fewer than three
// vertices has no area and is no face (the other faces then meet along its
// segment or point). Each vertex is the meet of the bisectors of the smallest
// of its class's first tetrahedron's sites with the other three: the canonical
// definition build_voronoi_tree gives cut vertices (so a cut neighbour writes
// their shared corners alike), and one definition per point for all assembled
// cells. The faces are those a cut of any box around the cell by its bisectors
// leaves (caps, surface id plane + 1, reversed where the site is the
// bisector's second), in another order; checked as made: every directed edge
// matched by one reverse edge (whose face's plane is the edge's line), each face
// turning the way its outward side says (exactly). Returns nothing when the
// star is not as that argument expects (an infinite tetrahedron, a face through
// one vertex twice, three corners in a row, an unmatched edge): the caller then
// cuts the cell. Throws std::logic_error when a face turns the wrong way (a
// bug, never a property of the input).
// `plane_to`: per site, (neighbour, bisector plane) for its Delaunay neighbours
// above it, sorted.
std::optional<Solid> assemble_inner_cell(const Triangulated& tri, std::uint32_t site, std::span<const std::uint32_t> bisectors,
                                         std::span<const std::array<std::uint32_t, 2>> plane_pairs,
                                         std::span<const std::vector<std::array<std::uint32_t, 2>>> plane_to,
                                         const PlaneSet& set) {
  const Delaunay& dt = *tri.dt;
  const Delaunay::Vertex_handle v = tri.vertex_of[site];
  thread_local std::vector<Delaunay::Cell_handle> star;
  star.clear();
  // The thread-safe walk: cells are assembled on several threads at once, and
  // incident_cells marks the cells it visits in the triangulation itself, so two
  // walks over stars that share cells could each skip cells the other had
  // marked, and a cell's assembly fail where it succeeds alone (it was then cut
  // instead: a valid fragment of other bytes, about one build in twenty of a
  // 12 x 12 x 12 grid of the cube on two threads).
  dt.incident_cells_threadsafe(v, std::back_inserter(star));
  for (const auto& c : star) {
    if (dt.is_infinite(c)) return std::nullopt;
  }
  std::sort(star.begin(), star.end(), [](const auto& a, const auto& b) { return a->info() < b->info(); });
  Solid solid;
  // Sized for the cell at once (about 2 vertices and 6 corners per face).
  solid.faces.reserve(bisectors.size());
  solid.loops.reserve(bisectors.size());
  solid.corners.reserve(6 * bisectors.size());
  solid.defs.reserve(star.size());
  solid.approx.reserve(star.size());
  thread_local std::vector<std::array<std::uint32_t, 2>> vertex_of_sphere;  // (sphere, vertex), in order of first use
  vertex_of_sphere.clear();
  thread_local std::vector<std::uint32_t> ring;
  for (const std::uint32_t plane : bisectors) {
    const auto& pair = plane_pairs[plane];
    const std::uint32_t other = pair[0] == site ? pair[1] : pair[0];
    const Delaunay::Vertex_handle w = tri.vertex_of[other];
    // The first numbered tetrahedron around the edge (site, other).
    std::uint32_t start = no_index;
    for (std::uint32_t i = 0; i < star.size() && start == no_index; ++i) {
      if (star[i]->has_vertex(w)) start = i;
    }
    if (start == no_index) return std::nullopt;
    // Around the edge counter-clockwise seen from `other` (outside the cell): in a
    // positively oriented tetrahedron (site, other, a, b) the turn from a to b is
    // counter-clockwise about other - site, so the next one is across from a.
    ring.clear();
    Delaunay::Cell_handle c = star[start];
    do {
      ring.push_back(tri.sphere_of[c->info()]);
      const int is = c->index(v), io = c->index(w);
      int a = -1, b = -1;
      for (int k = 0; k < 4; ++k) {
        if (k == is || k == io) continue;
        (a < 0 ? a : b) = k;
      }
      if (!even_permutation(is, io, a, b)) std::swap(a, b);
      c = c->neighbor(a);
      if (ring.size() > star.size()) return std::nullopt;
    } while (c != star[start]);
    // Runs of one class are one vertex; start the loop where a run starts.
    std::size_t first = ring.size();
    for (std::size_t k = 0; k < ring.size(); ++k) {
      if (ring[k] != ring[(k + ring.size() - 1) % ring.size()]) {
        first = k;
        break;
      }
    }
    if (first == ring.size()) continue;  // one point: no area
    thread_local std::vector<std::uint32_t> corners;
    corners.clear();
    for (std::size_t k = 0; k < ring.size(); ++k) {
      const std::uint32_t cls = ring[(first + k) % ring.size()];
      if (k == 0 || cls != corners.back()) corners.push_back(cls);
    }
    if (corners.size() < 3) continue;  // a segment: no area
    for (std::size_t k = 0; k < corners.size(); ++k) {
      for (std::size_t l = k + 1; l < corners.size(); ++l) {
        if (corners[k] == corners[l]) return std::nullopt;
      }
    }
    SolidFace face;
    face.plane = PlaneRef::cut(plane);
    face.reversed = pair[0] != site;  // the bisector is negative on pair[0]'s side
    face.convex = true;
    face.surface = static_cast<SurfaceId>(plane + 1);  // the cap id clipped gives a cut by this plane
    face.first_loop = static_cast<std::uint32_t>(solid.loops.size());
    face.loop_count = 1;
    solid.loops.push_back({static_cast<std::uint32_t>(solid.corners.size()), static_cast<std::uint32_t>(corners.size())});
    for (const std::uint32_t sphere : corners) {
      std::uint32_t vertex = no_index;
      for (const auto& [known, index] : vertex_of_sphere) {
        if (known == sphere) vertex = index;
      }
      if (vertex == no_index) {
        vertex = static_cast<std::uint32_t>(solid.defs.size());
        vertex_of_sphere.push_back({sphere, vertex});
        const std::array<std::uint32_t, 4>& four = tri.points_of[sphere];
        std::array<PlaneRef, 3> planes;
        for (int k = 0; k < 3; ++k) {
          const auto& to = plane_to[four[0]];
          const std::array<std::uint32_t, 2> key{four[k + 1], 0};
          const auto found = std::lower_bound(to.begin(), to.end(), key);
          if (found == to.end() || (*found)[0] != four[k + 1]) return std::nullopt;
          planes[k] = PlaneRef::cut((*found)[1]);
        }
        solid.defs.push_back(PointDef::three_planes(planes[0], planes[1], planes[2]));
        solid.approx.push_back(approximate(set, solid.defs.back()));
      }
      solid.corners.push_back({vertex, EdgeLine{}});
    }
    solid.faces.push_back(face);
  }
  if (solid.faces.size() < 4) return std::nullopt;
  // Each edge's line: the plane of the face across it, found by its reverse edge.
  thread_local std::vector<std::array<std::uint32_t, 3>> edges;  // from, to, face
  edges.clear();
  for (std::uint32_t f = 0; f < solid.faces.size(); ++f) {
    for (const CornerEdge& e : loop_edges(solid.corners, solid.loops[solid.faces[f].first_loop])) {
      edges.push_back({e.from, e.to, f});
    }
  }
  std::sort(edges.begin(), edges.end());
  for (std::size_t k = 1; k < edges.size(); ++k) {
    if (edges[k][0] == edges[k - 1][0] && edges[k][1] == edges[k - 1][1]) return std::nullopt;
  }
  for (std::uint32_t f = 0; f < solid.faces.size(); ++f) {
    const SolidLoop& loop = solid.loops[solid.faces[f].first_loop];
    for (const CornerEdge& e : loop_edges(solid.corners, loop)) {
      const std::array<std::uint32_t, 3> key{e.to, e.from, 0};
      const auto found = std::lower_bound(edges.begin(), edges.end(), key);
      if (found == edges.end() || (*found)[0] != e.to || (*found)[1] != e.from) return std::nullopt;
      solid.corners[e.corner].line.other = solid.faces[(*found)[2]].plane;
    }
    // The face turns counter-clockwise seen from outside; its corners are in
    // convex position with no three in a row.
    const SolidFace& face = solid.faces[f];
    const SolidCorner* c = &solid.corners[loop.first_corner];
    const Sign turn = orient_in_plane(set, projection_of(set, face.plane), solid.defs[c[0].vertex], solid.approx[c[0].vertex],
                                      solid.defs[c[1].vertex], solid.approx[c[1].vertex], solid.defs[c[2].vertex],
                                      solid.approx[c[2].vertex]);
    if (turn == Sign::zero) return std::nullopt;
    if ((turn == Sign::positive) == face.reversed) {
      throw std::logic_error("build_voronoi_tree: an inner cell's face turns the wrong way");
    }
  }
  solid.convex = true;
#ifndef NDEBUG
  // Every corner on its face's plane and its edge's line, exactly (debug builds).
  if (const std::string problem = check_solid(set, solid); !problem.empty()) {
    throw std::logic_error("build_voronoi_tree: an assembled inner cell is not sound: " + problem);
  }
#endif
  return solid;
}

// --- cutting --------------------------------------------------------------------

// Cuts every piece by cut plane `plane`, keeping the n.x + d < 0 side (or the
// other): pieces the plane misses are kept or dropped whole. `Piece` is Solid
// for pieces that are spent (a piece kept whole is moved out) or const Solid
// for pieces another group or cell shares (it is copied).
template <class Piece>
std::vector<Solid> clipped(const PlaneSet& set, const InputShells& shells, std::span<Piece> pieces,
                           std::uint32_t plane, bool keep_below) {
  std::vector<Solid> kept;
  kept.reserve(pieces.size());
  for (Piece& piece : pieces) {
    SolidCut cut =
        cut_solid(set, piece, PlaneRef::cut(plane), plane + 1, shells, keep_below ? CutSides::below : CutSides::above);
    if (cut.plane_missed) {
      if (cut.all_below == keep_below) kept.push_back(std::move(piece));
      continue;
    }
    for (Solid& side : keep_below ? cut.below : cut.above) kept.push_back(std::move(side));
  }
  return kept;
}

// The same in place.
void clip(const PlaneSet& set, const InputShells& shells, std::vector<Solid>& pieces, std::uint32_t plane,
          bool keep_below) {
  pieces = clipped(set, shells, std::span<Solid>(pieces), plane, keep_below);
}

struct Group {
  std::uint32_t begin = 0, end = 0;  // into the site order
  std::int32_t left = -1, right = -1;
  Box box;
};

class VoronoiCutter {
 public:
  /// `place`: per site, where its cell lies (place_cells); `assemble` makes an
  /// inside cell's solid over the set run() is given, or nothing (it is then cut).
  VoronoiCutter(const PlaneInput& input, std::span<const Vec3> sites, std::span<const Box> cell_boxes,
                const Box& solid_box, double margin, std::span<const std::vector<std::uint32_t>> bisectors_of,
                std::span<const std::array<std::uint32_t, 2>> plane_pairs, std::vector<Plane>& planes,
                std::span<const CellPlace> place,
                const std::function<std::optional<Solid>(std::uint32_t, const PlaneSet&)>& assemble,
                const std::function<void()>& on_site)
      : input_(input), sites_(sites), bisectors_of_(bisectors_of), plane_pairs_(plane_pairs), place_(place),
        assemble_(assemble), on_site_(on_site) {
    for (std::uint32_t s = 0; s < sites.size(); ++s) {
      if (!intersection(cell_boxes[s], solid_box).empty()) order_.push_back(s);
    }
    if (!order_.empty()) build_group(0, static_cast<std::uint32_t>(order_.size()), cell_boxes, solid_box, margin);
    box_base_ = static_cast<std::uint32_t>(planes.size());
    for (const Group& g : groups_) {
      for (int a = 0; a < 3; ++a) {
        // A group without a cell to cut has no box (its planes are never cut by).
        Vec3 n{0, 0, 0};
        axis_of(n, a) = -1;
        planes.push_back({n, g.box.empty() ? 0.0 : axis_of(g.box.lo, a)});  // -x + lo < 0: x > lo
        axis_of(n, a) = 1;
        planes.push_back({n, g.box.empty() ? 0.0 : -axis_of(g.box.hi, a)});  // x - hi < 0: x < hi
      }
    }
    box_end_ = static_cast<std::uint32_t>(planes.size());
    pieces_.resize(sites.size());
  }

  std::uint32_t box_base() const { return box_base_; }
  std::uint32_t box_end() const { return box_end_; }
  /// The k-d groups (groups()[0] the root, when there are sites) and the site
  /// order their ranges index.
  const std::vector<Group>& groups() const { return groups_; }
  const std::vector<std::uint32_t>& order() const { return order_; }

  /// Runs the groups over `set` (whose cut planes must be the `planes` built by
  /// the constructor); returns each site's pieces.
  std::vector<std::vector<Solid>> run(const PlaneSet& set) {
    set_ = &set;
    if (!groups_.empty()) {
      const std::vector<Solid> whole{input_.solid};
      process(0, whole, groups_[0].box);
    }
    return std::move(pieces_);
  }

 private:
  std::uint32_t build_group(std::uint32_t begin, std::uint32_t end, std::span<const Box> cell_boxes,
                            const Box& solid_box, double margin) {
    const auto index = static_cast<std::uint32_t>(groups_.size());
    groups_.push_back({begin, end, -1, -1, {}});
    // The box holds the cells that are cut (those that may meet the surface);
    // inside cells are assembled and outside ones dropped, needing no container.
    Box cells, spread;
    for (std::uint32_t i = begin; i < end; ++i) {
      if (place_[order_[i]] == CellPlace::surface) cells.add(cell_boxes[order_[i]]);
      spread.add(sites_[order_[i]]);
    }
    if (!cells.empty()) groups_[index].box = intersection(grown(cells, margin), solid_box);
    if (end - begin > leaf_group_size) {
      const Vec3 extent = spread.hi - spread.lo;
      const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : extent.y >= extent.z ? 1 : 2;
      const std::uint32_t middle = begin + (end - begin) / 2;
      std::nth_element(order_.begin() + begin, order_.begin() + middle, order_.begin() + end,
                       [&](std::uint32_t a, std::uint32_t b) {
                         const double pa = axis_of(sites_[a], axis), pb = axis_of(sites_[b], axis);
                         return pa < pb || (pa == pb && a < b);
                       });
      const std::uint32_t left = build_group(begin, middle, cell_boxes, solid_box, margin);
      const std::uint32_t right = build_group(middle, end, cell_boxes, solid_box, margin);
      groups_[index].left = static_cast<std::int32_t>(left);
      groups_[index].right = static_cast<std::int32_t>(right);
    }
    return index;
  }

  // Group g's container: `parent` (its parent group's container, shared with the
  // sibling, so read, not copied) cut by the planes of the group's box that are
  // inside the parent's box.
  void process(std::uint32_t g, const std::vector<Solid>& parent, const Box& parent_box) {
    const Group& group = groups_[g];
    if (group.box.empty()) {
      // No cell here is cut: nothing needs the container.
      for (std::uint32_t i = group.begin; i < group.end; ++i) {
        uncut(order_[i]);
        if (on_site_) on_site_();
      }
      return;
    }
    std::vector<Solid> pieces;
    bool cut = false;
    const auto cut_by = [&](std::uint32_t plane) {
      if (!cut) {
        pieces = clipped(*set_, input_.shells, std::span<const Solid>(parent), plane, true);
        cut = true;
      } else if (!pieces.empty()) {
        clip(*set_, input_.shells, pieces, plane, true);
      }
    };
    // The box's planes inside the parent's box, the one cutting off the largest
    // share of the parent's box first: the first cut reads the whole parent,
    // the later ones only what is left (in axis order, the first cut was often
    // a thin margin's trim, and the split that halves the parent came last).
    std::array<std::pair<double, std::uint32_t>, 6> box_cuts;
    std::size_t box_cut_count = 0;
    for (int a = 0; a < 3; ++a) {
      const double extent = axis_of(parent_box.hi, a) - axis_of(parent_box.lo, a);
      if (axis_of(group.box.lo, a) > axis_of(parent_box.lo, a)) {
        box_cuts[box_cut_count++] = {(axis_of(group.box.lo, a) - axis_of(parent_box.lo, a)) / extent, 2 * a};
      }
      if (axis_of(group.box.hi, a) < axis_of(parent_box.hi, a)) {
        box_cuts[box_cut_count++] = {(axis_of(parent_box.hi, a) - axis_of(group.box.hi, a)) / extent, 2 * a + 1};
      }
    }
    std::sort(box_cuts.begin(), box_cuts.begin() + box_cut_count,
              [](const auto& x, const auto& y) { return x.first > y.first || (x.first == y.first && x.second < y.second); });
    for (std::size_t k = 0; k < box_cut_count; ++k) cut_by(box_base_ + 6 * g + box_cuts[k].second);
    if (!cut) pieces = parent;
    if (group.left < 0) {
      for (std::uint32_t i = group.begin; i < group.end; ++i) {
        const std::uint32_t site = order_[i];
        if (place_[site] != CellPlace::surface) {
          uncut(site);
        } else if (!pieces.empty()) {
          pieces_[site] = cell(site, pieces);
        }
        if (on_site_) on_site_();
      }
      return;
    }
    if (pieces.empty()) {
      for (std::uint32_t i = group.begin; i < group.end; ++i) {
        uncut(order_[i]);
        if (on_site_) on_site_();
      }
      return;
    }
    tbb::parallel_invoke([&] { process(static_cast<std::uint32_t>(group.left), pieces, group.box); },
                         [&] { process(static_cast<std::uint32_t>(group.right), pieces, group.box); });
  }

  // A cell that is not cut out of its group's container: an inside cell is
  // assembled (or, when assemble_ declines it, cut out of the whole input,
  // which its group's box need not hold), an outside cell has no part of the
  // solid, and a surface cell whose container is empty neither.
  void uncut(std::uint32_t site) {
    if (place_[site] != CellPlace::inside) return;
    std::optional<Solid> solid = assemble_(site, *set_);
    if (solid) {
      pieces_[site].push_back(std::move(*solid));
    } else {
      pieces_[site] = cell(site, std::vector<Solid>{input_.solid});
    }
  }

  // The site's part of `container`: cut by its bisectors, nearest neighbour first
  // (the pieces shrink fastest), keeping the site's side.
  // The first cut reads the container, which the group's other cells share.
  std::vector<Solid> cell(std::uint32_t site, const std::vector<Solid>& container) const {
    const std::vector<std::uint32_t>& planes = bisectors_of_[site];
    if (planes.empty()) return container;
    std::vector<Solid> pieces =
        clipped(*set_, input_.shells, std::span<const Solid>(container), planes[0], plane_pairs_[planes[0]][0] == site);
    for (std::size_t k = 1; k < planes.size() && !pieces.empty(); ++k) {
      clip(*set_, input_.shells, pieces, planes[k], plane_pairs_[planes[k]][0] == site);
    }
    return pieces;
  }

  const PlaneInput& input_;
  std::span<const Vec3> sites_;
  std::span<const std::vector<std::uint32_t>> bisectors_of_;
  std::span<const std::array<std::uint32_t, 2>> plane_pairs_;
  std::span<const CellPlace> place_;
  const std::function<std::optional<Solid>(std::uint32_t, const PlaneSet&)>& assemble_;
  const std::function<void()>& on_site_;
  std::vector<std::uint32_t> order_;
  std::vector<Group> groups_;
  std::uint32_t box_base_ = 0, box_end_ = 0;
  const PlaneSet* set_ = nullptr;
  std::vector<std::vector<Solid>> pieces_;
};

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

Box solid_box_of(const Mesh& mesh) {
  Box box;
  for (const Vec3& p : mesh.positions) box.add(p);
  return box;
}

// A quarter of the Euclidean length of (x, y, z): scaled by its largest
// component, so that no square overflows or underflows, and quartered, so
// that the length of any finite vector is finite.
double quarter_length(double x, double y, double z) {
  const double largest = std::max({std::fabs(x), std::fabs(y), std::fabs(z)});
  if (!(largest > 0)) return 0;
  x /= largest, y /= largest, z /= largest;
  return largest / 4 * std::sqrt(x * x + y * y + z * z);
}

// Per site, whether its cell provably misses the box [lo, hi]: its distance to
// the box is more than twice the smallest, over all sites, distance from a site
// to the box's farthest point. Every point of the box is then strictly nearer
// that site than this one, by a margin no rounding of these distances (a few
// ulps) or of the sites onto their grid (2^-24 of the largest coordinate)
// closes. Leaving such a site out changes no cell's part of the box, and keeps
// it from coarsening the grid: a site at 1e150 beside a unit cube made the
// spacing 2^-24 of 1e150, and every site near the cube merged into one.
// Differences are taken of halves, so that none overflows whatever the
// coordinates.
std::vector<std::uint8_t> far_sites(std::span<const Vec3> sites, const Vec3& lo, const Vec3& hi) {
  const auto gap = [](double x, double low, double high) {
    return x < low ? low / 2 - x / 2 : x > high ? x / 2 - high / 2 : 0.0;
  };
  const auto reach = [](double x, double low, double high) {
    return std::max(std::fabs(x / 2 - low / 2), std::fabs(x / 2 - high / 2));
  };
  double nearest_reach = INFINITY;  // an eighth of it, as every length below
  for (const Vec3& s : sites) {
    nearest_reach =
        std::min(nearest_reach, quarter_length(reach(s.x, lo.x, hi.x), reach(s.y, lo.y, hi.y), reach(s.z, lo.z, hi.z)));
  }
  std::vector<std::uint8_t> far(sites.size(), 0);
  for (std::size_t i = 0; i < sites.size(); ++i) {
    const Vec3& s = sites[i];
    const double distance = quarter_length(gap(s.x, lo.x, hi.x), gap(s.y, lo.y, hi.y), gap(s.z, lo.z, hi.z));
    far[i] = distance / 2 > nearest_reach ? 1 : 0;
  }
  return far;
}

}  // namespace

QuantizedSites quantize_sites(std::span<const Vec3> sites, const Vec3& lo, const Vec3& hi) {
  if (sites.empty()) throw std::invalid_argument("quantize_sites: no sites");
  for (const Vec3& s : sites) {
    if (!std::isfinite(s.x) || !std::isfinite(s.y) || !std::isfinite(s.z)) {
      throw std::invalid_argument("quantize_sites: a site has a NaN or infinite coordinate");
    }
  }
  const std::vector<std::uint8_t> far = far_sites(sites, lo, hi);
  Box box;
  box.add(lo);
  box.add(hi);
  for (std::size_t i = 0; i < sites.size(); ++i) {
    if (!far[i]) box.add(sites[i]);
  }
  const auto out_of_range = [](double largest) {
    char magnitude[32];
    std::snprintf(magnitude, sizeof magnitude, "%.3g", largest);
    return UnsupportedGeometryError(std::string("Voronoi cells need coordinates of magnitude 2^-476 to 2^500 (about "
                                                "1e-143 to 3e150), where every bisector is exact in doubles; the solid's "
                                                "box and the sites reach ") + magnitude);
  };
  // The sentinels lie within 8 times the box's largest coordinate of the
  // origin: a box beyond 2^496 is refused before they are made (their
  // distances' squares would overflow), as it would be after.
  const double box_largest = std::max({std::fabs(box.lo.x), std::fabs(box.lo.y), std::fabs(box.lo.z),
                                       std::fabs(box.hi.x), std::fabs(box.hi.y), std::fabs(box.hi.z)});
  if (!(box_largest < 0x1p496)) throw out_of_range(box_largest);
  // The sentinels lie around this box; the grid must hold them too.
  double largest = 0;
  for (const Vec3& p : sentinel_sites(box)) largest = std::max({largest, std::fabs(p.x), std::fabs(p.y), std::fabs(p.z)});
  if (!(largest > 0)) largest = 1;
  int exponent = 0;
  std::frexp(largest, &exponent);  // largest < 2^exponent
  // Spacing 2^(exponent - 24): largest / h < 2^24, so |k| <= 2^24 after rounding
  // (grid_limit), with room for the sentinels' own rounding.
  const int step_exponent = exponent - 24;
  if (2 * step_exponent < -1000 || exponent > 500) throw out_of_range(largest);
  QuantizedSites out;
  out.step = std::ldexp(1.0, step_exponent);
  std::map<std::array<std::int64_t, 3>, std::uint32_t> seen;
  out.site_of_input.reserve(sites.size());
  for (std::size_t i = 0; i < sites.size(); ++i) {
    if (far[i]) {
      out.site_of_input.push_back(no_index);
      ++out.far;
      continue;
    }
    const Vec3& s = sites[i];
    const std::array<std::int64_t, 3> k{grid_index(s.x, out.step), grid_index(s.y, out.step), grid_index(s.z, out.step)};
    const auto [it, inserted] = seen.emplace(k, static_cast<std::uint32_t>(out.sites.size()));
    if (inserted) {
      out.sites.push_back({static_cast<double>(k[0]) * out.step, static_cast<double>(k[1]) * out.step,
                           static_cast<double>(k[2]) * out.step});
    } else {
      ++out.merged;
    }
    out.site_of_input.push_back(it->second);
  }
  return out;
}

Plane exact_bisector(const Vec3& p, const Vec3& q, double step) {
  std::array<std::int64_t, 3> kp{}, kq{};
  for (int a = 0; a < 3; ++a) {
    kp[a] = grid_index(axis_of(p, a), step);
    kq[a] = grid_index(axis_of(q, a), step);
    if (static_cast<double>(kp[a]) * step != axis_of(p, a) || static_cast<double>(kq[a]) * step != axis_of(q, a) ||
        std::llabs(kp[a]) > 2 * grid_limit || std::llabs(kq[a]) > 2 * grid_limit) {
      throw std::invalid_argument("exact_bisector: a site is not on the grid");
    }
  }
  if (kp == kq) throw std::invalid_argument("exact_bisector: equal sites");
  // |k| <= 2^25 (checked above), so each square <= 2^50 and the sum of three
  // differences < 3 2^50 < 2^53: exact in int64 and as a double, and so is its
  // product with h^2, a power of two (quantize_sites keeps it normal).
  std::int64_t d = 0;
  for (int a = 0; a < 3; ++a) d += kp[a] * kp[a] - kq[a] * kq[a];
  const double h = step;
  return {{std::ldexp(static_cast<double>(kq[0] - kp[0]), 1) * h, std::ldexp(static_cast<double>(kq[1] - kp[1]), 1) * h,
           std::ldexp(static_cast<double>(kq[2] - kp[2]), 1) * h},
          static_cast<double>(d) * h * h};
}

namespace {

// A pair of sites as one key: the first in the high half.
std::uint64_t pair_key(const std::array<std::uint32_t, 2>& pair) { return std::uint64_t{pair[0]} << 32 | pair[1]; }

// What the cells are made of, shared by build_voronoi_tree and
// voronoi_cell_planes: the quantized sites, the sentinels on their grid, the
// Delaunay bisectors (each site's sorted nearest neighbour first), the solid's
// box grown by a margin that holds it strictly inside.
struct CellPlanes {
  QuantizedSites quantized;
  std::vector<Vec3> points;  ///< the sites, then the sentinels
  Triangulated triangulated;
  std::vector<Plane> planes;
  std::vector<std::array<std::uint32_t, 2>> plane_pairs;
  /// Per site pair (pair_key), its bisector's plane: looked up for every vertex
  /// made canonical, so hashed (only found and added, never walked in order).
  std::unordered_map<std::uint64_t, std::uint32_t> plane_of_pair;
  std::vector<std::vector<std::uint32_t>> bisectors_of;
  std::size_t neighbour_pairs = 0;
  double margin = 0;
  Box solid_box;
};

CellPlanes cell_planes(const Mesh& mesh, std::span<const Vec3> given_sites) {
  CellPlanes cell;
  const Box mesh_box = solid_box_of(mesh);
  cell.quantized = quantize_sites(given_sites, mesh_box.lo, mesh_box.hi);
  const QuantizedSites& quantized = cell.quantized;
  const std::vector<Vec3>& sites = quantized.sites;
  const auto site_count = static_cast<std::uint32_t>(sites.size());

  // The solid's box grown by a margin: it holds the solid strictly inside.
  // The box the sentinels surround: as quantize_sites takes it, so they fit its grid.
  Box around = mesh_box;
  for (std::size_t i = 0; i < given_sites.size(); ++i) {
    if (quantized.site_of_input[i] != no_index) around.add(given_sites[i]);
  }
  const double extent = std::max({mesh_box.hi.x - mesh_box.lo.x, mesh_box.hi.y - mesh_box.lo.y, mesh_box.hi.z - mesh_box.lo.z});
  const double margin = std::ldexp(extent, -20);
  const Box solid_box = grown(mesh_box, margin);

  // Sites, then the sentinels on the same grid.
  std::vector<Vec3>& points = cell.points;
  points = sites;
  for (const Vec3& s : sentinel_sites(around)) {
    points.push_back({std::nearbyint(s.x / quantized.step) * quantized.step, std::nearbyint(s.y / quantized.step) * quantized.step,
                      std::nearbyint(s.z / quantized.step) * quantized.step});
  }
  cell.triangulated = triangulate(points, site_count, quantized.step);

  // Working planes: the Delaunay bisectors, then the groups' box planes, then
  // the bisectors canonical definitions add.
  std::vector<Plane>& planes = cell.planes;
  std::vector<std::array<std::uint32_t, 2>>& plane_pairs = cell.plane_pairs;
  std::vector<std::vector<std::uint32_t>>& bisectors_of = cell.bisectors_of;
  bisectors_of.resize(site_count);
  for (const auto& pair : cell.triangulated.pairs) {
    const auto index = static_cast<std::uint32_t>(planes.size());
    planes.push_back(exact_bisector(points[pair[0]], points[pair[1]], quantized.step));
    plane_pairs.push_back(pair);
    cell.plane_of_pair.emplace(pair_key(pair), index);
    bisectors_of[pair[0]].push_back(index);
    if (pair[1] < site_count) {
      bisectors_of[pair[1]].push_back(index);
      ++cell.neighbour_pairs;
    }
  }
  for (std::uint32_t s = 0; s < site_count; ++s) {
    const Vec3 p = sites[s];
    auto distance = [&](std::uint32_t plane) {
      const auto& pair = plane_pairs[plane];
      const Vec3 d = points[pair[0] == s ? pair[1] : pair[0]] - p;
      return dot(d, d);
    };
    std::sort(bisectors_of[s].begin(), bisectors_of[s].end(), [&](std::uint32_t a, std::uint32_t b) {
      const double da = distance(a), db = distance(b);
      return da < db || (da == db && a < b);
    });
  }

  cell.margin = margin;
  cell.solid_box = solid_box;
  return cell;
}

}  // namespace

VoronoiCellPlanes voronoi_cell_planes(const Mesh& mesh, std::span<const Vec3> sites) {
  if (mesh.positions.empty()) throw std::invalid_argument("voronoi_cell_planes needs a non-empty mesh");
  if (sites.empty()) throw std::invalid_argument("voronoi_cell_planes needs at least one site");
  CellPlanes cell = cell_planes(mesh, sites);
  VoronoiCellPlanes out;
  out.cells.resize(cell.quantized.sites.size());
  for (std::size_t s = 0; s < out.cells.size(); ++s) {
    for (const std::uint32_t plane : cell.bisectors_of[s]) {
      // Stored as B_pq with p the lower index: negative on p's side.
      const Plane& b = cell.planes[plane];
      out.cells[s].push_back(cell.plane_pairs[plane][0] == s ? b : Plane{-b.normal, -b.offset});
    }
  }
  out.quantized = std::move(cell.quantized);
  return out;
}

namespace {

// Canonical definitions (the file comment): every vertex of the cells' pieces
// defined by two or more bisectors gets, in place of them, the bisectors of the
// smallest of their sites with each of the others (the same point), after its
// other plane; its approximation follows. The bisectors this needs that were
// not cut are added to `cell.planes`, `cell.plane_of_pair` and `site_pairs`
// (per plane, its two sites; no_index for a plane that is no bisector).
void make_definitions_canonical(std::vector<std::vector<Solid>>& cells, CellPlanes& cell,
                                std::vector<std::array<std::uint32_t, 2>>& site_pairs, const InputGeometry& geometry) {
  const auto is_bisector = [&](PlaneRef ref) {
    return ref.bits != no_index && ref.is_cut() && site_pairs[ref.index()][0] != no_index;
  };
  for (std::vector<Solid>& pieces : cells) {
    for (Solid& solid : pieces) {
      for (std::size_t v = 0; v < solid.defs.size(); ++v) {
        PointDef& def = solid.defs[v];
        if (def.kind != PointKind::three_planes) continue;
        // At most three planes: fixed arrays, not a vector's allocation per vertex.
        std::array<PlaneRef, 3> canonical;
        std::size_t others = 0;
        std::array<std::uint32_t, 6> involved;
        std::size_t involved_count = 0;
        int bisectors = 0;
        for (const PlaneRef ref : def.planes) {
          if (is_bisector(ref)) {
            ++bisectors;
            const auto pair = site_pairs[ref.index()];
            involved[involved_count++] = pair[0];
            involved[involved_count++] = pair[1];
          } else {
            canonical[others++] = ref;
          }
        }
        if (bisectors < 2) continue;
        // Sorted and made unique by hand: six values at most (std::sort on a
        // prefix of a fixed array draws a false -Warray-bounds from GCC 12).
        for (std::size_t i = 1; i < involved_count; ++i) {
          for (std::size_t j = i; j > 0 && involved[j] < involved[j - 1]; --j) std::swap(involved[j], involved[j - 1]);
        }
        std::size_t distinct = 0;
        for (std::size_t i = 0; i < involved_count; ++i) {
          if (distinct == 0 || involved[i] != involved[distinct - 1]) involved[distinct++] = involved[i];
        }
        involved_count = distinct;
        if (involved_count != static_cast<std::size_t>(bisectors) + 1) continue;
        for (std::size_t k = 1; k < involved_count; ++k) {
          const std::array<std::uint32_t, 2> pair{involved[0], involved[k]};
          auto found = cell.plane_of_pair.find(pair_key(pair));
          if (found == cell.plane_of_pair.end()) {
            const auto index = static_cast<std::uint32_t>(cell.planes.size());
            cell.planes.push_back(exact_bisector(cell.points[pair[0]], cell.points[pair[1]], cell.quantized.step));
            site_pairs.push_back(pair);
            found = cell.plane_of_pair.emplace(pair_key(pair), index).first;
          }
          canonical[others + k - 1] = PlaneRef::cut(found->second);
        }
        if (std::equal(canonical.begin(), canonical.end(), def.planes.begin())) continue;
        for (int k = 0; k < 3; ++k) def.planes[k] = canonical[k];
        // The cache follows the definition (the file's reader recomputes it bit for bit).
        solid.approx[v] = approximate(geometry.plane_set(cell.planes), def);
      }
    }
  }
}

}  // namespace

MeshTree build_voronoi_tree(const Mesh& mesh, std::span<const Vec3> given_sites, const TreeRecipe& recipe,
                            const BuildRunOptions& run, VoronoiReport* report_out) {
  if (recipe.strategy != Strategy::voronoi) throw std::invalid_argument("build_voronoi_tree needs recipe.strategy voronoi");
  if (recipe.kernel != KernelKind::plane) throw std::invalid_argument("recipe.kernel must be plane");
  if (given_sites.empty()) throw std::invalid_argument("build_voronoi_tree needs at least one site");
  for (SurfaceId surface : mesh.surfaces) {
    if (surface != original_surface) {
      throw std::invalid_argument("build_voronoi_tree needs every input triangle on surface 0 (caps are numbered by plane)");
    }
  }
  detail::require_fracturable_extent(mesh);
  if (!run.input_validated) require_valid_solid(mesh, "input", recipe.allow_self_intersections);
  const auto start = std::chrono::steady_clock::now();
  VoronoiReport report;
  report.sites_given = given_sites.size();

  CellPlanes cell = cell_planes(mesh, given_sites);
  report.sites_merged = cell.quantized.merged;
  report.sites_far = cell.quantized.far;
  report.step = cell.quantized.step;
  report.neighbour_pairs = cell.neighbour_pairs;
  const std::vector<Vec3>& sites = cell.quantized.sites;
  const auto site_count = static_cast<std::uint32_t>(sites.size());
  const double margin = cell.margin;
  const Box solid_box = cell.solid_box;
  Triangulated& triangulated = cell.triangulated;
  std::vector<Plane>& planes = cell.planes;
  std::vector<std::array<std::uint32_t, 2>>& plane_pairs = cell.plane_pairs;
  std::vector<std::vector<std::uint32_t>>& bisectors_of = cell.bisectors_of;
  const std::vector<Vec3>& points = cell.points;
  const QuantizedSites& quantized = cell.quantized;

  const PlaneInput input = prepare_plane_input(mesh);
  const unsigned threads = run.threads == 0 ? static_cast<unsigned>(tbb::info::default_concurrency()) : run.threads;
  tbb::task_arena arena(static_cast<int>(threads));
  std::atomic<std::size_t> sites_done{0};
  const std::function<void()> on_site = [&] {
    const std::size_t done = ++sites_done;
    if (run.progress) run.progress(done);
  };
  // Cells inside the solid are assembled from the triangulation, not cut
  // (place_cells, assemble_inner_cell); not for a self-intersecting input
  // accepted on request, whose inside no point query decides.
  const std::vector<CellPlace> place =
      recipe.allow_self_intersections
          ? std::vector<CellPlace>(site_count, CellPlace::surface)
          : place_cells(mesh, sites, triangulated.cell_boxes, triangulated.pairs, planes, plane_pairs, bisectors_of);
  std::atomic<std::size_t> cells_assembled{0};
  std::vector<std::vector<std::array<std::uint32_t, 2>>> plane_to(site_count);
  for (std::uint32_t p = 0; p < plane_pairs.size(); ++p) plane_to[plane_pairs[p][0]].push_back({plane_pairs[p][1], p});
  for (auto& to : plane_to) std::sort(to.begin(), to.end());
  const std::function<std::optional<Solid>(std::uint32_t, const PlaneSet&)> assemble = [&](std::uint32_t s,
                                                                                           const PlaneSet& set) {
    std::optional<Solid> solid = assemble_inner_cell(triangulated, s, bisectors_of[s], plane_pairs, plane_to, set);
    if (solid) ++cells_assembled;
    return solid;
  };
  VoronoiCutter cutter(input, sites, triangulated.cell_boxes, solid_box, margin, bisectors_of, plane_pairs, planes,
                       place, assemble, on_site);
  std::vector<std::vector<Solid>> cells;
  {
    const PlaneSet set = input.geometry.plane_set(planes);
    arena.execute([&] { cells = cutter.run(set); });
  }
  triangulated.dt.reset();  // only the assembly needed it
  report.cells_inside = static_cast<std::size_t>(std::count(place.begin(), place.end(), CellPlace::inside));
  report.cells_assembled = cells_assembled;
  const std::uint32_t box_base = cutter.box_base(), box_end = cutter.box_end();
  // Per plane, the two sites it bisects; none for the groups' box planes.
  std::vector<std::array<std::uint32_t, 2>> site_pairs(planes.size(), {no_index, no_index});
  for (std::uint32_t p = 0; p < planes.size(); ++p) {
    if (p < box_base) site_pairs[p] = plane_pairs[p];
    if (p >= box_end) site_pairs[p] = plane_pairs[p - (box_end - box_base)];
  }
  make_definitions_canonical(cells, cell, site_pairs, input.geometry);

  // Round and certify every fragment, in parallel; then number them in site order.
  const PlaneSet set = input.geometry.plane_set(planes);
  std::vector<std::vector<detail::VoronoiFragment>> rounded(site_count);
  SolidMeshOptions meshing;
  meshing.attributes = &input.mesh;
  meshing.interior_uv_scale = recipe.interior_uv_scale;
  meshing.allow_self_intersections = recipe.allow_self_intersections;
  meshing.trusted = &mesh;
  // Indexed once, at the first fragment that needs it: certifying a fragment
  // otherwise indexes the whole input again.
  const TrustedTrianglesOnce input_triangles(mesh);
  meshing.trusted_triangles = &input_triangles;
  meshing.keep_vertex_map = true;  // for the union's face triangles (set_part_hints)
  arena.execute([&] {
    tbb::parallel_for(std::uint32_t{0}, site_count, [&](std::uint32_t s) {
      for (Solid& solid : cells[s]) {
        RoundedSolid r = round_solid(set, solid, meshing);
        rounded[s].push_back({std::move(solid), std::move(r)});
      }
      std::vector<Solid>().swap(cells[s]);
    });
  });

  std::vector<std::vector<detail::VoronoiFragment*>> kept_of(site_count);  // per site, its fragments
  for (std::uint32_t s = 0; s < site_count; ++s) {
    if (rounded[s].empty()) ++report.cells_empty;
    for (detail::VoronoiFragment& r : rounded[s]) {
      if (r.rounded.collapsed) {
        ++report.fragments_vanished;
        report.vanished_volume += r.rounded.moved_volume;
        report.vanished_volume_bound += r.rounded.moved_volume_bound;
        continue;
      }
      if (!r.rounded.defect.empty()) {
        throw UnsupportedGeometryError("the fragment of Voronoi site " + std::to_string(s) +
                                       " cannot be written as a valid mesh: " + r.rounded.defect);
      }
      kept_of[s].push_back(&r);
      if (r.rounded.attempt != 0) ++report.fragments_retried;
    }
    if (kept_of[s].size() > 1) ++report.cells_split;
  }
  report.seconds_cells = seconds_since(start);

  // The hierarchy (voronoi_hierarchy.hpp), and the tree made of it.
  auto phase = std::chrono::steady_clock::now();
  std::vector<detail::SiteGroup> groups;
  for (const Group& group : cutter.groups()) groups.push_back({group.begin, group.end, group.left, group.right});
  const detail::VoronoiHierarchyInput hierarchy{set, groups, cutter.order(), kept_of, site_pairs, points,
                                                quantized.step, meshing, run.lean};
  detail::HierarchyCounts counts;
  std::vector<detail::VoronoiPart> top;
  arena.execute([&] { top = detail::glue_voronoi_hierarchy(hierarchy, counts); });
  report.nodes_glued = counts.nodes_glued;
  report.sets_unglued = counts.sets_unglued;
  report.nodes_retried = counts.nodes_retried;
  report.seconds_glue = seconds_since(phase);
  MeshTree tree = detail::voronoi_tree_of_parts(mesh, input, recipe, top, planes, site_pairs);

  phase = std::chrono::steady_clock::now();
  // Internal nodes' hulls from their children's hulls, as a plane tree's (each
  // union vertex is a part's, rounded alike): on fandisk x4 at 10^4 sites a
  // third less time than hulls of the unions' own meshes, the same hulls.
  detail::tree_hulls(arena, tree);
  report.seconds_hulls = seconds_since(phase);
  phase = std::chrono::steady_clock::now();
  arena.execute([&] { tree.bonds = find_bonds(tree); });  // on the build's threads
  report.seconds_bonds = seconds_since(phase);
  if (run.lean) {
    for (MeshTreeNode& node : tree.nodes) std::vector<ApproxPoint>().swap(node.solid->approx);
  }
  // The tree passes validate_tree, caches included, by construction, as a plane
  // build's does (build.cpp; README "Certificates carried, not re-checked"):
  // the links, depths, leaf ranges, leaf list (preorder) and one zero plane per
  // node, then the cell planes, are written above; every cell plane is an exact
  // bisector of two distinct grid sites (finite, its normal 2 (q - p) h non-zero);
  // every mesh is the input (validated) or one round_solid certified valid as
  // written; every mass is mass_properties of the node's mesh; every hull is
  // one convex_hull_of built (tree_hulls) over a leaf's positions or an
  // internal node's children's hulls' points; find_bonds emits the bonds; every solid is the exact cut of
  // the input or a glue of such (check_solid-sound: tested on every node), its
  // planes input planes or cell planes renamed above, and every vertex's
  // approximation is approximate() of its definition over planes of the same
  // coefficients (recomputed where a definition was made canonical), or none in a
  // lean build. The writer would re-check all of that (6 % of `fracture` on
  // fandisk subdivided to 52k triangles at 10^4 sites); the certificate carries
  // it, bound to the content by a digest. tests/formats/test_tree_certificate.cpp
  // holds Voronoi trees to it.
  // A lean tree's leaves go packed, as a lean plane build leaves them
  // (BuildRunOptions::lean), before the one certificate: packed by the caller
  // (pack_leaves), the tree was digested twice more, to carry the certificate
  // across (2 % of `fracture` fandisk x4 at 10^4 sites); the same bytes.
  if (run.lean) pack_leaves(tree);
  detail::TreeCertifier::certify(tree, true);
  if (run.report) {
    run.report->cutting_seconds = report.seconds_cells + report.seconds_glue;
    run.report->hull_seconds = report.seconds_hulls;
    run.report->bond_seconds = report.seconds_bonds;
    run.report->pieces_vanished = report.fragments_vanished;
    run.report->vanished_volume = report.vanished_volume;
    run.report->vanished_volume_bound = report.vanished_volume_bound;
  }
  if (report_out) *report_out = report;
  return tree;
}

}  // namespace shatter
