#pragma once
// Certificates for the pieces a cut writes: exact, linear-time proofs that a
// rounded piece is a valid solid (closed, oriented, 2-manifold, no zero-area
// triangle, no self-intersection, positive volume), tried before the full check
// (validate_mesh_against), which decides whatever they decline.
//
// A certificate either proves validity or proves nothing: it never rejects a
// piece, it only declines, and then the full check runs. So what is written never
// depends on whether a certificate applied (the full check accepts exactly the
// valid meshes too); only the time does.
//
// The argument (README, "Certificates"): a closed, consistently oriented,
// 2-manifold, connected triangle surface all of whose triangles face strictly
// away from a point c, and whose triangles around every vertex v wind exactly
// once around the ray from c through v, projects radially from c onto the unit
// sphere as a covering map of one sheet (a local homeomorphism, by the
// orientations and the winding, of a closed surface onto the sphere, of degree
// one by the facing). A one-sheeted covering is injective: no two points of the
// surface lie on one ray from c, so no two triangles meet beyond the elements
// they share, no two vertices coincide, and no triangle has zero area (its
// orientation against c is strictly negative). The surface bounds the region of
// the points seen from c before it, of positive volume. Every test is an exact
// orientation on the doubles as written; nothing is rounded or compared with a
// tolerance.

#include <cstdint>

#include "shatter/kernel/mesh.hpp"

namespace shatter {

/// How often the piece certificates decided, over the whole process (relaxed
/// atomic counts, for the benchmark and the tests; never read by the build).
struct CertifyCounts {
  std::uint64_t attempts = 0;  ///< certify_piece calls
  std::uint64_t star = 0;      ///< of these, accepted: star-shaped around a centre it tried
  /// Of the attempts, declined (the full check decided): not a connected closed
  /// oriented manifold, or star-shaped around none of the centres tried.
  std::uint64_t declined = 0;
};

/// The counts so far (since the start or the last reset_certify_counts).
CertifyCounts certify_counts();
/// Sets the counts to zero.
void reset_certify_counts();

/// Whether the mesh has exactly one connected component (triangles joined across
/// their edges, by index) and every vertex is used. Preconditions: indices in
/// range. O(T) (union-find over vertices). Never throws.
bool connected_surface(const Mesh& mesh);

/// A fast exact certificate that `mesh` is a valid solid (validate_mesh would find
/// no defect): it is a connected, closed, consistently oriented 2-manifold (checked
/// here, linear) and star-shaped around one of a few centres computed from the
/// mesh: its vertex average, then its volume centroid, then the deepest point
/// of its kernel that a linear program in doubles finds (certify_star_shaped;
/// see the file comment for why that proves validity: each centre is only
/// tried, exactly). Meant for pieces that are not known to be convex: most
/// pieces of curved meshes are star-shaped around some point even when some
/// edge is concave, often their centroid.
/// Preconditions: none (any mesh; out-of-range indices and coordinates that are
/// not finite or not below 2^500 in magnitude make it decline).
/// Guarantees: true only for a mesh validate_mesh finds valid; false proves nothing.
/// Counted in certify_counts(). Cost: O(T) per centre tried, usually declining at
/// the first triangle that faces a centre, and O(T) expected for the program.
/// Never throws.
/// `topology_sound`: the caller knows by construction that the mesh is a
/// closed, consistently oriented 2-manifold by index with every vertex used
/// (is_closed_oriented_manifold would hold), as round_solid knows of a
/// triangulation of a valid exact solid's faces over their own vertices with
/// none merged; that check is then skipped (connectivity is still
/// established, by the one-ray count or connected_surface). The guarantee
/// then rests on that knowledge.
bool certify_piece(const Mesh& mesh, bool topology_sound = false);

}  // namespace shatter
