#pragma once
// The contact geometry of a tree without exact solids (the retired kernels'),
// for find_bonds (bonds.cpp): every leaf's cap on every cut gathered into one
// face, projected into the cut plane, with its convex hull and outline; and the
// exact 2D predicates that decide whether two such faces overlap. Private to
// meshtree.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include "shatter/kernel/predicates.hpp"
#include "shatter/kernel/projection.hpp"
#include "shatter/kernel/vec.hpp"
#include "shatter/meshtree/tree.hpp"

namespace shatter::detail {

// --- exact orientation ----------------------------------------------------------

namespace expansion {

// Error-free transformations (Shewchuk, "Adaptive precision floating-point
// arithmetic and fast robust geometric predicates", 1997): hi + lo equals the
// exact result. They need round-to-nearest doubles and no overflow or underflow,
// which the caller ensures.
struct TwoTerm {
  double hi, lo;
};
inline TwoTerm two_sum(double a, double b) {
  const double x = a + b, b_virtual = x - a, a_virtual = x - b_virtual;
  return {x, (a - a_virtual) + (b - b_virtual)};
}
inline TwoTerm two_diff(double a, double b) {
  const double x = a - b, b_virtual = a - x, a_virtual = x + b_virtual;
  return {x, (a - a_virtual) + (b_virtual - b)};
}
inline TwoTerm split(double a) {
  constexpr double splitter = 134217729.0;  // 2^27 + 1
  const double c = splitter * a, big = c - a, hi = c - big;
  return {hi, a - hi};
}
inline TwoTerm two_product(double a, double b) {
  const double x = a * b;
  const TwoTerm as = split(a), bs = split(b);
  const double error = x - as.hi * bs.hi - as.lo * bs.hi - as.hi * bs.lo;
  return {x, as.lo * bs.lo - error};
}

// The sign of (a1 + a0) - (b1 + b0) for two 2-term expansions, exactly: their
// difference as a 4-term non-overlapping expansion (Shewchuk's Two_Two_Diff),
// whose sign is that of its largest non-zero term.
inline Sign sign_of_difference(TwoTerm a, TwoTerm b) {
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

}  // namespace expansion

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
inline Sign orientation(Vec2 a, Vec2 b, Vec2 c) {
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
  if (expansion::two_diff(a.x, c.x).lo == 0 && expansion::two_diff(b.x, c.x).lo == 0 &&
      expansion::two_diff(a.y, c.y).lo == 0 && expansion::two_diff(b.y, c.y).lo == 0) {
    return expansion::sign_of_difference(expansion::two_product(acx, bcy), expansion::two_product(acy, bcx));
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
  std::uint32_t first_triangle, triangle_count;              // into Faces::triangles
  std::uint32_t first_hull_corner, hull_corner_count;        // into Faces::hull_corners
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

/// Every leaf's cap triangles gathered into faces, one per (leaf, cut), each with
/// its exact convex hull and the outline overlaps are measured on; faces whose
/// triangles have no interior in the projection are left out. `projections[k]`
/// projects internal node k's plane (unused for leaves). Preconditions: those of
/// find_bonds. Deterministic: faces come leaf by leaf, cut by cut.
Faces gather_cap_faces(const MeshTree& tree, const std::vector<PlaneProjection>& projections);

// --- overlap of two faces -----------------------------------------------------------

// Interiors of two counter-clockwise convex polygons are disjoint iff one edge
// line of either has the other polygon entirely on its closed outer side. (Their
// Minkowski difference is a convex polygon whose edges are the two polygons'
// edges; the origin lies outside its interior iff an edge line has it on the
// closed outer side, which is that statement.) Exact, as orientation is.
inline bool an_edge_of_separates(std::span<const Vec2> edges_of, std::span<const Vec2> other) {
  for (std::size_t e = 0; e < edges_of.size(); ++e) {
    const Vec2 p = edges_of[e], q = edges_of[(e + 1) % edges_of.size()];
    const bool all_outside =
        std::none_of(other.begin(), other.end(), [&](Vec2 r) { return orientation(p, q, r) == Sign::positive; });
    if (all_outside) return true;
  }
  return false;
}

inline bool interiors_intersect(std::span<const Vec2> a, std::span<const Vec2> b) {
  return !an_edge_of_separates(a, b) && !an_edge_of_separates(b, a);
}

struct Box2 {
  double min_u, max_u, min_v, max_v;
};
inline Box2 box_of(const std::array<Vec2, 3>& t) {
  return {std::min({t[0].x, t[1].x, t[2].x}), std::max({t[0].x, t[1].x, t[2].x}), std::min({t[0].y, t[1].y, t[2].y}),
          std::max({t[0].y, t[1].y, t[2].y})};
}
inline bool boxes_overlap(const Box2& a, const Box2& b) {
  return a.min_u <= b.max_u && b.min_u <= a.max_u && a.min_v <= b.max_v && b.min_v <= a.max_v;
}

// Whether p lies in the open interior of triangle t, whichever way t turns. A
// triangle with no interior never holds p: its three sub-areas sum to zero, so
// they cannot share a sign. Exact.
inline bool strictly_inside(const std::array<Vec2, 3>& t, Vec2 p) {
  const Box2 box = box_of(t);
  if (p.x <= box.min_u || p.x >= box.max_u || p.y <= box.min_v || p.y >= box.max_v) return false;
  const Sign turn = orientation(t[0], t[1], p);
  return turn != Sign::zero && orientation(t[1], t[2], p) == turn && orientation(t[2], t[0], p) == turn;
}

}  // namespace shatter::detail
