// Exports and statistics of a mesh tree: node selection parsing and partitions,
// mesh files that read back exactly (and all or none of them), GLBs decoded again
// with tinygltf and checked against the tree, and statistics with known values.
// The trees are built by hand from boxes sliced into slabs, so every count and
// volume is known.

#include <catch2/catch.hpp>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <cmath>
#include <cstdio>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "shatter/generators/solids.hpp"
#include "shatter/kernel/error.hpp"
#include "shatter/kernel/io.hpp"
#include "shatter/kernel/mass.hpp"
#include "shatter/meshtree/build.hpp"
#include "shatter/formats/export.hpp"
#include "shatter/meshtree/stats.hpp"
#include "support/checks.hpp"
#include "support/gltf.hpp"
#include "support/scratch.hpp"

#include "shatter/formats/tinygltf.hpp"

using namespace shatter;
namespace fs = std::filesystem;

namespace {

// --- hand-built trees ------------------------------------------------------------

// The shape of a tree: a leaf when `children` is empty. An internal node's box is
// cut into slabs across axis depth % 3, one per child, sized by `weights` (equal
// when empty).
struct Shape {
  std::vector<Shape> children;
  std::vector<double> weights;
};

Shape leaf() { return {}; }
Shape split(std::vector<Shape> children, std::vector<double> weights = {}) {
  return {std::move(children), std::move(weights)};
}

struct TreeBuilder {
  MeshTree tree;
  Vec3 root_lo, root_hi;
  bool with_attributes = false;

  // Triangles on a face of the root box keep surface 0; those on a slab face
  // inside it get the cap surface of the node that was cut.
  void mark_caps(Mesh& mesh, NodeIndex parent) const {
    for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
      bool on_root_face = false;
      for (int axis = 0; axis < 3; ++axis) {
        const double c0 = mesh.positions[mesh.triangles[t][0]][axis];
        const bool flat = c0 == mesh.positions[mesh.triangles[t][1]][axis] &&
                          c0 == mesh.positions[mesh.triangles[t][2]][axis];
        if (flat && (c0 == root_lo[axis] || c0 == root_hi[axis])) on_root_face = true;
      }
      if (!on_root_face) mesh.surfaces[t] = cap_surface_of(parent);
    }
  }

  // Face normals per corner and planar uvs, as a textured input would carry.
  static void add_attributes(Mesh& mesh) {
    for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
      const Vec3 a = mesh.positions[mesh.triangles[t][0]];
      const Vec3 b = mesh.positions[mesh.triangles[t][1]];
      const Vec3 c = mesh.positions[mesh.triangles[t][2]];
      const Vec3 normal = normalized(cross(b - a, c - a));
      for (VertexIndex v : mesh.triangles[t]) {
        mesh.corners.normals.push_back(normal);
        mesh.corners.uvs.push_back({mesh.positions[v].x + mesh.positions[v].z, mesh.positions[v].y});
      }
    }
  }

  NodeIndex add(const Shape& shape, Vec3 lo, Vec3 hi, NodeIndex parent, std::uint32_t depth) {
    const auto index = static_cast<NodeIndex>(tree.nodes.size());
    tree.nodes.emplace_back();
    tree.cut_planes.emplace_back();
    {
      MeshTreeNode& node = tree.nodes.back();
      node.mesh = test::box(lo, hi);
      if (parent != no_node) mark_caps(*node.mesh, parent);
      if (with_attributes) add_attributes(*node.mesh);
      node.mass = mass_properties(node.mesh);
      node.parent = parent;
      node.depth = depth;
      node.first_leaf = static_cast<LeafIndex>(tree.leaf_nodes.size());
      node.seed = index * 7 + 1;
    }
    if (shape.children.empty()) {
      tree.leaf_nodes.push_back(index);
      tree.nodes[index].leaf_count = 1;
      return index;
    }
    const int axis = static_cast<int>(depth % 3);
    std::vector<double> weights = shape.weights;
    if (weights.empty()) weights.assign(shape.children.size(), 1.0);
    double total = 0;
    for (double w : weights) total += w;
    double done = 0;
    std::vector<NodeIndex> children;
    for (std::size_t i = 0; i < shape.children.size(); ++i) {
      Vec3 child_lo = lo, child_hi = hi;
      const double from = lo[axis] + (hi[axis] - lo[axis]) * done / total;
      done += weights[i];
      const double to = i + 1 == shape.children.size() ? hi[axis] : lo[axis] + (hi[axis] - lo[axis]) * done / total;
      (axis == 0 ? child_lo.x : axis == 1 ? child_lo.y : child_lo.z) = from;
      (axis == 0 ? child_hi.x : axis == 1 ? child_hi.y : child_hi.z) = to;
      if (i == 0) {
        Vec3 normal;
        (axis == 0 ? normal.x : axis == 1 ? normal.y : normal.z) = 1;
        tree.cut_planes[index] = {normal, -to};
      }
      const NodeIndex child = add(shape.children[i], child_lo, child_hi, index, depth + 1);
      tree.nodes[child].above_parent_plane = i > 0;
      children.push_back(child);
    }
    MeshTreeNode& node = tree.nodes[index];
    node.children = std::move(children);
    node.leaf_count = static_cast<std::uint32_t>(tree.leaf_nodes.size()) - node.first_leaf;
    return index;
  }
};

MeshTree tree_of(const Shape& shape, Vec3 lo = {0, 0, 0}, Vec3 hi = {1, 1, 1}, bool with_attributes = false) {
  TreeBuilder builder;
  builder.root_lo = lo;
  builder.root_hi = hi;
  builder.with_attributes = with_attributes;
  builder.add(shape, lo, hi, no_node, 0);
  return std::move(builder.tree);
}

Shape binary(int levels) { return levels == 0 ? leaf() : split({binary(levels - 1), binary(levels - 1)}); }

// A root with three children: one split again (into a leaf and a split pair),
// one leaf, one split into two; depths 1 to 3.
Shape lopsided() { return split({split({leaf(), split({leaf(), leaf()})}), leaf(), split({leaf(), leaf()})}); }

struct NamedTree {
  std::string name;
  MeshTree tree;
};

std::vector<NamedTree> sample_trees() {
  std::vector<NamedTree> trees;
  trees.push_back({"lone root", tree_of(leaf())});
  trees.push_back({"root and two leaves", tree_of(binary(1))});
  trees.push_back({"lopsided", tree_of(lopsided(), {-1, 2, 0.5}, {3, 4, 1.5})});
  trees.push_back({"binary depth 4", tree_of(binary(4))});
  trees.push_back({"three-way splits", tree_of(split({split({leaf(), leaf(), leaf()}), leaf(), leaf()}))});
  return trees;
}

std::uint32_t max_depth_of(const MeshTree& tree) {
  std::uint32_t depth = 0;
  for (const MeshTreeNode& node : tree.nodes) depth = std::max(depth, node.depth);
  return depth;
}

// Every leaf covered by exactly one selected node, in leaf order.
void require_partition(const MeshTree& tree, const std::vector<NodeIndex>& nodes) {
  std::uint32_t next_leaf = 0;
  for (NodeIndex index : nodes) {
    REQUIRE(index < tree.nodes.size());
    REQUIRE(tree.nodes[index].first_leaf == next_leaf);
    next_leaf += tree.nodes[index].leaf_count;
  }
  REQUIRE(next_leaf == tree.leaf_count());
}

// --- files ---------------------------------------------------------------------------

fs::path scratch_folder(const std::string& name) {
  const fs::path folder = test::process_scratch_folder("shatter-export-test") / name;
  fs::remove_all(folder);
  fs::create_directories(folder);
  return folder;
}

std::vector<std::string> file_names_in(const fs::path& folder) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(folder)) names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

// --- GLB decoding: support/gltf.hpp ------------------------------------------------

using test::accessor_values;
using test::decode_glb;

// The triangles of one primitive side (caps or not) of a mesh, in mesh order.
std::vector<TriangleIndex> triangles_on(const Mesh& mesh, bool interior) {
  std::vector<TriangleIndex> triangles;
  for (TriangleIndex t = 0; t < mesh.triangle_count(); ++t) {
    if ((mesh.surfaces[t] != original_surface) == interior) triangles.push_back(t);
  }
  return triangles;
}

// A decoded primitive holds exactly the tree mesh's triangles of its side, in
// order, each corner at the float-rounded position (and attributes) of the corner.
void require_primitive_matches(const tinygltf::Model& model, const tinygltf::Primitive& primitive, const Mesh& mesh,
                               bool interior) {
  REQUIRE(primitive.mode == TINYGLTF_MODE_TRIANGLES);
  REQUIRE(primitive.material == (interior ? 1 : 0));
  const tinygltf::Accessor& position_accessor = model.accessors.at(static_cast<std::size_t>(primitive.attributes.at("POSITION")));
  REQUIRE(position_accessor.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT);
  REQUIRE(position_accessor.type == TINYGLTF_TYPE_VEC3);
  REQUIRE(position_accessor.minValues.size() == 3);
  REQUIRE(position_accessor.maxValues.size() == 3);
  REQUIRE(model.accessors.at(static_cast<std::size_t>(primitive.indices)).componentType ==
          TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT);

  const std::vector<float> positions = accessor_values<float>(model, primitive.attributes.at("POSITION"), 3);
  const std::vector<std::uint32_t> indices = accessor_values<std::uint32_t>(model, primitive.indices, 1);
  const std::vector<TriangleIndex> triangles = triangles_on(mesh, interior);
  REQUIRE(indices.size() == 3 * triangles.size());

  // Every vertex has a normal (tests/viewer/test_glb_normals.cpp checks which);
  // on the original surface it is the input's where the mesh has normals.
  REQUIRE(primitive.attributes.count("NORMAL") == 1);
  const bool has_input_normals = mesh.corners.has_normals() && !interior;
  const bool has_uvs = primitive.attributes.count("TEXCOORD_0") == 1;
  REQUIRE(has_uvs == mesh.corners.has_uvs());
  const std::vector<float> normals = accessor_values<float>(model, primitive.attributes.at("NORMAL"), 3);
  const std::vector<float> uvs =
      has_uvs ? accessor_values<float>(model, primitive.attributes.at("TEXCOORD_0"), 2) : std::vector<float>{};

  for (std::size_t i = 0; i < triangles.size(); ++i) {
    for (std::size_t c = 0; c < 3; ++c) {
      const std::size_t vertex = indices[3 * i + c];
      REQUIRE(vertex < position_accessor.count);
      const Vec3 expected = mesh.positions[mesh.triangles[triangles[i]][c]];
      CHECK(positions[3 * vertex] == static_cast<float>(expected.x));
      CHECK(positions[3 * vertex + 1] == static_cast<float>(expected.y));
      CHECK(positions[3 * vertex + 2] == static_cast<float>(expected.z));
      for (std::size_t axis = 0; axis < 3; ++axis) {
        CHECK(positions[3 * vertex + axis] >= position_accessor.minValues[axis]);
        CHECK(positions[3 * vertex + axis] <= position_accessor.maxValues[axis]);
      }
      const std::size_t corner = 3 * triangles[i] + c;
      if (has_input_normals) {
        CHECK(normals[3 * vertex] == static_cast<float>(mesh.corners.normals[corner].x));
        CHECK(normals[3 * vertex + 2] == static_cast<float>(mesh.corners.normals[corner].z));
      }
      if (has_uvs) {
        CHECK(uvs[2 * vertex] == static_cast<float>(mesh.corners.uvs[corner].x));
        CHECK(uvs[2 * vertex + 1] == static_cast<float>(1.0 - mesh.corners.uvs[corner].y));
      }
    }
  }
}

void require_glb_matches(const MeshTree& tree, const std::vector<NodeIndex>& selection, const std::string& bytes) {
  const tinygltf::Model model = decode_glb(bytes);
  REQUIRE(model.asset.version == "2.0");
  REQUIRE(model.scenes.size() == 1);
  REQUIRE(model.defaultScene == 0);
  REQUIRE(model.scenes[0].nodes == std::vector<int>{0});
  REQUIRE(model.materials.size() == 2);
  REQUIRE(model.materials[0].name == glb_exterior_material);
  REQUIRE(model.materials[1].name == glb_interior_material);
  REQUIRE(model.nodes.size() == tree.nodes.size());

  const std::set<NodeIndex> selected(selection.begin(), selection.end());
  std::size_t meshes = 0;
  for (NodeIndex i = 0; i < tree.nodes.size(); ++i) {
    const MeshTreeNode& node = tree.nodes[i];
    const tinygltf::Node& gltf_node = model.nodes[i];
    INFO("node " << i);
    REQUIRE(gltf_node.name == (node.is_leaf() ? "leaf " + std::to_string(node.first_leaf) : "node " + std::to_string(i)));
    REQUIRE(gltf_node.children == std::vector<int>(node.children.begin(), node.children.end()));
    REQUIRE(gltf_node.matrix.empty());
    REQUIRE(gltf_node.translation.empty());

    const tinygltf::Value& extras = gltf_node.extras;
    REQUIRE(extras.IsObject());
    REQUIRE(extras.Get("tree_node").GetNumberAsInt() == static_cast<int>(i));
    REQUIRE(extras.Get("depth").GetNumberAsInt() == static_cast<int>(node.depth));
    REQUIRE(extras.Get("first_leaf").GetNumberAsInt() == static_cast<int>(node.first_leaf));
    REQUIRE(extras.Get("leaf_count").GetNumberAsInt() == static_cast<int>(node.leaf_count));
    REQUIRE(extras.Get("volume").GetNumberAsDouble() == node.mass.volume);
    if (node.is_leaf()) {
      REQUIRE(extras.Get("leaf").GetNumberAsInt() == static_cast<int>(node.first_leaf));
      REQUIRE_FALSE(extras.Has("plane"));
    } else {
      const tinygltf::Value& plane = extras.Get("plane");
      REQUIRE(plane.ArrayLen() == 4);
      const Plane& cut = tree.cut_planes[i];
      REQUIRE(plane.Get(0).GetNumberAsDouble() == cut.normal.x);
      REQUIRE(plane.Get(1).GetNumberAsDouble() == cut.normal.y);
      REQUIRE(plane.Get(2).GetNumberAsDouble() == cut.normal.z);
      REQUIRE(plane.Get(3).GetNumberAsDouble() == cut.offset);
    }

    if (!selected.count(i)) {
      REQUIRE(gltf_node.mesh == -1);
      continue;
    }
    ++meshes;
    REQUIRE(gltf_node.mesh >= 0);
    const tinygltf::Mesh& mesh = model.meshes.at(static_cast<std::size_t>(gltf_node.mesh));
    const bool has_exterior = !triangles_on(node.mesh, false).empty();
    const bool has_interior = !triangles_on(node.mesh, true).empty();
    REQUIRE(mesh.primitives.size() == static_cast<std::size_t>(has_exterior) + static_cast<std::size_t>(has_interior));
    std::size_t p = 0;
    if (has_exterior) require_primitive_matches(model, mesh.primitives[p++], node.mesh, false);
    if (has_interior) require_primitive_matches(model, mesh.primitives[p++], node.mesh, true);
  }
  REQUIRE(model.meshes.size() == meshes);
}

}  // namespace

// --- selection -------------------------------------------------------------------------

TEST_CASE("node selections parse from leaves, all and depth:K, and nothing else") {
  CHECK(parse_node_selection("leaves") == NodeSelection{NodeSelectionKind::leaves, 0});
  CHECK(parse_node_selection("all") == NodeSelection{NodeSelectionKind::all, 0});
  CHECK(parse_node_selection("depth:0") == NodeSelection{NodeSelectionKind::depth, 0});
  CHECK(parse_node_selection("depth:3") == NodeSelection{NodeSelectionKind::depth, 3});
  CHECK(parse_node_selection("depth:007") == NodeSelection{NodeSelectionKind::depth, 7});
  CHECK(parse_node_selection("depth:4294967295") == NodeSelection{NodeSelectionKind::depth, 4294967295u});

  for (const char* bad : {"", "leaf", "Leaves", "ALL", " all", "all ", "depth", "depth:", "depth:-1", "depth:+1",
                          "depth: 1", "depth:1 ", "depth:1x", "depth:1.5", "depth:4294967296", "depth=2", "nodes"}) {
    INFO("'" << bad << "'");
    CHECK_THROWS_AS(parse_node_selection(bad), std::invalid_argument);
  }
  CHECK_THROWS_WITH(parse_node_selection("some"), Catch::Contains("leaves, all or depth:K"));
  CHECK_THROWS_WITH(parse_node_selection("depth:x"), Catch::Contains("depth:K"));

  for (const char* good : {"leaves", "all", "depth:0", "depth:12"}) {
    CHECK(node_selection_name(parse_node_selection(good)) == good);
  }
}

TEST_CASE("leaves and depth:K partition the leaves, and all lists every node") {
  for (const NamedTree& sample : sample_trees()) {
    const MeshTree& tree = sample.tree;
    INFO(sample.name);

    const std::vector<NodeIndex> leaves = select_nodes(tree, parse_node_selection("leaves"));
    CHECK(leaves == tree.leaf_nodes);
    require_partition(tree, leaves);

    const std::vector<NodeIndex> all = select_nodes(tree, parse_node_selection("all"));
    REQUIRE(all.size() == tree.nodes.size());
    for (NodeIndex i = 0; i < all.size(); ++i) CHECK(all[i] == i);

    const std::uint32_t deepest = max_depth_of(tree);
    for (std::uint32_t depth = 0; depth <= deepest + 2; ++depth) {
      INFO("depth " << depth);
      const std::vector<NodeIndex> cut = select_nodes(tree, {NodeSelectionKind::depth, depth});
      require_partition(tree, cut);
      for (NodeIndex index : cut) {
        const MeshTreeNode& node = tree.nodes[index];
        CHECK((node.depth == depth || (node.is_leaf() && node.depth < depth)));
      }
      if (depth == 0) CHECK(cut == std::vector<NodeIndex>{0});
      if (depth >= deepest) CHECK(cut == tree.leaf_nodes);
    }
  }
  CHECK(select_nodes(MeshTree{}, parse_node_selection("all")).empty());
  CHECK(select_nodes(MeshTree{}, parse_node_selection("depth:1")).empty());
}

TEST_CASE("the lopsided tree cut at depth 1 and 2 gives the expected nodes") {
  const MeshTree tree = tree_of(lopsided());
  // Preorder: 0 root; 1 (split) -> 2 leaf, 3 (split) -> 4, 5; 6 leaf; 7 (split) -> 8, 9.
  REQUIRE(tree.nodes.size() == 10);
  CHECK(select_nodes(tree, parse_node_selection("depth:1")) == std::vector<NodeIndex>{1, 6, 7});
  CHECK(select_nodes(tree, parse_node_selection("depth:2")) == std::vector<NodeIndex>{2, 3, 6, 8, 9});
  CHECK(select_nodes(tree, parse_node_selection("depth:3")) == std::vector<NodeIndex>{2, 4, 5, 6, 8, 9});
}

// --- mesh files ------------------------------------------------------------------------

TEST_CASE("file names are zero-padded to one width per tree") {
  const MeshTree tree = tree_of(lopsided());
  CHECK(file_naming_for(parse_node_selection("leaves")) == FileNaming::by_leaf);
  CHECK(file_naming_for(parse_node_selection("all")) == FileNaming::by_node);
  CHECK(file_naming_for(parse_node_selection("depth:1")) == FileNaming::by_node);
  CHECK(mesh_file_name(tree, 2, FileNaming::by_leaf, MeshFormat::off) == "leaf-0000.off");
  CHECK(mesh_file_name(tree, 9, FileNaming::by_leaf, MeshFormat::ply) == "leaf-0005.ply");
  CHECK(mesh_file_name(tree, 9, FileNaming::by_node, MeshFormat::obj) == "node-00009.obj");
  CHECK(mesh_file_name(tree, 0, FileNaming::by_node, MeshFormat::stl) == "node-00000.stl");
  CHECK_THROWS_AS(mesh_file_name(tree, 1, FileNaming::by_leaf, MeshFormat::off), std::invalid_argument);
  CHECK_THROWS_AS(mesh_file_name(tree, 10, FileNaming::by_node, MeshFormat::off), std::invalid_argument);

  // Widths grow with the tree: 10,001 leaves need 5 digits, 100,001 nodes 6.
  MeshTree wide;
  wide.nodes.resize(100001);
  for (NodeIndex i = 0; i < 10001; ++i) {
    wide.nodes[i].first_leaf = i;
    wide.nodes[i].leaf_count = 1;
    wide.leaf_nodes.push_back(i);
  }
  CHECK(mesh_file_name(wide, 7, FileNaming::by_leaf, MeshFormat::off) == "leaf-00007.off");
  CHECK(mesh_file_name(wide, 10000, FileNaming::by_leaf, MeshFormat::off) == "leaf-10000.off");
  CHECK(mesh_file_name(wide, 12, FileNaming::by_node, MeshFormat::off) == "node-000012.off");
}

TEST_CASE("mesh files read back as the leaves, positions bit for bit") {
  // Coordinates that are not short decimals, so text formats must round-trip.
  const MeshTree tree = tree_of(lopsided(), {-0.1, 1.0 / 3.0, 1e-7}, {2.0 / 7.0, 1.7, 12345.678});
  const std::vector<NodeIndex> leaves = select_nodes(tree, parse_node_selection("leaves"));
  for (const MeshFormat format : {MeshFormat::off, MeshFormat::obj, MeshFormat::ply, MeshFormat::stl}) {
    const std::string extension(format_name(format));
    INFO(extension);
    const fs::path folder = scratch_folder("leaves-" + extension) / "created";
    const std::vector<fs::path> paths = write_mesh_files(tree, leaves, folder, format, FileNaming::by_leaf);
    REQUIRE(paths.size() == 6);
    std::vector<std::string> expected_names;
    for (int i = 0; i < 6; ++i) expected_names.push_back("leaf-000" + std::to_string(i) + "." + extension);
    CHECK(file_names_in(folder) == expected_names);
    for (std::size_t i = 0; i < paths.size(); ++i) {
      CHECK(paths[i] == folder / expected_names[i]);
      const Mesh& written = tree.nodes[leaves[i]].mesh;
      const Mesh read = read_mesh(paths[i]);
      REQUIRE(read.triangle_count() == written.triangle_count());
      for (std::size_t t = 0; t < read.triangle_count(); ++t) {
        for (std::size_t c = 0; c < 3; ++c) {
          // Bit-equal doubles (no tolerance): operator== on Vec3 compares storage.
          REQUIRE(read.positions[read.triangles[t][c]] == written.positions[written.triangles[t][c]]);
        }
      }
    }
  }
}

TEST_CASE("depth and all selections write files named by node index") {
  const MeshTree tree = tree_of(lopsided());
  const fs::path folder = scratch_folder("depth-2");
  const std::vector<NodeIndex> cut = select_nodes(tree, parse_node_selection("depth:2"));
  write_mesh_files(tree, cut, folder, MeshFormat::off, FileNaming::by_node);
  CHECK(file_names_in(folder) ==
        std::vector<std::string>{"node-00002.off", "node-00003.off", "node-00006.off", "node-00008.off",
                                 "node-00009.off"});
  CHECK(read_mesh(folder / "node-00003.off").triangle_count() == tree.nodes[3].mesh->triangle_count());

  // A selection that by_leaf cannot name is refused before anything is written.
  const fs::path refused = scratch_folder("refused");
  CHECK_THROWS_AS(write_mesh_files(tree, cut, refused, MeshFormat::off, FileNaming::by_leaf), std::invalid_argument);
  CHECK(file_names_in(refused).empty());
}

TEST_CASE("a failing file removes the files written before it") {
  const MeshTree tree = tree_of(binary(2));
  const fs::path folder = scratch_folder("failing");
  // A folder where the third file should go makes its rename fail.
  fs::create_directories(folder / "leaf-0002.off" / "occupied");
  const std::vector<NodeIndex> leaves = tree.leaf_nodes;
  CHECK_THROWS_AS(write_mesh_files(tree, leaves, folder, MeshFormat::off, FileNaming::by_leaf), IoError);
  CHECK(file_names_in(folder) == std::vector<std::string>{"leaf-0002.off"});
  CHECK(fs::is_directory(folder / "leaf-0002.off" / "occupied"));
}

// --- GLB ---------------------------------------------------------------------------------

TEST_CASE("the GLB holds the tree as its node hierarchy, meshes on the selected nodes") {
  for (const NamedTree& sample : sample_trees()) {
    INFO(sample.name);
    const MeshTree& tree = sample.tree;
    for (const char* selection_text : {"leaves", "all", "depth:0", "depth:1", "depth:2"}) {
      INFO(selection_text);
      const std::vector<NodeIndex> selection = select_nodes(tree, parse_node_selection(selection_text));
      const std::string bytes = encode_glb(tree, selection);
      REQUIRE(bytes.substr(0, 4) == "glTF");
      require_glb_matches(tree, selection, bytes);
      CHECK(encode_glb(tree, selection) == bytes);  // deterministic
    }
  }
}

TEST_CASE("GLB primitives count the tree's exterior and cap triangles") {
  const MeshTree tree = tree_of(binary(1));
  const std::vector<NodeIndex> all = select_nodes(tree, parse_node_selection("all"));
  const tinygltf::Model model = decode_glb(encode_glb(tree, all));
  REQUIRE(model.meshes.size() == 3);
  // The root has no caps: one primitive; each half has 2 cap triangles on x = 0.5.
  REQUIRE(model.meshes[0].primitives.size() == 1);
  const auto triangle_count = [&](const tinygltf::Primitive& primitive) {
    return model.accessors.at(static_cast<std::size_t>(primitive.indices)).count / 3;
  };
  CHECK(triangle_count(model.meshes[0].primitives[0]) == 12);
  for (std::size_t m = 1; m < 3; ++m) {
    REQUIRE(model.meshes[m].primitives.size() == 2);
    CHECK(triangle_count(model.meshes[m].primitives[0]) == 10);
    CHECK(triangle_count(model.meshes[m].primitives[1]) == 2);
    CHECK(model.meshes[m].primitives[1].material == 1);
  }
  // Without attributes each face is shaded flat: a box face's two triangles
  // share their face normal, so every face has its own 4 vertices (6 faces on
  // the root, 5 on the exterior of a child and 1 on its cap).
  const auto vertex_count = [&](const tinygltf::Primitive& primitive) {
    return model.accessors.at(static_cast<std::size_t>(primitive.attributes.at("POSITION"))).count;
  };
  CHECK(vertex_count(model.meshes[0].primitives[0]) == 24);
  CHECK(vertex_count(model.meshes[1].primitives[0]) == 20);
  CHECK(vertex_count(model.meshes[1].primitives[1]) == 4);
  const tinygltf::Accessor& root_positions =
      model.accessors.at(static_cast<std::size_t>(model.meshes[0].primitives[0].attributes.at("POSITION")));
  CHECK(root_positions.minValues == std::vector<double>{0, 0, 0});
  CHECK(root_positions.maxValues == std::vector<double>{1, 1, 1});
}

TEST_CASE("GLB un-welds vertices where corner attributes differ") {
  const MeshTree tree = tree_of(lopsided(), {0, 0, 0}, {1, 2, 3}, true);
  const std::vector<NodeIndex> leaves = tree.leaf_nodes;
  const std::string bytes = encode_glb(tree, leaves);
  require_glb_matches(tree, leaves, bytes);
  const tinygltf::Model model = decode_glb(bytes);
  // Face normals make every box face its own 4 vertices. Only on the original
  // surface: caps take their cut plane's normal, and this hand-made tree marks
  // a slab's faces of several cuts with one cap surface.
  for (const tinygltf::Mesh& mesh : model.meshes) {
    for (const tinygltf::Primitive& primitive : mesh.primitives) {
      if (primitive.material != 0) continue;
      const std::size_t triangles = model.accessors.at(static_cast<std::size_t>(primitive.indices)).count / 3;
      const std::size_t vertices = model.accessors.at(static_cast<std::size_t>(primitive.attributes.at("NORMAL"))).count;
      CHECK(vertices == 2 * triangles);
    }
  }
}

TEST_CASE("GLB edge cases: empty selection, duplicates, bad indices, bad meshes") {
  const MeshTree tree = tree_of(binary(2));
  const std::vector<NodeIndex> none;
  const tinygltf::Model empty = decode_glb(encode_glb(tree, none));
  CHECK(empty.nodes.size() == tree.nodes.size());
  CHECK(empty.meshes.empty());
  CHECK(empty.buffers.empty());

  const std::vector<NodeIndex> twice{3, 3};
  const tinygltf::Model duplicate = decode_glb(encode_glb(tree, twice));
  CHECK(duplicate.meshes.size() == 1);

  const std::vector<NodeIndex> out_of_range{static_cast<NodeIndex>(tree.nodes.size())};
  CHECK_THROWS_AS(encode_glb(tree, out_of_range), std::invalid_argument);

  MeshTree broken = tree;
  broken.nodes[2].mesh->triangles[0][1] = 1000;
  const std::vector<NodeIndex> second_node{2};
  CHECK_THROWS_AS(encode_glb(broken, second_node), InvalidMeshError);
  CHECK_NOTHROW(encode_glb(broken, std::vector<NodeIndex>{3}));

  const tinygltf::Model lone = decode_glb(encode_glb(MeshTree{}, none));
  CHECK(lone.nodes.empty());
  CHECK(lone.scenes.size() == 1);
}

TEST_CASE("write_glb writes the encoded bytes atomically, creating the folder") {
  const MeshTree tree = tree_of(binary(2));
  const fs::path path = scratch_folder("glb") / "sub" / "tree.glb";
  write_glb(path, tree, tree.leaf_nodes);
  std::string bytes(fs::file_size(path), '\0');
  {
    std::FILE* file = std::fopen(path.c_str(), "rb");
    REQUIRE(file != nullptr);
    REQUIRE(std::fread(bytes.data(), 1, bytes.size(), file) == bytes.size());
    std::fclose(file);
  }
  CHECK(bytes == encode_glb(tree, tree.leaf_nodes));
  CHECK(file_names_in(path.parent_path()) == std::vector<std::string>{"tree.glb"});
  // A folder in the way: IoError, the folder untouched.
  CHECK_THROWS_AS(write_glb(path.parent_path(), tree, tree.leaf_nodes), IoError);
}

TEST_CASE("built trees: partitions, GLBs and statistics agree with the tree") {
  const Mesh torus = test::torus(2, 0.7, 24, 12);
  for (const Strategy strategy : {Strategy::thesis, Strategy::balanced, Strategy::axis}) {
    TreeRecipe recipe;
    recipe.fragments = 9;
    recipe.seed = 11;
    recipe.strategy = strategy;
    const MeshTree tree = build_mesh_tree(torus, recipe);
    INFO(strategy_name(strategy));
    CHECK(test::tree_problem(tree, true) == "");
    const std::uint32_t deepest = max_depth_of(tree);
    for (std::uint32_t depth = 0; depth <= deepest; ++depth) {
      require_partition(tree, select_nodes(tree, {NodeSelectionKind::depth, depth}));
    }
    for (const char* selection_text : {"leaves", "all", "depth:2"}) {
      const std::vector<NodeIndex> selection = select_nodes(tree, parse_node_selection(selection_text));
      require_glb_matches(tree, selection, encode_glb(tree, selection));
    }
    const TreeStats stats = tree_stats(tree);
    CHECK(stats.leaf_count == tree.leaf_count());
    CHECK(stats.leaf_count >= 9);
    CHECK(stats.bond_count == tree.bonds.size());
    CHECK(stats.total_leaf_volume == Approx(stats.root_volume).epsilon(1e-9));
    CHECK(stats.fragment_volume.min <= stats.fragment_volume.median);
    CHECK(stats.fragment_volume.median <= stats.fragment_volume.max);
    CHECK(stats.leaf_cap_triangles > 0);
  }
}

// --- statistics --------------------------------------------------------------------------

TEST_CASE("statistics of a tree with known volumes") {
  // Eight slabs of the 40 x 1 x 1 box, volumes 2, 4, 4, 4, 5, 5, 7, 9: mean 5,
  // population standard deviation 2, median (4 + 5) / 2.
  MeshTree tree = tree_of(split({leaf(), leaf(), leaf(), leaf(), leaf(), leaf(), leaf(), leaf()}, {2, 4, 4, 4, 5, 5, 7, 9}),
                          {0, 0, 0}, {40, 1, 1});
  const std::vector<double> volumes{2, 4, 4, 4, 5, 5, 7, 9};
  for (LeafIndex i = 0; i < 8; ++i) REQUIRE(tree.leaf(i).mass.volume == volumes[i]);
  tree.bonds.push_back({0, 1, 0, 0.5, {}, {1, 0, 0}});
  tree.bonds.push_back({1, 2, 0, 0.25, {}, {1, 0, 0}});

  const TreeStats stats = tree_stats(tree);
  CHECK(stats.node_count == 9);
  CHECK(stats.leaf_count == 8);
  CHECK(stats.internal_count == 1);
  CHECK(stats.max_depth == 1);
  CHECK(stats.min_leaf_depth == 1);
  CHECK(stats.fragment_volume.min == 2);
  CHECK(stats.fragment_volume.max == 9);
  CHECK(stats.fragment_volume.median == 4.5);
  CHECK(stats.fragment_volume.mean == 5);
  CHECK(stats.fragment_volume.coefficient_of_variation == 0.4);
  CHECK(stats.root_volume == 40);
  CHECK(stats.total_leaf_volume == 40);
  CHECK(stats.bond_count == 2);
  CHECK(stats.total_bond_area == 0.75);
  CHECK(stats.leaf_triangles == 8 * 12);
  CHECK(stats.leaf_cap_triangles == 7 * 2 * 2);  // seven inner cuts, two triangles on each side
  CHECK(stats.leaf_vertices == 8 * 8);
}

TEST_CASE("statistics: odd counts, equal fragments, lopsided depths, the empty tree") {
  const TreeStats odd = tree_stats(tree_of(split({leaf(), leaf(), leaf()}, {1, 3, 8}), {0, 0, 0}, {12, 1, 1}));
  CHECK(odd.fragment_volume.median == 3);
  CHECK(odd.fragment_volume.mean == 4);
  CHECK(odd.fragment_volume.coefficient_of_variation == Approx(std::sqrt(26.0 / 3.0) / 4.0));

  const TreeStats equal = tree_stats(tree_of(binary(3)));
  CHECK(equal.fragment_volume.coefficient_of_variation == 0);
  CHECK(equal.fragment_volume.median == 0.125);
  CHECK(equal.max_depth == 3);
  CHECK(equal.min_leaf_depth == 3);
  CHECK(equal.internal_count == 7);

  const TreeStats lopsided_stats = tree_stats(tree_of(lopsided()));
  CHECK(lopsided_stats.min_leaf_depth == 1);
  CHECK(lopsided_stats.max_depth == 3);

  const TreeStats lone = tree_stats(tree_of(leaf()));
  CHECK(lone.leaf_count == 1);
  CHECK(lone.internal_count == 0);
  CHECK(lone.fragment_volume.coefficient_of_variation == 0);
  CHECK(lone.fragment_volume.median == 1);
  CHECK(lone.leaf_cap_triangles == 0);

  const TreeStats empty = tree_stats(MeshTree{});
  CHECK(empty.node_count == 0);
  CHECK(empty.fragment_volume.mean == 0);

  std::vector<double> values{5, 1, 4, 2};
  CHECK(median_of(values) == 3);
  std::vector<double> none;
  CHECK(median_of(none) == 0);
}
