#pragma once
// Whether a point lies inside a closed solid mesh, decided exactly.

#include <memory>

#include "shatter/kernel/mesh.hpp"
#include "shatter/kernel/vec.hpp"

namespace shatter {

/// Point-in-solid queries against one mesh: CGAL's Side_of_triangle_mesh (ray
/// casting on an AABB tree; with exact predicates on the double input its
/// answer is exact, and a ray that meets an edge or a vertex is cast again in
/// another direction, drawn from a fixed seed).
class PointInSolid {
 public:
  /// Precondition: `mesh` is a closed, oriented solid (validate_mesh); it is
  /// copied, so it need not outlive this object. O(T log T).
  explicit PointInSolid(const Mesh& mesh);
  ~PointInSolid();
  PointInSolid(const PointInSolid&) = delete;
  PointInSolid& operator=(const PointInSolid&) = delete;

  /// True when `point` lies strictly inside the solid (not on its surface).
  /// Exact; deterministic. Not safe to call from several threads at once.
  bool strictly_inside(const Vec3& point) const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace shatter
