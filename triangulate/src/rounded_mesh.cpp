// Steps 1 and 2 of the rounding (solid_mesh.hpp): the solid's vertices rounded
// and merged where they meet, its faces triangulated, with the repairs of their
// loops a round asks for (rounding_loops.cpp). See rounding.hpp.
#include <algorithm>
#include <cstring>

#include "shatter/kernel/projection.hpp"
#include "shatter/kernel/predicates.hpp"
#include "rounding.hpp"

namespace shatter {

namespace rounding {

namespace {

// No given face triangles (triangulate's per-face marker).
constexpr std::size_t no_given = ~std::size_t{0};

// Per-corner attributes at a point of input triangle `source`: the corner's own
// value at one of its vertices, else interpolated with barycentric coordinates
// of the rounded point projected into the triangle (attributes never decide
// geometry, so rounded arithmetic serves).
struct AttributeSource {
  const Mesh& input;
  bool normals, uvs, tangents;

  void append(TriangleIndex source, const PointDef& def, const Vec3& p, CornerAttributes& out) const {
    const Triangle& t = input.triangles[source];
    double w[3] = {0, 0, 0};
    int corner = -1;
    if (def.kind == PointKind::input) {
      for (int c = 0; c < 3; ++c) {
        if (t[c] == def.a) corner = c;
      }
    }
    if (corner >= 0) {
      w[corner] = 1;
    } else {
      const Vec3 a = input.positions[t[0]], b = input.positions[t[1]], c = input.positions[t[2]];
      const Vec3 n = cross(b - a, c - a);
      const double area = dot(n, n);
      if (area > 0) {
        w[0] = dot(cross(b - p, c - p), n) / area;
        w[1] = dot(cross(c - p, a - p), n) / area;
        w[2] = dot(cross(a - p, b - p), n) / area;
      }
      double total = 0;
      for (double& x : w) {
        x = std::clamp(x, 0.0, 1.0);
        total += x;
      }
      if (!(total > 0)) w[0] = total = 1;
      for (double& x : w) x /= total;
    }
    const std::size_t base = 3 * std::size_t{source};
    if (normals) {
      Vec3 n;
      for (int c = 0; c < 3; ++c) n = n + input.corners.normals[base + c] * w[c];
      out.normals.push_back(corner >= 0 ? input.corners.normals[base + corner] : normalized(n));
    }
    if (uvs) {
      Vec2 uv;
      for (int c = 0; c < 3; ++c) {
        uv.x += input.corners.uvs[base + c].x * w[c];
        uv.y += input.corners.uvs[base + c].y * w[c];
      }
      out.uvs.push_back(corner >= 0 ? input.corners.uvs[base + corner] : uv);
    }
    if (tangents) {
      if (corner >= 0) {
        out.tangents.push_back(input.corners.tangents[base + corner]);
      } else {
        Vec3 d;
        for (int c = 0; c < 3; ++c) {
          const Vec4& g = input.corners.tangents[base + c];
          d = d + Vec3{g.x, g.y, g.z} * w[c];
        }
        d = normalized(d);
        out.tangents.push_back({d.x, d.y, d.z, input.corners.tangents[base].w});
      }
    }
  }
};

struct PositionHash {
  std::size_t operator()(const Vec3& p) const {
    auto bits = [](double x) {
      std::uint64_t b;
      x = x == 0 ? 0.0 : x;  // -0.0 and +0.0 are one position
      std::memcpy(&b, &x, sizeof b);
      return b;
    };
    return bits(p.x) * 0x9E3779B97F4A7C15ull ^ bits(p.y) * 0xC2B2AE3D27D4EB4Full ^ bits(p.z);
  }
};

struct PositionEqual {
  bool operator()(const Vec3& a, const Vec3& b) const { return a.x == b.x && a.y == b.y && a.z == b.z; }
};

}  // namespace

void triangulate(const PlaneSet& set, const Solid& solid, const SolidMeshOptions& options, std::size_t attempt,
                 Mesh& mesh, std::size_t& merged, std::vector<VertexIndex>* mesh_vertex_of,
                 bool repair_loops, bool route_crossed,
                 std::span<const std::pair<std::uint32_t, std::uint32_t>> folds,
                 std::vector<std::uint32_t>* face_of_triangle, std::size_t* folded,
                 bool thin_folds_only, std::span<const VertexIndex> snapped_to,
                 const mpq_class* snap_within, bool folds_apart_too,
                 FoldMerge fold_merge, std::vector<std::uint64_t>* triangle_origins) {
  const std::size_t n = solid.defs.size();
  thread_local std::vector<Vec3> positions;
  thread_local std::vector<PointDef> placed;
  positions.resize(n);
  placed.resize(n);
  for (std::size_t v = 0; v < n; ++v) {
    const OutputPoint point = output_point(set, solid.defs[v], solid.approx[v]);
    positions[v] = point.position;
    placed[v] = point.placed;
  }
  // The last round's hot pixels (snap_clusters): every vertex takes its
  // cluster's representative's place, and so merges with it below.
  if (!snapped_to.empty()) {
    for (std::size_t v = 0; v < n; ++v) {
      if (snapped_to[v] != v) positions[v] = positions[snapped_to[v]], placed[v] = placed[snapped_to[v]];
    }
  }
  // One representative per position: an open-addressing table keyed by a hash of
  // the position, collisions resolved by comparing positions.
  thread_local std::vector<VertexIndex> representative;
  representative.resize(n);
  merged = 0;
  {
    thread_local std::vector<VertexIndex> slots;
    std::size_t capacity = 16;
    while (capacity < 2 * n) capacity *= 2;
    slots.assign(capacity, no_index);
    for (VertexIndex v = 0; v < n; ++v) {
      std::size_t i = PositionHash{}(positions[v]) & (capacity - 1);
      while (slots[i] != no_index && !PositionEqual{}(positions[slots[i]], positions[v])) i = (i + 1) & (capacity - 1);
      if (slots[i] == no_index) {
        slots[i] = v;
        representative[v] = v;
      } else {
        representative[v] = slots[i];
        ++merged;
      }
    }
  }
  const Mesh* input = options.attributes;
  const bool normals = input && input->corners.has_normals();
  const bool uvs = input && input->corners.has_uvs();
  const bool tangents = input && input->corners.has_tangents();
  thread_local std::vector<Triangle> face_triangles;
  thread_local std::vector<std::vector<VertexIndex>> loops;
  thread_local std::vector<VertexIndex> out_index;
  out_index.assign(n, no_index);
  mesh = Mesh{};
  mesh.positions.reserve(n);
  mesh.triangles.reserve(solid.corners.size());
  mesh.surfaces.reserve(solid.corners.size());
  // The repair of loops over merged vertices (repair_merged_loops), when asked
  // for: every face's loops at once, since an edge of one face may pass through a
  // vertex of another.
  thread_local std::vector<std::vector<std::vector<VertexIndex>>> repaired;
  thread_local std::vector<std::uint8_t> repaired_changed;
  thread_local std::vector<std::uint32_t> emit_as, home;  // merge_coplanar_sheets, merge_folded_faces
  emit_as.clear();
  if (face_of_triangle != nullptr) face_of_triangle->clear();
  if (triangle_origins != nullptr) triangle_origins->clear();
  if (folded != nullptr) *folded = 0;
  // Folds are merged on the loops over representatives, which the repair
  // builds, merged vertices or not.
  const bool repairing = repair_loops && (merged > 0 || (route_crossed && !folds.empty()) || snap_within != nullptr);
  if (repairing) {
    repaired.assign(solid.faces.size(), {});
    repaired_changed.assign(solid.faces.size(), 0);
    std::vector<std::uint8_t> candidate(n, 0);
    for (VertexIndex v = 0; v < n; ++v) {
      if (representative[v] != v) candidate[representative[v]] = 1;
    }
    for (std::uint32_t f = 0; f < solid.faces.size(); ++f) {
      const SolidFace& face = solid.faces[f];
      for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
        const SolidLoop& loop = solid.loops[l];
        std::vector<VertexIndex> corners;
        for (std::uint32_t i = 0; i < loop.corner_count; ++i) {
          const VertexIndex v = representative[solid.corners[loop.first_corner + i].vertex];
          // A corner snapped onto an input point lies off the face's plane: the
          // face is triangulated over the placed points too, whose collinear
          // runs (a snapped corner on the line of an edge) it keeps out of its
          // triangles.
          const VertexIndex own = solid.corners[loop.first_corner + i].vertex;
          repaired_changed[f] |= v != own || !(placed[own] == solid.defs[own]);
          if (corners.empty() || corners.back() != v) corners.push_back(v);
        }
        while (corners.size() > 1 && corners.back() == corners.front()) corners.pop_back();
        repaired[f].push_back(std::move(corners));
      }
      if (repaired_changed[f]) {
        for (const auto& loop : repaired[f]) {
          for (const VertexIndex v : loop) candidate[v] = 1;
        }
      }
    }
    std::vector<VertexIndex> candidates;
    for (VertexIndex v = 0; v < n; ++v) {
      if ((candidate[v] || snap_within != nullptr) && representative[v] == v) candidates.push_back(v);
    }
    // Only loops through a candidate, or along an edge it may lie in, can
    // change; a loop that changes marks its face.
    const auto before = repaired;
    if (route_crossed) route_edges_through_crossed_corners(set, solid, placed, positions, repaired);
    repair_merged_loops(positions, repaired, candidates, snap_within);
    for (std::uint32_t f = 0; f < solid.faces.size(); ++f) repaired_changed[f] |= repaired[f] != before[f];
    if (route_crossed) {
      merge_coplanar_sheets(set, solid, positions, repaired, repaired_changed, emit_as, home);
      if (!folds.empty()) {
        const std::size_t count =
            merge_folded_faces(set, solid, positions, repaired, repaired_changed, emit_as, home, folds, thin_folds_only,
                               folds_apart_too, fold_merge);
        if (folded != nullptr) *folded = count;
      }
    }
  }
  for (std::uint32_t f = 0; f < solid.faces.size(); ++f) {
    if (repairing && route_crossed && emit_as[f] == no_index) continue;
    const SolidFace& face = solid.faces[repairing && route_crossed ? emit_as[f] : f];
    face_triangles.clear();
    std::size_t given_from = no_given;  // where the face's given triangles start in face_triangles, if given
    bool changed = false;
    if (repairing) {
      changed = repaired_changed[f];
      loops = repaired[f];
    } else if (merged > 0) {
      loops.clear();
      for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
        const SolidLoop& loop = solid.loops[l];
        std::vector<VertexIndex> corners;
        for (std::uint32_t i = 0; i < loop.corner_count; ++i) {
          const VertexIndex v = representative[solid.corners[loop.first_corner + i].vertex];
          changed |= v != solid.corners[loop.first_corner + i].vertex;
          if (corners.empty() || corners.back() != v) corners.push_back(v);
        }
        while (corners.size() > 1 && corners.back() == corners.front()) corners.pop_back();
        if (corners.size() >= 3) loops.push_back(std::move(corners));
      }
    }
    if (!changed) {
      const bool given = attempt == 0 && !options.face_triangles_first.empty() &&
                         options.face_triangles_first[f] < options.face_triangles_first[f + 1];
      if (given) {
        face_triangles.assign(options.face_triangles.begin() + options.face_triangles_first[f],
                              options.face_triangles.begin() + options.face_triangles_first[f + 1]);
        given_from = options.face_triangles_first[f];
      } else {
        const std::size_t face_attempt =
            attempt == 0 && !options.face_attempts.empty() ? options.face_attempts[f] : attempt;
        triangulate_face(set, solid, f, positions, face_triangles, face_attempt);
      }
    } else if (!loops.empty()) {
      // A face that cannot be triangulated over its placed corners is left out.
      // If it had vanished in the rounding (seen: a thin annulus cap whose two
      // loops snapped onto the same ridge of vertices) the rest closes up without
      // it; if not, certification finds the mesh open and refuses it.
      face_triangles.clear();
      const Projection projection = projection_of(set, face.plane);
      // Folded in every projection (a snapped corner went past its neighbour's
      // edge): a fan over the rounded corners, from the apex the attempt names,
      // skipping apexes with a triangle collinear in 3D (decided exactly).
      // Certification vouches for the result or refuses it.
      const auto fan_over_rounded = [&](const std::vector<VertexIndex>& corners) {
        const std::size_t k = corners.size();
        for (std::size_t step = 0; step < k; ++step) {
          const std::size_t apex = (attempt - 1 + step) % k;
          bool flat = false;
          for (std::size_t i = 1; i + 1 < k && !flat; ++i) {
            const Vec3 &a = positions[corners[apex]], &b = positions[corners[(apex + i) % k]],
                       &c = positions[corners[(apex + i + 1) % k]];
            // Distinct representatives have distinct positions: three of them
            // are collinear exactly when one lies strictly between the others.
            flat = strictly_inside_segment(a, b, c) || strictly_inside_segment(b, c, a) ||
                   strictly_inside_segment(c, a, b);
          }
          if (flat) continue;
          for (std::size_t i = 1; i + 1 < k; ++i) {
            face_triangles.push_back({corners[apex], corners[(apex + i) % k], corners[(apex + i + 1) % k]});
          }
          return;
        }
      };
      if (!triangulate_merged_face(set, face, loops, placed, projection, face_triangles, repairing) && repairing) {
        // Loops split where they touched lie side by side: each on its own.
        for (const auto& loop : loops) {
          if (loops.size() > 1 &&
              triangulate_merged_face(set, face, std::span<const std::vector<VertexIndex>>(&loop, 1), placed,
                                      projection, face_triangles, true)) {
            continue;
          }
          // A face with holes is left out rather than fanned over its outer loop.
          if (face.loop_count == 1) fan_over_rounded(loop);
        }
      }
    }
    const bool cap = face.surface != original_surface;
    PlaneBasis basis(Plane{});
    Vec3 cap_normal;
    if (cap && (normals || uvs || tangents)) {
      const ApproxPlane a = set.approx(face.plane);
      basis = PlaneBasis(Plane{{a.a.value, a.b.value, a.c.value}, a.d.value});
      cap_normal = face.reversed ? -basis.normal : basis.normal;
    }
    for (std::size_t i = 0; i < face_triangles.size(); ++i) {
      Triangle t = face_triangles[i];
      if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0]) continue;
      if (triangle_origins != nullptr) {
        const bool known = given_from != no_given && !options.face_triangle_origins.empty();
        triangle_origins->push_back(known ? options.face_triangle_origins[given_from + i] : ~std::uint64_t{0});
      }
      for (VertexIndex& v : t) {
        if (out_index[v] == no_index) {
          out_index[v] = static_cast<VertexIndex>(mesh.positions.size());
          mesh.positions.push_back(positions[v]);
        }
      }
      mesh.triangles.push_back({out_index[t[0]], out_index[t[1]], out_index[t[2]]});
      if (face_of_triangle != nullptr) face_of_triangle->push_back(f);
      mesh.surfaces.push_back(face.surface);
      for (VertexIndex v : t) {
        if (!cap) {
          if (input && (normals || uvs || tangents)) {
            AttributeSource{*input, normals, uvs, tangents}.append(face.source, solid.defs[v], positions[v],
                                                                   mesh.corners);
          }
          continue;
        }
        const Vec3 p = positions[v];
        if (normals) mesh.corners.normals.push_back(cap_normal);
        if (uvs) {
          mesh.corners.uvs.push_back(
              {dot(p, basis.u) * options.interior_uv_scale, dot(p, basis.v) * options.interior_uv_scale});
        }
        if (tangents) mesh.corners.tangents.push_back({basis.u.x, basis.u.y, basis.u.z, face.reversed ? -1.0 : 1.0});
      }
    }
  }
  if (mesh_vertex_of != nullptr) {
    mesh_vertex_of->resize(n);
    for (VertexIndex v = 0; v < n; ++v) (*mesh_vertex_of)[v] = out_index[representative[v]];
  }
}

}  // namespace rounding

}  // namespace shatter
