#include "bench_support.hpp"

#include <algorithm>
#include <cstdio>
#include <stdexcept>

namespace shatter::bench {

CgalMesh to_cgal(const Mesh& mesh) {
  CgalMesh out;
  out.reserve(static_cast<CgalMesh::size_type>(mesh.positions.size()),
              static_cast<CgalMesh::size_type>(mesh.positions.size() + mesh.triangles.size()),
              static_cast<CgalMesh::size_type>(mesh.triangles.size()));
  std::vector<CgalMesh::Vertex_index> vertices;
  vertices.reserve(mesh.positions.size());
  for (const auto& p : mesh.positions) vertices.push_back(out.add_vertex(Epick::Point_3(p.x, p.y, p.z)));
  for (const auto& [a, b, c] : mesh.triangles) {
    if (out.add_face(vertices[a], vertices[b], vertices[c]) == CgalMesh::null_face())
      throw std::runtime_error("the mesh is not a valid CGAL Surface_mesh (non-manifold face)");
  }
  return out;
}

double median(std::vector<double> values, double empty_value) {
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  if (n == 0) return empty_value;
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

std::string fixed(double value, int digits) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*f", digits, value);
  return buffer;
}

std::string with_thousands(std::uint64_t value) {
  std::string digits = std::to_string(value), out;
  for (std::size_t i = 0; i < digits.size(); ++i) {
    if (i && (digits.size() - i) % 3 == 0) out += ',';
    out += digits[i];
  }
  return out;
}

}  // namespace shatter::bench
