#pragma once
// Exact tests on rounded positions (doubles), against rational lengths: the
// questions snap rounding's repairs ask of a piece rounded to doubles
// (round_solid, shatter/triangulate/solid_mesh.hpp): which vertices share a
// pixel, which edges pass within a pixel of a vertex, where a vertex lies along
// an edge, and which way a face's loops turn once vertices merged. Every answer
// is exact, on GMP rationals over the doubles' exact values; a floating-point
// filter decides first where a function says so.
//
// Not installed (kernel/internal/): the lengths are rationals (a rounding move
// times a power of two), and no installed header names a GMP type.

#include <span>
#include <vector>

#include <gmpxx.h>

#include "shatter/kernel/implicit.hpp"
#include "shatter/kernel/vec.hpp"

namespace shatter {

/// Whether two coordinates lie within a length of each other: the pixel of
/// snap rounding, one axis at a time (round_solid's snap_clusters asks it per
/// axis, so that an L-infinity pixel is three calls).
class CoordinateReach {
 public:
  /// Preconditions: reach >= 0.
  explicit CoordinateReach(const mpq_class& reach);

  /// |a - b| <= reach, exactly. Decided in doubles when the rounded difference
  /// lies clearly apart from the reach rounded to a double (a relative 2^-40
  /// either way: the subtraction and the reach's conversion each err by less
  /// than 2^-52 relative, and below the normal range both are exact multiples
  /// of 2^-1074), else on rationals.
  /// Preconditions: finite inputs. Guarantees: exact. Failure: none.
  bool within(double a, double b) const;

 private:
  mpq_class reach_;
  double approximate_reach_;
};

/// Whether a point lies within a Euclidean distance of the open segment a-b:
/// within `reach` of the line through a and b, its orthogonal projection onto
/// the line strictly between a and b (snap rounding's hot pixel for an edge
/// passing by a vertex: the edge is routed through it).
class SegmentReach {
 public:
  /// Preconditions: reach >= 0.
  explicit SegmentReach(const mpq_class& reach);

  /// Whether p lies within reach of the line through a and b (|(b - a) x
  /// (p - a)|^2 <= reach^2 |b - a|^2) and projects strictly between a and b
  /// ((p - a).(b - a) > 0 and (p - b).(a - b) > 0), on rationals. False when a == b.
  /// Before that, a floating-point pre-test with an error bound rejects a point
  /// whose distance, less the bound, exceeds the reach by a factor 1.5.
  /// Preconditions: finite inputs. Guarantees: exact, whatever the scale of the
  /// coordinates beside the reach (a reach below an ulp of the coordinates
  /// included). Failure: none.
  bool within(const Vec3& a, const Vec3& b, const Vec3& p) const;

 private:
  mpq_class reach_;
  double approximate_reach_;
  bool reach_is_zero_;
};

/// Whether p's orthogonal projection onto the line through a and b falls
/// strictly between them: (p - a).(b - a) > 0 and (p - b).(a - b) > 0.
/// Preconditions: finite inputs. Guarantees: exact (rationals, no filter: its
/// callers ask it of the few corners a cheaper test left). False when a == b.
/// Failure: none.
bool projects_strictly_inside_segment(const Vec3& a, const Vec3& b, const Vec3& p);

/// Order along the direction from `from` to `to`: the sign of (p - q).(to - from),
/// negative when p comes first, zero when both project onto one point of the line.
/// Preconditions: finite inputs. Guarantees: exact (rationals). Failure: none.
Sign compare_along_direction(const Vec3& from, const Vec3& to, const Vec3& p, const Vec3& q);

/// Which of p and q lies nearer to `origin`: the sign of |p - origin|^2 -
/// |q - origin|^2, negative when p is nearer, zero at equal distances.
/// Preconditions: finite inputs. Guarantees: exact (rationals). Failure: none.
Sign compare_distance_to(const Vec3& origin, const Vec3& p, const Vec3& q);

/// Which way loops of positions turn in a plane's projection: the sign of twice
/// their signed area (the sum over their edges p -> q of p_u q_v - q_u p_v, u
/// and v the axes `projection` keeps), negated when the projection is flipped,
/// so positive means counter-clockwise seen from the front of the plane the
/// projection belongs to. The loops are a 2-chain: holes count negatively, edges
/// run both ways cancel. `loops`: indices into `positions`, each loop closing
/// from its last corner to its first.
/// Preconditions: indices in range; finite positions. Guarantees: exact
/// (rationals). Failure: none; zero for no loops.
Sign loops_orientation(std::span<const Vec3> positions, std::span<const std::vector<VertexIndex>> loops,
                       Projection projection);

}  // namespace shatter
