// split_solid (slicer/split.hpp) on its own, judged in exact arithmetic apart
// from the kernel (support/exact_faces.hpp): input solids and the pieces of a few cuts
// (faces with holes, non-convex faces, three-plane vertices), split by random
// planes, planes exactly through vertices, edges and faces, planes a few ulps
// off those, and planes touching or missing the solid. Every split must put
// every vertex on the side the rationals say, every face part on its side of the
// plane and on its face's plane and edge lines, tile each face exactly (equal
// vector areas), close up with the border edges, and leave two sides whose exact
// volumes (closed over the border) are positive and sum to the solid's.

#include <catch2/catch.hpp>

#include <gmpxx.h>

#include <algorithm>
#include <map>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "shatter/kernel/solid.hpp"
#include "shatter/slicer/split.hpp"
#include "support/exact_faces.hpp"
#include "support/plane_pieces.hpp"

using namespace shatter;
using namespace shatter::test;

namespace {

// A solid's faces as a FaceSet (to measure it like a side).
FaceSet faces_of(const Solid& solid) { return {solid.faces, solid.loops, solid.corners}; }

using FaceKey = std::tuple<std::uint32_t, bool, SurfaceId, std::uint32_t>;  // plane, reversed, surface, source
FaceKey key_of(const SolidFace& f) { return {f.plane.bits, f.reversed, f.surface, f.source}; }

bool same_faces(const FaceSet& a, const FaceSet& b) {
  if (a.faces.size() != b.faces.size() || a.loops.size() != b.loops.size() || a.corners.size() != b.corners.size()) {
    return false;
  }
  for (std::size_t i = 0; i < a.faces.size(); ++i) {
    const SolidFace &x = a.faces[i], &y = b.faces[i];
    if (key_of(x) != key_of(y) || x.convex != y.convex || x.first_loop != y.first_loop || x.loop_count != y.loop_count) {
      return false;
    }
  }
  for (std::size_t i = 0; i < a.loops.size(); ++i) {
    if (a.loops[i].first_corner != b.loops[i].first_corner || a.loops[i].corner_count != b.loops[i].corner_count) return false;
  }
  for (std::size_t i = 0; i < a.corners.size(); ++i) {
    if (a.corners[i].vertex != b.corners[i].vertex || !(a.corners[i].line == b.corners[i].line)) return false;
  }
  return true;
}

bool same_edges(const std::vector<LoopEdge>& a, const std::vector<LoopEdge>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a[i].from != b[i].from || a[i].to != b[i].to || !(a[i].line == b[i].line)) return false;
  }
  return true;
}

struct Tally {
  std::size_t splits = 0, misses = 0, crossed_faces = 0, crossed_non_convex = 0, crossed_with_holes = 0, lids = 0,
              parts_with_holes = 0, border_edges = 0, no_border = 0, new_vertices = 0, new_three_planes = 0,
              vertices_on_plane = 0, pieces = 0, points_compared = 0;
};

// A plane of the set, exactly: its coefficients, the dominant axis of its
// normal, and the normal's component there and d as rationals. Twice the vector
// area of any polygon on it is alpha n for a scalar alpha, which the component
// along that axis gives; its share of six times the volume (the fan from any
// point c of the plane: c . alpha n = -alpha d) is then -d alpha.
struct FacePlane {
  Z4 z;
  int axis;
  mpq_class normal_along, d;

  FacePlane(const PlaneSet& set, PlaneRef plane) : z(plane_z(set, plane)), axis(dominant_axis(z)) {
    normal_along = static_cast<mpq_class>(axis == 0 ? z.a : axis == 1 ? z.b : z.c);
    d = static_cast<mpq_class>(z.d);
  }
  // The shares of six times the volume of a face on the plane whose loops have
  // twice their vector area `along` the axis (outward or not: it is signed).
  mpq_class six(const mpq_class& along) const { return -d * along / normal_along; }
};

// What a piece's faces are, computed once per piece: exact points, each face's
// loops, twice its area along its plane's axis, its share of six times the volume.
struct Subject {
  const PlanePiece* piece;
  std::vector<H4> homogeneous;
  std::vector<Q3> points;
  struct Face {
    std::vector<std::vector<VertexIndex>> loops;
    mpq_class area, six;
  };
  std::vector<Face> faces;
  std::multimap<FaceKey, std::size_t> faces_of_key;
  std::map<std::uint32_t, FacePlane> planes;  // by PlaneRef bits
  mpq_class six = 0;

  const FacePlane& plane(const PlaneSet& set, PlaneRef ref) {
    auto it = planes.find(ref.bits);
    if (it == planes.end()) it = planes.emplace(ref.bits, FacePlane(set, ref)).first;
    return it->second;
  }
};

std::vector<std::vector<VertexIndex>> loops_of(const FaceSet& faces, const SolidFace& face) {
  std::vector<std::vector<VertexIndex>> loops;
  for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
    loops.push_back(loop_vertices(faces.loops, faces.corners, l));
  }
  return loops;
}

Subject subject_of(const PlanePiece& piece) {
  const PlaneSet set = piece.set();
  Subject subject{&piece, homogeneous_points(set, piece.solid.defs), {}, {}, {}, {}, 0};
  for (const H4& h : subject.homogeneous) subject.points.push_back(rational(h));
  const FaceSet faces = faces_of(piece.solid);
  for (const SolidFace& face : piece.solid.faces) {
    Subject::Face f{loops_of(faces, face), 0, 0};
    const FacePlane& plane = subject.plane(set, face.plane);
    for (const auto& loop : f.loops) f.area += twice_area_along(subject.points, loop, plane.axis);
    f.six = plane.six(f.area);
    subject.six += f.six;
    subject.faces_of_key.insert({key_of(face), subject.faces.size()});
    subject.faces.push_back(std::move(f));
  }
  return subject;
}

// The first few problems of one split, reported by one assertion (a systematic
// defect would otherwise repeat at every corner).
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

// Every property of one split.
void check_split(const PlaneSet& set, Subject& subject, PlaneRef cut, const SplitSolid& split, Tally& tally) {
  const Solid& solid = subject.piece->solid;
  const std::size_t n = solid.vertex_count();
  const Z4 plane = plane_z(set, cut);
  subject.planes.erase(cut.bits);  // the last split's plane went by the same index
  REQUIRE(split.defs.size() >= n);
  REQUIRE(split.approx.size() == split.defs.size());
  REQUIRE(split.sides.size() == split.defs.size());
  Problems problem;
  bool any_below = false, any_above = false;
  std::vector<int> sides;
  std::vector<std::size_t> on_plane;
  for (std::size_t v = 0; v < n; ++v) {
    if (!(split.defs[v] == solid.defs[v])) problem("vertex " + std::to_string(v) + " redefined");
    const int s = side_of(plane, subject.homogeneous[v]);
    sides.push_back(s);
    any_below |= s < 0;
    any_above |= s > 0;
    if (s == 0) on_plane.push_back(v);
  }
  tally.vertices_on_plane += on_plane.size();
  // New vertices lie on the cut, by definition and exactly.
  std::vector<H4> h = subject.homogeneous;
  std::vector<Q3> p = subject.points;
  for (std::size_t v = n; v < split.defs.size(); ++v) {
    h.push_back(homogeneous(set, split.defs[v]));
    p.push_back(rational(h.back()));
    sides.push_back(side_of(plane, h.back()));
    if (sides.back() != 0 || !split.defs[v].defined_on(cut) || split.defs[v].kind == PointKind::input) {
      problem("new vertex " + std::to_string(v) + " not defined on the cut");
    }
    on_plane.push_back(v);
    tally.new_three_planes += split.defs[v].kind == PointKind::three_planes;
  }
  tally.new_vertices += split.defs.size() - n;
  for (std::size_t v = 0; v < split.defs.size(); ++v) {
    if (static_cast<int>(split.sides[v]) != sides[v]) problem("vertex " + std::to_string(v) + " on the wrong side");
  }
  if (split.defs.size() > n) {
    // The rationals of the first new vertex, by Cramer's rule as well.
    const Q3 q = reference_point(set, split.defs[n]);
    if (!equal(q, p[n])) problem("two exact evaluations of a point differ");
    ++tally.points_compared;
  }
  REQUIRE(problem.report() == "");
  REQUIRE(split.plane_misses == !(any_below && any_above));
  if (split.plane_misses) {
    CHECK(split.all_below == !any_above);
    CHECK(split.defs.size() == n);
    CHECK(split.below.faces.empty());
    CHECK(split.above.faces.empty());
    CHECK(split.border.empty());
    ++tally.misses;
    return;
  }
  ++tally.splits;

  // Vertices on the plane, old and new, all at distinct points: one new vertex
  // per crossing edge, none where a vertex already was.
  std::set<std::tuple<mpq_class, mpq_class, mpq_class>> distinct;
  for (const std::size_t v : on_plane) distinct.insert({p[v].x, p[v].y, p[v].z});
  if (distinct.size() != on_plane.size()) problem("two vertices at one point");

  // How the plane meets each face of the solid.
  for (const SolidFace& face : solid.faces) {
    bool below = false, above = false;
    for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
      for (const VertexIndex v : loop_vertices(solid.loops, solid.corners, l)) {
        below |= sides[v] < 0;
        above |= sides[v] > 0;
      }
    }
    if (below && above) {
      ++tally.crossed_faces;
      tally.crossed_non_convex += !face.convex;
      tally.crossed_with_holes += face.loop_count > 1;
    }
    tally.lids += !below && !above;
  }

  std::map<FaceKey, mpq_class> parts_area;
  std::map<std::pair<VertexIndex, VertexIndex>, int> edge_count[2];
  mpq_class six[2] = {0, 0};
  const int cut_normal_sign[3] = {static_cast<int>(CGAL::sign(plane.a)), static_cast<int>(CGAL::sign(plane.b)),
                                  static_cast<int>(CGAL::sign(plane.c))};
  for (int s = 0; s < 2; ++s) {
    const FaceSet& side = s == 0 ? split.below : split.above;
    const int keep = s == 0 ? -1 : 1;
    for (std::size_t f = 0; f < side.faces.size(); ++f) {
      const SolidFace& part = side.faces[f];
      const std::string where = std::string(s == 0 ? "below" : "above") + " part " + std::to_string(f);
      const FaceKey key = key_of(part);
      const auto [first, last] = subject.faces_of_key.equal_range(key);
      if (first == last || part.loop_count == 0) {
        problem(where + ": not a part of a face of the solid");
        continue;
      }
      const std::vector<std::vector<VertexIndex>> loops = loops_of(side, part);
      bool strictly_on_side = false;
      for (const auto& loop : loops) {
        for (const VertexIndex u : loop) {
          if (u >= p.size()) {
            problem(where + ": vertex out of range");
            CHECK(problem.report() == "");
            return;
          }
          if (sides[u] * keep < 0) problem(where + ": a corner on the other side");
          strictly_on_side |= sides[u] == keep;
        }
        for (std::size_t i = 0; i < loop.size(); ++i) ++edge_count[s][{loop[i], loop[(i + 1) % loop.size()]}];
      }
      const FacePlane& face_plane = subject.plane(set, part.plane);
      // The sign that makes an area along the axis an area seen from outside.
      const int outward = sgn(face_plane.normal_along) * (part.reversed ? -1 : 1);
      // A face kept whole needs no arithmetic: it is the solid's own.
      const Subject::Face* whole = nullptr;
      for (auto it = first; it != last && whole == nullptr; ++it) {
        if (subject.faces[it->second].loops == loops) whole = &subject.faces[it->second];
      }
      mpq_class area = 0;
      if (whole != nullptr) {
        area = whole->area;
        six[s] += whole->six;
      } else {
        // A new part: on its face's plane and edge lines, one outer loop
        // counter-clockwise seen from outside and holes clockwise, convex as
        // marked, facing outward.
        bool convex = part.loop_count == 1;
        int outer_loops = 0;
        for (std::uint32_t l = part.first_loop; l < part.first_loop + part.loop_count; ++l) {
          const SolidLoop& loop = side.loops[l];
          const std::vector<VertexIndex>& vertices = loops[l - part.first_loop];
          if (vertices.size() < 3 || std::set<VertexIndex>(vertices.begin(), vertices.end()).size() != vertices.size()) {
            problem(where + ": a loop not simple");
          }
          const mpq_class loop_area = twice_area_along(p, vertices, face_plane.axis);
          const int orientation = sgn(loop_area) * outward;
          if (orientation == 0) problem(where + ": a flat loop");
          outer_loops += orientation > 0;
          area += loop_area;
          for (std::uint32_t i = 0; i < loop.corner_count; ++i) {
            const SolidCorner& corner = side.corners[loop.first_corner + i];
            const VertexIndex u = corner.vertex, w = vertices[(i + 1) % vertices.size()];
            if (side_of(face_plane.z, h[u]) != 0) problem(where + ": a corner off its face's plane");
            for (const VertexIndex x : {u, w}) {
              if (corner.line.other.bits != no_index && side_of(subject.plane(set, corner.line.other).z, h[x]) != 0) {
                problem(where + ": an edge off the plane across");
              }
              if (corner.line.is_segment() && !on_line(set.points[corner.line.p], set.points[corner.line.q], h[x])) {
                problem(where + ": an edge off its input segment");
              }
            }
            convex = convex && turn(face_plane.z, part.reversed, h[u], h[w], h[vertices[(i + 2) % vertices.size()]]) >= 0;
          }
        }
        if (outer_loops != 1) problem(where + ": " + std::to_string(outer_loops) + " outer loops");
        if (part.convex != convex) problem(where + ": convex flag wrong");
        if (sgn(area) * outward <= 0) problem(where + ": not facing outward");
        six[s] += face_plane.six(area);
      }
      tally.parts_with_holes += part.loop_count > 1;
      if (!strictly_on_side) {
        // A face in the plane: the lid of the side its outward normal looks out
        // of (the part lies on the cut's plane, so the normals are parallel).
        const int along = cut_normal_sign[face_plane.axis] * sgn(face_plane.normal_along) * (part.reversed ? -1 : 1);
        if (along != (s == 0 ? 1 : -1)) problem(where + ": a lid on the wrong side");
      }
      parts_area[key] += area;
    }
  }
  // The parts tile each face exactly.
  std::map<FaceKey, mpq_class> area_of_key;
  for (const auto& [key, index] : subject.faces_of_key) area_of_key[key] += subject.faces[index].area;
  if (parts_area != area_of_key) problem("the parts do not tile the faces");

  // Closed with the border: within a side every directed edge once, and the
  // edges without their reverse are the border (below: as given; above: reversed).
  std::multiset<std::pair<VertexIndex, VertexIndex>> open[2], border, reversed_border;
  for (int s = 0; s < 2; ++s) {
    for (const auto& [edge, count] : edge_count[s]) {
      if (count != 1) problem("a directed edge used twice on one side");
      if (edge_count[s].count({edge.second, edge.first}) == 0) open[s].insert(edge);
    }
  }
  for (const LoopEdge& e : split.border) {
    border.insert({e.from, e.to});
    reversed_border.insert({e.to, e.from});
    if (sides[e.from] != 0 || sides[e.to] != 0) problem("a border edge off the plane");
    // Its line: the plane of the below face it borders.
    bool borders_below_face = false;
    for (const SolidFace& part : split.below.faces) {
      if (!(part.plane == e.line.other)) continue;
      for (const auto& loop : loops_of(split.below, part)) {
        for (std::size_t i = 0; i < loop.size(); ++i) {
          borders_below_face |= loop[i] == e.from && loop[(i + 1) % loop.size()] == e.to;
        }
      }
    }
    if (!borders_below_face) problem("a border edge whose line is not its below face's plane");
  }
  if (open[0] != border) problem("the below side's open edges are not the border");
  if (open[1] != reversed_border) problem("the above side's open edges are not the border reversed");
  tally.border_edges += split.border.size();
  tally.no_border += split.border.empty();  // a plane between separate solids, holding a face of one

  // Volumes, each side closed by its cap over the border: the below cap faces
  // +n and runs the border reversed, the above cap the other way; on the cut's
  // plane, twice its area along the axis is the border's shoelace.
  const FacePlane cut_plane(set, cut);
  mpq_class border_area = 0;
  for (const LoopEdge& e : split.border) border_area += cross_along(p[e.from], p[e.to], cut_plane.axis);
  const mpq_class cap = cut_plane.six(border_area);
  const mpq_class below = six[0] - cap, above = six[1] + cap;
  if (sgn(below) <= 0 || sgn(above) <= 0) problem("a side without volume");
  if (below + above != subject.six) problem("the sides' volumes do not sum to the solid's");
  CHECK(problem.report() == "");
}

void check_pieces(const std::vector<PlanePiece>& pieces, std::uint64_t seed, int random_planes, Tally& tally) {
  SplitSolid split, again;
  for (const PlanePiece& piece : pieces) {
    Subject subject = subject_of(piece);
    for (const PartPlane& test_plane : part_planes(piece, seed + piece.solid.faces.size(), random_planes)) {
      std::vector<Plane> cuts = piece.cuts;
      cuts.push_back(test_plane.plane);
      const PlaneSet set = piece.input->geometry.plane_set(cuts);
      const PlaneRef cut = PlaneRef::cut(static_cast<std::uint32_t>(cuts.size() - 1));
      INFO(piece.name << ", plane kind " << test_plane.kind << " (" << test_plane.plane.normal.x << ", "
                      << test_plane.plane.normal.y << ", " << test_plane.plane.normal.z << ", "
                      << test_plane.plane.offset << ")");
      split_solid(set, piece.solid, cut, split);
      check_split(set, subject, cut, split, tally);
      if (test_plane.kind == PartPlane::missing) CHECK(split.plane_misses);
      // Deterministic, and nothing left over from the previous use of `again`.
      split_solid(set, piece.solid, cut, again);
      CHECK((again.defs == split.defs && again.sides == split.sides && same_faces(again.below, split.below) &&
             same_faces(again.above, split.above) && same_edges(again.border, split.border) &&
             again.plane_misses == split.plane_misses));
    }
    ++tally.pieces;
  }
}

// The matrix: `corpus_limit` picks the corpus meshes (by triangle count), then
// per seed up to `cuts` cuts of each mesh keep up to `max_pieces` pieces, each
// split by `random_planes` random planes and the planes of every other kind.
void run_split_matrix(std::size_t corpus_limit, std::initializer_list<std::uint64_t> seeds, int cuts,
                      std::size_t max_pieces, int random_planes) {
  Tally tally;
  for (const NamedMesh& mesh : part_test_meshes(corpus_limit)) {
    for (const std::uint64_t seed : seeds) {
      INFO(mesh.name << " seed " << seed);
      check_pieces(plane_pieces(mesh, seed, cuts, max_pieces), seed, random_planes, tally);
    }
  }
  INFO(tally.pieces << " pieces, " << tally.splits << " splits, " << tally.misses << " misses; crossed faces "
                    << tally.crossed_faces << " (" << tally.crossed_non_convex << " not convex, "
                    << tally.crossed_with_holes << " with holes), " << tally.lids << " faces in the plane, "
                    << tally.parts_with_holes << " parts with holes, " << tally.border_edges << " border edges, "
                    << tally.new_vertices << " new vertices (" << tally.new_three_planes << " met by three planes), "
                    << tally.vertices_on_plane << " vertices on the plane, " << tally.no_border
                    << " splits without a border");
  // Floors at about two thirds of what the smaller matrix measured (2026-12-02).
  CHECK(tally.pieces >= 150);
  CHECK(tally.splits >= 700);
  CHECK(tally.misses >= 500);
  CHECK(tally.crossed_non_convex >= 400);
  CHECK(tally.crossed_with_holes >= 80);
  CHECK(tally.lids >= 80);
  CHECK(tally.parts_with_holes >= 50);
  CHECK(tally.new_three_planes >= 1000);
  CHECK(tally.vertices_on_plane >= 2000);
  CHECK(tally.points_compared >= 500);
}

}  // namespace

TEST_CASE("split_solid: every vertex and face part on its side, faces tiled, sides closed, volumes exact",
          "[plane][split][property]") {
  run_split_matrix(500, {1, 2}, 3, 5, 2);
}

TEST_CASE("split_solid, the larger matrix: corpus meshes to 2,000 triangles, deeper pieces, seeds 1 to 4",
          "[plane][split][property][heavy]") {
  run_split_matrix(2000, {1, 2, 3, 4}, 6, 10, 4);
}

TEST_CASE("split_solid: planes touching a solid, and between two solids", "[plane][split]") {
  struct Known {
    std::string name;
    Mesh mesh;
    Plane plane;
    bool misses, all_below;
    std::size_t below_faces, above_faces;  // when it does not miss (coplanar triangles merged)
  };
  const std::vector<Known> cases{
      {"a box touched at its top face", box({0, 0, 0}, {1, 1, 1}), {{0, 0, 1}, -1}, true, true, 0, 0},
      {"a box touched at its bottom face from below", box({0, 0, 0}, {1, 1, 1}), {{0, 0, -1}, 0}, true, true, 0, 0},
      {"a box touched along an edge", box({0, 0, 0}, {1, 1, 1}), {{1, 1, 0}, -2}, true, true, 0, 0},
      {"a box touched at a corner", box({0, 0, 0}, {1, 1, 1}), {{-1, -1, -1}, 0}, true, true, 0, 0},
      {"a box beyond the plane", box({0, 0, 0}, {1, 1, 1}), {{1, 0, 0}, 5}, true, false, 0, 0},
      // The plane x = 2 holds the second box's face, which faces -x: the lid of
      // the side above. Nothing crosses it, so there is no border.
      {"two boxes, a face of the second on the plane", two_boxes(), {{1, 0, 0}, -2}, false, false, 6, 6},
      {"two boxes, the plane between them", two_boxes(), {{1, 0, 0}, -1.5}, false, false, 6, 6},
  };
  for (const Known& known : cases) {
    INFO(known.name);
    const std::vector<PlanePiece> pieces = plane_pieces({known.name, known.mesh}, 1, 0, 1);
    Subject subject = subject_of(pieces[0]);
    const std::vector<Plane> cuts{known.plane};
    const PlaneSet set = pieces[0].input->geometry.plane_set(cuts);
    SplitSolid split;
    split_solid(set, pieces[0].solid, PlaneRef::cut(0), split);
    Tally tally;
    check_split(set, subject, PlaneRef::cut(0), split, tally);
    REQUIRE(split.plane_misses == known.misses);
    if (known.misses) {
      CHECK(split.all_below == known.all_below);
    } else {
      CHECK(split.border.empty());
      CHECK(split.below.faces.size() == known.below_faces);
      CHECK(split.above.faces.size() == known.above_faces);
    }
  }
}
