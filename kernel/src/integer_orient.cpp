#include "shatter/kernel/integer_orient.hpp"

#include <array>
#include <bit>
#include <cstdint>

namespace shatter {
namespace {

#if defined(__SIZEOF_INT128__)
// __extension__: a GCC and Clang type that -Wpedantic would name as not ISO.
__extension__ typedef __int128 Int128;
__extension__ typedef unsigned __int128 Uint128;

// A double as (-1)^negative * odd * 2^exponent (odd = 0 for zero).
struct Dyadic {
  std::uint64_t odd = 0;
  int exponent = 0;
  bool negative = false;
};

// Precondition: x finite, zero or normal.
Dyadic dyadic(double x) {
  const auto bits = std::bit_cast<std::uint64_t>(x);
  const std::uint64_t fraction = bits & ((std::uint64_t{1} << 52) - 1);
  const int biased = static_cast<int>((bits >> 52) & 0x7ff);
  if (biased == 0) return {};  // zero (a subnormal is outside the precondition)
  const std::uint64_t mantissa = fraction | (std::uint64_t{1} << 52);
  const int trailing = std::countr_zero(mantissa);
  return {mantissa >> trailing, biased - 1075 + trailing, (bits >> 63) != 0};
}

// The column's four coordinates as integers times one power of two, or false
// when one of them would reach 2^61 in magnitude.
bool column_integers(const std::array<double, 4>& column, std::array<std::int64_t, 4>& out) {
  std::array<Dyadic, 4> parts;
  int least = 0, top = 0;
  bool any = false;
  for (int i = 0; i < 4; ++i) {
    parts[i] = dyadic(column[i]);
    if (parts[i].odd == 0) continue;
    const int width = static_cast<int>(std::bit_width(parts[i].odd));
    if (!any || parts[i].exponent < least) least = parts[i].exponent;
    if (!any || parts[i].exponent + width > top) top = parts[i].exponent + width;
    any = true;
  }
  if (any && top - least > 61) return false;
  for (int i = 0; i < 4; ++i) {
    // exponent - least <= 61 - width: the shift keeps every bit below 2^61.
    const auto magnitude = static_cast<std::int64_t>(parts[i].odd << (parts[i].odd == 0 ? 0 : parts[i].exponent - least));
    out[i] = parts[i].negative ? -magnitude : magnitude;
  }
  return true;
}

// A signed 192-bit integer, two's complement, least significant word first.
struct Int192 {
  std::uint64_t word[3] = {0, 0, 0};
};

Int192 negated(const Int192& x) {
  Int192 r;
  std::uint64_t carry = 1;
  for (int k = 0; k < 3; ++k) {
    const Uint128 sum = Uint128{~x.word[k]} + carry;
    r.word[k] = static_cast<std::uint64_t>(sum);
    carry = static_cast<std::uint64_t>(sum >> 64);
  }
  return r;
}

Int192 sum(const Int192& x, const Int192& y) {
  Int192 r;
  std::uint64_t carry = 0;
  for (int k = 0; k < 3; ++k) {
    const Uint128 s = Uint128{x.word[k]} + y.word[k] + carry;
    r.word[k] = static_cast<std::uint64_t>(s);
    carry = static_cast<std::uint64_t>(s >> 64);
  }
  return r;
}

// m * z exactly. Preconditions: |m| < 2^126, |z| < 2^63.
Int192 product(Int128 m, std::int64_t z) {
  const bool negative = (m < 0) != (z < 0);
  const Uint128 m_abs = m < 0 ? -static_cast<Uint128>(m) : static_cast<Uint128>(m);
  const std::uint64_t z_abs = z < 0 ? -static_cast<std::uint64_t>(z) : static_cast<std::uint64_t>(z);
  const Uint128 low = Uint128{static_cast<std::uint64_t>(m_abs)} * z_abs;
  const Uint128 high = Uint128{static_cast<std::uint64_t>(m_abs >> 64)} * z_abs;  // below 2^125
  Int192 r;
  r.word[0] = static_cast<std::uint64_t>(low);
  const Uint128 middle = (low >> 64) + static_cast<std::uint64_t>(high);
  r.word[1] = static_cast<std::uint64_t>(middle);
  r.word[2] = static_cast<std::uint64_t>(high >> 64) + static_cast<std::uint64_t>(middle >> 64);
  return negative ? negated(r) : r;
}
#endif

}  // namespace

std::optional<int> orient3d_by_integers(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
#if defined(__SIZEOF_INT128__)
  std::array<std::int64_t, 4> x, y, z;
  if (!column_integers({a.x, b.x, c.x, d.x}, x) || !column_integers({a.y, b.y, c.y, d.y}, y) ||
      !column_integers({a.z, b.z, c.z, d.z}, z)) {
    return std::nullopt;
  }
  // Differences below 2^62, minors below 2^125, as the header says.
  const std::int64_t adx = x[0] - x[3], bdx = x[1] - x[3], cdx = x[2] - x[3];
  const std::int64_t ady = y[0] - y[3], bdy = y[1] - y[3], cdy = y[2] - y[3];
  const std::int64_t adz = z[0] - z[3], bdz = z[1] - z[3], cdz = z[2] - z[3];
  const Int128 minor_a = Int128{bdx} * cdy - Int128{cdx} * bdy;
  const Int128 minor_b = Int128{cdx} * ady - Int128{adx} * cdy;
  const Int128 minor_c = Int128{adx} * bdy - Int128{bdx} * ady;
  const Int192 det = sum(sum(product(minor_a, adz), product(minor_b, bdz)), product(minor_c, cdz));
  if (static_cast<std::int64_t>(det.word[2]) < 0) return -1;
  return (det.word[0] | det.word[1] | det.word[2]) != 0 ? 1 : 0;
#else
  (void)a, (void)b, (void)c, (void)d;
  return std::nullopt;
#endif
}

}  // namespace shatter
