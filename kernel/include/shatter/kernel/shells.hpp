#pragma once
// The shells of a closed mesh and how they nest: which shell lies inside which,
// decided exactly. A closed, oriented, embedded surface bounds a solid (winding
// number 0 or 1 everywhere) exactly when its shells alternate going inward: a
// shell inside an even number of others faces outward, inside an odd number
// inward (a cavity). validate_mesh names a mesh that breaks this (misnested
// shells); repair_mesh reverses the shells that break it.

#include <cstdint>
#include <vector>

#include "shatter/kernel/mesh.hpp"

namespace shatter {

struct ShellNesting {
  /// #T: the shell of each triangle, numbered in order of first triangle.
  std::vector<std::uint32_t> shell_of_triangle;
  /// Per shell: the exact sign of its volume is positive (it faces outward).
  std::vector<bool> outward;
  /// Per shell: how many other shells contain it.
  std::vector<std::uint32_t> depth;

  std::size_t shell_count() const { return outward.size(); }
  /// The shell faces the way its depth asks: outward at even depth, inward at odd.
  bool well_nested(std::size_t shell) const { return outward[shell] == (depth[shell] % 2 == 0); }
};

/// Shells (edge-connected triangle sets) of `mesh`, each one's side and depth.
/// Preconditions: `mesh` is closed, consistently oriented and 2-manifold
/// (is_closed_oriented_manifold), with no zero-area triangle; its shells do not
/// intersect (validate_mesh finds no self-intersection). Then each shell lies
/// strictly inside or outside each other one, and one vertex of it tells which.
/// Guarantees: every decision exact (the volume's sign by signed_volume_sign,
/// containment by PointInSolid's ray parity); deterministic. Cost: linear for one
/// shell; with several, one point query per pair of shells whose boxes nest, after
/// an O(T log T) setup per containing shell.
ShellNesting shell_nesting(const Mesh& mesh);

}  // namespace shatter
