#include "shatter/slicer/split.hpp"

#include <algorithm>
#include <string>
#include <utility>

#include "shatter/kernel/error.hpp"
#include "shatter/kernel/face_loops.hpp"

namespace shatter {
namespace {

bool both_zero(Sign a, Sign b) { return a == Sign::zero && b == Sign::zero; }

// A corner of a face's loop after the crossing vertices are inserted: the edge
// from it to the next augmented corner lies on `line`.
class Splitter {
 public:
  Splitter(const PlaneSet& set, const Solid& solid, PlaneRef cut, SplitSolid& out, SplitSides sides)
      : set_(set), solid_(solid), cut_(cut), out_(out), sides_(sides) {}

  void run() {
    const std::size_t n = solid_.defs.size();
    out_.defs.assign(solid_.defs.begin(), solid_.defs.end());
    out_.approx.assign(solid_.approx.begin(), solid_.approx.end());
    out_.sides.resize(n);
    bool any_below = false, any_above = false, any_on = false;
    for (std::size_t v = 0; v < n; ++v) {
      const Sign s = side(set_, cut_, out_.defs[v], out_.approx[v]);
      out_.sides[v] = s;
      any_below |= s == Sign::negative;
      any_above |= s == Sign::positive;
      any_on |= s == Sign::zero;
    }
    out_.below.clear();
    out_.above.clear();
    out_.border.clear();
    out_.plane_misses = !(any_below && any_above);
    out_.all_below = !any_above;
    out_.other_side_partial = sides_ != SplitSides::both && !any_on;
    // Keeping the below side with no vertex on the plane, the above side is not
    // made at all: its only use would be the border, and then every zero edge
    // of the below side is a new edge along the cut (both its ends are
    // crossings), which the above side runs the other way; so the border is the
    // below side's zero edges, in the order collect_border would list them.
    // Not for a kept above side: its border is listed in the below side's order.
    below_only_ = out_.other_side_partial && sides_ == SplitSides::below;
    if (out_.plane_misses) return;
    out_.new_vertex_of_edge.reset(solid_.corners.size() / 4 + 8);
    zero_edges_below_.clear();
    zero_edges_above_.clear();
    for (const SolidFace& face : solid_.faces) split_face(face);
    collect_border();
  }

 private:
  Sign sign_of(VertexIndex v) const { return out_.sides[v]; }

  // The vertex where the cut crosses the edge u-v of `face` (lying on `line`),
  // made once per undirected edge.
  VertexIndex crossing_vertex(VertexIndex u, VertexIndex v, const SolidFace& face, const EdgeLine& line) {
    const auto candidate = static_cast<VertexIndex>(out_.defs.size());
    const VertexIndex found = out_.new_vertex_of_edge.insert(undirected_edge_key(u, v), candidate);
    if (found != candidate) return found;
    const PointDef def = edge_crossing_def(face, line, cut_);
    out_.defs.push_back(def);
    out_.approx.push_back(approximate(set_, def));
    out_.sides.push_back(Sign::zero);
    return candidate;
  }

  // The face's loops with crossing vertices inserted: augmented_loops_ over the
  // corners augmented_, each corner on the line of its edge to the next, as in a
  // solid (a crossing splits an edge into two on the same line), so that they are
  // walked with loop_edges like the solid's own loops.
  void augment(const SolidFace& face) {
    augmented_.clear();
    augmented_loops_.clear();
    for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
      const auto first = static_cast<std::uint32_t>(augmented_.size());
      for (const CornerEdge& edge : loop_edges(solid_.corners, solid_.loops[l])) {
        augmented_.push_back({edge.from, edge.line});
        const Sign a = sign_of(edge.from), b = sign_of(edge.to);
        if ((a == Sign::negative && b == Sign::positive) || (a == Sign::positive && b == Sign::negative)) {
          augmented_.push_back({crossing_vertex(edge.from, edge.to, face, edge.line), edge.line});
        }
      }
      augmented_loops_.push_back({first, static_cast<std::uint32_t>(augmented_.size()) - first});
    }
  }

  // The line of a new edge along the cut, inside a part of `face`.
  EdgeLine cut_line() const {
    EdgeLine line;
    line.other = cut_;
    return line;
  }

  void split_face(const SolidFace& face) {
    bool any_below = false, any_above = false;
    for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
      const SolidLoop& loop = solid_.loops[l];
      for (std::uint32_t i = 0; i < loop.corner_count; ++i) {
        const Sign s = sign_of(solid_.corners[loop.first_corner + i].vertex);
        any_below |= s == Sign::negative;
        any_above |= s == Sign::positive;
      }
    }
    if (!any_below && !any_above) {
      // In the plane: the lid of the side its outward normal looks out of.
      Sign facing = compare_normals(set_, face.plane, cut_);
      if (face.reversed) facing = flip(facing);
      copy_face(face, facing == Sign::positive ? out_.below : out_.above, facing == Sign::positive);
    } else if (!any_below) {
      // No vertex on the plane: the face has no edge there, so no border edge.
      if (!(out_.other_side_partial && sides_ == SplitSides::below)) copy_face(face, out_.above, false);
    } else if (!any_above) {
      if (!(out_.other_side_partial && sides_ == SplitSides::above)) copy_face(face, out_.below, true);
    } else if (face.convex) {
      augment(face);
      emit_convex_part(face, Sign::negative, out_.below, true);
      if (!below_only_) emit_convex_part(face, Sign::positive, out_.above, false);
    } else {
      augment(face);
      split_general(face);
    }
  }

  void note_zero_edge(VertexIndex u, VertexIndex v, const SolidFace& face, const EdgeLine& line, bool below) {
    if (!both_zero(sign_of(u), sign_of(v))) return;
    // On the cap, the edge lies on the cut and on this face's plane.
    LoopEdge edge{u, v, line};
    edge.line.other = face.plane;
    (below ? zero_edges_below_ : zero_edges_above_).push_back(edge);
  }

  void copy_face(const SolidFace& face, FaceSet& side_faces, bool below) {
    SolidFace copy = face;
    copy.first_loop = static_cast<std::uint32_t>(side_faces.loops.size());
    for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
      const SolidLoop& loop = solid_.loops[l];
      side_faces.loops.push_back({static_cast<std::uint32_t>(side_faces.corners.size()), loop.corner_count});
      for (const CornerEdge& edge : loop_edges(solid_.corners, loop)) {
        side_faces.corners.push_back(solid_.corners[edge.corner]);
        note_zero_edge(edge.from, edge.to, face, edge.line, below);
      }
    }
    side_faces.faces.push_back(copy);
  }

  // A convex face's part on one side: its augmented corners of that side or on the
  // plane, in order, form one run; the one jump between non-consecutive corners is
  // the new edge along the cut.
  void emit_convex_part(const SolidFace& face, Sign keep, FaceSet& side_faces, bool below) {
    const SolidLoop& loop = augmented_loops_.front();  // a convex face has one loop
    std::uint32_t start = loop.first_corner;
    while (sign_of(augmented_[start].vertex) != keep) ++start;
    SolidFace part = face;
    part.first_loop = static_cast<std::uint32_t>(side_faces.loops.size());
    part.loop_count = 1;
    const auto first_corner = static_cast<std::uint32_t>(side_faces.corners.size());
    // Walk from `start`; emit kept corners. A kept corner's edge is its own when
    // the corner after it is kept too, else the new edge along the cut, which ends
    // at the next kept corner: each emitted corner's edge is closed when that
    // corner is known.
    VertexIndex previous = no_index;
    EdgeLine previous_line;
    for (const CornerEdge& edge : loop_edges(augmented_, loop, start)) {
      if (sign_of(edge.from) == flip(keep)) continue;
      if (previous != no_index) close_edge(face, side_faces, previous, edge.from, previous_line, below);
      side_faces.corners.push_back({edge.from, EdgeLine{}});
      previous = edge.from;
      previous_line = sign_of(edge.to) == flip(keep) ? cut_line() : edge.line;
    }
    close_edge(face, side_faces, previous, augmented_[start].vertex, previous_line, below);
    side_faces.loops.push_back({first_corner, static_cast<std::uint32_t>(side_faces.corners.size()) - first_corner});
    side_faces.faces.push_back(part);
  }

  // Sets the line of the last emitted corner (vertex `from`), whose successor in
  // the part is vertex `to`.
  void close_edge(const SolidFace& face, FaceSet& side_faces, VertexIndex from, VertexIndex to, const EdgeLine& line,
                  bool below) {
    side_faces.corners.back().line = line;
    note_zero_edge(from, to, face, line, below);
  }

  // --- faces that are not convex, or have holes -----------------------------------
  // The parts of the cut line inside the face are found by a sweep along the line:
  // shifting the line infinitesimally to one side, the face's boundary crosses it
  // exactly at the edges from a vertex on the line to a vertex strictly on that
  // side, so the parity of those edges met so far tells whether the face is there.
  // A gap between consecutive points on the line with the face on both sides is a
  // new edge of both parts.

  void split_general(const SolidFace& face) {
    zero_points_.clear();
    for (const SolidLoop& loop : augmented_loops_) {
      for (const CornerEdge& edge : loop_edges(augmented_, loop)) {
        const VertexIndex u = edge.from, v = edge.to;
        const Sign su = sign_of(u), sv = sign_of(v);
        if (su == Sign::zero && sv != Sign::zero) count_at(u, sv);
        if (sv == Sign::zero && su != Sign::zero) count_at(v, su);
        if (su == Sign::zero) touch(u);
        if (sv == Sign::zero) touch(v);
      }
    }
    // Order along d = n_out × n_cut; a reversed face's outward normal is -n.
    const bool reversed = face.reversed;
    std::sort(zero_points_.begin(), zero_points_.end(), [&](const ZeroPoint& a, const ZeroPoint& b) {
      Sign s = compare_along(set_, face.plane, cut_, out_.defs[a.vertex], out_.approx[a.vertex], out_.defs[b.vertex],
                             out_.approx[b.vertex]);
      if (reversed) s = flip(s);
      // Distinct vertices at one point: the copies a piece that meets itself
      // along a chord has there (cut_solid), taken together below.
      return s == Sign::zero ? a.vertex < b.vertex : s == Sign::positive;
    });
    below_edges_.clear();
    above_edges_.clear();
    // The face's own edges, each to the side it bounds.
    for (const SolidLoop& loop : augmented_loops_) {
      for (const CornerEdge& corner_edge : loop_edges(augmented_, loop)) {
        const VertexIndex u = corner_edge.from, v = corner_edge.to;
        const Sign su = sign_of(u), sv = sign_of(v);
        const LoopEdge edge{u, v, corner_edge.line};
        if (both_zero(su, sv)) {
          // An edge along the cut bounds the side its face lies on. The face is on
          // the edge's left, and left of d = n_out x n_cut is the -n_cut side
          // (n_out x (n_out x n_cut) has component -(|n_out|^2 |n_cut|^2 -
          // (n_out·n_cut)^2) < 0 along n_cut): along +d the face is below.
          Sign s = compare_along(set_, face.plane, cut_, out_.defs[u], out_.approx[u], out_.defs[v], out_.approx[v]);
          if (reversed) s = flip(s);
          (s == Sign::positive ? below_edges_ : above_edges_).push_back(edge);
        } else if (su != Sign::positive && sv != Sign::positive) {
          below_edges_.push_back(edge);
        } else {
          above_edges_.push_back(edge);
        }
      }
    }
    // New edges where the face lies on both sides of the line, between
    // consecutive points (a point: the zero points at one place).
    const auto same_place = [&](std::size_t i, std::size_t j) {
      return compare_along(set_, face.plane, cut_, out_.defs[zero_points_[i].vertex], out_.approx[zero_points_[i].vertex],
                           out_.defs[zero_points_[j].vertex], out_.approx[zero_points_[j].vertex]) == Sign::zero;
    };
    bool inside_below = false, inside_above = false;
    for (std::size_t k = 0; k < zero_points_.size();) {
      std::size_t end = k + 1;
      while (end < zero_points_.size() && same_place(k, end)) ++end;
      for (std::size_t i = k; i < end; ++i) {
        inside_below ^= (zero_points_[i].below_count & 1u) != 0;
        inside_above ^= (zero_points_[i].above_count & 1u) != 0;
      }
      if (inside_below && inside_above && end < zero_points_.size()) {
        std::size_t next_end = end + 1;
        while (next_end < zero_points_.size() && same_place(end, next_end)) ++next_end;
        const VertexIndex a = vertex_toward(face, k, end, zero_points_[end].vertex);
        const VertexIndex b = vertex_toward(face, end, next_end, zero_points_[k].vertex);
        below_edges_.push_back({a, b, cut_line()});
        above_edges_.push_back({b, a, cut_line()});
      }
      k = end;
    }
    emit_parts(face, below_edges_, out_.below, true);
    if (!below_only_) emit_parts(face, above_edges_, out_.above, false);
  }

  // Of the zero points [begin, end) at one place, the vertex whose corner of
  // the face the new edge toward `toward` (on the line) starts into: the only
  // one unless copies of a vertex meet there (cut_solid gives each sheet of a
  // piece that meets itself along a chord its own copy of the chord's ends),
  // else the copy one of whose corners in the face's loops holds the direction
  // (strictly between its outgoing and incoming edges, clockwise from the
  // incoming one, exactly).
  VertexIndex vertex_toward(const SolidFace& face, std::size_t begin, std::size_t end, VertexIndex toward) const {
    if (end - begin == 1) return zero_points_[begin].vertex;
    const FaceGeometry geometry{set_, out_.defs, out_.approx, projection_of(set_, face.plane), face.reversed};
    for (const SolidLoop& loop : augmented_loops_) {
      VertexIndex before = augmented_[loop.first_corner + loop.corner_count - 1].vertex;
      for (const CornerEdge& edge : loop_edges(augmented_, loop)) {
        const VertexIndex at = edge.from, after = edge.to;
        bool ours = false;
        for (std::size_t i = begin; i < end && !ours; ++i) ours = zero_points_[i].vertex == at;
        if (ours && clockwise_before(geometry, at, before, toward, after)) return at;
        before = at;
      }
    }
    throw UnsupportedGeometryError("split: two distinct vertices at one point of a face (the solid is not embedded)");
  }

  struct ZeroPoint {
    VertexIndex vertex;
    std::uint32_t below_count, above_count;
  };
  void touch(VertexIndex v) {
    for (const ZeroPoint& p : zero_points_) {
      if (p.vertex == v) return;
    }
    zero_points_.push_back({v, 0, 0});
  }
  void count_at(VertexIndex v, Sign other) {
    touch(v);
    for (ZeroPoint& p : zero_points_) {
      if (p.vertex != v) continue;
      (other == Sign::negative ? p.below_count : p.above_count) += 1;
      return;
    }
  }

  void emit_parts(const SolidFace& face, std::vector<LoopEdge>& edges, FaceSet& side_faces, bool below) {
    const Projection projection = projection_of(set_, face.plane);
    const FaceGeometry geometry{set_, out_.defs, out_.approx, projection, face.reversed};
    regions_.clear();
    group_into_regions(geometry, edges, regions_);
    for (const Region& region : regions_) {
      SolidFace part = face;
      part.first_loop = static_cast<std::uint32_t>(side_faces.loops.size());
      part.loop_count = static_cast<std::uint32_t>(region.loops.size());
      for (const auto& loop : region.loops) {
        side_faces.loops.push_back(
            {static_cast<std::uint32_t>(side_faces.corners.size()), static_cast<std::uint32_t>(loop.size())});
        for (const LoopEdge& edge : loop) {
          side_faces.corners.push_back({edge.from, edge.line});
          note_zero_edge(edge.from, edge.to, face, edge.line, below);
        }
      }
      part.convex = region.loops.size() == 1 && is_convex_loop(geometry, region.loops.front());
      side_faces.faces.push_back(part);
    }
  }

  // Border edges: edges on the cut whose two faces went to different sides.
  void collect_border() {
    if (below_only_) {
      out_.border.assign(zero_edges_below_.begin(), zero_edges_below_.end());
      return;
    }
    above_zero_map_.reset(zero_edges_above_.size());
    for (std::uint32_t i = 0; i < zero_edges_above_.size(); ++i) {
      above_zero_map_.insert(directed_edge_key(zero_edges_above_[i].from, zero_edges_above_[i].to), i);
    }
    for (const LoopEdge& edge : zero_edges_below_) {
      if (above_zero_map_.find(directed_edge_key(edge.to, edge.from)) != IndexMap::absent) out_.border.push_back(edge);
    }
  }

  const PlaneSet& set_;
  const Solid& solid_;
  PlaneRef cut_;
  SplitSolid& out_;
  SplitSides sides_;
  bool below_only_ = false;  // the above side is not made (run)

  std::vector<SolidCorner> augmented_;     // the face's corners with crossings inserted
  std::vector<SolidLoop> augmented_loops_;  // the face's loops over augmented_
  std::vector<ZeroPoint> zero_points_;
  std::vector<LoopEdge> below_edges_, above_edges_;
  std::vector<Region> regions_;
  std::vector<LoopEdge> zero_edges_below_, zero_edges_above_;
  IndexMap above_zero_map_;
};

}  // namespace

void split_solid(const PlaneSet& set, const Solid& solid, PlaneRef cut, SplitSolid& out, SplitSides sides) {
  Splitter(set, solid, cut, out, sides).run();
}

}  // namespace shatter
