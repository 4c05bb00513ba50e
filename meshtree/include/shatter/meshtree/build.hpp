#pragma once
// The recursive builder: cuts a solid into at least N fragments and keeps every
// level as a MeshTree (seed thesis ch. 4, listing 4.1), then finds the bonds; and
// the options that decide what it builds. A tree records those options, so
// tree.hpp includes this header; the declarations here therefore name MeshTree
// by a forward declaration, and tree.hpp is included last, for the callers.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <string_view>

#include "shatter/kernel/mesh.hpp"

namespace shatter {

/// How the builder picks the next plane and the next node to cut.
enum class Strategy : std::uint8_t {
  /// A random plane through the node's volume centroid; a node's fragment budget is
  /// shared evenly among its children, whatever their size (the seed's method).
  thesis = 0,
  /// A random plane through the centroid, always cutting the largest-volume leaf
  /// next, which evens out fragment sizes.
  balanced = 1,
  /// Planes across the node's longest bounding-box axis (X, Y or Z) near the
  /// centroid, with offset and angle jitter (as PhysX APEX slices); the budget is
  /// shared among the children in proportion to their volume.
  axis = 2,
};

/// The kernel that made a tree (DESIGN.md, "Exact arithmetic"). Every tree this
/// version builds is `plane`: plane-based vertices (kernel/implicit.hpp), exact at
/// any depth and rounded once, certified. `fast` (rounded cut points) and `exact`
/// (CGAL Epeck rationals, rounded per node) are retired: the trees they made
/// still read (.shatter versions 1 and 2), and this says how they were made.
enum class KernelKind : std::uint8_t { fast = 0, exact = 1, plane = 2 };

/// The strategy's name as the CLI spells it ("thesis", "balanced", "axis");
/// "unknown" for a value outside the enum. Never throws.
std::string_view strategy_name(Strategy strategy);
/// The kernel's name as `shatter info` prints it ("fast", "exact", "plane");
/// "unknown" for a value outside the enum. Never throws.
std::string_view kernel_name(KernelKind kernel);
/// The strategy strategy_name spells `name`; nullopt for any other text. Never
/// throws.
std::optional<Strategy> strategy_named(std::string_view name);

/// Everything that decides a tree's contents. Two builds with equal options on
/// equal input give byte-identical trees, whatever `threads` is.
struct BuildOptions {
  std::uint32_t fragments = 2;  ///< stop at the first leaf count >= this (>= 1)
  std::uint64_t seed = 1;
  Strategy strategy = Strategy::thesis;
  /// Provenance, not a choice: build_mesh_tree builds only `plane` trees (and
  /// refuses any other value); a tree read from an older file may say otherwise.
  KernelKind kernel = KernelKind::plane;
  double interior_uv_scale = 1.0;
  /// Planes drawn for one node before the build fails. A plane is redrawn when it
  /// misses the node, or when a piece cannot be written as a valid double mesh
  /// (a sliver thinner than the rounding of its coordinates, or a pinch).
  std::uint32_t max_plane_tries = 64;
  /// Accept a self-intersecting input (only topology is promised then).
  bool allow_self_intersections = false;
  /// Worker threads; 0 means one per hardware thread. Never changes the output.
  unsigned threads = 0;
  /// The caller has already refused the input unless it is a valid solid, as
  /// require_valid_solid(mesh, name, allow_self_intersections) does (the full
  /// validate_mesh, self-intersections included), so the builder skips that
  /// check instead of repeating it. Set it only after such a check of this very
  /// mesh: on any other mesh the build's guarantees do not hold. Never changes
  /// the output; a built tree's options have it false again.
  bool input_validated = false;
};

struct MeshTree;

/// Called once per finished leaf with the number finished so far. May be called
/// from any worker thread, concurrently: it must be thread-safe and cheap.
using LeafProgressFn = std::function<void(std::size_t leaves_done)>;

/// Where a build's time went, and how often a drawn plane was not used. The
/// counts are part of the deterministic build; the seconds are wall-clock.
struct BuildReport {
  /// Cutting, mass properties, and making the stored meshes: rounding each piece
  /// once, certified.
  double cutting_seconds = 0;
  double hull_seconds = 0;     ///< convex hulls of every node (in parallel)
  double bond_seconds = 0;     ///< find_bonds
  std::uint64_t planes_missed = 0;    ///< drawn planes that missed their node
  /// Drawn planes that left a piece that cannot be written as a valid double mesh
  /// (or that pinched the solid).
  std::uint64_t planes_rejected = 0;
};

/// Builds the mesh tree of `mesh` with `options` (see BuildOptions, Strategy).
/// Preconditions: options.fragments >= 1, options.kernel plane and every triangle
/// of `mesh` on surface 0 (std::invalid_argument otherwise). The mesh is validated first, unless
/// options.input_validated says the caller did: a mesh that is not a closed,
/// oriented 2-manifold with positive volume, or that intersects itself (unless
/// options.allow_self_intersections), is refused with InvalidMeshError naming its
/// first defect.
/// Guarantees: at least options.fragments leaves, and no leaf cut that was not
/// needed to reach that count; every node's stored mesh a valid solid (closed,
/// oriented, 2-manifold, positive volume, no zero-area triangle, no
/// self-intersection; with allow_self_intersections only the topology), certified
/// as it is rounded; every node's exact solid kept (MeshTreeNode::solid, over
/// tree.geometry and tree.cut_planes), the children's solids partitioning their
/// parent's exactly; leaf ranges contiguous; cap triangles carry cap_surface_of(cut node);
/// mass properties and hulls filled; bonds = find_bonds(tree); shatter_version
/// this library's version_string (shatter/version.hpp). One version of shatter
/// gives a result that depends only on the mesh and the options other than
/// `threads`: byte-identical on any machine and thread count.
/// Throws UnsupportedGeometryError when none of max_plane_tries planes gives a node
/// valid pieces (all missed it, or its pieces are thinner than rounding).
/// When `report` is given, it is filled in.
MeshTree build_mesh_tree(const Mesh& mesh, const BuildOptions& options, const LeafProgressFn& progress = {},
                         BuildReport* report = nullptr);

}  // namespace shatter

// Last, and on purpose: MeshTree complete for every caller of build_mesh_tree
// (tree.hpp needs BuildOptions above, so it cannot come first).
#include "shatter/meshtree/tree.hpp"  // IWYU pragma: export
