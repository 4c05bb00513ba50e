#pragma once
// The robustness runner's model: seeded cases drawn from every degenerate class
// and every mesh, the invariant checks each case must pass, reproducer files, and
// the predicate audit. shatter-fuzz (main.cpp) is the command line over it;
// test_regressions replays the reproducers checked in under tests/regressions/.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "shatter/kernel/mesh.hpp"
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

/// One input: a mesh and what to do with it. `slice` cuts the mesh by planes[0],
/// then every piece by planes[1], and so on (a chain); `fracture` builds the mesh
/// tree with `build`.
struct Case {
  CaseClass kind = CaseClass::random_plane;
  std::string mesh_name;
  Mesh mesh;
  Operation op = Operation::slice;
  KernelKind kernel = KernelKind::fast;
  std::vector<Plane> planes;
  BuildOptions build;
  std::uint64_t seed = 0;  ///< the seed the case was drawn from (reported, replayed)
};

/// What one case showed. A failure is a broken promise; a refusal is the
/// documented UnsupportedGeometryError (counted, not a failure).
struct CaseOutcome {
  std::vector<std::string> failures;  ///< empty: every invariant held
  bool refused = false;
  std::size_t fast_pieces = 0;              ///< fast-kernel solids checked
  std::size_t fast_self_intersecting = 0;   ///< of those, embeddings that intersect themselves
  std::size_t fast_degenerate = 0;          ///< of those, other embedding defects (zero area, volume <= 0)
  std::size_t exact_pieces = 0;             ///< exact-kernel solids checked
  /// The smallest case that still fails: for a chain, the one cut of the piece
  /// where it first failed; unset when there is nothing smaller.
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
Case read_reproducer(const std::filesystem::path& path);

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

}  // namespace shatter::robust
