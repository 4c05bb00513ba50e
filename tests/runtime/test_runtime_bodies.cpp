// Breakable bodies without stepping: mass properties, the starting compounds, and
// impacts applied directly (World::apply_impact), over the catalogue of trees:
// mass and momentum conserved through every break, damage local, compounds the
// minimal covers of precomputed shapes, the seed's method agreeing.

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

#include "runtime_cases.hpp"
#include "shatter/generators/random.hpp"
#include "shatter/kernel/mass.hpp"
#include "shatter/meshtree/bonds.hpp"
#include "shatter/runtime/mass.hpp"
#include "shatter/runtime/world.hpp"

using namespace shatter;
using namespace shatter::test;
namespace rt = shatter::runtime;

namespace {

// A point on the surface of live cluster `body`: a vertex of the hull of one of
// its cover nodes, in world coordinates.
Vec3 surface_point(const rt::World& world, rt::BodyId body, Random& random) {
  const rt::BodyRecord& record = world.bodies()[body];
  const MeshTree& tree = world.shapes_of(record.object).tree();
  const NodeIndex node = record.cover[random.index(record.cover.size())];
  const Mesh& hull = tree.hull_of(node);
  return rt::apply(world.object_transform(body), hull.positions[random.index(hull.positions.size())]);
}

rt::BodyId random_cluster(const rt::World& world, Random& random) {
  std::vector<rt::BodyId> clusters;
  for (rt::BodyId b : world.live_bodies()) {
    if (world.bodies()[b].kind == rt::BodyKind::cluster && world.bodies()[b].leaf_count > 1) clusters.push_back(b);
  }
  return clusters.empty() ? rt::no_body : clusters[random.index(clusters.size())];
}

Vec3 random_vector(Random& random, double size) {
  return {random.uniform(-size, size), random.uniform(-size, size), random.uniform(-size, size)};
}

rt::RigidTransform random_placement(Random& random) {
  return {random_vector(random, 3), rt::axis_angle(random.direction(), random.uniform(0, 6.28))};
}

}  // namespace

TEST_CASE("a cluster's mass properties are its nodes' combined by the parallel-axis theorem") {
  for (const RuntimeCase& c : runtime_cases()) {
    INFO(c.name);
    const MeshTree& tree = *c.tree;
    const double density = 2500;
    std::vector<NodeIndex> leaves;
    for (LeafIndex l = 0; l < tree.leaf_count(); ++l) leaves.push_back(tree.leaf_nodes[l]);
    const rt::RigidMass whole = rt::cluster_mass(tree, std::vector<NodeIndex>{0}, density);
    const rt::RigidMass parts = rt::cluster_mass(tree, leaves, density);
    // The root's own integrals against the sum over its fragments: equal up to
    // the rounding of the fragments' meshes.
    const double size = std::cbrt(tree.nodes[0].mass.volume);
    CHECK(close(parts.mass, whole.mass, whole.mass));
    CHECK(close(parts.centroid, whole.centroid, size));
    const double largest = whole.principal_moments.z;
    for (std::size_t i = 0; i < 9; ++i) CHECK(close(parts.inertia[i], whole.inertia[i], largest, 1e-8));
    CHECK(whole.mass == Approx(density * tree.nodes[0].mass.volume).epsilon(1e-12));

    for (const rt::RigidMass* m : {&whole, &parts}) {
      // The frame is proper and diagonalises the inertia: R diag(moments) R^T.
      const rt::Matrix3 r = rt::matrix_of(m->frame.rotation);
      const double determinant =
          r[0] * (r[4] * r[8] - r[5] * r[7]) - r[1] * (r[3] * r[8] - r[5] * r[6]) + r[2] * (r[3] * r[7] - r[4] * r[6]);
      CHECK(determinant == Approx(1).epsilon(1e-12));
      CHECK(m->principal_moments.x <= m->principal_moments.y);
      CHECK(m->principal_moments.y <= m->principal_moments.z);
      CHECK(m->principal_moments.x > 0);
      const double moments[3] = {m->principal_moments.x, m->principal_moments.y, m->principal_moments.z};
      for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
          double value = 0;
          for (int k = 0; k < 3; ++k) value += r[3 * i + k] * moments[k] * r[3 * j + k];
          CHECK(close(value, m->inertia[3 * i + j], largest, 1e-10));
        }
      }
      CHECK(m->frame.translation == m->centroid);
    }
  }
}

TEST_CASE("combine_masses refuses what is not a solid") {
  MassProperties part;
  part.volume = 1;
  part.inertia = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  CHECK_THROWS_AS(rt::combine_masses({}, 1), std::invalid_argument);
  CHECK_THROWS_AS(rt::combine_masses(std::vector<MassProperties>{part}, 0), std::invalid_argument);
  part.volume = 0;
  CHECK_THROWS_AS(rt::combine_masses(std::vector<MassProperties>{part}, 1), std::invalid_argument);
  part.volume = NAN;
  CHECK_THROWS_AS(rt::combine_masses(std::vector<MassProperties>{part}, 1), std::invalid_argument);
}

TEST_CASE("a new object is one body per initial cluster, and a whole one is the root's hull alone") {
  for (const RuntimeCase& c : runtime_cases()) {
    INFO(c.name);
    rt::World world;
    const rt::ObjectId object = world.add_breakable(c.shapes, {}, {});
    const std::size_t clusters = c.shapes->initial_clusters().size();
    REQUIRE(world.live_bodies().size() == clusters);
    if (clusters == 1) CHECK(world.compound_of(0).nodes == std::vector<NodeIndex>{0});
    if (c.name.rfind("two-boxes", 0) == 0) CHECK(clusters == 2);
    check_bodies(world, object);
    // Two objects from one tree share its shapes: the second's compounds use the
    // very same hull shapes.
    const rt::ObjectId second = world.add_breakable(c.shapes, {{5, 0, 0}, {}}, {});
    check_bodies(world, second);
    CHECK(world.object_mass(second) == Approx(world.object_mass(object)).epsilon(1e-15));
  }
}

TEST_CASE("impacts conserve mass and momentum, and every body stays the minimal cover of one component") {
  std::size_t breaks = 0, created = 0;
  for (const RuntimeCase& c : runtime_cases()) {
    for (const rt::BondMode mode : {rt::BondMode::discrete, rt::BondMode::accumulating}) {
      for (std::uint64_t seed : {11u, 12u}) {
        INFO(c.name << ", " << rt::bond_mode_name(mode) << ", impact seed " << seed);
        Random random(seed);
        rt::World world;
        rt::BreakableParameters parameters;
        parameters.mode = mode;
        parameters.density = random.uniform(500, 3000);
        // The object moves and spins, so v + w x r is tested, not only rest.
        const rt::ObjectId object = world.add_breakable(c.shapes, random_placement(random), parameters,
                                                        random_vector(random, 5), random_vector(random, 3));
        const double mass = world.object_mass(object);
        CHECK(mass == Approx(parameters.density * c.tree->nodes[0].mass.volume).epsilon(1e-9));
        for (int hit = 0; hit < 6; ++hit) {
          const rt::BodyId body = random_cluster(world, random);
          if (body == rt::no_body) break;
          const rt::Momentum before = world.momentum();
          const MomentumScale scale = momentum_scale(world);
          const rt::BreakEvent event =
              world.apply_impact(body, surface_point(world, body, random), random.uniform(100, 4000));
          breaks += event.bonds_broken > 0 ? 1 : 0;
          created += event.created.size();
          const rt::Momentum after = world.momentum();
          CHECK(close(after.linear, before.linear, scale.linear));
          CHECK(close(after.angular, before.angular, scale.angular));
          CHECK(world.object_mass(object) == Approx(mass).epsilon(1e-9));
          CHECK(world.alive(body) == event.created.empty());
          for (rt::BodyId b : event.created) {
            CHECK(world.bodies()[b].parent == body);
            CHECK(world.bodies()[b].birth_step == world.step_count());
          }
          check_bodies(world, object);
        }
      }
    }
  }
  // The catalogue must exercise what it claims to.
  CHECK(breaks > 20);
  CHECK(created > 50);
}

TEST_CASE("after one impact, every broken bond is nearer the contact than every surviving one") {
  std::size_t checked = 0;
  for (const RuntimeCase& c : runtime_cases()) {
    for (const rt::BondMode mode : {rt::BondMode::discrete, rt::BondMode::accumulating}) {
      for (std::uint64_t seed : {21u, 22u, 23u}) {
        INFO(c.name << ", " << rt::bond_mode_name(mode) << ", seed " << seed);
        Random random(seed);
        rt::World world;
        rt::BreakableParameters parameters;
        parameters.mode = mode;
        parameters.min_distance = random.uniform(0.01, 0.1);
        const rt::RigidTransform placement = random_placement(random);
        const rt::ObjectId object = world.add_breakable(c.shapes, placement, parameters);
        const rt::BodyId body = 0;
        const Vec3 contact = surface_point(world, body, random);
        const Vec3 tree_contact = rt::apply(rt::inverse(placement), contact);
        const rt::BreakEvent event = world.apply_impact(body, contact, random.uniform(200, 3000));
        const std::vector<LeafIndex> leaves = world.leaves_of(body);  // its cover stays on record
        std::vector<bool> in_body(c.tree->leaf_count(), false);
        for (LeafIndex leaf : leaves) in_body[leaf] = true;
        double farthest_broken = 0, nearest_surviving = INFINITY;
        std::size_t broken = 0;
        for (std::size_t b = 0; b < c.tree->bonds.size(); ++b) {
          const Bond& bond = c.tree->bonds[b];
          if (!in_body[bond.first]) continue;
          // Inside the clamp every bond takes the same damage, so distances count from it.
          const double s = std::max(norm(bond.centroid - tree_contact), parameters.min_distance);
          if (world.bonds_alive(object)[b]) {
            nearest_surviving = std::min(nearest_surviving, s);
          } else {
            farthest_broken = std::max(farthest_broken, s);
            ++broken;
          }
        }
        CHECK(broken == event.bonds_broken);
        CHECK(farthest_broken <= nearest_surviving * (1 + 1e-12));
        if (broken > 0 && nearest_surviving < INFINITY) ++checked;
      }
    }
  }
  CHECK(checked > 30);  // impacts that broke some bonds and left others
}

TEST_CASE("the seed's method makes the same bodies as the incremental one, with colliders built on demand") {
  for (const RuntimeCase& c : runtime_cases()) {
    INFO(c.name);
    rt::World incremental, seed;
    rt::BreakableParameters parameters;
    parameters.method = rt::BreakMethod::seed_rebuild;
    const rt::ObjectId a = incremental.add_breakable(c.shapes, {}, {}, {1, 0, 0}, {0, 0, 2});
    const rt::ObjectId b = seed.add_breakable(c.shapes, {}, parameters, {1, 0, 0}, {0, 0, 2});
    Random random(31);
    for (int hit = 0; hit < 5; ++hit) {
      const rt::BodyId body = random_cluster(incremental, random);
      if (body == rt::no_body) break;
      const Vec3 point = surface_point(incremental, body, random);
      const double impulse = random.uniform(300, 3000);
      const rt::BreakEvent one = incremental.apply_impact(body, point, impulse);
      const rt::BreakEvent two = seed.apply_impact(body, point, impulse);
      REQUIRE(one.bonds_broken == two.bonds_broken);
      REQUIRE(one.created == two.created);
      for (rt::BodyId made : one.created) {
        CHECK(incremental.bodies()[made].cover == seed.bodies()[made].cover);
        CHECK(incremental.bodies()[made].mass.mass == Approx(seed.bodies()[made].mass.mass).epsilon(1e-9));
        CHECK(seed.compound_of(made).nodes == seed.bodies()[made].cover);
        CHECK_FALSE(seed.compound_of(made).uses_precomputed_shapes);
      }
    }
    CHECK(std::equal(incremental.bonds_alive(a).begin(), incremental.bonds_alive(a).end(), seed.bonds_alive(b).begin(),
                     seed.bonds_alive(b).end()));
    check_bodies(seed, b, false);
  }
}

TEST_CASE("accumulating bonds add up hits that discrete bonds shrug off") {
  const RuntimeCase c = runtime_case("box", 96, 3);
  for (const rt::BondMode mode : {rt::BondMode::discrete, rt::BondMode::accumulating}) {
    rt::World world;
    rt::BreakableParameters parameters;
    parameters.mode = mode;
    const rt::ObjectId object = world.add_breakable(c.shapes, {}, parameters);
    // Ten hits at a corner, each doing at most half a bond's hit points.
    const Vec3 corner{0.5, 0.4, 0.3};
    double nearest = INFINITY;
    LeafIndex nearest_leaf = 0;
    for (const Bond& bond : c.tree->bonds) {
      if (norm(bond.centroid - corner) < nearest) {
        nearest = norm(bond.centroid - corner);
        nearest_leaf = bond.first;
      }
    }
    const double s = std::max(nearest, parameters.min_distance);
    const double impulse = 0.5 * parameters.hit_points * s * s * s / parameters.frailty;
    std::size_t broken = 0;
    for (int i = 0; i < 10; ++i) {
      broken += world.apply_impact(world.body_of_leaf(object, nearest_leaf), corner, impulse).bonds_broken;
    }
    if (mode == rt::BondMode::discrete) {
      CHECK(broken == 0);
      const std::span<const double> hit_points = world.bond_hit_points(object);
      CHECK(std::all_of(hit_points.begin(), hit_points.end(), [&](double h) { return h == parameters.hit_points; }));
    } else {
      CHECK(broken > 0);
      const std::span<const double> hit_points = world.bond_hit_points(object);
      CHECK(std::any_of(hit_points.begin(), hit_points.end(),
                        [&](double h) { return h > 0 && h < parameters.hit_points; }));
    }
  }
}

TEST_CASE("bad arguments are refused, not simulated") {
  const RuntimeCase c = runtime_case("box", 24, 1);
  rt::World world;
  rt::BreakableParameters bad;
  bad.frailty = -1;
  CHECK_THROWS_AS(world.add_breakable(c.shapes, {}, bad), std::invalid_argument);
  bad = {};
  bad.min_distance = 0;
  CHECK_THROWS_AS(world.add_breakable(c.shapes, {}, bad), std::invalid_argument);
  CHECK_THROWS_AS(world.add_breakable(nullptr, {}, {}), std::invalid_argument);
  CHECK(world.object_count() == 0);
  CHECK_THROWS_AS(world.add_sphere(0, 1, {}, {}), std::invalid_argument);
  const rt::ObjectId object = world.add_breakable(c.shapes, {}, {});
  CHECK_THROWS_AS(world.apply_impact(0, {}, -1), std::invalid_argument);
  CHECK_THROWS_AS(world.apply_impact(7, {}, 1), std::invalid_argument);
  const rt::BodyId sphere = world.add_sphere(0.1, 1, {3, 3, 3}, {});
  CHECK_THROWS_AS(world.apply_impact(sphere, {}, 1), std::invalid_argument);
  CHECK_THROWS_AS(world.compound_of(sphere), std::invalid_argument);
  CHECK_THROWS_AS(rt::World(rt::WorldOptions{.time_step = 0}), std::invalid_argument);
  CHECK_THROWS_AS(rt::BreakableShapes::create(c.tree, {.collision_margin = 0}), std::invalid_argument);
  check_bodies(world, object);
}
