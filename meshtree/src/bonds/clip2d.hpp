#pragma once
// Rounded 2D polygon clipping, shared by the bond finders: it measures overlaps
// (area and centroid) that exact predicates have already decided.

#include <algorithm>
#include <span>
#include <vector>

#include "shatter/kernel/vec.hpp"

namespace shatter::detail {

inline double cross(Vec2 origin, Vec2 a, Vec2 b) {
  return (a.x - origin.x) * (b.y - origin.y) - (a.y - origin.y) * (b.x - origin.x);
}

// A convex polygon clipped by another, with area and centroid: Sutherland-Hodgman
// in doubles, a rounded construction that only yields numbers, never a decision.
// Coordinates are taken relative to a reference point near the cut, so that far
// from the origin the products stay small. Buffers are kept between calls.
class Clipper {
 public:
  struct Measure {
    double area = 0;          // >= 0: a polygon rounding to negative area counts 0
    double area_times_u = 0;  // area-weighted centroid numerators, relative to the reference
    double area_times_v = 0;
  };

  Measure overlap(std::span<const Vec2> subject, std::span<const Vec2> clip, Vec2 reference) {
    const auto local = [&](Vec2 p) { return Vec2{p.x - reference.x, p.y - reference.y}; };
    polygon_.clear();
    for (const Vec2 corner : subject) polygon_.push_back(local(corner));
    for (std::size_t e = 0; e < clip.size() && !polygon_.empty(); ++e) {
      clip_left_of(local(clip[e]), local(clip[(e + 1) % clip.size()]));
    }
    Measure measure;
    double twice_area = 0, sum_u = 0, sum_v = 0;
    for (std::size_t i = 1; i + 1 < polygon_.size(); ++i) {
      const Vec2 o = polygon_[0], a = polygon_[i], b = polygon_[i + 1];
      const double twice = cross(o, a, b);
      twice_area += twice;
      sum_u += twice * (o.x + a.x + b.x);
      sum_v += twice * (o.y + a.y + b.y);
    }
    if (twice_area > 0) {
      measure.area = 0.5 * twice_area;
      // centroid = sum(twice * corner sum) / (3 * twice_area), times the area.
      measure.area_times_u = sum_u / 6.0;
      measure.area_times_v = sum_v / 6.0;
    }
    return measure;
  }

 private:
  // Each corner's side is computed once (it was twice: as an edge's start and
  // as the previous edge's end), with the same arithmetic, so the same bits; a
  // polygon wholly on one side is kept or emptied without a copy. The clip was
  // a sixteenth of `fracture` cube -> 65,536.
  void clip_left_of(Vec2 p, Vec2 q) {
    const std::size_t n = polygon_.size();
    sides_.resize(n);
    bool all_inside = true, all_outside = true;
    for (std::size_t i = 0; i < n; ++i) {
      sides_[i] = cross(p, q, polygon_[i]);
      (sides_[i] >= 0 ? all_outside : all_inside) = false;
    }
    if (all_inside) return;
    if (all_outside) {
      polygon_.clear();
      return;
    }
    clipped_.clear();
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t j = i + 1 == n ? 0 : i + 1;
      const Vec2 s = polygon_[i], e = polygon_[j];
      const double side_s = sides_[i], side_e = sides_[j];
      const bool s_inside = side_s >= 0, e_inside = side_e >= 0;
      if (s_inside) clipped_.push_back(s);
      if (s_inside != e_inside) {
        const double t = std::clamp(side_s / (side_s - side_e), 0.0, 1.0);
        clipped_.push_back(Vec2{s.x + t * (e.x - s.x), s.y + t * (e.y - s.y)});
      }
    }
    polygon_.swap(clipped_);
  }

  std::vector<Vec2> polygon_, clipped_;
  std::vector<double> sides_;  // clip_left_of's, per corner
};

}  // namespace shatter::detail
