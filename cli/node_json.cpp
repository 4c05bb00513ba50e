#include "node_json.hpp"

#include <algorithm>

namespace shatter::cli {

using json = nlohmann::ordered_json;

std::vector<std::vector<std::size_t>> crossing_bonds_of_nodes(const MeshTree& tree) {
  std::vector<std::vector<std::size_t>> crossing(tree.nodes.size());
  const auto contains = [&](NodeIndex node, LeafIndex leaf) {
    const MeshTreeNode& n = tree.nodes[node];
    return leaf >= n.first_leaf && leaf - n.first_leaf < n.leaf_count;
  };
  for (std::size_t b = 0; b < tree.bonds.size(); ++b) {
    const Bond& bond = tree.bonds[b];
    // From each leaf up to (not including) the first node holding the other:
    // those are exactly the nodes the bond leaves.
    for (const auto& [from, to] : {std::pair{bond.first, bond.second}, std::pair{bond.second, bond.first}}) {
      for (NodeIndex node = tree.leaf_nodes[from]; node != no_node && !contains(node, to);
           node = tree.nodes[node].parent) {
        crossing[node].push_back(b);
      }
    }
  }
  return crossing;
}

json nodes_json(const MeshTree& tree, std::span<const NodeIndex> nodes) {
  const std::vector<std::vector<std::size_t>> crossing = crossing_bonds_of_nodes(tree);
  json out = json::array();
  for (NodeIndex index : nodes) {
    const MeshTreeNode& node = tree.nodes[index];
    json entry{{"node", index}, {"depth", node.depth}};
    if (node.is_leaf()) entry["leaf"] = node.first_leaf;
    entry["first_leaf"] = node.first_leaf;
    entry["leaf_count"] = node.leaf_count;
    entry["volume"] = node.mass.volume;
    entry["centroid"] = {node.mass.centroid.x, node.mass.centroid.y, node.mass.centroid.z};
    entry["triangles"] = node.mesh->triangle_count();
    entry["cap_triangles"] = static_cast<std::size_t>(std::count_if(
        node.mesh->surfaces.begin(), node.mesh->surfaces.end(), [](SurfaceId s) { return s != original_surface; }));
    json bonds = json::array();
    for (std::size_t b : crossing[index]) {
      const Bond& bond = tree.bonds[b];
      const bool first_inside = bond.first >= node.first_leaf && bond.first - node.first_leaf < node.leaf_count;
      bonds.push_back({{"leaf", first_inside ? bond.first : bond.second},
                       {"other", first_inside ? bond.second : bond.first},
                       {"area", bond.area}});
    }
    entry["bonds"] = std::move(bonds);
    out.push_back(std::move(entry));
  }
  return out;
}

}  // namespace shatter::cli
