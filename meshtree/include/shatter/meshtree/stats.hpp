#pragma once
// Summary statistics of a mesh tree: its shape (counts, depth), how evenly it
// split the solid (fragment volume spread, the seed thesis's complaint about the
// bunny), and how strongly the fragments hold together (bonds). `shatter info`
// prints them; the benchmarks compare strategies with them.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "shatter/meshtree/tree.hpp"

namespace shatter {

/// The spread of the leaves' volumes (nodes[leaf].mass.volume, unit density).
struct VolumeSpread {
  double min = 0;
  /// The middle value in sorted order; for an even count, the mean of the two
  /// middle values.
  double median = 0;
  double max = 0;
  double mean = 0;
  /// Population standard deviation divided by the mean: 0 for equal fragments.
  /// 0 when there are no leaves or the mean is 0 (a degenerate tree).
  double coefficient_of_variation = 0;
};

struct TreeStats {
  std::size_t node_count = 0;
  std::size_t leaf_count = 0;
  std::size_t internal_count = 0;  ///< node_count - leaf_count
  std::uint32_t max_depth = 0;     ///< depth of the deepest node; 0 for a lone root
  std::uint32_t min_leaf_depth = 0;

  VolumeSpread fragment_volume;
  double root_volume = 0;       ///< nodes[0].mass.volume
  double total_leaf_volume = 0; ///< sum over the leaves, in leaf order (equals root_volume up to rounding)

  std::size_t bond_count = 0;
  double total_bond_area = 0;   ///< sum of Bond::area, in bond order

  std::size_t leaf_triangles = 0;      ///< triangles over all leaves
  std::size_t leaf_cap_triangles = 0;  ///< of which on a cap (surface id > 0)
  std::size_t leaf_vertices = 0;       ///< vertices over all leaves (each leaf's own, welded)
};

/// Computes the statistics of `tree` from its nodes' stored fields and mass
/// properties (nothing is recomputed from the meshes but triangle counts).
/// Deterministic: sums run in leaf (or bond) order. An empty tree gives all zeros.
TreeStats tree_stats(const MeshTree& tree);

/// The median of `values` (reordered in place): the middle value, or for an even
/// count the mean of the two middle values; 0 for no values.
double median_of(std::vector<double>& values);

}  // namespace shatter
