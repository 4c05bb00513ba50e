#pragma once
// CGAL PMP's rule for whether two triangles of one mesh intersect, decided by
// CGAL's exact predicates alone: the oracle the tests judge shatter's exact
// self-intersection finder (test_self_intersections) and the pieces of the
// exact arrangement (test_arrangement) against, apart from the kernel's code.
// Triangles sharing one vertex intersect if either meets the other's opposite
// edge; sharing an edge, if the two fold onto each other (coplanar, on one
// side); sharing all three corners, always; sharing none, if they meet at all.

#include <CGAL/intersections.h>

#include "shatter/kernel/mesh.hpp"

namespace shatter::test {

/// Whether triangles `a` and `b` intersect beyond what they share by index,
/// with `point(v)` the Kernel's point of vertex v (any CGAL kernel; its
/// predicates decide, so the answer is exact when they are).
template <class Kernel, class PointOf>
bool pmp_pair_intersects(const Triangle& a, const Triangle& b, const PointOf& point) {
  int shared = 0, shared_a = -1, shared_b = -1;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      if (a[i] != b[j]) continue;
      ++shared;
      if (shared_a < 0) shared_a = i, shared_b = j;
    }
  }
  if (shared >= 3) return true;
  if (shared == 2) {
    int ia = 0, ib = 0;
    for (int i = 0; i < 3; ++i) {
      if (a[i] != b[0] && a[i] != b[1] && a[i] != b[2]) ia = i;
      if (b[i] != a[0] && b[i] != a[1] && b[i] != a[2]) ib = i;
    }
    const typename Kernel::Point_3 u = point(a[(ia + 1) % 3]), v = point(a[(ia + 2) % 3]), x = point(a[ia]),
                                   y = point(b[ib]);
    return CGAL::coplanar(u, v, x, y) && CGAL::coplanar_orientation(u, v, x, y) == CGAL::POSITIVE;
  }
  const typename Kernel::Triangle_3 ta(point(a[0]), point(a[1]), point(a[2])), tb(point(b[0]), point(b[1]), point(b[2]));
  if (shared == 1) {
    const typename Kernel::Segment_3 sa(point(a[(shared_a + 1) % 3]), point(a[(shared_a + 2) % 3]));
    const typename Kernel::Segment_3 sb(point(b[(shared_b + 1) % 3]), point(b[(shared_b + 2) % 3]));
    return CGAL::do_intersect(ta, sb) || CGAL::do_intersect(tb, sa);
  }
  return CGAL::do_intersect(ta, tb);
}

}  // namespace shatter::test
