#include "support/checks.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Mpzf.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <map>
#include <sstream>
#include <utility>

#include "shatter/kernel/validate.hpp"
#include "shatter/meshtree/validate_tree.hpp"

namespace shatter::test {
namespace {

// Epeck's exact number converted to gmpxx, whichever rational type CGAL chose.
mpq_class to_mpq(const mpq_class& q) { return q; }
template <class Rational>
auto to_mpq(const Rational& q) -> decltype(q.backend().data(), mpq_class()) {
  return mpq_class(q.backend().data());
}

// Six times the signed volume as the sum of a·(b×c) over the triangles, in the
// number type of the coordinates given (one entry per vertex, three per entry).
template <class Number>
Number six_volume(const std::vector<Triangle>& triangles, const std::vector<std::array<Number, 3>>& p) {
  Number sum(0);
  for (const Triangle& t : triangles) {
    const auto& a = p[t[0]];
    const auto& b = p[t[1]];
    const auto& c = p[t[2]];
    sum += a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0]);
  }
  return sum;
}

using EpickPoint = CGAL::Exact_predicates_inexact_constructions_kernel::Point_3;
EpickPoint epick(const Vec3& p) { return {p.x, p.y, p.z}; }

std::string point_text(const Vec3& v) {
  std::ostringstream out;
  out.precision(17);
  out << "(" << v.x << ", " << v.y << ", " << v.z << ")";
  return out.str();
}

}  // namespace

std::string convexity_problem(const Mesh& hull) {
  std::map<std::pair<VertexIndex, VertexIndex>, VertexIndex> far_corner;
  for (const Triangle& t : hull.triangles) {
    for (int c = 0; c < 3; ++c) far_corner[{t[c], t[(c + 1) % 3]}] = t[(c + 2) % 3];
  }
  for (std::size_t i = 0; i < hull.triangles.size(); ++i) {
    const Triangle& t = hull.triangles[i];
    const EpickPoint a = epick(hull.positions[t[0]]), b = epick(hull.positions[t[1]]), c = epick(hull.positions[t[2]]);
    for (int k = 0; k < 3; ++k) {
      const auto across = far_corner.find({t[(k + 1) % 3], t[k]});
      if (across == far_corner.end()) return "open at triangle " + std::to_string(i);
      if (CGAL::orientation(a, b, c, epick(hull.positions[across->second])) == CGAL::POSITIVE) {
        return "not convex at an edge of triangle " + std::to_string(i);
      }
    }
  }
  return {};
}

std::string containing_hull_problem(const Mesh& mesh, const Mesh& hull) {
  if (const std::string problem = solid_problem(hull); !problem.empty()) return "not a valid solid: " + problem;
  if (std::any_of(hull.surfaces.begin(), hull.surfaces.end(), [](SurfaceId s) { return s != 0; })) {
    return "a surface id other than 0";
  }
  if (const std::string problem = convexity_problem(hull); !problem.empty()) return problem;
  for (std::size_t i = 0; i < hull.triangles.size(); ++i) {
    const Triangle& t = hull.triangles[i];
    const EpickPoint a = epick(hull.positions[t[0]]), b = epick(hull.positions[t[1]]), c = epick(hull.positions[t[2]]);
    for (const Vec3& p : mesh.positions) {
      if (CGAL::orientation(a, b, c, epick(p)) == CGAL::POSITIVE) {
        return "mesh vertex " + point_text(p) + " lies outside hull triangle " + std::to_string(i);
      }
    }
  }
  return {};
}

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

std::string tree_problem(const MeshTree& tree, bool geometry) {
  const TreeValidationReport report = validate_tree(tree, {.geometry = geometry});
  return report.valid() ? std::string() : report.summary();
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
  // Each coordinate converted once, not once per corner.
  std::vector<std::array<mpq_class, 3>> p(mesh.positions.size());
  for (std::size_t v = 0; v < p.size(); ++v) {
    for (int axis = 0; axis < 3; ++axis) p[v][axis] = to_mpq(CGAL::exact(mesh.positions[v].cartesian(axis)));
  }
  return six_volume(mesh.triangles, p);
}

mpq_class exact_six_volume(const Mesh& mesh) {
  // CGAL's Mpzf is a binary floating-point integer: products and sums of doubles
  // stay exact without the rationals' gcd on every operation.
  std::vector<std::array<CGAL::Mpzf, 3>> p(mesh.positions.size());
  for (std::size_t v = 0; v < p.size(); ++v) {
    for (int axis = 0; axis < 3; ++axis) p[v][axis] = CGAL::Mpzf(mesh.positions[v][axis]);
  }
  return mpq_class(six_volume(mesh.triangles, p));
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

double surface_area(const Mesh& mesh) {
  double area = 0;
  for (const Triangle& t : mesh.triangles) {
    area += 0.5 * norm(cross(mesh.positions[t[1]] - mesh.positions[t[0]], mesh.positions[t[2]] - mesh.positions[t[0]]));
  }
  return area;
}

double largest_coordinate(const Mesh& mesh) {
  double largest = 0;
  for (const Vec3& p : mesh.positions) largest = std::max({largest, std::fabs(p.x), std::fabs(p.y), std::fabs(p.z)});
  return largest;
}

Box3 bounds(const Mesh& mesh) {
  Box3 box{mesh.positions.at(0), mesh.positions.at(0)};
  for (const Vec3& p : mesh.positions) {
    box.lo = {std::min(box.lo.x, p.x), std::min(box.lo.y, p.y), std::min(box.lo.z, p.z)};
    box.hi = {std::max(box.hi.x, p.x), std::max(box.hi.y, p.y), std::max(box.hi.z, p.z)};
  }
  return box;
}


bool same_solid(const Solid& a, const Solid& b) {
  return a.defs == b.defs && a.convex == b.convex && same_faces(a, b);
}

bool same_solids(const std::vector<Solid>& a, const std::vector<Solid>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (!same_solid(a[i], b[i])) return false;
  }
  return true;
}

}  // namespace shatter::test
