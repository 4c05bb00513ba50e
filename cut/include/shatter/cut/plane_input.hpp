#pragma once
// An input mesh made ready for the plane kernel: its solids, their shells, and
// one plane-based solid over input points and input planes.

#include "shatter/kernel/mesh.hpp"
#include "shatter/kernel/solid.hpp"
#include "shatter/cut/cut_solid.hpp"

namespace shatter {

struct PlaneInput {
  /// The input's solids (separate_solids), concatenated: the faces' `source`
  /// indices name its triangles, whose attributes output meshes interpolate.
  Mesh mesh;
  /// Input points (= mesh.positions) and one input plane per face.
  InputGeometry geometry;
  /// Which input shell each triangle lies on, and each shell's outer shell.
  InputShells shells;
  /// All of the input as one plane-based solid (several solids when the input
  /// has several), faces merged from coplanar triangles when the mesh carries no
  /// attributes (solid_from_mesh).
  Solid solid;
};

/// Prepares `mesh` for the plane kernel.
/// Precondition: a valid solid (require_valid_solid), possibly several, and not
/// self-intersecting. Guarantees: `solid` passes check_solid over
/// geometry.plane_set({}); deterministic. Throws InvalidMeshError on an open or
/// inconsistently oriented mesh.
PlaneInput prepare_plane_input(const Mesh& mesh);

}  // namespace shatter
