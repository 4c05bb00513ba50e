// Tree statistics: counts, fragment volume spread, bonds.

#include "shatter/meshtree/stats.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <numeric>

#include "shatter/meshtree/bonds.hpp"
#include "shatter/meshtree/packed_node.hpp"

namespace shatter {

double median_of(std::vector<double>& values) {
  if (values.empty()) return 0;
  const std::size_t middle = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(middle), values.end());
  const double upper = values[middle];
  if (values.size() % 2 == 1) return upper;
  // nth_element leaves every smaller value before `middle`: the lower middle is their maximum.
  const double lower = *std::max_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(middle));
  return std::midpoint(lower, upper);
}

namespace {

VolumeSpread spread_of(std::vector<double> volumes) {
  VolumeSpread spread;
  if (volumes.empty()) return spread;
  const auto [min, max] = std::minmax_element(volumes.begin(), volumes.end());
  spread.min = *min;
  spread.max = *max;
  const double count = static_cast<double>(volumes.size());
  double sum = 0;
  for (double v : volumes) sum += v;
  spread.mean = sum / count;
  // Two passes: the deviations are taken from the mean, which keeps the variance
  // accurate when the fragments are nearly equal (the one-pass formula cancels).
  double squared_deviations = 0;
  for (double v : volumes) squared_deviations += (v - spread.mean) * (v - spread.mean);
  const double deviation = std::sqrt(squared_deviations / count);
  spread.coefficient_of_variation = spread.mean != 0 ? deviation / spread.mean : 0;
  spread.median = median_of(volumes);
  return spread;
}

}  // namespace

TreeStats tree_stats(const MeshTree& tree) {
  TreeStats stats;
  stats.node_count = tree.nodes.size();
  stats.leaf_count = tree.leaf_count();
  stats.internal_count = stats.node_count - std::min(stats.leaf_count, stats.node_count);
  if (tree.nodes.empty()) return stats;

  for (const MeshTreeNode& node : tree.nodes) stats.max_depth = std::max(stats.max_depth, node.depth);
  stats.root_volume = tree.nodes.front().mass.volume;

  std::vector<double> volumes;
  volumes.reserve(tree.leaf_count());
  stats.min_leaf_depth = tree.leaf_nodes.empty() ? 0 : stats.max_depth;
  for (NodeIndex index : tree.leaf_nodes) {
    const MeshTreeNode& leaf = tree.nodes.at(index);
    volumes.push_back(leaf.mass.volume);
    stats.total_leaf_volume += leaf.mass.volume;  // in leaf order: the same sum on any thread count
    stats.min_leaf_depth = std::min(stats.min_leaf_depth, leaf.depth);
  }
  // The leaves' sizes; a packed leaf's (a lean tree's, pack_leaves) are read
  // from its bytes' counts and surface runs, not unpacked: whole-number sums,
  // in any order, on the caller's threads.
  std::atomic<std::size_t> triangles{0}, vertices{0}, cap_triangles{0};
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, tree.leaf_nodes.size(), 1024),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      std::size_t t = 0, v = 0, c = 0;
                      for (std::size_t i = range.begin(); i != range.end(); ++i) {
                        const NodeIndex leaf = tree.leaf_nodes[i];
                        if (tree.is_packed(leaf)) {
                          const PackedMeshSizes sizes = packed_mesh_sizes(tree.packed_shapes[leaf]);
                          t += sizes.triangles;
                          v += sizes.vertices;
                          c += sizes.cap_triangles;
                          continue;
                        }
                        const Mesh& mesh = tree.nodes[leaf].mesh;
                        t += mesh.triangle_count();
                        v += mesh.vertex_count();
                        c += static_cast<std::size_t>(std::count_if(mesh.surfaces.begin(), mesh.surfaces.end(),
                                                                    [](SurfaceId surface) { return surface != original_surface; }));
                      }
                      triangles += t;
                      vertices += v;
                      cap_triangles += c;
                    });
  stats.leaf_triangles = triangles;
  stats.leaf_vertices = vertices;
  stats.leaf_cap_triangles = cap_triangles;
  stats.fragment_volume = spread_of(std::move(volumes));

  stats.bond_count = tree.bond_count();
  for (std::size_t i = 0; i < tree.bond_count(); ++i) stats.total_bond_area += tree.bond(i).area;
  return stats;
}

}  // namespace shatter
