// shatter-bench-runtime: what an impact costs the BCRB runtime (runtime/), against
// the seed's method in the same run (seed thesis ch. 6.3: its runtime lagged at 64
// fragments, mostly from setting up colliders and rebuilding the fragment graph
// after every collision).
//
// Trees: the cube [-0.5,0.5]^3 (12 triangles) cut into N = 64, 256, 1,024, 4,096
// and 16,384 fragments (build_mesh_tree: plane kernel, thesis strategy, seed 1,
// 2 threads; the build is not timed, the loading is: BreakableShapes::create,
// which makes every node's hull shape and the bond arrays once).
//
// One impact: the whole cube as one body at rest, an impact at its corner
// (0.5, 0.5, 0.5) with the impulse p that gives discrete bonds a breaking radius
// r (p = hit points * r^3 / frailty, the default material; r = 0.25 m and
// 0.35 m by default, --radius): the bonds whose centroid lies within r of the
// corner break, so the same physical chip comes off at every N, in more
// fragments as N grows. Timed with std::chrono::steady_clock around
// World::apply_impact alone: damage, the connectivity of the hit cluster, the
// covers, the new bodies' masses and compounds, removing the hit body from
// Bullet's world and adding the new ones (their broadphase pairs are found in
// the next step, for both methods alike).
// Each repetition starts from a fresh World with the whole cube (made outside the
// clock). The three settings below run in three rounds of back-to-back batches,
// each setting >= 7 repetitions and >= 0.5 s of timed impacts in all (at most
// 2,100); medians, so a repetition the shared machine preempted does not count,
// and a stretch of load falls on all three alike. --repetitions N runs exactly N
// instead (rounded up to a multiple of 3): a fresh World costs about 30 ms of
// zeroing Bullet's pools (page faults, most of it system time), so the default's
// 2,100 repetitions of a 25 us impact take minutes, which a smoke run (papers/run
// --quick) does not need.
//   - incremental: BreakMethod::incremental, discrete bonds (the default).
//   - incremental, accumulating: the same impact with accumulating bonds, which
//     must damage every bond of the hit cluster, so it walks all of them.
//   - seed: BreakMethod::seed_rebuild, discrete bonds: every bond of the object
//     visited for damage; the hit cluster's fragment graph rebuilt from all bonds
//     (one list per fragment, merged along each surviving bond), each part's edges
//     copied out of all bonds again, minimal meshes by a breadth-first walk of the
//     tree (Listing 5.2), every cover node's convex hull computed from its mesh
//     (btConvexHullComputer) and its mass properties integrated from its mesh when
//     its body is made. Both methods make the same bodies (checked).
//
// Steps with M breakables: M cubes of --step-fragments (256) fragments on a grid
// 2 m apart. "resting": lying on the floor, Bullet's sleeping off so every step
// simulates them, 120 steps timed after 30 to settle, the median step.
// "breaking": each dropped from 1 m, tilted 20 degrees, stepped 90 steps
// (1/120 s) from release, through the landing and its breaks; the mean step, the
// slowest step, and bodies at the end.

#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "bench_support.hpp"
#include "csv.hpp"
#include "shatter/generators/solids.hpp"
#include "shatter/meshtree/build.hpp"
#include "shatter/meshtree/tree.hpp"
#include "shatter/runtime/scenes.hpp"
#include "shatter/runtime/shapes.hpp"
#include "shatter/runtime/world.hpp"

namespace {

using namespace shatter;
namespace rt = shatter::runtime;
using Clock = std::chrono::steady_clock;
using bench::CsvWriter;
using bench::fixed;
using bench::median;
using bench::with_thousands;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

struct Cube {
  std::uint32_t fragments = 0;
  std::shared_ptr<const MeshTree> tree;
  std::shared_ptr<const rt::BreakableShapes> shapes;
  double load_seconds = 0;
};

Cube cube(std::uint32_t fragments) {
  TreeRecipe recipe;
  recipe.fragments = fragments;
  recipe.seed = 1;
  Cube c;
  c.fragments = fragments;
  c.tree = std::make_shared<const MeshTree>(build_mesh_tree(test::box({-0.5, -0.5, -0.5}, {0.5, 0.5, 0.5}), recipe, {.threads = 2}));
  const Clock::time_point start = Clock::now();
  c.shapes = rt::BreakableShapes::create(c.tree);
  c.load_seconds = seconds_since(start);
  return c;
}

struct ImpactTiming {
  double seconds = 0;  ///< median
  std::size_t runs = 0;
  std::size_t bonds_broken = 0, bodies_created = 0;
};

// One impact on a fresh world with the whole cube, timed.
double one_impact(const Cube& c, const rt::BreakableParameters& parameters, double radius, ImpactTiming& timing) {
  const double impulse = parameters.hit_points * radius * radius * radius / parameters.frailty;
  rt::World world;
  world.add_breakable(c.shapes, {}, parameters);
  const Clock::time_point start = Clock::now();
  const rt::BreakEvent event = world.apply_impact(0, {0.5, 0.5, 0.5}, impulse);
  const double seconds = seconds_since(start);
  timing.bonds_broken = event.bonds_broken;
  timing.bodies_created = event.created.size();
  return seconds;
}

// The same impact under each (method, bonds) setting, in three rounds: in each
// round every setting runs a batch of repetitions back to back (warm caches,
// as a microbenchmark does) until the batch has ceil(min_runs / 3) and
// min_seconds / 3 (at most 700), then the next setting. Spreading each
// setting's batches over the run lets a stretch of load on the shared machine
// fall on all of them alike; the medians are over all batches.
std::vector<ImpactTiming> time_impacts(const Cube& c, double radius,
                                       const std::vector<rt::BreakableParameters>& settings, std::size_t min_runs,
                                       double min_seconds) {
  constexpr int rounds = 3;
  std::vector<ImpactTiming> timings(settings.size());
  std::vector<std::vector<double>> times(settings.size());
  for (int round = 0; round < rounds; ++round) {
    for (std::size_t k = 0; k < settings.size(); ++k) {
      double total = 0;
      for (std::size_t runs = 0;
           (runs < (min_runs + rounds - 1) / rounds || total < min_seconds / rounds) && runs < 700; ++runs) {
        times[k].push_back(one_impact(c, settings[k], radius, timings[k]));
        total += times[k].back();
      }
    }
  }
  for (std::size_t k = 0; k < settings.size(); ++k) {
    timings[k].seconds = median(times[k], bench::not_measured);
    timings[k].runs = times[k].size();
  }
  return timings;
}

struct StepTiming {
  double median_seconds = 0, mean_seconds = 0, slowest_seconds = 0;
  std::size_t bodies = 0, breaks = 0;
};

StepTiming time_steps(const Cube& c, std::uint32_t objects, bool dropped, int settle, int steps) {
  rt::World world(rt::WorldOptions{.sleeping = dropped});
  const int side = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(objects))));
  for (std::uint32_t k = 0; k < objects; ++k) {
    const Vec3 spot{2.0 * (static_cast<int>(k) % side), 0, 2.0 * (static_cast<int>(k) / side)};
    rt::RigidTransform placement{{spot.x, 0.5 + c.shapes->options().collision_margin, spot.z}, {}};
    if (dropped) placement = {{spot.x, 1.5, spot.z}, rt::axis_angle({1, 0, 1}, 20 * 3.141592653589793 / 180)};
    world.add_breakable(c.shapes, placement, {});
  }
  StepTiming timing;
  for (int i = 0; i < settle; ++i) world.step();
  std::vector<double> times;
  for (int i = 0; i < steps; ++i) {
    const Clock::time_point start = Clock::now();
    timing.breaks += world.step().breaks.size();
    times.push_back(seconds_since(start));
  }
  for (double t : times) timing.mean_seconds += t / steps;
  timing.slowest_seconds = *std::max_element(times.begin(), times.end());
  timing.median_seconds = median(times, bench::not_measured);
  timing.bodies = world.live_bodies().size();
  return timing;
}

std::string ms(double seconds) { return fixed(seconds * 1e3, seconds < 1e-3 ? 4 : seconds < 1e-1 ? 3 : 1); }

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "shatter-bench-runtime: the cost of one impact in the BCRB runtime against the seed's method, and "
      "step times with M breakables resting and breaking (see the header of bench/runtime_bench.cpp)."};
  bool quick = false;
  std::string csv_path;
  std::vector<std::uint32_t> sizes{64, 256, 1024, 4096, 16384};
  std::vector<std::uint32_t> counts{1, 4, 16, 64};
  std::uint32_t step_fragments = 256;
  std::vector<double> radii{0.25, 0.35};
  bool incremental_only = false;
  std::size_t repetitions = 0;
  app.add_flag("--quick", quick,
               "Smoke run: 64 and 256 fragments, few repetitions, 1 and 4 objects; fails (exit 2) if the two "
               "methods disagree or an impact breaks nothing");
  app.add_option("--csv", csv_path, "Also write every row as CSV to this file");
  app.add_option("--sizes", sizes, "Fragment counts of the impact table")->delimiter(',')->capture_default_str();
  app.add_option("--objects", counts, "Object counts of the step table")->delimiter(',')->capture_default_str();
  app.add_option("--radius", radii, "Breaking radii of the impact tables, m (the cube's edge is 1 m)")
      ->delimiter(',')
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_flag("--incremental-only", incremental_only,
               "Time only the incremental method (for profiling it); the seed column reads 0");
  app.add_option("--repetitions", repetitions,
                 "Repetitions of each impact setting, exactly (rounded up to a multiple of 3); by default at least "
                 "7 and 0.5 s of timed impacts, at most 2,100")
      ->check(CLI::Range(std::size_t{1}, std::size_t{2100}));
  app.add_option("--step-fragments", step_fragments, "Fragments of each object in the step table")
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  if (quick) {
    sizes = {64, 256};
    radii = {0.5};
    counts = {1, 4};
    step_fragments = 64;
  }
  const std::size_t min_runs = repetitions > 0 ? repetitions : quick ? 2 : 7;
  const double min_seconds = quick || repetitions > 0 ? 0.0 : 0.5;
  // The table is written at the end; the path is tried now, so a bad one fails before the long run.
  std::optional<CsvWriter> csv;
  if (!csv_path.empty()) {
    if (!std::ofstream(csv_path)) {
      std::cerr << "error: cannot write " << csv_path << '\n';
      return 4;
    }
    csv.emplace(
        "table,radius_m,fragments,objects,bonds,load_ms,bonds_broken,bodies_created,incremental_us,incremental_runs,"
        "accumulating_us,seed_us,seed_runs,seed_over_incremental,resting_median_ms_per_step,"
        "breaking_mean_ms_per_step,breaking_slowest_step_ms,bodies_after_breaking,breaks");
  }
  bool ok = true;

  std::map<std::uint32_t, Cube> cubes;
  for (std::uint32_t n : sizes) cubes.emplace(n, cube(n));
  for (const double radius : radii) {
    std::cout
        << "## One impact at a corner (breaking radius " << fixed(radius, 2) << " m), 1 thread\n\n"
        << "| fragments | bonds | load ms | bonds broken | bodies made | incremental µs | accumulating µs | seed µs "
           "| seed / incremental |\n"
        << "|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
    for (std::uint32_t n : sizes) {
      const Cube& c = cubes[n];
      std::vector<rt::BreakableParameters> settings(incremental_only ? 1 : 3);
      if (!incremental_only) {
        settings[1].mode = rt::BondMode::accumulating;
        settings[2].method = rt::BreakMethod::seed_rebuild;
      }
      const std::vector<ImpactTiming> timings = time_impacts(c, radius, settings, min_runs, min_seconds);
      const ImpactTiming& ours = timings[0];
      if (incremental_only) {
        std::cout << "| " << with_thousands(c.tree->leaf_count())
                  << " | incremental only: " << fixed(ours.seconds * 1e6, 1) << " µs, " << ours.bodies_created
                  << " bodies |\n";
        continue;
      }
      const ImpactTiming& accumulating = timings[1];
      const ImpactTiming& seed = timings[2];
      // The methods must agree; the smoke run also insists that its impact breaks
      // something off (the full run's small radii on coarse trees need not).
      if (ours.bonds_broken != seed.bonds_broken || ours.bodies_created != seed.bodies_created ||
          ours.bodies_created != accumulating.bodies_created || (quick && ours.bodies_created == 0)) {
        std::cerr << "error: at " << n << " fragments the methods disagree or nothing broke (" << ours.bodies_created
                  << " / " << accumulating.bodies_created << " / " << seed.bodies_created << " bodies)\n";
        ok = false;
      }
      const double ratio = seed.seconds / ours.seconds;
      std::cout << "| " << with_thousands(c.tree->leaf_count()) << " | " << with_thousands(c.tree->bonds.size())
                << " | " << ms(c.load_seconds) << " | " << ours.bonds_broken << " | " << ours.bodies_created << " | "
                << fixed(ours.seconds * 1e6, 1) << " | " << fixed(accumulating.seconds * 1e6, 1) << " | "
                << fixed(seed.seconds * 1e6, 1) << " | " << fixed(ratio, 1) << " |\n";
      if (csv) {
        csv->field("impact").field(radius).field(c.tree->leaf_count()).field(1).field(c.tree->bonds.size());
        csv->field(c.load_seconds * 1e3).field(ours.bonds_broken).field(ours.bodies_created);
        csv->field(ours.seconds * 1e6).field(ours.runs).field(accumulating.seconds * 1e6).field(seed.seconds * 1e6);
        csv->field(seed.runs).field(ratio).empty(5);
        csv->end_row();
      }
    }
    std::cout << '\n';
  }

  const Cube c = cube(step_fragments);
  std::cout
      << "## Steps of 1/120 s with M cubes of " << with_thousands(c.tree->leaf_count()) << " fragments, 1 thread\n\n"
      << "| objects | resting ms/step (median) | breaking ms/step (mean) | slowest breaking step ms | bodies after "
         "| breaks |\n"
      << "|---:|---:|---:|---:|---:|---:|\n";
  for (std::uint32_t m : counts) {
    const StepTiming resting = time_steps(c, m, false, quick ? 5 : 30, quick ? 10 : 120);
    const StepTiming breaking = time_steps(c, m, true, 0, quick ? 60 : 90);
    if (breaking.breaks == 0) {
      std::cerr << "error: " << m << " dropped objects did not break\n";
      ok = false;
    }
    std::cout << "| " << m << " | " << ms(resting.median_seconds) << " | " << ms(breaking.mean_seconds) << " | "
              << ms(breaking.slowest_seconds) << " | " << breaking.bodies << " | " << breaking.breaks << " |\n";
    if (csv) {
      csv->field("steps").empty().field(c.tree->leaf_count()).field(m).field(c.tree->bonds.size()).empty(9);
      csv->field(resting.median_seconds * 1e3).field(breaking.mean_seconds * 1e3);
      csv->field(breaking.slowest_seconds * 1e3).field(breaking.bodies).field(breaking.breaks);
      csv->end_row();
    }
  }
  if (csv) {
    try {
      csv->save(csv_path);
    } catch (const std::exception& e) {
      std::cerr << "error: " << e.what() << '\n';
      return 4;
    }
  }
  return ok ? 0 : 2;
}
