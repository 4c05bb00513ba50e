// shatter-bench-node: where one node of a deep mesh tree spends its time. A cube is
// fractured with build_mesh_tree's defaults (thesis strategy, seed 1) on 1 thread to
// N fragments; then, on every leaf, each step a node costs is timed on its own: the
// cut of the leaf's mesh (cut_mesh_by_plane: the exact cut, then every piece rounded
// and certified), the part of that cut spent preparing the mesh as an input
// (prepare_plane_input, which the builder does once for the root and not per node:
// it cuts each node's exact solid), the validation of a piece with and without the
// self-intersection test, the convex hull, and the mass properties.
// Reported: microseconds per leaf, and the leaves' mean triangle count.
//
// Timing: std::chrono::steady_clock around a loop over all leaves, each step
// repeated until the loop has taken >= 0.3 s in total; the mean per leaf.

#include <CLI/CLI.hpp>

#include <chrono>
#include <cstdint>
#include <functional>
#include <iostream>
#include <string>
#include <vector>

#include "bench_support.hpp"
#include "command_line.hpp"
#include "shatter/generators/solids.hpp"
#include "shatter/kernel/mass.hpp"
#include "shatter/kernel/validate.hpp"
#include "shatter/meshtree/build.hpp"
#include "shatter/cut/hull.hpp"
#include "shatter/cut/plane_cut.hpp"
#include "shatter/cut/plane_input.hpp"

namespace {

using Clock = std::chrono::steady_clock;

// Mean microseconds per leaf of `step` over all leaves.
double microseconds_per_leaf(const std::vector<const shatter::Mesh*>& leaves,
                             const std::function<void(const shatter::Mesh&)>& step) {
  const auto start = Clock::now();
  std::size_t calls = 0;
  do {
    for (const shatter::Mesh* leaf : leaves) step(*leaf);
    calls += leaves.size();
  } while (std::chrono::duration<double>(Clock::now() - start).count() < 0.3);
  return std::chrono::duration<double, std::micro>(Clock::now() - start).count() / static_cast<double>(calls);
}

// A plane through the leaf's vertex mean with a fixed oblique normal: a cut of the
// kind the builder makes, the same on every run.
shatter::Plane plane_through_middle(const shatter::Mesh& mesh) {
  shatter::Vec3 sum;
  for (const shatter::Vec3& p : mesh.positions) sum = sum + p;
  const shatter::Vec3 middle = sum * (1.0 / static_cast<double>(mesh.positions.size()));
  const shatter::Vec3 normal = shatter::normalized(shatter::Vec3{0.3, 0.5, 0.8});
  return {normal, -shatter::dot(normal, middle)};
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::uint32_t> counts{256, 4096};
  CLI::App app{
      "shatter-bench-node: fractures a unit cube into N fragments with build_mesh_tree's defaults (thesis "
      "strategy, seed 1) on 1 thread, and times, per leaf, each step a node costs: the cut of the leaf's mesh "
      "(cut_mesh_by_plane: the exact cut and the certified rounding of every piece), the prepare_plane_input "
      "part of that cut alone, validation with and without the self-intersection test, the convex hull and "
      "the mass properties (mean microseconds per leaf over >= 0.3 s). Prints one Markdown row per N. "
      "Exit status: 0, or 2 on a usage error.",
      "shatter-bench-node"};
  app.add_option("N", counts, "Fragment counts, each an integer from 2 to 1048576")
      ->check(CLI::Range(2u, 1u << 20))
      ->capture_default_str();
  if (const auto code = shatter::bench::parse_command_line(app, argc, argv, 2)) return *code;

  std::cout << "| N | mean leaf triangles | cut µs | of which prepare_plane_input µs | validate µs | "
               "validate without self-intersections µs | hull µs | mass µs |\n"
               "|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const std::uint32_t count : counts) {
    shatter::TreeRecipe recipe;
    recipe.fragments = count;
    const shatter::MeshTree tree = shatter::build_mesh_tree(shatter::test::unit_cube(), recipe, {.threads = 1});
    std::vector<const shatter::Mesh*> leaves;
    std::size_t triangles = 0;
    for (const shatter::NodeIndex node : tree.leaf_nodes) {
      leaves.push_back(&*tree.nodes[node].mesh);
      triangles += tree.nodes[node].mesh->triangles.size();
    }
    shatter::ValidationOptions without_self_intersections;
    without_self_intersections.check_self_intersections = false;
    const double cut = microseconds_per_leaf(
        leaves, [](const shatter::Mesh& m) { (void)shatter::cut_mesh_by_plane(m, plane_through_middle(m)); });
    const double prepare =
        microseconds_per_leaf(leaves, [](const shatter::Mesh& m) { (void)shatter::prepare_plane_input(m); });
    const double validate = microseconds_per_leaf(leaves, [](const shatter::Mesh& m) { (void)shatter::validate_mesh(m); });
    const double validate_topology = microseconds_per_leaf(
        leaves, [&](const shatter::Mesh& m) { (void)shatter::validate_mesh(m, without_self_intersections); });
    const double hull = microseconds_per_leaf(leaves, [](const shatter::Mesh& m) { (void)shatter::convex_hull_of(m); });
    const double mass = microseconds_per_leaf(leaves, [](const shatter::Mesh& m) { (void)shatter::mass_properties(m); });
    std::cout << "| " << shatter::bench::with_thousands(count) << " | "
              << shatter::bench::fixed(static_cast<double>(triangles) / static_cast<double>(leaves.size()), 1) << " | "
              << shatter::bench::fixed(cut, 1) << " | " << shatter::bench::fixed(prepare, 1) << " | "
              << shatter::bench::fixed(validate, 1) << " | "
              << shatter::bench::fixed(validate_topology, 1) << " | " << shatter::bench::fixed(hull, 1) << " | "
              << shatter::bench::fixed(mass, 2) << " |\n";
  }
  return 0;
}
