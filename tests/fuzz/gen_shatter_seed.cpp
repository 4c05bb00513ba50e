// Writes a .shatter seed for the fuzz_read_shatter corpus: the unit cube cut into
// N fragments by the library itself, so the seed is a file encode_shatter wrote
// and the fuzzer starts from every section filled in.
//
//   gen_shatter_seed <out.shatter> [fragments (default 4)]
//
// It writes the current format (version 3). The committed seeds of version 1
// (cube-4-fragments.shatter, fast kernel; cube-2-fragments-exact.shatter, exact
// kernel; and the bad-* and optional-section-* files derived from them) were
// written by version 1's encoder, and v2-cube-2-fragments-fast.shatter by the
// retired fast kernel; they are kept as they are: they keep version 1 and the
// retired kernels' trees reading fuzzed, and v2-cube-4-fragments-plane.shatter,
// the plane kernel's version 2 file, keeps version 2's exact representation
// fuzzed. The one seed this writes is
//   gen_shatter_seed .../v3-cube-4-fragments-plane.shatter 4

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

#include "shatter/generators/solids.hpp"
#include "shatter/meshtree/build.hpp"
#include "shatter/formats/file.hpp"

/// Builds the cube's tree with a fixed seed and writes its file; exit 0 on success.
int main(int argc, char** argv) {
  if (argc < 2 || argc > 3) {
    std::fprintf(stderr, "usage: %s <out.shatter> [fragments]\n", argv[0]);
    return 2;
  }
  try {
    shatter::TreeRecipe recipe;
    recipe.fragments = argc > 2 ? static_cast<std::uint32_t>(std::stoul(argv[2])) : 4;
    recipe.seed = 7;
    shatter::write_shatter_file(argv[1], shatter::build_mesh_tree(shatter::test::unit_cube(), recipe, {.threads = 1}));
  } catch (const std::exception& error) {
    std::fprintf(stderr, "error: %s\n", error.what());
    return 1;
  }
  return 0;
}
