#pragma once
// Prefaulting memory a caller is about to fill. On these virtual machines a
// page faulted in on first touch costs about twice what populating it in one
// call does (ByteBlocks, packed_shapes.cpp, and the builder's node blocks
// measured it; they map with MAP_POPULATE). For an array already allocated
// (a std::vector's reserved capacity) madvise(MADV_POPULATE_WRITE) does the
// same: the page tables are filled, no byte is changed. Not installed.

#include <sys/mman.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>

namespace shatter::detail {

/// Populates the whole pages of [begin, begin + bytes) for writing, in one
/// call (Linux 5.14 and later); a page only partly inside is left to fault in
/// as usual, so nothing outside the range is touched. Where the call is not
/// known or is refused, nothing happens: the pages fault in as they are
/// written. Precondition: the range lies in memory the caller owns.
inline void populate_for_writing(void* begin, std::size_t bytes) {
#ifdef MADV_POPULATE_WRITE
  constexpr std::uintptr_t page = 4096;
  const auto start = reinterpret_cast<std::uintptr_t>(begin);
  const std::uintptr_t first = (start + page - 1) & ~(page - 1), last = (start + bytes) & ~(page - 1);
  if (last > first) ::madvise(reinterpret_cast<void*>(first), last - first, MADV_POPULATE_WRITE);
#else
  (void)begin;
  (void)bytes;
#endif
}

/// Keeps about `ahead` bytes of a vector's reserved room past its size
/// populated as it fills, a chunk at a time: call ensure() after appending.
/// Never past the capacity (the vector must not reallocate meanwhile).
template <class Vector>
class PopulatedAhead {
 public:
  PopulatedAhead(Vector& vector, std::size_t ahead) : vector_(vector), chunk_(std::max<std::size_t>(1, ahead / sizeof(typename Vector::value_type))) {}
  void ensure() {
    if (vector_.size() + chunk_ / 2 <= populated_) return;
    const std::size_t from = std::max(populated_, vector_.size());
    const std::size_t to = std::min(vector_.capacity(), vector_.size() + chunk_);
    if (to > from) {
      populate_for_writing(reinterpret_cast<std::byte*>(vector_.data()) + from * sizeof(typename Vector::value_type),
                           (to - from) * sizeof(typename Vector::value_type));
    }
    populated_ = std::max(populated_, to);
  }

 private:
  Vector& vector_;
  std::size_t chunk_;
  std::size_t populated_ = 0;  // elements from the start known populated
};

}  // namespace shatter::detail
