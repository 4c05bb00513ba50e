#pragma once
// A flat open-addressing hash map from 64-bit keys (an edge's two vertex indices)
// to 32-bit values (a vertex or triangle index). The slicer, the cap linker and
// solid separation each do O(triangles) look-ups per cut; node-based maps
// (std::unordered_map) spend most of a small cut in the allocator, this spends none
// after the first reserve.

#include <algorithm>
#include <bit>
#include <cstdint>
#include <vector>

#include "shatter/kernel/mesh.hpp"

namespace shatter {

/// The key of a directed edge u -> v.
inline std::uint64_t directed_edge_key(VertexIndex u, VertexIndex v) {
  return (std::uint64_t{u} << 32) | v;
}
/// The key of an undirected edge: the same for (u, v) and (v, u).
inline std::uint64_t undirected_edge_key(VertexIndex u, VertexIndex v) {
  return u < v ? directed_edge_key(u, v) : directed_edge_key(v, u);
}

class IndexMap {
 public:
  static constexpr std::uint32_t absent = 0xffffffffu;

  /// An empty map sized for about `expected` keys without rehashing.
  explicit IndexMap(std::size_t expected = 0) { reset(expected); }

  /// Empties the map and sizes it for `expected` keys, keeping its storage.
  void reset(std::size_t expected) {
    const std::size_t capacity = std::bit_ceil(std::max<std::size_t>(16, expected * 2));
    slots_.assign(capacity, Slot{empty_key, absent});
    shift_ = 64 - std::countr_zero(capacity);
    size_ = 0;
  }

  /// The value stored for key, or `absent`.
  std::uint32_t find(std::uint64_t key) const {
    for (std::size_t i = index_of(key);; i = (i + 1) & mask()) {
      if (slots_[i].key == key) return slots_[i].value;
      if (slots_[i].key == empty_key) return absent;
    }
  }

  /// Stores value for key if the key is new; returns the value now stored (the
  /// old one when the key was present). Precondition: key != ~0.
  std::uint32_t insert(std::uint64_t key, std::uint32_t value) {
    if ((size_ + 1) * 2 > slots_.size()) grow();
    for (std::size_t i = index_of(key);; i = (i + 1) & mask()) {
      if (slots_[i].key == key) return slots_[i].value;
      if (slots_[i].key == empty_key) {
        slots_[i] = Slot{key, value};
        ++size_;
        return value;
      }
    }
  }

  std::size_t size() const { return size_; }

 private:
  static constexpr std::uint64_t empty_key = ~std::uint64_t{0};
  struct Slot {
    std::uint64_t key;
    std::uint32_t value;
  };

  std::size_t mask() const { return slots_.size() - 1; }
  std::size_t index_of(std::uint64_t key) const {
    // Fibonacci hashing spreads the two packed 32-bit halves over the table.
    return static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> shift_);
  }
  void grow() {
    std::vector<Slot> old = std::move(slots_);
    reset(old.size());
    for (const Slot& slot : old) {
      if (slot.key != empty_key) insert(slot.key, slot.value);
    }
  }

  std::vector<Slot> slots_;
  std::size_t size_ = 0;
  int shift_ = 60;
};

}  // namespace shatter
