#include "seed_mesh.hpp"

#include <unordered_map>

namespace seed_peer {

Piece to_piece(const shatter::Mesh& mesh) {
  Piece piece;
  piece.triangles.reserve(mesh.triangles.size());
  for (const auto& t : mesh.triangles) {
    std::array<Vec3f, 3> corners;
    for (int c = 0; c < 3; ++c) {
      const auto& p = mesh.positions[t[static_cast<std::size_t>(c)]];
      corners[static_cast<std::size_t>(c)] = {static_cast<float>(p.x), static_cast<float>(p.y),
                                              static_cast<float>(p.z)};
    }
    piece.triangles.push_back(corners);
  }
  return piece;
}

shatter::Mesh to_mesh(const Piece& piece, Compare weld) {
  std::vector<Vec3f> corners;
  corners.reserve(piece.triangles.size() * 3);
  for (const auto& t : piece.triangles)
    for (const auto& p : t) corners.push_back(p);
  const auto group = group_positions(corners, weld);
  shatter::Mesh mesh;
  std::unordered_map<std::uint32_t, shatter::VertexIndex> vertex;
  std::vector<shatter::VertexIndex> index(corners.size());
  for (std::size_t i = 0; i < corners.size(); ++i) {
    const auto [it, added] = vertex.emplace(group[i], static_cast<shatter::VertexIndex>(mesh.positions.size()));
    if (added) {
      const Vec3f p = corners[group[i]];
      mesh.positions.push_back({p.x, p.y, p.z});
    }
    index[i] = it->second;
  }
  for (std::size_t t = 0; t < piece.triangles.size(); ++t)
    mesh.triangles.push_back({index[3 * t], index[3 * t + 1], index[3 * t + 2]});
  mesh.surfaces.assign(mesh.triangles.size(), shatter::original_surface);
  return mesh;
}

}  // namespace seed_peer
