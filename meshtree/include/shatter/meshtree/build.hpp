#pragma once
// The recursive builder: cuts a solid into at least N fragments and keeps every
// level as a MeshTree (seed thesis ch. 4, listing 4.1), then finds the bonds.
// What it builds is the tree's recipe (recipe.hpp, kept in the tree); how one
// build runs (threads, progress, the report of where its time went) is declared
// here and never reaches the tree.

#include <cstddef>
#include <cstdint>
#include <functional>

#include "shatter/kernel/mesh.hpp"
#include "shatter/meshtree/recipe.hpp"
#include "shatter/meshtree/tree.hpp"

namespace shatter {

struct PlaneInput;  // shatter/cut/plane_input.hpp

/// Called once per finished leaf with the number finished so far. May be called
/// from any worker thread, concurrently: it must be thread-safe and cheap.
using LeafProgressFn = std::function<void(std::size_t leaves_done)>;

/// Where a build's time went, and how often a drawn plane was not used. The
/// counts are part of the deterministic build; the seconds are wall-clock.
struct BuildReport {
  /// Preparing the input for the plane kernel (unless BuildRunOptions::prepared,
  /// and with the build's check of the input beside it when it makes one),
  /// cutting, mass properties, and making the stored meshes: rounding each piece
  /// once, certified.
  double cutting_seconds = 0;
  double hull_seconds = 0;     ///< convex hulls of every node (in parallel)
  double bond_seconds = 0;     ///< find_bonds
  /// Drawn planes that missed their node: left it whole, or left only one piece
  /// that is not thinner than the rounding of its coordinates (redrawn).
  std::uint64_t planes_missed = 0;
  /// Drawn planes that gave a piece round_solid cannot write as a valid mesh
  /// (redrawn: the last case where a plane is redrawn for its pieces; 0 in every
  /// corpus build measured, README "Robustness").
  std::uint64_t planes_rejected = 0;
  /// Pieces of the tree's cuts that were thinner than the rounding of their
  /// coordinates and vanished (round_solid: they are no children; their volume
  /// moves to their neighbours across the cut), their exact volume summed (as
  /// doubles), and the sum of the bounds on what rounding can move that each
  /// was checked against: vanished_volume <= vanished_volume_bound. The
  /// children of a cut with a vanished piece have that much less volume than
  /// their parent, exactly.
  std::uint64_t pieces_vanished = 0;
  double vanished_volume = 0;
  double vanished_volume_bound = 0;
};

/// How one build runs: none of it changes the tree, so none of it is kept in the
/// tree or stored in its file.
struct BuildRunOptions {
  /// Worker threads; 0 means one per hardware thread.
  unsigned threads = 0;
  /// The caller has already refused the input unless it is a valid solid, as
  /// require_valid_solid(mesh, name, recipe.allow_self_intersections) does (the
  /// full validate_mesh, self-intersections included), so the builder skips that
  /// check instead of repeating it. Set it only after such a check of this very
  /// mesh: on any other mesh the build's guarantees do not hold.
  bool input_validated = false;
  /// When given: prepare_plane_input of this very mesh, made by the caller (as
  /// `shatter fracture` does, beside its check of the mesh:
  /// prepare_plane_input_beside), which the build uses instead of preparing the
  /// mesh again. It must outlive the build, which only reads it. Without it the
  /// build prepares the mesh itself, beside its own check when it makes one.
  const PlaneInput* prepared = nullptr;
  /// Called once per finished leaf (see LeafProgressFn); empty: not called.
  /// (Initialized here, like every field, so a designated initializer may leave
  /// it out without GCC's -Wmissing-field-initializers.)
  LeafProgressFn progress = {};
  /// When given, filled in when the build succeeds; left as it was when it throws.
  BuildReport* report = nullptr;
  /// Free what the build can recompute as soon as it no longer needs it, for a
  /// caller that only writes the tree (as `shatter fracture` does): every
  /// node's Solid::approx (the vertices' cached approximations, 64 bytes a
  /// vertex, a quarter of a cube's tree) is released once the node is cut or is
  /// known to stay a leaf, so the returned tree has none (MeshTreeNode::solid),
  /// and its mesh and solid are packed then (MeshTree::packed_shapes; read them
  /// through NodeShapes); the bonds are found packed (MeshTree::packed_bonds,
  /// `bonds` left empty; read them through MeshTree::bond). Everything else is
  /// as without it: the same values,
  /// bonds and .shatter bytes; fill_tree_caches restores the full tree. false:
  /// every node keeps its cache and its arrays.
  bool lean = false;
};

/// Builds the mesh tree of `mesh` by `recipe` (see TreeRecipe, Strategy), run as
/// `run` says.
/// Preconditions: recipe.fragments >= 1, recipe.max_plane_tries >= 1,
/// recipe.kernel plane and every triangle of `mesh` on surface 0
/// (std::invalid_argument otherwise). The mesh is validated first, unless
/// run.input_validated says the caller did: a mesh that is not a closed,
/// oriented 2-manifold with positive volume, or that intersects itself (unless
/// recipe.allow_self_intersections), is refused with InvalidMeshError naming its
/// first defect.
/// Guarantees: at least recipe.fragments leaves, and no leaf cut that was not
/// needed to reach that count; every node's stored mesh a valid solid (closed,
/// oriented, 2-manifold, positive volume, no zero-area triangle, no
/// self-intersection; with allow_self_intersections only the topology), certified
/// as it is rounded; every node's exact solid kept (MeshTreeNode::solid, over
/// tree.geometry and tree.cut_planes), the children's solids partitioning their
/// parent's exactly, but for pieces of a cut thinner than the rounding of their
/// coordinates, which vanish (no children; their volume, which moves to their
/// neighbours across the cut, is at most what rounding their vertices can move,
/// and is reported: BuildReport::pieces_vanished); every solid's approx
/// cached, or none when run.lean; leaf ranges contiguous; cap triangles carry cap_surface_of(cut node);
/// mass properties and hulls filled; bonds = find_bonds(tree) (run.lean: packed
/// as find_packed_plane_bonds packs them, in packed_bonds); tree.recipe =
/// `recipe`; shatter_version this library's version_string (shatter/version.hpp).
/// One version of shatter gives a result that depends only on the mesh and the
/// recipe: byte-identical on any machine, whatever `run` is.
/// Throws UnsupportedGeometryError when none of max_plane_tries planes drawn for
/// a node cuts it into pieces that can all be written (each missed it, as
/// PlaneCut::misses_as_written says, or left a piece round_solid cannot write
/// validly), or when a cut pinches a piece (cut_solid).
MeshTree build_mesh_tree(const Mesh& mesh, const TreeRecipe& recipe, const BuildRunOptions& run = {});

}  // namespace shatter
