#include "shatter/kernel/shells.hpp"

#include <algorithm>
#include <limits>
#include <memory>

#include "shatter/kernel/half_edges.hpp"
#include "shatter/kernel/inside.hpp"
#include "shatter/kernel/mass.hpp"
#include "shatter/kernel/union_find.hpp"

namespace shatter {

ShellNesting shell_nesting(const Mesh& mesh) {
  ShellNesting nesting;
  const std::size_t triangle_count = mesh.triangles.size();
  constexpr std::uint32_t unset = std::numeric_limits<std::uint32_t>::max();
  nesting.shell_of_triangle.assign(triangle_count, unset);
  if (triangle_count == 0) return nesting;

  const HalfEdgeTwins twins = half_edge_twins(mesh.triangles, mesh.vertex_count());
  UnionFind joined(triangle_count);
  for (std::uint32_t h = 0; h < twins.twin.size(); ++h) {
    if (twins.twin[h] != HalfEdgeTwins::none) joined.unite(h / 3, twins.twin[h] / 3);
  }
  std::vector<std::uint32_t> shell_of_root(triangle_count, unset);
  std::uint32_t shell_count = 0;
  for (std::uint32_t t = 0; t < triangle_count; ++t) {
    std::uint32_t& shell = shell_of_root[joined.find(t)];
    if (shell == unset) shell = shell_count++;
    nesting.shell_of_triangle[t] = shell;
  }
  if (shell_count == 1) {
    nesting.outward = {signed_volume_sign(mesh) == Sign::positive};
    nesting.depth = {0};
    return nesting;
  }

  // Each shell as a mesh of its own. A vertex belongs to one shell (the mesh is
  // manifold), so one renumbering serves them all.
  struct Shell {
    Mesh mesh;
    Vec3 lo, hi;
    std::unique_ptr<PointInSolid> inside;  // built only when another shell may lie in it
  };
  std::vector<Shell> shells(shell_count);
  std::vector<VertexIndex> local(mesh.vertex_count(), std::numeric_limits<VertexIndex>::max());
  for (std::size_t t = 0; t < triangle_count; ++t) {
    Mesh& shell = shells[nesting.shell_of_triangle[t]].mesh;
    Triangle corners{};
    for (int c = 0; c < 3; ++c) {
      const VertexIndex v = mesh.triangles[t][c];
      if (local[v] == std::numeric_limits<VertexIndex>::max()) {
        local[v] = static_cast<VertexIndex>(shell.positions.size());
        shell.positions.push_back(mesh.positions[v]);
      }
      corners[c] = local[v];
    }
    shell.triangles.push_back(corners);
  }
  nesting.outward.resize(shell_count);
  nesting.depth.assign(shell_count, 0);
  for (std::uint32_t s = 0; s < shell_count; ++s) {
    Shell& shell = shells[s];
    shell.mesh.surfaces.assign(shell.mesh.triangles.size(), original_surface);
    nesting.outward[s] = signed_volume_sign(shell.mesh) == Sign::positive;
    shell.lo = shell.hi = shell.mesh.positions.front();
    for (const Vec3& p : shell.mesh.positions) {
      shell.lo = {std::min(shell.lo.x, p.x), std::min(shell.lo.y, p.y), std::min(shell.lo.z, p.z)};
      shell.hi = {std::max(shell.hi.x, p.x), std::max(shell.hi.y, p.y), std::max(shell.hi.z, p.z)};
    }
  }
  // A shell inside another has its box inside the other's box: only those pairs
  // need a point query. (Box comparisons only skip queries; they decide nothing.)
  auto box_within = [](const Shell& inner, const Shell& outer) {
    return outer.lo.x <= inner.lo.x && outer.lo.y <= inner.lo.y && outer.lo.z <= inner.lo.z &&
           inner.hi.x <= outer.hi.x && inner.hi.y <= outer.hi.y && inner.hi.z <= outer.hi.z;
  };
  for (std::uint32_t s = 0; s < shell_count; ++s) {
    for (std::uint32_t t = 0; t < shell_count; ++t) {
      if (t == s || !box_within(shells[s], shells[t])) continue;
      if (!shells[t].inside) shells[t].inside = std::make_unique<PointInSolid>(shells[t].mesh);
      nesting.depth[s] += shells[t].inside->strictly_inside(shells[s].mesh.positions.front()) ? 1 : 0;
    }
  }
  return nesting;
}

}  // namespace shatter
