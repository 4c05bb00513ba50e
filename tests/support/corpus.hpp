#pragma once
// The test corpus (tests/data/corpus, see its README). Every accessor throws if
// the corpus reads back empty, so a property test can never pass by testing nothing.

#include <filesystem>
#include <vector>

namespace shatter::test {

/// The folder holding the corpus meshes (tests/data/corpus).
std::filesystem::path mesh_dir();
/// The valid meshes at the top of the corpus (*.off), sorted by name; never empty.
std::vector<std::filesystem::path> valid_meshes();
/// The meshes under bad/, which must be refused; never empty.
std::vector<std::filesystem::path> bad_meshes();
/// The meshes under self-intersecting/; never empty.
std::vector<std::filesystem::path> self_intersecting_meshes();

}  // namespace shatter::test
