#pragma once
// The runtime tests' catalogue: mesh trees built from generated solids (a box, an
// ellipsoid, a torus whose fragments' hulls overlap, the seed's hollow egg with a
// cavity, two boxes whose bond graph starts in two clusters) and from the knotted
// tube the repository ships (tests/data/corpus/knot1.off), at a few fragment counts and
// seeds, each built once per test process, and the property checks the tests
// share.

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "shatter/generators/corpus.hpp"
#include "shatter/generators/solids.hpp"
#include "shatter/kernel/io.hpp"
#include "shatter/kernel/union_find.hpp"
#include "shatter/meshtree/build.hpp"
#include "shatter/meshtree/cover.hpp"
#include "shatter/runtime/world.hpp"
#include "support/checks.hpp"

namespace shatter::test {

struct RuntimeCase {
  std::string name;
  std::shared_ptr<const MeshTree> tree;
  std::shared_ptr<const runtime::BreakableShapes> shapes;
};

inline Mesh runtime_mesh(const std::string& mesh) {
  if (mesh == "box") return box({-0.5, -0.4, -0.3}, {0.5, 0.4, 0.3});
  if (mesh == "ellipsoid") return ellipsoid({0, 0, 0}, {0.6, 0.4, 0.3}, 20, 10);
  if (mesh == "torus") return torus(0.6, 0.2, 16, 10);
  if (mesh == "hollow-egg") return hollow_egg();
  if (mesh == "two-boxes") return two_boxes();
  if (mesh == "knot1") return read_mesh(mesh_dir() / "knot1.off");
  FAIL("no runtime mesh " << mesh);
  return {};
}

/// The tree of `mesh` cut into `fragments` with `seed` (thesis strategy, plane
/// kernel, one thread), built once per process.
inline RuntimeCase runtime_case(const std::string& mesh, std::uint32_t fragments, std::uint64_t seed) {
  static std::map<std::string, RuntimeCase> built;
  const std::string name = mesh + "/" + std::to_string(fragments) + "/seed " + std::to_string(seed);
  auto found = built.find(name);
  if (found != built.end()) return found->second;
  TreeRecipe recipe;
  recipe.fragments = fragments;
  recipe.seed = seed;
  auto tree = std::make_shared<const MeshTree>(build_mesh_tree(runtime_mesh(mesh), recipe, {.threads = 1}));
  CHECK(test::tree_problem(*tree, true) == "");
  RuntimeCase c{name, tree, runtime::BreakableShapes::create(tree)};
  built.emplace(name, c);
  return c;
}

/// Every mesh at 24 fragments with two seeds, plus box and torus at 96: the
/// catalogue of the property tests (never empty).
inline std::vector<RuntimeCase> runtime_cases() {
  std::vector<RuntimeCase> cases;
  for (const char* mesh : {"box", "ellipsoid", "torus", "hollow-egg", "two-boxes", "knot1"}) {
    for (std::uint64_t seed : {1u, 7u}) cases.push_back(runtime_case(mesh, 24, seed));
  }
  cases.push_back(runtime_case("box", 96, 3));
  cases.push_back(runtime_case("torus", 96, 5));
  return cases;
}

/// Relative closeness with an absolute floor: |a - b| <= tolerance * scale + 1e-12.
inline bool close(double a, double b, double scale, double tolerance = 1e-9) {
  return std::abs(a - b) <= tolerance * scale + 1e-12;
}
inline bool close(Vec3 a, Vec3 b, double scale, double tolerance = 1e-9) {
  return norm(a - b) <= tolerance * scale + 1e-12;
}

/// Scales for comparing momenta: sum of m |v| and of |x m v| + |I w| over live bodies.
struct MomentumScale {
  double linear = 0, angular = 0;
};
inline MomentumScale momentum_scale(const runtime::World& world) {
  MomentumScale scale;
  for (runtime::BodyId b : world.live_bodies()) {
    const runtime::BodyState s = world.state(b);
    const runtime::RigidMass& mass = world.bodies()[b].mass;
    scale.linear += mass.mass * norm(s.linear_velocity);
    const double largest_moment =
        std::max({mass.principal_moments.x, mass.principal_moments.y, mass.principal_moments.z});
    scale.angular +=
        norm(s.pose.translation) * mass.mass * norm(s.linear_velocity) + largest_moment * norm(s.angular_velocity);
  }
  return scale;
}

/// Checks every invariant of the bodies of `object` that holds at any moment:
/// each leaf in exactly one live body, which body_of_leaf names; each live
/// cluster's compound is the minimal cover of its leaves, made of the
/// precomputed hull shapes (when `precomputed`); its leaves are exactly one
/// connected component of the surviving bonds; every surviving bond joins
/// leaves of one body.
inline void check_bodies(const runtime::World& world, runtime::ObjectId object, bool precomputed = true) {
  const MeshTree& tree = world.shapes_of(object).tree();
  std::vector<runtime::BodyId> owner(tree.leaf_count(), runtime::no_body);
  for (runtime::BodyId b : world.live_bodies()) {
    const runtime::BodyRecord& record = world.bodies()[b];
    if (record.kind != runtime::BodyKind::cluster || record.object != object) continue;
    const std::vector<LeafIndex> leaves = world.leaves_of(b);
    REQUIRE(leaves.size() == record.leaf_count);
    for (LeafIndex leaf : leaves) {
      INFO("leaf " << leaf << " in body " << b << " and body " << owner[leaf]);
      REQUIRE(owner[leaf] == runtime::no_body);
      owner[leaf] = b;
    }
    const runtime::CompoundView compound = world.compound_of(b);
    CHECK(compound.nodes == minimal_cover(tree, leaves));
    CHECK(compound.nodes == record.cover);
    if (precomputed) CHECK(compound.uses_precomputed_shapes);
  }
  for (LeafIndex leaf = 0; leaf < tree.leaf_count(); ++leaf) {
    INFO("leaf " << leaf);
    REQUIRE(owner[leaf] != runtime::no_body);
    CHECK(world.body_of_leaf(object, leaf) == owner[leaf]);
  }
  // Bodies are the connected components of the surviving bonds.
  const std::span<const std::uint8_t> alive = world.bonds_alive(object);
  UnionFind components(tree.leaf_count());
  for (std::size_t b = 0; b < tree.bonds.size(); ++b) {
    if (!alive[b]) continue;
    CHECK(owner[tree.bonds[b].first] == owner[tree.bonds[b].second]);
    components.unite(tree.bonds[b].first, tree.bonds[b].second);
  }
  std::map<runtime::BodyId, std::uint32_t> component_of_body;
  for (LeafIndex leaf = 0; leaf < tree.leaf_count(); ++leaf) {
    const auto [it, inserted] = component_of_body.emplace(owner[leaf], components.find(leaf));
    CHECK(it->second == components.find(leaf));  // one body, one component
  }
  std::map<std::uint32_t, runtime::BodyId> body_of_component;
  for (const auto& [body, comp] : component_of_body) {
    const auto [it, inserted] = body_of_component.emplace(comp, body);
    CHECK(inserted);  // one component, one body
  }
}

/// The placement that lays `shapes`' object on the floor at rest: its axis of
/// largest moment of inertia vertical (its broadest side down), unless its
/// moments are all equal (a cube) or it starts as several clusters (whose
/// common principal axes need not suit any of them): then the first of the
/// tree's own axes y, z, x that puts every cluster's lowest point at one height
/// is vertical. The lowest point
/// is one collision margin above y = 0, where Bullet's inflated hull touches.
inline runtime::RigidTransform resting_placement(const runtime::BreakableShapes& shapes) {
  const MeshTree& tree = shapes.tree();
  const runtime::RigidMass mass = runtime::cluster_mass(tree, std::vector<NodeIndex>{0}, 1.0);
  const Vec3 m = mass.principal_moments;
  // Lowest y of each initial cluster, turned by `rotation`.
  const auto lowest_points = [&](const runtime::Quaternion& rotation) {
    std::vector<double> lowest;
    for (const runtime::Cluster& cluster : shapes.initial_clusters()) {
      double y = INFINITY;
      for (NodeIndex node : minimal_cover(tree, cluster.leaves)) {
        for (const Vec3& p : tree.hull_of(node).positions) y = std::min(y, runtime::rotate(rotation, p).y);
      }
      lowest.push_back(y);
    }
    return lowest;
  };
  std::vector<runtime::Quaternion> candidates;
  if (m.z - m.x > 1e-6 * m.z && shapes.initial_clusters().size() == 1) {
    // body axes x, y, z -> world x, -z, y: the largest-moment axis up.
    const runtime::Quaternion lay = runtime::quaternion_of({1, 0, 0, 0, 0, 1, 0, -1, 0});
    candidates.push_back(runtime::multiply(lay, runtime::conjugate(mass.frame.rotation)));
  }
  candidates.push_back({});                                         // y up
  candidates.push_back(runtime::axis_angle({1, 0, 0}, -M_PI / 2));  // z up
  candidates.push_back(runtime::axis_angle({0, 0, 1}, M_PI / 2));   // x up
  const double size = std::cbrt(tree.nodes[0].mass.volume);
  for (const runtime::Quaternion& rotation : candidates) {
    const std::vector<double> lowest = lowest_points(rotation);
    const auto [low, high] = std::minmax_element(lowest.begin(), lowest.end());
    if (*high - *low > 1e-9 * size) continue;
    const Vec3 centre = runtime::rotate(rotation, mass.centroid);
    return {{-centre.x, shapes.options().collision_margin - *low, -centre.z}, rotation};
  }
  FAIL("no orientation puts every cluster on the floor");
  return {};
}

}  // namespace shatter::test
