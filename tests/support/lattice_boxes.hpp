#pragma once
// Random boxes on integer corners in [0, 4]^3 for the arrangement's union tests:
// their union's exact volume is the count of the unit voxels they cover.

#include <array>
#include <set>

#include "shatter/generators/random.hpp"
#include "shatter/generators/solids.hpp"

namespace shatter::test {

/// A box drawn on integer corners in [0, 4]^3, its corners and its surface (tessellated
/// once or twice per unit, drawn too).
struct LatticeBox {
  Mesh mesh;
  Vec3 lo, hi;
};

/// Draws one box from `random` (corners, then tessellation, in that order, so callers'
/// later draws stay where they were) and adds the unit voxels it covers to `voxels`.
inline LatticeBox random_lattice_box(Random& random, std::set<std::array<int, 3>>& voxels) {
  std::array<int, 3> lo{}, hi{};
  for (int c = 0; c < 3; ++c) {
    lo[c] = static_cast<int>(random.index(4));
    hi[c] = lo[c] + 1 + static_cast<int>(random.index(static_cast<std::size_t>(4 - lo[c])));
  }
  const Vec3 l{double(lo[0]), double(lo[1]), double(lo[2])}, h{double(hi[0]), double(hi[1]), double(hi[2])};
  LatticeBox box{grid_box(l, h, 1 + static_cast<int>(random.index(2))), l, h};
  for (int x = lo[0]; x < hi[0]; ++x)
    for (int y = lo[1]; y < hi[1]; ++y)
      for (int z = lo[2]; z < hi[2]; ++z) voxels.insert({x, y, z});
  return box;
}

}  // namespace shatter::test
