// shatter-seed-peer: the seed thesis's fragment modeller (chapter 4) as a benchmark
// peer. Reads a closed mesh, fractures it to N fragments the seed's way in single
// precision, validates every fragment with shatter's validate_mesh (the only use of
// shatter besides reading the file: no decision of the method goes through it), and
// prints one JSON line: fragments reached, time, and the first failure with its kind.
// README.md in this folder states every choice the thesis leaves open.

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <chrono>
#include <exception>
#include <iostream>

#include "../../command_line.hpp"
#include "seed_mesh.hpp"
#include "seed_modeller.hpp"
#include "shatter/kernel/io.hpp"
#include "shatter/kernel/validate.hpp"

namespace {

using namespace seed_peer;

constexpr int exit_ok = 0;        // every fragment made and valid
constexpr int exit_failed = 1;    // the method stopped or made an invalid fragment: the JSON says which
constexpr int exit_usage = 2;     // bad options or an unreadable mesh: one line on stderr, no JSON

double signed_volume(const shatter::Mesh& mesh) {
  double six = 0;
  for (const auto& t : mesh.triangles) six += dot(mesh.positions[t[0]], cross(mesh.positions[t[1]], mesh.positions[t[2]]));
  return six / 6;
}

Compare parse_compare(const std::string& s) { return s == "exact" ? Compare::exact : Compare::unity; }

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"The seed thesis's fragment modeller (Nielsen 2013, ch. 4) in single precision, as a benchmark "
               "peer: recursive planes through each piece's centre of mass, float cut points, border edges "
               "linked by comparing positions, caps by constrained Delaunay triangulation, hulls separated. "
               "Prints one JSON line; exit 0 when every fragment is made and valid, 1 when the method failed "
               "(the JSON names how), 2 on bad options or an unreadable mesh."};
  std::string mesh_path;
  int fragments = 8;
  std::uint32_t seed = 1;
  double time_cap = 600;
  std::string compare = "unity", weld = "unity", linker = "listing", area_origin = "mesh";
  bool validate = true;
  app.add_option("mesh", mesh_path, "closed triangle mesh (OFF, OBJ, PLY, STL)")->required();
  app.add_option("--fragments,-n", fragments, "fragments to make")->check(CLI::Range(1, 1 << 30));
  app.add_option("--seed", seed, "seed of the plane generator (std::mt19937)");
  app.add_option("--time-cap", time_cap, "seconds; the run stops (failure kind timeout) once past it")
      ->check(CLI::PositiveNumber);
  app.add_option("--compare", compare,
                 "how border-edge ends and shared hull vertices are compared: unity (Vector3 ==, "
                 "distance below 1e-5, the seed's) or exact (bitwise float equality)")
      ->check(CLI::IsMember({"unity", "exact"}));
  app.add_option("--weld", weld,
                 "which corners become one vertex when a fragment is validated: unity (the seed's own "
                 "Vector3 ==) or exact (bitwise)")
      ->check(CLI::IsMember({"unity", "exact"}));
  app.add_option("--linker", linker,
                 "listing (Listing 4.4 as printed: closure checked only after an edge is appended) or "
                 "check-first (not in the text: a loop closes as soon as it returns to its start, loops of "
                 "fewer than 3 vertices dropped)")
      ->check(CLI::IsMember({"listing", "check-first"}));
  app.add_option("--area-origin", area_origin,
                 "where Eq. 4.1's triangles meet: mesh (the mesh's origin, as the text says) or plane (the "
                 "plane's point nearest it, not in the text: Eq. 4.1 is then the loop's area)")
      ->check(CLI::IsMember({"mesh", "plane"}));
  app.add_flag("!--no-validate", validate, "skip validating the fragments (the build's own failures only)");
  if (const auto code = shatter::bench::parse_command_line(app, argc, argv, exit_usage)) return *code;

  const auto start = std::chrono::steady_clock::now();
  shatter::Mesh input;
  try {
    input = shatter::read_mesh(mesh_path);
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return exit_usage;
  }

  BuildOptions options;
  options.fragments = fragments;
  options.seed = seed;
  options.slice.compare = parse_compare(compare);
  options.slice.linker = linker == "check-first" ? Linker::check_first : Linker::listing;
  options.slice.area_origin = area_origin == "plane" ? AreaOrigin::plane : AreaOrigin::mesh;
  options.time_cap = time_cap;
  BuildResult build = build_fragments(to_piece(input), options, start);

  // Validation of every fragment (untimed in "seconds"), unless the build already failed.
  Failure failure = build.failure;
  std::size_t invalid = 0, checked = 0;
  double validate_seconds = 0;
  if (validate && failure.kind == FailureKind::none) {
    const auto v0 = std::chrono::steady_clock::now();
    const Compare weld_by = parse_compare(weld);
    for (std::size_t i = 0; i < build.leaves.size(); ++i) {
      if (std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() > time_cap) {
        if (failure.kind == FailureKind::none)
          failure = {FailureKind::timeout, 0, static_cast<int>(i),
                     "validation passed the cap after " + std::to_string(i) + " fragments"};
        break;
      }
      const shatter::Mesh mesh = to_mesh(build.leaves[i], weld_by);
      const shatter::ValidationReport report = shatter::validate_mesh(mesh);
      ++checked;
      std::string defect;
      if (!report.valid()) defect = report.summary();
      else if (!(signed_volume(mesh) > 0)) defect = "zero volume";
      if (defect.empty()) continue;
      ++invalid;
      if (failure.kind == FailureKind::none)
        failure = {FailureKind::invalid_piece, 0, static_cast<int>(i),
                   "fragment " + std::to_string(i) + " (" + std::to_string(mesh.triangles.size()) +
                       " triangles): " + defect};
    }
    validate_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - v0).count();
  }

  std::size_t triangles = 0;
  for (const auto& leaf : build.leaves) triangles += leaf.triangles.size();
  nlohmann::json out = {
      {"tool", "seed-peer"},
      {"mesh", mesh_path},
      {"seed", seed},
      {"fragments_requested", fragments},
      {"fragments", build.leaves.size()},
      {"levels", build.levels},
      {"triangles", triangles},
      {"status", failure.kind == FailureKind::none ? "ok"
                 : failure.kind == FailureKind::timeout ? "timeout" : "failed"},
      {"seconds", build.seconds},
      {"validated", validate},
      {"validate_seconds", validate_seconds},
      {"fragments_checked", checked},
      {"invalid_fragments", invalid},
      {"compare", compare},
      {"weld", weld},
      {"linker", linker},
      {"area_origin", area_origin},
      {"border_edges", build.stats.border_edges},
      {"tiny_border_edges", build.stats.tiny_border_edges},
      {"loops", build.stats.loops},
      {"misclassified_loops", build.stats.misclassified_loops},
      {"dropped_loops", build.stats.dropped_loops},
  };
  if (failure.kind == FailureKind::none) {
    out["failure"] = nullptr;
  } else {
    out["failure"] = {{"kind", failure_name(failure.kind)},
                      {"stage", failure.level > 0 ? "build" : "validation"},
                      {"level", failure.level},
                      {"piece", failure.piece},
                      {"detail", failure.detail}};
  }
  std::cout << out.dump() << std::endl;
  return failure.kind == FailureKind::none ? exit_ok : exit_failed;
}
