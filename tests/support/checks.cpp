#include "support/checks.hpp"

#include <algorithm>
#include <cstring>

#include "shatter/kernel/validate.hpp"

namespace shatter::test {
namespace {

// Epeck's exact number converted to gmpxx, whichever rational type CGAL chose.
mpq_class to_mpq(const mpq_class& q) { return q; }
template <class Rational>
auto to_mpq(const Rational& q) -> decltype(q.backend().data(), mpq_class()) {
  return mpq_class(q.backend().data());
}

template <class GetCoordinate>
mpq_class six_volume(const std::vector<Triangle>& triangles, GetCoordinate&& coordinate) {
  mpq_class sum = 0;
  for (const Triangle& t : triangles) {
    const mpq_class ax = coordinate(t[0], 0), ay = coordinate(t[0], 1), az = coordinate(t[0], 2);
    const mpq_class bx = coordinate(t[1], 0), by = coordinate(t[1], 1), bz = coordinate(t[1], 2);
    const mpq_class cx = coordinate(t[2], 0), cy = coordinate(t[2], 1), cz = coordinate(t[2], 2);
    sum += ax * (by * cz - bz * cy) - ay * (bx * cz - bz * cx) + az * (bx * cy - by * cx);
  }
  return sum;
}

}  // namespace

std::string solid_problem(const Mesh& mesh) {
  const std::size_t corners = 3 * mesh.triangles.size();
  if (mesh.surfaces.size() != mesh.triangles.size()) return "surface ids do not match the triangles";
  if (mesh.corners.has_normals() && mesh.corners.normals.size() != corners) return "normals channel size";
  if (mesh.corners.has_uvs() && mesh.corners.uvs.size() != corners) return "uv channel size";
  if (mesh.corners.has_tangents() && mesh.corners.tangents.size() != corners) return "tangent channel size";
  ValidationOptions options;
  options.check_self_intersections = false;
  const ValidationReport report = validate_mesh(mesh, options);
  if (!report.valid()) return report.summary();
  return {};
}

std::string topology_problem(const Mesh& mesh) {
  ValidationOptions options;
  options.check_self_intersections = false;
  const ValidationReport report = validate_mesh(mesh, options);
  for (const Defect& defect : report.defects) {
    if (defect.kind != DefectKind::zero_area_triangle && defect.kind != DefectKind::inward_orientation) {
      return std::string(defect_name(defect.kind)) + ": " + defect.first;
    }
  }
  return {};
}

std::string exact_solid_problem(const ExactMesh& mesh) {
  if (std::string problem = topology_problem(to_fast(mesh)); !problem.empty()) return problem;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Triangle& tri = mesh.triangles[t];
    if (CGAL::collinear(mesh.positions[tri[0]], mesh.positions[tri[1]], mesh.positions[tri[2]])) {
      return "zero-area triangle " + std::to_string(t);
    }
  }
  if (exact_six_volume(mesh) <= 0) return "volume not positive";
  return {};
}

mpq_class exact_six_volume(const ExactMesh& mesh) {
  return six_volume(mesh.triangles, [&](VertexIndex v, int axis) {
    return to_mpq(CGAL::exact(mesh.positions[v].cartesian(axis)));
  });
}

mpq_class exact_six_volume(const Mesh& mesh) {
  return six_volume(mesh.triangles, [&](VertexIndex v, int axis) { return mpq_class(mesh.positions[v][axis]); });
}

std::string canonical_bytes(const Mesh& mesh) {
  std::string bytes;
  auto put = [&](const void* data, std::size_t size) { bytes.append(static_cast<const char*>(data), size); };
  const std::uint64_t counts[] = {mesh.positions.size(), mesh.triangles.size(), mesh.corners.normals.size(),
                                  mesh.corners.uvs.size(), mesh.corners.tangents.size()};
  put(counts, sizeof counts);
  put(mesh.positions.data(), mesh.positions.size() * sizeof(Vec3));
  put(mesh.triangles.data(), mesh.triangles.size() * sizeof(Triangle));
  put(mesh.surfaces.data(), mesh.surfaces.size() * sizeof(SurfaceId));
  put(mesh.corners.normals.data(), mesh.corners.normals.size() * sizeof(Vec3));
  put(mesh.corners.uvs.data(), mesh.corners.uvs.size() * sizeof(Vec2));
  put(mesh.corners.tangents.data(), mesh.corners.tangents.size() * sizeof(Vec4));
  return bytes;
}

Box3 bounds(const Mesh& mesh) {
  Box3 box{mesh.positions.at(0), mesh.positions.at(0)};
  for (const Vec3& p : mesh.positions) {
    box.lo = {std::min(box.lo.x, p.x), std::min(box.lo.y, p.y), std::min(box.lo.z, p.z)};
    box.hi = {std::max(box.hi.x, p.x), std::max(box.hi.y, p.y), std::max(box.hi.z, p.z)};
  }
  return box;
}

}  // namespace shatter::test
