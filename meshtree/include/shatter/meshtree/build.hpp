#pragma once
// The recursive builder: cuts a solid into at least N fragments and keeps every
// level as a MeshTree (seed thesis ch. 4, listing 4.1), then finds the bonds.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include "shatter/kernel/exact.hpp"
#include "shatter/kernel/mesh.hpp"
#include "shatter/meshtree/tree.hpp"

namespace shatter {

/// Called once per finished leaf with the number finished so far. May be called
/// from any worker thread, concurrently: it must be thread-safe and cheap.
using LeafProgressFn = std::function<void(std::size_t leaves_done)>;

/// Where a build's time went, and how often a drawn plane was not used. The
/// counts are part of the deterministic build; the seconds are wall-clock.
struct BuildReport {
  /// Cutting, mass properties, and making the stored meshes: validating the
  /// pieces (fast, exact kernels) or rounding them once, certified (plane kernel).
  double cutting_seconds = 0;
  double hull_seconds = 0;     ///< convex hulls of every node (in parallel)
  double bond_seconds = 0;     ///< find_bonds
  std::uint64_t planes_missed = 0;    ///< drawn planes that missed their node
  /// Drawn planes that passed within 1e-8 of the node's size of a vertex, or whose
  /// rounded pieces were not valid solids (fast, exact kernels); plane kernel:
  /// planes that left a piece that cannot be written as a valid double mesh.
  std::uint64_t planes_rejected = 0;
};

/// Builds the mesh tree of `mesh` with `options` (see BuildOptions, Strategy).
/// Preconditions: options.fragments >= 1 and every triangle of `mesh` on surface 0
/// (std::invalid_argument otherwise). The mesh is validated first, unless
/// options.input_validated says the caller did: a mesh that is not a closed,
/// oriented 2-manifold with positive volume, or that intersects itself (unless
/// options.allow_self_intersections), is refused with InvalidMeshError naming its
/// first defect.
/// Guarantees: at least options.fragments leaves, and no leaf cut that was not
/// needed to reach that count; every node's stored mesh a valid solid (closed,
/// oriented, 2-manifold, positive volume, no zero-area triangle, no
/// self-intersection; with allow_self_intersections only the topology), because a
/// plane whose rounded pieces are not is redrawn; children partition their parent
/// (exact kernel: exactly, in the exact solids; fast: up to rounding of the cut
/// points); leaf ranges contiguous; cap triangles carry cap_surface_of(cut node);
/// mass properties and hulls filled; bonds = find_bonds(tree); shatter_version
/// this library's version_string (shatter/version.hpp). One version of shatter
/// gives a result that depends only on the mesh and the options other than
/// `threads`: byte-identical on any machine and thread count.
/// Throws UnsupportedGeometryError when none of max_plane_tries planes gives a node
/// valid pieces (all missed it, or its pieces are thinner than rounding).
/// When `report` is given, it is filled in.
MeshTree build_mesh_tree(const Mesh& mesh, const BuildOptions& options, const LeafProgressFn& progress = {},
                         BuildReport* report = nullptr);

/// The same build, also returning every node's exact solid (node order) when
/// options.kernel is exact (empty otherwise): the tree's meshes are those solids
/// rounded to the nearest doubles, so only these show that volumes add up exactly.
struct ExactBuild {
  MeshTree tree;
  std::vector<ExactMesh> exact_meshes;
};
ExactBuild build_mesh_tree_keeping_exact(const Mesh& mesh, const BuildOptions& options);

}  // namespace shatter
