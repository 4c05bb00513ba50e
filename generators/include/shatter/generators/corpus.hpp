#pragma once
// The test corpus: the meshes checked in under tests/data/corpus (its README names
// each file's source and terms), read by the tests, the robustness runner and the
// benchmarks. Its location is fixed when shatter is configured (the source tree's
// tests/data/corpus), so nothing beside the clone is needed.
//
// Every listing throws if it reads back empty, so a property test over the corpus
// can never pass by testing nothing.

#include <filesystem>
#include <vector>

namespace shatter::test {

/// Returns the folder holding the corpus meshes (the source tree's tests/data/corpus).
/// Does not check that it exists: a caller that reads a named file gets that
/// file's error.
std::filesystem::path mesh_dir();

/// Returns the valid meshes at the top of the corpus (*.off), sorted by name.
/// Throws std::runtime_error when there is none (or no folder).
std::vector<std::filesystem::path> valid_meshes();

/// Returns the meshes under bad/, which every reader or validator must refuse,
/// sorted by name. Throws std::runtime_error when there is none.
std::vector<std::filesystem::path> bad_meshes();

/// Returns the meshes under self-intersecting/, sorted by name. Throws
/// std::runtime_error when there is none.
std::vector<std::filesystem::path> self_intersecting_meshes();

/// Returns the .shatter files the retired fast and exact kernels wrote
/// (tests/data/retired, beside the corpus; its README says how), sorted by name.
/// Throws std::runtime_error when there is none.
std::vector<std::filesystem::path> retired_kernel_trees();

}  // namespace shatter::test
