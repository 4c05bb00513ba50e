// `shatter view TREE --original MESH` (issue 21): the server's answer about the
// original input (cli/view_original.cpp, compiled in here), checked over every
// corpus mesh against the library: the elements it highlights are as many as
// validate_mesh counts, the drawing data reads back as the file's doubles, and
// the bounding-box check accepts each mesh with its own repaired root and
// refuses a root one ulp outside. The page that draws it is tested in
// viewer/test/browser.mjs (case "original").

#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "shatter/generators/corpus.hpp"
#include "shatter/kernel/error.hpp"
#include "shatter/kernel/io.hpp"
#include "shatter/kernel/repair.hpp"
#include "shatter/kernel/validate.hpp"
#include "support/scratch.hpp"
#include "view_original.hpp"

using namespace shatter;
using namespace shatter::cli;
using namespace shatter::test;
namespace fs = std::filesystem;
using json = nlohmann::ordered_json;

namespace {

// A file in this test's own scratch folder (no shatter binary is run here).
fs::path scratch(const std::string& name) {
  return process_scratch_folder("test_view_original") / name;
}

std::vector<fs::path> every_corpus_mesh() {
  std::vector<fs::path> all = valid_meshes();
  for (const std::vector<fs::path>& more : {bad_meshes(), self_intersecting_meshes()}) {
    all.insert(all.end(), more.begin(), more.end());
  }
  return all;
}

std::optional<Mesh> readable(const fs::path& path) {
  try {
    return read_mesh(path);
  } catch (const std::exception&) {
    return std::nullopt;  // refused by the reader: --original refuses it too (checked below)
  }
}

std::size_t count_of(const ValidationReport& report, DefectKind kind) {
  const Defect* defect = report.find(kind);
  return defect ? defect->count : 0;
}

std::string refusal(const fs::path& path, const Mesh& root, const RepairReport& repair) {
  try {
    read_original_input(path.string(), root, repair);
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("the original's highlighted elements are validate_mesh's defects, over the whole corpus") {
  std::size_t shown = 0;
  for (const fs::path& path : every_corpus_mesh()) {
    CAPTURE(path.string());
    const std::optional<Mesh> mesh = readable(path);
    if (!mesh) {
      CHECK(refusal(path, Mesh{}, RepairReport{}).rfind("--original " + path.string() + ": ", 0) == 0);
      continue;
    }
    Mesh root = *mesh;
    const RepairReport repair = repair_mesh(root);
    if (root.positions.empty()) continue;  // nothing left to build a tree from
    const OriginalInput original = read_original_input(path.string(), root, repair);
    ++shown;
    const ValidationReport full = validate_mesh(*mesh);
    CHECK(original.boundary_edges.size() == count_of(full, DefectKind::boundary_edge));
    CHECK(original.non_manifold_edges.size() == count_of(full, DefectKind::non_manifold_edge));
    if (full.self_intersections_checked) {
      // validate_mesh also counts, as intersecting, the pairs of triangles of two fans that touch at a
      // non-manifold vertex (it tests one copy of the vertex per fan); the page marks that vertex's defect by
      // name only, and highlights the pairs that cross.
      if (count_of(full, DefectKind::non_manifold_vertex) == 0) {
        CHECK(original.self_intersecting_pairs == count_of(full, DefectKind::self_intersection));
      } else {
        CHECK(original.self_intersecting_pairs <= count_of(full, DefectKind::self_intersection));
      }
    }
    CHECK(original.self_intersecting_triangles.size() <= 2 * original.self_intersecting_pairs);
    CHECK((original.self_intersecting_pairs == 0) == original.self_intersecting_triangles.empty());

    // The answer, as the page parses it: the file's own doubles and triangles, the repair's lines.
    const json answer = json::parse(original_json(original, repair).dump());
    REQUIRE(answer["positions"].size() == 3 * mesh->positions.size());
    bool same_doubles = true;
    for (std::size_t v = 0; v < mesh->positions.size(); ++v) {
      for (int axis = 0; axis < 3; ++axis) {
        same_doubles = same_doubles && answer["positions"][3 * v + axis].get<double>() == mesh->positions[v][axis];
      }
    }
    CHECK(same_doubles);
    REQUIRE(answer["indices"].size() == 3 * mesh->triangles.size());
    CHECK(answer["indices"][answer["indices"].size() - 1].get<VertexIndex>() == mesh->triangles.back()[2]);
    CHECK(answer["boundary_edges"].size() == 2 * original.boundary_edges.size());
    // "valid" exactly when validate_mesh, self-intersection test included, finds nothing.
    CHECK((answer["validation"] == "valid") == full.valid());
    if (repair.empty()) {
      CHECK(answer["repair"].is_null());
    } else {
      REQUIRE(answer["repair"]["changes"].size() == repair.changes.size());
      for (std::size_t i = 0; i < repair.changes.size(); ++i) CHECK(answer["repair"]["changes"][i] == repair.changes[i].text);
      CHECK(answer["repair"]["triangles_after"] == root.triangles.size());
    }
  }
  CHECK(shown >= 20);
}

TEST_CASE("a cube with a hole: its four open edges, one cycle, and the repair that closed it") {
  const fs::path path = mesh_dir() / "bad" / "cube-ouvert.off";
  Mesh root = read_mesh(path);
  const RepairReport repair = repair_mesh(root);
  const OriginalInput original = read_original_input(path.string(), root, repair);
  REQUIRE(original.boundary_edges.size() == 4);
  std::vector<int> degree(original.mesh.positions.size(), 0);
  for (const Edge& edge : original.boundary_edges) {
    CHECK(edge[0] < edge[1]);
    ++degree[edge[0]];
    ++degree[edge[1]];
  }
  for (int d : degree) CHECK((d == 0 || d == 2));  // the rim of the missing face: each of its corners twice
  CHECK(original.non_manifold_edges.empty());
  CHECK(original.self_intersecting_triangles.empty());
  const json answer = original_json(original, repair);
  CHECK(answer["file"] == "cube-ouvert.off");
  CHECK(answer["validation"].get<std::string>().rfind("open mesh: 4 boundary edges", 0) == 0);
  CHECK(answer["repair"]["changes"][0] == "filled 1 hole (4 border edges) with 2 new triangles");
}

TEST_CASE("view --original is refused unless its bounding box holds the root's (equals it without a repair)") {
  const fs::path path = mesh_dir() / "knot1.off";
  const Mesh mesh = read_mesh(path);
  const RepairReport none;
  RepairReport repaired;
  repaired.changes.push_back({RepairKind::filled_holes, 1, "filled 1 hole"});
  CHECK(refusal(path, mesh, none).empty());
  CHECK(refusal(path, mesh, repaired).empty());

  // Every coordinate of every axis pushed one ulp out of the box: refused either way.
  for (int axis = 0; axis < 3; ++axis) {
    for (const double direction : {-std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()}) {
      Mesh moved = mesh;
      std::size_t extreme = 0;
      for (std::size_t v = 0; v < moved.positions.size(); ++v) {
        const double here = moved.positions[v][axis], best = moved.positions[extreme][axis];
        if (direction > 0 ? here > best : here < best) extreme = v;
      }
      Vec3& p = moved.positions[extreme];
      double& coordinate = axis == 0 ? p.x : axis == 1 ? p.y : p.z;
      coordinate = std::nextafter(coordinate, direction);
      CAPTURE(axis, direction);
      CHECK(refusal(path, moved, repaired).find("is not the input of this tree") != std::string::npos);
      CHECK(refusal(path, moved, none).find("is not the input of this tree") != std::string::npos);
    }
  }
  // A root strictly inside (repair dropped a part): fine after a repair, not without one.
  Mesh inside = mesh;
  inside.positions.erase(inside.positions.begin());
  for (Vec3& p : inside.positions) p = {p.x * 0.5, p.y * 0.5, p.z * 0.5};
  CHECK(refusal(path, inside, repaired).empty());
  CHECK(refusal(path, inside, none).find("the tree records no repair") != std::string::npos);
}

TEST_CASE("view --original refuses with one line what it cannot read or draw") {
  const Mesh root = read_mesh(mesh_dir() / "cube.off");
  const fs::path missing = scratch("missing.off");
  CHECK(refusal(missing, root, RepairReport{}).rfind("--original " + missing.string() + ": ", 0) == 0);
  const fs::path nan = scratch("nan.off");
  std::ofstream(nan) << "OFF\n3 1 0\n0 0 0\n1 0 0\nnan 1 0\n3 0 1 2\n";
  const std::string nan_refusal = refusal(nan, root, RepairReport{});
  CHECK(nan_refusal.rfind("--original " + nan.string() + ": ", 0) == 0);
  CHECK(nan_refusal.find('\n') == std::string::npos);
}
