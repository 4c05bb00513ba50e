// Fuzz target: the PLY reader. Property: any accepted input round-trips through
// the PLY writer (fuzz_support.hpp, check_read_round_trip).

#include "fuzz_support.hpp"

/// libFuzzer's entry point: one input, read as PLY.
extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  shatter::fuzz::check_read_round_trip(shatter::fuzz::as_bytes(data, size), shatter::MeshFormat::ply);
  return 0;
}
