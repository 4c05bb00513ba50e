#include "shatter/oracle/cut.hpp"

#include "shatter/kernel/projection_exact.hpp"
#include "shatter/cut/separate_exact.hpp"
#include "shatter/oracle/slice.hpp"

namespace shatter::oracle {
namespace {

// Appends one side's copy of the cap: triangles reversed for the above side, whose
// outward normal is -n, with attributes for the channels the mesh carries.
template <class Point>
void append_cap(BasicMesh<Point>& half, const Cap<Point>& cap, bool reversed, const PlaneBasis& basis,
                const CutOptions& options) {
  const bool normals = half.corners.has_normals(), uvs = half.corners.has_uvs(),
             tangents = half.corners.has_tangents();
  const Vec3 normal = reversed ? -basis.normal : basis.normal;
  for (Triangle t : cap.triangles) {
    if (reversed) std::swap(t[1], t[2]);
    half.triangles.push_back(t);
    half.surfaces.push_back(options.cap_surface);
    for (VertexIndex v : t) {
      if (normals) half.corners.normals.push_back(normal);
      if (uvs) {
        const Vec3 p = to_vec3(half.positions[v]);
        half.corners.uvs.push_back(
            {dot(p, basis.u) * options.interior_uv_scale, dot(p, basis.v) * options.interior_uv_scale});
      }
      // The UV axes are (u, v) on both sides; seen from -n they are left-handed.
      if (tangents) half.corners.tangents.push_back({basis.u.x, basis.u.y, basis.u.z, reversed ? -1.0 : 1.0});
    }
  }
}

template <class Point>
BasicMesh<Point> half_with_cap(const OpenHalf& half, std::vector<Point> positions) {
  BasicMesh<Point> mesh;
  mesh.positions = std::move(positions);
  mesh.triangles = half.triangles;
  mesh.surfaces = half.surfaces;
  mesh.corners = half.corners;
  return mesh;
}

Cap<Vec3> cap_of(const SlicedMesh<Vec3>& sliced, const Plane& plane) {
  return triangulate_cap(sliced.positions, sliced.border_edges, plane,
                         [&](VertexIndex v) { return exact_position(sliced, plane, v); });
}

Cap<ExactPoint> cap_of(const SlicedMesh<ExactPoint>& sliced, const Plane& plane) {
  return triangulate_cap(sliced.positions, sliced.border_edges, plane);
}

template <class Point>
CutResult<Point> cut(const BasicMesh<Point>& mesh, const Plane& plane, const CutOptions& options) {
  SlicedMesh<Point> sliced = slice_mesh(mesh, plane);
  CutResult<Point> result;
  if (sliced.plane_misses()) {
    result.plane_missed = true;
    auto& side = sliced.above.triangles.empty() ? result.below : result.above;
    side = separate_solids(mesh);
    return result;
  }
  const Cap<Point> cap = cap_of(sliced, plane);
  result.cap_method = cap.method;
  result.cap_loops = cap.loop_count;
  result.cap_triangles = cap.triangles.size();
  std::vector<Point>& positions = sliced.positions;
  positions.insert(positions.end(), cap.added_points.begin(), cap.added_points.end());

  const PlaneBasis basis(plane);
  BasicMesh<Point> below = half_with_cap(sliced.below, positions);
  append_cap(below, cap, false, basis, options);
  result.below = separate_solids(below);
  below = {};
  BasicMesh<Point> above = half_with_cap(sliced.above, std::move(positions));  // its last use
  append_cap(above, cap, true, basis, options);
  result.above = separate_solids(above);
  return result;
}

}  // namespace

CutResult<Vec3> cut_mesh(const Mesh& mesh, const Plane& plane, const CutOptions& options) {
  return cut(mesh, plane, options);
}
CutResult<ExactPoint> cut_mesh(const ExactMesh& mesh, const Plane& plane, const CutOptions& options) {
  return cut(mesh, plane, options);
}

}  // namespace shatter::oracle
