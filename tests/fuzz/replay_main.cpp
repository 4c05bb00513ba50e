// Replays inputs through a fuzz target without libFuzzer, so every target also
// builds with any compiler and its committed corpus runs as an ordinary test.
//
//   fuzz_<target> [--max-refusals=N] <file or directory>...
//
// Each file, and each regular file directly inside each directory (in name
// order, for a reproducible log), is passed once to LLVMFuzzerTestOneInput. A
// broken property aborts inside the target; this driver fails on its own when a
// path cannot be read or when no input was found at all, so an empty or missing
// corpus is an error, never a silent pass. With --max-refusals=N it also fails
// when the target turned away more than N inputs as a known limitation (a
// ceiling measured on the committed corpus), so a refusal cannot pass quietly.

#include <algorithm>
#include <charconv>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include "fuzz_support.hpp"

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
  // No floating-point traps, unlike the test main (tests/support/catch_main.cpp),
  // and as under libFuzzer: the fuzzers feed coordinates up to the top of the
  // double range, where CGAL's interval filters overflow, and subtract infinities,
  // by design before they fall back to exact arithmetic (regressions:
  // cube-ply-huge-coordinates-pinch.bin stopped inside CGAL's orientation). A NaN
  // the library makes reaches the targets' properties, which compare it (NaN fails
  // every comparison) or decide on exact values.
  int first = 1;
  std::optional<std::size_t> max_refusals;
  constexpr std::string_view flag = "--max-refusals=";
  if (argc > 1 && std::string_view(argv[1]).substr(0, flag.size()) == flag) {
    const std::string_view value = std::string_view(argv[1]).substr(flag.size());
    std::size_t n = 0;
    const auto [end, error] = std::from_chars(value.data(), value.data() + value.size(), n);
    if (error != std::errc() || end != value.data() + value.size()) {
      std::fprintf(stderr, "replay: bad %s\n", argv[1]);
      return 2;
    }
    max_refusals = n;
    first = 2;
  }
  if (argc <= first) {
    std::fprintf(stderr, "usage: %s [--max-refusals=N] <file or directory>...\n", argv[0]);
    return 2;
  }
  std::size_t replayed = 0;
  for (int a = first; a < argc; ++a) {
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
  const std::size_t refused = shatter::fuzz::known_limitation_refusals;
  std::printf("replayed %zu inputs, %zu turned away as a known limitation\n", replayed, refused);
  if (max_refusals && refused > *max_refusals) {
    std::fprintf(stderr, "replay: %zu refusals, above the ceiling of %zu\n", refused, *max_refusals);
    return 1;
  }
  return 0;
}
