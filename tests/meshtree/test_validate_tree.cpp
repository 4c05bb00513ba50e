// Property tests of validate_tree (meshtree/validate_tree.hpp) and of
// `shatter info --check`, which runs it. Built trees over generated and corpus
// meshes, strategies, seeds and a self-intersecting input, and trees the retired
// fast and exact kernels wrote (tests/data/retired), hold. Then every kind of
// defect in the catalogue below is injected into every tree that has a place for
// it, at places drawn from the tree, and the report must name the part and the
// index injected, whatever the tree. Defects of the structure are what the
// reader refuses, so the encoder refuses them too; stale caches only a tree in
// memory can have; defects of the geometry pass the reader, survive a write and
// a read, and `info --check` finds them in the file.

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <limits>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "shatter/kernel/implicit.hpp"
#include "shatter/kernel/io.hpp"
#include "shatter/meshtree/build.hpp"
#include "shatter/formats/file.hpp"
#include "shatter/meshtree/tree.hpp"
#include "shatter/meshtree/validate_tree.hpp"
#include "shatter/generators/corpus.hpp"
#include "shatter/generators/random.hpp"
#include "shatter/generators/solids.hpp"
#include "support/run_shatter.hpp"
#include "support/sanitizers.hpp"

using namespace shatter;

namespace {

// --- the trees --------------------------------------------------------------------

struct Sample {
  std::string name;
  MeshTree tree;
};

MeshTree built(const Mesh& mesh, Strategy strategy, std::uint32_t fragments, std::uint64_t seed,
               bool allow_self_intersections = false) {
  return build_mesh_tree(mesh, {.fragments = fragments,
                                .seed = seed,
                                .strategy = strategy,
                                .allow_self_intersections = allow_self_intersections});
}

// Made once: a convex and a concave solid with a cavity, a corpus mesh, a
// self-intersecting input allowed, a tree that is its root alone, and the two
// trees of the retired kernels (no exact representation).
const std::vector<Sample>& samples() {
  static const std::vector<Sample> all = [] {
    const Mesh knot = read_mesh(test::mesh_dir() / "knot1.off");
    const Mesh elk = read_mesh(test::mesh_dir() / "self-intersecting" / "elk.off");
    std::vector<Sample> trees;
    trees.push_back({"cube, thesis, 8", built(test::unit_cube(), Strategy::thesis, 8, 1)});
    trees.push_back({"knot1, balanced, 10", built(knot, Strategy::balanced, 10, 2)});
    trees.push_back({"hollow egg, axis, 6", built(test::hollow_egg(), Strategy::axis, 6, 3)});
    trees.push_back({"two boxes, balanced, 5", built(test::two_boxes(), Strategy::balanced, 5, 5)});
    trees.push_back({"torus, thesis, 8", built(test::torus(2, 0.6, 16, 10), Strategy::thesis, 8, 4)});
    trees.push_back({"elk, self-intersections allowed, 4", built(elk, Strategy::thesis, 4, 6, true)});
    trees.push_back({"cube, one fragment", built(test::unit_cube(), Strategy::thesis, 1, 7)});
    for (const std::filesystem::path& file : test::retired_kernel_trees()) {
      trees.push_back({file.filename().string(), read_shatter_file(file)});
    }
    return trees;
  }();
  return all;
}

// --- the defects --------------------------------------------------------------------

// Which of validate_tree's checks finds a defect (TreeValidationOptions).
enum class FoundBy { structure, caches, geometry };

struct Place {
  TreePart part;
  std::size_t index;
};

// One kind of defect: injects it at a place `random` draws among those the tree
// has, and returns that place; nothing when the tree has no such place.
struct Injector {
  std::string name;
  FoundBy found_by;
  std::function<std::optional<Place>(MeshTree&, test::Random&)> inject;
};

bool exact(const MeshTree& tree) { return !tree.geometry.points.empty(); }

// A node satisfying `wanted`, drawn uniformly; nothing when none does.
template <class Wanted>
std::optional<NodeIndex> draw_node(const MeshTree& tree, test::Random& random, Wanted&& wanted) {
  std::vector<NodeIndex> candidates;
  for (NodeIndex k = 0; k < tree.nodes.size(); ++k) {
    if (wanted(tree.nodes[k], k)) candidates.push_back(k);
  }
  if (candidates.empty()) return std::nullopt;
  return candidates[random.index(candidates.size())];
}

const auto any_node = [](const MeshTreeNode&, NodeIndex) { return true; };
const auto internal = [](const MeshTreeNode& node, NodeIndex) { return !node.is_leaf(); };
const auto non_root = [](const MeshTreeNode&, NodeIndex k) { return k > 0; };
const auto with_hull = [](const MeshTreeNode& node, NodeIndex) { return !node.convex && !node.hull->triangles.empty(); };

// Removes triangle t with its surface id and corner attributes.
void remove_triangle(Mesh& mesh, std::size_t t) {
  mesh.triangles.erase(mesh.triangles.begin() + static_cast<std::ptrdiff_t>(t));
  mesh.surfaces.erase(mesh.surfaces.begin() + static_cast<std::ptrdiff_t>(t));
  const auto corners = [&](auto& channel) {
    if (!channel.empty()) {
      channel.erase(channel.begin() + static_cast<std::ptrdiff_t>(3 * t),
                    channel.begin() + static_cast<std::ptrdiff_t>(3 * t + 3));
    }
  };
  corners(mesh.corners.normals);
  corners(mesh.corners.uvs);
  corners(mesh.corners.tangents);
}

// The mesh and a copy of it moved along x by 2^-16 of its extent, less than the
// width of any solid here, and far more than the rounding of its coordinates:
// two outward shells through each other, closed and manifold, self-intersecting.
void add_shifted_copy(Mesh& mesh) {
  double lo = mesh.positions[0].x, hi = lo;
  for (const Vec3& p : mesh.positions) {
    lo = std::min(lo, p.x);
    hi = std::max(hi, p.x);
  }
  Mesh copy = mesh;
  for (Vec3& p : copy.positions) p.x += (hi - lo) * 0x1p-16;
  const auto base = static_cast<VertexIndex>(mesh.positions.size());
  mesh.positions.insert(mesh.positions.end(), copy.positions.begin(), copy.positions.end());
  for (const Triangle& t : copy.triangles) mesh.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  mesh.surfaces.insert(mesh.surfaces.end(), copy.surfaces.begin(), copy.surfaces.end());
  mesh.corners.normals.insert(mesh.corners.normals.end(), copy.corners.normals.begin(), copy.corners.normals.end());
  mesh.corners.uvs.insert(mesh.corners.uvs.end(), copy.corners.uvs.begin(), copy.corners.uvs.end());
  mesh.corners.tangents.insert(mesh.corners.tangents.end(), copy.corners.tangents.begin(), copy.corners.tangents.end());
}

std::vector<Injector> injectors() {
  using R = test::Random;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<Injector> all;
  const auto add = [&](std::string name, FoundBy found_by, std::function<std::optional<Place>(MeshTree&, R&)> inject) {
    all.push_back({std::move(name), found_by, std::move(inject)});
  };
  const FoundBy structure = FoundBy::structure, caches = FoundBy::caches, geometry = FoundBy::geometry;

  // --- the structure: what the reader refuses
  add("recipe: no fragments", structure, [](MeshTree& t, R&) -> std::optional<Place> {
    t.recipe.fragments = 0;
    return Place{TreePart::recipe, 0};
  });
  add("recipe: an unknown kernel", structure, [](MeshTree& t, R&) -> std::optional<Place> {
    t.recipe.kernel = static_cast<KernelKind>(7);
    return Place{TreePart::recipe, 0};
  });
  add("node: a parent link that its parent does not return", structure, [](MeshTree& t, R& r) -> std::optional<Place> {
    const auto k = draw_node(t, r, non_root);
    if (!k) return std::nullopt;
    t.nodes[*k].parent = *k;
    return Place{TreePart::node, *k};
  });
  add("node: a depth one too deep", structure, [](MeshTree& t, R& r) -> std::optional<Place> {
    const auto k = draw_node(t, r, non_root);
    if (!k) return std::nullopt;
    ++t.nodes[*k].depth;
    return Place{TreePart::node, *k};
  });
  add("node: an internal node with one child", structure, [](MeshTree& t, R& r) -> std::optional<Place> {
    const auto k = draw_node(t, r, internal);
    if (!k) return std::nullopt;
    t.nodes[*k].children.resize(1);
    return Place{TreePart::node, *k};
  });
  add("node: a child listed twice", structure, [](MeshTree& t, R& r) -> std::optional<Place> {
    const auto k = draw_node(t, r, internal);
    if (!k) return std::nullopt;
    t.nodes[*k].children.back() = t.nodes[*k].children.front();
    return Place{TreePart::node, *k};
  });
  add("leaf range: starting one leaf late", structure, [](MeshTree& t, R& r) -> std::optional<Place> {
    const auto k = draw_node(t, r, any_node);
    ++t.nodes[*k].first_leaf;
    return Place{TreePart::leaf_range, *k};
  });
  add("leaf range: one leaf too many", structure, [](MeshTree& t, R& r) -> std::optional<Place> {
    const auto k = draw_node(t, r, any_node);
    ++t.nodes[*k].leaf_count;
    return Place{TreePart::leaf_range, *k};
  });
  add("leaf list: two leaves swapped", structure, [](MeshTree& t, R& r) -> std::optional<Place> {
    if (t.leaf_nodes.size() < 2) return std::nullopt;
    const std::size_t i = r.index(t.leaf_nodes.size() - 1);
    std::swap(t.leaf_nodes[i], t.leaf_nodes[i + 1]);
    return Place{TreePart::leaf_list, i};
  });
  add("leaf list: the last leaf missing", structure, [](MeshTree& t, R&) -> std::optional<Place> {
    t.leaf_nodes.pop_back();
    return Place{TreePart::leaf_list, 0};
  });
  add("mesh: a vertex index out of range", structure, [](MeshTree& t, R& r) -> std::optional<Place> {
    const auto k = draw_node(t, r, any_node);
    Mesh& mesh = *t.nodes[*k].mesh;
    mesh.triangles[r.index(mesh.triangles.size())][r.index(3)] = static_cast<VertexIndex>(mesh.positions.size());
    return Place{TreePart::mesh, *k};
  });
  add("mesh: a surface id missing", structure, [](MeshTree& t, R& r) -> std::optional<Place> {
    const auto k = draw_node(t, r, any_node);
    t.nodes[*k].mesh->surfaces.pop_back();
    return Place{TreePart::mesh, *k};
  });
  add("mesh: an attribute channel not three per triangle", structure, [](MeshTree& t, R& r) -> std::optional<Place> {
    const auto k = draw_node(t, r, any_node);
    t.nodes[*k].mesh->corners.uvs.resize(1);
    return Place{TreePart::mesh, *k};
  });
  add("hull: a vertex index out of range", structure, [](MeshTree& t, R& r) -> std::optional<Place> {
    const auto k = draw_node(t, r, with_hull);
    if (!k) return std::nullopt;
    Mesh& hull = *t.nodes[*k].hull;
    hull.triangles[r.index(hull.triangles.size())][r.index(3)] = no_index;
    return Place{TreePart::hull, *k};
  });
  add("bond: first not below second", structure, [](MeshTree& t, R& r) -> std::optional<Place> {
    if (t.bonds.empty()) return std::nullopt;
    const std::size_t i = r.index(t.bonds.size());
    std::swap(t.bonds[i].first, t.bonds[i].second);
    return Place{TreePart::bond, i};
  });
  add("bond: a leaf beyond the leaves", structure, [](MeshTree& t, R& r) -> std::optional<Place> {
    if (t.bonds.empty()) return std::nullopt;
    const std::size_t i = r.index(t.bonds.size());
    t.bonds[i].second = static_cast<LeafIndex>(t.leaf_count());
    return Place{TreePart::bond, i};
  });
  add("bond: cut at a leaf", structure, [](MeshTree& t, R& r) -> std::optional<Place> {
    if (t.bonds.empty()) return std::nullopt;
    const std::size_t i = r.index(t.bonds.size());
    t.bonds[i].cut_node = t.leaf_nodes[r.index(t.leaf_count())];
    return Place{TreePart::bond, i};
  });
  add("bond: two bonds out of order", structure, [](MeshTree& t, R& r) -> std::optional<Place> {
    if (t.bonds.size() < 2) return std::nullopt;
    const std::size_t i = r.index(t.bonds.size() - 1);
    std::swap(t.bonds[i], t.bonds[i + 1]);
    return Place{TreePart::bond, i + 1};
  });
  add("input point: a NaN coordinate", structure, [nan](MeshTree& t, R& r) -> std::optional<Place> {
    if (!exact(t)) return std::nullopt;
    const std::size_t p = r.index(t.geometry.points.size());
    t.geometry.points[p].y = nan;
    return Place{TreePart::input_point, p};
  });
  add("input plane: a point beyond the points", structure, [](MeshTree& t, R& r) -> std::optional<Place> {
    if (!exact(t) || t.geometry.planes.empty()) return std::nullopt;
    const std::size_t j = r.index(t.geometry.planes.size());
    t.geometry.planes[j][1] = static_cast<VertexIndex>(t.geometry.points.size());
    return Place{TreePart::input_plane, j};
  });
  // One plane per node, then a cell tree's cell planes (voronoi.hpp), each with
  // a non-zero normal: a plane past the nodes' that is zero is a broken cell plane.
  add("cut planes: fewer than nodes, or a zero cell plane", structure, [](MeshTree& t, R& r) -> std::optional<Place> {
    if (r.index(2) == 0) {
      t.cut_planes.pop_back();
      return Place{TreePart::cut_planes, 0};
    }
    t.cut_planes.emplace_back();
    return Place{TreePart::cut_planes, t.cut_planes.size() - 1};
  });
  add("solid: a corner's vertex out of range", structure, [](MeshTree& t, R& r) -> std::optional<Place> {
    if (!exact(t)) return std::nullopt;
    const auto k = draw_node(t, r, any_node);
    Solid& solid = *t.nodes[*k].solid;
    solid.corners[r.index(solid.corners.size())].vertex = static_cast<VertexIndex>(solid.defs.size());
    return Place{TreePart::solid, *k};
  });
  add("solid: a face on the node's own cut plane", structure, [](MeshTree& t, R& r) -> std::optional<Place> {
    if (!exact(t)) return std::nullopt;
    const auto k = draw_node(t, r, any_node);
    Solid& solid = *t.nodes[*k].solid;
    solid.faces[r.index(solid.faces.size())].plane = PlaneRef::cut(*k);
    return Place{TreePart::solid, *k};
  });
  add("hull: stored for a convex node", structure, [](MeshTree& t, R& r) -> std::optional<Place> {
    const auto k = draw_node(t, r, [](const MeshTreeNode& node, NodeIndex) { return node.convex; });
    if (!k) return std::nullopt;
    t.nodes[*k].hull = test::unit_cube();
    return Place{TreePart::hull, *k};
  });
  add("solid: marked convex without an exact representation", structure, [](MeshTree& t, R& r) -> std::optional<Place> {
    if (exact(t)) return std::nullopt;
    const auto k = draw_node(t, r, any_node);
    t.nodes[*k].convex = true;
    t.nodes[*k].hull = Mesh{};
    return Place{TreePart::solid, *k};
  });

  // --- the caches: only a tree in memory has them
  add("solid: a stale vertex approximation", caches, [](MeshTree& t, R& r) -> std::optional<Place> {
    if (!exact(t)) return std::nullopt;
    const auto k = draw_node(t, r, any_node);
    Solid& solid = *t.nodes[*k].solid;
    Estimate& x = solid.approx[r.index(solid.approx.size())].x;
    x.error = x.error * 2 + 1;  // differs whatever its magnitude
    return Place{TreePart::solid, *k};
  });
  add("input plane: a stale approximation", caches, [](MeshTree& t, R& r) -> std::optional<Place> {
    if (!exact(t) || t.geometry.planes.empty()) return std::nullopt;
    const std::size_t j = r.index(t.geometry.planes.size());
    Estimate& d = t.geometry.plane_approx[j].d;
    d.error = d.error * 2 + 1;
    return Place{TreePart::input_plane, j};
  });
  add("solid: a vertex of three planes, two of them the same", caches, [](MeshTree& t, R& r) -> std::optional<Place> {
    if (!exact(t)) return std::nullopt;
    const auto has_three = [](const MeshTreeNode& node, NodeIndex) {
      return std::any_of(node.solid->defs.begin(), node.solid->defs.end(),
                         [](const PointDef& def) { return def.kind == PointKind::three_planes; });
    };
    const auto k = draw_node(t, r, has_three);
    if (!k) return std::nullopt;
    for (PointDef& def : t.nodes[*k].solid->defs) {
      if (def.kind != PointKind::three_planes) continue;
      def.planes[1] = def.planes[0];
      break;
    }
    return Place{TreePart::solid, *k};
  });

  // --- the geometry: a file keeps it, the reader lets it through
  add("node: a zero plane normal", geometry, [](MeshTree& t, R& r) -> std::optional<Place> {
    if (exact(t)) return std::nullopt;  // there the solids are defined over the plane
    const auto k = draw_node(t, r, internal);
    if (!k) return std::nullopt;
    t.cut_planes[*k].normal = {0, 0, 0};
    return Place{TreePart::node, *k};
  });
  add("node: every child on one side of the plane", geometry, [](MeshTree& t, R& r) -> std::optional<Place> {
    const auto k = draw_node(t, r, internal);
    if (!k) return std::nullopt;
    for (const NodeIndex child : t.nodes[*k].children) t.nodes[child].above_parent_plane = true;
    return Place{TreePart::node, *k};
  });
  add("node: a negative volume", geometry, [](MeshTree& t, R& r) -> std::optional<Place> {
    const auto k = draw_node(t, r, any_node);
    t.nodes[*k].mass.volume = -t.nodes[*k].mass.volume;
    return Place{TreePart::node, *k};
  });
  add("node: a NaN centroid", geometry, [nan](MeshTree& t, R& r) -> std::optional<Place> {
    const auto k = draw_node(t, r, any_node);
    t.nodes[*k].mass.centroid.z = nan;
    return Place{TreePart::node, *k};
  });
  add("mesh: a triangle turned over", geometry, [](MeshTree& t, R& r) -> std::optional<Place> {
    const auto k = draw_node(t, r, any_node);
    Triangle& triangle = t.nodes[*k].mesh->triangles[r.index(t.nodes[*k].mesh->triangles.size())];
    std::swap(triangle[1], triangle[2]);
    return Place{TreePart::mesh, *k};
  });
  add("mesh: a triangle missing", geometry, [](MeshTree& t, R& r) -> std::optional<Place> {
    const auto k = draw_node(t, r, any_node);
    remove_triangle(*t.nodes[*k].mesh, r.index(t.nodes[*k].mesh->triangles.size()));
    return Place{TreePart::mesh, *k};
  });
  add("mesh: a second shell through the first", geometry, [](MeshTree& t, R& r) -> std::optional<Place> {
    if (t.recipe.allow_self_intersections) return std::nullopt;  // held to its topology only
    const auto k = draw_node(t, r, any_node);
    add_shifted_copy(*t.nodes[*k].mesh);
    return Place{TreePart::mesh, *k};
  });
  add("mesh: emptied", geometry, [](MeshTree& t, R& r) -> std::optional<Place> {
    const auto k = draw_node(t, r, any_node);
    t.nodes[*k].mesh = Mesh{};
    return Place{TreePart::mesh, *k};
  });
  add("hull: missing for a node not marked convex", geometry, [](MeshTree& t, R& r) -> std::optional<Place> {
    const auto k = draw_node(t, r, with_hull);
    if (!k) return std::nullopt;
    t.nodes[*k].hull = Mesh{};
    return Place{TreePart::hull, *k};
  });
  add("hull: a triangle turned over", geometry, [](MeshTree& t, R& r) -> std::optional<Place> {
    const auto k = draw_node(t, r, with_hull);
    if (!k) return std::nullopt;
    Triangle& triangle = t.nodes[*k].hull->triangles[r.index(t.nodes[*k].hull->triangles.size())];
    std::swap(triangle[1], triangle[2]);
    return Place{TreePart::hull, *k};
  });
  return all;
}

// "<part> <index>: ", how the report's summary starts.
std::string where(const Place& place) {
  std::string text(tree_part_name(place.part));
  if (place.part != TreePart::recipe) text.append(" ").append(std::to_string(place.index));
  return text + ": ";
}

bool starts_with(const std::string& text, const std::string& prefix) { return text.rfind(prefix, 0) == 0; }

// The report names `place`, on one line.
void check_names(const TreeValidationReport& report, const Place& place) {
  REQUIRE(report.defect.has_value());
  CHECK(tree_part_name(report.defect->part) == tree_part_name(place.part));
  CHECK(report.defect->index == place.index);
  CHECK(starts_with(report.summary(), where(place)));
  CHECK(report.defect->message.find('\n') == std::string::npos);
}

// Each injector twice per tree, at places drawn with these seeds.
constexpr std::uint64_t draw_seeds[] = {20261201, 7};

}  // namespace

TEST_CASE("built trees hold: structure, caches and geometry", "[validate_tree]") {
  REQUIRE(samples().size() == 9);
  CHECK(samples()[7].tree.recipe.kernel != KernelKind::plane);
  CHECK(samples()[8].tree.recipe.kernel != KernelKind::plane);
  for (const Sample& sample : samples()) {
    INFO(sample.name);
    const TreeValidationReport report = validate_tree(sample.tree, {.geometry = true});
    INFO(report.summary());
    CHECK(report.valid());
    CHECK(report.geometry_checked);
    CHECK(report.summary() == "valid");
    CHECK(validate_tree(sample.tree).valid());
    CHECK_FALSE(validate_tree(sample.tree).geometry_checked);
    CHECK(validate_tree(sample.tree, {.caches = false}).valid());
    // What the reader gives back holds too.
    CHECK(validate_tree(decode_shatter(encode_shatter(sample.tree)), {.geometry = true}).valid());
    // With the piece certificates (info --check): the same verdict.
    const TreeValidationReport certified = validate_tree(sample.tree, {.geometry = true, .certificates = true});
    CHECK(certified.valid());
    CHECK(certified.geometry_checked);
  }
}

TEST_CASE("every kind of defect, in every tree that has a place for it, is named by part and index",
          "[validate_tree]") {
  const std::vector<Injector> catalogue = injectors();
  std::map<std::string, std::size_t> injected;  // per injector, over all trees and draws
  for (const Sample& sample : samples()) {
    for (const Injector& injector : catalogue) {
      for (const std::uint64_t seed : draw_seeds) {
        MeshTree tree = sample.tree;
        test::Random random(seed);
        const std::optional<Place> place = injector.inject(tree, random);
        if (!place) continue;
        ++injected[injector.name];
        INFO(sample.name << "; " << injector.name << "; drawn with seed " << seed << ": expected " << where(*place));
        const TreeValidationReport report = validate_tree(tree, {.geometry = true});
        INFO("report: " << report.summary());
        check_names(report, *place);
        CHECK(report.geometry_checked == (injector.found_by == FoundBy::geometry));

        switch (injector.found_by) {
          case FoundBy::structure: {
            // The reader's own check (no caches) finds it, so no file can hold it:
            // the encoder refuses it with the same words.
            check_names(validate_tree(tree, {.caches = false}), *place);
            CHECK_THROWS_WITH(encode_shatter(tree), Catch::Contains(report.defect->message));
            break;
          }
          case FoundBy::caches: {
            CHECK(validate_tree(tree, {.caches = false}).valid());
            CHECK_THROWS_WITH(encode_shatter(tree), Catch::Contains(report.defect->message));
            break;
          }
          case FoundBy::geometry: {
            CHECK(validate_tree(tree).valid());
            // The file keeps it and the reader lets it through; the full check
            // finds it again, in the same words.
            const MeshTree read_back = decode_shatter(encode_shatter(tree));
            const TreeValidationReport again = validate_tree(read_back, {.geometry = true});
            check_names(again, *place);
            CHECK(again.summary() == report.summary());
            // A certificate never accepts the broken node: the full check it
            // falls back on names the same defect in the same words.
            CHECK(validate_tree(tree, {.geometry = true, .certificates = true}).summary() == report.summary());
            break;
          }
        }
      }
    }
  }
  // The catalogue cannot pass by testing nothing: every kind was injected.
  for (const Injector& injector : catalogue) {
    INFO(injector.name);
    CHECK(injected[injector.name] >= 2);
  }
}

TEST_CASE("a tree built with self-intersections allowed is held to its topology", "[validate_tree]") {
  const Sample& elk = samples()[5];
  REQUIRE(elk.tree.recipe.allow_self_intersections);
  for (NodeIndex k : {NodeIndex{0}, elk.tree.leaf_nodes.back()}) {
    MeshTree tree = elk.tree;
    add_shifted_copy(*tree.nodes[k].mesh);
    INFO("a shell through node " << k << "'s mesh");
    CHECK(validate_tree(tree, {.geometry = true}).valid());
    // Held to everything, the tree fails at its root: the elk itself.
    tree.recipe.allow_self_intersections = false;
    const TreeValidationReport strict = validate_tree(tree, {.geometry = true});
    check_names(strict, {TreePart::mesh, 0});
    CHECK(strict.defect->message.find("self-intersecting") != std::string::npos);
  }
}

TEST_CASE("every part has a name", "[validate_tree]") {
  for (int part = 0; part <= static_cast<int>(TreePart::solid); ++part) {
    CHECK(tree_part_name(static_cast<TreePart>(part)) != "unknown");
  }
  CHECK(tree_part_name(static_cast<TreePart>(200)) == "unknown");
}

// --- shatter info --check ----------------------------------------------------------

namespace {

namespace fs = std::filesystem;


}  // namespace

TEST_CASE("info --check says valid of built trees, in text and JSON", "[validate_tree][cli]") {
  const fs::path dir = test::scratch("valid");
  fs::create_directories(dir);
  for (const Sample& sample : samples()) {
    INFO(sample.name);
    const fs::path file = dir / "tree.shatter";
    write_shatter_file(file, sample.tree);
    const test::Run text = test::run_shatter("info --check " + test::quoted(file));
    CHECK(text.exit_code == 0);
    CHECK(text.err.empty());
    CHECK(text.out.find("\n  check: valid (") != std::string::npos);
    const test::Run json = test::run_shatter("info --check --json " + test::quoted(file));
    REQUIRE(json.exit_code == 0);
    CHECK(nlohmann::json::parse(json.out)["check"] == "valid");
    // Without --check, nothing is claimed.
    const test::Run plain = test::run_shatter("info --json " + test::quoted(file));
    REQUIRE(plain.exit_code == 0);
    CHECK(nlohmann::json::parse(plain.out).count("check") == 0);
  }
}

TEST_CASE("info --check refuses a file whose geometry is broken: exit 3, one line naming part and index",
          "[validate_tree][cli]") {
  // What is checked here is the command's plumbing (the exit code, the one line,
  // the place named as validate_tree names it, the JSON run alike); validate_tree
  // itself finds every defect in every tree in-process (the case above). So each
  // kind of defect goes through the command in every other sample, alternating,
  // so that every sample meets some kind (every third under the sanitizers,
  // where each run of shatter is several times slower).
  const std::size_t stride = test::sized(2, 3);
  const fs::path dir = test::scratch("broken");
  fs::create_directories(dir);
  std::size_t runs = 0, kind = 0;
  for (const Injector& injector : injectors()) {
    if (injector.found_by != FoundBy::geometry) continue;
    ++kind;
    for (std::size_t s = 0; s < samples().size(); ++s) {
      if ((s + kind) % stride != 0) continue;
      const Sample& sample = samples()[s];
      MeshTree tree = sample.tree;
      test::Random random(draw_seeds[0]);
      const std::optional<Place> place = injector.inject(tree, random);
      if (!place) continue;
      INFO(sample.name << "; " << injector.name << ": expected " << where(*place));
      const fs::path file = dir / "tree.shatter";
      write_shatter_file(file, tree);
      // The reader stays cheap: without --check the file reads.
      CHECK(test::run_shatter("info " + test::quoted(file)).exit_code == 0);
      const test::Run checked = test::run_shatter("info --check " + test::quoted(file));
      ++runs;
      CHECK(checked.exit_code == 3);
      CHECK(checked.out.empty());
      CHECK(test::is_one_error_line(checked.err));
      CHECK(starts_with(checked.err, "error: " + file.string() + ": invalid tree: " + where(*place)));
      const test::Run json = test::run_shatter("info --check --json " + test::quoted(file));
      CHECK(json.exit_code == 3);
      CHECK(json.out.empty());
      CHECK(json.err == checked.err);
    }
  }
  CHECK(runs >= 20 / stride);
}
