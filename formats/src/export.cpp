// Node selection, mesh-file export and GLB export of a mesh tree.

#include "shatter/formats/export.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstring>
#include <initializer_list>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <system_error>
#include <unordered_map>

#include "shatter/kernel/error.hpp"

// tinygltf is header-only: its implementation is compiled here, once (see
// tinygltf.hpp, which every other user of tinygltf includes).
#define TINYGLTF_IMPLEMENTATION
#include "shatter/formats/tinygltf.hpp"

namespace shatter {

// --- node selection ------------------------------------------------------------

NodeSelection parse_node_selection(std::string_view text) {
  if (text == "leaves") return {NodeSelectionKind::leaves, 0};
  if (text == "all") return {NodeSelectionKind::all, 0};
  constexpr std::string_view depth_prefix = "depth:";
  if (text.starts_with(depth_prefix)) {
    const std::string_view digits = text.substr(depth_prefix.size());
    std::uint32_t depth = 0;
    // from_chars accepts no sign and no spaces for unsigned types, and reports overflow.
    const auto [end, error] = std::from_chars(digits.data(), digits.data() + digits.size(), depth);
    if (!digits.empty() && error == std::errc() && end == digits.data() + digits.size()) {
      return {NodeSelectionKind::depth, depth};
    }
    throw std::invalid_argument("node selection '" + std::string(text) +
                                "': depth:K takes a whole number K >= 0 (the root is at depth 0)");
  }
  throw std::invalid_argument("node selection '" + std::string(text) +
                              "' is not one of leaves, all or depth:K (K >= 0)");
}

std::string node_selection_name(const NodeSelection& selection) {
  switch (selection.kind) {
    case NodeSelectionKind::leaves: return "leaves";
    case NodeSelectionKind::all: return "all";
    case NodeSelectionKind::depth: return "depth:" + std::to_string(selection.depth);
  }
  return "unknown";
}

std::vector<NodeIndex> select_nodes(const MeshTree& tree, const NodeSelection& selection) {
  std::vector<NodeIndex> selected;
  const auto node_count = static_cast<NodeIndex>(tree.nodes.size());
  switch (selection.kind) {
    case NodeSelectionKind::leaves:
      selected = tree.leaf_nodes;
      break;
    case NodeSelectionKind::all:
      selected.resize(node_count);
      for (NodeIndex i = 0; i < node_count; ++i) selected[i] = i;
      break;
    case NodeSelectionKind::depth:
      // In preorder, the nodes at depth K and the shallower leaves come in leaf
      // order, and none is inside another: exactly one node covers each leaf.
      for (NodeIndex i = 0; i < node_count; ++i) {
        const MeshTreeNode& node = tree.nodes[i];
        if (node.depth == selection.depth || (node.is_leaf() && node.depth < selection.depth)) selected.push_back(i);
      }
      break;
  }
  return selected;
}

// --- mesh files ----------------------------------------------------------------

namespace {

std::size_t decimal_digits(std::size_t value) {
  std::size_t digits = 1;
  while (value >= 10) {
    value /= 10;
    ++digits;
  }
  return digits;
}

std::string zero_padded(std::size_t value, std::size_t width) {
  std::string text = std::to_string(value);
  if (text.size() < width) text.insert(0, width - text.size(), '0');
  return text;
}

void require_node_index(const MeshTree& tree, NodeIndex index) {
  if (index >= tree.nodes.size()) {
    throw std::invalid_argument("node " + std::to_string(index) + " is out of range: the tree has " +
                                std::to_string(tree.nodes.size()) + " nodes");
  }
}

const MeshTreeNode& node_at(const MeshTree& tree, NodeIndex index) {
  require_node_index(tree, index);
  return tree.nodes[index];
}

}  // namespace

FileNaming file_naming_for(const NodeSelection& selection) {
  return selection.kind == NodeSelectionKind::leaves ? FileNaming::by_leaf : FileNaming::by_node;
}

std::string mesh_file_name(const MeshTree& tree, NodeIndex node, FileNaming naming, MeshFormat format) {
  const MeshTreeNode& named = node_at(tree, node);
  const std::string extension = "." + std::string(format_name(format));
  if (naming == FileNaming::by_node) {
    const std::size_t width = std::max<std::size_t>(5, decimal_digits(tree.nodes.size() - 1));
    return "node-" + zero_padded(node, width) + extension;
  }
  if (!named.is_leaf()) {
    throw std::invalid_argument("node " + std::to_string(node) + " is not a leaf: it cannot be named by leaf index");
  }
  const std::size_t width = std::max<std::size_t>(4, decimal_digits(std::max<std::size_t>(tree.leaf_count(), 1) - 1));
  return "leaf-" + zero_padded(named.first_leaf, width) + extension;
}

std::vector<std::filesystem::path> write_mesh_files(const MeshTree& tree, std::span<const NodeIndex> selection,
                                                    const std::filesystem::path& folder, MeshFormat format,
                                                    FileNaming naming) {
  // Every name first: a bad selection fails before anything touches the disk.
  std::vector<std::filesystem::path> paths;
  paths.reserve(selection.size());
  for (NodeIndex node : selection) paths.push_back(folder / mesh_file_name(tree, node, naming, format));

  std::error_code error;
  std::filesystem::create_directories(folder, error);
  if (error) throw IoError("cannot create output folder " + folder.string() + ": " + error.message());

  std::size_t written = 0;
  try {
    for (; written < selection.size(); ++written) write_mesh(tree.nodes[selection[written]].mesh, paths[written], format);
  } catch (...) {
    for (std::size_t i = 0; i < written; ++i) std::filesystem::remove(paths[i], error);
    throw;
  }
  return paths;
}

// --- glTF binary ---------------------------------------------------------------

namespace {

constexpr int exterior_material = 0;
constexpr int interior_material = 1;

// One glTF vertex: a welded vertex together with the attributes of a corner that
// uses it, as raw double bits (absent channels stay zero). Corners with equal
// keys share a glTF vertex; equality of bits, never a tolerance.
struct CornerKey {
  std::array<std::uint64_t, 10> bits{};
  friend bool operator==(const CornerKey&, const CornerKey&) = default;
};

struct CornerKeyHash {
  std::size_t operator()(const CornerKey& key) const {
    std::uint64_t hash = 0x9E3779B97F4A7C15ull;
    for (std::uint64_t word : key.bits) {
      hash ^= word + 0x9E3779B97F4A7C15ull + (hash << 6) + (hash >> 2);
    }
    return static_cast<std::size_t>(hash);
  }
};

// The vertices and triangles of one primitive, in glTF's float layout.
struct PrimitiveData {
  std::vector<float> positions;  // xyz
  std::vector<float> normals;    // xyz, one per vertex
  std::vector<float> uvs;        // uv, empty if absent
  std::vector<float> tangents;   // xyzw, empty if absent
  std::vector<std::uint32_t> indices;

  std::size_t vertex_count() const { return positions.size() / 3; }
};

void check_mesh_shape(const Mesh& mesh, NodeIndex node) {
  const std::size_t triangles = mesh.triangle_count();
  const auto fail = [&](const std::string& what) {
    throw InvalidMeshError("mesh of node " + std::to_string(node) + ": " + what);
  };
  if (mesh.surfaces.size() != triangles) fail("surface ids do not match the triangles");
  const CornerAttributes& corners = mesh.corners;
  if (corners.has_normals() && corners.normals.size() != 3 * triangles) fail("normals do not match the corners");
  if (corners.has_uvs() && corners.uvs.size() != 3 * triangles) fail("uvs do not match the corners");
  if (corners.has_tangents() && corners.tangents.size() != 3 * triangles) fail("tangents do not match the corners");
  for (std::size_t t = 0; t < triangles; ++t) {
    for (VertexIndex v : mesh.triangles[t]) {
      if (v >= mesh.positions.size()) fail("triangle " + std::to_string(t) + " uses a vertex out of range");
    }
  }
}

// The unit normal of a triangle from its double positions: the cross product of
// two edges, each first scaled by its largest component so that tiny or huge
// coordinates neither underflow nor overflow. A triangle without area (never
// in a valid mesh) covers no pixel; it gets +z, which shades nothing wrong.
Vec3 face_normal(const Mesh& mesh, const Triangle& triangle) {
  const auto scaled = [](Vec3 v) {
    const double largest = std::max({std::abs(v.x), std::abs(v.y), std::abs(v.z)});
    return largest > 0 ? v * (1.0 / largest) : v;
  };
  const Vec3 a = mesh.positions[triangle[0]];
  const Vec3 n = cross(scaled(mesh.positions[triangle[1]] - a), scaled(mesh.positions[triangle[2]] - a));
  const double length = norm(n);
  if (!(length > 0) || !std::isfinite(length)) return {0, 0, 1};
  return n * (1.0 / length);
}

// The outward unit normal of `node`'s caps on the cut of node `cut`: that cut
// plane's normal, pointing away from the side the node lies on. The side is
// read from the tree (the child of `cut` the node descends from), so it is
// exact. A cap whose cut is not an ancestor, or has no plane (only in a tree
// made by hand), takes its first triangle's own normal instead.
Vec3 cap_normal(const MeshTree& tree, NodeIndex node, NodeIndex cut, const Mesh& mesh, const Triangle& triangle) {
  if (cut >= tree.cut_planes.size()) return face_normal(mesh, triangle);  // no plane stored
  const Vec3 plane_normal = normalized(tree.cut_planes[cut].normal);
  if (!(norm(plane_normal) > 0) || !is_finite(plane_normal)) return face_normal(mesh, triangle);  // a zero plane
  NodeIndex child = node;
  while (child < tree.nodes.size() && tree.nodes[child].parent != cut && tree.nodes[child].parent != no_node) {
    child = tree.nodes[child].parent;
  }
  if (child < tree.nodes.size() && tree.nodes[child].parent == cut) {
    // The side n·x + d < 0 lies below the plane, so its cap faces +n.
    return tree.nodes[child].above_parent_plane ? -plane_normal : plane_normal;
  }
  return face_normal(mesh, triangle);
}

// The normal glTF gets at every corner of `node`'s mesh (3 per triangle): the
// input's per-corner normals on the original surface where the mesh has them,
// else each triangle's own (flat) normal; on caps always the cut plane's,
// outward, so a cap is flat and its edge with the surface stays a sharp crease.
std::vector<Vec3> export_normals(const MeshTree& tree, NodeIndex node) {
  const Mesh& mesh = tree.nodes[node].mesh;
  std::vector<Vec3> normals;
  normals.reserve(3 * mesh.triangle_count());
  std::unordered_map<SurfaceId, Vec3> cap_normal_of;
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    const SurfaceId surface = mesh.surfaces[t];
    Vec3 flat;
    if (surface != original_surface && surface - 1 < tree.nodes.size()) {
      const auto [found, inserted] = cap_normal_of.try_emplace(surface);
      if (inserted) found->second = cap_normal(tree, node, surface - 1, mesh, mesh.triangles[t]);
      flat = found->second;
    } else if (mesh.corners.has_normals()) {
      for (std::size_t c = 0; c < 3; ++c) normals.push_back(mesh.corners.normals[3 * t + c]);
      continue;
    } else {
      flat = face_normal(mesh, mesh.triangles[t]);
    }
    normals.insert(normals.end(), {flat, flat, flat});
  }
  return normals;
}

// The triangles of `mesh` whose surface is (interior) or is not (exterior) a cap,
// with each welded vertex split once per distinct combination of its corner's
// normal (`normals`, 3 per triangle) and attributes.
PrimitiveData primitive_of(const Mesh& mesh, const std::vector<Vec3>& normals, bool interior) {
  const CornerAttributes& corners = mesh.corners;
  PrimitiveData data;
  std::unordered_map<CornerKey, std::uint32_t, CornerKeyHash> vertex_of_corner;
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    if ((mesh.surfaces[t] != original_surface) != interior) continue;
    for (std::size_t c = 0; c < 3; ++c) {
      const std::size_t corner = 3 * t + c;
      const VertexIndex vertex = mesh.triangles[t][c];
      const Vec3 n = normals[corner];
      CornerKey key;
      key.bits[0] = vertex;
      key.bits[1] = std::bit_cast<std::uint64_t>(n.x);
      key.bits[2] = std::bit_cast<std::uint64_t>(n.y);
      key.bits[3] = std::bit_cast<std::uint64_t>(n.z);
      if (corners.has_uvs()) {
        key.bits[4] = std::bit_cast<std::uint64_t>(corners.uvs[corner].x);
        key.bits[5] = std::bit_cast<std::uint64_t>(corners.uvs[corner].y);
      }
      if (corners.has_tangents()) {
        const Vec4 tangent = corners.tangents[corner];
        key.bits[6] = std::bit_cast<std::uint64_t>(tangent.x);
        key.bits[7] = std::bit_cast<std::uint64_t>(tangent.y);
        key.bits[8] = std::bit_cast<std::uint64_t>(tangent.z);
        key.bits[9] = std::bit_cast<std::uint64_t>(tangent.w);
      }
      const auto [found, inserted] = vertex_of_corner.try_emplace(key, static_cast<std::uint32_t>(data.vertex_count()));
      data.indices.push_back(found->second);
      if (!inserted) continue;
      const Vec3 p = mesh.positions[vertex];
      data.positions.insert(data.positions.end(),
                            {static_cast<float>(p.x), static_cast<float>(p.y), static_cast<float>(p.z)});
      data.normals.insert(data.normals.end(), {static_cast<float>(n.x), static_cast<float>(n.y), static_cast<float>(n.z)});
      if (corners.has_uvs()) {
        const Vec2 uv = corners.uvs[corner];
        data.uvs.insert(data.uvs.end(), {static_cast<float>(uv.x), static_cast<float>(1.0 - uv.y)});
      }
      if (corners.has_tangents()) {
        const Vec4 tangent = corners.tangents[corner];
        data.tangents.insert(data.tangents.end(), {static_cast<float>(tangent.x), static_cast<float>(tangent.y),
                                                   static_cast<float>(tangent.z), static_cast<float>(tangent.w)});
      }
    }
  }
  return data;
}

// GLB's header holds the total length in 32 bits; keep well clear of it so the
// JSON chunk fits too.
constexpr std::size_t max_binary_chunk = std::size_t{0xF0000000u};

// Appends model parts to a glTF model with a single binary buffer.
class GltfWriter {
 public:
  explicit GltfWriter(tinygltf::Model& model) : model_(model) {
    model_.buffers.resize(1);
  }

  // An accessor over `values`, `components` floats per element.
  template <class Value>
  int add_accessor(const std::vector<Value>& values, int component_type, int type, std::size_t components,
                   int target) {
    const std::size_t bytes = values.size() * sizeof(Value);
    std::vector<unsigned char>& buffer = model_.buffers[0].data;
    if (buffer.size() + bytes > max_binary_chunk) {
      throw std::length_error("the GLB would exceed glTF binary's 4 GiB limit; export fewer nodes");
    }
    // Every component here is 4 bytes wide and every view a whole number of them,
    // so each view starts 4-byte aligned, as glTF requires.
    tinygltf::BufferView view;
    view.buffer = 0;
    view.byteOffset = buffer.size();
    view.byteLength = bytes;
    view.target = target;
    const std::size_t old_size = buffer.size();
    buffer.resize(old_size + bytes);
    std::memcpy(buffer.data() + old_size, values.data(), bytes);
    model_.bufferViews.push_back(std::move(view));

    tinygltf::Accessor accessor;
    accessor.bufferView = static_cast<int>(model_.bufferViews.size() - 1);
    accessor.byteOffset = 0;
    accessor.componentType = component_type;
    accessor.type = type;
    accessor.count = values.size() / components;
    model_.accessors.push_back(std::move(accessor));
    return static_cast<int>(model_.accessors.size() - 1);
  }

  int add_float_accessor(const std::vector<float>& values, int type, std::size_t components) {
    return add_accessor(values, TINYGLTF_COMPONENT_TYPE_FLOAT, type, components, TINYGLTF_TARGET_ARRAY_BUFFER);
  }

  // POSITION needs its bounds: taken from the floats written, so they hold exactly.
  int add_position_accessor(const std::vector<float>& positions) {
    const int index = add_float_accessor(positions, TINYGLTF_TYPE_VEC3, 3);
    std::vector<double> min(3, std::numeric_limits<double>::infinity());
    std::vector<double> max(3, -std::numeric_limits<double>::infinity());
    for (std::size_t i = 0; i < positions.size(); ++i) {
      min[i % 3] = std::min(min[i % 3], static_cast<double>(positions[i]));
      max[i % 3] = std::max(max[i % 3], static_cast<double>(positions[i]));
    }
    model_.accessors[static_cast<std::size_t>(index)].minValues = std::move(min);
    model_.accessors[static_cast<std::size_t>(index)].maxValues = std::move(max);
    return index;
  }

  tinygltf::Primitive add_primitive(const PrimitiveData& data, int material) {
    tinygltf::Primitive primitive;
    primitive.mode = TINYGLTF_MODE_TRIANGLES;
    primitive.material = material;
    primitive.attributes["POSITION"] = add_position_accessor(data.positions);
    primitive.attributes["NORMAL"] = add_float_accessor(data.normals, TINYGLTF_TYPE_VEC3, 3);
    if (!data.uvs.empty()) primitive.attributes["TEXCOORD_0"] = add_float_accessor(data.uvs, TINYGLTF_TYPE_VEC2, 2);
    if (!data.tangents.empty()) {
      primitive.attributes["TANGENT"] = add_float_accessor(data.tangents, TINYGLTF_TYPE_VEC4, 4);
    }
    primitive.indices = add_accessor(data.indices, TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT, TINYGLTF_TYPE_SCALAR, 1,
                                     TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
    return primitive;
  }

  // The mesh of a tree node, or -1 when it has no triangles (glTF needs at
  // least one primitive, and no primitive may be empty).
  int add_mesh(const Mesh& mesh, const std::vector<Vec3>& normals, const std::string& name) {
    tinygltf::Mesh gltf_mesh;
    gltf_mesh.name = name;
    for (const bool interior : {false, true}) {
      const PrimitiveData data = primitive_of(mesh, normals, interior);
      if (data.indices.empty()) continue;
      gltf_mesh.primitives.push_back(add_primitive(data, interior ? interior_material : exterior_material));
    }
    if (gltf_mesh.primitives.empty()) return -1;
    model_.meshes.push_back(std::move(gltf_mesh));
    return static_cast<int>(model_.meshes.size() - 1);
  }

 private:
  tinygltf::Model& model_;
};

tinygltf::Material material_named(std::string_view name, std::vector<double> base_colour, double roughness) {
  tinygltf::Material material;
  material.name = std::string(name);
  material.pbrMetallicRoughness.baseColorFactor = std::move(base_colour);
  material.pbrMetallicRoughness.metallicFactor = 0.0;
  material.pbrMetallicRoughness.roughnessFactor = roughness;
  return material;
}

// glTF's JSON numbers for the extras: integers as ints while they fit, else as
// doubles (exact up to 2^53, far beyond any tree's size).
tinygltf::Value count_value(std::uint64_t count) {
  if (count <= static_cast<std::uint64_t>(std::numeric_limits<int>::max())) {
    return tinygltf::Value(static_cast<int>(count));
  }
  return tinygltf::Value(static_cast<double>(count));
}

tinygltf::Value number_array(std::initializer_list<double> values) {
  tinygltf::Value::Array array;
  for (double value : values) array.emplace_back(value);
  return tinygltf::Value(std::move(array));
}

tinygltf::Value vec3_value(Vec3 v) { return number_array({v.x, v.y, v.z}); }

std::size_t cap_triangle_count(const Mesh& mesh) {
  return static_cast<std::size_t>(
      std::count_if(mesh.surfaces.begin(), mesh.surfaces.end(), [](SurfaceId s) { return s != original_surface; }));
}

tinygltf::Value extras_of(const MeshTree& tree, NodeIndex index) {
  const MeshTreeNode& node = tree.nodes[index];
  tinygltf::Value::Object extras;
  extras["tree_node"] = count_value(index);
  extras["depth"] = count_value(node.depth);
  extras["first_leaf"] = count_value(node.first_leaf);
  extras["leaf_count"] = count_value(node.leaf_count);
  extras["volume"] = tinygltf::Value(node.mass.volume);
  extras["centroid"] = vec3_value(node.mass.centroid);
  extras["triangles"] = count_value(node.mesh->triangle_count());
  extras["cap_triangles"] = count_value(cap_triangle_count(node.mesh));
  if (node.is_leaf()) {
    extras["leaf"] = count_value(node.first_leaf);
  } else if (index < tree.cut_planes.size()) {  // a tree made by hand may store none
    const Plane& plane = tree.cut_planes[index];
    extras["plane"] = number_array({plane.normal.x, plane.normal.y, plane.normal.z, plane.offset});
  }
  return tinygltf::Value(std::move(extras));
}

// The scene's extras: who made the tree and its bonds, so a viewer can draw and
// list them without the .shatter file.
tinygltf::Value scene_extras(const MeshTree& tree) {
  tinygltf::Value::Array bonds;
  bonds.reserve(tree.bonds.size());
  for (const Bond& bond : tree.bonds) {
    tinygltf::Value::Object entry;
    entry["first"] = count_value(bond.first);
    entry["second"] = count_value(bond.second);
    entry["cut_node"] = count_value(bond.cut_node);
    entry["area"] = tinygltf::Value(bond.area);
    entry["centroid"] = vec3_value(bond.centroid);
    entry["normal"] = vec3_value(bond.normal);
    bonds.emplace_back(std::move(entry));
  }
  tinygltf::Value::Object extras;
  extras["shatter_version"] = tinygltf::Value(tree.shatter_version);
  extras["leaves"] = count_value(tree.leaf_count());
  extras["bonds"] = tinygltf::Value(std::move(bonds));
  return tinygltf::Value(std::move(extras));
}

std::string gltf_node_name(const MeshTreeNode& node, NodeIndex index) {
  return node.is_leaf() ? "leaf " + std::to_string(node.first_leaf) : "node " + std::to_string(index);
}

}  // namespace

std::string encode_glb(const MeshTree& tree, std::span<const NodeIndex> selection) {
  std::vector<bool> selected(tree.nodes.size(), false);
  for (NodeIndex index : selection) {
    require_node_index(tree, index);
    selected[index] = true;
  }

  tinygltf::Model model;
  model.asset.version = "2.0";
  model.asset.generator = "shatter";
  model.materials.push_back(material_named(glb_exterior_material, {0.8, 0.8, 0.78, 1.0}, 0.6));
  model.materials.push_back(material_named(glb_interior_material, {0.78, 0.36, 0.24, 1.0}, 0.9));

  GltfWriter writer(model);
  model.nodes.resize(tree.nodes.size());
  for (NodeIndex i = 0; i < tree.nodes.size(); ++i) {
    const MeshTreeNode& node = tree.nodes[i];
    tinygltf::Node& gltf_node = model.nodes[i];
    gltf_node.name = gltf_node_name(node, i);
    gltf_node.extras = extras_of(tree, i);
    for (NodeIndex child : node.children) {
      require_node_index(tree, child);
      gltf_node.children.push_back(static_cast<int>(child));
    }
    if (selected[i]) {
      check_mesh_shape(node.mesh, i);
      gltf_node.mesh = writer.add_mesh(node.mesh, export_normals(tree, i), gltf_node.name);
    }
  }

  tinygltf::Scene scene;
  scene.name = "mesh tree";
  scene.extras = scene_extras(tree);
  if (!tree.nodes.empty()) scene.nodes.push_back(0);
  model.scenes.push_back(std::move(scene));
  model.defaultScene = 0;
  // A buffer without data is invalid glTF (byteLength >= 1): drop it when no
  // node was selected.
  if (model.buffers[0].data.empty()) model.buffers.clear();

  std::ostringstream stream;
  tinygltf::TinyGLTF gltf;
  if (!gltf.WriteGltfSceneToStream(&model, stream, false, true)) {
    throw std::runtime_error("tinygltf could not serialise the GLB");
  }
  return std::move(stream).str();
}

void write_glb(const std::filesystem::path& path, const MeshTree& tree, std::span<const NodeIndex> selection) {
  const std::string bytes = encode_glb(tree, selection);
  const std::filesystem::path folder = path.parent_path();
  if (!folder.empty()) {
    std::error_code error;
    std::filesystem::create_directories(folder, error);
    if (error) throw IoError("cannot create output folder " + folder.string() + ": " + error.message());
  }
  write_file_atomically(path, bytes);
}

}  // namespace shatter
