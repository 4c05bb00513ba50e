// Welding: one topological vertex per distinct position (DESIGN.md, "Data model").

#include <algorithm>
#include <bit>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "io_internal.hpp"
#include "shatter/kernel/position_key.hpp"

namespace shatter::io_detail {

using kernel_detail::key_of;
using kernel_detail::PositionKey;
using kernel_detail::PositionKeyHash;

namespace {

// Open addressing over vertex indices: a slot holds the index of the welded
// vertex whose position hashed there (or `empty`), and the position itself is
// read back from the mesh to compare keys. No node per vertex (std::unordered_map
// allocated one per distinct position, and its buckets cost a cache miss each):
// welding a million-triangle file went from most of the read to a small part.
class VertexTable {
 public:
  static constexpr VertexIndex empty = std::numeric_limits<VertexIndex>::max();

  explicit VertexTable(std::size_t expected) { resize(std::bit_ceil(std::max<std::size_t>(16, 2 * expected))); }

  /// The vertex at `key`'s position, or `fresh` after recording `fresh` there.
  VertexIndex find_or_insert(const PositionKey& key, VertexIndex fresh, const std::vector<Vec3>& positions) {
    if (2 * (size_ + 1) > slots_.size()) grow(positions);
    for (std::size_t i = slot_of(key);; i = (i + 1) & mask_) {
      const VertexIndex v = slots_[i];
      if (v == empty) {
        slots_[i] = fresh;
        ++size_;
        return fresh;
      }
      if (key_of(positions[v]) == key) return v;
    }
  }

 private:
  std::size_t slot_of(const PositionKey& key) const { return PositionKeyHash{}(key) & mask_; }
  void resize(std::size_t capacity) {
    slots_.assign(capacity, empty);
    mask_ = capacity - 1;
  }
  void grow(const std::vector<Vec3>& positions) {
    std::vector<VertexIndex> old = std::move(slots_);
    resize(2 * old.size());
    for (const VertexIndex v : old) {
      if (v == empty) continue;
      std::size_t i = slot_of(key_of(positions[v]));
      while (slots_[i] != empty) i = (i + 1) & mask_;
      slots_[i] = v;
    }
  }

  std::vector<VertexIndex> slots_;
  std::size_t mask_ = 0, size_ = 0;
};

// The weld both soups share: corner c lies at position_of(c); slot_of(c) is
// where the vertex found for c is remembered for the corners that share c's
// file vertex (it holds VertexTable::empty until then), or nullptr when every
// corner is looked up. Vertices are numbered by first use, each keeping the
// bits of its first corner (a vertex first written as -0.0 stays -0.0).
template <class PositionOf, class SlotOf>
Mesh weld_corners(std::size_t corner_count, std::size_t expected_vertices, const PositionOf& position_of,
                  const SlotOf& slot_of, CornerAttributes corners) {
  if (corner_count == 0) refuse("the file holds no faces");
  Mesh mesh;
  mesh.triangles.resize(corner_count / 3);
  mesh.surfaces.assign(corner_count / 3, original_surface);
  VertexTable vertex_of(expected_vertices);
  mesh.positions.reserve(expected_vertices);
  for (std::size_t corner = 0; corner < corner_count; ++corner) {
    VertexIndex* const slot = slot_of(corner);
    VertexIndex vertex = slot != nullptr ? *slot : VertexTable::empty;
    if (vertex == VertexTable::empty) {
      const Vec3 position = position_of(corner);
      const auto fresh = static_cast<VertexIndex>(mesh.positions.size());
      vertex = vertex_of.find_or_insert(key_of(position), fresh, mesh.positions);
      if (vertex == fresh) {
        if (mesh.positions.size() == std::numeric_limits<VertexIndex>::max()) {
          refuse("mesh has more than " + std::to_string(std::numeric_limits<VertexIndex>::max()) + " vertices");
        }
        mesh.positions.push_back(position);
      }
      if (slot != nullptr) *slot = vertex;
    }
    mesh.triangles[corner / 3][corner % 3] = vertex;
  }
  mesh.corners = std::move(corners);
  return mesh;
}

}  // namespace

Mesh weld(TriangleSoup soup) {
  // A closed mesh has about one vertex per six corners; the table grows past that.
  const std::span<const Vec3> positions = soup.corner_positions;
  return weld_corners(
      positions.size(), positions.size() / 4, [&](std::size_t c) { return positions[c]; },
      [](std::size_t) -> VertexIndex* { return nullptr; }, std::move(soup.corners));
}

Mesh weld(IndexedSoup soup) {
  // Each file vertex's welded vertex, found at its first corner: the lookup the
  // soup's weld makes there. Its later corners would find the same vertex
  // (the table only grows), so they take it from here.
  std::vector<VertexIndex> welded(soup.positions.size(), VertexTable::empty);
  const std::size_t corner_count = soup.corner_vertices.size();
  return weld_corners(
      corner_count, std::min(corner_count / 4, soup.positions.size()),
      [&](std::size_t c) { return soup.positions[soup.corner_vertices[c]]; },
      [&](std::size_t c) { return &welded[soup.corner_vertices[c]]; }, std::move(soup.corners));
}

}  // namespace shatter::io_detail
