#pragma once
// Voronoi fracture on the plane kernel: the fragments are the solid cut by the
// Voronoi cells of a set of sites, each cell cut out by its bisector planes.
//
// Exact cells. Sites are first quantized to a grid of spacing h = 2^e, every
// coordinate k h with |k| <= 2^24 (quantize_sites; exactness allows |k| < 2^25,
// the spare bit keeps rounding to the grid inside it). The bisector of sites p
// and q is then the plane
//     2 (q - p) . x + |p|^2 - |q|^2 = 0      (negative on p's side)
// whose four coefficients are exact doubles: 2 (k_q - k_p) h has |integer| <
// 2^26, and |p|^2 - |q|^2 = h^2 sum(k_p^2 - k_q^2) has |integer| < 3 2^50 <
// 2^53, so both are computed in 64-bit integers and scaled by a power of two
// without rounding (2b + 2 <= 53 bits is what bounds b = 25). The plane kernel
// itself takes any finite doubles as cut coefficients (its predicates are
// polynomials of degree <= 7 in them, decided exactly by CGAL::Mpzf whatever
// their bit length; 7b + 12 <= 383 bits at b = 53): the grid is set by
// exactness of the bisectors, not by the kernel. With exact coefficients the
// bisectors of any three sites p, q, r satisfy B_pq + B_qr = B_pr as
// polynomials, so they meet in one line exactly, and the cell of p, cut out of
// space by B_pq with p's side kept, and the cell of q, by the same plane with
// q's side kept, share that plane exactly: the cells partition space with no gap
// and no overlap, whatever the sites' degeneracy (co-spherical, coplanar,
// collinear), and each fragment is the solid cut by its cell's planes on the
// kernel's exact solids, whose pieces partition the solid exactly (cut_solid).
// Rounded bisectors of arbitrary double sites have no such identity: near a
// Voronoi vertex the three rounded planes need not meet in one line.
//
// Neighbours come from CGAL's Delaunay_triangulation_3 (Epick: its predicates
// are exact on double input), O(n log n) expected. Eight sentinel sites at the
// corners of a cube twice the sites' and the solid's box diagonal away from it
// are added: every point of the solid's box is then strictly nearer to some
// site than to any sentinel, so the cells restricted to the box are those of
// the sites alone, every site's cell is bounded, and the triangulation always
// has dimension 3 (one site, collinear or coplanar sites included).

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "shatter/kernel/mesh.hpp"
#include "shatter/kernel/vec.hpp"
#include "shatter/meshtree/build.hpp"
#include "shatter/meshtree/recipe.hpp"
#include "shatter/meshtree/tree.hpp"

namespace shatter {

/// Sites on the bisector-exact grid.
struct QuantizedSites {
  /// The distinct quantized sites, in the order of their first occurrence.
  std::vector<Vec3> sites;
  /// For each given site, the index of its quantized site in `sites`, or
  /// no_index for a far one.
  std::vector<std::uint32_t> site_of_input;
  /// The grid spacing h, a power of two: every coordinate is k h, |k| <= 2^24.
  double step = 0;
  /// Given sites that quantized onto an earlier one (merged into it).
  std::size_t merged = 0;
  /// Given sites left out because their cells provably miss the box: each
  /// farther from it than twice the smallest distance, over the sites, from a
  /// site to the box's farthest point.
  std::size_t far = 0;
};

/// Quantizes `sites` to the grid of the smallest power-of-two spacing h for
/// which every coordinate of the sites, of the box [lo, hi] and of the sentinel
/// sites around them (see the file comment) is k h with |k| <= 2^24: each
/// coordinate goes to the nearest grid value (ties to even). Sites that land on
/// one grid point are merged, deterministically: the first given one keeps its
/// place, the later ones map to it. Far sites (QuantizedSites::far), whose
/// cells miss the box, are left out before the grid is chosen: they would only
/// coarsen it. Throws std::invalid_argument on a non-finite coordinate or an
/// empty site list, and UnsupportedGeometryError (kernel/error.hpp) when the
/// box and the sites left are too large or too small for h^2 to be a normal
/// double (magnitudes outside 2^-476 to 2^500).
QuantizedSites quantize_sites(std::span<const Vec3> sites, const Vec3& lo, const Vec3& hi);

/// The bisector of two grid sites (quantize_sites), exactly: 2 (q - p) . x +
/// |p|^2 - |q|^2, negative on p's side. Precondition: p != q, both on a grid of
/// spacing `step` with |k| <= 2^24 (std::invalid_argument otherwise).
Plane exact_bisector(const Vec3& p, const Vec3& q, double step);

/// The planes that bound each site's Voronoi cell, as build_voronoi_tree cuts
/// them, for comparing other tools on the same cells (bench/voronoi_bench.cpp
/// hands them to a Manifold pipeline).
struct VoronoiCellPlanes {
  QuantizedSites quantized;  ///< the sites as the cells use them (quantize_sites)
  /// Per quantized site, the exact bisectors with its Delaunay neighbours (the
  /// sentinels included), nearest neighbour first; each is negative on the
  /// site's side, so the cell is where every one of them is <= 0.
  std::vector<std::vector<Plane>> cells;
};

/// The cells of `sites` around `mesh` exactly as build_voronoi_tree makes them:
/// sites quantized to the bisector-exact grid of the mesh's box, neighbours
/// from the Delaunay triangulation with the eight sentinels, every bisector an
/// exact Plane. Nothing is cut. Preconditions: `mesh` non-empty, sites finite
/// and non-empty. Throws as quantize_sites does.
VoronoiCellPlanes voronoi_cell_planes(const Mesh& mesh, std::span<const Vec3> sites);

/// What build_voronoi_tree did besides the tree.
struct VoronoiReport {
  std::size_t sites_given = 0;
  std::size_t sites_merged = 0;      ///< QuantizedSites::merged
  std::size_t sites_far = 0;         ///< QuantizedSites::far: their cells miss the solid's box
  std::size_t cells_empty = 0;       ///< sites whose cell misses the solid
  std::size_t cells_split = 0;       ///< cells that meet the solid in several pieces
  std::size_t neighbour_pairs = 0;   ///< Delaunay edges between sites
  /// Cells found to lie strictly inside the solid (their box meets no input
  /// triangle's), and of those the ones assembled as convex solids from the
  /// Delaunay triangulation instead of cut out of the solid (the others, whose
  /// star the assembly does not take, are cut).
  std::size_t cells_inside = 0, cells_assembled = 0;
  /// Fragments thinner than the rounding of their coordinates: they vanish
  /// (no leaf), their exact volume (summed as doubles) within the bound.
  std::size_t fragments_vanished = 0;
  double vanished_volume = 0, vanished_volume_bound = 0;
  /// Internal nodes made by gluing fragments (the hierarchy, see
  /// build_voronoi_tree), and face-connected sets of parts left unglued because
  /// their union was no closed 2-manifold as glued or did not round validly
  /// (their parts then hang one level higher).
  std::size_t nodes_glued = 0, sets_unglued = 0;
  /// Fragments whose first rounding did not certify (round_solid went on to a
  /// later attempt or a repair), and glued nodes likewise: a node triangulates
  /// each face as its part was certified (SolidMeshOptions::face_attempts), so
  /// it needs a later attempt only where the union itself breaks something.
  std::size_t fragments_retried = 0, nodes_retried = 0;
  double step = 0;                   ///< the site grid's spacing
  double seconds_cells = 0;          ///< quantizing, triangulating, cutting and rounding
  double seconds_glue = 0;           ///< gluing and rounding the internal nodes
  double seconds_hulls = 0, seconds_bonds = 0;
};

/// Cuts `mesh` into the Voronoi cells of `sites`: every cell's part of the solid
/// is cut out by the plane kernel (several components give several fragments,
/// a cell that misses the solid gives none), rounded and certified as every
/// cut piece is (round_solid). A cell whose box meets no input triangle's box
/// and whose site lies inside the solid (decided exactly) is its own fragment
/// whole: it is assembled as a convex solid from the Delaunay triangulation
/// instead (the same exact solid, VoronoiReport::cells_assembled). The fragments are the leaves; the root is the
/// input; between them, a hierarchy: the sites are split by a k-d tree
/// (median along the longest axis, groups of at most 8 at the bottom), and at
/// every group below the root, the face-connected sets of its parts (its
/// fragments, or its two halves' parts) are glued into one internal node each,
/// without a Boolean (voronoi_glue.hpp): twin cell faces deleted, the rest
/// joined by vertex identity, the union rounded (each face triangulated at the
/// attempt that certified its part: SolidMeshOptions::face_attempts) and
/// certified by round_solid.
/// A set whose union is not a closed 2-manifold as glued (parts touching along
/// an edge or at a point only, twins that do not cancel edge for edge, as
/// around a vanished sliver) or does not round validly is not glued: its parts
/// hang one level higher (VoronoiReport::sets_unglued). Every node's plane is
/// zero, which marks a cell node: its children are separated by the bisectors
/// the tree keeps after its node planes (MeshTree::cut_planes). One site, or
/// one fragment, gives the root alone. Bonds are the shared cell faces between
/// leaves (find_bonds), on their lowest common ancestor. recipe.strategy must
/// be voronoi; recipe.fragments is kept as the number of sites asked for.
/// Preconditions: as build_mesh_tree (a valid solid, every triangle on surface
/// 0; validated unless run.input_validated), sites finite and non-empty.
/// Guarantees: the fragments' exact solids partition the input's exactly (but
/// for vanished slivers, reported); an internal node's exact solid is the union
/// of its children's, so its exact volume is theirs summed, exactly; every
/// stored mesh valid as written;
/// deterministic at any run.threads. Throws UnsupportedGeometryError when a
/// fragment cannot be written validly (round_solid) or the solid and its sites
/// lie outside the grid's range (quantize_sites), std::invalid_argument on
/// bad arguments, InvalidMeshError on an invalid input.
MeshTree build_voronoi_tree(const Mesh& mesh, std::span<const Vec3> sites, const TreeRecipe& recipe,
                            const BuildRunOptions& run = {}, VoronoiReport* report = nullptr);

}  // namespace shatter
