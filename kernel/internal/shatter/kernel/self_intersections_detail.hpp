#pragma once
// The self-intersection finder with its block size as a parameter (not
// installed, kernel/internal/): the tests run its parallel path, which the
// public finder takes only on meshes of more than one block, on small meshes.

#include <cstddef>
#include <span>
#include <vector>

#include "shatter/kernel/mesh.hpp"
#include "shatter/kernel/self_intersections.hpp"

namespace shatter::detail {

/// self_intersecting_pairs, its work split into blocks of `block` triangles (the
/// public function uses 16,384): on more than one block and more than one
/// thread of the enclosing arena, the parallel path. Same preconditions and
/// result as self_intersecting_pairs, whatever the block size and thread count.
std::vector<TrianglePair> self_intersecting_pairs_in_blocks(std::span<const Vec3> positions,
                                                            std::span<const Triangle> triangles, std::size_t block);

}  // namespace shatter::detail
