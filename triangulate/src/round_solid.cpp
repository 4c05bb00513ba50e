// round_solid: the rounds of attempts and repairs that round a plane-based solid
// to a certified mesh (solid_mesh.hpp says what each does and why it ends),
// over the parts declared in rounding.hpp.
#include "shatter/triangulate/solid_mesh.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <span>
#include <stdexcept>
#include <vector>

#include "shatter/kernel/certify.hpp"
#include "shatter/kernel/error.hpp"
#include "shatter/kernel/face_loops.hpp"
#include "shatter/kernel/non_manifold.hpp"
#include "shatter/kernel/self_intersections.hpp"
#include "shatter/kernel/snap_predicates.hpp"
#include "rounding.hpp"

namespace shatter {

namespace rounding {

namespace {

Vec3 vertex_average(const Mesh& mesh) {
  Vec3 sum;
  for (const Vec3& p : mesh.positions) sum = sum + p;
  return sum * (1.0 / static_cast<double>(mesh.positions.size()));
}

// `result` but for its mesh, which the caller replaces (copying it would cost a
// mesh per certified piece).
RoundedSolid copy_without_mesh(RoundedSolid& result) {
  Mesh mesh = std::move(result.mesh);
  RoundedSolid copy = result;
  result.mesh = std::move(mesh);
  return copy;
}

// The full check, self-intersections included, narrowed by what is known to be
// valid already: the parts of a union (their pairs within one part skipped), or
// else the trusted mesh the piece was cut from. Both accept exactly the meshes
// validate_mesh accepts (validate.hpp says why).
ValidationReport validate_knowing(const Mesh& mesh, const SolidMeshOptions& options,
                                  std::span<const std::uint8_t> exact_vertices, bool topology_sound,
                                  std::span<const std::uint64_t> triangle_origins = {}) {
  if (!options.parts.empty()) {
    return validate_mesh_of_parts(mesh, options.parts, options.part_regions, topology_sound, triangle_origins);
  }
  if (options.trusted != nullptr && options.trusted_triangles != nullptr) {
    return validate_mesh_against(mesh, options.trusted_triangles->get(), options.cut, exact_vertices);
  }
  return validate_mesh_against(mesh, options.trusted, options.cut, exact_vertices);
}

// validate_mesh_against's exact vertices for a mesh that triangulates `solid`'s
// faces over their own vertices, no two merged (`mesh_vertex_of`: each solid
// vertex's mesh vertex, or no_index): every input vertex on no cap. Each face's
// triangles are then exactly counter-clockwise over exactly its region, and an
// input vertex is written where it is. The solid's input faces are parts of the
// valid input's surface, which meet only in what they share (a vertex a pinch
// split in two is one position again: merged); a cut may make a solid touch
// itself, but only on a cap (a cap through a face, an edge or a vertex on its
// plane, which the rounding then separates). So two triangles whose corners are
// all flagged meet only in what they share. (Flagging the caps' input vertices
// too failed test_split's nested islands: a cap through an island's edge.)
std::vector<std::uint8_t> exact_input_vertices(const Solid& solid, std::span<const VertexIndex> mesh_vertex_of,
                                               std::size_t mesh_vertex_count) {
  std::vector<std::uint8_t> exact(mesh_vertex_count, 0);
  for (VertexIndex v = 0; v < solid.defs.size(); ++v) {
    if (solid.defs[v].kind == PointKind::input && mesh_vertex_of[v] != no_index) exact[mesh_vertex_of[v]] = 1;
  }
  for (const SolidFace& face : solid.faces) {
    if (face.surface == original_surface) continue;
    for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
      for (const CornerEdge& edge : loop_edges(solid.corners, solid.loops[l])) {
        if (mesh_vertex_of[edge.from] != no_index) exact[mesh_vertex_of[edge.from]] = 0;
      }
    }
  }
  return exact;
}

}  // namespace

ValidationReport certify_rounded(const Mesh& mesh, const SolidMeshOptions& options, const ExactVertexSource* exact,
                                 std::span<const std::uint64_t> triangle_origins) {
  if (!options.allow_self_intersections) {
    // A triangulation of the exact solid's faces over their own vertices, none
    // merged (what `exact` says), has the solid's topology: closed, oriented,
    // 2-manifold by index, every vertex used.
    // Not for a union of parts: certifying it knowing its parts (its topology
    // sound as glued, only triangles at its parts' shared faces paired) costs
    // less than the star-shaped certificate's search for a centre, which about
    // half the unions decline after its linear program (1,463 of 2,745 on
    // fandisk x4 at 10^4 Voronoi sites).
    if (options.parts.empty() && certify_piece(mesh, exact != nullptr)) {
      ValidationReport certified;
      certified.vertex_count = mesh.vertex_count();
      certified.triangle_count = mesh.triangle_count();
      certified.self_intersections_checked = true;
      return certified;
    }
    const std::vector<std::uint8_t> exact_vertices =
        exact != nullptr ? exact_input_vertices(exact->solid, exact->mesh_vertex_of, mesh.positions.size())
                         : std::vector<std::uint8_t>{};
    return validate_knowing(mesh, options, exact_vertices, exact != nullptr, triangle_origins);
  }
  ValidationOptions topology_only;
  topology_only.check_self_intersections = false;
  ValidationReport report = validate_mesh(mesh, topology_only);
  // A surface allowed to cross itself may touch itself at a vertex.
  std::erase_if(report.defects, [](const Defect& d) { return d.kind == DefectKind::non_manifold_vertex; });
  return report;
}

namespace {

// round_solid; `collapse_wedges`: also the last repair above (not when rounding a
// solid it refined); `fold_merge`: how the folding rounds merge (FoldMerge; a
// refined solid of the widened split takes `groups` or `groups_one_way`).
RoundedSolid round_solid_rounds(const PlaneSet& set, const Solid& solid, const SolidMeshOptions& options,
                                bool collapse_wedges, FoldMerge fold_merge = FoldMerge::pairs) {
  if (!options.face_attempts.empty() && options.face_attempts.size() != solid.faces.size()) {
    throw std::invalid_argument("round_solid: face_attempts must hold one attempt per face");
  }
  if (!options.face_triangles_first.empty() &&
      (options.face_triangles_first.size() != solid.faces.size() + 1 ||
       !std::is_sorted(options.face_triangles_first.begin(), options.face_triangles_first.end()) ||
       options.face_triangles_first.back() > options.face_triangles.size())) {
    throw std::invalid_argument("round_solid: face_triangles_first must hold one ascending offset per face, and one more");
  }
  if (!options.face_triangle_origins.empty() && options.face_triangle_origins.size() != options.face_triangles.size()) {
    throw std::invalid_argument("round_solid: face_triangle_origins must be empty or hold one origin per face triangle");
  }

  RoundedSolid result;
  PieceVolumes piece(set, solid);
  ValidationReport first_report;
  bool flattened_whole = false;    // every triangle was in a two-sided sheet
  std::size_t sheets_cancelled = 0;  // triangles of two-sided sheets removed at this attempt
  std::optional<std::vector<VertexIndex>> touching_caps;  // solid vertices; found at the first need
  std::vector<VertexIndex> mesh_vertex_of, touching;
  // Attempt 0 is the cheapest triangulation. A fold that rounding made comes from
  // a sliver triangle (a corner nearly on the line of its neighbours, where two
  // input faces are nearly coplanar); later attempts take the roundest fans and
  // the exact Delaunay triangulation, which keep such corners out of slivers.
  // The second round of attempts (untangle_edges) also untangles edges that
  // rounding made non-manifold (pair_around_non_manifold_edges): a repair tried
  // only once the others have failed, so that every piece they write is written
  // as before it existed.
  // The third round (folding), tried only when the first two have failed,
  // merges faces that rounding folded against each other (merge_folded_faces):
  // attempts 1 to 3 again, each with the pairs of faces whose triangles the
  // second round's certification found folded, then with those its own
  // failures add, until a retry finds no new pair (at most fold_retries times).
  // It merges first only the pairs whose wedge is thin by its corners (the
  // faces' corners within reach of each other's planes, RoundingReach), then,
  // if that fails, every pair found (thin only where it folded).
  constexpr std::size_t attempts = 4, fold_retries = 6, fold_steps = (attempts - 1) * fold_retries;
  // A third phase merges the thin pairs again and also inserts rounded
  // vertices into the triangles they crossed within rounding's reach
  // (insert_vertices_into_crossed_triangles, 3D snap rounding's hot pixels).
  constexpr std::size_t plain_steps = 2 * attempts, steps = plain_steps + 3 * fold_steps;
  // The last round (snapping), tried only when all of the above has failed, so
  // that no piece written before it existed is written differently, is 3D snap
  // rounding at coarser pixels: for each pixel of 2^k times the largest
  // rounding move rho (k in snap_levels), vertices within a pixel of each other
  // are placed at one of them (snap_clusters) and edges passing within a pixel
  // of a vertex are routed through it (repair_merged_loops' `near`); then
  // attempts 1 to 3, each retried with the faces its failures find folded
  // merged (merge_folded_faces, every pair), until a retry finds no new pair.
  // Why it ends: six pixels x three attempts x at most snap_retries tries,
  // each one pass of triangulate and certify, every part of which is finite
  // (clusters by one union-find; insertions only of existing vertices into
  // edges, each edge taking each vertex once; spike removal and splitting only
  // shorten loops; merges only remove faces). Why what it writes is valid:
  // nothing of it is trusted, the mesh is taken only when certify_rounded
  // passes (closed, oriented, manifold, no self-intersection, positive volume)
  // and when the volume it moved, measured exactly against the exact piece, is
  // within what rounding the piece's vertices alone can move (rounding_sweep_bound,
  // as for folds merged), however large the pixel: what vanishes is a part
  // thinner than the rounding of its coordinates, between vertices a pixel apart:
  // the tip of a wedge between near-parallel planes, thinner than the rounding
  // near their shared edge, which folded when its corners were rounded one by
  // one.
  // (Pixels to 2^10 rho repair the fuzz's wedges; the pieces of a chain cut
  // again as written, themselves wedges 2^-20 to 2^-40 thick, need 2^16 and
  // 2^24: measured on the robustness corpus, 2026-12-03.)
  constexpr std::array<int, 6> snap_levels{1, 3, 6, 10, 16, 24};
  constexpr std::size_t snap_retries = 2, snap_steps = (attempts - 1) * snap_retries;
  // After it, tried only when every round above has failed (so that no piece
  // written before it existed is written differently; a piece that vanished
  // whole may now be written instead, when this certifies it), the folding round's
  // thin phase again with pairs of faces whose loops share no edge merged too
  // (merge_folded_faces' `apart_too`): a slab thinner than the rounding between
  // a cap and a face it passes ulps from (a cavity's face in a plane that holds
  // it up to rounding: issue 17's hollow-egg, corpus case 933) folds where no
  // edge of the cap is near; the face's loops become a hole of the cap and the
  // slab vanishes. Why it ends and why what it writes is valid: as the folding
  // round (a fixed number of retries, each a finite pass; certified, and the
  // volume moved held to the rounding's bound).
  constexpr std::size_t snap_end = steps + snap_levels.size() * snap_steps;
  constexpr std::size_t all_steps = snap_end + fold_steps;
  std::array<std::vector<std::pair<std::uint32_t, std::uint32_t>>, attempts> snap_folds;
  std::array<bool, attempts> snap_stalled{};
  std::vector<VertexIndex> snapped_to;
  mpq_class snap_pixel;
  // Per phase of the folding round (0 to 2) and the round of pairs apart (3).
  std::array<std::array<std::vector<std::pair<std::uint32_t, std::uint32_t>>, attempts>, 4> fold_pairs;
  std::array<std::array<bool, attempts>, 4> fold_stalled{};
  std::optional<RoundingReach> reach;
  std::vector<Vec3> output_positions;
  std::vector<std::uint32_t> face_of_triangle;
  // Where the first attempt's triangles came from (face_triangle_origins).
  std::vector<std::uint64_t> triangle_origins;
  // The first separation certified with some fans held still (see below), the
  // last resort.
  std::optional<RoundedSolid> held_fallback;
  // Whether the piece's exact volume is within what rounding its vertices can
  // move (rounding_sweep_bound): then it may vanish whole (see below).
  std::optional<bool> thin_whole;
  const auto within_its_rounding = [&] {
    if (!thin_whole) thin_whole = piece.six() <= 6 * piece.sweep(false);
    return *thin_whole;
  };
  // The second round's steps (untangle_edges, not folding) that removed
  // four-corner sheets and were not taken, run again without them once every
  // round above has failed (so that no piece written before it existed is
  // written differently): four triangles over four corners bound a tetrahedron,
  // thin when rounding made it, but it may be a part of the solid of its own
  // that touches the rest along an edge (a union of tetrahedra sharing an edge,
  // repaired by the mesh arrangement: removing it moved more volume than
  // rounding can, and the edge, untangled, certifies).
  std::vector<std::size_t> without_quads_steps;
  for (std::size_t pass = 0; pass < all_steps + without_quads_steps.size(); ++pass) {
    const bool without_quads = pass >= all_steps;
    const std::size_t step = without_quads ? without_quads_steps[pass - all_steps] : pass;
    const bool apart = step >= snap_end;
    const bool snapping = step >= steps && !apart;
    const bool folding = (step >= plain_steps && !snapping) || apart;
    const std::size_t phase = apart ? 3 : folding ? (step - plain_steps) / fold_steps : 0;
    const bool thin_only = phase != 1 && !snapping;
    const bool inserting = folding && phase == 2;
    const std::size_t snap_retry = snapping ? (step - steps) % snap_retries : 0;
    const std::size_t attempt = snapping ? 1 + (step - steps) % snap_steps / snap_retries
                                : apart  ? 1 + (step - snap_end) / fold_retries
                                : folding ? 1 + (step - plain_steps) % fold_steps / fold_retries
                                          : step % attempts;
    if (snapping && attempt == 1 && snap_retry == 0) {
      // A new pixel size: the clusters it makes, and where they place the vertices.
      if (!reach) {
        for (VertexIndex v = 0; v < solid.defs.size(); ++v) {
          output_positions.push_back(output_position(set, solid.defs[v], solid.approx[v]));
        }
        reach.emplace(set, solid, output_positions);
      }
      const int level = snap_levels[(step - steps) / snap_steps];
      for (auto& pairs : snap_folds) pairs.clear();
      snap_stalled = {};
      snap_pixel = reach->rho * mpq_class(mpz_class(1) << level);
      snap_clusters(solid, output_positions, snap_pixel, snapped_to);
    }
    std::size_t snapped = 0;
    if (snapping) {
      for (VertexIndex v = 0; v < solid.defs.size(); ++v) snapped += snapped_to[v] != v;
    }
    if (snapping && ((snap_retry > 0 && (snap_folds[attempt].empty() || snap_stalled[attempt])))) {
      continue;
    }
    const bool untangle_edges = step >= attempts;
    // The second round's pairs start every phase; each phase adds its own.
    auto& folds = fold_pairs[phase];
    auto& folds_stalled = fold_stalled[phase];
    if (folding && (folds[attempt].empty() || folds_stalled[attempt])) continue;
    Mesh mesh;
    std::size_t merged = 0, folded_faces = 0;
    ValidationReport report;
    triangulate(set, solid, options, attempt, mesh, merged, &mesh_vertex_of, attempt > 0, untangle_edges,
                folding    ? std::span<const std::pair<std::uint32_t, std::uint32_t>>(folds[attempt])
                : snapping ? std::span<const std::pair<std::uint32_t, std::uint32_t>>(snap_folds[attempt])
                           : std::span<const std::pair<std::uint32_t, std::uint32_t>>(),
                untangle_edges ? &face_of_triangle : nullptr, &folded_faces, thin_only,
                snapping ? std::span<const VertexIndex>(snapped_to) : std::span<const VertexIndex>(),
                snapping ? &snap_pixel : nullptr, apart, fold_merge,
                step == 0 && !options.face_triangle_origins.empty() ? &triangle_origins : nullptr);
    std::size_t inserted = 0;
    if (inserting) {
      if (!reach) {
        for (VertexIndex v = 0; v < solid.defs.size(); ++v) {
          output_positions.push_back(output_position(set, solid.defs[v], solid.approx[v]));
        }
        reach.emplace(set, solid, output_positions);
      }
      inserted = insert_vertices_into_crossed_triangles(set, solid, *reach, mesh, face_of_triangle);

    }
    // (Not when folds were merged: their volume is held to its bound below.)
    if (solid.convex && merged == 0 && !folding && certify_star_shaped(mesh, vertex_average(mesh))) {
      // A convex solid's rounding certified in O(T) exact orientations.
      result.mesh = std::move(mesh);
      result.merged_vertices = 0;
      result.retriangulated_faces = attempt == 0 ? 0 : solid.faces.size();
      result.attempt = snapping ? -1 : static_cast<int>(attempt);
      if (options.keep_vertex_map && result.attempt >= 0) result.mesh_vertex_of = mesh_vertex_of;
      result.valid = true;
      return result;
    } else {
      // Only the first rounding triangulates the exact solid's faces over their
      // own vertices, and only with none merged are they all apart.
      const ExactVertexSource source{solid, mesh_vertex_of};
      report = certify_rounded(mesh, options, step == 0 && merged == 0 ? &source : nullptr,
                               step == 0 ? std::span<const std::uint64_t>(triangle_origins) : std::span<const std::uint64_t>());
      if (mesh.triangles.empty()) {
        // Every vertex rounded onto a few points and the whole piece flattened
        // away: no defect is left to name, but nothing is left either.
        report.defects.push_back({DefectKind::zero_area_triangle, solid.faces.size(),
                                  "the whole piece (it is thinner than the rounding of its coordinates)"});
      }
    }
    if (step == 0) {
      first_report = report;
      // The first attempt's mesh is what a piece that cannot be certified
      // reports; one certified now is returned below without reading it.
      if (!report.valid()) result.mesh = mesh;
      result.merged_vertices = merged;
    }
    // Parts that rounded flat (two-sided sheets) vanish; if that is all of the
    // piece, the piece vanishes (below). The report is then the sheetless mesh's.
    if (!report.valid() && !mesh.triangles.empty()) {
      Mesh sheetless = mesh;
      std::vector<VertexIndex> renumbered;
      std::vector<std::uint32_t> kept;
      std::size_t quad_triangles = 0;
      if (const std::size_t gone = cancel_two_sided_sheets(sheetless, renumbered, untangle_edges && !without_quads,
                                                           untangle_edges ? &kept : nullptr, &quad_triangles);
          gone > 0) {
        // Once per step: taken, it returns and the list is never read.
        if (quad_triangles > 0 && untangle_edges && !folding && !snapping) without_quads_steps.push_back(step);
        if (sheetless.triangles.empty()) {
          // A repair that merged folds or snapped vertices can flatten a piece
          // that is not thin (it merged across a thick part): when the piece
          // cannot vanish whole (below), the later repairs are tried instead.
          if ((folding || snapping) && !within_its_rounding()) continue;
          flattened_whole = true;
          break;
        }
        sheets_cancelled = gone;
        mesh = std::move(sheetless);
        // The separation below names vertices by their new numbers.
        for (VertexIndex& v : mesh_vertex_of) {
          if (v != no_index) v = renumbered[v];
        }
        if (untangle_edges) {
          for (std::uint32_t& t : kept) t = face_of_triangle[t];
          face_of_triangle = std::move(kept);
        }
        report = certify_rounded(mesh, options);
      } else {
        sheets_cancelled = 0;
      }
    }
    // The faces this attempt folded (what is left once sheets vanished), for
    // the folding round: only a repair attempt (1 to 3) of the second round or
    // the folding round collects them.
    if (snapping && !report.valid() && !mesh.triangles.empty()) {
      const std::size_t before = snap_folds[attempt].size();
      add_folded_face_pairs(mesh, face_of_triangle, snap_folds[attempt]);
      if (snap_folds[attempt].size() == before) snap_stalled[attempt] = true;
    }
    if (untangle_edges && attempt > 0 && !snapping && !report.valid() && !mesh.triangles.empty()) {
      const std::size_t before = folds[attempt].size();
      add_folded_face_pairs(mesh, face_of_triangle, folds[attempt]);
      if (!folding) fold_pairs[1][attempt] = fold_pairs[2][attempt] = fold_pairs[3][attempt] = folds[attempt];
      if (folding && folds[attempt].size() == before) folds_stalled[attempt] = true;
    }
    if (report.valid()) {
      RoundedSolid written = copy_without_mesh(result);
      written.mesh = std::move(mesh);
      written.merged_vertices = merged;
      written.retriangulated_faces = attempt == 0 ? 0 : solid.faces.size();
      written.vanished_triangles = sheets_cancelled;
      written.folded_faces = folded_faces;
      written.inserted_vertices = inserted;
      written.snapped_vertices = snapped;
      // The volume the repairs moved is held to the bound of what rounding can
      // move, or the mesh is not taken (fuzz_slice corpus: cube-off-cap-routed-
      // through-vertex.bin, taken at the first round beyond the bound it reported).
      const bool within = !(sheets_cancelled > 0 || folding || snapping) ||
                          report_moved_volume(measured_moved_volume(piece, written.mesh), written);
      if (within) {
        const bool plain = merged == 0 && sheets_cancelled == 0 && inserted == 0 && !folding && !snapping;
        written.attempt = plain ? static_cast<int>(attempt) : -1;
        if (options.keep_vertex_map && plain) written.mesh_vertex_of = mesh_vertex_of;
        written.valid = true;
        return written;
      }
      // A fold merged over more than rounding can move: retrying with the
      // same pairs would only do it again.
      if (folding) folds_stalled[attempt] = true;
      if (snapping) snap_stalled[attempt] = true;
      continue;
    }
    // The piece may touch itself, exactly (see separate_touching): only then is
    // what is left a pinched vertex or an intersection, on a closed oriented mesh.
    const bool may_touch = !options.allow_self_intersections &&
                           std::all_of(report.defects.begin(), report.defects.end(), [&](const Defect& d) {
                             return d.kind == DefectKind::non_manifold_vertex ||
                                    d.kind == DefectKind::self_intersection ||
                                    (untangle_edges && d.kind == DefectKind::non_manifold_edge);
                           });
    if (!may_touch) continue;
    // The second round repeats the first but for the edges: nothing else to try.
    // (The folding round meets new meshes: a fold merged can leave a pinch.)
    if (untangle_edges && !folding && !snapping && report.find(DefectKind::non_manifold_edge) == nullptr) continue;
    std::vector<std::uint32_t> partner;
    if (report.find(DefectKind::non_manifold_edge) != nullptr) {
      std::optional<std::vector<std::uint32_t>> paired = pair_around_non_manifold_edges(mesh);
      if (!paired) continue;
      partner = std::move(*paired);
    }
    if (!touching_caps) touching_caps = corners_touching_caps(set, solid);
    touching.clear();
    for (const VertexIndex v : *touching_caps) {
      if (mesh_vertex_of[v] != no_index) touching.push_back(mesh_vertex_of[v]);
    }
    // The smallest move that certifies: a few bits below the neighbours' distance
    // first, then further. Returns the mesh separated with the fans `held` keep
    // still when it certifies within the volume bound; else leaves in `crossed`
    // the last separated mesh that failed validation (empty when none did).
    const auto separate = [&](std::span<const std::uint8_t> held, Mesh& crossed) -> std::optional<RoundedSolid> {
      crossed = Mesh{};
      for (const int bits : {40, 30, 20}) {
        Mesh separated = mesh;
        const Separation separation = separate_touching(separated, touching, std::ldexp(1.0, -bits), partner, held);
        if (separation.moved == 0) break;
        if (!validate_knowing(separated, options, {}, false).valid()) {
          crossed = std::move(separated);
          continue;
        }
        RoundedSolid written = copy_without_mesh(result);
        written.mesh = std::move(separated);
        written.merged_vertices = merged;
        written.retriangulated_faces = attempt == 0 ? 0 : solid.faces.size();
        written.separated_vertices = separation.moved;
        written.vanished_triangles = sheets_cancelled;
        written.folded_faces = folded_faces;
        written.inserted_vertices = inserted;
        written.snapped_vertices = snapped;
        MovedVolume moved{separation.volume_change, separation.volume_bound};
        if (sheets_cancelled > 0 || folding || snapping) {
          // The sheets' or the folds' volume as well: measured against the exact piece.
          moved = measured_moved_volume(piece, written.mesh);
          moved.bound += separation.volume_bound;
        }
        // Held to the bound, as above (a fold's wedge is thinner than the
        // rounding, so its volume is within it).
        if (!report_moved_volume(moved, written)) break;
        written.valid = true;
        return written;
      }
      return std::nullopt;
    };
    Mesh crossed;
    if (std::optional<RoundedSolid> written = separate({}, crossed)) return std::move(*written);
    // Every fan moving along its mean edge can push a fan into another's wedge:
    // a nearly flat fan (b9_mesh's union: the top of a solid whose conical
    // cavity touches it from below at a vertex) has a mean edge of no clear
    // direction, here into the solid, where the cavity's copy moves too. The
    // fans of the vertices of the triangles that crossed then keep their first
    // fan still and move only the others' copies (as step 9 of the repair
    // separates touching parts, repair_touching.hpp). Kept aside, and taken only
    // when every round here and below has failed, so that no piece certified
    // before it existed is written differently (not in the rounds of a refined
    // solid, whose failure lets the wedge split try its next plane).
    if (collapse_wedges && !held_fallback && !crossed.triangles.empty()) {
      std::vector<Triangle> shaped;
      std::vector<std::uint32_t> shaped_index;
      shaped_triangles(crossed, shaped, shaped_index);
      const std::vector<TrianglePair> pairs = self_intersecting_pairs(crossed.positions, shaped);
      if (!pairs.empty()) {
        std::vector<std::uint8_t> held(crossed.positions.size(), 0);
        for (const TrianglePair& pair : pairs) {
          for (const std::size_t t : {pair.first, pair.second}) {
            for (const VertexIndex v : shaped[t]) held[v] = 1;
          }
        }
        held_fallback = separate(held, crossed);
      }
    }
  }
  // A piece that cannot be certified and whose whole volume is within what the
  // rounding of its vertices can move (rounding_sweep_bound) is thinner than the
  // rounding of its coordinates: it vanishes whole, its volume moving to its
  // neighbours across the cut. A piece that rounded onto two-sided sheets or onto
  // a few points has no volume left, so it always qualifies, by the bound's
  // argument; the test is made all the same, exactly.
  const mpq_class six = piece.six();
  const mpq_class sweep = piece.sweep(false);
  if (six <= 6 * sweep) {
    const bool was_empty = result.mesh.triangles.empty();
    result.mesh = Mesh{};
    result.collapsed = true;
    result.moved_volume = mpq_class(six / 6).get_d();
    result.moved_volume_bound = sweep.get_d();
    // The first attempt's defect, or the collapse itself when no triangle was left to
    // have one.
    result.defect = flattened_whole ? "the whole piece (it rounds onto two-sided sheets: it is thinner than the "
                                      "rounding of its coordinates)"
                    : was_empty ? first_report.summary()
                                : "the whole piece (its volume is within what the rounding of its coordinates "
                                  "moves): " + first_report.summary();
    return result;
  }
  // The wedges beyond rounding's reach (see split_faces_along): the faces folded
  // against a cap, per cap plane, split along a plane offset from it into the
  // piece by 2, 1 and 4 times the rounding move, each refined solid rounded
  // again by every round above. Not for a union of parts (its caller keeps the
  // parts when it fails) nor for a solid allowed to cross itself.
  if (collapse_wedges && options.parts.empty() && !options.allow_self_intersections) {
    std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
    for (const auto& phase : fold_pairs) {
      for (const auto& found : phase) pairs.insert(pairs.end(), found.begin(), found.end());
    }
    for (const auto& found : snap_folds) pairs.insert(pairs.end(), found.begin(), found.end());
    // (cap face, face folded against it), the cap on a cut plane and the other
    // face on another plane; in order of the cap plane, then the face.
    std::vector<std::pair<std::uint32_t, std::uint32_t>> against;
    for (const auto& [f, g] : pairs) {
      for (const auto& [c, o] : {std::pair{f, g}, std::pair{g, f}}) {
        if (c < solid.faces.size() && o < solid.faces.size() && solid.faces[c].plane.is_cut() &&
            solid.faces[c].plane != solid.faces[o].plane) {
          against.emplace_back(c, o);
        }
      }
    }
    const auto plane_bits = [&](std::uint32_t f) { return solid.faces[f].plane.bits; };
    std::sort(against.begin(), against.end(), [&](const auto& x, const auto& y) {
      return plane_bits(x.first) != plane_bits(y.first) ? plane_bits(x.first) < plane_bits(y.first) : x < y;
    });
    if (!reach) {
      for (VertexIndex v = 0; v < solid.defs.size(); ++v) {
        output_positions.push_back(output_position(set, solid.defs[v], solid.approx[v]));
      }
      reach.emplace(set, solid, output_positions);
    }
    // Three passes: the wedge split as it was, then, when every plane has failed,
    // the strips thin by their corners merged into the caps
    // (round_merging_thin_strips), first on the piece itself, then on each
    // refined solid of the first pass instead of the rounds above; last, the
    // split widened to every face that meets the cap's plane as well
    // (`to_the_cap`, see widen_to_near_faces), rounded by the rounds above.
    for (const int pass : {0, 1, 2}) {
      const bool strips = pass == 1;
      const bool to_the_cap = pass == 2;
      if (strips) {
        if (std::optional<RoundedSolid> written =
                round_merging_thin_strips(set, solid, options, output_positions, *reach, snap_levels, piece)) {
          return std::move(*written);
        }
      }
      for (std::size_t i = 0; i < against.size();) {
        std::size_t j = i;
        std::vector<std::uint32_t> faces;
        while (j < against.size() && plane_bits(against[j].first) == plane_bits(against[i].first)) {
          faces.push_back(against[j++].second);
        }
        std::sort(faces.begin(), faces.end());
        faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
        const SolidFace& cap = solid.faces[against[i].first];
        i = j;
        const Plane& cut = set.cuts[cap.plane.index()];
        const double largest = std::max({std::fabs(cut.normal.x), std::fabs(cut.normal.y), std::fabs(cut.normal.z)});
        // When every plane has failed on the faces found folded (corpus cases 364
        // and 988: the cap passes a fraction of the rounding move over the tip of
        // a wedge between two earlier caps, or along a fan of an earlier cap
        // whose corners lie ulps from it, and faces the certification never
        // reached fold once the first ones merged), the split takes every face
        // with a corner strictly inside the piece within reach of the cap's plane
        // (exactly), so that all the strips by the cap are thin by their
        // corners, and the refined solid is rounded with its folds merged by
        // groups (FoldMerge::groups), then by groups with faces facing one way
        // too (groups_one_way). Adds the faces to `split` (kept sorted).
        // The last pass (`to_the_cap`) also takes every convex face with a corner
        // on the cap's plane: along the tip of a wedge between the cap and an
        // earlier cap nearly parallel to it (smoke corpus seed 7 case 28's other
        // piece: the earlier cap's triangles cross the new plane at 1e-9 rad, their
        // far corners 1e5 rounding moves off it), every face crossing the cap is
        // thin near its crossing line and may fold there once the first folds
        // merge, though none has a corner strictly inside within reach; split all
        // along the offset plane, the whole band by the cap is strips thin by
        // their corners, which the groups merge into the cap.
        FoldMerge refined_merge = FoldMerge::pairs;
        const auto widen_to_near_faces = [&](const SolidFace& c, std::vector<std::uint32_t>& split) {
          const PlaneReach near = reach->near(c.plane);
          const Sign inside = c.reversed ? Sign::positive : Sign::negative;
          const std::size_t before = split.size();
          for (std::uint32_t f = 0; f < solid.faces.size(); ++f) {
            const SolidFace& face = solid.faces[f];
            if (face.plane == c.plane || !face.convex || face.loop_count != 1) continue;
            if (std::binary_search(split.begin(), split.begin() + static_cast<std::ptrdiff_t>(before), f)) continue;
            for (const CornerEdge& edge : loop_edges(solid.corners, solid.loops[face.first_loop])) {
              const PlaneReach::Where where = near.locate(reach->point(edge.from));
              if ((where.side == inside || (to_the_cap && where.side == Sign::zero)) && where.within) {
                split.push_back(f);
                break;
              }
            }
          }
          std::sort(split.begin(), split.end());
        };
        // The piece refined along `split_plane` and rounded by every round above;
        // `within`: only if every crossing vertex lies strictly inside the piece and
        // at most that far from the cap's plane (an L1 distance; PlaneReach). A refinement
        // that cannot be made or rounded (a definition found degenerate, a face that
        // cannot be triangulated) leaves the refusal as it was.
        const auto refine = [&](const Plane& split_plane, const mpq_class* within,
                                bool* rounded = nullptr) -> std::optional<RoundedSolid> {
          std::vector<Plane> cuts(set.cuts.begin(), set.cuts.end());
          cuts.push_back(split_plane);
          const PlaneSet refined_set{set.points, set.inputs, set.input_approx, cuts};
          Solid refined;
          RoundedSolid written;
          try {
            const PlaneRef split_ref = PlaneRef::cut(static_cast<std::uint32_t>(cuts.size() - 1));
            if (!split_faces_along(refined_set, solid, split_ref, faces, refined)) {
              return std::nullopt;
            }
            if (within != nullptr) {
              const PlaneReach near(cut, *within);
              const Sign inside = cap.reversed ? Sign::positive : Sign::negative;
              for (VertexIndex v = static_cast<VertexIndex>(solid.defs.size()); v < refined.defs.size(); ++v) {
                const PlaneReach::Where where = near.locate(exact_coordinates(refined_set, refined.defs[v]));
                if (where.side != inside || !where.within) return std::nullopt;
              }
            }
            if (!check_solid(refined_set, refined).empty()) return std::nullopt;
            SolidMeshOptions refined_options = options;
            refined_options.face_attempts = {};
            refined_options.face_triangles = {};  // the refined solid's faces are others
            refined_options.face_triangles_first = {};
            refined_options.face_triangle_origins = {};
            if (rounded != nullptr) *rounded = true;
            if (strips) {
              std::vector<Vec3> positions;
              for (VertexIndex v = 0; v < refined.defs.size(); ++v) {
                positions.push_back(output_position(refined_set, refined.defs[v], refined.approx[v]));
              }
              RoundingReach refined_reach(refined_set, refined, positions);
              PieceVolumes refined_piece(refined_set, refined);
              std::optional<RoundedSolid> merged = round_merging_thin_strips(
                  refined_set, refined, refined_options, positions, refined_reach, snap_levels, refined_piece);
              if (!merged) return std::nullopt;
              written = std::move(*merged);
            } else {
              written = round_solid_rounds(refined_set, refined, refined_options, false, refined_merge);
            }
          } catch (const UnsupportedGeometryError&) {
            return std::nullopt;
          } catch (const std::domain_error&) {
            return std::nullopt;
          }
          if (!written.valid) return std::nullopt;
          // Held to the piece's own bound, against its exact volume (the refined
          // solid's, the same point set).
          if (!report_moved_volume(measured_moved_volume(piece, written.mesh), written)) return std::nullopt;
          written.attempt = -1;
          written.wedge_faces_split = refined.faces.size() - solid.faces.size();
          return written;
        };
        for (const FoldMerge merge : {FoldMerge::pairs, FoldMerge::groups, FoldMerge::groups_one_way}) {
          // (The strips' pass merges its own way: the faces widened once are enough.)
          if (strips && merge == FoldMerge::groups_one_way) break;
          // (The last pass widens at once: its pairs were the first pass's.)
          if (to_the_cap && merge == FoldMerge::pairs) continue;
          if (merge == FoldMerge::groups) widen_to_near_faces(cap, faces);
          refined_merge = merge;
          std::array<bool, 5> unrepresentable{};
          for (const int times : {2, 1, 4}) {
            // The piece lies behind the cap's outward normal: n.x + d < 0 when the cap
            // faces along +n, so the new plane n.x + d' = 0 with d' = d + h lies in
            // it; the doubles d' and h are whatever they round to, the plane exact.
            // The offset is held to the reach exactly (|d' - d| <= times rho max |n_i|),
            // stepping d' toward d while the rounding of d + h put it beyond: the
            // strips' corners on the new plane must lie within the thin rounds' reach.
            const mpq_class reach_offset = times * reach->rho * largest;
            const double h = reach_offset.get_d();
            double offset = cap.reversed ? cut.offset - h : cut.offset + h;
            const CoordinateReach offset_reach(reach_offset);
            while (offset != cut.offset && !offset_reach.within(offset, cut.offset)) {
              offset = std::nextafter(offset, cut.offset);
            }
            if (!(offset != cut.offset)) {
              unrepresentable[times] = true;
              continue;
            }
            if (std::optional<RoundedSolid> written = refine(Plane{cut.normal, offset}, nullptr)) {
              return std::move(*written);
            }
          }
          // No double offset within reach (the cap's offset d is large beside the
          // rounding of the corners: ulp(d) > times rho max |n_i|, corpus case 908):
          // the same plane scaled by lambda = 9/8 to 15/8, its coefficients rounded
          // to doubles and the offset stepped by 1 to 4 ulps into the piece, is tilted
          // from the cap's by the rounding of lambda n and moved by that of lambda d,
          // at a finer step than ulp(d). The first such plane whose crossing vertices
          // all lie strictly inside the piece and within the reach of the cap's plane
          // (decided exactly: the strips are thin by their corners, as above) is
          // rounded, once per reach that had no parallel plane, so a piece this
          // cannot repair costs at most two more rounds.
          for (const int times : {2, 1}) {
            if (!unrepresentable[times]) continue;
            const mpq_class within = times * reach->rho;
            bool rounded = false;
            for (int eighths = 9; eighths < 16 && !rounded; ++eighths) {
              const double lambda = eighths / 8.0;
              const Vec3 normal{lambda * cut.normal.x, lambda * cut.normal.y, lambda * cut.normal.z};
              double offset = lambda * cut.offset;
              for (int step = 0; step < 4 && !rounded; ++step) {
                offset = std::nextafter(offset, cap.reversed ? -HUGE_VAL : HUGE_VAL);
                if (std::optional<RoundedSolid> written = refine(Plane{normal, offset}, &within, &rounded)) {
                  return std::move(*written);
                }
              }
            }
          }
        }
      }
    }
  }
  if (held_fallback) return std::move(*held_fallback);
  result.defect = first_report.summary();
  result.collapsed = false;
  return result;
}

}  // namespace

}  // namespace rounding

RoundedSolid round_solid(const PlaneSet& set, const Solid& solid, const SolidMeshOptions& options) {
  RoundedSolid rounded = rounding::round_solid_rounds(set, solid, options, true);
  // A mesh written by a repair (a refined solid's, for one) has no map to keep.
  if (!rounded.valid || rounded.attempt < 0) rounded.mesh_vertex_of.clear();
  return rounded;
}

}  // namespace shatter
