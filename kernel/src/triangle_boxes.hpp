#pragma once
// Triangles' bounding boxes for CGAL's box intersection (kernel-internal): the
// self-intersection test's long triangles and validate_mesh_against's new
// triangles are both found through them.

#include <CGAL/box_intersection_d.h>

#include <algorithm>
#include <cstddef>
#include <span>

#include "shatter/kernel/mesh.hpp"

namespace shatter::detail {

using TriangleBox = CGAL::Box_intersection_d::Box_with_handle_d<double, 3, std::size_t, CGAL::Box_intersection_d::ID_EXPLICIT>;

/// The box of triangle `tri` over `positions`, carrying `handle` (its index).
inline TriangleBox box_of(std::span<const Vec3> positions, const Triangle& tri, std::size_t handle) {
  double lo[3], hi[3];
  for (int axis = 0; axis < 3; ++axis) {
    lo[axis] = hi[axis] = positions[tri[0]][axis];
    for (int c = 1; c < 3; ++c) {
      lo[axis] = std::min(lo[axis], positions[tri[c]][axis]);
      hi[axis] = std::max(hi[axis], positions[tri[c]][axis]);
    }
  }
  return TriangleBox(CGAL::Bbox_3(lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]), handle);
}

}  // namespace shatter::detail
