// shatter-bench-robustness: the degenerate cases of an exported shatter-fuzz
// corpus (shatter-fuzz --export-corpus) through shatter and its peers, so the
// robustness comparison a paper cites is computed from exactly the files anyone
// can fetch and feed to their own code (issue 20 items 3 and 4).
//
// Every tool does the same to each slice case: cut the mesh by the first plane
// into its pieces on both sides (shatter: one solid per piece, cavities with the
// solid around them; clip: each side as one mesh), then every piece by the next
// plane, and so on; each tool cuts its own output, as written in doubles. A tool's case
// ends as one of
//   ok       every piece it wrote is a valid solid (shatter::validate_mesh:
//            closed, oriented, 2-manifold, no zero-area triangle, no
//            self-intersection, positive volume)
//   invalid  it wrote a piece that is not (the first defect is kept)
//   refused  it said it could not (an exception, clip returning false)
//   crashed  a signal ended it
//   timeout  it passed the time limit
// Each (case, tool) runs in its own forked child, so a crash or a hang of one
// never touches another. Fracture cases (recursive cuts by shatter's recipe)
// are left out: the peers have no recipe of their own to follow there.
//
// Tools: `shatter` (cut_mesh_by_plane), `cgal-epick` (CGAL 5.5 PMP::clip with
// clip_volume on Surface_mesh<Epick>: exact predicates, double constructions),
// `cgal-epeck` (the same on Epeck, exact constructions, rounded to doubles to be
// written). The seed's float method and Manifold join through the same manifest
// (their runners live with them).

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/clip.h>
#include <CGAL/Surface_mesh.h>

#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "bench_support.hpp"
#include "csv.hpp"
#include "shatter/cut/plane_cut.hpp"
#include "shatter/kernel/error.hpp"
#include "shatter/kernel/io.hpp"
#include "shatter/kernel/validate.hpp"

namespace shatter::bench {
namespace {

namespace fs = std::filesystem;
namespace PMP = CGAL::Polygon_mesh_processing;

enum class Outcome { ok, invalid, refused, crashed, timeout };
constexpr std::array<const char*, 5> outcome_names = {"ok", "invalid", "refused", "crashed", "timeout"};

struct ToolResult {
  Outcome outcome = Outcome::ok;
  std::size_t pieces = 0;
  double seconds = 0;
  std::string detail;  ///< the first invalid piece's defect, or why it refused or stopped
};

/// The first defect of the first invalid piece among `pieces`, or "".
std::string first_invalid(const std::vector<Mesh>& pieces) {
  for (std::size_t k = 0; k < pieces.size(); ++k) {
    const ValidationReport report = validate_mesh(pieces[k]);
    if (!report.valid()) return "piece " + std::to_string(k) + ": " + report.summary();
  }
  return {};
}

// --- the tools: each returns the pieces of one cut of one piece (both sides) ---

std::vector<Mesh> cut_with_shatter(const Mesh& mesh, const Plane& plane) {
  PlaneCut cut = cut_mesh_by_plane(mesh, plane);
  std::vector<Mesh> pieces;
  if (cut.plane_missed) {
    pieces.push_back(mesh);
    return pieces;
  }
  for (CutPiece& piece : cut.pieces) {
    // A piece thinner than the rounding of its coordinates vanishes into its
    // neighbours, its volume reported: nothing of it is written.
    if (piece.vanished) continue;
    if (!piece.defect.empty()) throw UnsupportedGeometryError("a piece shatter could not write: " + piece.defect);
    pieces.push_back(std::move(piece.mesh));
  }
  return pieces;
}

template <class Kernel>
using SurfaceMesh = CGAL::Surface_mesh<typename Kernel::Point_3>;

template <class Kernel>
SurfaceMesh<Kernel> to_surface_mesh(const Mesh& mesh) {
  SurfaceMesh<Kernel> out;
  std::vector<typename SurfaceMesh<Kernel>::Vertex_index> vertices;
  vertices.reserve(mesh.vertex_count());
  for (const Vec3& p : mesh.positions) vertices.push_back(out.add_vertex(typename Kernel::Point_3(p.x, p.y, p.z)));
  for (const Triangle& t : mesh.triangles) {
    if (out.add_face(vertices[t[0]], vertices[t[1]], vertices[t[2]]) == SurfaceMesh<Kernel>::null_face()) {
      throw std::runtime_error("a face CGAL's Surface_mesh cannot add (the piece is not an oriented 2-manifold)");
    }
  }
  return out;
}

// A CGAL mesh as written to a file: every point rounded to the nearest doubles.
template <class Kernel>
Mesh to_written_mesh(const SurfaceMesh<Kernel>& mesh) {
  Mesh out;
  std::map<typename SurfaceMesh<Kernel>::Vertex_index, VertexIndex> index;
  for (const auto v : mesh.vertices()) {
    const auto& p = mesh.point(v);
    index[v] = static_cast<VertexIndex>(out.positions.size());
    out.positions.push_back({CGAL::to_double(p.x()), CGAL::to_double(p.y()), CGAL::to_double(p.z())});
  }
  for (const auto f : mesh.faces()) {
    std::vector<VertexIndex> corners;
    for (const auto v : CGAL::vertices_around_face(mesh.halfedge(f), mesh)) corners.push_back(index[v]);
    for (std::size_t k = 1; k + 1 < corners.size(); ++k) out.triangles.push_back({corners[0], corners[k], corners[k + 1]});
  }
  out.surfaces.assign(out.triangles.size(), original_surface);
  return out;
}

template <class Kernel>
std::vector<Mesh> cut_with_cgal(const Mesh& mesh, const Plane& plane) {
  const typename Kernel::Plane_3 below(plane.normal.x, plane.normal.y, plane.normal.z, plane.offset);
  std::vector<Mesh> pieces;
  for (const auto& side_plane : {below, below.opposite()}) {
    SurfaceMesh<Kernel> side = to_surface_mesh<Kernel>(mesh);
    if (!PMP::clip(side, side_plane, CGAL::parameters::clip_volume(true))) {
      throw std::runtime_error("PMP::clip returned false");
    }
    side.collect_garbage();
    // The side whole, not split into connected components: a solid with a
    // cavity would split into its outer shell and an inward-facing inner one,
    // which is no fault of clip's. Several solids in one mesh validate as one.
    if (side.number_of_faces() > 0) pieces.push_back(to_written_mesh<Kernel>(side));
  }
  return pieces;
}

using CutFn = std::vector<Mesh> (*)(const Mesh&, const Plane&);

struct Tool {
  const char* name;
  CutFn cut;
};
constexpr std::array<Tool, 3> all_tools = {Tool{"shatter", &cut_with_shatter},
                                           Tool{"cgal-epick", &cut_with_cgal<CGAL::Epick>},
                                           Tool{"cgal-epeck", &cut_with_cgal<CGAL::Epeck>}};

// The whole chain in this process: every piece of every cut checked as written.
ToolResult run_chain(const Tool& tool, const Mesh& input, const std::vector<Plane>& planes) {
  ToolResult result;
  const auto start = std::chrono::steady_clock::now();
  std::vector<Mesh> pieces{input};
  try {
    for (const Plane& plane : planes) {
      std::vector<Mesh> next;
      for (const Mesh& piece : pieces) {
        std::vector<Mesh> cut = tool.cut(piece, plane);
        if (const std::string defect = first_invalid(cut); !defect.empty()) {
          result.outcome = Outcome::invalid;
          result.detail = defect;
          result.pieces = next.size() + cut.size();
          return result;
        }
        for (Mesh& m : cut) next.push_back(std::move(m));
      }
      pieces = std::move(next);
    }
  } catch (const std::exception& e) {
    result.outcome = Outcome::refused;
    result.detail = e.what();
  }
  result.pieces = pieces.size();
  result.seconds = seconds_between(start, std::chrono::steady_clock::now());
  return result;
}

// One line on the pipe: outcome, pieces, seconds, detail (newlines flattened).
std::string encode(const ToolResult& r) {
  std::string detail = r.detail.substr(0, 300);
  for (char& c : detail) {
    if (c == '\n' || c == '\t') c = ' ';
  }
  std::ostringstream out;
  out << static_cast<int>(r.outcome) << '\t' << r.pieces << '\t' << r.seconds << '\t' << detail << '\n';
  return out.str();
}

ToolResult decode(const std::string& line) {
  ToolResult r;
  std::istringstream in(line);
  int outcome = 0;
  in >> outcome >> r.pieces >> r.seconds;
  r.outcome = static_cast<Outcome>(outcome);
  std::getline(in, r.detail);
  if (!r.detail.empty() && r.detail.front() == '\t') r.detail.erase(0, 1);
  return r;
}

// run_chain in a forked child, killed after `timeout` seconds.
ToolResult run_isolated(const Tool& tool, const Mesh& input, const std::vector<Plane>& planes, double timeout) {
  int fds[2];
  if (::pipe(fds) != 0) throw std::runtime_error("pipe failed");
  const auto start = std::chrono::steady_clock::now();
  const pid_t pid = fork_flushed();
  if (pid == 0) {
    ::close(fds[0]);
    write_all(fds[1], encode(run_chain(tool, input, planes)));
    ::_exit(0);
  }
  ::close(fds[1]);
  std::string text;
  bool timed_out = false;
  while (true) {
    const double left = timeout - seconds_between(start, std::chrono::steady_clock::now());
    if (left <= 0) {
      timed_out = true;
      break;
    }
    pollfd wait{fds[0], POLLIN, 0};
    if (::poll(&wait, 1, static_cast<int>(left * 1000) + 1) <= 0) continue;
    char buffer[512];
    const ssize_t got = ::read(fds[0], buffer, sizeof buffer);
    if (got <= 0) break;
    text.append(buffer, static_cast<std::size_t>(got));
  }
  ::close(fds[0]);
  if (timed_out) ::kill(pid, SIGKILL);
  const int status = wait_for_child(pid);
  ToolResult result;
  result.seconds = seconds_between(start, std::chrono::steady_clock::now());
  if (timed_out) {
    result.outcome = Outcome::timeout;
    result.detail = "passed " + fixed(timeout, 0) + " s";
  } else if (WIFSIGNALED(status)) {
    result.outcome = Outcome::crashed;
    result.detail = std::string("signal ") + ::strsignal(WTERMSIG(status));
  } else if (text.empty()) {
    result.outcome = Outcome::crashed;
    result.detail = "ended without a result (exit " + std::to_string(WEXITSTATUS(status)) + ")";
  } else {
    result = decode(text);
  }
  return result;
}

int run(const fs::path& corpus, const std::vector<std::string>& tool_names, double timeout, std::size_t max_cases,
        const std::string& csv_path) {
  std::ifstream in(corpus / "manifest.json");
  if (!in) throw IoError("cannot read " + (corpus / "manifest.json").string() + " (make one with shatter-fuzz --export-corpus)");
  const nlohmann::json manifest = nlohmann::json::parse(in);
  std::vector<const Tool*> tools;
  for (const std::string& name : tool_names) {
    const Tool* found = nullptr;
    for (const Tool& tool : all_tools) {
      if (name == tool.name) found = &tool;
    }
    if (!found) throw std::invalid_argument("unknown tool '" + name + "' (shatter, cgal-epick, cgal-epeck)");
    tools.push_back(found);
  }

  CsvWriter csv("id,class,mesh,planes,tool,outcome,pieces,seconds,detail");
  // [class][tool][outcome]
  std::map<std::string, std::vector<std::array<std::size_t, 5>>> tally;
  std::size_t cases = 0;
  for (const nlohmann::json& entry : manifest["cases"]) {
    if (entry["operation"] != "slice") continue;
    if (max_cases != 0 && cases == max_cases) break;
    ++cases;
    const Mesh mesh = read_mesh(corpus / entry["mesh"].get<std::string>());
    std::vector<Plane> planes;
    for (const nlohmann::json& p : entry["planes_hex"]) {
      std::array<double, 4> v{};
      for (std::size_t k = 0; k < 4; ++k) v[k] = std::strtod(p[k].get<std::string>().c_str(), nullptr);
      planes.push_back({{v[0], v[1], v[2]}, v[3]});
    }
    const std::string kind = entry["class"];
    auto& row = tally[kind];
    row.resize(tools.size());
    for (std::size_t t = 0; t < tools.size(); ++t) {
      const ToolResult r = run_isolated(*tools[t], mesh, planes, timeout);
      ++row[t][static_cast<std::size_t>(r.outcome)];
      csv.field(entry["id"].get<std::uint64_t>()).field(kind).field(entry["mesh"].get<std::string>());
      csv.field(planes.size()).field(tools[t]->name).field(outcome_names[static_cast<std::size_t>(r.outcome)]);
      csv.field(r.pieces).field(r.seconds).field(r.detail);
      csv.end_row();
    }
    if (cases % 100 == 0) std::fprintf(stderr, "%zu cases\n", cases);
  }
  if (!csv_path.empty()) csv.save(csv_path);

  // Markdown: per class, each tool's ok / invalid / refused / crashed / timeout.
  std::printf("%zu slice cases from %s\n\n| class |", cases, corpus.string().c_str());
  for (const Tool* tool : tools) std::printf(" %s ok / invalid / refused / crashed / timeout |", tool->name);
  std::printf("\n|---|");
  for (std::size_t t = 0; t < tools.size(); ++t) std::printf("---|");
  std::printf("\n");
  std::vector<std::array<std::size_t, 5>> totals(tools.size());
  for (const auto& [kind, row] : tally) {
    std::printf("| %s |", kind.c_str());
    for (std::size_t t = 0; t < tools.size(); ++t) {
      std::printf(" %zu / %zu / %zu / %zu / %zu |", row[t][0], row[t][1], row[t][2], row[t][3], row[t][4]);
      for (std::size_t o = 0; o < 5; ++o) totals[t][o] += row[t][o];
    }
    std::printf("\n");
  }
  std::printf("| all |");
  for (std::size_t t = 0; t < tools.size(); ++t) {
    std::printf(" %zu / %zu / %zu / %zu / %zu |", totals[t][0], totals[t][1], totals[t][2], totals[t][3], totals[t][4]);
  }
  std::printf("\n");
  return 0;
}

}  // namespace
}  // namespace shatter::bench

int main(int argc, char** argv) {
  CLI::App app{
      "shatter-bench-robustness: the slice cases of an exported shatter-fuzz corpus (shatter-fuzz --export-corpus DIR) "
      "through shatter and CGAL 5.5 PMP::clip over Epick and over Epeck. Each tool cuts the mesh by the case's "
      "planes in turn, every piece it wrote by the next plane; each (case, tool) runs in its own forked child and "
      "ends ok (every piece written is a valid solid), invalid, refused, crashed or timeout. Prints a Markdown "
      "table per class; --csv writes one row per case and tool. Exit 0 when it ran, 1 on errors, 2 on usage "
      "errors (the tools' outcomes never change it)."};
  std::string corpus, csv;
  std::vector<std::string> tools = {"shatter", "cgal-epick", "cgal-epeck"};
  double timeout = 20;
  std::size_t max_cases = 0;
  app.add_option("corpus", corpus, "The folder shatter-fuzz --export-corpus wrote")->required()->check(CLI::ExistingDirectory);
  app.add_option("--tools", tools, "Tools to run (default all: shatter, cgal-epick, cgal-epeck)")->delimiter(',');
  app.add_option("--timeout", timeout, "Seconds one tool may spend on one case (default 20)")->check(CLI::PositiveNumber);
  app.add_option("--max-cases", max_cases, "Stop after this many slice cases (default 0: all)");
  app.add_option("--csv", csv, "Also write one CSV row per case and tool to this file");
  CLI11_PARSE(app, argc, argv);
  try {
    return shatter::bench::run(corpus, tools, timeout, max_cases, csv);
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
