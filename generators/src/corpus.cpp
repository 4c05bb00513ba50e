#include "shatter/generators/corpus.hpp"

#include <algorithm>
#include <stdexcept>

namespace shatter::test {

std::filesystem::path mesh_dir() { return SHATTER_MESH_DIR; }

namespace {
std::vector<std::filesystem::path> files_in(const std::filesystem::path& dir, const char* extension) {
  std::vector<std::filesystem::path> found;
  if (std::filesystem::is_directory(dir)) {
    for (const auto& entry : std::filesystem::directory_iterator(dir)) {
      if (entry.is_regular_file() && entry.path().extension() == extension) found.push_back(entry.path());
    }
  }
  if (found.empty()) throw std::runtime_error("test corpus is empty: " + dir.string());
  std::sort(found.begin(), found.end());
  return found;
}
}  // namespace

std::vector<std::filesystem::path> valid_meshes() { return files_in(mesh_dir(), ".off"); }
std::vector<std::filesystem::path> bad_meshes() { return files_in(mesh_dir() / "bad", ".off"); }
std::vector<std::filesystem::path> self_intersecting_meshes() {
  return files_in(mesh_dir() / "self-intersecting", ".off");
}
std::vector<std::filesystem::path> retired_kernel_trees() {
  return files_in(mesh_dir().parent_path() / "retired", ".shatter");
}

}  // namespace shatter::test
