#include "robustness/repair_fuzz.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <exception>
#include <numeric>
#include <set>
#include <string>
#include <tuple>
#include <utility>

#include "shatter/cut/plane_cut.hpp"
#include "shatter/generators/random.hpp"
#include "shatter/generators/solids.hpp"
#include "shatter/kernel/error.hpp"
#include "shatter/kernel/mass.hpp"
#include "shatter/kernel/repair.hpp"
#include "shatter/kernel/validate.hpp"
#include "shatter/kernel/predicates.hpp"
#include "shatter/triangulate/solid_mesh.hpp"
#include "support/checks.hpp"

namespace shatter::robust {
namespace {

using test::Random;

constexpr std::array<std::string_view, damage_class_count> damage_names{
    "unwelded", "duplicated", "flipped", "holes", "nested", "touching", "overlapping", "mixed", "stray"};

// Meshes above this size are left out: repair runs CGAL's hole filling and
// orientation, whose cost would dominate a run without adding kinds of damage.
constexpr std::size_t largest_pool_mesh = 6000;

// An oriented triangle as the bits of its three positions, rotated so that the
// smallest comes first: the same triangle whatever its vertex indices and
// starting corner. Bits, not values, so that identity is identity.
using TriangleKey = std::array<std::uint64_t, 9>;

TriangleKey key_of(const std::array<Vec3, 3>& corners) {
  std::array<std::array<std::uint64_t, 3>, 3> bits;
  for (int c = 0; c < 3; ++c) {
    bits[c] = {std::bit_cast<std::uint64_t>(corners[c].x), std::bit_cast<std::uint64_t>(corners[c].y),
               std::bit_cast<std::uint64_t>(corners[c].z)};
  }
  const int first = int(std::min_element(bits.begin(), bits.end()) - bits.begin());
  TriangleKey key;
  for (int c = 0; c < 3; ++c) std::copy(bits[(first + c) % 3].begin(), bits[(first + c) % 3].end(), key.begin() + 3 * c);
  return key;
}

std::array<Vec3, 3> corners_of(const Mesh& mesh, const Triangle& t) {
  return {mesh.positions[t[0]], mesh.positions[t[1]], mesh.positions[t[2]]};
}

std::vector<TriangleKey> sorted_keys(const Mesh& mesh) {
  std::vector<TriangleKey> keys;
  keys.reserve(mesh.triangles.size());
  for (const Triangle& t : mesh.triangles) keys.push_back(key_of(corners_of(mesh, t)));
  std::sort(keys.begin(), keys.end());
  return keys;
}

// The damage below moves triangles around; corner attributes would have to
// follow, and what repair does with them is test_repair's business. Surfaces
// (one per triangle) are kept in step.
Mesh without_attributes(Mesh mesh) {
  mesh.corners = {};
  mesh.surfaces.assign(mesh.triangles.size(), original_surface);
  return mesh;
}

void append_triangle(Mesh& mesh, Triangle t) {
  mesh.triangles.push_back(t);
  mesh.surfaces.push_back(original_surface);
}

// Every triangle on its own three vertex copies, triangles and copies shuffled.
Mesh unweld(const Mesh& mesh, Random& random) {
  Mesh out;
  std::vector<std::size_t> order(mesh.triangles.size());
  std::iota(order.begin(), order.end(), std::size_t(0));
  for (std::size_t i = order.size(); i > 1; --i) std::swap(order[i - 1], order[random.index(i)]);
  for (std::size_t t : order) {
    const auto base = static_cast<VertexIndex>(out.positions.size());
    for (int c = 0; c < 3; ++c) out.positions.push_back(mesh.positions[mesh.triangles[t][c]]);
    append_triangle(out, {base, base + 1, base + 2});
  }
  return out;
}

Triangle rotated(Triangle t, std::size_t by) { return {t[by % 3], t[(by + 1) % 3], t[(by + 2) % 3]}; }

// Copies of existing triangles (rotated), triangles using one vertex twice, and
// back-to-back pairs over three vertices no triangle joins.
Mesh duplicate(Mesh mesh, Random& random) {
  const std::size_t n = mesh.triangles.size();
  const std::size_t copies = 1 + random.index(std::max<std::size_t>(1, n / 10));
  for (std::size_t k = 0; k < copies; ++k) append_triangle(mesh, rotated(mesh.triangles[random.index(n)], random.index(3)));
  const std::size_t repeated = random.index(4);
  for (std::size_t k = 0; k < repeated; ++k) {
    const Triangle& t = mesh.triangles[random.index(n)];
    append_triangle(mesh, {t[0], t[1], t[0]});
  }
  const std::size_t pairs = random.index(3);
  const auto v = static_cast<VertexIndex>(mesh.positions.size());
  auto joined = [&](const Triangle& t) {
    // The pair is removed whole, so it must not copy a triangle of the mesh.
    std::array<VertexIndex, 3> sorted = t;
    std::sort(sorted.begin(), sorted.end());
    for (std::size_t u = 0; u < n; ++u) {
      std::array<VertexIndex, 3> other = mesh.triangles[u];
      std::sort(other.begin(), other.end());
      if (other == sorted) return true;
    }
    return false;
  };
  for (std::size_t k = 0; k < pairs; ++k) {
    const Triangle t{static_cast<VertexIndex>(random.index(v)), static_cast<VertexIndex>(random.index(v)),
                     static_cast<VertexIndex>(random.index(v))};
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2] || joined(t)) continue;
    append_triangle(mesh, t);
    append_triangle(mesh, {t[0], t[2], t[1]});
  }
  return mesh;
}

Mesh flip_some(Mesh mesh, Random& random) {
  // Between one triangle and all of them: a whole shell reversed is damage too.
  const double share = random.index(4) == 0 ? 1.0 : random.uniform(0.0, 0.6);
  bool any = false;
  for (Triangle& t : mesh.triangles) {
    if (random.uniform() < share) std::swap(t[1], t[2]), any = true;
  }
  if (!any) std::swap(mesh.triangles[0][1], mesh.triangles[0][2]);
  return mesh;
}

// Removes triangles: a few scattered ones, or one edge-connected patch grown
// from a random triangle. Returns the removed indices' complement order kept.
Mesh punch_holes(const Mesh& mesh, Random& random) {
  const std::size_t n = mesh.triangles.size();
  const std::size_t budget = 1 + random.index(std::max<std::size_t>(1, std::min<std::size_t>(24, n / 8)));
  std::vector<char> removed(n, 0);
  if (random.index(2) == 0) {
    for (std::size_t k = 0; k < budget; ++k) removed[random.index(n)] = 1;
  } else {
    // A patch: breadth-first over triangles sharing a vertex index (welded
    // meshes), so the hole is one opening of up to `budget` triangles.
    std::vector<std::vector<std::size_t>> at_vertex(mesh.positions.size());
    for (std::size_t t = 0; t < n; ++t)
      for (VertexIndex v : mesh.triangles[t]) at_vertex[v].push_back(t);
    std::vector<std::size_t> queue{random.index(n)};
    removed[queue[0]] = 1;
    std::size_t taken = 1;
    for (std::size_t head = 0; head < queue.size() && taken < budget; ++head) {
      for (VertexIndex v : mesh.triangles[queue[head]]) {
        for (std::size_t u : at_vertex[v]) {
          if (taken == budget || removed[u]) continue;
          removed[u] = 1, ++taken;
          queue.push_back(u);
        }
      }
    }
  }
  Mesh out;
  out.positions = mesh.positions;
  for (std::size_t t = 0; t < n; ++t) {
    if (!removed[t]) append_triangle(out, mesh.triangles[t]);
  }
  return out;
}

// Triangles a closed surface does not need, which enclose nothing with it:
// on up to 8 of its edges an edge and a point near its middle (its exact
// midpoint when that lies inside the edge, a zero-area triangle; else, or by
// choice, one moved off the edge's line by 2^-10 to 2^-40 of the triangle,
// a fin), either way round; and reversed or repeated copies of up to 8 of its
// triangles.
Mesh add_stray_triangles(Mesh mesh, Random& random) {
  const std::size_t n = mesh.triangles.size();
  std::set<std::pair<VertexIndex, VertexIndex>> used;
  const std::size_t on_edges = random.index(9);
  for (std::size_t k = 0; k < on_edges; ++k) {
    const Triangle t = mesh.triangles[random.index(n)];
    const int c = static_cast<int>(random.index(3));
    const VertexIndex a = t[c], b = t[(c + 1) % 3];
    if (!used.insert({std::min(a, b), std::max(a, b)}).second) continue;
    const Vec3 pa = mesh.positions[a], pb = mesh.positions[b], across = mesh.positions[t[(c + 2) % 3]] - pa;
    Vec3 m = (pa + pb) * 0.5;
    if (!strictly_inside_segment(pa, pb, m) || random.index(2) == 0) {
      m = m + across * std::ldexp(1.0, -static_cast<int>(10 + random.index(31)));
      if (collinear(pa, pb, m)) continue;
    }
    mesh.positions.push_back(m);
    const auto mi = static_cast<VertexIndex>(mesh.positions.size() - 1);
    append_triangle(mesh, random.index(2) == 0 ? Triangle{a, b, mi} : Triangle{b, a, mi});
  }
  const std::size_t copies = random.index(9);
  for (std::size_t k = 0; k < copies; ++k) {
    Triangle copy = rotated(mesh.triangles[random.index(n)], random.index(3));
    if (random.index(2) == 0) std::swap(copy[1], copy[2]);
    append_triangle(mesh, copy);
  }
  // At least one: a case with no damage would test nothing.
  if (mesh.triangles.size() == n) append_triangle(mesh, {mesh.triangles[0][0], mesh.triangles[0][2], mesh.triangles[0][1]});
  return mesh;
}

double random_integer(Random& random, int lo, int hi) { return double(lo + int(random.index(std::size_t(hi - lo + 1)))); }

// A lattice box with integer corners and sides of 1 to 4.
Mesh lattice_box(Vec3 lo, Random& random) {
  return test::box(lo, {lo.x + random_integer(random, 1, 4), lo.y + random_integer(random, 1, 4),
                        lo.z + random_integer(random, 1, 4)});
}

}  // namespace

std::string_view damage_name(DamageClass kind) { return damage_names[static_cast<std::size_t>(kind)]; }

DamageCase make_damage_case(const MeshPool& pool, std::uint64_t seed, std::uint64_t index) {
  DamageCase c;
  Random mixer(seed ^ (index * 0xD1B54A32D192ED03ull));
  c.seed = mixer.next();
  Random random(c.seed);
  c.kind = static_cast<DamageClass>(index % damage_class_count);

  auto pick_pool = [&] {
    for (;;) {
      const auto& [name, mesh] = pool.meshes[random.index(pool.meshes.size())];
      if (mesh.triangles.size() > largest_pool_mesh) continue;
      c.mesh_name = name;
      c.original = without_attributes(mesh);
      return;
    }
  };
  auto keep_all = [&] {
    for (const Triangle& t : c.original.triangles) c.kept.push_back(corners_of(c.original, t));
  };
  auto keep_remaining = [&](const Mesh& holed) {
    for (const Triangle& t : holed.triangles) c.kept.push_back(corners_of(holed, t));
  };

  switch (c.kind) {
    case DamageClass::unwelded:
      pick_pool();
      c.damaged = unweld(c.original, random);
      c.exact = true;
      keep_all();
      break;
    case DamageClass::duplicated:
      pick_pool();
      c.damaged = duplicate(c.original, random);
      c.exact = true;
      keep_all();
      break;
    case DamageClass::flipped:
      pick_pool();
      c.damaged = flip_some(c.original, random);
      c.exact = true;
      keep_all();
      break;
    case DamageClass::stray:
      pick_pool();
      c.damaged = add_stray_triangles(c.original, random);
      c.exact = true;
      keep_all();
      break;
    case DamageClass::holes:
      pick_pool();
      c.damaged = punch_holes(c.original, random);
      keep_remaining(c.damaged);
      break;
    case DamageClass::nested: {
      // An outer convex shell and a smaller one strictly inside it, both facing
      // out: the repair must turn the inner one into a cavity, nothing else.
      Mesh outer, inner;
      if (random.index(2) == 0) {
        c.mesh_name = "lattice-box-in-box";
        outer = test::box({0, 0, 0}, {8, 8, 8});
        inner = lattice_box({random_integer(random, 1, 3), random_integer(random, 1, 3), random_integer(random, 1, 3)},
                            random);
      } else {
        c.mesh_name = "ellipsoid-in-ellipsoid";
        const Vec3 centre{random.uniform(-2, 2), random.uniform(-2, 2), random.uniform(-2, 2)};
        outer = test::ellipsoid(centre, {2, 1.5, 1}, 12, 8);
        inner = test::ellipsoid(centre, {0.75, 0.5, 0.25}, 10, 6);
      }
      c.original = test::merge({outer, test::flipped(inner)});
      c.damaged = test::merge({outer, inner});
      c.original = without_attributes(c.original), c.damaged = without_attributes(c.damaged);
      c.exact = true;
      keep_all();
      break;
    }
    case DamageClass::touching: {
      // Lattice boxes meeting at exactly one corner or along exactly one edge.
      const Mesh a = lattice_box({0, 0, 0}, random);
      Vec3 hi{0, 0, 0};
      for (const Vec3& p : a.positions) hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
      const bool along_edge = random.index(2) == 0;
      c.mesh_name = along_edge ? "lattice-boxes-sharing-an-edge" : "lattice-boxes-sharing-a-corner";
      Mesh b = along_edge ? test::box({hi.x, hi.y, 0}, {hi.x + random_integer(random, 1, 3),
                                                         hi.y + random_integer(random, 1, 3), hi.z})
                          : lattice_box(hi, random);
      c.damaged = without_attributes(test::merge({a, b}));
      c.original = c.damaged;
      // The parts come apart by moving copies of the positions they share a hair:
      // every triangle away from those is kept.
      std::vector<Vec3> shared;
      for (const Vec3& p : a.positions) {
        if (std::find(b.positions.begin(), b.positions.end(), p) != b.positions.end()) shared.push_back(p);
      }
      for (const Triangle& t : c.original.triangles) {
        const std::array<Vec3, 3> corners = corners_of(c.original, t);
        if (std::none_of(corners.begin(), corners.end(), [&](const Vec3& p) {
              return std::find(shared.begin(), shared.end(), p) != shared.end();
            })) {
          c.kept.push_back(corners);
        }
      }
      break;
    }
    case DamageClass::overlapping: {
      pick_pool();
      const test::Box3 box = test::bounds(c.original);
      const Vec3 size = box.hi - box.lo;
      const Vec3 shift{size.x * random.uniform(0.1, 0.5), size.y * random.uniform(-0.3, 0.3),
                       size.z * random.uniform(-0.3, 0.3)};
      c.damaged = without_attributes(test::merge({c.original, test::transformed(c.original, 1.0, shift)}));
      // Where the copies cross, the exact step keeps only their union: no
      // triangle is promised back, the volume is checked instead.
      break;
    }
    case DamageClass::mixed: {
      pick_pool();
      const Mesh holed = random.index(2) == 0 ? punch_holes(c.original, random) : c.original;
      keep_remaining(holed);
      // Flipped before duplicated: a copy reversed against its original is a
      // back-to-back pair, which repair removes whole (test_repair covers that).
      c.damaged = unweld(duplicate(flip_some(holed, random), random), random);
      break;
    }
  }
  const test::Box3 box = test::bounds(c.original);
  const Vec3 centre = (box.lo + box.hi) * 0.5;
  const Vec3 normal = random.direction();
  c.plane = {normal, -(normal.x * centre.x + normal.y * centre.y + normal.z * centre.z)};
  return c;
}

DamageOutcome run_damage_case(const DamageCase& c) {
  DamageOutcome out;
  auto fail = [&](std::string what) { out.failures.push_back(std::string(damage_name(c.kind)) + " " + c.mesh_name + ": " + what); };
  try {
    // A valid mesh is left bit for bit as it is, with an empty report.
    if (c.kind != DamageClass::touching) {
      Mesh untouched = c.original;
      const RepairReport report = repair_mesh(untouched);
      if (!report.empty() || test::canonical_bytes(untouched) != test::canonical_bytes(c.original))
        fail("repairing the valid original changed it: " + report.summary());
    }

    // A damage that happened to leave a valid solid (a shifted copy that misses
    // the original) is no damage: the repair must leave it as it is.
    const bool damaged_is_valid = validate_mesh(c.damaged).valid();
    // As the CLI repairs: with the exact self-intersection step.
    RepairOptions options;
    options.round_solid = round_repaired_solid;
    Mesh repaired = c.damaged;
    const RepairReport report = repair_mesh(repaired, options);
    out.changes = report.changes.size();
    Mesh again = c.damaged;
    repair_mesh(again, options);
    if (test::canonical_bytes(again) != test::canonical_bytes(repaired)) fail("two repairs of the same mesh differ");

    const ValidationReport validation = validate_mesh(repaired);
    out.valid = validation.valid();
    if (!out.valid) {
      out.refusal = validation.summary() + " [repair: " + report.summary();
      for (const RepairNote& note : report.notes) out.refusal += "; not done: " + note.text;
      out.refusal += "]";
      // The damage these classes make is what repair_mesh promises to undo.
      if (c.exact) fail("not repaired: " + out.refusal + " (report: " + report.summary() + ")");
      return out;
    }
    if (damaged_is_valid && (!report.empty() || test::canonical_bytes(repaired) != test::canonical_bytes(c.damaged)))
      fail("repair changed a damaged mesh that was valid already: " + report.summary());
    if (!damaged_is_valid && !report.changed()) fail("a damaged mesh came back valid with an empty report");

    const std::vector<TriangleKey> after = sorted_keys(repaired);
    if (c.exact && after != sorted_keys(c.original)) fail("the repair did not give the original triangles back");
    // Where repair separated parts touching at a vertex (lids over holes touching
    // there can pinch a surface too), a kept triangle's corner there may have
    // moved to a copy: by at most touching_separation times an edge's length.
    std::vector<Vec3> moved_copies;
    double reach = 0;
    if (report.find(RepairKind::separated_touching_parts)) {
      std::vector<Vec3> before_positions = c.damaged.positions;
      const auto less = [](const Vec3& a, const Vec3& b) { return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z); };
      std::sort(before_positions.begin(), before_positions.end(), less);
      for (const Vec3& p : repaired.positions) {
        if (!std::binary_search(before_positions.begin(), before_positions.end(), p, less)) moved_copies.push_back(p);
      }
      for (const Triangle& t : repaired.triangles) {
        for (int k = 0; k < 3; ++k) {
          reach = std::max(reach, norm(repaired.positions[t[(k + 1) % 3]] - repaired.positions[t[k]]));
        }
      }
      reach *= RepairOptions{}.touching_separation;
    }
    const auto kept_with_moved_corners = [&](const std::array<Vec3, 3>& corners) {
      std::array<std::vector<Vec3>, 3> options;
      for (int k = 0; k < 3; ++k) {
        options[k].push_back(corners[k]);
        for (const Vec3& q : moved_copies) {
          if (norm(q - corners[k]) <= reach) options[k].push_back(q);
        }
      }
      for (const Vec3& a : options[0])
        for (const Vec3& b : options[1])
          for (const Vec3& d : options[2])
            if (std::binary_search(after.begin(), after.end(), key_of({a, b, d}))) return true;
      return false;
    };
    std::size_t lost = 0, reversed = 0;
    for (const auto& corners : c.kept) {
      if (std::binary_search(after.begin(), after.end(), key_of(corners))) continue;
      if (!moved_copies.empty() && kept_with_moved_corners(corners)) continue;
      ++lost;
      reversed += std::binary_search(after.begin(), after.end(), key_of({corners[0], corners[2], corners[1]})) ||
                  (!moved_copies.empty() && kept_with_moved_corners({corners[0], corners[2], corners[1]}));
    }
    if (lost > 0 && !damaged_is_valid) {
      fail(std::to_string(lost) + " of the " + std::to_string(c.kept.size()) + " triangles the damage left were lost (" +
           std::to_string(reversed) + " of them reversed) (report: " + report.summary() + ")");
    }
    const double before_volume = signed_volume(c.original), after_volume = signed_volume(repaired);
    out.volume_change = std::abs(after_volume - before_volume) / std::abs(before_volume);
    if (c.kind == DamageClass::overlapping && report.find(RepairKind::resolved_self_intersections_exactly)) {
      // The union of the mesh and its shifted copy holds the mesh and is at most
      // both (the copies' volumes are equal; rounding moves far less than the
      // margin of a shift of a tenth of the size).
      if (!(after_volume > before_volume && after_volume < 2 * before_volume)) {
        fail("the union of the mesh and its shifted copy has volume " + std::to_string(after_volume) +
             " against the mesh's " + std::to_string(before_volume));
      }
    }
    if (c.kind == DamageClass::touching) {
      // Separated by moves of 2^-20 of an edge (RepairOptions::touching_separation):
      // the volume lost is at most what those moves sweep.
      if (!report.find(RepairKind::separated_touching_parts)) fail("valid without separating the parts: " + report.summary());
      double longest = 0;
      for (const Triangle& t : c.original.triangles) {
        for (int k = 0; k < 3; ++k) {
          longest = std::max(longest, norm(c.original.positions[t[(k + 1) % 3]] - c.original.positions[t[k]]));
        }
      }
      if (!(after_volume < before_volume) ||
          before_volume - after_volume > RepairOptions{}.touching_separation * longest * test::surface_area(c.original)) {
        fail("separating the parts changed the volume from " + std::to_string(before_volume) + " to " +
             std::to_string(after_volume));
      }
    }

    // What fracture --repair does next: the repaired solid is cut, every piece
    // rounded, certified and valid as written (or vanished, or counted as the
    // main run counts rounding's refusals).
    try {
      const PlaneCut cut = cut_mesh_by_plane(repaired, c.plane);
      for (const CutPiece& piece : cut.pieces) {
        if (piece.vanished) continue;
        if (!piece.defect.empty()) {
          ++out.unroundable;
          continue;
        }
        ++out.pieces;
        const ValidationReport piece_validation = validate_mesh(piece.mesh);
        if (!piece_validation.valid()) fail("a certified piece of the repaired solid is invalid: " + piece_validation.summary());
      }
    } catch (const UnsupportedGeometryError&) {
      ++out.pinched;
    }
  } catch (const std::exception& e) {
    fail(std::string("exception: ") + e.what());
  }
  return out;
}

}  // namespace shatter::robust
