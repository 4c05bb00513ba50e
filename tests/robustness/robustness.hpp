#pragma once
// The robustness runner's model: seeded cases drawn from every degenerate class
// and every mesh, the invariant checks each case must pass, reproducer files, and
// the predicate audit. shatter-fuzz (main.cpp) is the command line over it;
// CTest replays the reproducers checked in under tests/regressions/ (shatter-fuzz
// --replay, one test per file).

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "shatter/kernel/implicit.hpp"
#include "shatter/kernel/io.hpp"
#include "shatter/kernel/mesh.hpp"
#include "shatter/meshtree/build.hpp"
#include "shatter/meshtree/tree.hpp"

namespace shatter::robust {

/// The degenerate classes of issue 4, one per kind of trouble.
enum class CaseClass : std::uint8_t {
  random_plane,         ///< a random plane through the bounding box: the baseline
  vertex_plane,         ///< through a vertex: exactly (axis normal) or up to rounding (any normal)
  vertex_plane_ulps,    ///< the same, moved 1-4 ulps off
  edge_plane,           ///< holding an edge (exactly on lattice meshes, up to rounding elsewhere)
  edge_plane_ulps,      ///< the same, moved 1-4 ulps off
  face_plane,           ///< holding a face
  face_plane_ulps,      ///< the same, moved 1-4 ulps off
  many_vertices,        ///< grid-subdivided boxes cut along grid lines: dozens of vertices on the plane
  coplanar_faces,       ///< staircases and stacked boxes: coplanar faces, planes holding them
  slivers_needles,      ///< slivers, needle necks, flat tetrahedra down to 2^-40 thick
  nested_shells,        ///< cavities, islands in cavities, islands in islands
  pinch,                ///< a saddle vertex where the cut's cap loops touch
  near_parallel_chain,  ///< several cuts through one edge, turned by ever smaller angles
  extreme_scale,        ///< coordinates scaled by 2^-30 .. 2^30 (about 1e-9 .. 1e9)
  far_from_origin,      ///< shifted up to 1e9 away from the origin
  attribute_seams,      ///< per-corner normals and UVs with a seam at every vertex
};
inline constexpr int case_class_count = 16;
std::string_view class_name(CaseClass kind);
std::optional<CaseClass> parse_class(std::string_view name);

enum class Operation : std::uint8_t { slice, fracture };
std::string_view operation_name(Operation op);

/// What a replayed reproducer must show besides "no failure" (its `expect` line):
/// a regression checked in with its fix can pin the outcome the fix gave.
enum class Expected : std::uint8_t {
  no_failure,          ///< no line: every invariant holds (refusals are allowed)
  valid_as_written,    ///< `expect valid-as-written`: nothing refused, every piece written, read back and valid
};
std::string_view expected_name(Expected expected);

/// One input: a mesh and what to do with it. `slice` cuts the mesh by planes[0],
/// then every piece by planes[1], and so on (a chain); `fracture` builds the mesh
/// tree by `recipe`. Every output piece (each piece of each cut; a fracture's
/// leaves) is written in `format` and read back.
struct Case {
  CaseClass kind = CaseClass::random_plane;
  std::string mesh_name;
  Mesh mesh;
  Operation op = Operation::slice;
  std::vector<Plane> planes;
  TreeRecipe recipe;
  MeshFormat format = MeshFormat::off;  ///< the format output pieces are written in
  std::uint64_t seed = 0;  ///< the seed the case was drawn from (reported, replayed)
  Expected expected = Expected::no_failure;  ///< what a replay must show (reproducers only)
};

/// What one case showed. A failure is a broken promise; a refusal is the
/// documented UnsupportedGeometryError (counted, not a failure).
struct CaseOutcome {
  std::vector<std::string> failures;  ///< empty: every invariant held
  bool refused = false;
  std::size_t plane_pieces = 0;  ///< exact solids checked (check_solid, exact volume)
  /// Output pieces written (write_mesh_to_bytes in the case's format) and read
  /// back, and of those the ones validate_mesh (with self-intersections) finds
  /// invalid as read back (each also a failure).
  std::size_t written = 0, invalid_written = 0;
  std::size_t plane_unroundable = 0;  ///< plane pieces round_solid refused to write (not a failure)
  std::size_t plane_vanished = 0;     ///< plane pieces thinner than their rounding, collapsed whole (not written)
  std::size_t plane_separated = 0;    ///< plane pieces written after moving apart points where they touched themselves
  std::size_t plane_pinched = 0;      ///< plane cuts cut_solid refused as pinching a piece (not a failure)
  /// One line per refusal of a slice (an unroundable piece, with round_solid's
  /// defect, or a pinching cut), in the order met, and the chain's planes up to
  /// the first refused cut (a case that refuses the same, see remember_prefix).
  std::vector<std::string> refusals;
  std::optional<Case> refused_prefix;
  /// The plane-kernel predicate calls the checks themselves made (check_solid's
  /// corners-on-their-planes tests, whose true answers are zero, and the sides
  /// behind plane_missed), so a report can leave them out of the kernel's own.
  ImplicitCounters checker_predicates;
  /// The smallest case that still fails: the chain's planes up to the cut where
  /// it first failed, on the same mesh (its pieces are defined from the input);
  /// unset when there is nothing smaller.
  std::optional<Case> shrunk;
};

/// Loads every valid mesh of the shared corpus and the generated catalogue once.
/// Throws if the corpus is missing, so a run can never pass by testing nothing.
struct MeshPool {
  std::vector<std::pair<std::string, Mesh>> meshes;
  static MeshPool load();
};

/// The case numbered `index` of a run seeded with `seed`: its class is
/// index mod case_class_count (so every class gets its share), everything else is
/// drawn from splitmix64(seed, index). Deterministic.
Case make_case(const MeshPool& pool, std::uint64_t seed, std::uint64_t index);

/// Checks every invariant of DESIGN.md on the case's output (see robustness.cpp).
/// Never throws: an unexpected exception is a failure.
CaseOutcome run_case(const Case& c);

/// Writes a self-contained reproducer (text header with the planes as hex
/// doubles, then the mesh as OBJ), atomically. Returns its path.
std::filesystem::path write_reproducer(const std::filesystem::path& dir, const Case& c,
                                       const std::string& failure);
/// Reads a reproducer back. Throws InvalidMeshError on a malformed file.
/// Besides what write_reproducer writes, a hand-written reproducer may name a
/// mesh of the test corpus instead of holding one (`mesh-corpus <file>`, read
/// from tests/data/corpus as `shatter` reads it) and pin its outcome (`expect`).
Case read_reproducer(const std::filesystem::path& path);

/// Empty when `outcome` shows what `c.expected` asks for; else what it showed.
std::string unmet_expectation(const Case& c, const CaseOutcome& outcome);

/// The predicate audit: `queries` side-of-plane queries at points built exactly on
/// a plane, then moved by k ulps per coordinate, compared with an independent GMP
/// evaluation. Each base point gives the point itself, 8 points moved by -4..4
/// ulps in each coordinate, and 3 moved by 2^3..2^40 ulps in one coordinate, so
/// the filter's fall-back rate is seen both where it must fall back and where it
/// should not.
struct AuditBand {
  std::uint64_t queries = 0;
  std::uint64_t exact_fallbacks = 0;  ///< queries the floating-point filter passed to GMP
  std::uint64_t on_plane = 0;         ///< queries whose true answer is zero
};
struct AuditResult {
  std::uint64_t queries = 0;
  std::uint64_t disagreements = 0;
  AuditBand exact_on_plane, within_4_ulps, far_8_to_2e40_ulps;
  std::string first_disagreement;
};
AuditResult audit_side_of_plane(std::uint64_t queries, std::uint64_t seed, unsigned threads);

/// The plane kernel's predicates (kernel/implicit.hpp) audited the same way,
/// against an exact reference written here from the definitions in implicit.hpp
/// (GMP rationals: a segment_plane point as p + t(q - p), a three_planes point by
/// Cramer's rule; no code shared with kernel/src/implicit.cpp). Each scene is a
/// lattice (spacing 2^-30..2^30, sometimes shifted up to 2^40 spacings from the
/// origin) with hub points that many planes and points pass through exactly: cut
/// planes with small-integer normals through a hub, input planes through three
/// lattice points around it, segments across it, so that points of every kind
/// coincide with the hub and lie exactly on planes not among their own. Band 0
/// keeps the scene exact; band 1 moves three quarters of the constructed cut
/// planes' offsets by 1-4 ulps (of the plane's n·x terms) and a quarter of the
/// input points by -4..4 ulps per coordinate; band 2 moves them by 2^3..2^40 ulps
/// (points: along one axis). Rows: side() for each point kind against cut and input planes,
/// side() with an explicit plane, orient_in_plane (three defined points, and two
/// with an explicit point), compare_along, compare_coordinate.
inline constexpr int plane_audit_rows = 13;
std::string_view plane_audit_row_name(int row);
struct PlaneAuditResult {
  std::uint64_t queries = 0;
  std::uint64_t disagreements = 0;
  /// [row][band]: band 0 exact lattice, 1 moved 1-4 ulps, 2 moved 2^3..2^40 ulps.
  /// exact_fallbacks counts the queries implicit_counters() shows falling back.
  std::array<std::array<AuditBand, 3>, plane_audit_rows> bands{};
  std::array<std::array<std::uint64_t, 3>, plane_audit_rows> band_disagreements{};  ///< [row][band]
  std::string first_disagreement;
};
PlaneAuditResult audit_plane_predicates(std::uint64_t queries, std::uint64_t seed, unsigned threads);

}  // namespace shatter::robust
