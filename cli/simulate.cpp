// The `simulate` subcommand: a thin layer over runtime/ (World, scenes, Recording).

#include "simulate.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "shatter/kernel/error.hpp"
#include "shatter/kernel/io.hpp"
#include "shatter/formats/file.hpp"
#include "shatter/runtime/recording.hpp"
#include "errors.hpp"
#include "huge_page_objects.hpp"
#include "output_transaction.hpp"
#include "json_text.hpp"

namespace shatter::cli {

namespace {

using json = nlohmann::ordered_json;
namespace fs = std::filesystem;
namespace rt = shatter::runtime;

// Numbers in the text summary: six significant digits, the same on every run.
std::string number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", value);
  return text;
}

template <class Enum>
Enum enum_or_usage(std::optional<Enum> value, const char* option, const std::string& text) {
  if (!value) throw UsageError(std::string(option) + ": unknown value '" + text + "'");
  return *value;
}

bool names_glb(const std::string& path) {
  std::string extension = fs::path(path).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension == ".glb";
}

json parameters_json(const rt::BreakableParameters& p, double margin) {
  return json{{"density_kg_m3", p.density},          {"frailty_m3_per_N_s", p.frailty},
              {"impact_speed_m_s", p.impact_speed},  {"hit_points", p.hit_points},
              {"bonds", rt::bond_mode_name(p.mode)}, {"impulse", rt::impulse_model_name(p.impulse)},
              {"min_distance_m", p.min_distance},    {"friction", p.friction},
              {"restitution", p.restitution},        {"method", rt::break_method_name(p.method)},
              {"collision_margin_m", margin}};
}

// The scene as run: the options resolved for the object (a relative default as
// the number it came to), and the object's size and mass they were scaled by.
json scene_json(const rt::SceneOptions& o, const rt::SceneSizes& sizes) {
  json out{{"scene", rt::scene_name(o.kind)},
           {"object_size_m", sizes.object_size},
           {"object_mass_kg", sizes.object_mass},
           {"frailty_m3_per_N_s", sizes.frailty}};
  if (o.kind == rt::SceneKind::drop) {
    out["height_m"] = sizes.height;
    out["tilt_degrees"] = o.tilt_degrees;
    return out;
  }
  out["projectile_mass_kg"] = sizes.projectile_mass;
  out["projectile_speed_m_s"] = sizes.projectile_speed;
  out["projectile_radius_m"] = sizes.projectile_radius;
  if (o.kind == rt::SceneKind::wall) {
    out["wall_rows"] = o.wall_rows;
    out["wall_columns"] = o.wall_columns;
  }
  return out;
}

// Where each object's centre of mass starts, to tell how far its pieces went.
std::vector<Vec3> object_centres(const rt::World& world, std::size_t objects) {
  std::vector<Vec3> weighted(objects);
  std::vector<double> mass(objects, 0);
  for (rt::BodyId body : world.live_bodies()) {
    const rt::BodyRecord& record = world.bodies()[body];
    if (record.kind != rt::BodyKind::cluster) continue;
    weighted[record.object] = weighted[record.object] + record.mass.mass * world.state(body).pose.translation;
    mass[record.object] += record.mass.mass;
  }
  for (std::size_t k = 0; k < objects; ++k) {
    if (mass[k] > 0) weighted[k] = (1 / mass[k]) * weighted[k];
  }
  return weighted;
}

// The largest distance of a live cluster's centre of mass from where its object's
// centre of mass started, m: how far the pieces spread.
double farthest_piece(const rt::World& world, const std::vector<Vec3>& starts) {
  double farthest = 0;
  for (rt::BodyId body : world.live_bodies()) {
    const rt::BodyRecord& record = world.bodies()[body];
    if (record.kind != rt::BodyKind::cluster) continue;
    farthest = std::max(farthest, norm(world.state(body).pose.translation - starts[record.object]));
  }
  return farthest;
}

// What one step did, for the summary.
struct StepSummary {
  std::uint64_t step = 0;
  double time = 0;
  std::size_t live_bodies = 0, clusters = 0, awake = 0, impacts = 0, bonds_broken = 0, bodies_created = 0;
  double largest_impulse = 0;  ///< p of the strongest impact, N s
  double kinetic_energy = 0;
};

StepSummary summarise(const rt::World& world, const rt::StepReport& report) {
  StepSummary s;
  s.step = report.step;
  s.time = report.time;
  for (rt::BodyId body : world.live_bodies()) {
    ++s.live_bodies;
    if (world.bodies()[body].kind == rt::BodyKind::cluster) ++s.clusters;
    if (world.state(body).awake) ++s.awake;
  }
  s.impacts = report.impacts.size();
  for (const rt::Impact& impact : report.impacts) s.largest_impulse = std::max(s.largest_impulse, impact.impulse);
  for (const rt::BreakEvent& event : report.breaks) {
    s.bonds_broken += event.bonds_broken;
    s.bodies_created += event.created.size();
  }
  s.kinetic_energy = world.kinetic_energy();
  return s;
}

json summary_json(const StepSummary& s) {
  return json{{"step", s.step},
              {"time_s", s.time},
              {"live_bodies", s.live_bodies},
              {"clusters", s.clusters},
              {"awake", s.awake},
              {"impacts", s.impacts},
              {"largest_impulse_N_s", s.largest_impulse},
              {"bonds_broken", s.bonds_broken},
              {"bodies_created", s.bodies_created},
              {"kinetic_energy_J", s.kinetic_energy}};
}

json break_json(const rt::BreakEvent& event) {
  return json{{"step", event.step},
              {"time_s", event.time},
              {"object", event.object},
              {"cluster", event.body},
              {"impacts", event.impacts},
              {"bonds_broken", event.bonds_broken},
              {"bodies_created", event.created}};
}

void print_summary(const StepSummary& s) {
  std::cout << "step " << s.step << " t=" << number(s.time) << " s: " << s.live_bodies << " bodies (" << s.clusters
            << " clusters, " << s.awake << " awake), " << s.impacts << " impacts";
  if (s.impacts > 0) std::cout << " (largest " << number(s.largest_impulse) << " N s)";
  std::cout << ", " << s.bonds_broken << " bonds broken, " << s.bodies_created << " bodies created, kinetic energy "
            << number(s.kinetic_energy) << " J\n";
}

void print_break(const rt::BreakEvent& event) {
  std::cout << "  break at t=" << number(event.time) << " s (step " << event.step << "): object " << event.object
            << " cluster " << event.body << " lost " << event.bonds_broken << " bonds to " << event.impacts
            << " impact(s)";
  if (event.created.empty()) {
    std::cout << ", still in one piece\n";
    return;
  }
  std::cout << " and became " << event.created.size() << " bodies:";
  for (rt::BodyId body : event.created) std::cout << ' ' << body;
  std::cout << '\n';
}

rt::SceneOptions scene_options_of(const SimulateArgs& args) {
  rt::SceneOptions options = args.scene_options;
  options.kind = enum_or_usage(rt::scene_named(args.scene), "--scene", args.scene);
  options.parameters.mode = enum_or_usage(rt::bond_mode_named(args.bonds), "--bonds", args.bonds);
  options.parameters.impulse = enum_or_usage(rt::impulse_model_named(args.impulse), "--impulse", args.impulse);
  options.parameters.method = enum_or_usage(rt::break_method_named(args.method), "--method", args.method);
  return options;
}

}  // namespace

Command add_simulate_command(CLI::App& app) {
  auto args_owner = std::make_shared<SimulateArgs>();
  SimulateArgs& args = *args_owner;
  CLI::App* command = app.add_subcommand(
      "simulate",
      "Break a .shatter mesh tree in a headless Bullet scene (Breakable Composite Rigid Bodies, seed thesis ch. 5): "
      "one rigid body per cluster of bonded fragments, its collider the convex hulls of the cluster's minimal "
      "cover; after each fixed step, contacts whose impulse passes the threshold damage the hit cluster's bonds "
      "(frailty * p / s^3), and parts that come loose become bodies of their own. Units: metres (the tree's "
      "coordinates), kg, s, N s; y is up, the floor is y = 0. Prints a summary per step and every break; the "
      "same file and options give the same output bytes.");
  command->add_option("tree", args.input, "Mesh tree file (.shatter), as `fracture` writes it")->required();
  command
      ->add_option("--scene", args.scene,
                   "drop: the object, tilted, falls onto the floor from --height. shoot: it rests on the floor and "
                   "a sphere flies at its centre of mass along +x. wall: --wall-rows x --wall-columns copies stand "
                   "as a wall of bricks (thinnest side facing the shot) and a sphere is shot at the middle")
      ->check(CLI::IsMember({"drop", "shoot", "wall"}))
      ->capture_default_str();
  command->add_option("--steps", args.steps, "Number of fixed steps to run")
      ->check(CLI::Range(std::uint64_t{1}, std::uint64_t{10'000'000}))
      ->capture_default_str();
  command->add_option("--time-step", args.world.time_step, "Fixed step, s (every step the same)")
      ->check(CLI::Range(1e-6, 1.0))
      ->capture_default_str();
  command
      ->add_option("--solver-iterations", args.world.solver_iterations,
                   "Iterations of Bullet's sequential impulse solver per step")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  command->add_flag("--no-sleep", args.no_sleep,
                    "Keep resting bodies awake (Bullet otherwise puts them to sleep after 2 s at rest)");

  command->add_option("--density", args.scene_options.parameters.density, "Density of the object, kg/m^3")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  command
      ->add_option("--frailty", args.scene_options.frailty,
                   "f in damage = f * p / s^3, m^3/(N s): a bond at distance s from an impact of impulse p takes "
                   "that much damage; default: hit points (0.45 L)^3 / (M sqrt(g L)), L the object's size and M its "
                   "mass, so the impulse M sqrt(g L) the default shot gives the object breaks bonds within 0.45 L")
      ->check(CLI::PositiveNumber);
  command
      ->add_option("--impact-speed", args.scene_options.parameters.impact_speed,
                   "An impact is a contact point whose normal impulse in one step exceeds this times the hit "
                   "cluster's mass, m/s (N s per kg: the speed it alone would give the cluster; resting contact "
                   "gives about g dt, 0.08 m/s at 1/120 s)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  command
      ->add_option("--hit-points", args.scene_options.parameters.hit_points,
                   "Damage a bond takes before it breaks (same units as the damage)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  command
      ->add_option("--bonds", args.bonds,
                   "discrete: a bond breaks when one impact's damage reaches its hit points, lesser hits leave no "
                   "trace. accumulating: every impact's damage is taken off its hit points; it breaks at zero")
      ->check(CLI::IsMember({"discrete", "accumulating"}))
      ->capture_default_str();
  command
      ->add_option("--impulse", args.impulse,
                   "p of an impact. applied: the normal impulse Bullet's solver applied at the contact point. seed: "
                   "the seed's eq. 5.1, m1 |v1| + m2 |v2| (speeds at the start of the step, a static body counts "
                   "0), shared among the pair's contact points by their impulses")
      ->check(CLI::IsMember({"applied", "seed"}))
      ->capture_default_str();
  command
      ->add_option("--min-distance", args.scene_options.parameters.min_distance,
                   "s is taken as at least this, m, so damage stays finite (at most f p / min^3)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  command->add_option("--friction", args.scene_options.parameters.friction, "Friction coefficient of the object")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  command->add_option("--restitution", args.scene_options.parameters.restitution, "Restitution of the object")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  command
      ->add_option("--method", args.method,
                   "incremental: this runtime (connectivity searched from the broken bonds only, precomputed "
                   "colliders). seed: the seed's method, to compare (fragment graph rebuilt from all bonds, "
                   "colliders and masses built on demand): the same breaks, slower")
      ->check(CLI::IsMember({"incremental", "seed"}))
      ->capture_default_str();
  command
      ->add_option("--margin", args.shapes.collision_margin,
                   "Bullet's collision margin around every fragment's hull, m")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();

  command
      ->add_option("--height", args.scene_options.height,
                   "drop: gap between the object's lowest point and the floor at the start, m; default: twice the "
                   "object's size (the largest extent of its bounding box)")
      ->check(CLI::NonNegativeNumber);
  command
      ->add_option("--tilt", args.scene_options.tilt_degrees,
                   "drop: the object is turned this many degrees about the axis (1, 0, 1) so it lands on an edge")
      ->check(CLI::Range(-360.0, 360.0))
      ->capture_default_str();
  command
      ->add_option("--projectile-mass", args.scene_options.projectile_mass,
                   "shoot, wall: the sphere's mass, kg; default: the object's mass (one brick's in a wall)")
      ->check(CLI::PositiveNumber);
  command
      ->add_option("--projectile-speed", args.scene_options.projectile_speed,
                   "shoot, wall: the sphere's speed, m/s; default: 2 sqrt(g L), L the object's size (6.3 m/s for 1 m, the "
                   "speed of a fall from 2 L)")
      ->check(CLI::NonNegativeNumber);
  command
      ->add_option("--projectile-radius", args.scene_options.projectile_radius,
                   "shoot, wall: the sphere's radius, m; default (or 0): 15% of the object's size")
      ->check(CLI::NonNegativeNumber);
  command->add_option("--wall-rows", args.scene_options.wall_rows, "wall: bricks high")
      ->check(CLI::Range(1u, 64u))
      ->capture_default_str();
  command->add_option("--wall-columns", args.scene_options.wall_columns, "wall: bricks wide")
      ->check(CLI::Range(1u, 64u))
      ->capture_default_str();

  command->add_flag("--json", args.json,
                    "Print one JSON object: the parameters, a summary of every step, every break, the final state");
  command
      ->add_option("--print-every", args.print_every,
                   "Text output: a summary line every this many steps (break events are always printed)")
      // Bounded like --steps, so a negative number (which CLI11 reads as 2^64 - k) is refused.
      ->check(CLI::Range(std::uint64_t{1}, std::uint64_t{10'000'000}))
      ->capture_default_str();
  command->add_option("--record", args.record,
                      "Write the run as an animated glTF binary (.glb): one node per body that ever existed, moved "
                      "by translation and rotation channels and shown from its birth (a stepped scale channel); "
                      "written atomically after the last step, its folder created if missing");
  command
      ->add_option("--record-every", args.record_every,
                   "With --record: keep every this many steps (each body's first state and its death are always "
                   "kept)")
      ->check(CLI::Range(1u, 1'000'000u))
      ->capture_default_str();
  return {command, [args_owner] { return run_simulate(*args_owner); }};
}

int run_simulate(const SimulateArgs& args) {
  // Usage first: nothing is read or run for a command that cannot succeed.
  const rt::SceneOptions scene_options = scene_options_of(args);
  if (!args.record.empty()) {
    if (!names_glb(args.record)) throw UsageError("--record " + args.record + " must name a .glb file");
    if (std::error_code unknown; fs::is_directory(args.record, unknown)) {
      throw UsageError("--record " + args.record + " is a folder; it names the .glb file to write");
    }
  }
  rt::WorldOptions world_options = args.world;
  world_options.sleeping = !args.no_sleep;

  keep_small_objects_on_huge_pages();
  auto tree = std::make_shared<const MeshTree>(read_shatter_file(args.input));
  std::shared_ptr<const rt::BreakableShapes> shapes;
  try {
    shapes = rt::BreakableShapes::create(tree, args.shapes);
  } catch (const std::invalid_argument& e) {
    throw InvalidMeshError(args.input + " cannot be simulated: " + e.what());
  }
  rt::World world(world_options);
  rt::Scene scene;
  try {
    scene = rt::set_up_scene(world, shapes, scene_options);
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }
  const std::vector<Vec3> starts = object_centres(world, scene.objects.size());

  std::optional<rt::Recording> recording;
  if (!args.record.empty()) {
    recording.emplace(args.record_every);
    recording->capture(world);
  }
  json steps_json = json::array();
  json breaks_json = json::array();
  std::size_t bonds_broken = 0;
  if (!args.json) {
    std::cout << args.input << ": scene " << args.scene << ", " << scene.objects.size() << " breakable object(s) of "
              << tree->leaf_count() << " fragments and " << tree->bonds.size() << " bonds, " << args.steps
              << " steps of " << number(world_options.time_step) << " s\n";
    const rt::SceneSizes& sizes = scene.sizes;
    std::cout << "object " << number(sizes.object_size) << " m across, " << number(sizes.object_mass)
              << " kg, frailty " << number(sizes.frailty) << " m^3/(N s); ";
    if (scene_options.kind == rt::SceneKind::drop) {
      std::cout << "dropped from " << number(sizes.height) << " m\n";
    } else {
      std::cout << "a sphere of " << number(sizes.projectile_radius) << " m and " << number(sizes.projectile_mass)
                << " kg shot at " << number(sizes.projectile_speed) << " m/s\n";
    }
  }
  for (std::uint64_t i = 0; i < args.steps; ++i) {
    const rt::StepReport report = world.step();
    if (recording) recording->capture(world);
    const StepSummary summary = summarise(world, report);
    // scene_sizes keeps the scene's magnitudes where Bullet's products stay
    // finite; were a state to leave them anyway, that is a defect, not a number.
    if (!std::isfinite(summary.kinetic_energy)) {
      throw std::runtime_error("the simulation's state stopped being finite at step " + std::to_string(report.step));
    }
    bonds_broken += summary.bonds_broken;
    if (args.json) {
      steps_json.push_back(summary_json(summary));
      for (const rt::BreakEvent& event : report.breaks) breaks_json.push_back(break_json(event));
      continue;
    }
    if (report.step % args.print_every == 0 || !report.breaks.empty()) print_summary(summary);
    for (const rt::BreakEvent& event : report.breaks) print_break(event);
  }

  if (recording) {
    const std::string bytes = recording->encode_glb(world, 1.5 * scene.footprint + 1);
    OutputTransaction output;
    if (const fs::path folder = fs::path(args.record).parent_path(); !folder.empty()) output.create_folder(folder);
    output.write_file(args.record, bytes);
    output.commit();
  }

  const double farthest = farthest_piece(world, starts);
  std::size_t clusters = 0;
  double mass = 0;
  for (rt::BodyId body : world.live_bodies()) {
    if (world.bodies()[body].kind != rt::BodyKind::cluster) continue;
    ++clusters;
    mass += world.bodies()[body].mass.mass;
  }
  if (args.json) {
    // The objects' parameters as run: the frailty resolved for the object.
    rt::BreakableParameters resolved_parameters = scene_options.parameters;
    resolved_parameters.frailty = scene.sizes.frailty;
    json out{{"file", args.input},
             {"leaves", tree->leaf_count()},
             {"bonds", tree->bonds.size()},
             {"objects", scene.objects.size()},
             {"steps", args.steps},
             {"time_step_s", world_options.time_step},
             {"solver_iterations", world_options.solver_iterations},
             {"sleeping", world_options.sleeping},
             {"parameters", parameters_json(resolved_parameters, args.shapes.collision_margin)},
             {"scene", scene_json(scene_options, scene.sizes)},
             {"step_summaries", steps_json},
             {"breaks", breaks_json},
             {"final",
              {{"time_s", world.time()},
               {"live_bodies", world.live_bodies().size()},
               {"clusters", clusters},
               {"bodies_ever", world.bodies().size()},
               {"bonds_broken", bonds_broken},
               {"breakable_mass_kg", mass},
               {"farthest_piece_m", farthest},
               {"farthest_piece_object_sizes", farthest / scene.sizes.object_size},
               {"kinetic_energy_J", world.kinetic_energy()}}},
             {"record", args.record.empty() ? json(nullptr) : json(args.record)}};
    std::cout << json_text(out, 2) << '\n';
    return 0;
  }
  std::cout << "after " << number(world.time()) << " s: " << clusters << " clusters of " << scene.objects.size()
            << " object(s), " << bonds_broken << " bonds broken, " << world.bodies().size()
            << " bodies made in all, breakable mass " << number(mass) << " kg, farthest piece " << number(farthest)
            << " m (" << number(farthest / scene.sizes.object_size) << " object sizes) from where it started\n";
  if (recording) std::cout << "wrote " << args.record << '\n';
  return 0;
}

}  // namespace shatter::cli
