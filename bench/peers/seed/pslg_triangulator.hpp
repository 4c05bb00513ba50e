#pragma once
// The stand-in for Triangle [She96], which the seed's modeller ran as an external
// program on a .poly file (seed thesis 4.3.3): a constrained Delaunay triangulation of
// a planar straight-line graph, with the triangles reachable from the outside or from
// a hole point without crossing a segment eaten away, as Triangle's -p switch does.
// Like Triangle, its decisions are exact (orientation and in-circle signs: a double
// filter with Shewchuk's error bounds, GMP rationals when the filter cannot decide).
// Where Triangle would repair a bad PSLG on its own (a segment through a vertex or two
// crossing segments: Triangle splits them and inserts the crossing point), this
// reports a failure instead; README.md says why that changes no stopping point.

#include <array>
#include <string>
#include <vector>

namespace seed_peer {

/// A planar straight-line graph as a .poly file holds it.
struct Pslg {
  std::vector<std::array<double, 2>> points;   ///< #P by 2
  std::vector<std::array<int, 2>> segments;    ///< #S by 2 point indices
  std::vector<std::array<double, 2>> holes;    ///< one point inside each hole
};

struct PslgTriangulation {
  bool ok = false;
  std::string error;                            ///< why not, when !ok
  std::vector<std::array<int, 3>> triangles;    ///< #T by 3 point indices, counter-clockwise
};

/// Triangulates `pslg`: every point a vertex (exactly repeated points merged into
/// the first, as Triangle ignores duplicates), every segment a chain of edges, the
/// rest constrained Delaunay; then removes the triangles reachable from outside the
/// convex hull or from a hole point without crossing a segment. Returns !ok, with
/// the reason, when a segment passes through a vertex, two segments cross, or the
/// segment recovery does not finish within its step budget. O(P^2) for P points
/// (cavity search by scanning; caps hold at most a few thousand points).
PslgTriangulation triangulate_pslg(const Pslg& pslg);

}  // namespace seed_peer
