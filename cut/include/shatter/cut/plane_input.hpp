#pragma once
// An input mesh made ready for the plane kernel: its solids, their shells, and
// one plane-based solid over input points and input planes.

#include <functional>

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

/// prepare_plane_input(mesh) side by side with `check`, the caller's check of
/// the mesh (which throws to refuse it): the two run in parallel in the
/// caller's task arena, so on two threads the preparation, otherwise a serial
/// step between reading a mesh and its first cut, costs no time after the
/// check. Only when the mesh has no defect but what validate_mesh's
/// self-intersection search looks for (a linear pass decides it first): else,
/// and on one thread, `check` runs first and the preparation after.
/// Preconditions: `check` only reads the mesh; once it passes, those of
/// prepare_plane_input (the preparation may run on a self-intersecting mesh the
/// check then refuses: it only reads it, and what it throws there is dropped).
/// Guarantees: prepare_plane_input's result, after `check` passed.
/// Failure: what `check` throws, whatever the preparation did; else what
/// prepare_plane_input throws.
PlaneInput prepare_plane_input_beside(const Mesh& mesh, const std::function<void()>& check);

}  // namespace shatter
