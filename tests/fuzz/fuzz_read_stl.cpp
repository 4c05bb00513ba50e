// Fuzz target: the STL reader. Property: any accepted input round-trips through
// the STL writer (fuzz_support.hpp, check_read_round_trip).

#include "fuzz_support.hpp"

/// libFuzzer's entry point: one input, read as STL.
extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  shatter::fuzz::check_read_round_trip(shatter::fuzz::as_bytes(data, size), shatter::MeshFormat::stl);
  return 0;
}
