#pragma once
// Union-find over 0..n-1 (leaves, or a cluster's local indices): path halving,
// and the smaller index always becomes the representative, so the sets and their
// representatives never depend on the order of the joins.

#include <cstdint>
#include <numeric>
#include <vector>

namespace shatter::runtime {

class LeafSets {
 public:
  explicit LeafSets(std::size_t count) : parent_(count) { std::iota(parent_.begin(), parent_.end(), std::uint32_t{0}); }
  std::uint32_t find(std::uint32_t i) {
    while (parent_[i] != i) {
      parent_[i] = parent_[parent_[i]];
      i = parent_[i];
    }
    return i;
  }
  void join(std::uint32_t a, std::uint32_t b) {
    a = find(a);
    b = find(b);
    if (a < b) parent_[b] = a;
    if (b < a) parent_[a] = b;
  }

 private:
  std::vector<std::uint32_t> parent_;
};

}  // namespace shatter::runtime
