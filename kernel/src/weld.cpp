// Welding: one topological vertex per distinct position (DESIGN.md, "Data model").

#include <bit>
#include <cstdint>
#include <limits>
#include <string>
#include <unordered_map>

#include "io_internal.hpp"

namespace shatter::io_detail {

namespace {

/// The bit patterns of a position, with -0.0 stored as +0.0 so that the two
/// zeros, equal as numbers, weld. Every other pair of finite doubles is equal
/// exactly when its bits are, so the key compares positions by value.
struct PositionKey {
  std::uint64_t x, y, z;
  friend bool operator==(const PositionKey&, const PositionKey&) = default;
};

std::uint64_t value_bits(double coordinate) { return std::bit_cast<std::uint64_t>(coordinate == 0.0 ? 0.0 : coordinate); }

PositionKey key_of(Vec3 position) { return {value_bits(position.x), value_bits(position.y), value_bits(position.z)}; }

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

}  // namespace

Mesh weld(TriangleSoup soup) {
  if (soup.corner_positions.empty()) refuse("the file holds no faces");
  Mesh mesh;
  const std::size_t corner_count = soup.corner_positions.size();
  mesh.triangles.resize(soup.triangle_count());
  mesh.surfaces.assign(soup.triangle_count(), original_surface);

  std::unordered_map<PositionKey, VertexIndex, PositionKeyHash> vertex_of;
  vertex_of.reserve(corner_count);
  for (std::size_t corner = 0; corner < corner_count; ++corner) {
    const Vec3 position = soup.corner_positions[corner];
    const auto [entry, inserted] = vertex_of.try_emplace(key_of(position), static_cast<VertexIndex>(mesh.positions.size()));
    if (inserted) {
      if (mesh.positions.size() == std::numeric_limits<VertexIndex>::max()) {
        refuse("mesh has more than " + std::to_string(std::numeric_limits<VertexIndex>::max()) + " vertices");
      }
      // The first corner's own bits are kept: a vertex first written as -0.0 stays -0.0.
      mesh.positions.push_back(position);
    }
    mesh.triangles[corner / 3][corner % 3] = entry->second;
  }
  mesh.corners = std::move(soup.corners);
  return mesh;
}

}  // namespace shatter::io_detail
