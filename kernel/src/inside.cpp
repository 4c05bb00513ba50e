#include "shatter/kernel/inside.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Side_of_triangle_mesh.h>
#include <CGAL/Surface_mesh.h>

#include <vector>

namespace shatter {

namespace {
using Epick = CGAL::Exact_predicates_inexact_constructions_kernel;
using SurfaceMesh = CGAL::Surface_mesh<Epick::Point_3>;
}  // namespace

struct PointInSolid::State {
  SurfaceMesh surface;
  std::unique_ptr<CGAL::Side_of_triangle_mesh<SurfaceMesh, Epick>> side;
};

PointInSolid::PointInSolid(const Mesh& mesh) : state_(std::make_unique<State>()) {
  std::vector<SurfaceMesh::Vertex_index> vertices;
  vertices.reserve(mesh.positions.size());
  for (const Vec3& p : mesh.positions) vertices.push_back(state_->surface.add_vertex(Epick::Point_3(p.x, p.y, p.z)));
  for (const Triangle& t : mesh.triangles) state_->surface.add_face(vertices[t[0]], vertices[t[1]], vertices[t[2]]);
  state_->side = std::make_unique<CGAL::Side_of_triangle_mesh<SurfaceMesh, Epick>>(state_->surface);
}

PointInSolid::~PointInSolid() = default;

bool PointInSolid::strictly_inside(const Vec3& point) const {
  return (*state_->side)(Epick::Point_3(point.x, point.y, point.z)) == CGAL::ON_BOUNDED_SIDE;
}

}  // namespace shatter
