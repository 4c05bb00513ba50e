// Writes a .shatter seed for the fuzz_read_shatter corpus: the unit cube cut into
// N fragments by the library itself, so the seed is a file encode_shatter wrote
// and the fuzzer starts from every section filled in.
//
//   gen_shatter_seed <out.shatter> [fragments (default 4)] [fast|exact (default fast)]

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

#include "shatter/meshtree/build.hpp"
#include "shatter/meshtree/file.hpp"
#include "support/generators.hpp"

/// Builds the cube's tree with a fixed seed and writes its file; exit 0 on success.
int main(int argc, char** argv) {
  if (argc < 2 || argc > 4) {
    std::fprintf(stderr, "usage: %s <out.shatter> [fragments] [fast|exact]\n", argv[0]);
    return 2;
  }
  try {
    shatter::BuildOptions options;
    options.fragments = argc > 2 ? static_cast<std::uint32_t>(std::stoul(argv[2])) : 4;
    options.kernel = argc > 3 && std::string(argv[3]) == "exact" ? shatter::KernelKind::exact : shatter::KernelKind::fast;
    options.seed = 7;
    options.threads = 1;
    shatter::write_shatter_file(argv[1], shatter::build_mesh_tree(shatter::test::unit_cube(), options));
  } catch (const std::exception& error) {
    std::fprintf(stderr, "error: %s\n", error.what());
    return 1;
  }
  return 0;
}
