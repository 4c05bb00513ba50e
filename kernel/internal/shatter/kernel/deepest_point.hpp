#pragma once
// A candidate centre for the star-shaped certificate (certify.hpp): the point
// deepest inside every triangle's inner half-space, where the largest ball in
// the mesh's kernel is centred, found by a linear program in doubles.
//
// Only a candidate: nothing is decided on it. certify_piece tests the point it
// gives with the exact certificate (every triangle faces away from it, the
// triangles around every vertex wind once around it) and declines when that
// fails, so an error of the program's arithmetic costs time, never validity.
// Most pieces a cut of a curved mesh leaves are star-shaped around some point
// that is neither their vertex average nor their volume centroid: with this
// point tried too, 100 of the 134 pieces those two declined in fandisk
// subdivided once -> 256 are certified (shatter-bench-plane's counts).
//
// Not installed (kernel/internal/): its users are certify.cpp and the tests.

#include <array>
#include <optional>
#include <span>

#include "shatter/kernel/mesh.hpp"

namespace shatter::kernel_detail {

/// A half-space a·x <= b of R^d, d <= 4 (coefficients past d are not read).
struct HalfSpace {
  std::array<double, 4> a{};
  double b = 0;
};

/// Maximizes c·x over the x of R^d (1 <= d <= 4) with |x_j| <= box for every j
/// and a·x <= b + slack for every half-space of `constraints`: Seidel's
/// randomized incremental algorithm (R. Seidel, "Small-dimensional linear
/// programming and convex hulls made easy", Discrete Comput. Geom. 6, 1991),
/// whose expected time is O(d! n) for n constraints in random order (the
/// caller shuffles them; the order never changes which optimum value is
/// found, only the time). In doubles: `slack` is how far a constraint may be
/// passed before it counts as violated, so the answer is approximate.
/// Returns an optimal x, or nullopt when the constraints (so relaxed) leave no
/// point in the box. Preconditions: box > 0, slack >= 0, finite coefficients.
/// Never throws but for memory.
std::optional<std::array<double, 4>> maximize_in_box(int d, std::span<const HalfSpace> constraints,
                                                    const std::array<double, 4>& c, double box, double slack);

/// The point of the mesh's kernel (the points strictly behind every triangle's
/// plane, the region a star-shaped mesh is star-shaped around) farthest from
/// those planes, computed in doubles by maximize_in_box over (x, y, z, margin),
/// or nullopt when its margin is not clearly positive (an empty or flat kernel,
/// to the program's precision) or the mesh is empty, has a zero-area triangle
/// in doubles, non-finite coordinates or out-of-range indices.
/// Guarantees nothing exact: the caller tests the point (see the file comment).
/// O(T) expected; the constraints are shuffled with a fixed seed, so the same
/// mesh gives the same point.
std::optional<Vec3> deepest_inner_point(const Mesh& mesh);

}  // namespace shatter::kernel_detail
