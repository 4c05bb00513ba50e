#pragma once
// `shatter view TREE.shatter --original MESH` (issue 21): the input file a
// repaired tree was built from, read as the commands read their input, with
// what is wrong with it found on the server, for the page to draw beside the
// tree's root (GET /api/original).

#include <nlohmann/json.hpp>

#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include "shatter/kernel/mesh.hpp"
#include "shatter/kernel/repair.hpp"
#include "shatter/kernel/validate.hpp"

namespace shatter::cli {

/// An original input with its defects, element by element where the page
/// highlights them.
struct OriginalInput {
  std::string name;  ///< the file name shown on the page
  Mesh mesh;         ///< as read_mesh read it
  std::vector<std::string> read_warnings;
  /// validate_mesh's, in full. Its self-intersection test runs on closed
  /// manifolds only; self_intersecting_triangles covers open meshes too.
  ValidationReport report;
  std::vector<Edge> boundary_edges;      ///< edges with one triangle, as (low, high) vertex indices, sorted
  std::vector<Edge> non_manifold_edges;  ///< edges with three or more triangles, likewise
  /// Triangles in at least one intersecting pair (self_intersecting_pairs over
  /// the triangles that are not degenerate), ascending. Not looked for again
  /// when `report` tested the mesh and found none. Unlike validate_mesh, two fans
  /// that only touch at a non-manifold vertex are no pair here.
  std::vector<TriangleIndex> self_intersecting_triangles;
  std::size_t self_intersecting_pairs = 0;
  std::array<TriangleIndex, 2> first_intersecting_pair{};  ///< the first pair, when there is one
  std::size_t degenerate_triangles = 0;  ///< repeated index or exactly collinear corners: left out of that test
};

/// Reads `path` with read_mesh (the reader every command uses; its warnings
/// printed on stderr as "warning: <path>: ..." and kept) and finds its defects.
/// Refuses, by throwing, an original the page cannot draw or that is not the
/// input of the tree whose root is `root` and whose input repair is `repair`:
///  - IoError / InvalidMeshError from read_mesh, prefixed "--original <path>: ";
///  - InvalidMeshError "--original <path>: ..." for a NaN or infinite
///    coordinate or a triangle index out of range;
///  - InvalidMeshError "--original <path> is not the input of this tree: ..."
///    when the bounding boxes disagree. Without a repair the root is the input as
///    read, so the boxes must be equal; with one, the root's box must lie within
///    the original's, since repair moves no point and makes new ones only on the
///    input's triangles (rounded once to the nearest double, which keeps a
///    coordinate between the input's extremes), and may drop vertices.
/// The comparison is of doubles by <= and ==, exact; it rejects a wrong file
/// of another size or place, not one that shares the box.
OriginalInput read_original_input(const std::string& path, const Mesh& root, const RepairReport& repair);

/// The answer of GET /api/original:
///   {file, vertices, triangles, positions [x, y, z, ...], indices [a, b, c, ...],
///    validation (the report's one line, with the self-intersecting pairs
///    found beyond its test appended), defects [{kind, count, first}],
///    boundary_edges [a, b, ...], non_manifold_edges [a, b, ...],
///    self_intersecting_triangles [t, ...], degenerate_triangles, read_warnings,
///    repair {changes [text], not_done [text], vertices_before, triangles_before,
///            vertices_after, triangles_after} or null when the tree records none}.
/// Coordinates are written so that they read back as the same doubles.
nlohmann::ordered_json original_json(const OriginalInput& original, const RepairReport& repair);

}  // namespace shatter::cli
