#pragma once
// Scratch folders for tests: one per test process and tag, removed when the
// process exits, so that runs of the suite leave nothing in the temp folder
// (before, every run of the CLI tests left a folder per test binary behind).

#include <unistd.h>

#include <filesystem>
#include <mutex>
#include <set>
#include <string>
#include <system_error>

namespace shatter::test {

namespace detail {

// The folders handed out so far, removed with everything in them when the
// registry is destroyed at exit. A test that fails a check still exits
// normally (Catch2 reports and goes on), so its files go too; one that crashes
// leaves them where they were for a look.
class ScratchRegistry {
 public:
  static ScratchRegistry& instance() {
    static ScratchRegistry registry;
    return registry;
  }
  void add(const std::filesystem::path& folder) {
    const std::lock_guard<std::mutex> lock(mutex_);
    folders_.insert(folder);
  }
  ScratchRegistry(const ScratchRegistry&) = delete;
  ScratchRegistry& operator=(const ScratchRegistry&) = delete;
  ~ScratchRegistry() {
    for (const std::filesystem::path& folder : folders_) {
      std::error_code ignored;  // nothing to report to at exit
      std::filesystem::remove_all(folder, ignored);
    }
  }

 private:
  ScratchRegistry() = default;
  std::mutex mutex_;
  std::set<std::filesystem::path> folders_;
};

}  // namespace detail

/// This process's scratch folder for `tag` (`tag`-PID in the temp folder):
/// created if missing, and removed with all it holds when the process exits.
/// Distinct tags keep test binaries and callers apart; the PID keeps
/// concurrent runs of one binary apart. Throws std::filesystem::filesystem_error
/// when the folder cannot be created.
inline std::filesystem::path process_scratch_folder(const std::string& tag) {
  const std::filesystem::path folder = std::filesystem::temp_directory_path() / (tag + "-" + std::to_string(::getpid()));
  std::filesystem::create_directories(folder);
  detail::ScratchRegistry::instance().add(folder);
  return folder;
}

}  // namespace shatter::test
