#pragma once
// Mass properties of a cluster of fragments (seed thesis ch. 5.2.3), from the
// exact mass properties each mesh tree node stores: the nodes of the cluster's
// minimal cover are combined by the parallel-axis theorem, and the body frame is
// put at the centroid on the principal axes, so the rigid body's inertia is
// diagonal there.

#include <span>

#include "shatter/kernel/mass.hpp"
#include "shatter/meshtree/tree.hpp"
#include "shatter/runtime/transform.hpp"

namespace shatter::runtime {

/// A rigid body's mass properties. Units: kg, m, kg m^2; coordinates are the mesh
/// tree's ("tree coordinates").
struct RigidMass {
  double mass = 0;  ///< density times volume
  Vec3 centroid;    ///< centre of mass
  /// Inertia tensor about the centroid along the tree's axes, row-major, symmetric.
  Matrix3 inertia{};
  /// The inertia in the body frame: its eigenvalues, ascending.
  Vec3 principal_moments;
  /// The body frame in tree coordinates: origin at the centroid, axes the
  /// principal axes (a proper rotation: right-handed, determinant +1), so
  /// inertia = R diag(principal_moments) R^T with R = matrix_of(frame.rotation).
  RigidTransform frame;
};

/// Combines parts of one solid, each with its unit-density MassProperties, into
/// the solid's RigidMass at `density` (kg/m^3): volumes add up, the centroid is
/// their volume-weighted mean, and each part's inertia is moved to that centroid
/// by the parallel-axis theorem, I += V (|d|^2 Id - d d^T), before adding up.
/// The principal axes come from Eigen's SelfAdjointEigenSolver; each is signed so
/// its largest component is positive, and the third is the cross product of the
/// first two, so the frame is right-handed and the same on every run.
/// Preconditions: at least one part; every part's volume > 0 and finite values;
/// density > 0 and finite. Throws std::invalid_argument otherwise (naming the
/// first part at fault).
/// Complexity: O(parts), plus one 3x3 eigendecomposition.
RigidMass combine_masses(std::span<const MassProperties> parts, double density);

/// The RigidMass of the solid made of the tree nodes `nodes` (e.g. a minimal
/// cover), from the mass properties stored in each node: combine_masses of
/// tree.nodes[n].mass over n in `nodes`.
/// Preconditions: as combine_masses; every index < tree.nodes.size() (throws
/// std::invalid_argument otherwise). The nodes should not overlap (a cover's never
/// do); overlapping ones are counted twice.
RigidMass cluster_mass(const MeshTree& tree, std::span<const NodeIndex> nodes, double density);

}  // namespace shatter::runtime
