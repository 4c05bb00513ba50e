// shatter-bench-cut: one plane cut through the volume centroid, timed per input
// triangle for shatter's cut against CGAL PMP clip with clip_volume(true) run on
// both sides of the same plane. shatter's time is the library's one cut call, whole
// output included (cut_by_plane: the exact cut, then every piece rounded and
// certified against the validated input); its input conversion
// (prepare_plane_input) is timed apart, since a caller cutting on pays it once.
//
// Inputs: knot1.off and fandisk.off from the mesh folder, and a subdivided
// icosahedron projected to the unit sphere (20 * 4^K triangles, K = 8 by default:
// 1,310,720 triangles). Both methods see the same plane n·x + d = 0 with n the
// normalised (0.3, 0.5, 0.8) and d = -n·c, c the volume centroid.
//
// The input check `shatter slice` and `shatter fracture` make before cutting is
// timed on its own, two ways: as the commands make it (require_valid_solid: the
// piece certificate first, the self-intersection search only where it declines;
// since fbb9a22) and as the full search alone (validate_mesh, self-intersections
// included: what every input paid before). Check (the commands') + prepare + cut
// is the whole single-cut path after reading the file.
//
// Timing: std::chrono::steady_clock around the cut call only. Everything a method
// needs beforehand is prepared outside the clock on every run: shatter's
// prepare_plane_input (timed separately and reported), CGAL's two Surface_mesh
// copies. The outputs are destroyed after the clock stops. Each measurement is
// repeated until it has taken >= 0.3 s in total and at least 3 runs (a run that
// takes more than 60 s is not repeated); the median is reported. Validity checks
// run outside the clock, on the output of the first run.

#include <CGAL/Surface_mesh.h>
#include <CGAL/boost/graph/helpers.h>

#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <iostream>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <unordered_map>
#include <vector>

#include "bench_support.hpp"
#include "command_line.hpp"
#include "csv.hpp"
#include "shatter/generators/corpus.hpp"
#include "shatter/cut/plane_cut.hpp"
#include "shatter/cut/plane_input.hpp"
#include "shatter/kernel/io.hpp"
#include "shatter/kernel/mass.hpp"
#include "shatter/kernel/mesh.hpp"
#include "shatter/kernel/validate.hpp"

namespace {

using shatter::bench::CgalMesh;
using shatter::bench::cgal_clip_volume;
using shatter::bench::cgal_component_count;
using shatter::bench::cgal_self_intersects;
using shatter::bench::CsvWriter;
using shatter::bench::Epick;
using shatter::bench::fixed;
using shatter::bench::not_measured;
using shatter::bench::ratio_text;
using shatter::bench::signal_in_forked_child;
using shatter::bench::to_cgal;
using shatter::bench::with_thousands;
using Clock = std::chrono::steady_clock;

struct Options {
  std::filesystem::path mesh_dir = shatter::test::mesh_dir();
  std::optional<std::filesystem::path> csv;
  std::optional<int> sphere_subdivisions;
  bool quick = false;
  bool validate = true;
  bool cgal = true;         ///< time CGAL's clip too
  bool sphere_only = false;  ///< skip knot1 and fandisk
};

struct RepeatPolicy {
  int min_runs = 3;
  double min_total_seconds = 0.3;
  int max_runs = 1000;
  double no_repeat_seconds = 60.0;  ///< a run longer than this is not repeated
};

// ---------------------------------------------------------------------------
// The generated sphere: a subdivided icosahedron, welded, closed, outward.

shatter::Mesh make_icosphere(int subdivisions) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  shatter::Mesh mesh;
  const shatter::Vec3 base[12] = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                                  {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  for (const auto& p : base) mesh.positions.push_back(shatter::normalized(p));
  mesh.triangles = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                    {11, 10, 2}, {10, 7, 6}, {7, 1, 8},   {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                    {3, 8, 9},  {4, 9, 5},  {2, 4, 11},  {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (int level = 0; level < subdivisions; ++level) {
    std::unordered_map<std::uint64_t, shatter::VertexIndex> midpoints;
    midpoints.reserve(mesh.triangles.size() * 2);
    auto midpoint = [&](shatter::VertexIndex a, shatter::VertexIndex b) {
      const std::uint64_t key = (std::uint64_t{std::min(a, b)} << 32) | std::max(a, b);
      auto [it, inserted] = midpoints.try_emplace(key, 0);
      if (inserted) {
        it->second = static_cast<shatter::VertexIndex>(mesh.positions.size());
        mesh.positions.push_back(shatter::normalized((mesh.positions[a] + mesh.positions[b]) * 0.5));
      }
      return it->second;
    };
    std::vector<shatter::Triangle> next;
    next.reserve(mesh.triangles.size() * 4);
    for (const auto& [a, b, c] : mesh.triangles) {
      const auto ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
      next.push_back({a, ab, ca});
      next.push_back({b, bc, ab});
      next.push_back({c, ca, bc});
      next.push_back({ab, bc, ca});
    }
    mesh.triangles = std::move(next);
  }
  mesh.surfaces.assign(mesh.triangles.size(), shatter::original_surface);
  return mesh;
}

// ---------------------------------------------------------------------------
// Timing.

struct Timing {
  double median_ms = 0;
  int runs = 0;
  double setup_ms = 0;  ///< median time of the per-run preparation outside the clock
};

double ms_between(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

/// Runs `setup` (untimed), then `run` on its result (timed), repeatedly; calls
/// `inspect` (untimed) on the first run's output.
template <class Setup, class Run, class Inspect>
Timing measure(const RepeatPolicy& policy, Setup setup, Run run, Inspect inspect) {
  std::vector<double> times, setups;
  double total = 0;
  for (int i = 0; i < policy.max_runs; ++i) {
    const auto s0 = Clock::now();
    auto input = setup();
    const auto t0 = Clock::now();
    auto output = run(input);
    const auto t1 = Clock::now();
    const double ms = ms_between(t0, t1);
    times.push_back(ms);
    setups.push_back(ms_between(s0, t0));
    total += ms / 1000.0;
    if (i == 0) inspect(output);
    if (ms / 1000.0 > policy.no_repeat_seconds) break;
    if (static_cast<int>(times.size()) >= policy.min_runs && total >= policy.min_total_seconds) break;
  }
  return {shatter::bench::median(times, 0), static_cast<int>(times.size()), shatter::bench::median(setups, 0)};
}

// ---------------------------------------------------------------------------
// One input.

struct Row {
  std::string name;
  std::size_t triangles = 0;
  Timing plane, cgal;
  Timing check;  ///< validate_mesh with self-intersections: the full search
  Timing command_check;  ///< require_valid_solid: the commands' input check (certificate, else the search)
  std::size_t plane_pieces = 0, cgal_pieces = 0;
  std::size_t plane_valid = 0;  ///< plane pieces certified, and passing validate_mesh unless --no-validate
  // Validity (outside timing): -1 = not checked.
  long cgal_closed = -1;       ///< CGAL sides (of 2) that are closed
  long cgal_self_free = -1;    ///< CGAL sides (of 2) without self-intersections
  bool cgal_ok = true;         ///< every clip call returned true
  std::string note;
};

Row bench_mesh(const std::string& name, const shatter::Mesh& mesh, const RepeatPolicy& policy, bool validate,
               bool cgal) {
  Row row;
  row.name = name;
  row.triangles = mesh.triangle_count();

  {
    shatter::ValidationOptions vo;
    vo.check_self_intersections = false;
    const auto report = shatter::validate_mesh(mesh, vo);
    if (!report.valid()) throw std::runtime_error(name + ": input is not a valid solid: " + report.summary());
  }

  std::cerr << name << ": input check ..." << std::flush;
  row.check = measure(
      policy, [] { return 0; }, [&](int) { return shatter::validate_mesh(mesh); },
      [&](const shatter::ValidationReport& report) {
        if (!report.valid()) throw std::runtime_error(name + ": input is not a valid solid: " + report.summary());
      });
  std::cerr << " " << row.check.median_ms << " ms\n";
  std::cerr << name << ": the commands' input check ..." << std::flush;
  row.command_check = measure(
      policy, [] { return 0; },
      [&](int) {
        shatter::require_valid_solid(mesh, name, false);  // throws on an invalid input
        return 0;
      },
      [](int) {});
  std::cerr << " " << row.command_check.median_ms << " ms\n";

  const shatter::Vec3 centroid = shatter::mass_properties(mesh).centroid;
  const shatter::Vec3 n = shatter::normalized({0.3, 0.5, 0.8});
  const shatter::Plane plane{n, -shatter::dot(n, centroid)};
  std::cerr << name << ": " << mesh.triangle_count() << " triangles, plane (" << n.x << ", " << n.y << ", " << n.z
            << ", " << plane.offset << ")\n";

  // shatter: the input prepared per run, outside the clock; the clock covers the
  // cut and the certified rounding of every piece.
  std::cerr << "  plane ..." << std::flush;
  {
    const std::vector<shatter::Plane> cuts{plane};
    row.plane = measure(
        policy, [&] { return shatter::prepare_plane_input(mesh); },
        [&](const shatter::PlaneInput& input) {
          return shatter::cut_by_plane(input, input.geometry.plane_set(cuts), input.solid, &input.mesh,
                                       shatter::PlaneRef::cut(0));
        },
        [&](const shatter::PlaneCut& cut) {
          row.plane_pieces = cut.pieces.size();
          if (cut.plane_missed) row.note += "plane missed; ";
          row.plane_valid = 0;
          for (const auto& piece : cut.pieces) {
            row.plane_valid += piece.defect.empty() && (!validate || shatter::validate_mesh(piece.mesh).valid());
          }
        });
  }
  std::cerr << " " << row.plane.median_ms << " ms (" << row.plane.runs << " runs, prepare_plane_input "
            << row.plane.setup_ms << " ms)\n";

  if (!cgal) {
    row.cgal.median_ms = not_measured;
    row.note += "CGAL not timed (--no-cgal); ";
    return row;
  }
  // CGAL PMP clip, both sides: two copies made outside the clock.
  std::cerr << "  cgal clip ..." << std::flush;
  const CgalMesh cgal_input = to_cgal(mesh);
  const Epick::Plane_3 below_plane(n.x, n.y, n.z, plane.offset);
  const Epick::Plane_3 above_plane = below_plane.opposite();
  struct Clipped {
    CgalMesh below, above;
    bool ok_below = false, ok_above = false;
  };
  // CGAL clip (inexact constructions) can crash on a plane shatter cuts, e.g. the
  // icosphere of subdivision 1 through its centre: one untimed clip of each side
  // in a forked child first, and no timing where that child died.
  const int crash = signal_in_forked_child([&] {
    Clipped c{cgal_input, cgal_input};
    cgal_clip_volume(c.below, below_plane);
    cgal_clip_volume(c.above, above_plane);
  });
  if (crash != 0) {
    row.cgal.median_ms = not_measured;
    row.cgal_ok = false;
    row.note += "CGAL clip crashed (signal " + std::to_string(crash) + "): not timed; ";
    std::cerr << " crashed (signal " << crash << "), not timed\n";
    return row;
  }
  row.cgal = measure(
      policy, [&] { return Clipped{cgal_input, cgal_input}; },
      [&](Clipped& c) {
        // clip keeps the part on the negative side of the plane.
        c.ok_below = cgal_clip_volume(c.below, below_plane);
        c.ok_above = cgal_clip_volume(c.above, above_plane);
        return std::move(c);
      },
      [&](Clipped& c) {
        row.cgal_ok = c.ok_below && c.ok_above;
        if (!row.cgal_ok) row.note += "CGAL clip returned false; ";
        row.cgal_pieces = 0;
        if (validate) row.cgal_closed = row.cgal_self_free = 0;
        for (auto* side : {&c.below, &c.above}) {
          side->collect_garbage();
          row.cgal_pieces += cgal_component_count(*side);
          if (!validate) continue;
          row.cgal_closed += CGAL::is_closed(*side);
          row.cgal_self_free += !cgal_self_intersects(*side);
        }
      });
  std::cerr << " " << row.cgal.median_ms << " ms (" << row.cgal.runs << " runs)\n";
  return row;
}

// ---------------------------------------------------------------------------
// Output.

std::string ms_text(double ms) { return std::isnan(ms) ? "–" : fixed(ms, ms < 10 ? 3 : ms < 1000 ? 1 : 0); }

double ns_per_triangle(double ms, std::size_t triangles) { return ms * 1e6 / static_cast<double>(triangles); }

std::string check_text(long ok, std::size_t of) {
  return ok < 0 ? "n/c" : std::to_string(ok) + "/" + std::to_string(of);
}

void print_markdown(std::ostream& out, const std::vector<Row>& rows) {
  out << "| mesh | triangles | plane ms | plane ns/triangle | prepare_plane_input ms (untimed) | CGAL clip ms | "
         "CGAL/plane ratio |\n"
      << "|---|---:|---:|---:|---:|---:|---:|\n";
  for (const auto& r : rows) {
    out << "| " << r.name << " | " << with_thousands(r.triangles) << " | " << ms_text(r.plane.median_ms) << " | "
        << fixed(ns_per_triangle(r.plane.median_ms, r.triangles), 1) << " | " << ms_text(r.plane.setup_ms) << " | "
        << ms_text(r.cgal.median_ms) << " | " << ratio_text(r.cgal.median_ms / r.plane.median_ms) << " |\n";
  }
  out << "\n| mesh | input check ms (the commands': require_valid_solid) | full search ms (validate_mesh) | "
         "prepare_plane_input ms | input ns/triangle (check + prepare) | check + prepare + cut ms |\n"
      << "|---|---:|---:|---:|---:|---:|\n";
  for (const auto& r : rows) {
    const double input_ms = r.command_check.median_ms + r.plane.setup_ms;
    out << "| " << r.name << " | " << ms_text(r.command_check.median_ms) << " | " << ms_text(r.check.median_ms) << " | "
        << ms_text(r.plane.setup_ms) << " | " << fixed(ns_per_triangle(input_ms, r.triangles), 1) << " | "
        << ms_text(input_ms + r.plane.median_ms) << " |\n";
  }
  out << "\n| mesh | runs plane/CGAL | pieces plane | pieces CGAL | plane pieces certified and valid | "
         "CGAL sides closed | CGAL sides w/o self-intersection | note |\n"
      << "|---|---|---:|---:|---|---|---|---|\n";
  for (const auto& r : rows) {
    out << "| " << r.name << " | " << r.plane.runs << "/" << r.cgal.runs << " | " << r.plane_pieces << " | "
        << r.cgal_pieces << " | " << r.plane_valid << "/" << r.plane_pieces << " | " << check_text(r.cgal_closed, 2)
        << " | " << check_text(r.cgal_self_free, 2) << " | " << r.note << " |\n";
  }
}

void write_csv(const std::filesystem::path& path, const std::vector<Row>& rows) {
  CsvWriter csv(
      "mesh,triangles,plane_ms,plane_ns_per_triangle,runs_plane,prepare_plane_input_ms,pieces_plane,"
      "plane_pieces_valid,cgal_clip_ms,cgal_over_plane,runs_cgal,pieces_cgal,cgal_sides_closed,"
      "cgal_sides_without_self_intersection,cgal_clip_ok,input_check_ms,input_ns_per_triangle,"
      "check_prepare_cut_ms,command_check_ms,command_check_prepare_cut_ms");
  for (const auto& r : rows) {
    csv.field(r.name).field(r.triangles);
    csv.field(r.plane.median_ms).field(ns_per_triangle(r.plane.median_ms, r.triangles)).field(r.plane.runs);
    csv.field(r.plane.setup_ms).field(r.plane_pieces).field(r.plane_valid);
    csv.field(r.cgal.median_ms).field(r.cgal.median_ms / r.plane.median_ms).field(r.cgal.runs);
    // -1: not checked (--no-validate).
    csv.field(r.cgal_pieces).field(r.cgal_closed).field(r.cgal_self_free).field(r.cgal_ok);
    const double input_ms = r.check.median_ms + r.plane.setup_ms;
    csv.field(r.check.median_ms).field(ns_per_triangle(input_ms, r.triangles)).field(input_ms + r.plane.median_ms);
    // Appended, so the columns before keep their meaning (the full search as the check).
    csv.field(r.command_check.median_ms).field(r.command_check.median_ms + r.plane.setup_ms + r.plane.median_ms);
    csv.end_row();
  }
  csv.save(path);
}

/// Declares the command line: every option, its help and its checks, filling `options`.
void add_options(CLI::App& app, Options& options) {
  app.description(
      "shatter-bench-cut: one cut through the volume centroid (normal = normalised (0.3, 0.5, 0.8)) of "
      "knot1.off, fandisk.off and a subdivided icosahedron sphere (20 * 4^K triangles). Times shatter's cut "
      "(cut_by_plane: the exact cut and the certified rounding of every piece; the input check as the commands make it "
      "(require_valid_solid: certificate first), the full search (validate_mesh) "
      "and prepare_plane_input timed apart) against CGAL PMP clip(..., clip_volume(true)) on both sides of the same plane. Prints Markdown "
      "tables (median of >= 3 runs and >= 0.3 s; 1 run if > 60 s) with each method's pieces and their "
      "validity. Exit status: 0 on success, 1 on a usage error, a shatter piece that is not certified and "
      "valid, or any other failure.");
  app.add_option("--mesh-dir", options.mesh_dir, "Folder holding knot1.off and fandisk.off")->capture_default_str();
  app.add_option("--csv", options.csv, "Also write the results as CSV to this file (one row per mesh)");
  app.add_option("--sphere-subdivisions", options.sphere_subdivisions,
                 "Subdivisions K of the icosahedron, 0..10 (default 8: 1,310,720 triangles; 6 with --quick)")
      ->check(CLI::Range(0, 10));
  app.add_flag("--quick", options.quick, "Smoke run (CI): 1 run per measurement, sphere 20 * 4^6");
  app.add_flag_callback("--no-validate", [&options] { options.validate = false; },
                        "Skip the validity checks of the outputs");
  app.add_flag_callback("--no-cgal", [&options] { options.cgal = false; },
                        "Skip CGAL's clip (shatter's check, preparation and cut only: for profiling)");
  app.add_flag("--sphere-only", options.sphere_only, "Skip knot1.off and fandisk.off: the sphere's row only");
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  CLI::App app{"", "shatter-bench-cut"};
  add_options(app, options);
  if (const auto code = shatter::bench::parse_command_line(app, argc, argv, 1)) return *code;
  try {
    RepeatPolicy policy;
    if (options.quick) {
      policy.min_runs = 1;
      policy.min_total_seconds = 0.0;
    }
    const int k = options.sphere_subdivisions.value_or(options.quick ? 6 : 8);

    std::vector<Row> rows;
    for (const char* file : {"knot1.off", "fandisk.off"}) {
      if (options.sphere_only) break;
      const auto path = options.mesh_dir / file;
      if (!std::filesystem::exists(path)) throw std::runtime_error("mesh not found: " + path.string());
      rows.push_back(bench_mesh(file, shatter::read_mesh(path), policy, options.validate, options.cgal));
    }
    rows.push_back(
        bench_mesh("sphere 20*4^" + std::to_string(k), make_icosphere(k), policy, options.validate, options.cgal));

    std::cout << "One cut through the volume centroid, normal normalised (0.3, 0.5, 0.8); median of "
              << (options.quick ? "1 run (--quick)" : ">= 3 runs and >= 0.3 s (1 run if > 60 s)")
              << "; CGAL = PMP::clip(clip_volume(true)) on both sides, Surface_mesh<Epick>; "
              << std::thread::hardware_concurrency() << " hardware threads.\n\n";
    print_markdown(std::cout, rows);
    if (options.csv) write_csv(*options.csv, rows);

    // shatter promises every piece valid as written; CGAL's outputs are only reported.
    bool failed = false;
    for (const Row& r : rows) {
      if (r.plane_valid == r.plane_pieces) continue;
      failed = true;
      std::cerr << "FAILED: " << r.name << ": " << r.plane_pieces - r.plane_valid << " of " << r.plane_pieces
                << " pieces not certified or not valid\n";
    }
    return failed ? 1 : 0;
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << '\n';
    return 1;
  }
}
