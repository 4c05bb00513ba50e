#pragma once
// The exact key of a position, shared by welding (weld.cpp) and repair's vertex
// merge (repair.cpp), so both weld by the same rule, and its hash, which the
// hash tables of positions and triangles (validate.cpp's trusted triangles, the
// file writer's position lookup) take their slots from. Not installed
// (kernel/internal/).

#include <bit>
#include <cstddef>
#include <cstdint>

#include "shatter/kernel/vec.hpp"

namespace shatter::kernel_detail {

/// The bit patterns of a position, with -0.0 stored as +0.0 so that the two
/// zeros, equal as numbers, weld. Every other pair of finite doubles is equal
/// exactly when its bits are, so the key compares positions by value.
struct PositionKey {
  std::uint64_t x, y, z;
  friend bool operator==(const PositionKey&, const PositionKey&) = default;
};

inline std::uint64_t value_bits(double coordinate) {
  return std::bit_cast<std::uint64_t>(coordinate == 0.0 ? 0.0 : coordinate);
}

inline PositionKey key_of(Vec3 position) {
  return {value_bits(position.x), value_bits(position.y), value_bits(position.z)};
}

struct PositionKeyHash {
  std::size_t operator()(const PositionKey& key) const {
    // splitmix64 finaliser per coordinate: the low bits of doubles from files
    // are often zero, so they need mixing before the table uses them.
    auto mix = [](std::uint64_t v) {
      v ^= v >> 30;
      v *= 0xbf58476d1ce4e5b9ULL;
      v ^= v >> 27;
      v *= 0x94d049bb133111ebULL;
      return v ^ (v >> 31);
    };
    return static_cast<std::size_t>(mix(key.x) ^ mix(key.y + 0x9e3779b97f4a7c15ULL) ^ mix(key.z + 0x3c6ef372fe94f82aULL));
  }
};

}  // namespace shatter::kernel_detail
