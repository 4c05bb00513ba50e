// GLB exports that every viewer shades (issue 13): every vertex has a unit
// NORMAL; on the original surface it is the input's per-corner normal where the
// mesh has one and the triangle's own flat normal otherwise; on caps it is the
// cut plane's normal pointing out of the fragment, so caps are flat and their
// crease with the surface sharp. Also the extras a viewer reads: each node's
// centroid and triangle counts, and the tree's bonds. Checked on real trees
// (the demo knot, which has no normals, and an ellipsoid given smooth normals).

#include <catch2/catch.hpp>

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "shatter/kernel/io.hpp"
#include "shatter/meshtree/build.hpp"
#include "shatter/formats/export.hpp"
#include "shatter/generators/corpus.hpp"
#include "shatter/generators/solids.hpp"
#include "support/gltf.hpp"

using namespace shatter;
using test::accessor_values;
using test::decode_glb;

namespace {

Vec3 unit_face_normal(const Mesh& mesh, TriangleIndex t) {
  const Triangle& tri = mesh.triangles[t];
  return normalized(cross(mesh.positions[tri[1]] - mesh.positions[tri[0]], mesh.positions[tri[2]] - mesh.positions[tri[0]]));
}

// An ellipsoid with smooth per-corner normals (the gradient of its implicit
// equation at each vertex), as an input carrying normals would have.
Mesh ellipsoid_with_normals() {
  const Vec3 radii{1.0, 0.7, 0.5};
  Mesh mesh = test::ellipsoid({0, 0, 0}, radii, 24, 16);
  mesh.corners.normals.clear();
  for (const Triangle& triangle : mesh.triangles) {
    for (VertexIndex v : triangle) {
      const Vec3 p = mesh.positions[v];
      mesh.corners.normals.push_back(
          normalized({p.x / (radii.x * radii.x), p.y / (radii.y * radii.y), p.z / (radii.z * radii.z)}));
    }
  }
  return mesh;
}

MeshTree tree_of(const Mesh& mesh, std::uint32_t fragments) {
  TreeRecipe recipe;
  recipe.fragments = fragments;
  recipe.seed = 7;
  return build_mesh_tree(mesh, recipe);
}

// Checks every exported vertex normal of every node against what it must be,
// triangle by triangle. Returns how many cap corners were checked.
std::size_t check_normals(const MeshTree& tree) {
  const std::vector<NodeIndex> all = select_nodes(tree, parse_node_selection("all"));
  const tinygltf::Model model = decode_glb(encode_glb(tree, all));
  std::size_t cap_corners = 0;
  for (NodeIndex i = 0; i < tree.nodes.size(); ++i) {
    INFO("node " << i);
    const Mesh& mesh = tree.nodes[i].mesh;
    const tinygltf::Mesh& gltf_mesh = model.meshes.at(static_cast<std::size_t>(model.nodes[i].mesh));
    std::size_t p = 0;
    for (const bool interior : {false, true}) {
      std::vector<TriangleIndex> triangles;
      for (TriangleIndex t = 0; t < mesh.triangle_count(); ++t) {
        if ((mesh.surfaces[t] != original_surface) == interior) triangles.push_back(t);
      }
      if (triangles.empty()) continue;
      const tinygltf::Primitive& primitive = gltf_mesh.primitives.at(p++);
      REQUIRE(primitive.attributes.count("NORMAL") == 1);
      const std::vector<float> normals = accessor_values<float>(model, primitive.attributes.at("NORMAL"), 3);
      const std::vector<std::uint32_t> indices = accessor_values<std::uint32_t>(model, primitive.indices, 1);
      REQUIRE(indices.size() == 3 * triangles.size());
      for (std::size_t k = 0; k < triangles.size(); ++k) {
        const TriangleIndex t = triangles[k];
        for (std::size_t c = 0; c < 3; ++c) {
          const std::size_t v = indices[3 * k + c];
          const Vec3 n{normals[3 * v], normals[3 * v + 1], normals[3 * v + 2]};
          CHECK(std::abs(norm(n) - 1) < 1e-6);
          if (interior) {
            // Flat: the cut plane's normal, exactly (as floats) ...
            const Vec3 plane = normalized(tree.cut_planes[mesh.surfaces[t] - 1].normal);
            CHECK(std::abs(std::abs(dot(n, plane)) - 1) < 1e-6);
            // ... pointing the way the cap triangle faces: out of the fragment.
            CHECK(dot(n, unit_face_normal(mesh, t)) > 0.999);
            ++cap_corners;
          } else if (mesh.corners.has_normals()) {
            const Vec3 input = mesh.corners.normals[3 * t + c];
            CHECK(n.x == static_cast<float>(input.x));
            CHECK(n.y == static_cast<float>(input.y));
            CHECK(n.z == static_cast<float>(input.z));
          } else {
            CHECK(dot(n, unit_face_normal(mesh, t)) > 1 - 1e-6);
          }
        }
      }
    }
  }
  return cap_corners;
}

}  // namespace

TEST_CASE("GLB normals: flat per face on a mesh without normals, flat and outward on caps (knot1)") {
  const Mesh knot = read_mesh(test::mesh_dir() / "knot1.off");
  REQUIRE_FALSE(knot.corners.has_normals());
  const MeshTree tree = tree_of(knot, 12);
  REQUIRE(tree.leaf_count() >= 12);
  CHECK(check_normals(tree) > 0);
}

TEST_CASE("GLB normals: the input's where it has them, the plane's on caps (smooth ellipsoid)") {
  const MeshTree tree = tree_of(ellipsoid_with_normals(), 9);
  REQUIRE(tree.nodes[0].mesh->corners.has_normals());
  CHECK(check_normals(tree) > 0);
}

TEST_CASE("GLB normals: a cap never shares a vertex with the surface, so the crease stays sharp") {
  // Caps and surface are separate primitives; within the surface, flat shading
  // splits a vertex wherever its triangles' normals differ: a knot leaf has more
  // glTF vertices than welded ones.
  const MeshTree tree = tree_of(read_mesh(test::mesh_dir() / "knot1.off"), 4);
  const tinygltf::Model model = decode_glb(encode_glb(tree, tree.leaf_nodes));
  for (NodeIndex node : tree.leaf_nodes) {
    const tinygltf::Mesh& mesh = model.meshes.at(static_cast<std::size_t>(model.nodes[node].mesh));
    REQUIRE(mesh.primitives.size() == 2);
    CHECK(mesh.primitives[0].material == 0);
    CHECK(mesh.primitives[1].material == 1);
    std::size_t vertices = 0;
    for (const tinygltf::Primitive& primitive : mesh.primitives) {
      vertices += model.accessors.at(static_cast<std::size_t>(primitive.attributes.at("POSITION"))).count;
    }
    CHECK(vertices > tree.nodes[node].mesh->positions.size());
  }
}

TEST_CASE("GLB extras: every node's centroid and triangle counts, the tree's bonds in the scene") {
  const MeshTree tree = tree_of(read_mesh(test::mesh_dir() / "knot1.off"), 8);
  REQUIRE_FALSE(tree.bonds.empty());
  const tinygltf::Model model = decode_glb(encode_glb(tree, tree.leaf_nodes));
  for (NodeIndex i = 0; i < tree.nodes.size(); ++i) {
    const MeshTreeNode& node = tree.nodes[i];
    const tinygltf::Value& extras = model.nodes[i].extras;
    const tinygltf::Value& centroid = extras.Get("centroid");
    REQUIRE(centroid.ArrayLen() == 3);
    CHECK(centroid.Get(0).GetNumberAsDouble() == node.mass.centroid.x);
    CHECK(centroid.Get(1).GetNumberAsDouble() == node.mass.centroid.y);
    CHECK(centroid.Get(2).GetNumberAsDouble() == node.mass.centroid.z);
    CHECK(extras.Get("triangles").GetNumberAsInt() == static_cast<int>(node.mesh->triangle_count()));
    std::size_t caps = 0;
    for (SurfaceId s : node.mesh->surfaces) caps += s != original_surface;
    CHECK(extras.Get("cap_triangles").GetNumberAsInt() == static_cast<int>(caps));
  }
  const tinygltf::Value& scene = model.scenes.at(0).extras;
  CHECK(scene.Get("shatter_version").Get<std::string>() == tree.shatter_version);
  CHECK(scene.Get("leaves").GetNumberAsInt() == static_cast<int>(tree.leaf_count()));
  const tinygltf::Value& bonds = scene.Get("bonds");
  REQUIRE(bonds.ArrayLen() == tree.bonds.size());
  for (std::size_t b = 0; b < tree.bonds.size(); ++b) {
    const Bond& bond = tree.bonds[b];
    const tinygltf::Value& entry = bonds.Get(static_cast<int>(b));
    CHECK(entry.Get("first").GetNumberAsInt() == static_cast<int>(bond.first));
    CHECK(entry.Get("second").GetNumberAsInt() == static_cast<int>(bond.second));
    CHECK(entry.Get("cut_node").GetNumberAsInt() == static_cast<int>(bond.cut_node));
    CHECK(entry.Get("area").GetNumberAsDouble() == bond.area);
    CHECK(entry.Get("centroid").Get(2).GetNumberAsDouble() == bond.centroid.z);
    CHECK(entry.Get("normal").Get(0).GetNumberAsDouble() == bond.normal.x);
  }
}
