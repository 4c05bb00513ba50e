#pragma once
// Plane-based vertices: points that are never constructed, only defined.
//
// Every vertex the plane kernel ever makes is one of three kinds, each defined
// from a fixed set of inputs and never from another constructed point (Sugihara &
// Iri 1989; Bernstein & Fussell 2009; Attene 2020 calls the last two LPI and TPI):
//
//   input          an input point p, as its three doubles;
//   segment_plane  the meet of the line through two input points p, q (an input
//                  edge) with a plane P;
//   three_planes   the meet of three planes A, B, C.
//
// The planes come from a fixed set as well: cut planes, held as the four doubles
// n·x + d = 0 the caller gave, and input planes, each held as three input points
// (the plane of an input face). Cutting a piece again never refers to the points
// of the previous cut: a new vertex on an edge is the meet of the new plane with
// the edge's own line (an input segment, or two planes), so the degree of every
// predicate polynomial below is bounded once and for all, at any depth.
//
// Homogeneous coordinates, each a polynomial in the input doubles:
//   input          (p, 1)
//   segment_plane  (p P(q) - q P(p),  P(q) - P(p)),   P(x) = n_P·x + d_P
//   three_planes   (-(d_A n_B×n_C + d_B n_C×n_A + d_C n_A×n_B),  det(n_A, n_B, n_C))
// and an input plane through p0, p1, p2 is n = (p1 - p0) × (p2 - p0), d = -n·p0.
//
// Degrees in the input doubles (input coordinates, cut coefficients, and the
// constant 1 of an input point's w each count 1): the value n_Q·x̃ + d_Q w of
// side(Q, X), by the kind of X and of Q, as side_bound computes them from the
// very code that evaluates them (the test prints and checks this table):
//
//   | point X                               | Q a cut plane | Q an input plane |
//   |---------------------------------------|---------------|------------------|
//   | input point                           | 2             | 4                |
//   | segment_plane (input segment, cut)    | 4             | 5                |
//   | three_planes, three cuts              | 4             | 6                |
//   | three_planes, an input plane, 2 cuts  | 6             | 7                |
//
// No other kind is ever made: a new vertex lies on the cut that makes it, on an
// input segment or on an edge whose line involves an earlier cut, so a
// three_planes point has at most one input plane. If every input double is an
// integer times 2^e with |integer| < 2^b, side(Q, X)'s value is an integer times
// 2^(7e) or coarser with at most 7b + 12 bits (383 for b = 53), whatever the depth
// of the cut that made X. orient_in_plane on three points of the last kind is a
// polynomial of degree 14 (orient_bound). Tests evaluate these at depth 64 with
// integer inputs and check every value against the bound.
//
// Every predicate first evaluates its polynomial in floating point with a running
// error bound (Higham, "Accuracy and Stability of Numerical Algorithms", §3.3: each
// operation's rounding error, plus 2^-1074 per product for underflow, summed with
// the propagated bounds; the total inflated by 1 + 2^-40 for the rounding of the
// bound itself) and returns the sign when |value| exceeds the bound; otherwise, or
// on overflow, it evaluates the same polynomial exactly (CGAL::Mpzf, exact for
// ring operations on doubles). Zero is a real answer, never an epsilon.
//
// The points' exact values as GMP rationals (exact_coordinates, for the exact
// triangulation of a piece's faces, the tests and the audits) are declared in
// shatter/kernel/rationals.hpp, beside the sources and not installed: no
// installed header names a GMP or CGAL type, so a program using the library
// compiles without either.

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "shatter/kernel/mesh.hpp"
#include "shatter/kernel/vec.hpp"

namespace shatter {

/// A plane of the fixed set: cut plane i (is_cut) or input plane i.
struct PlaneRef {
  static constexpr std::uint32_t cut_bit = 0x80000000u;
  std::uint32_t bits = 0;

  static PlaneRef cut(std::uint32_t index) { return {index | cut_bit}; }
  static PlaneRef input(std::uint32_t index) { return {index}; }
  bool is_cut() const { return (bits & cut_bit) != 0; }
  std::uint32_t index() const { return bits & ~cut_bit; }
  friend bool operator==(PlaneRef, PlaneRef) = default;
};

/// How a vertex is defined (see the file comment).
enum class PointKind : std::uint8_t { input = 0, segment_plane = 1, three_planes = 2 };
/// The largest PointKind this version knows: readers refuse a stored kind above it.
inline constexpr PointKind last_point_kind = PointKind::three_planes;

/// A vertex, by definition. input: `a` is the input point. segment_plane: the
/// line through input points `a` and `b` met by plane `planes[0]`. three_planes:
/// the meet of planes[0..2]. Unused fields are zero, so equal definitions compare
/// equal.
struct PointDef {
  PointKind kind = PointKind::input;
  std::uint32_t a = 0, b = 0;
  std::array<PlaneRef, 3> planes{};

  static PointDef input(std::uint32_t point) { return {PointKind::input, point, 0, {}}; }
  static PointDef segment_plane(std::uint32_t p, std::uint32_t q, PlaneRef plane) {
    return {PointKind::segment_plane, p, q, {plane, PlaneRef{}, PlaneRef{}}};
  }
  static PointDef three_planes(PlaneRef first, PlaneRef second, PlaneRef third) {
    return {PointKind::three_planes, 0, 0, {first, second, third}};
  }
  /// True when the definition itself puts the point on `plane` (no arithmetic).
  bool defined_on(PlaneRef plane) const {
    if (kind == PointKind::segment_plane) return planes[0] == plane;
    if (kind == PointKind::three_planes) return planes[0] == plane || planes[1] == plane || planes[2] == plane;
    return false;
  }
  friend bool operator==(const PointDef&, const PointDef&) = default;
};

/// A double with a bound on its distance to an exact real: |value - exact| <= error.
struct Estimate {
  double value = 0;
  double error = 0;
};

/// Floating-point homogeneous coordinates of a defined point, each with its error
/// bound, scaled so that the exact w is positive: the point is (x/w, y/w, z/w).
/// A cache: every predicate on the point starts from it.
struct ApproxPoint {
  Estimate x, y, z, w;
};

/// The coefficients n_x, n_y, n_z, d of a plane, each with its error bound.
struct ApproxPlane {
  Estimate a, b, c, d;
};

/// The fixed set of planes a solid's vertices are defined from, and the input
/// points. A view: the caller owns the arrays, which must outlive it.
struct PlaneSet {
  std::span<const Vec3> points;                        ///< input points
  std::span<const std::array<VertexIndex, 3>> inputs;  ///< input plane i through these points
  std::span<const ApproxPlane> input_approx;           ///< input plane i's coefficients, approximated
  std::span<const Plane> cuts;                         ///< cut plane i

  /// The approximate coefficients of a plane (exact, error 0, for a cut).
  ApproxPlane approx(PlaneRef plane) const;
};

/// The approximate coefficients of the input plane through p0, p1, p2 (outward when
/// the three run counter-clockwise seen from outside), for PlaneSet::input_approx.
ApproxPlane approximate_input_plane(const Vec3& p0, const Vec3& p1, const Vec3& p2);

/// The cached approximation of a defined point.
/// Preconditions: the definition is sound: a segment_plane's endpoints lie strictly
/// on opposite sides of its plane, a three_planes' normals are linearly
/// independent. Guarantees: w > 0 exactly (the sign is normalised, exactly),
/// and w's estimate is positive: where the filter cannot tell w from zero, the
/// estimate is the exact coordinates rounded (nearest doubles, with bounds).
/// Throws std::domain_error when the definition is degenerate (w = 0 exactly).
ApproxPoint approximate(const PlaneSet& set, const PointDef& point);

/// True when the point lies on the plane by its definition alone: a point defined
/// on that plane, or an input plane's own defining points (and the meet of the
/// line through two of them with another plane). No arithmetic.
bool on_plane_by_definition(const PlaneSet& set, PlaneRef plane, const PointDef& point);

/// Which side of `plane` the point lies on: the exact sign of n·x + d at it.
/// Zero without arithmetic when on_plane_by_definition.
Sign side(const PlaneSet& set, PlaneRef plane, const PointDef& point, const ApproxPoint& approx);

/// side() for an explicit plane that need not be in the set (exact sign of n·x + d).
Sign side(const PlaneSet& set, const Plane& plane, const PointDef& point, const ApproxPoint& approx);

/// A plane's projection to 2D for orientation tests: drop `axis` (where the normal
/// is non-zero, chosen largest), keep (axis+1)%3, (axis+2)%3; `flipped` when the
/// normal's component on `axis` is negative, so that orientations are always as
/// seen from the plane's front (+n).
struct Projection {
  int axis = 2;
  bool flipped = false;
};
/// The projection of `plane`, decided exactly. Precondition: the normal is not zero.
Projection projection_of(const PlaneSet& set, PlaneRef plane);

/// The projection of `plane` that drops `axis` (any axis, not only the largest
/// component's), when the normal's floating-point component there certifies its
/// sign with a margin: |value| > 2 error (twice the bound the estimate carries).
/// Its `flipped` is then the exact sign of that component, so orientations in it
/// are seen from the plane's front as projection_of's are. For a fallback
/// projection where the largest one fails on points off the plane by a hair.
/// Preconditions: axis in 0..2. Guarantees: a returned projection is exact.
/// Failure: nullopt when the component is zero, and also when it is non-zero but
/// within twice its error bound (a one-sided filter: no exact fallback).
std::optional<Projection> projection_along_if_clear(const PlaneSet& set, PlaneRef plane, int axis);

/// Orientation of the triangle (p, q, r) of points on one plane, seen from the
/// plane's front through `projection` (projection_of that plane): positive when
/// counter-clockwise, zero when collinear. Exact.
Sign orient_in_plane(const PlaneSet& set, Projection projection, const PointDef& p, const ApproxPoint& pa,
                     const PointDef& q, const ApproxPoint& qa, const PointDef& r, const ApproxPoint& ra);

/// Orientation of (p, q, m) for points p, q on a plane and an explicit point m of
/// the projection's plane, given by its two kept coordinates (axis + 1, axis + 2)
/// as doubles: seen from the plane's front through `projection`, positive when
/// counter-clockwise. Exact. Used to certify that a chosen point lies inside a
/// polygon of defined points.
Sign orient_in_plane(const PlaneSet& set, Projection projection, const PointDef& p, const ApproxPoint& pa,
                     const PointDef& q, const ApproxPoint& qa, Vec2 m);

/// Order along the line A ∩ B, directed by n_A × n_B: the sign of
/// (n_A × n_B)·(q - p), positive when q comes after p. Exact.
Sign compare_along(const PlaneSet& set, PlaneRef line_a, PlaneRef line_b, const PointDef& p, const ApproxPoint& pa,
                   const PointDef& q, const ApproxPoint& qa);

/// Order along a coordinate axis: the sign of q[axis] - p[axis]. Exact.
Sign compare_coordinate(const PlaneSet& set, int axis, const PointDef& p, const ApproxPoint& pa, const PointDef& q,
                        const ApproxPoint& qa);

/// The sign of n_A·n_B: whether two planes face the same way (for parallel planes,
/// positive means the same orientation). Exact.
Sign compare_normals(const PlaneSet& set, PlaneRef a, PlaneRef b);

/// The point rounded to doubles, deterministically: each coordinate is x/w in
/// floating point when the error bound puts that within 2^-40 |x/w| of the exact
/// value (usually the correctly rounded value or an ulp off it), and the exact
/// value correctly rounded (nearest, ties to even) otherwise. Equal
/// definitions round to equal doubles, so pieces that share a vertex share its
/// position bit for bit. An input point comes back as it is.
Vec3 rounded_position(const PlaneSet& set, const PointDef& point, const ApproxPoint& approx);

/// The point's offset from `origin`, point - origin, with each coordinate within
/// 3 ulps of the exact difference: computed from the exact homogeneous
/// coordinates, so a point far from the origin keeps the shape of its
/// neighbourhood, which rounded_position(point) - origin loses once the ulps of
/// the point's coordinates are not small next to that neighbourhood (a part 0.25
/// across at 1e14 spans 16 of them). For measures (bond areas), never for
/// decisions. Precondition: `origin` finite. Cost: exact arithmetic (about a
/// microsecond; an input point costs one subtraction). Throws
/// std::domain_error for a definition whose planes do not meet in one point.
Vec3 position_relative_to(const PlaneSet& set, const PointDef& point, const Vec3& origin);

/// The position an output mesh gives the point: rounded_position, except that the
/// meet of an input segment with a plane that rounds to within 64 ulps (of the
/// segment end's largest coordinate, so 2^-46 of it) of an end of its segment
/// takes that end's position. A plane through an input vertex up to rounding
/// (x + y + d = 0 with d the rounded -(x + y), say) cuts the edges around it a few
/// ulps from it (more where an edge runs nearly along the plane); the tiny faces
/// between could not keep their orientation when rounded, and snapped onto the
/// vertex they vanish (round_solid merges vertices at one position). A point
/// that doubles hold exactly is never snapped (its rounding lost nothing). A
/// function of the definition alone, so pieces sharing a vertex place it alike.
Vec3 output_position(const PlaneSet& set, const PointDef& point, const ApproxPoint& approx);

/// output_position, with the definition of the point it places: the input point
/// snapped to, or the point itself.
struct OutputPoint {
  Vec3 position;
  PointDef placed;
};
OutputPoint output_point(const PlaneSet& set, const PointDef& point, const ApproxPoint& approx);

/// The bit-length bound of side(plane, point)'s exact value n_Q·x̃ + d_Q w, derived
/// from the very polynomial the predicate evaluates (the same template code run
/// over a degree type and a magnitude type): when every input double (input point
/// coordinates and cut coefficients) is an integer times 2^e with |integer| < 2^b,
/// the value is an integer times 2^(degree·e) of at most degree·b + magnitude_log2
/// bits, where 2^magnitude_log2 bounds the polynomial's coefficients' absolute sum.
struct PredicateBound {
  int degree = 0;          ///< total degree in the input doubles
  int magnitude_log2 = 0;  ///< ceil(log2(sum of |coefficients| of the expanded polynomial))
  int bits(int input_bits) const { return degree * input_bits + magnitude_log2; }
};
PredicateBound side_bound(const PlaneSet& set, PlaneRef plane, const PointDef& point);

/// The same for orient_in_plane(set, projection, p, q, r)'s determinant (in the
/// projection's frame, homogeneous coordinates as in the file comment).
PredicateBound orient_bound(const PlaneSet& set, Projection projection, const PointDef& p, const PointDef& q,
                            const PointDef& r);

/// Counters of floating-point filter failures, per thread.
struct ImplicitCounters {
  std::uint64_t side_calls = 0, side_exact = 0;
  std::uint64_t orient_calls = 0, orient_exact = 0;
  std::uint64_t order_calls = 0, order_exact = 0;
  std::uint64_t approximate_exact = 0;
  std::uint64_t rounding_exact = 0;
};
ImplicitCounters& implicit_counters();

}  // namespace shatter
