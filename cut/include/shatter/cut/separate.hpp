#pragma once
// Solid separation: a closed triangle set (a half of a cut plus its cap) falls into
// edge-connected shells; each shell facing inward (a cavity) joins the smallest
// outward shell that contains it. The result is one mesh per solid.

#include <vector>

#include "shatter/kernel/half_edges.hpp"
#include "shatter/kernel/mesh.hpp"

namespace shatter {

/// Splits `surface` into solids.
/// Preconditions: every directed edge is matched by exactly one reverse edge
/// (closed and consistently oriented).
/// Guarantees: each solid is closed, consistently oriented, 2-manifold, with its
/// vertices renumbered compactly in order of first use. Vertices where several
/// fans of triangles meet (pinches) are duplicated, one copy per fan. Every
/// decision (shell orientation, containment) is exact. Solids come in order of
/// their first triangle in `surface`; a cavity's triangles follow its solid's.
/// A shell that is flat or inward-facing with no outward shell around it (only a
/// self-intersecting input or a rounded embedding makes one) becomes a solid of
/// its own, so the output stays closed and oriented; validate_mesh reports it.
/// Throws UnsupportedGeometryError on a non-manifold edge (a directed edge used
/// twice); std::logic_error on an open surface (a bug upstream).
/// The same on exact points (ExactMesh): separate_exact.hpp, not installed.
std::vector<Mesh> separate_solids(const Mesh& surface);
/// separate_solids, with the surface's half-edge twins (half_edge_twins) already
/// found by the caller. Same result.
std::vector<Mesh> separate_solids(const Mesh& surface, const HalfEdgeTwins& twins);

}  // namespace shatter
