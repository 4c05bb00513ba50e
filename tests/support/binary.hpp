#pragma once
// Bytes of binary mesh files written by hand in tests (binary PLY and STL, in
// either byte order), so a reader can be fed exactly the damage a test wants.

#include <algorithm>
#include <array>
#include <bit>
#include <cstring>
#include <string>

namespace shatter::test {

/// Appends `value`'s bytes to `out`, big-endian when `big_endian`, else
/// little-endian, whatever the machine's own order.
template <class T>
void append_binary(std::string& out, T value, bool big_endian) {
  std::array<char, sizeof(T)> raw;
  std::memcpy(raw.data(), &value, sizeof(T));
  if (big_endian != (std::endian::native == std::endian::big)) std::reverse(raw.begin(), raw.end());
  out.append(raw.data(), raw.size());
}

}  // namespace shatter::test
