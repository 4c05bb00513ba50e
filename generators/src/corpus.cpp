#include "shatter/generators/corpus.hpp"

#include <algorithm>
#include <stdexcept>

namespace shatter::test {

std::filesystem::path mesh_dir() { return SHATTER_MESH_DIR; }

namespace {
std::vector<std::filesystem::path> meshes_in(const std::filesystem::path& dir) {
  std::vector<std::filesystem::path> found;
  if (std::filesystem::is_directory(dir)) {
    for (const auto& entry : std::filesystem::directory_iterator(dir)) {
      if (entry.is_regular_file() && entry.path().extension() == ".off") found.push_back(entry.path());
    }
  }
  if (found.empty()) throw std::runtime_error("test corpus is empty: " + dir.string());
  std::sort(found.begin(), found.end());
  return found;
}
}  // namespace

std::vector<std::filesystem::path> valid_meshes() { return meshes_in(mesh_dir()); }
std::vector<std::filesystem::path> bad_meshes() { return meshes_in(mesh_dir() / "bad"); }
std::vector<std::filesystem::path> self_intersecting_meshes() {
  return meshes_in(mesh_dir() / "self-intersecting");
}

}  // namespace shatter::test
