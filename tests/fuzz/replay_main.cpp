// Replays inputs through a fuzz target without libFuzzer, so every target also
// builds with any compiler and its committed corpus runs as an ordinary test.
//
//   fuzz_<target> <file or directory>...
//
// Each file, and each regular file directly inside each directory (in name
// order, for a reproducible log), is passed once to LLVMFuzzerTestOneInput. A
// broken property aborts inside the target; this driver fails on its own when a
// path cannot be read or when no input was found at all, so an empty or missing
// corpus is an error, never a silent pass.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <system_error>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace {

/// The files to replay for one command-line path, or an empty list with an
/// error printed when the path is neither a readable file nor a directory.
std::vector<std::filesystem::path> inputs_of(const std::filesystem::path& path) {
  std::vector<std::filesystem::path> files;
  std::error_code error;
  if (std::filesystem::is_directory(path, error)) {
    for (const auto& entry : std::filesystem::directory_iterator(path, error)) {
      if (entry.is_regular_file()) files.push_back(entry.path());
    }
    std::sort(files.begin(), files.end());
  } else if (std::filesystem::is_regular_file(path, error)) {
    files.push_back(path);
  }
  if (error) std::fprintf(stderr, "replay: %s: %s\n", path.c_str(), error.message().c_str());
  return files;
}

/// The whole content of a file, or false when it cannot be read.
bool read_file(const std::filesystem::path& path, std::string& bytes) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  return !in.bad();
}

}  // namespace

/// Replays every input named on the command line; exit 0 only when at least one
/// ran and every one returned.
int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s <file or directory>...\n", argv[0]);
    return 2;
  }
  std::size_t replayed = 0;
  for (int a = 1; a < argc; ++a) {
    const std::vector<std::filesystem::path> files = inputs_of(argv[a]);
    if (files.empty()) {
      std::fprintf(stderr, "replay: no input in %s\n", argv[a]);
      return 1;
    }
    for (const std::filesystem::path& file : files) {
      std::string bytes;
      if (!read_file(file, bytes)) {
        std::fprintf(stderr, "replay: cannot read %s\n", file.c_str());
        return 1;
      }
      std::fprintf(stderr, "replay: %s (%zu bytes)\n", file.c_str(), bytes.size());
      LLVMFuzzerTestOneInput(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
      ++replayed;
    }
  }
  std::printf("replayed %zu inputs\n", replayed);
  return 0;
}
