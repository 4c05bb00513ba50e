#pragma once
// A tree's recipe: everything that decides what the builder makes of a mesh
// (fragment count, seed, plane strategy, cap UV scale, ...). A tree keeps its
// recipe and the .shatter file stores it, so this header stands on its own:
// tree.hpp includes it, and build.hpp adds how one build runs (threads,
// progress, report), which is no part of the tree.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

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
  /// Voronoi cells of given sites (build_voronoi_tree, voronoi.hpp): the cells of
  /// neighbouring sites share one exact bisector plane; build_mesh_tree refuses it.
  voronoi = 3,
};

/// The kernel that made a tree (DESIGN.md, "Exact arithmetic"). Every tree this
/// version builds is `plane`: plane-based vertices (kernel/implicit.hpp), exact at
/// any depth and rounded once, certified. `fast` (rounded cut points) and `exact`
/// (CGAL Epeck rationals, rounded per node) are retired: the trees they made
/// still read (.shatter versions 1 and 2), and this says how they were made.
enum class KernelKind : std::uint8_t { fast = 0, exact = 1, plane = 2 };

/// The largest Strategy and KernelKind this version knows: a reader refuses a
/// stored value above them. A new enumerator must be added here, and to the
/// layout comment of formats/file.hpp, to be stored.
inline constexpr Strategy last_strategy = Strategy::voronoi;
inline constexpr KernelKind last_kernel = KernelKind::plane;

/// The strategy's name as the CLI spells it ("thesis", "balanced", "axis",
/// "voronoi");
/// "unknown" for a value outside the enum. Never throws.
std::string_view strategy_name(Strategy strategy);
/// The kernel's name as `shatter info` prints it ("fast", "exact", "plane");
/// "unknown" for a value outside the enum. Never throws.
std::string_view kernel_name(KernelKind kernel);
/// The strategy strategy_name spells `name`; nullopt for any other text. Never
/// throws.
std::optional<Strategy> strategy_named(std::string_view name);

/// Everything that decides a tree's contents, kept in the tree (MeshTree::recipe)
/// and stored by the .shatter file, field for field (its OPTS section). Two
/// builds of one recipe on equal input give byte-identical trees, however they
/// run (BuildRunOptions, build.hpp).
struct TreeRecipe {
  std::uint32_t fragments = 2;  ///< stop at the first leaf count >= this (>= 1)
  std::uint64_t seed = 1;
  Strategy strategy = Strategy::thesis;
  /// Provenance, not a choice: build_mesh_tree builds only `plane` trees (and
  /// refuses any other value); a tree read from an older file may say otherwise.
  KernelKind kernel = KernelKind::plane;
  double interior_uv_scale = 1.0;
  /// Planes drawn for one node before the build fails. A plane is redrawn when it
  /// misses the node as written (PlaneCut::misses_as_written: it leaves the node
  /// whole, or every piece but one is thinner than the rounding of its
  /// coordinates and vanishes), and in the one case left where its pieces decide:
  /// a piece round_solid cannot write as a valid mesh (counted in
  /// BuildReport::planes_rejected). A vanished piece no longer redraws the plane
  /// (issue 17): it is no child. It decides whether a build succeeds rather than
  /// what it makes, but the file has always stored it, so it stays with what the
  /// tree keeps.
  std::uint32_t max_plane_tries = 64;
  /// Accept a self-intersecting input, and one touching itself at vertices
  /// (only topology is promised then: closed, oriented, manifold along edges).
  bool allow_self_intersections = false;
  /// How a Voronoi tree's sites were made, as `fracture` spells its pattern
  /// options (e.g. "voronoi --sites 1000 --seed 1"), so that `info` can say; empty
  /// for a plane tree and for sites a program gave build_voronoi_tree. Kept by the
  /// .shatter file in its optional `patt` section (printable ASCII, 1 to 1024
  /// bytes), written only when not empty, so plane trees' files are unchanged.
  std::string pattern;
};

/// One step of splitmix64 (Steele, Lea & Flood 2014): advances `state` and
/// returns the next 64-bit value. The stream every node's seed and planes come
/// from: integer arithmetic only, so every machine draws the same tree.
std::uint64_t splitmix64(std::uint64_t& state);

/// The root node's seed (MeshTreeNode::seed) of a tree built with
/// TreeRecipe::seed `recipe_seed`. Deterministic.
std::uint64_t root_node_seed(std::uint64_t recipe_seed);

/// The seed of child `index` (0 for the first) of a node whose seed is
/// `parent_seed`: a node's seed depends on its path from the root alone, so a
/// subtree never depends on what other threads drew. Deterministic.
std::uint64_t child_node_seed(std::uint64_t parent_seed, std::size_t index);

}  // namespace shatter
