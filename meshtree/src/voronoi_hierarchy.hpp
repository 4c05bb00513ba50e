#pragma once
// The hierarchy of a Voronoi tree (voronoi.cpp cuts and rounds its fragments):
// the k-d groups of the sites, bottom up, each gluing the face-connected sets of
// its parts into nodes (voronoi_glue.hpp says why a union is exact), and the
// MeshTree made of the glued parts. Groups of sites near each other are
// compact, so their unions are mostly single solids; a set that is not
// (pinched, or not certified once rounded) stays unglued.

#include <atomic>
#include <cstdint>
#include <span>
#include <vector>

#include "shatter/cut/plane_input.hpp"
#include "shatter/kernel/solid.hpp"
#include "shatter/meshtree/recipe.hpp"
#include "shatter/meshtree/tree.hpp"
#include "shatter/triangulate/solid_mesh.hpp"
#include "voronoi_glue.hpp"

namespace shatter::detail {

/// A fragment as cut, and its rounding.
struct VoronoiFragment {
  Solid solid;
  RoundedSolid rounded;
};

/// A k-d group of the sites: the range [begin, end) of the site order, and its
/// two halves (-1 for a lowest group). Group 0 is the root, and a group's halves
/// come after it.
struct SiteGroup {
  std::uint32_t begin = 0, end = 0;
  std::int32_t left = -1, right = -1;
};

/// A node of the hierarchy being built: a fragment, or a glued set of parts.
struct VoronoiPart {
  Solid solid;
  Mesh mesh;
  std::vector<std::uint32_t> sites;  ///< the sites of its fragments, sorted
  std::vector<VoronoiPart> children;  ///< none for a fragment
  /// Per face of `solid`, the attempt of triangulate_face that wrote it in
  /// `mesh`; empty when `mesh` is no plain triangulation (RoundedSolid::attempt).
  std::vector<std::uint8_t> face_attempts;
  /// Per face of `solid`, the fragment whose face it is (numbered as
  /// glue_voronoi_hierarchy numbers them), and for a fragment its
  /// own number (no_index for a union): hints for certifying a union of parts
  /// (PartRegions: nothing of them is trusted).
  std::vector<std::uint32_t> face_regions;
  std::uint32_t sole_region = no_index;
  /// When `mesh` is a plain triangulation of `solid`: per vertex of `mesh`, the
  /// solid's vertex it rounds, and where face f's triangles start in `mesh`
  /// (face_first_triangle[f], one more for the end); else both empty. A union
  /// writes a face its part wrote with the same triangles
  /// (SolidMeshOptions::face_triangles).
  std::vector<VertexIndex> solid_vertex_of;
  std::vector<std::uint32_t> face_first_triangle;

  /// Frees the hints above, once the part is glued.
  void drop_hints();
};

/// What glue_voronoi_hierarchy reads.
struct VoronoiHierarchyInput {
  const PlaneSet& set;  ///< every fragment's planes
  std::span<const SiteGroup> groups;
  std::span<const std::uint32_t> order;  ///< the site order the groups' ranges index
  /// Per site, its kept fragments (certified, not collapsed), in order; their
  /// solids and meshes are moved out.
  std::span<const std::vector<VoronoiFragment*>> kept_of;
  SitePairs site_pairs;  ///< per plane of `set`, the sites it bisects
  std::span<const Vec3> points;  ///< the sites on their grid (quantize_sites)
  double step = 0;               ///< the grid's spacing
  const SolidMeshOptions& meshing;  ///< how each fragment was rounded
  bool lean = false;                ///< BuildRunOptions::lean
};

/// How the gluing went (VoronoiReport's counts).
struct HierarchyCounts {
  std::atomic<std::size_t> nodes_glued{0}, sets_unglued{0}, nodes_retried{0};
};

/// The hierarchy of the kept fragments: the lowest k-d groups and every second
/// level above them glue their parts' face-connected sets; each union is made
/// by glue_parts, rounded and certified knowing its parts (round_solid with
/// SolidMeshOptions::parts), and a set that cannot be glued or certified stays
/// unglued. Returns the root's children (the groups' top parts, a group holding
/// every fragment replaced by its children); nothing when fewer than two
/// fragments are kept. Runs in parallel on the calling arena; deterministic.
/// Throws what round_solid throws other than UnsupportedGeometryError (a union
/// round_solid cannot place stays unglued).
std::vector<VoronoiPart> glue_voronoi_hierarchy(const VoronoiHierarchyInput& in, HierarchyCounts& counts);

/// The tree of `mesh` whose root's children are `top` (glue_voronoi_hierarchy):
/// nodes in preorder, leaves numbered in that order, the bisectors the
/// fragments use renumbered after the nodes in the order of their site pairs
/// (planes and surfaces of every solid and mesh remapped), each node's mass
/// computed. Hulls, bonds and the certificate are left to the caller. `planes`:
/// the planes of the fragments' set beyond the input's; `site_pairs` says which
/// are bisectors. Moves the parts' solids and meshes into the nodes. Throws
/// std::logic_error if a fragment uses a plane that is no bisector (a container
/// box that cut into a cell's part of the solid).
MeshTree voronoi_tree_of_parts(const Mesh& mesh, const PlaneInput& input, const TreeRecipe& recipe,
                               std::vector<VoronoiPart>& top, std::span<const Plane> planes, SitePairs site_pairs);

}  // namespace shatter::detail
