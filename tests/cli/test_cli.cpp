// End-to-end tests of the shatter command: exit codes, the one-line error, files
// written (and nothing left behind on failure), determinism of the bytes.

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <fstream>
#include <sstream>
#include <vector>

#include "shatter/generators/corpus.hpp"
#include "shatter/generators/solids.hpp"
#include "shatter/kernel/io.hpp"
#include "shatter/kernel/validate.hpp"
#include "support/checks.hpp"
#include "support/run_shatter.hpp"
#include "support/sanitizers.hpp"

using namespace shatter;
using namespace shatter::test;
namespace fs = std::filesystem;

namespace {


std::size_t files_in(const fs::path& dir) {
  if (!fs::exists(dir)) return 0;
  return static_cast<std::size_t>(std::distance(fs::directory_iterator(dir), fs::directory_iterator()));
}

// Whether two files hold the same bytes (a CHECK on the strings would print
// megabytes of binary on failure).
bool same_bytes(const fs::path& a, const fs::path& b) { return slurp(a) == slurp(b); }

// The payloads of a .shatter file's sections by tag (file.hpp's layout: 12-byte
// header, then per section a tag, u64 length, u32 CRC and the payload).
std::map<std::string, std::string> sections_of(const std::string& bytes) {
  std::map<std::string, std::string> sections;
  std::size_t at = 12;
  while (at + 16 <= bytes.size()) {
    std::uint64_t length = 0;
    for (int i = 7; i >= 0; --i) length = length << 8 | static_cast<unsigned char>(bytes[at + 4 + i]);
    if (length > bytes.size() - at - 16) break;
    sections[bytes.substr(at, 4)] = bytes.substr(at + 16, length);
    at += 16 + length;
  }
  return sections;
}

// The tags of the sections whose payloads differ between two .shatter files, or
// "" when none does: says which part of the tree a failed byte comparison is in.
std::string differing_sections(const fs::path& a, const fs::path& b) {
  const auto first = sections_of(slurp(a)), second = sections_of(slurp(b));
  std::string differing;
  for (const auto& [tag, payload] : first) {
    const auto other = second.find(tag);
    if (other == second.end() || other->second != payload) differing += (differing.empty() ? "" : " ") + tag;
  }
  return differing;
}

// The names in `dir`, sorted.
std::vector<std::string> names_in(const fs::path& dir) {
  std::vector<std::string> names;
  if (!fs::exists(dir)) return names;
  for (const auto& entry : fs::directory_iterator(dir)) names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

// `leaf-0000.off`, ...: the names fracture --export and export --nodes leaves
// give a tree of fewer than 10,000 leaves.
std::vector<std::string> leaf_file_names(std::size_t leaves, const std::string& extension) {
  std::vector<std::string> names;
  for (std::size_t i = 0; i < leaves; ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "leaf-%04zu.%s", i, extension.c_str());
    names.push_back(name);
  }
  return names;
}

// A few meshes of the corpus: the demo mesh, a knotted tube (cuts give several
// pieces), a convex solid with flat faces, a CAD part with sharp edges.
std::vector<fs::path> fracture_meshes() {
  return {mesh_dir() / "knot1.off", mesh_dir() / "cube.off",
          mesh_dir() / "fandisk.off"};
}

// What `shatter info --json` says about a .shatter file.
nlohmann::json info_of(const fs::path& tree) {
  const Run run = run_shatter("info " + quoted(tree) + " --json");
  INFO(run.err);
  REQUIRE(run.exit_code == 0);
  return nlohmann::json::parse(run.out);
}

// The first problem of a fracture run that had to succeed and write `tree`, or ""
// (exit 0, nothing on stderr as it is not a terminal, the tree file there).
std::string fracture_problem(const Run& run, const fs::path& tree) {
  if (run.exit_code != 0) return "exit " + std::to_string(run.exit_code) + ": " + run.err;
  if (!run.err.empty()) return "stderr not empty: " + run.err;
  if (!fs::is_regular_file(tree)) return "no tree file written";
  return "";
}

// The words the refusal of each mesh under bad/ must contain.
const std::map<std::string, std::string>& defect_of_bad_mesh() {
  static const std::map<std::string, std::string> defect_of = {
      {"cube-ouvert.off", "boundary edges"},         {"tet-shuffled.off", "inconsistent"},
      {"tetrahedron.off", "inward"},                 {"degtri_sliding.off", "zero-area"},
      {"elephant-with-holes.off", "boundary edges"}, {"tetra_intersected_by_triangle.off", "boundary edges"},
      {"box-in-box-both-outward.off", "misnested shells"}};
  return defect_of;
}

}  // namespace

TEST_CASE("every bad mesh is refused with exit 3 and a line naming its defect") {
  const std::map<std::string, std::string>& defect_of = defect_of_bad_mesh();
  const auto bad = bad_meshes();
  REQUIRE(bad.size() == defect_of.size());
  for (const auto& path : bad) {
    INFO(path.filename());
    const std::string expected = defect_of.at(path.filename().string());
    const Run validate = run_shatter("validate " + quoted(path));
    CHECK(validate.exit_code == 3);
    CHECK(is_one_error_line(validate.err));
    CHECK(validate.err.find(expected) != std::string::npos);
    const fs::path out = scratch("bad-out");
    const Run slice = run_shatter("slice " + quoted(path) + " --plane 0,0,1,0 --out " + quoted(out));
    CHECK(slice.exit_code == 3);
    CHECK(is_one_error_line(slice.err));
    CHECK(slice.err.find(expected) != std::string::npos);
    CHECK(files_in(out) == 0);
  }
}

TEST_CASE("files other tools wrote are read with a warning line each, and fracture") {
  const fs::path wild = mesh_dir().parent_path() / "wild";
  const fs::path obj = wild / "tinyobjloader-issue-161-inconsistent-f.obj";
  const Run validate = run_shatter("validate " + quoted(obj));
  CHECK(validate.exit_code == 0);
  CHECK(validate.err == "warning: " + obj.string() +
                            ": OBJ: 3 of 36 face corners have no texture coordinate (the first: face 12 at line 37): "
                            "every texture coordinate dropped\n");
  const Run json = run_shatter("validate " + quoted(obj) + " --json");
  REQUIRE(json.exit_code == 0);
  const nlohmann::json report = nlohmann::json::parse(json.out);
  CHECK(report["valid"] == true);
  REQUIRE(report["read_warnings"].size() == 1);
  CHECK(report["read_warnings"][0].get<std::string>().find("OBJ: 3 of 36") == 0);
  // A clean file's report has the field, empty.
  const Run clean = run_shatter("validate " + quoted(mesh_dir() / "cube.off") + " --json");
  CHECK(nlohmann::json::parse(clean.out)["read_warnings"].empty());
  CHECK(clean.err.empty());

  const fs::path ply = wild / "blender-247-header-cube.ply";
  const fs::path out = scratch("wild-fracture");
  const Run fracture = run_shatter("fracture " + quoted(ply) + " --fragments 8 --out " + quoted(out / "cube.shatter"));
  CHECK(fracture.exit_code == 0);
  CHECK(fracture.err.find("warning: " + ply.string() + ": PLY: header line 3 starts with no PLY keyword") == 0);
  CHECK(fs::exists(out / "cube.shatter"));

  // An open multi-solid file is read whole and then refused for what it is.
  const Run open = run_shatter("validate " + quoted(wild / "assimp-triangle_with_two_solids.stl"));
  CHECK(open.exit_code == 3);
  CHECK(open.err.find("STL: 2 solids") != std::string::npos);
  CHECK(open.err.find("boundary edges") != std::string::npos);
}

TEST_CASE("self-intersecting meshes are refused unless allowed, then cut into closed oriented pieces") {
  const auto meshes = self_intersecting_meshes();
  REQUIRE(meshes.size() == 3);
  for (const auto& path : meshes) {
    INFO(path.filename());
    const fs::path out = scratch("self-out");
    const Run refused = run_shatter("slice " + quoted(path) + " --plane 0.2,1,0.1,0 --out " + quoted(out));
    CHECK(refused.exit_code == 3);
    CHECK(is_one_error_line(refused.err));
    CHECK(refused.err.find("self-intersecting") != std::string::npos);
    CHECK(refused.err.find("pairs") != std::string::npos);
    CHECK(files_in(out) == 0);
    const Run allowed =
        run_shatter("slice " + quoted(path) + " --plane 0.2,1,0.1,0 --allow-self-intersections --out " + quoted(out));
    CHECK(allowed.exit_code == 0);
    REQUIRE(files_in(out) >= 2);
    // Closed and oriented. (A piece may keep a point where the surface touches
    // itself: separated in memory, but welded again when read back, so a
    // non-manifold vertex is not a failure here.)
    for (const auto& entry : fs::directory_iterator(out)) {
      const ValidationReport report = validate_mesh(read_mesh(entry.path()));
      for (DefectKind kind : {DefectKind::boundary_edge, DefectKind::non_manifold_edge,
                              DefectKind::inconsistent_orientation, DefectKind::unused_vertex}) {
        CHECK(report.find(kind) == nullptr);
      }
    }
  }
}

TEST_CASE("slice writes pieces that read back exactly, the same bytes every run") {
  const fs::path mesh = mesh_dir() / "fandisk.off";
  for (const std::string format : {"off", "obj", "ply", "stl"}) {
    INFO(format);
    const fs::path first = scratch("first"), second = scratch("second");
    const std::string flags = " --plane 0.3,0.5,0.8,-0.2 --format " + format + " --json";
    const Run a = run_shatter("slice " + quoted(mesh) + flags + " --out " + quoted(first));
    const Run b = run_shatter("slice " + quoted(mesh) + flags + " --out " + quoted(second));
    REQUIRE(a.exit_code == 0);
    REQUIRE(b.exit_code == 0);
    REQUIRE(files_in(first) >= 2);
    CHECK(files_in(first) == files_in(second));
    for (const auto& entry : fs::directory_iterator(first)) {
      CHECK(slurp(entry.path()) == slurp(second / entry.path().filename()));
      const Mesh piece = read_mesh(entry.path());
      CHECK(solid_problem(piece) == "");
      // Text and binary writers round-trip doubles exactly.
      CHECK(canonical_bytes(read_mesh_from_bytes(write_mesh_to_bytes(piece, *parse_mesh_format(format)),
                                                 *parse_mesh_format(format))) == canonical_bytes(piece));
    }
  }
}

TEST_CASE("slice through vertices of the elephant writes every piece valid as read back") {
  // Issue 10's reproducer: x + y + d = 0 through a vertex of elephant.off, d the
  // rounded -(x + y). The retired kernels rounded a cut point onto that vertex,
  // which gave a piece with a zero-area triangle (written with exit 0 and a
  // warning; later refused with exit 3 by exact on 3 and fast on 5 of these 12
  // planes). The plane kernel writes every piece, certified. The same
  // construction through 11 more of its vertices.
  const fs::path mesh_path = mesh_dir() / "elephant.off";
  const Mesh elephant = read_mesh(mesh_path);
  std::vector<std::string> planes{"1,1,0,-0.062960299999999997"};
  for (std::size_t k = 1; k <= 11; ++k) {
    const Vec3 p = elephant.positions[(k * 2477) % elephant.positions.size()];
    char text[96];
    std::snprintf(text, sizeof text, "1,1,0,%.17g", -(p.x + p.y));
    planes.emplace_back(text);
  }
  for (const std::string& plane : planes) {
    INFO("--plane " << plane);
    const fs::path out = scratch("vertex-plane");
    const Run run = run_shatter("slice " + quoted(mesh_path) + " --plane " + plane + " --out " + quoted(out));
    REQUIRE(run.exit_code == 0);
    REQUIRE(files_in(out) >= 2);
    for (const auto& entry : fs::directory_iterator(out)) {
      INFO(entry.path().filename());
      CHECK(validate_mesh(read_mesh(entry.path())).summary() == "valid");
    }
  }
}

TEST_CASE("slice through a saddle vertex writes valid pieces and says where a piece touched itself") {
  // Issue 17: both exited 3 ("cannot be rounded ... non-manifold"): the lobes
  // below the saddle vertex are one piece, which touches itself there exactly.
  for (const auto& [file, plane] : {std::pair{"helmet.off", "0,1,0,-0.014781300000000001"},
                                    std::pair{"torus_quad.off", "1,1,0,-0.25782700000000003"}}) {
    INFO(file);
    const fs::path out = scratch("saddle");
    const Run run = run_shatter("slice " + quoted(mesh_dir() / file) + " --plane " + plane + " --out " + quoted(out));
    REQUIRE(run.exit_code == 0);
    CHECK(run.out.find("touched itself: 2 vertex copies moved apart") != std::string::npos);
    REQUIRE(files_in(out) == 2);
    for (const auto& entry : fs::directory_iterator(out)) {
      INFO(entry.path().filename());
      CHECK(validate_mesh(read_mesh(entry.path())).summary() == "valid");
    }
    const Run json = run_shatter("slice " + quoted(mesh_dir() / file) + " --plane " + plane + " --json --out " +
                                 quoted(scratch("saddle-json")));
    REQUIRE(json.exit_code == 0);
    const auto report = nlohmann::json::parse(json.out);
    CHECK(report["pieces"][0]["separated_vertices"] == 2);
    CHECK(report["pieces"][0]["moved_volume"].get<double>() <= report["pieces"][0]["moved_volume_bound"].get<double>());
  }
}

TEST_CASE("slice names a piece thinner than its rounding as vanished and writes the others") {
  // A plane through a corner of the cube up to rounding cuts off a tetrahedron far
  // thinner than an ulp: every one of its vertices rounds onto the corner.
  const fs::path out = scratch("vanish");
  const std::string plane = "-0.51784138889905429,0.87762787624213567,-0.40292203608095672,1.7983913012221466";
  const Run run = run_shatter("slice " + quoted(mesh_dir() / "cube.off") + " --plane " + plane + " --json --out " +
                              quoted(out));
  REQUIRE(run.exit_code == 0);
  const auto report = nlohmann::json::parse(run.out);
  REQUIRE(report["vanished"].size() == 1);
  CHECK(report["vanished"][0]["piece"] == "below-0");
  CHECK(std::fabs(report["vanished"][0]["volume"].get<double>()) < 1e-30);
  REQUIRE(report["pieces"].size() == 1);
  CHECK(report["pieces"][0]["file"] == "above-0.off");
  CHECK(files_in(out) == 1);
  CHECK(validate_mesh(read_mesh(out / "above-0.off")).summary() == "valid");
}

TEST_CASE("a plane that misses returns the mesh whole and says so") {
  const fs::path out = scratch("miss");
  const Run run = run_shatter("slice " + quoted(mesh_dir() / "cube.off") + " --plane 0,0,1,10 --out " + quoted(out));
  CHECK(run.exit_code == 0);
  CHECK(run.out.find("returned whole") != std::string::npos);
  CHECK(files_in(out) == 1);
}

TEST_CASE("slice writes the piece that meets itself along an edge on the plane either way up") {
  // A block with a diamond tunnel along y whose lowest edge (x = 2, z = 1) lies on
  // z = 1: above it, the block around the tunnel is one piece meeting itself along
  // that edge. shatter slice exited 3 ("pinched along the edge") until 2026-12-04.
  const std::vector<Vec2> section{{0, 0}, {4, 0}, {4, 4}, {0, 4}, {2, 1}, {3, 2}, {2, 3}, {1, 2}};
  const std::vector<std::vector<VertexIndex>> loops{{0, 1, 2, 3}, {4, 7, 6, 5}};
  const std::vector<Triangle> ends{{0, 1, 4}, {1, 2, 5}, {1, 5, 4}, {2, 3, 6}, {2, 6, 5}, {3, 0, 7}, {3, 7, 6}, {0, 4, 7}};
  const fs::path dir = scratch("tunnel");
  fs::create_directories(dir);
  const Mesh tunnel = prism(section, loops, ends, 3);
  REQUIRE(validate_mesh(tunnel).summary() == "valid");
  write_mesh(tunnel, dir / "tunnel.off", MeshFormat::off);
  for (const std::string plane : {"0,0,1,-1", "0,0,-1,1"}) {
    INFO(plane);
    const fs::path out = dir / ("out" + plane);
    const Run run = run_shatter("slice " + quoted(dir / "tunnel.off") + " --plane " + plane + " --json --out " + quoted(out));
    REQUIRE(run.exit_code == 0);
    const auto report = nlohmann::json::parse(run.out);
    REQUIRE(report["pieces"].size() == 2);
    REQUIRE(files_in(out) == 2);
    for (const auto& entry : fs::directory_iterator(out)) {
      INFO(entry.path().filename());
      CHECK(validate_mesh(read_mesh(entry.path())).summary() == "valid");
    }
  }
}

TEST_CASE("slice says a volume is beyond the double range, not JSON null") {
  // Found by probing extreme scales: a cube 2^600 on a side has a volume of
  // 2^1800, which no double holds (its sum comes out NaN); text output printed "null".
  const fs::path dir = scratch("huge");
  fs::create_directories(dir);
  const double side = std::ldexp(1.0, 600);
  Mesh cube = read_mesh(mesh_dir() / "cube.off");
  for (Vec3& p : cube.positions) p = p * side;
  write_mesh(cube, dir / "huge.off", MeshFormat::off);
  const Run run = run_shatter("slice " + quoted(dir / "huge.off") + " --plane 1,0,0,0 --out " + quoted(dir / "out"));
  REQUIRE(run.exit_code == 0);
  CHECK(run.out.find("null") == std::string::npos);
  CHECK(run.out.find("(beyond the double range)") != std::string::npos);
}

TEST_CASE("json output names a path that is not UTF-8 with its bad bytes as U+FFFD and the command succeeds") {
  // Found by a sweep (2026-12-07): a Linux file name may hold any byte but '/'
  // and NUL; the JSON writer threw on a byte that is not UTF-8, so each command
  // exited 1 after writing its files (fracture left its tree, slice its pieces).
  const fs::path dir = scratch("non-utf8");
  fs::create_directories(dir);
  const fs::path mesh = dir / "cube\xff.off", tree = dir / "tree\xfe.shatter";
  fs::copy_file(mesh_dir() / "cube.off", mesh);
  const std::vector<std::string> commands = {
      "validate " + quoted(mesh) + " --json",
      "slice " + quoted(mesh) + " --plane 1,0,0,0 --json --out " + quoted(dir / "pieces"),
      "fracture " + quoted(mesh) + " --fragments 4 --json --out " + quoted(tree),
      "info " + quoted(tree) + " --json --check",
      "simulate " + quoted(tree) + " --steps 3 --json",
  };
  for (const std::string& command : commands) {
    INFO(command);
    const Run run = run_shatter(command);
    INFO(run.err);
    REQUIRE(run.exit_code == 0);
    const nlohmann::json out = nlohmann::json::parse(run.out);  // throws on invalid JSON
    CHECK(run.out.find("\xef\xbf\xbd") != std::string::npos);  // U+FFFD, in UTF-8
  }
}

TEST_CASE("usage and I/O errors have their own exit codes and one error line") {
  const std::string cube = quoted(mesh_dir() / "cube.off");
  const fs::path out = scratch("usage");
  for (const std::string plane : {"1,2,3", "0,0,0,1", "1,2,x,4", "1,2,3,4,5", "nan,0,1,0"}) {
    const Run run = run_shatter("slice " + cube + " --plane " + plane + " --out " + quoted(out));
    CHECK(run.exit_code == 2);
    CHECK(is_one_error_line(run.err));
  }
  CHECK(run_shatter("slice " + cube + " --out " + quoted(out)).exit_code == 2);  // no --plane
  CHECK(run_shatter("frobnicate").exit_code == 2);
  const Run missing = run_shatter("validate /nonexistent/mesh.off");
  CHECK(missing.exit_code == 4);
  CHECK(is_one_error_line(missing.err));
  // The output folder cannot be created under a regular file.
  const fs::path file = scratch("a-file");
  std::ofstream(file) << "x";
  const Run blocked = run_shatter("slice " + cube + " --plane 0,0,1,-0.5 --out " + quoted(file / "sub"));
  CHECK(blocked.exit_code == 4);
  CHECK(is_one_error_line(blocked.err));
  CHECK(run_shatter("--help").exit_code == 0);
  CHECK(run_shatter("slice --help").exit_code == 0);
}

// --- fracture, info, export -------------------------------------------------------

TEST_CASE("fracture writes a tree info reads back: at least N leaves, as asked, the same bytes on any thread count") {
  const std::vector<std::string> strategies = {"thesis", "balanced", "axis"};
  std::size_t round = 0;  // walks the strategies, so each mesh meets each one
  for (const fs::path& mesh : fracture_meshes()) {
    for (const std::uint64_t seed : {1u, 7u, 12345u}) {
      const std::string strategy = strategies[round++ % strategies.size()];
      const auto fragments = static_cast<unsigned>(5 + seed % 7);
      INFO(mesh.filename() << " seed " << seed << " strategy " << strategy << " N " << fragments);
      const fs::path dir = scratch("fracture");
      const std::string flags = " --fragments " + std::to_string(fragments) + " --seed " + std::to_string(seed) +
                                " --strategy " + strategy + " --json";
      const std::string fracture = "fracture " + quoted(mesh) + flags;
      const Run one = run_shatter(fracture + " --threads 1 --out " + quoted(dir / "1.shatter"));
      REQUIRE(fracture_problem(one, dir / "1.shatter") == "");
      const Run two = run_shatter(fracture + " --threads 2 --out " + quoted(dir / "2.shatter"));
      REQUIRE(fracture_problem(two, dir / "2.shatter") == "");
      CHECK(same_bytes(dir / "1.shatter", dir / "2.shatter"));
      CHECK(differing_sections(dir / "1.shatter", dir / "2.shatter") == "");

      const nlohmann::json info = info_of(dir / "1.shatter");
      const std::size_t leaves = info["leaves"];
      CHECK(leaves >= fragments);
      CHECK(info["nodes"].get<std::size_t>() > leaves);  // the root was cut
      CHECK(info["options"]["fragments"] == fragments);
      CHECK(info["options"]["seed"] == seed);
      CHECK(info["options"]["strategy"] == strategy);
      CHECK(info["options"]["kernel"] == "plane");
      CHECK(std::abs(info["volume"]["leaves_relative_error"].get<double>()) < 1e-9);
      CHECK(info["bonds"]["count"].get<std::size_t>() >= leaves - 1);  // a solid's fragments hold together

      // The summary fracture printed is the tree's, as info reads it.
      const nlohmann::json summary = nlohmann::json::parse(one.out);
      CHECK(summary["fragments_requested"] == fragments);
      CHECK(summary["options"]["threads"] == 1);
      CHECK(summary["seconds"].get<double>() >= 0);
      CHECK(summary["export"].is_null());
      for (const char* key : {"leaves", "nodes", "max_depth", "bonds", "fragment_volume", "volume"}) {
        INFO(key);
        CHECK(summary[key] == info[key]);
      }
    }
  }
}

TEST_CASE("info --compare-bond-rules counts the seed's false box bonds against the true ones") {
  for (const fs::path& mesh : fracture_meshes()) {
    for (const char* seed : {"3", "11"}) {
      INFO(mesh.filename() << " seed " << seed);
      const fs::path dir = scratch("bond-rules");
      REQUIRE(run_shatter("fracture " + quoted(mesh) + " --fragments 12 --seed " + seed + " --out " +
                          quoted(dir / "t.shatter"))
                  .exit_code == 0);
      const Run run = run_shatter("info " + quoted(dir / "t.shatter") + " --json --compare-bond-rules");
      REQUIRE(run.exit_code == 0);
      const nlohmann::json info = nlohmann::json::parse(run.out);
      const nlohmann::json& rules = info["bounding_box_rule"];
      const auto true_bonds = rules["true_bonds"].get<std::size_t>();
      const auto box_bonds = rules["box_bonds"].get<std::size_t>();
      const auto false_box = rules["false_box_bonds"].get<std::size_t>();
      const auto missed = rules["missed_true_bonds"].get<std::size_t>();
      CHECK(true_bonds > 0);
      CHECK(true_bonds <= info["bonds"]["count"].get<std::size_t>());  // pairs, against bonds per cut
      CHECK(false_box <= box_bonds);
      CHECK(missed <= true_bonds);
      CHECK(true_bonds - missed == box_bonds - false_box);  // the pairs both rules find
      // Without the flag, no comparison is made or printed.
      CHECK(info_of(dir / "t.shatter").count("bounding_box_rule") == 0);
      const Run text = run_shatter("info " + quoted(dir / "t.shatter") + " --compare-bond-rules");
      CHECK(text.out.find("bounding-box rule: " + std::to_string(box_bonds) + " bonded pairs, " +
                          std::to_string(false_box) + " of them false") != std::string::npos);
    }
  }
}

TEST_CASE("fracture --fragments 1 keeps the solid whole, and --strategy balanced gives a valid tree too") {
  const fs::path dir = scratch("whole");
  for (const fs::path& mesh : fracture_meshes()) {
    INFO(mesh.filename());
    const Run whole = run_shatter("fracture " + quoted(mesh) + " --fragments 1 --out " + quoted(dir / "t.shatter"));
    REQUIRE(fracture_problem(whole, dir / "t.shatter") == "");
    const nlohmann::json info = info_of(dir / "t.shatter");
    CHECK(info["leaves"] == 1);
    CHECK(info["nodes"] == 1);
    CHECK(info["bonds"]["count"] == 0);

    const Run balanced = run_shatter("fracture " + quoted(mesh) + " --fragments 6 --strategy balanced --out " +
                                     quoted(dir / "balanced.shatter"));
    REQUIRE(fracture_problem(balanced, dir / "balanced.shatter") == "");
    const nlohmann::json balanced_info = info_of(dir / "balanced.shatter");
    CHECK(balanced_info["leaves"].get<std::size_t>() >= 6);
    CHECK(balanced_info["options"]["strategy"] == "balanced");
    CHECK(balanced_info["options"]["kernel"] == "plane");
  }
}

TEST_CASE("fracture --export writes one closed mesh file per leaf, the same files export writes") {
  const std::vector<std::string> formats = {"off", "obj", "ply", "stl"};
  std::size_t round = 0;
  for (const fs::path& mesh : fracture_meshes()) {
    for (const std::string& format : {formats[round % 4], formats[(round + 1) % 4]}) {
      INFO(mesh.filename() << " " << format);
      const fs::path dir = scratch("export-leaves");
      const std::string seed = std::to_string(3 + round);
      const Run run = run_shatter("fracture " + quoted(mesh) + " --fragments 8 --seed " + seed + " --out " +
                                  quoted(dir / "tree.shatter") + " --export " + quoted(dir / "leaves") +
                                  " --format " + format);
      REQUIRE(fracture_problem(run, dir / "tree.shatter") == "");
      CHECK(run.out.find("leaf-0000." + format) != std::string::npos);
      const std::size_t leaves = info_of(dir / "tree.shatter")["leaves"];
      const std::vector<std::string> names = names_in(dir / "leaves");
      CHECK(names == leaf_file_names(leaves, format));
      for (const std::string& name : names) {
        INFO(name);
        // The plane kernel (the default) certifies every written mesh: read back,
        // it is a valid solid, self-intersections included.
        CHECK(validate_mesh(read_mesh(dir / "leaves" / name)).summary() == "valid");
      }
      // export --nodes leaves of the written tree writes the very same files.
      const Run again = run_shatter("export " + quoted(dir / "tree.shatter") + " --out " + quoted(dir / "again") +
                                    " --format " + format);
      REQUIRE(again.exit_code == 0);
      REQUIRE(names_in(dir / "again") == names);
      for (const std::string& name : names) CHECK(same_bytes(dir / "leaves" / name, dir / "again" / name));
    }
    ++round;
  }
  // Without --format the leaves are OFF files.
  const fs::path dir = scratch("export-default");
  const Run run = run_shatter("fracture " + quoted(mesh_dir() / "cube.off") + " --fragments 3 --out " +
                              quoted(dir / "t.shatter") + " --export " + quoted(dir / "leaves"));
  REQUIRE(fracture_problem(run, dir / "t.shatter") == "");
  CHECK(names_in(dir / "leaves") == leaf_file_names(info_of(dir / "t.shatter")["leaves"], "off"));
}

TEST_CASE("fracture refuses a bad mesh with exit 3 and one line, and leaves nothing behind") {
  for (const fs::path& mesh : bad_meshes()) {
    INFO(mesh.filename());
    const fs::path dir = scratch("fracture-bad");
    const Run run = run_shatter("fracture " + quoted(mesh) + " --fragments 8 --out " +
                                quoted(dir / "sub" / "t.shatter") + " --export " + quoted(dir / "leaves"));
    CHECK(run.exit_code == 3);
    CHECK(is_one_error_line(run.err));
    CHECK(run.err.find(defect_of_bad_mesh().at(mesh.filename().string())) != std::string::npos);
    CHECK(run.err.find(mesh.filename().string()) != std::string::npos);  // names the file
    CHECK(run.out.empty());
    CHECK_FALSE(fs::exists(dir));
  }
  for (const fs::path& mesh : self_intersecting_meshes()) {
    INFO(mesh.filename());
    const fs::path dir = scratch("fracture-self");
    const Run refused = run_shatter("fracture " + quoted(mesh) + " --fragments 4 --out " + quoted(dir / "t.shatter"));
    CHECK(refused.exit_code == 3);
    CHECK(is_one_error_line(refused.err));
    CHECK_FALSE(fs::exists(dir));
    const Run allowed = run_shatter("fracture " + quoted(mesh) + " --fragments 4 --allow-self-intersections --out " +
                                    quoted(dir / "t.shatter"));
    CHECK(fracture_problem(allowed, dir / "t.shatter") == "");
    CHECK(info_of(dir / "t.shatter")["options"]["allow_self_intersections"] == true);
  }
}

// Every line of `err` that starts "error: ", and whether the last line is one.
std::vector<std::string> error_lines(const std::string& err) {
  std::vector<std::string> lines;
  std::size_t begin = 0;
  while (begin < err.size()) {
    const std::size_t end = std::min(err.find('\n', begin), err.size());
    if (err.compare(begin, 7, "error: ") == 0) lines.push_back(err.substr(begin, end - begin));
    begin = end + 1;
  }
  return lines;
}

TEST_CASE("a mesh --repair leaves empty is refused by every command with one error line, nothing written") {
  // Regression: validate --repair accepted these as "valid ..., 0 triangles" and
  // wrote an empty OFF file. Triangles back to back with their reversed copies,
  // with and without a triangle using one vertex twice, and a triangle whose three
  // corners are one point: each encloses no volume, and repair removes every triangle.
  const std::vector<std::pair<std::string, std::string>> meshes = {
      {"sheet.off", "OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 2 1\n"},
      {"two-sheets-and-a-spike.off",
       "OFF\n5 5 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n1 1 1\n3 0 1 2\n3 0 2 1\n3 0 3 1\n3 0 1 3\n3 4 4 2\n"},
      {"one-point.off", "OFF\n3 1 0\n0.5 0.5 0.5\n0.5 0.5 0.5\n0.5 0.5 0.5\n3 0 1 2\n"},
  };
  for (const auto& [name, text] : meshes) {
    INFO(name);
    const fs::path dir = scratch("repair-empty");
    const fs::path mesh = dir / name;
    fs::create_directories(dir);
    std::ofstream(mesh) << text;
    const std::vector<std::string> commands = {
        "validate --repair " + quoted(mesh) + " --out " + quoted(dir / "out" / "repaired.off"),
        "fracture --repair " + quoted(mesh) + " --fragments 4 --out " + quoted(dir / "out" / "t.shatter"),
        "slice --repair " + quoted(mesh) + " --plane 1,0,0,-0.25 --out " + quoted(dir / "out" / "piece"),
    };
    for (const std::string& command : commands) {
      INFO(command);
      const Run run = run_shatter(command);
      CHECK(run.exit_code == 3);
      const std::vector<std::string> errors = error_lines(run.err);
      REQUIRE(errors.size() == 1);
      CHECK(errors[0].find("empty") != std::string::npos);
      CHECK(errors[0].find(name) != std::string::npos);
      CHECK(run.err.substr(run.err.size() - errors[0].size() - 1) == errors[0] + "\n");  // the last line
      CHECK_FALSE(fs::exists(dir / "out"));
    }
    const Run json = run_shatter("validate --repair --json " + quoted(mesh));
    CHECK(json.exit_code == 3);
    const nlohmann::json report = nlohmann::json::parse(json.out);
    CHECK(report["valid"] == false);
    CHECK(report["triangles"] == 0);
    REQUIRE(!report["defects"].empty());
    CHECK(report["defects"][0]["defect"] == "empty");
  }
}

TEST_CASE("a single intersecting pair is named in the singular by every command") {
  // Regression: fracture and slice said "1 pairs". Two triangles back to back
  // are closed and oriented as far as topology goes, and cross each other: one pair.
  const fs::path dir = scratch("one-pair");
  fs::create_directories(dir);
  const fs::path mesh = dir / "sheet.off";
  std::ofstream(mesh) << "OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 2 1\n";
  for (const std::string& command : {"validate " + quoted(mesh),
                                     "fracture " + quoted(mesh) + " --fragments 2 --out " + quoted(dir / "t.shatter"),
                                     "slice " + quoted(mesh) + " --plane 1,0,0,-0.25 --out " + quoted(dir / "p")}) {
    INFO(command);
    const Run run = run_shatter(command);
    CHECK(run.exit_code == 3);
    CHECK(is_one_error_line(run.err));
    CHECK(run.err.find("self-intersecting: 1 pair of intersecting triangles") != std::string::npos);
  }
}

TEST_CASE("fracture usage errors exit 2 with one line, before anything is written") {
  const std::string cube = quoted(mesh_dir() / "cube.off");
  const fs::path dir = scratch("fracture-usage");
  const std::string out = " --out " + quoted(dir / "t.shatter");
  const std::vector<std::string> mistakes = {
      cube + out,                                                   // no --fragments
      cube + " --fragments 0" + out,                                // N >= 1
      cube + " --fragments -3" + out,
      cube + " --fragments x" + out,
      cube + " --fragments 4294967296" + out,                       // beyond 32 bits
      cube + " --fragments 4",                                      // no --out
      cube + " --fragments 4 --format obj" + out,                   // --format without --export
      cube + " --fragments 4 --export " + quoted(dir / "e") + " --format glb" + out,
      cube + " --fragments 4 --strategy random" + out,
      cube + " --fragments 4 --kernel exact" + out,                 // retired: no such option
      cube + " --fragments 4 --threads -1" + out,
      cube + " --fragments 4 --interior-uv-scale 0" + out,
      cube + " --fragments 4 --seed -1" + out,
      cube + " --fragments 4 --frobnicate" + out,
      "--fragments 4" + out,                                        // no mesh
      // More sites than --sites allows, by another pattern (each ran out of
      // memory until 2026-12-07: an internal error, or the kernel's OOM killer).
      cube + " --pattern grid --cells 1024,1024,1024" + out,
      cube + " --pattern clustered --clusters 1000000 --sites-per-cluster 1000000 --cluster-radius 0.1" + out,
      cube + " --pattern radial --rings 10000 --sectors 1001" + out,
  };
  for (const std::string& arguments : mistakes) {
    INFO(arguments);
    const Run run = run_shatter("fracture " + arguments);
    CHECK(run.exit_code == 2);
    CHECK(is_one_error_line(run.err));
    CHECK_FALSE(fs::exists(dir));
  }
  // --out naming a folder is caught before the (possibly long) build.
  fs::create_directories(dir);
  const Run folder = run_shatter("fracture " + cube + " --fragments 4 --out " + quoted(dir));
  CHECK(folder.exit_code == 2);
  CHECK(is_one_error_line(folder.err));
  CHECK(files_in(dir) == 0);
}

TEST_CASE("fracture I/O errors exit 4 and remove what the run wrote") {
  const fs::path dir = scratch("fracture-io");
  fs::create_directories(dir);
  const Run missing = run_shatter("fracture " + quoted(dir / "no-such-mesh.off") + " --fragments 4 --out " +
                                  quoted(dir / "t.shatter"));
  CHECK(missing.exit_code == 4);
  CHECK(is_one_error_line(missing.err));
  CHECK(files_in(dir) == 0);
  // The leaves are written first; the tree's folder cannot be made under a regular
  // file, so the leaves (and the folders made for them) go again.
  const fs::path file = dir / "a-file";
  std::ofstream(file) << "x";
  const Run blocked = run_shatter("fracture " + quoted(mesh_dir() / "cube.off") + " --fragments 4 --out " +
                                  quoted(file / "sub" / "t.shatter") + " --export " + quoted(dir / "new" / "leaves"));
  CHECK(blocked.exit_code == 4);
  CHECK(is_one_error_line(blocked.err));
  CHECK(names_in(dir) == std::vector<std::string>{"a-file"});
}

TEST_CASE("export writes mesh folders by node selection, and GLB files") {
  const fs::path dir = scratch("export");
  for (const fs::path& mesh : fracture_meshes()) {
    INFO(mesh.filename());
    const fs::path tree = dir / (mesh.stem().string() + ".shatter");
    const Run fracture = run_shatter("fracture " + quoted(mesh) + " --fragments 9 --out " + quoted(tree));
    REQUIRE(fracture_problem(fracture, tree) == "");
    const nlohmann::json info = info_of(tree);
    const std::size_t leaves = info["leaves"], nodes = info["nodes"];
    const std::uint32_t max_depth = info["max_depth"];

    const fs::path objs = dir / (mesh.stem().string() + "-obj");
    REQUIRE(run_shatter("export " + quoted(tree) + " --out " + quoted(objs) + " --format obj").exit_code == 0);
    CHECK(names_in(objs) == leaf_file_names(leaves, "obj"));

    // depth:0 is the root alone; depth:1 the root's pieces; deeper than the
    // deepest leaf, the leaves, named by node index.
    for (const auto& [selection, expected] : std::vector<std::pair<std::string, std::size_t>>{
             {"depth:0", 1}, {"depth:" + std::to_string(max_depth + 1), leaves}, {"all", nodes}}) {
      INFO(selection);
      std::string folder_name = mesh.stem().string() + "-" + selection;
      std::replace(folder_name.begin(), folder_name.end(), ':', '-');
      const fs::path folder = dir / folder_name;
      const Run run = run_shatter("export " + quoted(tree) + " --out " + quoted(folder) + " --nodes " + selection);
      REQUIRE(run.exit_code == 0);
      CHECK(files_in(folder) == expected);
    }
    const fs::path depth1 = dir / (mesh.stem().string() + "-depth1");
    REQUIRE(run_shatter("export " + quoted(tree) + " --out " + quoted(depth1) + " --nodes depth:1").exit_code == 0);
    const std::vector<std::string> level1 = names_in(depth1);
    CHECK(level1.size() >= 2);
    CHECK(level1.size() <= leaves);
    for (const std::string& name : level1) CHECK(name.rfind("node-", 0) == 0);
    CHECK(std::find(level1.begin(), level1.end(), "node-00000.off") == level1.end());  // not the root

    const fs::path glb = dir / (mesh.stem().string() + ".glb");
    const Run glb_run = run_shatter("export " + quoted(tree) + " --out " + quoted(glb) + " --nodes all");
    REQUIRE(glb_run.exit_code == 0);
    const std::string bytes = slurp(glb);
    CHECK(bytes.substr(0, 4) == "glTF");
    CHECK(bytes.size() % 4 == 0);  // GLB chunks are 4-byte aligned
  }
  const fs::path tree = dir / "cube.shatter";
  for (const std::string& arguments : {"--out " + quoted(dir / "x.glb") + " --format ply",
                                       "--out " + quoted(dir / "y") + " --nodes depth:x",
                                       "--out " + quoted(dir / "y") + " --nodes some", std::string("--format off")}) {
    INFO(arguments);
    const Run run = run_shatter("export " + quoted(tree) + " " + arguments);
    CHECK(run.exit_code == 2);
    CHECK(is_one_error_line(run.err));
    CHECK_FALSE(fs::exists(dir / "x.glb"));
    CHECK_FALSE(fs::exists(dir / "y"));
  }
}

TEST_CASE("info and export refuse a damaged .shatter file with exit 3 and one line") {
  const fs::path dir = scratch("damaged");
  const fs::path tree = dir / "good.shatter";
  fs::create_directories(dir);
  const Run fracture =
      run_shatter("fracture " + quoted(mesh_dir() / "knot1.off") + " --fragments 4 --out " + quoted(tree));
  REQUIRE(fracture_problem(fracture, tree) == "");
  const std::string good = slurp(tree);
  REQUIRE(good.size() > 1000);

  std::vector<std::pair<std::string, std::string>> damaged;
  for (const std::size_t length : {std::size_t{0}, std::size_t{5}, std::size_t{12}, std::size_t{40}, good.size() / 3,
                                   good.size() / 2, good.size() - 17, good.size() - 1}) {
    damaged.emplace_back("truncated to " + std::to_string(length), good.substr(0, length));
  }
  for (const std::size_t at : {std::size_t{0}, std::size_t{9}, std::size_t{60}, good.size() / 2, good.size() - 20}) {
    std::string flipped = good;
    flipped[at] = static_cast<char>(flipped[at] ^ 0x10);
    damaged.emplace_back("byte " + std::to_string(at) + " flipped", flipped);
  }
  damaged.emplace_back("a byte appended", good + '\0');
  damaged.emplace_back("a mesh file", slurp(mesh_dir() / "cube.off"));

  for (const auto& [what, bytes] : damaged) {
    INFO(what);
    const fs::path file = dir / "damaged.shatter";
    std::ofstream(file, std::ios::binary) << bytes;
    const Run info = run_shatter("info " + quoted(file));
    CHECK(info.exit_code == 3);
    CHECK(is_one_error_line(info.err));
    CHECK(info.out.empty());
    const Run json = run_shatter("info --json " + quoted(file));
    CHECK(json.exit_code == 3);
    CHECK(json.out.empty());
    const Run exported = run_shatter("export " + quoted(file) + " --out " + quoted(dir / "out"));
    CHECK(exported.exit_code == 3);
    CHECK(is_one_error_line(exported.err));
    CHECK_FALSE(fs::exists(dir / "out"));
  }
  const Run missing = run_shatter("info " + quoted(dir / "no-such.shatter"));
  CHECK(missing.exit_code == 4);
  CHECK(is_one_error_line(missing.err));
  // The good file still reads.
  CHECK(info_of(tree)["leaves"].get<std::size_t>() >= 4);
}

TEST_CASE("every subcommand's --help names every option") {
  const std::map<std::string, std::vector<std::string>> options_of = {
      {"validate", {"mesh", "--json"}},
      {"slice", {"mesh", "--plane", "--allow-self-intersections", "--out", "--format", "--interior-uv-scale",
                 "--json"}},
      {"fracture", {"mesh", "--fragments", "--seed", "--strategy", "thesis", "balanced", "axis", "--threads",
                    "--interior-uv-scale", "--allow-self-intersections", "--out", "--export", "--format", "--json"}},
      {"info", {"tree", "--json"}},
      {"export", {"tree", "--out", "--format", "glb", "--nodes", "leaves", "all", "depth:K"}},
  };
  const Run top = run_shatter("--help");
  CHECK(top.exit_code == 0);
  for (const auto& [command, options] : options_of) {
    INFO(command);
    CHECK(top.out.find(command) != std::string::npos);
    const Run help = run_shatter(command + " --help");
    CHECK(help.exit_code == 0);
    CHECK(help.err.empty());
    for (const std::string& option : options) {
      INFO(option);
      CHECK(help.out.find(option) != std::string::npos);
    }
    CHECK(help.out.find("--kernel") == std::string::npos);  // retired with the fast and exact kernels
  }
}

TEST_CASE("fracture draws a progress bar on a terminal and erases it") {
  // `script` (util-linux, in every Debian install) gives the command a terminal.
  // Without it the bar would go untested, so its absence fails, never skips.
  REQUIRE(std::system("command -v script >/dev/null 2>&1") == 0);
  const fs::path dir = scratch("progress");
  fs::create_directories(dir);
  // SHATTER_PROGRESS_DELAY_MS=0 draws from the first finished leaf: the default
  // half second of quiet would make the test depend on how fast the machine builds
  // (CI once built 2,048 fragments of the elephant before the bar was due).
  const std::string command = "SHATTER_PROGRESS_DELAY_MS=0 '" + std::string(SHATTER_EXE) + "' fracture " +
                              quoted(mesh_dir() / "elephant.off") + " --fragments 64 --threads 2 --out " +
                              quoted(dir / "t.shatter") + " >" + quoted(dir / "stdout.txt");
  const std::string transcript = (dir / "terminal.txt").string();
  const int status = std::system(("script -qec \"" + command + "\" /dev/null >'" + transcript + "' 2>&1").c_str());
  REQUIRE(WIFEXITED(status));
  REQUIRE(WEXITSTATUS(status) == 0);
  const std::string terminal = slurp(transcript);
  INFO(terminal);
  const std::size_t last_bar = terminal.rfind("fracturing [");
  REQUIRE(last_bar != std::string::npos);
  CHECK(terminal.find("leaves") != std::string::npos);
  // Erased: after the last bar, a carriage return, blanks, a carriage return, and
  // nothing else but what the terminal adds.
  const std::size_t erase = terminal.find('\r', last_bar);
  REQUIRE(erase != std::string::npos);
  const std::string tail = terminal.substr(erase);
  CHECK(tail.find_first_not_of(" \r\n") == std::string::npos);
  // The summary went to stdout as usual.
  CHECK(slurp(dir / "stdout.txt").find("fragments") != std::string::npos);

  // A delay that is not a whole number of milliseconds is a usage error, before
  // anything is read or written.
  for (const char* bad : {"-1", "0.5", "soon", "99999999999999999999"}) {
    INFO(bad);
    const fs::path out = dir / "bad.shatter";
    REQUIRE(::setenv("SHATTER_PROGRESS_DELAY_MS", bad, 1) == 0);
    const Run refused =
        run_shatter("fracture " + quoted(mesh_dir() / "elephant.off") + " --fragments 4 --out " + quoted(out));
    ::unsetenv("SHATTER_PROGRESS_DELAY_MS");
    CHECK(refused.exit_code == 2);
    CHECK(refused.err.find("SHATTER_PROGRESS_DELAY_MS") != std::string::npos);
    CHECK_FALSE(fs::exists(out));
  }
}

// --- the version, the exit-code table, all files or none -------------------------

TEST_CASE("shatter --version prints the project version, the one .shatter files and info carry") {
  const Run version = run_shatter("--version");
  CHECK(version.exit_code == 0);
  CHECK(version.out == std::string("shatter ") + SHATTER_VERSION + "\n");
  CHECK(version.err.empty());

  const fs::path dir = scratch("version");
  const Run fracture =
      run_shatter("fracture " + quoted(mesh_dir() / "cube.off") + " --fragments 3 --out " + quoted(dir / "t.shatter"));
  REQUIRE(fracture_problem(fracture, dir / "t.shatter") == "");
  // In the file: the optional `vers` section right after the header, holding the text.
  const std::string bytes = slurp(dir / "t.shatter");
  REQUIRE(bytes.size() > 16);
  CHECK(bytes.substr(12, 4) == "vers");
  CHECK(sections_of(bytes)["vers"] == SHATTER_VERSION);
  CHECK(info_of(dir / "t.shatter")["shatter_version"] == SHATTER_VERSION);
  const Run text = run_shatter("info " + quoted(dir / "t.shatter"));
  CHECK(text.out.find(std::string("\n  built by shatter ") + SHATTER_VERSION + "\n") != std::string::npos);

  // A file written before versions were recorded: the same file without `vers`.
  const std::size_t version_section = 16 + sections_of(bytes)["vers"].size();
  std::ofstream(dir / "old.shatter", std::ios::binary) << bytes.substr(0, 12) + bytes.substr(12 + version_section);
  const nlohmann::json old_info = info_of(dir / "old.shatter");
  CHECK(old_info["shatter_version"].is_null());
  CHECK(old_info["leaves"] == info_of(dir / "t.shatter")["leaves"]);
  CHECK(run_shatter("info " + quoted(dir / "old.shatter")).out.find("built by shatter") == std::string::npos);
}

TEST_CASE("every exit code of the table, each with one error line, and --help states the table") {
  const fs::path dir = scratch("exit-codes");
  fs::create_directories(dir);
  const std::string cube = quoted(mesh_dir() / "cube.off");
  const fs::path tree = dir / "t.shatter";
  REQUIRE(fracture_problem(run_shatter("fracture " + cube + " --fragments 2 --out " + quoted(tree)), tree) == "");
  std::string damaged = slurp(tree);
  damaged[damaged.size() / 2] = static_cast<char>(damaged[damaged.size() / 2] ^ 0x10);
  std::ofstream(dir / "damaged.shatter", std::ios::binary) << damaged;
  std::ofstream(dir / "a-file") << "x";

  struct Case {
    std::string what, arguments;
    int exit_code;
    std::string says;
  };
  const std::vector<Case> cases = {
      {"usage: a flag CLI11 refuses", "fracture " + cube + " --fragments 0 --out " + quoted(dir / "u.shatter"), 2,
       "(see --help)"},
      {"usage: flags a command finds inconsistent", "validate " + cube + " --out " + quoted(dir / "v.off"), 2,
       "--out writes the repaired mesh: it needs --repair"},
      {"invalid mesh", "slice " + quoted(bad_meshes().front()) + " --plane 0,0,1,0 --out " + quoted(dir / "s"), 3,
       "invalid mesh"},
      {"damaged .shatter file", "info " + quoted(dir / "damaged.shatter"), 3, "damaged .shatter file"},
      {"unwritable output", "slice " + cube + " --plane 0,0,1,-0.5 --out " + quoted(dir / "a-file" / "s"), 4,
       "cannot create output folder"},
  };
  for (const Case& c : cases) {
    INFO(c.what << ": " << c.arguments);
    const Run run = run_shatter(c.arguments);
    CHECK(run.exit_code == c.exit_code);
    CHECK(is_one_error_line(run.err));
    CHECK(run.err.find(c.says) != std::string::npos);
  }
  CHECK(names_in(dir) == std::vector<std::string>{"a-file", "damaged.shatter", "t.shatter"});
  CHECK(run_shatter("--help").out.find("Exit codes: 0 ok, 1 internal error, 2 usage error, 3 invalid input (mesh, "
                                       "geometry or .shatter file), 4 I/O error.") != std::string::npos);
}

// A file name longer than any file system allows (255 bytes): its folder can be
// made, but the file itself cannot be written, whoever runs the test (root too).
std::string unwritable_name(const std::string& extension) { return std::string(300, 'x') + "." + extension; }

TEST_CASE("all files or none: slice removes the pieces it wrote when the last one fails") {
  const fs::path dir = scratch("none-slice");
  fs::create_directories(dir / "out" / "above-0.off");  // a folder where the last piece goes
  std::ofstream(dir / "out" / "keep.txt") << "not this run's";
  const Run run = run_shatter("slice " + quoted(mesh_dir() / "cube.off") + " --plane 0,0,1,-0.5 --out " +
                              quoted(dir / "out"));
  CHECK(run.exit_code == 4);
  CHECK(is_one_error_line(run.err));
  CHECK(run.err.find("above-0.off") != std::string::npos);
  CHECK(run.out.empty());
  // below-0.off was written first, and is gone again; what was there stays.
  CHECK(names_in(dir / "out") == std::vector<std::string>{"above-0.off", "keep.txt"});
  CHECK(fs::is_directory(dir / "out" / "above-0.off"));
  // Without the obstacle the same run writes both pieces: the failure was the last write.
  fs::remove(dir / "out" / "above-0.off");
  REQUIRE(run_shatter("slice " + quoted(mesh_dir() / "cube.off") + " --plane 0,0,1,-0.5 --out " + quoted(dir / "out"))
              .exit_code == 0);
  CHECK(names_in(dir / "out") == std::vector<std::string>{"above-0.off", "below-0.off", "keep.txt"});
}

TEST_CASE("all files or none: fracture --export removes the leaves and folders it made when the tree fails") {
  const fs::path dir = scratch("none-fracture");
  fs::create_directories(dir);
  std::ofstream(dir / "keep.txt") << "not this run's";
  const std::string fracture = "fracture " + quoted(mesh_dir() / "cube.off") + " --fragments 4 --export " +
                               quoted(dir / "new" / "deeper" / "leaves") + " --out ";
  const Run run = run_shatter(fracture + quoted(dir / "tree-folder" / unwritable_name("shatter")));
  CHECK(run.exit_code == 4);
  CHECK(is_one_error_line(run.err));
  CHECK(run.out.empty());
  // The leaves, their three new folders and the tree's new folder are all gone.
  CHECK(names_in(dir) == std::vector<std::string>{"keep.txt"});
  // The same run with a tree name that can be written leaves them all.
  REQUIRE(fracture_problem(run_shatter(fracture + quoted(dir / "tree-folder" / "t.shatter")),
                           dir / "tree-folder" / "t.shatter") == "");
  CHECK(files_in(dir / "new" / "deeper" / "leaves") >= 4);
}

TEST_CASE("all files or none: export removes what it wrote when the last file fails") {
  const fs::path dir = scratch("none-export");
  fs::create_directories(dir);
  const fs::path tree = dir / "t.shatter";
  REQUIRE(fracture_problem(run_shatter("fracture " + quoted(mesh_dir() / "knot1.off") + " --fragments 5 --out " +
                                       quoted(tree)),
                           tree) == "");
  const std::size_t leaves = info_of(tree)["leaves"];
  REQUIRE(leaves >= 5);

  // Mesh files into a folder: a folder stands where the last leaf goes.
  const std::string last_leaf = leaf_file_names(leaves, "off").back();
  fs::create_directories(dir / "leaves" / last_leaf);
  const Run folder_run = run_shatter("export " + quoted(tree) + " --out " + quoted(dir / "leaves"));
  CHECK(folder_run.exit_code == 4);
  CHECK(is_one_error_line(folder_run.err));
  CHECK(folder_run.err.find(last_leaf) != std::string::npos);
  CHECK(names_in(dir / "leaves") == std::vector<std::string>{last_leaf});

  // One GLB in folders the run makes: the file cannot be written, the folders go.
  const Run glb_run =
      run_shatter("export " + quoted(tree) + " --out " + quoted(dir / "new" / "glb" / unwritable_name("glb")));
  CHECK(glb_run.exit_code == 4);
  CHECK(is_one_error_line(glb_run.err));
  CHECK(names_in(dir) == std::vector<std::string>{"leaves", "t.shatter"});

  // Without the obstacles the same runs write everything.
  fs::remove(dir / "leaves" / last_leaf);
  REQUIRE(run_shatter("export " + quoted(tree) + " --out " + quoted(dir / "leaves")).exit_code == 0);
  CHECK(names_in(dir / "leaves") == leaf_file_names(leaves, "off"));
  REQUIRE(run_shatter("export " + quoted(tree) + " --out " + quoted(dir / "new" / "glb" / "t.glb")).exit_code == 0);
  CHECK(fs::is_regular_file(dir / "new" / "glb" / "t.glb"));
}

TEST_CASE("fracture --pattern: every Voronoi pattern writes a valid tree, simulate breaks it, bad input is refused") {
  const fs::path dir = scratch("voronoi");
  fs::create_directories(dir);
  const std::string cube = quoted(mesh_dir() / "cube.off");
  const std::string sphere = quoted(mesh_dir() / "sphere.off");
  {
    std::ofstream(dir / "sites.txt") << "# four sites\n-0.5 0 0\n0.5 0 0\n0 0.5 0\n0 -0.5 0.25\n";
  }
  const std::vector<std::pair<std::string, std::size_t>> runs = {
      {cube + " --pattern voronoi --sites 30", 30},
      {sphere + " --pattern clustered --clusters 3 --sites-per-cluster 4 --cluster-radius 0.1", 2},
      {cube + " --pattern radial --rings 2 --sectors 6 --centre 0,0,0 --direction 0,0,1 --variability 0.2", 7},
      {cube + " --pattern grid --cells 3,2,2 --jitter 0.3", 12},
      {sphere + " --pattern brick --cells 3,3,2 --offset 0.5", 2},
      {cube + " --pattern sites --sites-file " + quoted(dir / "sites.txt"), 4}};
  for (std::size_t i = 0; i < runs.size(); ++i) {
    INFO(runs[i].first);
    const fs::path tree = dir / ("v" + std::to_string(i) + ".shatter");
    const Run run = run_shatter("fracture " + runs[i].first + " --threads 2 --out " + quoted(tree));
    REQUIRE(fracture_problem(run, tree) == "");
    const Run check = run_shatter("info --check --json " + quoted(tree));
    REQUIRE(check.exit_code == 0);
    const nlohmann::json info = nlohmann::json::parse(check.out);
    CHECK(info["check"] == "valid");
    CHECK(info["leaves"].get<std::size_t>() >= runs[i].second);
    CHECK(info["bonds"]["count"].get<std::size_t>() > 0);
  }
  // The same at one thread, byte for byte.
  REQUIRE(run_shatter("fracture " + runs[0].first + " --threads 1 --out " + quoted(dir / "one.shatter")).exit_code == 0);
  CHECK(slurp(dir / "one.shatter") == slurp(dir / "v0.shatter"));
  // A Voronoi tree breaks in the runtime.
  const Run shot = run_shatter("simulate " + quoted(dir / "v0.shatter") + " --scene shoot --steps 120 --json");
  REQUIRE(shot.exit_code == 0);
  CHECK(nlohmann::json::parse(shot.out)["breaks"].size() > 0);

  // A bad sites file: exit 3, one line naming the line.
  {
    std::ofstream(dir / "bad.txt") << "0 0 0\n1 2 three\n";
  }
  const Run bad = run_shatter("fracture " + cube + " --pattern sites --sites-file " + quoted(dir / "bad.txt") +
                              " --out " + quoted(dir / "bad.shatter"));
  CHECK(bad.exit_code == 3);
  CHECK(is_one_error_line(bad.err));
  CHECK(bad.err.find("line 2") != std::string::npos);
  CHECK_FALSE(fs::exists(dir / "bad.shatter"));
  // Usage mistakes: exit 2 before anything is read.
  for (const std::string& arguments :
       {cube + " --pattern voronoi", cube + " --pattern voronoi --sites 4 --fragments 4", cube + " --pattern hex --sites 4",
        cube + " --pattern radial --rings 2", cube + " --pattern radial --rings 2 --sectors 3 --direction 0,0,0",
        cube + " --pattern grid --cells 2,2", cube + " --pattern brick --cells 2,0,2", cube + " --pattern sites",
        cube + " --pattern radial --rings 1 --sectors 3 --variability 2", cube + " --fragments 4 --strategy voronoi"}) {
    INFO(arguments);
    const Run run = run_shatter("fracture " + arguments + " --out " + quoted(dir / "u.shatter"));
    CHECK(run.exit_code == 2);
    CHECK(is_one_error_line(run.err));
  }
  const Run help = run_shatter("fracture --help");
  for (const char* option : {"--pattern", "voronoi", "clustered", "radial", "grid", "brick", "--sites", "--clusters",
                             "--sites-per-cluster", "--cluster-radius", "--centre", "--direction", "--rings",
                             "--sectors", "--radius", "--variability", "--cells", "--offset", "--jitter",
                             "--sites-file", "mesh units"}) {
    INFO(option);
    CHECK(help.out.find(option) != std::string::npos);
  }
}
