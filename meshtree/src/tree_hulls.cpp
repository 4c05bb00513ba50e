#include "tree_hulls.hpp"

#include <tbb/parallel_for.h>

#include <utility>
#include <vector>

#include "shatter/cut/hull.hpp"

namespace shatter::detail {

void tree_hulls(tbb::task_arena& arena, MeshTree& tree) {
  std::vector<std::vector<NodeIndex>> by_depth;
  for (NodeIndex v = 0; v < tree.nodes.size(); ++v) {
    const std::uint32_t depth = tree.nodes[v].depth;
    if (by_depth.size() <= depth) by_depth.resize(depth + 1);
    by_depth[depth].push_back(v);
  }
  for (std::size_t d = by_depth.size(); d-- > 0;) {
    const std::vector<NodeIndex>& level = by_depth[d];
    arena.execute([&] {
      tbb::parallel_for(std::size_t{0}, level.size(), [&](std::size_t i) {
        MeshTreeNode& node = tree.nodes[level[i]];
        if (node.convex) return;
        NodeShapes shapes(tree);  // a lean build's nodes are packed
        if (node.is_leaf()) {
          // A lean build's leaf has it already, unless its cut was undone.
          if (!node.hull.present()) node.hull = convex_hull_of(shapes.mesh(level[i]));
          return;
        }
        std::vector<Vec3> points;
        for (const NodeIndex c : node.children) {
          const Mesh& child_hull = tree.nodes[c].convex ? shapes.mesh(c) : *std::as_const(tree.nodes[c]).hull;
          points.insert(points.end(), child_hull.positions.begin(), child_hull.positions.end());
        }
        node.hull = convex_hull_of_points(points);
      });
    });
  }
}

}  // namespace shatter::detail
