#pragma once
// What the benchmarks share: the peer's mesh type and conversion, the median of
// repeated timings, number formatting for the Markdown tables, and the CGAL clip
// replay of a mesh tree's planes in a forked, time-limited child.

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>

#include <sys/types.h>

#include <array>
#include <chrono>
#include <cstdint>
#include <functional>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "shatter/kernel/mesh.hpp"
#include "shatter/meshtree/tree.hpp"

namespace shatter::bench {

using Epick = CGAL::Epick;
/// The peer's mesh: CGAL's Surface_mesh over doubles with exact predicates.
using CgalMesh = CGAL::Surface_mesh<Epick::Point_3>;

/// The same triangles as a Surface_mesh. Throws std::runtime_error when a face
/// cannot be added (the mesh is not an oriented 2-manifold).
CgalMesh to_cgal(const Mesh& mesh);

/// CGAL 5.5 PMP::clip(clip_volume(true)) of `mesh` by `plane`: keeps the part on the
/// plane's negative side, closed by a cap. Returns what clip returned (false: CGAL
/// could not clip, the mesh is then unspecified). The one place the benchmarks
/// instantiate clip over Epick (its templates cost about a minute of compilation
/// per kernel; the robustness benchmark alone instantiates it over Epeck too).
bool cgal_clip_volume(CgalMesh& mesh, const Epick::Plane_3& plane);

/// The number of connected components of `mesh` (0 when it has no face).
std::size_t cgal_component_count(CgalMesh& mesh);

/// Whether two faces of `mesh` intersect other than along a shared edge or vertex
/// (PMP::does_self_intersect).
bool cgal_self_intersects(const CgalMesh& mesh);

/// The allocator the benchmark runs on, for the header of its tables: "jemalloc,
/// transparent huge pages left to the kernel (THP mode: madvise)" or "the C
/// library's malloc (...)". The kernel's mode is read from /sys; "unknown" when
/// that cannot be read.
std::string allocator_description();

/// Seconds from `a` to `b` on the steady clock (negative when b is earlier).
double seconds_between(std::chrono::steady_clock::time_point a, std::chrono::steady_clock::time_point b);

/// A ratio for the tables: two decimals below 10, one above; "–" where a timing is
/// missing (the ratio is NaN or infinite).
std::string ratio_text(double ratio);

/// The median; `empty_value` when there is nothing to take it of.
double median(std::vector<double> values, double empty_value);

/// `value` with `digits` digits after the point, never in exponent form.
std::string fixed(double value, int digits);

/// 65536 -> "65,536".
std::string with_thousands(std::uint64_t value);

/// The corners (lo, hi) of `mesh`'s box grown on every side by `fraction` of its
/// extent along that axis: the peers' container (voro++) and cell walls (CGAL),
/// which then lie outside the solid. Precondition: `mesh` has a position.
std::array<Vec3, 2> grown_box(const Mesh& mesh, double fraction);

/// Each triangle into four by its edge midpoints (shared per edge, so the mesh
/// stays closed and welded); flat: the new vertices are (a + b) / 2 in doubles,
/// so the triangles of one input triangle stay coplanar. Makes the benchmarks'
/// larger inputs (fandisk x4: 51,784 triangles, the issue 22 target's size).
Mesh subdivide_midpoints(const Mesh& mesh);

/// A measurement that was not taken (printed "–", an empty CSV field).
inline constexpr double not_measured = std::numeric_limits<double>::quiet_NaN();

/// Seconds with about four significant digits, never in exponent form; "–" for NaN.
std::string seconds_text(double s);

// ---------------------------------------------------------------------------
// The peer CGAL 5.5 PMP::clip(clip_volume(true)) on Surface_mesh<Epick>, replaying
// the very planes of a shatter tree. For each internal node in preorder, the
// peer's piece for that node is clipped on both sides of the node's plane (two
// copies, clipped by the plane and by its opposite), each side is split into
// connected components, and those are matched to the node's children on that side
// by nearest area-weighted surface centroid. A side whose clip returns false or
// throws, or whose component count differs from shatter's child count, ends the
// replay of those children's subtrees: counted, and their leaves reported missing.
// Its time is the sum of the clip and split_connected_components calls only.

/// What one replay did; a timeout or crash keeps the progress made before it.
struct PeerResult {
  enum class Status { ok, timeout, crashed, error } status = Status::ok;
  double clip_seconds = not_measured;  ///< a lower bound unless status is ok
  std::size_t internal_nodes = 0, nodes_done = 0;
  std::size_t failed_clips = 0, threw = 0, mismatches = 0, missing = 0;
  long pieces = -1, invalid = -1;  ///< leaf pieces produced and how many are invalid; -1 = not checked
  bool clipping_finished = false;
  std::string detail;  ///< why it is not ok

  std::string status_name() const;
  /// Seconds to compare with, when the replay ran to its end.
  double comparable_seconds() const { return status == Status::ok ? clip_seconds : not_measured; }
};

struct ReplayLimits {
  double timeout_seconds = 60;    ///< wall clock of the whole replay, checks included
  std::uint64_t memory_mb = 8192; ///< address space the child may add to this process's
  /// Check every leaf piece (closed, no self-intersection, volume > 0) after the clock.
  bool check_pieces = true;
};

/// Flushes every output stream (or the child's copy of buffered output would be
/// written twice), then forks: 0 in the child, the child's pid in the parent.
/// Throws std::runtime_error when fork fails.
pid_t fork_flushed();

/// Waits for the child `pid` to end, retrying when a signal interrupts the wait,
/// and returns its wait status.
int wait_for_child(pid_t pid);

/// Writes all of `text` to the pipe `fd`; when the reader is gone, it stops.
void write_all(int fd, const std::string& text);

/// Runs `body` once in a forked child and returns the signal that ended the child,
/// or 0 when `body` returned (an exception escaping it ends the child with
/// SIGABRT). For a peer that can crash on input shatter handles (CGAL clip over
/// Epick segfaults triangulating some nearly degenerate cap polygons): a benchmark
/// times in its own process only what survived here. Throws std::runtime_error
/// when fork fails.
int signal_in_forked_child(const std::function<void()>& body);

/// What a child of run_reporting_child said and how it ended.
struct ChildReport {
  std::vector<std::string> lines;  ///< every line it sent, in order
  bool timed_out = false;          ///< killed at the limit's timeout
  int signal = 0;                  ///< the signal that ended it (SIGKILL after a timeout), else 0
};

/// Runs `body` in a forked child under `limits` (timeout and address space;
/// check_pieces is the body's business): the child reports through the `send`
/// it is given, a line at a time, over a pipe, and an exception escaping `body`
/// is sent as "error <what>". Returns the lines the parent read before the
/// child ended or the timeout killed it. Throws std::runtime_error only when
/// pipe or fork fails.
ChildReport run_reporting_child(const std::function<void(const std::function<void(const std::string&)>&)>& body,
                                const ReplayLimits& limits);

/// Replays `tree` (built from `input`) with CGAL clip in a forked child process
/// under `limits`, because after a few levels rounded points can make CGAL's
/// pieces degenerate and clip may then hang, explode or crash. Throws
/// std::runtime_error only when pipe or fork fails.
PeerResult replay_with_cgal_isolated(const MeshTree& tree, const Mesh& input, const ReplayLimits& limits);

// ---------------------------------------------------------------------------
// The peer CGAL 5.5 PMP::clip(clip_volume(true)) on Surface_mesh<Epick> cutting
// given Voronoi cells out of a mesh, the per-cell pipeline of the fracture tools:
// for each cell, a copy of the input clipped by the cell as a closed mesh (the
// intersection of the cell's half-spaces and of the input's box grown by a
// tenth: CGAL::halfspace_intersection_3 around the cell's site, its faces
// triangulated), then split into connected components, its fragments. Its time
// is the sum of the clip and split_connected_components calls only (the copy
// and the cell's mesh are made outside the clock). Clipping by each plane in
// turn instead hung inside clip on the first cube cell at 10^2 sites (its 11th
// plane; 2026-12-07), as corefinement on inexact constructions can.

/// What one run of the cells did; a timeout or crash keeps the progress made.
struct CellClipResult {
  PeerResult::Status status = PeerResult::Status::ok;
  double clip_seconds = not_measured;  ///< a lower bound unless status is ok
  std::size_t cells = 0, cells_done = 0;
  std::size_t failed_clips = 0, threw = 0;  ///< cells whose clip returned false, or threw
  std::size_t fragments = 0;
  long invalid = -1;      ///< fragments not closed, self-intersecting or of volume <= 0; -1 = not checked
  double volume = NAN;    ///< the fragments' volumes summed (PMP::volume), when checked
  bool clipping_finished = false;
  std::string detail;  ///< why it is not ok
};

/// Cuts `cells` (each a list of planes whose negative sides hold the cell;
/// sites[i] strictly inside cell i) out of `input` with CGAL clip in a forked
/// child process under `limits` (clip can hang, explode or crash on nearly
/// degenerate input). Throws std::runtime_error only when pipe or fork fails.
CellClipResult clip_cells_with_cgal_isolated(const Mesh& input, const std::vector<std::vector<Plane>>& cells,
                                             std::span<const Vec3> sites, const ReplayLimits& limits);

}  // namespace shatter::bench
