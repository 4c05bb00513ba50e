#include "shatter/kernel/half_edges.hpp"

namespace shatter {

HalfEdgeTwins half_edge_twins(std::span<const Triangle> triangles, std::size_t vertex_count) {
  HalfEdgeTwins result;
  const std::size_t half_edge_count = 3 * triangles.size();
  result.twin.assign(half_edge_count, HalfEdgeTwins::none);
  // The half-edges leaving each vertex, as (target, half-edge), grouped by source.
  std::vector<std::uint32_t> first_out(vertex_count + 1, 0);
  for (const Triangle& tri : triangles) {
    for (const VertexIndex v : tri) ++first_out[v + 1];
  }
  for (std::size_t v = 0; v < vertex_count; ++v) first_out[v + 1] += first_out[v];
  struct Out {
    VertexIndex target;
    std::uint32_t half_edge;
  };
  std::vector<Out> out(half_edge_count);
  {
    std::vector<std::uint32_t> fill(first_out.begin(), first_out.end() - 1);
    for (std::uint32_t t = 0; t < triangles.size(); ++t) {
      const Triangle& tri = triangles[t];
      for (std::uint32_t c = 0; c < 3; ++c) out[fill[tri[c]]++] = {tri[c == 2 ? 0 : c + 1], 3 * t + c};
    }
  }
  // Half-edge h = (u -> w) is the first of its directed edge when no earlier
  // half-edge leaving u goes to w; its twin is the first half-edge leaving w for
  // u. Each group is filled in half-edge order, so "first" is the lowest index.
  for (std::uint32_t t = 0; t < triangles.size(); ++t) {
    const Triangle& tri = triangles[t];
    for (std::uint32_t c = 0; c < 3; ++c) {
      const std::uint32_t h = 3 * t + c;
      const VertexIndex u = tri[c], w = tri[c == 2 ? 0 : c + 1];
      bool first = true;
      for (std::uint32_t k = first_out[u]; k < first_out[u + 1]; ++k) {
        if (out[k].half_edge == h) break;
        if (out[k].target == w) {
          first = false;
          break;
        }
      }
      if (!first) {
        if (!result.repeated) result.repeated = Edge{u, w};
        continue;
      }
      for (std::uint32_t k = first_out[w]; k < first_out[w + 1]; ++k) {
        if (out[k].target == u) {
          result.twin[h] = out[k].half_edge;
          break;
        }
      }
    }
  }
  // The twin of a first copy is a first copy, whose twin is it back: the pairing
  // is symmetric by construction. What is left unpaired is open or repeated.
  for (std::uint32_t h = 0; h < half_edge_count; ++h) {
    if (result.twin[h] == HalfEdgeTwins::none) {
      result.first_unmatched = h;
      break;
    }
  }
  return result;
}

}  // namespace shatter
