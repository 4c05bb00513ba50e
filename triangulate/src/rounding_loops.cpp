// Loops over merged vertices: snap rounding's repairs of a face's loops, and
// faces rounded onto one plane or folded, merged. See rounding.hpp.
#include "rounding.hpp"
#include "rounding_exact.hpp"

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "shatter/kernel/predicates.hpp"
#include "shatter/kernel/projection_exact.hpp"
#include "shatter/kernel/snap_predicates.hpp"
#include "shatter/kernel/union_find.hpp"

namespace shatter {

// --- Loops over merged vertices ---------------------------------------------------
// When vertices merge (rounded onto one point), the faces' loops over the
// representatives can stop being simple polygons, as in snap rounding in the
// plane (Hobby 1999; Halperin & Packer 2002's iterated form), and they are
// repaired the way snap rounding repairs segments, all decided on the rounded
// doubles by exact predicates:
// 1. A vertex lying exactly inside an edge (collinear and strictly between its
//    ends) is inserted into the edge, in every loop that has the edge: the edge
//    passes through that "hot pixel". A face that rounded onto the edges around
//    it then runs forth and back along them, and its neighbours on both sides
//    share vertices again.
// 2. Spikes x -> y -> x (an edge run forth and back) are removed, repeatedly:
//    they enclose nothing. A loop left with fewer than 3 corners vanishes. Two
//    loops of a face that run one edge both ways (a hole rounded against the
//    outer loop) are joined across it: the edge bounds the face on neither side.
// 3. A loop through one vertex twice (two parts that rounding made touch) is
//    split there into simple loops, each triangulated on its own; the vertex is
//    then pinched, which the separation below handles.
// Each step only removes corners, or inserts a vertex into an edge that passes
// through it, so it ends; it changes no position.

// (Step 1's test is the kernel's strictly_inside_segment.)

namespace rounding {

namespace {

// Step 2's spikes: x -> y -> x (an edge run forth and back) and repeated
// corners, removed until none is left.
void remove_spikes(std::vector<VertexIndex>& loop) {
  bool changed = true;
  while (changed && loop.size() >= 3) {
    changed = false;
    for (std::size_t i = 0; i < loop.size() && loop.size() >= 3; ++i) {
      const std::size_t k = loop.size();
      if (loop[i] == loop[(i + 2) % k]) {
        // x y x: drop y and the second x.
        const std::size_t y = (i + 1) % k, x2 = (i + 2) % k;
        loop.erase(loop.begin() + static_cast<std::ptrdiff_t>(std::max(y, x2)));
        loop.erase(loop.begin() + static_cast<std::ptrdiff_t>(std::min(y, x2)));
        changed = true;
      } else if (loop[i] == loop[(i + 1) % k]) {
        loop.erase(loop.begin() + static_cast<std::ptrdiff_t>((i + 1) % k));
        changed = true;
      }
    }
  }
}

// Step 2's edges run both ways: when one loop of a face runs a -> b and another
// runs b -> a (a hole that rounding laid against the outer loop, or two holes
// against each other), the two edges bound the face's region on no side, as a
// spike does, and cancel: the loops are joined into one across them (the face's
// region, as the sum of its oriented loops, is unchanged). Joins the first such
// pair; returns whether it found one.
bool join_at_antiparallel_edge(std::vector<std::vector<VertexIndex>>& face) {
  for (std::size_t p = 0; p < face.size(); ++p) {
    const std::vector<VertexIndex>& first = face[p];
    for (std::size_t i = 0; i < first.size(); ++i) {
      const VertexIndex a = first[i], b = first[(i + 1) % first.size()];
      for (std::size_t q = 0; q < face.size(); ++q) {
        if (q == p) continue;
        const std::vector<VertexIndex>& second = face[q];
        for (std::size_t j = 0; j < second.size(); ++j) {
          if (second[j] != b || second[(j + 1) % second.size()] != a) continue;
          // first from b round to a, then second from a round to just before b.
          std::vector<VertexIndex> joined;
          for (std::size_t k = 0; k < first.size(); ++k) joined.push_back(first[(i + 1 + k) % first.size()]);
          for (std::size_t k = 1; k + 1 < second.size(); ++k) joined.push_back(second[(j + 1 + k) % second.size()]);
          face[p] = std::move(joined);
          face.erase(face.begin() + static_cast<std::ptrdiff_t>(q));
          return true;
        }
      }
    }
  }
  return false;
}

// The same within one loop: a loop that runs an edge a -> b and later b -> a
// (a face of a merged group that lies between two others along the edge, so
// that the group's sum crosses it twice) bounds the sum's region on neither side
// there; the two edges cancel and the loop falls into the two loops on either
// side of them. Splits the first such loop; returns whether it found one.
bool split_at_antiparallel_edge(std::vector<std::vector<VertexIndex>>& face) {
  for (std::size_t p = 0; p < face.size(); ++p) {
    const std::vector<VertexIndex>& loop = face[p];
    const std::size_t k = loop.size();
    for (std::size_t i = 0; i < k; ++i) {
      const VertexIndex a = loop[i], b = loop[(i + 1) % k];
      for (std::size_t j = i + 1; j < k; ++j) {
        if (loop[j] != b || loop[(j + 1) % k] != a) continue;
        // loop[i + 1 .. j - 1] (from b round to just before b) and loop[j + 1 .. i - 1]
        // (from a round to just before a), cyclically.
        std::vector<VertexIndex> inner(loop.begin() + static_cast<std::ptrdiff_t>(i + 1),
                                       loop.begin() + static_cast<std::ptrdiff_t>(j));
        std::vector<VertexIndex> outer;
        for (std::size_t m = (j + 1) % k; m != i; m = (m + 1) % k) outer.push_back(loop[m]);
        face[p] = std::move(inner);
        face.push_back(std::move(outer));
        return true;
      }
    }
  }
  return false;
}

// Rewrites every loop of every face, putting after each corner a the vertices
// `inserted(a, b)` names for its edge to the next corner b, in their order.
template <class InsertedFn>
void insert_along_loop_edges(std::vector<std::vector<std::vector<VertexIndex>>>& loops, InsertedFn&& inserted) {
  for (auto& face : loops) {
    for (auto& loop : face) {
      std::vector<VertexIndex> out;
      for (std::size_t i = 0; i < loop.size(); ++i) {
        const VertexIndex a = loop[i], b = loop[(i + 1) % loop.size()];
        out.push_back(a);
        const std::vector<VertexIndex> inside = inserted(a, b);
        out.insert(out.end(), inside.begin(), inside.end());
      }
      loop = std::move(out);
    }
  }
}

}  // namespace

void repair_merged_loops(std::span<const Vec3> positions, std::vector<std::vector<std::vector<VertexIndex>>>& loops,
                         std::span<const VertexIndex> candidates, const mpq_class* near) {
  // Within `near` of the line of a -> b and strictly between a and b along it.
  const std::optional<SegmentReach> near_segment =
      near != nullptr ? std::optional<SegmentReach>(SegmentReach(*near)) : std::nullopt;
  const double margin = near != nullptr ? 2 * near->get_d() : 0;
  // The candidates by x, so that each edge visits only those within its box's x range.
  std::vector<VertexIndex> by_x(candidates.begin(), candidates.end());
  std::sort(by_x.begin(), by_x.end(), [&](VertexIndex u, VertexIndex w) {
    return positions[u].x != positions[w].x ? positions[u].x < positions[w].x : u < w;
  });
  // 1. Vertices inside edges.
  insert_along_loop_edges(loops, [&](VertexIndex a, VertexIndex b) {
    const Vec3 &pa = positions[a], &pb = positions[b];
    const Vec3 lo{std::min(pa.x, pb.x) - margin, std::min(pa.y, pb.y) - margin, std::min(pa.z, pb.z) - margin};
    const Vec3 hi{std::max(pa.x, pb.x) + margin, std::max(pa.y, pb.y) + margin, std::max(pa.z, pb.z) + margin};
    std::vector<VertexIndex> inside;
    const auto first = std::lower_bound(by_x.begin(), by_x.end(), lo.x,
                                        [&](VertexIndex v, double x) { return positions[v].x < x; });
    for (auto it = first; it != by_x.end() && positions[*it].x <= hi.x; ++it) {
      const VertexIndex v = *it;
      const Vec3& p = positions[v];
      if (v == a || v == b || p.x < lo.x || p.x > hi.x || p.y < lo.y || p.y > hi.y || p.z < lo.z || p.z > hi.z) {
        continue;
      }
      if (strictly_inside_segment(pa, pb, p) || (near_segment && near_segment->within(pa, pb, p))) inside.push_back(v);
    }
    // In order from a to b, along the first coordinate where they differ
    // (exact comparisons of the doubles themselves); near the edge but off its
    // line, by the projection onto it (exactly), ties by index, so that both
    // ways of an edge take the same vertices in reverse order.
    const auto get = pa.x != pb.x ? &Vec3::x : pa.y != pb.y ? &Vec3::y : &Vec3::z;
    const bool rising = pa.*get < pb.*get;
    if (near == nullptr) {
      std::sort(inside.begin(), inside.end(), [&](VertexIndex u, VertexIndex w) {
        return rising ? positions[u].*get < positions[w].*get : positions[u].*get > positions[w].*get;
      });
    } else {
      // The projection from the edge's smaller end, so that both ways agree.
      const Vec3& from = a < b ? pa : pb;
      const Vec3& to = a < b ? pb : pa;
      std::sort(inside.begin(), inside.end(), [&](VertexIndex u, VertexIndex w) {
        const Sign order = compare_along_direction(from, to, positions[u], positions[w]);
        return order != Sign::zero ? order == Sign::negative : u < w;
      });
      if (b < a) std::reverse(inside.begin(), inside.end());
    }
    inside.erase(std::unique(inside.begin(), inside.end()), inside.end());
    return inside;
  });
  // 2. Spikes, edges run both ways by two loops, and 3. loops through a vertex twice.
  for (auto& face : loops) {
    for (bool again = true; again;) {
      for (auto& loop : face) remove_spikes(loop);
      std::erase_if(face, [](const std::vector<VertexIndex>& loop) { return loop.size() < 3; });
      again = join_at_antiparallel_edge(face);
    }
    std::vector<std::vector<VertexIndex>> simple;
    for (auto& loop : face) {
      if (loop.size() < 3) continue;
      // Split at the first repeated vertex until none is left.
      std::vector<std::vector<VertexIndex>> pending{std::move(loop)};
      while (!pending.empty()) {
        std::vector<VertexIndex> current = std::move(pending.back());
        pending.pop_back();
        bool split = false;
        for (std::size_t i = 0; i < current.size() && !split; ++i) {
          for (std::size_t j = i + 1; j < current.size(); ++j) {
            if (current[i] != current[j]) continue;
            std::vector<VertexIndex> inner(current.begin() + static_cast<std::ptrdiff_t>(i),
                                           current.begin() + static_cast<std::ptrdiff_t>(j));
            current.erase(current.begin() + static_cast<std::ptrdiff_t>(i),
                          current.begin() + static_cast<std::ptrdiff_t>(j));
            if (inner.size() >= 3) pending.push_back(std::move(inner));
            if (current.size() >= 3) pending.push_back(std::move(current));
            split = true;
            break;
          }
        }
        if (!split && current.size() >= 3) simple.push_back(std::move(current));
      }
    }
    face = std::move(simple);
  }
}

bool route_edges_through_crossed_corners(const PlaneSet& set, const Solid& solid, std::span<const PointDef> placed,
                                         std::span<const Vec3> positions,
                                         std::vector<std::vector<std::vector<VertexIndex>>>& loops) {
  std::vector<std::optional<ExactPoint>> exact(positions.size());
  const auto exact_of = [&](VertexIndex v) -> const ExactPoint& {
    if (!exact[v]) exact[v] = exact_point(set, placed[v]);
    return *exact[v];
  };
  // Edge (a, b) as a directed key -> the corners to route it through.
  std::unordered_map<std::uint64_t, std::vector<VertexIndex>> through;
  const auto key = [](VertexIndex a, VertexIndex b) { return (std::uint64_t{a} << 32) | b; };
  for (std::uint32_t f = 0; f < loops.size(); ++f) {
    const Projection projection = projection_of(set, solid.faces[f].plane);
    const int u = (projection.axis + 1) % 3, w = (projection.axis + 2) % 3;
    const PlaneProjection kept{u, w};
    std::vector<VertexIndex> corners;
    for (const auto& loop : loops[f]) corners.insert(corners.end(), loop.begin(), loop.end());
    for (const auto& loop : loops[f]) {
      for (std::size_t i = 0; i < loop.size(); ++i) {
        const VertexIndex a = loop[i], b = loop[(i + 1) % loop.size()];
        const Vec3 &pa = positions[a], &pb = positions[b];
        double magnitude = 0;
        for (int k = 0; k < 3; ++k) magnitude = std::max({magnitude, std::fabs(pa[k]), std::fabs(pb[k])});
        const double margin = std::ldexp(magnitude, -30);
        for (const VertexIndex v : corners) {
          if (v == a || v == b) continue;
          const Vec3& pv = positions[v];
          bool near = true;
          for (int k = 0; k < 3; ++k) {
            near = near && pv[k] >= std::min(pa[k], pb[k]) - margin && pv[k] <= std::max(pa[k], pb[k]) + margin;
          }
          if (!near) continue;
          const Sign rounded = orient2d(kept(pa), kept(pb), kept(pv));
          if (rounded == Sign::zero) continue;  // on the line: step 1's case
          const Sign before = orientation_in_projection(kept, exact_of(a), exact_of(b), exact_of(v));
          if (before == Sign::zero || before == rounded) continue;
          // Strictly between a and b along the edge, exactly.
          if (projects_strictly_inside_segment(pa, pb, pv)) through[key(a, b)].push_back(v);
        }
      }
    }
  }
  if (through.empty()) return false;
  // Both directions of an edge take the same corners, in order along it (by the
  // square of the distance from its start, exactly on the doubles).
  insert_along_loop_edges(loops, [&](VertexIndex a, VertexIndex b) {
    std::vector<VertexIndex> inside;
    for (const std::uint64_t k : {key(a, b), key(b, a)}) {
      if (const auto it = through.find(k); it != through.end()) inside.insert(inside.end(), it->second.begin(), it->second.end());
    }
    if (inside.empty()) return inside;
    std::sort(inside.begin(), inside.end());
    inside.erase(std::unique(inside.begin(), inside.end()), inside.end());
    const Vec3& pa = positions[a];
    std::stable_sort(inside.begin(), inside.end(), [&](VertexIndex x, VertexIndex y) {
      return compare_distance_to(pa, positions[x], positions[y]) == Sign::negative;
    });
    return inside;
  });
  return true;
}

namespace {

// The faces of `group` (indices into `loops`, each written as the face
// `emit_as` names) merged into one face: as 2-chains on a common plane they add
// up to the sum of their loops as traversed, in which an edge run both ways
// cancels (join_at_antiparallel_edge, spikes). The merged face faces the way of
// the member whose outward side its loops turn counter-clockwise about (the
// exact signed area of the loops on the doubles, in that member's projection),
// is held by the group's first face and written as that member; when nothing
// is left (or nothing turns one way) the group vanishes whole. `home[f]`: the
// face holding f's loops afterwards (the group's first, or no_index when it
// vanished). `caps_first`: a member on a cut plane that sees the loops
// counter-clockwise is preferred to the group's order. Changes no position.
void merge_face_group(const PlaneSet& set, const Solid& solid, std::span<const Vec3> positions,
                      std::span<const std::uint32_t> group, std::vector<std::vector<std::vector<VertexIndex>>>& loops,
                      std::vector<std::uint8_t>& changed, std::vector<std::uint32_t>& emit_as,
                      std::vector<std::uint32_t>& home, bool caps_first = false) {
  std::vector<std::vector<VertexIndex>> sum;
  for (const std::uint32_t f : group) sum.insert(sum.end(), loops[f].begin(), loops[f].end());
  for (bool again = true; again;) {
    for (auto& loop : sum) remove_spikes(loop);
    std::erase_if(sum, [](const std::vector<VertexIndex>& loop) { return loop.size() < 3; });
    again = join_at_antiparallel_edge(sum) || split_at_antiparallel_edge(sum);
  }
  // Which way the loops turn in face f's projection, seen from its outside.
  const auto turn_seen_from = [&](std::uint32_t f) {
    const Sign s = loops_orientation(positions, sum, projection_of(set, solid.faces[f].plane));
    return solid.faces[f].reversed ? flip(s) : s;
  };
  // The first member (of those on a cut plane when `caps_only`) that sees the
  // loops counter-clockwise, or no_index.
  const auto first_seeing = [&](bool caps_only) {
    for (const std::uint32_t f : group) {
      if ((!caps_only || solid.faces[emit_as[f]].plane.is_cut()) && turn_seen_from(emit_as[f]) == Sign::positive) {
        return emit_as[f];
      }
    }
    return no_index;
  };
  std::uint32_t as = caps_first ? first_seeing(true) : no_index;
  if (as == no_index) as = first_seeing(false);
  const std::uint32_t first = group.front();
  for (const std::uint32_t f : group) {
    emit_as[f] = no_index;
    loops[f].clear();
  }
  for (std::uint32_t& h : home) {
    if (h != no_index && std::find(group.begin(), group.end(), h) != group.end()) h = as == no_index ? no_index : first;
  }
  if (as == no_index) return;  // nothing left, or nothing facing one way: the group vanishes
  emit_as[first] = as;
  loops[first] = std::move(sum);
  changed[first] = 1;
}

}  // namespace

bool merge_coplanar_sheets(const PlaneSet& set, const Solid& solid, std::span<const Vec3> positions,
                           std::vector<std::vector<std::vector<VertexIndex>>>& loops,
                           std::vector<std::uint8_t>& changed, std::vector<std::uint32_t>& emit_as,
                           std::vector<std::uint32_t>& home) {
  const auto count = static_cast<std::uint32_t>(loops.size());
  emit_as.resize(count);
  home.resize(count);
  for (std::uint32_t f = 0; f < count; ++f) emit_as[f] = home[f] = f;
  std::unordered_map<std::uint64_t, std::uint32_t> face_of_edge;
  const auto key = [](VertexIndex a, VertexIndex b) { return (std::uint64_t{a} << 32) | b; };
  for (std::uint32_t f = 0; f < count; ++f) {
    for (const auto& loop : loops[f]) {
      for (std::size_t i = 0; i < loop.size(); ++i) face_of_edge[key(loop[i], loop[(i + 1) % loop.size()])] = f;
    }
  }
  // Three corners of a face's loops that are not collinear on the doubles.
  const auto frame = [&](std::uint32_t f) -> std::optional<std::array<VertexIndex, 3>> {
    std::vector<VertexIndex> corners;
    for (const auto& loop : loops[f]) corners.insert(corners.end(), loop.begin(), loop.end());
    if (corners.size() < 3) return std::nullopt;
    const Vec3 &a = positions[corners[0]];
    for (std::size_t j = 1; j < corners.size(); ++j) {
      for (std::size_t k = j + 1; k < corners.size(); ++k) {
        if (!collinear(a, positions[corners[j]], positions[corners[k]])) {
          return std::array<VertexIndex, 3>{corners[0], corners[j], corners[k]};
        }
      }
    }
    return std::nullopt;
  };
  const auto on_plane_of = [&](const std::array<VertexIndex, 3>& t, std::uint32_t g) {
    for (const auto& loop : loops[g]) {
      for (const VertexIndex v : loop) {
        if (orient3d(positions[t[0]], positions[t[1]], positions[t[2]], positions[v]) != Sign::zero) return false;
      }
    }
    return true;
  };
  // Outward normals of two faces point the same way (exactly).
  const auto same_facing = [&](std::uint32_t f, std::uint32_t g) {
    const bool same_plane = compare_normals(set, solid.faces[f].plane, solid.faces[g].plane) == Sign::positive;
    return same_plane == (solid.faces[f].reversed == solid.faces[g].reversed);
  };
  UnionFind groups;
  groups.reset(count);
  std::vector<std::optional<std::array<VertexIndex, 3>>> frames(count);
  std::vector<std::uint8_t> framed(count, 0), opposite(count, 0);
  bool any = false;
  for (std::uint32_t f = 0; f < count; ++f) {
    for (const auto& loop : loops[f]) {
      for (std::size_t i = 0; i < loop.size(); ++i) {
        const auto it = face_of_edge.find(key(loop[(i + 1) % loop.size()], loop[i]));
        if (it == face_of_edge.end()) continue;
        const std::uint32_t g = it->second;
        if (g == f || groups.find(f) == groups.find(g)) continue;
        if (!framed[f]) frames[f] = frame(f), framed[f] = 1;
        if (!frames[f] || !on_plane_of(*frames[f], g)) continue;
        const std::uint32_t rf = groups.find(f), rg = groups.find(g);
        const bool flips = !same_facing(f, g);
        groups.unite(f, g);
        opposite[groups.find(f)] = opposite[rf] || opposite[rg] || flips;
        any = true;
      }
    }
  }
  if (!any) return false;
  bool merged_any = false;
  std::vector<std::vector<std::uint32_t>> members(count);
  for (std::uint32_t f = 0; f < count; ++f) members[groups.find(f)].push_back(f);
  for (std::uint32_t root = 0; root < count; ++root) {
    const std::vector<std::uint32_t>& group = members[root];
    if (group.size() < 2 || !opposite[root]) continue;
    merge_face_group(set, solid, positions, group, loops, changed, emit_as, home);
    merged_any = true;
  }
  return merged_any;
}

std::size_t merge_folded_faces(const PlaneSet& set, const Solid& solid, std::span<const Vec3> positions,
                        std::vector<std::vector<std::vector<VertexIndex>>>& loops, std::vector<std::uint8_t>& changed,
                        std::vector<std::uint32_t>& emit_as, std::vector<std::uint32_t>& home,
                        std::span<const std::pair<std::uint32_t, std::uint32_t>> folds, bool thin_only,
                        bool apart_too, FoldMerge mode) {
  const bool by_members = mode != FoldMerge::pairs;
  const auto count = static_cast<std::uint32_t>(loops.size());
  std::unordered_map<std::uint64_t, std::uint32_t> face_of_edge;
  const auto key = [](VertexIndex a, VertexIndex b) { return (std::uint64_t{a} << 32) | b; };
  for (std::uint32_t f = 0; f < count; ++f) {
    for (const auto& loop : loops[f]) {
      for (std::size_t i = 0; i < loop.size(); ++i) face_of_edge[key(loop[i], loop[(i + 1) % loop.size()])] = f;
    }
  }
  const auto share_edge = [&](std::uint32_t f, std::uint32_t g) {
    for (const auto& loop : loops[f]) {
      for (std::size_t i = 0; i < loop.size(); ++i) {
        const auto it = face_of_edge.find(key(loop[(i + 1) % loop.size()], loop[i]));
        if (it != face_of_edge.end() && it->second == g) return true;
      }
    }
    return false;
  };
  UnionFind groups;
  groups.reset(count);
  bool any = false;
  std::optional<RoundingReach> reach;
  if (by_members) {
    // Whether faces x and y (holding loops) may merge: as below, pair by pair,
    // but for faces facing one way (groups_one_way, thin only).
    const auto mergeable = [&](std::uint32_t x, std::uint32_t y) {
      if (!(apart_too && thin_only) && !share_edge(x, y)) return false;
      const SolidFace &a = solid.faces[emit_as[x]], &b = solid.faces[emit_as[y]];
      const Sign facing = compare_outward_normals(set, a, b);
      if (facing == Sign::zero) return false;
      const bool one_way = facing == Sign::positive;
      if (one_way && mode != FoldMerge::groups_one_way) return false;
      if (!thin_only && !one_way) return true;
      if (!reach) reach.emplace(set, solid, positions);
      return reach->within(loops[y], a.plane) || reach->within(loops[x], b.plane);
    };
    // The faces holding loops in each group, kept by the group's representative
    // (the union-find's smallest index), so a pair looks only at its two groups.
    std::vector<std::vector<std::uint32_t>> holding(count);
    for (std::uint32_t x = 0; x < count; ++x) {
      if (!loops[x].empty()) holding[x].push_back(x);
    }
    for (bool progress = true; progress;) {
      progress = false;
      for (const auto& [f, g] : folds) {
        if (f >= count || g >= count) continue;
        const std::uint32_t hf = home[f], hg = home[g];
        if (hf == no_index || hg == no_index || hf == hg) continue;
        const std::uint32_t rf = groups.find(hf), rg = groups.find(hg);
        if (rf == rg) continue;
        bool joined = false;
        for (std::size_t i = 0; i < holding[rf].size() && !joined; ++i) {
          for (std::size_t j = 0; j < holding[rg].size() && !joined; ++j) {
            joined = mergeable(holding[rf][i], holding[rg][j]);
          }
        }
        if (!joined) continue;
        groups.unite(rf, rg);
        const std::uint32_t kept = std::min(rf, rg), gone = std::max(rf, rg);
        holding[kept].insert(holding[kept].end(), holding[gone].begin(), holding[gone].end());
        holding[gone].clear();
        any = progress = true;
      }
    }
  }
  for (const auto& [f, g] : by_members ? std::span<const std::pair<std::uint32_t, std::uint32_t>>() : folds) {
    if (f >= count || g >= count) continue;
    const std::uint32_t hf = home[f], hg = home[g];
    if (hf == no_index || hg == no_index || hf == hg || groups.find(hf) == groups.find(hg)) continue;
    if (!(apart_too && thin_only) && !share_edge(hf, hg)) continue;
    // Facing opposite ways (their outward normals' dot product negative,
    // exactly): the solid lies between them, in the wedge. Two faces facing one
    // way crowd an edge only beside such a wedge; merging them would fill
    // what lies outside the solid between them.
    const SolidFace &a = solid.faces[emit_as[hf]], &b = solid.faces[emit_as[hg]];
    if (compare_outward_normals(set, a, b) != Sign::negative) continue;
    if (thin_only) {
      if (!reach) reach.emplace(set, solid, positions);
      if (!reach->within(loops[hg], a.plane) && !reach->within(loops[hf], b.plane)) continue;
    }
    groups.unite(hf, hg);
    any = true;
  }
  if (!any) return 0;
  std::vector<std::vector<std::uint32_t>> members(count);
  for (std::uint32_t f = 0; f < count; ++f) {
    if (!loops[f].empty()) members[groups.find(f)].push_back(f);
  }
  std::size_t merged = 0;
  for (const std::vector<std::uint32_t>& group : members) {
    if (group.size() < 2) continue;
    merge_face_group(set, solid, positions, group, loops, changed, emit_as, home, by_members);
    merged += group.size();
  }
  return merged;
}

}  // namespace rounding

}  // namespace shatter
