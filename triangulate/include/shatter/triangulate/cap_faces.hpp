#pragma once
// Caps of the plane kernel: the region a cut leaves open, closed by polygon faces
// on the cut plane (no triangles: faces stay polygons until output). The border
// edges are linked into loops by vertex index and grouped into connected regions,
// an outer loop with its holes, by exact predicates (kernel/face_loops.hpp). A cap
// adds no vertex and no edge: its boundary is exactly the border edges.

#include <span>

#include "shatter/kernel/solid.hpp"

namespace shatter {

/// Builds the caps of a cut from its border edges (SplitSolid::border: directed as
/// the below side runs them).
/// `defs`/`approx`: the split's vertices. `convex`: the solid cut was convex, so the
/// border is one convex loop (no predicate is needed to group it). `surface`: the
/// caps' surface id. `below_chords`, `above_chords`: concave edges of the surface
/// that lie on the cut across the cap, both of whose faces went to that side
/// (cut_solid finds them): each in both directions, directed and lined as the
/// cap facing +n runs them. That side's cap is split along them, so that each
/// piece of the side meeting the edge gets its own cap face there.
/// Guarantees: `below_cap` faces lie on `cut` facing +n, their loops running the
/// border edges reversed; `above_cap` is the same regions facing -n (reversed
/// faces) running the border edges as given (each side's regions split along its
/// chords); each face one connected region whose corners carry their edge lines
/// (the cut met by the plane of the face across). Both are cleared first. Throws
/// UnsupportedGeometryError as group_into_regions.
void make_caps(const PlaneSet& set, PlaneRef cut, std::span<const PointDef> defs,
               std::span<const ApproxPoint> approx, std::span<const LoopEdge> border, bool convex, SurfaceId surface,
               FaceSet& below_cap, FaceSet& above_cap, std::span<const LoopEdge> below_chords = {},
               std::span<const LoopEdge> above_chords = {});

}  // namespace shatter
