#include "robustness/robustness.hpp"

#include <gmpxx.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <fstream>
#include <limits>
#include <optional>
#include <set>
#include <sstream>

#include "shatter/generators/corpus.hpp"
#include "shatter/generators/random.hpp"
#include "shatter/generators/solids.hpp"
#include "shatter/kernel/error.hpp"
#include "shatter/kernel/exact.hpp"
#include "shatter/kernel/implicit.hpp"
#include "shatter/kernel/io.hpp"
#include "shatter/kernel/predicates.hpp"
#include "shatter/kernel/rationals.hpp"
#include "shatter/kernel/solid.hpp"
#include "shatter/kernel/validate.hpp"
#include "shatter/meshtree/build.hpp"
#include "shatter/cut/plane_cut.hpp"
#include "shatter/formats/file.hpp"
#include "shatter/cut/plane_input.hpp"
#include "shatter/triangulate/solid_mesh.hpp"
#include "support/checks.hpp"
#include "support/degenerate.hpp"

namespace shatter::robust {
namespace {

using test::Random;

constexpr std::array<std::string_view, case_class_count> class_names{
    "random-plane",   "vertex-plane",  "vertex-plane-ulps", "edge-plane",          "edge-plane-ulps",
    "face-plane",     "face-plane-ulps", "many-vertices",   "coplanar-faces",      "slivers-needles",
    "nested-shells",  "pinch",         "near-parallel-chain", "extreme-scale",     "far-from-origin",
    "attribute-seams"};

// Meshes above this size take 16-fragment fractures and far shifts only rarely:
// they would dominate a run's time without adding new kinds of trouble.
constexpr std::size_t large_mesh_triangles = 3000;

std::uint64_t mix(std::uint64_t seed, std::uint64_t index) {
  Random random(seed ^ (index * 0xD1B54A32D192ED03ull));
  return random.next();
}

Vec3 random_point_in(const test::Box3& box, Random& random) {
  return {random.uniform(box.lo.x, box.hi.x), random.uniform(box.lo.y, box.hi.y), random.uniform(box.lo.z, box.hi.z)};
}

Vec3 random_vertex(const Mesh& mesh, Random& random) { return mesh.positions[random.index(mesh.positions.size())]; }

int random_ulps(Random& random) {
  const int magnitude = 1 + int(random.index(4));
  return random.index(2) ? magnitude : -magnitude;
}

// A small-integer normal: planes through lattice points stay exact.
Vec3 small_integer_normal(Random& random) {
  for (;;) {
    const Vec3 n{double(random.index(5)) - 2, double(random.index(5)) - 2, double(random.index(5)) - 2};
    if (n.x != 0 || n.y != 0 || n.z != 0) return n;
  }
}

// A mesh of the pool with at most max_triangles. Large meshes are drawn a quarter
// as often as the others: each still gets its share of every class, without
// dominating the run's time.
const std::pair<std::string, Mesh>& pick(const MeshPool& pool, Random& random, std::size_t max_triangles) {
  for (;;) {
    const auto& candidate = pool.meshes[random.index(pool.meshes.size())];
    const std::size_t size = candidate.second.triangles.size();
    if (size > max_triangles || (size > large_mesh_triangles && random.index(4) != 0)) continue;
    return candidate;
  }
}

// A plane of the given class for `mesh` (the mesh classes get planes suited to
// their lattice coordinates in make_case itself).
Plane plane_of_class(CaseClass kind, const Mesh& mesh, Random& random) {
  const Triangle& t = mesh.triangles[random.index(mesh.triangles.size())];
  const Vec3 a = mesh.positions[t[0]], b = mesh.positions[t[1]], c = mesh.positions[t[2]];
  switch (kind) {
    case CaseClass::vertex_plane:
    case CaseClass::vertex_plane_ulps: {
      const Plane plane = random.index(2) ? test::axis_plane_through(a, int(random.index(3)))
                                          : test::plane_through(a, random.direction());
      return kind == CaseClass::vertex_plane ? plane : test::offset_by_ulps(plane, random_ulps(random));
    }
    case CaseClass::edge_plane:
    case CaseClass::edge_plane_ulps: {
      const Plane plane = test::plane_through(a, cross(b - a, random.index(2) ? small_integer_normal(random)
                                                                              : random.direction()));
      return kind == CaseClass::edge_plane ? plane : test::offset_by_ulps(plane, random_ulps(random));
    }
    case CaseClass::face_plane:
    case CaseClass::face_plane_ulps: {
      const Plane plane = test::plane_through_points(a, b, c);
      return kind == CaseClass::face_plane ? plane : test::offset_by_ulps(plane, random_ulps(random));
    }
    default: {
      const test::Box3 box = test::bounds(mesh);
      return test::plane_through(random_point_in(box, random), random.direction());
    }
  }
}

// A lattice plane for a lattice mesh: an axis or small-integer normal through one
// of its vertices, exactly.
Plane lattice_plane(const Mesh& mesh, Random& random) {
  const Vec3 v = random_vertex(mesh, random);
  if (random.index(2)) return test::axis_plane_through(v, int(random.index(3)));
  return test::plane_through(v, small_integer_normal(random));
}

Mesh scaled_by_power_of_two(Mesh mesh, int exponent) {
  for (Vec3& p : mesh.positions) p = {std::ldexp(p.x, exponent), std::ldexp(p.y, exponent), std::ldexp(p.z, exponent)};
  return mesh;
}

bool is_valid_solid(const Mesh& mesh) { return validate_mesh(mesh).valid(); }

// The mesh with its vertices numbered in order of first use by the triangles, as
// every reader numbers them: the reproducer's OBJ then reads back as this very
// mesh, so a replay cuts the same solid (the plane kernel's point definitions
// name input points by index).
Mesh in_first_use_order(Mesh mesh) {
  constexpr VertexIndex unseen = std::numeric_limits<VertexIndex>::max();
  std::vector<VertexIndex> renumbered(mesh.positions.size(), unseen);
  std::vector<Vec3> positions;
  positions.reserve(mesh.positions.size());
  for (Triangle& t : mesh.triangles) {
    for (VertexIndex& v : t) {
      if (renumbered[v] == unseen) {
        renumbered[v] = static_cast<VertexIndex>(positions.size());
        positions.push_back(mesh.positions[v]);
      }
      v = renumbered[v];
    }
  }
  mesh.positions = std::move(positions);
  return mesh;
}

std::string describe(const Plane& p) {
  std::ostringstream out;
  out.precision(17);
  out << "(" << p.normal.x << ", " << p.normal.y << ", " << p.normal.z << "; " << p.offset << ")";
  return out.str();
}

// --- checks ---------------------------------------------------------------

// The rounded meshes' volume promise: the pieces' volumes sum to the parent's
// within 1e-9 relative, plus what rounding each cut point by half an ulp of the
// largest coordinate can move across the surface (matters far from the origin).
// `vanished_bound`: the most that pieces thinner than their rounding took with
// them when they vanished (BuildReport::vanished_volume_bound), 0 for a slice.
bool rounded_volumes_add_up(const mpq_class& parent_six, const mpq_class& pieces_six, const Mesh& parent,
                            double vanished_bound = 0) {
  const double difference = std::fabs(mpq_class(pieces_six - parent_six).get_d());
  const double rounding = 2 * std::numeric_limits<double>::epsilon() * test::largest_coordinate(parent) * test::surface_area(parent);
  return difference <= 1e-9 * std::fabs(parent_six.get_d()) + 6 * rounding + 6 * vanished_bound;
}

// Attribute channels survive a cut: present in every piece exactly when present
// in the input, finite, normals of unit length; surface ids are the input's own
// or the new cap's.
std::string channel_problem(const Mesh& piece, const Mesh& parent) {
  if (piece.corners.has_normals() != parent.corners.has_normals()) return "normals channel lost or invented";
  if (piece.corners.has_uvs() != parent.corners.has_uvs()) return "uv channel lost or invented";
  if (piece.corners.has_tangents() != parent.corners.has_tangents()) return "tangent channel lost or invented";
  for (const Vec3& n : piece.corners.normals) {
    if (!is_finite(n) || std::fabs(norm(n) - 1) > 1e-9) return "a corner normal is not a finite unit vector";
  }
  for (const Vec2& uv : piece.corners.uvs) {
    if (!std::isfinite(uv.x) || !std::isfinite(uv.y)) return "a corner uv is not finite";
  }
  return {};
}

std::string surface_problem(const Mesh& piece, const std::set<SurfaceId>& allowed) {
  for (SurfaceId s : piece.surfaces) {
    if (!allowed.count(s)) return "surface id " + std::to_string(s) + " is neither the input's nor a cap's";
  }
  return {};
}

// What reading a written piece back showed: `mismatch` when the file does not
// read back as the mesh written (refused, or other triangles or positions): a
// broken promise of the writers and readers whatever the kernel; else the
// validation of what was read, in full (self-intersections included).
struct ReadBack {
  std::string mismatch;
  ValidationReport report;
};

ReadBack write_and_read_back(const Mesh& mesh, MeshFormat format) {
  ReadBack back;
  const std::string bytes = write_mesh_to_bytes(mesh, format);
  Mesh read;
  try {
    read = read_mesh_from_bytes(bytes, format);
  } catch (const std::exception& e) {
    back.mismatch = std::string("the written ") + std::string(format_name(format)) + " does not read back: " + e.what();
    return back;
  }
  // The reader numbers vertices by first use and welds equal positions: compare
  // triangle by triangle, corner by corner.
  if (read.triangles.size() != mesh.triangles.size()) {
    back.mismatch = "read back with " + std::to_string(read.triangles.size()) + " triangles, written with " +
                    std::to_string(mesh.triangles.size());
    return back;
  }
  for (std::size_t t = 0; t < read.triangles.size(); ++t) {
    for (int k = 0; k < 3; ++k) {
      const Vec3 a = read.positions[read.triangles[t][k]], b = mesh.positions[mesh.triangles[t][k]];
      if (!(a.x == b.x && a.y == b.y && a.z == b.z)) {
        back.mismatch = "read back with other positions (triangle " + std::to_string(t) + ")";
        return back;
      }
    }
  }
  back.report = validate_mesh(read);
  return back;
}

struct Checker {
  const Case& c;
  CaseOutcome& outcome;

  void fail(std::string what) { outcome.failures.push_back(std::move(what)); }

  // Runs a check, charging the plane-kernel predicate calls it makes to the
  // checker rather than the kernel.
  template <class F>
  auto as_checker(F&& check) {
    const ImplicitCounters before = implicit_counters();
    auto result = check();
    const ImplicitCounters& now = implicit_counters();
    ImplicitCounters& to = outcome.checker_predicates;
    to.side_calls += now.side_calls - before.side_calls, to.side_exact += now.side_exact - before.side_exact;
    to.orient_calls += now.orient_calls - before.orient_calls;
    to.orient_exact += now.orient_exact - before.orient_exact;
    to.order_calls += now.order_calls - before.order_calls, to.order_exact += now.order_exact - before.order_exact;
    return result;
  }

  // Writes an output piece in the case's format, reads it back and validates what
  // was read in full. A piece invalid as written is a failure: every piece the
  // library returns without a defect is certified.
  void check_written(const Mesh& mesh, const std::string& where) {
    ++outcome.written;
    const ReadBack back = write_and_read_back(mesh, c.format);
    if (!back.mismatch.empty()) {
      ++outcome.invalid_written;
      fail(where + ": " + back.mismatch);
      return;
    }
    if (!back.report.valid()) {
      ++outcome.invalid_written;
      fail(where + ": invalid as written (" + std::string(format_name(c.format)) + "): " + back.report.summary());
    }
  }

  // --- slices ----------------------------------------------------------------

  // A piece's size on its vertices' approximations: the area, summed perimeter
  // and count of its faces' fan triangles, and its largest coordinate.
  struct Extent {
    double area = 0, perimeter = 0, triangles = 0, largest = 0;
    /// The most volume moving every point by at most delta can sweep (Steiner's
    /// bound over the fan triangles, as round_solid's with pi taken as 4).
    double sweep(double delta) const { return delta * (2 * area + delta * (4 * perimeter + 5 * delta * triangles)); }
    /// Twice the volume over the area: a slab's thickness.
    double thickness(const mpq_class& six) const { return area > 0 ? 2 * std::fabs(mpq_class(six / 6).get_d()) / area : 0; }
  };
  // Measured on the exact corners, each rounded to the nearest double: the
  // corners' approximations can be no finite point at all (a w near zero),
  // which gave a piece no area and failed a legitimate vanish (shatter-fuzz
  // --class face-plane --seed 20261129: torus-huge-1e6, seed 4159175719316230272).
  static Extent extent(const PlaneSet& set, const Solid& solid) {
    std::vector<Vec3> points;
    Extent e;
    for (const PointDef& def : solid.defs) {
      const std::array<mpq_class, 3> exact = exact_coordinates(set, def);
      points.push_back({exact[0].get_d(), exact[1].get_d(), exact[2].get_d()});
      e.largest = std::max({e.largest, std::fabs(points.back().x), std::fabs(points.back().y), std::fabs(points.back().z)});
    }
    for (const SolidFace& face : solid.faces) {
      const Vec3 centre = points[solid.corners[solid.loops[face.first_loop].first_corner].vertex];
      for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
        for (const CornerEdge& edge : loop_edges(solid.corners, solid.loops[l])) {
          const Vec3 b = points[edge.from], c = points[edge.to];
          e.area += 0.5 * norm(cross(b - centre, c - centre));
          e.perimeter += norm(b - centre) + norm(c - b) + norm(centre - c);
          e.triangles += 1;
        }
      }
    }
    return e;
  }

  // A piece of a chain: its exact solid, six times its exact volume,
  // and its rounded mesh when round_solid could write it (the next cut's
  // certification trusts it, as the builder's does).
  struct PlanePiece {
    Solid solid;
    mpq_class six;
    std::optional<Mesh> rounded;
  };

  // One cut of `parent` by cut plane i of `set` (the library's one
  // cut call, cut_by_plane), every promise checked: it refuses only a pinch
  // (counted); plane_missed agrees with the exact sides of the vertices; every
  // piece sound (check_solid) with a positive exact volume, the volumes summing to
  // the parent's exactly; every piece's mesh, when it has no defect, written,
  // read back and valid, and when it has one, really invalid; attributes kept.
  // Appends the pieces the chain goes on with.
  void plane_cut(const PlaneInput& input, const PlaneSet& set, const PlanePiece& parent, std::size_t i,
                 const std::set<SurfaceId>& surfaces, const std::string& where, std::vector<PlanePiece>& next) {
    const PlaneRef cut_ref = PlaneRef::cut(static_cast<std::uint32_t>(i));
    PlaneCutOptions options;
    options.cap_surface = SurfaceId(i + 1);
    PlaneCut cut;
    try {
      cut = cut_by_plane(input, set, parent.solid, parent.rounded ? &*parent.rounded : nullptr, cut_ref, options);
    } catch (const UnsupportedGeometryError& error) {
      if (std::string(error.what()).find("pinched") != std::string::npos) {
        ++outcome.plane_pinched;  // documented: the piece is not cut, and the chain stops there
        remember_refusal(i, where + ": pinched: " + error.what());
      } else {
        fail(where + ": cut_by_plane refused a sound solid: " + error.what());
      }
      return;
    }
    // The sides of the vertices: input points by side_of_plane on their doubles
    // (audited below), defined points by side().
    bool any_below = false, any_above = false;
    as_checker([&] {
      for (std::size_t v = 0; v < parent.solid.defs.size(); ++v) {
        const PointDef& def = parent.solid.defs[v];
        const Sign s = def.kind == PointKind::input ? side_of_plane(c.planes[i], set.points[def.a])
                                                    : side(set, cut_ref, def, parent.solid.approx[v]);
        any_below |= s == Sign::negative;
        any_above |= s == Sign::positive;
      }
      return true;
    });
    if (cut.plane_missed != !(any_below && any_above)) {
      fail(where + ": plane_missed disagrees with the exact sides of the vertices");
    }
    if (cut.plane_missed) {
      if (!cut.pieces.empty()) fail(where + ": plane missed, yet pieces were returned");
      if (cut.whole_above != any_above) fail(where + ": the missed plane names the wrong side");
      next.push_back(parent);  // whole, as `shatter slice` returns it
      return;
    }
    const auto above = std::count_if(cut.pieces.begin(), cut.pieces.end(), [](const CutPiece& p) { return p.above; });
    if (above == 0 || std::size_t(above) == cut.pieces.size()) {
      fail(where + ": a cut with vertices on both sides left a side empty");
    }
    mpq_class sum = 0;
    std::size_t k = 0;
    for (CutPiece& piece : cut.pieces) {
      const std::string name = where + " piece " + std::to_string(k++);
      ++outcome.plane_pieces;
      if (std::string p = as_checker([&] { return check_solid(set, piece.solid); }); !p.empty()) {
        fail(name + ": unsound solid: " + p);
        continue;
      }
      const mpq_class six = test::exact_six_volume(set, piece.solid);
      if (six <= 0) fail(name + ": exact volume not positive");
      sum += six;
      if (piece.vanished) {
        // Thinner than the rounding of its coordinates: its exact volume, which
        // is what moves, is within the bound round_solid reports, and within
        // what moving its points by 2^-40 of its largest coordinate can sweep
        // (measured here on its own); nothing is written.
        if (!piece.mesh.triangles.empty()) fail(name + ": a vanished piece kept triangles");
        const double volume = mpq_class(six / 6).get_d();
        if (!(std::fabs(piece.moved_volume - volume) <= 1e-12 * volume)) {
          fail(name + ": a vanished piece reports another moved volume than its own");
        }
        if (!(volume <= piece.moved_volume_bound * (1 + 1e-12))) {
          fail(name + ": a vanished piece's volume is beyond the bound reported for it");
        }
        const Extent e = extent(set, piece.solid);
        if (!(volume <= e.sweep(std::ldexp(e.largest, -40)))) {
          char measured[160];
          std::snprintf(measured, sizeof measured, "volume %a, area %a, largest coordinate %a", volume, e.area,
                        e.largest);
          fail(name + ": a piece vanished that moving its points by 2^-40 of its coordinates cannot sweep (" +
               measured + ")");
        }
        ++outcome.plane_vanished;
        next.push_back({std::move(piece.solid), six, std::nullopt});
        continue;
      }
      if (!piece.defect.empty()) {
        // solid_mesh.hpp: a defect is named exactly when the mesh fails
        // validate_mesh. (Found by this runner: a cap whose corners all rounded
        // onto the edges around it failed the whole piece, though the mesh
        // closed up without it; tests/regressions holds the reproducers.)
        if (!piece.mesh.triangles.empty() && validate_mesh(piece.mesh).valid()) {
          fail(name + ": a piece named a defect, yet its mesh passes validate_mesh");
        }
        ++outcome.plane_unroundable;  // refused, as `shatter slice` refuses it (exit 3)
        const Extent e = extent(set, piece.solid);
        const double thickness = e.thickness(six);
        const std::string relative = thickness > 0 && e.largest > 0
                                         ? "2^" + std::to_string(std::ilogb(thickness) - std::ilogb(e.largest))
                                         : "0";
        remember_refusal(i, name + ": unroundable (" + std::to_string(piece.solid.faces.size()) +
                                " faces, mean thickness " + relative + " of its largest coordinate): " + piece.defect);
        next.push_back({std::move(piece.solid), six, std::nullopt});
        continue;
      }
      if (std::string p = channel_problem(piece.mesh, input.mesh); !p.empty()) fail(name + ": " + p);
      if (std::string p = surface_problem(piece.mesh, surfaces); !p.empty()) fail(name + ": " + p);
      check_written(piece.mesh, name);
      if (piece.separated_vertices > 0) {
        // Where the exact piece touched itself, the moves stay within their bound.
        ++outcome.plane_separated;
        if (!(piece.moved_volume <= piece.moved_volume_bound * (1 + 1e-12))) {
          fail(name + ": the separation moved volume " + std::to_string(piece.moved_volume) + " beyond its bound " +
               std::to_string(piece.moved_volume_bound));
        }
      }
      next.push_back({std::move(piece.solid), six, std::move(piece.mesh)});
    }
    if (sum != parent.six) fail(where + ": exact volumes do not add up to the parent's exactly");
  }

  // A refusal at cut i: named, and the chain's first i + 1 planes kept once (the
  // first refusal's; the same argument as remember_prefix).
  void remember_refusal(std::size_t i, std::string what) {
    outcome.refusals.push_back(std::move(what));
    if (outcome.refused_prefix) return;
    outcome.refused_prefix = c;
    outcome.refused_prefix->planes.resize(std::min(i + 1, c.planes.size()));
  }

  // A chain that failed at cut i is reproduced by the chain's first i + 1
  // planes on the same mesh (cut_solid is exact and deterministic: the pieces of
  // the shorter chain are those of the longer one).
  void remember_prefix(std::size_t i, std::size_t failures_before) {
    if (outcome.shrunk || outcome.failures.size() == failures_before || i + 1 >= c.planes.size()) return;
    Case smaller = c;
    smaller.planes.resize(i + 1);
    outcome.shrunk = std::move(smaller);
  }

  void slice_chain() {
    const PlaneInput input = prepare_plane_input(c.mesh);
    // Every cut plane of the chain in the set at once: cut i is PlaneRef::cut(i).
    const PlaneSet set = input.geometry.plane_set(c.planes);
    if (std::string p = as_checker([&] { return check_solid(set, input.solid); }); !p.empty()) {
      fail("the input's plane-based solid is unsound: " + p);
      return;
    }
    std::vector<PlanePiece> pieces;
    pieces.push_back({input.solid, test::exact_six_volume(set, input.solid), input.mesh});
    if (pieces[0].six != test::exact_six_volume(c.mesh)) fail("the input's plane-based solid has another volume");
    std::set<SurfaceId> surfaces(input.mesh.surfaces.begin(), input.mesh.surfaces.end());
    for (std::size_t i = 0; i < c.planes.size(); ++i) {
      surfaces.insert(SurfaceId(i + 1));
      std::vector<PlanePiece> next;
      for (std::size_t p = 0; p < pieces.size(); ++p) {
        const std::size_t before = outcome.failures.size();
        plane_cut(input, set, pieces[p], i, surfaces, "cut " + std::to_string(i) + " of piece " + std::to_string(p),
                  next);
        remember_prefix(i, before);
      }
      pieces = std::move(next);
    }
  }

  void fracture() {
    BuildReport report;
    const MeshTree tree = build_mesh_tree(c.mesh, c.recipe, {.threads = 1, .report = &report});
    if (tree.leaf_count() < c.recipe.fragments) fail("fewer leaves than fragments asked for");
    // Links, leaf ranges, meshes' indices, bonds, the exact representation: the
    // rest of this check indexes through them.
    if (const std::string problem = test::tree_problem(tree); !problem.empty()) {
      fail("the tree: " + problem);
      return;
    }
    std::vector<mpq_class> six;
    for (NodeIndex v = 0; v < tree.nodes.size(); ++v) {
      const Mesh& mesh = tree.nodes[v].mesh;
      if (std::string p = test::solid_problem(mesh); !p.empty()) fail("node " + std::to_string(v) + ": " + p);
      six.push_back(test::exact_six_volume(mesh));
    }
    check_exact_solids(tree, report);
    for (NodeIndex v = 0; v < tree.nodes.size(); ++v) {
      const MeshTreeNode& node = tree.nodes[v];
      if (node.is_leaf()) continue;
      mpq_class total = 0;
      for (NodeIndex child : node.children) total += six[child];
      if (!rounded_volumes_add_up(six[v], total, node.mesh, report.vanished_volume_bound)) {
        fail("node " + std::to_string(v) + ": children's volumes");
      }
    }
    // Every leaf written as `shatter fracture --export` writes it, read back and
    // validated.
    for (NodeIndex leaf : tree.leaf_nodes) {
      check_written(tree.nodes[leaf].mesh, "leaf node " + std::to_string(leaf));
    }
    // Invariant 4 on a quarter of the builds (it doubles their cost).
    if (c.seed % 4 == 0) {
      if (encode_shatter(build_mesh_tree(c.mesh, c.recipe, {.threads = 2})) != encode_shatter(tree)) {
        fail("1 and 2 threads built different bytes");
      }
    }
  }

  // Every node's exact solid sound over the tree's plane set, its stored mesh
  // valid with self-intersections checked, and the children's exact volumes
  // summing to their parent's exactly (the root's being the input's), but for
  // pieces that vanished: then to less, by the volume the build reports within
  // its bound.
  void check_exact_solids(const MeshTree& tree, const BuildReport& build) {
    if (tree.cut_planes.size() != tree.nodes.size()) {
      fail("tree with " + std::to_string(tree.cut_planes.size()) + " cut planes for " +
           std::to_string(tree.nodes.size()) + " nodes");
      return;
    }
    const PlaneSet set = tree.plane_set();
    std::vector<std::optional<mpq_class>> six(tree.nodes.size());
    for (NodeIndex v = 0; v < tree.nodes.size(); ++v) {
      const MeshTreeNode& node = tree.nodes[v];
      const std::string name = "node " + std::to_string(v);
      ++outcome.plane_pieces;
      if (std::string p = as_checker([&] { return check_solid(set, node.solid); }); !p.empty()) {
        fail(name + ": unsound solid: " + p);
      } else {
        six[v] = test::exact_six_volume(set, node.solid);
        if (*six[v] <= 0) fail(name + ": exact volume not positive");
      }
      const ValidationReport report = validate_mesh(node.mesh);
      if (!report.valid()) fail(name + ": stored mesh invalid: " + report.summary());
    }
    if (six[0] && *six[0] != test::exact_six_volume(c.mesh)) fail("root: exact volume is not the input's");
    mpq_class vanished_six = 0;
    for (NodeIndex v = 0; v < tree.nodes.size(); ++v) {
      const MeshTreeNode& node = tree.nodes[v];
      if (node.is_leaf() || !six[v]) continue;
      mpq_class total = 0;
      bool known = true;
      for (NodeIndex child : node.children) {
        if (six[child]) total += *six[child];
        known = known && six[child].has_value();
      }
      if (!known || total == *six[v]) continue;
      if (build.pieces_vanished > 0 && total < *six[v]) {
        vanished_six += *six[v] - total;
      } else {
        fail("node " + std::to_string(v) + ": children's exact volumes");
      }
    }
    const double vanished = mpq_class(vanished_six / 6).get_d();
    if (!(std::fabs(vanished - build.vanished_volume) <= 1e-9 * build.vanished_volume) ||
        !(build.vanished_volume <= build.vanished_volume_bound)) {
      fail("the tree's vanished volume " + std::to_string(vanished) + " is not the reported " +
           std::to_string(build.vanished_volume) + " within its bound " + std::to_string(build.vanished_volume_bound));
    }
    outcome.plane_vanished += build.pieces_vanished;
  }
};

// --- reproducer text ---------------------------------------------------------

std::string hex(double value) {
  char buffer[64];
  const auto end = std::to_chars(buffer, buffer + sizeof buffer, value, std::chars_format::hex).ptr;
  return std::string(buffer, end);
}

double parse_hex(const std::string& text) {
  double value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value, std::chars_format::hex);
  if (error != std::errc() || end != text.data() + text.size()) {
    throw InvalidMeshError("reproducer: bad hexadecimal double '" + text + "'");
  }
  return value;
}

std::optional<Strategy> parse_strategy(std::string_view name) {
  for (Strategy s : {Strategy::thesis, Strategy::balanced, Strategy::axis}) {
    if (strategy_name(s) == name) return s;
  }
  return std::nullopt;
}

// --- the predicate audit -----------------------------------------------------

// An independent exact reference for sign(n·p + d): every double is m * 2^e with
// a 53-bit integer m, so the sum is an integer times a power of two, evaluated in
// GMP integers after aligning exponents. (side_of_plane's own fall-back uses
// rationals; the two share no code.)
struct ScaledInteger {
  mpz_class mantissa;
  long exponent = 0;
};

ScaledInteger to_scaled(double x) {
  int exponent = 0;
  const double fraction = std::frexp(x, &exponent);  // x = fraction * 2^exponent, |fraction| in [0.5, 1)
  return {mpz_class(static_cast<long>(std::ldexp(fraction, 53))), long(exponent) - 53};
}

int reference_sign(const Plane& plane, Vec3 p) {
  std::array<ScaledInteger, 4> terms;
  const std::array<std::pair<double, double>, 3> products{
      {{plane.normal.x, p.x}, {plane.normal.y, p.y}, {plane.normal.z, p.z}}};
  for (int i = 0; i < 3; ++i) {
    const ScaledInteger a = to_scaled(products[i].first), b = to_scaled(products[i].second);
    terms[i] = {a.mantissa * b.mantissa, a.exponent + b.exponent};
  }
  terms[3] = to_scaled(plane.offset);
  long lowest = std::numeric_limits<long>::max();
  for (const ScaledInteger& t : terms) {
    if (t.mantissa != 0) lowest = std::min(lowest, t.exponent);
  }
  mpz_class sum = 0;
  for (const ScaledInteger& t : terms) {
    if (t.mantissa == 0) continue;
    mpz_class shifted;
    mpz_mul_2exp(shifted.get_mpz_t(), t.mantissa.get_mpz_t(), static_cast<mp_bitcnt_t>(t.exponent - lowest));
    sum += shifted;
  }
  return sgn(sum);
}

// A double with a `bits`-bit random mantissa times 2^exponent, random sign.
double short_double(Random& random, int bits, int exponent) {
  const double mantissa = double((random.next() >> (64 - bits)) | (1ull << (bits - 1)));
  return std::ldexp(random.index(2) ? mantissa : -mantissa, exponent - bits);
}

double ulps_away(double x, int k) {
  for (int i = 0; i < std::abs(k); ++i) x = std::nextafter(x, k > 0 ? INFINITY : -INFINITY);
  return x;
}

// A plane and a point exactly on it: short mantissas keep the products exact, and
// the offset is the negated exact dot product, kept only when it is a double.
// Three families: general short-mantissa planes over scales 2^-40..2^40 (1e-12 ..
// 1e12), small-integer normals through dyadic lattice points, and axis planes.
std::pair<Plane, Vec3> exact_point_on_plane(Random& random) {
  for (;;) {
    const int family = int(random.index(3));
    Plane plane;
    Vec3 p;
    if (family == 0) {
      const int scale = int(random.index(81)) - 40;
      const int normal_scale = int(random.index(21)) - 10;
      plane.normal = {short_double(random, 24, normal_scale + int(random.index(3))),
                      short_double(random, 24, normal_scale + int(random.index(3))),
                      short_double(random, 24, normal_scale + int(random.index(3)))};
      p = {short_double(random, 26, scale + int(random.index(3))), short_double(random, 26, scale + int(random.index(3))),
           short_double(random, 26, scale + int(random.index(3)))};
    } else if (family == 1) {
      plane.normal = small_integer_normal(random);
      const int scale = int(random.index(61)) - 30;
      p = {std::ldexp(double(random.index(1 << 20)), scale), std::ldexp(double(random.index(1 << 20)), scale),
           std::ldexp(double(random.index(1 << 20)), scale)};
    } else {
      (random.index(3) == 0 ? plane.normal.x : random.index(2) ? plane.normal.y : plane.normal.z) =
          short_double(random, 20, int(random.index(41)) - 20);
      p = {short_double(random, 53, int(random.index(61)) - 30), short_double(random, 53, int(random.index(61)) - 30),
           short_double(random, 53, int(random.index(61)) - 30)};
    }
    // d = -(n·p) exactly, if that is a double.
    const mpq_class exact = -(mpq_class(plane.normal.x) * p.x + mpq_class(plane.normal.y) * p.y +
                              mpq_class(plane.normal.z) * p.z);
    const double rounded = exact.get_d();
    if (std::isfinite(rounded) && mpq_class(rounded) == exact) {
      plane.offset = rounded;
      return {plane, p};
    }
  }
}


// --- the plane kernel's predicate audit --------------------------------------
//
// The reference is written from the geometric definitions of implicit.hpp, not
// from its homogeneous polynomials, and evaluated in GMP rationals: an input plane
// through p0, p1, p2 has n = (p1 - p0) x (p2 - p0), d = -n·p0; a segment_plane point
// is p + t (q - p) with t = P(p) / (P(p) - P(q)); a three_planes point solves the
// three plane equations by Cramer's rule. kernel/src/implicit.cpp evaluates the
// homogeneous polynomials over CGAL::Mpzf; nothing is shared.

struct RefPlane {
  mpq_class a, b, c, d;
};
struct RefPoint {
  std::array<mpq_class, 3> x;
};

RefPlane ref_cut_plane(const Plane& p) {
  return {mpq_class(p.normal.x), mpq_class(p.normal.y), mpq_class(p.normal.z), mpq_class(p.offset)};
}

RefPlane ref_input_plane(const Vec3& p0, const Vec3& p1, const Vec3& p2) {
  const mpq_class ux = mpq_class(p1.x) - p0.x, uy = mpq_class(p1.y) - p0.y, uz = mpq_class(p1.z) - p0.z;
  const mpq_class vx = mpq_class(p2.x) - p0.x, vy = mpq_class(p2.y) - p0.y, vz = mpq_class(p2.z) - p0.z;
  RefPlane h{uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx, 0};
  h.d = -(h.a * p0.x + h.b * p0.y + h.c * p0.z);
  return h;
}

mpq_class ref_value(const RefPlane& h, const RefPoint& p) { return h.a * p.x[0] + h.b * p.x[1] + h.c * p.x[2] + h.d; }

int ref_sign(const mpq_class& v) { return sgn(v) < 0 ? -1 : sgn(v) > 0 ? 1 : 0; }

RefPoint ref_input_point(const Vec3& p) { return {{mpq_class(p.x), mpq_class(p.y), mpq_class(p.z)}}; }

// A scene of input points, input planes and cut planes (see audit_plane_predicates).
struct AuditScene {
  std::vector<Vec3> points;
  std::vector<std::array<VertexIndex, 3>> inputs;
  std::vector<ApproxPlane> input_approx;
  std::vector<Plane> cuts;
  std::vector<RefPlane> input_ref, cut_ref;
  // The hub structure: per hub, its point, the segments across it, and the cut
  // and input planes through it (exactly in band 0).
  struct Hub {
    std::uint32_t point = 0;
    std::vector<std::pair<std::uint32_t, std::uint32_t>> segments;
    std::vector<PlaneRef> cuts, inputs;
  };
  std::array<Hub, 2> hubs;
  std::vector<std::uint32_t> loose_points;  ///< random lattice points

  PlaneSet set() const { return {points, inputs, input_approx, cuts}; }
  const RefPlane& ref(PlaneRef plane) const { return plane.is_cut() ? cut_ref[plane.index()] : input_ref[plane.index()]; }
  std::uint32_t plane_count() const { return static_cast<std::uint32_t>(cuts.size() + inputs.size()); }
  PlaneRef plane(std::uint32_t k) const {
    return k < cuts.size() ? PlaneRef::cut(k) : PlaneRef::input(k - static_cast<std::uint32_t>(cuts.size()));
  }
};

// The exact point of a definition, or none when the definition is unsound (the
// segment's ends not strictly on opposite sides of its plane; three planes not
// meeting in one point): such definitions are never made, so never queried.
std::optional<RefPoint> ref_point(const AuditScene& s, const PointDef& def) {
  if (def.kind == PointKind::input) return ref_input_point(s.points[def.a]);
  if (def.kind == PointKind::segment_plane) {
    const RefPoint p = ref_input_point(s.points[def.a]), q = ref_input_point(s.points[def.b]);
    const RefPlane& h = s.ref(def.planes[0]);
    const mpq_class at_p = ref_value(h, p), at_q = ref_value(h, q);
    if (ref_sign(at_p) * ref_sign(at_q) >= 0) return std::nullopt;
    const mpq_class t = at_p / (at_p - at_q);
    RefPoint x;
    for (int k = 0; k < 3; ++k) x.x[k] = p.x[k] + t * (q.x[k] - p.x[k]);
    return x;
  }
  const RefPlane* h[3] = {&s.ref(def.planes[0]), &s.ref(def.planes[1]), &s.ref(def.planes[2])};
  const mpq_class* m[3][3] = {{&h[0]->a, &h[0]->b, &h[0]->c}, {&h[1]->a, &h[1]->b, &h[1]->c}, {&h[2]->a, &h[2]->b, &h[2]->c}};
  // det of the normals with column `replaced` swapped for -d.
  auto det = [&](int replaced) {
    mpq_class e[3][3];
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) e[r][c] = c == replaced ? mpq_class(-h[r]->d) : *m[r][c];
    }
    return mpq_class(e[0][0] * (e[1][1] * e[2][2] - e[1][2] * e[2][1]) - e[0][1] * (e[1][0] * e[2][2] - e[1][2] * e[2][0]) +
                     e[0][2] * (e[1][0] * e[2][1] - e[1][1] * e[2][0]));
  };
  const mpq_class d = det(-1);
  if (d == 0) return std::nullopt;
  RefPoint x;
  for (int k = 0; k < 3; ++k) x.x[k] = det(k) / d;
  return x;
}

std::string hex3(const Vec3& p) { return "(" + hex(p.x) + ", " + hex(p.y) + ", " + hex(p.z) + ")"; }

std::string describe_plane(const AuditScene& s, PlaneRef plane) {
  if (plane.is_cut()) {
    const Plane& p = s.cuts[plane.index()];
    return "cut " + std::to_string(plane.index()) + " [" + hex(p.normal.x) + " " + hex(p.normal.y) + " " +
           hex(p.normal.z) + " " + hex(p.offset) + "]";
  }
  const auto& t = s.inputs[plane.index()];
  return "input plane " + std::to_string(plane.index()) + " through " + hex3(s.points[t[0]]) + " " +
         hex3(s.points[t[1]]) + " " + hex3(s.points[t[2]]);
}

std::string describe_def(const AuditScene& s, const PointDef& def) {
  if (def.kind == PointKind::input) return "input " + hex3(s.points[def.a]);
  if (def.kind == PointKind::segment_plane) {
    return "segment " + hex3(s.points[def.a]) + " " + hex3(s.points[def.b]) + " meets " +
           describe_plane(s, def.planes[0]);
  }
  return "meet of " + describe_plane(s, def.planes[0]) + ", " + describe_plane(s, def.planes[1]) + ", " +
         describe_plane(s, def.planes[2]);
}

// The smallest power of two at least one ulp of x (2^-1074 for zero).
double ulp_of(double x) {
  x = std::fabs(x);
  return std::nextafter(x, INFINITY) - x;
}

// Band 1 moves by -4..4 ulps (0 excluded for offsets), band 2 by 2^3..2^40 ulps.
double moved(double x, double unit, int band, Random& random) {
  if (band == 1) {
    const int k = 1 + int(random.index(4));
    return x + (random.index(2) ? k : -k) * unit;
  }
  return x + (random.index(2) ? 1 : -1) * std::ldexp(unit, 3 + int(random.index(38)));
}

AuditScene make_audit_scene(Random& random, int band) {
  AuditScene s;
  const int e = int(random.index(61)) - 30;  // lattice spacing 2^e
  const int bits = 2 + int(random.index(19));  // coordinates within 2^bits spacings of the centre
  const double extent = std::ldexp(1.0, bits);
  Vec3 centre{};
  if (random.index(4) == 0) {
    // Far from the origin: up to 2^(bits + 20) spacings away (integers below 2^41).
    const double far = std::ldexp(1.0, bits + int(random.index(21)));
    centre = {std::floor(random.uniform(-far, far)), std::floor(random.uniform(-far, far)),
              std::floor(random.uniform(-far, far))};
  }
  auto lattice_point = [&] {
    return Vec3{centre.x + std::floor(random.uniform(-extent, extent)), centre.y + std::floor(random.uniform(-extent, extent)),
                centre.z + std::floor(random.uniform(-extent, extent))};
  };
  auto small_vector = [&] {
    const double step = std::ldexp(1.0, int(random.index(std::size_t(bits / 2 + 1))));
    for (;;) {
      const Vec3 u{double(int(random.index(7)) - 3), double(int(random.index(7)) - 3), double(int(random.index(7)) - 3)};
      if (u.x != 0 || u.y != 0 || u.z != 0) return u * step;
    }
  };
  // Integer lattice coordinates until the end, then scaled by 2^e (exactly).
  std::vector<Vec3> lattice;
  auto add = [&](Vec3 p) {
    lattice.push_back(p);
    return static_cast<std::uint32_t>(lattice.size() - 1);
  };
  std::array<Vec3, 2> hub_at;
  std::vector<std::array<std::uint32_t, 3>> triples;
  std::array<std::vector<std::size_t>, 2> hub_triples;
  for (int h = 0; h < 2; ++h) {
    hub_at[h] = lattice_point();
    AuditScene::Hub& hub = s.hubs[h];
    hub.point = add(hub_at[h]);
    for (int k = 0; k < 3; ++k) {  // segments across the hub
      const Vec3 u = small_vector();
      const double m = double(1 + random.index(3));
      std::uint32_t a = add(hub_at[h] + u), b = add(hub_at[h] - u * m);
      if (a > b) std::swap(a, b);
      hub.segments.push_back({a, b});
    }
    for (int k = 0; k < 3; ++k) {  // input planes through the hub, not through a defining point at it
      Vec3 u, v;
      do {
        u = small_vector(), v = small_vector();
      } while (cross(u, v) == Vec3{});
      const std::uint32_t p0 = add(hub_at[h] + u), p1 = add(hub_at[h] + v), p2 = add(hub_at[h] - u - v);
      hub_triples[h].push_back(triples.size());
      triples.push_back(random.index(2) ? std::array{p0, p1, p2} : std::array{p0, p2, p1});
    }
  }
  for (int k = 0; k < 6; ++k) s.loose_points.push_back(add(lattice_point()));
  s.points.resize(lattice.size());
  for (std::size_t i = 0; i < lattice.size(); ++i) {
    s.points[i] = {std::ldexp(lattice[i].x, e), std::ldexp(lattice[i].y, e), std::ldexp(lattice[i].z, e)};
    if (band > 0 && random.index(4) == 0) {
      Vec3& p = s.points[i];
      if (band == 1) {
        p = {ulps_away(p.x, int(random.index(9)) - 4), ulps_away(p.y, int(random.index(9)) - 4),
             ulps_away(p.z, int(random.index(9)) - 4)};
      } else {
        double& x = random.index(3) == 0 ? p.x : random.index(2) ? p.y : p.z;
        x = moved(x, ulp_of(x), 2, random);
      }
    }
  }
  // Input planes: the hubs' triples, and two through random triples of points.
  for (int k = 0; k < 2; ++k) {
    const auto pick = [&] { return static_cast<std::uint32_t>(random.index(s.points.size())); };
    triples.push_back({pick(), pick(), pick()});
  }
  for (std::size_t t = 0; t < triples.size(); ++t) {
    const auto& [p0, p1, p2] = triples[t];
    const RefPlane h = ref_input_plane(s.points[p0], s.points[p1], s.points[p2]);
    if (h.a == 0 && h.b == 0 && h.c == 0) continue;  // collinear: no plane
    const PlaneRef ref = PlaneRef::input(static_cast<std::uint32_t>(s.inputs.size()));
    for (int h2 = 0; h2 < 2; ++h2) {
      if (std::find(hub_triples[h2].begin(), hub_triples[h2].end(), t) != hub_triples[h2].end()) s.hubs[h2].inputs.push_back(ref);
    }
    s.inputs.push_back({p0, p1, p2});
    s.input_approx.push_back(approximate_input_plane(s.points[p0], s.points[p1], s.points[p2]));
    s.input_ref.push_back(h);
  }
  // Cut planes: five through each hub with small-integer normals (times 2^f),
  // one through a loose point, one in general position.
  auto through = [&](const Vec3& lattice_at, Vec3 normal) {
    const Vec3 at{std::ldexp(lattice_at.x, e), std::ldexp(lattice_at.y, e), std::ldexp(lattice_at.z, e)};
    // |n| < 2^10 and coordinates below 2^42 spacings: -n·at is exact in doubles.
    Plane plane{normal, -(normal.x * at.x + normal.y * at.y + normal.z * at.z)};
    if (band > 0 && random.index(4) != 0) {
      const double scale = std::fabs(normal.x * at.x) + std::fabs(normal.y * at.y) + std::fabs(normal.z * at.z) +
                           std::fabs(plane.offset);
      const double largest = std::max({std::fabs(normal.x), std::fabs(normal.y), std::fabs(normal.z)});
      const double unit = ulp_of(std::max(scale, largest * std::ldexp(1.0, e)));
      plane.offset = moved(plane.offset, unit, band, random);
    }
    return plane;
  };
  for (int h = 0; h < 2; ++h) {
    for (int k = 0; k < 5; ++k) {
      s.hubs[h].cuts.push_back(PlaneRef::cut(static_cast<std::uint32_t>(s.cuts.size())));
      s.cuts.push_back(through(hub_at[h], small_integer_normal(random) * std::ldexp(1.0, int(random.index(9)) - 4)));
    }
  }
  s.cuts.push_back(through(lattice[s.loose_points[random.index(s.loose_points.size())]], small_integer_normal(random)));
  {
    const Vec3 n = random.direction();
    const Vec3 at = s.points[random.index(s.points.size())];
    s.cuts.push_back({n, -dot(n, at)});
  }
  for (const Plane& p : s.cuts) s.cut_ref.push_back(ref_cut_plane(p));
  return s;
}

constexpr std::array<std::string_view, plane_audit_rows> plane_audit_row_names{
    "side: input point, cut plane",          "side: input point, input plane",
    "side: segment_plane, cut plane",        "side: segment_plane, input plane",
    "side: three cuts, cut plane",           "side: three cuts, input plane",
    "side: input+2 cuts, cut plane",         "side: input+2 cuts, input plane",
    "side: explicit plane (any point)",      "orient_in_plane (three points)",
    "orient_in_plane (explicit point)",      "compare_along",
    "compare_coordinate"};
constexpr int row_side_explicit = 8, row_orient = 9, row_orient_explicit = 10, row_along = 11, row_coordinate = 12;

// The point kind's row group: input, segment_plane, three cut planes, an input
// plane and two cuts.
int kind_group(const PointDef& def) {
  if (def.kind == PointKind::input) return 0;
  if (def.kind == PointKind::segment_plane) return 1;
  const bool any_input = !def.planes[0].is_cut() || !def.planes[1].is_cut() || !def.planes[2].is_cut();
  return any_input ? 3 : 2;
}

std::uint64_t fallbacks_so_far() {
  const ImplicitCounters& c = implicit_counters();
  return c.side_exact + c.orient_exact + c.order_exact;
}

struct PlaneAuditor {
  PlaneAuditResult& result;
  std::uint64_t budget;
  int band = 0;

  bool full() const { return result.queries >= budget; }

  // Records one query; `what` describes it for the first disagreement.
  template <class Describe>
  void record(int row, int expected, Sign got, std::uint64_t fallbacks_before, const Describe& what) {
    AuditBand& b = result.bands[std::size_t(row)][std::size_t(band)];
    ++result.queries;
    ++b.queries;
    b.on_plane += expected == 0;
    b.exact_fallbacks += fallbacks_so_far() != fallbacks_before ? 1 : 0;
    if (static_cast<int>(got) != expected) {
      ++result.band_disagreements[std::size_t(row)][std::size_t(band)];
      if (result.disagreements++ == 0) {
        result.first_disagreement = std::string(plane_audit_row_names[std::size_t(row)]) + ", band " +
                                    std::to_string(band) + ": " + what() + ": kernel says " +
                                    std::to_string(static_cast<int>(got)) + ", reference " + std::to_string(expected);
      }
    }
  }
};

struct AuditPoint {
  PointDef def;
  ApproxPoint approx;
  RefPoint exact;
};

// Adds the definition when it is sound (and not already there).
void add_point(const AuditScene& s, const PlaneSet& set, std::vector<AuditPoint>& out, const PointDef& def) {
  for (const AuditPoint& p : out) {
    if (p.def == def) return;
  }
  std::optional<RefPoint> exact = ref_point(s, def);
  if (!exact) return;
  out.push_back({def, approximate(set, def), std::move(*exact)});
}

PointDef segment_def(std::uint32_t a, std::uint32_t b, PlaneRef plane) {
  return PointDef::segment_plane(std::min(a, b), std::max(a, b), plane);
}

// x / w, or nothing where w is zero or the quotient would overflow: decided on the
// exponents before dividing, so no floating-point trap fires (the runner traps
// division by zero and overflow). |x| < 2^ex and |w| >= 2^(ew-1), so
// |x / w| < 2^(ex-ew+1), which rounds below the largest double when ex - ew <= 1022.
std::optional<double> quotient(double x, double w) {
  if (w == 0 || !std::isfinite(x) || !std::isfinite(w)) return std::nullopt;
  if (x == 0) return 0.0;
  int ex = 0, ew = 0;
  std::frexp(x, &ex);
  std::frexp(w, &ew);
  if (ex - ew > 1022) return std::nullopt;
  return x / w;
}

// One scene's queries, until the budget is spent.
void audit_scene(PlaneAuditor& auditor, const AuditScene& s, Random& random) {
  const PlaneSet set = s.set();
  auto any_cut = [&] { return PlaneRef::cut(static_cast<std::uint32_t>(random.index(s.cuts.size()))); };
  auto pick = [&](const std::vector<PlaneRef>& from) { return from[random.index(from.size())]; };
  // Three distinct planes from `from` in random order (from has at least three).
  auto three = [&](const std::vector<PlaneRef>& from) {
    std::vector<PlaneRef> shuffled = from;
    for (std::size_t i = shuffled.size(); i > 1; --i) std::swap(shuffled[i - 1], shuffled[random.index(i)]);
    return std::array{shuffled[0], shuffled[1], shuffled[2]};
  };

  // The points: every kind, most of them at a hub (exactly in band 0).
  std::vector<AuditPoint> points;
  for (const AuditScene::Hub& hub : s.hubs) {
    add_point(s, set, points, PointDef::input(hub.point));
    for (const auto& [a, b] : hub.segments) {
      const PlaneRef plane = random.index(4) == 0 && !hub.inputs.empty() ? pick(hub.inputs) : pick(hub.cuts);
      add_point(s, set, points, segment_def(a, b, plane));
    }
    for (int k = 0; k < 2; ++k) {
      const auto c = three(hub.cuts);
      add_point(s, set, points, PointDef::three_planes(c[0], c[1], c[2]));
      if (!hub.inputs.empty()) {
        std::array<PlaneRef, 3> planes{pick(hub.inputs), c[0], c[1]};
        std::swap(planes[0], planes[random.index(3)]);
        add_point(s, set, points, PointDef::three_planes(planes[0], planes[1], planes[2]));
      }
    }
  }
  for (std::uint32_t p : s.loose_points) add_point(s, set, points, PointDef::input(p));
  for (int k = 0; k < 2; ++k) {
    const auto a = static_cast<std::uint32_t>(random.index(s.points.size()));
    const auto b = static_cast<std::uint32_t>(random.index(s.points.size()));
    if (a != b) add_point(s, set, points, segment_def(a, b, any_cut()));
    add_point(s, set, points, PointDef::three_planes(any_cut(), any_cut(), any_cut()));
    add_point(s, set, points,
              PointDef::three_planes(PlaneRef::input(static_cast<std::uint32_t>(random.index(s.inputs.size()))), any_cut(),
                                     any_cut()));
  }

  // side() against every plane of the set.
  for (const AuditPoint& p : points) {
    for (std::uint32_t k = 0; k < s.plane_count() && !auditor.full(); ++k) {
      const PlaneRef plane = s.plane(k);
      if (p.def.defined_on(plane)) continue;  // zero by definition: no arithmetic to audit
      const int expected = ref_sign(ref_value(s.ref(plane), p.exact));
      const std::uint64_t before = fallbacks_so_far();
      const Sign got = side(set, plane, p.def, p.approx);
      auditor.record(2 * kind_group(p.def) + (plane.is_cut() ? 0 : 1), expected, got, before,
                     [&] { return describe_def(s, p.def) + " against " + describe_plane(s, plane); });
    }
    // side() with an explicit plane: a cut plane given as its doubles, the one the
    // point is defined on when there is one (zero the hard way).
    for (int k = 0; k < 2 && !auditor.full(); ++k) {
      PlaneRef plane = any_cut();
      if (k == 0 && p.def.kind != PointKind::input && p.def.planes[0].is_cut()) plane = p.def.planes[0];
      const int expected = ref_sign(ref_value(s.ref(plane), p.exact));
      const std::uint64_t before = fallbacks_so_far();
      const Sign got = side(set, s.cuts[plane.index()], p.def, p.approx);
      auditor.record(row_side_explicit, expected, got, before,
                     [&] { return describe_def(s, p.def) + " against explicit " + describe_plane(s, plane); });
    }
  }

  // orient_in_plane: points defined on one plane through hub 0, many at the hub
  // and many on one line of that plane (exactly collinear in band 0).
  const AuditScene::Hub& hub = s.hubs[0];
  std::vector<PlaneRef> hub_planes = hub.cuts;
  hub_planes.insert(hub_planes.end(), hub.inputs.begin(), hub.inputs.end());
  const PlaneRef on = pick(hub_planes);
  std::vector<AuditPoint> in_plane;
  {
    // Planes the others may be: cuts only when `on` is an input plane (a point is
    // never the meet of two input planes).
    std::vector<PlaneRef> others;
    for (std::uint32_t k = 0; k < s.plane_count(); ++k) {
      const PlaneRef plane = s.plane(k);
      if (plane != on && (on.is_cut() || plane.is_cut())) others.push_back(plane);
    }
    std::vector<PlaneRef> hub_others;
    for (PlaneRef plane : hub_planes) {
      if (plane != on && (on.is_cut() || plane.is_cut())) hub_others.push_back(plane);
    }
    const PlaneRef line = pick(others);
    for (int tries = 0; tries < 24 && in_plane.size() < 12; ++tries) {
      switch (random.index(4)) {
        case 0:
          if (hub_others.size() >= 2) {
            const PlaneRef a = pick(hub_others), b = pick(hub_others);
            if (a != b) add_point(s, set, in_plane, PointDef::three_planes(on, a, b));
          }
          break;
        case 1: {  // on the line on ∩ line
          const PlaneRef b = random.index(2) ? pick(others) : line;
          const PlaneRef a = line.is_cut() || b.is_cut() ? line : any_cut();
          if (a != b) add_point(s, set, in_plane, PointDef::three_planes(on, a, b));
          break;
        }
        case 2: {
          const auto& [a, b] = hub.segments[random.index(hub.segments.size())];
          if (on.is_cut() || random.index(2)) add_point(s, set, in_plane, segment_def(a, b, on));
          break;
        }
        default: {
          const auto a = static_cast<std::uint32_t>(random.index(s.points.size()));
          const auto b = static_cast<std::uint32_t>(random.index(s.points.size()));
          if (a != b) add_point(s, set, in_plane, segment_def(a, b, on));
        }
      }
    }
  }
  if (in_plane.size() >= 3) {
    const RefPlane& h = s.ref(on);
    const Projection projection = projection_of(set, on);
    const mpq_class& n_axis = projection.axis == 0 ? h.a : projection.axis == 1 ? h.b : h.c;
    const bool projection_sound = n_axis != 0 && (sgn(n_axis) < 0) == projection.flipped;
    const int i = (projection.axis + 1) % 3, j = (projection.axis + 2) % 3;
    for (int k = 0; k < 32 && !auditor.full(); ++k) {
      const AuditPoint& p = in_plane[random.index(in_plane.size())];
      const AuditPoint& q = in_plane[random.index(in_plane.size())];
      const AuditPoint& r = in_plane[random.index(in_plane.size())];
      if (&p == &q || &q == &r || &r == &p) continue;
      // Seen from the plane's front: the sign of n · ((q - p) x (r - p)).
      std::array<mpq_class, 3> u, v;
      for (int a = 0; a < 3; ++a) u[a] = q.exact.x[a] - p.exact.x[a], v[a] = r.exact.x[a] - p.exact.x[a];
      int expected = ref_sign(h.a * (u[1] * v[2] - u[2] * v[1]) + h.b * (u[2] * v[0] - u[0] * v[2]) +
                              h.c * (u[0] * v[1] - u[1] * v[0]));
      if (!projection_sound) expected = 2;  // any answer is a disagreement: the projection is wrong
      const std::uint64_t before = fallbacks_so_far();
      const Sign got = orient_in_plane(set, projection, p.def, p.approx, q.def, q.approx, r.def, r.approx);
      auditor.record(row_orient, expected, got, before, [&] {
        return "on " + describe_plane(s, on) + ": " + describe_def(s, p.def) + "; " + describe_def(s, q.def) + "; " +
               describe_def(s, r.def);
      });
    }
    // With an explicit point m of the projection's plane: the hub's own kept
    // coordinates, a point's rounded ones, or those moved by an ulp.
    for (int k = 0; k < 16 && !auditor.full(); ++k) {
      const AuditPoint& p = in_plane[random.index(in_plane.size())];
      const AuditPoint& q = in_plane[random.index(in_plane.size())];
      if (&p == &q) continue;
      Vec2 m;
      if (random.index(2)) {
        const Vec3& at = s.points[hub.point];
        m = {at[i], at[j]};
      } else {
        const AuditPoint& r = in_plane[random.index(in_plane.size())];
        const double w = r.approx.w.value;
        const double coords[3] = {r.approx.x.value, r.approx.y.value, r.approx.z.value};
        // The approximation's x/w can overflow or divide by an underflowed w: m
        // must be a point, so take the hub's then.
        const std::optional<double> mx = quotient(coords[i], w), my = quotient(coords[j], w);
        m = mx && my ? Vec2{*mx, *my} : Vec2{s.points[hub.point][i], s.points[hub.point][j]};
      }
      if (random.index(3) == 0) m = {ulps_away(m.x, int(random.index(5)) - 2), ulps_away(m.y, int(random.index(5)) - 2)};
      if (!std::isfinite(m.x) || !std::isfinite(m.y)) m = {s.points[hub.point][i], s.points[hub.point][j]};
      const mpq_class mi(m.x), mj(m.y);
      int expected = ref_sign((q.exact.x[i] - p.exact.x[i]) * (mj - p.exact.x[j]) -
                              (q.exact.x[j] - p.exact.x[j]) * (mi - p.exact.x[i]));
      if (projection.flipped) expected = -expected;
      if (!projection_sound) expected = 2;
      const std::uint64_t before = fallbacks_so_far();
      const Sign got = orient_in_plane(set, projection, p.def, p.approx, q.def, q.approx, m);
      auditor.record(row_orient_explicit, expected, got, before, [&] {
        return "on " + describe_plane(s, on) + ": " + describe_def(s, p.def) + "; " + describe_def(s, q.def) +
               "; m (" + hex(m.x) + ", " + hex(m.y) + ")";
      });
    }
  }

  // compare_along: the line of a hub cut and another plane through the hub;
  // points on that line (many at the hub) and anywhere.
  {
    const PlaneRef a = pick(hub.cuts);
    const PlaneRef b = pick(hub_planes);
    const RefPlane &ha = s.ref(a), &hb = s.ref(b);
    const std::array<mpq_class, 3> direction{ha.b * hb.c - ha.c * hb.b, ha.c * hb.a - ha.a * hb.c,
                                             ha.a * hb.b - ha.b * hb.a};
    if (a != b && (direction[0] != 0 || direction[1] != 0 || direction[2] != 0)) {
      std::vector<AuditPoint> on_line;
      for (int tries = 0; tries < 12; ++tries) {
        const PlaneRef x = b.is_cut() && random.index(2) ? PlaneRef::input(std::uint32_t(random.index(s.inputs.size())))
                                                         : any_cut();
        if (x != a && x != b) add_point(s, set, on_line, PointDef::three_planes(a, b, x));
      }
      for (int k = 0; k < 4 && !points.empty(); ++k) on_line.push_back(points[random.index(points.size())]);
      for (int k = 0; k < 24 && on_line.size() >= 2 && !auditor.full(); ++k) {
        const AuditPoint& p = on_line[random.index(on_line.size())];
        const AuditPoint& q = on_line[random.index(on_line.size())];
        if (&p == &q) continue;
        mpq_class value = 0;
        for (int c = 0; c < 3; ++c) value += direction[std::size_t(c)] * (q.exact.x[c] - p.exact.x[c]);
        const std::uint64_t before = fallbacks_so_far();
        const Sign got = compare_along(set, a, b, p.def, p.approx, q.def, q.approx);
        auditor.record(row_along, ref_sign(value), got, before, [&] {
          return "along " + describe_plane(s, a) + " x " + describe_plane(s, b) + ": " + describe_def(s, p.def) + "; " +
                 describe_def(s, q.def);
        });
      }
    }
  }

  // compare_coordinate: pairs of any points of the scene, any axis.
  std::vector<const AuditPoint*> all;
  for (const AuditPoint& p : points) all.push_back(&p);
  for (const AuditPoint& p : in_plane) all.push_back(&p);
  for (int k = 0; k < 32 && all.size() >= 2 && !auditor.full(); ++k) {
    const AuditPoint& p = *all[random.index(all.size())];
    const AuditPoint& q = *all[random.index(all.size())];
    if (&p == &q) continue;
    const int axis = int(random.index(3));
    const std::uint64_t before = fallbacks_so_far();
    const Sign got = compare_coordinate(set, axis, p.def, p.approx, q.def, q.approx);
    auditor.record(row_coordinate, ref_sign(q.exact.x[axis] - p.exact.x[axis]), got, before, [&] {
      return "axis " + std::to_string(axis) + ": " + describe_def(s, p.def) + "; " + describe_def(s, q.def);
    });
  }
}

}  // namespace

std::string_view class_name(CaseClass kind) { return class_names[static_cast<std::size_t>(kind)]; }

std::optional<CaseClass> parse_class(std::string_view name) {
  for (int i = 0; i < case_class_count; ++i) {
    if (class_names[i] == name) return static_cast<CaseClass>(i);
  }
  return std::nullopt;
}

std::string_view operation_name(Operation op) { return op == Operation::slice ? "slice" : "fracture"; }

MeshPool MeshPool::load() {
  MeshPool pool;
  for (const auto& path : test::valid_meshes()) pool.meshes.emplace_back(path.filename().string(), read_mesh(path));
  for (test::NamedMesh& m : test::generated_meshes()) pool.meshes.emplace_back(m.name, std::move(m.mesh));
  pool.meshes.emplace_back("staircase-4", test::staircase(4));
  pool.meshes.emplace_back("stacked-boxes-3", test::stacked_boxes(3));
  pool.meshes.emplace_back("pinch-saddle", test::pinch_saddle());
  pool.meshes.emplace_back("needle-bridge-2^-20", test::needle_bridge(0x1p-20));
  pool.meshes.emplace_back("nested-islands", test::nested_islands());
  for (const auto& [name, mesh] : pool.meshes) {
    if (!is_valid_solid(mesh)) throw std::runtime_error("mesh pool: " + name + " is not a valid solid");
  }
  return pool;
}

Case make_case(const MeshPool& pool, std::uint64_t seed, std::uint64_t index) {
  Case c;
  c.seed = mix(seed, index);
  Random random(c.seed);
  c.kind = static_cast<CaseClass>(index % case_class_count);
  c.op = random.index(4) == 0 ? Operation::fracture : Operation::slice;

  auto use = [&](const std::string& name, Mesh mesh) {
    c.mesh_name = name;
    c.mesh = std::move(mesh);
  };
  auto use_pool = [&](std::size_t max_triangles) {
    const auto& [name, mesh] = pick(pool, random, max_triangles);
    use(name, mesh);
  };
  const std::size_t any_size = std::numeric_limits<std::size_t>::max();
  switch (c.kind) {
    case CaseClass::random_plane: {
      use_pool(any_size);
      const int chain = 1 + int(random.index(3));
      for (int i = 0; i < chain; ++i) c.planes.push_back(plane_of_class(c.kind, c.mesh, random));
      break;
    }
    case CaseClass::vertex_plane:
    case CaseClass::vertex_plane_ulps:
    case CaseClass::edge_plane:
    case CaseClass::edge_plane_ulps:
    case CaseClass::face_plane:
    case CaseClass::face_plane_ulps:
      use_pool(any_size);
      c.planes.push_back(plane_of_class(c.kind, c.mesh, random));
      break;
    case CaseClass::many_vertices: {
      const int n = 2 + int(random.index(7));
      const int exponent = int(random.index(9)) - 4;  // lattice spacing 2^-4 .. 2^4: still exact
      use("grid-box-" + std::to_string(n) + "x2^" + std::to_string(exponent),
          scaled_by_power_of_two(test::grid_box({0, 0, 0}, {double(n), double(n), double(n)}, n), exponent));
      c.planes.push_back(lattice_plane(c.mesh, random));
      break;
    }
    case CaseClass::coplanar_faces: {
      if (random.index(2)) {
        const int steps = 2 + int(random.index(5));
        use("staircase-" + std::to_string(steps), test::staircase(steps));
      } else {
        const int floors = 2 + int(random.index(4));
        use("stacked-boxes-" + std::to_string(floors), test::stacked_boxes(floors));
      }
      if (random.index(3) == 0) {
        const Triangle& t = c.mesh.triangles[random.index(c.mesh.triangles.size())];
        c.planes.push_back(test::plane_through_points(c.mesh.positions[t[0]], c.mesh.positions[t[1]], c.mesh.positions[t[2]]));
      } else {
        c.planes.push_back(lattice_plane(c.mesh, random));
      }
      break;
    }
    case CaseClass::slivers_needles: {
      const int thinness = 10 + int(random.index(31));  // 2^-10 .. 2^-40
      switch (random.index(3)) {
        case 0: use("sliver", test::sliver()); break;
        case 1: use("needle-bridge-2^-" + std::to_string(thinness), test::needle_bridge(std::ldexp(1.0, -thinness))); break;
        default: use("flat-tetrahedron-2^-" + std::to_string(thinness), test::flat_tetrahedron(std::ldexp(1.0, -thinness)));
      }
      c.planes.push_back(random.index(2) ? lattice_plane(c.mesh, random)
                                         : plane_of_class(CaseClass::random_plane, c.mesh, random));
      break;
    }
    case CaseClass::nested_shells: {
      switch (random.index(3)) {
        case 0: use("nested-islands", test::nested_islands()); break;
        case 1: use("hollow-egg", test::hollow_egg()); break;
        default: use("nested-shells-island", test::nested_shells_with_island());
      }
      c.planes.push_back(random.index(2) ? lattice_plane(c.mesh, random)
                                         : plane_of_class(CaseClass::random_plane, c.mesh, random));
      break;
    }
    case CaseClass::pinch: {
      use("pinch-saddle", test::pinch_saddle());
      // z = 0 through the saddle, moved 0-4 ulps, or tilted about the saddle vertex.
      const Vec3 saddle{1, 1, 0};
      Plane plane = random.index(2) ? test::axis_plane_through(saddle, 2)
                                    : test::plane_through(saddle, {double(random.index(3)) - 1, double(random.index(3)) - 1, 4});
      if (random.index(2)) {
        // k ulps of the saddle's coordinates (about 1), not of the offset: when the
        // offset is 0 its own ulp is subnormal, a far smaller step.
        const int ulps = random_ulps(random);
        plane.offset = plane.offset == 0 ? ulps * 0x1p-52 : test::offset_by_ulps(plane, ulps).offset;
      }
      c.planes.push_back(plane);
      break;
    }
    case CaseClass::near_parallel_chain: {
      use_pool(large_mesh_triangles);
      const Triangle& t = c.mesh.triangles[random.index(c.mesh.triangles.size())];
      const double start = std::pow(10.0, -random.uniform(1, 8));
      const double ratio = std::pow(10.0, -random.uniform(0.5, 3));
      c.planes = test::near_parallel_fan(c.mesh.positions[t[0]], c.mesh.positions[t[1]], random.direction(),
                                         2 + int(random.index(2)), start, ratio);
      break;
    }
    case CaseClass::extreme_scale: {
      const auto& [name, mesh] = pick(pool, random, large_mesh_triangles);
      const int exponent = int(random.index(61)) - 30;  // 2^±30 is about 1e±9
      use(name + " x2^" + std::to_string(exponent), scaled_by_power_of_two(mesh, exponent));
      c.planes.push_back(random.index(2) ? plane_of_class(CaseClass::vertex_plane, c.mesh, random)
                                         : plane_of_class(CaseClass::random_plane, c.mesh, random));
      break;
    }
    case CaseClass::far_from_origin: {
      const auto& [name, mesh] = pick(pool, random, large_mesh_triangles);
      // Shifting rounds every coordinate: a shift that makes the solid invalid is
      // halved until it does not (such inputs are refused, and tested elsewhere).
      Vec3 shift = random.direction() * std::pow(10.0, random.uniform(3, 9));
      Mesh moved;
      for (int tries = 0; tries < 40; ++tries, shift = shift * 0.5) {
        moved = test::transformed(mesh, 1.0, shift);
        if (is_valid_solid(moved)) break;
      }
      if (!is_valid_solid(moved)) moved = mesh, shift = {};
      std::ostringstream label;
      label.precision(3);
      label << name << " +" << norm(shift);
      use(label.str(), std::move(moved));
      c.planes.push_back(plane_of_class(random.index(2) ? CaseClass::vertex_plane : CaseClass::random_plane, c.mesh, random));
      break;
    }
    case CaseClass::attribute_seams: {
      const auto& [name, mesh] = pick(pool, random, large_mesh_triangles);
      use(name + " with seams", test::with_seams(mesh));
      c.planes.push_back(plane_of_class(random.index(2) ? CaseClass::vertex_plane : CaseClass::random_plane, c.mesh, random));
      break;
    }
  }
  const bool large = c.mesh.triangles.size() > large_mesh_triangles;
  if (c.op == Operation::fracture) {
    static constexpr std::uint32_t fragment_choices[] = {2, 3, 4, 8, 16};
    c.recipe.fragments = fragment_choices[random.index(large ? 4 : 5)];
    c.recipe.seed = random.next();
    c.recipe.strategy = static_cast<Strategy>(random.index(3));
  }
  c.mesh = in_first_use_order(std::move(c.mesh));
  // Output pieces are written as OFF, and in a quarter of the cases as OBJ, PLY
  // or STL (drawn last, so the rest of the case does not depend on it).
  static constexpr MeshFormat other_formats[] = {MeshFormat::obj, MeshFormat::ply, MeshFormat::stl};
  c.format = random.index(4) == 0 ? other_formats[random.index(3)] : MeshFormat::off;
  return c;
}

CaseOutcome run_case(const Case& c) {
  CaseOutcome outcome;
  Checker checker{c, outcome};
  try {
    if (c.op == Operation::slice) {
      checker.slice_chain();
    } else {
      checker.fracture();
    }
  } catch (const UnsupportedGeometryError& e) {
    // A fracture that runs out of planes is the builder's documented refusal. A
    // slice refuses only pinches and unroundable pieces, both counted where they
    // happen: anything else escaping it is a failure.
    if (c.op == Operation::slice) {
      outcome.failures.push_back(std::string("unsupported geometry: ") + e.what());
    } else {
      outcome.refused = true;
    }
  } catch (const std::exception& e) {
    outcome.failures.push_back(std::string("exception: ") + e.what());
  }
  return outcome;
}

std::filesystem::path write_reproducer(const std::filesystem::path& dir, const Case& c, const std::string& failure) {
  std::ostringstream out;
  out << "shatter-reproducer 1\n"
      << "# replay: shatter-fuzz --replay <this file>\n"
      << "class " << class_name(c.kind) << "\n"
      << "mesh-name " << c.mesh_name << "\n"
      << "operation " << operation_name(c.op) << "\n"
      << "format " << format_name(c.format) << "\n"
      << "seed " << c.seed << "\n"
      << "failure " << failure.substr(0, failure.find('\n')) << "\n";
  for (const Plane& p : c.planes) {
    out << "plane " << hex(p.normal.x) << ' ' << hex(p.normal.y) << ' ' << hex(p.normal.z) << ' ' << hex(p.offset)
        << "  # " << describe(p) << "\n";
  }
  if (c.op == Operation::fracture) {
    out << "fragments " << c.recipe.fragments << "\nbuild-seed " << c.recipe.seed << "\nstrategy "
        << strategy_name(c.recipe.strategy) << "\n";
  }
  const std::string mesh = write_mesh_to_bytes(c.mesh, MeshFormat::obj);
  out << "mesh-obj " << mesh.size() << "\n" << mesh;
  std::filesystem::create_directories(dir);
  const std::filesystem::path path =
      dir / (std::string(class_name(c.kind)) + "-" + std::string(operation_name(c.op)) + "-" + std::to_string(c.seed) +
             ".repro");
  write_file_atomically(path, out.str());
  return path;
}

Case read_reproducer(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError("cannot open reproducer " + path.string());
  std::string line;
  if (!std::getline(in, line) || line != "shatter-reproducer 1") {
    throw InvalidMeshError(path.string() + ": not a shatter reproducer (version 1)");
  }
  Case c;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    std::string key;
    fields >> key;
    auto rest = [&] {
      std::string value;
      std::getline(fields >> std::ws, value);
      return value;
    };
    if (key == "class") {
      const auto kind = parse_class(rest());
      if (!kind) throw InvalidMeshError(path.string() + ": unknown class");
      c.kind = *kind;
    } else if (key == "mesh-name") {
      c.mesh_name = rest();
    } else if (key == "operation") {
      c.op = rest() == "fracture" ? Operation::fracture : Operation::slice;
    } else if (key == "kernel") {
      // Reproducers written while there were three kernels name theirs.
      const std::string kernel = rest();
      if (kernel != "plane") {
        throw InvalidMeshError(path.string() + ": a reproducer of the retired " + kernel + " kernel");
      }
    } else if (key == "format") {
      const auto format = parse_mesh_format(rest());
      if (!format) throw InvalidMeshError(path.string() + ": unknown format");
      c.format = *format;
    } else if (key == "seed") {
      fields >> c.seed;
    } else if (key == "failure") {
      continue;
    } else if (key == "plane") {
      std::array<std::string, 4> words;
      for (std::string& w : words) fields >> w;
      c.planes.push_back({{parse_hex(words[0]), parse_hex(words[1]), parse_hex(words[2])}, parse_hex(words[3])});
    } else if (key == "fragments") {
      fields >> c.recipe.fragments;
    } else if (key == "build-seed") {
      fields >> c.recipe.seed;
    } else if (key == "strategy") {
      const auto strategy = parse_strategy(rest());
      if (!strategy) throw InvalidMeshError(path.string() + ": unknown strategy");
      c.recipe.strategy = *strategy;
    } else if (key == "expect") {
      const std::string name = rest();
      if (name == expected_name(Expected::valid_as_written)) {
        c.expected = Expected::valid_as_written;
      } else {
        throw InvalidMeshError(path.string() + ": unknown expectation '" + name + "'");
      }
    } else if (key == "mesh-corpus") {
      // The mesh as `shatter` reads it from the test corpus; a name, never a path.
      const std::string name = rest();
      if (name.empty() || name.find("..") != std::string::npos) throw InvalidMeshError(path.string() + ": bad mesh-corpus");
      c.mesh = read_mesh(test::mesh_dir() / name);
      return c;
    } else if (key == "mesh-obj") {
      std::size_t size = 0;
      fields >> size;
      std::string bytes(size, '\0');
      if (!in.read(bytes.data(), std::streamsize(size))) throw InvalidMeshError(path.string() + ": truncated mesh");
      c.mesh = read_mesh_from_bytes(bytes, MeshFormat::obj);
      return c;
    } else {
      throw InvalidMeshError(path.string() + ": unknown field '" + key + "'");
    }
  }
  throw InvalidMeshError(path.string() + ": no mesh");
}

std::string_view expected_name(Expected expected) {
  switch (expected) {
    case Expected::no_failure: return "no-failure";
    case Expected::valid_as_written: return "valid-as-written";
  }
  return "unknown";
}

std::string unmet_expectation(const Case& c, const CaseOutcome& outcome) {
  const std::size_t refusals = (outcome.refused ? 1 : 0) + outcome.plane_unroundable + outcome.plane_pinched;
  const std::string shown = std::to_string(outcome.written) + " pieces written, " +
                            std::to_string(outcome.invalid_written) + " invalid as written, " +
                            std::to_string(refusals) + " refusals";
  switch (c.expected) {
    case Expected::no_failure: return {};
    case Expected::valid_as_written:
      if (outcome.written > 0 && outcome.invalid_written == 0 && refusals == 0) return {};
      break;
  }
  return "expected " + std::string(expected_name(c.expected)) + ", the replay shows " + shown;
}

AuditResult audit_side_of_plane(std::uint64_t queries, std::uint64_t seed, unsigned threads) {
  constexpr std::uint64_t block = 1 << 16;
  const std::uint64_t blocks = (queries + block - 1) / block;
  std::vector<AuditResult> per_block(blocks);
  tbb::task_arena arena(threads == 0 ? tbb::task_arena::automatic : int(threads));
  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<std::uint64_t>(0, blocks), [&](const tbb::blocked_range<std::uint64_t>& range) {
      for (std::uint64_t b = range.begin(); b != range.end(); ++b) {
        AuditResult& result = per_block[b];
        Random random(mix(seed, b));
        const std::uint64_t count = std::min(block, queries - b * block);
        while (result.queries < count) {
          const auto [plane, on] = exact_point_on_plane(random);
          for (int k = 0; k < 12 && result.queries < count; ++k) {
            Vec3 q = on;
            AuditBand* band = &result.exact_on_plane;
            if (k >= 1 && k <= 8) {
              q = {ulps_away(on.x, int(random.index(9)) - 4), ulps_away(on.y, int(random.index(9)) - 4),
                   ulps_away(on.z, int(random.index(9)) - 4)};
              band = &result.within_4_ulps;
            } else if (k > 8) {
              // 2^j ulps along one axis: scale the coordinate's ulp, exactly.
              const int j = 3 + int(random.index(38));
              double& c = random.index(3) == 0 ? q.x : random.index(2) ? q.y : q.z;
              const double ulp = std::nextafter(std::fabs(c), INFINITY) - std::fabs(c);
              c += (random.index(2) ? 1 : -1) * std::ldexp(ulp, j);
              band = &result.far_8_to_2e40_ulps;
            }
            const int expected = reference_sign(plane, q);
            const std::uint64_t fallbacks_before = predicate_counters().side_of_plane_exact;
            const int got = static_cast<int>(side_of_plane(plane, q));
            ++result.queries;
            ++band->queries;
            band->on_plane += expected == 0;
            band->exact_fallbacks += predicate_counters().side_of_plane_exact - fallbacks_before;
            if (got != expected && result.disagreements++ == 0) {
              result.first_disagreement = "plane " + describe(plane) + " point (" + hex(q.x) + ", " + hex(q.y) + ", " +
                                          hex(q.z) + "): filter says " + std::to_string(got) + ", GMP " +
                                          std::to_string(expected);
            }
          }
        }
      }
    });
  });
  AuditResult total;
  auto add = [](AuditBand& to, const AuditBand& from) {
    to.queries += from.queries;
    to.exact_fallbacks += from.exact_fallbacks;
    to.on_plane += from.on_plane;
  };
  for (const AuditResult& r : per_block) {
    total.queries += r.queries;
    total.disagreements += r.disagreements;
    add(total.exact_on_plane, r.exact_on_plane);
    add(total.within_4_ulps, r.within_4_ulps);
    add(total.far_8_to_2e40_ulps, r.far_8_to_2e40_ulps);
    if (total.first_disagreement.empty()) total.first_disagreement = r.first_disagreement;
  }
  return total;
}

}  // namespace shatter::robust

namespace shatter::robust {

std::string_view plane_audit_row_name(int row) { return plane_audit_row_names[static_cast<std::size_t>(row)]; }

PlaneAuditResult audit_plane_predicates(std::uint64_t queries, std::uint64_t seed, unsigned threads) {
  constexpr std::uint64_t block = 1 << 14;
  const std::uint64_t blocks = (queries + block - 1) / block;
  std::vector<PlaneAuditResult> per_block(blocks);
  tbb::task_arena arena(threads == 0 ? tbb::task_arena::automatic : int(threads));
  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<std::uint64_t>(0, blocks), [&](const tbb::blocked_range<std::uint64_t>& range) {
      for (std::uint64_t b = range.begin(); b != range.end(); ++b) {
        // Seeds apart from the side_of_plane audit's blocks.
        Random random(mix(seed ^ 0x5A17E0A11D17ull, b));
        PlaneAuditor auditor{per_block[b], std::min(block, queries - b * block)};
        while (!auditor.full()) {
          auditor.band = int(random.index(3));
          const AuditScene scene = make_audit_scene(random, auditor.band);
          audit_scene(auditor, scene, random);
        }
      }
    });
  });
  PlaneAuditResult total;
  for (const PlaneAuditResult& r : per_block) {
    total.queries += r.queries;
    total.disagreements += r.disagreements;
    for (int row = 0; row < plane_audit_rows; ++row) {
      for (int band = 0; band < 3; ++band) {
        total.band_disagreements[std::size_t(row)][std::size_t(band)] +=
            r.band_disagreements[std::size_t(row)][std::size_t(band)];
        AuditBand& to = total.bands[std::size_t(row)][std::size_t(band)];
        const AuditBand& from = r.bands[std::size_t(row)][std::size_t(band)];
        to.queries += from.queries;
        to.exact_fallbacks += from.exact_fallbacks;
        to.on_plane += from.on_plane;
      }
    }
    if (total.first_disagreement.empty()) total.first_disagreement = r.first_disagreement;
  }
  return total;
}

}  // namespace shatter::robust
