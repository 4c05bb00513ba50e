#pragma once
// Bonds worked out by brute force, apart from find_bonds and find_plane_bonds,
// and the comparison of a tree's bonds with them. Header-only.
//
// - plane_reference_bonds: for a plane-kernel tree, from the leaves' exact solids.
//   For every internal node k and every pair of leaves below it on opposite sides
//   of its plane (by parent links, not leaf ranges), the exact area shared by
//   their faces lying on plane k. Each face is projected to 2D exactly (dropping
//   the coordinate of the normal's largest component). One face of a pair is cut
//   into convex pieces with signs (a face found convex here is one piece; any
//   other is the signed fan of triangles from its first corner, whose signed sum
//   is the face's indicator, holes included); the other face's loops are clipped
//   by each piece (Sutherland-Hodgman, whose signed area is exact for any
//   subject and a convex clipper), and the signed sum is the shared area. Points
//   are homogeneous coordinates in CGAL::Mpzf from their definitions
//   (support/exact_faces.hpp, not the kernel's evaluation), so the clipping is
//   exact ring arithmetic; areas are summed as GMP rationals. A pair is bonded
//   exactly when that area is positive: touching along an edge or at a point is
//   no bond.
// - mesh_reference_bonds: for a fast- or exact-kernel tree, from the leaf meshes'
//   cap triangles (surface id k + 1), intersected the same exact way.
// - bond_mismatch: what differs between a list of bonds and a reference: the
//   (first, second, cut) triples exactly, the areas within the tolerance below,
//   and the promised order, normals and centroids.

#include <CGAL/Mpzf.h>

#include <gmpxx.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "shatter/kernel/projection.hpp"
#include "shatter/meshtree/tree.hpp"
#include "support/checks.hpp"
#include "support/exact_faces.hpp"
#include "support/implicit_reference.hpp"

namespace shatter::test {

using BondKey = std::tuple<LeafIndex, LeafIndex, NodeIndex>;  // first < second, cut node

/// A bond as the brute force finds it.
struct ReferenceBond {
  double area = 0;       ///< in the plane (the exact projected area, rounded, times the projection's scale)
  double perimeter = 0;  ///< of the two leaves' faces on the cut, in the plane (rounded): for tolerances
  /// The overlap's bounding box in 3D (rounded outward by a few ulps): the
  /// centroid must lie in it.
  Vec3 lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
  /// The plane both faces lie on (a cut plane index) and whether `first` lies
  /// above it: set by plane_reference_bonds, for a cell plane (voronoi.hpp),
  /// whose bond names a node without that plane.
  std::uint32_t plane = 0;
  bool first_above = false;
};

/// What the brute force looked at, so a test can tell it was not vacuous.
struct ReferenceStats {
  std::size_t cuts = 0;           ///< internal nodes with faces on both sides
  std::size_t face_pairs = 0;     ///< cross-side face pairs whose boxes meet
  std::size_t touching_pairs = 0; ///< of those, leaf pairs whose faces meet in no area (edge or point contact, or apart)
  std::size_t face_problems = 0;  ///< faces on a cut facing the wrong way for their side (should be 0)
};

struct Reference {
  std::map<BondKey, ReferenceBond> bonds;
  ReferenceStats stats;
};

/// Which side of ancestor k's plane a leaf lies on, by walking parent links (not
/// by leaf ranges). Nullopt when k is not an ancestor of the leaf.
inline std::optional<bool> leaf_above(const MeshTree& tree, LeafIndex leaf, NodeIndex k) {
  for (NodeIndex n = tree.leaf_nodes[leaf]; tree.nodes[n].parent != no_node; n = tree.nodes[n].parent) {
    if (tree.nodes[n].parent == k) return tree.nodes[n].above_parent_plane;
  }
  return std::nullopt;
}

/// The node that holds two leaves apart: their lowest common ancestor, by parent links.
inline NodeIndex separating_ancestor(const MeshTree& tree, LeafIndex a, LeafIndex b) {
  std::vector<NodeIndex> above_a;
  for (NodeIndex n = tree.leaf_nodes[a]; n != no_node; n = tree.nodes[n].parent) above_a.push_back(n);
  for (NodeIndex n = tree.leaf_nodes[b]; n != no_node; n = tree.nodes[n].parent) {
    if (std::find(above_a.begin(), above_a.end(), n) != above_a.end()) return n;
  }
  return no_node;
}

/// Which side of cell plane k (voronoi.hpp: a cut plane past the nodes') a leaf
/// lies on, when it has a face on it: the exact side of its first vertex off the
/// plane (by the leaf's geometry, not its faces' orientation). Nullopt otherwise.
inline std::optional<bool> leaf_above_cell_plane(const MeshTree& tree, const PlaneSet& set, LeafIndex leaf,
                                                 std::uint32_t k, const Q4& h) {
  const Solid& solid = tree.leaf(leaf).solid;
  const bool on_it = std::any_of(solid.faces.begin(), solid.faces.end(),
                                 [&](const SolidFace& face) { return face.plane == PlaneRef::cut(k); });
  if (!on_it) return std::nullopt;
  for (const PointDef& def : solid.defs) {
    const Q3 q = rational(homogeneous(set, def));
    const int s = sgn(mpq_class(h.a * q.x + h.b * q.y + h.c * q.z + h.d));
    if (s != 0) return s > 0;
  }
  return std::nullopt;
}

namespace reference_detail {

// A point of the projection in homogeneous coordinates: (u / w, v / w), exact
// in CGAL::Mpzf, so orientations and the clipping's new points cost no gcd.
struct P2 {
  CGAL::Mpzf u, v, w;
};

inline int sign(const CGAL::Mpzf& x) { return static_cast<int>(CGAL::sign(x)); }

// Orientation of (a, b, c): the sign of det[a; b; c] times those of the w's.
inline int orient(const P2& a, const P2& b, const P2& c) {
  const CGAL::Mpzf det = a.u * (b.v * c.w - b.w * c.v) - a.v * (b.u * c.w - b.w * c.u) + a.w * (b.u * c.v - b.v * c.u);
  return sign(det) * sign(a.w) * sign(b.w) * sign(c.w);
}

// The line through two points, l = from x to, with the sign that orients it.
struct Line {
  CGAL::Mpzf a, b, c;
  int sign;
  CGAL::Mpzf at(const P2& p) const { return a * p.u + b * p.v + c * p.w; }
  // Positive left of from -> to.
  int side(const P2& p) const { return reference_detail::sign(at(p)) * sign * reference_detail::sign(p.w); }
};
inline Line line_through(const P2& from, const P2& to) {
  return {from.v * to.w - from.w * to.v, from.w * to.u - from.u * to.w, from.u * to.v - from.v * to.u,
          sign(from.w) * sign(to.w)};
}

// A box of exact 2D points, rounded outward (a conservative filter only).
struct Box2 {
  double lo_u = INFINITY, hi_u = -INFINITY, lo_v = INFINITY, hi_v = -INFINITY;
  void add(const mpq_class& pu, const mpq_class& pv) {
    const double u = pu.get_d(), v = pv.get_d();  // within an ulp
    const double eu = 4 * std::numeric_limits<double>::epsilon() * std::fabs(u) + 1e-300;
    const double ev = 4 * std::numeric_limits<double>::epsilon() * std::fabs(v) + 1e-300;
    lo_u = std::min(lo_u, u - eu);
    hi_u = std::max(hi_u, u + eu);
    lo_v = std::min(lo_v, v - ev);
    hi_v = std::max(hi_v, v + ev);
  }
  void add(const Box2& o) {
    lo_u = std::min(lo_u, o.lo_u);
    hi_u = std::max(hi_u, o.hi_u);
    lo_v = std::min(lo_v, o.lo_v);
    hi_v = std::max(hi_v, o.hi_v);
  }
  bool meets(const Box2& o) const { return lo_u <= o.hi_u && o.lo_u <= hi_u && lo_v <= o.hi_v && o.lo_v <= hi_v; }
};

// A convex polygon, counter-clockwise in the projection, and the sign it enters
// its face's indicator with: a convex face is one piece (+1); another face is
// the signed fan of triangles from its first corner over its loops (oriented to
// wind once counter-clockwise), whose signed sum is the face's indicator, holes
// included, up to a set of no area.
struct Piece {
  std::vector<P2> polygon;
  int sign;
  Box2 box;
};

struct CapFace {
  LeafIndex leaf;
  bool above;
  std::vector<Piece> pieces;
  std::vector<std::vector<P2>> loops;  // oriented so that the face winds once counter-clockwise
  std::vector<Box2> loop_boxes;
  Box2 box;
  double perimeter;  // in the projection
};

// The polygon `subject` clipped by the convex, counter-clockwise polygon
// `clipper` (Sutherland-Hodgman, exact). For a subject that is not convex the
// result may run along the clipper's edges and back, which adds no area: its
// signed area is still that of the subject's winding inside the clipper. A new
// point where p -> q crosses the line l is (l·q) p - (l·p) q.
inline std::vector<P2> clip(const std::vector<P2>& subject, const std::vector<P2>& clipper) {
  std::vector<P2> polygon = subject, kept;
  std::vector<int> sides;
  for (std::size_t e = 0; e < clipper.size() && !polygon.empty(); ++e) {
    const Line line = line_through(clipper[e], clipper[(e + 1) % clipper.size()]);
    sides.clear();
    for (const P2& p : polygon) sides.push_back(line.side(p));
    kept.clear();
    for (std::size_t i = 0; i < polygon.size(); ++i) {
      const std::size_t j = (i + 1) % polygon.size();
      const P2& p = polygon[i];
      const P2& q = polygon[j];
      if (sides[i] >= 0) kept.push_back(p);
      if (sides[i] * sides[j] < 0) {
        const CGAL::Mpzf lp = line.at(p), lq = line.at(q);
        kept.push_back({lq * p.u - lp * q.u, lq * p.v - lp * q.v, lq * p.w - lp * q.w});
      }
    }
    polygon.swap(kept);
  }
  return polygon;
}

// Whether some edge line of counter-clockwise convex polygon `a` has all of `b`
// on its closed outer side (then `b` adds no area inside `a`).
inline bool separated(const std::vector<P2>& a, const std::vector<P2>& b) {
  for (std::size_t e = 0; e < a.size(); ++e) {
    const Line line = line_through(a[e], a[(e + 1) % a.size()]);
    bool all_out = true;
    for (std::size_t c = 0; c < b.size() && all_out; ++c) all_out = line.side(b[c]) <= 0;
    if (all_out) return true;
  }
  return false;
}

// Twice the signed area, exactly: the shoelace over the points as rationals.
inline mpq_class twice_area(const std::vector<P2>& polygon) {
  std::vector<std::pair<mpq_class, mpq_class>> q;
  for (const P2& p : polygon) {
    const mpq_class w = static_cast<mpq_class>(p.w);
    q.emplace_back(static_cast<mpq_class>(p.u) / w, static_cast<mpq_class>(p.v) / w);
  }
  mpq_class twice = 0;
  for (std::size_t i = 0; i < q.size(); ++i) {
    const auto& a = q[i];
    const auto& b = q[(i + 1) % q.size()];
    twice += a.first * b.second - a.second * b.first;
  }
  return twice;
}

}  // namespace reference_detail

/// The exact brute force for a plane-kernel tree (see the file comment).
inline Reference plane_reference_bonds(const MeshTree& tree) {
  using namespace reference_detail;
  Reference reference;
  const PlaneSet set = tree.plane_set();
  // Node planes, then a cell tree's cell planes (voronoi.hpp).
  for (std::uint32_t k = 0; k < tree.cut_planes.size(); ++k) {
    const bool cell_plane = k >= tree.nodes.size();
    if (!cell_plane && tree.nodes[k].is_leaf()) continue;
    const PlaneRef cut = PlaneRef::cut(k);
    const Q4 h = reference_plane(set, cut);
    const mpq_class n[3] = {h.a, h.b, h.c};
    int axis = 0;
    for (int a = 1; a < 3; ++a) {
      if (abs(n[a]) > abs(n[axis])) axis = a;
    }
    // A Voronoi hierarchy's glued node was cut by no plane (voronoi_hierarchy.cpp pushes a
    // zero one): nothing is bonded across it. Its scale below would be 0 / 0,
    // which trapped once the test files compiled at -O0 under the sanitizers
    // (at -O1 the unused division was never reached).
    if (sgn(n[axis]) == 0) continue;
    const int iu = (axis + 1) % 3, iv = (axis + 2) % 3;
    const double scale = std::sqrt(mpq_class(h.a * h.a + h.b * h.b + h.c * h.c).get_d()) / std::fabs(n[axis].get_d());
    std::vector<CapFace> faces;
    std::map<LeafIndex, std::vector<Vec3>> points_on_cut;  // rounded, for the overlap's 3D box
    for (LeafIndex leaf = 0; leaf < tree.leaf_count(); ++leaf) {
      const std::optional<bool> above =
          cell_plane ? leaf_above_cell_plane(tree, set, leaf, k, h) : leaf_above(tree, leaf, k);
      if (!above) continue;
      const Solid& solid = tree.leaf(leaf).solid;
      struct Projected {
        P2 point;
        Box2 box;
      };
      std::map<VertexIndex, Projected> projected;
      const auto point = [&](VertexIndex v) -> const Projected& {
        auto it = projected.find(v);
        if (it == projected.end()) {
          const H4 x = homogeneous(set, solid.defs[v]);
          const Q3 q = rational(x);
          const CGAL::Mpzf c[3] = {x.x, x.y, x.z};
          const mpq_class r[3] = {q.x, q.y, q.z};
          Projected projected_point{{c[iu], c[iv], x.w}, {}};
          projected_point.box.add(r[iu], r[iv]);
          it = projected.emplace(v, projected_point).first;
          points_on_cut[leaf].push_back({q.x.get_d(), q.y.get_d(), q.z.get_d()});
        }
        return it->second;
      };
      for (const SolidFace& face : solid.faces) {
        if (!(face.plane == cut)) continue;
        // Below the plane a leaf's face on it faces +n; above, -n.
        if (face.reversed != *above) ++reference.stats.face_problems;
        CapFace cap{leaf, *above, {}, {}, {}, {}, 0};
        std::vector<std::vector<P2>> loops;
        std::vector<std::vector<Box2>> boxes;  // each corner's
        mpq_class twice = 0;
        for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
          const SolidLoop& loop = solid.loops[l];
          loops.emplace_back();
          boxes.emplace_back();
          cap.loop_boxes.emplace_back();
          for (std::uint32_t i = 0; i < loop.corner_count; ++i) {
            const Projected& corner = point(solid.corners[loop.first_corner + i].vertex);
            loops.back().push_back(corner.point);
            boxes.back().push_back(corner.box);
            cap.loop_boxes.back().add(corner.box);
          }
          cap.box.add(cap.loop_boxes.back());
          twice += twice_area(loops.back());
          for (std::size_t i = 0; i < boxes.back().size(); ++i) {
            const Box2& a = boxes.back()[i];
            const Box2& b = boxes.back()[(i + 1) % boxes.back().size()];
            // Rounded; an edge's length within a few ulps (only for the tolerance).
            cap.perimeter += std::hypot(b.lo_u - a.lo_u, b.lo_v - a.lo_v);
          }
        }
        // The face's orientation in the projection: its loops' signed area.
        const int face_sign = sgn(twice);
        bool convex = loops.size() == 1;
        for (std::size_t i = 0; convex && i < loops[0].size(); ++i) {
          const std::vector<P2>& loop = loops[0];
          convex = orient(loop[i], loop[(i + 1) % loop.size()], loop[(i + 2) % loop.size()]) * face_sign >= 0;
        }
        if (face_sign < 0) {
          for (std::size_t l = 0; l < loops.size(); ++l) {
            std::reverse(loops[l].begin(), loops[l].end());
            std::reverse(boxes[l].begin(), boxes[l].end());
          }
        }
        if (convex) {
          cap.pieces.push_back({loops[0], 1, cap.box});
        } else {
          const P2& origin = loops[0][0];
          for (std::size_t l = 0; l < loops.size(); ++l) {
            const std::vector<P2>& loop = loops[l];
            for (std::size_t i = 0; i < loop.size(); ++i) {
              const std::size_t j = (i + 1) % loop.size();
              const int s = orient(origin, loop[i], loop[j]);
              if (s == 0) continue;
              Piece piece{s > 0 ? std::vector<P2>{origin, loop[i], loop[j]} : std::vector<P2>{origin, loop[j], loop[i]}, s,
                          boxes[0][0]};
              piece.box.add(boxes[l][i]);
              piece.box.add(boxes[l][j]);
              cap.pieces.push_back(std::move(piece));
            }
          }
        }
        cap.loops = std::move(loops);
        faces.push_back(std::move(cap));
      }
    }
    std::map<std::pair<LeafIndex, LeafIndex>, mpq_class> shared;  // (below, above) -> twice the projected area
    std::map<std::pair<LeafIndex, LeafIndex>, double> perimeter;
    bool any_pair = false;
    for (const CapFace& below : faces) {
      if (below.above) continue;
      for (const CapFace& above : faces) {
        if (!above.above || !below.box.meets(above.box)) continue;
        any_pair = true;
        ++reference.stats.face_pairs;
        mpq_class& total = shared[{below.leaf, above.leaf}];
        perimeter[{below.leaf, above.leaf}] += below.perimeter + above.perimeter;
        // One face as its pieces, the other as its loops clipped by each piece:
        // the face with fewer pieces (a convex face is one) is cut up.
        const bool below_cut_up = below.pieces.size() <= above.pieces.size();
        const CapFace& cut_up = below_cut_up ? below : above;
        const CapFace& whole = below_cut_up ? above : below;
        for (const Piece& piece : cut_up.pieces) {
          if (!piece.box.meets(whole.box)) continue;
          for (std::size_t l = 0; l < whole.loops.size(); ++l) {
            if (!piece.box.meets(whole.loop_boxes[l]) || separated(piece.polygon, whole.loops[l])) continue;
            total += piece.sign * twice_area(clip(whole.loops[l], piece.polygon));
          }
        }
      }
    }
    reference.stats.cuts += any_pair;
    for (const auto& [pair, twice] : shared) {
      if (sgn(twice) <= 0) {
        ++reference.stats.touching_pairs;
        continue;
      }
      const auto [below, above] = pair;
      ReferenceBond bond;
      bond.area = mpq_class(twice / 2).get_d() * scale;
      bond.perimeter = perimeter[pair] * scale;
      // The overlap lies in both leaves' faces on the cut: in both boxes.
      for (int a = 0; a < 3; ++a) {
        double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
        for (int side = 0; side < 2; ++side) {
          for (const Vec3& q : points_on_cut[side == 0 ? below : above]) {
            lo[side] = std::min(lo[side], q[a]);
            hi[side] = std::max(hi[side], q[a]);
          }
        }
        const double l = std::max(lo[0], lo[1]), u = std::min(hi[0], hi[1]);
        const double pad = 4 * std::numeric_limits<double>::epsilon() * std::max(std::fabs(l), std::fabs(u));
        (a == 0 ? bond.lo.x : a == 1 ? bond.lo.y : bond.lo.z) = l - pad;
        (a == 0 ? bond.hi.x : a == 1 ? bond.hi.y : bond.hi.z) = u + pad;
      }
      const NodeIndex cut_node = cell_plane ? separating_ancestor(tree, below, above) : k;
      bond.plane = k;
      bond.first_above = above < below;
      reference.bonds[{std::min(below, above), std::max(below, above), cut_node}] = bond;
    }
  }
  return reference;
}

/// The brute force for a fast- or exact-kernel tree: every cross-side pair of
/// cap triangles of every cut (surface id k + 1 on the leaf meshes), projected
/// and intersected exactly (the clipping above, on the doubles as they are),
/// with only a closed box filter, which cannot miss a shared area.
inline Reference mesh_reference_bonds(const MeshTree& tree) {
  using namespace reference_detail;
  struct Cap {
    LeafIndex leaf;
    std::vector<P2> triangle;  // counter-clockwise in the projection
    Box2 box;
    std::array<Vec3, 3> corners;
  };
  Reference reference;
  for (NodeIndex k = 0; k < tree.nodes.size(); ++k) {
    const MeshTreeNode& node = tree.nodes[k];
    if (node.is_leaf()) continue;
    const Plane& plane = tree.cut_planes[k];
    const PlaneProjection projection = PlaneProjection::of(plane);
    const int dropped = 3 - projection.u_axis - projection.v_axis;
    const double scale = norm(plane.normal) / std::fabs(plane.normal[dropped]);
    std::vector<Cap> below, above;
    for (LeafIndex leaf = 0; leaf < tree.leaf_count(); ++leaf) {
      const std::optional<bool> side = leaf_above(tree, leaf, k);
      if (!side) continue;
      const Mesh& mesh = tree.leaf(leaf).mesh;
      for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
        if (mesh.surfaces[t] != cap_surface_of(k)) continue;
        Cap cap{leaf, {}, {}, {}};
        for (int c = 0; c < 3; ++c) {
          cap.corners[c] = mesh.positions[mesh.triangles[t][c]];
          const Vec2 q = projection(cap.corners[c]);
          cap.triangle.push_back({CGAL::Mpzf(q.x), CGAL::Mpzf(q.y), CGAL::Mpzf(1)});
          cap.box.add(mpq_class(q.x), mpq_class(q.y));
        }
        const int turn = orient(cap.triangle[0], cap.triangle[1], cap.triangle[2]);
        if (turn == 0) continue;  // no interior in the projection
        if (turn < 0) std::swap(cap.triangle[1], cap.triangle[2]);
        (*side ? above : below).push_back(std::move(cap));
      }
    }
    std::map<std::pair<LeafIndex, LeafIndex>, mpq_class> areas;
    std::map<std::pair<LeafIndex, LeafIndex>, ReferenceBond> found;
    reference.stats.cuts += !below.empty() && !above.empty();
    for (const Cap& b : below) {
      for (const Cap& a : above) {
        if (!b.box.meets(a.box)) continue;
        ++reference.stats.face_pairs;
        if (separated(b.triangle, a.triangle) || separated(a.triangle, b.triangle)) continue;
        const mpq_class twice = twice_area(clip(b.triangle, a.triangle));
        if (sgn(twice) <= 0) continue;
        const std::pair<LeafIndex, LeafIndex> pair{std::min(a.leaf, b.leaf), std::max(a.leaf, b.leaf)};
        areas[pair] += twice;
        ReferenceBond& bond = found[pair];
        for (int c = 0; c < 3; ++c) {
          bond.perimeter += norm(b.corners[c] - b.corners[(c + 1) % 3]) + norm(a.corners[c] - a.corners[(c + 1) % 3]);
        }
        // Loosely: the union of the two triangles' boxes (the overlap is in both).
        for (const auto* cap : {&a, &b}) {
          for (const Vec3& p : cap->corners) {
            bond.lo = {std::min(bond.lo.x, p.x), std::min(bond.lo.y, p.y), std::min(bond.lo.z, p.z)};
            bond.hi = {std::max(bond.hi.x, p.x), std::max(bond.hi.y, p.y), std::max(bond.hi.z, p.z)};
          }
        }
      }
    }
    for (auto& [pair, bond] : found) {
      bond.area = mpq_class(areas.at(pair) / 2).get_d() * scale;
      reference.bonds[{pair.first, pair.second, k}] = bond;
    }
  }
  return reference;
}

/// The area tolerance of a bond: the rounded overlap find_plane_bonds and
/// find_bonds measure has its corners within a few ulps of the largest
/// coordinate L of the tree (x/w rounded, or the fast kernel's rounded cut
/// points) of the exact ones, and moving a polygon's corners by d changes its
/// area by at most d times its perimeter, which is at most the sum of the two
/// caps' perimeters P; the clipping in doubles adds rounding of relative order
/// 1e-16 per operation. 64 ulps of L times P, plus 1e-9 of the area, bounds both
/// with room.
inline double bond_area_tolerance(const ReferenceBond& bond, double largest) {
  return 64 * std::numeric_limits<double>::epsilon() * largest * bond.perimeter + 1e-9 * bond.area;
}

/// The largest absolute coordinate of the tree's root mesh.
inline double tree_largest_coordinate(const MeshTree& tree) { return largest_coordinate(tree.nodes[0].mesh); }

/// Empty when `bonds` are exactly the reference's (first, second, cut) triples,
/// sorted without duplicates, each with its area within bond_area_tolerance, a
/// unit normal pointing from first into second, and a centroid on the cut's plane
/// inside the overlap's box; else the number of differences and the first few.
inline std::string bond_mismatch(const MeshTree& tree, const std::vector<Bond>& bonds, const Reference& reference) {
  std::ostringstream out;
  std::size_t problems = 0;
  const auto problem = [&](const std::string& text) {
    if (++problems <= 6) out << "\n    " << text;
  };
  const double largest = tree_largest_coordinate(tree);
  const auto name = [](const BondKey& key) {
    return std::to_string(std::get<0>(key)) + "-" + std::to_string(std::get<1>(key)) + " on cut " +
           std::to_string(std::get<2>(key));
  };
  std::map<BondKey, const Bond*> found;
  for (std::size_t i = 0; i < bonds.size(); ++i) {
    const Bond& bond = bonds[i];
    const BondKey key{bond.first, bond.second, bond.cut_node};
    if (bond.first >= bond.second) problem("bond " + name(key) + ": first not below second");
    if (i > 0) {
      const Bond& previous = bonds[i - 1];
      if (!(std::tie(previous.first, previous.second, previous.cut_node) < key)) {
        problem("bond " + name(key) + ": out of order or repeated");
      }
    }
    found[key] = &bond;
    const auto expected = reference.bonds.find(key);
    if (expected == reference.bonds.end()) {
      problem("bond " + name(key) + " is not in the brute force (area " + std::to_string(bond.area) + ")");
      continue;
    }
    const ReferenceBond& ref = expected->second;
    const double tolerance = bond_area_tolerance(ref, largest);
    if (!(std::fabs(bond.area - ref.area) <= tolerance)) {
      std::ostringstream text;
      text.precision(17);
      text << "bond " << name(key) << ": area " << bond.area << ", brute force " << ref.area << " (tolerance "
           << tolerance << ")";
      problem(text.str());
    }
    const bool on_cell_plane = ref.plane >= tree.nodes.size();
    const Plane& cut_plane = tree.cut_planes[on_cell_plane ? ref.plane : bond.cut_node];
    const std::optional<bool> first_above =
        on_cell_plane ? std::optional<bool>(ref.first_above) : leaf_above(tree, bond.first, bond.cut_node);
    const Vec3 unit = normalized(cut_plane.normal);
    if (!first_above || !(dot(bond.normal, *first_above ? -unit : unit) > 1 - 1e-12) ||
        !(std::fabs(norm(bond.normal) - 1) < 1e-12)) {
      problem("bond " + name(key) + ": normal not the unit normal from first into second");
    }
    const double pad = 64 * std::numeric_limits<double>::epsilon() * largest;
    const double distance = (dot(cut_plane.normal, bond.centroid) + cut_plane.offset) / norm(cut_plane.normal);
    bool in_box = std::fabs(distance) <= pad;
    for (int a = 0; a < 3; ++a) in_box = in_box && bond.centroid[a] >= ref.lo[a] - pad && bond.centroid[a] <= ref.hi[a] + pad;
    if (!in_box) problem("bond " + name(key) + ": centroid off the plane or outside the overlap");
  }
  for (const auto& [key, ref] : reference.bonds) {
    if (found.count(key) == 0) problem("bond " + name(key) + " of the brute force is missing (area " + std::to_string(ref.area) + ")");
  }
  if (problems == 0) return {};
  return std::to_string(problems) + " difference(s) from the brute force's " + std::to_string(reference.bonds.size()) +
         " bonds:" + out.str();
}

/// A check of bonds for trees too large for the brute force, still apart from
/// find_bonds: every bond joins two leaves on opposite sides of its cut, and on
/// every cut the bonds' areas add up to the cap's area. The caps of one cut are
/// the same region seen from both sides and the leaves' overlaps tile it, so a
/// missing or wrong bond shows in the sum unless its area is below the
/// tolerance. The cap area is taken from the cut node's children (their faces
/// on the plane for the plane kernel, their cap triangles otherwise), rounded;
/// the tolerance is 1e-9 of it plus 64 ulps of the largest coordinate times
/// the cap's perimeter (the rounding of its corners).
inline std::string bond_sum_problem(const MeshTree& tree, const std::vector<Bond>& bonds) {
  std::ostringstream out;
  std::size_t problems = 0;
  const auto problem = [&](const std::string& text) {
    if (++problems <= 6) out << "\n    " << text;
  };
  std::vector<double> bonded(tree.nodes.size(), 0.0);
  for (const Bond& bond : bonds) {
    if (bond.cut_node >= tree.nodes.size() || bond.second >= tree.leaf_count() || bond.first >= bond.second) {
      problem("bond out of range");
      continue;
    }
    const std::optional<bool> a = leaf_above(tree, bond.first, bond.cut_node);
    const std::optional<bool> b = leaf_above(tree, bond.second, bond.cut_node);
    if (!a || !b || *a == *b) problem("a bond on cut " + std::to_string(bond.cut_node) + " not across it");
    bonded[bond.cut_node] += bond.area;
  }
  const double largest = tree_largest_coordinate(tree);
  for (NodeIndex k = 0; k < tree.nodes.size(); ++k) {
    if (tree.nodes[k].is_leaf()) continue;
    double area = 0, perimeter = 0;
    for (const NodeIndex child : tree.nodes[k].children) {
      if (tree.nodes[child].above_parent_plane) continue;
      if (tree.has_exact_representation()) {
        const Solid& solid = tree.nodes[child].solid;
        const auto at = [&](VertexIndex v) {
          const ApproxPoint& p = solid.approx[v];
          return Vec3{p.x.value / p.w.value, p.y.value / p.w.value, p.z.value / p.w.value};
        };
        for (const SolidFace& face : solid.faces) {
          if (!(face.plane == PlaneRef::cut(k))) continue;
          Vec3 twice;
          const Vec3 origin = at(solid.corners[solid.loops[face.first_loop].first_corner].vertex);
          for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
            const SolidLoop& loop = solid.loops[l];
            for (std::uint32_t i = 0; i < loop.corner_count; ++i) {
              const Vec3 a = at(solid.corners[loop.first_corner + i].vertex) - origin;
              const Vec3 b = at(solid.corners[loop.first_corner + (i + 1) % loop.corner_count].vertex) - origin;
              twice = twice + cross(a, b);
              perimeter += norm(b - a);
            }
          }
          area += norm(twice) / 2;
        }
      } else {
        const Mesh& mesh = tree.nodes[child].mesh;
        for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
          if (mesh.surfaces[t] != cap_surface_of(k)) continue;
          const Vec3 a = mesh.positions[mesh.triangles[t][0]], b = mesh.positions[mesh.triangles[t][1]],
                     c = mesh.positions[mesh.triangles[t][2]];
          area += norm(cross(b - a, c - a)) / 2;
          perimeter += norm(b - a) + norm(c - b) + norm(a - c);
        }
      }
    }
    const double tolerance = 1e-9 * area + 64 * std::numeric_limits<double>::epsilon() * largest * perimeter;
    if (!(std::fabs(bonded[k] - area) <= tolerance)) {
      std::ostringstream text;
      text.precision(17);
      text << "cut " << k << ": bonds' areas sum to " << bonded[k] << ", its cap has " << area;
      problem(text.str());
    }
  }
  if (problems == 0) return {};
  return std::to_string(problems) + " problem(s):" + out.str();
}

}  // namespace shatter::test
