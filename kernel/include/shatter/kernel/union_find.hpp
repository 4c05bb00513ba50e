#pragma once
// Union-find over the indices 0..n-1 (triangles, faces, leaves, ...): path
// halving, and the smaller index always becomes the representative, so the sets
// and their representatives never depend on the order of the unions. Defined in
// the header: find and unite sit in the innermost loops of their callers.

#include <cstdint>
#include <numeric>
#include <vector>

namespace shatter {

class UnionFind {
 public:
  UnionFind() = default;
  /// n singletons.
  explicit UnionFind(std::size_t n) { reset(n); }
  /// Back to n singletons, keeping the storage (for a reused, e.g. thread_local, instance).
  void reset(std::size_t n) {
    parent_.resize(n);
    std::iota(parent_.begin(), parent_.end(), std::uint32_t{0});
  }
  /// The representative of x's set: its smallest index. Precondition: x < n.
  std::uint32_t find(std::uint32_t x) {
    while (parent_[x] != x) {
      parent_[x] = parent_[parent_[x]];
      x = parent_[x];
    }
    return x;
  }
  /// Joins the sets of a and b. Precondition: a, b < n. Returns true when they
  /// were two sets (so a caller can count the sets left without a second find).
  bool unite(std::uint32_t a, std::uint32_t b) {
    a = find(a);
    b = find(b);
    if (a < b) parent_[b] = a;
    else if (b < a) parent_[a] = b;
    return a != b;
  }

 private:
  std::vector<std::uint32_t> parent_;
};

}  // namespace shatter
