// Gluing Voronoi fragments (voronoi_glue.hpp says why it is exact).

#include "voronoi_glue.hpp"

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "shatter/kernel/union_find.hpp"

namespace shatter::detail {
namespace {

struct DefHash {
  std::size_t operator()(const PointDef& d) const {
    std::uint64_t h = static_cast<std::uint64_t>(d.kind) * 0x9E3779B97F4A7C15ull;
    const auto mix = [&](std::uint64_t x) { h = (h ^ x) * 0xBF58476D1CE4E5B9ull; h ^= h >> 31; };
    mix(d.a);
    mix(d.b);
    for (const PlaneRef p : d.planes) mix(p.bits);
    return static_cast<std::size_t>(h);
  }
};

bool is_pair(const std::array<std::uint32_t, 2>& pair) { return pair[0] != no_index; }

bool holds(std::span<const std::uint32_t> sites, std::uint32_t site) {
  return std::binary_search(sites.begin(), sites.end(), site);
}

// The site across a face of part `part` on a bisector: the one of the plane's two
// sites that is not the part's; no_index when the face is on no bisector, or
// when the part holds both sites (a face whose twin is missing).
std::uint32_t site_across(const GluePart& part, const SolidFace& face, SitePairs pairs) {
  if (!face.plane.is_cut() || face.plane.index() >= pairs.size()) return no_index;
  const auto& pair = pairs[face.plane.index()];
  if (!is_pair(pair)) return no_index;
  const bool first = holds(part.sites, pair[0]), second = holds(part.sites, pair[1]);
  if (first == second) return no_index;
  return first ? pair[1] : pair[0];
}

// Site -> the parts holding it (several for a cell split into several
// fragments), as a sorted list.
class PartsOfSite {
 public:
  explicit PartsOfSite(std::span<const GluePart> parts) {
    for (std::uint32_t i = 0; i < parts.size(); ++i) {
      for (const std::uint32_t s : parts[i].sites) entries_.push_back({s, i});
    }
    std::sort(entries_.begin(), entries_.end());
  }
  /// The parts holding `site`, in increasing order.
  std::span<const std::array<std::uint32_t, 2>> operator()(std::uint32_t site) const {
    const auto begin = std::lower_bound(entries_.begin(), entries_.end(), std::array<std::uint32_t, 2>{site, 0});
    auto end = begin;
    while (end != entries_.end() && (*end)[0] == site) ++end;
    return {begin, end};
  }

 private:
  std::vector<std::array<std::uint32_t, 2>> entries_;
};

// Whether two defined points are one point, decided exactly. A three_planes
// point is the only point on its three (independent) planes; a segment_plane
// point is the only point of its segment's line on its plane. Points of
// different input segments, or an input point and a segment's inner point, are
// taken as different: in an embedded input they are (a self-intersecting input
// may give a false "different", which only leaves parts unglued, never a wrong
// union).
bool same_point(const PlaneSet& set, const PointDef& p, const ApproxPoint& pa, const PointDef& q, const ApproxPoint& qa) {
  if (p == q) return true;
  const auto on_all = [&](const PointDef& definer, const PointDef& point, const ApproxPoint& approx) {
    for (const PlaneRef plane : definer.planes) {
      if (side(set, plane, point, approx) != Sign::zero) return false;
    }
    return true;
  };
  if (q.kind == PointKind::three_planes) return on_all(q, p, pa);
  if (p.kind == PointKind::three_planes) return on_all(p, q, qa);
  if (p.kind == PointKind::segment_plane && q.kind == PointKind::segment_plane && p.a == q.a && p.b == q.b) {
    return side(set, q.planes[0], p, pa) == Sign::zero;
  }
  return false;
}

std::uint64_t edge_key(std::uint32_t from, std::uint32_t to) { return (std::uint64_t{from} << 32) | to; }

}  // namespace

std::vector<std::vector<std::uint32_t>> face_connected_groups(std::span<const GluePart> parts, SitePairs pairs) {
  const PartsOfSite parts_of(parts);
  UnionFind groups(parts.size());
  for (std::uint32_t i = 0; i < parts.size(); ++i) {
    for (const SolidFace& face : parts[i].solid->faces) {
      const std::uint32_t across = site_across(parts[i], face, pairs);
      if (across == no_index) continue;
      for (const auto& [site, j] : parts_of(across)) groups.unite(i, j);
    }
  }
  std::vector<std::vector<std::uint32_t>> out;
  std::vector<std::uint32_t> slot(parts.size(), no_index);
  for (std::uint32_t i = 0; i < parts.size(); ++i) {
    const std::uint32_t root = groups.find(i);  // the smallest index: a group's first part
    if (slot[root] == no_index) {
      slot[root] = static_cast<std::uint32_t>(out.size());
      out.emplace_back();
    }
    out[slot[root]].push_back(i);
  }
  return out;
}

namespace {

// A corner of a glued loop under its edge's undirected key (the smaller vertex
// first); `forward` when the corner's edge runs from the smaller to the larger.
struct CornerOfEdge {
  std::uint64_t key;
  std::uint32_t corner;
  bool forward;
};

// glue_parts' working arrays, kept per thread between calls: a hierarchy glues
// thousands of sets, and fresh large allocations each cost their pages'
// zeroing again (a third of the gluing's time when allocated per call).
struct GlueScratch {
  std::vector<std::uint32_t> first_vertex, first_face, id, owner, number, next_corner;
  std::unordered_map<PointDef, std::uint32_t, DefHash> by_def;
  UnionFind same;
  std::vector<char> deleted, seen, has_fan;
  std::vector<std::uint64_t> one, other;
  std::vector<Vec3> positions;  // per id, rounded
  std::vector<std::pair<std::array<std::int64_t, 3>, std::uint32_t>> grid;  // (cell, id), sorted
  std::vector<CornerOfEdge> edges;  // sorted by edge, then direction
  std::vector<std::uint32_t> reverse_of;  // per corner, the corner running its edge the other way
};

}  // namespace

std::optional<Solid> glue_parts(const PlaneSet& set, std::span<const GluePart> parts, SitePairs pairs, std::string& why,
                                std::vector<std::array<std::uint32_t, 2>>* face_origin,
                                std::vector<std::uint32_t>* vertex_of) {
  const PartsOfSite parts_of(parts);
  thread_local GlueScratch scratch;
  // Plain references, not a structured binding: lambdas below capture them
  // (clang 14, which the sanitized build uses, cannot capture a binding).
  auto& first_vertex = scratch.first_vertex;
  auto& first_face = scratch.first_face;
  auto& id = scratch.id;
  auto& owner = scratch.owner;
  auto& number = scratch.number;
  auto& next_corner = scratch.next_corner;
  auto& by_def = scratch.by_def;
  auto& same = scratch.same;
  auto& deleted = scratch.deleted;
  auto& seen = scratch.seen;
  auto& has_fan = scratch.has_fan;
  auto& one = scratch.one;
  auto& other = scratch.other;
  auto& positions = scratch.positions;
  auto& grid = scratch.grid;
  auto& edges = scratch.edges;
  auto& reverse_of = scratch.reverse_of;

  // Every vertex of every part gets a global id; equal definitions share one.
  first_vertex.assign(parts.size() + 1, 0);
  first_face.assign(parts.size() + 1, 0);
  for (std::size_t i = 0; i < parts.size(); ++i) {
    first_vertex[i + 1] = first_vertex[i] + static_cast<std::uint32_t>(parts[i].solid->defs.size());
    first_face[i + 1] = first_face[i] + static_cast<std::uint32_t>(parts[i].solid->faces.size());
  }
  id.resize(first_vertex.back());
  owner.clear();  // per id: the global vertex (part's first + v) that defines it
  {
    by_def.clear();
    by_def.reserve(first_vertex.back());
    for (std::uint32_t i = 0; i < parts.size(); ++i) {
      const Solid& solid = *parts[i].solid;
      for (std::uint32_t v = 0; v < solid.defs.size(); ++v) {
        const auto [it, inserted] = by_def.emplace(solid.defs[v], static_cast<std::uint32_t>(owner.size()));
        if (inserted) owner.push_back(first_vertex[i] + v);
        id[first_vertex[i] + v] = it->second;
      }
    }
  }
  const auto part_and_vertex = [&](std::uint32_t global) {
    const auto i = static_cast<std::uint32_t>(std::upper_bound(first_vertex.begin(), first_vertex.end(), global) - first_vertex.begin() - 1);
    return std::array<std::uint32_t, 2>{i, global - first_vertex[i]};
  };
  same.reset(owner.size());

  // The twin faces: per bisector, the faces of the parts on either side.
  struct Twin {
    std::uint32_t plane, part, face;
  };
  std::vector<Twin> twins;
  deleted.assign(first_face.back(), 0);  // per part's face (first_face[part] + f)
  for (std::uint32_t i = 0; i < parts.size(); ++i) {
    const Solid& solid = *parts[i].solid;
    for (std::uint32_t f = 0; f < solid.faces.size(); ++f) {
      const std::uint32_t across = site_across(parts[i], solid.faces[f], pairs);
      if (across == no_index || parts_of(across).empty()) continue;
      twins.push_back({solid.faces[f].plane.index(), i, f});
      deleted[first_face[i] + f] = 1;
    }
  }
  std::sort(twins.begin(), twins.end(), [](const Twin& a, const Twin& b) {
    return std::tie(a.plane, a.part, a.face) < std::tie(b.plane, b.part, b.face);
  });

  // The directed edges of a run of twins, over ids: one side's, and the other's reversed.
  const auto gather = [&](std::size_t begin, std::size_t end) {
    one.clear();
    other.clear();
    const std::uint32_t first_site = pairs[twins[begin].plane][0];
    for (std::size_t t = begin; t < end; ++t) {
      const Solid& solid = *parts[twins[t].part].solid;
      const SolidFace& face = solid.faces[twins[t].face];
      const bool first_side = holds(parts[twins[t].part].sites, first_site);
      for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
        for (const CornerEdge& edge : loop_edges(solid.corners, solid.loops[l])) {
          const std::uint32_t u = same.find(id[first_vertex[twins[t].part] + edge.from]);
          const std::uint32_t v = same.find(id[first_vertex[twins[t].part] + edge.to]);
          (first_side ? one : other).push_back(first_side ? edge_key(u, v) : edge_key(v, u));
        }
      }
    }
    std::sort(one.begin(), one.end());
    std::sort(other.begin(), other.end());
  };
  const auto approx_of = [&](std::uint32_t id_root) -> std::pair<const PointDef&, const ApproxPoint&> {
    const auto [i, v] = part_and_vertex(owner[id_root]);
    return {parts[i].solid->defs[v], parts[i].solid->approx[v]};
  };
  // Equal points of different definitions (a point where four or more cells
  // meet, defined from different triples in different parts), wherever the
  // parts meet: candidates are the pairs whose rounded positions are within
  // what rounding can move two copies of one point apart (rounded_position is
  // within 2^-40 of each coordinate's magnitude), each decided exactly.
  {
    positions.resize(owner.size());
    for (std::uint32_t k = 0; k < owner.size(); ++k) {
      const auto [d, a] = approx_of(k);
      positions[k] = rounded_position(set, d, a);
    }
    // Cells 2^8 times the tolerance wide, scaled to the largest coordinate: a
    // pair within tolerance lies in one cell or in neighbouring ones, and a
    // point is rarely within reach of a side, so most points look in their own
    // cell only (at four times the tolerance, most looked in eight or more,
    // each a binary search: 40 % of the gluing's own time). Larger cells only
    // add candidates the `near` filter drops; the pairs tested exactly are the
    // same, and so is the union-find's result (its representatives do not
    // depend on the order of the unions).
    double largest = 0;
    for (const Vec3& p : positions) largest = std::max({largest, std::fabs(p.x), std::fabs(p.y), std::fabs(p.z)});
    const double cell = 0x1p-30 * largest;
    using Key = std::array<std::int64_t, 3>;
    const auto key_of = [&](const Vec3& p) {
      return cell > 0 ? Key{static_cast<std::int64_t>(std::floor(p.x / cell)), static_cast<std::int64_t>(std::floor(p.y / cell)),
                            static_cast<std::int64_t>(std::floor(p.z / cell))}
                      : Key{0, 0, 0};
    };
    // The grid as (cell, id) pairs sorted by cell: a cell's ids are one run.
    grid.clear();
    for (std::uint32_t k = 0; k < positions.size(); ++k) grid.push_back({key_of(positions[k]), k});
    std::sort(grid.begin(), grid.end());
    const auto near = [](double a, double b) { return std::fabs(a - b) <= 0x1p-38 * std::max(std::fabs(a), std::fabs(b)); };
    const auto test_run = [&](std::uint32_t a, auto first, auto last) {
      for (auto entry = first; entry != last; ++entry) {
        const std::uint32_t b = entry->second;
        const Vec3& p = positions[a];
        const Vec3& q = positions[b];
        if (b <= a || !near(p.x, q.x) || !near(p.y, q.y) || !near(p.z, q.z) || same.find(a) == same.find(b)) continue;
        const auto [ad, aa] = approx_of(a);
        const auto [bd, ba] = approx_of(b);
        if (same_point(set, ad, aa, bd, ba)) same.unite(a, b);
      }
    };
    // A point within tolerance of another lies in its cell, or in a neighbour
    // across a side it is within tolerance of: only those cells are looked in.
    // The grid is walked run by run, so a point's own cell is at hand.
    for (std::size_t begin = 0; begin < grid.size();) {
      std::size_t end = begin + 1;
      while (end < grid.size() && grid[end].first == grid[begin].first) ++end;
      const Key key = grid[begin].first;
      for (std::size_t at = begin; at < end; ++at) {
        const std::uint32_t a = grid[at].second;
        std::array<std::array<std::int64_t, 2>, 3> range{};
        for (int axis = 0; axis < 3 && cell > 0; ++axis) {
          const double c = axis == 0 ? positions[a].x : axis == 1 ? positions[a].y : positions[a].z;
          const double reach = 0x1p-38 * std::fabs(c) * 2 + 0x1p-38 * largest;
          range[axis] = {std::floor((c - reach) / cell) < static_cast<double>(key[axis]) ? -1 : 0,
                         std::floor((c + reach) / cell) > static_cast<double>(key[axis]) ? 1 : 0};
        }
        for (std::int64_t dx = range[0][0]; dx <= range[0][1]; ++dx) {
          for (std::int64_t dy = range[1][0]; dy <= range[1][1]; ++dy) {
            for (std::int64_t dz = range[2][0]; dz <= range[2][1]; ++dz) {
              if (dx == 0 && dy == 0 && dz == 0) {
                test_run(a, grid.begin() + static_cast<std::ptrdiff_t>(begin), grid.begin() + static_cast<std::ptrdiff_t>(end));
                continue;
              }
              const Key neighbour{key[0] + dx, key[1] + dy, key[2] + dz};
              const auto run = std::equal_range(grid.begin(), grid.end(), std::pair<Key, std::uint32_t>{neighbour, 0},
                                                [](const auto& x, const auto& y) { return x.first < y.first; });
              test_run(a, run.first, run.second);
            }
          }
        }
      }
      begin = end;
    }
  }
  // Every run of twins on one plane must cancel, edge for edge.
  for (std::size_t begin = 0; begin < twins.size();) {
    std::size_t end = begin;
    while (end < twins.size() && twins[end].plane == twins[begin].plane) ++end;
    gather(begin, end);
    if (one != other) {
      why = "the twin faces on a bisector do not share their boundary edges";
      return std::nullopt;
    }
    begin = end;
  }

  // The kept faces over compact vertex numbers, in part and face order.
  Solid glued;
  {
    // The kept faces' sizes, so no vector is moved while it grows.
    std::size_t faces = 0, loops = 0, corners = 0;
    for (std::uint32_t i = 0; i < parts.size(); ++i) {
      const Solid& solid = *parts[i].solid;
      for (std::uint32_t f = 0; f < solid.faces.size(); ++f) {
        if (deleted[first_face[i] + f]) continue;
        ++faces;
        loops += solid.faces[f].loop_count;
        for (std::uint32_t l = solid.faces[f].first_loop; l < solid.faces[f].first_loop + solid.faces[f].loop_count; ++l) {
          corners += solid.loops[l].corner_count;
        }
      }
    }
    glued.faces.reserve(faces);
    glued.loops.reserve(loops);
    glued.corners.reserve(corners);
    glued.defs.reserve(owner.size());
    glued.approx.reserve(owner.size());
  }
  number.assign(owner.size(), no_index);
  if (face_origin != nullptr) face_origin->clear();
  for (std::uint32_t i = 0; i < parts.size(); ++i) {
    const Solid& solid = *parts[i].solid;
    for (std::uint32_t f = 0; f < solid.faces.size(); ++f) {
      if (deleted[first_face[i] + f]) continue;
      SolidFace face = solid.faces[f];
      face.first_loop = static_cast<std::uint32_t>(glued.loops.size());
      for (std::uint32_t l = solid.faces[f].first_loop; l < solid.faces[f].first_loop + solid.faces[f].loop_count; ++l) {
        const SolidLoop& loop = solid.loops[l];
        glued.loops.push_back({static_cast<std::uint32_t>(glued.corners.size()), loop.corner_count});
        for (std::uint32_t c = loop.first_corner; c < loop.first_corner + loop.corner_count; ++c) {
          SolidCorner corner = solid.corners[c];
          const std::uint32_t root = same.find(id[first_vertex[i] + corner.vertex]);
          if (number[root] == no_index) {
            number[root] = static_cast<std::uint32_t>(glued.defs.size());
            const auto [d, a] = approx_of(root);
            glued.defs.push_back(d);
            glued.approx.push_back(a);
          }
          corner.vertex = number[root];
          glued.corners.push_back(corner);
        }
      }
      glued.faces.push_back(face);
      if (face_origin != nullptr) face_origin->push_back({i, f});
    }
  }

  // Closed and 2-manifold as glued: every directed edge once with its reverse,
  // and one fan of faces around every vertex. The corners sorted by their
  // edge's undirected key put the two runs of an edge side by side, which
  // pairs each corner with its reverse in one pass (a binary search per corner
  // of the fan walk below took a third of the gluing's own time).
  edges.clear();
  next_corner.resize(glued.corners.size());
  for (const SolidLoop& loop : glued.loops) {
    for (const CornerEdge& edge : loop_edges(glued.corners, loop)) {
      if (edge.from == edge.to) {
        why = "a loop runs through one point twice in a row";
        return std::nullopt;
      }
      const bool forward = edge.from < edge.to;
      edges.push_back({forward ? edge_key(edge.from, edge.to) : edge_key(edge.to, edge.from), edge.corner, forward});
      next_corner[edge.corner] = edge.corner + 1 == loop.first_corner + loop.corner_count ? loop.first_corner : edge.corner + 1;
    }
  }
  std::sort(edges.begin(), edges.end(), [](const CornerOfEdge& a, const CornerOfEdge& b) {
    return a.key != b.key ? a.key < b.key : a.forward < b.forward;
  });
  reverse_of.resize(glued.corners.size());
  bool open = false;
  for (std::size_t e = 0; e < edges.size();) {
    std::size_t end = e + 1;
    while (end < edges.size() && edges[end].key == edges[e].key) ++end;
    for (std::size_t k = e + 1; k < end; ++k) {
      if (edges[k].forward == edges[k - 1].forward) {
        why = "the parts touch along an edge only (an edge used twice one way)";
        return std::nullopt;
      }
    }
    if (end - e == 2) {
      reverse_of[edges[e].corner] = edges[e + 1].corner;
      reverse_of[edges[e + 1].corner] = edges[e].corner;
    } else {
      open = true;  // a single run (two runs each way are refused above)
    }
    e = end;
  }
  if (open) {
    why = "the glued surface is open";
    return std::nullopt;
  }
  seen.assign(glued.corners.size(), 0);
  has_fan.assign(glued.defs.size(), 0);
  for (std::uint32_t c = 0; c < glued.corners.size(); ++c) {
    if (seen[c]) continue;
    const VertexIndex v = glued.corners[c].vertex;
    if (has_fan[v]) {
      why = "the parts touch at a point only (a vertex with several fans)";
      return std::nullopt;
    }
    has_fan[v] = 1;
    // Around v: the edge v -> w of corner c, its reverse w -> v, then the edge
    // after that reverse, which leaves v again.
    for (std::uint32_t at = c; !seen[at];) {
      seen[at] = 1;
      at = next_corner[reverse_of[at]];
    }
  }
  if (vertex_of != nullptr) {
    vertex_of->resize(first_vertex.back());
    for (std::uint32_t g = 0; g < first_vertex.back(); ++g) (*vertex_of)[g] = number[same.find(id[g])];
  }
  glued.convex = solid_is_convex(set, glued);
  return glued;
}

}  // namespace shatter::detail
