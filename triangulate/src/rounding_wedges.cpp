// Wedges beyond rounding's reach of a cap: the faces split there and the thin
// strips merged. See rounding.hpp.
#include "rounding.hpp"

#include <algorithm>
#include <unordered_map>

#include "shatter/kernel/index_map.hpp"

namespace shatter {

// --- Wedges beyond rounding's reach ------------------------------------------------
// The last repair, tried only when every round above has failed and the piece
// could not vanish whole: a cap folded against faces that share an edge with it
// and lie nearly in its plane, though not all of their corners lie within
// rounding's reach of it (a chain of near-parallel cuts: the earlier cap's
// clipped faces run from the wedge's tip, on the cap, to corners far off its
// plane), so the thin round cannot merge them and merging them whole moves more
// than rounding may. Such faces are split where they leave rounding's reach:
// along their line with a new plane parallel to the cap's, offset into the
// piece by a few times the rounding move (the cap's doubles with another
// offset, a plane of the set like any cut, so every new vertex is defined
// exactly, as split_solid defines one). The solid is the same point set, with
// more faces: the strips between the cap and the new plane are thin by their
// corners, and the rounds above, run again on the refined solid, merge them
// into the cap (the thin part of the wedge vanishes) and certify the result.
// The volume moved is held to the original piece's bound, measured against its
// exact volume, which the refinement does not change.

namespace rounding {

bool split_faces_along(const PlaneSet& set, const Solid& solid, PlaneRef plane, std::span<const std::uint32_t> split,
                       Solid& out) {
  out = Solid{};
  out.defs = solid.defs;
  out.approx = solid.approx;
  out.convex = solid.convex;
  std::vector<std::uint8_t> splitting(solid.faces.size(), 0);
  std::vector<Sign> sides(solid.defs.size(), Sign::zero);
  std::vector<std::uint8_t> sided(solid.defs.size(), 0);
  const auto side_of = [&](VertexIndex v) {
    if (!sided[v]) sides[v] = side(set, plane, solid.defs[v], solid.approx[v]), sided[v] = 1;
    return sides[v];
  };
  for (const std::uint32_t f : split) {
    const SolidFace& face = solid.faces[f];
    if (!face.convex || face.loop_count != 1) continue;
    bool below = false, above = false;
    for (const CornerEdge& edge : loop_edges(solid.corners, solid.loops[face.first_loop])) {
      below |= side_of(edge.from) == Sign::negative;
      above |= side_of(edge.from) == Sign::positive;
    }
    splitting[f] = below && above;
  }
  // The crossing vertex of each crossed edge of a face split, once per edge.
  IndexMap crossing(64);
  bool any = false;
  for (std::uint32_t f = 0; f < solid.faces.size(); ++f) {
    if (!splitting[f]) continue;
    any = true;
    const SolidFace& face = solid.faces[f];
    for (const CornerEdge& edge : loop_edges(solid.corners, solid.loops[face.first_loop])) {
      const Sign a = side_of(edge.from), b = side_of(edge.to);
      if (a == Sign::zero || b == Sign::zero || a == b) continue;
      const auto candidate = static_cast<VertexIndex>(out.defs.size());
      if (crossing.insert(undirected_edge_key(edge.from, edge.to), candidate) != candidate) continue;
      const PointDef def = edge_crossing_def(face, solid.corners[edge.corner].line, plane);
      out.defs.push_back(def);
      out.approx.push_back(approximate(set, def));
    }
  }
  if (!any) return false;
  std::vector<SolidCorner> augmented;
  for (std::uint32_t f = 0; f < solid.faces.size(); ++f) {
    const SolidFace& face = solid.faces[f];
    SolidFace copy = face;
    copy.first_loop = static_cast<std::uint32_t>(out.loops.size());
    for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
      augmented.clear();
      for (const CornerEdge& edge : loop_edges(solid.corners, solid.loops[l])) {
        const EdgeLine& line = solid.corners[edge.corner].line;
        augmented.push_back({edge.from, line});
        const VertexIndex x = crossing.find(undirected_edge_key(edge.from, edge.to));
        if (x != no_index) augmented.push_back({x, line});
      }
      if (!splitting[f]) {
        out.loops.push_back({static_cast<std::uint32_t>(out.corners.size()), static_cast<std::uint32_t>(augmented.size())});
        out.corners.insert(out.corners.end(), augmented.begin(), augmented.end());
        continue;
      }
      // A convex loop with corners strictly on both sides meets the plane at
      // exactly two of its (augmented) corners: the chord between them.
      std::vector<std::size_t> on;
      for (std::size_t i = 0; i < augmented.size(); ++i) {
        const VertexIndex v = augmented[i].vertex;
        if (v >= solid.defs.size() || side_of(v) == Sign::zero) on.push_back(i);
      }
      if (on.size() != 2) return false;
      EdgeLine chord;
      chord.other = plane;
      for (const auto& [from, to] : {std::pair{on[0], on[1]}, std::pair{on[1], on[0]}}) {
        if (from != on[0]) copy.first_loop = static_cast<std::uint32_t>(out.loops.size());
        const auto first = static_cast<std::uint32_t>(out.corners.size());
        for (std::size_t i = from; i != to; i = (i + 1) % augmented.size()) out.corners.push_back(augmented[i]);
        out.corners.push_back({augmented[to].vertex, chord});
        out.loops.push_back({first, static_cast<std::uint32_t>(out.corners.size()) - first});
        copy.loop_count = 1;
        out.faces.push_back(copy);
      }
    }
    if (!splitting[f]) {
      copy.loop_count = face.loop_count;
      out.faces.push_back(copy);
    }
  }
  return true;
}

// --- Strips thin by their corners --------------------------------------------------
// After the wedge split, tried only when it has failed too (so that every piece
// written before is written as before): a corner strictly inside the piece a
// fraction of an ulp from a cap's plane (an earlier cap's vertex, the new plane
// through it up to rounding: smoke corpus seed 7 case 28) takes the position of
// its own crossings with the cap (output_point snaps a crossing within 64 ulps
// of its segment's end onto it), and the faces between it and the cap, thin by
// their corners, then lie on the cap over triangles of the cap's own, laid
// over them or crossing them. The folding rounds merge only the pairs
// certification names, and it never names these: their triangles cancel as
// sheets, or cross the cap's only where thicker folds cross it too, which it
// names first. Such faces are found here from the exact solid instead.

namespace {

// For each cap (a face on a cut plane), the faces reached from it across shared
// edges, face by face, whose corners all lie within rounding's reach of the
// cap's plane (RoundingReach: exactly, in the L1 norm), not on its plane: the
// strips between the cap and the corners by it, as pairs (cap, face), by cap,
// then in the order they were reached. The wedge each bounds with the cap is
// no thicker than the reach, so merging it moves at most the reach times its
// area, as a fold's merge does.
std::vector<std::pair<std::uint32_t, std::uint32_t>> strips_thin_by_corners(const Solid& solid, RoundingReach& reach) {
  const auto count = static_cast<std::uint32_t>(solid.faces.size());
  std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> faces_of_edge;
  const auto key = [](VertexIndex a, VertexIndex b) {
    return (std::uint64_t{std::min(a, b)} << 32) | std::max(a, b);
  };
  for (std::uint32_t f = 0; f < count; ++f) {
    const SolidFace& face = solid.faces[f];
    for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
      for (const CornerEdge& edge : loop_edges(solid.corners, solid.loops[l])) {
        faces_of_edge[key(edge.from, edge.to)].push_back(f);
      }
    }
  }
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
  std::vector<std::uint8_t> visited(count);
  std::vector<std::uint32_t> reached;
  for (std::uint32_t c = 0; c < count; ++c) {
    const SolidFace& cap = solid.faces[c];
    if (!cap.plane.is_cut()) continue;
    std::fill(visited.begin(), visited.end(), 0);
    visited[c] = 1;
    reached.assign(1, c);
    for (std::size_t next = 0; next < reached.size(); ++next) {
      const SolidFace& from = solid.faces[reached[next]];
      for (std::uint32_t l = from.first_loop; l < from.first_loop + from.loop_count; ++l) {
        for (const CornerEdge& edge : loop_edges(solid.corners, solid.loops[l])) {
          for (const std::uint32_t g : faces_of_edge[key(edge.from, edge.to)]) {
            if (visited[g]) continue;
            visited[g] = 1;
            if (solid.faces[g].plane == cap.plane || !reach.within(g, cap.plane)) continue;
            pairs.emplace_back(c, g);
            reached.push_back(g);
          }
        }
      }
    }
  }
  return pairs;
}

}  // namespace

std::optional<RoundedSolid> round_merging_thin_strips(const PlaneSet& set, const Solid& solid,
                                                      const SolidMeshOptions& options,
                                                      std::span<const Vec3> positions, RoundingReach& reach,
                                                      std::span<const int> snap_levels, PieceVolumes& piece) {
  const std::vector<std::pair<std::uint32_t, std::uint32_t>> strips = strips_thin_by_corners(solid, reach);
  if (strips.empty()) return std::nullopt;
  std::vector<VertexIndex> snapped_to, mesh_vertex_of, renumbered;
  std::vector<std::uint32_t> face_of_triangle, kept;
  mpq_class pixel;
  for (std::size_t level = 0; level <= snap_levels.size(); ++level) {
    const bool snapping = level > 0;
    std::size_t snapped = 0;
    if (snapping) {
      pixel = reach.rho * mpq_class(mpz_class(1) << snap_levels[level - 1]);
      snap_clusters(solid, positions, pixel, snapped_to);
      for (VertexIndex v = 0; v < solid.defs.size(); ++v) snapped += snapped_to[v] != v;
    }
    for (const FoldMerge mode : {FoldMerge::pairs, FoldMerge::groups}) {
      for (std::size_t attempt = 1; attempt < 4; ++attempt) {
        Mesh mesh;
        std::size_t merged = 0, folded = 0;
        triangulate(set, solid, options, attempt, mesh, merged, &mesh_vertex_of, true, true, strips, &face_of_triangle,
                    &folded, true, snapping ? std::span<const VertexIndex>(snapped_to) : std::span<const VertexIndex>(),
                    snapping ? &pixel : nullptr, false, mode);
        if (mesh.triangles.empty()) continue;
        ValidationReport report = certify_rounded(mesh, options);
        std::size_t gone = 0;
        if (!report.valid()) {
          Mesh sheetless = mesh;
          gone = cancel_two_sided_sheets(sheetless, renumbered, true, &kept);
          if (gone == 0 || sheetless.triangles.empty()) continue;
          mesh = std::move(sheetless);
          if (!certify_rounded(mesh, options).valid()) continue;
        }
        RoundedSolid written;
        if (!report_moved_volume(measured_moved_volume(piece, mesh), written)) continue;
        written.mesh = std::move(mesh);
        written.valid = true;
        written.merged_vertices = merged;
        written.retriangulated_faces = solid.faces.size();
        written.vanished_triangles = gone;
        written.folded_faces = folded;
        written.snapped_vertices = snapped;
        written.attempt = -1;
        return written;
      }
    }
  }
  return std::nullopt;
}

}  // namespace rounding

}  // namespace shatter
