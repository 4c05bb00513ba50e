#include "shatter/kernel/mass.hpp"

#include <gmpxx.h>

#include <cmath>

#include "shatter/kernel/error.hpp"

namespace shatter {
namespace {

// Unit roundoff of IEEE double (round to nearest).
constexpr double unit_roundoff = 0x1p-53;

bool indices_in_range(const Triangle& t, std::size_t vertex_count) {
  return t[0] < vertex_count && t[1] < vertex_count && t[2] < vertex_count;
}

// The ten volume integrals of 1, x, y, z, x^2, y^2, z^2, xy, yz, zx over the solid,
// accumulated face by face with the divergence theorem. Each triangle contributes
// the exact integrals over the tetrahedron it spans with the (local) origin; the
// polynomial subexpressions are those of D. Eberly, "Polyhedral Mass Properties
// (Revisited)", 2002 (itself a simplification of Mirtich 1996).
struct VolumeIntegrals {
  double one = 0;
  Vec3 first;                      // integrals of x, y, z
  Vec3 square;                     // integrals of x^2, y^2, z^2
  double xy = 0, yz = 0, zx = 0;   // mixed integrals
};

// For one coordinate with values w0, w1, w2 at the corners: the sums Eberly calls
// f1 = w0 + w1 + w2, f2 = sum of degree-2 monomials, f3 = sum of degree-3
// monomials, and g_i = f2 + w_i (f1 + w_i), used for the mixed integrals.
struct CornerSums {
  double f1, f2, f3, g0, g1, g2;
};

CornerSums corner_sums(double w0, double w1, double w2) {
  const double sum01 = w0 + w1;
  const double w0_squared = w0 * w0;
  const double partial = w0_squared + w1 * sum01;
  CornerSums s{};
  s.f1 = sum01 + w2;
  s.f2 = partial + w2 * s.f1;
  s.f3 = w0 * w0_squared + w1 * partial + w2 * s.f2;
  s.g0 = s.f2 + w0 * (s.f1 + w0);
  s.g1 = s.f2 + w1 * (s.f1 + w1);
  s.g2 = s.f2 + w2 * (s.f1 + w2);
  return s;
}

// The power of two the coordinates (relative to `origin`) are divided by before
// they are integrated: 0 while the largest lies within [2^-60, 2^60], where the
// integrals' degree-5 terms stay far from underflow and overflow (so the
// results are the unscaled ones bit for bit), else its exponent. Scaling by a
// power of two is exact, so a mass is lost only where the result itself leaves
// the range of doubles: before, a cube 1e-105 across had its centroid NaN (its
// first moments underflowed to 0, then times 1 / volume, infinite) and
// fragments of one 1e-100 across a volume of 0.
int scale_exponent(std::span<const Vec3> positions, Vec3 origin) {
  double largest = 0;
  for (const Vec3& p : positions) {
    const Vec3 d = p - origin;
    largest = std::fmax(largest, std::fmax(std::fabs(d.x), std::fmax(std::fabs(d.y), std::fabs(d.z))));
  }
  if (!(largest > 0) || !std::isfinite(largest)) return 0;
  int exponent = 0;
  std::frexp(largest, &exponent);
  return exponent >= -60 && exponent <= 60 ? 0 : exponent;
}

// The integrals over the mesh's coordinates relative to `origin`, divided by
// 2^shift (the results in those units: the volume is 2^-3shift times the true one).
VolumeIntegrals integrate(std::span<const Vec3> positions, std::span<const Triangle> triangles, Vec3 origin,
                          int shift) {
  VolumeIntegrals sums;
  const std::size_t vertex_count = positions.size();
  const auto local = [&](VertexIndex v) {
    const Vec3 d = positions[v] - origin;
    return shift == 0 ? d : Vec3{std::ldexp(d.x, -shift), std::ldexp(d.y, -shift), std::ldexp(d.z, -shift)};
  };
  for (const Triangle& t : triangles) {
    if (!indices_in_range(t, vertex_count)) continue;  // precondition broken: stay finite, never read out of range
    const Vec3 p0 = local(t[0]);
    const Vec3 p1 = local(t[1]);
    const Vec3 p2 = local(t[2]);
    // Twice the area vector; its components weight the divergence-theorem terms.
    const Vec3 d = cross(p1 - p0, p2 - p0);
    const CornerSums x = corner_sums(p0.x, p1.x, p2.x);
    const CornerSums y = corner_sums(p0.y, p1.y, p2.y);
    const CornerSums z = corner_sums(p0.z, p1.z, p2.z);
    sums.one += d.x * x.f1;
    sums.first.x += d.x * x.f2;
    sums.first.y += d.y * y.f2;
    sums.first.z += d.z * z.f2;
    sums.square.x += d.x * x.f3;
    sums.square.y += d.y * y.f3;
    sums.square.z += d.z * z.f3;
    sums.xy += d.x * (p0.y * x.g0 + p1.y * x.g1 + p2.y * x.g2);
    sums.yz += d.y * (p0.z * y.g0 + p1.z * y.g1 + p2.z * y.g2);
    sums.zx += d.z * (p0.x * z.g0 + p1.x * z.g1 + p2.x * z.g2);
  }
  // The constant factors of the exact integrals over a tetrahedron.
  sums.one /= 6;
  sums.first = sums.first * (1.0 / 24);
  sums.square = sums.square * (1.0 / 60);
  sums.xy /= 120;
  sums.yz /= 120;
  sums.zx /= 120;
  return sums;
}

Sign sign_of(const mpq_class& value) {
  const int s = sgn(value);
  return s < 0 ? Sign::negative : s > 0 ? Sign::positive : Sign::zero;
}

// det(a, b, c) = a . (b x c), the six triple products summed exactly.
mpq_class exact_determinant(Vec3 a, Vec3 b, Vec3 c) {
  const mpq_class ax(a.x), ay(a.y), az(a.z), bx(b.x), by(b.y), bz(b.z), cx(c.x), cy(c.y), cz(c.z);
  return ax * (by * cz - bz * cy) + ay * (bz * cx - bx * cz) + az * (bx * cy - by * cx);
}

Sign signed_volume_sign_exact(const Mesh& mesh) {
  mpq_class total = 0;
  const std::size_t vertex_count = mesh.vertex_count();
  for (const Triangle& t : mesh.triangles) {
    if (!indices_in_range(t, vertex_count)) continue;
    total += exact_determinant(mesh.positions[t[0]], mesh.positions[t[1]], mesh.positions[t[2]]);
  }
  return sign_of(total);
}

// Coordinates in this range (or exactly zero) keep every product the filter forms
// away from underflow and overflow; see signed_volume_sign.
bool in_filter_range(double x) {
  const double magnitude = std::fabs(x);
  return magnitude == 0 || (magnitude >= 0x1p-200 && magnitude <= 0x1p200);
}

}  // namespace

MassProperties mass_properties(const Mesh& mesh) { return mass_properties(mesh.positions, mesh.triangles); }

MassProperties mass_properties(std::span<const Vec3> positions, std::span<const Triangle> triangles) {
  MassProperties result;
  if (positions.empty()) return result;
  // Integrating about a vertex of the mesh keeps the coordinates small relative to
  // the object's size, so a mesh far from the world origin loses no precision to
  // cancellation between huge first and second moments.
  const Vec3 origin = positions.front();
  // In units of 2^shift (scale_exponent), scaled back last.
  const int shift = scale_exponent(positions, origin);
  const VolumeIntegrals sums = integrate(positions, triangles, origin, shift);
  const double volume = sums.one;
  result.volume = std::ldexp(volume, 3 * shift);
  // A flat (zero-volume) mesh has no centre of mass: report the origin, finite.
  const Vec3 local_centroid = volume != 0 ? sums.first * (1.0 / volume) : Vec3{};
  result.centroid = origin + Vec3{std::ldexp(local_centroid.x, shift), std::ldexp(local_centroid.y, shift),
                                  std::ldexp(local_centroid.z, shift)};

  // Parallel-axis shift of the second moments to the centroid, then the inertia
  // tensor I = integral of (|r|^2 Id - r r^T): diagonal terms are sums of two
  // squared moments, off-diagonal terms the negated products of inertia.
  const Vec3 c = local_centroid;
  const double xx = sums.square.x - volume * c.x * c.x;
  const double yy = sums.square.y - volume * c.y * c.y;
  const double zz = sums.square.z - volume * c.z * c.z;
  const double xy = sums.xy - volume * c.x * c.y;
  const double yz = sums.yz - volume * c.y * c.z;
  const double zx = sums.zx - volume * c.z * c.x;
  result.inertia = {yy + zz, -xy, -zx,  //
                    -xy, xx + zz, -yz,  //
                    -zx, -yz, xx + yy};
  if (shift != 0) {
    for (double& entry : result.inertia) entry = std::ldexp(entry, 5 * shift);
  }
  return result;
}

double signed_volume(const Mesh& mesh) {
  if (mesh.positions.empty()) return 0;
  const Vec3 origin = mesh.positions.front();  // precision, as in mass_properties
  const std::size_t vertex_count = mesh.vertex_count();
  double six_volume = 0;
  for (const Triangle& t : mesh.triangles) {
    if (!indices_in_range(t, vertex_count)) continue;
    const Vec3 a = mesh.positions[t[0]] - origin;
    const Vec3 b = mesh.positions[t[1]] - origin;
    const Vec3 c = mesh.positions[t[2]] - origin;
    six_volume += dot(a, cross(b, c));
  }
  return six_volume / 6;
}

Sign signed_volume_sign(const Mesh& mesh) {
  // The sign of S = sum over triangles of det(a, b, c), taken about the world
  // origin: S is a polynomial in the input doubles, so it can be evaluated
  // exactly (subtracting a reference point first would round). For a closed
  // oriented mesh S is six times the signed volume whatever the reference point.
  const std::size_t vertex_count = mesh.vertex_count();
  bool filter_applies = true;
  for (const Vec3& p : mesh.positions) {
    if (!is_finite(p)) throw InvalidMeshError("signed volume: non-finite vertex coordinate");
    filter_applies = filter_applies && in_filter_range(p.x) && in_filter_range(p.y) && in_filter_range(p.z);
  }
  const double term_count = static_cast<double>(mesh.triangle_count()) + 4;
  filter_applies = filter_applies && term_count * unit_roundoff <= 0.125;

  if (filter_applies) {
    // Error bound. Write S as the sum of the 6T triple products +-a_i b_j c_k and
    // P for the sum of their absolute values. Each triangle's determinant is
    // evaluated as a.x*(b.y*c.z - b.z*c.y) + a.y*(...) + a.z*(...), so each triple
    // product passes through at most 5 roundings (two products, a subtraction,
    // two additions); the running sum over T triangles adds at most T - 1 more.
    // With n = T + 4, every term carries a factor (1 + theta), |theta| <= gamma_n
    // = n u / (1 - n u) (Higham, "Accuracy and Stability of Numerical Algorithms",
    // Lemma 3.1), hence |S~ - S| <= gamma_n P. The permanent P~ is computed with
    // the same structure on non-negative terms, so P~ >= (1 - u)^n P >= (1 - n u) P,
    // and the error is at most n u P~ / (1 - n u)^2 <= 1.31 n u P~ for n u <= 1/8.
    // The bound 2 n u P~ covers that and its own rounding (2 n u is exact; the
    // product rounds by at most a factor 1 - u).
    // The standard model (relative error u per rounding) needs every rounding to
    // stay clear of underflow and overflow. With every coordinate 0 or in
    // [2^-200, 2^200], coordinates are multiples of 2^-252; exact products of two
    // are multiples of 2^-504, so any nonzero rounded result at that level is at
    // least 2^-504 and a multiple of 2^-556; exact products with a third
    // coordinate, and their sums, are multiples of 2^-808. So every nonzero value
    // the evaluation rounds is at least 2^-808, far above the subnormal range, and
    // nothing exceeds 2^600 n. The argument holds whether or not the compiler
    // contracts a*b + c into fused multiply-adds, which only removes roundings.
    double sum = 0, permanent = 0;
    for (const Triangle& t : mesh.triangles) {
      if (!indices_in_range(t, vertex_count)) continue;
      const Vec3 a = mesh.positions[t[0]], b = mesh.positions[t[1]], c = mesh.positions[t[2]];
      sum += a.x * (b.y * c.z - b.z * c.y) + a.y * (b.z * c.x - b.x * c.z) + a.z * (b.x * c.y - b.y * c.x);
      permanent += std::fabs(a.x) * (std::fabs(b.y * c.z) + std::fabs(b.z * c.y)) +
                   std::fabs(a.y) * (std::fabs(b.z * c.x) + std::fabs(b.x * c.z)) +
                   std::fabs(a.z) * (std::fabs(b.x * c.y) + std::fabs(b.y * c.x));
    }
    const double bound = (2 * term_count * unit_roundoff) * permanent;
    if (sum > bound) return Sign::positive;
    if (sum < -bound) return Sign::negative;
  }
  return signed_volume_sign_exact(mesh);
}

}  // namespace shatter
