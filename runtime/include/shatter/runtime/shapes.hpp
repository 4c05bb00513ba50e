#pragma once
// What every breakable object made from one mesh tree shares, computed once when
// the tree is loaded: one Bullet convex hull shape per tree node (the node's
// convex hull, precomputed by the tree), the bond graph's starting clusters and
// each cluster's bonds. A body made later only picks existing hull shapes for its
// compound collider; nothing here is rebuilt after an impact (seed thesis ch. 6.3
// found building colliders after every collision to be a main cost).

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "shatter/meshtree/tree.hpp"

namespace shatter::runtime {

/// Index of a bond in MeshTree::bonds.
using BondIndex = std::uint32_t;

/// How the node shapes are made.
struct ShapeOptions {
  /// Bullet's collision margin of every hull shape, in metres (tree units). Bullet
  /// inflates a convex shape by its margin, so fragments that touch overlap by
  /// twice this once they are separate bodies; the solver pushes them apart
  /// without counting it as an impulse (split impulse). Bullet's own default,
  /// 0.04 m, is larger than the fragments of a finely broken metre-sized object.
  /// Must be > 0 and finite.
  double collision_margin = 0.002;
};

/// A connected set of leaves of the bond graph and the bonds among them.
struct Cluster {
  std::vector<LeafIndex> leaves;  ///< increasing
  std::vector<BondIndex> bonds;   ///< increasing; both leaves of each are in `leaves`
};

/// The shared, immutable collider and bond data of one mesh tree. Objects and
/// worlds hold it by shared_ptr; it must outlive every World that uses it
/// (holding the shared_ptr guarantees that).
class BreakableShapes {
 public:
  /// Builds one btConvexHullShape per node of `tree` from MeshTree::hull_of(node)
  /// (its positions, taken relative to the node's centroid so every shape sits
  /// near its own origin, with ShapeOptions::collision_margin), each node's
  /// unit-density RigidMass, the bond graph as flat arrays (each leaf's bonds,
  /// the bonds' centroids, a k-d tree over them), and the connected components
  /// of the bond graph over all leaves (union-find), each with its bonds and
  /// minimal cover: the clusters a new breakable object starts as.
  /// Preconditions: `tree` is well formed (as build_mesh_tree and
  /// read_shatter_file return it), non-empty, every node's hull has at least one
  /// position, all finite, every node's volume positive, every bond's leaves in
  /// range and distinct, its centroid finite. Throws std::invalid_argument
  /// naming the first node or bond at fault otherwise, and for a bad
  /// ShapeOptions.
  /// Complexity: O(total hull positions + nodes + bonds log bonds), one 3x3
  /// eigendecomposition per node; no hull is computed, only copied.
  static std::shared_ptr<const BreakableShapes> create(std::shared_ptr<const MeshTree> tree,
                                                       const ShapeOptions& options = {});

  ~BreakableShapes();
  BreakableShapes(const BreakableShapes&) = delete;
  BreakableShapes& operator=(const BreakableShapes&) = delete;

  const MeshTree& tree() const;
  const ShapeOptions& options() const;
  /// The connected components of the whole bond graph, ordered by their smallest
  /// leaf: one when every leaf is bonded to the rest, as after a normal build.
  std::span<const Cluster> initial_clusters() const;
  /// Implementation detail, for the runtime's own sources: the Bullet shapes.
  struct Impl;
  const Impl& impl() const { return *impl_; }

 private:
  explicit BreakableShapes(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace shatter::runtime
