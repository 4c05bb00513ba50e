#pragma once
// One complete cut of a solid: slice, cap both halves, separate the solids.
//
// The test oracle (tests/oracle/, never installed): the cut of the retired `exact`
// kernel, on CGAL Epeck rationals, which the properties compare the plane
// kernel's pieces against (exact volumes and partition), and the `fast` variant
// that rounds each crossing point, kept for the tests that show what rounding
// every cut does. The product cuts with cut_by_plane (meshtree/plane_cut.hpp).

#include <vector>

#include "shatter/kernel/exact.hpp"
#include "shatter/kernel/mesh.hpp"
#include "shatter/triangulate/cap.hpp"

namespace shatter::oracle {

struct CutOptions {
  /// Surface id of the new cap triangles (ids below it are left as they are).
  SurfaceId cap_surface = 1;
  /// Cap UVs are the cap's 2D coordinates in the plane times this scale.
  double interior_uv_scale = 1.0;
};

template <class Point>
struct CutResult {
  std::vector<BasicMesh<Point>> below;  ///< solids on the n·x + d < 0 side
  std::vector<BasicMesh<Point>> above;  ///< solids on the n·x + d > 0 side
  /// True when the plane misses or only touches the solid: the input comes back
  /// whole (separated into its solids) on the one side it lies on.
  bool plane_missed = false;
  CapMethod cap_method = CapMethod::none;
  std::size_t cap_loops = 0;
  std::size_t cap_triangles = 0;
};

/// Cuts a closed solid by `plane` (n·x + d = 0) and closes both halves.
/// Preconditions: `mesh` passes validate_mesh (closed, oriented, manifold, positive
/// volume; self-intersections are tolerated but then only topology is promised);
/// plane.normal != 0 and finite. Guarantees (exact kernel, valid input): every
/// solid closed, oriented, 2-manifold, positive volume, no zero-area triangle, no
/// unused vertex; volumes sum to the input's exactly; each cap's boundary equals the
/// border edges. Fast kernel: the same topology; the rounded embedding may be
/// invalid (validate_mesh on the output tells; the CLI counts such pieces). Cap triangles get
/// the plane normal (flipped per side) if the mesh has normals, cap UVs if it has
/// UVs, the plane basis as tangent if it has tangents. Deterministic.
CutResult<Vec3> cut_mesh(const Mesh& mesh, const Plane& plane, const CutOptions& options = {});
CutResult<ExactPoint> cut_mesh(const ExactMesh& mesh, const Plane& plane, const CutOptions& options = {});

}  // namespace shatter::oracle
