#include "output_transaction.hpp"

#include "shatter/kernel/error.hpp"

namespace shatter::cli {

namespace fs = std::filesystem;

OutputTransaction::~OutputTransaction() {
  if (committed_) return;
  std::error_code ignored;
  for (const fs::path& file : files_) fs::remove(file, ignored);
  // A folder created later can only lie inside one created earlier, so the
  // reverse order empties every folder before it is removed. fs::remove leaves
  // a folder that holds anything else, which this run did not make.
  for (auto folder = folders_.rbegin(); folder != folders_.rend(); ++folder) fs::remove(*folder, ignored);
}

void OutputTransaction::create_folder(const fs::path& folder) {
  // Which of its ancestors are missing, found before anything is made; a folder
  // whose existence cannot be told is not this run's to remove.
  std::vector<fs::path> missing;
  std::error_code unknown;
  for (fs::path p = folder; !p.empty() && !fs::exists(p, unknown) && !unknown; p = p.parent_path()) {
    missing.push_back(p);
    if (p == p.parent_path()) break;
  }
  // Recorded before creating, shallowest first, so a failure half-way still
  // removes what was made.
  folders_.insert(folders_.end(), missing.rbegin(), missing.rend());
  std::error_code error;
  fs::create_directories(folder, error);
  if (error) throw IoError("cannot create output folder " + folder.string() + ": " + error.message());
}

void OutputTransaction::write_file(const fs::path& path, std::string_view bytes) {
  write_file_atomically(path, bytes);
  files_.push_back(path);
}

void OutputTransaction::write_file_rewritable(const fs::path& path,
                                              const std::function<void(const RewritableSink&)>& produce) {
  write_file_atomically_rewritable(path, produce);
  files_.push_back(path);
}

void OutputTransaction::write_mesh(const fs::path& path, const Mesh& mesh, MeshFormat format) {
  write_file(path, write_mesh_to_bytes(mesh, format));
}

void OutputTransaction::commit() { committed_ = true; }

}  // namespace shatter::cli
