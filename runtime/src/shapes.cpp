#include "shatter/runtime/shapes.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "shapes_impl.hpp"
#include "shatter/kernel/union_find.hpp"
#include "shatter/meshtree/bonds.hpp"
#include "shatter/meshtree/cover.hpp"

namespace shatter::runtime {

namespace {

std::unique_ptr<btConvexHullShape> hull_shape(const MeshTree& tree, NodeIndex node, double margin) {
  const Mesh& hull = tree.hull_of(node);
  const Vec3 centre = tree.nodes[node].mass.centroid;
  if (hull.positions.empty()) {
    throw std::invalid_argument("BreakableShapes: node " + std::to_string(node) + " has an empty convex hull");
  }
  if (!(tree.nodes[node].mass.volume > 0) || !is_finite(centre)) {
    throw std::invalid_argument("BreakableShapes: node " + std::to_string(node) +
                                " has a non-positive volume or a non-finite centroid");
  }
  auto shape = std::make_unique<btConvexHullShape>();
  for (const Vec3& p : hull.positions) {
    if (!is_finite(p)) {
      throw std::invalid_argument("BreakableShapes: node " + std::to_string(node) + " has a non-finite hull position");
    }
    shape->addPoint(btVector3(p.x - centre.x, p.y - centre.y, p.z - centre.z), false);
  }
  shape->recalcLocalAabb();
  shape->setMargin(margin);
  shape->setUserIndex(static_cast<int>(node));
  return shape;
}

// Splits order[begin, end) at its median along the widest axis of its box until
// at most `leaf_size` centroids are left; nth_element is deterministic, so the
// tree is the same on every run.
std::uint32_t build_search_node(BondSearchTree& search, const std::vector<Vec3>& centroids, std::uint32_t begin,
                                std::uint32_t end) {
  constexpr std::uint32_t leaf_size = 8;
  BondSearchTree::Node node;
  node.begin = begin;
  node.end = end;
  node.lo = node.hi = centroids[search.order[begin]];
  for (std::uint32_t i = begin; i < end; ++i) {
    const Vec3 c = centroids[search.order[i]];
    node.lo = {std::min(node.lo.x, c.x), std::min(node.lo.y, c.y), std::min(node.lo.z, c.z)};
    node.hi = {std::max(node.hi.x, c.x), std::max(node.hi.y, c.y), std::max(node.hi.z, c.z)};
  }
  const auto index = static_cast<std::uint32_t>(search.nodes.size());
  search.nodes.push_back(node);
  if (end - begin <= leaf_size) return index;
  const Vec3 extent = node.hi - node.lo;
  const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : extent.y >= extent.z ? 1 : 2;
  const std::uint32_t middle = begin + (end - begin) / 2;
  std::nth_element(search.order.begin() + begin, search.order.begin() + middle, search.order.begin() + end,
                   [&](BondIndex a, BondIndex b) {
                     const double ca = centroids[a][axis], cb = centroids[b][axis];
                     return ca < cb || (ca == cb && a < b);
                   });
  const std::uint32_t left = build_search_node(search, centroids, begin, middle);
  const std::uint32_t right = build_search_node(search, centroids, middle, end);
  search.nodes[index].left = left;
  search.nodes[index].right = right;
  return index;
}

BondSearchTree build_search_tree(const std::vector<Vec3>& centroids) {
  BondSearchTree search;
  if (centroids.empty()) return search;
  search.order.resize(centroids.size());
  for (BondIndex b = 0; b < centroids.size(); ++b) search.order[b] = b;
  build_search_node(search, centroids, 0, static_cast<std::uint32_t>(centroids.size()));
  search.points.reserve(centroids.size());
  for (BondIndex b : search.order) search.points.push_back(centroids[b]);
  return search;
}

}  // namespace

BreakableShapes::BreakableShapes(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
BreakableShapes::~BreakableShapes() = default;

const MeshTree& BreakableShapes::tree() const { return *impl_->tree; }
const ShapeOptions& BreakableShapes::options() const { return impl_->options; }
std::span<const Cluster> BreakableShapes::initial_clusters() const { return impl_->initial_clusters; }

std::shared_ptr<const BreakableShapes> BreakableShapes::create(std::shared_ptr<const MeshTree> tree,
                                                               const ShapeOptions& options) {
  if (!tree || tree->nodes.empty() || tree->leaf_count() == 0) {
    throw std::invalid_argument("BreakableShapes: the mesh tree is empty");
  }
  if (!(options.collision_margin > 0) || !std::isfinite(options.collision_margin)) {
    throw std::invalid_argument("BreakableShapes: the collision margin must be positive and finite");
  }
  auto impl = std::make_unique<Impl>();
  impl->options = options;
  impl->node_shapes.reserve(tree->nodes.size());
  for (NodeIndex node = 0; node < tree->nodes.size(); ++node) {
    impl->node_shapes.push_back(hull_shape(*tree, node, options.collision_margin));
    impl->node_masses.push_back(cluster_mass(*tree, std::span<const NodeIndex>(&node, 1), 1.0));
  }

  const std::size_t leaves = tree->leaf_count();
  const std::size_t bond_count = tree->bonds.size();
  UnionFind sets(leaves);
  impl->adjacency_begin.assign(leaves + 1, 0);
  impl->bond_centroids.reserve(bond_count);
  impl->bond_first.reserve(bond_count);
  for (std::size_t b = 0; b < bond_count; ++b) {
    const Bond& bond = tree->bonds[b];
    if (bond.first >= leaves || bond.second >= leaves || bond.first == bond.second || !is_finite(bond.centroid)) {
      throw std::invalid_argument("BreakableShapes: bond " + std::to_string(b) +
                                  " names a leaf out of range, joins a leaf to itself or has a non-finite centroid");
    }
    sets.unite(bond.first, bond.second);
    ++impl->adjacency_begin[bond.first + 1];
    ++impl->adjacency_begin[bond.second + 1];
    impl->bond_centroids.push_back(bond.centroid);
    impl->bond_first.push_back(bond.first);
  }
  for (std::size_t leaf = 0; leaf < leaves; ++leaf) impl->adjacency_begin[leaf + 1] += impl->adjacency_begin[leaf];
  impl->adjacent_bond.resize(2 * bond_count);
  impl->adjacent_leaf.resize(2 * bond_count);
  std::vector<std::uint32_t> fill(impl->adjacency_begin.begin(), impl->adjacency_begin.end() - 1);
  for (BondIndex b = 0; b < bond_count; ++b) {
    const Bond& bond = tree->bonds[b];
    impl->adjacent_bond[fill[bond.first]] = b;
    impl->adjacent_leaf[fill[bond.first]++] = bond.second;
    impl->adjacent_bond[fill[bond.second]] = b;
    impl->adjacent_leaf[fill[bond.second]++] = bond.first;
  }
  impl->bond_search = build_search_tree(impl->bond_centroids);

  // Clusters numbered by their smallest leaf, which is also their representative.
  impl->initial_cluster_of_leaf.assign(leaves, UINT32_MAX);
  std::vector<std::uint32_t> cluster_of_root(leaves, UINT32_MAX);
  for (LeafIndex leaf = 0; leaf < leaves; ++leaf) {
    const LeafIndex root = sets.find(leaf);
    if (cluster_of_root[root] == UINT32_MAX) {
      cluster_of_root[root] = static_cast<std::uint32_t>(impl->initial_clusters.size());
      impl->initial_clusters.emplace_back();
    }
    impl->initial_cluster_of_leaf[leaf] = cluster_of_root[root];
    impl->initial_clusters[cluster_of_root[root]].leaves.push_back(leaf);
  }
  for (BondIndex b = 0; b < bond_count; ++b) {
    impl->initial_clusters[impl->initial_cluster_of_leaf[tree->bonds[b].first]].bonds.push_back(b);
  }
  for (const Cluster& cluster : impl->initial_clusters) {
    impl->initial_covers.push_back(minimal_cover(*tree, cluster.leaves));
  }
  impl->tree = std::move(tree);
  return std::shared_ptr<const BreakableShapes>(new BreakableShapes(std::move(impl)));
}

}  // namespace shatter::runtime
