// Welding: one topological vertex per distinct position (DESIGN.md, "Data model").

#include <cstdint>
#include <limits>
#include <string>
#include <unordered_map>

#include "io_internal.hpp"
#include "position_key.hpp"

namespace shatter::io_detail {

using kernel_detail::key_of;
using kernel_detail::PositionKey;
using kernel_detail::PositionKeyHash;

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
