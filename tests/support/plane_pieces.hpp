#pragma once
// Plane-kernel solids for the tests of the kernel's parts (split, caps,
// triangulation): input solids of generated, degenerate and corpus meshes, and
// the pieces a few cuts leave of them, whose faces have holes, are not convex,
// and have vertices met by three planes. Planes of every kind for one solid: at
// random through it, exactly through its vertices (along its edges and faces on
// lattice solids), a few ulps off those, and touching or missing it.
// Header-only, like the tests that use it.

#include <algorithm>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "shatter/generators/corpus.hpp"
#include "shatter/generators/random.hpp"
#include "shatter/generators/solids.hpp"
#include "shatter/kernel/error.hpp"
#include "shatter/kernel/io.hpp"
#include "shatter/kernel/solid.hpp"
#include "shatter/cut/cut_solid.hpp"
#include "shatter/cut/plane_input.hpp"
#include "support/degenerate.hpp"

namespace shatter::test {

/// A solid of the plane kernel with what it is defined over: its input, and the
/// cut planes so far (the solid's vertices refer to cuts[0 .. cuts.size())).
struct PlanePiece {
  std::string name;
  std::shared_ptr<const PlaneInput> input;
  std::vector<Plane> cuts;
  Solid solid;
  int depth = 0;  ///< cuts that made it

  PlaneSet set() const { return input->geometry.plane_set(cuts); }
};

/// The meshes the parts' tests run over: generated solids (convex, tori, nested
/// shells, separate solids, slivers, tiny, huge, far from the origin),
/// degenerate lattice solids (coplanar faces, holes, cavities with islands,
/// pinched regions, needles) and the small corpus meshes. `corpus_limit`:
/// corpus meshes with at most this many triangles.
inline std::vector<NamedMesh> part_test_meshes(std::size_t corpus_limit) {
  std::vector<NamedMesh> meshes = generated_meshes();
  meshes.push_back({"staircase", staircase(4)});
  meshes.push_back({"stacked-boxes", stacked_boxes(3)});
  meshes.push_back({"pinch-saddle", pinch_saddle()});
  meshes.push_back({"needle-bridge", needle_bridge(0x1p-20)});
  meshes.push_back({"nested-islands", nested_islands()});
  meshes.push_back({"box-with-through-hole", box_with_through_hole()});
  meshes.push_back({"pit-and-bump", pit_and_bump()});
  for (const auto& path : valid_meshes()) {
    Mesh mesh = read_mesh(path);
    if (mesh.triangles.size() <= corpus_limit) meshes.push_back({path.filename().string(), std::move(mesh)});
  }
  return meshes;
}

/// The approximate vertex average of a solid (rounded: it only places planes).
inline Vec3 vertex_average(const Solid& solid) {
  Vec3 sum;
  for (const ApproxPoint& a : solid.approx) sum = sum + Vec3{a.x.value / a.w.value, a.y.value / a.w.value, a.z.value / a.w.value};
  return sum * (1.0 / static_cast<double>(solid.approx.size()));
}

/// The input solid of `mesh` and the pieces of up to `cuts` successive cuts, each
/// through the vertex average of the piece with the most vertices by a random
/// plane, keeping every piece made (up to `max_pieces` in all). A plane that
/// misses or pinches a piece is drawn again.
inline std::vector<PlanePiece> plane_pieces(const NamedMesh& mesh, std::uint64_t seed, int cuts, std::size_t max_pieces) {
  auto input = std::make_shared<const PlaneInput>(prepare_plane_input(mesh.mesh));
  std::vector<PlanePiece> pieces{{mesh.name, input, {}, input->solid, 0}};
  Random random(seed);
  std::vector<std::size_t> open{0};  // pieces that may still be cut
  for (int made = 0, attempt = 0; made < cuts && attempt < 8 * cuts && pieces.size() < max_pieces; ++attempt) {
    std::size_t largest = open.front();
    for (const std::size_t i : open) {
      if (pieces[i].solid.vertex_count() > pieces[largest].solid.vertex_count()) largest = i;
    }
    PlanePiece parent = pieces[largest];
    const Vec3 normal = random.direction();
    parent.cuts.push_back({normal, -dot(normal, vertex_average(parent.solid))});
    const PlaneSet set = parent.set();
    SolidCut cut;
    try {
      cut = cut_solid(set, parent.solid, PlaneRef::cut(static_cast<std::uint32_t>(parent.cuts.size() - 1)),
                      static_cast<SurfaceId>(parent.cuts.size()), input->shells);
    } catch (const UnsupportedGeometryError&) {
      continue;  // pinched: another plane
    }
    if (cut.plane_missed) continue;
    ++made;
    open.erase(std::find(open.begin(), open.end(), largest));
    for (const auto* side : {&cut.below, &cut.above}) {
      for (const Solid& solid : *side) {
        if (pieces.size() >= max_pieces) break;
        open.push_back(pieces.size());
        pieces.push_back({mesh.name + " cut " + std::to_string(parent.cuts.size()), input, parent.cuts, solid,
                          parent.depth + 1});
      }
    }
  }
  return pieces;
}

/// A test plane and what it is.
struct PartPlane {
  Plane plane;
  enum Kind { random, through_vertex, through_face, ulps_off, touching, missing } kind;
};

/// Planes for one piece: `random_count` through random points of its box, an
/// axis plane exactly through a random input-point vertex and the same plane
/// moved 1 to 3 ulps, an axis plane through its extreme input vertex on a random
/// axis (touching it when no vertex lies beyond), the plane of a random input
/// face through three of its points (exact on lattice solids) and that plane
/// moved 1 to 3 ulps, and two planes beyond it, one on either side.
inline std::vector<PartPlane> part_planes(const PlanePiece& piece, std::uint64_t seed, int random_count) {
  Random random(seed);
  const Solid& solid = piece.solid;
  Vec3 lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
  std::vector<Vec3> inputs;  // the piece's vertices that are input points, exactly
  for (std::size_t v = 0; v < solid.defs.size(); ++v) {
    const ApproxPoint& a = solid.approx[v];
    const Vec3 p{a.x.value / a.w.value, a.y.value / a.w.value, a.z.value / a.w.value};
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
    if (solid.defs[v].kind == PointKind::input) inputs.push_back(piece.input->geometry.points[solid.defs[v].a]);
  }
  std::vector<PartPlane> planes;
  for (int i = 0; i < random_count; ++i) {
    const Vec3 p{random.uniform(lo.x, hi.x), random.uniform(lo.y, hi.y), random.uniform(lo.z, hi.z)};
    planes.push_back({plane_through(p, random.direction()), PartPlane::random});
  }
  if (!inputs.empty()) {
    const Plane exact = axis_plane_through(inputs[random.index(inputs.size())], static_cast<int>(random.index(3)));
    planes.push_back({exact, PartPlane::through_vertex});
    planes.push_back({offset_by_ulps(exact, 1 + static_cast<int>(random.index(3))), PartPlane::ulps_off});
    const int axis = static_cast<int>(random.index(3));
    Vec3 top = inputs.front();
    for (const Vec3& p : inputs) {
      if (p[axis] > top[axis]) top = p;
    }
    planes.push_back({axis_plane_through(top, axis), PartPlane::touching});
  }
  const SolidFace& face = solid.faces[random.index(solid.faces.size())];
  if (!face.plane.is_cut()) {
    const auto& through = piece.input->geometry.planes[face.plane.index()];
    const auto& points = piece.input->geometry.points;
    const Plane exact = plane_through_points(points[through[0]], points[through[1]], points[through[2]]);
    planes.push_back({exact, PartPlane::through_face});
    planes.push_back({offset_by_ulps(exact, -1 - static_cast<int>(random.index(3))), PartPlane::ulps_off});
  }
  // Beyond the box by a margin far above rounding: the piece wholly below the
  // first plane, wholly above the second.
  const double margin = norm(hi - lo) + 1;
  planes.push_back({{{1, 0, 0}, -(hi.x + margin)}, PartPlane::missing});
  const Vec3 n{0.3, -1, 0.2};
  const double lowest = (n.x > 0 ? n.x * lo.x : n.x * hi.x) + (n.y > 0 ? n.y * lo.y : n.y * hi.y) +
                        (n.z > 0 ? n.z * lo.z : n.z * hi.z);
  planes.push_back({{n, -lowest + margin}, PartPlane::missing});
  return planes;
}

}  // namespace shatter::test
