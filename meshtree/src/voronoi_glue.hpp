#pragma once
// Gluing Voronoi fragments into the internal nodes of a cell tree (voronoi_hierarchy.hpp),
// without a Boolean.
//
// The face of the fragment of site p on the bisector B_pq and the face of the
// fragment of q on it are one region of the plane: the solid's part of the cells'
// common facet, each side holding it with its own outward orientation. The union
// of fragments that share such faces is their faces with every twin pair deleted,
// joined along the twins' boundary edges. Vertices are identified by definition
// (canonical in voronoi.cpp, so equal points mostly share one) and, on a twin's
// boundary where definitions differ, by an exact equality test (side() of one
// point on the other's defining planes); the twins' directed boundary edges must
// then cancel exactly, plane by plane, or the parts are not glued. Nothing is
// rounded or compared in floating point: the glued solid's exact region is the
// union of the parts', so its exact volume is their sum.

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "shatter/kernel/solid.hpp"

namespace shatter::detail {

/// A part to glue: a fragment's or a glued node's exact solid, and the sites
/// whose fragments it holds (sorted).
struct GluePart {
  const Solid* solid = nullptr;
  std::span<const std::uint32_t> sites;
};

/// For each cut plane of the set: the two sites it bisects (first < second), or
/// {no_index, no_index} for a plane that is no bisector.
using SitePairs = std::span<const std::array<std::uint32_t, 2>>;

/// The parts grouped by shared cell faces: part i and part j are in one group when
/// i has a face on the bisector of a site of i and a site of j (a cell split into
/// several fragments puts its site in several parts: each is grouped with i,
/// and glue_parts finds out whether the twins cancel). Each group lists
/// its parts in increasing order; groups are ordered by their first part.
/// Deterministic; O(faces log parts).
std::vector<std::vector<std::uint32_t>> face_connected_groups(std::span<const GluePart> parts, SitePairs pairs);

/// The union of `parts` (two or more, face-connected, over `set`) as one exact
/// solid: faces on a bisector between two of the parts deleted, the rest kept in
/// part order with their loops, corners and lines (a kept corner's line may name
/// the plane of a deleted face: its edge lies on it), vertices identified as the
/// file comment says, convexity decided exactly. Returns nothing, with the reason
/// in `why`, when the union is not a closed 2-manifold solid as glued: twin faces
/// whose boundary edges do not cancel (a missing twin, as around a vanished
/// sliver, or an edge subdivided on one side only), a directed edge used twice
/// (parts touching along an edge only) or a vertex with several fans (parts
/// touching at a point). Never throws on such input. `face_origin`, when given,
/// receives for each face of the union the part and the face of it it was kept
/// from; `vertex_of`, for each vertex of each part (part i's vertex v at the sum
/// of the earlier parts' vertex counts, plus v), its vertex in the union, or
/// no_index when only deleted faces use it.
std::optional<Solid> glue_parts(const PlaneSet& set, std::span<const GluePart> parts, SitePairs pairs,
                                std::string& why,
                                std::vector<std::array<std::uint32_t, 2>>* face_origin = nullptr,
                                std::vector<std::uint32_t>* vertex_of = nullptr);

}  // namespace shatter::detail
