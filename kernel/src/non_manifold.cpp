#include "shatter/kernel/non_manifold.hpp"

#include <algorithm>
#include <utility>

#include "shatter/kernel/predicates.hpp"
#include "shatter/kernel/solid.hpp"
#include "shatter/kernel/union_find.hpp"

namespace shatter {

std::optional<std::vector<std::uint32_t>> pair_around_non_manifold_edges(const Mesh& mesh) {
  struct Use {
    std::uint64_t key;   // the undirected edge
    std::uint32_t slot;  // 3 t + c
  };
  std::vector<Use> uses;
  uses.reserve(3 * mesh.triangles.size());
  for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t) {
    for (std::uint32_t c = 0; c < 3; ++c) {
      const VertexIndex a = mesh.triangles[t][c], b = mesh.triangles[t][(c + 1) % 3];
      uses.push_back({(std::uint64_t{std::min(a, b)} << 32) | std::max(a, b), 3 * t + c});
    }
  }
  std::sort(uses.begin(), uses.end(), [](const Use& x, const Use& y) {
    return x.key != y.key ? x.key < y.key : x.slot < y.slot;
  });
  std::vector<std::uint32_t> partner(uses.size(), no_index);
  std::vector<Vec3> thirds;
  std::vector<std::uint32_t> slots;
  for (std::size_t i = 0; i < uses.size();) {
    std::size_t j = i;
    while (j < uses.size() && uses[j].key == uses[i].key) ++j;
    if (j - i > 2) {
      const auto u = static_cast<VertexIndex>(uses[i].key >> 32), v = static_cast<VertexIndex>(uses[i].key);
      thirds.clear();
      slots.clear();
      for (std::size_t k = i; k < j; ++k) {
        const std::uint32_t t = uses[k].slot / 3, c = uses[k].slot % 3;
        slots.push_back(uses[k].slot);
        thirds.push_back(mesh.positions[mesh.triangles[t][(c + 2) % 3]]);
      }
      const std::optional<std::vector<std::size_t>> order =
          order_around_line(mesh.positions[u], mesh.positions[v], thirds);
      if (!order || (j - i) % 2 != 0) return std::nullopt;
      const auto runs_forward = [&](std::size_t k) {  // u -> v
        const std::uint32_t slot = slots[k];
        return mesh.triangles[slot / 3][slot % 3] == u;
      };
      const std::size_t count = order->size();
      for (std::size_t k = 0; k < count; ++k) {
        const std::size_t here = (*order)[k], next = (*order)[(k + 1) % count];
        if (runs_forward(here) == runs_forward(next)) return std::nullopt;
        if (runs_forward(here)) continue;
        partner[slots[here]] = slots[next] / 3;
        partner[slots[next]] = slots[here] / 3;
      }
    }
    i = j;
  }
  return partner;
}

std::vector<VertexFan> split_vertex_fans(Mesh& mesh, std::span<const std::uint32_t> partner) {
  const std::size_t n = mesh.positions.size();
  // The triangle corners at each vertex (corner = 3 t + c), grouped by vertex, in
  // triangle order within a vertex.
  std::vector<std::uint32_t> first(n + 1, 0);
  for (const Triangle& t : mesh.triangles) {
    for (const VertexIndex v : t) ++first[v + 1];
  }
  for (std::size_t v = 0; v < n; ++v) first[v + 1] += first[v];
  std::vector<std::uint32_t> slot(first.begin(), first.end() - 1), at(first.back());
  for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t) {
    for (std::uint32_t c = 0; c < 3; ++c) at[slot[mesh.triangles[t][c]]++] = 3 * t + c;
  }
  const auto vertex_of = [&](std::uint32_t corner, std::uint32_t step) {
    return mesh.triangles[corner / 3][(corner % 3 + step) % 3];
  };

  std::vector<VertexFan> split;
  UnionFind fans;
  std::vector<std::pair<VertexIndex, std::uint32_t>> entering;  // (w of the edge w -> v, position among v's corners)
  std::vector<std::uint32_t> fan_of_root;
  std::vector<VertexFan> found;
  for (VertexIndex v = 0; v < n; ++v) {
    const std::uint32_t begin = first[v], count = first[v + 1] - first[v];
    if (count < 2) continue;
    fans.reset(count);
    entering.clear();
    for (std::uint32_t i = 0; i < count; ++i) entering.push_back({vertex_of(at[begin + i], 2), i});
    std::sort(entering.begin(), entering.end());
    for (std::uint32_t i = 0; i < count; ++i) {
      // Corner i leaves v along its triangle's slot at that corner, v -> next; the
      // corners entering v along next -> v are its neighbours (only the paired one
      // on a non-manifold edge).
      const std::uint32_t corner = at[begin + i];
      const VertexIndex next = vertex_of(corner, 1);
      const std::uint32_t paired = partner.empty() ? no_index : partner[corner];
      auto it = std::lower_bound(entering.begin(), entering.end(), std::pair<VertexIndex, std::uint32_t>{next, 0});
      for (; it != entering.end() && it->first == next; ++it) {
        if (paired == no_index || paired == at[begin + it->second] / 3) fans.unite(i, it->second);
      }
    }
    fan_of_root.assign(count, no_index);
    found.clear();
    for (std::uint32_t i = 0; i < count; ++i) {
      const std::uint32_t root = fans.find(i);
      if (fan_of_root[root] == no_index) {
        fan_of_root[root] = static_cast<std::uint32_t>(found.size());
        found.push_back({v, v, {}});
      }
      found[fan_of_root[root]].corners.push_back(at[begin + i]);
    }
    if (found.size() < 2) continue;
    for (std::size_t f = 1; f < found.size(); ++f) {
      found[f].vertex = static_cast<VertexIndex>(mesh.positions.size());
      mesh.positions.push_back(mesh.positions[v]);
      for (const std::uint32_t c : found[f].corners) mesh.triangles[c / 3][c % 3] = found[f].vertex;
    }
    for (VertexFan& fan : found) split.push_back(std::move(fan));
  }
  return split;
}

}  // namespace shatter
