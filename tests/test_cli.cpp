// End-to-end tests of the shatter command: exit codes, the one-line error, files
// written (and nothing left behind on failure), determinism of the bytes.

#include <catch2/catch.hpp>

#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <map>
#include <fstream>
#include <sstream>

#include "shatter/kernel/io.hpp"
#include "shatter/kernel/validate.hpp"
#include "support/checks.hpp"
#include "support/corpus.hpp"

using namespace shatter;
using namespace shatter::test;
namespace fs = std::filesystem;

namespace {

struct Run {
  int exit_code;
  std::string out;
  std::string err;
};

std::string slurp(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

fs::path scratch(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("shatter-cli-test-" + std::to_string(::getpid())) / name;
  fs::remove_all(dir);
  fs::create_directories(dir.parent_path());
  return dir;
}

// Runs the shatter binary with `arguments` (already shell-quoted).
Run run_shatter(const std::string& arguments) {
  const fs::path out = scratch("stdout.txt"), err = scratch("stderr.txt");
  const std::string command = std::string("'") + SHATTER_EXE + "' " + arguments + " >'" + out.string() + "' 2>'" +
                              err.string() + "' </dev/null";
  const int status = std::system(command.c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(out), slurp(err)};
}

std::string quoted(const fs::path& p) { return "'" + p.string() + "'"; }

bool is_one_error_line(const std::string& err) {
  return err.rfind("error: ", 0) == 0 && err.find('\n') == err.size() - 1;
}

std::size_t files_in(const fs::path& dir) {
  if (!fs::exists(dir)) return 0;
  return static_cast<std::size_t>(std::distance(fs::directory_iterator(dir), fs::directory_iterator()));
}

}  // namespace

TEST_CASE("every bad mesh is refused with exit 3 and a line naming its defect") {
  const std::map<std::string, std::string> defect_of = {
      {"cube-ouvert.off", "boundary edges"},         {"tet-shuffled.off", "inconsistent"},
      {"tetrahedron.off", "inward"},                 {"degtri_sliding.off", "zero-area"},
      {"elephant-with-holes.off", "boundary edges"}, {"tetra_intersected_by_triangle.off", "boundary edges"}};
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
    for (const std::string kernel : {"fast", "exact"}) {
      INFO(format << " " << kernel);
      const fs::path first = scratch("first"), second = scratch("second");
      const std::string flags = " --plane 0.3,0.5,0.8,-0.2 --kernel " + kernel + " --format " + format + " --json";
      const Run a = run_shatter("slice " + quoted(mesh) + flags + " --out " + quoted(first));
      const Run b = run_shatter("slice " + quoted(mesh) + flags + " --out " + quoted(second));
      REQUIRE(a.exit_code == 0);
      REQUIRE(b.exit_code == 0);
      CHECK(a.out.find("\"invalid_embeddings\": 0") != std::string::npos);
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
}

TEST_CASE("a plane that misses returns the mesh whole and says so") {
  const fs::path out = scratch("miss");
  const Run run = run_shatter("slice " + quoted(mesh_dir() / "cube.off") + " --plane 0,0,1,10 --out " + quoted(out));
  CHECK(run.exit_code == 0);
  CHECK(run.out.find("returned whole") != std::string::npos);
  CHECK(files_in(out) == 1);
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
