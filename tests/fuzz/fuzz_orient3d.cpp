// Fuzz target: orient3d, the exact orientation every hull, certificate and
// input check decides with, and its integer stage on its own.
//
// Input layout: byte 0 chooses how the four points are made from the rest (its
// value mod 4), then native doubles, read as far as the input goes (missing
// bytes read as zero):
//   0  four points, 12 doubles as they are;
//   1  a, b, c as they are, d = a + s (b - a) + t (c - a) for the next two
//      doubles s and t, in floating point: nearly or exactly coplanar;
//   2  each coordinate an integer (8 bytes, its top bits dropped to the width
//      the next byte gives) times a power of two per column (the byte after):
//      columns at and beyond the integer stage's 61 bits;
//   3  a, b, d as they are, c = a + 2 (b - a): collinear, or not quite.
// Inputs with a non-finite coordinate are skipped.
//
// Properties: orient3d agrees with the determinant in GMP rationals, and flips
// under an odd permutation of the points; the integer stage, where every
// coordinate is zero or normal, answers exactly when every column spreads over
// at most 61 bits, and then agrees with the rationals.

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <optional>
#include <span>
#include <string>

#include "fuzz_support.hpp"
#include "shatter/kernel/integer_orient.hpp"
#include "shatter/kernel/predicates.hpp"
#include "support/orient_reference.hpp"

namespace {

using shatter::Sign;
using shatter::Vec3;
using shatter::fuzz::require;

// The input as a stream of doubles and bytes; reads past its end give zeros.
class Reader {
 public:
  explicit Reader(std::span<const std::uint8_t> bytes) : bytes_(bytes) {}
  std::uint8_t byte() { return at_ < bytes_.size() ? bytes_[at_++] : 0; }
  std::uint64_t word() {
    std::uint64_t value = 0;
    for (int k = 0; k < 8; ++k) value |= std::uint64_t{byte()} << (8 * k);
    return value;
  }
  double real() {
    const std::uint64_t bits = word();
    double value = 0;
    std::memcpy(&value, &bits, sizeof value);
    return value;
  }
  Vec3 point() {
    const double x = real(), y = real();
    return {x, y, real()};
  }

 private:
  std::span<const std::uint8_t> bytes_;
  std::size_t at_ = 0;
};

bool finite(const Vec3& p) { return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z); }
bool zero_or_normal(double x) { return x == 0 || std::isnormal(x); }
bool zero_or_normal(const Vec3& p) { return zero_or_normal(p.x) && zero_or_normal(p.y) && zero_or_normal(p.z); }

// Mode 2's coordinate: an integer of up to 64 bits times 2^exponent.
double scaled_integer(Reader& in, int exponent) {
  const int width = 1 + in.byte() % 64;
  std::uint64_t magnitude = in.word();
  if (width < 64) magnitude &= (std::uint64_t{1} << width) - 1;
  const double value = std::ldexp(static_cast<double>(magnitude), exponent);  // rounds beyond 53 bits
  return in.byte() % 2 ? -value : value;
}

Sign flipped(Sign s) { return s == Sign::positive ? Sign::negative : s == Sign::negative ? Sign::positive : Sign::zero; }

std::string describe(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const auto text = [](const Vec3& p) {
    char buffer[96];
    std::snprintf(buffer, sizeof buffer, "(%a, %a, %a)", p.x, p.y, p.z);
    return std::string(buffer);
  };
  return text(a) + " " + text(b) + " " + text(c) + " " + text(d);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Reader in({data, size});
  Vec3 a, b, c, d;
  switch (in.byte() % 4) {
    case 0:
      a = in.point(), b = in.point(), c = in.point(), d = in.point();
      break;
    case 1: {
      a = in.point(), b = in.point(), c = in.point();
      const double s = in.real(), t = in.real();
      d = a + (b - a) * s + (c - a) * t;
      break;
    }
    case 2: {
      Vec3* points[4] = {&a, &b, &c, &d};
      for (int axis = 0; axis < 3; ++axis) {
        const int exponent = static_cast<int>(in.byte()) * 4 - 512;
        for (Vec3* p : points) {
          const double value = scaled_integer(in, exponent);
          (axis == 0 ? p->x : axis == 1 ? p->y : p->z) = value;
        }
      }
      break;
    }
    default:
      a = in.point(), b = in.point(), d = in.point();
      c = a + (b - a) * 2.0;
      break;
  }
  if (!finite(a) || !finite(b) || !finite(c) || !finite(d)) return 0;
  const std::string where = describe(a, b, c, d);

  const Sign expected = shatter::test::reference_orient3d(a, b, c, d);
  require(shatter::orient3d(a, b, c, d) == expected, "orient3d disagrees with the rationals at " + where);
  require(shatter::orient3d(b, a, c, d) == flipped(expected), "orient3d does not flip with two points swapped at " + where);

  if (zero_or_normal(a) && zero_or_normal(b) && zero_or_normal(c) && zero_or_normal(d)) {
    const bool in_range = shatter::integer_orient_available && shatter::test::column_spread({a.x, b.x, c.x, d.x}) <= 61 &&
                          shatter::test::column_spread({a.y, b.y, c.y, d.y}) <= 61 &&
                          shatter::test::column_spread({a.z, b.z, c.z, d.z}) <= 61;
    const std::optional<int> on_integers = shatter::orient3d_by_integers(a, b, c, d);
    require(on_integers.has_value() == in_range, "the integer stage answers outside its range, or not within it, at " + where);
    require(!on_integers || *on_integers == shatter::test::shewchuk_sign(expected),
            "the integer stage disagrees with the rationals at " + where);
  }
  return 0;
}
