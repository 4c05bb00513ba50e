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
#include <set>
#include <sstream>

#include "shatter/kernel/error.hpp"
#include "shatter/kernel/exact.hpp"
#include "shatter/kernel/io.hpp"
#include "shatter/kernel/predicates.hpp"
#include "shatter/kernel/validate.hpp"
#include "shatter/meshtree/build.hpp"
#include "shatter/meshtree/cut.hpp"
#include "shatter/meshtree/file.hpp"
#include "shatter/slicer/slice.hpp"
#include "shatter/triangulate/cap.hpp"
#include "support/checks.hpp"
#include "support/corpus.hpp"
#include "support/degenerate.hpp"
#include "support/generators.hpp"

namespace shatter::robust {
namespace {

using test::Random;

constexpr std::array<std::string_view, case_class_count> class_names{
    "random-plane",   "vertex-plane",  "vertex-plane-ulps", "edge-plane",          "edge-plane-ulps",
    "face-plane",     "face-plane-ulps", "many-vertices",   "coplanar-faces",      "slivers-needles",
    "nested-shells",  "pinch",         "near-parallel-chain", "extreme-scale",     "far-from-origin",
    "attribute-seams"};

// Meshes above this size take the exact kernel's fracture and far shifts only
// rarely: they would dominate a run's time without adding new kinds of trouble.
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

std::string describe(const Plane& p) {
  std::ostringstream out;
  out.precision(17);
  out << "(" << p.normal.x << ", " << p.normal.y << ", " << p.normal.z << "; " << p.offset << ")";
  return out.str();
}

// --- checks ---------------------------------------------------------------

// The fast kernel's volume promise: the pieces' volumes sum to the parent's
// within 1e-9 relative, plus what rounding each cut point by half an ulp of the
// largest coordinate can move across the surface (matters far from the origin).
bool fast_volumes_add_up(const mpq_class& parent_six, const mpq_class& pieces_six, const Mesh& parent) {
  const double difference = std::fabs(mpq_class(pieces_six - parent_six).get_d());
  const double rounding = 2 * std::numeric_limits<double>::epsilon() * test::largest_coordinate(parent) * test::surface_area(parent);
  return difference <= 1e-9 * std::fabs(parent_six.get_d()) + 6 * rounding;
}

template <class Point>
Sign side_of(const Plane& plane, const Point& p) {
  return side_of_plane(plane, p);
}

// Whether the plane misses or only touches the solid, decided from its vertices.
template <class Point>
bool plane_leaves_one_side_empty(const BasicMesh<Point>& mesh, const Plane& plane) {
  bool below = false, above = false;
  for (const Point& p : mesh.positions) {
    const Sign s = side_of(plane, p);
    below |= s == Sign::negative;
    above |= s == Sign::positive;
  }
  return !(below && above);
}

template <class Point>
std::size_t piece_count(const CutResult<Point>& r) {
  return r.below.size() + r.above.size();
}

// Attribute channels survive a cut: present in every piece exactly when present
// in the input, finite, normals of unit length; surface ids are the input's own
// or the new cap's.
template <class Point>
std::string attribute_problem(const BasicMesh<Point>& piece, const BasicMesh<Point>& parent, SurfaceId cap) {
  if (piece.corners.has_normals() != parent.corners.has_normals()) return "normals channel lost or invented";
  if (piece.corners.has_uvs() != parent.corners.has_uvs()) return "uv channel lost or invented";
  if (piece.corners.has_tangents() != parent.corners.has_tangents()) return "tangent channel lost or invented";
  for (const Vec3& n : piece.corners.normals) {
    if (!is_finite(n) || std::fabs(norm(n) - 1) > 1e-9) return "a corner normal is not a finite unit vector";
  }
  for (const Vec2& uv : piece.corners.uvs) {
    if (!std::isfinite(uv.x) || !std::isfinite(uv.y)) return "a corner uv is not finite";
  }
  std::set<SurfaceId> allowed(parent.surfaces.begin(), parent.surfaces.end());
  allowed.insert(cap);
  for (SurfaceId s : piece.surfaces) {
    if (!allowed.count(s)) return "surface id " + std::to_string(s) + " is neither the input's nor the cap's";
  }
  return {};
}

// Invariant 3, checked apart from cut_mesh: the cap over the slice's border edges
// has exactly those edges as its boundary and adds no vertex on it.
template <class Point>
std::string cap_problem(const BasicMesh<Point>& mesh, const Plane& plane) {
  const SlicedMesh<Point> sliced = slice_mesh(mesh, plane);
  if (sliced.plane_misses()) return {};
  Cap<Point> cap;
  if constexpr (std::is_same_v<Point, Vec3>) {
    cap = triangulate_cap(sliced.positions, sliced.border_edges, plane,
                          [&](VertexIndex v) { return exact_position(sliced, plane, v); });
  } else {
    cap = triangulate_cap(sliced.positions, sliced.border_edges, plane);
  }
  if (!cap_boundary_is_border(cap.triangles, sliced.border_edges)) return "cap boundary is not the border edges";
  return {};
}

struct Checker {
  const Case& c;
  CaseOutcome& outcome;

  void fail(std::string what) { outcome.failures.push_back(std::move(what)); }

  // One fast cut of `parent`, every promise checked; returns the pieces that
  // are valid solids (the chain goes on with those only: cut_mesh promises only
  // topology for a parent whose embedding is degenerate).
  std::vector<Mesh> fast_cut(const Mesh& parent, const Plane& plane, SurfaceId cap, bool first_cut,
                             const std::string& where) {
    CutOptions options;
    options.cap_surface = cap;
    const CutResult<Vec3> result = cut_mesh(parent, plane, options);
    if (result.plane_missed != plane_leaves_one_side_empty(parent, plane)) {
      fail(where + ": plane_missed disagrees with the exact sides of the vertices");
    }
    std::vector<Mesh> valid;
    mpq_class pieces_six = 0;
    std::size_t k = 0;
    for (const auto* side : {&result.below, &result.above}) {
      for (const Mesh& piece : *side) {
        const std::string name = where + " piece " + std::to_string(k++);
        ++outcome.fast_pieces;
        if (std::string p = test::topology_problem(piece); !p.empty()) fail(name + ": " + p);
        if (std::string p = attribute_problem(piece, parent, cap); !p.empty()) fail(name + ": " + p);
        const ValidationReport report = validate_mesh(piece);
        if (report.find(DefectKind::self_intersection)) {
          ++outcome.fast_self_intersecting;
        } else if (!report.valid()) {
          ++outcome.fast_degenerate;
        } else {
          valid.push_back(piece);
        }
        pieces_six += test::exact_six_volume(piece);
      }
    }
    if (piece_count(result) == 0) fail(where + ": no pieces");
    if (!fast_volumes_add_up(test::exact_six_volume(parent), pieces_six, parent)) {
      fail(where + ": pieces' volumes do not add up to the parent's");
    }
    if (first_cut) {
      if (std::string p = cap_problem(parent, plane); !p.empty()) fail(where + ": " + p);
      const CutResult<Vec3> again = cut_mesh(parent, plane, options);
      bool same = piece_count(again) == piece_count(result);
      for (std::size_t i = 0; same && i < result.below.size(); ++i) {
        same = test::canonical_bytes(again.below[i]) == test::canonical_bytes(result.below[i]);
      }
      for (std::size_t i = 0; same && i < result.above.size(); ++i) {
        same = test::canonical_bytes(again.above[i]) == test::canonical_bytes(result.above[i]);
      }
      if (!same) fail(where + ": the same cut twice gave different bytes");
    }
    return valid;
  }

  std::vector<ExactMesh> exact_cut(const ExactMesh& parent, const Plane& plane, SurfaceId cap, bool first_cut,
                                   const std::string& where) {
    CutOptions options;
    options.cap_surface = cap;
    const CutResult<ExactPoint> result = cut_mesh(parent, plane, options);
    if (result.plane_missed != plane_leaves_one_side_empty(parent, plane)) {
      fail(where + ": plane_missed disagrees with the exact sides of the vertices");
    }
    std::vector<ExactMesh> pieces;
    mpq_class pieces_six = 0;
    std::size_t k = 0;
    for (const auto* side : {&result.below, &result.above}) {
      for (const ExactMesh& piece : *side) {
        const std::string name = where + " piece " + std::to_string(k++);
        ++outcome.exact_pieces;
        if (std::string p = test::exact_solid_problem(piece); !p.empty()) fail(name + ": " + p);
        if (std::string p = attribute_problem(piece, parent, cap); !p.empty()) fail(name + ": " + p);
        pieces_six += test::exact_six_volume(piece);
        pieces.push_back(piece);
      }
    }
    if (pieces.empty()) fail(where + ": no pieces");
    if (pieces_six != test::exact_six_volume(parent)) fail(where + ": exact volumes do not add up exactly");
    if (first_cut) {
      if (std::string p = cap_problem(parent, plane); !p.empty()) fail(where + ": " + p);
    }
    return pieces;
  }

  // Records the cut where the chain first failed as the shrunk case.
  void remember_smallest(const Mesh& parent, const Plane& plane, std::size_t failures_before) {
    if (outcome.shrunk || outcome.failures.size() == failures_before || c.planes.size() == 1) return;
    Case smaller = c;
    smaller.mesh = parent;
    smaller.mesh.surfaces.assign(parent.triangles.size(), original_surface);
    smaller.mesh_name = c.mesh_name + " (one piece of the chain)";
    smaller.planes = {plane};
    outcome.shrunk = std::move(smaller);
  }

  void slice_chain() {
    if (c.kernel == KernelKind::fast) {
      std::vector<Mesh> pieces{c.mesh};
      for (std::size_t i = 0; i < c.planes.size(); ++i) {
        std::vector<Mesh> next;
        for (std::size_t p = 0; p < pieces.size(); ++p) {
          const std::size_t before = outcome.failures.size();
          const std::string where = "cut " + std::to_string(i) + " of piece " + std::to_string(p);
          for (Mesh& piece : fast_cut(pieces[p], c.planes[i], SurfaceId(i + 1), i == 0, where)) {
            next.push_back(std::move(piece));
          }
          remember_smallest(pieces[p], c.planes[i], before);
        }
        pieces = std::move(next);
      }
    } else {
      std::vector<ExactMesh> pieces{to_exact(c.mesh)};
      for (std::size_t i = 0; i < c.planes.size(); ++i) {
        std::vector<ExactMesh> next;
        for (std::size_t p = 0; p < pieces.size(); ++p) {
          const std::size_t before = outcome.failures.size();
          const std::string where = "cut " + std::to_string(i) + " of piece " + std::to_string(p);
          for (ExactMesh& piece : exact_cut(pieces[p], c.planes[i], SurfaceId(i + 1), i == 0, where)) {
            next.push_back(std::move(piece));
          }
          remember_smallest(to_fast(pieces[p]), c.planes[i], before);
        }
        pieces = std::move(next);
      }
    }
  }

  void check_leaf_ranges(const MeshTree& tree) {
    for (NodeIndex v = 0; v < tree.nodes.size(); ++v) {
      const MeshTreeNode& node = tree.nodes[v];
      if (node.is_leaf()) {
        if (node.leaf_count != 1 || tree.leaf_nodes.at(node.first_leaf) != v) fail("node " + std::to_string(v) + ": leaf range");
        continue;
      }
      LeafIndex next = node.first_leaf;
      for (NodeIndex child : node.children) {
        if (tree.nodes[child].first_leaf != next || tree.nodes[child].parent != v) {
          fail("node " + std::to_string(v) + ": children's leaf ranges are not contiguous");
        }
        next += tree.nodes[child].leaf_count;
      }
      if (next != node.first_leaf + node.leaf_count) fail("node " + std::to_string(v) + ": leaf ranges do not cover it");
    }
  }

  void fracture() {
    BuildOptions options = c.build;
    options.threads = 1;
    ExactBuild built = build_mesh_tree_keeping_exact(c.mesh, options);
    const MeshTree& tree = built.tree;
    if (tree.leaf_count() < options.fragments) fail("fewer leaves than fragments asked for");
    check_leaf_ranges(tree);
    std::vector<mpq_class> six;
    for (NodeIndex v = 0; v < tree.nodes.size(); ++v) {
      const Mesh& mesh = tree.nodes[v].mesh;
      if (std::string p = test::solid_problem(mesh); !p.empty()) fail("node " + std::to_string(v) + ": " + p);
      six.push_back(test::exact_six_volume(mesh));
    }
    // The builder redraws any plane whose rounded pieces intersect themselves;
    // the leaves are checked again here, independently.
    for (NodeIndex leaf : tree.leaf_nodes) {
      ++outcome.fast_pieces;
      if (validate_mesh(tree.nodes[leaf].mesh).find(DefectKind::self_intersection)) {
        ++outcome.fast_self_intersecting;
        fail("leaf node " + std::to_string(leaf) + ": self-intersecting, though the builder promises none");
      }
    }
    for (NodeIndex v = 0; v < tree.nodes.size(); ++v) {
      const MeshTreeNode& node = tree.nodes[v];
      if (node.is_leaf()) continue;
      mpq_class total = 0;
      for (NodeIndex child : node.children) total += six[child];
      if (!fast_volumes_add_up(six[v], total, node.mesh)) fail("node " + std::to_string(v) + ": children's volumes");
    }
    if (c.kernel == KernelKind::exact) {
      if (built.exact_meshes.size() != tree.nodes.size()) {
        fail("exact build returned " + std::to_string(built.exact_meshes.size()) + " exact solids");
        return;
      }
      std::vector<mpq_class> exact_six;
      for (NodeIndex v = 0; v < tree.nodes.size(); ++v) {
        ++outcome.exact_pieces;
        if (std::string p = test::exact_solid_problem(built.exact_meshes[v]); !p.empty()) {
          fail("exact node " + std::to_string(v) + ": " + p);
        }
        exact_six.push_back(test::exact_six_volume(built.exact_meshes[v]));
      }
      for (NodeIndex v = 0; v < tree.nodes.size(); ++v) {
        if (tree.nodes[v].is_leaf()) continue;
        mpq_class total = 0;
        for (NodeIndex child : tree.nodes[v].children) total += exact_six[child];
        if (total != exact_six[v]) fail("exact node " + std::to_string(v) + ": children's volumes not exact");
      }
    }
    // Invariant 4 on a quarter of the builds (it doubles their cost).
    if (c.seed % 4 == 0) {
      BuildOptions parallel = options;
      parallel.threads = 2;
      if (encode_shatter(build_mesh_tree(c.mesh, parallel)) != encode_shatter(tree)) {
        fail("1 and 2 threads built different bytes");
      }
    }
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
  c.kernel = random.index(5) < 2 ? KernelKind::exact : KernelKind::fast;

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
  // The exact kernel's rationals make large meshes slow: a quarter of their draws.
  if (large && c.kernel == KernelKind::exact && random.index(4) != 0) c.kernel = KernelKind::fast;
  if (c.op == Operation::fracture) {
    if (large) c.kernel = KernelKind::fast;
    static constexpr std::uint32_t fragment_choices[] = {2, 3, 4, 8, 16};
    c.build.fragments = fragment_choices[random.index(large || c.kernel == KernelKind::exact ? 4 : 5)];
    c.build.seed = random.next();
    c.build.strategy = static_cast<Strategy>(random.index(3));
    c.build.kernel = c.kernel;
  }
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
  } catch (const UnsupportedGeometryError&) {
    outcome.refused = true;
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
      << "kernel " << kernel_name(c.kernel) << "\n"
      << "seed " << c.seed << "\n"
      << "failure " << failure.substr(0, failure.find('\n')) << "\n";
  for (const Plane& p : c.planes) {
    out << "plane " << hex(p.normal.x) << ' ' << hex(p.normal.y) << ' ' << hex(p.normal.z) << ' ' << hex(p.offset)
        << "  # " << describe(p) << "\n";
  }
  if (c.op == Operation::fracture) {
    out << "fragments " << c.build.fragments << "\nbuild-seed " << c.build.seed << "\nstrategy "
        << strategy_name(c.build.strategy) << "\n";
  }
  const std::string mesh = write_mesh_to_bytes(c.mesh, MeshFormat::obj);
  out << "mesh-obj " << mesh.size() << "\n" << mesh;
  std::filesystem::create_directories(dir);
  const std::filesystem::path path =
      dir / (std::string(class_name(c.kind)) + "-" + std::string(operation_name(c.op)) + "-" +
             std::string(kernel_name(c.kernel)) + "-" + std::to_string(c.seed) + ".repro");
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
      c.kernel = rest() == "exact" ? KernelKind::exact : KernelKind::fast;
    } else if (key == "seed") {
      fields >> c.seed;
    } else if (key == "failure") {
      continue;
    } else if (key == "plane") {
      std::array<std::string, 4> words;
      for (std::string& w : words) fields >> w;
      c.planes.push_back({{parse_hex(words[0]), parse_hex(words[1]), parse_hex(words[2])}, parse_hex(words[3])});
    } else if (key == "fragments") {
      fields >> c.build.fragments;
    } else if (key == "build-seed") {
      fields >> c.build.seed;
    } else if (key == "strategy") {
      const auto strategy = parse_strategy(rest());
      if (!strategy) throw InvalidMeshError(path.string() + ": unknown strategy");
      c.build.strategy = *strategy;
    } else if (key == "mesh-obj") {
      std::size_t size = 0;
      fields >> size;
      std::string bytes(size, '\0');
      if (!in.read(bytes.data(), std::streamsize(size))) throw InvalidMeshError(path.string() + ": truncated mesh");
      c.mesh = read_mesh_from_bytes(bytes, MeshFormat::obj);
      c.build.kernel = c.kernel;
      return c;
    } else {
      throw InvalidMeshError(path.string() + ": unknown field '" + key + "'");
    }
  }
  throw InvalidMeshError(path.string() + ": no mesh");
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
