// Writes a .shatter seed for the fuzz_read_shatter corpus: the unit cube cut into
// N fragments by the library itself, so the seed is a file encode_shatter wrote
// and the fuzzer starts from every section filled in.
//
//   gen_shatter_seed <out.shatter> [fragments (default 4)] [fast|exact|plane (default plane)]
//
// It writes the current format (version 2). The committed seeds of version 1
// (cube-4-fragments.shatter, fast; cube-2-fragments-exact.shatter, exact; and the
// bad-* and optional-section-* files derived from them) were written by version
// 1's encoder and are kept as they are: they are what keeps version 1 reading
// fuzzed. The version 2 seeds are
//   gen_shatter_seed .../v2-cube-4-fragments-plane.shatter 4 plane
//   gen_shatter_seed .../v2-cube-2-fragments-fast.shatter 2 fast

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

#include "shatter/generators/solids.hpp"
#include "shatter/meshtree/build.hpp"
#include "shatter/meshtree/file.hpp"

/// Builds the cube's tree with a fixed seed and writes its file; exit 0 on success.
int main(int argc, char** argv) {
  if (argc < 2 || argc > 4) {
    std::fprintf(stderr, "usage: %s <out.shatter> [fragments] [fast|exact|plane]\n", argv[0]);
    return 2;
  }
  try {
    shatter::BuildOptions options;
    options.fragments = argc > 2 ? static_cast<std::uint32_t>(std::stoul(argv[2])) : 4;
    const std::string kernel = argc > 3 ? argv[3] : "plane";
    if (kernel == "fast") {
      options.kernel = shatter::KernelKind::fast;
    } else if (kernel == "exact") {
      options.kernel = shatter::KernelKind::exact;
    } else if (kernel == "plane") {
      options.kernel = shatter::KernelKind::plane;
    } else {
      std::fprintf(stderr, "error: unknown kernel '%s' (fast, exact or plane)\n", kernel.c_str());
      return 2;
    }
    options.seed = 7;
    options.threads = 1;
    shatter::write_shatter_file(argv[1], shatter::build_mesh_tree(shatter::test::unit_cube(), options));
  } catch (const std::exception& error) {
    std::fprintf(stderr, "error: %s\n", error.what());
    return 1;
  }
  return 0;
}
