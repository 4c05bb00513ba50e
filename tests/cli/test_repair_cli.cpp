// `shatter validate|slice|fracture --repair` end to end (the library's repair_mesh:
// tests/kernel/test_repair.cpp): changes printed one line each, repaired meshes
// written only when valid, what repair cannot fix refused after saying what it did.

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <string>

#include "shatter/generators/solids.hpp"
#include "shatter/kernel/io.hpp"
#include "support/checks.hpp"
#include "shatter/generators/corpus.hpp"
#include "support/run_shatter.hpp"

using namespace shatter;
using namespace shatter::test;
namespace fs = std::filesystem;

namespace {

fs::path bad(const std::string& name) { return mesh_dir() / "bad" / name; }
std::string last_line(const std::string& text) {
  const std::size_t end = text.find_last_not_of('\n');
  const std::size_t start = text.rfind('\n', end);
  return text.substr(start == std::string::npos ? 0 : start + 1, end - (start == std::string::npos ? 0 : start + 1) + 1);
}

}  // namespace

TEST_CASE("validate --repair prints the changes and exits 0 on a repaired mesh", "[repair][cli]") {
  const fs::path out = scratch("cube-closed.off");
  const Run run = run_shatter("validate " + quoted(bad("cube-ouvert.off")) + " --repair --out " + quoted(out));
  CHECK(run.exit_code == 0);
  CHECK(run.err == "repair: filled 1 hole (4 border edges) with 2 new triangles\n");
  CHECK(run.out.find("valid closed oriented 2-manifold") != std::string::npos);
  const Mesh written = read_mesh(out);
  CHECK(solid_problem(written).empty());
  CHECK(exact_six_volume(written) == 48);

  // Without --repair the same file is refused, and nothing is ever written.
  const Run plain = run_shatter("validate " + quoted(bad("cube-ouvert.off")));
  CHECK(plain.exit_code == 3);
  CHECK(plain.err.find("repair") == std::string::npos);
}

TEST_CASE("validate --repair refuses what repair cannot fix, after saying what it did", "[repair][cli]") {
  const fs::path out = scratch("never.off");
  const Run run = run_shatter("validate " + quoted(bad("degtri_sliding.off")) + " --repair --out " + quoted(out));
  CHECK(run.exit_code == 3);
  CHECK(run.err.rfind("repair: ", 0) == 0);
  CHECK(last_line(run.err).rfind("error: invalid mesh ", 0) == 0);
  // All flat (CGAL's degtri_sliding.off): repair removes it whole, as a piece
  // that encloses no volume, and the refusal says so.
  CHECK(run.err.find("repair: removed 8 triangles in 1 flat piece") != std::string::npos);
  CHECK(last_line(run.err).find("after --repair: encloses no volume: every piece of it is flat") != std::string::npos);
  CHECK_FALSE(fs::exists(out));
}

TEST_CASE("validate --repair on a valid mesh says no change, and --json lists changes", "[repair][cli]") {
  const Run valid = run_shatter("validate " + quoted(mesh_dir() / "cube.off") + " --repair");
  CHECK(valid.exit_code == 0);
  CHECK(valid.err.find("no change") != std::string::npos);

  const Run json_run = run_shatter("validate " + quoted(bad("tetrahedron.off")) + " --repair --json");
  CHECK(json_run.exit_code == 0);
  const auto out = nlohmann::json::parse(json_run.out);
  CHECK(out["valid"] == true);
  REQUIRE(out["repair"].size() == 1);
  CHECK(out["repair"][0]["change"] == "reversed_triangles");
  CHECK(out["repair"][0]["count"] == 4);

  // --out is for the repaired mesh only.
  const Run usage = run_shatter("validate " + quoted(mesh_dir() / "cube.off") + " --out " + quoted(scratch("x.off")));
  CHECK(usage.exit_code == 2);
}

TEST_CASE("slice and fracture --repair proceed with the repaired mesh", "[repair][cli]") {
  const fs::path pieces = scratch("pieces");
  const Run refused = run_shatter("slice " + quoted(bad("tet-shuffled.off")) + " --plane 0,0,1,-0.25 --out " +
                                  quoted(pieces));
  CHECK(refused.exit_code == 3);
  const Run slice = run_shatter("slice " + quoted(bad("tet-shuffled.off")) + " --plane 0,0,1,-0.25 --out " +
                                quoted(pieces) + " --repair");
  CHECK(slice.exit_code == 0);
  CHECK(slice.err.find("repair: reversed") != std::string::npos);
  CHECK(fs::exists(pieces / "below-0.off"));
  CHECK(fs::exists(pieces / "above-0.off"));

  const fs::path tree = scratch("tree.shatter");
  const Run fracture = run_shatter("fracture " + quoted(bad("cube-ouvert.off")) + " --fragments 4 --out " +
                                   quoted(tree) + " --repair --json");
  CHECK(fracture.exit_code == 0);
  CHECK(fracture.err.find("repair: filled 1 hole") != std::string::npos);
  const auto out = nlohmann::json::parse(fracture.out);
  CHECK(out["repair"][0]["change"] == "filled_holes");
  CHECK(out["leaves"].get<int>() >= 4);

  // The tree says its root is the repaired input, and info reads that back.
  const auto info = nlohmann::json::parse(run_shatter("info --json " + quoted(tree)).out);
  REQUIRE(info["input_repair"].is_object());
  CHECK(info["input_repair"]["repair"] == out["repair"]);
  CHECK(info["input_repair"]["triangles_after"].get<int>() > info["input_repair"]["triangles_before"].get<int>());
  CHECK(run_shatter("info " + quoted(tree)).out.find("input repaired before the build") != std::string::npos);
  const fs::path as_read = scratch("as-read.shatter");
  REQUIRE(run_shatter("fracture " + quoted(mesh_dir() / "cube.off") + " --fragments 4 --repair --out " + quoted(as_read)).exit_code == 0);
  CHECK(nlohmann::json::parse(run_shatter("info --json " + quoted(as_read)).out)["input_repair"].is_null());

  // The stray flat triangle through the tetrahedron is removed: it encloses nothing.
  const Run stray = run_shatter("fracture " + quoted(bad("tetra_intersected_by_triangle.off")) +
                                " --fragments 2 --out " + quoted(scratch("tetra.shatter")) + " --repair");
  CHECK(stray.exit_code == 0);
  CHECK(stray.err.find("repair: removed 1 triangle in 1 flat piece") != std::string::npos);

}

TEST_CASE("validate --repair separates two cubes sharing an edge, says so, and --json names it", "[repair][cli]") {
  const fs::path in = scratch("cubes-sharing-an-edge.off"), out = scratch("cubes-apart.off");
  write_mesh(merge({box({0, 0, 0}, {1, 1, 1}), box({1, 1, 0}, {2, 2, 1})}), in, MeshFormat::off);
  const Run refused = run_shatter("validate " + quoted(in));
  CHECK(refused.exit_code == 3);

  const Run run = run_shatter("validate " + quoted(in) + " --repair --out " + quoted(out));
  CHECK(run.exit_code == 0);
  CHECK(run.err.find("repair: separated parts touching at 2 vertices (on 1 edge with more than two triangles") !=
        std::string::npos);
  const Mesh written = read_mesh(out);
  CHECK(solid_problem(written).empty());
  CHECK(written.vertex_count() == 16);

  const Run json_run = run_shatter("validate " + quoted(in) + " --repair --json");
  CHECK(json_run.exit_code == 0);
  const auto json = nlohmann::json::parse(json_run.out);
  CHECK(json["valid"] == true);
  bool named = false;
  for (const auto& change : json["repair"]) named = named || (change["change"] == "separated_touching_parts" && change["count"] == 2);
  CHECK(named);
}

TEST_CASE("validate and fracture --repair resolve self-intersections exactly", "[repair][cli]") {
  // The corpus elk (7 intersecting pairs) was refused after --repair
  // ("self-intersections remain") until the exact step; two overlapping boxes
  // come back as their union.
  const fs::path elk = mesh_dir() / "self-intersecting" / "elk.off";
  const fs::path out = scratch("elk-repaired.off");
  const Run run = run_shatter("validate " + quoted(elk) + " --repair --json --out " + quoted(out));
  CHECK(run.exit_code == 0);
  const auto json = nlohmann::json::parse(run.out);
  CHECK(json["valid"] == true);
  bool named = false;
  for (const auto& change : json["repair"]) named = named || change["change"] == "resolved_self_intersections_exactly";
  CHECK(named);
  CHECK(solid_problem(read_mesh(out)).empty());

  const fs::path boxes = scratch("two-boxes.off");
  write_mesh(merge({box({0, 0, 0}, {2, 2, 2}), box({1, 1, 1}, {3, 3, 3})}), boxes, MeshFormat::off);
  const fs::path united = scratch("two-boxes-united.off");
  const Run union_run = run_shatter("validate " + quoted(boxes) + " --repair --out " + quoted(united));
  CHECK(union_run.exit_code == 0);
  CHECK(union_run.err.find("repair: resolved ") != std::string::npos);
  CHECK(exact_six_volume(read_mesh(united)) == 6 * 15);  // 8 + 8 - 1
  const Run fracture = run_shatter("fracture " + quoted(boxes) + " --repair --fragments 4 --out " +
                                   quoted(scratch("two-boxes.shatter")));
  CHECK(fracture.exit_code == 0);
}

TEST_CASE("a --repair that finds no volume enclosed refuses in one line naming why, writing nothing", "[repair][cli]") {
  // A flat quad and a cross of two coplanar sheets (each triangle with a back
  // side over the other diagonal): every piece lies in one plane, so repair
  // removes them whole and the refusal names that, not only the emptiness left.
  // (Before flat pieces were removed, the exact arrangement found every cell
  // wound <= 0: the same refusal with that reason.)
  const fs::path quad = scratch("flat-quad.off"), cross = scratch("flat-cross.off");
  std::ofstream(quad) << "OFF\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";
  std::ofstream(cross) << "OFF\n8 8 0\n-2 -1 0\n2 -1 0\n2 1 0\n-2 1 0\n-1 -2 0\n1 -2 0\n1 2 0\n-1 2 0\n"
                          "3 0 1 2\n3 0 2 3\n3 1 0 3\n3 1 3 2\n3 4 5 6\n3 4 6 7\n3 5 4 7\n3 5 7 6\n";
  const std::string reason = "encloses no volume: every piece of it is flat (all its corners in one plane)";
  for (const fs::path& input : {quad, cross}) {
    INFO(input.filename());
    const std::string head = "error: invalid mesh " + input.string() + " after --repair: " + reason + " (what is left: ";
    const fs::path out = scratch("never.off");
    const Run validate = run_shatter("validate " + quoted(input) + " --repair --out " + quoted(out));
    CHECK(validate.exit_code == 3);
    CHECK(validate.err.find(" flat piece") != std::string::npos);
    CHECK(last_line(validate.err) == head + "no triangle)");
    CHECK(validate.out.find("  no volume: ") != std::string::npos);
    CHECK_FALSE(fs::exists(out));

    const Run json_run = run_shatter("validate " + quoted(input) + " --repair --json");
    CHECK(json_run.exit_code == 3);
    CHECK(last_line(json_run.err).rfind(head, 0) == 0);
    const auto report = nlohmann::json::parse(json_run.out);
    CHECK(report["valid"] == false);
    REQUIRE(report["defects"].size() >= 2);
    CHECK(report["defects"][0]["defect"] == "empty");
    CHECK(report["defects"][1]["defect"] == "no volume");

    const fs::path pieces = scratch("no-pieces");
    const Run slice = run_shatter("slice " + quoted(input) + " --plane 0,0,1,0 --repair --out " + quoted(pieces));
    CHECK(slice.exit_code == 3);
    CHECK(last_line(slice.err).rfind(head, 0) == 0);
    CHECK_FALSE(fs::exists(pieces));
    const fs::path tree = scratch("no.shatter");
    const Run fracture =
        run_shatter("fracture " + quoted(input) + " --fragments 2 --repair --json --out " + quoted(tree));
    CHECK(fracture.exit_code == 3);
    CHECK(fracture.out.empty());
    CHECK(last_line(fracture.err).rfind(head, 0) == 0);
    CHECK_FALSE(fs::exists(tree));
  }
}
