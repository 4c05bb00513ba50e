// make_caps (triangulate/cap_faces.hpp): the caps of splits of input solids and
// of cut pieces, by planes of every kind, must be bounded by exactly the border
// edges, be the same regions on both sides facing opposite ways, group each
// hole with the innermost outer loop around it, and cover the cross-section
// exactly: the cap's area equals the one found here by clipping the solid's own
// faces in rationals, apart from split_solid and make_caps (support/exact_faces.hpp).
// Known cuts (a box with a through-hole, nested shells through their cavities,
// tori, two solids at once) give the expected numbers of faces and holes.

#include <catch2/catch.hpp>

#include <gmpxx.h>

#include <algorithm>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "shatter/kernel/solid.hpp"
#include "shatter/slicer/split.hpp"
#include "shatter/triangulate/cap_faces.hpp"
#include "support/exact_faces.hpp"
#include "support/plane_pieces.hpp"

using namespace shatter;
using namespace shatter::test;

namespace {

// A piece measured once: its vertices exactly (homogeneous and rational), and
// twice each face's vector area.
struct Subject {
  const PlanePiece* piece;
  std::vector<H4> homogeneous;
  std::vector<Q3> points;
  std::vector<Q3> face_areas;
};

Subject subject_of(const PlanePiece& piece) {
  Subject subject{&piece, homogeneous_points(piece.set(), piece.solid.defs), {}, {}};
  for (const H4& h : subject.homogeneous) subject.points.push_back(rational(h));
  for (const SolidFace& face : piece.solid.faces) {
    subject.face_areas.push_back(twice_face_area(subject.points, piece.solid.loops, piece.solid.corners, face));
  }
  return subject;
}

// Twice the area along `axis` of the part of a closed loop on the n·x + d <= 0
// side (Sutherland-Hodgman against one plane: the clipped loop may run along
// the plane and back, which adds no area, so the signed area is exact).
mpq_class twice_area_below(const Q4& plane, const std::vector<Q3>& loop, int axis) {
  std::vector<Q3> kept;
  for (std::size_t i = 0; i < loop.size(); ++i) {
    const Q3& a = loop[i];
    const Q3& b = loop[(i + 1) % loop.size()];
    const mpq_class fa = plane.a * a.x + plane.b * a.y + plane.c * a.z + plane.d;
    const mpq_class fb = plane.a * b.x + plane.b * b.y + plane.c * b.z + plane.d;
    if (sgn(fa) <= 0) kept.push_back(a);
    if ((sgn(fa) < 0 && sgn(fb) > 0) || (sgn(fa) > 0 && sgn(fb) < 0)) {
      const mpq_class t = fa / (fa - fb);
      kept.push_back({a.x + t * (b.x - a.x), a.y + t * (b.y - a.y), a.z + t * (b.z - a.z)});
    }
  }
  mpq_class sum = 0;
  for (std::size_t i = 0; i < kept.size(); ++i) sum += cross_along(kept[i], kept[(i + 1) % kept.size()], axis);
  return sum;
}

// The cap's area (twice, along the cut's dominant axis, facing +n) from the
// solid's faces alone: the faces' parts below the plane, the faces lying in it
// that face +n (the below side's lids) and the cap close a solid, whose vector
// areas sum to zero. Only faces the plane crosses are clipped.
mpq_class twice_cross_section(const PlaneSet& set, PlaneRef cut, const Subject& subject, const std::vector<int>& sides,
                              int axis) {
  const Solid& solid = subject.piece->solid;
  const Q4 plane = reference_plane(set, cut);
  const Q3 normal{plane.a, plane.b, plane.c};
  mpq_class below = 0;
  for (std::size_t f = 0; f < solid.faces.size(); ++f) {
    const SolidFace& face = solid.faces[f];
    bool any_below = false, any_above = false;
    for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
      for (const VertexIndex v : loop_vertices(solid.loops, solid.corners, l)) {
        any_below |= sides[v] < 0;
        any_above |= sides[v] > 0;
      }
    }
    const mpq_class& whole = axis == 0 ? subject.face_areas[f].x : axis == 1 ? subject.face_areas[f].y : subject.face_areas[f].z;
    if (!any_above && any_below) {
      below += whole;
    } else if (!any_above && !any_below) {
      if (sgn(dotq(outward_normal(set, face), normal)) > 0) below += whole;  // the below side's lid
    } else if (any_below) {
      for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
        std::vector<Q3> loop;
        for (const VertexIndex v : loop_vertices(solid.loops, solid.corners, l)) loop.push_back(subject.points[v]);
        below += twice_area_below(plane, loop, axis);
      }
    }
  }
  return -below;
}

// Exact ray cast along the dominant axis' projection: whether `q` lies strictly
// inside the loop; nullopt when it lies on the loop.
std::optional<bool> inside(int axis, const std::vector<Q3>& loop, const Q3& q) {
  const auto uv = [axis](const Q3& p) {
    return axis == 0 ? std::pair{p.y, p.z} : axis == 1 ? std::pair{p.z, p.x} : std::pair{p.x, p.y};
  };
  const auto [x, y] = uv(q);
  bool in = false;
  for (std::size_t i = 0; i < loop.size(); ++i) {
    const auto [ax, ay] = uv(loop[i]);
    const auto [bx, by] = uv(loop[(i + 1) % loop.size()]);
    const int o = sgn(mpq_class((bx - ax) * (y - ay) - (by - ay) * (x - ax)));
    if (o == 0 && std::min(ax, bx) <= x && x <= std::max(ax, bx) && std::min(ay, by) <= y && y <= std::max(ay, by)) {
      return std::nullopt;
    }
    if ((ay <= y) != (by <= y) && (o > 0) == (by > ay)) in = !in;
  }
  return in;
}

std::vector<Q3> loop_points(const FaceSet& caps, std::uint32_t l, const std::vector<Q3>& p) {
  std::vector<Q3> points;
  for (const VertexIndex v : loop_vertices(caps.loops, caps.corners, l)) points.push_back(p[v]);
  return points;
}

using DirectedEdge = std::pair<VertexIndex, VertexIndex>;

struct Tally {
  std::size_t caps = 0, cap_faces = 0, faces_with_holes = 0, caps_of_several_faces = 0, convex_paths = 0,
              touching_loops = 0, holes_placed = 0, no_border = 0;
};

struct CapCounts {
  std::size_t faces = 0, loops = 0;
};

// The first few problems of one cap, reported by one assertion.
class Problems {
 public:
  void operator()(const std::string& text) {
    if (++count_ <= 5) text_ += "\n    " + text;
  }
  std::string report() const { return count_ == 0 ? "" : std::to_string(count_) + " problem(s):" + text_; }

 private:
  std::size_t count_ = 0;
  std::string text_;
};

// Every property of the caps of one split; returns their face and loop counts.
CapCounts check_caps(const PlaneSet& set, PlaneRef cut, const Subject& subject, const SplitSolid& split,
                     FaceSet& below_cap, FaceSet& above_cap, Tally& tally) {
  const Solid& solid = subject.piece->solid;
  const SurfaceId surface = 1000 + cut.index();
  make_caps(set, cut, split.defs, split.approx, split.border, solid.convex, surface, below_cap, above_cap);
  REQUIRE(below_cap.faces.size() == above_cap.faces.size());
  REQUIRE(below_cap.loops.size() == above_cap.loops.size());
  if (split.border.empty()) {
    // A plane holding a face of one solid and crossing none: nothing to close.
    CHECK(below_cap.faces.empty());
    ++tally.no_border;
    return {};
  }
  REQUIRE_FALSE(below_cap.faces.empty());
  const Z4 plane = plane_z(set, cut);
  const int axis = dominant_axis(plane);
  const int up = static_cast<int>(CGAL::sign(axis == 0 ? plane.a : axis == 1 ? plane.b : plane.c));
  std::vector<H4> h = subject.homogeneous;
  std::vector<Q3> p = subject.points;
  for (std::size_t v = p.size(); v < split.defs.size(); ++v) {
    h.push_back(homogeneous(set, split.defs[v]));
    p.push_back(rational(h.back()));
  }
  std::vector<int> sides;
  for (const H4& point : h) sides.push_back(side_of(plane, point));
  Problems problem;

  // Bounded by exactly the border: below runs it reversed, above as given, each
  // corner keeping its border edge's line.
  std::map<DirectedEdge, EdgeLine> border_line;
  for (const LoopEdge& e : split.border) border_line[{e.from, e.to}] = e.line;
  REQUIRE(border_line.size() == split.border.size());
  std::multiset<DirectedEdge> below_edges, above_edges, border, reversed_border;
  for (const LoopEdge& e : split.border) {
    border.insert({e.from, e.to});
    reversed_border.insert({e.to, e.from});
  }
  mpq_class cap_area = 0;
  for (std::size_t f = 0; f < below_cap.faces.size(); ++f) {
    const SolidFace& below = below_cap.faces[f];
    const SolidFace& above = above_cap.faces[f];
    const std::string where = "cap face " + std::to_string(f);
    if (!(below.plane == cut) || !(above.plane == cut) || below.reversed || !above.reversed ||
        below.surface != surface || above.surface != surface) {
      problem(where + ": not on the cut facing its side, with the cap's surface");
    }
    REQUIRE(below.loop_count == above.loop_count);
    REQUIRE(below.loop_count >= 1);
    bool convex = below.loop_count == 1;
    mpq_class face_area = 0;
    for (std::uint32_t k = 0; k < below.loop_count; ++k) {
      const std::vector<VertexIndex> b = loop_vertices(below_cap.loops, below_cap.corners, below.first_loop + k);
      const std::vector<VertexIndex> a = loop_vertices(above_cap.loops, above_cap.corners, above.first_loop + k);
      REQUIRE(b.size() == a.size());
      REQUIRE(b.size() >= 3);
      if (std::set<VertexIndex>(b.begin(), b.end()).size() != b.size()) problem(where + ": a loop not simple");
      // The same loop backwards on the above side.
      std::vector<VertexIndex> a_reversed(a.rbegin(), a.rend());
      const auto at = std::find(a_reversed.begin(), a_reversed.end(), b.front());
      if (at == a_reversed.end()) {
        problem(where + ": the above loop is not the below one");
        continue;
      }
      std::rotate(a_reversed.begin(), at, a_reversed.end());
      if (a_reversed != b) problem(where + ": the above loop is not the below one reversed");
      const SolidLoop& below_loop = below_cap.loops[below.first_loop + k];
      const SolidLoop& above_loop = above_cap.loops[above.first_loop + k];
      for (std::size_t i = 0; i < b.size(); ++i) {
        const DirectedEdge e{b[i], b[(i + 1) % b.size()]}, r{a[i], a[(i + 1) % a.size()]};
        below_edges.insert(e);
        above_edges.insert(r);
        const auto line = border_line.find({e.second, e.first});
        if (line == border_line.end() || !(below_cap.corners[below_loop.first_corner + i].line == line->second)) {
          problem(where + ": a below corner without its border edge's line");
        }
        const auto above_line = border_line.find(r);
        if (above_line == border_line.end() || !(above_cap.corners[above_loop.first_corner + i].line == above_line->second)) {
          problem(where + ": an above corner without its border edge's line");
        }
        convex = convex && turn(plane, false, h[e.first], h[e.second], h[b[(i + 2) % b.size()]]) >= 0;
      }
      // The outer loop first, counter-clockwise seen from +n; holes clockwise.
      const mpq_class loop_area = twice_area_along(p, b, axis);
      if (sgn(loop_area) * up != (k == 0 ? 1 : -1)) problem(where + ": loop " + std::to_string(k) + " turns the wrong way");
      face_area += loop_area;
    }
    if (below.convex != convex || above.convex != convex) problem(where + ": convex flag wrong");
    if (sgn(face_area) * up <= 0) problem(where + ": no area");
    cap_area += face_area;
    tally.faces_with_holes += below.loop_count > 1;
  }
  if (below_edges != reversed_border) problem("the below cap does not run the border reversed");
  if (above_edges != border) problem("the above cap does not run the border");

  // Each hole lies in its own outer loop and in no outer loop inside that one.
  for (std::size_t f = 0; f < below_cap.faces.size(); ++f) {
    const SolidFace& face = below_cap.faces[f];
    const std::vector<Q3> outer = loop_points(below_cap, face.first_loop, p);
    for (std::uint32_t l = face.first_loop + 1; l < face.first_loop + face.loop_count; ++l) {
      const std::vector<Q3> hole = loop_points(below_cap, l, p);
      std::optional<bool> in_own;
      for (std::size_t i = 0; i < hole.size() && !in_own; ++i) in_own = inside(axis, outer, hole[i]);
      if (!in_own) continue;  // every corner on the outer loop
      if (!*in_own) problem("a hole outside its outer loop");
      ++tally.holes_placed;
      for (std::size_t g = 0; g < below_cap.faces.size(); ++g) {
        if (g == f) continue;
        const std::vector<Q3> other = loop_points(below_cap, below_cap.faces[g].first_loop, p);
        std::optional<bool> hole_in_other, other_in_outer;
        for (std::size_t i = 0; i < hole.size() && !hole_in_other; ++i) hole_in_other = inside(axis, other, hole[i]);
        for (std::size_t i = 0; i < other.size() && !other_in_outer; ++i) other_in_outer = inside(axis, outer, other[i]);
        if (hole_in_other.value_or(false) && other_in_outer.value_or(false)) problem("a hole under the wrong outer loop");
      }
    }
  }
  // Loops touching at a vertex.
  std::map<VertexIndex, int> loops_at;
  for (std::uint32_t l = 0; l < below_cap.loops.size(); ++l) {
    for (const VertexIndex v : loop_vertices(below_cap.loops, below_cap.corners, l)) ++loops_at[v];
  }
  for (const auto& [v, count] : loops_at) tally.touching_loops += count > 1;

  // The cross-section, exactly.
  if (cap_area != twice_cross_section(set, cut, subject, sides, axis)) problem("the cap is not the cross-section");

  // A convex solid's cap may be linked by index alone: the same loop as grouping
  // it by predicates gives.
  if (solid.convex) {
    FaceSet grouped_below, grouped_above;
    make_caps(set, cut, split.defs, split.approx, split.border, false, surface, grouped_below, grouped_above);
    REQUIRE(grouped_below.faces.size() == 1);
    REQUIRE(below_cap.faces.size() == 1);
    if (!below_cap.faces[0].convex || !grouped_below.faces[0].convex) problem("a convex solid's cap not convex");
    std::vector<VertexIndex> linked = loop_vertices(below_cap.loops, below_cap.corners, 0);
    const std::vector<VertexIndex> grouped = loop_vertices(grouped_below.loops, grouped_below.corners, 0);
    const auto at = std::find(linked.begin(), linked.end(), grouped.front());
    REQUIRE(at != linked.end());
    std::rotate(linked.begin(), at, linked.end());
    if (linked != grouped) problem("linking by index and grouping by predicates differ");
    ++tally.convex_paths;
  }
  CHECK(problem.report() == "");
  ++tally.caps;
  tally.cap_faces += below_cap.faces.size();
  tally.caps_of_several_faces += below_cap.faces.size() > 1;
  return {below_cap.faces.size(), below_cap.loops.size()};
}

// The caps of one plane through one piece; nullopt when the plane misses it.
std::optional<CapCounts> cap_of(const Subject& subject, const Plane& plane, FaceSet& below_cap, FaceSet& above_cap,
                                Tally& tally) {
  const PlanePiece& piece = *subject.piece;
  std::vector<Plane> cuts = piece.cuts;
  cuts.push_back(plane);
  const PlaneSet set = piece.input->geometry.plane_set(cuts);
  const PlaneRef cut = PlaneRef::cut(static_cast<std::uint32_t>(cuts.size() - 1));
  SplitSolid split;
  split_solid(set, piece.solid, cut, split);
  if (split.plane_misses) return std::nullopt;
  return check_caps(set, cut, subject, split, below_cap, above_cap, tally);
}

void run_cap_matrix(std::size_t corpus_limit, std::initializer_list<std::uint64_t> seeds, int cuts,
                    std::size_t max_pieces, int random_planes) {
  Tally tally;
  // Reused across calls: make_caps must clear what the last call left.
  FaceSet below_cap, above_cap;
  for (const NamedMesh& mesh : part_test_meshes(corpus_limit)) {
    for (const std::uint64_t seed : seeds) {
      for (const PlanePiece& piece : plane_pieces(mesh, seed, cuts, max_pieces)) {
        const Subject subject = subject_of(piece);
        for (const PartPlane& test_plane : part_planes(piece, seed * 31 + piece.solid.faces.size(), random_planes)) {
          INFO(piece.name << " seed " << seed << ", plane kind " << test_plane.kind);
          cap_of(subject, test_plane.plane, below_cap, above_cap, tally);
        }
      }
    }
  }
  INFO(tally.caps << " caps of " << tally.cap_faces << " faces; " << tally.faces_with_holes << " faces with holes, "
                  << tally.caps_of_several_faces << " caps of several faces, " << tally.holes_placed
                  << " holes placed, " << tally.touching_loops << " vertices where loops touch, "
                  << tally.convex_paths << " convex caps linked by index");
  // Floors at about two thirds of what the smaller matrix measured (2026-12-02).
  CHECK(tally.caps >= 800);
  CHECK(tally.faces_with_holes >= 60);
  CHECK(tally.caps_of_several_faces >= 80);
  CHECK(tally.holes_placed >= 60);
  CHECK(tally.convex_paths >= 160);
}

}  // namespace

TEST_CASE("make_caps: bounded by the border, both sides alike, holes placed, the cross-section covered exactly",
          "[plane][caps][property]") {
  run_cap_matrix(500, {3, 4}, 3, 5, 3);
}

TEST_CASE("make_caps, the larger matrix: corpus meshes to 2,000 triangles, deeper pieces, seeds 3 to 6",
          "[plane][caps][property][heavy]") {
  run_cap_matrix(2000, {3, 4, 5, 6}, 6, 10, 4);
}

TEST_CASE("make_caps: holes and islands where they are known", "[plane][caps]") {
  struct Known {
    std::string name;
    Mesh mesh;
    Plane plane;
    CapCounts expected;
  };
  const std::vector<Known> cases{
      {"box with a through-hole, across the hole", box_with_through_hole(), {{0, 0, 1}, -0.5}, {1, 2}},
      {"box with a through-hole, tilted across the hole", box_with_through_hole(), {{0.1, -0.2, 1}, -0.5}, {1, 2}},
      {"box with a through-hole, along the hole", box_with_through_hole(), {{1, 0, 0}, -1.5}, {2, 2}},
      {"nested shells with an island, through the cavity", nested_shells_with_island(), {{0, 0, 1}, -2.1}, {2, 3}},
      {"nested shells with an island, tilted", nested_shells_with_island(), {{0.2, 0.1, 1}, -2.5}, {2, 3}},
      {"nested islands, through every shell", nested_islands(), {{0, 0, 1}, -4.5}, {3, 5}},
      {"nested islands, across y", nested_islands(), {{0, -1, 0}, 4.5}, {3, 5}},
      {"torus, through its hole", torus(1.0, 0.35, 20, 20), {{0, 0, 1}, 0.01}, {1, 2}},
      {"torus, across its ring twice", torus(1.0, 0.35, 20, 20), {{1, 0, 0}, 0.01}, {2, 2}},
      {"hollow egg, through its cavity", hollow_egg(), {{0.1, 0.2, 1}, -0.05}, {1, 2}},
      {"two boxes, both at once", two_boxes(), {{0, 0, 1}, -0.5}, {2, 2}},
      {"stairs, along a riser", staircase(4), {{1, 0, 0}, -2}, {1, 1}},
      // Two triangles touching at the saddle vertex: two faces sharing a corner.
      {"a saddle, through its saddle vertex", pinch_saddle(), {{0, 0, 1}, 0}, {2, 2}},
  };
  FaceSet below_cap, above_cap;
  Tally tally;
  for (const Known& known : cases) {
    INFO(known.name);
    const std::vector<PlanePiece> pieces = plane_pieces({known.name, known.mesh}, 1, 0, 1);
    const Subject subject = subject_of(pieces[0]);
    const std::optional<CapCounts> counts = cap_of(subject, known.plane, below_cap, above_cap, tally);
    REQUIRE(counts.has_value());
    CHECK(counts->faces == known.expected.faces);
    CHECK(counts->loops == known.expected.loops);
  }
  CHECK(tally.caps == cases.size());
  CHECK(tally.touching_loops >= 1);
}

TEST_CASE("make_caps of no border edges is empty on both sides", "[plane][caps]") {
  const PlaneInput input = prepare_plane_input(unit_cube());
  const std::vector<Plane> cuts{{{0, 0, 1}, -0.5}};
  const PlaneSet set = input.geometry.plane_set(cuts);
  FaceSet below_cap, above_cap;
  below_cap.faces.emplace_back();
  above_cap.loops.emplace_back();
  for (const bool convex : {true, false}) {
    make_caps(set, PlaneRef::cut(0), input.solid.defs, input.solid.approx, {}, convex, 1, below_cap, above_cap);
    CHECK(below_cap.faces.empty());
    CHECK(below_cap.loops.empty());
    CHECK(above_cap.faces.empty());
    CHECK(above_cap.loops.empty());
  }
}
