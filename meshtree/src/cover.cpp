#include "shatter/meshtree/cover.hpp"

#include <array>
#include <stdexcept>
#include <string>

namespace shatter {
namespace {

// LSD radix sort on 8-bit digits. A comparison sort would make the cover
// O(n log n); the digits are bounded by the leaf count, so only the passes the
// largest possible index needs are run.
void radix_sort(std::vector<LeafIndex>& values, LeafIndex largest_possible) {
  constexpr int digit_bits = 8;
  constexpr std::size_t bucket_count = std::size_t{1} << digit_bits;
  std::vector<LeafIndex> scratch(values.size());
  for (int shift = 0; shift < 32 && (largest_possible >> shift) != 0; shift += digit_bits) {
    std::array<std::size_t, bucket_count> starts{};
    for (const LeafIndex v : values) ++starts[(v >> shift) & (bucket_count - 1)];
    std::size_t next = 0;
    for (std::size_t& start : starts) {
      const std::size_t count = start;
      start = next;
      next += count;
    }
    for (const LeafIndex v : values) scratch[starts[(v >> shift) & (bucket_count - 1)]++] = v;
    values.swap(scratch);
  }
}

}  // namespace

std::vector<NodeIndex> minimal_cover(const MeshTree& tree, std::span<const LeafIndex> leaves) {
  const std::size_t leaf_count = tree.leaf_count();
  for (const LeafIndex leaf : leaves) {
    if (leaf >= leaf_count) {
      throw std::invalid_argument("minimal_cover: leaf " + std::to_string(leaf) + " is out of range (the tree has " +
                                  std::to_string(leaf_count) + " leaves)");
    }
  }
  std::vector<NodeIndex> cover;
  if (leaves.empty()) return cover;

  std::vector<LeafIndex> sorted(leaves.begin(), leaves.end());
  radix_sort(sorted, static_cast<LeafIndex>(leaf_count - 1));

  std::size_t i = 0;
  while (i < sorted.size()) {
    // A maximal run [run_begin, run_end) of consecutive leaf indices (duplicates
    // skipped): no cover node can straddle a gap, so each run is covered alone.
    const std::size_t run_begin = sorted[i];
    std::size_t run_end = run_begin + 1;
    for (++i; i < sorted.size() && sorted[i] <= run_end; ++i) {
      if (sorted[i] == run_end) ++run_end;
    }

    std::size_t next_leaf = run_begin;
    while (next_leaf < run_end) {
      // The highest ancestor of next_leaf inside the run starts at next_leaf: an
      // ancestor starting earlier would contain the node emitted just before,
      // whose parent already failed to fit.
      NodeIndex node = tree.leaf_nodes[next_leaf];
      for (;;) {
        const NodeIndex parent = tree.nodes[node].parent;
        if (parent == no_node) break;
        const MeshTreeNode& p = tree.nodes[parent];
        if (p.first_leaf != next_leaf || std::size_t{p.first_leaf} + p.leaf_count > run_end) break;
        node = parent;
      }
      cover.push_back(node);
      next_leaf = std::size_t{tree.nodes[node].first_leaf} + tree.nodes[node].leaf_count;
    }
  }
  return cover;
}

}  // namespace shatter
