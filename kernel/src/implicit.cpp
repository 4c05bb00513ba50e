#include "shatter/kernel/implicit.hpp"
#include "shatter/kernel/rationals.hpp"

#include <CGAL/Mpzf.h>
#include <mpfr.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace shatter {
namespace {

// --- number types -------------------------------------------------------------
// Every polynomial below is written once, as a template over its number type, and
// run over four: Estimate (floating point with a running error bound: the filter),
// CGAL::Mpzf (exact ring arithmetic on doubles: the fall-back), and Degree and
// Magnitude, which run the same code symbolically to derive its bit-length bound.

constexpr double unit_roundoff = 0x1p-53;
// A product whose exact value is subnormal may lose up to half of 2^-1074; sums of
// doubles are exact in the subnormal range, so only products add this.
constexpr double underflow_error = 0x1p-1074;
// The error bounds are themselves computed in floating point, each operation on
// non-negative terms losing at most a relative u; no polynomial here takes more
// than 2^10 of them, so inflating the final bound by 2^-40 covers that loss.
constexpr double bound_inflation = 1 + 0x1p-40;
// rounded_position accepts a floating-point quotient within this relative bound.
constexpr double rounding_tolerance = 0x1p-40;
// output_point snaps a cut point to an end of its input segment within this many
// ulps of the end's largest coordinate.
constexpr double snap_ulps = 64;

[[gnu::always_inline]] inline Estimate operator+(Estimate a, Estimate b) {
  const double sum = a.value + b.value;
  return {sum, a.error + b.error + unit_roundoff * std::fabs(sum)};
}
[[gnu::always_inline]] inline Estimate operator-(Estimate a, Estimate b) {
  const double difference = a.value - b.value;
  return {difference, a.error + b.error + unit_roundoff * std::fabs(difference)};
}
Estimate operator-(Estimate a) { return {-a.value, a.error}; }
[[gnu::always_inline]] inline Estimate operator*(Estimate a, Estimate b) {
  const double product = a.value * b.value;
  return {product, std::fabs(a.value) * b.error + std::fabs(b.value) * a.error + a.error * b.error +
                       unit_roundoff * std::fabs(product) + underflow_error};
}

/// The sign of an approximation when its bound certifies it; zero otherwise (the
/// caller then goes exact). NaN or overflow never certify.
int certified_sign(Estimate a) {
  if (std::fabs(a.value) > a.error * bound_inflation) return a.value > 0 ? 1 : -1;
  return 0;
}

// A double that enters the filter with no error: a cut plane's coefficient, an
// input point's coordinate. As an Estimate it would carry an error of exactly
// zero, and every term of the general operators above that it multiplies adds
// exactly zero (x + 0 = x for the non-negative errors): these operators leave
// those terms out, so they give the same values and the same bounds, bit for
// bit, with about half the arithmetic. (Only where a value overflows to
// infinity do they differ: the general code's bound is then NaN, 0 times
// infinity, and this one's infinite; neither certifies a sign.) The
// approximations the kernel caches (approximate) are therefore those of the
// general code, as validate_tree checks them.
struct ErrorFree {
  double value = 0;
};
[[gnu::always_inline]] inline Estimate operator*(ErrorFree a, ErrorFree b) {
  const double product = a.value * b.value;
  return {product, unit_roundoff * std::fabs(product) + underflow_error};
}
[[gnu::always_inline]] inline Estimate operator*(ErrorFree a, Estimate b) {
  const double product = a.value * b.value;
  return {product, std::fabs(a.value) * b.error + unit_roundoff * std::fabs(product) + underflow_error};
}
[[gnu::always_inline]] inline Estimate operator*(Estimate a, ErrorFree b) {
  const double product = a.value * b.value;
  return {product, std::fabs(b.value) * a.error + unit_roundoff * std::fabs(product) + underflow_error};
}
[[gnu::always_inline]] inline Estimate operator+(Estimate a, ErrorFree b) {
  const double sum = a.value + b.value;
  return {sum, a.error + unit_roundoff * std::fabs(sum)};
}

using Exact = CGAL::Mpzf;

// Degree of a polynomial in the input doubles.
struct Degree {
  int value = 0;
};
Degree operator+(Degree a, Degree b) { return {std::max(a.value, b.value)}; }
Degree operator-(Degree a, Degree b) { return {std::max(a.value, b.value)}; }
Degree operator-(Degree a) { return a; }
Degree operator*(Degree a, Degree b) { return {a.value + b.value}; }

// The polynomial evaluated on |inputs| = 1 with every operation made additive: an
// upper bound on the sum of its expanded coefficients' absolute values.
struct Magnitude {
  double value = 0;
};
Magnitude operator+(Magnitude a, Magnitude b) { return {a.value + b.value}; }
Magnitude operator-(Magnitude a, Magnitude b) { return {a.value + b.value}; }
Magnitude operator-(Magnitude a) { return a; }
Magnitude operator*(Magnitude a, Magnitude b) { return {a.value * b.value}; }

// An input double as each number type.
template <class NT>
NT input(double value);
template <>
Estimate input<Estimate>(double value) { return {value, 0}; }
template <>
Exact input<Exact>(double value) { return Exact(value); }
template <>
Degree input<Degree>(double) { return {1}; }
template <>
Magnitude input<Magnitude>(double) { return {1}; }

template <class NT>
struct V3 {
  NT x, y, z;
};
template <class NT>
V3<NT> operator-(const V3<NT>& a, const V3<NT>& b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
// Over one number type, or an ErrorFree operand and an Estimate (the
// operations in the same order either way).
template <class A, class B>
[[gnu::always_inline]] inline auto cross(const V3<A>& a, const V3<B>& b) -> V3<decltype(a.y * b.z - a.z * b.y)> {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
template <class A, class B>
[[gnu::always_inline]] inline auto dot(const V3<A>& a, const V3<B>& b) -> decltype(a.x * b.x) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}

template <class NT>
struct P4 {
  V3<NT> n;
  NT d;
};
template <class NT>
struct H4 {
  NT x, y, z, w;
};

template <class NT>
V3<NT> input_point(const PlaneSet& set, std::uint32_t index) {
  const Vec3& p = set.points[index];
  return {input<NT>(p.x), input<NT>(p.y), input<NT>(p.z)};
}

// The input plane through p0, p1, p2: n = (p1 - p0) x (p2 - p0), d = -n·p0.
template <class NT>
P4<NT> input_plane_from_points(const V3<NT>& p0, const V3<NT>& p1, const V3<NT>& p2) {
  const V3<NT> n = cross(p1 - p0, p2 - p0);
  return {n, -dot(n, p0)};
}

template <class NT>
P4<NT> plane_coefficients(const PlaneSet& set, PlaneRef plane) {
  if (plane.is_cut()) {
    const Plane& cut = set.cuts[plane.index()];
    return {{input<NT>(cut.normal.x), input<NT>(cut.normal.y), input<NT>(cut.normal.z)}, input<NT>(cut.offset)};
  }
  const auto& points = set.inputs[plane.index()];
  return input_plane_from_points(input_point<NT>(set, points[0]), input_point<NT>(set, points[1]),
                                 input_point<NT>(set, points[2]));
}
// The filter reads input planes from their cache instead of recomputing them.
template <>
P4<Estimate> plane_coefficients<Estimate>(const PlaneSet& set, PlaneRef plane) {
  const ApproxPlane a = set.approx(plane);
  return {{a.a, a.b, a.c}, a.d};
}

template <class NT, class P>
auto evaluate(const P4<NT>& plane, const V3<P>& p) -> decltype(dot(plane.n, p) + plane.d) {
  return dot(plane.n, p) + plane.d;
}

// A cut plane's coefficients, error-free.
P4<ErrorFree> cut_coefficients(const PlaneSet& set, PlaneRef plane) {
  const Plane& cut = set.cuts[plane.index()];
  return {{{cut.normal.x}, {cut.normal.y}, {cut.normal.z}}, {cut.offset}};
}

// The homogeneous coordinates of the line through input points p and q met by
// a plane, and of the meet of three planes, as in implicit.hpp: over one number
// type, or (the filter) over error-free operands and Estimates mixed, the same
// expressions either way.
template <class Point, class Coefficient>
auto segment_plane_homogeneous(const V3<Point>& p, const V3<Point>& q, const P4<Coefficient>& plane) {
  const auto at_p = evaluate(plane, p), at_q = evaluate(plane, q);
  using NT = decltype(at_q - at_p);
  return H4<NT>{p.x * at_q - q.x * at_p, p.y * at_q - q.y * at_p, p.z * at_q - q.z * at_p, at_q - at_p};
}
template <class A, class B, class C>
auto three_planes_homogeneous(const P4<A>& a, const P4<B>& b, const P4<C>& c) {
  const auto bc = cross(b.n, c.n), ca = cross(c.n, a.n), ab = cross(a.n, b.n);
  using NT = decltype(dot(a.n, bc));
  return H4<NT>{-(a.d * bc.x + b.d * ca.x + c.d * ab.x), -(a.d * bc.y + b.d * ca.y + c.d * ab.y),
                -(a.d * bc.z + b.d * ca.z + c.d * ab.z), dot(a.n, bc)};
}

// The homogeneous coordinates of a definition, as in implicit.hpp.
template <class NT>
H4<NT> homogeneous(const PlaneSet& set, const PointDef& point) {
  switch (point.kind) {
    case PointKind::input: {
      const V3<NT> p = input_point<NT>(set, point.a);
      return {p.x, p.y, p.z, input<NT>(1.0)};
    }
    case PointKind::segment_plane:
      return segment_plane_homogeneous(input_point<NT>(set, point.a), input_point<NT>(set, point.b),
                                       plane_coefficients<NT>(set, point.planes[0]));
    case PointKind::three_planes:
      return three_planes_homogeneous(plane_coefficients<NT>(set, point.planes[0]),
                                      plane_coefficients<NT>(set, point.planes[1]),
                                      plane_coefficients<NT>(set, point.planes[2]));
  }
  return {};
}

// The filter's three_planes_homogeneous, the planes taken one by one, each as
// the type its numbers are (homogeneous_estimate): `known` holds the first ones.
template <class... Known>
H4<Estimate> three_planes_from(const PlaneSet& set, const PointDef& point, const Known&... known) {
  if constexpr (sizeof...(Known) == 3) {
    return three_planes_homogeneous(known...);
  } else {
    const PlaneRef plane = point.planes[sizeof...(Known)];
    if (plane.is_cut()) return three_planes_from(set, point, known..., cut_coefficients(set, plane));
    return three_planes_from(set, point, known..., plane_coefficients<Estimate>(set, plane));
  }
}

// homogeneous<Estimate> with the numbers it starts from error-free where they
// are (input points, cut planes; an input plane's coefficients are
// approximated): the same expressions, so the same values and bounds. Every
// vertex of a Voronoi cell is three cut planes; a plane tree's are input
// segments met by cut planes, and two cut planes with an input plane.
H4<Estimate> homogeneous_estimate(const PlaneSet& set, const PointDef& point) {
  switch (point.kind) {
    case PointKind::input:
      break;
    case PointKind::segment_plane: {
      const Vec3& pp = set.points[point.a];
      const Vec3& qq = set.points[point.b];
      const V3<ErrorFree> p{{pp.x}, {pp.y}, {pp.z}}, q{{qq.x}, {qq.y}, {qq.z}};
      if (point.planes[0].is_cut()) return segment_plane_homogeneous(p, q, cut_coefficients(set, point.planes[0]));
      return segment_plane_homogeneous(p, q, plane_coefficients<Estimate>(set, point.planes[0]));
    }
    case PointKind::three_planes:
      return three_planes_from(set, point);
  }
  return homogeneous<Estimate>(set, point);
}

template <class NT>
H4<NT> negated(const H4<NT>& h) {
  return {-h.x, -h.y, -h.z, -h.w};
}

// Exact homogeneous coordinates with w > 0.
H4<Exact> exact_normalised(const PlaneSet& set, const PointDef& point) {
  H4<Exact> h = homogeneous<Exact>(set, point);
  const int s = h.w.sign();
  if (s == 0) throw std::domain_error("degenerate point definition: its planes do not meet in one point");
  return s < 0 ? negated(h) : h;
}

// An exact value as an estimate: the nearest double to it, with a bound that
// holds (the distance to the far end of CGAL's enclosing interval).
Estimate estimate_of(const Exact& value) {
  const std::pair<double, double> interval = CGAL::to_interval(value);
  const double nearest = CGAL::to_double(value);
  return {nearest, std::max(nearest - interval.first, interval.second - nearest)};
}

H4<Estimate> cached(const ApproxPoint& p) { return {p.x, p.y, p.z, p.w}; }

template <class NT, class H>
auto side_value(const P4<NT>& plane, const H4<H>& h) -> decltype(plane.n.x * h.x) {
  return plane.n.x * h.x + plane.n.y * h.y + plane.n.z * h.z + plane.d * h.w;
}

Sign to_sign(int s) { return s < 0 ? Sign::negative : s > 0 ? Sign::positive : Sign::zero; }

template <class NT>
NT coordinate(const H4<NT>& h, int axis) {
  return axis == 0 ? h.x : axis == 1 ? h.y : h.z;
}

// det [[p_i, p_j, p_w], [q_i, q_j, q_w], [r_i, r_j, r_w]] for the kept axes i, j.
template <class NT>
NT projected_orientation(int i, int j, const H4<NT>& p, const H4<NT>& q, const H4<NT>& r) {
  const NT pi = coordinate(p, i), pj = coordinate(p, j);
  const NT qi = coordinate(q, i), qj = coordinate(q, j);
  const NT ri = coordinate(r, i), rj = coordinate(r, j);
  return pi * (qj * r.w - rj * q.w) - pj * (qi * r.w - ri * q.w) + p.w * (qi * rj - ri * qj);
}

// (n_A × n_B)·(q̃ p_w - p̃ q_w): the order of q after p along the line A ∩ B.
template <class NT>
NT along_value(const P4<NT>& a, const P4<NT>& b, const H4<NT>& p, const H4<NT>& q) {
  const V3<NT> direction = cross(a.n, b.n);
  const V3<NT> difference{q.x * p.w - p.x * q.w, q.y * p.w - p.y * q.w, q.z * p.w - p.z * q.w};
  return dot(direction, difference);
}

mpq_class to_mpq(const Exact& value) { return static_cast<mpq_class>(value); }

double correctly_rounded(const mpq_class& value) {
  mpfr_t rounded;
  mpfr_init2(rounded, 53);
  // Subnormal results need the exponent range of doubles, or MPFR would keep 53
  // bits where a double keeps fewer.
  const mpfr_exp_t old_emin = mpfr_get_emin(), old_emax = mpfr_get_emax();
  mpfr_set_emin(-1073);
  mpfr_set_emax(1024);
  const int inexact = mpfr_set_q(rounded, value.get_mpq_t(), MPFR_RNDN);
  mpfr_subnormalize(rounded, inexact, MPFR_RNDN);
  const double result = mpfr_get_d(rounded, MPFR_RNDN);
  mpfr_set_emin(old_emin);
  mpfr_set_emax(old_emax);
  mpfr_clear(rounded);
  return result;
}

}  // namespace

ApproxPlane PlaneSet::approx(PlaneRef plane) const {
  if (plane.is_cut()) {
    const Plane& cut = cuts[plane.index()];
    return {{cut.normal.x, 0}, {cut.normal.y, 0}, {cut.normal.z, 0}, {cut.offset, 0}};
  }
  return input_approx[plane.index()];
}

ApproxPlane approximate_input_plane(const Vec3& p0, const Vec3& p1, const Vec3& p2) {
  auto point = [](const Vec3& p) { return V3<Estimate>{{p.x, 0}, {p.y, 0}, {p.z, 0}}; };
  const P4<Estimate> plane = input_plane_from_points(point(p0), point(p1), point(p2));
  return {plane.n.x, plane.n.y, plane.n.z, plane.d};
}

bool on_plane_by_definition(const PlaneSet& set, PlaneRef plane, const PointDef& point) {
  if (point.defined_on(plane)) return true;
  if (plane.is_cut()) return false;
  // An input plane holds the three input points it is defined by, and the meet of
  // the line through two of them with any plane.
  const auto& defining = set.inputs[plane.index()];
  auto defines = [&](std::uint32_t p) { return p == defining[0] || p == defining[1] || p == defining[2]; };
  if (point.kind == PointKind::input) return defines(point.a);
  if (point.kind == PointKind::segment_plane) return defines(point.a) && defines(point.b);
  return false;
}

ImplicitCounters& implicit_counters() {
  thread_local ImplicitCounters counters;
  return counters;
}

// Whether h's bounds put every coordinate's floating-point quotient x / w
// within 2^-40 of the point's largest coordinate of the exact one (the bound as
// rounded_position takes it). False, without dividing, outside the ranges
// where the arithmetic below cannot overflow: a value or error beyond 2^500, or
// a w whose error is over half of it.
bool quotients_fine(const H4<Estimate>& h) {
  const double w = h.w.value, ew = h.w.error;
  if (!(w > 0x1p-500 && w < 0x1p500 && ew * 2 <= w)) return false;
  const Estimate coordinates[3] = {h.x, h.y, h.z};
  double q[3], largest = 0;
  for (int k = 0; k < 3; ++k) {
    if (!(std::fabs(coordinates[k].value) < 0x1p500 && coordinates[k].error < 0x1p500)) return false;
    q[k] = coordinates[k].value / w;
    largest = std::max(largest, std::fabs(q[k]));
  }
  for (int k = 0; k < 3; ++k) {
    const double bound =
        (coordinates[k].error + std::fabs(q[k]) * ew) / (w - ew) * bound_inflation + unit_roundoff * std::fabs(q[k]);
    if (!(bound <= rounding_tolerance * largest)) return false;
  }
  return true;
}

// n.p + d for a cut plane (error-free coefficients) and an input point, summed
// with error-free transformations (Ogita, Rump & Oishi 2005, Dot2): the value
// within u |value| + 2 (4u)^2 sum |terms| of the exact one, where the plain sum
// is only within 4u sum |terms|. Far from the origin the terms are the
// coordinates' magnitude and the value a distance to the plane, which the plain
// sum knows only to the terms' ulps.
Estimate compensated_value(const P4<ErrorFree>& plane, const V3<ErrorFree>& p) {
  const double terms[4][2] = {{plane.n.x.value, p.x.value}, {plane.n.y.value, p.y.value}, {plane.n.z.value, p.z.value},
                              {plane.d.value, 1.0}};
  double sum = 0, correction = 0, magnitude = 0;
  for (const auto& [a, b] : terms) {
    const double product = a * b;
    const double product_error = std::fma(a, b, -product);
    const double next = sum + product;
    const double z = next - sum;
    correction += ((sum - (next - z)) + (product - z)) + product_error;
    sum = next;
    magnitude += std::fabs(product);
  }
  const double value = sum + correction;
  return {value, (unit_roundoff * std::fabs(value) + 32 * unit_roundoff * unit_roundoff * magnitude) * bound_inflation +
                     4 * underflow_error};
}

// A segment's meet with a plane in cartesian coordinates, w = 1 exactly:
// x = p + t (q - p) with t = at_p / (at_p - at_q), each coordinate an Estimate
// whose bound holds the exact value (|a/d - a^/d^| <= (e_a + |a^/d^| e_d) /
// (|d^| - e_d), inflated for the bound's rounding, plus the division's). Far
// from the origin the homogeneous form x = p at_q - q at_p, w = at_q - at_p
// carries at_p's and at_q's errors times the coordinates' magnitude, which
// cancel in x / w but not in its bounds: a cut point of fandisk moved to
// (5e5, 4e6, 150) was bounded to 0.12 where it is known to 1e-9, and nearly
// every predicate on such points took the exact path (13 times the time of
// the same fracture at the origin). False when at_p - at_q's bound does not
// keep it from zero or a bound is not finite.
bool segment_plane_cartesian(const V3<ErrorFree>& p, const V3<ErrorFree>& q, const Estimate& at_p,
                             const Estimate& at_q, ApproxPoint& out) {
  const Estimate across = at_p - at_q;
  const double magnitude = std::fabs(across.value);
  // Ranges in which nothing below overflows (the test builds trap it).
  if (!(magnitude > 0x1p-250 && across.error * 2 <= magnitude && std::fabs(at_p.value) < 0x1p250 &&
        at_p.error < 0x1p250)) {
    return false;
  }
  const double t = at_p.value / across.value;
  const Estimate fraction{t, (at_p.error + std::fabs(t) * across.error) / (magnitude - across.error) * bound_inflation +
                                 2 * unit_roundoff * std::fabs(t) + underflow_error};
  const auto along = [&](ErrorFree from, ErrorFree to) {
    const double step = to.value - from.value;
    return fraction * Estimate{step, unit_roundoff * std::fabs(step)} + from;
  };
  out = {along(p.x, q.x), along(p.y, q.y), along(p.z, q.z), {1, 0}};
  return std::isfinite(out.x.error) && std::isfinite(out.y.error) && std::isfinite(out.z.error);
}

bool segment_plane_cartesian(const PlaneSet& set, const PointDef& point, ApproxPoint& out) {
  const Vec3& pp = set.points[point.a];
  const Vec3& qq = set.points[point.b];
  for (const double c : {pp.x, pp.y, pp.z, qq.x, qq.y, qq.z}) {
    if (!(std::fabs(c) < 0x1p250)) return false;
  }
  const V3<ErrorFree> p{{pp.x}, {pp.y}, {pp.z}}, q{{qq.x}, {qq.y}, {qq.z}};
  if (point.planes[0].is_cut()) {
    const P4<ErrorFree> plane = cut_coefficients(set, point.planes[0]);
    for (const ErrorFree c : {plane.n.x, plane.n.y, plane.n.z, plane.d}) {
      if (!(std::fabs(c.value) < 0x1p250)) return false;
    }
    return segment_plane_cartesian(p, q, compensated_value(plane, p), compensated_value(plane, q), out);
  }
  const P4<Estimate> plane = plane_coefficients<Estimate>(set, point.planes[0]);
  return segment_plane_cartesian(p, q, evaluate(plane, p), evaluate(plane, q), out);
}

ApproxPoint approximate(const PlaneSet& set, const PointDef& point) {
  if (point.kind == PointKind::input) {
    const Vec3& p = set.points[point.a];
    return {{p.x, 0}, {p.y, 0}, {p.z, 0}, {1, 0}};
  }
  H4<Estimate> h = homogeneous_estimate(set, point);
  const int s = certified_sign(h.w);
  if (s < 0) h = negated(h);
  // A segment's point whose homogeneous bounds are coarse next to the point
  // (far from the origin) in cartesian form where that form's are fine;
  // elsewhere, and for nearly every point near the origin, the homogeneous
  // estimate as it always was.
  if (point.kind == PointKind::segment_plane && !quotients_fine(h)) {
    ApproxPoint cartesian;
    if (segment_plane_cartesian(set, point, cartesian) &&
        quotients_fine({cartesian.x, cartesian.y, cartesian.z, cartesian.w})) {
      return cartesian;
    }
  }
  if (s == 0) {
    // The filter cannot tell w from zero, so its estimate may be noise: a short
    // segment near a plane far from the origin (a unit cube at 1e15) had both
    // ends' values round to zero, and x, y, z and w with them, so x / w was NaN
    // wherever a box or a projection was taken. The exact coordinates, rounded,
    // are the estimate then.
    ++implicit_counters().approximate_exact;
    const H4<Exact> exact = exact_normalised(set, point);  // throws on w = 0
    return {estimate_of(exact.x), estimate_of(exact.y), estimate_of(exact.z), estimate_of(exact.w)};
  }
  return {h.x, h.y, h.z, h.w};
}

Sign side(const PlaneSet& set, PlaneRef plane, const PointDef& point, const ApproxPoint& approx) {
  if (on_plane_by_definition(set, plane, point)) return Sign::zero;
  ImplicitCounters& counters = implicit_counters();
  ++counters.side_calls;
  const int s = certified_sign(plane.is_cut() ? side_value(cut_coefficients(set, plane), cached(approx))
                                              : side_value(plane_coefficients<Estimate>(set, plane), cached(approx)));
  if (s != 0) return to_sign(s);
  ++counters.side_exact;
  return to_sign(side_value(plane_coefficients<Exact>(set, plane), exact_normalised(set, point)).sign());
}

Sign side(const PlaneSet& set, const Plane& plane, const PointDef& point, const ApproxPoint& approx) {
  ImplicitCounters& counters = implicit_counters();
  ++counters.side_calls;
  const P4<ErrorFree> coefficients{{{plane.normal.x}, {plane.normal.y}, {plane.normal.z}}, {plane.offset}};
  const int s = certified_sign(side_value(coefficients, cached(approx)));
  if (s != 0) return to_sign(s);
  ++counters.side_exact;
  const P4<Exact> exact{{Exact(plane.normal.x), Exact(plane.normal.y), Exact(plane.normal.z)}, Exact(plane.offset)};
  return to_sign(side_value(exact, exact_normalised(set, point)).sign());
}

std::optional<Projection> projection_along_if_clear(const PlaneSet& set, PlaneRef plane, int axis) {
  const ApproxPlane a = set.approx(plane);
  const Estimate components[3] = {a.a, a.b, a.c};
  const Estimate& c = components[axis];
  if (std::fabs(c.value) > 2 * c.error) return Projection{axis, c.value < 0};
  return std::nullopt;
}

Projection projection_of(const PlaneSet& set, PlaneRef plane) {
  const ApproxPlane a = set.approx(plane);
  const Estimate components[3] = {a.a, a.b, a.c};
  int axis = 0;
  for (int k = 1; k < 3; ++k) {
    if (std::fabs(components[k].value) > std::fabs(components[axis].value)) axis = k;
  }
  int s = certified_sign(components[axis]);
  if (s == 0) {
    // Every component is within its error of zero: decide exactly, taking the
    // first non-zero component.
    const P4<Exact> exact = plane_coefficients<Exact>(set, plane);
    const Exact* n[3] = {&exact.n.x, &exact.n.y, &exact.n.z};
    for (axis = 0; axis < 3 && n[axis]->sign() == 0; ++axis) {
    }
    if (axis == 3) throw std::domain_error("plane with a zero normal");
    s = n[axis]->sign();
  }
  return {axis, s < 0};
}

namespace {

// An approximation's cartesian coordinate x / w as an Estimate whose bound holds
// the exact quotient: |x/w - x^/w^| <= (e_x + |x^/w^| e_w) / (w^ - e_w) for
// w > 0, inflated for the bound's own rounding, plus the division's rounding.
// False when the bound does not keep w from zero (or is not finite).
bool cartesian_of(const Estimate& x, const Estimate& w, Estimate& out) {
  if (!(w.value - w.error > 0)) return false;
  const double q = x.value / w.value;
  out = {q, (x.error + std::fabs(q) * w.error) / (w.value - w.error) * bound_inflation +
                2 * unit_roundoff * std::fabs(q) + underflow_error};
  return std::isfinite(out.error);
}

// The projected point (coordinates i, j) of an approximation, as two Estimates.
bool projected_cartesian(int i, int j, const ApproxPoint& point, Estimate (&out)[2]) {
  const Estimate coordinates[3] = {point.x, point.y, point.z};
  return cartesian_of(coordinates[i], point.w, out[0]) && cartesian_of(coordinates[j], point.w, out[1]);
}

// The sign of (q - p) x (r - p) in the projection's coordinates i, j, from the
// points' cartesian approximations, when their bounds certify it; zero
// otherwise. The same sign as projected_orientation's determinant, which is
// w_p w_q w_r times it (every w positive). A second filter for small triangles
// far from the origin: there the determinant's terms are the coordinates'
// magnitudes squared times the w's, and its filter fails once the triangle's
// area is below about 2^-50 of them (a face of a unit cube's piece at 1e6 took
// the exact path at half of `fracture`'s time), while the differences of
// coordinates keep the triangle's shape to within the approximations' errors.
int translated_orientation_sign(const Estimate (&p)[2], const Estimate (&q)[2], const Estimate (&r)[2]) {
  const Estimate qi = q[0] - p[0], qj = q[1] - p[1];
  const Estimate ri = r[0] - p[0], rj = r[1] - p[1];
  return certified_sign(qi * rj - qj * ri);
}

int translated_orientation_sign(int i, int j, const ApproxPoint& p, const ApproxPoint& q, const ApproxPoint& r) {
  Estimate cp[2], cq[2], cr[2];
  if (!projected_cartesian(i, j, p, cp) || !projected_cartesian(i, j, q, cq) || !projected_cartesian(i, j, r, cr)) {
    return 0;
  }
  return translated_orientation_sign(cp, cq, cr);
}

}  // namespace

Sign orient_in_plane(const PlaneSet& set, Projection projection, const PointDef& p, const ApproxPoint& pa,
                     const PointDef& q, const ApproxPoint& qa, const PointDef& r, const ApproxPoint& ra) {
  ImplicitCounters& counters = implicit_counters();
  ++counters.orient_calls;
  if (p == q || q == r || r == p) return Sign::zero;
  const int i = (projection.axis + 1) % 3, j = (projection.axis + 2) % 3;
  int s = certified_sign(projected_orientation(i, j, cached(pa), cached(qa), cached(ra)));
  if (s == 0) s = translated_orientation_sign(i, j, pa, qa, ra);
  if (s == 0) {
    ++counters.orient_exact;
    s = projected_orientation(i, j, exact_normalised(set, p), exact_normalised(set, q), exact_normalised(set, r))
            .sign();
  }
  return to_sign(projection.flipped ? -s : s);
}

Sign orient_in_plane(const PlaneSet& set, Projection projection, const PointDef& p, const ApproxPoint& pa,
                     const PointDef& q, const ApproxPoint& qa, Vec2 m) {
  ImplicitCounters& counters = implicit_counters();
  ++counters.orient_calls;
  const int i = (projection.axis + 1) % 3, j = (projection.axis + 2) % 3;
  auto lifted = [&](auto zero, auto mi, auto mj, auto one) {
    using NT = decltype(zero);
    H4<NT> h{zero, zero, zero, one};
    (i == 0 ? h.x : i == 1 ? h.y : h.z) = mi;
    (j == 0 ? h.x : j == 1 ? h.y : h.z) = mj;
    return h;
  };
  int s = certified_sign(projected_orientation(
      i, j, cached(pa), cached(qa), lifted(Estimate{0, 0}, Estimate{m.x, 0}, Estimate{m.y, 0}, Estimate{1, 0})));
  if (s == 0) {
    Estimate cp[2], cq[2];
    const Estimate cm[2] = {{m.x, 0}, {m.y, 0}};
    if (projected_cartesian(i, j, pa, cp) && projected_cartesian(i, j, qa, cq)) s = translated_orientation_sign(cp, cq, cm);
  }
  if (s == 0) {
    ++counters.orient_exact;
    s = projected_orientation(i, j, exact_normalised(set, p), exact_normalised(set, q),
                              lifted(Exact(0.0), Exact(m.x), Exact(m.y), Exact(1.0)))
            .sign();
  }
  return to_sign(projection.flipped ? -s : s);
}

Sign compare_along(const PlaneSet& set, PlaneRef line_a, PlaneRef line_b, const PointDef& p, const ApproxPoint& pa,
                   const PointDef& q, const ApproxPoint& qa) {
  ImplicitCounters& counters = implicit_counters();
  ++counters.order_calls;
  if (p == q) return Sign::zero;
  const int s = certified_sign(along_value(plane_coefficients<Estimate>(set, line_a),
                                           plane_coefficients<Estimate>(set, line_b), cached(pa), cached(qa)));
  if (s != 0) return to_sign(s);
  ++counters.order_exact;
  return to_sign(along_value(plane_coefficients<Exact>(set, line_a), plane_coefficients<Exact>(set, line_b),
                             exact_normalised(set, p), exact_normalised(set, q))
                     .sign());
}

namespace {

// Whether p and q are both defined on one cut plane whose normal lies along
// `axis` (its other two coefficients zero: the doubles that define a cut plane
// are its exact coefficients): every point of that plane has the one
// coordinate -offset / normal[axis] there. A Voronoi build's group boxes and a
// grid's bisectors are such planes, and the points they make are compared
// along them when faces they cross are walked (lowest_corner, locate_in_loop);
// the filter cannot settle an exact tie, which took the exact path 69,000
// times in a Voronoi build of the elephant at 10^4 sites.
bool on_one_plane_across(const PlaneSet& set, int axis, const PointDef& p, const PointDef& q) {
  if (p.kind == PointKind::input || q.kind == PointKind::input) return false;
  const int count = p.kind == PointKind::segment_plane ? 1 : 3;
  for (int k = 0; k < count; ++k) {
    const PlaneRef plane = p.planes[k];
    if (!plane.is_cut() || !q.defined_on(plane)) continue;
    const Vec3& n = set.cuts[plane.index()].normal;
    const double across[3] = {n.x, n.y, n.z};
    if (across[(axis + 1) % 3] == 0 && across[(axis + 2) % 3] == 0) return true;
  }
  return false;
}

}  // namespace

Sign compare_coordinate(const PlaneSet& set, int axis, const PointDef& p, const ApproxPoint& pa, const PointDef& q,
                        const ApproxPoint& qa) {
  ImplicitCounters& counters = implicit_counters();
  ++counters.order_calls;
  if (p == q) return Sign::zero;
  auto value = [axis](const auto& ph, const auto& qh) { return coordinate(qh, axis) * ph.w - coordinate(ph, axis) * qh.w; };
  const int s = certified_sign(value(cached(pa), cached(qa)));
  if (s != 0) return to_sign(s);
  if (on_one_plane_across(set, axis, p, q)) return Sign::zero;
  ++counters.order_exact;
  return to_sign(value(exact_normalised(set, p), exact_normalised(set, q)).sign());
}

Sign compare_normals(const PlaneSet& set, PlaneRef a, PlaneRef b) {
  const int s = certified_sign(dot(plane_coefficients<Estimate>(set, a).n, plane_coefficients<Estimate>(set, b).n));
  if (s != 0) return to_sign(s);
  return to_sign(dot(plane_coefficients<Exact>(set, a).n, plane_coefficients<Exact>(set, b).n).sign());
}

Vec3 rounded_position(const PlaneSet& set, const PointDef& point, const ApproxPoint& approx) {
  if (point.kind == PointKind::input) return set.points[point.a];
  // q = x/w with |x - x̂| <= ex, |w - ŵ| <= ew (ŵ > 0): |x/w - x̂/ŵ| <= (ex + |x̂/ŵ| ew) / (ŵ - ew),
  // and the division rounds once more. Accepted when that is within 2^-40 of |x/w|
  // (a few thousand ulps at worst; in practice the quotient is usually the
  // correctly rounded value or next to it, see the rounding audit).
  const double w = approx.w.value, ew = approx.w.error;
  Vec3 result;
  double* out[3] = {&result.x, &result.y, &result.z};
  const Estimate coordinates[3] = {approx.x, approx.y, approx.z};
  bool exact_needed = !(w - ew * bound_inflation > 0);
  for (int k = 0; k < 3 && !exact_needed; ++k) {
    const double q = coordinates[k].value / w;
    const double bound =
        (coordinates[k].error + std::fabs(q) * ew) / (w - ew) * bound_inflation + unit_roundoff * std::fabs(q);
    if (!(bound <= rounding_tolerance * std::fabs(q)) || !std::isfinite(q) ||
        (q != 0 && std::fabs(q) < 0x1p-1000)) {
      exact_needed = true;
    }
    *out[k] = q;
  }
  if (!exact_needed) return result;
  ++implicit_counters().rounding_exact;
  const std::array<mpq_class, 3> exact = exact_coordinates(set, point);
  return {correctly_rounded(exact[0]), correctly_rounded(exact[1]), correctly_rounded(exact[2])};
}

Vec3 position_relative_to(const PlaneSet& set, const PointDef& point, const Vec3& origin) {
  if (point.kind == PointKind::input) return set.points[point.a] - origin;
  // (x - o w) / w with x - o w exact: two conversions to double (each within an
  // ulp: Mpzf keeps the top 64 bits) and one division.
  const H4<Exact> h = exact_normalised(set, point);
  const double w = CGAL::to_double(h.w);
  const Exact coordinates[3] = {h.x, h.y, h.z};
  const double from[3] = {origin.x, origin.y, origin.z};
  double offset[3];
  for (int k = 0; k < 3; ++k) {
    offset[k] = CGAL::to_double(Exact(coordinates[k] - Exact(from[k]) * h.w)) / w;
  }
  if (std::isfinite(offset[0]) && std::isfinite(offset[1]) && std::isfinite(offset[2])) {
    return {offset[0], offset[1], offset[2]};
  }
  // w or a difference outside the doubles' range: the exact quotients, rounded.
  const std::array<mpq_class, 3> exact = exact_coordinates(set, point);
  return {correctly_rounded(exact[0] - mpq_class(origin.x)), correctly_rounded(exact[1] - mpq_class(origin.y)),
          correctly_rounded(exact[2] - mpq_class(origin.z))};
}

OutputPoint output_point(const PlaneSet& set, const PointDef& point, const ApproxPoint& approx) {
  const Vec3 rounded = rounded_position(set, point, approx);
  if (point.kind != PointKind::segment_plane) return {rounded, point};
  for (const std::uint32_t end : {point.a, point.b}) {
    const Vec3& p = set.points[end];
    const double largest = std::max({std::fabs(p.x), std::fabs(p.y), std::fabs(p.z)});
    const double reach = snap_ulps * (std::nextafter(largest, INFINITY) - largest);
    if (std::fabs(rounded.x - p.x) <= reach && std::fabs(rounded.y - p.y) <= reach &&
        std::fabs(rounded.z - p.z) <= reach) {
      // A point that doubles hold exactly lost nothing to rounding: nothing to
      // repair, and its tiny faces keep their shape as written.
      const std::array<mpq_class, 3> exact = exact_coordinates(set, point);
      if (exact[0] == rounded.x && exact[1] == rounded.y && exact[2] == rounded.z) return {rounded, point};
      return {p, PointDef::input(end)};
    }
  }
  return {rounded, point};
}

Vec3 output_position(const PlaneSet& set, const PointDef& point, const ApproxPoint& approx) {
  return output_point(set, point, approx).position;
}

std::array<mpq_class, 3> exact_coordinates(const PlaneSet& set, const PointDef& point) {
  const H4<Exact> h = exact_normalised(set, point);
  const mpq_class w = to_mpq(h.w);
  return {to_mpq(h.x) / w, to_mpq(h.y) / w, to_mpq(h.z) / w};
}

std::array<mpq_class, 4> exact_plane_coefficients(const PlaneSet& set, PlaneRef plane) {
  const P4<Exact> p = plane_coefficients<Exact>(set, plane);
  return {to_mpq(p.n.x), to_mpq(p.n.y), to_mpq(p.n.z), to_mpq(p.d)};
}

PlaneReach::PlaneReach(const std::array<mpq_class, 4>& plane, const mpq_class& reach) : plane_(plane) {
  limit_ = reach * std::max({mpq_class(abs(plane[0])), mpq_class(abs(plane[1])), mpq_class(abs(plane[2]))});
}

PlaneReach::PlaneReach(const PlaneSet& set, PlaneRef plane, const mpq_class& reach)
    : PlaneReach(exact_plane_coefficients(set, plane), reach) {}

PlaneReach::PlaneReach(const Plane& plane, const mpq_class& reach)
    : PlaneReach({mpq_class(plane.normal.x), mpq_class(plane.normal.y), mpq_class(plane.normal.z),
                  mpq_class(plane.offset)},
                 reach) {}

PlaneReach::Where PlaneReach::locate(const std::array<mpq_class, 3>& x) const {
  const mpq_class value = plane_[0] * x[0] + plane_[1] * x[1] + plane_[2] * x[2] + plane_[3];
  const int s = sgn(value);
  return {s > 0 ? Sign::positive : s < 0 ? Sign::negative : Sign::zero, abs(value) <= limit_};
}

PlaneReach::Where PlaneReach::locate(const Vec3& p) const {
  return locate({mpq_class(p.x), mpq_class(p.y), mpq_class(p.z)});
}

std::array<mpq_class, 4> exact_homogeneous(const PlaneSet& set, const PointDef& point) {
  const H4<Exact> h = homogeneous<Exact>(set, point);
  return {to_mpq(h.x), to_mpq(h.y), to_mpq(h.z), to_mpq(h.w)};
}

PredicateBound side_bound(const PlaneSet& set, PlaneRef plane, const PointDef& point) {
  const Degree degree = side_value(plane_coefficients<Degree>(set, plane), homogeneous<Degree>(set, point));
  const Magnitude magnitude =
      side_value(plane_coefficients<Magnitude>(set, plane), homogeneous<Magnitude>(set, point));
  return {degree.value, static_cast<int>(std::ceil(std::log2(magnitude.value)))};
}

PredicateBound orient_bound(const PlaneSet& set, Projection projection, const PointDef& p, const PointDef& q,
                            const PointDef& r) {
  const int i = (projection.axis + 1) % 3, j = (projection.axis + 2) % 3;
  const Degree degree = projected_orientation(i, j, homogeneous<Degree>(set, p), homogeneous<Degree>(set, q),
                                              homogeneous<Degree>(set, r));
  const Magnitude magnitude = projected_orientation(i, j, homogeneous<Magnitude>(set, p),
                                                    homogeneous<Magnitude>(set, q), homogeneous<Magnitude>(set, r));
  return {degree.value, static_cast<int>(std::ceil(std::log2(magnitude.value)))};
}

}  // namespace shatter
