// solid_from_mesh (kernel/solid.hpp): every generated, degenerate and corpus
// solid becomes a sound plane-based solid with the mesh's exact volume, with
// coplanar merging on and off. What merging must produce is worked out here
// apart from the kernel: triangles grouped by exact coplanarity and surface id,
// a group with a pinched boundary left as its triangles; each face then covers
// exactly its group's triangles (equal exact vector areas), faces outward, its
// convexity and the solid's are decided right, and every edge's line names the
// plane across. Every point is an input double, so sums and products of
// coordinates are exact in CGAL::Mpzf (a binary floating-point integer).
// Shuffled vertex numbers and triangle orders and random surface ids give the
// seeds; open and doubly-used edges are refused.

#include <catch2/catch.hpp>

#include <CGAL/Mpzf.h>

#include <algorithm>
#include <array>
#include <map>
#include <numeric>
#include <random>
#include <span>
#include <string>
#include <vector>

#include "shatter/generators/corpus.hpp"
#include "shatter/generators/random.hpp"
#include "shatter/generators/solids.hpp"
#include "shatter/kernel/error.hpp"
#include "shatter/kernel/io.hpp"
#include "shatter/kernel/rationals.hpp"
#include "shatter/kernel/solid.hpp"
#include "support/checks.hpp"
#include "support/degenerate.hpp"

using namespace shatter;
using namespace shatter::test;

namespace {

// Generated, degenerate and corpus solids: convex and not, several shells,
// faces with holes and pinched coplanar regions, needles and slivers, tiny,
// huge and far from the origin.
std::vector<NamedMesh> all_solids() {
  std::vector<NamedMesh> meshes = generated_meshes();
  meshes.push_back({"staircase", staircase(4)});
  meshes.push_back({"stacked-boxes", stacked_boxes(4)});
  meshes.push_back({"pinch-saddle", pinch_saddle()});
  meshes.push_back({"needle-bridge", needle_bridge(0x1p-20)});
  meshes.push_back({"flat-tetrahedron", flat_tetrahedron(0x1p-30)});
  meshes.push_back({"nested-islands", nested_islands()});
  meshes.push_back({"box-with-through-hole", box_with_through_hole()});
  meshes.push_back({"pit-and-bump", pit_and_bump()});
  for (const auto& path : valid_meshes()) meshes.push_back({path.filename().string(), read_mesh(path)});
  return meshes;
}

// Exact 3D vectors of input doubles.
struct Z3 {
  CGAL::Mpzf x, y, z;
};
Z3 z3(const Vec3& p) { return {CGAL::Mpzf(p.x), CGAL::Mpzf(p.y), CGAL::Mpzf(p.z)}; }
Z3 sub(const Z3& a, const Z3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
Z3 add(const Z3& a, const Z3& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
Z3 cross(const Z3& a, const Z3& b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
int sign_of_dot(const Z3& a, const Z3& b) { return CGAL::sign(a.x * b.x + a.y * b.y + a.z * b.z); }
bool equal(const Z3& a, const Z3& b) { return a.x == b.x && a.y == b.y && a.z == b.z; }
Z3 zero3() { return {CGAL::Mpzf(0), CGAL::Mpzf(0), CGAL::Mpzf(0)}; }

// Twice the vector area of a closed polygon.
Z3 twice_area(const std::vector<Z3>& p, const std::vector<VertexIndex>& loop) {
  Z3 sum = zero3();
  for (std::size_t i = 0; i < loop.size(); ++i) sum = add(sum, cross(p[loop[i]], p[loop[(i + 1) % loop.size()]]));
  return sum;
}

std::vector<VertexIndex> loop_vertices(const Solid& solid, std::uint32_t l) {
  std::vector<VertexIndex> vertices;
  const SolidLoop& loop = solid.loops[l];
  for (std::uint32_t i = 0; i < loop.corner_count; ++i) vertices.push_back(solid.corners[loop.first_corner + i].vertex);
  return vertices;
}

// The same solid with its vertices renumbered, its triangles reordered and
// rotated, and surface ids: all 0 (`surfaces` 1), random per triangle
// (`patches` false), or by random boxes (`patches` true: a triangle takes the id
// of the last of three boxes holding its centroid, 0 outside them, so flat faces
// get islands of another id).
Mesh shuffled(const Mesh& mesh, std::uint64_t seed, SurfaceId surfaces, bool patches) {
  Random random(seed);
  std::vector<VertexIndex> order(mesh.positions.size());
  std::iota(order.begin(), order.end(), 0u);
  for (std::size_t i = order.size(); i > 1; --i) std::swap(order[i - 1], order[random.index(i)]);
  Mesh out;
  out.positions.resize(mesh.positions.size());
  for (VertexIndex v = 0; v < order.size(); ++v) out.positions[order[v]] = mesh.positions[v];
  const Box3 whole = bounds(mesh);
  std::vector<std::pair<Box3, SurfaceId>> boxes;
  for (int k = 0; k < 3 && surfaces > 1; ++k) {
    Box3 box;
    for (int axis = 0; axis < 3; ++axis) {
      const double a = random.uniform(whole.lo[axis], whole.hi[axis]), b = random.uniform(whole.lo[axis], whole.hi[axis]);
      (axis == 0 ? box.lo.x : axis == 1 ? box.lo.y : box.lo.z) = std::min(a, b);
      (axis == 0 ? box.hi.x : axis == 1 ? box.hi.y : box.hi.z) = std::max(a, b);
    }
    boxes.push_back({box, static_cast<SurfaceId>(1 + random.index(surfaces - 1))});
  }
  std::vector<TriangleIndex> triangles(mesh.triangles.size());
  std::iota(triangles.begin(), triangles.end(), 0u);
  for (std::size_t i = triangles.size(); i > 1; --i) std::swap(triangles[i - 1], triangles[random.index(i)]);
  for (const TriangleIndex t : triangles) {
    Triangle tri = mesh.triangles[t];
    std::rotate(tri.begin(), tri.begin() + static_cast<std::ptrdiff_t>(random.index(3)), tri.end());
    out.triangles.push_back({order[tri[0]], order[tri[1]], order[tri[2]]});
    SurfaceId surface = 0;
    if (surfaces > 1 && !patches) surface = static_cast<SurfaceId>(random.index(surfaces));
    if (patches) {
      const Vec3 c = (mesh.positions[tri[0]] + mesh.positions[tri[1]] + mesh.positions[tri[2]]) * (1.0 / 3);
      for (const auto& [box, id] : boxes) {
        if (box.lo.x <= c.x && c.x <= box.hi.x && box.lo.y <= c.y && c.y <= box.hi.y && box.lo.z <= c.z &&
            c.z <= box.hi.z) {
          surface = id;
        }
      }
    }
    out.surfaces.push_back(surface);
  }
  return out;
}

Z3 twice_triangle_area(const std::vector<Z3>& p, const Triangle& t) { return cross(sub(p[t[1]], p[t[0]]), sub(p[t[2]], p[t[0]])); }

// What coplanar merging must make of a mesh, decided here in rationals: groups
// of edge-connected triangles on one plane with one surface id, the boundary
// cycles of each, and whether a boundary passes a vertex twice (then the group
// stays as single triangles).
struct ExpectedFaces {
  std::vector<std::uint32_t> group_of;              // per triangle
  std::vector<std::vector<TriangleIndex>> members;  // per group
  std::vector<bool> pinched;                        // per group
  std::vector<std::size_t> cycles;                  // per group: boundary cycles
  std::size_t face_count = 0;
};

ExpectedFaces expected_faces(const Mesh& mesh, const std::vector<Z3>& p, bool merge) {
  const std::size_t n = mesh.triangles.size();
  std::map<std::pair<VertexIndex, VertexIndex>, TriangleIndex> triangle_of;
  for (TriangleIndex t = 0; t < n; ++t) {
    for (int c = 0; c < 3; ++c) triangle_of[{mesh.triangles[t][c], mesh.triangles[t][(c + 1) % 3]}] = t;
  }
  std::vector<std::uint32_t> parent(n);
  std::iota(parent.begin(), parent.end(), 0u);
  const auto find = [&](std::uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  if (merge) {
    for (TriangleIndex t = 0; t < n; ++t) {
      const Triangle& tri = mesh.triangles[t];
      const Z3 normal = twice_triangle_area(p, tri);
      for (int c = 0; c < 3; ++c) {
        const TriangleIndex other = triangle_of.at({tri[(c + 1) % 3], tri[c]});
        if (mesh.surfaces[other] != mesh.surfaces[t]) continue;
        // Coplanar, and (a valid solid has no folds) facing the same way.
        bool coplanar = true;
        for (const VertexIndex w : mesh.triangles[other]) coplanar = coplanar && sign_of_dot(normal, sub(p[w], p[tri[0]])) == 0;
        if (coplanar && sign_of_dot(normal, twice_triangle_area(p, mesh.triangles[other])) > 0) parent[find(t)] = find(other);
      }
    }
  }
  ExpectedFaces expected;
  expected.group_of.resize(n);
  std::map<std::uint32_t, std::uint32_t> index_of_root;
  for (TriangleIndex t = 0; t < n; ++t) {
    const auto [it, added] = index_of_root.try_emplace(find(t), static_cast<std::uint32_t>(expected.members.size()));
    if (added) expected.members.emplace_back();
    expected.group_of[t] = it->second;
    expected.members[it->second].push_back(t);
  }
  for (std::uint32_t g = 0; g < expected.members.size(); ++g) {
    std::multimap<VertexIndex, VertexIndex> next;  // boundary edge u -> v
    for (const TriangleIndex t : expected.members[g]) {
      const Triangle& tri = mesh.triangles[t];
      for (int c = 0; c < 3; ++c) {
        const VertexIndex u = tri[c], v = tri[(c + 1) % 3];
        if (expected.group_of[triangle_of.at({v, u})] != g) next.insert({u, v});
      }
    }
    bool pinched = false;
    for (auto it = next.begin(); it != next.end(); ++it) pinched = pinched || next.count(it->first) > 1;
    std::size_t cycles = 0;
    if (!pinched) {
      std::map<VertexIndex, VertexIndex> successor(next.begin(), next.end());
      while (!successor.empty()) {
        ++cycles;
        for (VertexIndex v = successor.begin()->first; successor.count(v) != 0;) {
          const VertexIndex w = successor.at(v);
          successor.erase(v);
          v = w;
        }
      }
    }
    expected.pinched.push_back(pinched);
    expected.cycles.push_back(cycles);
    expected.face_count += pinched ? expected.members[g].size() : 1;
  }
  return expected;
}

// Convex as a mesh, decided here in rationals: one edge-connected shell, and at
// every edge the far corner of the triangle across not above this triangle's plane.
bool mesh_is_convex(const Mesh& mesh, const std::vector<Z3>& p) {
  std::map<std::pair<VertexIndex, VertexIndex>, TriangleIndex> triangle_of;
  for (TriangleIndex t = 0; t < mesh.triangles.size(); ++t) {
    for (int c = 0; c < 3; ++c) triangle_of[{mesh.triangles[t][c], mesh.triangles[t][(c + 1) % 3]}] = t;
  }
  std::vector<bool> reached(mesh.triangles.size(), false);
  std::vector<TriangleIndex> stack{0};
  reached[0] = true;
  while (!stack.empty()) {
    const Triangle tri = mesh.triangles[stack.back()];
    stack.pop_back();
    const Z3 normal = twice_triangle_area(p, tri);
    for (int c = 0; c < 3; ++c) {
      const TriangleIndex other = triangle_of.at({tri[(c + 1) % 3], tri[c]});
      for (const VertexIndex w : mesh.triangles[other]) {
        if (sign_of_dot(normal, sub(p[w], p[tri[0]])) > 0) return false;
      }
      if (!reached[other]) {
        reached[other] = true;
        stack.push_back(other);
      }
    }
  }
  return std::all_of(reached.begin(), reached.end(), [](bool r) { return r; });
}

struct Tally {
  std::size_t solids = 0, convex = 0, not_convex = 0, merged_faces = 0, faces_with_holes = 0, pinched_groups = 0,
              coplanar_edges = 0;
};

// Every property of solid_from_mesh on one mesh, merging on or off.
void check_solid_from_mesh(const std::string& name, const Mesh& mesh, bool merge, Tally& tally) {
  INFO(name << (merge ? ", merging coplanar triangles" : ", one face per triangle"));
  InputGeometry geometry;
  geometry.points = mesh.positions;
  const Solid solid = solid_from_mesh(mesh, merge, geometry);
  const PlaneSet set = geometry.plane_set({});
  REQUIRE(check_solid(set, solid) == "");
  CHECK(geometry.planes.size() == solid.faces.size());
  CHECK(geometry.plane_approx.size() == solid.faces.size());

  std::vector<Z3> input;
  for (const Vec3& p : mesh.positions) input.push_back(z3(p));
  // An input plane's normal, exactly: (p1 - p0) x (p2 - p0) of its points.
  const auto normal_of = [&](PlaneRef plane) {
    const auto& through = geometry.planes[plane.index()];
    return cross(sub(input[through[1]], input[through[0]]), sub(input[through[2]], input[through[0]]));
  };
  // No point is made: every vertex is an input point, once.
  std::vector<Z3> points;
  std::vector<bool> seen(mesh.positions.size(), false);
  for (const PointDef& def : solid.defs) {
    REQUIRE(def.kind == PointKind::input);
    REQUIRE(def.a < mesh.positions.size());
    CHECK_FALSE(seen[def.a]);
    seen[def.a] = true;
    points.push_back(input[def.a]);
  }
  // The exact volume: six times it, over the faces' fans and over the triangles.
  CGAL::Mpzf six_solid(0), six_mesh(0);
  for (const SolidFace& face : solid.faces) {
    const Z3& c = points[solid.corners[solid.loops[face.first_loop].first_corner].vertex];
    for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
      const std::vector<VertexIndex> loop = loop_vertices(solid, l);
      for (std::size_t i = 0; i < loop.size(); ++i) {
        const Z3 n = cross(points[loop[i]], points[loop[(i + 1) % loop.size()]]);
        six_solid = six_solid + (c.x * n.x + c.y * n.y + c.z * n.z);
      }
    }
  }
  for (const Triangle& t : mesh.triangles) {
    const Z3 n = cross(input[t[1]], input[t[2]]);
    six_mesh = six_mesh + (input[t[0]].x * n.x + input[t[0]].y * n.y + input[t[0]].z * n.z);
  }
  CHECK(six_solid == six_mesh);
  CHECK(CGAL::sign(six_mesh) > 0);
  const ExpectedFaces expected = expected_faces(mesh, input, merge);
  CHECK(solid.faces.size() == expected.face_count);
  if (!merge) CHECK(solid.vertex_count() == mesh.positions.size());

  // Directed edge (as input points) -> face running it, for the lines.
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> face_of_edge;
  for (std::uint32_t f = 0; f < solid.faces.size(); ++f) {
    const SolidFace& face = solid.faces[f];
    for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
      const std::vector<VertexIndex> loop = loop_vertices(solid, l);
      for (std::size_t i = 0; i < loop.size(); ++i) {
        face_of_edge[{solid.defs[loop[i]].a, solid.defs[loop[(i + 1) % loop.size()]].a}] = f;
      }
    }
  }
  std::vector<std::size_t> faces_of_group(expected.members.size(), 0);
  for (std::uint32_t f = 0; f < solid.faces.size(); ++f) {
    const SolidFace& face = solid.faces[f];
    INFO("face " << f << " from triangle " << face.source);
    REQUIRE(face.source < mesh.triangles.size());
    REQUIRE_FALSE(face.plane.is_cut());
    REQUIRE(face.plane.index() < geometry.planes.size());
    CHECK_FALSE(face.reversed);
    CHECK(face.surface == mesh.surfaces[face.source]);
    const std::uint32_t g = expected.group_of[face.source];
    ++faces_of_group[g];
    // The face covers exactly its group's triangles (or, for a pinched group,
    // its own triangle), and faces the way they do.
    Z3 area = zero3();
    for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
      area = add(area, twice_area(points, loop_vertices(solid, l)));
    }
    Z3 group_area = zero3();
    if (expected.pinched[g]) {
      group_area = twice_triangle_area(input, mesh.triangles[face.source]);
      CHECK(face.loop_count == 1);
    } else {
      for (const TriangleIndex t : expected.members[g]) group_area = add(group_area, twice_triangle_area(input, mesh.triangles[t]));
      CHECK(face.loop_count == expected.cycles[g]);
    }
    CHECK(equal(area, group_area));
    const Z3 normal = normal_of(face.plane);
    CHECK(sign_of_dot(area, normal) > 0);
    if (!merge) {
      CHECK(face.source == f);
      REQUIRE(face.loop_count == 1);
      const std::vector<VertexIndex> loop = loop_vertices(solid, face.first_loop);
      REQUIRE(loop.size() == 3);
      const Triangle& tri = mesh.triangles[f];
      const auto at = std::find(tri.begin(), tri.end(), solid.defs[loop[0]].a) - tri.begin();
      REQUIRE(at < 3);
      for (int c = 0; c < 3; ++c) CHECK(solid.defs[loop[c]].a == tri[(at + c) % 3]);
    }
    // Convex: one loop turning left or straight at every corner (seen from outside).
    bool convex = face.loop_count == 1;
    for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count && convex; ++l) {
      const std::vector<VertexIndex> loop = loop_vertices(solid, l);
      for (std::size_t i = 0; i < loop.size() && convex; ++i) {
        const Z3& a = points[loop[i]];
        const Z3& b = points[loop[(i + 1) % loop.size()]];
        const Z3& c = points[loop[(i + 2) % loop.size()]];
        convex = sign_of_dot(cross(sub(b, a), sub(c, b)), normal) >= 0;
      }
    }
    CHECK(face.convex == convex);
    // Every edge lies on its input segment and names the plane of the face
    // across, unless that face is coplanar (merging off, or a pinched group).
    for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
      const SolidLoop& loop = solid.loops[l];
      for (std::uint32_t i = 0; i < loop.corner_count; ++i) {
        const SolidCorner& corner = solid.corners[loop.first_corner + i];
        const std::uint32_t u = solid.defs[corner.vertex].a;
        const std::uint32_t v = solid.defs[solid.corners[loop.first_corner + (i + 1) % loop.corner_count].vertex].a;
        CHECK(corner.line.p == std::min(u, v));
        CHECK(corner.line.q == std::max(u, v));
        const auto across = face_of_edge.find({v, u});
        REQUIRE(across != face_of_edge.end());
        const PlaneRef other = solid.faces[across->second].plane;
        const Z3& on_mine = input[geometry.planes[face.plane.index()][0]];
        bool coplanar = true;
        for (const VertexIndex w : geometry.planes[other.index()]) coplanar = coplanar && sign_of_dot(normal, sub(input[w], on_mine)) == 0;
        if (coplanar) {
          CHECK(corner.line.other.bits == no_index);
          ++tally.coplanar_edges;
        } else {
          CHECK(corner.line.other == other);
        }
      }
    }
    tally.faces_with_holes += face.loop_count > 1;
    tally.merged_faces += !expected.pinched[g] && expected.members[g].size() > 1;
  }
  for (std::uint32_t g = 0; g < expected.members.size(); ++g) {
    CHECK(faces_of_group[g] == (expected.pinched[g] ? expected.members[g].size() : 1));
    tally.pinched_groups += expected.pinched[g];
  }
  const bool convex = mesh_is_convex(mesh, input);
  CHECK(solid.convex == convex);
  CHECK(solid_is_convex(set, solid) == convex);
  ++tally.solids;
  ++(convex ? tally.convex : tally.not_convex);
}

}  // namespace

TEST_CASE("solid_from_mesh: every solid sound, its exact volume the mesh's, merged or not", "[plane][solid][property]") {
  Tally merged, unmerged;
  for (const NamedMesh& m : all_solids()) {
    check_solid_from_mesh(m.name, m.mesh, true, merged);
    check_solid_from_mesh(m.name, m.mesh, false, unmerged);
  }
  INFO(merged.solids << " solids (" << merged.convex << " convex), " << merged.merged_faces << " merged faces, "
                     << merged.faces_with_holes << " with holes, " << merged.pinched_groups << " pinched groups");
  CHECK(merged.solids >= 25);
  CHECK(merged.convex >= 4);
  CHECK(merged.not_convex >= 15);
  CHECK(merged.merged_faces >= 500);
  CHECK(merged.faces_with_holes >= 5);   // the through-hole's top and bottom among them
  CHECK(merged.pinched_groups >= 1);     // the pit and the bump's top
  CHECK(unmerged.merged_faces == 0);
  CHECK(unmerged.coplanar_edges > 1000);  // edges inside flat regions, with no plane across
}

TEST_CASE("solid_from_mesh: renumbered, reordered, with random surface ids (seeds 1 to 6)", "[plane][solid][property]") {
  // Merging must follow the surface ids (coplanar triangles of two surfaces stay
  // apart), which random ids turn into ragged and pinched regions, and patches
  // of ids into faces with islands cut out of them.
  const std::vector<NamedMesh> meshes{{"grid-box-4", grid_box({-1, -1, -1}, {1, 1, 1}, 4)},
                                      {"staircase", staircase(4)},
                                      {"box-with-through-hole", box_with_through_hole()},
                                      {"nested-islands", nested_islands()},
                                      {"pit-and-bump", pit_and_bump()},
                                      {"torus", torus(1.0, 0.35, 12, 8)}};
  Tally tally;
  for (const NamedMesh& m : meshes) {
    for (std::uint64_t seed = 1; seed <= 6; ++seed) {
      const SurfaceId surfaces = seed <= 2 ? 1 : seed % 2 == 1 ? 2 : 3;
      const bool patches = seed >= 5;
      const Mesh mesh = shuffled(m.mesh, seed, surfaces, patches);
      INFO("seed " << seed << ", " << surfaces << " surface ids" << (patches ? " in patches" : ""));
      check_solid_from_mesh(m.name, mesh, true, tally);
    }
  }
  CHECK(tally.solids == meshes.size() * 6);
  CHECK(tally.merged_faces >= 1000);
  CHECK(tally.faces_with_holes >= 6);
  CHECK(tally.pinched_groups >= 10);
}

TEST_CASE("solid_from_mesh appends its planes to the geometry it is given", "[plane][solid]") {
  // Two solids over one geometry (as a build's nodes share it): the second's
  // faces name planes after the first's, and both stay sound over the union.
  const Mesh a = box({0, 0, 0}, {1, 1, 1});
  const Mesh b = staircase(3);
  Mesh both = merge({a, b});
  InputGeometry geometry;
  geometry.points = both.positions;
  Mesh first = both, second = both;
  first.triangles.assign(both.triangles.begin(), both.triangles.begin() + 12);
  first.surfaces.assign(12, 0);
  second.triangles.assign(both.triangles.begin() + 12, both.triangles.end());
  second.surfaces.assign(second.triangles.size(), 0);
  const Solid s1 = solid_from_mesh(first, true, geometry);
  const std::size_t after_first = geometry.planes.size();
  const Solid s2 = solid_from_mesh(second, true, geometry);
  CHECK(after_first == s1.faces.size());
  CHECK(geometry.planes.size() == s1.faces.size() + s2.faces.size());
  for (const SolidFace& face : s2.faces) CHECK(face.plane.index() >= after_first);
  const PlaneSet set = geometry.plane_set({});
  CHECK(check_solid(set, s1) == "");
  CHECK(check_solid(set, s2) == "");
  CHECK(exact_six_volume(set, s1) == exact_six_volume(a));
  CHECK(exact_six_volume(set, s2) == exact_six_volume(b));
}

TEST_CASE("loop_edges walks each edge of a loop once from any corner, fan_edges the edges of a fan",
          "[plane][solid]") {
  // A triangle and a square over one corner array, each corner's line naming its
  // corner, so an edge's line shows which corner it was taken from.
  std::vector<SolidCorner> corners;
  for (const VertexIndex v : {0u, 1u, 2u, 10u, 11u, 12u, 13u}) corners.push_back({v, EdgeLine{PlaneRef::cut(v)}});
  const SolidLoop triangle{0, 3}, square{3, 4};
  using Walk = std::vector<std::array<std::uint32_t, 3>>;  // corner, from, to per edge
  const auto walk = [](std::span<const SolidCorner> of, const LoopEdges& edges) {
    Walk out;
    for (const CornerEdge& edge : edges) {
      CHECK(edge.line == of[edge.corner].line);
      out.push_back({edge.corner, edge.from, edge.to});
    }
    return out;
  };
  const Walk triangle_edges{{0, 0, 1}, {1, 1, 2}, {2, 2, 0}};
  const Walk square_edges{{3, 10, 11}, {4, 11, 12}, {5, 12, 13}, {6, 13, 10}};
  const Walk square_from_third{{5, 12, 13}, {6, 13, 10}, {3, 10, 11}, {4, 11, 12}};
  const Walk square_from_last{{6, 13, 10}, {3, 10, 11}, {4, 11, 12}, {5, 12, 13}};
  CHECK(walk(corners, loop_edges(corners, triangle)) == triangle_edges);
  CHECK(walk(corners, loop_edges(corners, square)) == square_edges);
  CHECK(walk(corners, loop_edges(corners, square, 3)) == square_edges);
  CHECK(walk(corners, loop_edges(corners, square, 5)) == square_from_third);
  CHECK(walk(corners, loop_edges(corners, square, 6)) == square_from_last);
  CHECK(walk(corners, loop_edges(corners, SolidLoop{3, 0})).empty());
  CHECK(walk(corners, loop_edges(corners, SolidLoop{3, 0}, 3)).empty());
  // Fans: the edges that do not touch the apex, from the corner after it.
  const Walk triangle_fan_from_first{{1, 1, 2}};
  const Walk square_fan_from_second{{5, 12, 13}, {6, 13, 10}};
  const Walk square_fan_from_last{{3, 10, 11}, {4, 11, 12}};
  CHECK(walk(corners, fan_edges(corners, triangle, 0)) == triangle_fan_from_first);
  CHECK(walk(corners, fan_edges(corners, square, 4)) == square_fan_from_second);
  CHECK(walk(corners, fan_edges(corners, square, 6)) == square_fan_from_last);
  CHECK(walk(corners, fan_edges(corners, SolidLoop{3, 1}, 3)).empty());

  // On real solids: from every corner of every loop, the walk is the loop's walk
  // rotated to start there, and the fan is that walk without its first and last
  // edges (the two at the apex).
  std::size_t rotations = 0;
  for (const Mesh& mesh : {staircase(3), box_with_through_hole()}) {
    InputGeometry geometry;
    geometry.points = mesh.positions;
    const Solid solid = solid_from_mesh(mesh, true, geometry);
    for (const SolidLoop& loop : solid.loops) {
      const Walk whole = walk(solid.corners, loop_edges(solid.corners, loop));
      REQUIRE(whole.size() == loop.corner_count);
      for (std::uint32_t k = 0; k < loop.corner_count; ++k) {
        Walk rotated = whole;
        std::rotate(rotated.begin(), rotated.begin() + k, rotated.end());
        CHECK(walk(solid.corners, loop_edges(solid.corners, loop, loop.first_corner + k)) == rotated);
        const Walk fan(rotated.begin() + 1, rotated.end() - 1);
        CHECK(walk(solid.corners, fan_edges(solid.corners, loop, loop.first_corner + k)) == fan);
        ++rotations;
      }
    }
  }
  CHECK(rotations >= 100);
}

TEST_CASE("solid_from_mesh refuses an open mesh and an edge used twice in one direction", "[plane][solid][errors]") {
  std::size_t refused = 0;
  for (const NamedMesh& m : generated_meshes()) {
    Random random(m.mesh.triangles.size());
    for (int k = 0; k < 3; ++k) {
      Mesh open = m.mesh;
      const std::size_t t = random.index(open.triangles.size());
      open.triangles.erase(open.triangles.begin() + static_cast<std::ptrdiff_t>(t));
      open.surfaces.erase(open.surfaces.begin() + static_cast<std::ptrdiff_t>(t));
      Mesh doubled = m.mesh;
      doubled.triangles.push_back(doubled.triangles[random.index(doubled.triangles.size())]);
      doubled.surfaces.push_back(0);
      for (const bool merge : {true, false}) {
        INFO(m.name << " triangle " << t << (merge ? " merged" : ""));
        InputGeometry geometry;
        geometry.points = m.mesh.positions;
        CHECK_THROWS_AS(solid_from_mesh(open, merge, geometry), InvalidMeshError);
        CHECK_THROWS_AS(solid_from_mesh(doubled, merge, geometry), InvalidMeshError);
        refused += 2;
      }
    }
  }
  CHECK(refused >= 100);
}

TEST_CASE("half_edge_twins pairs exactly what a map of directed edges pairs, on sound and broken meshes",
          "[plane][solid][property]") {
  // The reference: each directed edge's first half-edge, from a std::map; a
  // half-edge's twin is the first half-edge of its reverse, when both are firsts.
  const auto reference = [](const Mesh& mesh) {
    std::map<std::pair<VertexIndex, VertexIndex>, std::uint32_t> first;
    HalfEdgeTwins expected;
    expected.twin.assign(3 * mesh.triangles.size(), HalfEdgeTwins::none);
    for (std::uint32_t h = 0; h < 3 * mesh.triangles.size(); ++h) {
      const Triangle& t = mesh.triangles[h / 3];
      const auto [it, inserted] = first.try_emplace({t[h % 3], t[(h % 3 + 1) % 3]}, h);
      if (!inserted && !expected.repeated) expected.repeated = Edge{t[h % 3], t[(h % 3 + 1) % 3]};
    }
    for (std::uint32_t h = 0; h < 3 * mesh.triangles.size(); ++h) {
      const Triangle& t = mesh.triangles[h / 3];
      const VertexIndex u = t[h % 3], w = t[(h % 3 + 1) % 3];
      if (first.at({u, w}) != h) continue;
      if (const auto back = first.find({w, u}); back != first.end()) expected.twin[h] = back->second;
    }
    for (std::uint32_t h = 0; h < expected.twin.size(); ++h) {
      if (expected.twin[h] == HalfEdgeTwins::none) {
        expected.first_unmatched = h;
        break;
      }
    }
    return expected;
  };
  std::mt19937_64 random(1203);
  std::size_t broken = 0;
  for (const auto& named : test::generated_meshes()) {
    for (int trial = 0; trial < 20; ++trial) {
      Mesh mesh = named.mesh;
      // Some trials break the mesh: a triangle flipped (a directed edge twice),
      // removed (open edges) or duplicated.
      const std::size_t t = random() % mesh.triangles.size();
      switch (trial % 4) {
        case 1: std::swap(mesh.triangles[t][1], mesh.triangles[t][2]); break;
        case 2: mesh.triangles.erase(mesh.triangles.begin() + static_cast<std::ptrdiff_t>(t)); break;
        case 3: mesh.triangles.push_back(mesh.triangles[t]); break;
        default: std::shuffle(mesh.triangles.begin(), mesh.triangles.end(), random); break;
      }
      INFO(named.name << ", trial " << trial);
      const HalfEdgeTwins expected = reference(mesh);
      const HalfEdgeTwins found = half_edge_twins(mesh.triangles, mesh.positions.size());
      CHECK(found.twin == expected.twin);
      CHECK(found.repeated == expected.repeated);
      CHECK(found.first_unmatched == expected.first_unmatched);
      broken += expected.repeated || expected.first_unmatched != HalfEdgeTwins::none;
    }
  }
  CHECK(broken > 20);
}

TEST_CASE("compare_outward_normals: the exact sign of two faces' outward normals' dot product", "[plane][solid]") {
  // Cut planes with small integer normals (perpendicular and parallel pairs are
  // common) and input planes through random and lattice points, each face
  // either way round, against the planes' exact coefficients.
  std::size_t same = 0, opposite = 0, perpendicular = 0;
  Random random(17);
  InputGeometry geometry;
  std::vector<Plane> cuts;
  for (int i = 0; i < 24; ++i) {
    const auto small = [&] { return double(random.index(5)) - 2; };
    const Vec3 n{small(), small(), small()};
    cuts.push_back({n.x == 0 && n.y == 0 && n.z == 0 ? Vec3{0, 0, 1} : n, small()});
    const bool lattice = i % 2 == 0;
    const auto point = [&] {
      return lattice ? Vec3{small(), small(), small()}
                     : Vec3{random.uniform(-1, 1), random.uniform(-1, 1), random.uniform(-1, 1)};
    };
    const Vec3 p0 = point(), p1 = point(), p2 = point();
    const Vec3 normal = cross(p1 - p0, p2 - p0);
    if (normal.x == 0 && normal.y == 0 && normal.z == 0) continue;  // exact on these inputs: collinear
    const auto first = static_cast<VertexIndex>(geometry.points.size());
    geometry.points.insert(geometry.points.end(), {p0, p1, p2});
    geometry.planes.push_back({first, first + 1, first + 2});
    geometry.plane_approx.push_back(approximate_input_plane(p0, p1, p2));
  }
  const PlaneSet set = geometry.plane_set(cuts);
  std::vector<PlaneRef> planes;
  for (std::uint32_t k = 0; k < cuts.size(); ++k) planes.push_back(PlaneRef::cut(k));
  for (std::uint32_t k = 0; k < geometry.planes.size(); ++k) planes.push_back(PlaneRef::input(k));
  for (const PlaneRef a : planes) {
    for (const PlaneRef b : planes) {
      const std::array<mpq_class, 4> na = exact_plane_coefficients(set, a), nb = exact_plane_coefficients(set, b);
      const int dot_product = sgn(na[0] * nb[0] + na[1] * nb[1] + na[2] * nb[2]);
      const int dot_sign = (dot_product > 0) - (dot_product < 0);
      for (const bool reversed_a : {false, true}) {
        for (const bool reversed_b : {false, true}) {
          SolidFace fa, fb;
          fa.plane = a, fa.reversed = reversed_a;
          fb.plane = b, fb.reversed = reversed_b;
          const int expected = reversed_a != reversed_b ? -dot_sign : dot_sign;
          const Sign answer = compare_outward_normals(set, fa, fb);
          REQUIRE(static_cast<int>(answer) == expected);
          REQUIRE(compare_outward_normals(set, fb, fa) == answer);
          same += expected > 0, opposite += expected < 0, perpendicular += expected == 0;
        }
      }
    }
  }
  CHECK(same > 100);
  CHECK(opposite > 100);
  CHECK(perpendicular > 20);
}
