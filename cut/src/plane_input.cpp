#include "shatter/cut/plane_input.hpp"

#include <tbb/parallel_invoke.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <exception>
#include <optional>

#include "shatter/kernel/half_edges.hpp"
#include "shatter/kernel/mass.hpp"
#include "shatter/kernel/union_find.hpp"
#include "shatter/kernel/validate.hpp"
#include "shatter/cut/separate.hpp"

namespace shatter {
namespace {

void append_mesh(const Mesh& part, Mesh& whole) {
  const auto base = static_cast<VertexIndex>(whole.positions.size());
  whole.positions.insert(whole.positions.end(), part.positions.begin(), part.positions.end());
  for (Triangle t : part.triangles) whole.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  whole.surfaces.insert(whole.surfaces.end(), part.surfaces.begin(), part.surfaces.end());
  whole.corners.normals.insert(whole.corners.normals.end(), part.corners.normals.begin(), part.corners.normals.end());
  whole.corners.uvs.insert(whole.corners.uvs.end(), part.corners.uvs.begin(), part.corners.uvs.end());
  whole.corners.tangents.insert(whole.corners.tangents.end(), part.corners.tangents.begin(),
                                part.corners.tangents.end());
}

}  // namespace

PlaneInput prepare_plane_input(const Mesh& mesh) {
  PlaneInput input;
  // One topology pass serves separation, shells and the solid. A mesh of one
  // shell (the common case) comes out of separate_solids with its triangles in
  // order, so its half-edges keep their twins; several shells are regrouped by
  // solid, and their twins found again.
  HalfEdgeTwins twins = half_edge_twins(mesh.triangles, mesh.positions.size());
  const auto shells_of = [](const HalfEdgeTwins& of, std::size_t triangle_count) {
    UnionFind sets(triangle_count);
    for (std::uint32_t h = 0; h < 3 * triangle_count; ++h) {
      if (of.twin[h] != HalfEdgeTwins::none) sets.unite(h / 3, of.twin[h] / 3);
    }
    return sets;
  };
  UnionFind shell_sets = shells_of(twins, mesh.triangles.size());
  bool one_shell = true;
  for (std::uint32_t t = 0; t < mesh.triangles.size() && one_shell; ++t) one_shell = shell_sets.find(t) == 0;
  std::vector<Mesh> solids = separate_solids(mesh, twins);
  std::vector<std::size_t> first_triangle;
  if (solids.size() == 1) {
    first_triangle.push_back(0);
    input.mesh = std::move(solids.front());  // the common case: nothing to append to
  } else {
    for (const Mesh& solid : solids) {
      first_triangle.push_back(input.mesh.triangles.size());
      append_mesh(solid, input.mesh);
    }
  }
  first_triangle.push_back(input.mesh.triangles.size());
  if (!one_shell) {
    twins = half_edge_twins(input.mesh.triangles, input.mesh.positions.size());
    shell_sets = shells_of(twins, input.mesh.triangles.size());
  }

  // Shells: edge-connected triangles; in each solid the outward one is the outer.
  const std::size_t triangle_count = input.mesh.triangles.size();
  std::vector<std::uint32_t> shell_of_root(triangle_count, no_index);
  input.shells.shell_of_triangle.resize(triangle_count);
  std::vector<std::vector<TriangleIndex>> shell_triangles;
  for (std::uint32_t t = 0; t < triangle_count; ++t) {
    const std::uint32_t root = shell_sets.find(t);
    if (shell_of_root[root] == no_index) {
      shell_of_root[root] = static_cast<std::uint32_t>(shell_triangles.size());
      shell_triangles.emplace_back();
    }
    input.shells.shell_of_triangle[t] = shell_of_root[root];
    shell_triangles[shell_of_root[root]].push_back(t);
  }
  input.shells.outer_of_shell.assign(shell_triangles.size(), no_index);
  for (std::size_t s = 0; s + 1 < first_triangle.size(); ++s) {
    // The shells of solid s, and the one facing outward among them.
    std::uint32_t outer = no_index;
    std::vector<std::uint32_t> members;
    for (std::size_t t = first_triangle[s]; t < first_triangle[s + 1]; ++t) {
      const std::uint32_t shell = input.shells.shell_of_triangle[t];
      if (members.empty() || members.back() != shell) {
        if (std::find(members.begin(), members.end(), shell) == members.end()) members.push_back(shell);
      }
    }
    // A solid of one shell has it as its outer one, whatever its volume's sign
    // (separate_solids keeps a shell that faces inward with no container alone).
    if (members.size() == 1) {
      input.shells.outer_of_shell[members.front()] = members.front();
      continue;
    }
    for (const std::uint32_t shell : members) {
      Mesh part;
      part.positions = input.mesh.positions;
      for (TriangleIndex t : shell_triangles[shell]) part.triangles.push_back(input.mesh.triangles[t]);
      if (signed_volume_sign(part) == Sign::positive) outer = shell;
    }
    for (const std::uint32_t shell : members) input.shells.outer_of_shell[shell] = outer == no_index ? shell : outer;
  }

  const bool has_attributes =
      input.mesh.corners.has_normals() || input.mesh.corners.has_uvs() || input.mesh.corners.has_tangents();
  input.geometry.points = input.mesh.positions;
  input.solid = solid_from_mesh(input.mesh, !has_attributes, input.geometry, &twins);
  return input;
}

PlaneInput prepare_plane_input_beside(const Mesh& mesh, const std::function<void()>& check) {
  // The preparation reads only a mesh whose every other defect is ruled out
  // first (one linear pass): on a non-finite coordinate or a zero-area
  // triangle it would meet floating-point exceptions, which a program may trap.
  // On one thread nothing overlaps, so nothing is checked twice either.
  ValidationOptions without_search;
  without_search.check_self_intersections = false;
  if (tbb::this_task_arena::max_concurrency() < 2 || !validate_mesh(mesh, without_search).valid()) {
    check();
    return prepare_plane_input(mesh);
  }
  std::optional<PlaneInput> prepared;
  std::exception_ptr preparation_failed;
  // The check's exception, if any, is the one parallel_invoke rethrows: the
  // preparation's is caught here and only rethrown once the check passed.
  tbb::parallel_invoke(check, [&] {
    try {
      prepared = prepare_plane_input(mesh);
    } catch (...) {
      preparation_failed = std::current_exception();
    }
  });
  if (preparation_failed) std::rethrow_exception(preparation_failed);
  return std::move(*prepared);
}

}  // namespace shatter
