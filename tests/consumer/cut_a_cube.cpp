// Cuts the unit cube with the installed library and checks the pieces: a plane
// cut (cut_mesh_by_plane) into two certified halves of volume 1/2, and a
// mesh tree of 8 fragments (plane kernel) that validate_tree accepts, geometry
// included, whose leaves are valid solids adding up to the cube, written to
// .shatter bytes and read back, then broken in the runtime (one strong impact at
// a corner splits the one body into several that together hold all 8 leaves).
// Exit 0 when all hold.
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

#include "shatter/kernel/mass.hpp"
#include "shatter/kernel/mesh.hpp"
#include "shatter/kernel/validate.hpp"
#include "shatter/formats/formats.hpp"  // the whole API up to the file, as an installed user would include it
#include "shatter/runtime/shapes.hpp"
#include "shatter/runtime/world.hpp"

namespace {

int failures = 0;

void expect(bool holds, const std::string& what) {
  if (holds) return;
  std::fprintf(stderr, "cut_a_cube: %s\n", what.c_str());
  ++failures;
}

shatter::Mesh unit_cube() {
  shatter::Mesh cube;
  for (int i = 0; i < 8; ++i) cube.positions.push_back({double(i & 1), double((i >> 1) & 1), double((i >> 2) & 1)});
  cube.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                    {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  cube.surfaces.assign(cube.triangles.size(), shatter::original_surface);
  return cube;
}

}  // namespace

int main() {
  const shatter::Mesh cube = unit_cube();
  expect(shatter::validate_mesh(cube).valid(), "the unit cube is not valid");

  const shatter::PlaneCut halves = shatter::cut_mesh_by_plane(cube, shatter::Plane{{0, 0, 1}, -0.5});
  expect(halves.certified(), "a half of the cube is not certified");
  expect(halves.pieces.size() == 2 && !halves.pieces[0].above && halves.pieces[1].above,
         "z = 1/2 does not cut the cube into a piece below and one above");
  for (const shatter::CutPiece& half : halves.pieces) {
    expect(shatter::validate_mesh(half.mesh).valid(), "a half is not a valid solid");
    expect(std::fabs(shatter::signed_volume(half.mesh) - 0.5) < 1e-15, "a half's volume is not 1/2");
  }

  shatter::TreeRecipe recipe;
  recipe.fragments = 8;
  recipe.seed = 7;
  const shatter::MeshTree tree = shatter::build_mesh_tree(cube, recipe);
  expect(tree.leaf_count() == 8, "the tree has " + std::to_string(tree.leaf_count()) + " leaves, not 8");
  const shatter::TreeValidationReport report = shatter::validate_tree(tree, {.geometry = true});
  expect(report.valid(), "validate_tree: " + report.summary());
  double volume = 0;
  for (shatter::LeafIndex leaf = 0; leaf < tree.leaf_count(); ++leaf) {
    const shatter::Mesh& piece = tree.leaf(leaf).mesh;
    expect(shatter::validate_mesh(piece).valid(), "leaf " + std::to_string(leaf) + " is not a valid solid");
    volume += shatter::signed_volume(piece);
  }
  expect(std::fabs(volume - 1) < 1e-12, "the leaves' volumes add up to " + std::to_string(volume));
  const shatter::MeshTree read_back = shatter::decode_shatter(shatter::encode_shatter(tree));
  expect(read_back.nodes.size() == tree.nodes.size(), "the tree read back has another node count");

  // The runtime: the cube as one body, struck at a corner hard enough that the
  // damage f p / s^3 reaches every bond's hit points.
  namespace runtime = shatter::runtime;
  const auto shapes = runtime::BreakableShapes::create(std::make_shared<const shatter::MeshTree>(read_back));
  runtime::World world;
  const runtime::ObjectId object = world.add_breakable(shapes, {{0, 0, 0}, {}}, runtime::BreakableParameters{});
  const std::vector<runtime::BodyId> before = world.live_bodies();
  expect(before.size() == 1, "the cube does not start as one body");
  const runtime::BreakEvent event = world.apply_impact(before.front(), {0, 0, 0}, 1e6);
  expect(event.created.size() >= 2, "a 1e6 N s impact did not split the cube");
  std::size_t leaves_held = 0;
  for (runtime::BodyId body : world.live_bodies()) leaves_held += world.leaves_of(body).size();
  expect(leaves_held == 8, "the bodies after the impact hold " + std::to_string(leaves_held) + " leaves, not 8");
  expect(world.object_count() == 1 && object == 0, "one object was placed, not one");

  if (failures == 0) std::printf("cut_a_cube: %zu leaves, volume %.17g, %zu bodies after one impact\n", tree.leaf_count(), volume,
                                 world.live_bodies().size());
  return failures == 0 ? 0 : 1;
}
