// The certificate a built tree carries to the writer (tree.hpp TreeCertificate,
// validate_tree.hpp certificate_holds): the writer stands on it instead of
// re-validating, so these tests hold it to its promise. It holds for every built
// tree, and validate_tree agrees that such a tree is valid (it never vouches for
// an invalid tree); a change to any field validate_tree reads makes it stop
// holding; a leaf corrupted after the build is refused by the writer as if no
// certificate had been made; a change that keeps the tree valid costs only the
// full check; the reader and validate_tree never consult it.

#include <catch2/catch.hpp>
#include <tbb/task_arena.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "shatter/formats/file.hpp"
#include "shatter/generators/solids.hpp"
#include "shatter/kernel/mass.hpp"
#include "shatter/meshtree/build.hpp"
#include "shatter/meshtree/packed_node.hpp"
#include "shatter/meshtree/tree.hpp"
#include "shatter/meshtree/sites.hpp"
#include "shatter/meshtree/validate_tree.hpp"
#include "shatter/meshtree/voronoi.hpp"
#include "support/checks.hpp"

namespace shatter {
namespace {

struct Built {
  std::string name;
  MeshTree tree;
};

// Built trees over meshes, strategies, seeds and both build modes (lean packs
// the internal nodes; pack_leaves, as `shatter fracture` calls it, the leaves).
std::vector<Built> built_trees() {
  const std::vector<std::pair<std::string, Mesh>> meshes = {{"cube", test::unit_cube()},
                                                            {"torus", test::torus(2, 0.6, 16, 10)},
                                                            {"hollow egg", test::hollow_egg()}};
  std::vector<Built> trees;
  std::uint64_t seed = 11;
  for (const auto& [name, mesh] : meshes) {
    for (const Strategy strategy : {Strategy::thesis, Strategy::balanced, Strategy::axis}) {
      for (const bool lean : {false, true}) {
        TreeRecipe recipe;
        recipe.fragments = 9;
        recipe.seed = seed++;
        recipe.strategy = strategy;
        trees.push_back({name + ", " + std::string(strategy_name(strategy)) + (lean ? ", lean" : "") + ", seed " +
                             std::to_string(recipe.seed),
                         build_mesh_tree(mesh, recipe, {.threads = 1, .lean = lean})});
      }
    }
    // Voronoi trees (build_voronoi_tree certifies its own): a flat one and
    // hierarchies of glued cells.
    for (const std::uint32_t sites : {6u, 40u}) {
      for (const bool lean : {false, true}) {
        TreeRecipe recipe;
        recipe.strategy = Strategy::voronoi;
        recipe.seed = seed++;
        recipe.fragments = sites;
        trees.push_back({name + ", voronoi " + std::to_string(sites) + " sites" + (lean ? ", lean" : "") + ", seed " +
                             std::to_string(recipe.seed),
                         build_voronoi_tree(mesh, uniform_sites(mesh, sites, recipe.seed), recipe,
                                            {.threads = 1, .lean = lean})});
      }
    }
  }
  return trees;
}

const std::vector<Built>& trees() {
  static const std::vector<Built> built = built_trees();
  return built;
}

// A leaf chosen by `salt`, so the cases below touch different leaves of
// different trees.
NodeIndex some_leaf(const MeshTree& tree, std::size_t salt) { return tree.leaf_nodes[salt % tree.leaf_count()]; }

// A tree with its leaves unpacked into their nodes (a lean build's leaves are
// packed as they finish), so a test can change a leaf's arrays.
MeshTree unpacked(const MeshTree& tree) {
  MeshTree copy = tree;
  REQUIRE_FALSE(fill_tree_caches(copy).has_value());
  return copy;
}

TEST_CASE("every built tree carries a certificate that holds, and validate_tree agrees it is valid", "[certificate]") {
  for (const Built& built : trees()) {
    INFO(built.name);
    CHECK(built.tree.certificate.present());
    CHECK(certificate_holds(built.tree));
    // The certificate never vouches for a tree the full check would refuse.
    CHECK(test::tree_problem(built.tree) == "");
    // It says every mass is its mesh's, bit for bit (the writer then leaves
    // them out without recomputing them): true of every node.
    REQUIRE(built.tree.certificate.masses_derived());
    NodeShapes shapes(built.tree);
    for (std::size_t k = 0; k < built.tree.nodes.size(); ++k) {
      INFO("node " << k);
      const MassProperties derived = mass_properties(shapes.mesh(static_cast<NodeIndex>(k)));
      CHECK(std::memcmp(&derived, &built.tree.nodes[k].mass, sizeof derived) == 0);
    }
    // pack_leaves carries it (packing is lossless), and the bytes are those
    // of the full check's path, which recomputes and compares every mass.
    MeshTree packed = built.tree;
    pack_leaves(packed);
    CHECK(certificate_holds(packed));
    CHECK(packed.certificate.masses_derived());
    CHECK(validate_tree(packed).valid());
    MeshTree uncertified = built.tree;
    uncertified.certificate = TreeCertificate();
    REQUIRE_FALSE(certificate_holds(uncertified));
    const std::string bytes = encode_shatter(uncertified);
    CHECK(encode_shatter(built.tree) == bytes);
    CHECK(encode_shatter(packed) == bytes);
    // certify_tree vouches for validity alone: validate_tree compares no mass.
    MeshTree recertified = uncertified;
    REQUIRE(certify_tree(recertified).valid());
    CHECK(certificate_holds(recertified));
    CHECK_FALSE(recertified.certificate.masses_derived());
    CHECK(encode_shatter(recertified) == bytes);
    // What the reader makes of the file it checked itself: no certificate,
    // and it writes the same bytes back.
    const MeshTree decoded = decode_shatter(bytes);
    CHECK_FALSE(decoded.certificate.present());
    CHECK(encode_shatter(decoded) == bytes);
  }
}

TEST_CASE("a change to any field validate_tree reads makes the certificate stop holding", "[certificate]") {
  // One change per field of the tree, each a single bit or a single element:
  // the smallest changes a digest could miss.
  using Change = std::function<void(MeshTree&, NodeIndex leaf)>;
  const std::vector<std::pair<std::string, Change>> changes = {
      {"recipe fragments", [](MeshTree& t, NodeIndex) { t.recipe.fragments ^= 1; }},
      {"recipe seed", [](MeshTree& t, NodeIndex) { t.recipe.seed ^= 1; }},
      {"recipe max_plane_tries", [](MeshTree& t, NodeIndex) { t.recipe.max_plane_tries ^= 1; }},
      {"recipe allow_self_intersections", [](MeshTree& t, NodeIndex) { t.recipe.allow_self_intersections ^= true; }},
      // (push_back: GCC 12 warns falsely, -Wrestrict, on assigning a literal here)
      {"recipe pattern", [](MeshTree& t, NodeIndex) { t.recipe.pattern.push_back('x'); }},
      {"leaf mesh position", [](MeshTree& t, NodeIndex k) { t.nodes[k].mesh->positions[0].x = std::nextafter(t.nodes[k].mesh->positions[0].x, 1e9); }},
      {"leaf mesh triangle", [](MeshTree& t, NodeIndex k) { t.nodes[k].mesh->triangles[0][1] ^= 1; }},
      {"leaf mesh surface", [](MeshTree& t, NodeIndex k) { t.nodes[k].mesh->surfaces[0] ^= 1; }},
      {"leaf mesh normals", [](MeshTree& t, NodeIndex k) { t.nodes[k].mesh->corners.normals.resize(3 * t.nodes[k].mesh->triangles.size()); }},
      {"leaf mass", [](MeshTree& t, NodeIndex k) { t.nodes[k].mass.inertia[8] = -t.nodes[k].mass.inertia[8]; }},
      {"root hull", [](MeshTree& t, NodeIndex) { t.nodes[0].hull->positions.push_back({}); }},
      {"leaf solid definition", [](MeshTree& t, NodeIndex k) { t.nodes[k].solid->defs[0].b ^= 1; }},
      {"leaf solid approximation", [](MeshTree& t, NodeIndex k) { t.nodes[k].solid->approx.pop_back(); }},
      {"leaf solid face", [](MeshTree& t, NodeIndex k) { t.nodes[k].solid->faces[0].reversed ^= true; }},
      {"leaf solid loop", [](MeshTree& t, NodeIndex k) { t.nodes[k].solid->loops[0].corner_count ^= 1; }},
      {"leaf solid corner", [](MeshTree& t, NodeIndex k) { t.nodes[k].solid->corners[0].line.other.bits ^= 1; }},
      {"leaf solid convex", [](MeshTree& t, NodeIndex k) { t.nodes[k].solid->convex ^= true; }},
      {"leaf convex", [](MeshTree& t, NodeIndex k) { t.nodes[k].convex ^= true; }},
      {"leaf parent", [](MeshTree& t, NodeIndex k) { t.nodes[k].parent ^= 1; }},
      {"root children", [](MeshTree& t, NodeIndex) { std::swap(t.nodes[0].children.front(), t.nodes[0].children.back()); }},
      {"leaf side", [](MeshTree& t, NodeIndex k) { t.nodes[k].above_parent_plane ^= true; }},
      {"leaf depth", [](MeshTree& t, NodeIndex k) { t.nodes[k].depth ^= 1; }},
      {"leaf first_leaf", [](MeshTree& t, NodeIndex k) { t.nodes[k].first_leaf ^= 1; }},
      {"leaf leaf_count", [](MeshTree& t, NodeIndex k) { t.nodes[k].leaf_count ^= 2; }},
      {"leaf seed", [](MeshTree& t, NodeIndex k) { t.nodes[k].seed ^= 1; }},
      {"leaf list", [](MeshTree& t, NodeIndex) { t.leaf_nodes.back() ^= 1; }},
      {"bond leaf", [](MeshTree& t, NodeIndex) { t.bonds.back().second ^= 1; }},
      {"bond area", [](MeshTree& t, NodeIndex) { t.bonds.back().area = -t.bonds.back().area; }},
      {"bond normal", [](MeshTree& t, NodeIndex) { t.bonds.back().normal.z = -t.bonds.back().normal.z; }},
      {"input point", [](MeshTree& t, NodeIndex) { t.geometry.points.back().y = -t.geometry.points.back().y; }},
      {"input plane", [](MeshTree& t, NodeIndex) { t.geometry.planes.back()[2] ^= 1; }},
      {"input plane approximation", [](MeshTree& t, NodeIndex) { t.geometry.plane_approx.back().d.error *= 2; }},
      {"cut plane", [](MeshTree& t, NodeIndex) { t.cut_planes[0].offset = std::nextafter(t.cut_planes[0].offset, 1e9); }},
      {"a leaf's unused cut plane", [](MeshTree& t, NodeIndex k) { t.cut_planes[k].offset = -0.0; }},
      {"packed nodes", [](MeshTree& t, NodeIndex) { t.packed_shapes.resize(t.packed_shapes.size() + 1); }},
  };
  std::size_t salt = 0;
  for (const Built& built : trees()) {
    if (!built.tree.packed_shapes.empty()) continue;  // the leaves' arrays are changed in place
    // A lean Voronoi tree keeps no approximations to change.
    if (built.tree.nodes[built.tree.leaf_nodes.front()].solid->approx.empty()) continue;
    REQUIRE(certificate_holds(built.tree));
    for (const auto& [name, change] : changes) {
      INFO(built.name << ": " << name);
      MeshTree tree = built.tree;
      change(tree, some_leaf(tree, salt++));
      CHECK_FALSE(certificate_holds(tree));
    }
  }
  // What validate_tree does not read is outside the digest: encode_shatter
  // checks the version's and the repair's text itself on every call.
  MeshTree tree = trees().front().tree;
  tree.shatter_version = "9.9.9";
  CHECK(certificate_holds(tree));
  tree.shatter_version = "not valid";
  CHECK_THROWS_WITH(encode_shatter(tree), Catch::Contains("shatter_version"));
}

TEST_CASE("the digest hashes nodes, bonds and packed nodes in runs: any run's change is seen, on any threads", "[certificate]") {
  // Large enough for several runs of each (256 nodes, 4,096 bonds, 256 packed
  // nodes a run): the trees above fit in one.
  for (const bool lean : {false, true}) {
    TreeRecipe recipe;
    recipe.fragments = 700;
    recipe.seed = 5;
    MeshTree built = build_mesh_tree(test::unit_cube(), recipe, {.threads = 2, .lean = lean});
    if (!lean) pack_leaves(built);  // packed leaves, as `shatter fracture` writes
    INFO((lean ? "lean" : "packed leaves") << ", " << built.nodes.size() << " nodes, " << built.bond_count() << " bonds");
    REQUIRE(built.nodes.size() > 4 * 256);
    REQUIRE(built.bond_count() > 4096);
    REQUIRE(built.packed_shapes.size() == built.nodes.size());
    // The same verdict from an arena of one thread and of four.
    const auto holds_on = [](const MeshTree& tree, int threads) {
      return tbb::task_arena(threads).execute([&] { return certificate_holds(tree); });
    };
    CHECK(holds_on(built, 1));
    CHECK(holds_on(built, 4));
    // Item `which` (0: in the first run, 1: a middle one, 2: the last) of n.
    const auto item = [](int which, std::size_t n) { return which == 0 ? std::size_t{3} : which == 1 ? n / 2 + 1 : n - 1; };
    using Change = std::function<void(MeshTree&, int which)>;
    const std::vector<std::pair<std::string, Change>> changes = {
        {"node seed", [&](MeshTree& t, int which) { t.nodes[item(which, t.nodes.size())].seed ^= 1; }},
        {"two nodes' seeds swapped across runs",
         [&](MeshTree& t, int which) { std::swap(t.nodes[which].seed, t.nodes[item(which, t.nodes.size())].seed); }},
        {"packed node byte",
         [&](MeshTree& t, int which) {
           // The first packed entry from there (pack_leaves packs leaves only;
           // the last node in preorder is a leaf).
           std::size_t k = item(which, t.packed_shapes.size());
           while (t.packed_shapes[k].empty()) ++k;
           std::vector<std::uint8_t> bytes(t.packed_shapes[k].begin(), t.packed_shapes[k].end());
           REQUIRE_FALSE(bytes.empty());
           bytes.back() ^= 1;
           t.packed_shapes.assign(k, bytes);
         }},
        {"bond area",
         [&](MeshTree& t, int which) {
           double& area = t.packed_bonds.empty() ? t.bonds[item(which, t.bonds.size())].area
                                                 : t.packed_bonds[item(which, t.packed_bonds.size())].area;
           area = -area;
         }},
    };
    for (const auto& [name, change] : changes) {
      for (const int which : {0, 1, 2}) {
        INFO(name << ", place " << which);
        MeshTree tree = built;
        change(tree, which);
        CHECK_FALSE(holds_on(tree, 1));
        CHECK_FALSE(holds_on(tree, 4));
      }
    }
  }
}

TEST_CASE("the writer refuses a tree whose leaf was corrupted after the build, certificate or not", "[certificate]") {
  // Each corruption leaves a tree validate_tree refuses; the writer must refuse
  // it too, whatever certificate the tree still carries.
  using Corruption = std::function<void(MeshTree&, NodeIndex leaf)>;
  const std::vector<std::pair<std::string, Corruption>> corruptions = {
      {"a triangle index past the leaf's vertices",
       [](MeshTree& t, NodeIndex k) { t.nodes[k].mesh->triangles.back()[2] = static_cast<VertexIndex>(t.nodes[k].mesh->positions.size()); }},
      {"a surface id missing", [](MeshTree& t, NodeIndex k) { t.nodes[k].mesh->surfaces.pop_back(); }},
      {"a solid corner past the solid's vertices",
       [](MeshTree& t, NodeIndex k) { t.nodes[k].solid->corners[1].vertex = static_cast<VertexIndex>(t.nodes[k].solid->defs.size()); }},
      {"a solid vertex used by no corner", [](MeshTree& t, NodeIndex k) { t.nodes[k].solid->defs.push_back(t.nodes[k].solid->defs[0]); }},
      {"a stale approximation",
       [](MeshTree& t, NodeIndex k) { t.nodes[k].solid->approx[0].x.value = t.nodes[k].solid->approx[0].x.value * 2 + 1; }},
      {"a hull on a convex leaf", [](MeshTree& t, NodeIndex k) {
         t.nodes[k].convex = true;
         t.nodes[k].hull = t.nodes[k].mesh;
       }},
  };
  std::size_t salt = 0;
  for (const Built& built : trees()) {
    const MeshTree base = unpacked(built.tree);
    for (const auto& [name, corrupt] : corruptions) {
      INFO(built.name << ": " << name);
      MeshTree tree = base;
      // Corrupted, then certified as a build would: the carried certificate
      // of the tree as built is kept.
      tree.certificate = built.tree.certificate;
      const NodeIndex leaf = some_leaf(tree, salt++);
      if (name == std::string("a stale approximation") && tree.nodes[leaf].solid->approx.empty()) continue;
      corrupt(tree, leaf);
      REQUIRE_FALSE(validate_tree(tree).valid());
      CHECK(tree.certificate.present());
      CHECK_FALSE(certificate_holds(tree));
      CHECK_THROWS_AS(encode_shatter(tree), std::invalid_argument);
      CHECK_THROWS_AS(write_shatter(tree, [](std::string_view) {}), std::invalid_argument);
    }
    // A packed leaf's bytes corrupted after pack_leaves (as `shatter fracture`
    // packs them): refused as a packing that does not unpack.
    MeshTree packed = built.tree;
    pack_leaves(packed);
    REQUIRE(certificate_holds(packed));
    const NodeIndex leaf = some_leaf(packed, salt++);
    INFO(built.name << ": packed leaf " << leaf << " truncated");
    packed.packed_shapes.assign(leaf, packed.packed_shapes[leaf].first(packed.packed_shapes[leaf].size() / 2));
    CHECK_FALSE(certificate_holds(packed));
    CHECK_THROWS_WITH(encode_shatter(packed), Catch::Contains("do not unpack"));
  }
}

TEST_CASE("a tree changed but still valid is checked in full and written", "[certificate]") {
  std::size_t salt = 0;
  for (const Built& built : trees()) {
    INFO(built.name);
    MeshTree tree = unpacked(built.tree);
    const std::string before = encode_shatter(tree);
    // One ulp off a leaf's vertex: the position no longer derives from the
    // solid, so the file stores it; the tree is as valid as before.
    Vec3& position = tree.nodes[some_leaf(tree, salt++)].mesh->positions[0];
    position.x = std::nextafter(position.x, 1e9);
    CHECK_FALSE(certificate_holds(tree));
    const std::string after = encode_shatter(tree);
    CHECK(after != before);
    CHECK(encode_shatter(decode_shatter(after)) == after);
  }
}

TEST_CASE("certify_tree certifies a valid hand-made tree and nothing else", "[certificate]") {
  MeshTree tree = unpacked(trees().front().tree);
  tree.certificate = TreeCertificate();
  CHECK_FALSE(certificate_holds(tree));
  CHECK(certify_tree(tree).valid());
  CHECK(certificate_holds(tree));
  tree.nodes[tree.leaf_nodes[0]].mesh->triangles[0][0] = 1u << 30;
  CHECK_FALSE(certificate_holds(tree));
  CHECK_FALSE(certify_tree(tree).valid());
  CHECK_FALSE(tree.certificate.present());
  CHECK_THROWS_AS(encode_shatter(tree), std::invalid_argument);
}

}  // namespace
}  // namespace shatter
