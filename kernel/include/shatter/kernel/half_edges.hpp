#pragma once
// Half-edge twins of a triangle mesh, by index: the one topology pass that
// separating solids, finding shells and building the plane kernel's solid share.

#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <vector>

#include "shatter/kernel/mesh.hpp"

namespace shatter {

/// Half-edge 3t + c runs from corner c of triangle t to corner c + 1 (mod 3).
struct HalfEdgeTwins {
  static constexpr std::uint32_t none = std::numeric_limits<std::uint32_t>::max();
  /// #3T: the half-edge running the other way along the same edge, or `none`
  /// (a boundary edge, or, where a directed edge repeats, one of its copies).
  std::vector<std::uint32_t> twin;
  /// The first directed edge (from, to) used by two half-edges, scanning half-edges
  /// in order; then `twin` pairs only the first copy. Empty when none repeats.
  std::optional<Edge> repeated;
  /// The first half-edge without a twin, or `none`: the mesh is closed exactly when
  /// it is `none` and nothing repeats.
  std::uint32_t first_unmatched = none;
};

/// Pairs every half-edge with its reverse, by vertex index only.
/// Preconditions: every index < vertex_count; no triangle repeats an index;
/// 3 * triangles.size() < 2^32 - 1.
/// Guarantees: deterministic; twin is an involution on the paired half-edges.
/// Cost: linear, on flat arrays (the half-edges leaving each vertex are gathered
/// by a counting sort, and a twin is found in its target's short list): no hash
/// table, whose random probes cost more than the rest on large meshes.
HalfEdgeTwins half_edge_twins(std::span<const Triangle> triangles, std::size_t vertex_count);

}  // namespace shatter
