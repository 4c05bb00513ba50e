#include "shatter/kernel/face_loops.hpp"

#include <algorithm>

#include "shatter/kernel/error.hpp"
#include "shatter/kernel/index_map.hpp"

namespace shatter {

Sign FaceGeometry::orient(VertexIndex p, VertexIndex q, VertexIndex r) const {
  const Sign s = orient_in_plane(set, projection, defs[p], approx[p], defs[q], approx[q], defs[r], approx[r]);
  return reversed ? flip(s) : s;
}

namespace {

// Orientation in the projection's own frame (no flip): for ray casting, where
// only the frame's consistency matters.
Sign raw_orient(const FaceGeometry& g, VertexIndex p, VertexIndex q, VertexIndex r) {
  return orient_in_plane(g.set, Projection{g.projection.axis, false}, g.defs[p], g.approx[p], g.defs[q], g.approx[q],
                         g.defs[r], g.approx[r]);
}

Sign compare_on(const FaceGeometry& g, int axis, VertexIndex p, VertexIndex q) {
  return compare_coordinate(g.set, axis, g.defs[p], g.approx[p], g.defs[q], g.approx[q]);
}


// The lexicographically smallest vertex of a loop in the projection frame.
std::size_t lowest_corner(const FaceGeometry& g, std::span<const LoopEdge> loop) {
  const int i = (g.projection.axis + 1) % 3, j = (g.projection.axis + 2) % 3;
  std::size_t best = 0;
  for (std::size_t k = 1; k < loop.size(); ++k) {
    const VertexIndex a = loop[best].from, b = loop[k].from;
    Sign s = compare_on(g, i, b, a);
    if (s == Sign::zero) s = compare_on(g, j, b, a);
    if (s == Sign::negative) best = k;
  }
  return best;
}

// Orientation of a simple loop seen from outside: the turn at its lowest corner,
// which for a simple polygon is a strict convex turn of the polygon's own sense.
Sign loop_orientation(const FaceGeometry& g, std::span<const LoopEdge> loop) {
  const std::size_t k = lowest_corner(g, loop);
  const LoopEdge& into = loop[(k + loop.size() - 1) % loop.size()];
  return g.orient(into.from, loop[k].from, loop[k].to);
}

bool loop_has_vertex(std::span<const LoopEdge> loop, VertexIndex v) {
  return std::any_of(loop.begin(), loop.end(), [v](const LoopEdge& e) { return e.from == v; });
}

// Is loop `inner` inside loop `outer` (the two do not cross)? Decided at a
// vertex of `inner` off `outer`: not one of its corners, nor at the place of
// one (where a piece meets itself along a chord, copies of a vertex lie at one
// point, cut_solid).
bool loop_inside(const FaceGeometry& g, std::span<const LoopEdge> inner, std::span<const LoopEdge> outer) {
  for (const LoopEdge& e : inner) {
    if (loop_has_vertex(outer, e.from)) continue;
    const Sign where = locate_in_loop(g, e.from, outer);
    if (where != Sign::zero) return where == Sign::positive;
  }
  throw UnsupportedGeometryError("face loops: every vertex of a loop lies on another loop; cannot place it");
}

}  // namespace

Sign locate_in_loop(const FaceGeometry& g, VertexIndex v, std::span<const LoopEdge> loop) {
  const int i = (g.projection.axis + 1) % 3, j = (g.projection.axis + 2) % 3;
  bool inside = false;
  for (const LoopEdge& e : loop) {
    const Sign height = compare_on(g, j, v, e.from);
    if (height == Sign::zero && compare_on(g, i, v, e.from) == Sign::zero) return Sign::zero;
    const bool a_above = height == Sign::positive;
    const bool b_above = compare_on(g, j, v, e.to) == Sign::positive;
    if (a_above == b_above) continue;
    const Sign o = raw_orient(g, e.from, e.to, v);
    if (o == Sign::zero) return Sign::zero;
    if (b_above ? o == Sign::positive : o == Sign::negative) inside = !inside;
  }
  return inside ? Sign::positive : Sign::negative;
}

bool clockwise_before(const FaceGeometry& g, VertexIndex v, VertexIndex a, VertexIndex b, VertexIndex c) {
  // Halves: angle in (0, pi) clockwise from v->a is 0, exactly pi is 1, beyond 2.
  auto half = [&](VertexIndex x) {
    const Sign s = g.orient(v, a, x);
    return s == Sign::negative ? 0 : s == Sign::zero ? 1 : 2;
  };
  const int hb = half(b), hc = half(c);
  if (hb != hc) return hb < hc;
  if (hb == 1) return false;  // both opposite a: the same ray, cannot happen for distinct edges
  return g.orient(v, b, c) == Sign::negative;
}

bool inside_loop(const FaceGeometry& g, VertexIndex v, std::span<const LoopEdge> loop) {
  const int j = (g.projection.axis + 2) % 3;
  bool inside = false;
  for (const LoopEdge& e : loop) {
    const bool a_above = compare_on(g, j, v, e.from) == Sign::positive;
    const bool b_above = compare_on(g, j, v, e.to) == Sign::positive;
    if (a_above == b_above) continue;
    const Sign o = raw_orient(g, e.from, e.to, v);
    if (o == Sign::zero) throw UnsupportedGeometryError("face loops: a point to place lies on a loop's edge");
    // The edge crosses the horizontal line through v; it crosses the ray to the
    // right of v when v is left of an upward edge or right of a downward one.
    if (b_above ? o == Sign::positive : o == Sign::negative) inside = !inside;
  }
  return inside;
}

bool is_convex_loop(const FaceGeometry& g, std::span<const LoopEdge> loop) {
  for (std::size_t k = 0; k < loop.size(); ++k) {
    const LoopEdge& e = loop[k];
    const LoopEdge& next = loop[(k + 1) % loop.size()];
    // Two edges on one known line go straight, without arithmetic: a cut puts a
    // crossing vertex on every edge it crosses, whose three points are exactly
    // collinear and would take the exact fallback of orient_in_plane (1.7 % of
    // a Voronoi build of a curved mesh went there).
    if (e.line == next.line && (e.line.other.bits != no_index || e.line.is_segment())) continue;
    if (g.orient(e.from, e.to, next.to) == Sign::negative) return false;
  }
  return true;
}

void group_into_regions(const FaceGeometry& g, std::vector<LoopEdge>& edges, std::vector<Region>& regions) {
  regions.clear();
  if (edges.empty()) return;
  std::stable_sort(edges.begin(), edges.end(), [](const LoopEdge& a, const LoopEdge& b) { return a.from < b.from; });
  IndexMap first_out(edges.size());
  for (std::uint32_t e = 0; e < edges.size(); ++e) {
    if (e == 0 || edges[e].from != edges[e - 1].from) first_out.insert(edges[e].from, e);
  }
  auto outgoing = [&](VertexIndex v, std::uint32_t& begin, std::uint32_t& end) {
    begin = first_out.find(v);
    if (begin == IndexMap::absent) {
      end = begin = 0;
      return;
    }
    end = begin;
    while (end < edges.size() && edges[end].from == v) ++end;
  };

  std::vector<bool> used(edges.size(), false);
  std::vector<std::uint32_t> walk;
  std::vector<std::vector<LoopEdge>> cycles;
  IndexMap position;  // vertex -> index in the stack where it is an edge's `from`
  std::vector<LoopEdge> stack;
  for (std::uint32_t start = 0; start < edges.size(); ++start) {
    if (used[start]) continue;
    walk.clear();
    std::uint32_t e = start;
    for (;;) {
      used[e] = true;
      walk.push_back(e);
      const VertexIndex v = edges[e].to;
      std::uint32_t begin, end;
      outgoing(v, begin, end);
      if (begin == end) throw std::logic_error("face loops: a vertex has no outgoing edge (the boundary is open)");
      std::uint32_t next = begin;
      if (end - begin > 1) {
        for (std::uint32_t c = begin + 1; c < end; ++c) {
          if (clockwise_before(g, v, edges[e].from, edges[c].to, edges[next].to)) next = c;
        }
        if (used[next] && next != start) {
          // The clockwise rule met a used edge: take any unused one (only a
          // boundary that is not embedded gets here).
          next = end;
          for (std::uint32_t c = begin; c < end; ++c) {
            if (!used[c]) next = c;
          }
          if (next == end) next = start;
        }
      }
      if (next == start || used[next]) break;
      e = next;
    }
    // Split the closed walk into simple cycles.
    stack.clear();
    position.reset(walk.size());
    for (std::uint32_t index : walk) {
      const LoopEdge& edge = edges[index];
      position.insert(edge.from, static_cast<std::uint32_t>(stack.size()));
      stack.push_back(edge);
      const std::uint32_t at = position.find(edge.to);
      if (at != IndexMap::absent) {
        cycles.emplace_back(stack.begin() + at, stack.end());
        stack.resize(at);
        position.reset(walk.size());
        for (std::uint32_t k = 0; k < stack.size(); ++k) position.insert(stack[k].from, k);
      }
    }
    if (!stack.empty()) throw std::logic_error("face loops: a walk did not close");
  }

  // Outer loops start regions; holes join the innermost outer loop around them.
  std::vector<std::vector<LoopEdge>*> holes;
  for (auto& cycle : cycles) {
    if (loop_orientation(g, cycle) == Sign::positive) {
      regions.emplace_back();
      regions.back().loops.push_back(std::move(cycle));
    } else {
      holes.push_back(&cycle);
    }
  }
  if (regions.empty()) throw UnsupportedGeometryError("face loops: only clockwise loops (no outer boundary)");
  for (std::vector<LoopEdge>* hole : holes) {
    if (regions.size() == 1) {
      regions.front().loops.push_back(std::move(*hole));
      continue;
    }
    std::size_t best = regions.size();
    for (std::size_t r = 0; r < regions.size(); ++r) {
      const auto& outer = regions[r].loops.front();
      if (!loop_inside(g, *hole, outer)) continue;
      if (best == regions.size() || loop_inside(g, outer, regions[best].loops.front())) best = r;
    }
    if (best == regions.size()) throw UnsupportedGeometryError("face loops: a hole lies in no outer loop");
    regions[best].loops.push_back(std::move(*hole));
  }
}

}  // namespace shatter
