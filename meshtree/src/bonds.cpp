#include "shatter/meshtree/bonds.hpp"

#include <CGAL/box_intersection_d.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>
#include <span>

#include "shatter/kernel/predicates.hpp"
#include "shatter/kernel/projection.hpp"
#include "shatter/meshtree/tree.hpp"
#include "clip2d.hpp"

namespace shatter {
namespace {

using detail::Clipper;
using detail::cross;

// --- exact orientation ----------------------------------------------------------

// Error-free transformations (Shewchuk, "Adaptive precision floating-point
// arithmetic and fast robust geometric predicates", 1997): hi + lo equals the
// exact result. They need round-to-nearest doubles and no overflow or underflow,
// which the caller ensures.
struct TwoTerm {
  double hi, lo;
};
TwoTerm two_sum(double a, double b) {
  const double x = a + b, b_virtual = x - a, a_virtual = x - b_virtual;
  return {x, (a - a_virtual) + (b - b_virtual)};
}
TwoTerm two_diff(double a, double b) {
  const double x = a - b, b_virtual = a - x, a_virtual = x + b_virtual;
  return {x, (a - a_virtual) + (b_virtual - b)};
}
TwoTerm split(double a) {
  constexpr double splitter = 134217729.0;  // 2^27 + 1
  const double c = splitter * a, big = c - a, hi = c - big;
  return {hi, a - hi};
}
TwoTerm two_product(double a, double b) {
  const double x = a * b;
  const TwoTerm as = split(a), bs = split(b);
  const double error = x - as.hi * bs.hi - as.lo * bs.hi - as.hi * bs.lo;
  return {x, as.lo * bs.lo - error};
}

// The sign of (a1 + a0) - (b1 + b0) for two 2-term expansions, exactly: their
// difference as a 4-term non-overlapping expansion (Shewchuk's Two_Two_Diff),
// whose sign is that of its largest non-zero term.
Sign sign_of_difference(TwoTerm a, TwoTerm b) {
  const TwoTerm low = two_diff(a.lo, b.lo);
  const TwoTerm mid = two_sum(a.hi, low.hi);
  const TwoTerm next = two_diff(mid.lo, b.hi);
  const TwoTerm top = two_sum(mid.hi, next.hi);
  for (const double term : {top.hi, top.lo, next.lo, low.lo}) {
    if (term > 0) return Sign::positive;
    if (term < 0) return Sign::negative;
  }
  return Sign::zero;
}

// The exact orientation of (a, b, c). Caps on the two sides of a cut share
// vertices, and sliced faces have long runs of nearly collinear corners, so
// undecided cases are the rule here, not the exception; the kernel's orient2d
// would settle each in arbitrary precision. In front of it:
//   1. Shewchuk's floating-point filter (c as the base point, so a point tested
//      against an edge it ends gives an exact zero);
//   2. when the four coordinate differences are exact (points near each other,
//      as near-collinear ones are), the determinant's exact sign from two exact
//      products.
// Magnitudes are kept where neither step can overflow or underflow; anything
// else goes to orient2d.
Sign orientation(Vec2 a, Vec2 b, Vec2 c) {
  const double acx = a.x - c.x, bcx = b.x - c.x, acy = a.y - c.y, bcy = b.y - c.y;
  constexpr double smallest = 0x1p-450, largest = 0x1p450;
  const auto in_range = [](double difference) {
    const double magnitude = std::fabs(difference);
    return magnitude == 0 || (magnitude >= smallest && magnitude <= largest);
  };
  if (!in_range(acx) || !in_range(bcx) || !in_range(acy) || !in_range(bcy)) return orient2d(a, b, c);
  // Differences of doubles carry their true signs, and in this range so do products.
  const double detleft = acx * bcy, detright = acy * bcx;
  double detsum;
  if (detleft > 0) {
    if (detright <= 0) return Sign::positive;
    detsum = detleft + detright;
  } else if (detleft < 0) {
    if (detright >= 0) return Sign::negative;
    detsum = -detleft - detright;
  } else {
    return detright > 0 ? Sign::negative : detright < 0 ? Sign::positive : Sign::zero;
  }
  constexpr double epsilon = 0x1p-53;
  constexpr double error_bound = (3.0 + 16.0 * epsilon) * epsilon;  // Shewchuk's ccwerrboundA
  const double det = detleft - detright;
  if (det >= error_bound * detsum) return Sign::positive;
  if (-det >= error_bound * detsum) return Sign::negative;
  if (two_diff(a.x, c.x).lo == 0 && two_diff(b.x, c.x).lo == 0 && two_diff(a.y, c.y).lo == 0 &&
      two_diff(b.y, c.y).lo == 0) {
    return sign_of_difference(two_product(acx, bcy), two_product(acy, bcx));
  }
  return orient2d(a, b, c);
}

// --- faces ------------------------------------------------------------------------

// A leaf's cap on one cut: all its cap triangles of that cut. Caps come sliced by
// every later cut, so a face is often dozens of slivers fanning out from its
// corners, and testing those pairwise against the other side's would cost far
// more than the faces themselves. A face is therefore tested as a whole first,
// through its convex hull, and triangle by triangle only where that cannot decide
// (CutBonds).
struct Face {
  NodeIndex cut;
  LeafIndex leaf;
  bool above;
  /// The triangles fill the hull up to rounding (see hull_fill_tolerance): the
  /// overlap of two such faces is measured on their outlines.
  bool fills_hull;
  std::uint32_t first_triangle, triangle_count;  // into Faces::triangles
  std::uint32_t first_hull_corner, hull_corner_count;  // into Faces::hull_corners
  std::uint32_t first_outline_corner, outline_corner_count;  // into Faces::outline_corners
  double min_u, max_u, min_v, max_v;
};

struct Faces {
  std::vector<Face> faces;
  /// Every face's cap triangles, as indices into its leaf's mesh.
  std::vector<TriangleIndex> triangles;
  std::vector<Vec2> hull_corners;  ///< counter-clockwise, strictly convex
  /// The hull without the corners rounding made (see outline_tolerance): what
  /// overlaps are measured on, never decided on.
  std::vector<Vec2> outline_corners;
  std::vector<std::uint32_t> order;  ///< face indices, cut by cut
  std::vector<std::size_t> start;    ///< cut k's faces are order[start[k], start[k + 1])

  std::span<const TriangleIndex> triangles_of(const Face& face) const {
    return {triangles.data() + face.first_triangle, face.triangle_count};
  }
  std::span<const Vec2> hull_of(const Face& face) const {
    return {hull_corners.data() + face.first_hull_corner, face.hull_corner_count};
  }
  std::span<const Vec2> outline_of(const Face& face) const {
    return {outline_corners.data() + face.first_outline_corner, face.outline_corner_count};
  }
};


// Twice the area of a counter-clockwise polygon, fanned from its first corner so
// that no large products are summed.
double twice_area_of(std::span<const Vec2> polygon) {
  double twice = 0;
  for (std::size_t i = 1; i + 1 < polygon.size(); ++i) twice += cross(polygon[0], polygon[i], polygon[i + 1]);
  return twice;
}

// The relative shortfall below which a face's triangles count as filling its
// hull. It only chooses how an overlap is measured, never whether one exists:
// rounding moves the cut points that subdivide a face's edges by an ulp or so,
// which makes a convex face non-convex by areas near 1e-16 of its own; a face
// that is truly non-convex misses its hull by far more.
constexpr double hull_fill_tolerance = 1e-12;

// A hull corner whose turn spans less than this fraction of the hull's area is
// left out of the outline the overlaps are measured on. Rounded cut points make
// hulls of sliced faces carry such corners by the handful; each changes a measured
// area by no more than that fraction, and dropping them halves the clipping work.
constexpr double outline_tolerance = 1e-13;

// Builds faces from the leaves, then groups them by cut (a counting sort).
class FaceBuilder {
 public:
  Faces build(const MeshTree& tree, const std::vector<PlaneProjection>& projections) {
    Faces result;
    std::size_t triangle_count = 0;
    for (LeafIndex leaf = 0; leaf < tree.leaf_count(); ++leaf) triangle_count += tree.leaf(leaf).mesh.triangle_count();
    result.triangles.reserve(triangle_count);
    for (LeafIndex leaf = 0; leaf < tree.leaf_count(); ++leaf) {
      const Mesh& mesh = tree.leaf(leaf).mesh;
      // (cut, triangle) packed in one integer: sorting them groups a face.
      caps_.clear();
      // A leaf has a few surfaces over many triangles: looking each up once
      // spares a visit to a (large, far away) tree node per triangle.
      SurfaceId cached_surface = original_surface;
      NodeIndex cached_cut = no_node;
      for (TriangleIndex t = 0; t < mesh.triangles.size(); ++t) {
        const SurfaceId surface = mesh.surfaces[t];
        if (surface == original_surface) continue;
        if (surface != cached_surface) {
          cached_surface = surface;
          cached_cut = cut_of(tree, surface, leaf);
        }
        if (cached_cut != no_node) caps_.push_back(std::uint64_t{cached_cut} << 32 | t);
      }
      std::sort(caps_.begin(), caps_.end());
      vertex_stamp_.assign(mesh.vertex_count(), no_stamp);
      for (std::size_t i = 0; i < caps_.size();) {
        const auto cut = static_cast<NodeIndex>(caps_[i] >> 32);
        std::size_t end = i;
        while (end < caps_.size() && caps_[end] >> 32 == cut) ++end;
        add_face(mesh, std::span(caps_).subspan(i, end - i), projections[cut], cut, leaf,
                 leaf_is_above(tree, cut, leaf), result);
        i = end;
      }
    }
    result.start.assign(tree.nodes.size() + 1, 0);
    for (const Face& face : result.faces) ++result.start[face.cut + 1];
    for (std::size_t k = 0; k < tree.nodes.size(); ++k) result.start[k + 1] += result.start[k];
    result.order.resize(result.faces.size());
    std::vector<std::size_t> next(result.start.begin(), result.start.end() - 1);
    for (std::uint32_t f = 0; f < result.faces.size(); ++f) result.order[next[result.faces[f].cut]++] = f;
    return result;
  }

 private:
  // Which side of internal node `cut`'s plane `leaf` lies on: the side of the
  // child whose range holds it. Children are scanned, not searched, so that no
  // order of the children list is assumed; a cut rarely makes more than a few.
  static bool leaf_is_above(const MeshTree& tree, NodeIndex cut, LeafIndex leaf) {
    for (const NodeIndex child : tree.nodes[cut].children) {
      const MeshTreeNode& c = tree.nodes[child];
      if (leaf >= c.first_leaf && leaf - c.first_leaf < c.leaf_count) return c.above_parent_plane;
    }
    return false;  // unreachable in a well-formed tree: the leaf is in the cut's range
  }

  // The cut a triangle's surface id names, when that node is an internal ancestor
  // of `leaf`; otherwise no_node (an input surface id, which bonds ignore).
  static NodeIndex cut_of(const MeshTree& tree, SurfaceId surface, LeafIndex leaf) {
    if (surface == original_surface || surface - 1 >= tree.nodes.size()) return no_node;
    const NodeIndex cut = surface - 1;
    const MeshTreeNode& node = tree.nodes[cut];
    if (node.is_leaf() || leaf < node.first_leaf || leaf - node.first_leaf >= node.leaf_count) return no_node;
    return cut;
  }

  void add_face(const Mesh& mesh, std::span<const std::uint64_t> caps, const PlaneProjection& projection,
                NodeIndex cut, LeafIndex leaf, bool above, Faces& out) {
    const auto face_number = static_cast<std::uint32_t>(out.faces.size());
    Face face{cut, leaf, above, false, static_cast<std::uint32_t>(out.triangles.size()),
              static_cast<std::uint32_t>(caps.size()), static_cast<std::uint32_t>(out.hull_corners.size()),
              0, static_cast<std::uint32_t>(out.outline_corners.size()), 0, 0, 0, 0, 0};
    points_.clear();
    // Summed unsigned: a triangle's orientation is decided where it matters.
    double twice_triangle_area = 0;
    for (const std::uint64_t cap : caps) {
      const auto t = static_cast<TriangleIndex>(cap & 0xffffffffu);
      out.triangles.push_back(t);
      const Triangle& triangle = mesh.triangles[t];
      std::array<Vec2, 3> corners;
      for (int c = 0; c < 3; ++c) {
        corners[c] = projection(mesh.positions[triangle[c]]);
        if (vertex_stamp_[triangle[c]] != face_number) {
          vertex_stamp_[triangle[c]] = face_number;
          points_.push_back(corners[c]);
        }
      }
      twice_triangle_area += std::fabs(cross(corners[0], corners[1], corners[2]));
    }
    convex_hull(points_, hull_);
    // Collinear points only: no triangle of the face has an interior.
    if (hull_.size() < 3) {
      out.triangles.resize(face.first_triangle);
      return;
    }
    for (const Vec2 p : hull_) out.hull_corners.push_back(p);
    face.hull_corner_count = static_cast<std::uint32_t>(hull_.size());
    face.min_u = face.max_u = hull_[0].x;
    face.min_v = face.max_v = hull_[0].y;
    for (const Vec2 p : hull_) {
      face.min_u = std::min(face.min_u, p.x);
      face.max_u = std::max(face.max_u, p.x);
      face.min_v = std::min(face.min_v, p.y);
      face.max_v = std::max(face.max_v, p.y);
    }
    const double twice_hull_area = twice_area_of(hull_);
    face.fills_hull = twice_triangle_area >= twice_hull_area * (1 - hull_fill_tolerance);
    // The first corner (lowest x, then y) is a true corner and always stays; each
    // later one goes if the triangle it adds to the outline kept so far is thin,
    // so the area given up is at most the tolerance per corner.
    out.outline_corners.push_back(hull_[0]);
    for (std::size_t i = 1; i < hull_.size(); ++i) {
      const Vec2 next = hull_[(i + 1) % hull_.size()];
      if (cross(out.outline_corners.back(), hull_[i], next) > outline_tolerance * twice_hull_area) {
        out.outline_corners.push_back(hull_[i]);
      }
    }
    face.outline_corner_count = static_cast<std::uint32_t>(out.outline_corners.size()) - face.first_outline_corner;
    if (face.outline_corner_count < 3) {  // too thin to thin out: the hull as it is
      out.outline_corners.resize(face.first_outline_corner);
      out.outline_corners.insert(out.outline_corners.end(), hull_.begin(), hull_.end());
      face.outline_corner_count = static_cast<std::uint32_t>(hull_.size());
    }
    out.faces.push_back(face);
  }

  // Andrew's monotone chain, counter-clockwise, collinear points dropped; fewer
  // than three corners when the points are collinear.
  static void convex_hull(std::vector<Vec2>& points, std::vector<Vec2>& hull) {
    if (points.size() < 3) {
      hull.clear();
      return;
    }
    std::sort(points.begin(), points.end(),
              [](Vec2 a, Vec2 b) { return a.x < b.x || (!(b.x < a.x) && a.y < b.y); });
    hull.assign(2 * points.size(), Vec2{});
    std::size_t k = 0;
    for (const Vec2 p : points) {  // lower chain
      while (k >= 2 && orientation(hull[k - 2], hull[k - 1], p) != Sign::positive) --k;
      hull[k++] = p;
    }
    const std::size_t lower = k + 1;
    for (std::size_t i = points.size() - 1; i-- > 0;) {  // upper chain
      while (k >= lower && orientation(hull[k - 2], hull[k - 1], points[i]) != Sign::positive) --k;
      hull[k++] = points[i];
    }
    hull.resize(k - 1);  // the last point repeats the first
  }

  static constexpr std::uint32_t no_stamp = 0xffffffffu;
  std::vector<std::uint64_t> caps_;
  std::vector<std::uint32_t> vertex_stamp_;  // the last face that took each vertex of the leaf
  std::vector<Vec2> points_, hull_;
};

// --- overlap of two faces -----------------------------------------------------------

// Interiors of two counter-clockwise convex polygons are disjoint iff one edge
// line of either has the other polygon entirely on its closed outer side. (Their
// Minkowski difference is a convex polygon whose edges are the two polygons'
// edges; the origin lies outside its interior iff an edge line has it on the
// closed outer side, which is that statement.) Exact, as orientation is.
bool an_edge_of_separates(std::span<const Vec2> edges_of, std::span<const Vec2> other) {
  for (std::size_t e = 0; e < edges_of.size(); ++e) {
    const Vec2 p = edges_of[e], q = edges_of[(e + 1) % edges_of.size()];
    const bool all_outside = std::none_of(other.begin(), other.end(),
                                          [&](Vec2 r) { return orientation(p, q, r) == Sign::positive; });
    if (all_outside) return true;
  }
  return false;
}

bool interiors_intersect(std::span<const Vec2> a, std::span<const Vec2> b) {
  return !an_edge_of_separates(a, b) && !an_edge_of_separates(b, a);
}

struct Box2 {
  double min_u, max_u, min_v, max_v;
};
Box2 box_of(const std::array<Vec2, 3>& t) {
  return {std::min({t[0].x, t[1].x, t[2].x}), std::max({t[0].x, t[1].x, t[2].x}),
          std::min({t[0].y, t[1].y, t[2].y}), std::max({t[0].y, t[1].y, t[2].y})};
}
bool boxes_overlap(const Box2& a, const Box2& b) {
  return a.min_u <= b.max_u && b.min_u <= a.max_u && a.min_v <= b.max_v && b.min_v <= a.max_v;
}

// Whether p lies in the open interior of triangle t, whichever way t turns. A
// triangle with no interior never holds p: its three sub-areas sum to zero, so
// they cannot share a sign. Exact.
bool strictly_inside(const std::array<Vec2, 3>& t, Vec2 p) {
  const Box2 box = box_of(t);
  if (p.x <= box.min_u || p.x >= box.max_u || p.y <= box.min_v || p.y >= box.max_v) return false;
  const Sign turn = orientation(t[0], t[1], p);
  return turn != Sign::zero && orientation(t[1], t[2], p) == turn && orientation(t[2], t[0], p) == turn;
}

// --- one cut ------------------------------------------------------------------------

// The bonds of one cut: its faces sorted by min u and swept, each side keeping the
// faces whose u-range still reaches the sweep line; a pair whose closed boxes
// overlap is then decided exactly:
//   1. the centroid of the outlines' overlap (a rounded point, tested exactly)
//      lies inside a triangle of each face: a bond, the common case, settled
//      without looking at the other triangles;
//   2. otherwise hulls whose interiors do not meet: no bond (a face lies in its
//      hull);
//   3. otherwise (faces that touch, or are far from convex) triangle against
//      triangle, until one pair's interiors meet.
// A bond between faces that fill their hulls is measured on the overlap of their
// outlines; otherwise triangle pair by triangle pair. Buffers are kept between
// cuts.
class CutBonds {
 public:
  void run(const MeshTree& tree, const Faces& faces, std::span<const std::uint32_t> cut_faces, const Plane& plane,
           const PlaneProjection& projection, std::vector<Bond>& bonds) {
    tree_ = &tree;
    faces_ = &faces;
    reference_ = faces.hull_corners[faces.faces[cut_faces.front()].first_hull_corner];
    const int dropped = 3 - projection.u_axis - projection.v_axis;
    // Projected area times |n| / |n_dropped| is the area in the plane.
    area_scale_ = norm(plane.normal) / std::fabs(plane.normal[dropped]);
    unit_normal_ = normalized(plane.normal);
    plane_ = plane;
    projection_ = projection;

    order_.assign(cut_faces.begin(), cut_faces.end());
    std::sort(order_.begin(), order_.end(), [&](std::uint32_t a, std::uint32_t b) {
      const double ua = faces.faces[a].min_u, ub = faces.faces[b].min_u;
      return ua < ub || (!(ub < ua) && a < b);
    });
    active_[0].clear();
    active_[1].clear();
    for (const std::uint32_t index : order_) {
      const Face& face = faces.faces[index];
      std::vector<std::uint32_t>& others = active_[face.above ? 0 : 1];
      std::size_t kept = 0;
      for (const std::uint32_t other_index : others) {
        const Face& other = faces.faces[other_index];
        if (other.max_u < face.min_u) continue;  // passed for good: every later min u is larger
        others[kept++] = other_index;
        if (other.max_v < face.min_v || other.min_v > face.max_v) continue;
        add_bond_if_touching(face.above ? other : face, face.above ? face : other, bonds);
      }
      others.resize(kept);
      active_[face.above ? 1 : 0].push_back(index);
    }
  }

 private:
  void add_bond_if_touching(const Face& below, const Face& above, std::vector<Bond>& bonds) {
    const Faces& faces = *faces_;
    const Clipper::Measure outlines = clipper_.overlap(faces.outline_of(below), faces.outline_of(above), reference_);
    bool touching = false;
    if (outlines.area > 0) {
      const Vec2 witness{reference_.x + outlines.area_times_u / outlines.area,
                         reference_.y + outlines.area_times_v / outlines.area};
      touching = inside_a_triangle(below, witness) && inside_a_triangle(above, witness);
    }
    if (!touching) {
      if (!interiors_intersect(faces.hull_of(below), faces.hull_of(above))) return;
      if (!some_triangles_overlap(below, above)) return;
    }

    Clipper::Measure measure = outlines;
    if (!below.fills_hull || !above.fills_hull) measure = triangle_overlaps(below, above);
    double local_u, local_v;
    if (measure.area > 0) {
      local_u = measure.area_times_u / measure.area;
      local_v = measure.area_times_v / measure.area;
    } else {
      // The overlap exists exactly but its area rounds to nothing: the centre of
      // the faces' box overlap still lies in both leaves' boxes.
      local_u = 0.5 * (std::max(below.min_u, above.min_u) + std::min(below.max_u, above.max_u)) - reference_.x;
      local_v = 0.5 * (std::max(below.min_v, above.min_v) + std::min(below.max_v, above.max_v)) - reference_.y;
    }
    Bond bond;
    bond.first = std::min(below.leaf, above.leaf);
    bond.second = std::max(below.leaf, above.leaf);
    bond.cut_node = below.cut;
    bond.area = measure.area * area_scale_;
    bond.centroid = lift(reference_.x + local_u, reference_.y + local_v);
    // From below (n·x + d < 0) into above is along +n.
    bond.normal = bond.first == below.leaf ? unit_normal_ : -unit_normal_;
    bonds.push_back(bond);
  }

  // The projected corners of a face's triangle, as stored (either turn).
  std::array<Vec2, 3> corners_of(const Face& face, TriangleIndex t) const {
    const Mesh& mesh = tree_->leaf(face.leaf).mesh;
    const Triangle& triangle = mesh.triangles[t];
    return {projection_(mesh.positions[triangle[0]]), projection_(mesh.positions[triangle[1]]),
            projection_(mesh.positions[triangle[2]])};
  }

  bool inside_a_triangle(const Face& face, Vec2 p) const {
    const auto triangles = faces_->triangles_of(face);
    return std::any_of(triangles.begin(), triangles.end(),
                       [&](TriangleIndex t) { return strictly_inside(corners_of(face, t), p); });
  }

  // The face's triangles with an interior, counter-clockwise, with their boxes.
  void ccw_triangles(const Face& face, std::vector<std::array<Vec2, 3>>& triangles, std::vector<Box2>& boxes) const {
    triangles.clear();
    boxes.clear();
    for (const TriangleIndex t : faces_->triangles_of(face)) {
      std::array<Vec2, 3> corners = corners_of(face, t);
      const Sign turn = orientation(corners[0], corners[1], corners[2]);
      if (turn == Sign::zero) continue;
      if (turn == Sign::negative) std::swap(corners[1], corners[2]);
      triangles.push_back(corners);
      boxes.push_back(box_of(corners));
    }
  }

  bool some_triangles_overlap(const Face& below, const Face& above) {
    ccw_triangles(below, below_triangles_, below_boxes_);
    ccw_triangles(above, above_triangles_, above_boxes_);
    for (std::size_t i = 0; i < below_triangles_.size(); ++i) {
      for (std::size_t j = 0; j < above_triangles_.size(); ++j) {
        if (boxes_overlap(below_boxes_[i], above_boxes_[j]) &&
            interiors_intersect(below_triangles_[i], above_triangles_[j])) {
          return true;
        }
      }
    }
    return false;
  }

  Clipper::Measure triangle_overlaps(const Face& below, const Face& above) {
    ccw_triangles(below, below_triangles_, below_boxes_);
    ccw_triangles(above, above_triangles_, above_boxes_);
    Clipper::Measure total;
    for (std::size_t i = 0; i < below_triangles_.size(); ++i) {
      for (std::size_t j = 0; j < above_triangles_.size(); ++j) {
        if (!boxes_overlap(below_boxes_[i], above_boxes_[j])) continue;
        const Clipper::Measure m = clipper_.overlap(below_triangles_[i], above_triangles_[j], reference_);
        total.area += m.area;
        total.area_times_u += m.area_times_u;
        total.area_times_v += m.area_times_v;
      }
    }
    return total;
  }

  // The point of the plane over (u, v) of its projection.
  Vec3 lift(double u, double v) const {
    const int dropped = 3 - projection_.u_axis - projection_.v_axis;
    const double w = -(plane_.offset + plane_.normal[projection_.u_axis] * u + plane_.normal[projection_.v_axis] * v) /
                     plane_.normal[dropped];
    std::array<double, 3> xyz{};
    xyz[static_cast<std::size_t>(projection_.u_axis)] = u;
    xyz[static_cast<std::size_t>(projection_.v_axis)] = v;
    xyz[static_cast<std::size_t>(dropped)] = w;
    return {xyz[0], xyz[1], xyz[2]};
  }

  const MeshTree* tree_ = nullptr;
  const Faces* faces_ = nullptr;
  Vec2 reference_;
  double area_scale_ = 1;
  Vec3 unit_normal_;
  Plane plane_;
  PlaneProjection projection_;
  std::vector<std::uint32_t> order_;
  std::array<std::vector<std::uint32_t>, 2> active_;  // [0] below, [1] above
  Clipper clipper_;
  std::vector<std::array<Vec2, 3>> below_triangles_, above_triangles_;
  std::vector<Box2> below_boxes_, above_boxes_;
};

// --- bounding boxes -----------------------------------------------------------------

struct LeafBox {
  std::array<double, 3> lo, hi;
  LeafIndex leaf;
};

// CGAL's box-intersection traits over LeafBox, with the leaf index as the box id
// (CGAL's own explicit ids come from a global counter).
struct LeafBoxTraits {
  using Box_parameter = const LeafBox&;
  using NT = double;
  using ID = std::size_t;
  static NT min_coord(Box_parameter box, int axis) { return box.lo[static_cast<std::size_t>(axis)]; }
  static NT max_coord(Box_parameter box, int axis) { return box.hi[static_cast<std::size_t>(axis)]; }
  static ID id(Box_parameter box) { return box.leaf; }
  static int dimension() { return 3; }
};

}  // namespace

std::vector<Bond> find_bonds(const MeshTree& tree) {
  if (!tree.cut_planes.empty()) return find_plane_bonds(tree);
  std::vector<PlaneProjection> projections(tree.nodes.size());
  for (NodeIndex k = 0; k < tree.nodes.size(); ++k) {
    if (!tree.nodes[k].is_leaf()) projections[k] = PlaneProjection::of(tree.nodes[k].plane);
  }
  const Faces faces = FaceBuilder().build(tree, projections);

  std::vector<Bond> bonds;
  CutBonds cut_bonds;
  for (NodeIndex k = 0; k < tree.nodes.size(); ++k) {
    const std::span<const std::uint32_t> cut_faces(faces.order.data() + faces.start[k],
                                                   faces.start[k + 1] - faces.start[k]);
    if (cut_faces.size() < 2) continue;
    cut_bonds.run(tree, faces, cut_faces, tree.nodes[k].plane, projections[k], bonds);
  }
  std::sort(bonds.begin(), bonds.end(), [](const Bond& a, const Bond& b) {
    if (a.first != b.first) return a.first < b.first;
    if (a.second != b.second) return a.second < b.second;
    return a.cut_node < b.cut_node;
  });
  return bonds;
}

std::vector<std::pair<LeafIndex, LeafIndex>> find_bounding_box_bonds(const MeshTree& tree) {
  std::vector<LeafBox> boxes;
  boxes.reserve(tree.leaf_count());
  for (LeafIndex leaf = 0; leaf < tree.leaf_count(); ++leaf) {
    const Mesh& mesh = tree.leaf(leaf).mesh;
    if (mesh.positions.empty()) continue;
    LeafBox box{{mesh.positions[0].x, mesh.positions[0].y, mesh.positions[0].z},
                {mesh.positions[0].x, mesh.positions[0].y, mesh.positions[0].z},
                leaf};
    for (const Vec3& p : mesh.positions) {
      for (int axis = 0; axis < 3; ++axis) {
        const auto a = static_cast<std::size_t>(axis);
        box.lo[a] = std::min(box.lo[a], p[axis]);
        box.hi[a] = std::max(box.hi[a], p[axis]);
      }
    }
    boxes.push_back(box);
  }

  std::vector<std::pair<LeafIndex, LeafIndex>> pairs;
  CGAL::box_self_intersection_d<CGAL::Sequential_tag>(
      boxes.begin(), boxes.end(),
      [&pairs](const LeafBox& a, const LeafBox& b) {
        pairs.emplace_back(std::min(a.leaf, b.leaf), std::max(a.leaf, b.leaf));
      },
      LeafBoxTraits(), std::ptrdiff_t{10}, CGAL::Box_intersection_d::CLOSED);
  std::sort(pairs.begin(), pairs.end());
  // The self-intersection reports each pair once; unique() only guards the promise.
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  return pairs;
}

BondRuleComparison compare_bond_rules(const MeshTree& tree) {
  std::vector<std::pair<LeafIndex, LeafIndex>> true_pairs;
  for (const Bond& bond : find_bonds(tree)) {
    // Bonds are sorted by pair, so a pair bonded on several cuts is adjacent.
    if (true_pairs.empty() || true_pairs.back() != std::pair{bond.first, bond.second}) {
      true_pairs.emplace_back(bond.first, bond.second);
    }
  }
  const std::vector<std::pair<LeafIndex, LeafIndex>> box_pairs = find_bounding_box_bonds(tree);

  BondRuleComparison comparison;
  comparison.true_bonds = true_pairs.size();
  comparison.box_bonds = box_pairs.size();
  std::size_t both = 0;
  for (std::size_t t = 0, b = 0; t < true_pairs.size() && b < box_pairs.size();) {
    if (true_pairs[t] < box_pairs[b]) {
      ++t;
    } else if (box_pairs[b] < true_pairs[t]) {
      ++b;
    } else {
      ++both, ++t, ++b;
    }
  }
  comparison.false_box_bonds = box_pairs.size() - both;
  comparison.missed_true_bonds = true_pairs.size() - both;
  return comparison;
}

}  // namespace shatter
