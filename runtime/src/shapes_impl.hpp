#pragma once
// BreakableShapes' private part, shared by the runtime's sources (never installed).

#include <btBulletCollisionCommon.h>

#include <memory>
#include <vector>

#include "shatter/runtime/mass.hpp"
#include "shatter/runtime/shapes.hpp"

namespace shatter::runtime {

/// A static k-d tree over the bonds' centroids, for "which bonds lie within r of
/// this point" in O(log B + answers): a discrete bond farther than the breaking
/// radius cannot break, so a discrete impact needs only those.
struct BondSearchTree {
  struct Node {
    Vec3 lo, hi;                        ///< bounding box of its centroids
    std::uint32_t begin = 0, end = 0;   ///< its range of `order`
    std::uint32_t left = 0, right = 0;  ///< children; both 0 for a leaf (the root is never a child)
  };
  std::vector<Node> nodes;       ///< nodes[0] is the root (absent when there are no bonds)
  std::vector<BondIndex> order;  ///< bonds in leaf order
  std::vector<Vec3> points;      ///< points[i] is the centroid of bond order[i]

  /// Calls visit(bond, |c - centre|^2) for every bond whose centroid c has
  /// |c - centre| <= radius (tested in doubles), in tree order.
  template <class Visit>
  void for_each_within(Vec3 centre, double radius, Visit&& visit) const {
    if (nodes.empty()) return;
    const double radius2 = radius * radius;
    std::uint32_t stack[64];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const Node& node = nodes[stack[--top]];
      double gap2 = 0;
      for (int axis = 0; axis < 3; ++axis) {
        const double c = centre[axis];
        const double below = node.lo[axis] - c, above = c - node.hi[axis];
        const double gap = below > 0 ? below : above > 0 ? above : 0;
        gap2 += gap * gap;
      }
      if (gap2 > radius2) continue;
      if (node.left == 0) {
        for (std::uint32_t i = node.begin; i < node.end; ++i) {
          const Vec3 d = points[i] - centre;
          const double distance2 = dot(d, d);
          if (distance2 <= radius2) visit(order[i], distance2);
        }
      } else {
        stack[top++] = node.right;
        stack[top++] = node.left;
      }
    }
  }
};

struct BreakableShapes::Impl {
  std::shared_ptr<const MeshTree> tree;
  ShapeOptions options;
  /// One per tree node, its points relative to the node's centroid; its user
  /// index is the node index, so a compound's children name their nodes.
  /// Bullet's compound takes non-const child pointers but never changes a child
  /// during collision, so one shape serves every compound and every world.
  std::vector<std::unique_ptr<btConvexHullShape>> node_shapes;
  /// Per node, its RigidMass at unit density, so a body of one node needs no
  /// eigendecomposition.
  std::vector<RigidMass> node_masses;

  /// The bond graph as flat arrays: leaf l's bonds are
  /// adjacent_bond[adjacency_begin[l] .. adjacency_begin[l + 1]), the leaf across
  /// each in adjacent_leaf at the same place.
  std::vector<std::uint32_t> adjacency_begin;
  std::vector<BondIndex> adjacent_bond;
  std::vector<LeafIndex> adjacent_leaf;
  std::vector<Vec3> bond_centroids;   ///< per bond, packed for the damage loop
  std::vector<LeafIndex> bond_first;  ///< per bond, its first leaf (whose cluster is the bond's)
  BondSearchTree bond_search;

  std::vector<Cluster> initial_clusters;
  std::vector<std::vector<NodeIndex>> initial_covers;  ///< minimal cover of each initial cluster
  std::vector<std::uint32_t> initial_cluster_of_leaf;
};

}  // namespace shatter::runtime
