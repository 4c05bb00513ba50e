// Repairs of a rounded mesh: two-sided sheets cancelled, hot pixels (vertices
// inserted into edges that pass by them, clusters snapped), folds found. See
// rounding.hpp.
#include "rounding.hpp"

#include <algorithm>
#include <type_traits>
#include <unordered_map>

#include "shatter/kernel/predicates.hpp"
#include "shatter/kernel/self_intersections.hpp"
#include "shatter/kernel/snap_predicates.hpp"
#include "shatter/kernel/union_find.hpp"

namespace shatter {

// --- Parts thinner than the rounding --------------------------------------------
// Rounding can flatten a part of a piece that is thinner than the rounding of its
// coordinates: its two sides round onto the same vertices, and the mesh holds the
// same triangle twice, once each way (a two-sided sheet: non-manifold edges where
// it meets the rest, or the whole piece). Such a pair bounds no volume and removing
// it keeps every directed edge matched by its reverse, so the part vanishes into
// its neighbour (the piece across the cut, or the rest of the piece) and what is
// left is certified like any rounding. This is the collapse step of iterated snap
// rounding (Halperin & Packer 2002; in 3D, Lazard & Valque 2025, behind CGAL 6's
// autorefine_triangle_soup): elements that rounding made degenerate are
// eliminated, by index, not by distance.

namespace rounding {

std::size_t cancel_two_sided_sheets(Mesh& mesh, std::vector<VertexIndex>& renumbered, bool quads,
                                    std::vector<std::uint32_t>* kept_triangles, std::size_t* quad_triangles) {
  if (quad_triangles != nullptr) *quad_triangles = 0;
  const std::size_t count = mesh.triangles.size();
  // Key: the triangle rotated to start at its smallest index; its reverse is then
  // (a, c, b) for (a, b, c).
  auto rotated = [](Triangle t) {
    const auto smallest = std::min_element(t.begin(), t.end());
    std::rotate(t.begin(), smallest, t.end());
    return t;
  };
  std::vector<std::uint32_t> order(count);
  for (std::uint32_t t = 0; t < count; ++t) order[t] = t;
  std::vector<Triangle> keys(count);
  for (std::size_t t = 0; t < count; ++t) keys[t] = rotated(mesh.triangles[t]);
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    return keys[a] != keys[b] ? keys[a] < keys[b] : a < b;
  });
  auto find = [&](const Triangle& key) {
    return std::lower_bound(order.begin(), order.end(), key,
                            [&](std::uint32_t t, const Triangle& k) { return keys[t] < k; });
  };
  std::vector<std::uint8_t> removed(count, 0);
  std::size_t gone = 0;
  for (std::uint32_t t = 0; t < count; ++t) {
    if (removed[t]) continue;
    const Triangle& key = keys[t];
    const Triangle reverse{key[0], key[2], key[1]};
    if (reverse == key) continue;  // a repeated index: not a sheet
    for (auto it = find(reverse); it != order.end() && keys[*it] == reverse; ++it) {
      if (!removed[*it]) {
        removed[t] = removed[*it] = 1;
        gone += 2;
        break;
      }
    }
  }
  if (quads) {
    // Directed edge -> the triangles running it, among those left.
    std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> running;
    const auto edge = [](VertexIndex a, VertexIndex b) { return (std::uint64_t{a} << 32) | b; };
    for (std::uint32_t t = 0; t < count; ++t) {
      if (removed[t]) continue;
      for (int c = 0; c < 3; ++c) running[edge(mesh.triangles[t][c], mesh.triangles[t][(c + 1) % 3])].push_back(t);
    }
    const auto unremoved = [&](const Triangle& key) -> std::uint32_t {
      for (auto it = find(rotated(key)); it != order.end() && keys[*it] == rotated(key); ++it) {
        if (!removed[*it]) return *it;
      }
      return no_index;
    };
    for (std::uint32_t t = 0; t < count; ++t) {
      for (int c = 0; c < 3 && !removed[t]; ++c) {
        // t = (a, b, c) with the diagonal c -> a; its partner runs a -> c.
        const VertexIndex a = mesh.triangles[t][c], b = mesh.triangles[t][(c + 1) % 3], cc = mesh.triangles[t][(c + 2) % 3];
        const auto it = running.find(edge(a, cc));
        if (it == running.end()) continue;
        for (const std::uint32_t u : it->second) {
          if (u == t || removed[u]) continue;
          const Triangle& tu = mesh.triangles[u];
          VertexIndex d = no_index;
          for (int k = 0; k < 3; ++k) {
            if (tu[k] != a && tu[k] != cc) d = tu[k];
          }
          if (d == no_index || d == b) continue;
          const std::uint32_t q1 = unremoved({a, d, b});
          const std::uint32_t q2 = unremoved({b, d, cc});
          if (q1 == no_index || q2 == no_index || q1 == q2 || q1 == t || q1 == u || q2 == t || q2 == u) continue;
          // A tetrahedron of its own stays (see above; diplodocus.off).
          const auto alone = [&](VertexIndex x, VertexIndex y) {
            const auto there = running.find(edge(x, y)), back = running.find(edge(y, x));
            return there != running.end() && there->second.size() == 1 && back != running.end() &&
                   back->second.size() == 1;
          };
          if (alone(a, b) && alone(b, cc) && alone(cc, d) && alone(d, a) && alone(a, cc) && alone(b, d) &&
              orient3d(mesh.positions[a], mesh.positions[b], mesh.positions[cc], mesh.positions[d]) != Sign::zero) {
            continue;
          }
          removed[t] = removed[u] = removed[q1] = removed[q2] = 1;
          gone += 4;
          if (quad_triangles != nullptr) *quad_triangles += 4;
          break;
        }
      }
    }
  }
  if (gone == 0) return 0;
  Mesh kept;
  std::vector<VertexIndex> index(mesh.positions.size(), no_index);
  for (std::uint32_t t = 0; t < count; ++t) {
    if (removed[t]) continue;
    Triangle out;
    for (int c = 0; c < 3; ++c) {
      VertexIndex& v = index[mesh.triangles[t][c]];
      if (v == no_index) {
        v = static_cast<VertexIndex>(kept.positions.size());
        kept.positions.push_back(mesh.positions[mesh.triangles[t][c]]);
      }
      out[c] = v;
    }
    kept.triangles.push_back(out);
    if (kept_triangles != nullptr) kept_triangles->push_back(t);
    kept.surfaces.push_back(mesh.surfaces[t]);
    for (int c = 0; c < 3; ++c) {
      if (mesh.corners.has_normals()) kept.corners.normals.push_back(mesh.corners.normals[3 * t + c]);
      if (mesh.corners.has_uvs()) kept.corners.uvs.push_back(mesh.corners.uvs[3 * t + c]);
      if (mesh.corners.has_tangents()) kept.corners.tangents.push_back(mesh.corners.tangents[3 * t + c]);
    }
  }
  mesh = std::move(kept);
  renumbered = std::move(index);
  return gone;
}

void shaped_triangles(const Mesh& mesh, std::vector<Triangle>& shaped, std::vector<std::uint32_t>& index) {
  for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t) {
    const Triangle& tri = mesh.triangles[t];
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[2] == tri[0]) continue;
    if (collinear(mesh.positions[tri[0]], mesh.positions[tri[1]], mesh.positions[tri[2]])) continue;
    shaped.push_back(tri);
    index.push_back(t);
  }
}

std::size_t insert_vertices_into_crossed_triangles(const PlaneSet& set, const Solid& solid, RoundingReach& reach,
                                                   Mesh& mesh, std::vector<std::uint32_t>& face_of) {
  std::vector<Triangle> shaped;
  std::vector<std::uint32_t> shaped_index;
  shaped_triangles(mesh, shaped, shaped_index);
  const std::size_t count = mesh.triangles.size();
  std::vector<VertexIndex> insert(count, no_index);
  const auto try_insert = [&](std::uint32_t t, std::uint32_t u) {
    if (insert[t] != no_index) return;
    const Triangle& tri = mesh.triangles[t];
    const PlaneRef plane = solid.faces[face_of[t]].plane;
    const Projection projection = projection_of(set, plane);
    const int i = (projection.axis + 1) % 3, j = (projection.axis + 2) % 3;
    const auto kept = [&](const Vec3& p) { return Vec2{p[i], p[j]}; };
    for (const VertexIndex v : mesh.triangles[u]) {
      if (v == tri[0] || v == tri[1] || v == tri[2]) continue;
      const Vec3& p = mesh.positions[v];
      if (!strictly_inside_triangle(kept(mesh.positions[tri[0]]), kept(mesh.positions[tri[1]]),
                                    kept(mesh.positions[tri[2]]), kept(p))) {
        continue;
      }
      if (!reach.within(p, plane)) continue;
      insert[t] = v;
      return;
    }
  };
  for (const TrianglePair& pair : self_intersecting_pairs(mesh.positions, shaped)) {
    const std::uint32_t t = shaped_index[pair.first], u = shaped_index[pair.second];
    if (face_of[t] == face_of[u]) continue;
    try_insert(t, u);
    try_insert(u, t);
  }
  std::size_t inserted = 0;
  for (std::uint32_t t = 0; t < count; ++t) {
    const VertexIndex v = insert[t];
    if (v == no_index) continue;
    const Triangle tri = mesh.triangles[t];
    const std::array<Triangle, 3> parts{Triangle{tri[0], tri[1], v}, Triangle{tri[1], tri[2], v}, Triangle{tri[2], tri[0], v}};
    mesh.triangles[t] = parts[0];
    for (int k = 1; k < 3; ++k) {
      mesh.triangles.push_back(parts[k]);
      mesh.surfaces.push_back(mesh.surfaces[t]);
      face_of.push_back(face_of[t]);
    }
    // Corner attributes: corners c and c + 1 of the triangle, then the mean.
    const auto spread = [&](auto& values) {
      if (values.empty()) return;
      using Value = std::decay_t<decltype(values[0])>;
      const Value a = values[3 * t], b = values[3 * t + 1], c = values[3 * t + 2];
      Value mean = a;
      if constexpr (std::is_same_v<Value, Vec2>) {
        mean = Vec2{(a.x + b.x + c.x) / 3, (a.y + b.y + c.y) / 3};
      } else if constexpr (std::is_same_v<Value, Vec3>) {
        mean = normalized(a + b + c);
      } else {
        const Vec3 d = normalized(Vec3{a.x + b.x + c.x, a.y + b.y + c.y, a.z + b.z + c.z});
        mean = Value{d.x, d.y, d.z, a.w};
      }
      values[3 * t + 2] = mean;
      for (const auto& [x, y] : {std::pair{b, c}, std::pair{c, a}}) {
        values.push_back(x);
        values.push_back(y);
        values.push_back(mean);
      }
    };
    spread(mesh.corners.normals);
    spread(mesh.corners.uvs);
    spread(mesh.corners.tangents);
    ++inserted;
  }
  return inserted;
}

bool snap_clusters(const Solid& solid, std::span<const Vec3> positions, const mpq_class& within,
                   std::vector<VertexIndex>& snapped_to) {
  const auto n = static_cast<VertexIndex>(positions.size());
  std::vector<VertexIndex> order(n);
  for (VertexIndex v = 0; v < n; ++v) order[v] = v;
  std::sort(order.begin(), order.end(), [&](VertexIndex a, VertexIndex b) {
    return positions[a].x != positions[b].x ? positions[a].x < positions[b].x : a < b;
  });
  // Exactly (CoordinateReach: in doubles where they decide).
  const CoordinateReach pixel(within);
  const auto close = [&](VertexIndex a, VertexIndex b, int axis) {
    return pixel.within(positions[a][axis], positions[b][axis]);
  };
  UnionFind clusters;
  clusters.reset(n);
  bool any = false;
  for (std::size_t i = 0; i < order.size(); ++i) {
    for (std::size_t j = i + 1; j < order.size() && close(order[i], order[j], 0); ++j) {
      if (close(order[i], order[j], 1) && close(order[i], order[j], 2)) {
        clusters.unite(order[i], order[j]);
        any = true;
      }
    }
  }
  snapped_to.resize(n);
  for (VertexIndex v = 0; v < n; ++v) snapped_to[v] = v;
  if (!any) return false;
  std::vector<VertexIndex> best(n, no_index);
  const auto better = [&](VertexIndex a, VertexIndex b) {  // a preferred to b
    const bool ia = solid.defs[a].kind == PointKind::input, ib = solid.defs[b].kind == PointKind::input;
    return ia != ib ? ia : a < b;
  };
  for (VertexIndex v = 0; v < n; ++v) {
    VertexIndex& b = best[clusters.find(v)];
    if (b == no_index || better(v, b)) b = v;
  }
  for (VertexIndex v = 0; v < n; ++v) snapped_to[v] = best[clusters.find(v)];
  return true;
}

void add_folded_face_pairs(const Mesh& mesh, std::span<const std::uint32_t> face_of,
                           std::vector<std::pair<std::uint32_t, std::uint32_t>>& pairs) {
  const auto add = [&](std::uint32_t f, std::uint32_t g) {
    if (f != g) pairs.emplace_back(std::min(f, g), std::max(f, g));
  };
  struct Use {
    std::uint64_t key;
    std::uint32_t triangle;
    bool forward;
  };
  std::vector<Use> uses;
  for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t) {
    for (int c = 0; c < 3; ++c) {
      const VertexIndex a = mesh.triangles[t][c], b = mesh.triangles[t][(c + 1) % 3];
      uses.push_back({(std::uint64_t{std::min(a, b)} << 32) | std::max(a, b), t, a < b});
    }
  }
  std::sort(uses.begin(), uses.end(), [](const Use& x, const Use& y) {
    return x.key != y.key ? x.key < y.key : x.triangle < y.triangle;
  });
  for (std::size_t i = 0; i < uses.size();) {
    std::size_t j = i;
    while (j < uses.size() && uses[j].key == uses[i].key) ++j;
    const bool folded = j - i > 2 || (j - i == 2 && uses[i].forward == uses[i + 1].forward);
    if (folded) {
      for (std::size_t k = i; k < j; ++k) {
        for (std::size_t l = k + 1; l < j; ++l) add(face_of[uses[k].triangle], face_of[uses[l].triangle]);
      }
    }
    i = j;
  }
  std::vector<Triangle> shaped;
  std::vector<std::uint32_t> shaped_index;
  shaped_triangles(mesh, shaped, shaped_index);
  for (const TrianglePair& p : self_intersecting_pairs(mesh.positions, shaped)) {
    add(face_of[shaped_index[p.first]], face_of[shaped_index[p.second]]);
  }
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
}

}  // namespace rounding

}  // namespace shatter
