// The volume rounding a piece's vertices can move, and the volume a repaired
// mesh moved, both exact (rationals). See rounding.hpp.
#include "rounding.hpp"

#include <algorithm>

namespace shatter {

namespace rounding {

mpq_class rounding_sweep_bound(const PlaneSet& set, const Solid& solid, bool any_triangulation) {
  const std::size_t n = solid.defs.size();
  std::vector<std::array<mpq_class, 3>> exact(n);
  std::vector<mpq_class> moved(n);
  for (std::size_t v = 0; v < n; ++v) {
    exact[v] = exact_coordinates(set, solid.defs[v]);
    const Vec3 p = output_position(set, solid.defs[v], solid.approx[v]);
    const double coordinates[3] = {p.x, p.y, p.z};
    for (int k = 0; k < 3; ++k) moved[v] += abs(mpq_class(coordinates[k]) - exact[v][k]);
  }
  auto length1 = [&](VertexIndex a, VertexIndex b) {
    return mpq_class(abs(exact[a][0] - exact[b][0]) + abs(exact[a][1] - exact[b][1]) + abs(exact[a][2] - exact[b][2]));
  };
  mpq_class bound = 0;
  for (const SolidFace& face : solid.faces) {
    const VertexIndex centre = solid.corners[solid.loops[face.first_loop].first_corner].vertex;
    mpq_class face_delta = 0;
    if (any_triangulation) {
      for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
        for (const CornerEdge& edge : loop_edges(solid.corners, solid.loops[l])) {
          if (moved[edge.from] > face_delta) face_delta = moved[edge.from];
        }
      }
    }
    for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
      for (const CornerEdge& edge : loop_edges(solid.corners, solid.loops[l])) {
        if (edge.from == centre || edge.to == centre) continue;
        const auto& a = exact[centre];
        const auto& b = exact[edge.from];
        const auto& c = exact[edge.to];
        const mpq_class u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
        const mpq_class w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        const mpq_class area = (abs(u[1] * w[2] - u[2] * w[1]) + abs(u[2] * w[0] - u[0] * w[2]) +
                                abs(u[0] * w[1] - u[1] * w[0])) / 2;
        const mpq_class perimeter = length1(centre, edge.from) + length1(edge.from, edge.to) + length1(edge.to, centre);
        const mpq_class delta =
            any_triangulation ? face_delta : std::max({moved[centre], moved[edge.from], moved[edge.to]});
        bound += delta * ((any_triangulation ? 4 : 2) * area + delta * (4 * perimeter + 5 * delta));
      }
    }
  }
  return bound;
}

MovedVolume measured_moved_volume(PieceVolumes& piece, const Mesh& mesh) {
  mpq_class mesh_six = 0;
  for (const Triangle& t : mesh.triangles) {
    const Vec3 &a = mesh.positions[t[0]], &b = mesh.positions[t[1]], &c = mesh.positions[t[2]];
    const mpq_class ax(a.x), ay(a.y), az(a.z), bx(b.x), by(b.y), bz(b.z), cx(c.x), cy(c.y), cz(c.z);
    mesh_six += ax * (by * cz - bz * cy) + ay * (bz * cx - bx * cz) + az * (bx * cy - by * cx);
  }
  return {abs(mesh_six - piece.six()) / 6, piece.sweep(/*any_triangulation=*/true)};
}

bool report_moved_volume(const MovedVolume& moved, RoundedSolid& result) {
  result.moved_volume = moved.change.get_d();
  result.moved_volume_bound = moved.bound.get_d();
  return moved.change <= moved.bound;
}

}  // namespace rounding

}  // namespace shatter
