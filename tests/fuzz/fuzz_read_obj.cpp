// Fuzz target: the OBJ reader. Property: any accepted input round-trips through
// the OBJ writer (fuzz_support.hpp, check_read_round_trip).

#include "fuzz_support.hpp"

/// libFuzzer's entry point: one input, read as OBJ.
extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  shatter::fuzz::check_read_round_trip(shatter::fuzz::as_bytes(data, size), shatter::MeshFormat::obj);
  return 0;
}
