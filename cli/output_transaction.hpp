#pragma once
// "All files or none": the one way every shatter command writes its outputs.

#include <filesystem>
#include <functional>
#include <string_view>
#include <vector>

#include "shatter/kernel/atomic_file.hpp"
#include "shatter/kernel/io.hpp"
#include "shatter/kernel/mesh.hpp"

namespace shatter::cli {

/// The files and folders one run writes, kept only if the run commits.
///
/// Each file is written atomically (write_file_atomically: a temporary file
/// beside it, renamed over it), so no file is ever half-written. The transaction
/// remembers every file it wrote and every folder it created; unless commit() is
/// called, its destructor removes them again (the files, then the folders in the
/// reverse order of their creation, each only if empty), so a run that fails
/// part-way leaves nothing of itself behind. Write the file other programs look
/// for last (fracture's .shatter file), so that its rename is the run's point of
/// no return.
/// Limits: a file that already existed under a name the run writes has been
/// replaced, and is gone after a rollback too; a run killed by a signal rolls
/// nothing back.
class OutputTransaction {
 public:
  OutputTransaction() = default;
  OutputTransaction(const OutputTransaction&) = delete;
  OutputTransaction& operator=(const OutputTransaction&) = delete;

  /// Removes everything written unless commit() was called. Never throws:
  /// what cannot be removed stays.
  ~OutputTransaction();

  /// Creates `folder` and its missing parents, remembering the ones it creates.
  /// Throws IoError "cannot create output folder <folder>: <reason>" (the ones
  /// made before the failure are removed with the rest).
  void create_folder(const std::filesystem::path& folder);

  /// Writes `bytes` to `path` atomically and remembers it. The folder must
  /// exist. Throws IoError naming `path` (which is then as it was).
  void write_file(const std::filesystem::path& path, std::string_view bytes);

  /// Writes to `path` atomically what `produce` hands its sink, piece by piece,
  /// going back over bytes already handed when it asks
  /// (write_file_atomically_rewritable: a large file is never held whole), and
  /// remembers it. Throws IoError naming `path`, or what `produce` throws; either
  /// way `path` is as it was.
  void write_file_rewritable(const std::filesystem::path& path, const std::function<void(const RewritableSink&)>& produce);

  /// write_file of write_mesh_to_bytes(mesh, format): the bytes write_mesh writes.
  void write_mesh(const std::filesystem::path& path, const Mesh& mesh, MeshFormat format);

  /// Keeps everything written so far: the run succeeded.
  void commit();

 private:
  std::vector<std::filesystem::path> files_;
  std::vector<std::filesystem::path> folders_;  ///< in the order they were created
  bool committed_ = false;
};

}  // namespace shatter::cli
