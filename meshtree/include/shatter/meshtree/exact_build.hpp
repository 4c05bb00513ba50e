#pragma once
// The exact kernel's build, keeping what it rounds: every node's exact solid
// beside the tree. Apart from build.hpp because it brings in CGAL's exact number
// types (Epeck), which nothing that only builds or reads trees should compile.

#include <vector>

#include "shatter/kernel/exact.hpp"
#include "shatter/kernel/mesh.hpp"
#include "shatter/meshtree/build.hpp"
#include "shatter/meshtree/tree.hpp"

namespace shatter {

/// A built tree and, when options.kernel is exact, every node's exact solid in
/// node order (empty otherwise): the tree's meshes are those solids rounded to the
/// nearest doubles, so only these show that volumes add up exactly.
struct ExactBuild {
  MeshTree tree;
  std::vector<ExactMesh> exact_meshes;
};

/// build_mesh_tree(mesh, options), also returning the exact solids (ExactBuild).
/// Preconditions, guarantees and errors: those of build_mesh_tree; `tree` is the
/// tree build_mesh_tree returns for the same arguments.
ExactBuild build_mesh_tree_keeping_exact(const Mesh& mesh, const BuildOptions& options);

}  // namespace shatter
