#include "shatter/runtime/recording.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <map>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "shatter/formats/export.hpp"

#include "shatter/formats/tinygltf.hpp"

namespace shatter::runtime {

Recording::Recording(std::uint32_t every_steps) : every_steps_(every_steps) {
  if (every_steps == 0) throw std::invalid_argument("a recording keeps every k-th step, k >= 1");
}

void Recording::capture(const World& world) {
  const std::uint64_t step = world.step_count();
  if (captured_ && step <= last_step_) {
    throw std::invalid_argument("step " + std::to_string(step) + " is already recorded or earlier than the last");
  }
  captured_ = true;
  last_step_ = step;
  const std::span<const BodyRecord> bodies = world.bodies();
  samples_.resize(bodies.size());
  const bool regular = step % every_steps_ == 0;
  for (BodyId body : world.live_bodies()) {
    if (regular || samples_[body].empty()) samples_[body].push_back({step, world.object_transform(body)});
  }
}

namespace {

// A UV sphere of radius 1 with smooth normals: the projectile's look.
Mesh unit_sphere() {
  constexpr int slices = 24, stacks = 12;
  Mesh mesh;
  mesh.positions.push_back({0, 1, 0});
  for (int i = 1; i < stacks; ++i) {
    const double polar = std::numbers::pi * i / stacks;
    for (int j = 0; j < slices; ++j) {
      const double azimuth = 2 * std::numbers::pi * j / slices;
      mesh.positions.push_back(
          {std::sin(polar) * std::cos(azimuth), std::cos(polar), std::sin(polar) * std::sin(azimuth)});
    }
  }
  mesh.positions.push_back({0, -1, 0});
  const auto ring = [](int i, int j) { return static_cast<VertexIndex>(1 + (i - 1) * slices + (j % slices)); };
  const auto bottom = static_cast<VertexIndex>(mesh.positions.size() - 1);
  for (int j = 0; j < slices; ++j) {
    mesh.triangles.push_back({0, ring(1, j + 1), ring(1, j)});
    for (int i = 1; i + 1 < stacks; ++i) {
      mesh.triangles.push_back({ring(i, j), ring(i, j + 1), ring(i + 1, j)});
      mesh.triangles.push_back({ring(i, j + 1), ring(i + 1, j + 1), ring(i + 1, j)});
    }
    mesh.triangles.push_back({ring(stacks - 1, j), ring(stacks - 1, j + 1), bottom});
  }
  mesh.surfaces.assign(mesh.triangles.size(), original_surface);
  for (const Triangle& t : mesh.triangles) {
    for (VertexIndex v : t) mesh.corners.normals.push_back(mesh.positions[v]);
  }
  return mesh;
}

// A slab [-h, h] x [-t, 0] x [-h, h], t = h / 100: the floor's look.
Mesh floor_slab(double h) {
  const double t = h / 100;
  Mesh mesh;
  for (int i = 0; i < 8; ++i) mesh.positions.push_back({i & 1 ? h : -h, i & 2 ? 0 : -t, i & 4 ? h : -h});
  mesh.triangles = {{0, 1, 5}, {0, 5, 4}, {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2},
                    {1, 3, 7}, {1, 7, 5}, {0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}};
  mesh.surfaces.assign(mesh.triangles.size(), original_surface);
  return mesh;
}

// A tree of one node holding `mesh`, so encode_glb draws it as it draws fragments.
MeshTree single_node_tree(Mesh mesh) {
  MeshTree tree;
  tree.nodes.resize(1);
  tree.cut_planes.resize(1);  // a leaf's plane: unused, zero
  tree.nodes[0].mesh = std::move(mesh);
  tree.nodes[0].leaf_count = 1;
  tree.leaf_nodes = {0};
  return tree;
}

tinygltf::Model decode(const std::string& bytes) {
  tinygltf::Model model;
  tinygltf::TinyGLTF loader;
  std::string error, warning;
  if (!loader.LoadBinaryFromMemory(&model, &error, &warning, reinterpret_cast<const unsigned char*>(bytes.data()),
                                   static_cast<unsigned int>(bytes.size()))) {
    throw std::runtime_error("tinygltf could not read back an exported GLB: " + error);
  }
  return model;
}

constexpr std::size_t max_binary_chunk = std::size_t{0xF0000000u};

class ModelBuilder {
 public:
  ModelBuilder() {
    model_.asset.version = "2.0";
    model_.asset.generator = "shatter simulate";
    model_.buffers.resize(1);
  }

  // Appends the meshes of `source` (a GLB encode_glb wrote) with their data;
  // materials are shared by name. Returns the index its mesh 0 got.
  int append_meshes(const tinygltf::Model& source) {
    std::vector<int> material_of(source.materials.size());
    for (std::size_t m = 0; m < source.materials.size(); ++m) {
      int found = -1;
      for (std::size_t t = 0; t < model_.materials.size() && found < 0; ++t) {
        if (model_.materials[t].name == source.materials[m].name) found = static_cast<int>(t);
      }
      if (found < 0) {
        found = static_cast<int>(model_.materials.size());
        model_.materials.push_back(source.materials[m]);
      }
      material_of[m] = found;
    }
    std::vector<unsigned char>& data = model_.buffers[0].data;
    pad();
    const std::size_t base = data.size();
    if (!source.buffers.empty()) {
      check_room(source.buffers[0].data.size());
      data.insert(data.end(), source.buffers[0].data.begin(), source.buffers[0].data.end());
    }
    const int view_base = static_cast<int>(model_.bufferViews.size());
    for (tinygltf::BufferView view : source.bufferViews) {
      view.buffer = 0;
      view.byteOffset += base;
      model_.bufferViews.push_back(std::move(view));
    }
    const int accessor_base = static_cast<int>(model_.accessors.size());
    for (tinygltf::Accessor accessor : source.accessors) {
      accessor.bufferView += view_base;
      model_.accessors.push_back(std::move(accessor));
    }
    const int mesh_base = static_cast<int>(model_.meshes.size());
    for (tinygltf::Mesh mesh : source.meshes) {
      for (tinygltf::Primitive& primitive : mesh.primitives) {
        for (auto& attribute : primitive.attributes) attribute.second += accessor_base;
        if (primitive.indices >= 0) primitive.indices += accessor_base;
        if (primitive.material >= 0) primitive.material = material_of[static_cast<std::size_t>(primitive.material)];
      }
      model_.meshes.push_back(std::move(mesh));
    }
    return mesh_base;
  }

  // An accessor over floats, `components` per element; with_bounds adds
  // min and max (animation inputs need them).
  int add_floats(const std::vector<float>& values, int type, std::size_t components, bool with_bounds) {
    pad();
    std::vector<unsigned char>& data = model_.buffers[0].data;
    const std::size_t bytes = values.size() * sizeof(float);
    check_room(bytes);
    tinygltf::BufferView view;
    view.buffer = 0;
    view.byteOffset = data.size();
    view.byteLength = bytes;
    data.resize(data.size() + bytes);
    std::memcpy(data.data() + view.byteOffset, values.data(), bytes);
    model_.bufferViews.push_back(std::move(view));
    tinygltf::Accessor accessor;
    accessor.bufferView = static_cast<int>(model_.bufferViews.size() - 1);
    accessor.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
    accessor.type = type;
    accessor.count = values.size() / components;
    if (with_bounds) {
      accessor.minValues.assign(components, std::numeric_limits<double>::infinity());
      accessor.maxValues.assign(components, -std::numeric_limits<double>::infinity());
      for (std::size_t i = 0; i < values.size(); ++i) {
        accessor.minValues[i % components] = std::min(accessor.minValues[i % components], double{values[i]});
        accessor.maxValues[i % components] = std::max(accessor.maxValues[i % components], double{values[i]});
      }
    }
    model_.accessors.push_back(std::move(accessor));
    return static_cast<int>(model_.accessors.size() - 1);
  }

  tinygltf::Model& model() { return model_; }

 private:
  void pad() {
    std::vector<unsigned char>& data = model_.buffers[0].data;
    while (data.size() % 4 != 0) data.push_back(0);
  }
  void check_room(std::size_t bytes) const {
    if (model_.buffers[0].data.size() + bytes > max_binary_chunk) {
      throw std::length_error("the recording would exceed glTF binary's 4 GiB limit; record fewer steps");
    }
  }

  tinygltf::Model model_;
};

// A pose with a non-finite number is no state of a valid simulation; glTF cannot
// hold it either, so the export stops rather than write a file readers reject.
std::vector<double> translation_of(const RigidTransform& t) {
  if (!std::isfinite(t.translation.x) || !std::isfinite(t.translation.y) || !std::isfinite(t.translation.z)) {
    throw std::runtime_error("recording: a body's position is not finite");
  }
  return {t.translation.x, t.translation.y, t.translation.z};
}

// glTF wants unit rotation quaternions with every component in [-1, 1], and the
// Khronos validator checks both. Bullet's are unit only up to rounding (a w of
// 1 + 2^-52 was written once, out of range), so each one written is renormalized
// and clamped. Components in glTF order: x, y, z, w.
std::array<double, 4> gltf_rotation(const Quaternion& q) {
  const double length = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
  if (!std::isfinite(length) || !(length > 0)) {
    throw std::runtime_error("recording: a body's rotation is not a finite non-zero quaternion");
  }
  std::array<double, 4> xyzw{q.x / length, q.y / length, q.z / length, q.w / length};
  for (double& component : xyzw) component = std::clamp(component, -1.0, 1.0);
  return xyzw;
}

tinygltf::Value body_extras(const BodyRecord& record, BodyId id, double time_step) {
  tinygltf::Value::Object extras;
  extras["body"] = tinygltf::Value(static_cast<int>(id));
  extras["kind"] = tinygltf::Value(std::string(record.kind == BodyKind::cluster ? "cluster" : "sphere"));
  if (record.kind == BodyKind::cluster) {
    extras["object"] = tinygltf::Value(static_cast<int>(record.object));
    extras["leaves"] = tinygltf::Value(static_cast<int>(record.leaf_count));
    if (record.parent != no_body) extras["parent"] = tinygltf::Value(static_cast<int>(record.parent));
  }
  extras["mass"] = tinygltf::Value(record.mass.mass);
  extras["birth_time"] = tinygltf::Value(static_cast<double>(record.birth_step) * time_step);
  if (record.death_step != std::numeric_limits<std::uint64_t>::max()) {
    extras["death_time"] = tinygltf::Value(static_cast<double>(record.death_step) * time_step);
  }
  return tinygltf::Value(std::move(extras));
}

}  // namespace

std::string Recording::encode_glb(const World& world, double floor_half_size) const {
  if (!captured_) throw std::invalid_argument("nothing was recorded");
  if (!(floor_half_size > 0) || !std::isfinite(floor_half_size)) {
    throw std::invalid_argument("the floor's half size must be positive and finite (m)");
  }
  const std::span<const BodyRecord> bodies = world.bodies();
  const double dt = world.options().time_step;
  ModelBuilder builder;
  constexpr std::uint64_t alive = std::numeric_limits<std::uint64_t>::max();
  // A body gets a node when it has a pose to show: a capture, or its death. One
  // made and broken within one state (apply_impact twice) was never seen.
  const auto drawn = [&](BodyId b) {
    const BodyRecord& record = bodies[b];
    return b < samples_.size() && record.death_step != record.birth_step &&
           (!samples_[b].empty() || record.death_step != alive);
  };

  // The tree nodes any recorded cluster uses, per distinct set of shapes, in
  // the order objects were added: each set's meshes are exported once.
  std::vector<const BreakableShapes*> shape_sets;
  std::vector<std::vector<bool>> used;
  std::vector<std::size_t> set_of_object(world.object_count());
  for (ObjectId o = 0; o < world.object_count(); ++o) {
    const BreakableShapes* shapes = &world.shapes_of(o);
    std::size_t set = 0;
    while (set < shape_sets.size() && shape_sets[set] != shapes) ++set;
    if (set == shape_sets.size()) {
      shape_sets.push_back(shapes);
      used.emplace_back(shapes->tree().nodes.size(), false);
    }
    set_of_object[o] = set;
  }
  for (BodyId b = 0; b < bodies.size(); ++b) {
    if (bodies[b].kind != BodyKind::cluster || !drawn(b)) continue;
    for (NodeIndex node : bodies[b].cover) used[set_of_object[bodies[b].object]][node] = true;
  }
  std::vector<std::map<NodeIndex, int>> mesh_of_node(shape_sets.size());
  for (std::size_t set = 0; set < shape_sets.size(); ++set) {
    std::vector<NodeIndex> selection;
    for (NodeIndex node = 0; node < used[set].size(); ++node) {
      if (used[set][node]) selection.push_back(node);
    }
    if (selection.empty()) continue;
    const int first = builder.append_meshes(decode(shatter::encode_glb(shape_sets[set]->tree(), selection)));
    // encode_glb gives the selected nodes meshes in node order (none is empty: a
    // valid node has triangles).
    for (std::size_t i = 0; i < selection.size(); ++i) mesh_of_node[set][selection[i]] = first + static_cast<int>(i);
  }
  int sphere_mesh = -1;  // only when a sphere was recorded: glTF frowns on unused meshes
  for (BodyId b = 0; b < bodies.size(); ++b) {
    if (bodies[b].kind == BodyKind::sphere && drawn(b) && sphere_mesh < 0) {
      sphere_mesh = builder.append_meshes(
          decode(shatter::encode_glb(single_node_tree(unit_sphere()), std::vector<NodeIndex>{0})));
    }
  }
  const int floor_mesh = builder.append_meshes(
      decode(shatter::encode_glb(single_node_tree(floor_slab(floor_half_size)), std::vector<NodeIndex>{0})));

  tinygltf::Model& model = builder.model();
  tinygltf::Scene scene;
  scene.name = "simulation";
  tinygltf::Node floor;
  floor.name = "floor";
  floor.mesh = floor_mesh;
  model.nodes.push_back(std::move(floor));
  scene.nodes.push_back(0);

  tinygltf::Animation animation;
  animation.name = "simulation";
  const auto add_channel = [&](int node, const char* path, int input, int output, const char* interpolation) {
    tinygltf::AnimationSampler sampler;
    sampler.input = input;
    sampler.output = output;
    sampler.interpolation = interpolation;
    animation.samplers.push_back(std::move(sampler));
    tinygltf::AnimationChannel channel;
    channel.sampler = static_cast<int>(animation.samplers.size() - 1);
    channel.target_node = node;
    channel.target_path = path;
    animation.channels.push_back(std::move(channel));
  };

  for (BodyId b = 0; b < bodies.size(); ++b) {
    if (!drawn(b)) continue;
    const BodyRecord& record = bodies[b];
    std::vector<Sample> keys = samples_[b];
    if (record.death_step != alive) keys.push_back({record.death_step, record.death_transform});

    const int node_index = static_cast<int>(model.nodes.size());
    tinygltf::Node node;
    node.name = (record.kind == BodyKind::cluster ? "cluster " : "sphere ") + std::to_string(b);
    node.extras = body_extras(record, b, dt);
    node.translation = translation_of(keys.front().pose);
    const std::array<double, 4> q0 = gltf_rotation(keys.front().pose.rotation);
    node.rotation = {q0.begin(), q0.end()};
    node.scale = record.birth_step == 0 ? std::vector<double>{1, 1, 1} : std::vector<double>{0, 0, 0};
    model.nodes.push_back(std::move(node));
    scene.nodes.push_back(node_index);
    if (record.kind == BodyKind::cluster) {
      for (NodeIndex tree_node : record.cover) {
        tinygltf::Node part;
        part.name = "tree node " + std::to_string(tree_node);
        part.mesh = mesh_of_node[set_of_object[record.object]].at(tree_node);
        model.nodes[static_cast<std::size_t>(node_index)].children.push_back(static_cast<int>(model.nodes.size()));
        model.nodes.push_back(std::move(part));
      }
    } else {
      tinygltf::Node ball;
      ball.name = "sphere mesh";
      ball.mesh = sphere_mesh;
      ball.scale = {record.radius, record.radius, record.radius};
      model.nodes[static_cast<std::size_t>(node_index)].children.push_back(static_cast<int>(model.nodes.size()));
      model.nodes.push_back(std::move(ball));
    }

    std::vector<float> times, translations, rotations;
    Quaternion previous = keys.front().pose.rotation;
    for (const Sample& key : keys) {
      times.push_back(static_cast<float>(static_cast<double>(key.step) * dt));
      for (double v : translation_of(key.pose)) translations.push_back(static_cast<float>(v));
      // q and -q are one rotation; keep neighbours in one hemisphere so every
      // player interpolates the short way.
      Quaternion q = key.pose.rotation;
      if (q.w * previous.w + q.x * previous.x + q.y * previous.y + q.z * previous.z < 0) q = {-q.w, -q.x, -q.y, -q.z};
      previous = q;
      for (double v : gltf_rotation(q)) rotations.push_back(static_cast<float>(v));
    }
    const int time_accessor = builder.add_floats(times, TINYGLTF_TYPE_SCALAR, 1, true);
    add_channel(node_index, "translation", time_accessor,
                builder.add_floats(translations, TINYGLTF_TYPE_VEC3, 3, false), "LINEAR");
    add_channel(node_index, "rotation", time_accessor, builder.add_floats(rotations, TINYGLTF_TYPE_VEC4, 4, false),
                "LINEAR");

    std::vector<float> shown_times, shown;
    if (record.birth_step > 0) {
      shown_times.push_back(0);
      shown.insert(shown.end(), {0, 0, 0});
    }
    shown_times.push_back(static_cast<float>(static_cast<double>(record.birth_step) * dt));
    shown.insert(shown.end(), {1, 1, 1});
    if (record.death_step != alive) {
      shown_times.push_back(static_cast<float>(static_cast<double>(record.death_step) * dt));
      shown.insert(shown.end(), {0, 0, 0});
    }
    const int shown_input = builder.add_floats(shown_times, TINYGLTF_TYPE_SCALAR, 1, true);
    add_channel(node_index, "scale", shown_input, builder.add_floats(shown, TINYGLTF_TYPE_VEC3, 3, false), "STEP");
  }
  model.scenes.push_back(std::move(scene));
  model.defaultScene = 0;
  if (!animation.channels.empty()) model.animations.push_back(std::move(animation));

  std::ostringstream stream;
  tinygltf::TinyGLTF writer;
  if (!writer.WriteGltfSceneToStream(&model, stream, false, true)) {
    throw std::runtime_error("tinygltf could not serialise the recording");
  }
  return std::move(stream).str();
}

}  // namespace shatter::runtime
