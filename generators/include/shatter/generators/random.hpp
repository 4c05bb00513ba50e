#pragma once
// The tests' and benchmarks' own random numbers: splitmix64, so a seed gives the
// same stream on every machine and standard library (std::uniform_*_distribution
// does not promise that; DESIGN.md, invariant 4).

#include <cstddef>
#include <cstdint>

#include "shatter/kernel/mesh.hpp"

namespace shatter::test {

/// splitmix64 (Steele, Lea and Flood 2014): a 64-bit state advanced by a constant
/// and mixed; not for cryptography.
class Random {
 public:
  explicit Random(std::uint64_t seed) : state_(seed) {}
  /// Returns the next 64 random bits.
  std::uint64_t next() {
    std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  /// Returns a double uniform in [0, 1): the top 53 bits of next().
  double uniform() { return static_cast<double>(next() >> 11) * 0x1p-53; }
  /// Returns a double uniform in [lo, hi) (up to rounding). Precondition: lo <= hi.
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  /// Returns an index in [0, n). Precondition: n > 0. (The modulo bias, below
  /// n / 2^64, does not matter for test cases.)
  std::size_t index(std::size_t n) { return static_cast<std::size_t>(next() % n); }
  /// Returns a unit direction uniform on the sphere (up to rounding).
  Vec3 direction();

 private:
  std::uint64_t state_;
};

}  // namespace shatter::test
