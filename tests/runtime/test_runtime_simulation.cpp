// Breakable objects stepped by Bullet: resting takes no damage, breaks conserve
// mass and momentum at the moment they happen, every leaf is in one body at every
// step, runs repeat bit for bit, and the recording is a well-formed animated glTF.

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "runtime_cases.hpp"
#include "shatter/runtime/recording.hpp"
#include "shatter/runtime/scenes.hpp"
#include "shatter/runtime/world.hpp"

#include "shatter/formats/tinygltf.hpp"

using namespace shatter;
using namespace shatter::test;
namespace rt = shatter::runtime;

namespace {

// What a run did, to compare two runs and to require that a test saw breaks.
struct RunLog {
  std::vector<std::string> events;
  std::size_t breaks = 0, created = 0;
};

// Steps `world` for `steps` steps, checking at every step (between Bullet's step
// and the damage pass, and after it) what must hold at any moment.
RunLog run_checked(rt::World& world, const std::vector<rt::ObjectId>& objects, int steps, rt::Recording* recording,
                   bool precomputed = true) {
  RunLog log;
  std::vector<double> masses;
  for (rt::ObjectId object : objects) masses.push_back(world.object_mass(object));
  for (int i = 0; i < steps; ++i) {
    world.advance();
    const rt::Momentum before = world.momentum();
    const MomentumScale scale = momentum_scale(world);
    const rt::StepReport report = world.resolve_damage();
    if (recording) recording->capture(world);
    INFO("step " << report.step);
    if (!report.breaks.empty()) {
      // A break happens between steps: the bodies' momentum just before and just
      // after it are the same.
      const rt::Momentum after = world.momentum();
      CHECK(close(after.linear, before.linear, scale.linear));
      CHECK(close(after.angular, before.angular, scale.angular));
    }
    for (rt::ObjectId object : objects) check_bodies(world, object, precomputed);
    for (std::size_t k = 0; k < objects.size(); ++k) {
      CHECK(world.object_mass(objects[k]) == Approx(masses[k]).epsilon(1e-9));
    }
    for (const rt::BreakEvent& event : report.breaks) {
      ++log.breaks;
      log.created += event.created.size();
      std::string line = std::to_string(event.step) + " " + std::to_string(event.body) + " " +
                         std::to_string(event.bonds_broken) + ":";
      for (rt::BodyId b : event.created) (line += ' ') += std::to_string(b);  // not " " + s: GCC 12's false -Wrestrict
      log.events.push_back(line);
    }
  }
  return log;
}

// A frail material, so that every case breaks into several bodies.
rt::SceneOptions scene(rt::SceneKind kind) {
  rt::SceneOptions options;
  options.kind = kind;
  options.frailty = 2e-4;
  options.wall_rows = 2;
  options.wall_columns = 2;
  return options;
}

}  // namespace

TEST_CASE("an object resting on the floor takes no damage") {
  std::size_t cases = 0;
  for (const RuntimeCase& c : runtime_cases()) {
    for (const rt::ImpulseModel model : {rt::ImpulseModel::applied, rt::ImpulseModel::seed_momentum}) {
      for (const bool sleeping : {true, false}) {
        INFO(c.name << ", impulse " << rt::impulse_model_name(model) << (sleeping ? ", sleeping" : ", awake"));
        rt::World world(rt::WorldOptions{.sleeping = sleeping});
        rt::BreakableParameters parameters;
        parameters.impulse = model;
        parameters.mode = rt::BondMode::accumulating;  // so any damage at all would show
        const rt::ObjectId object = world.add_breakable(c.shapes, resting_placement(*c.shapes), parameters);
        const std::size_t bodies = world.live_bodies().size();
        std::size_t impacts = 0;
        for (int i = 0; i < 240; ++i) impacts += world.step().impacts.size();
        CHECK(impacts == 0);
        const std::span<const double> hit_points = world.bond_hit_points(object);
        CHECK(std::all_of(hit_points.begin(), hit_points.end(), [&](double h) { return h == parameters.hit_points; }));
        CHECK(world.live_bodies().size() == bodies);
        CHECK(world.bodies().size() == bodies);
        ++cases;
      }
    }
  }
  CHECK(cases == 4 * runtime_cases().size());
}

TEST_CASE("dropped and shot objects break with mass and momentum conserved and every leaf in one body") {
  std::size_t breaks = 0, created = 0;
  for (const char* mesh : {"box", "ellipsoid", "torus", "hollow-egg", "knot1"}) {
    for (const rt::SceneKind kind : {rt::SceneKind::drop, rt::SceneKind::shoot}) {
      for (const rt::BreakMethod method : {rt::BreakMethod::incremental, rt::BreakMethod::seed_rebuild}) {
        const RuntimeCase c = runtime_case(mesh, 24, 7);
        INFO(c.name << ", " << rt::scene_name(kind) << ", " << rt::break_method_name(method));
        rt::World world;
        rt::SceneOptions options = scene(kind);
        options.parameters.method = method;
        const rt::Scene placed = rt::set_up_scene(world, c.shapes, options);
        const RunLog log = run_checked(world, placed.objects, 150, nullptr, method == rt::BreakMethod::incremental);
        breaks += log.breaks;
        created += log.created;
      }
    }
  }
  CHECK(breaks > 8);
  CHECK(created > 30);
}

TEST_CASE("a wall of bricks shot at breaks, and two runs give the same events and recording bytes") {
  for (const char* mesh : {"box", "torus"}) {
    const RuntimeCase c = runtime_case(mesh, 24, 1);
    INFO(c.name);
    std::string bytes[2];
    RunLog logs[2];
    for (int run = 0; run < 2; ++run) {
      rt::World world;
      const rt::Scene placed = rt::set_up_scene(world, c.shapes, scene(rt::SceneKind::wall));
      CHECK(placed.objects.size() == 4);
      rt::Recording recording(2);
      recording.capture(world);
      logs[run] = run_checked(world, placed.objects, 120, &recording);
      bytes[run] = recording.encode_glb(world, 3);
    }
    CHECK(logs[0].breaks > 0);
    CHECK(logs[0].events == logs[1].events);
    CHECK(bytes[0] == bytes[1]);
  }
}

TEST_CASE("the recording has a node per body ever made, moved and shown from its birth to its death") {
  const RuntimeCase c = runtime_case("box", 96, 3);
  rt::World world;
  const rt::Scene placed = rt::set_up_scene(world, c.shapes, scene(rt::SceneKind::shoot));
  const std::uint32_t every = 3;
  rt::Recording recording(every);
  recording.capture(world);
  for (int i = 0; i < 60; ++i) {
    world.step();
    recording.capture(world);
  }
  REQUIRE(world.bodies().size() > 3);  // the shot broke the box
  const std::string bytes = recording.encode_glb(world, 4);

  tinygltf::Model model;
  tinygltf::TinyGLTF loader;
  std::string error, warning;
  REQUIRE(loader.LoadBinaryFromMemory(&model, &error, &warning, reinterpret_cast<const unsigned char*>(bytes.data()),
                                      static_cast<unsigned>(bytes.size())));
  REQUIRE(model.scenes.size() == 1);
  REQUIRE(model.animations.size() == 1);
  const tinygltf::Animation& animation = model.animations[0];
  const double dt = world.options().time_step;

  // The scene's roots: the floor, then one node per body in order.
  const std::vector<int>& roots = model.scenes[0].nodes;
  REQUIRE(roots.size() == 1 + world.bodies().size());
  CHECK(model.nodes[static_cast<std::size_t>(roots[0])].name == "floor");
  const auto read_floats = [&](int accessor_index) {
    const tinygltf::Accessor& accessor = model.accessors[static_cast<std::size_t>(accessor_index)];
    const tinygltf::BufferView& view = model.bufferViews[static_cast<std::size_t>(accessor.bufferView)];
    const std::size_t components = accessor.type == TINYGLTF_TYPE_SCALAR ? 1
                                   : accessor.type == TINYGLTF_TYPE_VEC3 ? 3
                                                                         : 4;
    std::vector<float> values(accessor.count * components);
    std::memcpy(values.data(), model.buffers[0].data.data() + view.byteOffset + accessor.byteOffset,
                values.size() * sizeof(float));
    return values;
  };
  for (rt::BodyId b = 0; b < world.bodies().size(); ++b) {
    INFO("body " << b);
    const rt::BodyRecord& record = world.bodies()[b];
    const int node = roots[1 + b];
    const tinygltf::Node& gltf_node = model.nodes[static_cast<std::size_t>(node)];
    if (record.kind == rt::BodyKind::cluster) {
      std::vector<NodeIndex> parts;
      for (int child : gltf_node.children) {
        const std::string& name = model.nodes[static_cast<std::size_t>(child)].name;
        parts.push_back(static_cast<NodeIndex>(std::stoul(name.substr(name.rfind(' ') + 1))));
        CHECK(model.nodes[static_cast<std::size_t>(child)].mesh >= 0);
      }
      CHECK(parts == record.cover);
    }
    std::set<std::string> paths;
    for (const tinygltf::AnimationChannel& channel : animation.channels) {
      if (channel.target_node != node) continue;
      paths.insert(channel.target_path);
      const tinygltf::AnimationSampler& sampler = animation.samplers[static_cast<std::size_t>(channel.sampler)];
      const std::vector<float> times = read_floats(sampler.input);
      REQUIRE(!times.empty());
      CHECK(std::is_sorted(times.begin(), times.end()));
      CHECK(std::adjacent_find(times.begin(), times.end()) == times.end());
      if (channel.target_path == "scale") {
        CHECK(sampler.interpolation == "STEP");
        const std::vector<float> scale = read_floats(sampler.output);
        // Hidden before birth, shown from it, hidden again from its death.
        std::size_t k = 0;
        if (record.birth_step > 0) {
          CHECK(times[0] == 0.0f);
          CHECK(scale[0] == 0.0f);
          k = 1;
        }
        CHECK(times[k] == static_cast<float>(static_cast<double>(record.birth_step) * dt));
        CHECK(scale[3 * k] == 1.0f);
        if (record.death_step != UINT64_MAX) {
          CHECK(times.back() == static_cast<float>(static_cast<double>(record.death_step) * dt));
          CHECK(scale.back() == 0.0f);
        }
      } else {
        CHECK(sampler.interpolation == "LINEAR");
        // A key for every kept state the body lived in, and its death.
        const std::uint64_t last = record.death_step == UINT64_MAX ? world.step_count() : record.death_step - 1;
        std::size_t expected = 0;
        for (std::uint64_t step = record.birth_step; step <= last; ++step) {
          if (step % every == 0 || step == record.birth_step) ++expected;
        }
        if (record.death_step != UINT64_MAX) ++expected;
        CHECK(times.size() == expected);
      }
    }
    CHECK(paths == std::set<std::string>{"rotation", "scale", "translation"});
  }
  CHECK(placed.projectile != rt::no_body);
}

namespace {

// The tree of `mesh` with every position times `scale` (a power of two, so the
// scaled coordinates are exact), cut into 8 fragments.
std::shared_ptr<const MeshTree> scaled_tree(const std::string& mesh, double scale) {
  Mesh scaled = runtime_mesh(mesh);
  for (Vec3& p : scaled.positions) p = scale * p;
  TreeRecipe recipe;
  recipe.fragments = 8;
  recipe.seed = 3;
  BuildRunOptions run;
  run.threads = 1;
  return std::make_shared<const MeshTree>(build_mesh_tree(scaled, recipe, run));
}

// Shoot options with `change` made (rather than designated initializers, which
// -Wextra flags for every member left out).
template <class Change>
rt::SceneOptions shoot_with(Change change) {
  rt::SceneOptions options;
  options.kind = rt::SceneKind::shoot;
  change(options);
  return options;
}

}  // namespace

TEST_CASE("unset scene options scale with the object: the projectile with its mass, lengths with its size, speeds with its root") {
  for (const char* mesh : {"box", "torus", "knot1"}) {
    const auto unit = scaled_tree(mesh, 1);
    for (const rt::SceneKind kind : {rt::SceneKind::drop, rt::SceneKind::shoot, rt::SceneKind::wall}) {
      rt::SceneOptions options;
      options.kind = kind;
      const rt::SceneSizes base = rt::scene_sizes(*unit, options);
      INFO(mesh << ", " << rt::scene_name(kind));
      REQUIRE(base.object_size > 0);
      REQUIRE(base.object_mass > 0);
      // The defaults themselves, as documented.
      CHECK(base.object_mass == Approx(options.parameters.density * unit->nodes[0].mass.volume).epsilon(1e-12));
      CHECK(base.projectile_mass == Approx(rt::scene_defaults::mass_in_object_masses * base.object_mass));
      CHECK(base.projectile_radius == Approx(rt::scene_defaults::radius_in_sizes * base.object_size));
      CHECK(base.height == Approx(rt::scene_defaults::height_in_sizes * base.object_size));
      CHECK(base.projectile_speed == Approx(rt::scene_defaults::speed_in_sqrt_g_size *
                                            std::sqrt(rt::scene_defaults::gravity * base.object_size)));
      // An impulse of M sqrt(g L) breaks bonds within break_radius_in_sizes object sizes.
      const double reference_impulse = base.object_mass * std::sqrt(rt::scene_defaults::gravity * base.object_size);
      CHECK(std::cbrt(base.frailty * reference_impulse / options.parameters.hit_points) ==
            Approx(rt::scene_defaults::break_radius_in_sizes * base.object_size));
      for (const double s : {0.25, 4.0}) {
        INFO("scaled by " << s);
        const rt::SceneSizes scaled = rt::scene_sizes(*scaled_tree(mesh, s), options);
        CHECK(scaled.object_size == Approx(s * base.object_size).epsilon(1e-12));
        CHECK(scaled.object_mass == Approx(s * s * s * base.object_mass).epsilon(1e-12));
        CHECK(scaled.projectile_mass == Approx(s * s * s * base.projectile_mass).epsilon(1e-12));
        CHECK(scaled.projectile_radius == Approx(s * base.projectile_radius).epsilon(1e-12));
        CHECK(scaled.height == Approx(s * base.height).epsilon(1e-12));
        CHECK(scaled.projectile_speed == Approx(std::sqrt(s) * base.projectile_speed).epsilon(1e-12));
        // L^3 / (L^3 sqrt(L)): a larger object of the same shape is less frail, in proportion to its blow.
        CHECK(scaled.frailty == Approx(base.frailty / std::sqrt(s)).epsilon(1e-12));
      }
      // A denser object is shot by a heavier sphere, no bigger and no faster.
      rt::SceneOptions dense = options;
      dense.parameters.density = 3 * options.parameters.density;
      const rt::SceneSizes heavier = rt::scene_sizes(*unit, dense);
      CHECK(heavier.projectile_mass == Approx(3 * base.projectile_mass).epsilon(1e-12));
      CHECK(heavier.projectile_radius == base.projectile_radius);
      CHECK(heavier.projectile_speed == base.projectile_speed);
      CHECK(heavier.height == base.height);
      CHECK(heavier.frailty == Approx(base.frailty / 3).epsilon(1e-12));
      // Tougher bonds need a frailer material for the same damage radius.
      rt::SceneOptions tough = options;
      tough.parameters.hit_points = 5;
      CHECK(rt::scene_sizes(*unit, tough).frailty == Approx(5 * base.frailty).epsilon(1e-12));
    }
  }
}

TEST_CASE("set scene options are used as given, whatever the object, and placed as resolved") {
  for (const double s : {0.25, 1.0, 4.0}) {
    const auto tree = scaled_tree("box", s);
    const auto shapes = rt::BreakableShapes::create(tree);
    INFO("box scaled by " << s);
    rt::SceneOptions options;
    options.kind = rt::SceneKind::shoot;
    options.projectile_mass = 7;
    options.projectile_speed = 0;  // set to 0 is a sphere at rest, not the default
    options.projectile_radius = 0.05;
    options.height = 0;
    options.frailty = 3e-4;
    const rt::SceneSizes sizes = rt::scene_sizes(*tree, options);
    CHECK(sizes.frailty == 3e-4);
    CHECK(sizes.projectile_mass == 7);
    CHECK(sizes.projectile_speed == 0);
    CHECK(sizes.projectile_radius == 0.05);
    CHECK(sizes.height == 0);

    for (const bool explicit_options : {true, false}) {
      INFO((explicit_options ? "set" : "unset"));
      rt::SceneOptions placed_options = options;
      if (!explicit_options) placed_options = shoot_with([](rt::SceneOptions&) {});
      rt::World world;
      const rt::Scene scene = rt::set_up_scene(world, shapes, placed_options);
      const rt::SceneSizes expected = rt::scene_sizes(*tree, placed_options);
      REQUIRE(scene.projectile != rt::no_body);
      const rt::BodyRecord& sphere = world.bodies()[scene.projectile];
      CHECK(sphere.mass.mass == Approx(expected.projectile_mass).epsilon(1e-12));
      CHECK(sphere.radius == expected.projectile_radius);
      CHECK(world.state(scene.projectile).linear_velocity.x == Approx(expected.projectile_speed).epsilon(1e-12));
      CHECK(scene.sizes.projectile_mass == expected.projectile_mass);
      // The object is made with the resolved frailty, whatever parameters.frailty says.
      CHECK(world.parameters_of(scene.objects.at(0)).frailty == expected.frailty);
    }
    // A set drop height of 0 stays 0 (the object starts on the floor), not the default.
    rt::World world;
    options.kind = rt::SceneKind::drop;
    const rt::Scene dropped = rt::set_up_scene(world, shapes, options);
    CHECK(dropped.sizes.height == 0);
  }
  // Radius 0 keeps its old meaning, the default; out-of-range values name the option.
  const auto tree = scaled_tree("box", 1);
  const rt::SceneOptions zero_radius = shoot_with([](rt::SceneOptions& o) { o.projectile_radius = 0.0; });
  CHECK(rt::scene_sizes(*tree, zero_radius).projectile_radius ==
        Approx(rt::scene_defaults::radius_in_sizes * rt::scene_sizes(*tree, {}).object_size));
  CHECK_THROWS_WITH(rt::scene_sizes(*tree, shoot_with([](rt::SceneOptions& o) { o.projectile_mass = -1.0; })),
                    Catch::Contains("projectile mass"));
  CHECK_THROWS_WITH(rt::scene_sizes(*tree, shoot_with([](rt::SceneOptions& o) { o.projectile_speed = std::nan(""); })),
                    Catch::Contains("projectile speed"));
  CHECK_THROWS_WITH(rt::scene_sizes(*tree, shoot_with([](rt::SceneOptions& o) { o.height = -0.5; })),
                    Catch::Contains("drop height"));
  CHECK_THROWS_WITH(rt::scene_sizes(*tree, shoot_with([](rt::SceneOptions& o) { o.frailty = 0.0; })),
                    Catch::Contains("frailty"));
  // Magnitudes whose products Bullet's solver would overflow are refused, naming
  // them (`simulate --density 1e300` printed a kinetic energy of NaN at every
  // step, found by a sweep, 2026-12-07); within the limits a shot runs finite.
  CHECK_THROWS_WITH(rt::scene_sizes(*tree, shoot_with([](rt::SceneOptions& o) { o.parameters.density = 1e300; })),
                    Catch::Contains("object mass"));
  CHECK_THROWS_WITH(rt::scene_sizes(*tree, shoot_with([](rt::SceneOptions& o) { o.projectile_mass = 1e200; })),
                    Catch::Contains("projectile mass"));
  CHECK_THROWS_WITH(rt::scene_sizes(*tree, shoot_with([](rt::SceneOptions& o) { o.projectile_speed = 1e200; })),
                    Catch::Contains("projectile speed"));
  CHECK_THROWS_WITH(rt::scene_sizes(*tree, shoot_with([](rt::SceneOptions& o) { o.projectile_radius = 1e300; })),
                    Catch::Contains("projectile radius"));
  CHECK_THROWS_WITH(rt::scene_sizes(*tree, shoot_with([](rt::SceneOptions& o) {
                      o.projectile_mass = 1e40;
                      o.projectile_speed = 1e45;
                    })),
                    Catch::Contains("kinetic energy"));
  const auto shapes = rt::BreakableShapes::create(tree, {});
  rt::World world;
  rt::set_up_scene(world, shapes, shoot_with([](rt::SceneOptions& o) {
                     o.parameters.density = 1e50;
                     o.projectile_speed = 1e30;
                   }));
  for (int step = 0; step < 60; ++step) {
    world.step();
    REQUIRE(std::isfinite(world.kinetic_energy()));
  }
}
