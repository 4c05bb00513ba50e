// The robustness runner's own tests: reproducers keep their case, cases are
// reproducible and cover every class, the checks can fail, and the degenerate
// generators are what they claim.

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <array>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "robustness/corpus_export.hpp"
#include "robustness/robustness.hpp"
#include "shatter/generators/corpus.hpp"
#include "shatter/generators/solids.hpp"
#include "shatter/kernel/error.hpp"
#include "shatter/kernel/io.hpp"
#include "shatter/meshtree/build.hpp"
#include "support/checks.hpp"
#include "support/degenerate.hpp"
#include "support/scratch.hpp"

using namespace shatter;
using namespace shatter::robust;
namespace fs = std::filesystem;

namespace {

fs::path scratch(const std::string& name) {
  const fs::path dir = shatter::test::process_scratch_folder("shatter-test-robustness") / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

}  // namespace

TEST_CASE("a reproducer keeps the case: planes bit for bit, mesh, options") {
  const MeshPool pool = MeshPool::load();
  const fs::path dir = scratch("round-trip");
  for (std::uint64_t index = 0; index < 4 * case_class_count; ++index) {
    const Case c = make_case(pool, 99, index);
    INFO(class_name(c.kind) << " " << c.mesh_name);
    const Case back = read_reproducer(write_reproducer(dir, c, "a failure\nwith a second line"));
    CHECK(back.kind == c.kind);
    CHECK(back.op == c.op);
    CHECK(back.format == c.format);
    CHECK(back.seed == c.seed);
    CHECK(back.mesh_name == c.mesh_name);
    REQUIRE(back.planes.size() == c.planes.size());
    for (std::size_t i = 0; i < c.planes.size(); ++i) {
      CHECK(same_bits(back.planes[i].normal.x, c.planes[i].normal.x));
      CHECK(same_bits(back.planes[i].normal.y, c.planes[i].normal.y));
      CHECK(same_bits(back.planes[i].normal.z, c.planes[i].normal.z));
      CHECK(same_bits(back.planes[i].offset, c.planes[i].offset));
    }
    if (c.op == Operation::fracture) {
      CHECK(back.recipe.fragments == c.recipe.fragments);
      CHECK(back.recipe.seed == c.recipe.seed);
      CHECK(back.recipe.strategy == c.recipe.strategy);
    }
    // The same mesh, bit for bit: cases number their vertices as readers do, so
    // a replay cuts the very solid (the plane kernel's points name input points by
    // index). A second trip is the identity too.
    CHECK(back.mesh.triangles.size() == c.mesh.triangles.size());
    CHECK(test::exact_six_volume(back.mesh) == test::exact_six_volume(c.mesh));
    CHECK(back.mesh.corners.has_normals() == c.mesh.corners.has_normals());
    CHECK(test::canonical_bytes(back.mesh) == test::canonical_bytes(c.mesh));
    const Case twice = read_reproducer(write_reproducer(dir, back, "again"));
    CHECK(test::canonical_bytes(twice.mesh) == test::canonical_bytes(back.mesh));
  }
}

TEST_CASE("a reproducer may name a corpus mesh and pin its outcome, and a replay that differs fails") {
  // tests/regressions' issue-10 file: the elephant, read from the corpus as
  // `shatter` reads it, and the outcome it must show.
  const fs::path regressions = test::mesh_dir().parent_path().parent_path() / "regressions";
  const Mesh elephant = read_mesh(test::mesh_dir() / "elephant.off");
  const Case c = read_reproducer(regressions / "issue10-elephant-vertex-plane-slice-plane.repro");
  CHECK(test::canonical_bytes(c.mesh) == test::canonical_bytes(elephant));
  REQUIRE(c.planes.size() == 1);
  CHECK(c.planes[0].offset == -0.062960299999999997);
  CHECK(c.expected == Expected::valid_as_written);
  const CaseOutcome outcome = run_case(c);
  CHECK(outcome.failures.empty());
  CHECK(unmet_expectation(c, outcome) == "");
  // An outcome other than the one pinned is not met: the replay would fail.
  CaseOutcome refused = outcome;
  ++refused.plane_unroundable;
  CHECK(unmet_expectation(c, refused) != "");
  // A name, never a path out of the corpus; unknown expectations and reproducers
  // of the retired kernels are refused.
  const fs::path dir = scratch("corpus-reproducer");
  for (const auto& [field, value] : {std::pair{"mesh-corpus", "../regressions/x.repro"}, std::pair{"expect", "passes"},
                                     std::pair{"expect", "refused-as-written"}, std::pair{"kernel", "fast"}}) {
    std::ofstream(dir / "bad.repro") << "shatter-reproducer 1\n" << field << " " << value << "\nmesh-corpus cube.off\n";
    CHECK_THROWS_AS(read_reproducer(dir / "bad.repro"), InvalidMeshError);
  }
}

TEST_CASE("operations are drawn slice 3/4, fracture 1/4, and output formats OFF 3/4, others 1/4") {
  const MeshPool pool = MeshPool::load();
  std::map<Operation, int> operations;
  std::map<MeshFormat, int> formats;
  constexpr int cases = 400;
  for (std::uint64_t index = 0; index < cases; ++index) {
    const Case c = make_case(pool, 20261129, index);
    ++operations[c.op];
    ++formats[c.format];
  }
  INFO("slices " << operations[Operation::slice] << ", fractures " << operations[Operation::fracture]);
  CHECK(operations[Operation::fracture] >= cases * 15 / 100);
  CHECK(operations[Operation::slice] >= cases * 65 / 100);
  CHECK(formats[MeshFormat::off] >= cases * 65 / 100);
  for (MeshFormat f : {MeshFormat::obj, MeshFormat::ply, MeshFormat::stl}) CHECK(formats[f] > 0);
}

TEST_CASE("cases are a pure function of (seed, index), and every class is drawn") {
  const MeshPool pool = MeshPool::load();
  std::vector<int> per_class(case_class_count, 0);
  for (std::uint64_t index = 0; index < 2 * case_class_count; ++index) {
    const Case a = make_case(pool, 7, index), b = make_case(pool, 7, index);
    CHECK(test::canonical_bytes(a.mesh) == test::canonical_bytes(b.mesh));
    REQUIRE(a.planes.size() == b.planes.size());
    for (std::size_t i = 0; i < a.planes.size(); ++i) CHECK(same_bits(a.planes[i].offset, b.planes[i].offset));
    ++per_class[static_cast<std::size_t>(a.kind)];
    CHECK(test::solid_problem(a.mesh) == "");
  }
  for (int count : per_class) CHECK(count == 2);
}

TEST_CASE("slice chains and fractures pass, every piece written and read back valid") {
  Case c;
  c.mesh = test::staircase(3);
  // A tread plane (holding faces), then a plane through vertices up to rounding.
  c.planes = {test::axis_plane_through({1, 0, 1}, 2), test::plane_through({1, 1, 1}, {1, 1, 0.5})};
  for (MeshFormat format : {MeshFormat::off, MeshFormat::obj, MeshFormat::ply, MeshFormat::stl}) {
    c.format = format;
    const CaseOutcome outcome = run_case(c);
    CHECK(outcome.failures == std::vector<std::string>{});
    CHECK(outcome.plane_pieces >= 4);
    CHECK(outcome.written + outcome.plane_unroundable + outcome.plane_vanished == outcome.plane_pieces);
    CHECK(outcome.invalid_written == 0);
  }
  // With attributes: every triangle its own face, attributes interpolated.
  c.mesh = test::with_seams(test::torus(1, 0.3, 12, 8));
  c.planes = {test::plane_through({0.1, 0, 0}, {1, 0.2, 0.1})};
  CHECK(run_case(c).failures == std::vector<std::string>{});
  c.op = Operation::fracture;
  c.mesh = test::torus(1, 0.3, 12, 8);
  c.recipe.fragments = 4;
  c.recipe.seed = 4;  // a multiple of 4: the 2-thread rebuild is compared too
  c.seed = 4;
  const CaseOutcome fracture = run_case(c);
  CHECK(fracture.failures == std::vector<std::string>{});
  CHECK(!fracture.refused);
  CHECK(fracture.written >= 4);
  CHECK(fracture.plane_pieces > fracture.written);  // every node, the root too
}

TEST_CASE("a failure is caught, shrunk to the chain's prefix and reproduced when replayed") {
  // An inward cube breaks the cut's precondition: the exact volumes come out
  // negative, a failure at the first cut of a two-cut chain.
  Case c;
  c.mesh = test::flipped(test::unit_cube());
  c.planes = {test::plane_through({0.5, 0.5, 0.5}, {0.3, 0.4, 1}), test::axis_plane_through({0.25, 0, 0}, 0)};
  const CaseOutcome outcome = run_case(c);
  REQUIRE(!outcome.failures.empty());
  REQUIRE(outcome.shrunk.has_value());
  CHECK(outcome.shrunk->planes.size() == 1);
  const fs::path dir = scratch("plane-failure");
  const fs::path path = write_reproducer(dir, *outcome.shrunk, outcome.failures.front());
  const Case back = read_reproducer(path);
  CHECK(!run_case(back).failures.empty());
}

TEST_CASE("the plane kernel's predicates agree with the audit's own exact reference") {
  const PlaneAuditResult r = audit_plane_predicates(30000, 7, 1);
  CHECK(r.queries == 30000);
  CHECK(r.disagreements == 0);
  INFO(r.first_disagreement);
  for (int row = 0; row < plane_audit_rows; ++row) {
    INFO(plane_audit_row_name(row));
    // Every predicate is asked in every band, and the exact band holds true zeros
    // that the floating-point filter must hand to exact arithmetic.
    for (int band = 0; band < 3; ++band) CHECK(r.bands[row][band].queries > 0);
    CHECK(r.bands[row][0].on_plane > 0);
    CHECK(r.bands[row][0].exact_fallbacks > 0);
  }
}

TEST_CASE("degenerate generators give valid solids with exact degeneracies") {
  for (int steps = 1; steps <= 6; ++steps) CHECK(test::solid_problem(test::staircase(steps)) == "");
  for (int floors = 1; floors <= 5; ++floors) CHECK(test::solid_problem(test::stacked_boxes(floors)) == "");
  for (int k = 10; k <= 40; k += 10) {
    CHECK(test::solid_problem(test::needle_bridge(std::ldexp(1.0, -k))) == "");
    CHECK(test::solid_problem(test::flat_tetrahedron(std::ldexp(1.0, -k))) == "");
  }
  CHECK(test::solid_problem(test::nested_islands()) == "");
  CHECK(test::solid_problem(test::with_seams(test::torus(1, 0.3, 8, 6))) == "");
  // The saddle: z = 0 holds the saddle vertex and the four top corners exactly.
  const Mesh saddle = test::pinch_saddle();
  REQUIRE(test::solid_problem(saddle) == "");
  const test::PlaneContact contact = test::plane_contact(saddle, test::axis_plane_through({1, 1, 0}, 2));
  CHECK(contact.on == 5);
  CHECK(contact.above == 2);
  CHECK(contact.below == 6);
  // Moved one ulp, the plane holds none of them.
  CHECK(test::plane_contact(saddle, test::offset_by_ulps({{0, 0, 1}, -1.0}, 1)).on == 0);
  // A staircase tread plane holds whole faces: many vertices on it.
  CHECK(test::plane_contact(test::staircase(4), test::axis_plane_through({0, 0, 2}, 2)).on >= 8);
  // Near-parallel planes through one edge all hold its first end up to rounding.
  for (const Plane& p : test::near_parallel_fan({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, 4, 1e-3, 1e-2)) {
    CHECK(p.offset == 0);
  }
}

TEST_CASE("an exported corpus holds every case exactly as drawn, and nothing half-written", "[export]") {
  const MeshPool pool = MeshPool::load();
  const std::uint64_t seed = 20261203;
  std::vector<std::uint64_t> indices;
  for (std::uint64_t i = 0; i < 2 * case_class_count; ++i) indices.push_back(i);  // every class twice
  const fs::path dir = scratch("export") / "corpus";
  const ExportSummary summary = export_corpus(pool, seed, indices, dir);
  CHECK(summary.cases == indices.size());
  CHECK_FALSE(fs::exists(fs::path(dir.string() + ".partial")));
  REQUIRE(fs::exists(dir / "README.md"));

  std::ifstream in(dir / "manifest.json");
  const nlohmann::json manifest = nlohmann::json::parse(in);
  CHECK(manifest["seed"] == seed);
  REQUIRE(manifest["cases"].size() == indices.size());
  std::size_t mesh_files = 0;
  for (const auto& entry : fs::directory_iterator(dir / "meshes")) mesh_files += entry.is_regular_file() ? 1 : 0;
  CHECK(mesh_files == summary.mesh_files);
  CHECK(mesh_files < indices.size());  // cases on one corpus mesh share its file

  for (std::size_t k = 0; k < indices.size(); ++k) {
    const nlohmann::json& entry = manifest["cases"][k];
    const Case c = make_case(pool, seed, indices[k]);
    INFO("case " << indices[k] << " (" << class_name(c.kind) << ")");
    CHECK(entry["id"] == indices[k]);
    CHECK(entry["class"] == std::string(class_name(c.kind)));
    CHECK(entry["seed"] == c.seed);
    CHECK(entry["operation"] == std::string(operation_name(c.op)));
    // The mesh reads back bit for bit, attributes included.
    const Mesh read = read_mesh(dir / entry["mesh"].get<std::string>());
    REQUIRE(read.vertex_count() == c.mesh.vertex_count());
    for (std::size_t v = 0; v < read.vertex_count(); ++v) {
      REQUIRE(same_bits(read.positions[v].x, c.mesh.positions[v].x));
      REQUIRE(same_bits(read.positions[v].y, c.mesh.positions[v].y));
      REQUIRE(same_bits(read.positions[v].z, c.mesh.positions[v].z));
    }
    CHECK(read.triangles == c.mesh.triangles);
    CHECK(read.corners.uvs == c.mesh.corners.uvs);
    CHECK(read.corners.normals == c.mesh.corners.normals);
    if (c.op == Operation::slice) {
      REQUIRE(entry["planes"].size() == c.planes.size());
      for (std::size_t p = 0; p < c.planes.size(); ++p) {
        const std::array<double, 4> expected = {c.planes[p].normal.x, c.planes[p].normal.y, c.planes[p].normal.z,
                                                c.planes[p].offset};
        for (std::size_t q = 0; q < 4; ++q) {
          // Both spellings give the very doubles of the case.
          CHECK(same_bits(entry["planes"][p][q].get<double>(), expected[q]));
          CHECK(same_bits(std::strtod(entry["planes_hex"][p][q].get<std::string>().c_str(), nullptr), expected[q]));
        }
      }
    } else {
      CHECK(entry["fragments"] == c.recipe.fragments);
      CHECK(entry["build_seed"] == c.recipe.seed);
      CHECK(entry["strategy"] == std::string(strategy_name(c.recipe.strategy)));
    }
  }

  // The same cases give the same bytes; an existing folder is refused untouched.
  const fs::path again = scratch("export-again") / "corpus";
  export_corpus(pool, seed, indices, again);
  const auto bytes_of = [](const fs::path& path) {
    std::ifstream file(path, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  };
  CHECK(bytes_of(dir / "manifest.json") == bytes_of(again / "manifest.json"));
  CHECK_THROWS_AS(export_corpus(pool, seed, indices, dir), std::invalid_argument);
  CHECK(bytes_of(dir / "manifest.json") == bytes_of(again / "manifest.json"));
}
