#include "shatter/kernel/predicates.hpp"

#include <gmpxx.h>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>
#include <cmath>

#include "order_around.hpp"
#include "shatter/kernel/integer_orient.hpp"
#include "shatter/kernel/fp_environment.hpp"

namespace shatter {
namespace {

// Unit roundoff of IEEE double (round to nearest).
constexpr double unit_roundoff = 0x1p-53;

// Below this magnitude products may be subnormal and the relative error model of
// the filter no longer holds; such queries go to the exact path.
constexpr double smallest_safe_magnitude = 0x1p-960;

Sign sign_of(const mpq_class& value) {
  const int s = sgn(value);
  return s < 0 ? Sign::negative : s > 0 ? Sign::positive : Sign::zero;
}

Sign side_of_plane_exact(const Plane& plane, Vec3 p) {
  // mpq_class from a double is exact, so this is the real value of n·p + d.
  const mpq_class value = mpq_class(plane.normal.x) * mpq_class(p.x) +
                          mpq_class(plane.normal.y) * mpq_class(p.y) +
                          mpq_class(plane.normal.z) * mpq_class(p.z) + mpq_class(plane.offset);
  return sign_of(value);
}

// The filter: the sign of n·p + d when the double evaluation proves it, else zero
// (undecided). Recursive summation of four terms, three of them rounded products,
// errs by at most gamma_4 * sum|term| (Higham, "Accuracy and Stability", eq. 3.5),
// with gamma_4 = 4u / (1 - 4u). The computed magnitude underestimates the true one
// by at most a factor (1 - gamma_4), and the product below rounds once more; 6u
// covers all three. NaN or overflow fails the comparison: undecided.
int filtered_sign(const Vec3& n, const Vec3& p, double offset) {
  const double value = n.x * p.x + n.y * p.y + n.z * p.z + offset;
  const double magnitude = std::fabs(n.x * p.x) + std::fabs(n.y * p.y) + std::fabs(n.z * p.z) + std::fabs(offset);
  const double bound = magnitude * (6 * unit_roundoff);
  if (magnitude >= smallest_safe_magnitude && std::fabs(value) > bound) return value > 0 ? 1 : -1;
  return 0;
}

// Below these no product or sum of the filter can overflow (2^500 * 2^500 * 3 +
// 2^1000 < 2^1023).
constexpr double largest_safe_factor = 0x1p500;
constexpr double largest_safe_offset = 0x1p1000;

// --- orient3d -------------------------------------------------------------------
// Shewchuk, "Adaptive Precision Floating-Point Arithmetic and Fast Robust
// Geometric Predicates", Discrete & Computational Geometry 18 (1997): a double
// filter with a proven error bound, then, when the bound cannot certify the sign,
// the determinant computed exactly as a sum of doubles (an expansion). The exact
// stage is much cheaper than rationals, which matters because the hulls of cut
// pieces test nearly and exactly coplanar points all the time. Cheaper still,
// and tried first: the determinant on integers (integer_orient.hpp), which
// takes nearly all of those queries (the points of one piece share a scale):
// 99.5 % of the queries past the filter in `fracture` of blobby x4 and
// fandisk x4 -> 4,096, which the expansions took about 0.3 us each.

// The range in which both stages below are exact (finite, and the filter's bound
// holds): coordinates below 2^300 in magnitude, so no product of three differences
// or sum of six overflows (2^903 * 6 < 2^1023); and nonzero coordinates at least
// 2^-300, so every coordinate is a multiple of 2^-352, every product of three
// difference components a multiple of 2^-1056, which a double represents exactly
// even among the subnormals: the error-free transformations below stay error free.
constexpr double largest_exact_coordinate = 0x1p300;
constexpr double smallest_exact_coordinate = 0x1p-300;

bool below_largest(const Vec3& p) {
  // Written so that NaN fails.
  return std::fabs(p.x) < largest_exact_coordinate && std::fabs(p.y) < largest_exact_coordinate &&
         std::fabs(p.z) < largest_exact_coordinate;
}
bool above_smallest(double x) { return x == 0 || std::fabs(x) >= smallest_exact_coordinate; }
bool above_smallest(const Vec3& p) { return above_smallest(p.x) && above_smallest(p.y) && above_smallest(p.z); }

// The filter: Shewchuk's orient3d on the rounded differences, with his bound
// ("errboundA", (7 + 56u)u times the permanent), which assumes no underflow. With
// coordinates below 2^300 a product that underflows errs by at most 2^-1075 and
// is multiplied afterwards by at most one difference (< 2^301), so the six
// products and the three outer ones add less than 2^-771; the bound uses 8u and
// 2^-770, which also covers the rounding of the bound itself. Returns the sign of
// det[a - d, b - d, c - d] (Shewchuk's convention), or 0 when undecided.
int orient3d_filter(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, double& permanent_out) {
  const double adx = a.x - d.x, bdx = b.x - d.x, cdx = c.x - d.x;
  const double ady = a.y - d.y, bdy = b.y - d.y, cdy = c.y - d.y;
  const double adz = a.z - d.z, bdz = b.z - d.z, cdz = c.z - d.z;
  const double bdxcdy = bdx * cdy, cdxbdy = cdx * bdy;
  const double cdxady = cdx * ady, adxcdy = adx * cdy;
  const double adxbdy = adx * bdy, bdxady = bdx * ady;
  const double det = adz * (bdxcdy - cdxbdy) + bdz * (cdxady - adxcdy) + cdz * (adxbdy - bdxady);
  const double permanent = (std::fabs(bdxcdy) + std::fabs(cdxbdy)) * std::fabs(adz) +
                           (std::fabs(cdxady) + std::fabs(adxcdy)) * std::fabs(bdz) +
                           (std::fabs(adxbdy) + std::fabs(bdxady)) * std::fabs(cdz);
  const double bound = 8 * unit_roundoff * permanent + 0x1p-770;
  permanent_out = permanent;
  if (det > bound) return 1;
  if (-det > bound) return -1;
  return 0;
}

// Error-free transformations (Shewchuk, section 2). Each returns the rounded
// result and stores the exact rounding error in `error`, so that result + error
// equals the real value. Sums are error free for all finite doubles; products
// within the range above. The file is compiled with -ffp-contract=off: a fused
// multiply-add the compiler chose on its own would break them.
inline double two_sum(double a, double b, double& error) {
  const double x = a + b;
  const double b_virtual = x - a;
  const double a_virtual = x - b_virtual;
  error = (a - a_virtual) + (b - b_virtual);
  return x;
}
// Precondition: |a| >= |b| or a == 0.
inline double fast_two_sum(double a, double b, double& error) {
  const double x = a + b;
  error = b - (x - a);
  return x;
}
inline double two_product(double a, double b, double& error) {
  const double x = a * b;
#if defined(__FP_FAST_FMA)
  error = std::fma(a, b, -x);
#else
  // Dekker's product: split each factor into two 26-bit halves (Veltkamp), whose
  // pairwise products are exact.
  constexpr double splitter = 0x1p27 + 1;
  const double ca = splitter * a, a_hi = ca - (ca - a), a_lo = a - a_hi;
  const double cb = splitter * b, b_hi = cb - (cb - b), b_lo = b - b_hi;
  error = a_lo * b_lo - (((x - a_hi * b_hi) - a_lo * b_hi) - a_hi * b_lo);
#endif
  return x;
}

// Expansions: components in order of increasing magnitude, nonoverlapping, no
// zeros (so an empty expansion is zero, and the sign is that of the last
// component). Capacities are the worst case of the determinant below.

// h = e * b (Shewchuk's Scale-Expansion with zero elimination). h holds 2m.
int scale_expansion(const double* e, int m, double b, double* h) {
  if (m == 0 || b == 0) return 0;
  int n = 0;
  double error = 0;
  double q = two_product(e[0], b, error);
  if (error != 0) h[n++] = error;
  for (int i = 1; i < m; ++i) {
    double product_error = 0;
    const double product = two_product(e[i], b, product_error);
    const double sum = two_sum(q, product_error, error);
    if (error != 0) h[n++] = error;
    q = fast_two_sum(product, sum, error);
    if (error != 0) h[n++] = error;
  }
  if (q != 0) h[n++] = q;
  return n;
}

// h = e + f (Fast-Expansion-Sum with zero elimination: the components taken in
// order of magnitude from both, as a merge would give them, through one pass of
// two-sums). h holds m + k.
int sum_expansions(const double* e, int m, const double* f, int k, double* h) {
  if (m == 0) {
    std::copy(f, f + k, h);
    return k;
  }
  if (k == 0) {
    std::copy(e, e + m, h);
    return m;
  }
  int i = 0, j = 0;
  const auto next = [&] {
    if (j == k || (i < m && std::fabs(e[i]) < std::fabs(f[j]))) return e[i++];
    return f[j++];
  };
  const double g0 = next(), g1 = next();
  int n = 0;
  double error = 0;
  double q = fast_two_sum(g1, g0, error);
  if (error != 0) h[n++] = error;
  for (int t = 2; t < m + k; ++t) {
    q = two_sum(q, next(), error);
    if (error != 0) h[n++] = error;
  }
  if (q != 0) h[n++] = q;
  return n;
}

// h = e * f for a short f (at most two components). h holds 2m * k.
int multiply_expansions(const double* e, int m, const double* f, int k, double* h) {
  if (k == 0) return 0;
  if (k == 1) return scale_expansion(e, m, f[0], h);
  double first[64], second[64];
  const int n0 = scale_expansion(e, m, f[0], first);
  const int n1 = scale_expansion(e, m, f[1], second);
  return sum_expansions(first, n0, second, n1, h);
}

// x - y as an expansion of at most two components.
int difference(double x, double y, double* h) {
  double error = 0;
  const double rounded = two_sum(x, -y, error);
  int n = 0;
  if (error != 0) h[n++] = error;
  if (rounded != 0) h[n++] = rounded;
  return n;
}

struct Short {
  double c[2];
  int n;
};

// p * s - q * t, every factor a short expansion. Holds 16.
int minor(const Short& p, const Short& s, const Short& q, const Short& t, double* h) {
  double ps[8], qt[8];
  const int n_ps = multiply_expansions(p.c, p.n, s.c, s.n, ps);
  int n_qt = multiply_expansions(q.c, q.n, t.c, t.n, qt);
  for (int i = 0; i < n_qt; ++i) qt[i] = -qt[i];
  return sum_expansions(ps, n_ps, qt, n_qt, h);
}

// The exact sign of det[a - d, b - d, c - d], within the range above, from the
// exact differences (two components each) multiplied out in full: up to 192
// components. The last resort of orient3d_adaptive.
int orient3d_exact(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  Short adx, ady, adz, bdx, bdy, bdz, cdx, cdy, cdz;
  adx.n = difference(a.x, d.x, adx.c), ady.n = difference(a.y, d.y, ady.c), adz.n = difference(a.z, d.z, adz.c);
  bdx.n = difference(b.x, d.x, bdx.c), bdy.n = difference(b.y, d.y, bdy.c), bdz.n = difference(b.z, d.z, bdz.c);
  cdx.n = difference(c.x, d.x, cdx.c), cdy.n = difference(c.y, d.y, cdy.c), cdz.n = difference(c.z, d.z, cdz.c);
  // Along the z column: adz (bdx cdy - cdx bdy) + bdz (cdx ady - adx cdy) + cdz (adx bdy - bdx ady).
  double m[16], term_a[64], term_b[64], term_c[64], ab[128], det[192];
  int n = minor(bdx, cdy, cdx, bdy, m);
  const int n_a = multiply_expansions(m, n, adz.c, adz.n, term_a);
  n = minor(cdx, ady, adx, cdy, m);
  const int n_b = multiply_expansions(m, n, bdz.c, bdz.n, term_b);
  n = minor(adx, bdy, bdx, ady, m);
  const int n_c = multiply_expansions(m, n, cdz.c, cdz.n, term_c);
  const int n_ab = sum_expansions(term_a, n_a, term_b, n_b, ab);
  const int n_det = sum_expansions(ab, n_ab, term_c, n_c, det);
  if (n_det == 0) return 0;
  return det[n_det - 1] > 0 ? 1 : -1;
}

// Shewchuk's adaptive stages B and C (section 4.3 of the paper), then the full
// expansion. B: the determinant of the rounded differences, exactly (at most 24
// components); when no difference was rounded it is the answer, else its
// rounded sum decides if it clears (3 + 28u)u times the permanent. C: B plus the
// terms first-order in the differences' rounding errors, in floating point,
// decides if it clears (26 + 288u)u^2 times the permanent plus (3 + 8u)u times
// itself. Nearly coplanar points, the hulls' daily fare, mostly stop at B or C;
// only exact zeros with rounded differences (and even nearer misses) pay for the
// full expansion. Within the range above no step underflows with loss (every
// quantity is a multiple of 2^-1056), so the paper's bounds hold as proved.
int orient3d_adaptive(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, double permanent) {
  double adx_tail = 0, bdx_tail = 0, cdx_tail = 0, ady_tail = 0, bdy_tail = 0, cdy_tail = 0, adz_tail = 0,
         bdz_tail = 0, cdz_tail = 0;
  const double adx = two_sum(a.x, -d.x, adx_tail), bdx = two_sum(b.x, -d.x, bdx_tail), cdx = two_sum(c.x, -d.x, cdx_tail);
  const double ady = two_sum(a.y, -d.y, ady_tail), bdy = two_sum(b.y, -d.y, bdy_tail), cdy = two_sum(c.y, -d.y, cdy_tail);
  const double adz = two_sum(a.z, -d.z, adz_tail), bdz = two_sum(b.z, -d.z, bdz_tail), cdz = two_sum(c.z, -d.z, cdz_tail);

  // x1 * y1 - x2 * y2 exactly, at most four components.
  const auto two_by_two = [](double x1, double y1, double x2, double y2, double* h) {
    double e1 = 0, e2 = 0;
    const double p1 = two_product(x1, y1, e1);
    const double p2 = two_product(x2, y2, e2);
    const double first[2] = {e1, p1}, second[2] = {-e2, -p2};
    double terms[4];
    int n = 0;
    for (const double t : first) {
      if (t != 0) terms[n++] = t;
    }
    int k = 0;
    double negated[2];
    for (const double t : second) {
      if (t != 0) negated[k++] = t;
    }
    return sum_expansions(terms, n, negated, k, h);
  };
  double minor[4], term_a[8], term_b[8], term_c[8], ab[16], b_det[24];
  int n = two_by_two(bdx, cdy, cdx, bdy, minor);
  const int n_a = scale_expansion(minor, n, adz, term_a);
  n = two_by_two(cdx, ady, adx, cdy, minor);
  const int n_b = scale_expansion(minor, n, bdz, term_b);
  n = two_by_two(adx, bdy, bdx, ady, minor);
  const int n_c = scale_expansion(minor, n, cdz, term_c);
  const int n_ab = sum_expansions(term_a, n_a, term_b, n_b, ab);
  const int n_det = sum_expansions(ab, n_ab, term_c, n_c, b_det);

  if (adx_tail == 0 && bdx_tail == 0 && cdx_tail == 0 && ady_tail == 0 && bdy_tail == 0 && cdy_tail == 0 &&
      adz_tail == 0 && bdz_tail == 0 && cdz_tail == 0) {
    return n_det == 0 ? 0 : b_det[n_det - 1] > 0 ? 1 : -1;
  }
  double det = 0;
  for (int i = 0; i < n_det; ++i) det += b_det[i];
  // Non-strict, as in the paper: a bound of zero means a zero permanent, and then
  // every monomial of the determinant has an exactly zero factor (a difference
  // rounds to zero only when it is zero; in the range above no product
  // underflows), so the estimate's zero is the answer.
  const auto sign = [](double x) { return x > 0 ? 1 : x < 0 ? -1 : 0; };
  const double bound_b = (3 + 28 * unit_roundoff) * unit_roundoff * permanent;
  if (det >= bound_b || -det >= bound_b) return sign(det);

  const double bound_c = (26 + 288 * unit_roundoff) * unit_roundoff * unit_roundoff * permanent +
                         (3 + 8 * unit_roundoff) * unit_roundoff * std::fabs(det);
  det += (adz * ((bdx * cdy_tail + cdy * bdx_tail) - (bdy * cdx_tail + cdx * bdy_tail)) +
          adz_tail * (bdx * cdy - bdy * cdx)) +
         (bdz * ((cdx * ady_tail + ady * cdx_tail) - (cdy * adx_tail + adx * cdy_tail)) +
          bdz_tail * (cdx * ady - cdy * adx)) +
         (cdz * ((adx * bdy_tail + bdy * adx_tail) - (ady * bdx_tail + bdx * ady_tail)) +
          cdz_tail * (adx * bdy - ady * bdx));
  if (det >= bound_c || -det >= bound_c) return sign(det);
  ++predicate_counters().orient3d_full;
  return orient3d_exact(a, b, c, d);
}

// Outside that range: rationals, exact for any finite double.
int orient3d_rational(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const mpq_class adx = mpq_class(a.x) - d.x, ady = mpq_class(a.y) - d.y, adz = mpq_class(a.z) - d.z;
  const mpq_class bdx = mpq_class(b.x) - d.x, bdy = mpq_class(b.y) - d.y, bdz = mpq_class(b.z) - d.z;
  const mpq_class cdx = mpq_class(c.x) - d.x, cdy = mpq_class(c.y) - d.y, cdz = mpq_class(c.z) - d.z;
  const mpq_class det = adz * (bdx * cdy - cdx * bdy) + bdz * (cdx * ady - adx * cdy) + cdz * (adx * bdy - bdx * ady);
  return sgn(det);
}

}  // namespace

PredicateCounters& predicate_counters() {
  thread_local PredicateCounters counters;
  return counters;
}

Sign side_of_plane(const Plane& plane, Vec3 p) {
  PredicateCounters& counters = predicate_counters();
  ++counters.side_of_plane_calls;
  const Vec3 n = plane.normal;
  int sign = 0;
  if (std::fmax(std::fmax(std::fabs(n.x), std::fabs(n.y)), std::fabs(n.z)) < largest_safe_factor &&
      std::fmax(std::fmax(std::fabs(p.x), std::fabs(p.y)), std::fabs(p.z)) < largest_safe_factor &&
      std::fabs(plane.offset) < largest_safe_offset) {
    sign = filtered_sign(n, p, plane.offset);
  } else {
    // Here a product may overflow to infinity by design (the filter then defers
    // to the exact path): held, so a program that traps overflow is not stopped.
    const HeldFloatingPointEnvironment held;
    sign = filtered_sign(n, p, plane.offset);
  }
  if (sign != 0) return sign > 0 ? Sign::positive : Sign::negative;
  ++counters.side_of_plane_exact;
  return side_of_plane_exact(plane, p);
}

Sign orient3d(Vec3 a, Vec3 b, Vec3 c, Vec3 d) {
  PredicateCounters& counters = predicate_counters();
  ++counters.orient3d_calls;
  int s = 0;
  if (below_largest(a) && below_largest(b) && below_largest(c) && below_largest(d)) {
    double permanent = 0;
    s = orient3d_filter(a, b, c, d, permanent);
    if (s == 0) {
      if (above_smallest(a) && above_smallest(b) && above_smallest(c) && above_smallest(d)) {
        ++counters.orient3d_expansion;
        if (const std::optional<int> on_integers = orient3d_by_integers(a, b, c, d)) {
          ++counters.orient3d_integer;
          s = *on_integers;
        } else {
          s = orient3d_adaptive(a, b, c, d, permanent);
        }
      } else {
        ++counters.orient3d_gmp;
        s = orient3d_rational(a, b, c, d);
      }
    }
  } else {
    ++counters.orient3d_gmp;
    s = orient3d_rational(a, b, c, d);
  }
  // The determinant above is Shewchuk's, det[a - d, b - d, c - d] = -det[b - a, c - a, d - a].
  return s > 0 ? Sign::negative : s < 0 ? Sign::positive : Sign::zero;
}

std::optional<Sign> orient3d_if_clear(Vec3 a, Vec3 b, Vec3 c, Vec3 d) {
  if (!(below_largest(a) && below_largest(b) && below_largest(c) && below_largest(d))) return std::nullopt;
  double permanent = 0;
  const int s = orient3d_filter(a, b, c, d, permanent);
  if (s == 0) return std::nullopt;
  return s > 0 ? Sign::negative : Sign::positive;  // Shewchuk's sign, flipped as in orient3d
}

Sign orient2d(Vec2 a, Vec2 b, Vec2 c) {
  using Point = CGAL::Epick::Point_2;
  // CGAL's Epick orientation is exact for double input (static filter, then
  // interval arithmetic, then exact arithmetic).
  const CGAL::Orientation o = CGAL::orientation(Point(a.x, a.y), Point(b.x, b.y), Point(c.x, c.y));
  return o == CGAL::LEFT_TURN ? Sign::positive : o == CGAL::RIGHT_TURN ? Sign::negative : Sign::zero;
}

Sign coplanar_orientation(Vec3 p, Vec3 q, Vec3 r, Vec3 s) {
  const auto xy = [](const Vec3& v) { return Vec2{v.x, v.y}; };
  const auto yz = [](const Vec3& v) { return Vec2{v.y, v.z}; };
  const auto zx = [](const Vec3& v) { return Vec2{v.z, v.x}; };
  const auto in = [&](auto project) -> std::optional<Sign> {
    const Sign o = orient2d(project(p), project(q), project(r));
    if (o == Sign::zero) return std::nullopt;
    const Sign t = orient2d(project(p), project(q), project(s));
    return o == Sign::positive ? t : flip(t);
  };
  if (const auto s1 = in(xy)) return *s1;
  if (const auto s2 = in(yz)) return *s2;
  if (const auto s3 = in(zx)) return *s3;
  return Sign::zero;  // p, q, r collinear: outside the precondition
}

bool collinear(Vec3 a, Vec3 b, Vec3 c) {
  // A line in 3D projects onto a line (or a point) in all three coordinate
  // planes, and three points off one line stay off it in at least one of them.
  return orient2d({a.x, a.y}, {b.x, b.y}, {c.x, c.y}) == Sign::zero &&
         orient2d({a.y, a.z}, {b.y, b.z}, {c.y, c.z}) == Sign::zero &&
         orient2d({a.z, a.x}, {b.z, b.x}, {c.z, c.x}) == Sign::zero;
}

bool strictly_inside_segment(Vec3 a, Vec3 b, Vec3 p) {
  if (!collinear(a, b, p)) return false;
  for (const auto get : {&Vec3::x, &Vec3::y, &Vec3::z}) {
    const double lo = std::min(a.*get, b.*get), hi = std::max(a.*get, b.*get);
    if (lo < hi) return lo < p.*get && p.*get < hi;
  }
  return false;  // a == b
}

bool strictly_inside_triangle(Vec2 a, Vec2 b, Vec2 c, Vec2 p) {
  const Sign s0 = orient2d(a, b, p);
  const Sign s1 = orient2d(b, c, p);
  const Sign s2 = orient2d(c, a, p);
  return s0 != Sign::zero && s0 == s1 && s1 == s2;
}

std::optional<std::vector<std::size_t>> order_around_line(Vec3 a, Vec3 b, std::span<const Vec3> around) {
  if (around.empty()) return std::vector<std::size_t>{};
  const Vec3 r = around[0];
  return kernel_detail::order_by_half_turns(
      around.size(), [&](std::size_t i, std::size_t j) { return orient3d(a, b, around[i], around[j]); },
      [&](std::size_t i) { return coplanar_orientation(a, b, r, around[i]); });
}

}  // namespace shatter
