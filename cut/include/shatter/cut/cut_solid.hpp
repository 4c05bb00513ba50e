#pragma once
// One complete cut of a plane-based solid: split (slicer), caps (triangulate),
// then the pieces of each side separated into solids, each with its vertices
// numbered compactly.

#include <cstdint>
#include <vector>

#include "shatter/kernel/solid.hpp"

namespace shatter {

struct SolidCut {
  std::vector<Solid> below;  ///< solids on the n·x + d < 0 side
  std::vector<Solid> above;  ///< solids on the n·x + d > 0 side
  /// True when the plane misses or only touches the solid: nothing is cut, and
  /// below and above are empty.
  bool plane_missed = false;
  bool all_below = false;  ///< with plane_missed: the side the solid lies on
  std::size_t cap_faces = 0;  ///< connected regions of the cap (each an outer loop and its holes)
  std::size_t cap_loops = 0;  ///< loops of the cap, holes included
};

/// What an untouched shell of the input is: which input shell an input triangle
/// lies on, and for each input shell the outer shell of its input solid (itself
/// for an outer shell, the shell around it for a cavity). A cut leaves shells it
/// does not touch whole; these tables tell a standalone solid from a cavity.
struct InputShells {
  std::vector<std::uint32_t> shell_of_triangle;
  std::vector<std::uint32_t> outer_of_shell;
};

/// Which sides of a cut cut_solid makes into solids.
enum class CutSides : std::uint8_t { both, below, above };

/// Cuts `solid` by the cut plane `cut` of `set` and closes both sides.
/// Preconditions: as split_solid (a sound, embedded solid over `set`).
/// Guarantees: every solid closed (every directed edge matched by its reverse),
/// one outer shell with the cavities inside it, faces connected regions, cap
/// faces on `cut` with surface id `cap_surface`, no unused vertex; children of a
/// convex solid are convex (no predicate spent on it), others have `convex`
/// decided exactly. Their union is the solid and they meet only on the cut
/// (exactly: no point is rounded). Deterministic: solids in the order of their
/// first face. Where the plane holds a concave edge of the surface across the
/// cap (a chord: both its faces on one side), the cap of that side is split
/// along it and the pieces meeting there are separate solids, each with its own
/// cap face. When the two sides of a chord are one piece (a tunnel whose lowest
/// edge lies on the plane), that piece meets itself along the chord: each of its
/// two sheets there has its own copies of the chord's ends (distinct vertices at
/// one exact point), so that the solid stays sound (check_solid), and a face
/// whose loops met at such an end is relinked into the loops its corners then
/// make. A solid may touch itself at a point exactly (a saddle vertex of the
/// surface on the plane, a cavity's corner on the cap, or those copies:
/// round_solid separates such points when it writes the piece). Throws
/// UnsupportedGeometryError as split_solid and make_caps.
/// `shells` describes the input shells (InputShells) for the faces' `source`
/// triangles; it matters only when a cut leaves a whole shell untouched.
/// `sides`: below or above makes the solids of that side only (the other list
/// stays empty; what is made is the same as with both), for a caller that
/// keeps one side (a cell cut out of a solid plane by plane).
SolidCut cut_solid(const PlaneSet& set, const Solid& solid, PlaneRef cut, SurfaceId cap_surface,
                   const InputShells& shells, CutSides sides = CutSides::both);

}  // namespace shatter
