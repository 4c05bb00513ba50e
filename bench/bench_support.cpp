#include "bench_support.hpp"

#include <CGAL/Convex_hull_3/dual/halfspace_intersection_3.h>
#include <CGAL/Polygon_mesh_processing/clip.h>
#include <CGAL/Polygon_mesh_processing/connected_components.h>
#include <CGAL/Polygon_mesh_processing/measure.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Polygon_mesh_processing/triangulate_faces.h>
#include <CGAL/boost/graph/helpers.h>

#include <poll.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <unordered_map>
#include <utility>

namespace shatter::bench {

namespace PMP = CGAL::Polygon_mesh_processing;

bool cgal_clip_volume(CgalMesh& mesh, const Epick::Plane_3& plane) {
  return PMP::clip(mesh, plane, CGAL::parameters::clip_volume(true));
}

std::size_t cgal_component_count(CgalMesh& mesh) {
  if (mesh.number_of_faces() == 0) return 0;
  auto [ids, created] = mesh.add_property_map<CgalMesh::Face_index, std::size_t>("f:bench_component", 0);
  const std::size_t count = PMP::connected_components(mesh, ids);
  mesh.remove_property_map(ids);
  (void)created;
  return count;
}

bool cgal_self_intersects(const CgalMesh& mesh) { return PMP::does_self_intersect(mesh); }

std::string allocator_description() {
  // The bracketed word of e.g. "always [madvise] never".
  std::ifstream in("/sys/kernel/mm/transparent_hugepage/enabled");
  std::string modes, mode = "unknown";
  std::getline(in, modes);
  const std::size_t open = modes.find('['), close = modes.find(']');
  if (open != std::string::npos && close != std::string::npos && close > open) mode = modes.substr(open + 1, close - open - 1);
#if SHATTER_WITH_JEMALLOC
  return "jemalloc, transparent huge pages left to the kernel (THP mode: " + mode + ")";
#else
  return "the C library's malloc (kernel THP mode: " + mode + ")";
#endif
}

double seconds_between(std::chrono::steady_clock::time_point a, std::chrono::steady_clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

std::string ratio_text(double ratio) {
  if (std::isnan(ratio) || std::isinf(ratio)) return "–";
  return fixed(ratio, ratio < 10 ? 2 : 1);
}

CgalMesh to_cgal(const Mesh& mesh) {
  CgalMesh out;
  out.reserve(static_cast<CgalMesh::size_type>(mesh.positions.size()),
              static_cast<CgalMesh::size_type>(mesh.positions.size() + mesh.triangles.size()),
              static_cast<CgalMesh::size_type>(mesh.triangles.size()));
  std::vector<CgalMesh::Vertex_index> vertices;
  vertices.reserve(mesh.positions.size());
  for (const auto& p : mesh.positions) vertices.push_back(out.add_vertex(Epick::Point_3(p.x, p.y, p.z)));
  for (const auto& [a, b, c] : mesh.triangles) {
    if (out.add_face(vertices[a], vertices[b], vertices[c]) == CgalMesh::null_face())
      throw std::runtime_error("the mesh is not a valid CGAL Surface_mesh (non-manifold face)");
  }
  return out;
}

double median(std::vector<double> values, double empty_value) {
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  if (n == 0) return empty_value;
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

std::string fixed(double value, int digits) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*f", digits, value);
  return buffer;
}

std::string with_thousands(std::uint64_t value) {
  std::string digits = std::to_string(value), out;
  for (std::size_t i = 0; i < digits.size(); ++i) {
    if (i && (digits.size() - i) % 3 == 0) out += ',';
    out += digits[i];
  }
  return out;
}

std::string seconds_text(double s) {
  if (std::isnan(s)) return "–";
  return fixed(s, s < 0.001 ? 6 : s < 0.01 ? 5 : s < 0.1 ? 4 : s < 1 ? 3 : s < 100 ? 2 : 1);
}

std::string PeerResult::status_name() const {
  switch (status) {
    case Status::ok: return "ok";
    case Status::timeout: return "timeout";
    case Status::crashed: return "crashed";
    case Status::error: return "error";
  }
  return "?";
}

// ---------------------------------------------------------------------------
// The peer: CGAL clip replaying a tree's planes (moved from tree_bench.cpp).

namespace {
using Clock = std::chrono::steady_clock;


/// Area-weighted centroid of the surface, computed the same way for both sides of
/// the matching; it needs no closed surface, unlike a volume centroid. Falls back
/// to the vertex average for a surface of zero area.
template <class TriangleVisitor>
shatter::Vec3 surface_centroid(TriangleVisitor for_each_triangle) {
  shatter::Vec3 weighted{}, vertex_sum{};
  double area = 0;
  std::size_t corners = 0;
  for_each_triangle([&](shatter::Vec3 a, shatter::Vec3 b, shatter::Vec3 c) {
    const double w = shatter::norm(shatter::cross(b - a, c - a));
    weighted = weighted + (a + b + c) * (w / 3.0);
    area += w;
    vertex_sum = vertex_sum + a + b + c;
    corners += 3;
  });
  if (area > 0) return weighted * (1.0 / area);
  return corners ? vertex_sum * (1.0 / static_cast<double>(corners)) : shatter::Vec3{};
}

shatter::Vec3 surface_centroid(const shatter::Mesh& mesh) {
  return surface_centroid([&](auto&& visit) {
    for (const auto& [a, b, c] : mesh.triangles) visit(mesh.positions[a], mesh.positions[b], mesh.positions[c]);
  });
}

shatter::Vec3 surface_centroid(const CgalMesh& mesh) {
  return surface_centroid([&](auto&& visit) {
    for (const auto face : mesh.faces()) {
      std::array<shatter::Vec3, 3> corner{};
      std::size_t k = 0;
      for (const auto v : CGAL::vertices_around_face(mesh.halfedge(face), mesh)) {
        const auto& p = mesh.point(v);
        if (k < 3) corner[k] = {p.x(), p.y(), p.z()};
        ++k;
      }
      if (k == 3) visit(corner[0], corner[1], corner[2]);
    }
  });
}

/// Pairs every component with one child, closest centroids first. Returns for each
/// component the index into `children`.
std::vector<std::size_t> match_by_centroid(const std::vector<CgalMesh>& components, const MeshTree& tree,
                                           const std::vector<NodeIndex>& children) {
  struct Pair {
    double distance;
    std::size_t component, child;
  };
  std::vector<shatter::Vec3> child_centroids;
  for (const NodeIndex child : children) child_centroids.push_back(surface_centroid(*tree.nodes[child].mesh));
  std::vector<Pair> pairs;
  for (std::size_t i = 0; i < components.size(); ++i) {
    const shatter::Vec3 c = surface_centroid(components[i]);
    for (std::size_t j = 0; j < children.size(); ++j) pairs.push_back({shatter::norm(c - child_centroids[j]), i, j});
  }
  std::sort(pairs.begin(), pairs.end(), [](const Pair& a, const Pair& b) {
    return a.distance != b.distance ? a.distance < b.distance
                                    : std::pair(a.component, a.child) < std::pair(b.component, b.child);
  });
  constexpr std::size_t unassigned = std::numeric_limits<std::size_t>::max();
  std::vector<std::size_t> child_of(components.size(), unassigned);
  std::vector<bool> taken(children.size(), false);
  for (const Pair& p : pairs) {
    if (child_of[p.component] != unassigned || taken[p.child]) continue;
    child_of[p.component] = p.child;
    taken[p.child] = true;
  }
  return child_of;
}

bool peer_piece_valid(const CgalMesh& piece) {
  if (piece.number_of_faces() == 0 || !CGAL::is_triangle_mesh(piece) || !CGAL::is_closed(piece)) return false;
  if (PMP::does_self_intersect(piece)) return false;
  return PMP::volume(piece) > 0;
}

/// Runs in the forked child: replays the tree with CGAL and reports through `send`
/// (one line at a time, see PeerResult parsing in the parent).
void replay_with_cgal(const MeshTree& tree, const shatter::Mesh& input, bool check_pieces,
                      const std::function<void(const std::string&)>& send) {
  const std::size_t internal_nodes = tree.nodes.size() - tree.leaf_count();
  std::size_t nodes_done = 0, failed_clips = 0, threw = 0, mismatches = 0, missing = 0;
  double clip_seconds = 0;
  auto report_progress = [&] {
    send("progress " + std::to_string(nodes_done) + " " + std::to_string(internal_nodes) + " " +
         fixed(clip_seconds, 6));
  };

  std::vector<std::optional<CgalMesh>> piece(tree.nodes.size());
  piece[0] = to_cgal(input);
  auto last_report = Clock::now();
  for (std::size_t index = 0; index < tree.nodes.size(); ++index) {
    const auto& node = tree.nodes[index];
    if (node.is_leaf() || !piece[index]) continue;
    // Two copies, made outside the clock: clip keeps the plane's negative side.
    std::array<CgalMesh, 2> side{*piece[index], std::move(*piece[index])};
    piece[index].reset();
    const shatter::Plane& cut = tree.cut_planes[index];
    const Epick::Plane_3 below_plane(cut.normal.x, cut.normal.y, cut.normal.z, cut.offset);
    const std::array<Epick::Plane_3, 2> plane{below_plane, below_plane.opposite()};
    std::array<bool, 2> clipped{false, false}, thrown{false, false};
    std::array<std::vector<CgalMesh>, 2> components;
    for (std::size_t s = 0; s < 2; ++s) {
      try {
        const auto t0 = Clock::now();
        clipped[s] = cgal_clip_volume(side[s], plane[s]);
        if (clipped[s]) {
          side[s].collect_garbage();  // the default index maps need dense indices
          PMP::split_connected_components(side[s], components[s]);
        }
        clip_seconds += seconds_between(t0, Clock::now());
      } catch (...) {
        thrown[s] = true;
      }
    }
    ++nodes_done;
    for (std::size_t s = 0; s < 2; ++s) {
      std::vector<NodeIndex> children;
      for (const NodeIndex child : node.children)
        if (tree.nodes[child].above_parent_plane == (s == 1)) children.push_back(child);
      const bool usable = !thrown[s] && clipped[s] && components[s].size() == children.size();
      if (thrown[s]) {
        ++threw;
      } else if (!clipped[s]) {
        ++failed_clips;
      } else if (!usable) {
        ++mismatches;
      }
      if (!usable) {
        for (const NodeIndex child : children) missing += tree.nodes[child].leaf_count;
        continue;
      }
      const auto child_of = match_by_centroid(components[s], tree, children);
      for (std::size_t k = 0; k < child_of.size(); ++k) piece[children[child_of[k]]] = std::move(components[s][k]);
    }
    if (seconds_between(last_report, Clock::now()) > 0.25) {
      report_progress();
      last_report = Clock::now();
    }
  }
  send("clipped " + fixed(clip_seconds, 6) + " " + std::to_string(nodes_done) + " " + std::to_string(internal_nodes) +
       " " + std::to_string(failed_clips) + " " + std::to_string(threw) + " " + std::to_string(mismatches) + " " +
       std::to_string(missing));
  if (!check_pieces) return;
  std::size_t pieces = 0, invalid = 0;
  for (const NodeIndex leaf : tree.leaf_nodes) {
    if (!piece[leaf]) continue;
    ++pieces;
    bool valid = false;
    try {
      valid = peer_piece_valid(*piece[leaf]);
    } catch (...) {
    }
    invalid += !valid;
  }
  send("checked " + std::to_string(pieces) + " " + std::to_string(invalid));
}

void apply_peer_line(const std::string& line, PeerResult& result) {
  std::istringstream in(line);
  std::string tag;
  in >> tag;
  if (tag == "progress") {
    in >> result.nodes_done >> result.internal_nodes >> result.clip_seconds;
  } else if (tag == "clipped") {
    in >> result.clip_seconds >> result.nodes_done >> result.internal_nodes >> result.failed_clips >> result.threw >>
        result.mismatches >> result.missing;
    result.clipping_finished = true;
  } else if (tag == "checked") {
    in >> result.pieces >> result.invalid;
  } else if (tag == "error") {
    result.status = PeerResult::Status::error;
    std::getline(in >> std::ws, result.detail);
  }
}

/// Runs in the forked child: cuts the cells out of `input` with CGAL and reports
/// through `send` (progress lines, then "cells_clipped ...", then
/// "cells_checked ..." when `check_pieces`).
void clip_cells_with_cgal(const shatter::Mesh& input, const std::vector<std::vector<shatter::Plane>>& cells,
                          std::span<const shatter::Vec3> sites, bool check_pieces,
                          const std::function<void(const std::string&)>& send) {
  const CgalMesh whole = to_cgal(input);
  // The input's box grown by a tenth bounds every cell (a cell without its
  // container's walls may be unbounded), and cuts nothing of the input.
  const auto [lo, hi] = grown_box(input, 0.1);
  const std::array<Epick::Plane_3, 6> walls{Epick::Plane_3(-1, 0, 0, lo.x), Epick::Plane_3(1, 0, 0, -hi.x),
                                            Epick::Plane_3(0, -1, 0, lo.y), Epick::Plane_3(0, 1, 0, -hi.y),
                                            Epick::Plane_3(0, 0, -1, lo.z), Epick::Plane_3(0, 0, 1, -hi.z)};
  std::size_t cells_done = 0, failed_clips = 0, threw = 0, fragments = 0;
  double clip_seconds = 0;
  std::vector<CgalMesh> pieces;  // every fragment, checked after the clock
  auto last_report = Clock::now();
  for (std::size_t c = 0; c < cells.size(); ++c) {
    std::vector<CgalMesh> components;
    try {
      // Outside the clock: the input's copy, and the cell as a closed triangle
      // mesh (the intersection of its half-spaces, around its site).
      CgalMesh piece = whole;
      std::vector<Epick::Plane_3> planes(walls.begin(), walls.end());
      for (const shatter::Plane& plane : cells[c]) {
        planes.emplace_back(plane.normal.x, plane.normal.y, plane.normal.z, plane.offset);
      }
      CgalMesh cell;
      CGAL::halfspace_intersection_3(planes.begin(), planes.end(), cell,
                                     boost::make_optional(Epick::Point_3(sites[c].x, sites[c].y, sites[c].z)));
      PMP::triangulate_faces(cell);
      const auto t0 = Clock::now();
      const bool clipped = PMP::clip(piece, cell, CGAL::parameters::clip_volume(true));
      if (clipped && piece.number_of_faces() > 0) {
        piece.collect_garbage();  // the default index maps need dense indices
        PMP::split_connected_components(piece, components);
      }
      clip_seconds += seconds_between(t0, Clock::now());
      if (!clipped) ++failed_clips;
    } catch (...) {
      ++threw;
      components.clear();
    }
    ++cells_done;
    fragments += components.size();
    if (check_pieces) {
      for (CgalMesh& component : components) pieces.push_back(std::move(component));
    }
    if (seconds_between(last_report, Clock::now()) > 0.25) {
      send("cells_progress " + std::to_string(cells_done) + " " + fixed(clip_seconds, 6));
      last_report = Clock::now();
    }
  }
  send("cells_clipped " + fixed(clip_seconds, 6) + " " + std::to_string(cells_done) + " " + std::to_string(failed_clips) +
       " " + std::to_string(threw) + " " + std::to_string(fragments));
  if (!check_pieces) return;
  std::size_t invalid = 0;
  double volume = 0;
  for (const CgalMesh& piece : pieces) {
    bool valid = false;
    try {
      valid = peer_piece_valid(piece);
      if (CGAL::is_closed(piece)) volume += PMP::volume(piece);
    } catch (...) {
    }
    invalid += !valid;
  }
  char volume_text[64];
  std::snprintf(volume_text, sizeof volume_text, "%.17g", volume);
  send("cells_checked " + std::to_string(invalid) + " " + volume_text);
}

void apply_cell_line(const std::string& line, CellClipResult& result) {
  std::istringstream in(line);
  std::string tag;
  in >> tag;
  if (tag == "cells_progress") {
    in >> result.cells_done >> result.clip_seconds;
  } else if (tag == "cells_clipped") {
    in >> result.clip_seconds >> result.cells_done >> result.failed_clips >> result.threw >> result.fragments;
    result.clipping_finished = true;
  } else if (tag == "cells_checked") {
    in >> result.invalid >> result.volume;
  } else if (tag == "error") {
    result.status = PeerResult::Status::error;
    std::getline(in >> std::ws, result.detail);
  }
}

/// The address space the process uses now, so the child's limit can be "this much more".
std::uint64_t current_address_space_bytes() {
  std::ifstream statm("/proc/self/statm");
  std::uint64_t pages = 0;
  statm >> pages;
  return pages * static_cast<std::uint64_t>(::sysconf(_SC_PAGESIZE));
}

}  // namespace

pid_t fork_flushed() {
  std::cout.flush();
  std::cerr.flush();
  std::fflush(nullptr);
  const pid_t pid = ::fork();
  if (pid < 0) throw std::runtime_error(std::string("fork failed: ") + std::strerror(errno));
  return pid;
}

int wait_for_child(pid_t pid) {
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  return status;
}

void write_all(int fd, const std::string& text) {
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return;
    done += static_cast<std::size_t>(n);
  }
}

int signal_in_forked_child(const std::function<void()>& body) {
  const pid_t pid = fork_flushed();
  if (pid == 0) {
    body();
    ::_exit(0);  // no destructors or atexit handlers of the parent's state
  }
  const int status = wait_for_child(pid);
  return WIFSIGNALED(status) ? WTERMSIG(status) : 0;
}

ChildReport run_reporting_child(const std::function<void(const std::function<void(const std::string&)>&)>& body,
                                const ReplayLimits& limits) {
  int fds[2];
  if (::pipe(fds) != 0) throw std::runtime_error(std::string("pipe failed: ") + std::strerror(errno));
  const pid_t pid = fork_flushed();
  if (pid == 0) {
    ::close(fds[0]);
    // Should this process be orphaned while CGAL hangs, it still ends.
    ::alarm(static_cast<unsigned>(std::ceil(limits.timeout_seconds)) + 30);
    const rlim_t limit =
        static_cast<rlim_t>(current_address_space_bytes() + limits.memory_mb * 1024 * 1024);
    const rlimit address_space{limit, limit};
    ::setrlimit(RLIMIT_AS, &address_space);
    const int out = fds[1];
    try {
      body([out](const std::string& line) { write_all(out, line + "\n"); });
    } catch (const std::exception& e) {
      write_all(out, std::string("error ") + e.what() + "\n");
    } catch (...) {
      write_all(out, "error unknown exception\n");
    }
    ::close(out);
    ::_exit(0);  // no destructors or atexit handlers of the parent's state
  }

  ::close(fds[1]);
  ChildReport report;
  std::string pending;
  const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                           std::chrono::duration<double>(limits.timeout_seconds));
  for (;;) {
    const double remaining = seconds_between(Clock::now(), deadline);
    if (remaining <= 0) {
      report.timed_out = true;
      break;
    }
    pollfd watch{fds[0], POLLIN, 0};
    const int ready = ::poll(&watch, 1, static_cast<int>(std::min(remaining * 1000.0, 1000.0)) + 1);
    if (ready < 0 && errno == EINTR) continue;
    if (ready <= 0) continue;
    char buffer[4096];
    const ssize_t n = ::read(fds[0], buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;  // end of file: the child is done (or died)
    pending.append(buffer, static_cast<std::size_t>(n));
    for (std::size_t eol; (eol = pending.find('\n')) != std::string::npos;) {
      report.lines.push_back(pending.substr(0, eol));
      pending.erase(0, eol + 1);
    }
  }
  if (report.timed_out) ::kill(pid, SIGKILL);
  ::close(fds[0]);
  const int status = wait_for_child(pid);
  if (WIFSIGNALED(status)) report.signal = WTERMSIG(status);
  return report;
}

namespace {

// How a CGAL child ended, into `status` and `detail` (left as the lines set them
// when it ran to its end): a timeout, a signal, or no final line (`finished`)
// although it exited; `progress` says how far it got, `what` names the run.
void settle_status(const ChildReport& child, const ReplayLimits& limits, bool finished, const std::string& progress,
                   const char* what, PeerResult::Status& status, std::string& detail) {
  if (child.timed_out) {
    status = PeerResult::Status::timeout;
    detail = "no result within " + fixed(limits.timeout_seconds, 0) + " s (" +
             (finished ? "clipping finished, checking pieces" : progress) + ")";
  } else if (child.signal != 0) {
    status = PeerResult::Status::crashed;
    detail = std::string("signal ") + std::to_string(child.signal) + " (" + ::strsignal(child.signal) + ") after " +
             progress;
  } else if (status == PeerResult::Status::ok && !finished) {
    status = PeerResult::Status::error;
    detail = std::string(what) + " ended without a result after " + progress;
  }
}

}  // namespace

PeerResult replay_with_cgal_isolated(const MeshTree& tree, const Mesh& input, const ReplayLimits& limits) {
  const ChildReport child = run_reporting_child(
      [&](const std::function<void(const std::string&)>& send) {
        replay_with_cgal(tree, input, limits.check_pieces, send);
      },
      limits);
  PeerResult result;
  for (const std::string& line : child.lines) apply_peer_line(line, result);
  const std::string progress = std::to_string(result.nodes_done) + "/" + std::to_string(result.internal_nodes) +
                               " nodes clipped in " + seconds_text(result.clip_seconds) + " s";
  settle_status(child, limits, result.clipping_finished, progress, "the replay", result.status, result.detail);
  return result;
}

CellClipResult clip_cells_with_cgal_isolated(const Mesh& input, const std::vector<std::vector<Plane>>& cells,
                                             std::span<const Vec3> sites, const ReplayLimits& limits) {
  const ChildReport child = run_reporting_child(
      [&](const std::function<void(const std::string&)>& send) {
        clip_cells_with_cgal(input, cells, sites, limits.check_pieces, send);
      },
      limits);
  CellClipResult result;
  result.cells = cells.size();
  for (const std::string& line : child.lines) apply_cell_line(line, result);
  const std::string progress = std::to_string(result.cells_done) + "/" + std::to_string(result.cells) +
                               " cells clipped in " + seconds_text(result.clip_seconds) + " s";
  settle_status(child, limits, result.clipping_finished, progress, "the cells", result.status, result.detail);
  return result;
}

std::array<Vec3, 2> grown_box(const Mesh& mesh, double fraction) {
  Vec3 lo = mesh.positions.front(), hi = lo;
  for (const Vec3& p : mesh.positions) {
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  }
  const Vec3 room = (hi - lo) * fraction;
  return {lo - room, hi + room};
}

Mesh subdivide_midpoints(const Mesh& mesh) {
  Mesh out;
  out.positions = mesh.positions;
  std::unordered_map<std::uint64_t, VertexIndex> midpoint_of;
  auto midpoint = [&](VertexIndex a, VertexIndex b) {
    const std::uint64_t key = (std::uint64_t{std::min(a, b)} << 32) | std::max(a, b);
    const auto [it, inserted] = midpoint_of.try_emplace(key, static_cast<VertexIndex>(out.positions.size()));
    if (inserted) out.positions.push_back((mesh.positions[a] + mesh.positions[b]) * 0.5);
    return it->second;
  };
  for (const auto& [a, b, c] : mesh.triangles) {
    const auto ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
    out.triangles.push_back({a, ab, ca});
    out.triangles.push_back({ab, b, bc});
    out.triangles.push_back({ca, bc, c});
    out.triangles.push_back({ab, bc, ca});
  }
  out.surfaces.assign(out.triangles.size(), original_surface);
  return out;
}


}  // namespace shatter::bench
