#pragma once
// One plane cut of a plane-based solid (kernel/solid.hpp): every face is split
// along its line with the cut into its parts below and above, and the edges the
// caps must close are collected. No point is constructed: a vertex where the cut
// crosses an edge is defined from the edge's line and the cut plane.
//
// Degeneracy policy (every case decided by the exact side of each vertex):
// - A vertex on the plane is shared by both sides, never duplicated.
// - An edge with endpoints strictly on both sides gets one new vertex, made once
//   per undirected edge, which both faces of the edge and both sides use.
// - A face with vertices strictly on both sides is split along its line with the
//   plane into one or more connected parts per side (a non-convex face or a face
//   with holes can give several); the parts of the line inside the face become new
//   edges, in both sides' parts.
// - A face with no vertex strictly on one side goes whole to the other side.
// - A face lying in the plane goes below when its outward normal points along +n
//   (it is then the lid of the solid below), above otherwise. An edge along the
//   plane is a border edge exactly when its two faces went to different sides.

#include <cstdint>
#include <vector>

#include "shatter/kernel/index_map.hpp"
#include "shatter/kernel/solid.hpp"

namespace shatter {

/// Which sides of a split split_solid must give in full.
enum class SplitSides : std::uint8_t { both, below, above };

/// The result of split_solid. Reused between calls to spare allocations.
struct SplitSolid {
  /// The solid's vertices, then one new vertex per crossing edge.
  std::vector<PointDef> defs;
  std::vector<ApproxPoint> approx;
  std::vector<Sign> sides;  ///< per vertex, exact
  FaceSet below, above;
  /// Every border edge (where the surface meets the cut and a cap must close it)
  /// once, directed as the below side's face runs it: the below cap runs them
  /// reversed, the above cap as given. Seen from +n the cut region lies to the
  /// left of each reversed edge. Each edge's line: `other` is the plane of the
  /// below face it borders, `p, q` the input segment when it lies on one.
  std::vector<LoopEdge> border;
  /// True when no vertex lies strictly on one of the two sides: the plane misses
  /// or only touches the solid, which then lies whole on the other side.
  bool plane_misses = false;
  bool all_below = false;  ///< with plane_misses: the side the solid lies on
  /// True when split_solid left out the faces of the side it was not asked for
  /// that lie whole on that side (SplitSides below or above, and no vertex of
  /// the solid on the plane): that side's FaceSet then holds only the parts of
  /// the faces the plane crosses, and nothing when the side asked for is below.
  bool other_side_partial = false;

  // Work space.
  IndexMap new_vertex_of_edge;
};

/// Splits `solid` by the cut plane `cut` of `set`.
/// Preconditions: `solid` is closed and sound (check_solid), defined over `set`,
/// and embedded (its faces meet only at shared edges and vertices), which every
/// solid made from a valid mesh by cuts is.
/// Guarantees: the degeneracy policy above; every face part is one connected
/// region (an outer loop and its holes), its corners on its face's plane and
/// edge lines, with loops running counter-clockwise seen from outside; the parts'
/// edges and `border` together are closed: every directed edge of a side is
/// matched by its reverse within the side or by a border edge. Deterministic.
/// Complexity: O(V + C) for V vertices and C corners, plus O(k log k) for a face
/// crossing the plane at k points when it is not convex. Throws
/// UnsupportedGeometryError when a face part's hole cannot be placed (a face whose
/// loops touch at every vertex of a hole; not made by cuts of a valid solid).
/// `sides`: with below or above, when no vertex of the solid lies on the plane,
/// the faces lying whole on the other side are not copied (other_side_partial),
/// nor, with below, the above parts of the faces it crosses: for a caller that
/// keeps one side. Everything else is as with both, bit for
/// bit (the kept side, `border`, the new vertices and their numbers): such faces
/// hold no edge on the plane, so they add no border edge. With a vertex on the
/// plane both sides are made in full (the chords of a cut need both).
void split_solid(const PlaneSet& set, const Solid& solid, PlaneRef cut, SplitSolid& out,
                 SplitSides sides = SplitSides::both);

}  // namespace shatter
