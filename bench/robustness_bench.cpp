// shatter-bench-robustness: the degenerate cases of an exported shatter-fuzz
// corpus (shatter-fuzz --export-corpus) through shatter and its peers, so the
// robustness comparison a paper cites is computed from exactly the files anyone
// can fetch and feed to their own code (issue 20 items 3 and 4).
//
// Every tool does the same to each slice case: cut the mesh by the first plane
// into its pieces on both sides (shatter, the seed's method: one solid per
// connected piece; clip, Manifold: each side as one mesh), then every piece by the
// next plane, and so on; each tool cuts its own output, as written in doubles. Each
// cut is judged by the same rules for every tool (judge_cut):
//   - every piece written is a valid solid (shatter::validate_mesh: closed,
//     oriented, 2-manifold, no zero-area triangle, no self-intersection, positive
//     volume);
//   - a side is lost when the tool wrote nothing on it although the exact answer
//     there, rounded to doubles, holds a piece: a vertex of the piece cut lies
//     strictly on that side of the case's plane (exact sign), and shatter's exact
//     cut of that same piece keeps a piece there that does not vanish when rounded
//     (a sliver thinner than the rounding of its coordinates has no valid double
//     form, so writing nothing there is right); a side is spurious when the tool
//     wrote a piece there although no vertex of the piece cut lies strictly on it
//     (the exact answer there is empty).
// A tool's case ends as one of
//   ok       every cut passed
//   invalid  a cut did not (the first defect is kept)
//   refused  the tool said it could not (an exception, clip returning false, the
//            seed's method naming its failure, Manifold reporting an error status)
//   crashed  a signal ended it, or it ended without an answer
//   timeout  it passed the time limit
// Each (case, tool) runs in its own forked child, so a crash or a hang of one
// never touches another (Manifold: one Node worker serves the cases in turn and is
// killed and restarted when a case crashes it or passes the limit). Fracture cases
// (recursive cuts by shatter's recipe) are left out: the peers have no recipe of
// their own to follow there.
//
// Tools: `shatter` (cut_mesh_by_plane), `cgal-epick` (CGAL 5.5 PMP::clip with
// clip_volume on Surface_mesh<Epick>: exact predicates, double constructions),
// `cgal-epeck` (the same on Epeck, exact constructions, rounded to doubles to be
// written), `seed` (the seed thesis's float slice, bench/peers/seed, linked: the
// piece rounded to floats, the plane as Unity's Plane in floats, its pieces welded
// by its own position comparison and widened to doubles), `manifold` (npm
// manifold-3d's splitByPlane in bench/peers/manifold/robustness.mjs, its pieces
// handed back in float64).

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/clip.h>
#include <CGAL/Surface_mesh.h>

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <charconv>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <cerrno>
#include <cmath>
#include <random>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

#include "bench_support.hpp"
#include "csv.hpp"
#include "shatter/cut/plane_cut.hpp"
#include "shatter/kernel/error.hpp"
#include "seed_mesh.hpp"
#include "seed_modeller.hpp"
#include "shatter/kernel/io.hpp"
#include "shatter/kernel/predicates.hpp"
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

/// What one tool wrote for one cut of one piece: below (n·x + d < 0), above.
struct SidedPieces {
  std::array<std::vector<Mesh>, 2> side;
  std::size_t count() const { return side[0].size() + side[1].size(); }
};

/// Whether the exact answer on one side, rounded to doubles to be written, holds a
/// piece: shatter's exact cut of `parent` asked (cut_mesh_by_plane; a piece thinner
/// than the rounding of its coordinates vanishes and is no piece). Only asked when a
/// tool wrote nothing on a side that holds a vertex; when shatter's cut cannot
/// answer (it throws), the vertex decides (true).
bool exact_side_written(const Mesh& parent, const Plane& plane, bool above) {
  try {
    const PlaneCut cut = cut_mesh_by_plane(parent, plane);
    if (cut.plane_missed) return cut.whole_above == above;
    for (const CutPiece& piece : cut.pieces) {
      if (piece.above == above && !piece.vanished) return true;
    }
    return false;
  } catch (const std::exception&) {
    return true;
  }
}

/// The judge of one cut, the same for every tool: the first defect of what the tool
/// wrote for `parent` cut by `plane`, or "" (the rules are in this file's head).
std::string judge_cut(const Mesh& parent, const Plane& plane, const SidedPieces& cut) {
  std::size_t k = 0;
  for (const auto& pieces : cut.side) {
    for (const Mesh& piece : pieces) {
      const ValidationReport report = validate_mesh(piece);
      if (!report.valid()) return "piece " + std::to_string(k) + ": " + report.summary();
      ++k;
    }
  }
  std::array<bool, 2> holds{false, false};  // a vertex of the parent strictly below, above
  for (const Triangle& t : parent.triangles) {
    for (const VertexIndex v : t) {
      const Sign s = side_of_plane(plane, parent.positions[v]);
      if (s != Sign::zero) holds[s == Sign::positive ? 1 : 0] = true;
    }
  }
  static constexpr std::array<const char*, 2> names = {"below", "above"};
  for (std::size_t s = 0; s < 2; ++s) {
    if (holds[s] && cut.side[s].empty() && exact_side_written(parent, plane, s == 1)) {
      return std::string("lost side: nothing written ") + names[s] + " the plane, where the exact cut has a piece";
    }
    if (!holds[s] && !cut.side[s].empty()) {
      return std::string("spurious side: a piece written ") + names[s] + " the plane, where the piece has no vertex";
    }
  }
  return {};
}

// --- the tools: each returns the pieces of one cut of one piece (both sides) ---

SidedPieces cut_with_shatter(const Mesh& mesh, const Plane& plane) {
  PlaneCut cut = cut_mesh_by_plane(mesh, plane);
  SidedPieces pieces;
  if (cut.plane_missed) {
    pieces.side[cut.whole_above ? 1 : 0].push_back(mesh);
    return pieces;
  }
  for (CutPiece& piece : cut.pieces) {
    // A piece thinner than the rounding of its coordinates vanishes into its
    // neighbours, its volume reported: nothing of it is written.
    if (piece.vanished) continue;
    if (!piece.defect.empty()) throw UnsupportedGeometryError("a piece shatter could not write: " + piece.defect);
    pieces.side[piece.above ? 1 : 0].push_back(std::move(piece.mesh));
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
SidedPieces cut_with_cgal(const Mesh& mesh, const Plane& plane) {
  const typename Kernel::Plane_3 below(plane.normal.x, plane.normal.y, plane.normal.z, plane.offset);
  SidedPieces pieces;
  for (std::size_t s = 0; s < 2; ++s) {
    const auto side_plane = s == 0 ? below : below.opposite();
    SurfaceMesh<Kernel> side = to_surface_mesh<Kernel>(mesh);
    // Epick's clip is instantiated once for all the benchmarks (bench_support),
    // which spares this file about a minute of compile in every build.
    bool clipped = false;
    if constexpr (std::is_same_v<Kernel, CGAL::Epick>) {
      clipped = cgal_clip_volume(side, side_plane);
    } else {
      clipped = PMP::clip(side, side_plane, CGAL::parameters::clip_volume(true));
    }
    if (!clipped) throw std::runtime_error("PMP::clip returned false");
    side.collect_garbage();
    // The side whole, not split into connected components: a solid with a
    // cavity would split into its outer shell and an inward-facing inner one,
    // which is no fault of clip's. Several solids in one mesh validate as one.
    if (side.number_of_faces() > 0) pieces.side[s].push_back(to_written_mesh<Kernel>(side));
  }
  return pieces;
}

// The seed's own float slice (bench/peers/seed, seed thesis 4.2-4.4, the text's
// reading: Unity's ==, Listing 4.4 as printed, Eq. 4.1 about the mesh's origin). The
// piece as Unity would hold it (floats), the plane as Unity's Plane(normal, d) would
// hold it: the normal normalized in floats, d / |n| rounded to a float. Its
// hulls welded by its own comparison, as written. A failure it names is a refusal.
SidedPieces cut_with_seed(const Mesh& mesh, const Plane& plane) {
  const double length = std::sqrt(dot(plane.normal, plane.normal));
  seed_peer::PlaneF seed_plane;
  seed_plane.normal = seed_peer::normalized(seed_peer::Vec3f{static_cast<float>(plane.normal.x),
                                                             static_cast<float>(plane.normal.y),
                                                             static_cast<float>(plane.normal.z)});
  seed_plane.distance = static_cast<float>(plane.offset / length);
  std::mt19937 hole_rng(1);  // the random point inside each hole (4.3.3)
  const seed_peer::SliceOutcome slice = seed_peer::slice_piece(seed_peer::to_piece(mesh), seed_plane, {}, hole_rng);
  if (slice.failure.kind != seed_peer::FailureKind::none) {
    throw std::runtime_error(std::string(seed_peer::failure_name(slice.failure.kind)) + ": " + slice.failure.detail);
  }
  SidedPieces pieces;
  for (std::size_t k = 0; k < slice.pieces.size(); ++k) {
    pieces.side[slice.above[k] ? 1 : 0].push_back(seed_peer::to_mesh(slice.pieces[k], seed_peer::Compare::unity));
  }
  return pieces;
}

using CutFn = SidedPieces (*)(const Mesh&, const Plane&);

/// Judges one cut of `parent` (judge_cut). An invalid cut marks `result` invalid,
/// counting the pieces made so far with the cut's, and returns false; a valid one
/// moves its pieces onto `next` and returns true.
bool accept_cut(const Mesh& parent, const Plane& plane, SidedPieces& cut, std::vector<Mesh>& next, ToolResult& result) {
  if (const std::string defect = judge_cut(parent, plane, cut); !defect.empty()) {
    result.outcome = Outcome::invalid;
    result.detail = defect;
    result.pieces = next.size() + cut.count();
    return false;
  }
  for (auto& side : cut.side)
    for (Mesh& m : side) next.push_back(std::move(m));
  return true;
}

struct Tool {
  const char* name;
  CutFn cut;  ///< null for manifold, which runs in its Node worker
};
constexpr std::array<Tool, 5> all_tools = {Tool{"shatter", &cut_with_shatter},
                                           Tool{"cgal-epick", &cut_with_cgal<CGAL::Epick>},
                                           Tool{"cgal-epeck", &cut_with_cgal<CGAL::Epeck>},
                                           Tool{"seed", &cut_with_seed}, Tool{"manifold", nullptr}};

// Where a refused cut is written as a reproducer (--refusal-reproducers), and
// the case it belongs to; empty for none.
struct RefusalSink {
  fs::path dir;
  std::uint64_t id = 0;
  std::string kind, mesh;
};
RefusalSink refusal_sink;

// The piece a tool refused and the plane it refused it for, as a
// tests/regressions reproducer (a slice of that piece as written, the seed line
// naming the corpus case), so that a refusal in a chain can be replayed alone.
void write_refusal_reproducer(const Tool& tool, const Mesh& piece, const Plane& plane, const std::string& why) {
  const auto hex = [](double v) {  // as the reproducer reader parses it (std::chars_format::hex)
    char text[64];
    return std::string(text, std::to_chars(text, text + sizeof text, v, std::chars_format::hex).ptr);
  };
  std::ostringstream out;
  out << "shatter-reproducer 1\n# replay: shatter-fuzz --replay <this file>\nclass " << refusal_sink.kind
      << "\nmesh-name " << refusal_sink.mesh << "-chain-piece\noperation slice\nformat off\nseed " << refusal_sink.id
      << "\nfailure (before the fix) " << why.substr(0, why.find('\n')) << "\nplane " << hex(plane.normal.x) << ' '
      << hex(plane.normal.y) << ' ' << hex(plane.normal.z) << ' ' << hex(plane.offset) << "\n";
  const std::string mesh = write_mesh_to_bytes(piece, MeshFormat::obj);
  out << "mesh-obj " << mesh.size() << "\n" << mesh;
  fs::create_directories(refusal_sink.dir);
  write_file_atomically(refusal_sink.dir / (std::string(tool.name) + "-corpus-" + std::to_string(refusal_sink.id) + ".repro"),
                        out.str());
}

// The whole chain in this process: every cut judged as written.
ToolResult run_chain(const Tool& tool, const Mesh& input, const std::vector<Plane>& planes) {
  ToolResult result;
  const auto start = std::chrono::steady_clock::now();
  std::vector<Mesh> pieces{input};
  try {
    for (const Plane& plane : planes) {
      std::vector<Mesh> next;
      for (const Mesh& piece : pieces) {
        SidedPieces cut;
        try {
          cut = tool.cut(piece, plane);
        } catch (const std::exception& e) {
          if (!refusal_sink.dir.empty()) write_refusal_reproducer(tool, piece, plane, e.what());
          throw;
        }
        if (!accept_cut(piece, plane, cut, next, result)) return result;
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

// --- Manifold: one Node worker for many cases ---

/// A piece of the worker's answer as a shatter mesh (its float64 positions).
Mesh mesh_from_answer(const nlohmann::json& piece) {
  Mesh mesh;
  const auto& p = piece["positions"];
  for (std::size_t k = 0; k + 2 < p.size(); k += 3) {
    mesh.positions.push_back({p[k].get<double>(), p[k + 1].get<double>(), p[k + 2].get<double>()});
  }
  const auto& t = piece["triangles"];
  for (std::size_t k = 0; k + 2 < t.size(); k += 3) {
    mesh.triangles.push_back({t[k].get<VertexIndex>(), t[k + 1].get<VertexIndex>(), t[k + 2].get<VertexIndex>()});
  }
  mesh.surfaces.assign(mesh.triangles.size(), original_surface);
  return mesh;
}

/// The worker's answer for one case judged cut by cut, as run_chain judges the
/// others (bench/peers/manifold/robustness.mjs documents the answer).
ToolResult judge_manifold_answer(const nlohmann::json& answer, const Mesh& input, const std::vector<Plane>& planes) {
  ToolResult result;
  std::vector<Mesh> parents{input}, next;
  std::size_t level = 0;
  for (const nlohmann::json& cut : answer["cuts"]) {
    const std::size_t cut_level = cut["level"].get<std::size_t>();
    if (cut_level != level) {
      parents = std::move(next);
      next.clear();
      level = cut_level;
    }
    const std::size_t parent = cut["parent"].get<std::size_t>();
    if (level >= planes.size() || parent >= parents.size()) throw std::runtime_error("manifold worker: a cut out of order");
    SidedPieces pieces;
    for (std::size_t s = 0; s < 2; ++s) {
      const nlohmann::json& piece = cut[s == 0 ? "below" : "above"];
      if (!piece.is_null()) pieces.side[s].push_back(mesh_from_answer(piece));
    }
    if (!accept_cut(parents[parent], planes[level], pieces, next, result)) return result;
  }
  result.pieces = next.size();
  const nlohmann::json& error = answer["error"];
  if (!error.is_null()) {
    result.outcome = error["kind"] == "refused" ? Outcome::refused : Outcome::crashed;
    result.detail = error["detail"].get<std::string>();
  } else if (answer["cuts"].empty() && !planes.empty()) {
    throw std::runtime_error("manifold worker: an answer without cuts or error");
  }
  if (answer["input_precision"].is_string() && answer["input_precision"] != "float64") {
    result.detail += (result.detail.empty() ? "" : "; ") + std::string("input ") +
                     answer["input_precision"].get<std::string>();
  }
  return result;
}

/// The Node worker (`node robustness.mjs`), started when first needed and again
/// after a case that killed it or passed the limit.
class ManifoldWorker {
 public:
  ManifoldWorker(std::string node, std::string script) : node_(std::move(node)), script_(std::move(script)) {}
  ManifoldWorker(const ManifoldWorker&) = delete;
  ManifoldWorker& operator=(const ManifoldWorker&) = delete;
  ~ManifoldWorker() { stop(); }

  /// One case: its answer judged, or crashed / timeout when the worker died or
  /// passed `timeout` seconds (the worker is then killed, and started again for
  /// the next case). Throws when the worker cannot be started at all.
  ToolResult run(const Mesh& input, const std::vector<Plane>& planes, double timeout) {
    if (pid_ < 0) start();
    std::vector<double> positions;
    for (const Vec3& p : input.positions) positions.insert(positions.end(), {p.x, p.y, p.z});
    std::vector<VertexIndex> triangles;
    for (const Triangle& t : input.triangles) triangles.insert(triangles.end(), {t[0], t[1], t[2]});
    nlohmann::json plane_list = nlohmann::json::array();
    for (const Plane& p : planes) plane_list.push_back({p.normal.x, p.normal.y, p.normal.z, p.offset});
    const nlohmann::json request = {{"positions", positions}, {"triangles", triangles}, {"planes", plane_list}};
    const auto start_time = std::chrono::steady_clock::now();
    std::string answer;
    const LineStatus status = send(request.dump() + "\n") ? read_line(answer, timeout, start_time) : LineStatus::closed;
    ToolResult result;
    result.seconds = seconds_between(start_time, std::chrono::steady_clock::now());
    if (status == LineStatus::timeout) {
      stop();
      result.outcome = Outcome::timeout;
      result.detail = "passed " + fixed(timeout, 0) + " s";
      return result;
    }
    if (status == LineStatus::closed) {
      const int wait_status = stop();
      result.outcome = Outcome::crashed;
      result.detail = WIFSIGNALED(wait_status)
                          ? std::string("node ended by signal ") + ::strsignal(WTERMSIG(wait_status))
                          : "node ended without an answer (exit " + std::to_string(WEXITSTATUS(wait_status)) + ")";
      return result;
    }
    const double seconds = result.seconds;
    result = judge_manifold_answer(nlohmann::json::parse(answer), input, planes);
    result.seconds = seconds;
    if (result.outcome == Outcome::crashed) stop();  // the worker exits after a trap anyway
    return result;
  }

 private:
  enum class LineStatus { ok, closed, timeout };

  void start() {
    int in[2], out[2];
    if (::pipe(in) != 0 || ::pipe(out) != 0) throw std::runtime_error("pipe failed");
    const pid_t pid = fork_flushed();
    if (pid == 0) {
      ::dup2(in[0], 0);
      ::dup2(out[1], 1);
      ::close(in[0]);
      ::close(in[1]);
      ::close(out[0]);
      ::close(out[1]);
      ::execlp(node_.c_str(), node_.c_str(), script_.c_str(), static_cast<char*>(nullptr));
      std::fprintf(stderr, "error: cannot run %s: %s\n", node_.c_str(), std::strerror(errno));
      ::_exit(127);
    }
    ::close(in[0]);
    ::close(out[1]);
    pid_ = pid;
    to_ = in[1];
    from_ = out[0];
    buffer_.clear();
    std::string ready;
    if (read_line(ready, 120, std::chrono::steady_clock::now()) != LineStatus::ok) {
      stop();
      throw std::runtime_error("the Manifold worker (" + node_ + " " + script_ + ") did not start");
    }
  }

  /// Kills the worker if it runs; returns its wait status (0 when none ran).
  int stop() {
    if (pid_ < 0) return 0;
    ::kill(pid_, SIGKILL);
    return stop_after_exit();
  }

  /// Closes the pipes and reaps a worker that ended (or was killed) on its own.
  int stop_after_exit() {
    if (pid_ < 0) return 0;
    ::close(to_);
    ::close(from_);
    const int status = wait_for_child(pid_);
    pid_ = to_ = from_ = -1;
    return status;
  }

  bool send(const std::string& text) {
    std::size_t done = 0;
    while (done < text.size()) {
      const ssize_t n = ::write(to_, text.data() + done, text.size() - done);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) return false;
      done += static_cast<std::size_t>(n);
    }
    return true;
  }

  LineStatus read_line(std::string& line, double timeout, std::chrono::steady_clock::time_point start) {
    while (true) {
      if (const auto end = buffer_.find('\n'); end != std::string::npos) {
        line = buffer_.substr(0, end);
        buffer_.erase(0, end + 1);
        return LineStatus::ok;
      }
      const double left = timeout - seconds_between(start, std::chrono::steady_clock::now());
      if (left <= 0) return LineStatus::timeout;
      pollfd wait{from_, POLLIN, 0};
      if (::poll(&wait, 1, static_cast<int>(left * 1000) + 1) <= 0) continue;
      char chunk[65536];
      const ssize_t got = ::read(from_, chunk, sizeof chunk);
      if (got < 0 && errno == EINTR) continue;
      if (got <= 0) return LineStatus::closed;
      buffer_.append(chunk, static_cast<std::size_t>(got));
    }
  }

  std::string node_, script_;
  pid_t pid_ = -1;
  int to_ = -1, from_ = -1;
  std::string buffer_;
};

int run(const fs::path& corpus, const std::vector<std::string>& tool_names, double timeout, std::size_t max_cases,
        const std::string& csv_path, const std::string& node, const std::string& manifold_script,
        const std::vector<std::uint64_t>& only_ids) {
  std::ifstream in(corpus / "manifest.json");
  if (!in) throw IoError("cannot read " + (corpus / "manifest.json").string() + " (make one with shatter-fuzz --export-corpus)");
  const nlohmann::json manifest = nlohmann::json::parse(in);
  std::vector<const Tool*> tools;
  for (const std::string& name : tool_names) {
    const Tool* found = nullptr;
    for (const Tool& tool : all_tools) {
      if (name == tool.name) found = &tool;
    }
    if (!found) throw std::invalid_argument("unknown tool '" + name + "' (shatter, cgal-epick, cgal-epeck, seed, manifold)");
    tools.push_back(found);
  }
  std::unique_ptr<ManifoldWorker> manifold;
  for (const Tool* tool : tools) {
    if (tool->cut != nullptr) continue;
    if (manifold_script.empty()) throw std::invalid_argument("the manifold tool needs --manifold-worker (bench/peers/manifold/robustness.mjs)");
    manifold = std::make_unique<ManifoldWorker>(node, manifold_script);
  }
  ::signal(SIGPIPE, SIG_IGN);  // a worker that dies mid-request is a crash of its case, not of this runner

  CsvWriter csv("id,class,mesh,planes,tool,outcome,pieces,seconds,detail");
  // [class][tool][outcome]
  std::map<std::string, std::vector<std::array<std::size_t, 5>>> tally;
  std::size_t cases = 0;
  for (const nlohmann::json& entry : manifest["cases"]) {
    if (entry["operation"] != "slice") continue;
    if (!only_ids.empty() &&
        std::find(only_ids.begin(), only_ids.end(), entry["id"].get<std::uint64_t>()) == only_ids.end()) {
      continue;
    }
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
    refusal_sink.id = entry["id"].get<std::uint64_t>();
    refusal_sink.kind = kind;
    refusal_sink.mesh = fs::path(entry["mesh"].get<std::string>()).stem().string();
    auto& row = tally[kind];
    row.resize(tools.size());
    for (std::size_t t = 0; t < tools.size(); ++t) {
      const ToolResult r = tools[t]->cut != nullptr ? run_isolated(*tools[t], mesh, planes, timeout)
                                                    : manifold->run(mesh, planes, timeout);
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
      "through shatter, CGAL 5.5 PMP::clip over Epick and over Epeck, the seed's float method and Manifold (a Node "
      "worker). Each tool cuts the mesh by the case's planes in turn, every piece it wrote by the next plane; each "
      "(case, tool) runs in its own child and ends ok (every cut: every piece written a valid solid, no side lost "
      "or spurious), invalid, refused, crashed or timeout. Prints a Markdown "
      "table per class; --csv writes one row per case and tool. Exit 0 when it ran, 1 on errors, 2 on usage "
      "errors (the tools' outcomes never change it)."};
  std::string corpus, csv;
  std::vector<std::string> tools = {"shatter", "cgal-epick", "cgal-epeck", "seed"};
  std::string node = "node", manifold_script;
  double timeout = 20;
  std::size_t max_cases = 0;
  app.add_option("corpus", corpus, "The folder shatter-fuzz --export-corpus wrote")->required()->check(CLI::ExistingDirectory);
  app.add_option("--tools", tools,
                 "Tools to run: shatter, cgal-epick, cgal-epeck, seed, manifold (default all but manifold)")
      ->delimiter(',');
  app.add_option("--manifold-worker", manifold_script, "bench/peers/manifold/robustness.mjs, for the manifold tool");
  app.add_option("--node", node, "The Node.js to run the Manifold worker with (default node)");
  app.add_option("--timeout", timeout, "Seconds one tool may spend on one case (default 20)")->check(CLI::PositiveNumber);
  app.add_option("--max-cases", max_cases, "Stop after this many slice cases (default 0: all)");
  app.add_option("--csv", csv, "Also write one CSV row per case and tool to this file");
  std::vector<std::uint64_t> only_ids;
  app.add_option("--ids", only_ids, "Run only the slice cases with these ids (comma-separated; default all)")
      ->delimiter(',');
  std::string refusal_dir;
  app.add_option("--refusal-reproducers", refusal_dir,
                 "Write the piece and plane of each refused cut into this folder as a tests/regressions reproducer "
                 "(TOOL-corpus-ID.repro: a slice of that piece as written)");
  CLI11_PARSE(app, argc, argv);
  shatter::bench::refusal_sink.dir = refusal_dir;
  try {
    return shatter::bench::run(corpus, tools, timeout, max_cases, csv, node, manifold_script, only_ids);
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
