#include "support/union_volume.hpp"

#include <CGAL/Polygon_mesh_processing/corefinement.h>
#include <CGAL/Polygon_mesh_processing/measure.h>
#include <CGAL/Surface_mesh.h>

#include <stdexcept>
#include <string>
#include <utility>

namespace shatter::test {

namespace {

using EpeckMesh = CGAL::Surface_mesh<ExactKernel::Point_3>;

EpeckMesh exact_mesh(const Mesh& mesh) {
  EpeckMesh out;
  std::vector<EpeckMesh::Vertex_index> vertices;
  vertices.reserve(mesh.positions.size());
  for (const Vec3& p : mesh.positions) vertices.push_back(out.add_vertex(ExactKernel::Point_3(p.x, p.y, p.z)));
  for (const Triangle& t : mesh.triangles) out.add_face(vertices[t[0]], vertices[t[1]], vertices[t[2]]);
  return out;
}

}  // namespace

ExactKernel::FT six_volume_of_union(const std::vector<Mesh>& solids) {
  if (solids.empty()) throw std::runtime_error("six_volume_of_union: no solid");
  EpeckMesh united = exact_mesh(solids.front());
  for (std::size_t s = 1; s < solids.size(); ++s) {
    EpeckMesh next = exact_mesh(solids[s]), result;
    if (!CGAL::Polygon_mesh_processing::corefine_and_compute_union(united, next, result)) {
      throw std::runtime_error("six_volume_of_union: CGAL could not unite solid " + std::to_string(s));
    }
    united = std::move(result);
  }
  return 6 * CGAL::Polygon_mesh_processing::volume(united);
}

}  // namespace shatter::test
