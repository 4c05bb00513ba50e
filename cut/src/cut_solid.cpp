#include "shatter/cut/cut_solid.hpp"

#include <tbb/parallel_invoke.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <exception>
#include <numeric>

#include "shatter/kernel/error.hpp"
#include "shatter/kernel/face_loops.hpp"
#include "shatter/kernel/index_map.hpp"
#include "shatter/kernel/union_find.hpp"
#include "shatter/slicer/split.hpp"
#include "shatter/triangulate/cap_faces.hpp"

namespace shatter {
namespace {

// Appends `from`'s faces to `to`, renumbering their loops and corners.
void append_faces(const FaceSet& from, FaceSet& to) {
  const auto loop_base = static_cast<std::uint32_t>(to.loops.size());
  const auto corner_base = static_cast<std::uint32_t>(to.corners.size());
  for (SolidFace face : from.faces) {
    face.first_loop += loop_base;
    to.faces.push_back(face);
  }
  for (SolidLoop loop : from.loops) {
    loop.first_corner += corner_base;
    to.loops.push_back(loop);
  }
  to.corners.insert(to.corners.end(), from.corners.begin(), from.corners.end());
}

// The solid made of the given faces of `faces`, its vertices numbered compactly in
// order of first use. Its arrays are sized exactly first (a count, then the
// copy): the pieces are kept in the tree, so slack would stay allocated, and
// growing by doubling would copy them again.
Solid extract(std::span<const PointDef> defs, std::span<const ApproxPoint> approx, const FaceSet& faces,
              std::span<const std::uint32_t> chosen, std::vector<VertexIndex>& local) {
  Solid solid;
  local.assign(defs.size(), no_index);
  // The vertices in order of first use, so that each is copied once (a vertex
  // has several corners).
  thread_local std::vector<VertexIndex> used;
  used.clear();
  std::size_t loop_count = 0, corner_count = 0;
  for (std::uint32_t f : chosen) {
    const SolidFace& face = faces.faces[f];
    loop_count += face.loop_count;
    for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
      const SolidLoop& loop = faces.loops[l];
      corner_count += loop.corner_count;
      for (std::uint32_t i = 0; i < loop.corner_count; ++i) {
        const VertexIndex vertex = faces.corners[loop.first_corner + i].vertex;
        VertexIndex& number = local[vertex];
        if (number == no_index) {
          number = static_cast<VertexIndex>(used.size());
          used.push_back(vertex);
        }
      }
    }
  }
  solid.faces.reserve(chosen.size());
  solid.loops.reserve(loop_count);
  solid.corners.reserve(corner_count);
  solid.defs.reserve(used.size());
  solid.approx.reserve(used.size());
  for (const VertexIndex vertex : used) {
    solid.defs.push_back(defs[vertex]);
    solid.approx.push_back(approx[vertex]);
  }
  for (std::uint32_t f : chosen) {
    SolidFace face = faces.faces[f];
    const std::uint32_t first_loop = face.first_loop;
    face.first_loop = static_cast<std::uint32_t>(solid.loops.size());
    for (std::uint32_t l = first_loop; l < first_loop + face.loop_count; ++l) {
      const SolidLoop& loop = faces.loops[l];
      solid.loops.push_back({static_cast<std::uint32_t>(solid.corners.size()), loop.corner_count});
      for (std::uint32_t i = 0; i < loop.corner_count; ++i) {
        SolidCorner corner = faces.corners[loop.first_corner + i];
        corner.vertex = local[corner.vertex];
        solid.corners.push_back(corner);
      }
    }
    solid.faces.push_back(face);
  }
  return solid;
}

// --- placing an untouched cavity ------------------------------------------------
// A shell of the solid that the cut did not touch is a cavity (the outer shell is
// always touched when the plane crosses the solid). When its side fell into several
// solids it belongs to the one around it, found by an exact ray cast from one of
// its vertices (an input point) to a far input-like point: the parity of the faces
// crossed. A ray through an edge, a vertex or along a plane is degenerate and is
// cast again in another direction.

bool solid_contains(const PlaneSet& set, const Solid& solid, std::uint32_t point_index) {
  const Vec3 p = set.points[point_index];
  Vec3 lo = p, hi = p;
  for (const ApproxPoint& a : solid.approx) {
    const Vec3 v{a.x.value / a.w.value, a.y.value / a.w.value, a.z.value / a.w.value};
    lo = {std::min(lo.x, v.x), std::min(lo.y, v.y), std::min(lo.z, v.z)};
    hi = {std::max(hi.x, v.x), std::max(hi.y, v.y), std::max(hi.z, v.z)};
  }
  const double reach = 4 * (std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z}) + std::fabs(p.x) + std::fabs(p.y) +
                            std::fabs(p.z)) + 1;
  // Directions with no simple relation to the axes or to each other.
  static constexpr double directions[][3] = {{1, 0.3183098861837907, 0.1414213562373095},
                                             {-0.2718281828459045, 1, 0.5772156649015329},
                                             {0.6180339887498949, -0.4142135623730950, 1},
                                             {-1, -0.7071067811865476, 0.2236067977499790},
                                             {0.1732050807568877, 1, -0.8660254037844386},
                                             {0.9, 0.8, -1}};
  std::vector<Vec3> points(set.points.begin(), set.points.end());
  const auto far_index = static_cast<std::uint32_t>(points.size());
  points.emplace_back();
  std::vector<PointDef> defs(solid.defs);
  std::vector<ApproxPoint> approx(solid.approx);
  const auto hit_index = static_cast<VertexIndex>(defs.size());
  defs.emplace_back();
  approx.emplace_back();
  for (const auto& d : directions) {
    points[far_index] = {p.x + reach * d[0], p.y + reach * d[1], p.z + reach * d[2]};
    const PlaneSet extended{points, set.inputs, set.input_approx, set.cuts};
    const PointDef from = PointDef::input(point_index), to = PointDef::input(far_index);
    const ApproxPoint from_approx = approximate(extended, from), to_approx = approximate(extended, to);
    bool odd = false, degenerate = false;
    try {
      for (const SolidFace& face : solid.faces) {
        const Sign s_from = side(extended, face.plane, from, from_approx);
        const Sign s_to = side(extended, face.plane, to, to_approx);
        if (s_to == Sign::zero) {
          degenerate = true;  // the far point on a face's plane: try another direction
          break;
        }
        // A ray starting on a face's plane leaves it at once (the far point is off
        // it): no crossing. (The cavity's vertex is not on the piece's surface.)
        if (s_from == Sign::zero || s_from == s_to) continue;
        defs[hit_index] = PointDef::segment_plane(point_index, far_index, face.plane);
        approx[hit_index] = approximate(extended, defs[hit_index]);
        const FaceGeometry geometry{extended, defs, approx, projection_of(extended, face.plane), face.reversed};
        std::vector<LoopEdge> loop;
        bool inside = false;
        for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
          loop.clear();
          for (const CornerEdge& edge : loop_edges(solid.corners, solid.loops[l])) loop.push_back({edge.from, edge.to, {}});
          if (inside_loop(geometry, hit_index, loop)) inside = !inside;
        }
        if (inside) odd = !odd;
      }
    } catch (const UnsupportedGeometryError&) {
      degenerate = true;  // the ray met an edge of a face
    }
    if (!degenerate) return odd;
  }
  throw UnsupportedGeometryError("cannot place a cavity: every ray cast from it was degenerate");
}

// Appends solid `part`'s faces and vertices to `host`.
void absorb(Solid& host, const Solid& part) {
  const auto vertex_base = static_cast<VertexIndex>(host.defs.size());
  const auto loop_base = static_cast<std::uint32_t>(host.loops.size());
  const auto corner_base = static_cast<std::uint32_t>(host.corners.size());
  host.defs.insert(host.defs.end(), part.defs.begin(), part.defs.end());
  host.approx.insert(host.approx.end(), part.approx.begin(), part.approx.end());
  for (SolidFace f : part.faces) {
    f.first_loop += loop_base;
    host.faces.push_back(f);
  }
  for (SolidLoop l : part.loops) {
    l.first_corner += corner_base;
    host.loops.push_back(l);
  }
  for (SolidCorner c : part.corners) {
    c.vertex += vertex_base;
    host.corners.push_back(c);
  }
}

// Where a piece meets itself along a chord (both faces of the surface there in
// one piece), four of its faces run the chord: the two of the surface, each
// closing up with the cap face that runs the chord the other way (separate_side),
// so each directed edge is run twice and the piece is no sound solid. As at a
// point where a piece touches itself, the part thinner than any rounding, the
// segment, gives way, here already in the exact solid: around each end of such
// a chord the corners of the faces (a face's corners there: where its loops
// meet at the vertex, each incoming edge with the outgoing edge first
// clockwise from it, as group_into_regions links them) fall into fans,
// neighbours across an edge, across a doubled edge only a surface face and a
// cap face, and every fan but the first gets its own copy of the vertex (the
// same exact point). Each sheet then runs its own edge, every edge is run once
// each way (check_solid), a face whose loops met at the vertex is relinked
// into the loops its corners now make, and round_solid moves the copies apart
// a hair when it writes the piece, as it does the fans of a pinched vertex.
void separate_pinched_chords(const PlaneSet& set, Solid& solid, PlaneRef cut) {
  thread_local std::vector<std::uint64_t> directed, doubled;
  directed.clear();
  doubled.clear();
  for (const SolidLoop& loop : solid.loops) {
    for (const CornerEdge& edge : loop_edges(solid.corners, loop)) directed.push_back(directed_edge_key(edge.from, edge.to));
  }
  std::sort(directed.begin(), directed.end());
  for (std::size_t i = 1; i < directed.size(); ++i) {
    if (directed[i] == directed[i - 1]) doubled.push_back(directed[i]);
  }
  if (doubled.empty()) return;
  const auto is_doubled = [&](VertexIndex u, VertexIndex v) {
    return std::binary_search(doubled.begin(), doubled.end(), directed_edge_key(u, v)) ||
           std::binary_search(doubled.begin(), doubled.end(), directed_edge_key(v, u));
  };
  const std::size_t corner_count = solid.corners.size();
  std::vector<std::uint8_t> at_chord(solid.defs.size(), 0);
  std::vector<std::uint32_t> next(corner_count), prev(corner_count), face_of(corner_count);
  for (std::uint32_t f = 0; f < solid.faces.size(); ++f) {
    const SolidFace& face = solid.faces[f];
    for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
      for (const CornerEdge& edge : loop_edges(solid.corners, solid.loops[l])) {
        if (is_doubled(edge.from, edge.to)) at_chord[edge.from] = at_chord[edge.to] = 1;
        const std::uint32_t after = loop_edges(solid.corners, solid.loops[l]).next(edge.corner);
        next[edge.corner] = after;
        prev[after] = edge.corner;
        face_of[edge.corner] = f;
      }
    }
  }
  // A corner of a face's region at a chord's end v: the corner whose edge comes
  // in (w -> v) and the corner at v whose edge goes out (v -> x).
  struct Sector {
    VertexIndex vertex;
    std::uint32_t in, out;
  };
  std::vector<Sector> sectors;
  thread_local std::vector<std::uint32_t> at_vertex;
  for (std::uint32_t f = 0; f < solid.faces.size(); ++f) {
    const SolidFace& face = solid.faces[f];
    at_vertex.clear();
    for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
      const SolidLoop& loop = solid.loops[l];
      for (std::uint32_t c = loop.first_corner; c < loop.first_corner + loop.corner_count; ++c) {
        if (at_chord[solid.corners[c].vertex]) at_vertex.push_back(c);
      }
    }
    std::sort(at_vertex.begin(), at_vertex.end(), [&](std::uint32_t a, std::uint32_t b) {
      return solid.corners[a].vertex != solid.corners[b].vertex ? solid.corners[a].vertex < solid.corners[b].vertex
                                                                : a < b;
    });
    const FaceGeometry geometry{set, solid.defs, solid.approx, projection_of(set, face.plane), face.reversed};
    for (std::size_t begin = 0; begin < at_vertex.size();) {
      const VertexIndex v = solid.corners[at_vertex[begin]].vertex;
      std::size_t end = begin;
      while (end < at_vertex.size() && solid.corners[at_vertex[end]].vertex == v) ++end;
      for (std::size_t i = begin; i < end; ++i) {
        // The edge coming in at this visit of v, continued by the outgoing edge
        // first clockwise from it among the face's visits of v.
        const std::uint32_t in = prev[at_vertex[i]];
        const VertexIndex w = solid.corners[in].vertex;
        std::uint32_t out = at_vertex[begin];
        for (std::size_t k = begin + 1; k < end; ++k) {
          const std::uint32_t candidate = at_vertex[k];
          if (clockwise_before(geometry, v, w, solid.corners[next[candidate]].vertex, solid.corners[next[out]].vertex)) {
            out = candidate;
          }
        }
        sectors.push_back({v, in, out});
      }
      begin = end;
    }
  }
  std::sort(sectors.begin(), sectors.end(), [](const Sector& a, const Sector& b) {
    return a.vertex != b.vertex ? a.vertex < b.vertex : a.out < b.out;
  });
  const auto is_cap = [&](std::uint32_t corner) { return solid.faces[face_of[corner]].plane == cut; };
  // Per corner: the vertex its edge leaves from, and (next) the corner after
  // it, as the sectors make them.
  std::vector<VertexIndex> from(corner_count);
  for (std::uint32_t c = 0; c < corner_count; ++c) from[c] = solid.corners[c].vertex;
  UnionFind fans;
  for (std::size_t begin = 0; begin < sectors.size();) {
    const VertexIndex v = sectors[begin].vertex;
    std::size_t end = begin;
    while (end < sectors.size() && sectors[end].vertex == v) ++end;
    const auto count = static_cast<std::uint32_t>(end - begin);
    fans.reset(count);
    // Sector i leaves v towards x; the sector entering v from x is its neighbour
    // around v, across a doubled edge only the one of the other kind.
    for (std::uint32_t i = 0; i < count; ++i) {
      const Sector& a = sectors[begin + i];
      const VertexIndex x = solid.corners[next[a.out]].vertex;
      const bool chord = is_doubled(v, x);
      for (std::uint32_t j = 0; j < count; ++j) {
        const Sector& b = sectors[begin + j];
        if (solid.corners[b.in].vertex == x && (!chord || is_cap(a.out) != is_cap(b.in))) fans.unite(i, j);
      }
    }
    std::vector<VertexIndex> copy_of_root(count, no_index);
    copy_of_root[fans.find(0)] = v;
    for (std::uint32_t i = 0; i < count; ++i) {
      VertexIndex& copy = copy_of_root[fans.find(i)];
      if (copy == no_index) {
        copy = static_cast<VertexIndex>(solid.defs.size());
        solid.defs.push_back(solid.defs[v]);
        solid.approx.push_back(solid.approx[v]);
      }
      const Sector& s = sectors[begin + i];
      from[s.out] = copy;
      next[s.in] = s.out;
    }
    begin = end;
  }
  // The loops again, each face's as its corners now follow each other (the same
  // loops, from the same corners, where nothing changed).
  std::vector<SolidLoop> loops;
  std::vector<SolidCorner> corners;
  loops.reserve(solid.loops.size());
  corners.reserve(corner_count);
  std::vector<std::uint8_t> placed(corner_count, 0);
  for (SolidFace& face : solid.faces) {
    const std::uint32_t first_loop = face.first_loop, loop_count = face.loop_count;
    face.first_loop = static_cast<std::uint32_t>(loops.size());
    for (std::uint32_t l = first_loop; l < first_loop + loop_count; ++l) {
      const SolidLoop& loop = solid.loops[l];
      for (std::uint32_t start = loop.first_corner; start < loop.first_corner + loop.corner_count; ++start) {
        if (placed[start]) continue;
        SolidLoop relinked{static_cast<std::uint32_t>(corners.size()), 0};
        for (std::uint32_t c = start; !placed[c]; c = next[c]) {
          placed[c] = 1;
          corners.push_back({from[c], solid.corners[c].line});
          ++relinked.corner_count;
        }
        loops.push_back(relinked);
      }
    }
    face.loop_count = static_cast<std::uint32_t>(loops.size()) - face.first_loop;
  }
  solid.loops = std::move(loops);
  solid.corners = std::move(corners);
}

// The pieces of one side: its faces plus its cap, separated into edge-connected
// shells. A shell with a cap face is the outer shell of a piece (the cut crossed
// it). A shell without one was not touched, so it is a whole input shell, and
// the input tells what it is: an outer shell is a solid of its own, a cavity
// joins its own outer shell when that is whole too, and otherwise the piece
// around it (an exact ray cast; pieces with a cap face are never nested).
void separate_side(const PlaneSet& set, PlaneRef cut, std::span<const PointDef> defs,
                   std::span<const ApproxPoint> approx, const FaceSet& faces, std::size_t first_cap_face,
                   bool parent_convex, const InputShells& shells,
                   std::span<const std::uint64_t> chord_keys, std::vector<Solid>& out) {
  thread_local std::vector<VertexIndex> local;
  thread_local std::vector<std::uint32_t> chosen;
  if (parent_convex) {
    chosen.resize(faces.faces.size());
    std::iota(chosen.begin(), chosen.end(), 0u);
    out.push_back(extract(defs, approx, faces, chosen, local));
    out.back().convex = true;
    return;
  }
  thread_local UnionFind components;
  thread_local IndexMap face_of_edge;
  components.reset(faces.faces.size());
  face_of_edge.reset(faces.corners.size());
  // A chord has four faces: the two of the surface and the two cap faces on
  // either side of it. Each face of the surface closes up with the cap face that
  // runs the chord the other way, the one on its own side of the edge.
  struct ChordUse {
    std::uint64_t key;
    std::uint32_t face;
    VertexIndex from;
    bool cap;
  };
  thread_local std::vector<ChordUse> chord_uses;
  chord_uses.clear();
  // Per corner, its face and the face across its edge (no_index while unmatched),
  // for deciding the pieces' convexity (solid_convex) from this one pass.
  thread_local std::vector<std::uint32_t> face_of_corner, across;
  face_of_corner.resize(faces.corners.size());
  across.assign(faces.corners.size(), no_index);
  for (std::uint32_t f = 0; f < faces.faces.size(); ++f) {
    const SolidFace& face = faces.faces[f];
    for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
      for (const CornerEdge& edge : loop_edges(faces.corners, faces.loops[l])) {
        face_of_corner[edge.corner] = f;
        const std::uint64_t key = undirected_edge_key(edge.from, edge.to);
        if (!chord_keys.empty() && std::find(chord_keys.begin(), chord_keys.end(), key) != chord_keys.end()) {
          chord_uses.push_back({key, f, edge.from, f >= first_cap_face});
          continue;
        }
        const std::uint32_t first = face_of_edge.insert(key, edge.corner);
        if (first == edge.corner) continue;
        const std::uint32_t other = face_of_corner[first];
        across[edge.corner] = other;
        across[first] = f;
        if (other != f) components.unite(f, other);
      }
    }
  }
  for (const ChordUse& surface : chord_uses) {
    if (surface.cap) continue;
    for (const ChordUse& cap : chord_uses) {
      if (cap.cap && cap.key == surface.key && cap.from != surface.from) components.unite(surface.face, cap.face);
    }
  }
  // Chords whose two sides are one piece (a tunnel whose lowest edge lies on
  // the plane): that piece meets itself along the chord, and its sheets there
  // get their own copies of the chord's ends once it is extracted.
  bool any_pinched = false;
  for (const ChordUse& a : chord_uses) {
    for (const ChordUse& b : chord_uses) {
      any_pinched = any_pinched || (!a.cap && !b.cap && a.key == b.key && a.face < b.face &&
                                    components.find(a.face) == components.find(b.face));
    }
  }
  thread_local std::vector<std::uint8_t> touched;
  thread_local std::vector<std::uint32_t> group_of_root;
  touched.assign(faces.faces.size(), 0);
  for (std::uint32_t f = static_cast<std::uint32_t>(first_cap_face); f < faces.faces.size(); ++f) {
    touched[components.find(f)] = 1;
  }
  // Components in order of their first face, so the output is deterministic.
  group_of_root.assign(faces.faces.size(), no_index);
  std::vector<std::vector<std::uint32_t>> groups;
  std::vector<std::uint8_t> group_touched;
  for (std::uint32_t f = 0; f < faces.faces.size(); ++f) {
    const std::uint32_t root = components.find(f);
    if (group_of_root[root] == no_index) {
      group_of_root[root] = static_cast<std::uint32_t>(groups.size());
      groups.emplace_back();
      group_touched.push_back(touched[root]);
    }
    groups[group_of_root[root]].push_back(f);
  }
  auto input_shell_of = [&](const std::vector<std::uint32_t>& group) {
    return shells.shell_of_triangle[faces.faces[group.front()].source];
  };
  // Pieces: touched shells, then whole outer shells; remember which input shell
  // each whole outer shell is.
  const std::size_t first = out.size();
  std::vector<std::uint32_t> whole_outer_shell;  // per piece: input shell id, or no_index if touched
  for (std::size_t g = 0; g < groups.size(); ++g) {
    const bool is_piece =
        group_touched[g] || shells.outer_of_shell[input_shell_of(groups[g])] == input_shell_of(groups[g]);
    if (!is_piece) continue;
    out.push_back(extract(defs, approx, faces, groups[g], local));
    if (any_pinched && group_touched[g]) separate_pinched_chords(set, out.back(), cut);
    whole_outer_shell.push_back(group_touched[g] ? no_index : input_shell_of(groups[g]));
  }
  const std::size_t piece_count = out.size() - first;
  // Whether the piece of group g is convex, as solid_is_convex decides it on
  // the extracted piece (which keeps the group's faces in order, each face's
  // loops and corners in order, over the same points): each edge once, from
  // the face that comes first, against the first vertex of the face across off
  // its plane. The group is one edge-connected shell.
  const auto group_convex = [&](const std::vector<std::uint32_t>& group) {
    for (const std::uint32_t f : group) {
      const SolidFace& face = faces.faces[f];
      for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
        const SolidLoop& loop = faces.loops[l];
        for (std::uint32_t c = loop.first_corner; c < loop.first_corner + loop.corner_count; ++c) {
          const std::uint32_t g = across[c];
          if (g == no_index) return false;
          if (g < f) continue;
          if (outward_side_of_face(set, face, faces.faces[g], faces.loops, faces.corners, defs, approx) ==
              Sign::positive) {
            return false;
          }
        }
      }
    }
    return true;
  };
  // Decided on the group unless the piece was changed after extraction (chords'
  // copies) or takes a cavity below (then it has two shells: not convex).
  std::vector<std::uint8_t> decided(piece_count, 0);
  if (chord_keys.empty()) {
    for (std::size_t g = 0, k = 0; g < groups.size(); ++g) {
      const bool is_piece =
          group_touched[g] || shells.outer_of_shell[input_shell_of(groups[g])] == input_shell_of(groups[g]);
      if (!is_piece) continue;
      out[first + k].convex = group_convex(groups[g]);
      decided[k++] = 1;
    }
  }
  for (std::size_t g = 0; g < groups.size(); ++g) {
    if (group_touched[g]) continue;
    const std::uint32_t shell = input_shell_of(groups[g]);
    const std::uint32_t outer = shells.outer_of_shell[shell];
    if (outer == shell) continue;  // a piece already
    std::size_t owner = out.size();
    for (std::size_t k = 0; k < piece_count; ++k) {
      if (whole_outer_shell[k] == outer) owner = first + k;
    }
    if (owner == out.size()) {
      // Its outer shell was cut: the touched piece around it.
      const SolidFace& face = faces.faces[groups[g].front()];
      const std::uint32_t point = defs[faces.corners[faces.loops[face.first_loop].first_corner].vertex].a;
      std::size_t candidates = 0, last = out.size();
      for (std::size_t k = 0; k < piece_count; ++k) {
        if (whole_outer_shell[k] != no_index) continue;
        ++candidates;
        last = first + k;
      }
      if (candidates == 1) {
        owner = last;
      } else {
        for (std::size_t k = 0; k < piece_count && owner == out.size(); ++k) {
          if (whole_outer_shell[k] == no_index && solid_contains(set, out[first + k], point)) owner = first + k;
        }
      }
      if (owner == out.size()) throw UnsupportedGeometryError("cannot place a cavity: no piece contains it");
    }
    absorb(out[owner], extract(defs, approx, faces, groups[g], local));
    decided[owner - first] = 0;
  }
  for (std::size_t k = first; k < out.size(); ++k) {
    if (!decided[k - first]) out[k].convex = solid_is_convex(set, out[k]);
  }
}

// Whether segment u -> v starts into the interior of a cap region at u, where
// the region's boundary runs a -> u -> b (region on the left): the "in cone" test
// of polygon triangulation (O'Rourke, "Computational Geometry in C", 1998, 1.6).
bool starts_inside(const FaceGeometry& g, VertexIndex a, VertexIndex u, VertexIndex b, VertexIndex v) {
  if (v == a || v == b) return false;
  if (g.orient(a, u, b) != Sign::negative) {  // convex (or straight) corner
    return g.orient(u, v, a) == Sign::positive && g.orient(v, u, b) == Sign::positive;
  }
  return !(g.orient(u, v, b) != Sign::negative && g.orient(v, u, a) != Sign::negative);
}

// The chords of a cut: concave edges of the surface that lie on the cut between
// two border vertices, both of whose faces went to one side, running through
// the cap (the in-cone test at an end). The pieces of that side meet along such
// an edge; split along it, that side's cap gives each of them a face there
// (make_caps). Each chord comes in both directions, directed and lined as the
// cap facing +n runs it: opposite to the side's face across, whose plane is the
// edge's line. `keys`: the chords' undirected edge keys, per side.
struct Chords {
  std::vector<LoopEdge> below, above;
  std::vector<std::uint64_t> below_keys, above_keys;
  bool empty() const { return below.empty() && above.empty(); }
};

void find_chords(const PlaneSet& set, PlaneRef cut, const SplitSolid& split, const FaceSet& below_cap,
                 Chords& chords) {
  // Cleared, not replaced: the caller's chords are thread-local and keep their storage.
  chords.below.clear();
  chords.above.clear();
  chords.below_keys.clear();
  chords.above_keys.clear();
  thread_local std::vector<std::uint8_t> on_border;
  on_border.assign(split.defs.size(), 0);
  for (const LoopEdge& e : split.border) on_border[e.from] = on_border[e.to] = 1;
  bool any_zero_border_vertex = false;
  for (std::size_t v = 0; v < split.defs.size() && !any_zero_border_vertex; ++v) {
    any_zero_border_vertex = split.sides[v] == Sign::zero && on_border[v];
  }
  if (!any_zero_border_vertex) return;
  const FaceGeometry geometry{set, split.defs, split.approx, projection_of(set, cut), false};
  thread_local IndexMap border_edges;
  border_edges.reset(split.border.size());
  for (const LoopEdge& e : split.border) border_edges.insert(undirected_edge_key(e.from, e.to), 1);
  for (const bool below : {true, false}) {
    const FaceSet& side_faces = below ? split.below : split.above;
    for (const SolidFace& face : side_faces.faces) {
      for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
        for (const CornerEdge& edge : loop_edges(side_faces.corners, side_faces.loops[l])) {
          const VertexIndex u = edge.from, v = edge.to;
          if (!on_border[u] || !on_border[v] || split.sides[u] != Sign::zero || split.sides[v] != Sign::zero) continue;
          if (border_edges.find(undirected_edge_key(u, v)) != IndexMap::absent) continue;
          bool across = false;
          for (const SolidLoop& c : below_cap.loops) {
            // Each cap corner `at` with the corners before and after it.
            VertexIndex before = below_cap.corners[c.first_corner + c.corner_count - 1].vertex;
            for (const CornerEdge& cap_edge : loop_edges(below_cap.corners, c)) {
              const VertexIndex at = cap_edge.from, after = cap_edge.to;
              across = across || ((at == u || at == v) && starts_inside(geometry, before, at, after, at == u ? v : u));
              before = at;
            }
          }
          if (!across) continue;
          // The cap runs it opposite to this face; facing +n, the above cap's
          // direction is reversed once more.
          const EdgeLine line{face.plane, edge.line.p, edge.line.q};
          (below ? chords.below : chords.above).push_back(below ? LoopEdge{v, u, line} : LoopEdge{u, v, line});
          if (u < v) (below ? chords.below_keys : chords.above_keys).push_back(undirected_edge_key(u, v));
        }
      }
    }
  }
}

}  // namespace

SolidCut cut_solid(const PlaneSet& set, const Solid& solid, PlaneRef cut, SurfaceId cap_surface,
                   const InputShells& shells, CutSides sides) {
  thread_local SplitSolid split;
  thread_local FaceSet below_cap, above_cap, below_side, above_side;
  SolidCut result;
  split_solid(set, solid, cut, split,
              sides == CutSides::both ? SplitSides::both : sides == CutSides::below ? SplitSides::below : SplitSides::above);
  if (split.plane_misses) {
    result.plane_missed = true;
    result.all_below = split.all_below;
    return result;
  }
  make_caps(set, cut, split.defs, split.approx, split.border, solid.convex, cap_surface, below_cap, above_cap);
  result.cap_faces = below_cap.faces.size();
  result.cap_loops = below_cap.loops.size();
  if (split.other_side_partial) {
    // One side, and no vertex of the solid on the plane: no edge of the surface
    // lies on the cut but the border edges, so there is no chord (find_chords
    // would find none), and the kept side's faces take its cap in place, not
    // copied again; the same faces in the same order as below.
    const bool below = sides == CutSides::below;
    FaceSet& kept = below ? split.below : split.above;
    const std::size_t first_cap = kept.faces.size();
    append_faces(below ? below_cap : above_cap, kept);
    separate_side(set, cut, split.defs, split.approx, kept, first_cap, solid.convex, shells, {},
                  below ? result.below : result.above);
    return result;
  }
  thread_local Chords chords;
  find_chords(set, cut, split, below_cap, chords);
  if (!chords.empty()) {
    make_caps(set, cut, split.defs, split.approx, split.border, solid.convex, cap_surface, below_cap, above_cap,
              chords.below, chords.above);
  }
  // This thread's scratch, named here: a side run on another thread must read
  // these, not that thread's own.
  const SplitSolid& split_here = split;
  const FaceSet &below_cap_here = below_cap, &above_cap_here = above_cap;
  const Chords& chords_here = chords;
  FaceSet &below_side_here = below_side, &above_side_here = above_side;
  const auto separate = [&](bool below) {
    FaceSet& side = below ? below_side_here : above_side_here;
    side.clear();
    append_faces(below ? split_here.below : split_here.above, side);
    const std::size_t first_cap = side.faces.size();
    append_faces(below ? below_cap_here : above_cap_here, side);
    separate_side(set, cut, split_here.defs, split_here.approx, side, first_cap, solid.convex, shells,
                  below ? chords_here.below_keys : chords_here.above_keys, below ? result.below : result.above);
  };
  // The two sides of a large solid (the first cuts of a build, whose pieces are
  // few and large: its serial part) are separated in parallel; each is a pure
  // function of the split, so the pieces are the same either way, and so is
  // what is thrown: the below side's refusal first, as in turn. Isolated: a
  // thread waiting here runs no other cut, which would overwrite the scratch
  // both sides read.
  constexpr std::size_t parallel_faces = 1024;
  if (sides == CutSides::both && solid.faces.size() >= parallel_faces) {
    std::exception_ptr failed[2];
    const auto separate_or_keep = [&](bool below) {
      try {
        separate(below);
      } catch (...) {
        failed[below ? 0 : 1] = std::current_exception();
      }
    };
    tbb::this_task_arena::isolate(
        [&] { tbb::parallel_invoke([&] { separate_or_keep(true); }, [&] { separate_or_keep(false); }); });
    for (const std::exception_ptr& e : failed) {
      if (e) std::rethrow_exception(e);
    }
    return result;
  }
  for (const bool below : {true, false}) {
    if (sides != (below ? CutSides::above : CutSides::below)) separate(below);
  }
  return result;
}

}  // namespace shatter
