#pragma once
// The seed thesis's fragment modeller (chapter 4), in single precision: one slice of a
// piece by a plane (4.2 sorting and splitting triangles, 4.3 capping, 4.4 separating
// hulls) and the recursive build around it (Listing 4.1). README.md lists every
// choice the text leaves open and the section it comes from.

#include <array>
#include <chrono>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "unity_float.hpp"

namespace seed_peer {

/// A piece as the seed's MeshBuilder accumulates it: triangles one by one, each with
/// its own three float corners (counter-clockwise seen from outside). Which corners
/// are "the same vertex" is decided by comparing positions, as the seed does.
struct Piece {
  std::vector<std::array<Vec3f, 3>> triangles;
};

/// How positions are compared wherever the seed compares vertices (linking border
/// edges, 4.3.1; "a vertex in common", 4.4).
enum class Compare { unity, exact };

/// How Listing 4.4 is read. `listing`: as printed, a loop is checked for closure
/// only after an edge has been appended to it, so a border edge whose two ends
/// compare equal and that was skipped while linking its neighbours is left as a
/// loop that can never close. `check_first` (not in the text; to see what the
/// method meets next): a loop is closed as soon as its last vertex matches its
/// start, the first edge's B included, and loops of fewer than 3 vertices are dropped.
enum class Linker { listing, check_first };

/// Where Eq. 4.1's triangles meet. `mesh`: the mesh's own origin, as the text says
/// ("an edge from each of the two vertices to the origin"). `plane`: the plane's
/// point nearest that origin (not in the text), which makes Eq. 4.1 the loop's
/// signed area.
enum class AreaOrigin { mesh, plane };

struct SliceOptions {
  Compare compare = Compare::unity;
  Linker linker = Linker::listing;
  AreaOrigin area_origin = AreaOrigin::mesh;
};

/// What one slice met, for the report (not used by any decision).
struct SliceStats {
  std::size_t border_edges = 0;
  std::size_t tiny_border_edges = 0;   ///< border edges whose two ends compare equal (shorter than 1e-5 under unity)
  std::size_t loops = 0;
  std::size_t misclassified_loops = 0; ///< loops Eq. 4.1 calls a hole while their area turns as a polygon's, or the reverse
  std::size_t dropped_loops = 0;       ///< check_first: loops of fewer than 3 vertices left out

  void add(const SliceStats& o) {
    border_edges += o.border_edges;
    tiny_border_edges += o.tiny_border_edges;
    loops += o.loops;
    misclassified_loops += o.misclassified_loops;
    dropped_loops += o.dropped_loops;
  }
};

/// What stopped a build, in the order the method meets them.
enum class FailureKind {
  none,
  edge_linking_failed,   ///< border edges left, none starts where the open loop ends (4.3.1)
  loop_not_closed,       ///< every border edge used, the loop never came back to its start (4.3.1)
  triangulation_failed,  ///< the PSLG could not be triangulated, or no point inside a hole was found (4.3.3)
  invalid_piece,         ///< a piece is not a valid solid (open, non-manifold, self-intersecting, zero volume)
  timeout,               ///< the time cap passed
};
const char* failure_name(FailureKind kind);

struct Failure {
  FailureKind kind = FailureKind::none;
  int level = 0;          ///< the recursion level of the split (1 = the first cut), 0 for validation
  int piece = -1;         ///< index of the piece in its level (or among the leaves, for validation)
  std::string detail;     ///< what exactly, with numbers
};

struct SliceOutcome {
  Failure failure;             ///< kind none when the slice succeeded
  std::vector<Piece> pieces;   ///< the hulls of both sides (4.4), empty sides left out
  std::vector<bool> above;     ///< per piece: on the plane's positive side (GetSide true)
  SliceStats stats;
};

/// Slices `piece` by `plane` the seed's way: triangles sorted by Plane.GetSide,
/// straddling ones split with cut points ray-cast in floats and their B0-B1 edges
/// saved; the edges linked into loops (Listing 4.4), each loop classified polygon or
/// hole by Eq. 4.1, the PSLG triangulated (Triangle's CDT, pslg_triangulator.hpp)
/// with a random point inside each hole drawn from `hole_rng`; the cap added to both
/// sides; each side split into hulls sharing no vertex (Listing 4.6).
SliceOutcome slice_piece(const Piece& piece, const PlaneF& plane, const SliceOptions& options,
                         std::mt19937& hole_rng);

/// The point the seed's random plane goes through: the piece's centre of mass, as
/// the volume-weighted centroid of the tetrahedra from the origin to each triangle,
/// in floats. `volume6` receives six times the float volume.
Vec3f centre_of_mass(const Piece& piece, float& volume6);

/// A direction uniform on the unit sphere (the distribution of Unity's
/// Random.onUnitSphere): a point uniform in [-1, 1)^3 by rejection from the ball,
/// normalized in floats. Each coordinate takes the top 24 bits of one mt19937 draw.
Vec3f random_direction(std::mt19937& rng);

/// The recursive build (Listing 4.1, level by level): see README.md "The build order".
struct BuildOptions {
  int fragments = 8;          ///< stop once this many leaves exist
  std::uint32_t seed = 1;     ///< seeds the plane generator (and, offset, the hole-point one)
  SliceOptions slice;
  double time_cap = 600;      ///< seconds; the build stops with kind timeout past it
};

struct BuildResult {
  std::vector<Piece> leaves;
  Failure failure;
  int levels = 0;
  SliceStats stats;           ///< summed over every slice made
  double seconds = 0;         ///< wall time of the build alone (reading and validation excluded)
};

BuildResult build_fragments(const Piece& source, const BuildOptions& options,
                            std::chrono::steady_clock::time_point start);

/// For every position, the index of the first position of its group: positions are
/// grouped by the transitive closure of `compare` (Unity's approximate == or
/// bitwise equality). O(n log n) when few positions lie within 2e-5 of each other in
/// x (a hash of the bitwise-distinct positions, then a sweep along x).
std::vector<std::uint32_t> group_positions(const std::vector<Vec3f>& positions, Compare compare);

}  // namespace seed_peer
